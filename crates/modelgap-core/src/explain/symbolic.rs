//! Stage 2b of discovery, **symbolic search**: when the typed library leaves
//! more of the missing effort than its band (or needs three terms or more to
//! explain it), formulas of the signals acting at the place are built and
//! sized against it — a static regression on the estimate, no simulation.
//!
//! Units are enforced by construction: every signal `x` enters a formula as
//! `x/a`, with `a` a scale in `x`'s own unit, so each function acts on a
//! dimensionless number and the formula's coefficient carries the missing
//! effort's unit. The grammar, for each signal (flows, positions,
//! displacements, efforts):
//!
//! | factor | formula of `u = x/a` | scale `a` |
//! |---|---|---|
//! | power | `u`, `|u|`, `u²` | the signal's RMS |
//! | bump | `exp(−u²)` (a Gaussian) | scanned |
//! | Lorentzian | `1/(1 + u²)` | scanned |
//! | peak | `u/(1 + u²)` (an eddy-current brake's torque–speed curve) | scanned |
//! | reciprocal | `1/u` beyond `|u| = 1`, `u` within (a constant-power load `P/v`, drawing as a resistor below its drop-out `a`) | scanned |
//! | arctangent | `atan u` (a soft saturation) | scanned |
//! | decay | `exp(−|u|)` | scanned |
//! | logarithm | `sign(u)·ln(1 + |u|)` | scanned |
//! | hyperbolic tangent | `tanh u` (of a flow only inside a product: alone it is the library's sign) | scanned |
//! | signed root | `sign(u)·√|u|` (alone) | the signal's RMS |
//!
//! Scales are scanned over [`SCALES`] times the signal's RMS. A formula is
//! one factor alone (not a power, which the library has) or the product of
//! two factors of different signals, one of them scanned (a product of two
//! powers is the library's product family). Every formula's gain against
//! the residual, made orthogonal to the law's terms so far, is computed; the
//! best few go back to the screen, which lets one join the law by its usual
//! rules with the whole search counted as its scan: 36 formulas on a motor's
//! shaft (its speed alone), 1917 on a drive's carriage (speed and
//! position), 5638 at Silverbox's mass (speed, position and the spring's
//! displacement: 2 ln 5638 ≈ 17 added to the information criterion). The
//! first scanned factor's scale becomes the term's shape parameter, freed by
//! the confirming fit.

use rayon::prelude::*;

use super::estimate::{ActingSignal, MissingSignal, SignalRole};
use super::screen::{Family, LawTerm, num, rms_of, shaped, sig, term};

/// A typed law of this many terms or more at one place may be mimicking a
/// shape the library lacks: a law that starts from a formula competes with it.
pub(super) const MIMICRY_TERMS: usize = 3;

/// Scales of a scanned factor, in units of the signal's RMS.
pub(super) const SCALES: [f64; 5] = [0.1, 0.25, 0.6, 1.5, 4.0];

/// Formulas handed back to the screen.
const OFFERED: usize = 6;

/// The shape of a factor.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Shape {
    Linear,
    Absolute,
    Square,
    Bump,
    Lorentzian,
    Peak,
    Reciprocal,
    Arctangent,
    Decay,
    Logarithm,
    Tanh,
    Root,
}

impl Shape {
    /// Whether its scale is scanned (and may become the term's shape parameter).
    fn scanned(self) -> bool {
        !matches!(
            self,
            Shape::Linear | Shape::Absolute | Shape::Square | Shape::Root
        )
    }

    fn value(self, u: f64) -> f64 {
        match self {
            Shape::Linear => u,
            Shape::Absolute => u.abs(),
            Shape::Square => u * u,
            Shape::Bump => (-u * u).exp(),
            Shape::Lorentzian => 1.0 / (1.0 + u * u),
            Shape::Peak => u / (1.0 + u * u),
            Shape::Reciprocal => u / (u * u).max(1.0),
            Shape::Arctangent => u.atan(),
            Shape::Decay => (-u.abs()).exp(),
            Shape::Logarithm => sign(u) * (1.0 + u.abs()).ln(),
            Shape::Tanh => u.tanh(),
            Shape::Root => sign(u) * u.abs().sqrt(),
        }
    }

    /// The factor in law syntax, `u` written out as `(x / a)`.
    fn expr(self, u: &str) -> String {
        match self {
            Shape::Linear => u.to_string(),
            Shape::Absolute => format!("abs{u}"),
            Shape::Square => format!("{u}^2"),
            Shape::Bump => format!("exp(-{u}^2)"),
            Shape::Lorentzian => format!("1 / (1 + {u}^2)"),
            Shape::Peak => format!("{u} / (1 + {u}^2)"),
            Shape::Reciprocal => format!("{u} / max({u}^2, 1)"),
            Shape::Arctangent => format!("atan{u}"),
            Shape::Decay => format!("exp(-abs{u})"),
            Shape::Logarithm => format!("sign{u} * ln(1 + abs{u})"),
            Shape::Tanh => format!("tanh{u}"),
            Shape::Root => format!("sign{u} * sqrt(abs{u})"),
        }
    }

    /// The factor in words.
    fn label(self, u: &str) -> String {
        match self {
            Shape::Linear => u.to_string(),
            Shape::Absolute => format!("|{u}|"),
            Shape::Square => format!("{u}²"),
            Shape::Bump => format!("exp(−{u}²)"),
            Shape::Lorentzian => format!("1/(1 + {u}²)"),
            Shape::Peak => format!("{u}/(1 + {u}²)"),
            Shape::Reciprocal => format!("{u}/max({u}², 1)"),
            Shape::Arctangent => format!("atan {u}"),
            Shape::Decay => format!("exp(−|{u}|)"),
            Shape::Logarithm => format!("sign {u} · ln(1 + |{u}|)"),
            Shape::Tanh => format!("tanh {u}"),
            Shape::Root => format!("sign {u} · √|{u}|"),
        }
    }
}

/// `sign` as the law syntax has it (`sign(0) = 0`).
fn sign(x: f64) -> f64 {
    if x == 0.0 { 0.0 } else { x.signum() }
}

/// One factor of a formula: a shape of one signal at one scale.
struct Factor<'a> {
    signal: &'a ActingSignal,
    /// Index of the signal among those searched.
    which: usize,
    shape: Shape,
    scale: f64,
    values: Vec<f64>,
}

impl Factor<'_> {
    /// `(x / a)` with `a` the shape parameter `§` when `free`, else its number.
    fn u(&self, free: bool) -> (String, String) {
        let a = if free {
            "§".to_string()
        } else {
            num(self.scale)
        };
        let unit = if self.signal.unit.is_empty() {
            String::new()
        } else {
            format!(" {}", self.signal.unit)
        };
        let shown = if free {
            "§".to_string()
        } else {
            format!("{}{unit}", sig(self.scale))
        };
        (
            format!("({} / {a})", self.signal.name),
            format!("({} / {shown})", self.signal.label),
        )
    }
}

/// A formula: one factor, or the product of two.
struct Formula {
    a: usize,
    b: Option<usize>,
}

/// The best formulas against `residual` (what the law so far leaves of the
/// estimate at the samples `idx`, weights `w`), each made orthogonal to the
/// columns `against` (the law's terms and any nuisance) before it is sized:
/// up to [`OFFERED`] terms with their columns (as built, not made
/// orthogonal), best first, and how many formulas were searched.
pub(super) fn search(
    m: &MissingSignal,
    idx: &[usize],
    residual: &[f64],
    w: &[f64],
    against: &[&[f64]],
) -> (Vec<(LawTerm, Vec<f64>)>, usize) {
    let n = idx.len();
    if n < 20 || residual.len() != n || w.len() != n {
        return (Vec::new(), 0);
    }
    let signals: Vec<(&ActingSignal, Vec<f64>, f64)> = (m.acting.iter())
        .filter(|a| a.role.is_plain())
        .filter_map(|a| {
            let v: Vec<f64> = idx
                .iter()
                .map(|&k| a.values.get(k).copied())
                .collect::<Option<_>>()?;
            let s = rms_of(&v);
            (s.is_finite() && s > 0.0 && v.iter().all(|x| x.is_finite())).then_some((a, v, s))
        })
        .collect();
    let mut factors: Vec<Factor> = Vec::new();
    for (which, (a, v, s)) in signals.iter().enumerate() {
        let mut push = |shape: Shape, scale: f64| {
            factors.push(Factor {
                signal: a,
                which,
                shape,
                scale,
                values: v.iter().map(|x| shape.value(x / scale)).collect(),
            })
        };
        for shape in [Shape::Linear, Shape::Absolute, Shape::Square, Shape::Root] {
            push(shape, *s);
        }
        for shape in [
            Shape::Bump,
            Shape::Lorentzian,
            Shape::Peak,
            Shape::Reciprocal,
            Shape::Arctangent,
            Shape::Decay,
            Shape::Logarithm,
            Shape::Tanh,
        ] {
            for k in SCALES {
                push(shape, k * s);
            }
        }
    }
    let mut formulas: Vec<Formula> = Vec::new();
    for (i, f) in factors.iter().enumerate() {
        // Alone: a scanned shape (tanh only of what is not a flow: of a flow it is the
        // library's sign), or the signed root.
        let sign_of_flow = f.shape == Shape::Tanh && f.signal.role == SignalRole::Flow;
        if (f.shape.scanned() && !sign_of_flow) || f.shape == Shape::Root {
            formulas.push(Formula { a: i, b: None });
        }
        for (j, g) in factors.iter().enumerate().skip(i + 1) {
            // Two signals, one factor scanned at least; the root only alone.
            if g.which != f.which
                && (f.shape.scanned() || g.shape.scanned())
                && f.shape != Shape::Root
                && g.shape != Shape::Root
            {
                formulas.push(Formula { a: i, b: Some(j) });
            }
        }
    }
    let basis = orthonormal(against, w);
    let column = |f: &Formula| -> Vec<f64> {
        let a = &factors[f.a].values;
        match f.b {
            Some(b) => a
                .iter()
                .zip(&factors[b].values)
                .map(|(x, y)| x * y)
                .collect(),
            None => a.clone(),
        }
    };
    let mut gains: Vec<(usize, f64)> = (formulas.par_iter().enumerate())
        .filter_map(|(i, f)| {
            let c = column(f);
            let cc: f64 = (0..n).map(|r| w[r] * c[r] * c[r]).sum();
            let cr: f64 = (0..n).map(|r| w[r] * c[r] * residual[r]).sum();
            let mut left = cc;
            for q in &basis {
                let p: f64 = (0..n).map(|r| w[r] * q[r] * c[r]).sum();
                left -= p * p;
            }
            // A formula the law's terms already span is no news.
            if left.is_nan() || left <= 1e-9 * cc {
                return None;
            }
            let gain = cr * cr / left;
            gain.is_finite().then_some((i, gain))
        })
        .collect();
    gains.sort_by(|a, b| b.1.total_cmp(&a.1));
    gains.truncate(OFFERED);
    let found = gains
        .into_iter()
        .map(|(i, _)| {
            let f = &formulas[i];
            (build(m, &factors, f), column(f))
        })
        .collect();
    (found, formulas.len())
}

/// The law term of a formula: its first scanned factor's scale is the shape
/// parameter (bounds a grid step and a half either way), the rest numbers.
fn build(m: &MissingSignal, factors: &[Factor], f: &Formula) -> LawTerm {
    let parts: Vec<&Factor> = std::iter::once(&factors[f.a])
        .chain(f.b.map(|b| &factors[b]))
        .collect();
    let free = parts.iter().position(|p| p.shape.scanned());
    let (mut expr, mut label) = (Vec::new(), Vec::new());
    for (k, p) in parts.iter().enumerate() {
        let (u, shown) = p.u(free == Some(k));
        expr.push(p.shape.expr(&u));
        label.push(p.shape.label(&shown));
    }
    let paren = |s: &String| {
        if parts.len() > 1 && (s.contains(" / (") || s.contains(" * ")) {
            format!("({s})")
        } else {
            s.clone()
        }
    };
    let expr = expr.iter().map(paren).collect::<Vec<_>>().join(" * ");
    let label = label.join(" · ");
    let t = term("c_sym", Family::Symbolic, label, expr, m.unit.clone());
    match free.map(|k| parts[k]) {
        Some(p) => {
            // Half a decade either way: wider than the scan's step (×2.5), so the confirming
            // fit can settle between grid points.
            shaped(
                t,
                "a",
                &p.signal.unit,
                p.scale,
                p.scale / 3.0,
                p.scale * 3.0,
            )
        }
        None => t,
    }
}

/// An orthonormal basis (weights `w`) of the columns `cols` (modified
/// Gram–Schmidt, dependent columns dropped).
fn orthonormal(cols: &[&[f64]], w: &[f64]) -> Vec<Vec<f64>> {
    let n = w.len();
    let mut basis: Vec<Vec<f64>> = Vec::new();
    for c in cols {
        if c.len() != n {
            continue;
        }
        let mut v = c.to_vec();
        let norm0: f64 = (0..n).map(|r| w[r] * v[r] * v[r]).sum::<f64>().sqrt();
        for q in &basis {
            let p: f64 = (0..n).map(|r| w[r] * q[r] * v[r]).sum();
            for r in 0..n {
                v[r] -= p * q[r];
            }
        }
        let norm: f64 = (0..n).map(|r| w[r] * v[r] * v[r]).sum::<f64>().sqrt();
        if norm > 1e-9 * norm0 && norm > 0.0 {
            for x in &mut v {
                *x /= norm;
            }
            basis.push(v);
        }
    }
    basis
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::explain::estimate::Quantity;

    fn place(speed: Vec<f64>, value: Vec<f64>) -> MissingSignal {
        let n = speed.len();
        MissingSignal {
            location: "1m".into(),
            place: "the shaft (1m)".into(),
            quantity: Quantity::Effort,
            unit: "N m".into(),
            t: (0..n).map(|k| k as f64 * 1e-3).collect(),
            value,
            band: vec![1e-4; n],
            acting: vec![ActingSignal {
                name: "1m.f".into(),
                label: "speed".into(),
                unit: "rad/s".into(),
                role: SignalRole::Flow,
                values: speed,
            }],
            explained: 1.0,
        }
    }

    #[test]
    fn the_formulas_parse_in_the_law_syntax_and_the_columns_match_them() {
        let speed: Vec<f64> = (0..400).map(|k| 40.0 * (k as f64 * 0.02).sin()).collect();
        let m = place(speed.clone(), vec![0.0; 400]);
        let idx: Vec<usize> = (0..400).collect();
        // An arctangent at one of the scan's scales.
        let a = SCALES[2] * rms_of(&speed);
        let r: Vec<f64> = speed.iter().map(|x| (x / a).atan()).collect();
        let (found, searched) = search(&m, &idx, &r, &vec![1.0; 400], &[]);
        // A speed alone: 7 shapes at 5 scales each (its tanh is the library's sign) and the
        // root.
        assert_eq!(searched, 36);
        assert_eq!(found.len(), OFFERED);
        for (t, col) in &found {
            assert!(t.expr.contains("1m.f"), "{}", t.expr);
            assert_eq!(t.unit, "N m");
            assert_eq!(col.len(), 400);
        }
        // The best is the arctangent itself, at its scale, and its column is the residual.
        let (best, col) = &found[0];
        assert_eq!(best.expr, "atan(1m.f / §)");
        let sh = best.shape.as_ref().expect("a scanned scale");
        assert_eq!(sh.unit, "rad/s");
        assert!((sh.value / a - 1.0).abs() < 1e-12, "{sh:?}");
        assert!(col.iter().zip(&r).all(|(c, x)| (c - x).abs() < 1e-12));
    }
}
