//! Held-out error: whether what an effect explains holds on data its fit did
//! not see. Two-fold cross-validation over the two halves of the recording —
//! the parameters fitted on one half, the error measured on the other — for
//! the model without the effect and with it. An effect is kept only when it
//! lowers the held-out error on both halves: a law that fits noise, or that
//! the two halves want with different parameters, does not.
//!
//! Each half's fit is one Gauss–Newton step from the fit on the whole
//! recording, on the Jacobian there (one simulation per free parameter): the
//! whole fit is close to each half's, so the step is the half's fit to first
//! order, and a check costs a handful of simulations rather than four fits.
//! A parameter a half hardly sees (less than a tenth of what it moves: an
//! initial state that has died out by then) keeps its whole-recording value in
//! the fit on that half. An effect that acts mostly in one half (a bump in
//! time, a change late in the run) has no held-out error: a half that holds
//! less than a tenth of what any of its own parameters moves is not a test of
//! it, and neither fold is then judged. Lattice parameters (a vertex) are
//! held.

use super::*;

/// The share of what each parameter moves (Σ of its Jacobian column squared)
/// that each half must hold for the folds to test it.
const ACTS_IN_HALF: f64 = 0.1;

/// The held-out error of two models, each fitted on one half of the
/// recording and measured on the other: ½Σr² of the weighted residuals on
/// the first half, then on the second.
#[derive(Clone, Debug, PartialEq)]
pub(super) struct HeldOut {
    /// Without the effect (the model as it was).
    pub(super) without: [f64; 2],
    /// With it.
    pub(super) with: [f64; 2],
    /// Whether every parameter of the model with the effect acts in both
    /// halves ([`ACTS_IN_HALF`]): else the folds test nothing.
    pub(super) judged: bool,
    /// For each effect of the model with it, each parameter: half the difference
    /// between its fits on the two halves, when both halves see it (`None` when one
    /// does not, or it is held). Noise alone puts the two fits about 2σ apart (each
    /// has half the data); a model that is still wrong puts them further.
    pub(super) spread: Vec<Vec<Option<f64>>>,
    /// Residuals in each fold (for the RMS of the text).
    pub(super) sizes: [usize; 2],
    /// What the two folds are, for the text: the recording's halves, or the two
    /// halves of what follows an event.
    pub(super) folds: [&'static str; 2],
}

impl HeldOut {
    /// Whether the effect lowers the held-out error on both halves (true when
    /// the halves cannot test it: nothing speaks against it).
    pub(super) fn lowers(&self) -> bool {
        !self.judged || self.with.iter().zip(&self.without).all(|(a, b)| a < b)
    }

    /// The held-out RMS without and with the effect, each half, as text
    /// (weighted residuals: in units of each output's noise floor).
    pub(super) fn text(&self) -> String {
        if !self.judged {
            return "it acts mostly in one half, so the halves cannot test it".to_string();
        }
        let n_per_half = self.sizes;
        let rms = |cost: f64, n: usize| (2.0 * cost / n.max(1) as f64).sqrt();
        format!(
            "{} {:.3} → {:.3}, {} {:.3} → {:.3} times the floor",
            self.folds[0],
            rms(self.without[0], n_per_half[0]),
            rms(self.with[0], n_per_half[0]),
            self.folds[1],
            rms(self.without[1], n_per_half[1]),
            rms(self.with[1], n_per_half[1]),
        )
    }
}

/// The time of a candidate at `values` that is an event inside the recording (a
/// step, a fault at `t` more than a twentieth of the record from either end), which
/// a fit on the half before it cannot see: it is held out on what follows it
/// ([`held_out_after`]). One at the record's very edge is a constant in disguise
/// (a mass "changing" at 3 ms re-calibrates the mass): see [`edge_time`].
pub(super) fn event_time(c: &Candidate, values: &[f64], rec: &Recording) -> Option<f64> {
    time_of(c, values).filter(|&t| inside(t, rec))
}

/// The time (s) of a candidate at `values` that changes at one time within a twentieth
/// of the record's edge (a step or a fault at `t` that [`event_time`] does not count): there
/// a change cannot be told from the initial state or from a constant.
pub(super) fn edge_time(c: &Candidate, values: &[f64], rec: &Recording) -> Option<f64> {
    time_of(c, values).filter(|&t| !inside(t, rec))
}

/// The value of a candidate's time in the recording (`t_fault`, a law's `t_step`), if it
/// has one: a parameter in s named `t` or `t_…`, not a duration such as a lag's `tau`.
fn time_of(c: &Candidate, values: &[f64]) -> Option<f64> {
    (c.params.iter().zip(values))
        .find(|(p, _)| is_time(p))
        .map(|(_, v)| *v)
}

fn is_time(p: &crate::effect::EffectParam) -> bool {
    p.unit == "s" && (p.name == "t" || p.name.starts_with("t_"))
}

/// Whether `t` is more than a twentieth of the record from either end.
fn inside(t: f64, rec: &Recording) -> bool {
    let times = rec.t();
    let (Some(&t0), Some(&t1)) = (times.first(), times.last()) else {
        return false;
    };
    let margin = 0.05 * (t1 - t0);
    t > t0 + margin && t < t1 - margin
}

/// The held-out error of the model without and with `effect` (a candidate at its
/// values, last of `with`): an event inside the record on the two halves of what
/// follows it ([`held_out_after`]), anything else on the record's halves
/// ([`held_out`]). `None` when a simulation fails.
pub(super) fn held_out_effect(
    target: &Target,
    without: &[(&Candidate, &[f64])],
    with: &[(&Candidate, &[f64])],
    effect: (&Candidate, &[f64]),
) -> Option<HeldOut> {
    match event_time(effect.0, effect.1, target.rec) {
        Some(t) => held_out_after(target, without, with, t),
        None => held_out(target, without, with),
    }
}

/// The held-out error of the model without and with an effect: `without`
/// and `with` are the effects built in (each with its values from a fit on
/// the whole recording). `None` when a simulation fails.
pub(super) fn held_out(
    target: &Target,
    without: &[(&Candidate, &[f64])],
    with: &[(&Candidate, &[f64])],
) -> Option<HeldOut> {
    let n = target.rec.len();
    let folds = Folds {
        of: (0..n).map(|k| Some(usize::from(k >= n / 2))).collect(),
        names: ["first half", "second half"],
        hold_times: false,
    };
    check(target, without, with, &folds)
}

/// The held-out error of an event at `t_event` (a step, a fault at a time inside the
/// record, which a fit on the half before it cannot see): the two folds are the two halves
/// of what follows it, each predicted by a fit on the other and on everything before the
/// event, the event's time held. A change that holds after it lowers both; a step fitted
/// to a wander of the noise or to what the model still lacks does not.
pub(super) fn held_out_after(
    target: &Target,
    without: &[(&Candidate, &[f64])],
    with: &[(&Candidate, &[f64])],
    t_event: f64,
) -> Option<HeldOut> {
    let t = target.rec.t();
    let t1 = *t.last()?;
    let mid = 0.5 * (t_event + t1);
    let folds = Folds {
        of: (t.iter())
            .map(|&tk| (tk >= t_event).then_some(usize::from(tk >= mid)))
            .collect(),
        names: [
            "the first half after the event",
            "the second half after the event",
        ],
        hold_times: true,
    };
    check(target, without, with, &folds)
}

/// The two held-out folds: for each sample, the fold it is held out in (`None`:
/// always fitted on).
struct Folds {
    of: Vec<Option<usize>>,
    names: [&'static str; 2],
    /// Whether times of the record (an event's `t_fault`) are held.
    hold_times: bool,
}

fn check(
    target: &Target,
    without: &[(&Candidate, &[f64])],
    with: &[(&Candidate, &[f64])],
    folds: &Folds,
) -> Option<HeldOut> {
    let (cost_without, _, _) = two_fold(target, without, folds)?;
    let (cost_with, acting, spread) = two_fold(target, with, folds)?;
    let m = target.names.len();
    let sizes = [0, 1].map(|h| m * folds.of.iter().filter(|f| **f == Some(h)).count());
    // Judged when every parameter the effect adds acts in both halves.
    let before: Vec<&str> = (without.iter())
        .flat_map(|(c, _)| c.params.iter().map(|p| p.name.as_str()))
        .collect();
    let judged = acting
        .iter()
        .all(|(name, both)| *both || before.contains(&name.as_str()));
    Some(HeldOut {
        without: cost_without,
        with: cost_with,
        judged,
        spread,
        sizes,
        folds: folds.names,
    })
}

/// A free parameter by name, and whether it acts in both halves.
type Acting = (String, bool);

/// Per effect, per parameter: half the difference of its two halves' fits.
type Spread = Vec<Vec<Option<f64>>>;

/// ½Σr² on each half of the model with `effects`, each predicted by a fit on
/// the other half (one Gauss–Newton step from `effects`' values, the
/// parameters the other half hardly sees held), for each free parameter
/// whether it acts in both halves, and each parameter's half-split spread.
fn two_fold(
    target: &Target,
    effects: &[(&Candidate, &[f64])],
    folds: &Folds,
) -> Option<([f64; 2], Vec<Acting>, Spread)> {
    let m = target.n_residuals();
    let mut r0 = vec![0.0; m];
    target.residuals(effects, &mut r0).ok()?;
    if r0.iter().any(|v| !v.is_finite()) {
        return None;
    }
    // The free directions: every continuous parameter with room to move.
    let free: Vec<(usize, usize)> = (effects.iter().enumerate())
        .flat_map(|(e, (c, _))| {
            (c.params.iter().enumerate())
                .filter(|(_, p)| !p.is_discrete() && p.lower < p.upper)
                .filter(|(_, p)| !(folds.hold_times && is_time(p)))
                .map(move |(i, _)| (e, i))
        })
        .collect();
    let fd = screen_fd_step(target.model);
    let columns: Vec<Vec<f64>> = free
        .par_iter()
        .map(|&(e, i)| {
            let p = &effects[e].0.params[i];
            let x = effects[e].1[i];
            // Within the bounds: a scanned quantiser's step is bounded closer than a
            // finite-difference step.
            let h = step_in_box(x, fd * p.scale, p.lower, p.upper);
            if h == 0.0 {
                return Some(vec![0.0; m]);
            }
            let mut values: Vec<Vec<f64>> = effects.iter().map(|(_, v)| v.to_vec()).collect();
            values[e][i] = x + h;
            let moved: Vec<(&Candidate, &[f64])> = (effects.iter().zip(&values))
                .map(|((c, _), v)| (*c, v.as_slice()))
                .collect();
            let mut r1 = vec![0.0; m];
            target.residuals(&moved, &mut r1).ok()?;
            let col: Vec<f64> = r1.iter().zip(&r0).map(|(a, b)| (a - b) / h).collect();
            col.iter().all(|v| v.is_finite()).then_some(col)
        })
        .collect::<Option<Vec<_>>>()?;
    let n = target.rec.len();
    let in_fold = |row: usize, h: usize| folds.of.get(row % n).copied().flatten() == Some(h);
    // Each column's share of what it moves in each fold, and in what each fold is
    // predicted from (everything but it).
    let shares: Vec<([f64; 2], [f64; 2])> = (columns.iter())
        .map(|col| {
            let total: f64 = col.iter().map(|v| v * v).sum();
            let within = |h: usize| -> f64 {
                (0..m)
                    .filter(|&row| in_fold(row, h))
                    .map(|row| col[row].powi(2))
                    .sum()
            };
            if total > 0.0 {
                let (a, b) = (within(0) / total, within(1) / total);
                ([a, b], [1.0 - a, 1.0 - b])
            } else {
                ([0.0, 0.0], [0.0, 0.0])
            }
        })
        .collect();
    let acting: Vec<Acting> = (free.iter().zip(&shares))
        .map(|(&(e, i), (sh, _))| {
            let name = effects[e].0.params[i].name.clone();
            (name, sh[0] >= ACTS_IN_HALF && sh[1] >= ACTS_IN_HALF)
        })
        .collect();
    let mut out = [0.0; 2];
    let mut steps: Vec<Vec<f64>> = Vec::with_capacity(2);
    for (h, o) in out.iter_mut().enumerate() {
        // Fitted on the rest, with what it sees.
        let seen: Vec<Vec<f64>> = (columns.iter().zip(&shares))
            .map(|(col, (_, trained))| {
                if trained[h] >= ACTS_IN_HALF {
                    col.clone()
                } else {
                    vec![0.0; m]
                }
            })
            .collect();
        let columns = &seen;
        let delta = half_step(columns, &r0, |row| !in_fold(row, h));
        steps.push(delta.clone());
        *o = 0.5
            * (0..m)
                .filter(|&row| in_fold(row, h))
                .map(|row| {
                    let moved: f64 = (columns.iter().zip(&delta)).map(|(c, d)| c[row] * d).sum();
                    (r0[row] + moved).powi(2)
                })
                .sum::<f64>();
    }
    let mut spread: Spread = effects
        .iter()
        .map(|(c, _)| vec![None; c.params.len()])
        .collect();
    for (k, (&(e, i), (sh, _))) in free.iter().zip(&shares).enumerate() {
        if sh[0] >= ACTS_IN_HALF && sh[1] >= ACTS_IN_HALF && !folds.hold_times {
            spread[e][i] = Some(0.5 * (steps[0][k] - steps[1][k]).abs());
        }
    }
    Some((out, acting, spread))
}

/// The standard errors of `params` (the effect at `index` of the model a
/// [`HeldOut`] was checked with) widened to the halves' spread where it is the
/// larger: a ± that a model still wrong cannot make small.
pub(super) fn widen(params: &mut [FittedParam], held: &HeldOut, index: usize) {
    let Some(spread) = held.spread.get(index) else {
        return;
    };
    for (p, s) in params.iter_mut().zip(spread) {
        if let Some(s) = s
            && p.std_error.is_finite()
            && *s > p.std_error
        {
            p.std_error = *s;
        }
    }
}

/// The Gauss–Newton step `δ` minimising ‖r + Jδ‖² over the rows `train`
/// keeps, by the pseudo-inverse: a direction the rows do not see (an
/// eigenvalue of the scaled normal matrix below 1e-9 of the largest) does
/// not move.
fn half_step(columns: &[Vec<f64>], r: &[f64], train: impl Fn(usize) -> bool) -> Vec<f64> {
    let k = columns.len();
    if k == 0 {
        return Vec::new();
    }
    let rows: Vec<usize> = (0..r.len()).filter(|&row| train(row)).collect();
    let mut jtj = nalgebra::DMatrix::<f64>::zeros(k, k);
    let mut jtr = nalgebra::DVector::<f64>::zeros(k);
    for a in 0..k {
        for b in 0..=a {
            let v: f64 = rows
                .iter()
                .map(|&row| columns[a][row] * columns[b][row])
                .sum();
            jtj[(a, b)] = v;
            jtj[(b, a)] = v;
        }
        jtr[a] = rows.iter().map(|&row| columns[a][row] * r[row]).sum();
    }
    // Scaled to unit diagonal, so the cut-off compares directions, not units; a column
    // of zeros (held) does not move.
    let d: Vec<f64> = (0..k)
        .map(|a| {
            let v = jtj[(a, a)];
            if v > 0.0 { 1.0 / v.sqrt() } else { 0.0 }
        })
        .collect();
    let scaled = nalgebra::DMatrix::from_fn(k, k, |a, b| jtj[(a, b)] * d[a] * d[b]);
    let rhs = nalgebra::DVector::from_fn(k, |a, _| -jtr[a] * d[a]);
    let eig = scaled.symmetric_eigen();
    let top = eig.eigenvalues.iter().copied().fold(0.0, f64::max);
    let mut y = nalgebra::DVector::<f64>::zeros(k);
    for (j, &lambda) in eig.eigenvalues.iter().enumerate() {
        if lambda > 1e-9 * top {
            let v = eig.eigenvectors.column(j);
            y += v * (v.dot(&rhs) / lambda);
        }
    }
    (0..k).map(|a| y[a] * d[a]).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn half_step_solves_least_squares_and_leaves_unseen_directions() {
        // r + J δ with J = [[1, 0], [1, 0], [0, 1], [0, 1]], r = [-1, -3, 2, 2]:
        // trained on rows 0 and 1, δ₀ = 2 and the second column, zero there, stays.
        let columns = vec![vec![1.0, 1.0, 0.0, 0.0], vec![0.0, 0.0, 1.0, 1.0]];
        let r = [-1.0, -3.0, 2.0, 2.0];
        let d = half_step(&columns, &r, |row| row < 2);
        assert!((d[0] - 2.0).abs() < 1e-12, "{d:?}");
        assert_eq!(d[1], 0.0);
        // Trained on all rows, both move.
        let d = half_step(&columns, &r, |_| true);
        assert!(
            (d[0] - 2.0).abs() < 1e-12 && (d[1] + 2.0).abs() < 1e-12,
            "{d:?}"
        );
    }

    #[test]
    fn a_change_at_the_edge_has_an_edge_time_and_a_lag_has_none() {
        use crate::effect::{EffectKind, EffectParam};
        use crate::recording::Signal;
        let t: Vec<f64> = (0..1000).map(|k| k as f64 * 0.01).collect();
        let rec = Recording::new(t.clone(), vec![Signal::new("y", t)]).unwrap();
        let candidate = |param: &str| Candidate {
            id: param.into(),
            name: param.into(),
            kind: EffectKind::AbruptChange,
            acts_on: "y".into(),
            params: vec![EffectParam::new(param, "s", 1.0, (0.0, 10.0), 1.0)],
        };
        // A fault 40 ms into a 10 s record: at the edge, and no event.
        assert_eq!(edge_time(&candidate("t_fault"), &[0.04], &rec), Some(0.04));
        assert_eq!(event_time(&candidate("t_fault"), &[0.04], &rec), None);
        // Mid-record: an event, not at the edge.
        assert_eq!(edge_time(&candidate("t_fault"), &[5.0], &rec), None);
        assert_eq!(event_time(&candidate("t_fault"), &[5.0], &rec), Some(5.0));
        // A sensor's lag of 2.5 ms, or of 5 s, is a duration, not a time of the record (a
        // pair with a lag was refused as "at the edge").
        assert_eq!(edge_time(&candidate("tau"), &[0.0025], &rec), None);
        assert_eq!(event_time(&candidate("tau"), &[5.0], &rec), None);
    }

    #[test]
    fn an_effect_fitted_to_noise_does_not_lower_the_held_out_error() {
        let mut held = HeldOut {
            without: [10.0, 10.0],
            with: [9.0, 10.5],
            judged: true,
            spread: Vec::new(),
            sizes: [1, 1],
            folds: ["first half", "second half"],
        };
        assert!(!held.lowers());
        held.with = [9.0, 9.5];
        assert!(held.lowers());
        // An effect the halves cannot test is not refused.
        held.with = [9.0, 10.5];
        held.judged = false;
        assert!(held.lowers());
    }
}
