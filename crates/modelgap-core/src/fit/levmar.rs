//! Bounded Levenberg–Marquardt in scaled variables: [`fit`] and its [`FitOptions`].
//!
//! See the [module docs](super) for the method.

use crate::error::{CoreError, Result};
use crate::math::{DMatrix, DVector};

use super::problem::{Cancel, ResidualProblem};
use super::report::{FitReport, Termination, uncertainty};

/// The default finite-difference step, relative to each parameter's scale (an absolute
/// step of `DEFAULT_FD_STEP × scale`): √(10⁻⁸), for residuals that come from adaptive
/// simulations at a relative tolerance of 10⁻⁸ (see the [module docs](super)).
pub const DEFAULT_FD_STEP: f64 = 1e-4;

/// An accepted step that lowered the cost by more than this many times what the linear
/// model predicted is followed further ([`Solver::extend`]).
const EXTEND_RATIO: f64 = 1.25;

/// The most extensions of one accepted step.
const MAX_EXTENSIONS: usize = 4;

/// Nielsen's initial damping, relative to the largest diagonal entry of JᵀJ (τ in Madsen,
/// Nielsen & Tingleff 2004, who suggest 10⁻⁶…1; 10⁻³ suits starts that are not close).
const TAU: f64 = 1e-3;

/// Consecutive rejected trial steps before the fit gives up as stalled. The damping grows
/// by a factor 2^k at the k-th rejection, so the step has long fallen below `xtol` by then
/// unless the damping cannot shrink it.
const MAX_REJECTIONS: usize = 40;

/// Rejected steps in a row after which a secant Jacobian is replaced by finite differences
/// ([`FitOptions::secant`]).
const SECANT_REJECTIONS: usize = 2;

/// Options of [`fit`]: tolerances, limits and finite-difference steps.
#[derive(Clone, Debug, PartialEq)]
pub struct FitOptions {
    /// What is fitted (a candidate's name), used in errors. Default `"fit"`.
    pub name: String,
    /// The most accepted steps. Default 50.
    pub max_iterations: usize,
    /// Converged when a step changes the cost by at most this fraction, both actually and
    /// as predicted by the linear model (relative). Default 1e-10.
    pub ftol: f64,
    /// Converged when the step is at most this many scales in every parameter (relative to
    /// `scales`). Default 1e-8.
    pub xtol: f64,
    /// Converged when every free Jacobian column is this close to orthogonal to the
    /// residual: |J_iᵀr| ≤ gtol·‖J_i‖·‖r‖ (cosine, unitless). Default 1e-10.
    pub gtol: f64,
    /// Absolute finite-difference step per parameter, in its unit; `None` uses
    /// [`DEFAULT_FD_STEP`] × scale. Default `None`.
    pub fd_steps: Option<Vec<f64>>,
    /// Between finite-difference Jacobians, update the Jacobian by secant (Broyden
    /// rank-one) steps from the residuals each trial point gives anyway: a step then costs
    /// one evaluation instead of `n + 1`. A finite-difference Jacobian is taken at the
    /// start, after two rejected steps in a row, and before the fit may end, so a fit ends
    /// by the same tests on the same kind of Jacobian, and its standard errors come from
    /// finite differences at the final point (Madsen, Nielsen & Tingleff 2004, §3.4). For
    /// problems whose evaluation is a long simulation. Default `false`.
    pub secant: bool,
}

impl Default for FitOptions {
    fn default() -> Self {
        Self {
            name: "fit".to_owned(),
            max_iterations: 50,
            ftol: 1e-10,
            xtol: 1e-8,
            gtol: 1e-10,
            fd_steps: None,
            secant: false,
        }
    }
}

/// Bounded Levenberg–Marquardt.
///
/// Minimises ½Σr² of `problem` from `x0` inside `bounds` (`(lower, upper)` per parameter,
/// infinite ends allowed, `lower == upper` fixes a parameter). `scales` gives each
/// parameter's typical size (positive, in its unit): the solver works in x / scale, and
/// the default finite-difference steps and `xtol` are relative to it. A start value outside
/// the bounds is moved onto the nearest bound. `cancel` is checked before every evaluation;
/// when set, the fit returns the best point so far with [`Termination::Cancelled`] (the
/// start point is evaluated once even then, for `cost_before`).
///
/// Not converging is an outcome, not an error: see [`FitReport::termination`].
///
/// # Errors
/// - [`CoreError::Fit`] (naming `opts.name`) when the inputs cannot work: no parameters or
///   residuals, lengths that disagree with `problem.n_params()`, a non-finite start value,
///   bounds that are NaN or empty, scales or finite-difference steps that are not positive
///   and finite, negative or NaN tolerances, or a residual that is not finite at the start
///   point.
/// - The problem's own error when its residuals cannot be evaluated at the start point.
///
/// # Example
///
/// ```
/// use modelgap_core::fit::{fit, FitOptions, ResidualProblem};
///
/// /// y = p·t with y measured at t = 1, 2, 3 and p bounded to [0, 1].
/// struct Line;
/// impl ResidualProblem for Line {
///     fn n_params(&self) -> usize { 1 }
///     fn n_residuals(&self) -> usize { 3 }
///     fn residuals(&self, p: &[f64], out: &mut [f64]) -> modelgap_core::Result<()> {
///         for (k, o) in out.iter_mut().enumerate() {
///             let t = (k + 1) as f64;
///             *o = 2.0 * t - p[0] * t;
///         }
///         Ok(())
///     }
/// }
///
/// let report = fit(&Line, &[0.0], &[(0.0, 1.0)], &[1.0], &FitOptions::default(), None)?;
/// assert_eq!(report.params, vec![1.0]); // the optimum 2 lies outside: pinned at the bound
/// assert!(report.std_errors[0].is_infinite());
/// # Ok::<(), modelgap_core::CoreError>(())
/// ```
pub fn fit(
    problem: &dyn ResidualProblem,
    x0: &[f64],
    bounds: &[(f64, f64)],
    scales: &[f64],
    opts: &FitOptions,
    cancel: Option<&Cancel>,
) -> Result<FitReport> {
    let fd_steps = validate(problem, x0, bounds, scales, opts)?;
    let n = x0.len();
    let m = problem.n_residuals();
    let x: Vec<f64> = x0
        .iter()
        .zip(bounds)
        .map(|(&x, &(lo, hi))| x.clamp(lo, hi))
        .collect();

    let mut r = vec![0.0; m];
    problem.residuals(&x, &mut r)?;
    if let Some((k, v)) = r.iter().enumerate().find(|(_, v)| !v.is_finite()) {
        return Err(fit_error(
            opts,
            format!("residual {k} is {v} at the start point {x:?}, expected a finite number"),
        ));
    }
    let cost = half_sum_of_squares(&r);
    if !cost.is_finite() {
        return Err(fit_error(
            opts,
            format!("the cost ½Σr² overflows at the start point {x:?}"),
        ));
    }

    let mut solver = Solver {
        problem,
        opts,
        bounds,
        scales,
        fd_steps,
        cancel,
        n,
        m,
        x,
        r,
        cost,
        x_trial: vec![0.0; n],
        r_trial: vec![0.0; m],
        r_fd: vec![0.0; m],
        jac: vec![0.0; n * m],
        jtj: vec![0.0; n * n],
        g: vec![0.0; n],
        jac_fresh: false,
        jac_exact: false,
        jac_incomplete: false,
        secant_steps: 0,
        evaluations: 1,
    };
    Ok(solver.run())
}

/// Checks the inputs; returns the absolute finite-difference steps.
fn validate(
    problem: &dyn ResidualProblem,
    x0: &[f64],
    bounds: &[(f64, f64)],
    scales: &[f64],
    opts: &FitOptions,
) -> Result<Vec<f64>> {
    let n = problem.n_params();
    if n == 0 {
        return Err(fit_error(opts, "the problem has no parameters".into()));
    }
    if problem.n_residuals() == 0 {
        return Err(fit_error(opts, "the problem has no residuals".into()));
    }
    let one_per_param = |what: &str, len: usize| {
        if len == n {
            Ok(())
        } else {
            Err(fit_error(
                opts,
                format!("{what} has {len} values, expected {n} (one per parameter)"),
            ))
        }
    };
    one_per_param("x0", x0.len())?;
    one_per_param("bounds", bounds.len())?;
    one_per_param("scales", scales.len())?;
    for (i, &x) in x0.iter().enumerate() {
        if !x.is_finite() {
            return Err(fit_error(
                opts,
                format!("start value of parameter {i} is {x}, expected a finite number"),
            ));
        }
    }
    for (i, &(lo, hi)) in bounds.iter().enumerate() {
        if lo.is_nan() || hi.is_nan() || lo > hi || lo == f64::INFINITY || hi == f64::NEG_INFINITY {
            return Err(fit_error(
                opts,
                format!(
                    "bounds of parameter {i} are ({lo}, {hi}), expected lower <= upper \
                     around finite values"
                ),
            ));
        }
    }
    for (i, &s) in scales.iter().enumerate() {
        if !(s > 0.0 && s.is_finite()) {
            return Err(fit_error(
                opts,
                format!("scale of parameter {i} is {s}, expected a positive finite number"),
            ));
        }
    }
    for (what, tol) in [
        ("ftol", opts.ftol),
        ("xtol", opts.xtol),
        ("gtol", opts.gtol),
    ] {
        if tol.is_nan() || tol < 0.0 {
            return Err(fit_error(
                opts,
                format!("{what} is {tol}, expected a non-negative number"),
            ));
        }
    }
    match &opts.fd_steps {
        None => Ok(scales.iter().map(|s| DEFAULT_FD_STEP * s).collect()),
        Some(steps) => {
            one_per_param("fd_steps", steps.len())?;
            for (i, &h) in steps.iter().enumerate() {
                if !(h > 0.0 && h.is_finite()) {
                    return Err(fit_error(
                        opts,
                        format!(
                            "finite-difference step of parameter {i} is {h}, expected a \
                             positive finite number"
                        ),
                    ));
                }
            }
            Ok(steps.clone())
        }
    }
}

fn fit_error(opts: &FitOptions, reason: String) -> CoreError {
    CoreError::Fit {
        what: opts.name.clone(),
        reason,
    }
}

fn half_sum_of_squares(r: &[f64]) -> f64 {
    0.5 * r.iter().map(|v| v * v).sum::<f64>()
}

fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}

/// Evaluates the residuals at a trial point; `None` when they are an error or not finite.
fn try_cost(
    problem: &dyn ResidualProblem,
    x: &[f64],
    out: &mut [f64],
    evaluations: &mut usize,
) -> Option<f64> {
    if x.iter().any(|v| !v.is_finite()) {
        return None;
    }
    *evaluations += 1;
    problem.residuals(x, out).ok()?;
    let cost = half_sum_of_squares(out);
    // A NaN or infinite residual makes the sum NaN or infinite.
    cost.is_finite().then_some(cost)
}

/// The state of one fit: the current (best) point, scratch buffers, and the Jacobian.
struct Solver<'a> {
    problem: &'a dyn ResidualProblem,
    opts: &'a FitOptions,
    bounds: &'a [(f64, f64)],
    scales: &'a [f64],
    fd_steps: Vec<f64>,
    cancel: Option<&'a Cancel>,
    n: usize,
    m: usize,
    /// The current point: the best found so far.
    x: Vec<f64>,
    /// Residuals at `x`.
    r: Vec<f64>,
    /// ½Σr² at `x`.
    cost: f64,
    x_trial: Vec<f64>,
    r_trial: Vec<f64>,
    r_fd: Vec<f64>,
    /// Jacobian in scaled variables, ∂r/∂z = scale·∂r/∂x; column i at `i*m..(i+1)*m`.
    jac: Vec<f64>,
    /// JᵀJ in scaled variables, n × n row-major.
    jtj: Vec<f64>,
    /// Gradient of the cost in scaled variables, Jᵀr.
    g: Vec<f64>,
    /// Whether `jac`, `jtj` and `g` belong to `x`.
    jac_fresh: bool,
    /// Whether `jac` is of finite differences (not updated by secant steps since).
    jac_exact: bool,
    /// Whether a column of that Jacobian could not be formed for a parameter that is not
    /// fixed (the residuals failed on both sides): a stationary point is then unproven.
    jac_incomplete: bool,
    /// Accepted steps since the last finite-difference Jacobian (secant updates since).
    secant_steps: usize,
    evaluations: usize,
}

impl Solver<'_> {
    fn cancelled(&self) -> bool {
        self.cancel.is_some_and(Cancel::is_cancelled)
    }

    fn run(&mut self) -> FitReport {
        let cost_before = self.cost;
        let mut iterations = 0;
        let mut damping: Option<f64> = None;
        let mut nu = 2.0;
        let termination = loop {
            if self.cancelled() {
                break Termination::Cancelled;
            }
            // Secant updates drift from the true Jacobian: after as many steps as two fresh
            // ones cost evaluations, finite differences again (the curtain's wind fit crept
            // 43 secant steps around its optimum, 75 simulations: its explain took 19.1 s CPU,
            // 15.1 with this; after n steps instead, the two decays of the tests took as many
            // evaluations as without secant steps).
            if !self.jac_exact && self.secant_steps > 2 * self.n {
                self.jac_fresh = false;
            }
            if !self.jac_fresh && !self.jacobian(true) {
                break Termination::Cancelled;
            }
            if self.cost == 0.0 {
                break Termination::Converged;
            }
            let free = self.free_set();
            if free.is_empty() || self.gradient_is_small(&free) {
                if !self.jac_exact {
                    // A secant Jacobian's gradient may vanish where the true one does not.
                    self.jac_fresh = false;
                    continue;
                }
                break Termination::Converged;
            }
            if iterations >= self.opts.max_iterations {
                break Termination::MaxIterations;
            }
            let mu = damping.get_or_insert_with(|| {
                let largest = free
                    .iter()
                    .map(|&i| self.jtj[i * self.n + i])
                    .fold(0.0, f64::max);
                if largest > 0.0 { TAU * largest } else { TAU }
            });
            let exact = self.jac_exact;
            let (accepted, done) = self.trial_steps(&free, mu, &mut nu);
            if accepted {
                iterations += 1;
            }
            match done {
                // The tests were made on a secant Jacobian: they are made again on finite
                // differences at the point reached.
                Some(Termination::Converged | Termination::Stalled) if !exact => {
                    self.jac_fresh = false;
                }
                Some(termination) => break termination,
                None => {}
            }
        };

        let (std_errors, correlation) = self.uncertainty(termination);
        let (robust_std_errors, robust_lags) = if std_errors.iter().any(|s| s.is_finite()) {
            super::report::robust_uncertainty(
                &self.jac,
                &self.r,
                &std_errors,
                self.scales,
                self.problem.series_length(),
            )
        } else {
            (vec![f64::INFINITY; self.n], 0)
        };
        // `uncertainty` leaves a Jacobian at the final point unless cancelled.
        let termination = if termination == Termination::Converged && self.jac_incomplete {
            Termination::Stalled
        } else {
            termination
        };
        FitReport {
            params: self.x.clone(),
            std_errors,
            cost_before,
            cost_after: self.cost,
            iterations,
            evaluations: self.evaluations,
            termination,
            correlation,
            robust_std_errors,
            robust_lags,
        }
    }

    /// Tries damped steps from the current Jacobian until one lowers the cost or the fit
    /// ends. Returns whether a step was taken, and the termination if the fit is over.
    fn trial_steps(
        &mut self,
        free: &[usize],
        mu: &mut f64,
        nu: &mut f64,
    ) -> (bool, Option<Termination>) {
        let (n, xtol, ftol) = (self.n, self.opts.xtol, self.opts.ftol);
        let mut rejections = 0;
        let mut d = vec![0.0; n];
        // Only a secant Jacobian is replaced after rejections: finite differences at the
        // same point would give the same steps again.
        let started_exact = self.jac_exact;
        loop {
            if self.cancelled() {
                return (false, Some(Termination::Cancelled));
            }
            if let Some(h) = self.solve(free, *mu) {
                self.x_trial.copy_from_slice(&self.x);
                for (&i, h_i) in free.iter().zip(&h) {
                    let (lo, hi) = self.bounds[i];
                    self.x_trial[i] = (self.x[i] + self.scales[i] * h_i).clamp(lo, hi);
                }
                for (i, d_i) in d.iter_mut().enumerate() {
                    *d_i = (self.x_trial[i] - self.x[i]) / self.scales[i];
                }
                let step = d.iter().fold(0.0_f64, |acc, v| acc.max(v.abs()));
                if step == 0.0 {
                    return (false, Some(Termination::Converged));
                }
                // A step of at most xtol scales is still taken if it lowers the cost, and
                // then ends the fit: the point no longer moves.
                let short = step <= xtol;
                // Predicted reduction of the linear model for the (clamped) step d:
                // L(0) − L(d) = −gᵀd − ½ dᵀ(JᵀJ)d.
                let quad: f64 = (0..n)
                    .map(|i| d[i] * dot(&self.jtj[i * n..(i + 1) * n], &d))
                    .sum();
                let predicted = -dot(&self.g, &d) - 0.5 * quad;
                match try_cost(
                    self.problem,
                    &self.x_trial,
                    &mut self.r_trial,
                    &mut self.evaluations,
                ) {
                    // The damping shrank the step only because trial points could not be
                    // evaluated: the fit cannot go on.
                    None if short => return (false, Some(Termination::Stalled)),
                    None => {}
                    Some(cost_trial) => {
                        let actual = self.cost - cost_trial;
                        let tiny = ftol * self.cost;
                        let done = short || (predicted <= tiny && actual.abs() <= tiny);
                        if actual > 0.0 {
                            let rho = if predicted > 0.0 {
                                actual / predicted
                            } else {
                                0.5 // no usable ratio: keep the damping
                            };
                            *mu *= f64::max(1.0 / 3.0, 1.0 - (2.0 * rho - 1.0).powi(3));
                            *nu = 2.0;
                            // Where the Jacobian was, for the secant update.
                            let before = self.opts.secant.then(|| (self.x.clone(), self.r.clone()));
                            std::mem::swap(&mut self.x, &mut self.x_trial);
                            std::mem::swap(&mut self.r, &mut self.r_trial);
                            self.cost = cost_trial;
                            self.jac_fresh = false;
                            if rho > EXTEND_RATIO && !done {
                                self.extend(&d);
                            }
                            if let Some((x_before, r_before)) = before {
                                // The whole move, extensions included, from where the
                                // Jacobian was.
                                let moved: Vec<f64> = (0..n)
                                    .map(|i| (self.x[i] - x_before[i]) / self.scales[i])
                                    .collect();
                                let change: Vec<f64> =
                                    self.r.iter().zip(&r_before).map(|(a, b)| a - b).collect();
                                self.secant_update(&moved, &change);
                                self.secant_steps += 1;
                            }
                            return (true, done.then_some(Termination::Converged));
                        }
                        if self.opts.secant {
                            // A rejected point still tells how the residuals change along d.
                            let change: Vec<f64> = self
                                .r_trial
                                .iter()
                                .zip(&self.r)
                                .map(|(a, b)| a - b)
                                .collect();
                            self.secant_update(&d, &change);
                        }
                        if done {
                            return (false, Some(Termination::Converged));
                        }
                    }
                }
            }
            // Rejected (no decrease, a failed evaluation, or an unsolvable system).
            *mu *= *nu;
            *nu *= 2.0;
            rejections += 1;
            if !started_exact && rejections >= SECANT_REJECTIONS {
                // The secant Jacobian no longer leads downhill: finite differences again
                // (with the damping its rejections raised: measured on the cloth's fits,
                // restoring it cost a quarter more evaluations).
                self.jac_fresh = false;
                return (false, None);
            }
            if rejections >= MAX_REJECTIONS || !mu.is_finite() {
                return (false, Some(Termination::Stalled));
            }
        }
    }

    /// Goes on along an accepted step `d` (scaled) that lowered the cost more than the
    /// linear model predicted: the point moves by `d` again, and again (at most
    /// [`MAX_EXTENSIONS`] times), while the cost keeps falling. One residual evaluation
    /// each, against `n + 1` for a fresh Jacobian: a fit crawling along a curved valley
    /// (a resonance whose frequency a parameter moves) takes a few long steps instead of
    /// many short ones. Bounds clamp each extension; one that does not lower the cost is
    /// dropped. (Doubling each extension took a drive's friction law to another minimum,
    /// an offset said as a sign magnitude 0.09 mm/s wide.)
    fn extend(&mut self, d: &[f64]) {
        for _ in 0..MAX_EXTENSIONS {
            if self.cancelled() {
                return;
            }
            self.x_trial.copy_from_slice(&self.x);
            let mut moved = false;
            for (i, d_i) in d.iter().enumerate() {
                let (lo, hi) = self.bounds[i];
                let v = (self.x[i] + self.scales[i] * d_i).clamp(lo, hi);
                moved |= v != self.x[i];
                self.x_trial[i] = v;
            }
            if !moved {
                return;
            }
            match try_cost(
                self.problem,
                &self.x_trial,
                &mut self.r_trial,
                &mut self.evaluations,
            ) {
                Some(c) if c < self.cost => {
                    std::mem::swap(&mut self.x, &mut self.x_trial);
                    std::mem::swap(&mut self.r, &mut self.r_trial);
                    self.cost = c;
                }
                _ => return,
            }
        }
    }

    /// Solves (JᵀJ + μI)h = −g over the free parameters; `None` if no solver gives a
    /// finite answer.
    fn solve(&self, free: &[usize], mu: f64) -> Option<Vec<f64>> {
        let (n, k) = (self.n, free.len());
        let a = DMatrix::from_fn(k, k, |p, q| {
            self.jtj[free[p] * n + free[q]] + if p == q { mu } else { 0.0 }
        });
        let b = DVector::from_fn(k, |p, _| -self.g[free[p]]);
        let h = match a.clone().cholesky() {
            Some(chol) => chol.solve(&b),
            None => match a.clone().lu().solve(&b) {
                Some(h) => h,
                None => {
                    let eps = f64::EPSILON * a.norm();
                    a.svd(true, true).solve(&b, eps).ok()?
                }
            },
        };
        h.iter()
            .all(|v| v.is_finite())
            .then(|| h.iter().copied().collect())
    }

    /// Forward-difference Jacobian at `x` (backward near the upper bound), then JᵀJ and g.
    /// Returns `false`, leaving the Jacobian stale, if `watch_cancel` and the flag is set.
    fn jacobian(&mut self, watch_cancel: bool) -> bool {
        let mut incomplete = false;
        for i in 0..self.n {
            if watch_cancel && self.cancelled() {
                return false;
            }
            let (lo, hi) = self.bounds[i];
            incomplete |= !self.fd_column(i) && lo < hi;
        }
        self.normal_equations();
        self.jac_fresh = true;
        self.jac_exact = true;
        self.secant_steps = 0;
        self.jac_incomplete = incomplete;
        true
    }

    /// Column `i` of the Jacobian at `x` by a forward difference (backward near the upper
    /// bound, the other side if the residuals fail on one). Returns whether it was formed;
    /// if not, the column is zero and the parameter does not move this iteration.
    fn fd_column(&mut self, i: usize) -> bool {
        let m = self.m;
        let (lo, hi) = self.bounds[i];
        let xi = self.x[i];
        let h = self.fd_steps[i];
        let primary = super::step_in_box(xi, h, lo, hi);
        // If the residuals fail on one side, try the other.
        let alternate = (lo..=hi).contains(&(xi - primary)).then_some(-primary);
        let col = i * m..(i + 1) * m;
        let mut filled = false;
        for step in std::iter::once(primary).chain(alternate) {
            self.x_trial.copy_from_slice(&self.x);
            self.x_trial[i] = (xi + step).clamp(lo, hi);
            let h_eff = self.x_trial[i] - xi; // the step actually taken, exactly
            if h_eff == 0.0 {
                continue;
            }
            if try_cost(
                self.problem,
                &self.x_trial,
                &mut self.r_fd,
                &mut self.evaluations,
            )
            .is_none()
            {
                continue;
            }
            let factor = self.scales[i] / h_eff;
            let column = &mut self.jac[col.clone()];
            for ((c, r_fd), r) in column.iter_mut().zip(&self.r_fd).zip(&self.r) {
                *c = (r_fd - r) * factor;
            }
            if column.iter().all(|c| c.is_finite()) {
                filled = true;
                break;
            }
        }
        if !filled {
            self.jac[col].fill(0.0);
        }
        filled
    }

    /// JᵀJ and g = Jᵀr from the Jacobian and the residuals at `x`.
    fn normal_equations(&mut self) {
        let (n, m) = (self.n, self.m);
        for i in 0..n {
            let ci = &self.jac[i * m..(i + 1) * m];
            self.g[i] = dot(ci, &self.r);
            for j in 0..=i {
                let v = dot(ci, &self.jac[j * m..(j + 1) * m]);
                self.jtj[i * n + j] = v;
                self.jtj[j * n + i] = v;
            }
        }
    }

    /// Broyden's rank-one update: the Jacobian is changed least (in Frobenius norm) so that
    /// it maps the scaled move `d` onto the residuals' `change`, J ← J + (Δr − J d) dᵀ/dᵀd;
    /// then JᵀJ and g at `x`. The Jacobian then belongs to `x` but is no longer exact.
    fn secant_update(&mut self, d: &[f64], change: &[f64]) {
        let m = self.m;
        let dd = dot(d, d);
        if dd > 0.0 && dd.is_finite() && change.iter().all(|v| v.is_finite()) {
            let mut miss = change.to_vec();
            for (i, &d_i) in d.iter().enumerate().filter(|(_, d_i)| **d_i != 0.0) {
                for (u, j) in miss.iter_mut().zip(&self.jac[i * m..(i + 1) * m]) {
                    *u -= j * d_i;
                }
            }
            for (i, &d_i) in d.iter().enumerate().filter(|(_, d_i)| **d_i != 0.0) {
                let w = d_i / dd;
                for (j, u) in self.jac[i * m..(i + 1) * m].iter_mut().zip(&miss) {
                    *j += u * w;
                }
            }
        }
        self.normal_equations();
        self.jac_fresh = true;
        self.jac_exact = false;
    }

    /// The parameters that may move: not fixed, and not at a bound that the gradient
    /// pushes against.
    fn free_set(&self) -> Vec<usize> {
        (0..self.n)
            .filter(|&i| {
                let (lo, hi) = self.bounds[i];
                let (x, g) = (self.x[i], self.g[i]);
                // The cost falls along −g: at the lower bound g > 0 pushes outward.
                lo < hi && !(x <= lo && g > 0.0) && !(x >= hi && g < 0.0)
            })
            .collect()
    }

    /// MINPACK's gradient test: every free column of J is nearly orthogonal to r.
    fn gradient_is_small(&self, free: &[usize]) -> bool {
        let r_norm = (2.0 * self.cost).sqrt();
        free.iter().all(|&i| {
            let column_norm = self.jtj[i * self.n + i].sqrt();
            self.g[i].abs() <= self.opts.gtol * column_norm * r_norm
        })
    }

    /// Standard errors and correlations at the final point (a fresh Jacobian if needed;
    /// none after a cancellation, which leaves them undetermined).
    fn uncertainty(&mut self, termination: Termination) -> (Vec<f64>, Vec<Vec<f64>>) {
        let determined = (self.jac_fresh && self.jac_exact)
            || (termination != Termination::Cancelled && self.jacobian(false));
        let free: Vec<bool> = if determined {
            let free = self.free_set();
            (0..self.n).map(|i| free.contains(&i)).collect()
        } else {
            vec![false; self.n]
        };
        uncertainty(&self.jtj, &free, self.scales, self.cost, self.m)
    }
}

#[cfg(test)]
mod tests {
    use approx::assert_relative_eq;

    use super::*;

    /// A problem from a closure, for tests.
    struct FnProblem<F> {
        n: usize,
        m: usize,
        f: F,
    }

    impl<F> ResidualProblem for FnProblem<F>
    where
        F: Fn(&[f64], &mut [f64]) -> Result<()> + Sync,
    {
        fn n_params(&self) -> usize {
            self.n
        }
        fn n_residuals(&self) -> usize {
            self.m
        }
        fn residuals(&self, params: &[f64], out: &mut [f64]) -> Result<()> {
            (self.f)(params, out)
        }
    }

    fn problem<F>(n: usize, m: usize, f: F) -> FnProblem<F>
    where
        F: Fn(&[f64], &mut [f64]) -> Result<()> + Sync,
    {
        FnProblem { n, m, f }
    }

    /// A 64-bit LCG (Knuth's MMIX constants) with Box–Muller: reproducible normal noise
    /// without a rand dependency.
    struct Normal(u64);

    impl Normal {
        fn uniform(&mut self) -> f64 {
            self.0 = self
                .0
                .wrapping_mul(6_364_136_223_846_793_005)
                .wrapping_add(1_442_695_040_888_963_407);
            // The top 53 bits, shifted into (0, 1): never 0, so ln is finite.
            ((self.0 >> 11) as f64 + 0.5) / (1u64 << 53) as f64
        }

        fn sample(&mut self) -> f64 {
            let (u1, u2) = (self.uniform(), self.uniform());
            (-2.0 * u1.ln()).sqrt() * (2.0 * std::f64::consts::PI * u2).cos()
        }
    }

    const A_TRUE: f64 = 2.0;
    const B_TRUE: f64 = 0.7;
    const SIGMA: f64 = 0.02;

    /// y = a·e^(−b·t) + N(0, σ²) at t = 0, 0.05, …, 5 s.
    fn noisy_decay(seed: u64) -> (Vec<f64>, Vec<f64>) {
        let mut noise = Normal(seed.wrapping_mul(0x9E37_79B9_7F4A_7C15) ^ 0xD1B5_4A32_D192_ED03);
        let t: Vec<f64> = (0..=100).map(|k| 0.05 * k as f64).collect();
        let y = t
            .iter()
            .map(|t| A_TRUE * (-B_TRUE * t).exp() + SIGMA * noise.sample())
            .collect();
        (t, y)
    }

    fn fit_decay(seed: u64) -> FitReport {
        let (t, y) = noisy_decay(seed);
        let p = problem(2, t.len(), |x: &[f64], out: &mut [f64]| {
            for ((o, t), y) in out.iter_mut().zip(&t).zip(&y) {
                *o = y - x[0] * (-x[1] * t).exp();
            }
            Ok(())
        });
        let bounds = [(0.0, 10.0), (0.0, 10.0)];
        fit(
            &p,
            &[1.0, 1.0],
            &bounds,
            &[1.0, 1.0],
            &FitOptions::default(),
            None,
        )
        .unwrap()
    }

    #[test]
    fn noisy_exponential_decay_recovers_parameters_within_three_std_errors() {
        let report = fit_decay(1);
        assert_eq!(report.termination, Termination::Converged);
        assert!(report.cost_after < report.cost_before);
        for (p, (truth, se)) in report
            .params
            .iter()
            .zip([A_TRUE, B_TRUE].iter().zip(&report.std_errors))
        {
            assert!(se.is_finite() && *se > 0.0);
            assert!((p - truth).abs() <= 3.0 * se, "{p} vs {truth} ± {se}");
        }
        // a and b are positively correlated for a decay: a larger a needs a faster decay.
        let c = report.correlation[0][1];
        assert!(c > 0.0 && c < 1.0, "{c}");
        assert_eq!(report.correlation[1][0], c);
    }

    #[test]
    fn std_errors_match_monte_carlo_spread_within_factor_two() {
        let reports: Vec<FitReport> = (0..50).map(fit_decay).collect();
        for k in 0..2 {
            let values: Vec<f64> = reports.iter().map(|r| r.params[k]).collect();
            let mean = values.iter().sum::<f64>() / values.len() as f64;
            let spread = (values.iter().map(|v| (v - mean).powi(2)).sum::<f64>()
                / (values.len() - 1) as f64)
                .sqrt();
            let reported = reports.iter().map(|r| r.std_errors[k]).sum::<f64>() / 50.0;
            let ratio = reported / spread;
            assert!((0.5..=2.0).contains(&ratio), "parameter {k}: ratio {ratio}");
            let within = reports
                .iter()
                .filter(|r| (r.params[k] - [A_TRUE, B_TRUE][k]).abs() <= 3.0 * r.std_errors[k])
                .count();
            assert!(
                within >= 48,
                "parameter {k}: {within} of 50 within 3 std errors"
            );
        }
    }

    fn rosenbrock() -> impl ResidualProblem {
        problem(2, 2, |x: &[f64], out: &mut [f64]| {
            out[0] = 10.0 * (x[1] - x[0] * x[0]);
            out[1] = 1.0 - x[0];
            Ok(())
        })
    }

    const FREE: (f64, f64) = (f64::NEG_INFINITY, f64::INFINITY);

    #[test]
    fn rosenbrock_converges_from_classic_start() {
        let p = rosenbrock();
        let report = fit(
            &p,
            &[-1.2, 1.0],
            &[FREE; 2],
            &[1.0; 2],
            &FitOptions::default(),
            None,
        )
        .unwrap();
        assert_eq!(report.termination, Termination::Converged);
        // A zero-residual problem: LM ends within about xtol = 1e-8 of (1, 1); 1e-6 leaves
        // room for the finite-difference Jacobian.
        assert_relative_eq!(report.params[0], 1.0, epsilon = 1e-6);
        assert_relative_eq!(report.params[1], 1.0, epsilon = 1e-6);
        assert!(report.cost_after < 1e-12);
        assert_relative_eq!(report.cost_before, 12.1, epsilon = 1e-12);
        assert!(report.iterations <= 50);
    }

    /// y = a₁e^(−b₁t) + a₂e^(−b₂t) + noise: four parameters, two of them rates.
    fn fit_two_decays(secant: bool) -> FitReport {
        let mut noise = Normal(7);
        let t: Vec<f64> = (0..=200).map(|k| 0.05 * k as f64).collect();
        let y: Vec<f64> = t
            .iter()
            .map(|t| 2.0 * (-0.4 * t).exp() + 1.0 * (-3.0 * t).exp() + 0.01 * noise.sample())
            .collect();
        let p = problem(4, t.len(), |x: &[f64], out: &mut [f64]| {
            for ((o, t), y) in out.iter_mut().zip(&t).zip(&y) {
                *o = y - x[0] * (-x[1] * t).exp() - x[2] * (-x[3] * t).exp();
            }
            Ok(())
        });
        let opts = FitOptions {
            secant,
            ..FitOptions::default()
        };
        fit(
            &p,
            &[1.0, 1.0, 1.0, 5.0],
            &[(0.0, 10.0); 4],
            &[1.0; 4],
            &opts,
            None,
        )
        .unwrap()
    }

    #[test]
    fn secant_jacobian_reaches_the_same_fit_with_fewer_evaluations() {
        let (exact, secant) = (fit_two_decays(false), fit_two_decays(true));
        assert_eq!(secant.termination, Termination::Converged);
        for k in 0..4 {
            // The same optimum, to well within a standard error; the same standard errors
            // (both from finite differences at the final point).
            let se = exact.std_errors[k];
            assert!(
                (secant.params[k] - exact.params[k]).abs() < 1e-3 * se,
                "parameter {k}: {} vs {} ± {se}",
                secant.params[k],
                exact.params[k]
            );
            assert_relative_eq!(secant.std_errors[k], se, max_relative = 1e-3);
        }
        assert_relative_eq!(secant.cost_after, exact.cost_after, max_relative = 1e-9);
        assert!(
            secant.evaluations < exact.evaluations,
            "{} evaluations with secant steps, {} without",
            secant.evaluations,
            exact.evaluations
        );
    }

    #[test]
    fn secant_jacobian_converges_on_rosenbrock() {
        let opts = FitOptions {
            secant: true,
            ..FitOptions::default()
        };
        let report = fit(
            &rosenbrock(),
            &[-1.2, 1.0],
            &[FREE; 2],
            &[1.0; 2],
            &opts,
            None,
        )
        .unwrap();
        assert_eq!(report.termination, Termination::Converged);
        assert_relative_eq!(report.params[0], 1.0, epsilon = 1e-6);
        assert_relative_eq!(report.params[1], 1.0, epsilon = 1e-6);
    }

    #[test]
    fn iteration_limit_ends_with_max_iterations_and_a_better_point() {
        let p = rosenbrock();
        let opts = FitOptions {
            max_iterations: 2,
            ..FitOptions::default()
        };
        let report = fit(&p, &[-1.2, 1.0], &[FREE; 2], &[1.0; 2], &opts, None).unwrap();
        assert_eq!(report.termination, Termination::MaxIterations);
        assert_eq!(report.iterations, 2);
        assert!(report.cost_after < report.cost_before);
        assert!(report.std_errors.iter().all(|s| !s.is_nan()));
    }

    #[test]
    fn parameter_starting_at_zero_with_small_scale_converges() {
        // y = e^(−(p / 1e-3)·t): p is of order 1e-3 and starts at 0. The prediction is
        // rounded to 1e-12 like an ODE solver's own error; a step relative to p (0 here)
        // would see only that noise.
        let t: Vec<f64> = (0..200).map(|k| 0.01 * k as f64).collect();
        let model = |p: f64, t: f64| ((-(p / 1e-3) * t).exp() / 1e-12).round() * 1e-12;
        let y: Vec<f64> = t.iter().map(|&t| model(2.5e-3, t)).collect();
        let p = problem(1, t.len(), |x: &[f64], out: &mut [f64]| {
            for ((o, &t), y) in out.iter_mut().zip(&t).zip(&y) {
                *o = y - model(x[0], t);
            }
            Ok(())
        });
        let report = fit(
            &p,
            &[0.0],
            &[(-1.0, 1.0)],
            &[1e-3],
            &FitOptions::default(),
            None,
        )
        .unwrap();
        assert_eq!(report.termination, Termination::Converged);
        // The rounding to 1e-12 limits how well p is pinned down; 1e-9 (1e-6 of a scale)
        // is far above that and far below the start error of 2.5e-3.
        assert_relative_eq!(report.params[0], 2.5e-3, epsilon = 1e-9);
    }

    #[test]
    fn optimum_outside_bounds_ends_on_bound_with_infinite_std_error() {
        // y = a·t + c with a = 2, c = 0.5, but a is bounded to [0, 1].
        let t: Vec<f64> = (0..20).map(|k| 0.1 * k as f64).collect();
        let p = problem(2, t.len(), |x: &[f64], out: &mut [f64]| {
            for (o, t) in out.iter_mut().zip(&t) {
                *o = 2.0 * t + 0.5 - (x[0] * t + x[1]);
            }
            Ok(())
        });
        let bounds = [(0.0, 1.0), (-10.0, 10.0)];
        let report = fit(
            &p,
            &[0.5, 0.0],
            &bounds,
            &[1.0, 1.0],
            &FitOptions::default(),
            None,
        )
        .unwrap();
        assert_eq!(report.termination, Termination::Converged);
        assert_eq!(report.params[0], 1.0);
        assert_eq!(report.std_errors[0], f64::INFINITY);
        assert!(report.std_errors[1].is_finite() && report.std_errors[1] > 0.0);
        assert_eq!(report.correlation[0], vec![1.0, 0.0]);
        // With a = 1 the best c is 0.5 + mean(t) = 0.5 + 0.95.
        assert_relative_eq!(report.params[1], 1.45, epsilon = 1e-8);
    }

    fn err_above_one(x: &[f64], out: &mut [f64]) -> Result<()> {
        if x[0] > 1.0 {
            return Err(CoreError::model(format!("cannot simulate x = {}", x[0])));
        }
        // Flattening residual: the undamped Gauss–Newton step from 0 lands near 3.6.
        for (k, o) in out.iter_mut().enumerate() {
            *o = (1.0 + k as f64) * (10.0 * (x[0] - 0.5)).atan();
        }
        Ok(())
    }

    #[test]
    fn failed_trial_points_raise_damping_and_fit_still_converges() {
        let p = problem(1, 3, err_above_one);
        let report = fit(
            &p,
            &[0.0],
            &[(-10.0, 10.0)],
            &[1.0],
            &FitOptions::default(),
            None,
        )
        .unwrap();
        assert_eq!(report.termination, Termination::Converged);
        // A zero-residual optimum; 1e-8 is xtol in units of the scale 1.
        assert_relative_eq!(report.params[0], 0.5, epsilon = 1e-8);
    }

    #[test]
    fn start_on_upper_bound_takes_backward_differences() {
        // Residuals fail above 1 and the start is 1: a forward step would fail.
        let p = problem(1, 3, err_above_one);
        let report = fit(
            &p,
            &[1.0],
            &[(0.0, 1.0)],
            &[1.0],
            &FitOptions::default(),
            None,
        )
        .unwrap();
        assert_eq!(report.termination, Termination::Converged);
        assert_relative_eq!(report.params[0], 0.5, epsilon = 1e-8);
    }

    #[test]
    fn residuals_failing_around_the_start_end_stalled_not_converged() {
        // Evaluable only at x = 0 exactly: no finite difference can be formed.
        let p = problem(1, 2, |x: &[f64], out: &mut [f64]| {
            if x[0] != 0.0 {
                return Err(CoreError::model("unstable"));
            }
            out.fill(1.0);
            Ok(())
        });
        let report = fit(&p, &[0.0], &[FREE], &[1.0], &FitOptions::default(), None).unwrap();
        assert_eq!(report.termination, Termination::Stalled);
        assert_eq!(report.params, vec![0.0]);
        assert_eq!(report.std_errors, vec![f64::INFINITY]);
    }

    #[test]
    fn simulation_noise_floor_ends_converged_near_optimum() {
        // e^(−b·t) plus a deterministic 1e-9 wobble in b, like an ODE solver's error; the
        // finite-difference step 1e-4 stands well above it.
        let t: Vec<f64> = (0..500).map(|k| 0.01 * k as f64).collect();
        let model = |b: f64, t: f64| (-b * t).exp() + 1e-9 * (1e9 * b * (1.0 + t)).sin();
        let y: Vec<f64> = t.iter().map(|&t| (-0.7 * t).exp()).collect();
        let p = problem(1, t.len(), |x: &[f64], out: &mut [f64]| {
            for ((o, &t), y) in out.iter_mut().zip(&t).zip(&y) {
                *o = y - model(x[0], t);
            }
            Ok(())
        });
        let opts = FitOptions {
            fd_steps: Some(vec![1e-4]),
            ..FitOptions::default()
        };
        let report = fit(&p, &[0.1], &[(0.0, 5.0)], &[1.0], &opts, None).unwrap();
        assert_eq!(report.termination, Termination::Converged);
        // The wobble moves the optimum by about 1e-9 / |∂y/∂b| ≈ 1e-8; 1e-6 is generous.
        assert_relative_eq!(report.params[0], 0.7, epsilon = 1e-6);
    }

    #[test]
    fn cancel_before_start_returns_start_point() {
        let cancel = Cancel::new();
        cancel.cancel();
        let p = rosenbrock();
        let report = fit(
            &p,
            &[-1.2, 1.0],
            &[FREE; 2],
            &[1.0; 2],
            &FitOptions::default(),
            Some(&cancel),
        )
        .unwrap();
        assert_eq!(report.termination, Termination::Cancelled);
        assert_eq!(report.params, vec![-1.2, 1.0]);
        assert_eq!(report.cost_before, report.cost_after);
        assert_eq!(report.iterations, 0);
        assert_eq!(report.evaluations, 1);
        assert!(report.std_errors.iter().all(|s| s.is_infinite()));
    }

    #[test]
    fn non_finite_residual_at_start_is_a_fit_error_naming_the_fit() {
        let p = problem(1, 4, |_: &[f64], out: &mut [f64]| {
            out.fill(1.0);
            out[2] = f64::NAN;
            Ok(())
        });
        let opts = FitOptions {
            name: "coulomb@1m".into(),
            ..FitOptions::default()
        };
        let e = fit(&p, &[0.0], &[FREE], &[1.0], &opts, None).unwrap_err();
        match &e {
            CoreError::Fit { what, reason } => {
                assert_eq!(what, "coulomb@1m");
                assert!(reason.contains("residual 2 is NaN"), "{reason}");
            }
            other => panic!("expected CoreError::Fit, got {other:?}"),
        }
        assert!(e.to_string().starts_with("fit of coulomb@1m: "));
    }

    #[test]
    fn residual_error_at_start_is_returned_as_is() {
        let p = problem(1, 3, err_above_one);
        let e = fit(&p, &[2.0], &[FREE], &[1.0], &FitOptions::default(), None).unwrap_err();
        assert!(matches!(e, CoreError::Model { .. }), "{e:?}");
    }

    #[test]
    fn mismatched_inputs_are_fit_errors() {
        let p = rosenbrock();
        let opts = FitOptions::default();
        type Case<'a> = (&'a [f64], &'a [(f64, f64)], &'a [f64]);
        let cases: [Case<'_>; 5] = [
            (&[0.0], &[FREE; 2], &[1.0; 2]),
            (&[0.0, 0.0], &[FREE], &[1.0; 2]),
            (&[0.0, 0.0], &[FREE; 2], &[1.0, 0.0]),
            (&[0.0, f64::NAN], &[FREE; 2], &[1.0; 2]),
            (&[0.0, 0.0], &[FREE, (1.0, 0.0)], &[1.0; 2]),
        ];
        for (x0, bounds, scales) in cases {
            let e = fit(&p, x0, bounds, scales, &opts, None).unwrap_err();
            assert!(matches!(e, CoreError::Fit { .. }), "{e:?}");
        }
        let bad_steps = FitOptions {
            fd_steps: Some(vec![1e-6, -1.0]),
            ..FitOptions::default()
        };
        let e = fit(&p, &[0.0, 0.0], &[FREE; 2], &[1.0; 2], &bad_steps, None).unwrap_err();
        assert!(
            e.to_string()
                .contains("finite-difference step of parameter 1"),
            "{e}"
        );
    }

    #[test]
    fn start_outside_bounds_moves_onto_the_bound() {
        let p = problem(1, 1, |x: &[f64], out: &mut [f64]| {
            out[0] = x[0] - 3.0;
            Ok(())
        });
        let report = fit(
            &p,
            &[5.0],
            &[(0.0, 1.0)],
            &[1.0],
            &FitOptions::default(),
            None,
        )
        .unwrap();
        // Cost before is measured at the clamped start 1: ½(1 − 3)² = 2.
        assert_eq!(report.cost_before, 2.0);
        assert_eq!(report.params, vec![1.0]);
    }

    #[test]
    fn fixed_parameter_does_not_move() {
        let p = rosenbrock();
        let report = fit(
            &p,
            &[0.5, 0.0],
            &[(0.5, 0.5), FREE],
            &[1.0; 2],
            &FitOptions::default(),
            None,
        )
        .unwrap();
        assert_eq!(report.params[0], 0.5);
        // With x0 fixed at 0.5 the best x1 is 0.25.
        assert_relative_eq!(report.params[1], 0.25, epsilon = 1e-8);
        assert_eq!(report.std_errors[0], f64::INFINITY);
    }

    #[test]
    fn same_input_gives_same_bits() {
        assert_eq!(fit_decay(7), fit_decay(7));
    }
}
