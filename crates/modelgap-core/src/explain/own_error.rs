//! The model's own error against the noise.
//!
//! A model whose prediction moves by more than the noise when its step is halved or its
//! start is nudged ([`Model::prediction_spread`]: a cloth at too coarse a step, a scene that
//! branches) cannot tell an effect of that size from its own numerics. Measured on a
//! curtain swaying 0.2 m along its rail: the paper's step at h = 0.01 s leaves 13 mm RMS
//! against a run converged in the step, 13 times the markers' noise — and against such a
//! recording explain named a skin friction for a hidden damping and called a control
//! "unexplained". Explain says so beside its verdict.

use crate::error::Result;
use crate::model::Model;
use crate::recording::Recording;
use crate::residual::rms;

/// How far the model's own prediction moves, in noise units.
#[derive(Clone, Debug, PartialEq)]
pub(super) struct OwnError {
    /// RMS over the outputs of the spread's RMS over each output's noise σ.
    pub ratio: f64,
    /// The output whose spread is largest against its noise, and that ratio.
    pub worst: (String, f64),
}

/// The model's own error on `rec` for the outputs `names` with noise `sigma` (one each);
/// `None` when the model's prediction is sharp (it has no spread) or no output is named.
///
/// # Errors
/// The model's, when it cannot simulate the recording.
pub(super) fn own_error(
    model: &dyn Model,
    rec: &Recording,
    names: &[String],
    sigma: &[f64],
) -> Result<Option<OwnError>> {
    let Some(spread) = model.prediction_spread(rec)? else {
        return Ok(None);
    };
    let mut sum = 0.0;
    let mut counted = 0usize;
    let mut worst = (String::new(), 0.0_f64);
    for (name, &s) in names.iter().zip(sigma) {
        let Some(values) = spread.get(name).filter(|_| s > 0.0 && s.is_finite()) else {
            continue;
        };
        let r = rms(values) / s;
        sum += r * r;
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
    }))
}

/// The warning to give when the model's own error `own` is above the noise (`None`
/// within it). The verdict is not changed by it yet: the project's own cloth recordings
/// are simulated at the model's step (the model's numerics are the truth's), and on them
/// a verdict cut to the model's own error turned every found effect into "partial".
pub(super) fn own_error_warning(own: &OwnError) -> Option<String> {
    (own.ratio > 1.0).then(|| {
        format!(
            "the model's own prediction moves by {:.1}× the noise (RMS over the outputs; \
             {:.1}× on `{}`) between its run and runs at half its step or with its start \
             nudged by a micrometre: on a recording of the real system an effect of that size \
             cannot be told from the model's numerics, and fitted values may carry them; \
             refine the model's step (a smaller dt or stretch tolerance, or for a cloth \
             integrator = \"bdf2\")",
            own.ratio, own.worst.1, own.worst.0
        )
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn own(ratio: f64) -> OwnError {
        OwnError {
            ratio,
            worst: ("m3.x".into(), 2.0 * ratio),
        }
    }

    #[test]
    fn a_model_within_the_noise_is_not_warned_and_one_above_it_is() {
        assert_eq!(own_error_warning(&own(0.8)), None);
        let w = own_error_warning(&own(4.0)).unwrap();
        assert!(
            w.contains("4.0× the noise") && w.contains("8.0× on `m3.x`") && w.contains("bdf2"),
            "{w}"
        );
    }
}
