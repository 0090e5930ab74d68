//! Simulation: drive a compiled model with input signals and get states and
//! outputs at requested times.
//!
//! Three integrators: the exact discretisation of a linear time-invariant
//! model (matrix exponential over each interval, exact for constant,
//! zero-order-hold and piecewise-linear inputs), an adaptive explicit
//! Dormand–Prince 5(4) and an L-stable Rosenbrock method for stiff models.
//! [`Solver::Auto`] takes the exact path when it applies and otherwise
//! lets the ODE solver switch to the stiff method when it detects stiffness.
//! Discontinuities (PWM edges, zero-order-hold samples, parameter changes)
//! are breakpoints the integrator stops at exactly.

use std::collections::BTreeMap;

use modelgap_core::{Recording, Signal};
use nalgebra::{DMatrix, DVector};

use crate::compiled::CompiledModel;
use crate::error::{BondError, Result};
use crate::graph::BondGraph;
use crate::ode::{self, Method, OdeOptions, OdeStats, OdeSystem};

/// How a sampled input is held between its samples.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum Hold {
    /// Straight lines between samples.
    #[default]
    Linear,
    /// The last sample's value until the next sample.
    Zero,
}

/// What drives one input signal.
#[derive(Clone, Debug, PartialEq)]
pub enum Drive {
    /// A constant value.
    Constant(f64),
    /// A sampled signal (times in s, strictly increasing), held as `hold`
    /// between samples and constant outside them.
    Sampled {
        /// Sample times (s).
        t: Vec<f64>,
        /// Sample values.
        values: Vec<f64>,
        /// How to fill between samples.
        hold: Hold,
    },
    /// A pulse-width-modulated signal: `high` for the first `duty` fraction
    /// of each period, `low` for the rest, starting at t = 0.
    Pwm {
        /// Switching frequency (Hz).
        frequency_hz: f64,
        /// Fraction of each period spent high, in [0, 1].
        duty: f64,
        /// Value when on.
        high: f64,
        /// Value when off.
        low: f64,
    },
}

impl Drive {
    /// A PWM between 0 and 1 with the given duty cycle and frequency.
    pub fn pwm(duty: f64, frequency_hz: f64) -> Drive {
        Drive::Pwm {
            frequency_hz,
            duty,
            high: 1.0,
            low: 0.0,
        }
    }

    fn check(&self, name: &str) -> Result<()> {
        let bad = |detail: String| {
            Err(BondError::BadInput {
                input: name.to_string(),
                detail,
            })
        };
        match self {
            Drive::Constant(v) if !v.is_finite() => bad(format!("value must be finite, found {v}")),
            Drive::Sampled { t, values, .. } => {
                if t.is_empty() || t.len() != values.len() {
                    return bad(format!(
                        "needs as many times as values, found {} and {}",
                        t.len(),
                        values.len()
                    ));
                }
                if let Some(i) = values.iter().position(|v| !v.is_finite()) {
                    return bad(format!("sample {i} is not finite ({})", values[i]));
                }
                if let Some(i) = t
                    .windows(2)
                    .position(|w| w[1].partial_cmp(&w[0]) != Some(std::cmp::Ordering::Greater))
                {
                    return bad(format!(
                        "time is not strictly increasing at sample {}",
                        i + 1
                    ));
                }
                Ok(())
            }
            Drive::Pwm {
                frequency_hz,
                duty,
                high,
                low,
            } => {
                if !(frequency_hz.is_finite() && *frequency_hz > 0.0) {
                    return bad(format!(
                        "PWM frequency must be positive, found {frequency_hz}"
                    ));
                }
                if !(0.0..=1.0).contains(duty) {
                    return bad(format!("PWM duty must be in [0, 1], found {duty}"));
                }
                if !(high.is_finite() && low.is_finite()) {
                    return bad("PWM levels must be finite".to_string());
                }
                Ok(())
            }
            Drive::Constant(_) => Ok(()),
        }
    }

    /// The value at time `t`; `cursor` speeds up monotone queries of sampled drives.
    #[inline]
    fn value(&self, t: f64, cursor: &mut usize) -> f64 {
        match self {
            Drive::Constant(v) => *v,
            Drive::Sampled {
                t: ts,
                values,
                hold,
            } => {
                let n = ts.len();
                if t <= ts[0] {
                    return values[0];
                }
                if t >= ts[n - 1] {
                    return values[n - 1];
                }
                let mut i = (*cursor).min(n - 2);
                if ts[i] > t {
                    i = ts.partition_point(|&x| x <= t).saturating_sub(1);
                }
                while i + 1 < n - 1 && ts[i + 1] <= t {
                    i += 1;
                }
                *cursor = i;
                match hold {
                    Hold::Zero => values[i],
                    Hold::Linear => {
                        let w = (t - ts[i]) / (ts[i + 1] - ts[i]);
                        values[i] + w * (values[i + 1] - values[i])
                    }
                }
            }
            Drive::Pwm {
                frequency_hz,
                duty,
                high,
                low,
            } => {
                // A small tolerance puts a query at an edge time on the new
                // side, also when rounding leaves `t f` just below a whole
                // number of periods (the rising edge).
                let x = t * frequency_hz;
                let phase = x - (x + 1e-12).floor();
                if phase + 1e-12 < *duty { *high } else { *low }
            }
        }
    }

    /// Times in `(t0, t1]` where the drive jumps.
    fn breakpoints(&self, t0: f64, t1: f64, out: &mut Vec<f64>) {
        match self {
            Drive::Constant(_) => {}
            Drive::Sampled {
                t,
                hold: Hold::Zero,
                ..
            } => {
                out.extend(t.iter().copied().filter(|&x| x > t0 && x <= t1));
            }
            Drive::Sampled {
                hold: Hold::Linear, ..
            } => {}
            Drive::Pwm {
                frequency_hz, duty, ..
            } => {
                if *duty <= 0.0 || *duty >= 1.0 {
                    return;
                }
                let period = 1.0 / frequency_hz;
                let k0 = (t0 / period).floor() as i64;
                let k1 = (t1 / period).ceil() as i64;
                for k in k0..=k1 {
                    for edge in [k as f64 * period, (k as f64 + duty) * period] {
                        if edge > t0 && edge <= t1 {
                            out.push(edge);
                        }
                    }
                }
            }
        }
    }
}

/// Which integrator to use.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum Solver {
    /// Exact discretisation for LTI models with non-PWM drives, else the
    /// ODE solver with automatic stiffness switching.
    #[default]
    Auto,
    /// Exact discretisation (errors for a model that is not LTI).
    Exact,
    /// Dormand–Prince 5(4), adaptive, explicit.
    Dopri5,
    /// Rosenbrock, adaptive, L-stable (for stiff models).
    Rosenbrock,
}

/// A parameter that changes value at a time (an abrupt fault).
#[derive(Clone, Debug, PartialEq)]
pub struct ParamChange {
    /// When the change happens (s).
    pub at: f64,
    /// The parameter.
    pub name: String,
    /// Its new value.
    pub value: f64,
}

/// Options of a simulation.
#[derive(Clone, Debug, PartialEq)]
pub struct SimOptions {
    /// Integrator. Default: [`Solver::Auto`].
    pub solver: Solver,
    /// Relative tolerance of the adaptive solvers. Default 1e-8.
    pub rtol: f64,
    /// Absolute tolerance of the adaptive solvers. Default 1e-10.
    pub atol: f64,
    /// Largest step (s) of the adaptive solvers. Default: unlimited.
    pub max_step: f64,
    /// Initial state, in state order; default all zero (at rest, uncharged).
    pub initial_state: Option<Vec<f64>>,
    /// Parameter changes during the run (faults), applied in time order.
    pub changes: Vec<ParamChange>,
}

impl Default for SimOptions {
    fn default() -> SimOptions {
        SimOptions {
            solver: Solver::Auto,
            rtol: 1e-8,
            atol: 1e-10,
            max_step: f64::INFINITY,
            initial_state: None,
            changes: Vec::new(),
        }
    }
}

/// The drives of a simulation's inputs, by input name; inputs without a
/// drive keep the model's default value.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Inputs {
    drives: BTreeMap<String, Drive>,
}

impl Inputs {
    /// No drives: every input at its default.
    pub fn new() -> Inputs {
        Inputs::default()
    }

    /// Drives `name` with `drive`.
    #[must_use]
    pub fn with(mut self, name: &str, drive: Drive) -> Inputs {
        self.drives.insert(name.to_string(), drive);
        self
    }

    /// Drives `name` with `drive`.
    pub fn set(&mut self, name: &str, drive: Drive) {
        self.drives.insert(name.to_string(), drive);
    }

    /// Drives every model input found in `rec` from that recording (linear hold).
    pub fn from_recording(rec: &Recording, input_names: &[String]) -> Inputs {
        let mut inputs = Inputs::new();
        for name in input_names {
            if let Some(s) = rec.signal(name) {
                inputs.set(
                    name,
                    Drive::Sampled {
                        t: rec.t().to_vec(),
                        values: s.values.clone(),
                        hold: Hold::Linear,
                    },
                );
            }
        }
        inputs
    }

    /// The drive of an input, if set.
    pub fn get(&self, name: &str) -> Option<&Drive> {
        self.drives.get(name)
    }
}

/// The result of a simulation: states, inputs and outputs at the requested times.
#[derive(Clone, Debug, PartialEq)]
pub struct Run {
    /// Output times (s).
    pub t: Vec<f64>,
    /// State names.
    pub state_names: Vec<String>,
    /// States, one `Vec` per state.
    pub states: Vec<Vec<f64>>,
    /// Input names.
    pub input_names: Vec<String>,
    /// Inputs as applied, one `Vec` per input.
    pub inputs: Vec<Vec<f64>>,
    /// Output names.
    pub output_names: Vec<String>,
    /// Outputs, one `Vec` per output.
    pub outputs: Vec<Vec<f64>>,
    /// Solver statistics (zero for the exact path but `steps`).
    pub stats: OdeStats,
}

impl Run {
    /// An output by name.
    pub fn output(&self, name: &str) -> Option<&[f64]> {
        self.output_names
            .iter()
            .position(|n| n == name)
            .map(|i| self.outputs[i].as_slice())
    }

    /// A state by name (`p3`).
    pub fn state(&self, name: &str) -> Option<&[f64]> {
        self.state_names
            .iter()
            .position(|n| n == name)
            .map(|i| self.states[i].as_slice())
    }

    /// The run as a recording: inputs, then outputs (and states when `with_states`).
    ///
    /// # Errors
    /// [`BondError::Core`] if the run holds non-finite values.
    pub fn to_recording(&self, with_states: bool) -> Result<Recording> {
        let mut signals = Vec::new();
        for (n, v) in self.input_names.iter().zip(&self.inputs) {
            signals.push(Signal {
                name: n.clone(),
                values: v.clone(),
            });
        }
        for (n, v) in self.output_names.iter().zip(&self.outputs) {
            signals.push(Signal {
                name: n.clone(),
                values: v.clone(),
            });
        }
        if with_states {
            for (n, v) in self.state_names.iter().zip(&self.states) {
                signals.push(Signal {
                    name: n.clone(),
                    values: v.clone(),
                });
            }
        }
        Ok(Recording::new(self.t.clone(), signals)?)
    }
}

/// Evenly spaced output times from 0 to `duration` at `rate_hz`, inclusive.
pub fn time_grid(duration: f64, rate_hz: f64) -> Vec<f64> {
    let n = (duration * rate_hz).round() as usize;
    (0..=n).map(|k| k as f64 / rate_hz).collect()
}

/// Simulates a bond graph: compiles it (applying parameter changes at
/// their times) and integrates from t = 0 to the last output time.
///
/// # Errors
/// Causality and equation errors of the graph; [`BondError::BadInput`] for a
/// drive of an unknown input or a malformed drive; [`BondError::BadOptions`]
/// for unsorted or non-finite times; [`BondError::Ode`] if the solver fails.
///
/// # Example
/// ```
/// # use modelgap_bond::{library, simulate::*};
/// let motor = library::dc_motor();
/// let run = simulate(&motor, &Inputs::new(), &time_grid(0.5, 1000.0), &SimOptions::default()).unwrap();
/// let omega = run.output("omega").unwrap();
/// assert!((omega[500] - 239.0438).abs() < 0.5); // close to steady state after 0.5 s
/// ```
pub fn simulate(g: &BondGraph, inputs: &Inputs, t_out: &[f64], opts: &SimOptions) -> Result<Run> {
    let model = CompiledModel::new(g)?;
    if opts.changes.is_empty() {
        return simulate_compiled(&model, inputs, t_out, opts);
    }
    // Piecewise: one compiled model per interval between changes.
    let mut changes = opts.changes.clone();
    changes.sort_by(|a, b| a.at.total_cmp(&b.at));
    let mut graph = g.clone();
    let mut x0 = opts.initial_state.clone();
    let mut t_start = t_out.first().copied().unwrap_or(0.0);
    let mut run: Option<Run> = None;
    let mut seg_opts = opts.clone();
    seg_opts.changes.clear();
    if let Some(c) = changes.iter().find(|c| !c.at.is_finite()) {
        return Err(BondError::BadOptions(format!(
            "the change of '{}' must happen at a finite time, found {}",
            c.name, c.at
        )));
    }
    // A change at or before the first output time applies from the start.
    let mut bounds: Vec<f64> = changes.iter().map(|c| c.at.max(t_start)).collect();
    bounds.push(f64::INFINITY);
    let mut ci = 0;
    for &end in &bounds {
        let model = CompiledModel::new(&graph)?;
        // Times of this segment: t_out in [t_start, end), plus the segment's end to carry the state.
        let mut seg_t: Vec<f64> = t_out
            .iter()
            .copied()
            .filter(|&t| t >= t_start && t < end)
            .collect();
        let last_t = t_out.last().copied().unwrap_or(0.0);
        let carry = end.is_finite() && end <= last_t;
        if carry {
            seg_t.push(end);
        }
        if seg_t.is_empty() {
            t_start = end;
        } else {
            seg_opts.initial_state = x0.clone();
            let t0 = t_start;
            let seg = simulate_from(&model, inputs, t0, &seg_t, &seg_opts)?;
            x0 = Some(
                seg.states
                    .iter()
                    .map(|s| *s.last().unwrap_or(&0.0))
                    .collect(),
            );
            let keep = if carry { seg_t.len() - 1 } else { seg_t.len() };
            run = Some(match run {
                None => truncate(seg, keep),
                Some(r) => append(r, truncate(seg, keep)),
            });
            t_start = end;
        }
        while ci < changes.len() && changes[ci].at <= end {
            graph.set_param(&changes[ci].name, changes[ci].value)?;
            ci += 1;
        }
    }
    run.ok_or_else(|| BondError::BadOptions("no output times".to_string()))
}

fn truncate(mut r: Run, n: usize) -> Run {
    r.t.truncate(n);
    for v in r
        .states
        .iter_mut()
        .chain(r.inputs.iter_mut())
        .chain(r.outputs.iter_mut())
    {
        v.truncate(n);
    }
    r
}

fn append(mut a: Run, b: Run) -> Run {
    a.t.extend(b.t);
    for (x, y) in a.states.iter_mut().zip(b.states) {
        x.extend(y);
    }
    for (x, y) in a.inputs.iter_mut().zip(b.inputs) {
        x.extend(y);
    }
    for (x, y) in a.outputs.iter_mut().zip(b.outputs) {
        x.extend(y);
    }
    a.stats.steps += b.stats.steps;
    a.stats.rejected += b.stats.rejected;
    a.stats.rhs_evals += b.stats.rhs_evals;
    a.stats.jacobian_evals += b.stats.jacobian_evals;
    a.stats.lu_decompositions += b.stats.lu_decompositions;
    a
}

/// Simulates an already compiled model from t = `t_out[0]`.
///
/// # Errors
/// As [`simulate`].
pub fn simulate_compiled(
    model: &CompiledModel,
    inputs: &Inputs,
    t_out: &[f64],
    opts: &SimOptions,
) -> Result<Run> {
    let t0 = t_out.first().copied().unwrap_or(0.0);
    simulate_from(model, inputs, t0, t_out, opts)
}

fn simulate_from(
    model: &CompiledModel,
    inputs: &Inputs,
    t0: f64,
    t_out: &[f64],
    opts: &SimOptions,
) -> Result<Run> {
    if t_out.is_empty() {
        return Err(BondError::BadOptions("no output times".to_string()));
    }
    if let Some(i) = t_out.iter().position(|t| !t.is_finite()) {
        return Err(BondError::BadOptions(format!(
            "output time {i} is not finite"
        )));
    }
    if let Some(i) = t_out
        .windows(2)
        .position(|w| w[1].partial_cmp(&w[0]) != Some(std::cmp::Ordering::Greater))
    {
        return Err(BondError::BadOptions(format!(
            "output times must be strictly increasing (at index {})",
            i + 1
        )));
    }
    for name in inputs.drives.keys() {
        if !model.input_names.contains(name) {
            return Err(BondError::BadInput {
                input: name.clone(),
                detail: format!(
                    "the model has no such input (inputs: {})",
                    model.input_names.join(", ")
                ),
            });
        }
    }
    let drives: Vec<Drive> = model
        .input_names
        .iter()
        .zip(&model.input_defaults)
        .map(|(n, d)| inputs.drives.get(n).cloned().unwrap_or(Drive::Constant(*d)))
        .collect();
    for (n, d) in model.input_names.iter().zip(&drives) {
        d.check(n)?;
    }
    let n = model.n_states();
    let x0 = match &opts.initial_state {
        Some(x) if x.len() != n => {
            return Err(BondError::BadOptions(format!(
                "initial state has {} values, the model has {n} states",
                x.len()
            )));
        }
        Some(x) if x.iter().any(|v| !v.is_finite()) => {
            let i = x.iter().position(|v| !v.is_finite()).unwrap_or(0);
            return Err(BondError::BadOptions(format!(
                "initial state {} must be finite, found {}",
                model.state_names[i], x[i]
            )));
        }
        Some(x) => x.clone(),
        None => vec![0.0; n],
    };
    let t_end = *t_out.last().unwrap_or(&t0);
    let has_pwm = drives.iter().any(|d| matches!(d, Drive::Pwm { .. }));
    let exact = match opts.solver {
        Solver::Exact if !model.is_lti => {
            return Err(BondError::BadOptions(
                "the exact solver needs a linear time-invariant model (no nonlinear law, no modulated element)".to_string(),
            ));
        }
        Solver::Exact => true,
        Solver::Auto => model.is_lti && !has_pwm,
        _ => false,
    };
    let mut states = vec![0.0; t_out.len() * n];
    let stats = if exact {
        exact_lti(model, &drives, t0, &x0, t_out, &mut states)?
    } else {
        let mut bps = Vec::new();
        for d in &drives {
            d.breakpoints(t0, t_end, &mut bps);
        }
        bps.sort_by(f64::total_cmp);
        bps.dedup();
        let method = match opts.solver {
            Solver::Dopri5 => Method::Dopri5,
            Solver::Rosenbrock => Method::Rosenbrock,
            _ => Method::Auto,
        };
        let ode_opts = OdeOptions {
            rtol: opts.rtol,
            atol: opts.atol,
            max_step: opts.max_step,
            ..OdeOptions::default()
        };
        let mut sys = System::new(model, &drives);
        ode::solve(
            &mut sys,
            method,
            t0,
            &x0,
            t_out,
            &bps,
            &ode_opts,
            &mut states,
        )?
    };
    // Outputs and applied inputs at the output times.
    let m = model.n_inputs();
    let p = model.n_outputs();
    let mut scratch = model.scratch();
    let mut u = vec![0.0; m];
    let mut y = vec![0.0; p];
    let mut cursors = vec![0usize; m];
    let mut run = Run {
        t: t_out.to_vec(),
        state_names: model.state_names.clone(),
        states: vec![Vec::with_capacity(t_out.len()); n],
        input_names: model.input_names.clone(),
        inputs: vec![Vec::with_capacity(t_out.len()); m],
        output_names: model.output_names.clone(),
        outputs: vec![Vec::with_capacity(t_out.len()); p],
        stats,
    };
    for (k, &t) in t_out.iter().enumerate() {
        let x = &states[k * n..(k + 1) * n];
        for j in 0..m {
            u[j] = drives[j].value(t, &mut cursors[j]);
        }
        model.eval(t, x, &u, &mut scratch);
        model.read_outputs(&scratch, &mut y);
        for (column, &v) in run.states.iter_mut().zip(x) {
            column.push(v);
        }
        for (column, &v) in run.inputs.iter_mut().zip(&u) {
            column.push(v);
        }
        for (i, &v) in y.iter().enumerate() {
            if !v.is_finite() {
                return Err(BondError::Ode(ode::OdeError::NonFinite { t, component: i }));
            }
            run.outputs[i].push(v);
        }
    }
    Ok(run)
}

/// The model as an ODE system driven by the drives.
struct System<'a> {
    model: &'a CompiledModel,
    drives: &'a [Drive],
    cursors: Vec<usize>,
    u: Vec<f64>,
    scratch: Vec<f64>,
}

impl<'a> System<'a> {
    fn new(model: &'a CompiledModel, drives: &'a [Drive]) -> System<'a> {
        System {
            model,
            drives,
            cursors: vec![0; drives.len()],
            u: vec![0.0; drives.len()],
            scratch: model.scratch(),
        }
    }
}

impl OdeSystem for System<'_> {
    fn dim(&self) -> usize {
        self.model.n_states()
    }

    #[inline]
    fn rhs(&mut self, t: f64, x: &[f64], dx: &mut [f64]) {
        for (j, d) in self.drives.iter().enumerate() {
            self.u[j] = d.value(t, &mut self.cursors[j]);
        }
        self.model.eval(t, x, &self.u, &mut self.scratch);
        self.model.read_derivatives(&self.scratch, dx);
    }
}

/// The affine model `ẋ = A x + B u + c` of an LTI compiled model, read off
/// the tape with unit vectors (exact, since the tape is affine).
pub fn affine_matrices(model: &CompiledModel) -> (DMatrix<f64>, DMatrix<f64>, DVector<f64>) {
    let n = model.n_states();
    let m = model.n_inputs();
    let mut scratch = model.scratch();
    let mut dx = vec![0.0; n];
    let zero_x = vec![0.0; n];
    let zero_u = vec![0.0; m];
    model.eval(0.0, &zero_x, &zero_u, &mut scratch);
    model.read_derivatives(&scratch, &mut dx);
    let c = DVector::from_column_slice(&dx);
    let mut a = DMatrix::zeros(n, n);
    let mut b = DMatrix::zeros(n, m);
    let mut x = zero_x.clone();
    for j in 0..n {
        x[j] = 1.0;
        model.eval(0.0, &x, &zero_u, &mut scratch);
        model.read_derivatives(&scratch, &mut dx);
        for i in 0..n {
            a[(i, j)] = dx[i] - c[i];
        }
        x[j] = 0.0;
    }
    let mut u = zero_u.clone();
    for j in 0..m {
        u[j] = 1.0;
        model.eval(0.0, &zero_x, &u, &mut scratch);
        model.read_derivatives(&scratch, &mut dx);
        for i in 0..n {
            b[(i, j)] = dx[i] - c[i];
        }
        u[j] = 0.0;
    }
    (a, b, c)
}

/// Discretisation over one interval `h`: `x⁺ = Φ x + Γ0 w0 + Γ1 (w1 − w0)`
/// with `w = [u; 1]` (the constant term rides as an input equal to 1).
struct Discrete {
    phi: DMatrix<f64>,
    gamma0: DMatrix<f64>,
    gamma1: DMatrix<f64>,
}

fn discretise(a: &DMatrix<f64>, bw: &DMatrix<f64>, h: f64) -> Discrete {
    // exp of [[A h, B h, 0], [0, 0, I], [0, 0, 0]] gives Φ, Γ0 and Γ1 (first-order hold).
    let n = a.nrows();
    let m = bw.ncols();
    let mut big = DMatrix::zeros(n + 2 * m, n + 2 * m);
    big.view_mut((0, 0), (n, n)).copy_from(&(a * h));
    big.view_mut((0, n), (n, m)).copy_from(&(bw * h));
    for j in 0..m {
        big[(n + j, n + m + j)] = 1.0;
    }
    let e = big.exp();
    Discrete {
        phi: e.view((0, 0), (n, n)).into_owned(),
        gamma0: e.view((0, n), (n, m)).into_owned(),
        gamma1: e.view((0, n + m), (n, m)).into_owned(),
    }
}

fn exact_lti(
    model: &CompiledModel,
    drives: &[Drive],
    t0: f64,
    x0: &[f64],
    t_out: &[f64],
    out: &mut [f64],
) -> Result<OdeStats> {
    let n = model.n_states();
    let m = model.n_inputs();
    let (a, b, c) = affine_matrices(model);
    let mut bw = DMatrix::zeros(n, m + 1);
    bw.view_mut((0, 0), (n, m)).copy_from(&b);
    bw.set_column(m, &c);
    // The grid: output times plus every sample time of sampled drives, so
    // that inputs are exactly linear (or constant) on each interval.
    let t_end = *t_out.last().unwrap_or(&t0);
    let mut grid: Vec<f64> = t_out.to_vec();
    let mut zoh = vec![false; m];
    for (j, d) in drives.iter().enumerate() {
        match d {
            Drive::Sampled { t, hold, .. } => {
                grid.extend(t.iter().copied().filter(|&x| x > t0 && x < t_end));
                zoh[j] = *hold == Hold::Zero;
            }
            // A PWM is constant between its edges: put every edge on the grid.
            Drive::Pwm { .. } => {
                d.breakpoints(t0, t_end, &mut grid);
                zoh[j] = true;
            }
            Drive::Constant(_) => {}
        }
    }
    if t0 < t_out[0] {
        grid.push(t0);
    }
    grid.sort_by(f64::total_cmp);
    grid.dedup_by(|x, y| (*x - *y).abs() <= 1e-12 * x.abs().max(1.0));
    let mut cache: Vec<(f64, Discrete)> = Vec::new();
    let mut x = DVector::from_column_slice(x0);
    let mut x_next = DVector::zeros(n);
    let mut w0 = DVector::zeros(m + 1);
    let mut w1 = DVector::zeros(m + 1);
    let mut cursors = vec![0usize; m];
    let mut k_out = 0;
    let mut steps = 0;
    let mut t = grid[0];
    if (t - t_out[0]).abs() <= 1e-12 * t.abs().max(1.0) {
        out[..n].copy_from_slice(x.as_slice());
        k_out = 1;
    }
    for &t_next in &grid[1..] {
        let h = t_next - t;
        let idx = match cache.iter().position(|(hh, _)| (hh - h).abs() <= 1e-12 * h) {
            Some(i) => i,
            None => {
                cache.push((h, discretise(&a, &bw, h)));
                cache.len() - 1
            }
        };
        let d = &cache[idx].1;
        for j in 0..m {
            w0[j] = drives[j].value(t, &mut cursors[j]);
            // Zero-order hold: the value is constant over the interval.
            w1[j] = if zoh[j] {
                w0[j]
            } else {
                drives[j].value(t_next, &mut cursors[j])
            };
        }
        w0[m] = 1.0;
        w1[m] = 1.0;
        // x⁺ = Φ x + Γ0 w0 + Γ1 (w1 − w0), without allocating.
        for (a, b) in w1.iter_mut().zip(w0.iter()) {
            *a -= b;
        }
        x_next.gemv(1.0, &d.phi, &x, 0.0);
        x_next.gemv(1.0, &d.gamma0, &w0, 1.0);
        x_next.gemv(1.0, &d.gamma1, &w1, 1.0);
        std::mem::swap(&mut x, &mut x_next);
        steps += 1;
        t = t_next;
        if k_out < t_out.len() && (t - t_out[k_out]).abs() <= 1e-12 * t.abs().max(1.0) {
            if let Some(i) = x.iter().position(|v| !v.is_finite()) {
                return Err(BondError::Ode(ode::OdeError::NonFinite { t, component: i }));
            }
            out[k_out * n..(k_out + 1) * n].copy_from_slice(x.as_slice());
            k_out += 1;
        }
    }
    Ok(OdeStats {
        steps,
        ..OdeStats::default()
    })
}
