//! Stage 3 of discovery, **confirm**: each candidate sized by one linearised
//! step on top of what is already built in (the screen of the menu), then the
//! best confirmed by a fit of the simulation error — alone, or jointly with a
//! first effect ([`fit_pair`]) — with the model's free parameters fitted beside
//! it. Ranking and the verdict are in [`super`] and [`crate::judge`].

use super::*;
use crate::effect::EffectParam;

/// The most steps of a pair's joint fit.
const PAIR_ITERATIONS: usize = 12;

/// A pair's joint fit of at least this many parameters updates its Jacobian by secant steps.
const SECANT_PAIR_PARAMS: usize = 6;

/// A start whose weighted residual is within this share (relative, in norm) of the
/// calibrated model's is the calibrated model: the calibration's columns of the Jacobian
/// there serve its screen.
const NOMINAL_TOLERANCE: f64 = 1e-4;

/// The most steps a fit made on the model for fitting goes on for on the model
/// as given, when the two disagree at its end ([`checked_on_the_model_as_given`]).
const CHECK_ITERATIONS: usize = 10;

/// Rounds of [`CHECK_ITERATIONS`] steps on the model as given: another round runs while
/// the last one ended at its step limit and still lowered the cost by a unit of evidence.
/// A law with a kink sharper than the fixed step resolves (a bump stop's contact) is fitted
/// biased on the model for fitting; one round left a stop of 5000 N/m at 5394 N/m, 2.3
/// times the floor, and a pair search then carried the rest beside a "damper that is off"
/// by 0.009 %.
const CHECK_ROUNDS: usize = 5;

/// A fit of one candidate on top of fixed effects; `fixed[i]` pins parameter i.
#[derive(Clone)]
pub(super) struct CandidateProblem<'a> {
    target: &'a Target<'a>,
    /// The model simulated: the target's model for fitting, or the model as given.
    model: &'a dyn Model,
    base: &'a [Effect],
    candidate: &'a Candidate,
    fixed: Vec<Option<f64>>,
    /// The candidate's parameters with a prior (a free parameter of the
    /// model), by index, when the target weighs priors.
    priors: Vec<(usize, Prior)>,
    /// The weighted residual of `model` with `base` alone, when known: where
    /// the candidate vanishes, the problem's own.
    beneath: Option<&'a [f64]>,
}

impl<'a> CandidateProblem<'a> {
    fn new(
        target: &'a Target<'a>,
        base: &'a [Effect],
        candidate: &'a Candidate,
        fixed: Vec<Option<f64>>,
    ) -> Self {
        let priors = if target.prior_weight > 0.0 {
            (candidate.params.iter().enumerate())
                .filter_map(|(i, p)| p.prior.map(|pr| (i, pr)))
                .collect()
        } else {
            Vec::new()
        };
        CandidateProblem {
            target,
            model: target.model,
            base,
            candidate,
            fixed,
            priors,
            beneath: None,
        }
    }
}

impl CandidateProblem<'_> {
    /// The residual of what lies beneath the candidate (the target's nominal one, or
    /// [`CandidateProblem::beneath`]), when the problem at `free` is just that: no prior
    /// rows, the candidate vanishing at its own values and the calibration's (if any) where
    /// calibration put them.
    fn nominal(&self, free: &[f64]) -> Option<&[f64]> {
        let r = if self.base.is_empty() {
            self.target.nominal.as_deref()?
        } else {
            self.beneath?
        };
        if !self.priors.is_empty()
            || !std::ptr::eq(
                self.model as *const dyn Model as *const u8,
                self.target.model as *const dyn Model as *const u8,
            )
        {
            return None;
        }
        let full = self.full(free);
        let own = self.candidate.params.len() - self.target.n_calibration(self.candidate);
        let calibrated =
            (self.candidate.params[own..].iter().zip(&full[own..])).all(|(p, v)| *v == p.initial);
        let mut plain = self.candidate.clone();
        plain.params.truncate(own);
        (calibrated && self.target.model.vanishes(&plain, &full[..own])).then_some(r)
    }

    fn full(&self, free: &[f64]) -> Vec<f64> {
        let mut it = free.iter();
        self.fixed
            .iter()
            .map(|f| f.unwrap_or_else(|| *it.next().unwrap_or(&0.0)))
            .collect()
    }
}

impl ResidualProblem for CandidateProblem<'_> {
    fn n_params(&self) -> usize {
        self.fixed.iter().filter(|f| f.is_none()).count()
    }

    fn n_residuals(&self) -> usize {
        self.target.n_residuals() + self.priors.len()
    }

    /// One series per output, then the priors.
    fn series_length(&self) -> Option<usize> {
        Some(self.target.rec.len())
    }

    /// The data's weighted residuals, then one row per prior.
    fn residuals(&self, params: &[f64], out: &mut [f64]) -> Result<()> {
        let full = self.full(params);
        let mut effects: Vec<(&Candidate, &[f64])> = self
            .base
            .iter()
            .map(|e| (&e.candidate, e.values.as_slice()))
            .collect();
        effects.push((self.candidate, &full));
        let (data, priors) = out.split_at_mut(self.target.n_residuals());
        self.target.residuals_of(self.model, &effects, data)?;
        for (o, (i, prior)) in priors.iter_mut().zip(&self.priors) {
            *o = self.target.prior_weight * (full[*i] - prior.mean) / prior.std;
        }
        Ok(())
    }
}

/// A joint fit of two candidates (on top of nothing else): the parameters
/// of `first` then those of `second`.
#[derive(Clone, Copy)]
pub(super) struct PairProblem<'a> {
    target: &'a Target<'a>,
    /// The model simulated: the target's model for fitting, or the model as given.
    model: &'a dyn Model,
    first: &'a Candidate,
    second: &'a Candidate,
}

impl ResidualProblem for PairProblem<'_> {
    fn n_params(&self) -> usize {
        self.first.params.len() + self.second.params.len()
    }

    fn n_residuals(&self) -> usize {
        self.target.n_residuals()
    }

    /// One series per output.
    fn series_length(&self) -> Option<usize> {
        Some(self.target.rec.len())
    }

    fn residuals(&self, params: &[f64], out: &mut [f64]) -> Result<()> {
        let (a, b) = params.split_at(self.first.params.len());
        self.target
            .residuals_of(self.model, &[(self.first, a), (self.second, b)], out)
    }
}

/// Fits `first` and `second` jointly from `start` (their values in that
/// order). Returns the two fitted effects' values, the report and the
/// weighted residual.
pub(super) fn fit_pair(
    target: &Target,
    first: &Candidate,
    second: &Candidate,
    start: &[f64],
    opts: &ExplainOptions,
) -> Result<(FitReport, Vec<f64>)> {
    let problem = PairProblem {
        target,
        model: target.model,
        first,
        second,
    };
    let params: Vec<&crate::effect::EffectParam> =
        first.params.iter().chain(&second.params).collect();
    // A parameter on a lattice (a cloth's vertex) stays where its single fit's search put it:
    // a finite difference of a fraction of a vertex moves nothing, and each cost a simulation
    // (the curtain's damping beside a point mass: 43 simulations for two parameters that move).
    let bounds: Vec<(f64, f64)> = (params.iter().zip(start))
        .map(|(p, &x)| {
            if p.is_discrete() {
                (x, x)
            } else {
                (p.lower, p.upper)
            }
        })
        .collect();
    let scales: Vec<f64> = params.iter().map(|p| p.scale).collect();
    let checked = PairProblem {
        model: target.accurate.unwrap_or(target.model),
        ..problem
    };
    let name = format!("{} + {}", first.name, second.name);
    // A pair that has not settled in this many steps is not the pair: it ranks by where it
    // got (on the curtain, damping beside a wind crawled 26 steps, 168 simulations, to leave
    // thirteen times what the right pair leaves).
    let mut opts = opts.clone();
    opts.fit.max_iterations = opts.fit.max_iterations.min(PAIR_ITERATIONS);
    // A pair with many parameters (Silverbox's cubic spring beside a second, its six free
    // parameters fitted with them: nine or ten) updates its Jacobian by secant steps between
    // finite-difference ones, as a costly model's fits do: a step then costs one simulation
    // instead of ten (Silverbox's pairs 58.6 → 16.3 s CPU, its verdict and its error left
    // the same).
    opts.fit.secant |= params.len() >= SECANT_PAIR_PARAMS;
    fit_and_check(
        target, &problem, &checked, start, &bounds, &scales, name, &opts,
    )
}

/// Fits `problem` (on the target's model for fitting) from `start`, with the model's own
/// tolerances and finite-difference steps, then holds the fit against `accurate` (the same
/// problem on the model as given, [`checked_on_the_model_as_given`]): the report and the
/// weighted residual there.
#[allow(clippy::too_many_arguments)]
fn fit_and_check(
    target: &Target,
    problem: &dyn ResidualProblem,
    accurate: &dyn ResidualProblem,
    start: &[f64],
    bounds: &[(f64, f64)],
    scales: &[f64],
    name: String,
    opts: &ExplainOptions,
) -> Result<(FitReport, Vec<f64>)> {
    let mut fit_opts = fit_options_for(target.model, opts, scales);
    fit_opts.name = name;
    let report = fit(
        problem,
        start,
        bounds,
        scales,
        &fit_opts,
        opts.cancel.as_deref(),
    )?;
    checked_on_the_model_as_given(target, accurate, report, bounds, scales, &fit_opts, opts)
}

/// A fit made on the target's model for fitting, held against the model as
/// given: its report and weighted residual there. When the two models' costs
/// at the point found differ by more than one unit of evidence (a relative
/// difference above `1 / n`, `n` the number of whitened samples: an effect
/// sharper than the fixed step resolves), the fit goes on from that point on
/// the model as given, for at most [`CHECK_ITERATIONS`] steps. `accurate` is
/// the problem on the model as given (the same as the fit's when there is no
/// copy for fitting).
fn checked_on_the_model_as_given(
    target: &Target,
    accurate: &dyn ResidualProblem,
    mut report: FitReport,
    bounds: &[(f64, f64)],
    scales: &[f64],
    fit_opts: &FitOptions,
    opts: &ExplainOptions,
) -> Result<(FitReport, Vec<f64>)> {
    let mut weighted = vec![0.0; accurate.n_residuals()];
    accurate.residuals(&report.params, &mut weighted)?;
    if target.accurate.is_none() {
        return Ok((report, weighted));
    }
    let cost = 0.5 * weighted.iter().map(|r| r * r).sum::<f64>();
    let n = target.n_whitened();
    if !(cost.is_finite() && (cost - report.cost_after).abs() * n <= cost) {
        let again = FitOptions {
            max_iterations: CHECK_ITERATIONS,
            ..fit_opts.clone()
        };
        for _ in 0..CHECK_ROUNDS {
            let start = report.params.clone();
            let mut polished = fit(
                accurate,
                &start,
                bounds,
                scales,
                &again,
                opts.cancel.as_deref(),
            )?;
            let (before, after) = (polished.cost_before, polished.cost_after);
            polished.iterations += report.iterations;
            polished.evaluations += report.evaluations;
            polished.cost_before = report.cost_before;
            report = polished;
            let more = report.termination == crate::fit::Termination::MaxIterations
                && (before - after) * n > after;
            if !more {
                break;
            }
        }
        accurate.residuals(&report.params, &mut weighted)?;
    } else {
        report.cost_after = cost;
    }
    Ok((report, weighted))
}

/// The candidate with its bounds fitted to the recording: a fault time lies
/// inside it, two samples from either end.
pub(super) fn prepared(c: &Candidate, rec: &Recording) -> Candidate {
    let mut c = c.clone();
    let t = rec.t();
    if let (Some(&t0), Some(&t1)) = (t.first(), t.last()) {
        let dt = if t.len() > 1 {
            (t1 - t0) / (t.len() - 1) as f64
        } else {
            0.0
        };
        for p in &mut c.params {
            if p.name == "t_fault" && p.unit == "s" {
                p.lower = t0 + 2.0 * dt;
                p.upper = (t1 - 2.0 * dt).max(p.lower);
                p.initial = 0.5 * (p.lower + p.upper);
                p.scale = (t1 - t0) / 20.0;
                if p.grid == 0 {
                    p.grid = 24;
                }
            }
        }
    }
    c
}

/// One Gauss–Newton step from `x0` (forward differences with absolute
/// `steps`), clamped to the bounds: returns the cost the linearised model
/// predicts there (½‖r + J δ‖², never below 0) and the point. Two residual
/// evaluations per parameter at most; `None` if the start cannot be simulated.
pub(super) fn linearised_step(
    problem: &CandidateProblem,
    x0: &[f64],
    steps: &[f64],
    bounds: &[(f64, f64)],
) -> Option<(f64, Vec<f64>, Vec<f64>)> {
    let m = problem.n_residuals();
    let k = x0.len();
    // Where the candidate leaves the model as it is, its residual is the model's own.
    let r0 = match problem.nominal(x0) {
        Some(r) => r.to_vec(),
        None => {
            let mut r0 = vec![0.0; m];
            problem.residuals(x0, &mut r0).ok()?;
            r0
        }
    };
    if r0.iter().any(|v| !v.is_finite()) {
        return None;
    }
    let cost0 = 0.5 * r0.iter().map(|v| v * v).sum::<f64>();
    if k == 0 {
        return Some((cost0, Vec::new(), r0));
    }
    let mut jac = nalgebra::DMatrix::zeros(m, k);
    let mut r1 = vec![0.0; m];
    let mut x = x0.to_vec();
    for j in 0..k {
        let h = step_in_box(x0[j], steps[j], bounds[j].0, bounds[j].1);
        if h == 0.0 {
            continue;
        }
        x[j] = x0[j] + h;
        if problem.residuals(&x, &mut r1).is_err() || r1.iter().any(|v| !v.is_finite()) {
            return Some((cost0, x0.to_vec(), r0));
        }
        x[j] = x0[j];
        for i in 0..m {
            jac[(i, j)] = (r1[i] - r0[i]) / h;
        }
    }
    // From where the candidate leaves the model as calibrated, the calibration re-adjusts
    // beside it (its columns are the same for every such start), as in the confirming fit;
    // what the calibration alone would gain is not the candidate's.
    // (A bond graph's edit of a missing element at 0 is not the graph as it was, but it
    // predicts the same to the solver's tolerance.)
    let at_nominal = problem.nominal(x0).is_some()
        || (problem.target.nominal.as_deref()).is_some_and(|n| {
            if n.len() != r0.len() {
                // A problem weighing priors has their residuals after the data's.
                return false;
            }
            let d: f64 = n.iter().zip(&r0).map(|(a, b)| (a - b) * (a - b)).sum();
            let s: f64 = n.iter().map(|a| a * a).sum();
            d <= NOMINAL_TOLERANCE * NOMINAL_TOLERANCE * s
        });
    let cal: &[Vec<f64>] = if at_nominal
        && problem.base.is_empty()
        && (problem.target.calibration_columns.iter()).all(|c| c.len() == m)
    {
        &problem.target.calibration_columns
    } else {
        &[]
    };
    let r0v = nalgebra::DVector::from_column_slice(&r0);
    let cal_jac = nalgebra::DMatrix::from_fn(m, cal.len(), |i, j| cal[j][i]);
    let cal_normal = (cal_jac.transpose() * &cal_jac).lu();
    // The residual `r` after the calibration's least-squares move.
    let readjusted = |r: nalgebra::DVector<f64>| -> nalgebra::DVector<f64> {
        if cal.is_empty() {
            return r;
        }
        match cal_normal.solve(&(-(cal_jac.transpose() * &r))) {
            Some(d) => r + &cal_jac * d,
            None => r,
        }
    };
    // The candidate's columns, then the calibration's.
    let mut full_jac = jac.clone().resize_horizontally(k + cal.len(), 0.0);
    if !cal.is_empty() {
        full_jac.columns_mut(k, cal.len()).copy_from(&cal_jac);
    }
    let jt_j = full_jac.transpose() * &full_jac;
    let jt_r = full_jac.transpose() * &r0v;
    let delta = jt_j
        .lu()
        .solve(&(-jt_r))
        .unwrap_or_else(|| nalgebra::DVector::zeros(k + cal.len()));
    let x1: Vec<f64> = (0..k)
        .map(|j| (x0[j] + delta[j]).clamp(bounds[j].0, bounds[j].1))
        .collect();
    let d = nalgebra::DVector::from_iterator(k, (0..k).map(|j| x1[j] - x0[j]));
    // The step's residual with the calibration re-adjusted, less what the calibration
    // re-adjusted alone would remove.
    let predicted = readjusted(&r0v + &jac * d) - (readjusted(r0v.clone()) - &r0v);
    let cost1 = 0.5 * predicted.iter().map(|v| v * v).sum::<f64>();
    Some(if cost1 < cost0 {
        (cost1, x1, predicted.as_slice().to_vec())
    } else {
        (cost0, x0.to_vec(), r0)
    })
}

/// Result of fitting one candidate (before scoring).
pub(super) struct Fitted {
    pub(super) candidate: Candidate,
    pub(super) values: Vec<f64>,
    pub(super) report: Option<FitReport>,
    pub(super) cost: f64,
    pub(super) weighted: Vec<f64>,
    pub(super) error: Option<String>,
    /// Sized by the screen alone (not confirmed by a fit).
    pub(super) screened: bool,
}

/// Where the confirming fit of a candidate starts, and what the screen
/// predicts there.
#[derive(Clone)]
pub(super) struct Start {
    /// The full parameter vector the screen started from (the best grid point; the
    /// calibration's at their calibrated values): where the confirming fit starts.
    pub(super) from: Vec<f64>,
    /// Where the screen's linearised step went.
    pub(super) x: Vec<f64>,
    /// The cost a linearised step predicts at `x`.
    pub(super) cost: f64,
    /// The weighted residual it predicts there (the data's rows).
    pub(super) predicted: Vec<f64>,
}

/// The screen of one candidate on top of `base`: the cost one linearised
/// (Gauss–Newton) step in its own parameters reaches from its start, the
/// model's free parameters held at their calibrated values — from the best
/// point of its grid when it has grid parameters (every combination scored
/// so, in parallel). `k + 1` simulations per start, `k` where the candidate
/// vanishes at its start and `beneath` (the weighted residual with `base`
/// alone, on the target's model) is known.
pub(super) fn screen_candidate(
    target: &Target,
    base: &[Effect],
    beneath: Option<&[f64]>,
    c: &Candidate,
    opts: &ExplainOptions,
) -> std::result::Result<Start, String> {
    let cancel = opts.cancel.as_deref();
    let bounds: Vec<(f64, f64)> = c.params.iter().map(|p| (p.lower, p.upper)).collect();
    let scales: Vec<f64> = c.params.iter().map(|p| p.scale).collect();
    let own = c.params.len() - target.n_calibration(c);
    // Grid starts: the cartesian product of each grid parameter's points.
    let grid_axes: Vec<(usize, Vec<f64>)> = c
        .params
        .iter()
        .enumerate()
        .filter(|(_, p)| p.grid > 0)
        .map(|(i, p)| (i, p.grid_points()))
        .collect();
    let mut combos: Vec<Vec<usize>> = vec![Vec::new()];
    for (_, pts) in &grid_axes {
        combos = combos
            .into_iter()
            .flat_map(|prefix| (0..pts.len()).map(move |k| [prefix.clone(), vec![k]].concat()))
            .collect();
    }
    let scored: Vec<Start> = combos
        .par_iter()
        .filter_map(|combo| {
            if cancel.is_some_and(Cancel::is_cancelled) {
                return None;
            }
            let mut fixed: Vec<Option<f64>> = vec![None; c.params.len()];
            for (a, (i, pts)) in grid_axes.iter().enumerate() {
                fixed[*i] = Some(pts[combo[a]]);
            }
            // The calibration's parameters held where calibration put them, and a lattice
            // parameter off the grid at its start (a gradient cannot move it).
            for (i, p) in c.params.iter().enumerate() {
                if i >= own || (p.is_discrete() && fixed[i].is_none()) {
                    fixed[i] = Some(p.initial);
                }
            }
            let problem = CandidateProblem {
                beneath,
                ..CandidateProblem::new(target, base, c, fixed)
            };
            let free_idx: Vec<usize> = (0..c.params.len())
                .filter(|i| problem.fixed[*i].is_none())
                .collect();
            let x0: Vec<f64> = free_idx.iter().map(|&i| c.params[i].initial).collect();
            let fd = screen_fd_step(target.model);
            let steps: Vec<f64> = free_idx.iter().map(|&i| fd * scales[i]).collect();
            let b: Vec<(f64, f64)> = free_idx.iter().map(|&i| bounds[i]).collect();
            let (cost, free, mut predicted) = linearised_step(&problem, &x0, &steps, &b)?;
            predicted.truncate(target.n_residuals());
            cost.is_finite().then(|| Start {
                from: problem.full(&x0),
                x: problem.full(&free),
                cost,
                predicted,
            })
        })
        .collect();
    let best = scored
        .into_iter()
        .min_by(|a, b| a.cost.total_cmp(&b.cost))
        .ok_or_else(|| {
            if grid_axes.is_empty() {
                "the model cannot be simulated with this effect at its start".to_string()
            } else {
                "no grid start could be simulated".to_string()
            }
        })?;
    // When the grid holds every one of the candidate's own parameters, the grid point alone
    // would be its size (a skin friction scored at 0, 2.5 and 5 only, never at the 0.5 a
    // curtain shows): its continuous ones take the linearised step from the best point.
    let stepped: Vec<usize> = (0..own).filter(|&i| !c.params[i].is_discrete()).collect();
    if stepped.is_empty() || (0..own).any(|i| !c.params[i].is_discrete() && c.params[i].grid == 0) {
        return Ok(best);
    }
    let fixed: Vec<Option<f64>> = (0..c.params.len())
        .map(|i| (!stepped.contains(&i)).then_some(best.from[i]))
        .collect();
    let problem = CandidateProblem::new(target, base, c, fixed);
    let x0: Vec<f64> = stepped.iter().map(|&i| best.from[i]).collect();
    let fd = screen_fd_step(target.model);
    let steps: Vec<f64> = stepped.iter().map(|&i| fd * scales[i]).collect();
    let b: Vec<(f64, f64)> = stepped.iter().map(|&i| bounds[i]).collect();
    match linearised_step(&problem, &x0, &steps, &b) {
        Some((cost, free, mut predicted)) if cost < best.cost => {
            predicted.truncate(target.n_residuals());
            Ok(Start {
                x: problem.full(&free),
                cost,
                predicted,
                ..best
            })
        }
        _ => Ok(best),
    }
}

/// Fits one candidate on top of `base`: its screen, then a local fit of
/// every parameter from the screen's point.
pub(super) fn fit_candidate(
    target: &Target,
    base: &[Effect],
    candidate: &Candidate,
    opts: &ExplainOptions,
) -> Fitted {
    let c = prepared(candidate, target.rec);
    match screen_candidate(target, base, None, &c, opts) {
        Ok(start) => confirm(target, base, &c, &start.from, opts),
        Err(e) => failed_fit(&c, e),
    }
}

/// A candidate whose screen or fit failed.
pub(super) fn failed_fit(c: &Candidate, error: String) -> Fitted {
    Fitted {
        candidate: c.clone(),
        values: c.initial(),
        report: None,
        cost: f64::INFINITY,
        weighted: Vec::new(),
        error: Some(error),
        screened: false,
    }
}

/// A candidate sized by the screen alone: its linearised step's point, cost
/// and residual, never fitted by simulation.
pub(super) fn screened_fit(c: &Candidate, start: Start) -> Fitted {
    Fitted {
        candidate: c.clone(),
        values: start.x,
        report: None,
        cost: start.cost,
        weighted: start.predicted,
        error: None,
        screened: true,
    }
}

/// The confirming fit: every parameter (the candidate's and the model's
/// free ones) fitted by simulation error from `start`.
pub(super) fn confirm(
    target: &Target,
    base: &[Effect],
    c: &Candidate,
    start: &[f64],
    opts: &ExplainOptions,
) -> Fitted {
    if c.params.iter().any(EffectParam::is_discrete) {
        return confirm_on_lattice(target, base, c, start, opts);
    }
    match fit_held(target, base, c, start, &[], opts) {
        Ok((report, weighted)) => confirmed(target, c, report, weighted),
        Err(e) => failed_fit(c, e.to_string()),
    }
}

/// A law confirmed with more than one term (`fitted`), made as simple as its
/// evidence allows: each term dropped in turn — the law without it built and
/// fitted from the confirmed values — and the drop that costs least (of drops
/// within the significance margin of it, the one leaving fewest parameters) taken
/// while the simpler law scores at least as well (evidence over the model as
/// given, `base_weighted`, whitened with the full law's noise model, its
/// parameters counted); then again on what is left. The screen may take a
/// term to mend a shape its estimate bent (the calibration took part of a law
/// that is not linear, the smoother lags a sharp one); the joint fit no
/// longer needs it.
pub(super) fn simplest_law(
    target: &Target,
    law: &screen::Law,
    fitted: Fitted,
    base_weighted: &[f64],
    opts: &ExplainOptions,
) -> Fitted {
    let rhos = target.rhos(&fitted.weighted);
    let before = target.whitened_cost(base_weighted, &rhos);
    let evidence = |f: &Fitted| {
        let own = f.candidate.params.len() - target.n_calibration(&f.candidate);
        score(
            before,
            target.whitened_cost(&f.weighted, &rhos),
            own,
            target.n_whitened(),
        )
    };
    let mut law = law.clone();
    let mut best = fitted;
    while law.terms.len() > 1 {
        let trials: Vec<(screen::Law, Fitted)> = (0..law.terms.len())
            .into_par_iter()
            .filter_map(|j| {
                let mut smaller = law.clone();
                smaller.terms.remove(j);
                let c = prepared(
                    &target.joint(&target.model.law_candidate(&smaller)?),
                    target.rec,
                );
                // From the confirmed values, by name (the law's parameter names are unique).
                let start: Vec<f64> = (c.params.iter())
                    .map(|p| {
                        (best.candidate.params.iter().zip(&best.values))
                            .find(|(q, _)| q.name == p.name)
                            .map_or(p.initial, |(_, v)| v.clamp(p.lower, p.upper))
                    })
                    .collect();
                let f = confirm(target, &[], &c, &start, opts);
                f.error.is_none().then_some((smaller, f))
            })
            .collect();
        // The drop with the most evidence; of drops within the significance margin of it,
        // the one that leaves the fewest parameters (a sign with a constant beside it and a
        // sign with a sharp `|tanh|` beside it, on a drive with an offset, scored 55072.8
        // and 55071.4: which of them won turned on how far their fits were polished).
        let floor = evidence(&best);
        let trials: Vec<(screen::Law, Fitted)> = (trials.into_iter())
            .filter(|t| evidence(&t.1) >= floor)
            .collect();
        let most = (trials.iter())
            .map(|t| evidence(&t.1))
            .fold(f64::NEG_INFINITY, f64::max);
        let Some((smaller, f)) = trials
            .into_iter()
            .filter(|t| evidence(&t.1) >= most - opts.significance)
            .min_by(|a, b| {
                (a.1.candidate.params.len())
                    .cmp(&b.1.candidate.params.len())
                    .then(evidence(&b.1).total_cmp(&evidence(&a.1)))
            })
        else {
            break;
        };
        law = smaller;
        best = f;
    }
    best
}

/// A candidate confirmed by a fit: its report and weighted residual (the data's rows only:
/// the priors' are part of the fit, not of the residual).
fn confirmed(target: &Target, c: &Candidate, report: FitReport, mut weighted: Vec<f64>) -> Fitted {
    weighted.truncate(target.n_residuals());
    Fitted {
        candidate: c.clone(),
        values: report.params.clone(),
        cost: report.cost_after,
        report: Some(report),
        weighted,
        error: None,
        screened: false,
    }
}

/// The most rounds of moves and refits a lattice search makes.
const LATTICE_ROUNDS: usize = 6;

/// The confirming fit of a candidate with discrete parameters
/// ([`EffectParam::step`]): the continuous ones fitted by simulation error
/// with the discrete held, then a compass search on the lattice — each
/// discrete parameter moved by a stride of whole steps either way, with the
/// continuous held, while a move lowers the error, the stride halved from
/// about half its grid's spacing down to one step — and the continuous ones
/// fitted again where it stopped, until no move lowers the error. A gradient
/// cannot place a lattice parameter (the error is flat between its points).
fn confirm_on_lattice(
    target: &Target,
    base: &[Effect],
    c: &Candidate,
    start: &[f64],
    opts: &ExplainOptions,
) -> Fitted {
    let on_lattice = |i: usize, v: f64| {
        let p = &c.params[i];
        let top = ((p.upper - p.lower) / p.step).floor();
        p.lower + ((v - p.lower) / p.step).round().clamp(0.0, top) * p.step
    };
    let discrete: Vec<usize> = (0..c.params.len())
        .filter(|&i| c.params[i].is_discrete())
        .collect();
    let mut x: Vec<f64> = start.to_vec();
    for &i in &discrete {
        x[i] = on_lattice(i, x[i]);
    }
    // The widest stride: a power of two about half the grid's spacing, in steps.
    let widest = (discrete.iter())
        .map(|&i| {
            let p = &c.params[i];
            let spacing = (p.upper - p.lower) / (p.grid.max(2) - 1) as f64;
            (0.5 * spacing / p.step).max(1.0).log2().floor().exp2()
        })
        .fold(1.0, f64::max);
    let fit_at = |x: &[f64]| fit_held(target, base, c, x, &discrete, opts);
    let mut fitted = match fit_at(&x) {
        Ok(f) => f,
        Err(e) => return failed_fit(c, e.to_string()),
    };
    let held_cost = |x: &[f64]| {
        let problem = CandidateProblem::new(target, base, c, x.iter().map(|v| Some(*v)).collect());
        let mut r = vec![0.0; problem.n_residuals()];
        match problem.residuals(&[], &mut r) {
            Ok(()) if r.iter().all(|v| v.is_finite()) => 0.5 * r.iter().map(|v| v * v).sum::<f64>(),
            _ => f64::INFINITY,
        }
    };
    for _ in 0..LATTICE_ROUNDS {
        if opts.cancel.as_deref().is_some_and(Cancel::is_cancelled) {
            break;
        }
        let mut x = fitted.0.params.clone();
        // Moves are scored on the model the fits simulate; so is the point they move from
        // (the fit's own cost is the model's as given).
        let mut cost = held_cost(&x);
        let mut moved = false;
        let mut stride = widest;
        while stride >= 1.0 {
            // Every move of this stride, scored in parallel; the best taken while it helps.
            let moves: Vec<Vec<f64>> = (discrete.iter())
                .flat_map(|&i| [-1.0, 1.0].map(|dir| (i, dir)))
                .filter_map(|(i, dir)| {
                    let v = on_lattice(i, x[i] + dir * stride * c.params[i].step);
                    (v != x[i]).then(|| {
                        let mut y = x.clone();
                        y[i] = v;
                        y
                    })
                })
                .collect();
            let best = (moves.into_par_iter())
                .map(|y| (held_cost(&y), y))
                .min_by(|a, b| a.0.total_cmp(&b.0));
            match best {
                Some((cy, y)) if cy < cost => {
                    (x, cost, moved) = (y, cy, true);
                }
                _ => stride *= 0.5,
            }
        }
        if !moved {
            break;
        }
        match fit_at(&x) {
            Ok(f) if f.0.cost_after < fitted.0.cost_after => fitted = f,
            _ => break,
        }
    }
    let (report, weighted) = fitted;
    confirmed(target, c, report, weighted)
}

/// A fit of `c`'s parameters from `x` with those in `held` held at their
/// values there: its report over every parameter (a held one has no ±) and
/// the weighted residual on the model as given.
fn fit_held(
    target: &Target,
    base: &[Effect],
    c: &Candidate,
    x: &[f64],
    held: &[usize],
    opts: &ExplainOptions,
) -> Result<(FitReport, Vec<f64>)> {
    let fixed: Vec<Option<f64>> = (0..x.len())
        .map(|i| held.contains(&i).then_some(x[i]))
        .collect();
    let free: Vec<usize> = (0..x.len()).filter(|i| !held.contains(i)).collect();
    let bounds: Vec<(f64, f64)> = (free.iter())
        .map(|&i| (c.params[i].lower, c.params[i].upper))
        .collect();
    let scales: Vec<f64> = free.iter().map(|&i| c.params[i].scale).collect();
    let x0: Vec<f64> = free.iter().map(|&i| x[i]).collect();
    let problem = CandidateProblem::new(target, base, c, fixed);
    let checked = CandidateProblem {
        model: target.accurate.unwrap_or(target.model),
        ..problem.clone()
    };
    let (report, weighted) = fit_and_check(
        target,
        &problem,
        &checked,
        &x0,
        &bounds,
        &scales,
        c.name.clone(),
        opts,
    )?;
    // The report over every parameter: the held ones at their values, with no ±.
    let n = x.len();
    let slot = |i: usize| free.iter().position(|&f| f == i);
    let params = (0..n)
        .map(|i| slot(i).map_or(x[i], |k| report.params[k]))
        .collect();
    let std_errors = (0..n)
        .map(|i| slot(i).map_or(f64::INFINITY, |k| report.std_errors[k]))
        .collect();
    let robust_std_errors = (0..n)
        .map(|i| slot(i).map_or(f64::INFINITY, |k| report.robust_std_errors[k]))
        .collect();
    let correlation = (0..n)
        .map(|i| {
            (0..n)
                .map(|j| match (slot(i), slot(j)) {
                    (Some(a), Some(b)) => report.correlation[a][b],
                    _ if i == j => 1.0,
                    _ => 0.0,
                })
                .collect()
        })
        .collect();
    Ok((
        FitReport {
            params,
            std_errors,
            robust_std_errors,
            correlation,
            ..report
        },
        weighted,
    ))
}

pub(super) fn failed_clone(f: &Fitted) -> Fitted {
    Fitted {
        candidate: f.candidate.clone(),
        values: f.values.clone(),
        report: None,
        cost: f64::INFINITY,
        weighted: Vec::new(),
        error: f.error.clone(),
        screened: false,
    }
}
