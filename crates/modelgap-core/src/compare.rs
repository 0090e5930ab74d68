//! compare: a model's prediction held against a recording — residuals,
//! their statistics, the noise floor and the windows where the model fails.

use std::collections::BTreeMap;

use serde::Serialize;

use crate::error::{CoreError, Result};
use crate::judge::recording_findings;
use crate::model::{Model, Prediction};
use crate::recording::Recording;
use crate::residual::{
    FailureWindow, ResidualStats, effective_sample_size, failure_windows, quantisation_step, stats,
    third_difference_stats,
};

/// Fewest samples from which a noise floor is estimated (third differences
/// need four; a median of them a few more).
pub const MIN_FLOOR_SAMPLES: usize = 8;

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
    /// Whether [`compare`] asks the model for its predictability band
    /// ([`Model::prediction_spread`]) and widens the failure band by it.
    /// Default true.
    pub predictability: bool,
}

impl Default for CompareOptions {
    fn default() -> CompareOptions {
        CompareOptions {
            noise: BTreeMap::new(),
            band_sigmas: 4.0,
            band_fraction: None,
            min_window: None,
            predictability: true,
        }
    }
}

/// One measured output held against its prediction.
#[derive(Clone, Debug, PartialEq, Serialize, serde::Deserialize)]
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
    /// How the floor was found and how far it can be trusted.
    #[serde(default)]
    pub noise_method: FloorKind,
    /// The measurement's quantisation step, when it lies on a lattice (its
    /// rounding error is part of the floor).
    #[serde(default)]
    pub quantum: Option<f64>,
    /// The band the residual must leave to count as failure (the noise
    /// band; with a predictability band, sample k's band is this plus the
    /// model's spread at k, see [`compare_prediction_with_spread`]).
    pub band: f64,
    /// Where the residual leaves its band.
    pub windows: Vec<FailureWindow>,
    /// Effective number of independent samples of the residual.
    pub effective_samples: f64,
    /// Why this output cannot be judged, when it cannot (it reads a
    /// constant throughout: its floor and its ratio to it mean nothing).
    #[serde(default)]
    pub finding: Option<String>,
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
#[derive(Clone, Debug, PartialEq, Serialize, serde::Deserialize)]
pub struct Comparison {
    /// Model name.
    pub model: String,
    /// Sample times (s).
    pub t: Vec<f64>,
    /// One entry per output the model predicts and the recording measures.
    pub outputs: Vec<OutputComparison>,
    /// What keeps the recording, or an output of it, from being judged
    /// ([`crate::judge::recording_findings`]): too few samples, a dead
    /// sensor, a time base that hides the model's time constants.
    #[serde(default)]
    pub warnings: Vec<String>,
}

impl Comparison {
    /// The comparison of one output.
    pub fn output(&self, name: &str) -> Option<&OutputComparison> {
        self.outputs.iter().find(|o| o.name == name)
    }
}

/// How a noise floor was found, and how far it can be trusted.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, serde::Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum FloorKind {
    /// Given by the user (`--noise NAME=SIGMA`).
    Given,
    /// From the measurement's third differences, which are white noise:
    /// what no smooth model can follow.
    White,
    /// The measurement is quantised and its rounding (`step/√12`) is most of
    /// the floor.
    Quantised,
    /// From third differences that are not white but correlated: correlated
    /// noise or a filtered signal, which shows only its fastest part there.
    /// The floor is likely too low.
    Coloured,
    /// From third differences the signal's own fast content leaks into (an
    /// oversampled resonance, a fast smooth signal): the floor is likely too
    /// high, and "at the floor" is not evidence.
    SignalContent,
    /// From the output's power where the inputs are quiet
    /// ([`quiet_band_noise`](crate::residual::quiet_band_noise)): the band
    /// above the inputs' bandwidth, where a model driven by them puts no power.
    /// Taken where the third differences carry the signal
    /// ([`FloorKind::SignalContent`]) and this is lower.
    QuietBand,
    /// From discovery's smoother (explain only): the white measurement noise
    /// that the model with a free effort at the place that explains most finds
    /// likeliest — what a model lacking nothing else would still leave. Taken
    /// where the third differences carry the signal ([`FloorKind::SignalContent`]).
    Smoother,
    /// Estimated, but the record is too short or too flat to check.
    #[default]
    Unchecked,
}

/// Above this lag-1 autocorrelation of the third differences, the signal
/// itself leaks into them ([`third_difference_whiteness`](crate::residual::third_difference_whiteness); white noise gives
/// −0.75, correlated noise about −0.68 to −0.6).
const SIGNAL_CONTENT_WHITENESS: f64 = -0.45;

/// The standard deviation of the lag-1 autocorrelation of white noise's third
/// differences over `n` samples is about `WHITENESS_SPREAD / √n` (measured
/// over 300 seeds at n = 200 … 4000).
const WHITENESS_SPREAD: f64 = 0.46;

/// A measurement's noise floor and how it was found.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Floor {
    /// The floor: the RMS a perfect model would leave (σ), in the output's unit.
    pub sigma: f64,
    /// Whether the user gave it.
    pub given: bool,
    /// The quantisation step of the measurement, when it is quantised
    /// ([`quantisation_step`]).
    pub quantum: Option<f64>,
    /// How it was found and how far it can be trusted.
    pub kind: FloorKind,
    /// The lag-1 autocorrelation of the measurement's third differences
    /// ([`third_difference_whiteness`](crate::residual::third_difference_whiteness)), when it could be read.
    pub whiteness: Option<f64>,
}

impl Floor {
    /// A plain-words warning when the floor of output `name` cannot be
    /// trusted (correlated noise, the signal's own fast content) or was read
    /// where the inputs are quiet; `None` for a floor given, white, quantised
    /// or from the smoother (explain says how it found that one).
    pub fn warning(&self, name: &str, unit: &str) -> Option<String> {
        let w = self.whiteness.unwrap_or(f64::NAN);
        let sigma = match unit.trim() {
            "" | "1" => format!("{:.3e}", self.sigma),
            u => format!("{:.3e} {u}", self.sigma),
        };
        let why = match self.kind {
            FloorKind::Coloured => format!(
                "are not white (lag-1 correlation {w:.2}; white noise gives -0.75): the noise is \
                 correlated or the signal filtered, which shows only its fastest part there, so \
                 the floor is likely too low and the residual may never reach it"
            ),
            FloorKind::SignalContent => format!(
                "carry the signal itself (lag-1 correlation {w:.2}; white noise gives -0.75): an \
                 oversampled resonance or a fast smooth signal leaks into them, so the floor is \
                 likely too high and reaching it is not evidence that nothing is missing"
            ),
            FloorKind::QuietBand => {
                return Some(format!(
                    "the noise floor of `{name}` ({sigma}) is read from its power above the \
                     inputs' bandwidth, where a model driven by them puts none: its third \
                     differences carry the signal itself (an oversampled resonance); give the \
                     sensor's noise with --noise {name}=SIGMA if you know it"
                ));
            }
            _ => return None,
        };
        Some(format!(
            "the noise floor of `{name}` ({sigma}) is estimated from third differences that \
             {why}; give the sensor's noise with --noise {name}=SIGMA"
        ))
    }
}

/// The noise floor of a measurement: given by the user, or estimated from
/// its high-frequency part (what no smooth model can follow) and, for a
/// quantised signal ([`quantisation_step`]), its rounding error `step/√12`
/// added in quadrature. Never 0: a noise-free signal gets a floor of 1e-9
/// of its RMS (so weights stay finite). Its [`FloorKind`] says whether the
/// third differences it comes from are white noise
/// ([`third_difference_whiteness`](crate::residual::third_difference_whiteness)).
pub fn noise_floor(name: &str, measured: &[f64], given: &BTreeMap<String, f64>) -> Floor {
    let quantum = quantisation_step(measured);
    let (sigma, whiteness) = third_difference_stats(measured);
    if let Some(&sigma) = given.get(name) {
        return Floor {
            sigma,
            given: true,
            quantum,
            kind: FloorKind::Given,
            whiteness,
        };
    }
    let rounding = quantum.map_or(0.0, |q| q / 12f64.sqrt());
    let size = crate::residual::rms(measured);
    let white_limit = -0.75 + 4.0 * WHITENESS_SPREAD / (measured.len().max(1) as f64).sqrt();
    let kind = if rounding > 0.0 && rounding >= sigma {
        FloorKind::Quantised
    } else {
        match whiteness {
            None => FloorKind::Unchecked,
            Some(w) if w <= white_limit => FloorKind::White,
            Some(w) if w <= SIGNAL_CONTENT_WHITENESS => FloorKind::Coloured,
            Some(_) => FloorKind::SignalContent,
        }
    };
    Floor {
        sigma: sigma
            .hypot(rounding)
            .max(1e-9 * size)
            .max(f64::MIN_POSITIVE),
        given: false,
        quantum,
        kind,
        whiteness,
    }
}

/// [`noise_floor`], and where the third differences carry the signal
/// ([`FloorKind::SignalContent`]) the output's power where the recorded
/// `inputs` are quiet instead, when it is lower ([`FloorKind::QuietBand`]):
/// the band above the inputs' bandwidth holds only noise.
pub fn noise_floor_beside(
    name: &str,
    measured: &[f64],
    inputs: &[&[f64]],
    given: &BTreeMap<String, f64>,
) -> Floor {
    let floor = noise_floor(name, measured, given);
    if floor.kind != FloorKind::SignalContent {
        return floor;
    }
    match crate::residual::quiet_band_noise(measured, inputs) {
        Some(quiet) if quiet < floor.sigma => {
            let rounding = floor.quantum.map_or(0.0, |q| q / 12f64.sqrt());
            let size = crate::residual::rms(measured);
            Floor {
                sigma: quiet
                    .hypot(rounding)
                    .max(1e-9 * size)
                    .max(f64::MIN_POSITIVE),
                kind: FloorKind::QuietBand,
                ..floor
            }
        }
        _ => floor,
    }
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
    compare_prediction_with_spread(model, rec, prediction, None, opts)
}

/// Compares a prediction with a recording, counting as model failure only
/// what lies beyond both the noise band and the model's own predictability
/// band `spread` ([`Model::prediction_spread`]).
///
/// The two bands add: at sample k the residual fails when
/// `|r_k| > band + spread_k`, with `band` the noise band of
/// [`CompareOptions`] (`band_sigmas` × noise floor, or the paper's fraction).
/// Measurement noise and the model's own uncertainty are independent
/// sources of a right model's residual, and either alone can reach its
/// bound; a linear sum never blames a right model for their coincidence
/// (a root sum of squares would, by up to 30 %). Outputs the spread does not
/// name keep the noise band alone. A window's peak is the residual's own.
///
/// # Errors
/// As [`compare_prediction`]; [`CoreError::LengthMismatch`] if a spread
/// series has the wrong length.
pub fn compare_prediction_with_spread(
    model: &dyn Model,
    rec: &Recording,
    prediction: &Prediction,
    spread: Option<&Prediction>,
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
    let names = shared_outputs(model, rec)?;
    if t.len() < MIN_FLOOR_SAMPLES
        && let Some(name) = names.iter().find(|n| !opts.noise.contains_key(*n))
    {
        return Err(CoreError::InvalidArgument {
            name: "recording",
            reason: format!(
                "it has {} sample{}: at least {MIN_FLOOR_SAMPLES} are needed to estimate the noise \
                 floor of `{name}`; give the floor of every output (--noise NAME=SIGMA)",
                t.len(),
                if t.len() == 1 { "" } else { "s" }
            ),
        });
    }
    let measured_all: Vec<(&str, &[f64])> = names
        .iter()
        .map(|n| Ok((n.as_str(), rec.values(n)?)))
        .collect::<Result<_>>()?;
    let findings = recording_findings(t, &measured_all, &model.time_constants(rec));
    let mut outputs = Vec::new();
    let mut floor_warnings = Vec::new();
    let input_names = model.inputs();
    let inputs: Vec<&[f64]> = (input_names.iter())
        .filter_map(|n| rec.signal(n).map(|s| s.values.as_slice()))
        .collect();
    for name in names {
        let measured = rec.values(&name)?.to_vec();
        let predicted = prediction
            .get(&name)
            .ok_or_else(|| CoreError::model(format!("the model did not predict output '{name}'")))?
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
        let found = noise_floor_beside(&name, &measured, &inputs, &opts.noise);
        let Floor {
            sigma: floor,
            given,
            quantum,
            kind: noise_method,
            ..
        } = found;
        let unit = model.unit(&name);
        if let Some(w) = found.warning(&name, &unit) {
            floor_warnings.push(w);
        }
        let band = match opts.band_fraction {
            Some(f) => f * crate::residual::steady_state(&predicted).abs(),
            None => opts.band_sigmas * floor,
        };
        if let Some(w) = start_offset(&name, &unit, &residual, band) {
            floor_warnings.push(w);
        }
        let windows = match spread.and_then(|s| s.get(&name)) {
            Some(s) if s.len() != residual.len() => {
                return Err(CoreError::LengthMismatch {
                    name: format!("spread of {name}"),
                    expected: residual.len(),
                    found: s.len(),
                });
            }
            Some(s) => windows_beyond_spread(t, &residual, s, band, min_window),
            None => failure_windows(t, &residual, band, min_window),
        };
        outputs.push(OutputComparison {
            unit,
            stats: stats(&measured, &predicted),
            effective_samples: effective_sample_size(&residual),
            measured,
            predicted,
            residual,
            noise_floor: floor,
            noise_given: given,
            noise_method,
            quantum,
            band,
            windows,
            finding: findings
                .iter()
                .find(|f| f.output.as_deref() == Some(name.as_str()))
                .map(|f| f.message.clone()),
            name,
        });
    }
    Ok(Comparison {
        model: model.name(),
        t: t.to_vec(),
        outputs,
        warnings: (findings.into_iter().map(|f| f.message))
            .chain(floor_warnings)
            .collect(),
    })
}

/// Samples at the start of a recording whose mean residual [`start_offset`] reads.
const START_SAMPLES: usize = 5;

/// The warning when output `name` starts far from the model: the mean of the residual's
/// first [`START_SAMPLES`] samples beyond `band` and more than twice the residual's RMS (a
/// recording that starts away from the model's initial state, whose error then decays; a
/// fit or explain would otherwise take it for an effect).
pub(crate) fn start_offset(name: &str, unit: &str, residual: &[f64], band: f64) -> Option<String> {
    if residual.len() < 4 * START_SAMPLES {
        return None;
    }
    let start = residual[..START_SAMPLES].iter().sum::<f64>() / START_SAMPLES as f64;
    let rms = crate::residual::rms(residual);
    (start.abs() > band && start.abs() > 2.0 * rms).then(|| {
        format!(
            "`{name}` starts {} {unit} from the model (its first {START_SAMPLES} samples' \
             mean residual, {:.1} times its RMS over the record): the recording may not start \
             where the model does — give the initial state (a bond graph's `[initial]`, with \
             `free = true` for fit to find it) or start at the steady state (--steady-start)",
            crate::story::num(start),
            start.abs() / rms
        )
    })
}

/// Failure windows of `residual` against the band `band + spread_k`: found
/// on the excess `sign(r) max(0, |r| − spread)` against `band`, with each
/// window's peak taken from the residual itself.
fn windows_beyond_spread(
    t: &[f64],
    residual: &[f64],
    spread: &[f64],
    band: f64,
    min_window: f64,
) -> Vec<FailureWindow> {
    let excess: Vec<f64> = residual
        .iter()
        .zip(spread)
        .map(|(r, s)| r.signum() * (r.abs() - s.abs()).max(0.0))
        .collect();
    let mut windows = failure_windows(t, &excess, band, min_window);
    for w in &mut windows {
        let first = t.partition_point(|&ti| ti < w.start);
        let last = t.partition_point(|&ti| ti <= w.end);
        if let Some(k) =
            (first..last).max_by(|&a, &b| residual[a].abs().total_cmp(&residual[b].abs()))
        {
            let r = residual[k];
            w.peak = r.abs();
            w.peak_time = t[k];
            w.sign = if r > 0.0 {
                1
            } else if r < 0.0 {
                -1
            } else {
                0
            };
        }
    }
    windows
}

/// Simulates the model on the recording and compares; with
/// [`CompareOptions::predictability`], the model's predictability band
/// ([`Model::prediction_spread`]) widens the failure band (see
/// [`compare_prediction_with_spread`]).
///
/// # Errors
/// The model's prediction errors, and those of [`compare_prediction`].
pub fn compare(model: &dyn Model, rec: &Recording, opts: &CompareOptions) -> Result<Comparison> {
    let prediction = model.predict(rec)?;
    let spread = if opts.predictability {
        model.prediction_spread(rec)?
    } else {
        None
    };
    compare_prediction_with_spread(model, rec, &prediction, spread.as_ref(), opts)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_start_away_from_the_model_is_said_and_a_model_error_throughout_is_not() {
        // A first-order decay from 4 units off, then noise-like wiggles of 0.05.
        let decay: Vec<f64> = (0..200)
            .map(|k| 4.0 * (-f64::from(k) / 20.0).exp() + 0.05 * (f64::from(k) * 1.7).sin())
            .collect();
        let w = start_offset("T", "K", &decay, 0.2).unwrap();
        assert!(w.starts_with("`T` starts 3."), "{w}");
        // An error of the same size throughout (a wrong gain) is no start.
        let throughout: Vec<f64> = (0..200).map(|k| 4.0 * (f64::from(k) * 0.1).sin()).collect();
        assert_eq!(start_offset("T", "K", &throughout, 0.2), None);
        // Within the band, nothing to say.
        let small: Vec<f64> = decay.iter().map(|r| r * 0.01).collect();
        assert_eq!(start_offset("T", "K", &small, 0.2), None);
    }

    #[test]
    fn spread_widens_the_band_and_peaks_stay_the_residuals() {
        let t: Vec<f64> = (0..10).map(f64::from).collect();
        let residual = [0.0, 0.0, 3.0, 5.0, 3.0, 0.0, 0.0, -4.0, 0.0, 0.0];
        // Noise band 1: two windows. A spread of 4.5 around the first
        // excursion covers it (5 < 1 + 4.5); the second has no spread.
        let plain = failure_windows(&t, &residual, 1.0, 0.0);
        assert_eq!(plain.len(), 2);
        let spread = [0.0, 0.0, 4.5, 4.5, 4.5, 0.0, 0.0, 0.0, 0.0, 0.0];
        let w = windows_beyond_spread(&t, &residual, &spread, 1.0, 0.0);
        assert_eq!(w.len(), 1);
        assert_eq!((w[0].start, w[0].peak, w[0].sign), (7.0, 4.0, -1));
        // A narrower spread leaves the peak sample out: its peak is the residual's 5.
        let spread = [0.0, 0.0, 3.0, 3.0, 3.0, 0.0, 0.0, 0.0, 0.0, 0.0];
        let w = windows_beyond_spread(&t, &residual, &spread, 1.0, 0.0);
        assert_eq!((w[0].start, w[0].end, w[0].peak), (3.0, 3.0, 5.0));
    }
}
