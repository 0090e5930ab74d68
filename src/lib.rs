//! modelgap holds physical models against measurements and shows where they fail.
//!
//! It builds and diagnoses models of physical systems as **bond graphs** (elements, causality,
//! equations in the notation of the literature, simulation, causal graphs, fault trees and
//! temporal signatures), reads and writes **measurements** as CSV or MCAP recordings, and
//! compares the two. A cloth simulator and the loop that names the physical effect a model
//! is missing are on their way; see the README.
//!
//! This crate is the facade: it re-exports the workspace's crates under one name and ships
//! the `modelgap` command-line tool.
//!
//! # Example
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
//! The same with a recording on disk: [`io::write_recording_path`] stores a run (from
//! [`bond::simulate::Run::to_recording`]) as CSV or MCAP, and
//! [`bond::diagnosis::diagnose`] diagnoses a recording against a model.
//!
//! # Map
//!
//! - [`Recording`], [`Signal`]: measured or simulated signals on one time axis.
//! - [`io`]: CSV and MCAP readers and writers ([`io::read_recording_path`],
//!   [`io::write_recording_path`] choose by extension).
//! - [`residual`]: residual statistics, the noise floor, thresholds, failure windows.
//! - [`bond`]: the bond-graph crate (`modelgap-bond`): [`bond::BondGraph`], model files,
//!   [`bond::library`], causality, equations, simulation and diagnosis.
//! - [`prelude`]: the names most programs need, in one `use`.
//! - [`Error`], [`Result`]: one error type over the workspace's crates.

pub use modelgap_bond as bond;
pub use modelgap_cloth as cloth;
pub use modelgap_core::residual::{FailureWindow, NoiseFloor, Residual, ResidualStats, Threshold};
pub use modelgap_core::{
    Candidate, CompareOptions, Comparison, CoreError, Effect, EffectKind, EffectParam,
    ExplainOptions, Explanation, Location, Model, OutputComparison, Prediction, RankedCandidate,
    Recording, Signal, Verdict, compare, explain, fit, io, judge, math, noise, report, residual,
    story,
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
