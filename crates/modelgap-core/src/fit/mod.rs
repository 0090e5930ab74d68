//! Least-squares fitting of a few parameters by simulation error: a bounded
//! Levenberg–Marquardt solver.
//!
//! A [`ResidualProblem`] writes one residual per sample (measured minus simulated) for a
//! parameter vector; [`fit`] minimises the cost ½Σr² inside box bounds and returns a
//! [`FitReport`] with the parameters, their standard errors and correlations, the cost
//! before and after, and why it stopped ([`Termination`]). A shared [`Cancel`] flag stops
//! it between evaluations.
//!
//! # Example
//!
//! ```
//! use modelgap_core::fit::{fit, FitOptions, ResidualProblem, Termination};
//!
//! /// y = a·e^(−b·t) sampled at t = 0, 0.1, …, 2 s.
//! struct Decay {
//!     t: Vec<f64>,
//!     y: Vec<f64>,
//! }
//!
//! impl ResidualProblem for Decay {
//!     fn n_params(&self) -> usize {
//!         2
//!     }
//!     fn n_residuals(&self) -> usize {
//!         self.t.len()
//!     }
//!     fn residuals(&self, p: &[f64], out: &mut [f64]) -> modelgap_core::Result<()> {
//!         for ((o, t), y) in out.iter_mut().zip(&self.t).zip(&self.y) {
//!             *o = y - p[0] * (-p[1] * t).exp();
//!         }
//!         Ok(())
//!     }
//! }
//!
//! let t: Vec<f64> = (0..21).map(|k| 0.1 * k as f64).collect();
//! let y = t.iter().map(|t| 2.0 * (-0.7 * t).exp()).collect();
//! let problem = Decay { t, y };
//! let opts = FitOptions { name: "decay".into(), ..FitOptions::default() };
//! let bounds = [(0.0, 10.0), (0.0, 5.0)];
//! let report = fit(&problem, &[1.0, 0.0], &bounds, &[1.0, 1.0], &opts, None)?;
//! assert_eq!(report.termination, Termination::Converged);
//! assert!((report.params[0] - 2.0).abs() < 1e-6 && (report.params[1] - 0.7).abs() < 1e-6);
//! # Ok::<(), modelgap_core::CoreError>(())
//! ```
//!
//! # Why a solver of our own
//!
//! The fits in modelgap are tiny (1–4 parameters against 4 000–20 000 residuals) and run
//! thousands of times in parallel inside `explain`, each residual evaluation being a
//! simulation. General crates such as `levenberg-marquardt` have no bounds and take
//! finite-difference steps relative to the parameter value; modelgap needs
//!
//! - box bounds (a friction torque is not negative, a fault time lies inside the record);
//! - absolute finite-difference steps scaled to each parameter's typical size: a start
//!   value of 0 is common, and a relative step there falls below the ODE solver's own
//!   error, so the Jacobian is noise and the fit stalls;
//! - cancellation from the CLI (Ctrl-C) or Python (`KeyboardInterrupt`);
//! - parameter uncertainty (standard errors, correlations) for the ranking;
//! - graceful handling of trial points where the simulation fails.
//!
//! With at most a handful of parameters the normal equations are a few numbers; nalgebra
//! solves them.
//!
//! # Method
//!
//! - **Scaling.** The solver works in scaled variables z = x / scale (Marquardt scaling by
//!   the caller's `scales`), so the damping term μ‖Δz‖² treats all parameters alike and
//!   the step tolerance `xtol` reads in units of each parameter's scale.
//! - **Jacobian.** Forward differences with absolute steps: `FitOptions::fd_steps`, by
//!   default 10⁻⁴ × scale: about the square root of the simulations' relative error (their
//!   adaptive solvers run at rtol 10⁻⁸), the step that balances truncation against the
//!   solver's noise. At 10⁻⁶ a weak term (a cubic spring b·q³ beside a·q on the Silverbox)
//!   changed the output by less than the solver's error, its column was noise, and a fit
//!   left b where it started. Near the upper bound the step flips to a backward difference;
//!   if the residuals fail at the difference point the other side is tried, and a column
//!   that cannot be formed is zero (the parameter does not move in that iteration).
//!   Evaluations run serially: callers parallelise across fits.
//! - **Step.** (JᵀJ + μI)Δz = −Jᵀr over the free parameters, by Cholesky with LU and SVD
//!   as fallbacks. Bounds by projection: a parameter at a bound whose gradient pushes
//!   outward is frozen for the step, and each trial point is clamped into the box.
//! - **Acceptance and damping.** The gain ratio ρ = actual / predicted reduction of the
//!   cost (the prediction from the linear model of the clamped step); a step is taken when
//!   the cost falls, and μ follows Nielsen's update: μ·max(⅓, 1 − (2ρ − 1)³) after a
//!   success, μ·ν with ν doubling after each failure. A trial point whose residuals are
//!   an error or not finite is a failed step (more damping): no NaN leaves the solver.
//! - **Stopping.** See [`Termination`] and the tolerances of [`FitOptions`].
//!
//! References: K. Madsen, H. B. Nielsen, O. Tingleff, *Methods for non-linear least
//! squares problems*, IMM DTU, 2004 (the damping update, §3.2); J. J. Moré, *The
//! Levenberg–Marquardt algorithm: implementation and theory*, 1978 (the stopping tests).
//!
//! # Uncertainty
//!
//! Standard errors are sqrt(diag((JᵀJ)⁻¹) · s²) with s² = 2·cost / (m − n) at the solution
//! (m residuals, n parameters not pinned at a bound). They assume white residuals; for
//! correlated noise rescale by an effective sample size with
//! [`FitReport::scaled_std_errors`]. A parameter that the data do not determine (pinned at
//! a bound, a zero Jacobian column, a direction of JᵀJ that is numerically singular) gets
//! a standard error of `f64::INFINITY`; see [`FitReport`].

mod levmar;
mod problem;
mod report;

pub use levmar::{DEFAULT_FD_STEP, FitOptions, fit};
pub use problem::{Cancel, ResidualProblem};
pub use report::{FitReport, Termination};

/// A finite-difference step of about `h` (positive) from `x` that stays within
/// `[lo, hi]`: forward, backward near the upper bound, and the wider side when the
/// box is narrower than the step (a shape a scan pinned, bounded to its grid's
/// spacing); 0 when the box leaves no room.
pub(crate) fn step_in_box(x: f64, h: f64, lo: f64, hi: f64) -> f64 {
    if x + h <= hi {
        h
    } else if x - h >= lo {
        -h
    } else if hi - x >= x - lo {
        (hi - x).max(0.0)
    } else {
        (lo - x).min(0.0)
    }
}
