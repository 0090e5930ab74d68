//! Second effects: what the first effect leaves. The laws discovery finds
//! again with the first built in ([`laws_on_top`]), every candidate screened
//! on top of it, the best few fitted jointly with it, and the pair kept only
//! when it is significant, moves some prediction by as much as the noise
//! ([`MATERIAL_MOVE`]), and lowers the held-out error: fitted on either half
//! of the recording, it predicts the other half better than the first alone
//! ([`second_effect`], [`super::heldout`]).

use super::*;

/// What the search for a second effect on top of a first found.
pub(super) enum Second {
    /// The pair, ranked, and its joint weighted residual.
    Kept(Vec<RankedCandidate>, Vec<f64>),
    /// The best pair is significant in the recording but not added (it does
    /// not lower the held-out error, or moves no prediction by as much as the
    /// noise): why, for the verdict's reasons.
    NotAdded(String),
    /// No pair is significant.
    None,
}

/// A second effect screened on top of a first: the cost its linearised step
/// reaches, the candidate, and the step.
pub(super) type Screened = (f64, Candidate, Start);

/// The seconds screened on top of one first ([`screen_seconds`]).
pub(super) struct Seconds {
    /// Best first.
    pub(super) screened: Vec<Screened>,
    /// Whether discovery, on what the first leaves, found a law where it acts.
    pub(super) law_on_top: bool,
}

/// Every other candidate, and the laws discovery finds on what `best` leaves,
/// screened on top of it (one linearised step each), best first.
/// `first_weighted`, the first's own weighted residual, spares the screen a
/// simulation per start where a second vanishes.
pub(super) fn screen_seconds(
    target: &Target,
    opts: &ExplainOptions,
    candidates: &[Candidate],
    best: &RankedCandidate,
    first_weighted: Option<&[f64]>,
) -> Seconds {
    let first = best.effect();
    // The laws of what the first leaves: the missing effort estimated again with the first
    // built in (a Stribeck dip that Coulomb friction leaves at each reversal).
    let rediscovered = laws_on_top(target, best);
    // A law found on the model as given at the place of a first that is a law there too is
    // that place's law said another way: beside it, the pair is one law with its terms twice
    // (a geared drive's friction as a sign law and a symbolic law, each with its `|v|`).
    // What the first leaves there is found again on top of it.
    fn law_at(c: &Candidate) -> Option<&str> {
        c.id.starts_with("law@").then_some(c.acts_on.as_str())
    }
    let first_place = law_at(&first.candidate);
    let others: Vec<&Candidate> = candidates
        .iter()
        .filter(|c| first_place.is_none() || law_at(c) != first_place)
        .chain(&rediscovered)
        .filter(|c| c.id != first.candidate.id && !best.equivalent.contains(&c.id))
        .collect();
    let base = std::slice::from_ref(&first);
    // The first's residual is of the model the screen simulates only when there is no copy
    // for fitting, and the calibration is the one the screen holds.
    let beneath =
        first_weighted.filter(|_| target.accurate.is_none() && best.calibration.is_none());
    let mut screened: Vec<Screened> = others
        .par_iter()
        .filter_map(|c| {
            let c = prepared(c, target.rec);
            let s = screen_candidate(target, base, beneath, &c, opts).ok()?;
            Some((s.cost, c, s))
        })
        .collect();
    screened.sort_by(|a, b| a.0.total_cmp(&b.0));
    Seconds {
        screened,
        law_on_top: !rediscovered.is_empty(),
    }
}

/// A pair of a first and a second effect fitted jointly: the first's part and
/// the second's (each with the joint cost and weighted residual).
pub(super) type FittedPair = (Fitted, Fitted);

/// `second` fitted jointly with `best` (both sets of parameters free, the
/// second started from its screen on top of the first).
pub(super) fn fit_second(
    target: &Target,
    opts: &ExplainOptions,
    best: &RankedCandidate,
    second: &Screened,
) -> FittedPair {
    let (first_c, first_values) = first_of(target, best);
    let (_, c, start) = second;
    // The pair is fitted jointly from the first's values and the second's screen.
    let mut second = screened_fit(c, start.clone());
    // The calibration is the first's to carry: a second that carried it too would
    // hold a copy that overrides the first's, and the first's would move nothing
    // (on Silverbox, six dead parameters in each pair fit of fifteen).
    if best.calibration.is_some() {
        let own = second.candidate.params.len() - target.n_calibration(&second.candidate);
        second.candidate.params.truncate(own);
        second.values.truncate(own);
    }
    let start: Vec<f64> = first_values.iter().chain(&second.values).copied().collect();
    match fit_pair(target, &first_c, &second.candidate, &start, opts) {
        Ok((report, weighted)) => {
            let (a, b) = report.params.split_at(first_c.params.len());
            let mut first_report = report.clone();
            first_report.params = a.to_vec();
            first_report.std_errors = report.std_errors[..a.len()].to_vec();
            first_report.robust_std_errors = report.robust_std_errors[..a.len()].to_vec();
            let mut second_report = report.clone();
            second_report.params = b.to_vec();
            second_report.std_errors = report.std_errors[a.len()..].to_vec();
            second_report.robust_std_errors = report.robust_std_errors[a.len()..].to_vec();
            let f1 = Fitted {
                candidate: first_c.clone(),
                values: a.to_vec(),
                report: Some(first_report),
                cost: report.cost_after,
                weighted: weighted.clone(),
                error: None,
                screened: false,
            };
            let f2 = Fitted {
                candidate: second.candidate.clone(),
                values: b.to_vec(),
                report: Some(second_report),
                cost: report.cost_after,
                weighted,
                error: None,
                screened: false,
            };
            (f1, f2)
        }
        Err(e) => {
            let mut f = failed_clone(&second);
            f.error = Some(e.to_string());
            (f, second)
        }
    }
}

/// The pairs fitted first: the two that the screens on top of the firsts promise most.
const FIRST_PAIRS: usize = 2;

/// Each first's few best `seconds` (screened on top of it) fitted jointly with it, in the
/// order given. The two pairs the screens promise most are fitted first. When one of them
/// leaves only what noise leaves, of the rest only those whose screen promises nearly as
/// much, or that would say it with fewer parameters and promise a fair share of it, are
/// fitted — and every one on a first beside which discovery sees a law where it acts: a
/// linearised step on top of a first held at its single fit cannot size a second that the
/// first must make room for (the motor's brush drop, fitted alone, takes up most of its
/// Coulomb friction; beside it, Coulomb friction's screen leaves a cost of 38 900 where the
/// best single leaves 13 100 and the pair 4 800, and discovery finds its sign law). The
/// others could at best tie, and each fit
/// costs tens of simulations of a costly model (the curtain's drag: damping beside a wind,
/// 44 simulations, and three pairs more, where its skin friction beside air drag was at
/// the floor and the cloth offers no estimate to look with). Otherwise all are fitted.
pub(super) fn fit_pairs(
    target: &Target,
    opts: &ExplainOptions,
    judge: &Judge,
    firsts: &[&RankedCandidate],
    seconds: &[Seconds],
    reference_cost: f64,
) -> Vec<Vec<FittedPair>> {
    let looked: Vec<bool> = seconds.iter().map(|s| s.law_on_top).collect();
    let seconds: Vec<&[Screened]> = seconds.iter().map(|s| s.screened.as_slice()).collect();
    let mut order: Vec<(usize, usize)> = (seconds.iter().enumerate())
        .flat_map(|(f, s)| (0..s.len()).map(move |i| (f, i)))
        .collect();
    order.sort_by(|a, b| seconds[a.0][a.1].0.total_cmp(&seconds[b.0][b.1].0));
    let fit =
        |&(f, i): &(usize, usize)| ((f, i), fit_second(target, opts, firsts[f], &seconds[f][i]));
    let (one, two) = order.split_at(order.len().min(FIRST_PAIRS));
    let mut fitted: Vec<((usize, usize), FittedPair)> = one.par_iter().map(fit).collect();
    let settled = (fitted.iter())
        .filter(|(_, (_, b))| {
            b.error.is_none()
                && b.cost < reference_cost
                && all_at_floor(&judge.judge(&b.weighted), opts.floor_factor)
        })
        .min_by(|a, b| a.1.1.cost.total_cmp(&b.1.1.cost));
    let size = |(f, i): (usize, usize)| {
        let c = &seconds[f][i].1;
        firsts[f].candidate.params.len() + c.params.len() - target.n_calibration(c)
    };
    let rest: Vec<(usize, usize)> = match settled {
        Some(&(at, (_, ref b))) => {
            let gained = reference_cost - b.cost;
            let promised = |(f, i): (usize, usize)| reference_cost - seconds[f][i].0;
            (two.iter().copied())
                .filter(|&p| {
                    looked[p.0]
                        || promised(p) >= NEAR_SHARE * gained
                        || (size(p) < size(at) && promised(p) >= CONFIRM_SHARE * gained)
                })
                .collect()
        }
        None => two.to_vec(),
    };
    fitted.extend(rest.par_iter().map(fit).collect::<Vec<_>>());
    fitted.sort_by_key(|(at, _)| *at);
    let mut out: Vec<Vec<FittedPair>> = seconds.iter().map(|_| Vec::new()).collect();
    for ((f, _), pair) in fitted {
        out[f].push(pair);
    }
    out
}

/// The first with the model's free parameters, as it was confirmed, and its values: the
/// pair re-fits the calibration too (held at the calibrated values, a mass "changing" 3 ms
/// into Silverbox's record re-calibrated the mass beside the cubic spring).
fn first_of(target: &Target, best: &RankedCandidate) -> (Candidate, Vec<f64>) {
    let first = best.effect();
    match &best.calibration {
        Some(cal) => (
            target.joint(&prepared(&first.candidate, target.rec)),
            first.values.iter().chain(&cal.values).copied().collect(),
        ),
        None => (prepared(&first.candidate, target.rec), first.values.clone()),
    }
}

/// A second effect on top of `best`, of the `pairs` fitted with it ([`fit_second`]).
/// Returns the pair, ranked, and the joint residual when the best pair's gain over
/// `reference` (the weighted residual of the best single effect) is significant, it moves
/// some output's prediction by as much as its floor (`floors`, σ in the outputs' units:
/// [`MATERIAL_MOVE`]) and it lowers the held-out error.
pub(super) fn second_effect(
    target: &Target,
    opts: &ExplainOptions,
    best: &RankedCandidate,
    pairs: &[FittedPair],
    reference: &[f64],
    base_weighted: &[f64],
    floors: &[f64],
) -> Second {
    let first = best.effect();
    let (first_c, first_values) = first_of(target, best);
    let reference_cost = 0.5 * reference.iter().map(|r| r * r).sum::<f64>();
    // Each pair's evidence over the best single, its second effect's parameters counted; a
    // discovered law must beat a named effect of the menu by the significance margin.
    let gain_of = |joint_first: &Fitted, second: &Fitted| {
        let rhos2 = target.rhos(&joint_first.weighted);
        let k2 = second.candidate.params.len() - target.n_calibration(&second.candidate);
        score(
            target.whitened_cost(reference, &rhos2),
            target.whitened_cost(&joint_first.weighted, &rhos2),
            k2,
            target.n_whitened(),
        )
    };
    let preference = |second: &Fitted, gain: f64| {
        let law = second.candidate.id.starts_with("law@") || first.candidate.id.starts_with("law@");
        gain - if law { opts.significance } else { 0.0 }
    };
    let valid: Vec<(&Fitted, &Fitted, f64)> = pairs
        .iter()
        .filter(|(a, b)| a.error.is_none() && b.error.is_none())
        .map(|(a, b)| (a, b, gain_of(a, b)))
        .collect();
    let Some(&(_, best_second, _)) = valid
        .iter()
        .max_by(|x, y| preference(x.1, x.2).total_cmp(&preference(y.1, y.2)))
    else {
        return Second::None;
    };
    // The simplest of the pairs that leave the same (a wind fitted at 0.01 m/s beside the
    // drag it carries is still air): fewest parameters, then the most evidence.
    let best_cost = best_second.cost;
    let alike =
        |f: &Fitted| f.cost - best_cost <= SAME_EXPLANATION * (reference_cost - best_cost).max(0.0);
    // A named effect before a discovered law, then the fewest parameters.
    let k = |f: &Fitted| (f.candidate.id.starts_with("law@"), f.candidate.params.len());
    let Some((joint_first, second, gain)) = valid
        .iter()
        .filter(|(_, b, _)| alike(b))
        .min_by(|x, y| {
            k(x.1)
                .cmp(&k(y.1))
                .then(preference(y.1, y.2).total_cmp(&preference(x.1, x.2)))
        })
        .copied()
    else {
        return Second::None;
    };
    let rhos2 = target.rhos(&joint_first.weighted);
    if gain <= opts.significance {
        return Second::None;
    }
    // A change at the record's edge acts in one half only, where it cannot be told from the
    // start's state or from a constant: the halves cannot test it, and nothing else can
    // (Silverbox's linear stiffness "changing" 4.3 ms into the record beside the cubic,
    // once the calibration was the first's alone). A pair with one is not added.
    let edges = [
        (&first_c, joint_first.values.as_slice()),
        (&second.candidate, second.values.as_slice()),
    ];
    if let Some((c, t)) = edges
        .iter()
        .find_map(|(c, v)| heldout::edge_time(c, v, target.rec).map(|t| (c, t)))
    {
        return Second::NotAdded(format!(
            "a pair of effects, {} with {}, holds {} ({}) changing at {t:.4} s, at the \
             record's edge, where a change cannot be told from the initial state or a \
             constant, and the halves cannot test it: it is not added",
            first_c.id, second.candidate.id, c.id, c.name
        ));
    }
    // A law holds throughout: fitted on either half, the pair must predict the other half
    // better than the first alone. An event at one time, which a fit on the half before it
    // cannot see, must hold after it: fitted on either half of what follows it (and all
    // before), predict the other half better.
    let held = {
        let single = [(&first_c, first_values.as_slice())];
        let pair = [
            (&first_c, joint_first.values.as_slice()),
            (&second.candidate, second.values.as_slice()),
        ];
        // An event inside the record is held out on the two halves of what follows it.
        let check = heldout::held_out_effect(
            target,
            &single,
            &pair,
            (&second.candidate, second.values.as_slice()),
        );
        match check {
            Some(h) if h.lowers() => h,
            Some(h) => {
                return Second::NotAdded(format!(
                    "a second effect, {} ({}), lowers the error of the whole recording but \
                     not the held-out error (fitted on one half, measured on the other: {}): \
                     it is not added",
                    second.candidate.id,
                    second.candidate.name,
                    h.text()
                ));
            }
            None => {
                return Second::NotAdded(format!(
                    "a second effect, {}, could not be checked on held-out data (a \
                     simulation failed): it is not added",
                    second.candidate.id
                ));
            }
        }
    };
    // Held out, a second must also matter: an effect that nowhere moves any output's
    // prediction by as much as its noise is taking up a model error it does not explain,
    // however many samples it averages over (beside a first that leaves a hum or stands for two
    // stages, an inertia changed by 0.06 % moved the speed by at most 0.6 σ while lowering
    // the error significantly; every second that is the physics moved it by 4 σ or more).
    let mut single = vec![0.0; target.n_residuals()];
    if target
        .residuals(&[(&first_c, first_values.as_slice())], &mut single)
        .is_ok()
    {
        let moved = largest_move(target, floors, &single, &joint_first.weighted);
        if let Some((j, peak)) = moved.filter(|&(_, p)| p < MATERIAL_MOVE) {
            return Second::NotAdded(format!(
                "a second effect, {} ({}), lowers the error but nowhere moves a prediction by \
                 as much as the noise (at most {peak:.2} σ, on `{}`): it is too small to \
                 matter and is not added",
                second.candidate.id, second.candidate.name, target.names[j]
            ));
        }
    }
    let white2 = Whitening {
        cost_before: target.whitened_cost(base_weighted, &rhos2),
        rhos: rhos2,
    };
    let mut first_ranked = ranked(target, joint_first, &white2);
    first_ranked.candidate = best.candidate.clone();
    let mut second_ranked = ranked(target, second, &white2);
    second_ranked.score = gain;
    // The ± of both no smaller than the halves' fits are apart.
    heldout::widen(&mut first_ranked.params, &held, 0);
    heldout::widen(&mut second_ranked.params, &held, 1);
    Second::Kept(
        vec![first_ranked, second_ranked],
        joint_first.weighted.clone(),
    )
}

/// The candidates of the laws found where the model with `best` built in (and the
/// calibration as fitted with it) still misses an effort or flow: discovery's estimate
/// and screen once more, on what the first effect leaves. Empty when the estimate fails.
pub(super) fn laws_on_top(target: &Target, best: &RankedCandidate) -> Vec<Candidate> {
    let effects = target.with_first(best);
    let effects: Vec<(&Candidate, &[f64])> =
        effects.iter().map(|(c, v)| (c, v.as_slice())).collect();
    let Ok(mut missing) =
        (target.model).missing_signals(target.rec, &effects, &target.names, &target.estimate_sigma)
    else {
        return Vec::new();
    };
    missing.sort_by(|a, b| b.explained.total_cmp(&a.explained));
    let linear = target.calibration.is_none();
    let most = missing.first().map_or(0.0, |m| m.explained);
    missing
        .par_iter()
        .filter(|m| m.explained >= 0.5 * most && m.explained > 0.05)
        .flat_map(|m| screen::screen_laws(m, linear))
        .filter_map(|l| target.model.law_candidate(&l))
        .collect()
}

/// A second effect must move some output's prediction, somewhere in the record, by at
/// least this many times the output's noise floor (σ) to be added (dimensionless).
/// Measured on every pair of the batteries: the seconds that are the physics move a
/// prediction by 4 σ to 1600 σ, the ones that take up a model error beside the first
/// (a 0.06 % inertia beside a driver's hum or a single lag for two) by 0.45–0.6 σ.
const MATERIAL_MOVE: f64 = 1.0;

/// The output whose prediction the pair moves most from what the first alone predicts,
/// and by how much at most over the record, in units of that output's floor (`floors`,
/// in the outputs' units; `single` and `pair` weighted residuals).
fn largest_move(
    target: &Target,
    floors: &[f64],
    single: &[f64],
    pair: &[f64],
) -> Option<(usize, f64)> {
    let n = target.rec.len();
    (floors.iter().enumerate())
        .filter(|(_, floor)| **floor > 0.0)
        .map(|(j, floor)| {
            let a = &single[j * n..(j + 1) * n];
            let b = &pair[j * n..(j + 1) * n];
            let peak = a
                .iter()
                .zip(b)
                .map(|(x, y)| (x - y).abs())
                .fold(0.0, f64::max);
            (j, peak * target.sigma[j] / floor)
        })
        .max_by(|x, y| x.1.total_cmp(&y.1))
}
