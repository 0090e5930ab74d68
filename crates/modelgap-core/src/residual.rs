//! Domain-free statistics of residuals: error measures, the noise floor, thresholds, failure
//! windows, detection time and derivative estimates.
//!
//! A residual is `measured − predicted`, sample by sample, as in the parallel-model residuals
//! of bond-graph diagnosis: positive where the process lies above the model.
//!
//! The functions take slices that have passed a reader or [`crate::Recording::new`], so they
//! assume finite values (checked with `debug_assert!`). Slices that belong together must have
//! equal lengths; a mismatch is a bug in the caller and panics with a message.

use nalgebra::{DMatrix, DVector};
use serde::{Deserialize, Serialize};

/// Converts a median absolute deviation to a standard deviation for Gaussian data:
/// `1 / Φ⁻¹(3/4)`.
pub const MAD_TO_SIGMA: f64 = 1.482_602_218_505_602;

/// `Var(Δ³x) / σ²` for white noise of standard deviation σ: the third difference
/// `x[k+3] − 3x[k+2] + 3x[k+1] − x[k]` has variance `(1 + 9 + 9 + 1) σ² = 20 σ²`.
pub const THIRD_DIFFERENCE_VARIANCE: f64 = 20.0;

/// The share of samples at the end of a signal averaged for its steady-state value (10 %).
pub const STEADY_STATE_TAIL: f64 = 0.1;

/// Singular values below this are treated as zero in the local polynomial fits of
/// [`savgol_derivatives`]. The fits use time scaled to `[-1, 1]`, so their singular values
/// are of order 1 for well-posed windows.
const SAVGOL_RCOND: f64 = 1e-12;

/// The residual of one signal: `measured − predicted` per sample.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Residual {
    /// The signal's name.
    pub name: String,
    /// `measured − predicted`, one value per sample, in the signal's unit.
    pub values: Vec<f64>,
}

impl Residual {
    /// The residual `measured − predicted` of the signal `name`.
    ///
    /// # Panics
    ///
    /// When the slices differ in length.
    pub fn between(name: impl Into<String>, measured: &[f64], predicted: &[f64]) -> Self {
        assert_eq!(
            measured.len(),
            predicted.len(),
            "measured and predicted must have one value per sample each"
        );
        Self {
            name: name.into(),
            values: measured.iter().zip(predicted).map(|(m, p)| m - p).collect(),
        }
    }
}

/// Summary error measures of a residual.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct ResidualStats {
    /// Root mean square of the residual, in the signal's unit.
    pub rms: f64,
    /// `rms` divided by the RMS of the measured signal (dimensionless). When the measured
    /// signal is identically zero it is 0 for a zero residual and +∞ otherwise.
    pub nrms: f64,
    /// The largest absolute residual, in the signal's unit.
    pub max_abs: f64,
    /// The mean residual (the bias), in the signal's unit.
    pub mean: f64,
}

/// Error measures of `predicted` against `measured` (all zero for empty slices).
///
/// The normalised RMS divides by the RMS of the measured signal rather than its range, so a
/// signal that sits at a constant value still gives a meaningful scale.
///
/// # Panics
///
/// When the slices differ in length.
///
/// # Example
///
/// ```
/// # use modelgap_core::residual::stats;
/// let s = stats(&[1.0, 2.0, 3.0, 4.0], &[1.0, 2.0, 3.0, 2.0]);
/// assert_eq!((s.rms, s.max_abs, s.mean), (1.0, 2.0, 0.5));
/// ```
pub fn stats(measured: &[f64], predicted: &[f64]) -> ResidualStats {
    let residual = Residual::between("", measured, predicted).values;
    let n = residual.len();
    if n == 0 {
        return ResidualStats {
            rms: 0.0,
            nrms: 0.0,
            max_abs: 0.0,
            mean: 0.0,
        };
    }
    let r_rms = rms(&residual);
    let m_rms = rms(measured);
    let nrms = if m_rms > 0.0 {
        r_rms / m_rms
    } else if r_rms == 0.0 {
        0.0
    } else {
        f64::INFINITY
    };
    ResidualStats {
        rms: r_rms,
        nrms,
        max_abs: residual.iter().fold(0.0, |acc: f64, r| acc.max(r.abs())),
        mean: residual.iter().sum::<f64>() / n as f64,
    }
}

/// Root mean square of `values` (0 for an empty slice).
pub fn rms(values: &[f64]) -> f64 {
    if values.is_empty() {
        return 0.0;
    }
    (values.iter().map(|v| v * v).sum::<f64>() / values.len() as f64).sqrt()
}

/// The white-noise level of a signal, estimated from the data alone.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct NoiseFloor {
    /// Standard deviation of the white noise on the signal, in the signal's unit.
    pub sigma: f64,
}

impl NoiseFloor {
    /// Estimates the noise floor of `values` with [`estimate_noise_sigma`].
    pub fn estimate(values: &[f64]) -> Self {
        Self {
            sigma: estimate_noise_sigma(values),
        }
    }
}

/// Estimates the standard deviation of white noise on a sampled signal, robust to the smooth
/// signal underneath.
///
/// Takes the third difference `Δ³x` (which removes any quadratic trend exactly and shrinks a
/// smooth signal by `(ω dt)³`), measures its spread with the median absolute deviation
/// (robust to the few large values a step or spike makes) and scales it: for white Gaussian
/// noise `Var(Δ³x) = 20 σ²`, so `σ = 1.4826 · MAD(Δ³x) / √20`.
///
/// Returns 0 for fewer than 4 samples (no estimate) and for data where more than half the
/// third differences are equal (for example coarsely quantised, noise-free data).
///
/// # Example
///
/// ```
/// # use modelgap_core::residual::estimate_noise_sigma;
/// // A parabola has no noise at all.
/// let x: Vec<f64> = (0..100).map(|k| 0.5 * f64::from(k).powi(2)).collect();
/// assert!(estimate_noise_sigma(&x) < 1e-9);
/// ```
pub fn estimate_noise_sigma(values: &[f64]) -> f64 {
    third_difference_stats(values).0
}

/// What the third differences of `values` say, computed once: the noise σ of
/// [`estimate_noise_sigma`] and the whiteness of [`third_difference_whiteness`].
pub fn third_difference_stats(values: &[f64]) -> (f64, Option<f64>) {
    if values.len() < 4 {
        return (0.0, None);
    }
    debug_assert!(values.iter().all(|v| v.is_finite()));
    let d3: Vec<f64> = values
        .windows(4)
        .map(|w| w[3] - 3.0 * w[2] + 3.0 * w[1] - w[0])
        .collect();
    let mut sorted = d3.clone();
    let center = median(&mut sorted);
    let mut deviations: Vec<f64> = d3.iter().map(|d| (d - center).abs()).collect();
    let spread = MAD_TO_SIGMA * median(&mut deviations);
    let sigma = spread / THIRD_DIFFERENCE_VARIANCE.sqrt();
    if values.len() < 16 || !(spread > 0.0 && spread.is_finite()) {
        return (sigma, None);
    }
    let clipped: Vec<f64> = d3
        .iter()
        .map(|d| (d - center).clamp(-3.0 * spread, 3.0 * spread))
        .collect();
    let c0: f64 = clipped.iter().map(|c| c * c).sum();
    let c1: f64 = clipped.windows(2).map(|w| w[0] * w[1]).sum();
    (sigma, (c0 > 0.0).then(|| (c1 / c0).clamp(-1.0, 1.0)))
}

/// The lag-1 autocorrelation of a signal's third differences `Δ³x`: how far
/// the fast part that [`estimate_noise_sigma`] measures is white noise.
///
/// For white noise `Δ³x` is a moving average with weights (−1, 3, −3, 1), so its
/// lag-1 autocorrelation is exactly −15/20 = −0.75. Correlated noise (AR, a
/// filtered signal, a derivative taken from a smoothed position) shows only its
/// fastest part there and reads about −0.68 to −0.6; a smooth signal that leaks
/// into the third differences (an oversampled resonance) pushes it towards +1.
/// The differences are clipped at three robust standard deviations (a step in
/// the signal is one large value, not a correlation). `None` for fewer than 16
/// samples or when most third differences are equal (a staircase).
///
/// # Example
///
/// ```
/// # use modelgap_core::residual::third_difference_whiteness;
/// let mut g = modelgap_core::noise::Gaussian::new(5);
/// let white: Vec<f64> = (0..4000).map(|_| g.sample()).collect();
/// assert!((third_difference_whiteness(&white).unwrap() + 0.75).abs() < 0.04);
/// let resonance: Vec<f64> = (0..4000).map(|k| (0.6 * f64::from(k)).sin()).collect();
/// assert!(third_difference_whiteness(&resonance).unwrap() > 0.0);
/// ```
pub fn third_difference_whiteness(values: &[f64]) -> Option<f64> {
    third_difference_stats(values).1
}

/// Welch segments of [`quiet_band_noise`]: at most this many samples each.
const WELCH_SEGMENT: usize = 256;

/// An input is quiet at a frequency where its power is below this share of its peak.
const QUIET_POWER: f64 = 1e-4;

/// The fewest frequency bins a quiet band must have.
const QUIET_BINS: usize = 4;

/// The white noise on a measured output, read where the inputs are quiet: the
/// output's power in the band above the inputs' bandwidth, where no model
/// driven by them puts power (a linear one puts none, a mildly nonlinear one
/// little), taken as white noise spread flat over the whole band.
///
/// Power spectra by Welch's method (Hann windows of 256 samples, fewer on a
/// short record, half overlapping, means removed). The quiet band is every
/// bin above the highest one where some input has more than 1e-4 of its peak
/// power (and its neighbour, which the window's leakage reaches), to below
/// the Nyquist bin; it needs 4 bins.
/// `None` without inputs, with fewer than 64 samples, or without such a band
/// (an input that excites every frequency: white noise, a fast PWM).
///
/// A third difference reads an oversampled resonance's own fast content as
/// noise; a band the inputs never reach does not: on Silverbox (a multisine
/// up to 200 Hz at 610 Hz) the output's power above 220 Hz gives σ ≈ 2e-5 V,
/// where third differences give 4.7e-3 V. It is an upper bound where the
/// model's own nonlinearity puts harmonics into the band, and too low where a
/// sensor filters its noise (the noise is then not flat): a filtered signal's
/// third differences say so first ([`third_difference_whiteness`]).
///
/// # Example
///
/// ```
/// # use modelgap_core::residual::quiet_band_noise;
/// let mut g = modelgap_core::noise::Gaussian::new(3);
/// // A slow input, a smooth response to it, and white noise of 0.01 on the output.
/// let u: Vec<f64> = (0..8192).map(|k| (f64::from(k) * 0.01).sin()).collect();
/// let y: Vec<f64> = u.iter().map(|v| 2.0 * v + 0.01 * g.sample()).collect();
/// let sigma = quiet_band_noise(&y, &[&u]).unwrap();
/// assert!((sigma / 0.01 - 1.0).abs() < 0.1, "{sigma}");
/// // White noise as the input excites every frequency: no quiet band.
/// let w: Vec<f64> = (0..8192).map(|_| g.sample()).collect();
/// assert_eq!(quiet_band_noise(&y, &[&w]), None);
/// ```
pub fn quiet_band_noise(measured: &[f64], inputs: &[&[f64]]) -> Option<f64> {
    let n = measured.len();
    if inputs.is_empty() || n < 64 || inputs.iter().any(|u| u.len() != n) {
        return None;
    }
    let len = WELCH_SEGMENT.min(n / 4).max(16);
    let psd_y = welch(measured, len);
    let mut top = 0;
    for u in inputs {
        let psd = welch(u, len);
        let peak = psd.iter().copied().fold(0.0_f64, f64::max);
        if peak.is_nan() || peak <= 0.0 {
            continue;
        }
        let last = (psd.iter().rposition(|p| *p > QUIET_POWER * peak)).unwrap_or(0);
        top = top.max(last);
    }
    // The quiet bins: above the inputs' last loud bin (and its neighbour, which a
    // window's leakage reaches), below the Nyquist bin.
    let band = (top + 2)..(psd_y.len() - 1);
    if band.len() < QUIET_BINS {
        return None;
    }
    let mean = psd_y[band.clone()].iter().sum::<f64>() / band.len() as f64;
    (mean.is_finite() && mean > 0.0).then(|| mean.sqrt())
}

/// Welch's power spectrum of `x` in segments of `len` (Hann window, half
/// overlapping, each segment's mean removed), bins 0 ..= len/2, scaled so that
/// white noise of variance σ² reads σ² in every bin.
fn welch(x: &[f64], len: usize) -> Vec<f64> {
    let bins = len / 2 + 1;
    let window: Vec<f64> = (0..len)
        .map(|i| 0.5 - 0.5 * (2.0 * std::f64::consts::PI * i as f64 / len as f64).cos())
        .collect();
    let norm: f64 = window.iter().map(|w| w * w).sum();
    // The DFT's twiddles, once: cos and sin of 2πk/len.
    let (cos, sin): (Vec<f64>, Vec<f64>) = (0..len)
        .map(|k| {
            let a = 2.0 * std::f64::consts::PI * k as f64 / len as f64;
            (a.cos(), a.sin())
        })
        .unzip();
    let mut psd = vec![0.0; bins];
    let mut segments = 0usize;
    let mut seg = vec![0.0; len];
    let mut start = 0;
    while start + len <= x.len() {
        let part = &x[start..start + len];
        let mean = part.iter().sum::<f64>() / len as f64;
        for (s, (v, w)) in seg.iter_mut().zip(part.iter().zip(&window)) {
            *s = (v - mean) * w;
        }
        for (k, p) in psd.iter_mut().enumerate() {
            let (mut re, mut im) = (0.0, 0.0);
            for (i, v) in seg.iter().enumerate() {
                let j = (i * k) % len;
                re += v * cos[j];
                im -= v * sin[j];
            }
            *p += re * re + im * im;
        }
        segments += 1;
        start += len / 2;
    }
    let scale = 1.0 / (norm * segments.max(1) as f64);
    psd.iter_mut().for_each(|p| *p *= scale);
    psd
}

/// Relative tolerance under which two values of a signal count as the same level in
/// [`quantisation_step`] (decimal text rounds 0.6 to 0.6000000000000001).
const LEVEL_TOLERANCE: f64 = 1e-9;

/// How far, in steps, a gap between two levels may lie from a whole number of steps.
const LATTICE_TOLERANCE: f64 = 0.02;

/// The step of the lattice a quantised signal's values lie on (an ADC's or an encoder's
/// resolution), or `None` when they do not.
///
/// A signal is quantised when it takes at most half as many distinct levels as it has
/// samples, at least 3 of them, and every gap between neighbouring levels is a whole
/// number of the smallest gap (within 2 %). Such a signal carries a rounding error of up to
/// half a step that no model can follow: its noise floor is at least `step / √12`, while the
/// third difference of a staircase is mostly exactly 0 and measures nearly nothing.
///
/// # Example
///
/// ```
/// # use modelgap_core::residual::quantisation_step;
/// let x: Vec<f64> = (0..200).map(|k| (f64::from(k) * 0.013).sin()).collect();
/// let stairs: Vec<f64> = x.iter().map(|v| (v / 0.2).round() * 0.2).collect();
/// assert!((quantisation_step(&stairs).unwrap() - 0.2).abs() < 1e-9);
/// assert_eq!(quantisation_step(&x), None);
/// ```
pub fn quantisation_step(values: &[f64]) -> Option<f64> {
    if values.len() < 8 {
        return None;
    }
    let mut sorted = values.to_vec();
    sorted.sort_by(f64::total_cmp);
    let range = sorted[sorted.len() - 1] - sorted[0];
    if !(range > 0.0 && range.is_finite()) {
        return None;
    }
    let same = LEVEL_TOLERANCE
        * range
            .max(sorted[0].abs())
            .max(sorted[sorted.len() - 1].abs());
    let mut levels: Vec<f64> = Vec::new();
    for v in sorted {
        match levels.last() {
            Some(&last) if v - last <= same => {}
            _ => levels.push(v),
        }
        if levels.len() > values.len() / 2 {
            return None;
        }
    }
    if levels.len() < 3 {
        return None;
    }
    let step = levels
        .windows(2)
        .map(|w| w[1] - w[0])
        .fold(f64::INFINITY, f64::min);
    let on_lattice = levels.windows(2).all(|w| {
        let k = (w[1] - w[0]) / step;
        (k - k.round()).abs() <= LATTICE_TOLERANCE * k.round().max(1.0)
    });
    on_lattice.then_some(step)
}

/// The number of independent samples a residual is worth, given its correlation in time.
///
/// Uses the AR(1) approximation `n_eff = n (1 − ρ₁) / (1 + ρ₁)`, with `ρ₁` the lag-1
/// autocorrelation of the mean-removed residual, clamped to `[1, n]`: negative correlation is
/// not counted as extra information. White noise gives about `n`; slowly varying (coloured)
/// residuals give far fewer, which keeps improvement tests on them honest.
///
/// Returns `n` for fewer than 3 samples and for a constant residual (nothing to discount).
pub fn effective_sample_size(residual: &[f64]) -> f64 {
    let n = residual.len();
    if n < 3 {
        return n as f64;
    }
    let mean = residual.iter().sum::<f64>() / n as f64;
    let c0: f64 = residual.iter().map(|r| (r - mean).powi(2)).sum();
    if c0 == 0.0 {
        return n as f64;
    }
    let c1: f64 = residual
        .windows(2)
        .map(|w| (w[0] - mean) * (w[1] - mean))
        .sum();
    let rho = (c1 / c0).clamp(-1.0, 1.0);
    let n_eff = n as f64 * (1.0 - rho) / (1.0 + rho);
    n_eff.clamp(1.0, n as f64)
}

/// The steady-state value of a signal: the mean of its last 10 % of samples (at least one);
/// 0 for an empty slice.
pub fn steady_state(values: &[f64]) -> f64 {
    if values.is_empty() {
        return 0.0;
    }
    let tail = ((values.len() as f64 * STEADY_STATE_TAIL).ceil() as usize).clamp(1, values.len());
    values[values.len() - tail..].iter().sum::<f64>() / tail as f64
}

/// How far a residual may stray from zero before it counts as non-zero.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub enum Threshold {
    /// A fraction of the magnitude of the measured signal's steady-state value (the mean of
    /// its last 10 % of samples). The DC-motor diagnosis paper uses `fraction: 0.02` (2 %).
    FractionOfSteadyState {
        /// The fraction (dimensionless), 0.02 in the paper.
        fraction: f64,
    },
    /// A multiple of the measured signal's noise standard deviation
    /// ([`estimate_noise_sigma`]).
    Noise {
        /// How many standard deviations (dimensionless), typically 3 to 5.
        sigmas: f64,
    },
    /// A fixed band, in the signal's unit.
    Absolute(f64),
}

impl Threshold {
    /// The half-width of the band around zero for residuals of `measured`, in its unit.
    pub fn band(&self, measured: &[f64]) -> f64 {
        match *self {
            Self::FractionOfSteadyState { fraction } => fraction * steady_state(measured).abs(),
            Self::Noise { sigmas } => sigmas * estimate_noise_sigma(measured),
            Self::Absolute(band) => band,
        }
    }
}

/// An interval where a residual leaves its band.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct FailureWindow {
    /// Time of the first sample outside the band (s).
    pub start: f64,
    /// Time of the last sample outside the band (s).
    pub end: f64,
    /// The largest absolute residual in the window, in the signal's unit (≥ 0).
    pub peak: f64,
    /// Time of the peak (s).
    pub peak_time: f64,
    /// Sign of the residual at the peak: +1 (measured above the model), −1 (below), 0 if zero.
    pub sign: i8,
}

/// The share of the record `t` that failure windows (each from `start` to `end`, s) cover,
/// in [0, 1]: how much of it a model leaves outside its band (a count of windows grows as a
/// falling error wanders in and out).
///
/// ```
/// # use modelgap_core::residual::share_outside;
/// let t = [0.0, 1.0, 2.0, 3.0, 4.0];
/// assert_eq!(share_outside([(1.0, 2.0), (3.0, 3.0)], &t), 0.25);
/// assert_eq!(share_outside([], &t).to_string(), "0");
/// ```
pub fn share_outside(windows: impl IntoIterator<Item = (f64, f64)>, t: &[f64]) -> f64 {
    let (Some(&t0), Some(&t1)) = (t.first(), t.last()) else {
        return 0.0;
    };
    if t1 <= t0 {
        return 0.0;
    }
    let covered: f64 = windows.into_iter().map(|(a, b)| (b - a).max(0.0)).sum();
    if covered > 0.0 {
        (covered / (t1 - t0)).min(1.0)
    } else {
        // An empty sum of floats is −0.
        0.0
    }
}

/// The `n` windows with the largest peaks, in time order: what a list of a few shows of
/// many (a recording whose error grows after a quiet start would otherwise show the quiet
/// part's noise excursions first).
///
/// ```
/// # use modelgap_core::residual::{failure_windows, largest_windows};
/// let t = [0.0, 1.0, 2.0, 3.0, 4.0, 5.0, 6.0];
/// let r = [2.0, 0.0, 9.0, 0.0, 3.0, 0.0, 5.0];
/// let w = failure_windows(&t, &r, 1.0, 0.0);
/// let starts: Vec<f64> = largest_windows(&w, 2).iter().map(|w| w.start).collect();
/// assert_eq!(starts, [2.0, 6.0]);
/// ```
pub fn largest_windows(windows: &[FailureWindow], n: usize) -> Vec<&FailureWindow> {
    let mut by_peak: Vec<&FailureWindow> = windows.iter().collect();
    by_peak.sort_by(|a, b| b.peak.total_cmp(&a.peak));
    by_peak.truncate(n);
    by_peak.sort_by(|a, b| a.start.total_cmp(&b.start));
    by_peak
}

/// The intervals where `|residual| > band`.
///
/// Runs of consecutive samples outside the band become windows from their first to their
/// last sample's time. Windows separated by less than `min_duration` (s, from the end of one
/// to the start of the next) are merged, then windows shorter than `min_duration` are
/// dropped; `min_duration = 0` keeps every run, single samples included.
///
/// # Panics
///
/// When `t` and `residual` differ in length.
///
/// # Example
///
/// ```
/// # use modelgap_core::residual::failure_windows;
/// let t = [0.0, 1.0, 2.0, 3.0, 4.0, 5.0];
/// let r = [0.0, 2.0, -3.0, 0.0, 0.0, 0.0];
/// let w = failure_windows(&t, &r, 1.0, 0.0);
/// assert_eq!((w[0].start, w[0].end, w[0].peak, w[0].sign), (1.0, 2.0, 3.0, -1));
/// ```
pub fn failure_windows(
    t: &[f64],
    residual: &[f64],
    band: f64,
    min_duration: f64,
) -> Vec<FailureWindow> {
    assert_eq!(
        t.len(),
        residual.len(),
        "t and residual must have one value per sample each"
    );
    // Runs as (first, last, peak) sample indices.
    let mut runs: Vec<(usize, usize, usize)> = Vec::new();
    let mut current: Option<(usize, usize, usize)> = None;
    for (i, r) in residual.iter().enumerate() {
        if r.abs() > band {
            current = Some(match current {
                None => (i, i, i),
                Some((first, _, peak)) => {
                    let peak = if r.abs() > residual[peak].abs() {
                        i
                    } else {
                        peak
                    };
                    (first, i, peak)
                }
            });
        } else if let Some(run) = current.take() {
            runs.push(run);
        }
    }
    runs.extend(current);

    let mut merged: Vec<(usize, usize, usize)> = Vec::with_capacity(runs.len());
    for run in runs {
        match merged.last_mut() {
            Some(prev) if t[run.0] - t[prev.1] < min_duration => {
                prev.1 = run.1;
                if residual[run.2].abs() > residual[prev.2].abs() {
                    prev.2 = run.2;
                }
            }
            _ => merged.push(run),
        }
    }

    merged
        .into_iter()
        .filter(|&(first, last, _)| t[last] - t[first] >= min_duration)
        .map(|(first, last, peak)| {
            let r = residual[peak];
            FailureWindow {
                start: t[first],
                end: t[last],
                peak: r.abs(),
                peak_time: t[peak],
                sign: if r > 0.0 {
                    1
                } else if r < 0.0 {
                    -1
                } else {
                    0
                },
            }
        })
        .collect()
}

/// The detection index: the first sample from which `|residual| > band` holds for
/// `persistence_samples` consecutive samples (0 is treated as 1). `t[index]` is the detection
/// time; `None` when the residual never stays out of the band that long.
///
/// # Panics
///
/// When `t` and `residual` differ in length.
pub fn first_exceedance(
    t: &[f64],
    residual: &[f64],
    band: f64,
    persistence_samples: usize,
) -> Option<usize> {
    assert_eq!(
        t.len(),
        residual.len(),
        "t and residual must have one value per sample each"
    );
    let needed = persistence_samples.max(1);
    let mut run = 0;
    for (i, r) in residual.iter().enumerate() {
        if r.abs() > band {
            run += 1;
            if run == needed {
                return Some(i + 1 - needed);
            }
        } else {
            run = 0;
        }
    }
    None
}

/// Smoothed value, first and second derivative of `x(t)` at every sample, by local
/// polynomial least squares (Savitzky–Golay, generalised to non-uniform `t`).
///
/// At each sample a polynomial of degree `order` is fitted to the `window` samples around
/// it (centred, shifted inwards at the ends) in powers of `t − t_i`; its value and
/// derivatives at `t_i` are the estimates. `window` is clamped to `[1, n]` and `order` to
/// `window − 1`; with `order < 2` the second derivative is 0, with `order < 1` the first too.
/// Units: `x`'s, `x`'s per second, `x`'s per second squared. Empty input gives empty output.
///
/// # Panics
///
/// When `t` and `x` differ in length.
///
/// # Example
///
/// ```
/// # use modelgap_core::residual::savgol_derivatives;
/// let t: Vec<f64> = (0..20).map(|k| f64::from(k) * 0.1).collect();
/// let x: Vec<f64> = t.iter().map(|t| 3.0 * t * t).collect();
/// let (_, d1, d2) = savgol_derivatives(&t, &x, 7, 2);
/// assert!((d1[10] - 6.0).abs() < 1e-9 && (d2[10] - 6.0).abs() < 1e-9);
/// ```
pub fn savgol_derivatives(
    t: &[f64],
    x: &[f64],
    window: usize,
    order: usize,
) -> (Vec<f64>, Vec<f64>, Vec<f64>) {
    assert_eq!(
        t.len(),
        x.len(),
        "t and x must have one value per sample each"
    );
    let n = t.len();
    let mut smooth = Vec::with_capacity(n);
    let mut d1 = Vec::with_capacity(n);
    let mut d2 = Vec::with_capacity(n);
    if n == 0 {
        return (smooth, d1, d2);
    }
    debug_assert!(t.windows(2).all(|w| w[1] > w[0]), "t must be increasing");
    let window = window.clamp(1, n);
    let order = order.min(window - 1);
    let half = window / 2;

    for i in 0..n {
        let start = i.saturating_sub(half).min(n - window);
        let span = start..start + window;
        let scale = t[span.clone()]
            .iter()
            .fold(0.0_f64, |acc, &tj| acc.max((tj - t[i]).abs()));
        if order == 0 || scale == 0.0 {
            let mean = x[span].iter().sum::<f64>() / window as f64;
            smooth.push(if order == 0 { mean } else { x[i] });
            d1.push(0.0);
            d2.push(0.0);
            continue;
        }
        let a = DMatrix::from_fn(window, order + 1, |r, c| {
            let u = (t[start + r] - t[i]) / scale;
            u.powi(c as i32)
        });
        let b = DVector::from_column_slice(&x[span]);
        match a.svd(true, true).solve(&b, SAVGOL_RCOND) {
            Ok(c) => {
                smooth.push(c[0]);
                d1.push(c[1] / scale);
                d2.push(if order >= 2 {
                    2.0 * c[2] / (scale * scale)
                } else {
                    0.0
                });
            }
            // Unreachable for distinct times; keep the sample rather than fail.
            Err(_) => {
                smooth.push(x[i]);
                d1.push(0.0);
                d2.push(0.0);
            }
        }
    }
    (smooth, d1, d2)
}

/// The median of `values` (reorders them); 0 for an empty slice.
fn median(values: &mut [f64]) -> f64 {
    let n = values.len();
    if n == 0 {
        return 0.0;
    }
    let (_, &mut upper, _) = values.select_nth_unstable_by(n / 2, f64::total_cmp);
    if n % 2 == 1 {
        upper
    } else {
        // The lower middle is the largest value left of the upper middle.
        let lower = values[..n / 2]
            .iter()
            .copied()
            .fold(f64::NEG_INFINITY, f64::max);
        0.5 * (lower + upper)
    }
}

#[cfg(test)]
mod tests {
    use approx::assert_relative_eq;

    use super::*;

    /// A small deterministic Gaussian generator (splitmix64 + Box–Muller), seeded.
    struct Gauss(u64);

    impl Gauss {
        fn uniform(&mut self) -> f64 {
            self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
            let mut z = self.0;
            z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
            z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
            z ^= z >> 31;
            // 53 random bits in (0, 1].
            ((z >> 11) as f64 + 1.0) / (1u64 << 53) as f64
        }

        fn normal(&mut self) -> f64 {
            let (u1, u2) = (self.uniform(), self.uniform());
            (-2.0 * u1.ln()).sqrt() * (std::f64::consts::TAU * u2).cos()
        }
    }

    fn noisy_sine(n: usize, sigma: f64, seed: u64) -> Vec<f64> {
        let mut g = Gauss(seed);
        (0..n)
            .map(|k| 5.0 * (k as f64 * 0.01).sin() + sigma * g.normal())
            .collect()
    }

    #[test]
    fn stats_of_known_residual() {
        let s = stats(&[1.0, 2.0, 3.0, 4.0], &[1.0, 2.0, 3.0, 2.0]);
        assert_eq!(s.rms, 1.0);
        assert_eq!(s.max_abs, 2.0);
        assert_eq!(s.mean, 0.5);
        // rms(measured) = sqrt(30 / 4); a few ulps of rounding in the square root.
        assert_relative_eq!(s.nrms, 1.0 / 7.5_f64.sqrt(), epsilon = 1e-15);
    }

    #[test]
    fn nrms_guards_a_zero_measured_signal() {
        assert_eq!(stats(&[0.0, 0.0], &[0.0, 0.0]).nrms, 0.0);
        assert_eq!(stats(&[0.0, 0.0], &[1.0, 0.0]).nrms, f64::INFINITY);
        assert_eq!(stats(&[], &[]).rms, 0.0);
    }

    #[test]
    fn residual_is_measured_minus_predicted() {
        let r = Residual::between("i", &[3.0, 1.0], &[1.0, 2.0]);
        assert_eq!(r.values, vec![2.0, -1.0]);
        assert_eq!(r.name, "i");
    }

    #[test]
    fn noise_sigma_recovered_under_a_smooth_signal() {
        let sigma = 0.01;
        let x = noisy_sine(5000, sigma, 7);
        // MAD on 5000 correlated samples: a few percent of scatter, so 10 % is a safe bound.
        assert_relative_eq!(estimate_noise_sigma(&x), sigma, max_relative = 0.1);
        assert_relative_eq!(NoiseFloor::estimate(&x).sigma, sigma, max_relative = 0.1);
    }

    #[test]
    fn noise_sigma_is_robust_to_steps() {
        let sigma = 0.05;
        let mut g = Gauss(3);
        let x: Vec<f64> = (0..4000)
            .map(|k| if k % 1000 < 500 { 0.0 } else { 10.0 } + sigma * g.normal())
            .collect();
        // Eight steps spoil 24 of 3997 third differences; the median ignores them.
        assert_relative_eq!(estimate_noise_sigma(&x), sigma, max_relative = 0.1);
    }

    #[test]
    fn noise_sigma_of_noise_free_data_is_zero() {
        let x: Vec<f64> = (0..50).map(|k| 1.0 + 2.0 * f64::from(k)).collect();
        assert_eq!(estimate_noise_sigma(&x), 0.0);
        assert_eq!(estimate_noise_sigma(&[1.0, 5.0, 2.0]), 0.0);
    }

    #[test]
    fn white_noise_keeps_nearly_all_samples() {
        let x = {
            let mut g = Gauss(11);
            (0..10_000).map(|_| g.normal()).collect::<Vec<_>>()
        };
        let n_eff = effective_sample_size(&x);
        // ρ₁ of white noise scatters by 1/√n = 0.01, so n_eff within ±4 %.
        assert!(n_eff > 9_600.0 && n_eff <= 10_000.0, "{n_eff}");
    }

    #[test]
    fn coloured_noise_is_worth_fewer_samples() {
        let phi = 0.9;
        let mut g = Gauss(5);
        let mut x = vec![0.0; 20_000];
        for k in 1..x.len() {
            x[k] = phi * x[k - 1] + g.normal();
        }
        let expected = 20_000.0 * (1.0 - phi) / (1.0 + phi);
        // ρ₁ is estimated within about ±0.005, which moves n_eff by roughly ±5 %.
        assert_relative_eq!(effective_sample_size(&x), expected, max_relative = 0.1);
    }

    #[test]
    fn effective_sample_size_edge_cases() {
        assert_eq!(effective_sample_size(&[]), 0.0);
        assert_eq!(effective_sample_size(&[1.0, 2.0]), 2.0);
        assert_eq!(effective_sample_size(&[3.0; 10]), 10.0);
        let ramp: Vec<f64> = (0..100).map(f64::from).collect();
        assert!(effective_sample_size(&ramp) < 5.0);
    }

    #[test]
    fn steady_state_band_is_two_percent_of_final_mean() {
        let mut x = vec![0.0; 90];
        x.extend([-10.0; 10]);
        assert_relative_eq!(
            Threshold::FractionOfSteadyState { fraction: 0.02 }.band(&x),
            0.2,
            epsilon = 1e-15
        );
        assert_eq!(steady_state(&[4.0]), 4.0);
        assert_eq!(steady_state(&[]), 0.0);
    }

    #[test]
    fn noise_and_absolute_bands() {
        let x = noisy_sine(5000, 0.02, 9);
        assert_relative_eq!(
            Threshold::Noise { sigmas: 3.0 }.band(&x),
            0.06,
            max_relative = 0.1
        );
        assert_eq!(Threshold::Absolute(0.5).band(&x), 0.5);
    }

    #[test]
    fn failure_windows_merge_short_gaps_and_drop_short_windows() {
        let t: Vec<f64> = (0..20).map(f64::from).collect();
        let mut r = vec![0.0; 20];
        // Window A: samples 2..=5, with a one-sample dip at 4 that merging bridges.
        r[2] = 2.0;
        r[3] = 3.0;
        r[5] = 4.0;
        // A lone spike at 9: too short.
        r[9] = -9.0;
        // Window B: samples 13..=16, negative.
        r[13..=16].fill(-2.0);
        r[15] = -5.0;
        let w = failure_windows(&t, &r, 1.0, 2.5);
        assert_eq!(w.len(), 2, "{w:?}");
        assert_eq!(
            (w[0].start, w[0].end, w[0].peak, w[0].peak_time, w[0].sign),
            (2.0, 5.0, 4.0, 5.0, 1)
        );
        assert_eq!(
            (w[1].start, w[1].end, w[1].peak, w[1].peak_time, w[1].sign),
            (13.0, 16.0, 5.0, 15.0, -1)
        );

        let all = failure_windows(&t, &r, 1.0, 0.0);
        assert_eq!(all.len(), 4);
        assert_eq!((all[2].start, all[2].end), (9.0, 9.0));
    }

    #[test]
    fn failure_window_open_at_the_end_is_kept() {
        let t = [0.0, 1.0, 2.0];
        let w = failure_windows(&t, &[0.0, 5.0, 6.0], 1.0, 0.0);
        assert_eq!(w.len(), 1);
        assert_eq!((w[0].start, w[0].end), (1.0, 2.0));
        assert!(failure_windows(&t, &[0.0, 0.5, -0.5], 1.0, 0.0).is_empty());
    }

    #[test]
    fn first_exceedance_waits_for_persistence() {
        let t: Vec<f64> = (0..10).map(f64::from).collect();
        let r = [0.0, 2.0, 0.0, 2.0, 2.0, 0.0, -2.0, -2.0, -2.0, 0.0];
        assert_eq!(first_exceedance(&t, &r, 1.0, 1), Some(1));
        assert_eq!(first_exceedance(&t, &r, 1.0, 0), Some(1));
        assert_eq!(first_exceedance(&t, &r, 1.0, 2), Some(3));
        assert_eq!(first_exceedance(&t, &r, 1.0, 3), Some(6));
        assert_eq!(first_exceedance(&t, &r, 1.0, 4), None);
        assert_eq!(first_exceedance(&t, &r, 5.0, 1), None);
    }

    #[test]
    fn savgol_is_exact_for_polynomials_on_non_uniform_time() {
        let t: Vec<f64> = (0..40)
            .map(|k| {
                let k = f64::from(k);
                0.05 * k + 0.01 * (k * 1.7).sin()
            })
            .collect();
        let x: Vec<f64> = t.iter().map(|t| 1.0 - 2.0 * t + 4.0 * t * t).collect();
        let (s, d1, d2) = savgol_derivatives(&t, &x, 9, 3);
        for i in 0..t.len() {
            // A cubic fit reproduces a quadratic up to rounding in the solve.
            assert_relative_eq!(s[i], x[i], epsilon = 1e-9);
            assert_relative_eq!(d1[i], -2.0 + 8.0 * t[i], epsilon = 1e-7);
            assert_relative_eq!(d2[i], 8.0, epsilon = 1e-5);
        }
    }

    #[test]
    fn savgol_estimates_derivatives_of_a_sine() {
        let t: Vec<f64> = (0..400).map(|k| f64::from(k) * 0.01).collect();
        let x: Vec<f64> = t.iter().map(|t| t.sin()).collect();
        let (s, d1, d2) = savgol_derivatives(&t, &x, 11, 4);
        for i in 5..395 {
            // The quartic fit's truncation error over ±0.05 s is far below these bounds.
            assert_relative_eq!(s[i], t[i].sin(), epsilon = 1e-8);
            assert_relative_eq!(d1[i], t[i].cos(), epsilon = 1e-6);
            assert_relative_eq!(d2[i], -t[i].sin(), epsilon = 1e-3);
        }
    }

    #[test]
    fn savgol_handles_degenerate_sizes() {
        let (s, d1, d2) = savgol_derivatives(&[], &[], 5, 2);
        assert!(s.is_empty() && d1.is_empty() && d2.is_empty());
        let (s, d1, _) = savgol_derivatives(&[0.0], &[3.0], 5, 2);
        assert_eq!((s[0], d1[0]), (3.0, 0.0));
        // Two samples: the order drops to 1, a straight line through both.
        let (s, d1, d2) = savgol_derivatives(&[0.0, 2.0], &[1.0, 5.0], 5, 3);
        assert_relative_eq!(d1[0], 2.0, epsilon = 1e-12);
        assert_relative_eq!(s[1], 5.0, epsilon = 1e-12);
        assert_eq!(d2, vec![0.0, 0.0]);
    }

    #[test]
    fn median_of_odd_and_even_lengths() {
        assert_eq!(median(&mut [3.0, 1.0, 2.0]), 2.0);
        assert_eq!(median(&mut [4.0, 1.0, 3.0, 2.0]), 2.5);
        assert_eq!(median(&mut []), 0.0);
    }
}
