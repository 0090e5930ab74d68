//! Stage 2 of discovery, **screen**: which law the missing effort follows.
//!
//! The missing effort (or flow) the estimate found at a place
//! ([`MissingSignal`]) is regressed on a typed library of terms built from
//! the signals acting there — a static, linear regression, no simulation:
//!
//! | family | term | on |
//! |---|---|---|
//! | constant | `1` | every place |
//! | linear | `v` | flows, positions, displacements, efforts, inputs |
//! | sign | `tanh(v/ε)`, ε scanned from sharp to smooth | flows |
//! | Stribeck | `tanh(v/ε)·exp(−(v/v_s)²)`, `v_s` scanned | flows |
//! | absolute | `|v|` (with `v`: viscous friction that differs by direction) | flows |
//! | sign magnitude | `|tanh(v/ε)|`, ε scanned (with a sign term: Coulomb friction that differs by direction) | flows |
//! | quadratic drag | `v·|v|` | flows, positions, displacements |
//! | cubic | `v³` | flows, positions, displacements |
//! | hinge | `max(x − x₀, 0)` or `min(x − x₀, 0)`, x₀ scanned over the signal's 5–95 % quantiles | positions, displacements |
//! | square root | `√max(e, 0)` | node efforts (an orifice) |
//! | power | `sign(e)·|e|^p`, p scanned over 0.3 … 3 | node efforts (seepage, convection) |
//! | harmonics | `sin nθ`, `cos nθ`, every n in 1..=24 at once | angles |
//! | product | `a·b`, `a·|b|`, `a²·b` of two signals; `b·sin nθ`, `b·cos nθ` for n in 1..=12; an input times a signal, `u·b`, or a flow's sign, `u·tanh(f/ε)` | flows, positions, displacements, efforts, angles, inputs, the flow one transducer away (`i·sin nθ` at a shaft) |
//! | ripple | `sin(2πx/λ)`, `cos(2πx/λ)`, λ scanned over 1/100 … 1/2 of the travel | positions |
//! | step | `H(t − t₀)`, t₀ scanned | time |
//! | ramp | `max(t − t₀, 0)`, t₀ scanned | time |
//! | quantiser | `quantise(u, q) − u` (a driver's or converter's steps, rounding or truncating), q scanned over 1/500 … 1/8 of the input's range | inputs that take many values |
//! | symbolic | a formula of the signals, built by the symbolic search (`symbolic.rs`) when the rest leaves the estimate well above its band | flows, positions, displacements, efforts |
//!
//! Selection is sparse and forward: the block (one term, or a harmonic's
//! sine and cosine) that lowers the weighted residual most is added while
//! its gain beats the Bayesian information criterion counted in *effective*
//! samples (the estimate is smooth: its lag-1 correlation says how many
//! independent samples it holds) plus the size of its shape scan, and while
//! its coefficient agrees on both halves of the recording (a law, not an
//! episode). Where no single block joins, two may join together (each
//! beside the other by the same rules, `next_pair`): a law of two terms of
//! like size leaves, after either, the other's smooth shape. One member per
//! shape family. The result is a [`Law`]: terms
//! with coefficients, ± and units, ready to be built into the model and
//! confirmed by simulation ([`crate::Model::law_candidate`]).

use serde::Serialize;

use super::estimate::{ActingSignal, MissingSignal, Quantity, SignalRole};
use super::symbolic;

/// At most this many samples enter the regression (the estimate is smooth;
/// a longer record is decimated).
const MAX_SAMPLES: usize = 4000;
/// At most this many blocks in a law.
const MAX_BLOCKS: usize = 4;
/// A term joins a law only if it removes at least this share of what the law leaves.
const MIN_SHARE: f64 = 0.1;
/// A product of two signals joins a law only if it removes at least this share.
const PRODUCT_MIN_SHARE: f64 = 0.33;
/// Harmonics of an angle up to this order.
const MAX_HARMONIC: usize = 24;
/// Interior points of a step's or a ramp's time scan.
const TIME_SCAN: usize = 39;
/// Harmonics of an angle that a product with another signal takes, up to this order.
const MAX_PRODUCT_HARMONIC: usize = 12;

/// A term's family: one member of a shape family per law.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, serde::Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Family {
    /// A constant effort (a load, an offset).
    Constant,
    /// Proportional to a signal (viscous friction, a stiffness, a gain).
    Linear,
    /// `tanh(v/ε)`: Coulomb friction, a contact drop.
    Sign,
    /// `tanh(v/ε)·exp(−(v/v_s)²)`: the Stribeck excess at low speed.
    Stribeck,
    /// `|v|`: with a linear term, viscous friction that differs by direction.
    Absolute,
    /// `|tanh(v/ε)|`: with a sign term, Coulomb friction that differs by
    /// direction (a level while moving, either way, that holds nothing at rest).
    SignMagnitude,
    /// `v·|v|`: fan, aerodynamic or turbulent drag.
    QuadraticDrag,
    /// `v³`: a hardening (or softening) spring, a cubic damper.
    Cubic,
    /// `max(x − x₀, 0)` or `min(x − x₀, 0)`, `x₀` scanned: a stop or a second
    /// spring that engages past a point (a bilinear spring, a bump stop, a gap
    /// that closes).
    Hinge,
    /// `√e`: a free outflow through an orifice.
    SquareRoot,
    /// `sign(e)|e|^p`, `p` scanned: seepage, convection, a mixed outflow.
    Power,
    /// `sin nθ`, `cos nθ`: a ripple locked to the angle (cogging, eccentricity).
    Harmonic,
    /// `sin(2π x/λ)`, `cos(2π x/λ)`: a ripple locked to a position, its
    /// wavelength scanned (a linear motor's magnet pitch, a screw's lead).
    Ripple,
    /// `sin(2π f t)`, `cos(2π f t)`: a disturbance periodic in time, its
    /// frequency scanned (a neighbouring machine's vibration, a pulsating
    /// load, hum).
    Periodic,
    /// `H(t − t₀)`: something that changed at one time (a load, a fault).
    Step,
    /// `max(t − t₀, 0)`: a drift from one time on.
    Ramp,
    /// A product of two signals acting at the place (`q²·v`: damping that
    /// grows with the displacement; `x·v`), or of one with a harmonic of the
    /// angle (`v·sin nθ`: friction that varies around a turn).
    Product,
    /// `quantise(u, q) − u`: what an actuator that delivers its command `u`
    /// in steps of `q` adds to it (a driver's or a converter's resolution),
    /// rounding (`u` to the nearest step) or truncating (steps between them,
    /// with a constant).
    Quantiser,
    /// A formula the symbolic search built from the signals at the place
    /// when the typed library left the estimate well above its band: a
    /// shape, reported as such, with no physical law named.
    Symbolic,
}

impl Family {
    /// What the family is, physically, in a few words.
    pub fn physics(self) -> &'static str {
        match self {
            Family::Constant => "a constant load or offset",
            Family::Linear => "a proportional term (viscous, stiffness or gain)",
            Family::Sign => "a sign-like term (Coulomb friction, a contact drop)",
            Family::Stribeck => "a Stribeck excess at low speed",
            Family::Absolute => "a term in |v| (viscous friction that differs by direction)",
            Family::SignMagnitude => {
                "a term in |sign v| (Coulomb friction that differs by direction)"
            }
            Family::QuadraticDrag => "a quadratic drag (fan, air, turbulence)",
            Family::Cubic => "a cubic term (hardening spring, cubic damping)",
            Family::Hinge => {
                "a term that starts at one position (a stop, a bilinear spring, a gap that closes)"
            }
            Family::SquareRoot => "a square-root outflow (an orifice)",
            Family::Power => "a power law (seepage, convection, a mixed outflow)",
            Family::Harmonic => "a ripple locked to the angle",
            Family::Ripple => "a ripple locked to the position (a pitch)",
            Family::Periodic => "a disturbance periodic in time (a vibration, a pulsating load)",
            Family::Step => "a step at one time (a load or a fault)",
            Family::Ramp => "a drift from one time on",
            Family::Product => "a product of two signals (one modulates the other's effect)",
            Family::Quantiser => "the steps of a quantised input (an actuator's resolution)",
            Family::Symbolic => "a formula the symbolic search found (no named law of the library)",
        }
    }
}

/// One term of a law: `coefficient · expr`.
#[derive(Clone, Debug, PartialEq, Serialize, serde::Deserialize)]
pub struct LawTerm {
    /// Its parameter's name in the law (`c_sign`).
    pub param: String,
    /// The family.
    pub family: Family,
    /// The term in words and numbers (`tanh(speed of the shaft / 0.01 rad/s)`).
    pub label: String,
    /// The term in the model's law syntax, without its coefficient
    /// (`tanh('1m'.f / 1.0e-2)`).
    pub expr: String,
    /// The coefficient's unit.
    pub unit: String,
    /// The regression's coefficient.
    pub coefficient: f64,
    /// Its standard error (effective samples counted).
    pub std_error: f64,
    /// The largest |term| over the recording: with the largest missing
    /// effort, it bounds what the coefficient may become.
    pub term_max: f64,
    /// The term's shape parameter, when its family scans one (a width, a
    /// Stribeck speed, a time): confirmed by simulation with the coefficient.
    pub shape: Option<Shape>,
}

/// A shape parameter of a term, at the value its scan chose, with the range
/// the scan covered (widened threefold) as bounds. In [`LawTerm::expr`] it
/// is written `§`; [`Law::formula`] names it.
#[derive(Clone, Debug, PartialEq, Serialize, serde::Deserialize)]
pub struct Shape {
    /// Its parameter's name in the law (`eps_sign`).
    pub name: String,
    /// Its unit.
    pub unit: String,
    /// The scanned value.
    pub value: f64,
    /// Bounds.
    pub lower: f64,
    /// Bounds.
    pub upper: f64,
}

impl LawTerm {
    /// The term in law syntax with its shape parameter named.
    pub fn expr_named(&self) -> String {
        match &self.shape {
            Some(sh) => self.expr.replace('§', &sh.name),
            None => self.expr.clone(),
        }
    }
}

/// A law found at one place: the missing effort as a sum of terms.
#[derive(Clone, Debug, PartialEq, Serialize, serde::Deserialize)]
pub struct Law {
    /// The element the place is (`1m`).
    pub location: String,
    /// The place in words.
    pub place: String,
    /// Effort or flow.
    pub quantity: Quantity,
    /// The unit of the missing effort or flow.
    pub unit: String,
    /// The terms, in the order they were chosen.
    pub terms: Vec<LawTerm>,
    /// The share of the (weighted) missing signal the law explains, in [0, 1].
    pub explained: f64,
    /// The RMS of what the law leaves of the missing signal.
    pub residual_rms: f64,
    /// The largest |missing signal| estimated.
    pub missing_max: f64,
    /// The effective number of independent samples the regression counted.
    pub effective_samples: f64,
    /// The samples the regression used (indices into the missing signal) and
    /// the law's value at each: what the report draws beside the estimate.
    #[serde(skip)]
    pub fitted: Vec<(usize, f64)>,
}

impl Law {
    /// The law in the model's syntax, its coefficients as parameters:
    /// `c_sign * tanh('1m'.f / 1.0e-2) + c_const * 1`.
    pub fn formula(&self) -> String {
        let parts: Vec<String> = (self.terms.iter())
            .map(|t| {
                if t.family == Family::Constant {
                    t.param.clone()
                } else {
                    format!("{} * {}", t.param, t.expr_named())
                }
            })
            .collect();
        parts.join(" + ")
    }

    /// The shape each term's label reads at its `§`: its own, or for a term
    /// that shares the shape of the term before it (a periodic law's cosine
    /// reads its sine's frequency), that one's.
    fn shapes(&self) -> Vec<Option<&Shape>> {
        let mut last: Option<&Shape> = None;
        (self.terms.iter())
            .map(|t| {
                if t.shape.is_some() {
                    last = t.shape.as_ref();
                }
                t.shape.as_ref().or(last.filter(|_| t.label.contains('§')))
            })
            .collect()
    }

    /// The law with its numbers, in words:
    /// `0.021 N m · tanh(speed / 0.01 rad/s) + 0.002 N m`.
    pub fn describe(&self) -> String {
        // Each term by the size of its coefficient; a negative one after the first joins
        // with a minus sign (`+ -9.7e-4` read as a typo).
        let shapes = self.shapes();
        let parts: Vec<(bool, String)> = (self.terms.iter())
            .zip(&shapes)
            .enumerate()
            .map(|(i, (t, shape))| {
                let negative = i > 0 && t.coefficient < 0.0;
                let c = if negative {
                    -t.coefficient
                } else {
                    t.coefficient
                };
                let unit = if t.unit.is_empty() || t.unit == "1" {
                    String::new()
                } else {
                    format!(" {}", t.unit)
                };
                let label = match shape {
                    Some(sh) => t
                        .label
                        .replace('§', &format!("{} {}", sig(sh.value), sh.unit)),
                    None => t.label.clone(),
                };
                let text = if t.family == Family::Constant {
                    format!("{}{unit}", sig(c))
                } else {
                    format!("{}{unit} · {label}", sig(c))
                };
                (negative, text)
            })
            .collect();
        let mut out = String::new();
        for (i, (negative, text)) in parts.iter().enumerate() {
            if i > 0 {
                out.push_str(if *negative { " − " } else { " + " });
            }
            out.push_str(text);
        }
        out
    }

    /// The law with its parameters by name, each term in words:
    /// `c_sign · tanh(speed of the shaft (1m) / eps_sign) + c_const`.
    pub fn symbolic(&self) -> String {
        let parts: Vec<String> = (self.terms.iter())
            .zip(self.shapes())
            .map(|(t, shape)| {
                let label = match shape {
                    Some(sh) => t.label.replace('§', &sh.name),
                    None => t.label.clone(),
                };
                if t.family == Family::Constant {
                    t.param.clone()
                } else {
                    format!("{} · {label}", t.param)
                }
            })
            .collect();
        parts.join(" + ")
    }

    /// Whether a term is a formula of the symbolic search ([`Family::Symbolic`]).
    pub fn has_formula(&self) -> bool {
        self.terms.iter().any(|t| t.family == Family::Symbolic)
    }

    /// The families of its terms, in words (`a sign-like term …; a ripple …`).
    pub fn physics(&self) -> String {
        let mut seen: Vec<Family> = Vec::new();
        for t in &self.terms {
            if !seen.contains(&t.family) {
                seen.push(t.family);
            }
        }
        seen.iter()
            .map(|f| f.physics())
            .collect::<Vec<_>>()
            .join("; ")
    }
}

/// A candidate block: one or two columns (a harmonic's sine and cosine).
struct Block {
    family: Family,
    /// An id within the family (a signal, an order): harmonics of several
    /// orders may all enter; other families once.
    member: String,
    /// How many shapes the family scanned (its multiple-comparison cost).
    scanned: usize,
    terms: Vec<LawTerm>,
    columns: Vec<Vec<f64>>,
}

pub(super) fn term(
    param: &str,
    family: Family,
    label: String,
    expr: String,
    unit: String,
) -> LawTerm {
    LawTerm {
        param: param.to_string(),
        family,
        label,
        expr,
        unit,
        coefficient: 0.0,
        std_error: 0.0,
        term_max: 0.0,
        shape: None,
    }
}

/// `t` with a shape parameter `stem` at `value` within [`lo`, `hi`].
pub(super) fn shaped(
    mut t: LawTerm,
    stem: &str,
    unit: &str,
    value: f64,
    lo: f64,
    hi: f64,
) -> LawTerm {
    t.shape = Some(Shape {
        name: stem.to_string(),
        unit: unit.to_string(),
        value,
        lower: lo,
        upper: hi,
    });
    t
}

/// Exponents of the power-law term of an effort (1, the linear term, and ½,
/// the square root, are families of their own).
const POWERS: [f64; 14] = [
    0.3, 0.4, 0.6, 0.7, 0.8, 0.9, 1.1, 1.2, 1.3, 1.5, 1.75, 2.0, 2.5, 3.0,
];

/// Wavelengths of a position ripple tried: from a hundredth to half of the travel.
const RIPPLE_PERIODS: (f64, f64) = (2.0, 100.0);
/// Ripples offered to the selection: the best few wavelengths of the scan.
const RIPPLE_PEAKS: usize = 3;

/// The span of `x` (largest less smallest), when finite and positive.
fn span(x: &[f64]) -> Option<f64> {
    let (lo, hi) = (x.iter()).fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), v| {
        (l.min(*v), h.max(*v))
    });
    Some(hi - lo).filter(|s| s.is_finite() && *s > 0.0)
}

/// Ripples locked to the position `x` (values at the screen's samples, `y` the
/// missing signal there). Wavelengths from a hundredth to half of the travel
/// are scanned on a grid even in wavenumber, fine enough that the phase drifts
/// by at most π/8 over the travel; each is sized against `y` alone (a sine and
/// a cosine, least squares), and the few that explain most become blocks whose
/// wavelength is a shape parameter (its bounds three grid steps either way).
fn ripples(y: &[f64], a: &ActingSignal, x: &[f64], eu: &str) -> Vec<Block> {
    let Some(travel) = span(x).filter(|_| y.len() == x.len()) else {
        return Vec::new();
    };
    let tau = std::f64::consts::TAU;
    let (k_lo, k_hi) = (
        tau * RIPPLE_PERIODS.0 / travel,
        tau * RIPPLE_PERIODS.1 / travel,
    );
    let dk = std::f64::consts::FRAC_PI_4 / travel;
    let count = ((k_hi - k_lo) / dk).ceil() as usize + 1;
    // The share of y each wavenumber explains (a periodogram in the position).
    let centred = centred(y);
    let power: Vec<f64> = (0..count)
        .map(|i| {
            let k = k_lo + dk * i as f64;
            pair_power(x.iter().zip(&centred).map(|(xi, r)| {
                let (sn, cs) = (k * xi).sin_cos();
                (sn, cs, *r)
            }))
        })
        .collect();
    let peaks = highest_peaks(&power, RIPPLE_PEAKS);
    let n = &a.name;
    let label = &a.label;
    peaks
        .into_iter()
        .map(|i| {
            let k = k_lo + dk * i as f64;
            let lambda = tau / k;
            let (lam_lo, lam_hi) = (tau / (k + 3.0 * dk), tau / (k - 3.0 * dk).max(0.5 * k));
            Block {
                family: Family::Ripple,
                member: n.clone(),
                scanned: count,
                terms: vec![
                    shaped(
                        term(
                            "c_sinx",
                            Family::Ripple,
                            format!("sin(2π · {label} / §)"),
                            format!("sin({} * {n} / §)", num(tau)),
                            eu.to_string(),
                        ),
                        "lam",
                        &a.unit,
                        lambda,
                        lam_lo,
                        lam_hi,
                    ),
                    // The cosine reads the sine's wavelength (in its label, `§` too).
                    term(
                        "c_cosx",
                        Family::Ripple,
                        format!("cos(2π · {label} / §)"),
                        format!("cos({} * {n} / lam_sinx)", num(tau)),
                        eu.to_string(),
                    ),
                ],
                columns: vec![
                    x.iter().map(|v| (k * v).sin()).collect(),
                    x.iter().map(|v| (k * v).cos()).collect(),
                ],
            }
        })
        .collect()
}

/// `y` less its mean.
fn centred(y: &[f64]) -> Vec<f64> {
    let mean = y.iter().sum::<f64>() / y.len().max(1) as f64;
    y.iter().map(|v| v - mean).collect()
}

/// What a sine and a cosine explain of `r` by least squares (the explained
/// sum of squares), from `(sin, cos, r)` per sample; 0 when the two are
/// (nearly) collinear over the samples.
fn pair_power(samples: impl Iterator<Item = (f64, f64, f64)>) -> f64 {
    let (mut ss, mut cc, mut sc, mut sy, mut cy) = (0.0, 0.0, 0.0, 0.0, 0.0);
    for (sn, cs, r) in samples {
        ss += sn * sn;
        cc += cs * cs;
        sc += sn * cs;
        sy += sn * r;
        cy += cs * r;
    }
    let det = ss * cc - sc * sc;
    if det <= 1e-12 * ss.max(cc).powi(2) {
        return 0.0;
    }
    (cc * sy * sy - 2.0 * sc * sy * cy + ss * cy * cy) / det
}

/// The indices of the `keep` highest local maxima of `power` (positive), highest first.
fn highest_peaks(power: &[f64], keep: usize) -> Vec<usize> {
    let count = power.len();
    let mut peaks: Vec<usize> = (0..count)
        .filter(|&i| {
            let left = i == 0 || power[i] >= power[i - 1];
            let right = i + 1 == count || power[i] >= power[i + 1];
            left && right && power[i] > 0.0
        })
        .collect();
    peaks.sort_by(|&p, &q| power[q].total_cmp(&power[p]));
    peaks.truncate(keep);
    peaks
}

/// A disturbance periodic in time is looked for from this many periods over the record…
const PERIODIC_MIN_PERIODS: f64 = 3.0;
/// …up to this fraction of the screen's sampling rate.
const PERIODIC_MAX_RATE: f64 = 0.1;
/// Periodic terms offered to the selection: the best few frequencies of the scan.
const PERIODIC_PEAKS: usize = 3;
/// A frequency where an input carries this share of its variance or more (and a few
/// grid steps either way) is the drive's: a disturbance there cannot be told from
/// what the drive does through a missing law, and is not offered.
const PERIODIC_INPUT_SHARE: f64 = 0.01;
/// Grid steps either side of an input's line left out with it.
const PERIODIC_GUARD: usize = 3;

/// The periodogram of `r` (centred) at angular frequencies `w_lo + dw·i`, `i < count`,
/// on the uniform times `t`: the sine and cosine advanced by one rotation per sample,
/// recomputed exactly every 256 samples.
fn time_periodogram(t: &[f64], r: &[f64], w_lo: f64, dw: f64, count: usize) -> Vec<f64> {
    let dt = (t[t.len() - 1] - t[0]) / (t.len() - 1) as f64;
    (0..count)
        .map(|i| {
            let w = w_lo + dw * i as f64;
            let (rs, rc) = (w * dt).sin_cos();
            let (mut sn, mut cs) = (0.0, 1.0);
            pair_power(t.iter().zip(r).enumerate().map(|(k, (tk, rk))| {
                if k % 256 == 0 {
                    (sn, cs) = (w * tk).sin_cos();
                } else {
                    (sn, cs) = (sn * rc + cs * rs, cs * rc - sn * rs);
                }
                (sn, cs, *rk)
            }))
        })
        .collect()
}

/// Disturbances periodic in time (`y` the missing signal at the screen's times `t`,
/// uniform; `inputs` the recording's inputs there): frequencies from
/// [`PERIODIC_MIN_PERIODS`] periods over the record to [`PERIODIC_MAX_RATE`] of the
/// sampling rate, on a grid fine enough that the phase drifts by at most π/4 over the
/// record, each sized against `y` alone (a sine and a cosine, least squares), the
/// inputs' own lines left out ([`PERIODIC_INPUT_SHARE`]); the few that explain most
/// become blocks whose frequency is a shape parameter (three grid steps either way).
fn periodics(y: &[f64], t: &[f64], inputs: &[Vec<f64>], eu: &str) -> Vec<Block> {
    let n = t.len();
    if n < 20 || y.len() != n {
        return Vec::new();
    }
    let span = t[n - 1] - t[0];
    let dt = span / (n - 1) as f64;
    let uniform = (t.windows(2)).all(|p| ((p[1] - p[0]) - dt).abs() <= 1e-3 * dt);
    if !(span > 0.0 && uniform) {
        return Vec::new();
    }
    let tau = std::f64::consts::TAU;
    let (w_lo, w_hi) = (
        tau * PERIODIC_MIN_PERIODS / span,
        tau * PERIODIC_MAX_RATE / dt,
    );
    let dw = std::f64::consts::FRAC_PI_4 / span;
    if w_hi <= w_lo {
        return Vec::new();
    }
    let count = ((w_hi - w_lo) / dw).ceil() as usize + 1;
    let mut power = time_periodogram(t, &centred(y), w_lo, dw, count);
    for u in inputs {
        let u = centred(u);
        let total: f64 = u.iter().map(|v| v * v).sum();
        if !total.is_finite() || total <= 0.0 {
            continue;
        }
        let line = time_periodogram(t, &u, w_lo, dw, count);
        for (i, p) in line.iter().enumerate() {
            if *p >= PERIODIC_INPUT_SHARE * total {
                let lo = i.saturating_sub(PERIODIC_GUARD);
                let hi = (i + PERIODIC_GUARD).min(count - 1);
                power[lo..=hi].iter_mut().for_each(|q| *q = 0.0);
            }
        }
    }
    let offered = power.iter().filter(|p| **p > 0.0).count();
    highest_peaks(&power, PERIODIC_PEAKS)
        .into_iter()
        .map(|i| {
            let w = w_lo + dw * i as f64;
            let f = w / tau;
            let (f_lo, f_hi) = ((w - 3.0 * dw) / tau, (w + 3.0 * dw) / tau);
            Block {
                family: Family::Periodic,
                member: "t".to_string(),
                scanned: offered.max(1),
                terms: vec![
                    shaped(
                        term(
                            "c_sint",
                            Family::Periodic,
                            "sin(2π · § · t)".to_string(),
                            format!("sin({} * § * t)", num(tau)),
                            eu.to_string(),
                        ),
                        "f",
                        "Hz",
                        f,
                        f_lo.max(0.5 * f),
                        f_hi,
                    ),
                    // The cosine reads the sine's frequency (in its label, `§` too).
                    term(
                        "c_cost",
                        Family::Periodic,
                        "cos(2π · § · t)".to_string(),
                        format!("cos({} * f_sint * t)", num(tau)),
                        eu.to_string(),
                    ),
                ],
                columns: vec![
                    t.iter().map(|x| (w * x).sin()).collect(),
                    t.iter().map(|x| (w * x).cos()).collect(),
                ],
            }
        })
        .collect()
}

/// Steps of a quantiser tried per input: log-spaced, each this many times the last (fine
/// enough that the step of the 60th level from zero is met within a quarter of a step).
const QUANTUM_RATIO: f64 = 1.004;
/// The steps scanned span the input's range over this many steps at most and at least.
const QUANTUM_LEVELS: (f64, f64) = (500.0, 8.0);
/// An input must take at least this many distinct values for its steps to be told from
/// a table of its levels (a staircase command of eight levels can be made to say anything).
const QUANTUM_MIN_VALUES: usize = 64;
/// The scan's peaks are refined on a grid this many times finer (either way, a scan step).
const QUANTUM_REFINE: usize = 40;
/// Quantisers offered to the selection: the best few steps of the scan.
const QUANTUM_PEAKS: usize = 3;

/// What an actuator that delivers the input `u` (values `x` at the screen's samples, `y`
/// the missing signal there) in steps of `q` adds to it: `quantise(u, q) − u`, rounding,
/// or `q (⌊u/q⌋ + ½) − u`, the steps between the levels (with a constant: a converter that
/// truncates). The steps from 1/500 to 1/8 of the input's range are scanned
/// ([`QUANTUM_RATIO`]), each sized against `y` alone (with a constant), and the few that
/// explain most are refined ([`QUANTUM_REFINE`]) and become blocks whose step is a shape
/// parameter (bounded to one refined step either way: the error is not smooth in it).
fn quantisers(y: &[f64], a: &ActingSignal, x: &[f64], eu: &str) -> Vec<Block> {
    let Some(range) = span(x).filter(|_| y.len() == x.len()) else {
        return Vec::new();
    };
    let mut sorted = x.to_vec();
    sorted.sort_by(f64::total_cmp);
    sorted.dedup();
    if sorted.len() < QUANTUM_MIN_VALUES {
        return Vec::new();
    }
    let n = y.len() as f64;
    let y_mean = y.iter().sum::<f64>() / n;
    let (q_lo, q_hi) = (range / QUANTUM_LEVELS.0, range / QUANTUM_LEVELS.1);
    let count = ((q_hi / q_lo).ln() / QUANTUM_RATIO.ln()).ceil() as usize + 1;
    let step_error = |u: f64, q: f64, between: bool| {
        if between {
            q * ((u / q).floor() + 0.5) - u
        } else {
            q * (u / q).round() - u
        }
    };
    // The sum of squares of y each step explains, with a constant beside it.
    let power = |q: f64, between: bool| {
        let (mut s, mut ss, mut sy) = (0.0, 0.0, 0.0);
        for (&u, yi) in x.iter().zip(y) {
            let c = step_error(u, q, between);
            s += c;
            ss += c * c;
            sy += c * (yi - y_mean);
        }
        let cc = ss - s * s / n;
        if cc > 1e-12 * ss { sy * sy / cc } else { 0.0 }
    };
    let mut found: Vec<(f64, f64, bool)> = Vec::new();
    for between in [false, true] {
        let scan: Vec<(f64, f64)> = (0..count)
            .map(|i| {
                let q = q_lo * QUANTUM_RATIO.powi(i as i32);
                (q, power(q, between))
            })
            .collect();
        for i in 0..count {
            let left = i == 0 || scan[i].1 >= scan[i - 1].1;
            let right = i + 1 == count || scan[i].1 >= scan[i + 1].1;
            if left && right && scan[i].1 > 0.0 {
                found.push((scan[i].1, scan[i].0, between));
            }
        }
    }
    found.sort_by(|p, q| q.0.total_cmp(&p.0));
    found.truncate(QUANTUM_PEAKS);
    // Each peak refined within a grid step either way: the step of the n-th level is
    // off by n times the step's error, so it must be known far better than the grid.
    let fine = QUANTUM_RATIO.ln() / QUANTUM_REFINE as f64;
    for (p, q, between) in &mut found {
        let q0 = *q;
        for i in -(QUANTUM_REFINE as i32)..=QUANTUM_REFINE as i32 {
            let qi = q0 * (fine * i as f64).exp();
            let pi = power(qi, *between);
            if pi > *p {
                (*p, *q) = (pi, qi);
            }
        }
    }
    let (name, label, unit) = (&a.name, &a.label, &a.unit);
    found
        .into_iter()
        .map(|(_, q, between)| {
            let (text, expr) = if between {
                (
                    format!("({label} in steps of § between the levels − {label})"),
                    format!("(quantise({name} - 0.5 * §, §) + 0.5 * § - {name})"),
                )
            } else {
                (
                    format!("({label} in steps of § − {label})"),
                    format!("(quantise({name}, §) - {name})"),
                )
            };
            let (q_min, q_max) = (q * (-fine).exp(), q * fine.exp());
            Block {
                family: Family::Quantiser,
                member: name.clone(),
                scanned: 2 * count,
                terms: vec![shaped(
                    term("c_quant", Family::Quantiser, text, expr, per(eu, unit)),
                    "q",
                    unit,
                    q,
                    q_min,
                    q_max,
                )],
                columns: vec![x.iter().map(|&u| step_error(u, q, between)).collect()],
            }
        })
        .collect()
}

/// `a/(b)`, `a/b` for a simple unit, or `a` when `b` is dimensionless.
fn per(a: &str, b: &str) -> String {
    if b.is_empty() || b == "1" {
        a.to_string()
    } else if b.contains(' ') || b.contains('/') || b.contains('^') {
        format!("{a}/({b})")
    } else {
        format!("{a}/{b}")
    }
}

/// Four significant digits, in exponent form when very small or large.
pub(super) fn sig(x: f64) -> String {
    let a = x.abs();
    if a != 0.0 && !(1e-3..1e4).contains(&a) {
        format!("{x:.3e}")
    } else {
        format!("{x:.4}")
    }
}

pub(super) fn num(x: f64) -> String {
    format!("{x:.4e}")
}

pub(super) fn rms_of(x: &[f64]) -> f64 {
    (x.iter().map(|v| v * v).sum::<f64>() / x.len().max(1) as f64).sqrt()
}

/// The widths `ε` a sign term `tanh(v/ε)` of a flow of RMS `scale` is
/// scanned over, with the bounds its confirming fit keeps them in: from
/// sharp to smooth, 19 widths log-spaced over 0.05 % … 30 % of the RMS (each
/// 1.43 times the last: a sharp friction's width is met within 20 %, so no
/// second term is needed to mend the shape).
fn sign_widths(scale: f64) -> (Vec<f64>, f64, f64) {
    let eps: Vec<f64> = (0..19)
        .map(|i| scale * 5e-4 * (600.0_f64).powf(i as f64 / 18.0))
        .collect();
    let (lo, hi) = (eps[0] / 3.0, eps[eps.len() - 1] * 3.0);
    (eps, lo, hi)
}

/// The library at a place, evaluated on the (decimated) samples `idx`.
fn library(m: &MissingSignal, idx: &[usize]) -> Vec<Block> {
    let t: Vec<f64> = idx.iter().map(|&k| m.t[k]).collect();
    let mut out = vec![Block {
        family: Family::Constant,
        member: String::new(),
        scanned: 1,
        terms: vec![term(
            "c_const",
            Family::Constant,
            "1".into(),
            "1".into(),
            m.unit.clone(),
        )],
        columns: vec![vec![1.0; t.len()]],
    }];
    let single = |family, member: &str, scanned, term: LawTerm, col: Vec<f64>| Block {
        family,
        member: member.to_string(),
        scanned,
        terms: vec![term],
        columns: vec![col],
    };
    for a in &m.acting {
        let v: Vec<f64> = idx.iter().map(|&k| a.values[k]).collect();
        let scale = rms_of(&v);
        if !(scale.is_finite() && scale > 0.0) {
            continue;
        }
        // Names are made unique within a law when it is built.
        let (n, u, eu) = (&a.name, &a.unit, &m.unit);
        let linear = |name: &str| {
            single(
                Family::Linear,
                n,
                1,
                term(
                    &format!("c_{name}"),
                    Family::Linear,
                    a.label.clone(),
                    n.clone(),
                    per(eu, u),
                ),
                v.clone(),
            )
        };
        let sq = if u.is_empty() {
            String::new()
        } else {
            format!("({u})^2")
        };
        let cube = if u.is_empty() {
            String::new()
        } else {
            format!("({u})^3")
        };
        // `v·|v|` (drag on a flow, a one-sided spring on a displacement) and `v³`.
        let quadratic = |name: &str| {
            single(
                Family::QuadraticDrag,
                n,
                1,
                term(
                    &format!("c_{name}"),
                    Family::QuadraticDrag,
                    format!("{0} · |{0}|", a.label),
                    format!("{n} * abs({n})"),
                    per(eu, &sq),
                ),
                v.iter().map(|x| x * x.abs()).collect(),
            )
        };
        let cubic = || {
            single(
                Family::Cubic,
                n,
                1,
                term(
                    "c_cubic",
                    Family::Cubic,
                    format!("{}³", a.label),
                    format!("{n}^3"),
                    per(eu, &cube),
                ),
                v.iter().map(|x| x * x * x).collect(),
            )
        };
        match a.role {
            SignalRole::Flow => {
                out.push(linear("lin"));
                let (eps, elo, ehi) = sign_widths(scale);
                // Coulomb friction, `tanh(v/ε)`; then, over the same widths, the level friction
                // takes while moving either way, `|tanh(v/ε)|` (with a sign term: Coulomb
                // friction that differs by direction).
                let tanh_scans: [(Family, &str, String, String, bool); 2] = [
                    (
                        Family::Sign,
                        "c_sign",
                        format!("tanh({} / §)", a.label),
                        format!("tanh({n} / §)"),
                        false,
                    ),
                    (
                        Family::SignMagnitude,
                        "c_smag",
                        format!("|tanh({} / §)|", a.label),
                        format!("abs(tanh({n} / §))"),
                        true,
                    ),
                ];
                for (family, param, label, expr, magnitude) in tanh_scans {
                    for &e in &eps {
                        out.push(single(
                            family,
                            n,
                            eps.len(),
                            shaped(
                                term(param, family, label.clone(), expr.clone(), eu.clone()),
                                "eps",
                                u,
                                e,
                                elo,
                                ehi,
                            ),
                            v.iter()
                                .map(|x| {
                                    let s = (x / e).tanh();
                                    if magnitude { s.abs() } else { s }
                                })
                                .collect(),
                        ));
                    }
                }
                let sharp = 0.003 * scale;
                // Stribeck speeds: eight, log-spaced over 1 % … 60 % of the RMS flow.
                let vs_grid: Vec<f64> = (0..8)
                    .map(|i| scale * 0.01 * (60.0_f64).powf(i as f64 / 7.0))
                    .collect();
                let (vlo, vhi) = (vs_grid[0] / 3.0, vs_grid[vs_grid.len() - 1] * 3.0);
                for &vs in &vs_grid {
                    out.push(single(
                        Family::Stribeck,
                        n,
                        vs_grid.len(),
                        shaped(
                            term(
                                "c_stribeck",
                                Family::Stribeck,
                                format!("tanh({0} / {sharp:.3e} {u}) · exp(−({0} / §)²)", a.label),
                                format!("tanh({n} / {}) * exp(-({n} / §)^2)", num(sharp)),
                                eu.clone(),
                            ),
                            "vs",
                            u,
                            vs,
                            vlo,
                            vhi,
                        ),
                        v.iter()
                            .map(|x| (x / sharp).tanh() * (-(x / vs).powi(2)).exp())
                            .collect(),
                    ));
                }
                out.push(quadratic("drag"));
                out.push(cubic());
                out.push(single(
                    Family::Absolute,
                    n,
                    1,
                    term(
                        "c_abs",
                        Family::Absolute,
                        format!("|{}|", a.label),
                        format!("abs({n})"),
                        per(eu, u),
                    ),
                    v.iter().map(|x| x.abs()).collect(),
                ));
            }
            SignalRole::Displacement => {
                out.push(linear("lin"));
                out.push(cubic());
                out.push(quadratic("quad"));
                out.extend(hinges(a, &v, eu));
            }
            SignalRole::Position => {
                out.push(linear("lin"));
                out.push(cubic());
                out.push(quadratic("quad"));
                out.extend(hinges(a, &v, eu));
                let y: Vec<f64> = idx.iter().map(|&k| m.value[k]).collect();
                out.extend(ripples(&y, a, &v, eu));
            }
            SignalRole::Angle => {
                for order in 1..=MAX_HARMONIC {
                    let k = order as f64;
                    out.push(Block {
                        family: Family::Harmonic,
                        member: format!("{n}#{order}"),
                        scanned: MAX_HARMONIC,
                        terms: vec![
                            term(
                                &format!("c_sin{order}"),
                                Family::Harmonic,
                                format!("sin({order} · {})", a.label),
                                format!("sin({order} * {n})"),
                                eu.clone(),
                            ),
                            term(
                                &format!("c_cos{order}"),
                                Family::Harmonic,
                                format!("cos({order} · {})", a.label),
                                format!("cos({order} * {n})"),
                                eu.clone(),
                            ),
                        ],
                        columns: vec![
                            v.iter().map(|x| (k * x).sin()).collect(),
                            v.iter().map(|x| (k * x).cos()).collect(),
                        ],
                    });
                }
            }
            SignalRole::Effort => {
                out.push(linear("lin"));
                out.push(single(
                    Family::SquareRoot,
                    n,
                    1,
                    term(
                        "c_sqrt",
                        Family::SquareRoot,
                        format!("√{}", a.label),
                        format!("sqrt(max({n}, 0))"),
                        if u.is_empty() {
                            eu.clone()
                        } else {
                            format!("{eu}/({u})^0.5")
                        },
                    ),
                    v.iter().map(|x| x.max(0.0).sqrt()).collect(),
                ));
                // A power law of the effort, its exponent scanned: seepage (1.1–1.3), an
                // outflow between laminar and turbulent, natural convection (1.25–1.33).
                let (plo, phi) = (POWERS[0] / 1.5, POWERS[POWERS.len() - 1] * 1.5);
                for &p in &POWERS {
                    out.push(single(
                        Family::Power,
                        n,
                        POWERS.len(),
                        shaped(
                            term(
                                "c_pow",
                                Family::Power,
                                format!("sign({0}) |{0}|^§", a.label),
                                format!("sign({n}) * abs({n})^§"),
                                if u.is_empty() {
                                    eu.clone()
                                } else {
                                    format!("{eu}/({u})^p")
                                },
                            ),
                            "p",
                            "1",
                            p,
                            plo,
                            phi,
                        ),
                        v.iter().map(|x| x.signum() * x.abs().powf(p)).collect(),
                    ));
                }
            }
            // An input's gain is the menu's typed `gain@` effect on its source; as a law
            // term beside steps it mimics a sign of the flow under a staircase drive.
            // What an actuator's steps add to its command is not on the menu.
            SignalRole::Input => {
                let y: Vec<f64> = idx.iter().map(|&k| m.value[k]).collect();
                out.extend(quantisers(&y, a, &v, eu));
            }
            // Alone, a flow one transducer away is the transducer's modulus: it scales.
            SignalRole::Coupled => {}
        }
    }
    out.extend(products(m, idx));
    let y: Vec<f64> = idx.iter().map(|&k| m.value[k]).collect();
    let inputs: Vec<Vec<f64>> = (m.acting.iter())
        .filter(|a| a.role == SignalRole::Input)
        .map(|a| idx.iter().map(|&k| a.values[k]).collect())
        .collect();
    out.extend(periodics(&y, &t, &inputs, &m.unit));
    // Steps and ramps scanned over interior times (not within 5 % of either end).
    if let (Some(&t0), Some(&t1)) = (t.first(), t.last()) {
        let span = t1 - t0;
        if span > 0.0 {
            for i in 1..=TIME_SCAN {
                let ts = t0 + span * (0.05 + 0.9 * (i - 1) as f64 / (TIME_SCAN - 1) as f64);
                let (lo, hi) = (t0 + 0.02 * span, t1 - 0.02 * span);
                out.push(single(
                    Family::Step,
                    "t",
                    TIME_SCAN,
                    shaped(
                        term(
                            "c_step",
                            Family::Step,
                            "H(t − §)".to_string(),
                            "max(sign(t - §), 0)".to_string(),
                            m.unit.clone(),
                        ),
                        "t",
                        "s",
                        ts,
                        lo,
                        hi,
                    ),
                    t.iter().map(|&x| if x > ts { 1.0 } else { 0.0 }).collect(),
                ));
                out.push(single(
                    Family::Ramp,
                    "t",
                    TIME_SCAN,
                    shaped(
                        term(
                            "c_ramp",
                            Family::Ramp,
                            "max(t − §, 0)".to_string(),
                            "max(t - §, 0)".to_string(),
                            per(&m.unit, "s"),
                        ),
                        "t",
                        "s",
                        ts,
                        lo,
                        hi,
                    ),
                    t.iter().map(|&x| (x - ts).max(0.0)).collect(),
                ));
            }
        }
    }
    out
}

/// Where a hinge may start, per side: this many points from the 5 % to the 95 % quantile
/// of the signal.
const HINGE_SCAN: usize = 15;

/// The hinge family on a position or displacement `x` (values `v`): `max(x − x₀, 0)` and
/// `min(x − x₀, 0)` with `x₀` scanned over [`HINGE_SCAN`] quantiles — a stop, a bump
/// stop or a second spring that engages past `x₀` (a spring stiffer one way than the
/// other: `x₀` = 0), a gap that closes. `x₀` is a shape parameter within the signal's
/// range.
fn hinges(a: &ActingSignal, v: &[f64], eu: &str) -> Vec<Block> {
    let mut sorted: Vec<f64> = v.iter().copied().filter(|x| x.is_finite()).collect();
    if sorted.len() < 2 * HINGE_SCAN {
        return Vec::new();
    }
    sorted.sort_by(f64::total_cmp);
    let quantile = |q: f64| sorted[((sorted.len() - 1) as f64 * q).round() as usize];
    let (lo, hi) = (sorted[0], sorted[sorted.len() - 1]);
    if hi <= lo {
        return Vec::new();
    }
    let (n, u) = (&a.name, &a.unit);
    let mut out = Vec::new();
    for i in 0..HINGE_SCAN {
        let x0 = quantile(0.05 + 0.9 * i as f64 / (HINGE_SCAN - 1) as f64);
        for (param, f, upper) in [("c_above", "max", true), ("c_below", "min", false)] {
            out.push(Block {
                family: Family::Hinge,
                member: n.clone(),
                scanned: 2 * HINGE_SCAN,
                terms: vec![shaped(
                    term(
                        param,
                        Family::Hinge,
                        format!("{f}({} − §, 0)", a.label),
                        format!("{f}({n} - §, 0)"),
                        per(eu, u),
                    ),
                    "x0",
                    u,
                    x0,
                    lo,
                    hi,
                )],
                columns: vec![
                    v.iter()
                        .map(|&x| {
                            if upper {
                                (x - x0).max(0.0)
                            } else {
                                (x - x0).min(0.0)
                            }
                        })
                        .collect(),
                ],
            });
        }
    }
    out
}

/// The product family: for every two signals acting at the place (flows,
/// positions, displacements, efforts), `a·b`, `a·|b|`, `|a|·b`, `a²·b` and
/// `a·b²` (each odd in one of them, so that it is not a constant in
/// disguise) — a flow one transducer away among them, the winding's current
/// at a shaft — and for an angle with every other signal, `b·sin nθ` and
/// `b·cos nθ` (n in 1..=[`MAX_PRODUCT_HARMONIC`]), and for an input `u`
/// with every signal, `u·b` and, with a flow, `u·tanh(f/ε)` over the sign's
/// widths, and the time with the place's own flow, `t·f` (a loss that drifts
/// over the run). One family, one member per law: its size is the
/// multiple-comparison cost of taking any.
fn products(m: &MissingSignal, idx: &[usize]) -> Vec<Block> {
    let varying = |a: &&ActingSignal| {
        let v: Vec<f64> = idx.iter().map(|&k| a.values[k]).collect();
        let s = rms_of(&v);
        s.is_finite() && s > 0.0
    };
    let plain: Vec<&ActingSignal> = (m.acting.iter())
        .filter(|a| a.role.is_plain() || a.role == SignalRole::Coupled)
        .filter(varying)
        .collect();
    let angles: Vec<&ActingSignal> = (m.acting.iter())
        .filter(|a| a.role == SignalRole::Angle)
        .filter(varying)
        .collect();
    let col = |a: &ActingSignal| -> Vec<f64> { idx.iter().map(|&k| a.values[k]).collect() };
    let power = |u: &str, p: u32| match (u.is_empty(), p) {
        (true, _) => String::new(),
        (false, 1) => u.to_string(),
        (false, _) => format!("({u})^{p}"),
    };
    let times = |a: &str, b: &str| match (a.is_empty(), b.is_empty()) {
        (true, _) => b.to_string(),
        (_, true) => a.to_string(),
        _ => format!("{a} {b}"),
    };
    let eu = &m.unit;
    // Each factor form of a signal: x, |x|, x².
    struct Factor {
        label: String,
        expr: String,
        unit: String,
        odd: bool,
        values: Vec<f64>,
    }
    let factors = |a: &ActingSignal| -> Vec<Factor> {
        let v = col(a);
        let (n, l, u) = (&a.name, &a.label, &a.unit);
        vec![
            Factor {
                label: l.clone(),
                expr: n.clone(),
                unit: power(u, 1),
                odd: true,
                values: v.clone(),
            },
            Factor {
                label: format!("|{l}|"),
                expr: format!("abs({n})"),
                unit: power(u, 1),
                odd: false,
                values: v.iter().map(|x| x.abs()).collect(),
            },
            Factor {
                label: format!("({l})²"),
                expr: format!("{n}^2"),
                unit: power(u, 2),
                odd: false,
                values: v.iter().map(|x| x * x).collect(),
            },
        ]
    };
    // `x·y`, one term.
    let product = |x: &Factor, y: &Factor| {
        (
            format!("{}*{}", x.expr, y.expr),
            vec![term(
                "c_prod",
                Family::Product,
                format!("{} · {}", x.label, y.label),
                format!("{} * {}", x.expr, y.expr),
                per(eu, &times(&x.unit, &y.unit)),
            )],
            vec![x.values.iter().zip(&y.values).map(|(p, q)| p * q).collect()],
        )
    };
    let mut blocks: Vec<(String, Vec<LawTerm>, Vec<Vec<f64>>)> = Vec::new();
    for (i, a) in plain.iter().enumerate() {
        for b in &plain[i + 1..] {
            let (fa, fb) = (factors(a), factors(b));
            for x in &fa {
                for y in &fb {
                    // Odd in one of them at least: |a|·|b|, a²·|b| and a²·b² are positive
                    // throughout, a constant in disguise.
                    if !x.odd && !y.odd {
                        continue;
                    }
                    blocks.push(product(x, y));
                }
            }
        }
    }
    for th in &angles {
        let angle = col(th);
        for b in &plain {
            let v = col(b);
            for order in 1..=MAX_PRODUCT_HARMONIC {
                let k = order as f64;
                let unit = per(eu, &b.unit);
                blocks.push((
                    format!("{}#{order}*{}", th.name, b.name),
                    vec![
                        term(
                            &format!("c_{order}sin"),
                            Family::Product,
                            format!("{} · sin({order} · {})", b.label, th.label),
                            format!("{} * sin({order} * {})", b.name, th.name),
                            unit.clone(),
                        ),
                        term(
                            &format!("c_{order}cos"),
                            Family::Product,
                            format!("{} · cos({order} · {})", b.label, th.label),
                            format!("{} * cos({order} * {})", b.name, th.name),
                            unit,
                        ),
                    ],
                    vec![
                        v.iter()
                            .zip(&angle)
                            .map(|(x, q)| x * (k * q).sin())
                            .collect(),
                        v.iter()
                            .zip(&angle)
                            .map(|(x, q)| x * (k * q).cos())
                            .collect(),
                    ],
                ));
            }
        }
    }
    // An input that switches or scales an effect at the place: `u·b` for every signal, and
    // `u·tanh(f/ε)` for a flow over the sign's widths (a diode that conducts while a
    // switch is open, `(1 − m)·V_d·sign(i)`: beside the sign term, `m·tanh(i/ε)`).
    let inputs: Vec<&ActingSignal> = (m.acting.iter())
        .filter(|a| a.role == SignalRole::Input)
        .filter(varying)
        .collect();
    for u in &inputs {
        let (uf, uv) = (&factors(u)[0], col(u));
        for b in &plain {
            let bv = col(b);
            blocks.push(product(uf, &factors(b)[0]));
            if b.role != SignalRole::Flow {
                continue;
            }
            let (eps, lo, hi) = sign_widths(rms_of(&bv));
            for e in eps {
                blocks.push((
                    format!("{}*tanh({})", u.name, b.name),
                    vec![shaped(
                        term(
                            "c_prod",
                            Family::Product,
                            format!("{} · tanh({} / §)", u.label, b.label),
                            format!("{} * tanh({} / §)", u.name, b.name),
                            per(eu, &u.unit),
                        ),
                        "eps",
                        &b.unit,
                        e,
                        lo,
                        hi,
                    )],
                    vec![
                        uv.iter()
                            .zip(&bv)
                            .map(|(p, q)| p * (q / e).tanh())
                            .collect(),
                    ],
                ));
            }
        }
    }
    // A loss that drifts over the run (a bearing's grease warming, wear): `t·f`, `f` the
    // place's own flow and `t` the recording's time. (With every signal, `t·i` at a shaft
    // took a share of Coulomb friction beside a brush drop.)
    let time: Vec<f64> = idx.iter().map(|&k| m.t[k]).collect();
    for b in plain.iter().filter(|a| a.role == SignalRole::Flow) {
        blocks.push((
            format!("t*{}", b.name),
            vec![term(
                "c_prod",
                Family::Product,
                format!("t · {}", b.label),
                format!("t * {}", b.name),
                per(eu, &times("s", &b.unit)),
            )],
            vec![time.iter().zip(col(b)).map(|(p, q)| p * q).collect()],
        ));
    }
    let scanned = blocks.len();
    blocks
        .into_iter()
        .map(|(member, terms, columns)| Block {
            family: Family::Product,
            member,
            scanned,
            terms,
            columns,
        })
        .collect()
}

/// Weighted least squares of `y` on the columns `cols` (weights `w`):
/// coefficients, their unscaled covariance diagonal and the weighted RSS.
fn wls(cols: &[&[f64]], y: &[f64], w: &[f64]) -> Option<(Vec<f64>, Vec<f64>, f64)> {
    let k = cols.len();
    let n = y.len();
    let mut a = nalgebra::DMatrix::<f64>::zeros(k, k);
    let mut b = nalgebra::DVector::<f64>::zeros(k);
    for i in 0..k {
        for j in 0..=i {
            let mut s = 0.0;
            for r in 0..n {
                s += w[r] * cols[i][r] * cols[j][r];
            }
            a[(i, j)] = s;
            a[(j, i)] = s;
        }
        b[i] = (0..n).map(|r| w[r] * cols[i][r] * y[r]).sum();
    }
    // Columns scaled to unit norm for the solve: a badly scaled cubic next to a constant.
    let d: Vec<f64> = (0..k).map(|i| a[(i, i)].sqrt().max(1e-300)).collect();
    let scaled = nalgebra::DMatrix::from_fn(k, k, |i, j| a[(i, j)] / (d[i] * d[j]));
    let chol = scaled.cholesky()?;
    let sb = nalgebra::DVector::from_fn(k, |i, _| b[i] / d[i]);
    let beta_s = chol.solve(&sb);
    let inv = chol.inverse();
    let beta: Vec<f64> = (0..k).map(|i| beta_s[i] / d[i]).collect();
    let var: Vec<f64> = (0..k).map(|i| inv[(i, i)] / (d[i] * d[i])).collect();
    let mut rss = 0.0;
    for r in 0..n {
        let fit: f64 = (0..k).map(|i| beta[i] * cols[i][r]).sum();
        rss += w[r] * (y[r] - fit).powi(2);
    }
    (beta.iter().all(|b| b.is_finite()) && rss.is_finite()).then_some((beta, var, rss))
}

/// Effective independent samples in a smooth series: `n (1 − ρ)/(1 + ρ)`
/// from its lag-1 correlation.
fn effective(r: &[f64]) -> f64 {
    let n = r.len();
    if n < 4 {
        return n as f64;
    }
    let c0: f64 = r.iter().map(|x| x * x).sum();
    if c0 <= 0.0 {
        return n as f64;
    }
    let c1: f64 = r.windows(2).map(|w| w[0] * w[1]).sum();
    let rho = (c1 / c0).clamp(0.0, 0.999);
    (n as f64 * (1.0 - rho) / (1.0 + rho)).max(2.0)
}

/// The law the missing signal follows, or `None` when no term earns its place.
pub fn screen(m: &MissingSignal) -> Option<Law> {
    screen_with(m, true)
}

/// [`screen`], with or without the linear family: a model whose free
/// parameters are calibrated with every candidate already has its linear
/// terms (a stiffness, a damping, a gain that are free), and a law's linear
/// term beside them would be the same parameter twice. Without it, the
/// linear terms are still regressed out first, as nuisance (the missing
/// effort and every term made orthogonal to them): the calibration has
/// already taken the best linear part of a law (a linear spring calibrated
/// on a hardening one is stiffer than it is), and the law's coefficients are
/// those it has beside a linear term that the joint fit re-adjusts.
pub fn screen_with(m: &MissingSignal, linear: bool) -> Option<Law> {
    screen_laws(m, linear).into_iter().next()
}

/// The laws the screen offers at a place, best first: [`screen_with`]'s,
/// and a runner-up when a law starting from a formula of the symbolic
/// search and the typed library's law are within the search's cost and one
/// parameter of each other (the confirming fits by simulation decide).
pub fn screen_laws(m: &MissingSignal, linear: bool) -> Vec<Law> {
    let n_all = m.value.len();
    if n_all < 20 || m.t.len() != n_all || m.band.len() != n_all {
        return Vec::new();
    }
    let stride = n_all.div_ceil(MAX_SAMPLES).max(1);
    // The first and last few samples carry the smoother's start-up: left out.
    let skip = (n_all / 50).min(200);
    let idx: Vec<usize> = (skip..n_all - skip).step_by(stride).collect();
    if idx.len() < 20 {
        return Vec::new();
    }
    let y: Vec<f64> = idx.iter().map(|&k| m.value[k]).collect();
    if y.iter().any(|v| !v.is_finite()) {
        return Vec::new();
    }
    let mut bands: Vec<f64> = idx.iter().map(|&k| m.band[k]).collect();
    let median = {
        let mut b: Vec<f64> = bands.iter().copied().filter(|v| v.is_finite()).collect();
        b.sort_by(f64::total_cmp);
        b.get(b.len() / 2).copied().unwrap_or(1.0).max(1e-300)
    };
    for b in &mut bands {
        if !b.is_finite() {
            *b = f64::INFINITY;
        }
    }
    // Samples pinned worse than typical are weighed down; better ones are not raised.
    let w: Vec<f64> = bands
        .iter()
        .map(|b| (median / b.max(median)).powi(2))
        .collect();
    let mut lib = library(m, &idx);
    // Each block's columns as built, for the law's values: those regressed on may be made
    // orthogonal to the nuisance below.
    let mut y = y;
    let mut raw: Vec<Vec<Vec<f64>>> = Vec::new();
    let mut nuisance: Vec<Vec<f64>> = Vec::new();
    if !linear {
        nuisance = (lib.iter())
            .filter(|b| b.family == Family::Linear)
            .flat_map(|b| b.columns.iter().cloned())
            .collect();
        lib.retain(|b| b.family != Family::Linear);
        raw = lib.iter().map(|b| b.columns.clone()).collect();
        let refs: Vec<&[f64]> = nuisance.iter().map(Vec::as_slice).collect();
        if !refs.is_empty() {
            orthogonalise(&refs, &mut y, &w);
            for b in &mut lib {
                for col in &mut b.columns {
                    orthogonalise(&refs, col, &w);
                }
            }
        }
    }
    let y = y;
    let n = idx.len();
    let total: f64 = (0..n).map(|r| w[r] * y[r] * y[r]).sum();
    if total.is_nan() || total <= 0.0 {
        return Vec::new();
    }
    let typed = 0..lib.len();
    let wsum = w.iter().sum::<f64>().max(1e-300);
    // Forward selection over the typed library, from the blocks `chosen` (leaving `rss`).
    let greedy = |lib: &[Block], mut chosen: Vec<usize>, mut rss: f64| -> (Vec<usize>, f64) {
        while chosen.len() < MAX_BLOCKS {
            let residual = left_by(lib, &chosen, &y, &w);
            if let Some((bi, r)) = next_block(lib, &chosen, typed.clone(), &y, &w, rss, &residual) {
                chosen.push(bi);
                rss = r;
            } else if let Some((first, second, r)) = (chosen.len() + 2 <= MAX_BLOCKS)
                .then(|| next_pair(lib, &chosen, &y, &w, rss))
                .flatten()
            {
                chosen.extend([first, second]);
                rss = r;
            } else {
                break;
            }
        }
        (chosen, rss)
    };
    // The symbolic search's best formulas against `residual`, made orthogonal to the
    // blocks `chosen` and the nuisance, added to the library: their indices.
    let mut symbolic_blocks = |lib: &mut Vec<Block>, chosen: &[usize], residual: &[f64]| {
        let mut against: Vec<&[f64]> = nuisance.iter().map(Vec::as_slice).collect();
        against.extend((chosen.iter()).flat_map(|&c| lib[c].columns.iter().map(Vec::as_slice)));
        let (found, searched) = symbolic::search(m, &idx, residual, &w, &against);
        let first = lib.len();
        let refs: Vec<&[f64]> = nuisance.iter().map(Vec::as_slice).collect();
        for (t, col) in found {
            let mut b = Block {
                family: Family::Symbolic,
                member: String::new(),
                scanned: searched,
                terms: vec![t],
                columns: vec![col],
            };
            if !linear {
                raw.push(b.columns.clone());
            }
            if !refs.is_empty() {
                for col in &mut b.columns {
                    orthogonalise(&refs, col, &w);
                }
            }
            lib.push(b);
        }
        first..lib.len()
    };
    let (mut chosen, mut rss) = greedy(&lib, Vec::new(), total);
    // Whether the typed law leaves what the estimate's own noise would: its weighted mean
    // square within the band's, plus three standard errors of a mean square of that many
    // effective samples.
    let within_band = {
        let n_e = effective(&left_by(&lib, &chosen, &y, &w)).max(2.0);
        rss / wsum <= median * median * (1.0 + 3.0 * (2.0 / n_e).sqrt())
    };
    // Several typed terms for one place may be mimicking a shape the library lacks.
    let mimicking = chosen.len() >= symbolic::MIMICRY_TERMS;
    // When the typed library leaves more than the band, a symbolic search offers the
    // formula that explains most of what is left; it joins the law by the same rules (its
    // whole search counted as its scan), at most once.
    if !within_band {
        let residual = left_by(&lib, &chosen, &y, &w);
        let offered = symbolic_blocks(&mut lib, &chosen, &residual);
        if let Some((bi, r)) = next_block(&lib, &chosen, offered, &y, &w, rss, &residual) {
            chosen.push(bi);
            rss = r;
        }
    }
    // A law that starts from a formula may say with one term what the typed library says
    // with several (an eddy-current brake's peak, mimicked by a wide sign, a negative drag
    // and a cubic), or explain what it leaves: the two compete by the information
    // criterion, the formula's whole search counted as its scan. A typed law that loses is
    // offered too, and a formula that loses when it is within that scan's cost and one
    // parameter and leaves no more than the typed law (the screen's criterion then cannot
    // tell them apart, a simulation can; a formula that explains less, `atan ω` beside
    // Coulomb friction and a brush drop, only reshuffled what the pairs were made of). Where the typed law leaves only the band with
    // few terms there is no contest: a formula would only bend a named law's shape (a
    // Stribeck excess, found on what Coulomb friction leaves, was pre-empted by `atan`).
    let mut runner_up: Option<Vec<usize>> = None;
    if !within_band || mimicking {
        let offered = symbolic_blocks(&mut lib, &[], &y);
        if let Some((bi, r)) = next_block(&lib, &[], offered, &y, &w, total, &y) {
            let searched = lib[bi].scanned as f64;
            let (other, other_rss) = greedy(&lib, vec![bi], r);
            let n_e = effective(&left_by(&lib, &chosen, &y, &w))
                .max(effective(&left_by(&lib, &other, &y, &w)));
            let criterion = |chosen: &[usize], rss: f64| {
                n_e * rss.max(1e-300).ln()
                    + (chosen.iter())
                        .map(|&c| {
                            let b = &lib[c];
                            let shaped = b.terms.iter().filter(|t| t.shape.is_some()).count();
                            (b.columns.len() + shaped) as f64 * n_e.max(2.0).ln()
                                + 2.0 * (b.scanned as f64).ln()
                        })
                        .sum::<f64>()
            };
            let (typed_c, other_c) = (criterion(&chosen, rss), criterion(&other, other_rss));
            let margin = 2.0 * searched.ln() + n_e.max(2.0).ln();
            if chosen.is_empty() || other_c < typed_c {
                // The typed law stays on offer: a formula of two signals can follow the
                // screen's estimate better than the simulation (a drive's position stands in
                // for its direction of travel).
                runner_up = Some(std::mem::replace(&mut chosen, other)).filter(|c| !c.is_empty());
            } else if other_c < typed_c + margin && other_rss <= rss {
                runner_up = Some(other);
            }
        }
    }
    let built = Built {
        m,
        idx: &idx,
        lib: &lib,
        raw: &raw,
        y: &y,
        w: &w,
        total,
    };
    let out: Vec<Law> = std::iter::once(chosen)
        .chain(runner_up)
        .filter_map(|chosen| built.law(&chosen))
        .collect();
    out
}

/// What a law is made from: the place, the screen's samples, the library's
/// blocks (and their columns as built, when those regressed on were made
/// orthogonal to a nuisance), the estimate, the weights and its weighted
/// sum of squares.
struct Built<'a> {
    m: &'a MissingSignal,
    idx: &'a [usize],
    lib: &'a [Block],
    raw: &'a [Vec<Vec<f64>>],
    y: &'a [f64],
    w: &'a [f64],
    total: f64,
}

impl Built<'_> {
    /// The law of the blocks `chosen`: coefficients, their standard errors
    /// (effective samples counted), unique names, the share explained.
    fn law(&self, chosen: &[usize]) -> Option<Law> {
        let Built {
            m,
            idx,
            lib,
            raw,
            y,
            w,
            total,
        } = *self;
        if chosen.is_empty() {
            return None;
        }
        let n = idx.len();
        let residual = left_by(lib, chosen, y, w);
        let cols = design(lib, chosen);
        let (beta, var, rss) = wls(&cols, y, w)?;
        // The law's own values: its terms as built (not made orthogonal to the nuisance).
        let built: Vec<&[f64]> = if raw.is_empty() {
            cols.clone()
        } else {
            (chosen.iter())
                .flat_map(|&c| raw[c].iter().map(Vec::as_slice))
                .collect()
        };
        let fitted: Vec<(usize, f64)> = (0..n)
            .map(|r| (idx[r], (0..beta.len()).map(|i| beta[i] * built[i][r]).sum()))
            .collect();
        let n_eff = effective(&residual).min(n as f64);
        let dof = (n_eff - beta.len() as f64).max(1.0);
        let wsum: f64 = w.iter().sum::<f64>().max(1e-300);
        // σ² per unit weight, counted in effective samples.
        let s2 = rss / wsum * (n as f64) / dof;
        let mut terms: Vec<LawTerm> = Vec::new();
        let mut i = 0;
        for &c in chosen {
            let columns = if raw.is_empty() {
                &lib[c].columns
            } else {
                &raw[c]
            };
            for (t, col) in lib[c].terms.iter().zip(columns) {
                let mut t = t.clone();
                t.coefficient = beta[i];
                t.std_error = (var[i] * s2).sqrt();
                t.term_max = col.iter().fold(0.0_f64, |a, v| a.max(v.abs()));
                terms.push(t);
                i += 1;
            }
        }
        // Parameter names unique within the law.
        let mut seen: Vec<String> = Vec::new();
        for t in &mut terms {
            let mut name = t.param.clone();
            let mut k = 2;
            while seen.contains(&name) {
                name = format!("{}_{k}", t.param);
                k += 1;
            }
            t.param = name.clone();
            if let Some(sh) = t.shape.as_mut() {
                // `eps_sign`, `vs_stribeck_2`, `t_step`: the shape's stem and the term's name.
                sh.name = format!("{}{}", sh.name, name.trim_start_matches('c'));
            }
            seen.push(name);
        }
        Some(Law {
            location: m.location.clone(),
            place: m.place.clone(),
            quantity: m.quantity,
            unit: m.unit.clone(),
            terms,
            explained: (1.0 - rss / total).clamp(0.0, 1.0),
            residual_rms: (rss / wsum).sqrt(),
            missing_max: y.iter().fold(0.0_f64, |a, v| a.max(v.abs())),
            effective_samples: n_eff,
            fitted,
        })
    }
}

/// The columns of the blocks `chosen`, in order.
fn design<'a>(lib: &'a [Block], chosen: &[usize]) -> Vec<&'a [f64]> {
    (chosen.iter())
        .flat_map(|&c| lib[c].columns.iter().map(Vec::as_slice))
        .collect()
}

/// What the law made of the blocks `chosen` leaves of `y` (its weighted least squares).
fn left_by(lib: &[Block], chosen: &[usize], y: &[f64], w: &[f64]) -> Vec<f64> {
    let cols = design(lib, chosen);
    match wls(&cols, y, w) {
        Some((beta, _, _)) => (0..y.len())
            .map(|r| y[r] - (0..beta.len()).map(|i| beta[i] * cols[i][r]).sum::<f64>())
            .collect(),
        None => y.to_vec(),
    }
}

/// One step of the forward selection: of the blocks `offered` whose family the law does
/// not have yet, the one that lowers the weighted residual sum of squares (`rss`, leaving
/// `residual`) most, with that sum — if it earns its place: its gain beats the
/// information criterion counted in effective samples plus its scan's size, it removes a
/// tenth of what is left (a product or a formula a third), and its share agrees in sign
/// and size on both halves of the recording (a law, not an episode).
fn next_block(
    lib: &[Block],
    chosen: &[usize],
    offered: std::ops::Range<usize>,
    y: &[f64],
    w: &[f64],
    rss: f64,
    residual: &[f64],
) -> Option<(usize, f64)> {
    let n = y.len();
    let half = n / 2;
    let mut best: Option<(usize, f64)> = None;
    for bi in offered {
        if taken(lib, chosen, &lib[bi]) {
            continue;
        }
        let mut trial = chosen.to_vec();
        trial.push(bi);
        if let Some((_, _, r)) = wls(&design(lib, &trial), y, w)
            && best.is_none_or(|(_, br)| r < br)
        {
            best = Some((bi, r));
        }
    }
    let (bi, new_rss) = best?;
    let b = &lib[bi];
    let mut trial = chosen.to_vec();
    trial.push(bi);
    // The independent samples are those of what the law would leave (the estimate's own
    // noise), not of what it explains: a missing flow that is a clean step is as smooth
    // as a signal gets, and counted on itself it would be worth two samples.
    let n_eff = effective(&left_by(lib, &trial, y, w)).max(effective(residual));
    // A shape the scan chose (a width, a Stribeck speed, a step's time) is a parameter
    // the confirming fit frees: it counts as one.
    let shaped = b.terms.iter().filter(|t| t.shape.is_some()).count();
    let k_new = (b.columns.len() + shaped) as f64;
    let gain = n_eff * (rss / new_rss.max(1e-300)).ln();
    let cost = k_new * n_eff.max(2.0).ln() + 2.0 * (b.scanned as f64).ln();
    // Significant and worth a term: it removes a tenth of what is left at least (a
    // product a third: two signals multiplied mimic much — on Silverbox `v²·q` took a
    // share of the cubic spring's and of an input filter's error beside it).
    let share = if matches!(b.family, Family::Product | Family::Symbolic) {
        PRODUCT_MIN_SHARE
    } else {
        MIN_SHARE
    };
    if gain.is_nan() || gain <= cost || new_rss > (1.0 - share) * rss {
        return None;
    }
    // A law holds on both halves: the new block's share agrees in sign and size.
    if !matches!(b.family, Family::Step | Family::Ramp) {
        let agree = [0..half, half..n].map(|range| {
            let cols: Vec<Vec<f64>> = (trial.iter())
                .flat_map(|&c| lib[c].columns.iter().map(|col| col[range.clone()].to_vec()))
                .collect();
            let refs: Vec<&[f64]> = cols.iter().map(Vec::as_slice).collect();
            wls(&refs, &y[range.clone()], &w[range.clone()])
        });
        let [Some((a, _, _)), Some((c, _, _))] = agree else {
            return None;
        };
        let k = a.len();
        let first = k - b.columns.len();
        // The block's contribution's size on either half (RMS of its columns × coefficients).
        let size = |beta: &[f64]| -> f64 {
            (0..n)
                .map(|r| {
                    (first..k)
                        .map(|i| beta[i] * lib_col(lib, &trial, i)[r])
                        .sum::<f64>()
                        .powi(2)
                })
                .sum::<f64>()
                .sqrt()
        };
        let (sa, sc) = (size(&a), size(&c));
        let same_sign = (first..k).all(|i| {
            a[i] * c[i] >= 0.0 || (a[i].abs() < 0.1 * sa.max(1e-300) && b.columns.len() > 1)
        });
        if !same_sign || sa.min(sc) < 0.33 * sa.max(sc) {
            return None;
        }
    }
    Some((bi, new_rss))
}

/// Whether a block of `b`'s family is among the blocks `with` already (one
/// member per shape family; harmonics of different orders are different
/// members).
fn taken(lib: &[Block], with: &[usize], b: &Block) -> bool {
    with.iter().any(|&c| {
        let o = &lib[c];
        o.family == b.family && (b.family != Family::Harmonic || o.member == b.member)
    })
}

/// The firsts a pair of blocks is tried from: the blocks that alone leave least.
const PAIR_FIRSTS: usize = 3;

/// Two blocks that join the law together where neither joins alone: a law
/// of two terms of like size (a diode's drop `0.7 tanh(i/ε)` and the part
/// `−0.7 m tanh(i/ε)` a switch takes away) leaves, after either term, the
/// other's smooth shape, counted as a couple of effective samples, so
/// neither earns its place by itself. Of the [`PAIR_FIRSTS`] blocks that
/// alone leave least, each is tried with every other; the pair that leaves
/// least is taken if each of its blocks joins the law beside the other by
/// [`next_block`]'s rules (gain over cost in the samples the pair leaves,
/// share, both halves).
fn next_pair(
    lib: &[Block],
    chosen: &[usize],
    y: &[f64],
    w: &[f64],
    rss: f64,
) -> Option<(usize, usize, f64)> {
    let left = |blocks: &[usize]| -> Option<f64> {
        let mut trial = chosen.to_vec();
        trial.extend_from_slice(blocks);
        wls(&design(lib, &trial), y, w).map(|(_, _, r)| r)
    };
    let mut firsts: Vec<(usize, f64)> = (0..lib.len())
        .filter(|&b| !taken(lib, chosen, &lib[b]))
        .filter_map(|b| left(&[b]).filter(|r| r.is_finite()).map(|r| (b, r)))
        .collect();
    firsts.sort_by(|a, b| a.1.total_cmp(&b.1));
    let mut best: Option<(usize, usize, f64)> = None;
    for &(first, _) in firsts.iter().take(PAIR_FIRSTS) {
        let mut with = chosen.to_vec();
        with.push(first);
        for second in (0..lib.len()).filter(|&b| b != first && !taken(lib, &with, &lib[b])) {
            if let Some(r) = left(&[first, second]).filter(|r| r.is_finite())
                && best.is_none_or(|(_, _, br)| r < br)
            {
                best = Some((first, second, r));
            }
        }
    }
    let (first, second, r) = best?;
    // Each beside the other, by the rules a single block joins by.
    let joins = |a: usize, b: usize| {
        let mut with = chosen.to_vec();
        with.push(a);
        let rss_a = left(&[a])?;
        let residual = left_by(lib, &with, y, w);
        next_block(lib, &with, b..b + 1, y, w, rss_a, &residual)
    };
    (joins(first, second).is_some() && joins(second, first).is_some() && r < rss)
        .then_some((first, second, r))
}

/// `v` minus its weighted least-squares fit on `cols`: the part of `v`
/// orthogonal to them (left as it is when they are degenerate).
fn orthogonalise(cols: &[&[f64]], v: &mut [f64], w: &[f64]) {
    if let Some((beta, _, _)) = wls(cols, v, w) {
        for (r, x) in v.iter_mut().enumerate() {
            *x -= (0..beta.len()).map(|i| beta[i] * cols[i][r]).sum::<f64>();
        }
    }
}

/// Column `i` of the design made of the blocks `chosen`.
fn lib_col<'a>(lib: &'a [Block], chosen: &[usize], i: usize) -> &'a [f64] {
    let mut k = i;
    for &c in chosen {
        let cols = &lib[c].columns;
        if k < cols.len() {
            return &cols[k];
        }
        k -= cols.len();
    }
    &[]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_sign_law_that_an_input_switches_is_a_product_of_the_input_with_the_sign() {
        // A diode's drop while a switch is open: 0.7 (1 − m) tanh(i/0.05), m a duty cycle
        // between 0.2 and 0.8, the current crossing zero; the estimate's noise 2 mV.
        let n = 3000;
        let t: Vec<f64> = (0..n).map(|k| k as f64 * 1e-3).collect();
        let i: Vec<f64> = t.iter().map(|&s| 2.0 * (7.0 * s).sin() + 0.5).collect();
        let m: Vec<f64> = t.iter().map(|&s| 0.5 + 0.3 * (2.3 * s).sin()).collect();
        let mut noise = 0x2545_f491_4f6c_dd1d_u64;
        let value: Vec<f64> = (0..n)
            .map(|k| {
                noise ^= noise << 13;
                noise ^= noise >> 7;
                noise ^= noise << 17;
                let u = (noise >> 11) as f64 / (1u64 << 53) as f64 - 0.5;
                0.7 * (1.0 - m[k]) * (i[k] / 0.05).tanh() + 0.002 * 3.46 * u
            })
            .collect();
        let signal = |name: &str, label: &str, unit: &str, role, values: &[f64]| ActingSignal {
            name: name.into(),
            label: label.into(),
            unit: unit.into(),
            role,
            values: values.to_vec(),
        };
        let place = MissingSignal {
            location: "1L".into(),
            place: "the inductor's loop (1L)".into(),
            quantity: Quantity::Effort,
            unit: "V".into(),
            t,
            value,
            band: vec![0.002; n],
            acting: vec![
                signal("1L.f", "current", "A", SignalRole::Flow, &i),
                signal("m", "input m", "1", SignalRole::Input, &m),
            ],
            explained: 1.0,
        };
        let law = screen(&place).expect("a law");
        // (A third term may mend the width's grid, 0.0552 A for 0.05: the confirming fit
        // frees the width and drops what it does not need.)
        assert!(law.terms.len() <= 3, "{}", law.describe());
        let sign = (law.terms.iter())
            .find(|t| t.expr == "tanh(1L.f / §)")
            .unwrap_or_else(|| panic!("{}", law.describe()));
        let switched = (law.terms.iter())
            .find(|t| t.expr == "m * tanh(1L.f / §)")
            .unwrap_or_else(|| panic!("{}", law.describe()));
        assert!(
            (sign.coefficient / 0.7 - 1.0).abs() < 0.05,
            "{}",
            law.describe()
        );
        assert!(
            (switched.coefficient / -0.7 - 1.0).abs() < 0.05,
            "{}",
            law.describe()
        );
        assert_eq!(switched.family, Family::Product);
        assert_eq!(switched.unit, "V");
        // A drop the switch does not take away, the input still acting: one sign term.
        let mut plain = place.clone();
        plain.value = (i.iter().zip(&place.value).zip(&m))
            .map(|((x, v), mk)| v - 0.7 * (1.0 - mk) * (x / 0.05).tanh() + 0.35 * (x / 0.05).tanh())
            .collect();
        let law = screen(&plain).expect("a law");
        assert!(
            law.terms.iter().all(|t| t.family != Family::Product),
            "{}",
            law.describe()
        );
        let sign = (law.terms.iter())
            .find(|t| t.family == Family::Sign)
            .unwrap_or_else(|| panic!("{}", law.describe()));
        assert!(
            (sign.coefficient / 0.35 - 1.0).abs() < 0.05,
            "{}",
            law.describe()
        );
    }

    #[test]
    fn a_negative_term_joins_the_law_with_a_minus_sign() {
        let mut sign = term(
            "c_sign",
            Family::Sign,
            "tanh(i / 0.0068 A)".into(),
            "tanh(i / 0.0068)".into(),
            "V".into(),
        );
        sign.coefficient = 0.2351;
        let mut drag = term(
            "c_drag",
            Family::QuadraticDrag,
            "i · |i|".into(),
            "i * abs(i)".into(),
            "V/((A)^2)".into(),
        );
        drag.coefficient = -9.657e-4;
        let law = Law {
            location: "1e".into(),
            place: "the electrical loop (1e)".into(),
            quantity: Quantity::Effort,
            unit: "V".into(),
            terms: vec![sign, drag],
            explained: 0.95,
            residual_rms: 0.01,
            missing_max: 0.3,
            effective_samples: 100.0,
            fitted: Vec::new(),
        };
        assert_eq!(
            law.describe(),
            "0.2351 V · tanh(i / 0.0068 A) − 9.657e-4 V/((A)^2) · i · |i|"
        );
    }
    #[test]
    fn a_disturbance_periodic_in_time_is_found_off_the_drives_lines_and_not_on_them() {
        // 4 s at 1 kHz; a speed driven at 1.5 Hz and 4 Hz; the missing torque a vibration
        // of 0.02 N m at 13.3 Hz, the estimate's noise 1 mN m.
        let n = 4000;
        let t: Vec<f64> = (0..n).map(|k| k as f64 * 1e-3).collect();
        let tau = std::f64::consts::TAU;
        let u: Vec<f64> = (t.iter())
            .map(|&s| (tau * 1.5 * s).sin() + 0.5 * (tau * 4.0 * s).sin())
            .collect();
        let w: Vec<f64> = u.iter().map(|x| 20.0 * x).collect();
        let mut noise = 0x9e37_79b9_7f4a_7c15_u64;
        let mut gauss = move || {
            noise ^= noise << 13;
            noise ^= noise >> 7;
            noise ^= noise << 17;
            ((noise >> 11) as f64 / (1u64 << 53) as f64 - 0.5) * 3.46
        };
        let place = |f: f64, gauss: &mut dyn FnMut() -> f64| {
            let value: Vec<f64> = (t.iter())
                .map(|&s| 0.02 * (tau * f * s + 0.3).sin() + 1e-3 * gauss())
                .collect();
            let signal = |name: &str, role, values: &[f64]| ActingSignal {
                name: name.into(),
                label: name.into(),
                unit: String::new(),
                role,
                values: values.to_vec(),
            };
            MissingSignal {
                location: "1m".into(),
                place: "the shaft (1m)".into(),
                quantity: Quantity::Effort,
                unit: "N m".into(),
                t: t.clone(),
                value,
                band: vec![1e-3; n],
                acting: vec![
                    signal("1m.f", SignalRole::Flow, &w),
                    signal("V", SignalRole::Input, &u),
                ],
                explained: 1.0,
            }
        };
        let law = screen(&place(13.3, &mut gauss)).expect("a law");
        let sine = (law.terms.iter())
            .find(|t| t.family == Family::Periodic && t.shape.is_some())
            .unwrap_or_else(|| panic!("{}", law.describe()));
        let f = sine.shape.as_ref().map_or(0.0, |s| s.value);
        assert!((f - 13.3).abs() < 0.05, "{f}: {}", law.describe());
        let amplitude = (law.terms.iter())
            .filter(|t| t.family == Family::Periodic)
            .map(|t| t.coefficient.powi(2))
            .sum::<f64>()
            .sqrt();
        assert!((amplitude / 0.02 - 1.0).abs() < 0.1, "{}", law.describe());
        // The cosine reads the sine's frequency, by name and by value.
        assert!(
            law.symbolic().contains("c_cost · cos(2π · f_sint · t)"),
            "{}",
            law.symbolic()
        );
        assert!(!law.describe().contains('§'), "{}", law.describe());
        assert!(
            law.describe()
                .contains(&format!("cos(2π · {} Hz · t)", sig(f))),
            "{}",
            law.describe()
        );
        // The same vibration at the drive's 4 Hz: a law of the time there cannot be told
        // from what the drive does through one of the speed, and is not offered.
        let on_the_drive = screen(&place(4.0, &mut gauss));
        assert!(
            on_the_drive
                .as_ref()
                .is_none_or(|l| l.terms.iter().all(|t| t.family != Family::Periodic)),
            "{:?}",
            on_the_drive.map(|l| l.describe())
        );
    }
}
