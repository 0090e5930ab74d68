//! The model's own error against what explain can see.
//!
//! A model whose prediction moves when its step is halved, its tolerance tightened or its
//! start nudged ([`Model::numerical_error`]: a cloth at too coarse a step or too loose a
//! tolerance, a scene that branches) cannot tell an effect of that size from its own
//! numerics — and explain sees effects far below the noise's RMS (over 58 000 samples a
//! systematic 0.3 σ is significant). Measured on a curtain swaying 0.2 m along its rail:
//! the paper's step at h = 0.01 s leaves 13 mm RMS against a run converged in the step —
//! and against such a recording explain named a skin friction for a hidden damping and
//! called a control "unexplained"; the gentle curtain of `examples/data/curtain.toml`, its
//! truth at the same step solved to 1e-6, got a skin friction on a control. The numerics'
//! cost `½ Σ (e/σ)²` is set against the chosen effect's gain, and said beside the verdict.

use crate::error::Result;
use crate::model::Model;
use crate::recording::Recording;
use crate::residual::rms;

/// How far the model's own prediction moves, in noise units.
#[derive(Clone, Debug, PartialEq)]
pub(super) struct OwnError {
    /// RMS over the outputs of each output's numerical error (RMS) over its noise σ.
    pub ratio: f64,
    /// The output whose numerical error is largest against its noise, and that ratio.
    pub worst: (String, f64),
    /// `½ Σ (e/σ)²` over every output and sample: the cost the numerics alone add, in the
    /// units of explain's costs and gains.
    pub cost: f64,
}

/// The model's own error on `rec` for the outputs `names` with noise `sigma` (one each);
/// `None` when the model's prediction is sharp (no numerical error) or no output is named.
///
/// # Errors
/// The model's, when it cannot simulate the recording.
pub(super) fn own_error(
    model: &dyn Model,
    rec: &Recording,
    names: &[String],
    sigma: &[f64],
) -> Result<Option<OwnError>> {
    let Some(error) = model.numerical_error(rec)? else {
        return Ok(None);
    };
    let mut sum = 0.0;
    let mut cost = 0.0;
    let mut counted = 0usize;
    let mut worst = (String::new(), 0.0_f64);
    for (name, &s) in names.iter().zip(sigma) {
        let Some(values) = error.get(name).filter(|_| s > 0.0 && s.is_finite()) else {
            continue;
        };
        let r = rms(values) / s;
        sum += r * r;
        cost += 0.5 * values.iter().map(|e| (e / s) * (e / s)).sum::<f64>();
        counted += 1;
        if r > worst.1 {
            worst = (name.clone(), r);
        }
    }
    if counted == 0 {
        return Ok(None);
    }
    Ok(Some(OwnError {
        ratio: (sum / counted as f64).sqrt(),
        worst,
        cost,
    }))
}

/// How many times what the model's numerics cost an effect's gain must be to stand clear
/// of them.
pub const OWN_ERROR_MARGIN: f64 = 3.0;

/// The warning to give about the model's own error `own`: when the effect chosen lowers the
/// cost by `gain`, less than [`OWN_ERROR_MARGIN`] times what the numerics cost (it may be
/// them), or when nothing is chosen and the numerics cost more than an effect needs to be
/// significant (`significance`). `None` otherwise. The verdict is not changed by it yet:
/// the project's own cloth recordings are simulated at the model's step (the model's
/// numerics are the truth's), and on them a verdict cut to the model's own error turned
/// every found effect into "partial".
pub(super) fn own_error_warning(
    own: &OwnError,
    gain: Option<f64>,
    significance: f64,
) -> Option<String> {
    let moved = format!(
        "the model's own numerics move its prediction by {:.2}× the noise (RMS over the \
         outputs; {:.2}× on `{}`; runs at half its step, at a 100 times tighter stretch \
         tolerance and with its start nudged by a micrometre), a cost of {:.4} in the units \
         of the scores",
        own.ratio, own.worst.1, own.worst.0, own.cost
    );
    let refine = "refine the model's numerics (a smaller dt or stretch tolerance; for a \
                  cloth, integrator = \"bdf2\" if it is not already)";
    match gain {
        Some(g) if g < OWN_ERROR_MARGIN * own.cost => Some(format!(
            "the effect chosen lowers the cost by {g:.4}, only {:.2}× what {moved}: it may be \
             the numerics, not physics; {refine}",
            g / own.cost.max(f64::MIN_POSITIVE)
        )),
        None if own.cost > significance => Some(format!(
            "{moved}: on a recording of the real system an effect that costs less cannot be \
             told from them; {refine}"
        )),
        _ => None,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn own(cost: f64) -> OwnError {
        OwnError {
            ratio: 0.5,
            worst: ("m3.x".into(), 1.5),
            cost,
        }
    }

    #[test]
    fn numerics_below_what_is_significant_are_not_warned_of() {
        assert_eq!(own_error_warning(&own(4.0), None, 10.0), None);
        assert_eq!(own_error_warning(&own(4.0), Some(100.0), 10.0), None);
    }

    #[test]
    fn numerics_an_effect_could_be_are_warned_of() {
        let w = own_error_warning(&own(200.0), None, 10.0).unwrap();
        assert!(
            w.contains("0.50× the noise") && w.contains("1.50× on `m3.x`"),
            "{w}"
        );
        assert!(w.contains("cannot be told") && w.contains("bdf2"), "{w}");
        let w = own_error_warning(&own(200.0), Some(300.0), 10.0).unwrap();
        assert!(
            w.contains("only 1.50× what") && w.contains("may be the numerics"),
            "{w}"
        );
        assert_eq!(own_error_warning(&own(200.0), Some(700.0), 10.0), None);
    }
}
