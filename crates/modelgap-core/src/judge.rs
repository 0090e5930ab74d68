//! judge: is what a model leaves only what noise leaves? The evidence behind
//! "nothing is missing", and the checks that say when a recording cannot be
//! judged at all.
//!
//! A residual is taken for noise only when all of these hold:
//!
//! 1. **Level.** Its RMS is within the floor factor of the noise floor. A
//!    floor estimated from the data sees only the noise's fast part; when the
//!    residual is larger, it may still be coloured noise — that is accepted
//!    only when the noise model fitted to the residual ([`NoiseModel`], an
//!    AR(p)) is short-memory and mostly unpredictable (integrated
//!    correlation time at most [`MAX_NOISE_CORRELATION`] samples, prediction
//!    gain at most [`MAX_NOISE_PREDICTION_GAIN`]: a ramp is predictable from
//!    its own past, noise is not), its innovations are white (Ljung–Box over
//!    [`WHITENESS_LAGS`] lags: a missed oscillation is not an AR process of
//!    low order) and the tests below pass. A floor the user gave is the
//!    noise's whole σ and is taken as it is.
//! 2. **No failure window**: the residual never leaves its band of
//!    `band_sigmas` noise σ for five sample periods or more (for coloured
//!    noise, which wanders beyond 4σ in long excursions, a band wide enough to
//!    hold the false-alarm rate below over the recording's independent
//!    stretches).
//! 3. **No input correlation** (Haugh's test): the innovations of the
//!    residual's noise model are uncorrelated with the innovations of each
//!    recorded input at lags 0 to [`INPUT_LAGS`] samples. Noise does not know
//!    what the input did; a model error does (a sensor lag answers every
//!    voltage step, missing friction every reversal).
//! 4. **No bias**: the residual's mean is within chance of zero, its
//!    standard error taken from the noise model's long-run variance
//!    (coloured noise wanders; its mean is uncertain).
//!
//! Tests 3 and 4 hold a family-wise false-alarm rate of [`TEST_ALPHA`] over
//! every output, input and lag they are made on.
//!
//! [`recording_findings`] checks a recording before any of this: enough
//! samples, outputs that move at all (a dead sensor reads a constant), and a
//! time base on which the model's time constants can be seen.

use serde::{Deserialize, Serialize};

use crate::compare::Floor;
use crate::report::format_number;
use crate::residual::{failure_windows, rms};

/// Highest AR order of a residual's or an input's noise model.
pub const MAX_AR_ORDER: usize = 10;

/// Lags (samples) of the Ljung–Box test on a coloured residual's innovations.
pub const WHITENESS_LAGS: usize = 40;

/// Lags (samples) at which a residual's innovations are held against each
/// input's: a model error answers an input change within the model's time
/// constants, which the noise model's whitening shortens to a few samples.
pub const INPUT_LAGS: usize = 20;

/// Family-wise false-alarm rate of each test (input correlation, bias)
/// over every output, lag and input it is made on (Bonferroni).
pub const TEST_ALPHA: f64 = 1e-3;

/// Longest integrated correlation time (samples) of a residual that may be
/// taken for coloured noise when its level is above the white floor: AR(1)
/// noise with ρ up to about 0.98. Slower wander is a drift or a model error.
pub const MAX_NOISE_CORRELATION: f64 = 100.0;

/// Largest prediction gain (marginal over innovation variance) of a
/// residual that may be taken for coloured noise: AR(1) noise with ρ up to
/// about 0.98. A model error is mostly predictable from its own past (a
/// missed oscillation, a ramp); noise is not.
pub const MAX_NOISE_PREDICTION_GAIN: f64 = 25.0;

/// Fewest samples on which a verdict is given.
pub const MIN_SAMPLES: usize = 30;

/// A model's time constants and the sample period may differ by this factor
/// either way before the recording is said to hide the model's dynamics.
pub const TIME_BASE_FACTOR: f64 = 3.0;

/// An AR(p) model of a series: `x_k = Σ φ_i x_{k−i} + e_k` on the
/// mean-removed series, fitted by least squares with p chosen by BIC.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct NoiseModel {
    /// Mean of the series.
    pub mean: f64,
    /// AR coefficients φ_1 … φ_p (empty: white).
    pub coefficients: Vec<f64>,
    /// Standard deviation of the innovations e_k.
    pub innovation_sigma: f64,
    /// Standard deviation of the mean-removed series.
    pub marginal_sigma: f64,
}

impl NoiseModel {
    /// Fits the model to `x` (at least `4 (MAX_AR_ORDER + 1)` samples for
    /// any order above 0).
    pub fn fit(x: &[f64]) -> NoiseModel {
        let n = x.len();
        let mean = if n == 0 {
            0.0
        } else {
            x.iter().sum::<f64>() / n as f64
        };
        let y: Vec<f64> = x.iter().map(|v| v - mean).collect();
        let marginal_sigma = rms(&y);
        let max_p = if n >= 4 * (MAX_AR_ORDER + 1) {
            MAX_AR_ORDER
        } else {
            0
        };
        let m = n.saturating_sub(max_p);
        let mut best = (f64::INFINITY, Vec::new(), marginal_sigma);
        for p in 0..=max_p {
            let Some((phi, s2)) = least_squares_ar(&y, p, max_p) else {
                continue;
            };
            if s2 <= 0.0 || s2.is_nan() {
                // A series the model predicts exactly: take it and stop.
                best = (f64::NEG_INFINITY, phi, 0.0);
                break;
            }
            let bic = m as f64 * s2.ln() + p as f64 * (m as f64).ln();
            if bic < best.0 {
                best = (bic, phi, s2.sqrt());
            }
        }
        NoiseModel {
            mean,
            coefficients: best.1,
            innovation_sigma: best.2,
            marginal_sigma,
        }
    }

    /// The innovations `e_k` of `x` (mean removed), from sample `start` on
    /// (`start ≥ p`).
    pub fn innovations(&self, x: &[f64], start: usize) -> Vec<f64> {
        let p = self.coefficients.len();
        let start = start.max(p);
        (start..x.len())
            .map(|k| {
                let mut e = x[k] - self.mean;
                for (i, phi) in self.coefficients.iter().enumerate() {
                    e -= phi * (x[k - 1 - i] - self.mean);
                }
                e
            })
            .collect()
    }

    /// The long-run variance `σ_e² / (1 − Σφ)²`: n times the variance of the
    /// mean of n samples.
    pub fn long_run_variance(&self) -> f64 {
        let sum: f64 = self.coefficients.iter().sum();
        let d = (1.0 - sum).abs().max(1e-6);
        (self.innovation_sigma / d).powi(2)
    }

    /// Prediction gain: marginal over innovation variance (1 for white
    /// noise, 1/(1 − ρ²) for AR(1)); infinite for a series the model
    /// predicts exactly.
    pub fn prediction_gain(&self) -> f64 {
        if self.innovation_sigma > 0.0 {
            (self.marginal_sigma / self.innovation_sigma)
                .powi(2)
                .max(1.0)
        } else if self.marginal_sigma > 0.0 {
            f64::INFINITY
        } else {
            1.0
        }
    }

    /// Integrated correlation time, in samples: long-run over marginal
    /// variance (1 for white noise, (1 + ρ)/(1 − ρ) for AR(1)).
    pub fn correlation_samples(&self) -> f64 {
        if self.marginal_sigma > 0.0 {
            (self.long_run_variance() / self.marginal_sigma.powi(2)).max(1.0)
        } else {
            1.0
        }
    }
}

/// Least-squares AR(p) of `y` on samples `skip..` (the same for every p, so
/// that BIC compares like with like): the coefficients and the mean squared
/// innovation. `None` when the normal equations are singular.
fn least_squares_ar(y: &[f64], p: usize, skip: usize) -> Option<(Vec<f64>, f64)> {
    let n = y.len();
    if n <= skip {
        return None;
    }
    let m = (n - skip) as f64;
    if p == 0 {
        return Some((Vec::new(), y[skip..].iter().map(|v| v * v).sum::<f64>() / m));
    }
    let mut ata = nalgebra::DMatrix::<f64>::zeros(p, p);
    let mut atb = nalgebra::DVector::<f64>::zeros(p);
    for k in skip..n {
        for i in 0..p {
            let xi = y[k - 1 - i];
            atb[i] += xi * y[k];
            for j in 0..=i {
                ata[(i, j)] += xi * y[k - 1 - j];
            }
        }
    }
    for i in 0..p {
        for j in 0..i {
            ata[(j, i)] = ata[(i, j)];
        }
    }
    let phi = ata.cholesky()?.solve(&atb);
    let mut s = 0.0;
    for k in skip..n {
        let mut e = y[k];
        for i in 0..p {
            e -= phi[i] * y[k - 1 - i];
        }
        s += e * e;
    }
    Some((phi.iter().copied().collect(), s / m))
}

/// The strongest correlation of a residual's innovations with an input's.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct InputCorrelation {
    /// The input.
    pub input: String,
    /// Lag (samples) of the input before the residual.
    pub lag: usize,
    /// The correlation in standard errors (√n · r).
    pub z: f64,
}

/// Why a residual is, or is not, what noise leaves.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Judgement {
    /// RMS of the residual.
    pub rms: f64,
    /// The noise floor it is held against (σ).
    pub floor: f64,
    /// Whether the user gave the floor.
    pub floor_given: bool,
    /// σ of the noise the residual is taken for: the floor, or the
    /// residual's own level when it was accepted as coloured noise.
    pub noise_sigma: f64,
    /// Integrated correlation time (samples) of the residual's noise model.
    pub correlation_samples: f64,
    /// Whether the residual was accepted as coloured noise above the white floor.
    pub coloured: bool,
    /// The residual's mean in standard errors.
    pub bias_z: f64,
    /// The strongest input correlation, when the model has recorded inputs.
    pub input: Option<InputCorrelation>,
    /// Failure windows against `band_sigmas` × `noise_sigma` (wider for coloured noise).
    pub windows: usize,
    /// The measurement's quantisation step, when it is quantised: a residual
    /// within rounding plus noise is not held against the inputs.
    #[serde(default)]
    pub quantum: Option<f64>,
    /// Whether its level is the noise's (white, or accepted as coloured).
    pub level_ok: bool,
    /// Whether it is uncorrelated with every input (true without inputs).
    pub input_ok: bool,
    /// Whether its mean is within chance of zero.
    pub bias_ok: bool,
    /// Whether it is what noise leaves.
    pub at_floor: bool,
    /// Why not, in words (empty when at the floor).
    pub reasons: Vec<String>,
}

impl Judgement {
    /// RMS over the floor.
    pub fn ratio(&self) -> f64 {
        self.rms / self.floor
    }
}

/// Options of [`judge_residual`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct JudgeOptions {
    /// The RMS may be this many floors (1.3).
    pub floor_factor: f64,
    /// Band of the failure windows, in noise σ (4).
    pub band_sigmas: f64,
    /// How many outputs are judged together: the tests' thresholds are
    /// raised so that [`TEST_ALPHA`] holds over all of them (1).
    pub outputs: usize,
}

impl Default for JudgeOptions {
    fn default() -> JudgeOptions {
        JudgeOptions {
            floor_factor: 1.3,
            band_sigmas: 4.0,
            outputs: 1,
        }
    }
}

impl JudgeOptions {
    /// Largest |z| of a residual's mean taken for chance.
    pub fn z_bias(&self) -> f64 {
        normal_upper_quantile(TEST_ALPHA / (2.0 * self.outputs.max(1) as f64))
    }

    /// Largest |z| of an input cross-correlation taken for chance, with
    /// `inputs` inputs tested at `INPUT_LAGS + 1` lags each.
    pub fn z_input(&self, inputs: usize) -> f64 {
        let tests = self.outputs.max(1) * inputs.max(1) * (INPUT_LAGS + 1);
        normal_upper_quantile(TEST_ALPHA / (2.0 * tests as f64))
    }
}

/// The z with `P(Z > z) = p` for a standard normal Z, `0 < p < 0.5`
/// (Abramowitz & Stegun 26.2.23, error below 4.5e-4).
pub fn normal_upper_quantile(p: f64) -> f64 {
    let p = p.clamp(1e-300, 0.5);
    let t = (-2.0 * p.ln()).sqrt();
    t - (2.515_517 + 0.802_853 * t + 0.010_328 * t * t)
        / (1.0 + 1.432_788 * t + 0.189_269 * t * t + 0.001_308 * t * t * t)
}

/// Judges one output's residual: is it what noise leaves?
///
/// `t` and `residual` are the recording's times and `measured − predicted`;
/// `floor` the noise floor (σ), given by the user or estimated; `inputs`
/// the recorded inputs the model was driven by (empty for a model without
/// any, such as a cloth).
pub fn judge_residual(
    t: &[f64],
    residual: &[f64],
    floor: &Floor,
    inputs: &[(&str, &[f64])],
    opts: &JudgeOptions,
) -> Judgement {
    let (floor_given, quantum) = (floor.given, floor.quantum);
    let floor = floor.sigma;
    let n = residual.len();
    let level = rms(residual);
    let noise = NoiseModel::fit(residual);
    let correlation_samples = noise.correlation_samples();
    let bias_z = if n > 0 && noise.long_run_variance() > 0.0 {
        noise.mean / (noise.long_run_variance() / n as f64).sqrt()
    } else {
        0.0
    };
    let input = input_correlation(residual, &noise, inputs);
    // A quantised measurement's rounding error is a function of the signal,
    // so it answers the input too; a residual that never leaves rounding
    // plus noise is what the sensor leaves, whatever it correlates with.
    let rounding_only = quantum.is_some_and(|q| {
        let noise_part = (floor * floor - q * q / 12.0).max(0.0).sqrt();
        residual
            .iter()
            .all(|r| r.abs() <= 0.5 * q + opts.band_sigmas * noise_part)
    });
    let input_ok = rounding_only
        || input
            .as_ref()
            .is_none_or(|c| c.z.abs() <= opts.z_input(inputs.len()));
    let bias_ok = bias_z.abs() <= opts.z_bias();
    let mut reasons = Vec::new();
    let white_level = level <= opts.floor_factor * floor;
    let whiteness = ljung_box(&noise.innovations(residual, MAX_AR_ORDER), WHITENESS_LAGS);
    let white_innovations = whiteness
        <= chi2_upper_quantile(
            WHITENESS_LAGS.saturating_sub(noise.coefficients.len()),
            TEST_ALPHA / opts.outputs.max(1) as f64,
        );
    let noise_like = correlation_samples <= MAX_NOISE_CORRELATION
        && noise.prediction_gain() <= MAX_NOISE_PREDICTION_GAIN
        && white_innovations;
    let coloured = !white_level && !floor_given && input_ok && bias_ok && noise_like;
    let noise_sigma = if coloured {
        noise.marginal_sigma
    } else {
        floor
    };
    if !(white_level || coloured) {
        let mut why = format!(
            "RMS {} is {}× its noise floor {}",
            format_number(level),
            format_number(level / floor),
            format_number(floor)
        );
        if !floor_given && !noise_like {
            if white_innovations {
                why.push_str(&format!(
                    " and is {} % predictable from its own past (correlation time {} samples): \
                     a model error or a drift, not noise",
                    format_number(100.0 * (1.0 - 1.0 / noise.prediction_gain())),
                    format_number(correlation_samples)
                ));
            } else {
                why.push_str(&format!(
                    " and is no coloured noise either (Ljung–Box Q = {} over {WHITENESS_LAGS} \
                     lags after whitening): a model error",
                    format_number(whiteness)
                ));
            }
        }
        reasons.push(why);
    }
    let dt = if n > 1 {
        (t[n - 1] - t[0]) / (n - 1) as f64
    } else {
        0.0
    };
    // White noise rarely stays beyond 4σ for five samples; coloured noise wanders there in
    // long excursions, so its band is widened to hold the family-wise rate over the
    // recording's independent stretches (n / correlation time of them, per output).
    let sigmas = if coloured {
        let stretches = (n as f64 / correlation_samples).max(1.0);
        opts.band_sigmas.max(normal_upper_quantile(
            TEST_ALPHA / (2.0 * opts.outputs.max(1) as f64 * stretches),
        ))
    } else {
        opts.band_sigmas
    };
    let windows = failure_windows(t, residual, sigmas * noise_sigma, 5.0 * dt).len();
    if windows > 0 {
        reasons.push(format!(
            "leaves its band of ±{} ({} {}noise σ) in {windows} window(s)",
            format_number(sigmas * noise_sigma),
            format_number(sigmas),
            if coloured { "coloured " } else { "" }
        ));
    }
    if let Some(c) = input.as_ref().filter(|_| !input_ok) {
        reasons.push(format!(
            "follows input {} (correlation {} standard errors at a lag of {} samples): \
             noise does not know what the input did",
            c.input,
            format_number(c.z),
            c.lag
        ));
    }
    if !bias_ok {
        reasons.push(format!(
            "is biased: mean {} ({} standard errors from 0)",
            format_number(noise.mean),
            format_number(bias_z)
        ));
    }
    Judgement {
        rms: level,
        floor,
        floor_given,
        noise_sigma,
        correlation_samples,
        coloured,
        bias_z,
        input,
        windows,
        quantum,
        level_ok: white_level || coloured,
        input_ok,
        bias_ok,
        at_floor: reasons.is_empty(),
        reasons,
    }
}

/// Outputs up to which every output must be at its floor on its own.
pub const FEW_OUTPUTS: usize = 3;

/// Whether a set of outputs is at its floors: each output on its own when
/// there are at most [`FEW_OUTPUTS`]; with more (a cloth's marker
/// coordinates), the level pooled by [`at_noise_floor`] and every output
/// free of windows, input correlation and bias.
pub fn all_at_floor(judgements: &[Judgement], floor_factor: f64) -> bool {
    if judgements.is_empty() {
        return false;
    }
    if judgements.len() <= FEW_OUTPUTS {
        return judgements.iter().all(|j| j.at_floor);
    }
    let rms: Vec<f64> = judgements.iter().map(|j| j.rms).collect();
    let sigma: Vec<f64> = judgements.iter().map(|j| j.noise_sigma).collect();
    at_noise_floor(&rms, &sigma, floor_factor)
        && judgements
            .iter()
            .all(|j| j.windows == 0 && j.input_ok && j.bias_ok)
}

/// Whether residual RMS values sit at their noise floors `sigma`: each
/// within `factor` × its floor when there are at most [`FEW_OUTPUTS`];
/// with more, the quadratic mean of the ratios within `factor` and each
/// within 2 × `factor`. Among dozens of outputs (a cloth's marker
/// coordinates) one floor estimate is often off by 1.5×, and the strict
/// rule would call a found effect partial; a single output that an effect
/// leaves far from its floor still fails.
#[must_use]
pub fn at_noise_floor(rms: &[f64], sigma: &[f64], factor: f64) -> bool {
    let ratios = rms.iter().zip(sigma).map(|(r, s)| r / s);
    if rms.len() <= FEW_OUTPUTS {
        return ratios.into_iter().all(|q| q <= factor);
    }
    let mut sum = 0.0;
    for q in ratios {
        // NaN fails too.
        if q.is_nan() || q > 2.0 * factor {
            return false;
        }
        sum += q * q;
    }
    (sum / rms.len() as f64).sqrt() <= factor
}

/// The Ljung–Box statistic of `e` over lags `1..=lags`:
/// `Q = m (m + 2) Σ r_l² / (m − l)`, χ² with `lags − p` degrees of freedom
/// for the innovations of an AR(p) fit when they are white.
pub fn ljung_box(e: &[f64], lags: usize) -> f64 {
    let m = e.len();
    if m <= lags + 1 {
        return 0.0;
    }
    let mean = e.iter().sum::<f64>() / m as f64;
    let c0: f64 = e.iter().map(|v| (v - mean) * (v - mean)).sum();
    if c0 <= 0.0 || c0.is_nan() {
        return 0.0;
    }
    let mf = m as f64;
    (1..=lags)
        .map(|l| {
            let c: f64 = e[l..]
                .iter()
                .zip(e)
                .map(|(a, b)| (a - mean) * (b - mean))
                .sum();
            let r = c / c0;
            r * r / (mf - l as f64)
        })
        .sum::<f64>()
        * mf
        * (mf + 2.0)
}

/// The `1 − alpha` quantile of χ² with `k` degrees of freedom
/// (Wilson–Hilferty, within 1 % for k ≥ 10).
pub fn chi2_upper_quantile(k: usize, alpha: f64) -> f64 {
    let k = k.max(1) as f64;
    let z = normal_upper_quantile(alpha);
    let a = 2.0 / (9.0 * k);
    k * (1.0 - a + z * a.sqrt()).powi(3)
}

/// Haugh's test: the largest |√m · corr(e_k, v_{k−l})| over inputs and lags
/// `0..=INPUT_LAGS`, with `e` the residual's innovations and `v` each
/// input's own. `None` when no input varies.
fn input_correlation(
    residual: &[f64],
    noise: &NoiseModel,
    inputs: &[(&str, &[f64])],
) -> Option<InputCorrelation> {
    let n = residual.len();
    let start = MAX_AR_ORDER;
    if n < start + INPUT_LAGS + MIN_SAMPLES {
        return None;
    }
    let e = noise.innovations(residual, start);
    let e_norm = e.iter().map(|v| v * v).sum::<f64>().sqrt();
    let mut best: Option<InputCorrelation> = None;
    for (name, u) in inputs {
        if u.len() != n {
            continue;
        }
        let model = NoiseModel::fit(u);
        if model.marginal_sigma <= 0.0 || model.marginal_sigma.is_nan() {
            continue;
        }
        let v = model.innovations(u, start);
        for lag in 0..=INPUT_LAGS {
            // e[k] against v[k − lag], k from lag on.
            let (a, b) = (&e[lag..], &v[..v.len() - lag]);
            let m = a.len() as f64;
            let ab: f64 = a.iter().zip(b).map(|(x, y)| x * y).sum();
            let bb: f64 = b.iter().map(|y| y * y).sum::<f64>().sqrt();
            let aa: f64 = a.iter().map(|x| x * x).sum::<f64>().sqrt();
            if !(aa > 0.0 && bb > 0.0 && e_norm > 0.0) {
                continue;
            }
            let z = ab / (aa * bb) * m.sqrt();
            if best.as_ref().is_none_or(|c| z.abs() > c.z.abs()) {
                best = Some(InputCorrelation {
                    input: (*name).to_string(),
                    lag,
                    z,
                });
            }
        }
    }
    best
}

/// Something about a recording that keeps it from being judged, or one
/// output of it.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Finding {
    /// The output concerned, or `None` for the whole recording.
    pub output: Option<String>,
    /// What is wrong, in words.
    pub message: String,
}

/// The checks made before any verdict: at least [`MIN_SAMPLES`] samples;
/// each measured output moves at all (a constant is a dead or disconnected
/// sensor, or a system at rest: nothing to judge); and, given the model's
/// time constants (s), samples close enough to see them and a recording
/// long enough to hold them (a time column written in ms gives samples
/// 1000× too far apart).
///
/// `outputs` are the measured outputs by name.
pub fn recording_findings(
    t: &[f64],
    outputs: &[(&str, &[f64])],
    time_constants: &[f64],
) -> Vec<Finding> {
    let mut findings = Vec::new();
    let n = t.len();
    if n < MIN_SAMPLES {
        findings.push(Finding {
            output: None,
            message: format!(
                "the recording has {n} sample{}: at least {MIN_SAMPLES} are needed to tell a \
                 model error from noise",
                if n == 1 { "" } else { "s" }
            ),
        });
        return findings;
    }
    for (name, y) in outputs {
        let lo = y.iter().copied().fold(f64::INFINITY, f64::min);
        let hi = y.iter().copied().fold(f64::NEG_INFINITY, f64::max);
        if hi - lo <= 1e-12 * hi.abs().max(lo.abs()) {
            findings.push(Finding {
                output: Some((*name).to_string()),
                message: format!(
                    "output {name} reads {} throughout the recording: a dead or disconnected \
                     sensor, or a system at rest; nothing to judge it by",
                    format_number(lo)
                ),
            });
        }
    }
    let taus: Vec<f64> = time_constants
        .iter()
        .copied()
        .filter(|v| v.is_finite() && *v > 0.0)
        .collect();
    if let (Some(slowest), Some(fastest)) = (
        taus.iter().copied().reduce(f64::max),
        taus.iter().copied().reduce(f64::min),
    ) {
        let mut steps: Vec<f64> = t.windows(2).map(|w| w[1] - w[0]).collect();
        steps.sort_by(f64::total_cmp);
        let dt = steps[steps.len() / 2];
        let duration = t[n - 1] - t[0];
        let range = if slowest > fastest * 1.0001 {
            format!(
                "time constants of {}–{} s",
                format_number(fastest),
                format_number(slowest)
            )
        } else {
            format!("a time constant of {} s", format_number(slowest))
        };
        if dt > TIME_BASE_FACTOR * slowest {
            let unit_hint = if dt >= 10.0 * slowest {
                " is the time column in ms, not s?"
            } else {
                " was the recording sampled too slowly?"
            };
            findings.push(Finding {
                output: None,
                message: format!(
                    "samples {} s apart against the model's {range}: the model settles between \
                     samples and its dynamics cannot be seen;{unit_hint}",
                    format_number(dt)
                ),
            });
        } else if duration * TIME_BASE_FACTOR < fastest {
            findings.push(Finding {
                output: None,
                message: format!(
                    "the recording lasts {} s against the model's {range}: too short to see any \
                     of them; is the time column in s?",
                    format_number(duration)
                ),
            });
        }
    }
    findings
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::noise::Gaussian;

    fn estimated(sigma: f64) -> Floor {
        Floor {
            sigma,
            given: false,
            quantum: None,
            kind: crate::compare::FloorKind::White,
            whiteness: None,
        }
    }

    fn ar1(n: usize, rho: f64, sigma: f64, seed: u64) -> Vec<f64> {
        let mut g = Gaussian::new(seed);
        let mut x = 0.0;
        (0..n)
            .map(|_| {
                x = rho * x + (1.0 - rho * rho).sqrt() * g.sample();
                sigma * x
            })
            .collect()
    }

    fn steps(n: usize) -> Vec<f64> {
        (0..n)
            .map(|k| match k * 4 / n {
                0 => 0.0,
                1 => 12.0,
                2 => -12.0,
                _ => 6.0,
            })
            .collect()
    }

    #[test]
    fn chi2_quantiles() {
        // Tables: χ²_40(0.999) = 73.40, χ²_30(0.95) = 43.77.
        assert!((chi2_upper_quantile(40, 1e-3) - 73.40).abs() < 0.5);
        assert!((chi2_upper_quantile(30, 0.05) - 43.77).abs() < 0.3);
    }

    #[test]
    fn normal_quantiles() {
        assert!((normal_upper_quantile(0.025) - 1.96).abs() < 1e-3);
        assert!((normal_upper_quantile(5e-4) - 3.2905).abs() < 1e-3);
        let o = JudgeOptions::default();
        assert!((o.z_input(1) - normal_upper_quantile(5e-4 / 21.0)).abs() < 1e-12);
    }

    #[test]
    fn ar1_is_recovered() {
        let x = ar1(20_000, 0.9, 1.0, 3);
        let m = NoiseModel::fit(&x);
        assert!((m.coefficients[0] - 0.9).abs() < 0.02, "{m:?}");
        assert!((m.correlation_samples() - 19.0).abs() < 3.0, "{m:?}");
    }

    #[test]
    fn white_noise_at_its_floor_is_noise() {
        let n = 4000;
        let t: Vec<f64> = (0..n).map(|k| k as f64 * 1e-3).collect();
        let u = steps(n);
        for seed in 1..21 {
            let r = ar1(n, 0.0, 0.1, seed);
            let j = judge_residual(
                &t,
                &r,
                &estimated(0.1),
                &[("V", &u)],
                &JudgeOptions::default(),
            );
            assert!(j.at_floor, "seed {seed}: {:?}", j.reasons);
        }
    }

    #[test]
    fn coloured_noise_above_the_white_floor_is_noise_when_inputs_cannot_explain_it() {
        let n = 4000;
        let t: Vec<f64> = (0..n).map(|k| k as f64 * 1e-3).collect();
        let u = steps(n);
        for seed in 1..21 {
            let r = ar1(n, 0.95, 0.1, seed);
            // The third-difference floor of AR(1) noise with ρ = 0.95 is 0.175 σ.
            let j = judge_residual(
                &t,
                &r,
                &estimated(0.0175),
                &[("V", &u)],
                &JudgeOptions::default(),
            );
            assert!(j.at_floor && j.coloured, "seed {seed}: {:?}", j.reasons);
        }
    }

    #[test]
    fn a_missed_oscillation_is_not_coloured_noise() {
        let n = 4000;
        let t: Vec<f64> = (0..n).map(|k| k as f64 * 1e-3).collect();
        let noise = ar1(n, 0.0, 0.01, 2);
        for f in [3.0, 40.0, 240.0] {
            let r: Vec<f64> = t
                .iter()
                .zip(&noise)
                .map(|(t, e)| 0.05 * (2.0 * std::f64::consts::PI * f * t).sin() + e)
                .collect();
            let j = judge_residual(&t, &r, &estimated(0.01), &[], &JudgeOptions::default());
            assert!(!j.at_floor, "{f} Hz: {j:?}");
        }
    }

    #[test]
    fn a_lagging_sensor_follows_the_input() {
        // The residual of a first-order system y' = (u − y)/τ measured through a lag:
        // spikes that answer every input step, decaying with τ.
        let n = 4000;
        let t: Vec<f64> = (0..n).map(|k| k as f64 * 1e-3).collect();
        let u = steps(n);
        let mut y = 0.0;
        let mut lagged = 0.0;
        let noise = ar1(n, 0.0, 0.01, 5);
        let r: Vec<f64> = (0..n)
            .map(|k| {
                y += (u[k] - y) * 1e-3 / 0.03;
                lagged += (y - lagged) * 1e-3 / 0.003;
                lagged - y + noise[k]
            })
            .collect();
        let j = judge_residual(
            &t,
            &r,
            &estimated(0.01),
            &[("V", &u)],
            &JudgeOptions::default(),
        );
        assert!(!j.at_floor);
        assert!(j.input.as_ref().is_some_and(|c| c.z.abs() > 10.0), "{j:?}");
    }

    #[test]
    fn a_bias_is_found() {
        let n = 4000;
        let t: Vec<f64> = (0..n).map(|k| k as f64 * 1e-3).collect();
        let r: Vec<f64> = ar1(n, 0.0, 0.1, 9).iter().map(|v| v + 0.02).collect();
        let given = Floor {
            given: true,
            ..estimated(0.1)
        };
        let j = judge_residual(&t, &r, &given, &[], &JudgeOptions::default());
        assert!(!j.at_floor && j.bias_z > 4.0, "{j:?}");
    }

    #[test]
    fn findings_name_few_samples_dead_outputs_and_a_time_column_in_ms() {
        let t: Vec<f64> = (0..10).map(f64::from).collect();
        let f = recording_findings(&t, &[], &[]);
        assert!(f[0].message.contains("10 samples"), "{f:?}");

        let t: Vec<f64> = (0..4000).map(f64::from).collect();
        let zeros = vec![0.0; 4000];
        let f = recording_findings(&t, &[("omega", &zeros)], &[0.0059, 0.034]);
        assert_eq!(f.len(), 2, "{f:?}");
        assert!(f[0].message.contains("omega reads 0 throughout"), "{f:?}");
        assert!(f[1].message.contains("in ms"), "{f:?}");
        assert!(f[1].message.contains("0.0059–0.034 s"), "{f:?}");

        let t: Vec<f64> = (0..4000).map(|k| f64::from(k) * 1e-3).collect();
        let y: Vec<f64> = t.iter().map(|v| v.sin()).collect();
        assert!(recording_findings(&t, &[("omega", &y)], &[0.0059, 0.034]).is_empty());
    }
}
