//! What a fit minimises ([`ResidualProblem`]) and how it is stopped ([`Cancel`]).

use std::sync::atomic::{AtomicBool, Ordering};

/// A least-squares problem: parameters in, one residual per sample out.
///
/// The fit minimises ½Σr². Implementations are typically "simulate the model with these
/// effect parameters, subtract from the measurement"; they are `Sync` so that many fits can
/// run in parallel over shared data.
pub trait ResidualProblem: Sync {
    /// The number of parameters (the length of `params` in [`Self::residuals`]).
    fn n_params(&self) -> usize;

    /// The number of residuals (the length of `out` in [`Self::residuals`]).
    fn n_residuals(&self) -> usize;

    /// Writes one residual per sample into `out` (len n_residuals); allocates nothing of its
    /// own if it can.
    ///
    /// # Errors
    /// Whatever stops the evaluation (a model that cannot simulate these parameters). At
    /// the start point the error ends the fit; at a trial point it only rejects the step.
    fn residuals(&self, params: &[f64], out: &mut [f64]) -> crate::Result<()>;

    /// The residuals are time series of this many samples, one after the other (one per
    /// output), and any rows after the last whole series are independent (priors): the
    /// robust standard errors ([`crate::fit::FitReport::robust_std_errors`]) sum the
    /// score's correlation over time within this layout. `None` (the default): all rows
    /// are one series in time order.
    fn series_length(&self) -> Option<usize> {
        None
    }
}

/// A shared flag that stops long loops (Ctrl-C, a Python KeyboardInterrupt).
///
/// One flag can be shared by many fits (`&Cancel` is `Sync`); once set it stays set.
#[derive(Debug, Default)]
pub struct Cancel(AtomicBool);

impl Cancel {
    /// A flag that is not set.
    pub fn new() -> Self {
        Self(AtomicBool::new(false))
    }

    /// Sets the flag: loops that watch it stop at their next check.
    pub fn cancel(&self) {
        self.0.store(true, Ordering::Relaxed);
    }

    /// Whether the flag is set.
    pub fn is_cancelled(&self) -> bool {
        self.0.load(Ordering::Relaxed)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cancel_starts_clear_and_stays_set() {
        let c = Cancel::new();
        assert!(!c.is_cancelled());
        c.cancel();
        assert!(c.is_cancelled());
        c.cancel();
        assert!(c.is_cancelled());
        assert!(!Cancel::default().is_cancelled());
    }
}
