//! modelgap holds physical models against measurements, shows where they fail, names the
//! physical effect they are missing, adds it and shows the error fall.
//!
//! It builds and diagnoses models of physical systems as **bond graphs** (elements,
//! causality, equations in the notation of the literature, simulation, causal graphs, fault
//! trees and temporal signatures), simulates **cloth** with the impulse-based method for
//! inextensible cloth, reads and writes **measurements** as CSV or MCAP recordings (and reads
//! Parquet), and runs the **measurement loop** on either kind of model: [`compare()`] where
//! it fails, [`explain()`] which effect is missing (or that nothing is, or that the recording
//! cannot be judged), [`Model::with_effects`] to add it.
//!
//! This crate is the facade: it re-exports the workspace's crates under one name, loads a
//! model of any kind by file or name ([`load`]), and ships the `modelgap` command-line tool.
//!
//! # Example: the loop
//!
//! Hold the built-in DC motor against the bundled recording that hides a physical effect
//! (`examples/data/motor_hidden_effect.csv`): compare shows where it fails, explain names
//! what is missing, and the fix — the model with the effect built in, and its model file —
//! brings the error down to the noise floor.
//!
//! ```
//! use modelgap::{CompareOptions, ExplainOptions, LoadOptions, compare, explain};
//!
//! // The model and the recording, as the command line loads them.
//! let motor = modelgap::load_model("dc-motor", &LoadOptions::default())?;
//! let path = concat!(env!("CARGO_MANIFEST_DIR"), "/examples/data/motor_hidden_effect.csv");
//! let rec = modelgap::load_recording(path.as_ref(), motor.as_ref())?;
//!
//! // compare: where the model fails. The current's error is 5.6× its noise floor.
//! let before = compare(motor.as_ref(), &rec, &CompareOptions::default())?;
//! print!("{}", motor.story().comparison_text(&before));
//! let i = before.output("i").expect("the recording measures i");
//! assert!(i.rms_over_floor() > 4.0 && !i.windows.is_empty());
//!
//! // explain: which effect is missing, with its fitted value ± uncertainty.
//! let ex = explain(motor.as_ref(), &rec, &ExplainOptions::default())?;
//! print!("{}", motor.story().explanation_text(&ex, 3));
//! let chosen = &ex.chosen[0];
//! assert_eq!(chosen.candidate.id, "coulomb@1m"); // Coulomb friction on the shaft
//! assert!((chosen.params[0].value - 0.012).abs() < 5e-4); // tau_c, N m: the hidden truth
//!
//! // fix: the model with the effect built in, and its file for keeping (what `modelgap fix
//! // --out` writes); compared again, the error falls to the noise floor.
//! let fixed = motor.with_effects(&ex.effects())?;
//! let file = fixed.to_file_text().expect("a bond graph has a model file");
//! assert!(file.contains("Coulomb"));
//! let after = compare(fixed.as_ref(), &rec, &CompareOptions::default())?;
//! print!("{}", fixed.story().before_after_text(&before, &after));
//! let i_after = after.output("i").expect("the recording measures i");
//! assert!(i_after.rms_over_floor() < 1.3 && i_after.windows.is_empty());
//! # Ok::<(), modelgap::Error>(())
//! ```
//!
//! The same three calls run on a cloth scene and its marker recording ([`load_model`] knows
//! the kind). The report a person reads without the terminal — the plots of measured against
//! model with the error beneath, the ranking, the verdict — is
//! [`Story::write_report`](story::Story::write_report).
//!
//! # Example: a simulation
//!
//! Load the built-in DC motor, run it for half a second from rest and read the speed:
//!
//! ```
//! use modelgap::bond::library;
//! use modelgap::bond::simulate::{Inputs, SimOptions, simulate, time_grid};
//!
//! let motor = library::builtin("dc-motor")?;
//! let run = simulate(&motor, &Inputs::new(), &time_grid(0.5, 1000.0), &SimOptions::default())?;
//! let omega = run.output("omega").unwrap_or_default();
//! let last = omega.last().copied().unwrap_or(f64::NAN);
//! println!("omega after 0.5 s: {last:.2} rad/s"); // about 239 rad/s at 12 V
//! assert!((last - 239.04).abs() < 0.5);
//! # Ok::<(), modelgap::Error>(())
//! ```
//!
//! # Map
//!
//! The workspace is three library crates under this facade; dependencies point one way,
//! core ← bond, cloth ← `modelgap`:
//!
//! - [`modelgap_core`] (re-exported at the top of this crate): recordings and their CSV and
//!   MCAP files, residuals and noise floors, fitting, the effect-ranking loop and the report.
//!   Domain-free: it knows no bond graph and no cloth.
//! - [`modelgap_bond`] (as [`bond`]): bond graphs — elements, causality, equations,
//!   simulation, causal graphs, fault trees, temporal signatures, diagnosis, model files and
//!   the candidate effects a bond-graph model offers ([`bond::BondModel`]).
//! - [`modelgap_cloth`] (as [`cloth`]): the impulse-based cloth solver, meshes, colliders,
//!   scenes, marker recordings and the cloth's candidate effects ([`cloth::ClothModel`]).
//!
//! Inside this crate:
//!
//! - [`load`]: [`load_model`] and [`load_recording`], the one place that knows the kinds of
//!   model (bond-graph files and built-ins, cloth scene files and built-ins).
//! - [`Model`]: the seam every kind implements (predict, candidates, with effects, and the
//!   [`Model::story`] its results read by); [`Candidate`], [`Effect`].
//! - [`compare()`], [`explain()`] and their options and results ([`Comparison`],
//!   [`Explanation`], [`Verdict`]); [`judge`]: what noise leaves, and when a recording cannot
//!   be judged; [`fit`]: bounded Levenberg–Marquardt; [`calibrate()`]: a model's own free
//!   parameters fitted before the loop.
//! - [`story`], [`json`], [`report`]: the results as text, JSON and the HTML report with its
//!   Foxglove MCAP.
//! - [`Recording`], [`Signal`], [`io`]: signals on one time axis, CSV and MCAP (Parquet read)
//!   ([`io::read_recording_path`], [`io::write_recording_path`] choose by extension;
//!   [`io::atomic`] writes every file atomically).
//! - [`residual`]: residual statistics, the noise floor, thresholds, failure windows.
//! - [`prelude`]: the names most programs need, in one `use`.
//! - [`Error`], [`Result`]: one error type over the workspace's crates.

pub use modelgap_bond as bond;
pub use modelgap_cloth as cloth;
pub use modelgap_core::residual::{FailureWindow, NoiseFloor, Residual, ResidualStats, Threshold};
pub use modelgap_core::{
    Calibration, CalibrationOptions, Candidate, CompareOptions, Comparison, CoreError, Effect,
    EffectKind, EffectParam, ExplainOptions, Explanation, Location, Model, OutputComparison,
    Prediction, Prior, RankedCandidate, Recording, Signal, Verdict, calibrate, compare, explain,
    fit, io, json, judge, math, noise, report, residual, story, timing,
};

pub use modelgap_bond::BondError;
pub use modelgap_cloth::ClothError;

pub mod load;
pub use load::{LoadOptions, load_model, load_recording};

/// Everything that can go wrong in modelgap, whichever crate it comes from.
///
/// Each variant wraps a crate's own error unchanged; its message is that error's message.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum Error {
    /// An error of `modelgap-core`: recordings and their files.
    #[error(transparent)]
    Core(#[from] CoreError),
    /// An error of `modelgap-bond`: models, causality, equations, simulation, diagnosis.
    #[error(transparent)]
    Bond(#[from] BondError),
    /// An error of `modelgap-cloth`: meshes, scenes, markers, the solver.
    #[error(transparent)]
    Cloth(#[from] ClothError),
    /// A request that does not fit: a model or recording that is not there, an option the
    /// model's kind does not take ([`load`]).
    #[error("{0}")]
    Input(String),
    /// A parameter (or input default) that could not be set as asked ([`LoadOptions::set`]).
    #[error("setting {name} = {value}")]
    Set {
        /// The parameter or input.
        name: String,
        /// The value asked for.
        value: f64,
        /// Why not (an unknown name, an unphysical or too large value).
        #[source]
        source: Box<BondError>,
    },
}

/// `Result` with [`Error`] as the error type.
pub type Result<T, E = Error> = std::result::Result<T, E>;

/// The names most programs need: `use modelgap::prelude::*;`.
///
/// # Example
///
/// ```
/// use modelgap::prelude::*;
///
/// let motor = library::dc_motor();
/// let ss = StateSpace::linearise(&motor, None, None)?;
/// assert_eq!(ss.states, ["p3", "p8"]);
/// # Ok::<(), modelgap::Error>(())
/// ```
pub mod prelude {
    pub use crate::bond::diagnosis::{Diagnosis, DiagnosisOptions, diagnose};
    pub use crate::bond::simulate::{
        Drive, Hold, Inputs, ParamChange, Run, SimOptions, Solver, simulate, time_grid,
    };
    pub use crate::bond::{
        BondGraph, Causality, Element, ElementKind, Equations, StateSpace, assign_causality,
        library,
    };
    pub use crate::io::{read_recording_path, write_recording_path};
    pub use crate::{Error, Recording, Result, Signal, Threshold};
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn errors_of_both_crates_convert_and_keep_their_message() {
        let core = CoreError::EmptyRecording { path: None };
        let text = core.to_string();
        assert_eq!(Error::from(core).to_string(), text);
        let bond = bond::library::builtin("no-such-motor").unwrap_err();
        let text = bond.to_string();
        let e: Error = bond.into();
        assert!(matches!(e, Error::Bond(_)));
        assert_eq!(e.to_string(), text);
    }
}
