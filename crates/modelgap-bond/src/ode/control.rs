//! What both steppers share: the step budget, the step-size floor,
//! finiteness checks and the initial step guess.

use super::{OdeError, OdeOptions, OdeStats, OdeSystem};

/// Fails with [`OdeError::TooManySteps`] when the step budget is spent.
pub(super) fn check_budget(stats: &OdeStats, opts: &OdeOptions, t: f64) -> Result<(), OdeError> {
    if stats.steps + stats.rejected >= opts.max_steps {
        Err(OdeError::TooManySteps {
            t,
            max_steps: opts.max_steps,
        })
    } else {
        Ok(())
    }
}

/// Fails when the proposed step `h` cannot advance `t` (DOPRI5's test
/// `0.1 |h| ≤ ε |t|`, plus an absolute floor for `t` near 0). When the
/// rejections that shrank the step were caused by non-finite trial values,
/// reports those instead ([`OdeError::NonFinite`]).
pub(super) fn check_step_size(t: f64, h: f64, nonfinite: Option<usize>) -> Result<(), OdeError> {
    if h > 10.0 * f64::EPSILON * t.abs() && h >= f64::MIN_POSITIVE {
        return Ok(());
    }
    Err(match nonfinite {
        Some(component) => OdeError::NonFinite { t, component },
        None => OdeError::StepSizeUnderflow { t, h },
    })
}

/// Index of the first non-finite value of `v`, if any.
#[inline]
pub(super) fn first_nonfinite(v: &[f64]) -> Option<usize> {
    // Summing first keeps the common all-finite case to one pass without branches.
    if v.iter().sum::<f64>().is_finite() {
        None
    } else {
        v.iter().position(|x| !x.is_finite())
    }
}

/// Hairer's initial step guess (HNW I, Sect. II.4, and `HINIT` in DOPRI5), with
/// root-mean-square norms weighted by `atol + rtol·|x_i|`.
///
/// `f0 = f(t_eval, x)`; `order` is the exponent of the local error estimate;
/// `h_max` bounds the result and the Euler probe, which is evaluated no later
/// than `t_probe_max` (so it never lands on a breakpoint). Costs one rhs call;
/// `x1` and `f1` are scratch of length `dim`.
#[allow(clippy::too_many_arguments)] // explicit scratch buffers, so nothing allocates
pub(super) fn initial_step(
    sys: &mut dyn OdeSystem,
    t_eval: f64,
    x: &[f64],
    f0: &[f64],
    order: i32,
    h_max: f64,
    t_probe_max: f64,
    opts: &OdeOptions,
    x1: &mut [f64],
    f1: &mut [f64],
    stats: &mut OdeStats,
) -> f64 {
    let n = x.len() as f64;
    let scale = |xi: f64| opts.atol + opts.rtol * xi.abs();
    let d0 = (x.iter().map(|&xi| (xi / scale(xi)).powi(2)).sum::<f64>() / n).sqrt();
    let d1 = (x
        .iter()
        .zip(f0)
        .map(|(&xi, &fi)| (fi / scale(xi)).powi(2))
        .sum::<f64>()
        / n)
        .sqrt();
    let mut h0 = if d0 <= 1e-5 || d1 <= 1e-5 {
        1e-6
    } else {
        0.01 * d0 / d1
    };
    h0 = h0.min(h_max);
    for ((y, &xi), &fi) in x1.iter_mut().zip(x).zip(f0) {
        *y = xi + h0 * fi;
    }
    sys.rhs((t_eval + h0).min(t_probe_max).max(t_eval), x1, f1);
    stats.rhs_evals += 1;
    let d2 = (x
        .iter()
        .zip(f0.iter().zip(f1.iter()))
        .map(|(&xi, (&a, &b))| ((b - a) / scale(xi)).powi(2))
        .sum::<f64>()
        / n)
        .sqrt()
        / h0;
    // f64::max ignores a NaN d2 (a probe that left the model's domain).
    let d12 = d2.max(d1);
    let h1 = if d12 <= 1e-15 {
        (h0 * 1e-3).max(1e-6)
    } else {
        (0.01 / d12).powf(1.0 / f64::from(order))
    };
    (100.0 * h0).min(h1).min(h_max)
}
