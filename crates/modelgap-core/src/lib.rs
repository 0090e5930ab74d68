//! The domain-free core of modelgap: recordings, their CSV, MCAP and Parquet files, the
//! statistics that hold a model's prediction against a measurement, and the
//! measurement loop itself — [`compare()`] a [`Model`] with a recording,
//! [`explain()`] which [`Candidate`] effect it is missing, and tell the story
//! ([`story`], [`report`]).
//!
//! A [`Recording`] is a set of named signals on one strictly increasing time axis, checked
//! when it is built or read (finite values, one value per sample, unique names). The
//! [`io`] module reads and writes recordings as CSV text or MCAP files (JSON messages that
//! Foxglove plots as is), and reads Parquet files as pandas and Polars write them. The [`residual`] module measures how far a prediction is from a
//! measurement: error statistics, the measurement's noise floor, thresholds, the windows
//! where the residual leaves its band, and derivative estimates for temporal signatures.
//! Both simulators of modelgap (bond graphs, cloth) build on these.
//!
//! # Example
//!
//! ```
//! use modelgap_core::io::csv;
//! use modelgap_core::residual::{failure_windows, stats, Threshold};
//!
//! let text = "t,i\n0.0,0.0\n0.1,0.63\n0.2,0.86\n0.3,0.95\n0.4,0.98\n";
//! let measured = csv::read_signals(text.as_bytes())?;
//! let i = measured.values("i")?;
//! let predicted: Vec<f64> = measured.t().iter().map(|t| 1.0 - (-t / 0.1_f64).exp()).collect();
//!
//! let s = stats(i, &predicted);
//! let band = Threshold::FractionOfSteadyState { fraction: 0.02 }.band(i);
//! let residual: Vec<f64> = i.iter().zip(&predicted).map(|(m, p)| m - p).collect();
//! let windows = failure_windows(measured.t(), &residual, band, 0.0);
//! assert!(s.rms < 0.01 && windows.is_empty());
//! # Ok::<(), modelgap_core::CoreError>(())
//! ```
//!
//! # Modules
//!
//! - [`model`]: the [`Model`] trait, the seam every simulator implements, and [`Prediction`].
//! - [`effect`]: [`Candidate`] effects with their [`EffectParam`]s, and fitted [`Effect`]s.
//! - [`compare`](mod@compare): residuals, noise floors and failure windows per output.
//! - [`explain`](mod@explain): the effect-ranking loop — every candidate fitted in
//!   parallel, ranked by evidence with a noise-robust effective sample size, the verdict
//!   ("nothing is missing", one or two effects, or a partial explanation).
//! - [`story`]: the loop's results as text and as the HTML report.
//! - [`recording`]: [`Recording`] and [`Signal`].
//! - [`io`]: [`io::csv`] and [`io::mcap`] readers and writers, the [`io::parquet`] reader,
//!   and [`io::read_recording_path`] / [`io::write_recording_path`], which choose by
//!   extension.
//! - [`residual`]: [`residual::stats`], [`residual::estimate_noise_sigma`],
//!   [`residual::effective_sample_size`], [`residual::Threshold`],
//!   [`residual::failure_windows`], [`residual::first_exceedance`],
//!   [`residual::savgol_derivatives`].
//! - [`fit`]: [`fit::fit`], bounded Levenberg–Marquardt for a [`fit::ResidualProblem`],
//!   with [`fit::FitOptions`], [`fit::FitReport`] and a [`fit::Cancel`] flag.
//! - [`report`]: the HTML report page with SVG plots, and the comparison MCAP for Foxglove.
//! - [`noise`]: a seeded Gaussian generator for recordings made in tests and examples.
//! - [`math`]: the nalgebra aliases used across modelgap.
//! - [`error`]: [`CoreError`] and [`Result`].

pub mod calibrate;
pub mod compare;
pub mod effect;
pub mod error;
pub mod explain;
pub mod fit;
pub mod io;
pub mod json;
pub mod judge;
pub mod math;
pub mod model;
pub mod noise;
pub mod recording;
pub mod report;
pub mod residual;
pub mod story;
pub mod timing;

pub use calibrate::{Calibration, CalibrationOptions, FittedValue, calibrate};
pub use compare::{CompareOptions, Comparison, OutputComparison, compare};
pub use effect::{Candidate, Effect, EffectKind, EffectParam, Prior};
pub use error::{CoreError, Location, Result};
pub use explain::{ExplainOptions, Explanation, RankedCandidate, Verdict, explain};
pub use model::{Model, Prediction, QualitativeCheck};
pub use recording::{Recording, Signal};
