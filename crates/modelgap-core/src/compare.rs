//! compare: a model's prediction held against a recording — residuals,
//! their statistics, the noise floor and the windows where the model fails.

use std::collections::BTreeMap;

use serde::Serialize;

use crate::error::{CoreError, Result};
use crate::model::{Model, Prediction};
use crate::recording::Recording;
use crate::residual::{
    FailureWindow, ResidualStats, effective_sample_size, estimate_noise_sigma, failure_windows,
    stats,
};

/// Options of [`compare`].
#[derive(Clone, Debug, PartialEq)]
pub struct CompareOptions {
    /// Noise standard deviation per output, when the user knows it; else
    /// estimated from the measurement's high-frequency part.
    pub noise: BTreeMap<String, f64>,
    /// Half-width of the band a residual must leave to count as model
    /// failure, in noise standard deviations. Default 4.
    pub band_sigmas: f64,
    /// Or the paper's band: this fraction of the output's steady state
    /// (mean of the last 10 %), when set. Default `None`.
    pub band_fraction: Option<f64>,
    /// Shortest failure window (s); shorter excursions and gaps are merged
    /// or dropped. Default: 5 sample periods.
    pub min_window: Option<f64>,
}

impl Default for CompareOptions {
    fn default() -> CompareOptions {
        CompareOptions {
            noise: BTreeMap::new(),
            band_sigmas: 4.0,
            band_fraction: None,
            min_window: None,
        }
    }
}

/// One measured output held against its prediction.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct OutputComparison {
    /// Output name.
    pub name: String,
    /// Its unit.
    pub unit: String,
    /// The measurement.
    pub measured: Vec<f64>,
    /// The model's prediction.
    pub predicted: Vec<f64>,
    /// measured − predicted.
    pub residual: Vec<f64>,
    /// RMS, normalised RMS, largest error.
    pub stats: ResidualStats,
    /// The noise floor: the RMS a perfect model would leave (noise σ).
    pub noise_floor: f64,
    /// True when the floor was given by the user, false when estimated.
    pub noise_given: bool,
    /// The band the residual must leave to count as failure.
    pub band: f64,
    /// Where the residual leaves its band.
    pub windows: Vec<FailureWindow>,
    /// Effective number of independent samples of the residual.
    pub effective_samples: f64,
}

impl OutputComparison {
    /// RMS over noise floor: about 1 for a right model.
    pub fn rms_over_floor(&self) -> f64 {
        if self.noise_floor > 0.0 {
            self.stats.rms / self.noise_floor
        } else {
            f64::INFINITY
        }
    }
}

/// The result of [`compare`].
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Comparison {
    /// Model name.
    pub model: String,
    /// Sample times (s).
    pub t: Vec<f64>,
    /// One entry per output the model predicts and the recording measures.
    pub outputs: Vec<OutputComparison>,
}

impl Comparison {
    /// The comparison of one output.
    pub fn output(&self, name: &str) -> Option<&OutputComparison> {
        self.outputs.iter().find(|o| o.name == name)
    }
}

/// The noise floor of a measurement: given by the user, or estimated from
/// its high-frequency part (what no smooth model can follow). Never 0: a
/// noise-free signal gets a floor of 1e-9 of its RMS (so weights stay finite).
pub fn noise_floor(name: &str, measured: &[f64], given: &BTreeMap<String, f64>) -> (f64, bool) {
    if let Some(&s) = given.get(name) {
        return (s, true);
    }
    let sigma = estimate_noise_sigma(measured);
    let size = crate::residual::rms(measured);
    (sigma.max(1e-9 * size).max(f64::MIN_POSITIVE), false)
}

/// The outputs a prediction and a recording share, in the model's order.
pub fn shared_outputs(model: &dyn Model, rec: &Recording) -> Result<Vec<String>> {
    let shared: Vec<String> = model
        .outputs()
        .into_iter()
        .filter(|n| rec.signal(n).is_some())
        .collect();
    if shared.is_empty() {
        return Err(CoreError::InvalidArgument {
            name: "recording",
            reason: format!(
                "it measures none of the model's outputs ({}); it has {}",
                model.outputs().join(", "),
                rec.names().join(", ")
            ),
        });
    }
    Ok(shared)
}

/// Compares a prediction with a recording, output by output.
///
/// # Errors
/// [`CoreError::InvalidArgument`] for a bad option or no shared output;
/// [`CoreError::LengthMismatch`] if the prediction has the wrong length.
pub fn compare_prediction(
    model: &dyn Model,
    rec: &Recording,
    prediction: &Prediction,
    opts: &CompareOptions,
) -> Result<Comparison> {
    if !(opts.band_sigmas.is_finite() && opts.band_sigmas > 0.0) {
        return Err(CoreError::InvalidArgument {
            name: "band_sigmas",
            reason: format!("must be positive, found {}", opts.band_sigmas),
        });
    }
    let t = rec.t();
    let dt = if t.len() > 1 {
        (t[t.len() - 1] - t[0]) / (t.len() - 1) as f64
    } else {
        0.0
    };
    let min_window = opts.min_window.unwrap_or(5.0 * dt);
    let mut outputs = Vec::new();
    for name in shared_outputs(model, rec)? {
        let measured = rec.values(&name)?.to_vec();
        let predicted = prediction
            .get(&name)
            .ok_or_else(|| CoreError::Model {
                message: format!("the model did not predict output '{name}'"),
            })?
            .to_vec();
        if predicted.len() != measured.len() {
            return Err(CoreError::LengthMismatch {
                name,
                expected: measured.len(),
                found: predicted.len(),
            });
        }
        let residual: Vec<f64> = measured
            .iter()
            .zip(&predicted)
            .map(|(m, p)| m - p)
            .collect();
        let (floor, given) = noise_floor(&name, &measured, &opts.noise);
        let band = match opts.band_fraction {
            Some(f) => f * crate::residual::steady_state(&predicted).abs(),
            None => opts.band_sigmas * floor,
        };
        let windows = failure_windows(t, &residual, band, min_window);
        outputs.push(OutputComparison {
            unit: model.unit(&name),
            stats: stats(&measured, &predicted),
            effective_samples: effective_sample_size(&residual),
            name,
            measured,
            predicted,
            residual,
            noise_floor: floor,
            noise_given: given,
            band,
            windows,
        });
    }
    Ok(Comparison {
        model: model.name(),
        t: t.to_vec(),
        outputs,
    })
}

/// Simulates the model on the recording and compares.
///
/// # Errors
/// The model's prediction errors, and those of [`compare_prediction`].
pub fn compare(model: &dyn Model, rec: &Recording, opts: &CompareOptions) -> Result<Comparison> {
    let prediction = model.predict(rec)?;
    compare_prediction(model, rec, &prediction, opts)
}
