//! Stage 3 of discovery, **confirm**: each candidate sized by one linearised
//! step on top of what is already built in (the screen of the menu), then the
//! best confirmed by a fit of the simulation error — alone, or jointly with a
//! first effect ([`fit_pair`]) — with the model's free parameters fitted beside
//! it. Ranking and the verdict are in [`super`] and [`crate::judge`].

use super::*;

/// The most steps a fit made on the model for fitting goes on for on the model
/// as given, when the two disagree at its end ([`checked_on_the_model_as_given`]).
const CHECK_ITERATIONS: usize = 10;

/// A fit of one candidate on top of fixed effects; `fixed[i]` pins parameter i.
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
        }
    }
}

impl CandidateProblem<'_> {
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
    let bounds: Vec<(f64, f64)> = params.iter().map(|p| (p.lower, p.upper)).collect();
    let scales: Vec<f64> = params.iter().map(|p| p.scale).collect();
    let mut fit_opts = fit_options(target.model, opts);
    fit_opts.name = format!("{} + {}", first.name, second.name);
    let report = fit(
        &problem,
        start,
        &bounds,
        &scales,
        &fit_opts,
        opts.cancel.as_deref(),
    )?;
    let checked = PairProblem {
        model: target.accurate.unwrap_or(target.model),
        ..problem
    };
    checked_on_the_model_as_given(target, &checked, report, &bounds, &scales, &fit_opts, opts)
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
        let start = report.params.clone();
        let mut polished = fit(
            accurate,
            &start,
            bounds,
            scales,
            &again,
            opts.cancel.as_deref(),
        )?;
        polished.iterations += report.iterations;
        polished.evaluations += report.evaluations;
        polished.cost_before = report.cost_before;
        report = polished;
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
    let mut r0 = vec![0.0; m];
    problem.residuals(x0, &mut r0).ok()?;
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
        let h = if x0[j] + steps[j] <= bounds[j].1 {
            steps[j]
        } else {
            -steps[j]
        };
        x[j] = x0[j] + h;
        if problem.residuals(&x, &mut r1).is_err() || r1.iter().any(|v| !v.is_finite()) {
            return Some((cost0, x0.to_vec(), r0));
        }
        x[j] = x0[j];
        for i in 0..m {
            jac[(i, j)] = (r1[i] - r0[i]) / h;
        }
    }
    let jt_j = jac.transpose() * &jac;
    let jt_r = jac.transpose() * nalgebra::DVector::from_column_slice(&r0);
    let delta = jt_j
        .clone()
        .lu()
        .solve(&(-jt_r))
        .unwrap_or_else(|| nalgebra::DVector::zeros(k));
    let x1: Vec<f64> = (0..k)
        .map(|j| (x0[j] + delta[j]).clamp(bounds[j].0, bounds[j].1))
        .collect();
    let d = nalgebra::DVector::from_iterator(k, (0..k).map(|j| x1[j] - x0[j]));
    let predicted = nalgebra::DVector::from_column_slice(&r0) + &jac * d;
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
/// so, in parallel). `k + 1` simulations per start.
pub(super) fn screen_candidate(
    target: &Target,
    base: &[Effect],
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
        .map(|(i, p)| {
            let n = p.grid.max(1);
            let pts = (0..n)
                .map(|k| {
                    if n == 1 {
                        p.initial
                    } else {
                        p.lower + (p.upper - p.lower) * k as f64 / (n - 1) as f64
                    }
                })
                .collect();
            (i, pts)
        })
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
            // The calibration's parameters held where calibration put them.
            for (i, p) in c.params.iter().enumerate().skip(own) {
                fixed[i] = Some(p.initial);
            }
            let problem = CandidateProblem::new(target, base, c, fixed);
            let free_idx: Vec<usize> = (0..c.params.len())
                .filter(|i| problem.fixed[*i].is_none())
                .collect();
            let x0: Vec<f64> = free_idx.iter().map(|&i| c.params[i].initial).collect();
            let steps: Vec<f64> = free_idx.iter().map(|&i| GRID_FD_STEP * scales[i]).collect();
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
    scored
        .into_iter()
        .min_by(|a, b| a.cost.total_cmp(&b.cost))
        .ok_or_else(|| {
            if grid_axes.is_empty() {
                "the model cannot be simulated with this effect at its start".to_string()
            } else {
                "no grid start could be simulated".to_string()
            }
        })
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
    match screen_candidate(target, base, &c, opts) {
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
    let mut fit_opts = fit_options(target.model, opts);
    fit_opts.name = c.name.clone();
    let cancel = opts.cancel.as_deref();
    let bounds: Vec<(f64, f64)> = c.params.iter().map(|p| (p.lower, p.upper)).collect();
    let scales: Vec<f64> = c.params.iter().map(|p| p.scale).collect();
    let problem = CandidateProblem::new(target, base, c, vec![None; c.params.len()]);
    let res = fit(&problem, start, &bounds, &scales, &fit_opts, cancel);
    let checked = CandidateProblem {
        model: target.accurate.unwrap_or(target.model),
        ..problem
    };
    let res = res.and_then(|report| {
        checked_on_the_model_as_given(target, &checked, report, &bounds, &scales, &fit_opts, opts)
    });
    match res {
        Ok((report, mut weighted)) => {
            // The data's rows only: the priors' are part of the fit, not of the residual.
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
        Err(e) => failed_fit(c, e.to_string()),
    }
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
