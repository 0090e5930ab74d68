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

use crate::compiled::CompiledModel;
use crate::element::Scheduled;
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
    /// A cubic through the samples (Catmull–Rom: each piece through its two samples,
    /// with the slopes its neighbours give; straight lines at the first and last
    /// interval): a sampled analog signal. Between samples a straight line misses a
    /// tone's curvature: at a fiftieth of the sampling rate it drives a model 0.07 % too
    /// weakly, and a series RLC loop read "R is off by 0.07 %"; the cubic misses 60 times
    /// less. The exact discretisation follows it with straight lines over quarters of
    /// each interval ([`CUBIC_PIECES`]), 15 times closer than over whole ones.
    Cubic,
}

/// Straight pieces per sample interval the exact discretisation follows a cubic hold
/// with.
pub const CUBIC_PIECES: usize = 4;

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
    pub(crate) fn value(&self, t: f64, cursor: &mut usize) -> f64 {
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
                let w = (t - ts[i]) / (ts[i + 1] - ts[i]);
                match hold {
                    Hold::Zero => values[i],
                    Hold::Cubic if i >= 1 && i + 2 < n => {
                        let (p0, p1, p2, p3) =
                            (values[i - 1], values[i], values[i + 1], values[i + 2]);
                        0.5 * (2.0 * p1
                            + w * ((p2 - p0)
                                + w * ((2.0 * p0 - 5.0 * p1 + 4.0 * p2 - p3)
                                    + w * (3.0 * (p1 - p2) + p3 - p0))))
                    }
                    Hold::Linear | Hold::Cubic => values[i] + w * (values[i + 1] - values[i]),
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

    /// How many switching edges [`Drive::breakpoints`] would list in
    /// `(t0, t1]`, counted without listing them (an upper bound, as `f64`
    /// so that a PWM at 1 THz over an hour does not overflow).
    fn n_edges(&self, t0: f64, t1: f64) -> f64 {
        match self {
            Drive::Pwm {
                frequency_hz, duty, ..
            } if *duty > 0.0 && *duty < 1.0 => 2.0 * frequency_hz * (t1 - t0).max(0.0) + 2.0,
            _ => 0.0,
        }
    }

    /// Times in `(t0, t1]` where the drive jumps.
    pub(crate) fn breakpoints(&self, t0: f64, t1: f64, out: &mut Vec<f64>) {
        match self {
            Drive::Constant(_) => {}
            Drive::Sampled {
                t,
                values,
                hold: Hold::Zero,
            } => {
                // Only where the held value changes: a 1 kHz recording of a
                // voltage that steps four times has four discontinuities,
                // not four thousand.
                for k in 1..t.len() {
                    if values[k] != values[k - 1] && t[k] > t0 && t[k] <= t1 {
                        out.push(t[k]);
                    }
                }
            }
            Drive::Sampled {
                hold: Hold::Linear | Hold::Cubic,
                ..
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
    /// A fixed step (s) instead of adaptive ones, for a model the exact
    /// discretisation does not cover: RODAS4 (L-stable, order 4) with no error
    /// control, so the run is a smooth function of the model's parameters (see
    /// [`OdeOptions::fixed_step`]); `rtol`, `atol` and `solver` are then not
    /// used. Default `None`.
    pub fixed_step: Option<f64>,
    /// Initial state, in state order; default: the model's own (its file's
    /// `[initial]` values, all zero when it gives none: at rest, uncharged).
    pub initial_state: Option<Vec<f64>>,
    /// Parameter changes during the run (faults), applied in time order.
    pub changes: Vec<ParamChange>,
    /// The most discontinuities a run may have: PWM switching edges (two
    /// per period) plus parameter changes. Each is a point the integrator
    /// stops at and a value held in memory, so it is checked before the run
    /// starts ([`BondError::TooLarge`]). Default [`DEFAULT_MAX_EVENTS`].
    pub max_events: usize,
}

/// The default of [`SimOptions::max_events`]: ten million discontinuities
/// (a 20 kHz PWM for 250 s; 80 MB of edge times).
pub const DEFAULT_MAX_EVENTS: usize = 10_000_000;

/// The default limit of [`checked_time_grid`]: ten million output samples
/// (the DC motor's six columns, time included, take about 500 MB).
pub const DEFAULT_MAX_SAMPLES: usize = 10_000_000;

impl Default for SimOptions {
    fn default() -> SimOptions {
        SimOptions {
            solver: Solver::Auto,
            rtol: 1e-8,
            atol: 1e-10,
            max_step: f64::INFINITY,
            fixed_step: None,
            initial_state: None,
            changes: Vec::new(),
            max_events: DEFAULT_MAX_EVENTS,
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
        Inputs::from_recording_with(rec, input_names, Hold::Linear)
    }

    /// Drives every model input found in `rec` from that recording, held as `hold`.
    pub fn from_recording_with(rec: &Recording, input_names: &[String], hold: Hold) -> Inputs {
        Inputs::from_recording_held(rec, input_names, |_| hold)
    }

    /// Drives every model input found in `rec` from that recording, each held as
    /// `hold_of` its name says.
    pub fn from_recording_held<'a>(
        rec: &Recording,
        input_names: impl IntoIterator<Item = &'a String>,
        hold_of: impl Fn(&str) -> Hold,
    ) -> Inputs {
        let mut inputs = Inputs::new();
        for name in input_names {
            if let Some(s) = rec.signal(name) {
                inputs.set(
                    name,
                    Drive::Sampled {
                        t: rec.t().to_vec(),
                        values: s.values.clone(),
                        hold: hold_of(name),
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
///
/// Allocates `duration × rate_hz + 1` times whatever they are; with values
/// from a user, use [`checked_time_grid`].
pub fn time_grid(duration: f64, rate_hz: f64) -> Vec<f64> {
    let n = (duration * rate_hz).round() as usize;
    (0..=n).map(|k| k as f64 / rate_hz).collect()
}

/// [`time_grid`] after checking its arguments: both finite and positive,
/// and at most `max_samples` times (see [`DEFAULT_MAX_SAMPLES`]).
///
/// # Errors
/// [`BondError::BadOptions`] for a duration or rate that is not a positive
/// number; [`BondError::TooLarge`] (option `max_samples`) for more samples
/// than the limit, before anything is allocated.
///
/// # Example
/// ```
/// # use modelgap_bond::simulate::{checked_time_grid, DEFAULT_MAX_SAMPLES};
/// assert_eq!(checked_time_grid(1.0, 1000.0, DEFAULT_MAX_SAMPLES).unwrap().len(), 1001);
/// assert!(checked_time_grid(1.0, 1e12, DEFAULT_MAX_SAMPLES).is_err());
/// ```
pub fn checked_time_grid(duration: f64, rate_hz: f64, max_samples: usize) -> Result<Vec<f64>> {
    if !(duration.is_finite() && duration > 0.0) {
        return Err(BondError::BadOptions(format!(
            "the duration must be a positive number of seconds, found {duration}"
        )));
    }
    if !(rate_hz.is_finite() && rate_hz > 0.0) {
        return Err(BondError::BadOptions(format!(
            "the sample rate must be a positive number of Hz, found {rate_hz}"
        )));
    }
    let count = (duration * rate_hz).round() + 1.0;
    // Finite or +inf (a product past f64::MAX), never NaN: both arguments are positive.
    if count > max_samples as f64 {
        return Err(BondError::TooLarge {
            what: format!(
                "the output samples of {} s at {} Hz",
                crate::error::num(duration),
                crate::error::num(rate_hz)
            ),
            count,
            limit: max_samples,
            option: "max_samples",
        });
    }
    Ok(time_grid(duration, rate_hz))
}

/// Checks that the drives and parameter changes of a run over `[t0, t1]`
/// make at most `max_events` discontinuities, before any is listed.
fn check_events<'a>(
    drives: impl IntoIterator<Item = (&'a str, &'a Drive)>,
    n_changes: usize,
    t0: f64,
    t1: f64,
    max_events: usize,
) -> Result<()> {
    let mut total = n_changes as f64;
    let mut largest: Option<(&str, &Drive, f64)> = None;
    for (name, d) in drives {
        let n = d.n_edges(t0, t1);
        total += n;
        if largest.is_none_or(|(_, _, m)| n > m) {
            largest = Some((name, d, n));
        }
    }
    if total <= max_events as f64 {
        return Ok(());
    }
    let what = match largest {
        Some((name, Drive::Pwm { frequency_hz, .. }, n)) if n > 0.0 => format!(
            "the switching edges of the PWM on input {name} ({} Hz over {} s){}",
            crate::error::num(*frequency_hz),
            crate::error::num(t1 - t0),
            if total > n {
                " with the run's other discontinuities"
            } else {
                ""
            }
        ),
        _ => "the discontinuities of the run (parameter changes)".to_string(),
    };
    Err(BondError::TooLarge {
        what,
        count: total,
        limit: max_events,
        option: "max_events",
    })
}

/// Simulates a bond graph: compiles it (applying parameter changes at
/// their times) and integrates from t = 0 to the last output time.
///
/// Before integrating, the run is checked: the parameter changes must give
/// values the elements can have, the PWM edges and changes must stay within
/// [`SimOptions::max_events`], and every law must be finite at the start
/// (the initial state under the inputs' first values).
///
/// # Errors
/// Causality and equation errors of the graph; [`BondError::BadInput`] for a
/// drive of an unknown input or a malformed drive; [`BondError::BadOptions`]
/// for unsorted or non-finite times; the errors of
/// [`BondGraph::set_param`] for a change to a value its element cannot have;
/// [`BondError::TooLarge`] for too many discontinuities;
/// [`BondError::LawNotFinite`] for a law that is NaN or infinite at the
/// start; [`BondError::NonFiniteState`] when a state stops being finite
/// (naming it: `p3`, the momentum of I:L) and [`BondError::NonFiniteOutput`]
/// for an output; [`BondError::Ode`] if the solver fails otherwise.
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
    if !g.schedule().is_empty() {
        let (inputs, opts) = with_schedule(g, inputs, opts);
        let mut g = g.clone();
        g.clear_schedule();
        return simulate(&g, &inputs, t_out, &opts);
    }
    let model = CompiledModel::new(g)?;
    if opts.changes.is_empty() {
        return simulate_compiled(&model, inputs, t_out, opts);
    }
    // Every change is checked before the first segment runs.
    for c in &opts.changes {
        g.clone().set_param(&c.name, c.value)?;
    }
    if let (Some(&first), Some(&last)) = (t_out.first(), t_out.last()) {
        check_events(
            inputs.drives.iter().map(|(n, d)| (n.as_str(), d)),
            opts.changes.len(),
            first,
            last,
            opts.max_events,
        )?;
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

/// The drives and options of a run of `g` with its scheduled changes
/// ([`BondGraph::schedule`]) made: parameter changes join `opts.changes`;
/// an input that steps gets a held drive from its default through its
/// steps, unless `inputs` drives it already (a recording overrides the
/// file).
fn with_schedule(g: &BondGraph, inputs: &Inputs, opts: &SimOptions) -> (Inputs, SimOptions) {
    let mut inputs = inputs.clone();
    let mut opts = opts.clone();
    let mut steps: BTreeMap<&str, Vec<(f64, f64)>> = BTreeMap::new();
    for c in g.schedule() {
        match &c.what {
            Scheduled::Parameter(name) => opts.changes.push(ParamChange {
                at: c.at,
                name: name.clone(),
                value: c.value,
            }),
            Scheduled::Input(name) => steps.entry(name).or_default().push((c.at, c.value)),
        }
    }
    for (name, steps) in steps {
        if inputs.get(name).is_some() {
            continue;
        }
        let default = g.inputs().get(name).map_or(0.0, |i| i.default);
        // Held from a sample before the run's start, then each step; steps
        // at one time keep the last.
        let mut t = vec![steps[0].0.min(0.0) - 1.0];
        let mut values = vec![default];
        for (at, v) in steps {
            if let (Some(&last), Some(held)) = (t.last(), values.last_mut())
                && last == at
            {
                *held = v;
            } else {
                t.push(at);
                values.push(v);
            }
        }
        inputs.set(
            name,
            Drive::Sampled {
                t,
                values,
                hold: Hold::Zero,
            },
        );
    }
    (inputs, opts)
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
        None => model.initial_state.clone(),
    };
    let t_end = *t_out.last().unwrap_or(&t0);
    check_events(
        model.input_names.iter().map(String::as_str).zip(&drives),
        0,
        t0,
        t_end,
        opts.max_events,
    )?;
    // Every law finite where the run starts, or an error naming the law.
    let u0: Vec<f64> = drives.iter().map(|d| d.value(t0, &mut 0)).collect();
    model.check_finite(t0, &x0, &u0, true)?;
    let exact_ok =
        model.is_lti || model.is_state_affine && crate::exact::piecewise_constant(&drives);
    let exact = match opts.solver {
        Solver::Exact if !exact_ok => {
            return Err(BondError::BadOptions(
                "the exact solver needs a model affine in its states (no nonlinear law) and, unless it is also linear in its inputs, piecewise-constant inputs (constant, PWM, zero-order hold)".to_string(),
            ));
        }
        Solver::Exact => true,
        Solver::Auto => exact_ok,
        _ => false,
    };
    let p = model.n_outputs();
    let (states, stats) = if exact {
        crate::exact::integrate(model, &drives, t0, &x0, t_out)?
    } else {
        let mut bps = Vec::new();
        for d in &drives {
            d.breakpoints(t0, t_end, &mut bps);
        }
        bps.sort_by(f64::total_cmp);
        bps.dedup();
        let method = match opts.solver {
            _ if opts.fixed_step.is_some() => Method::Rosenbrock,
            Solver::Dopri5 => Method::Dopri5,
            Solver::Rosenbrock => Method::Rosenbrock,
            _ => Method::Auto,
        };
        let ode_opts = OdeOptions {
            rtol: opts.rtol,
            atol: opts.atol,
            max_step: opts.max_step,
            fixed_step: opts.fixed_step,
            ..OdeOptions::default()
        };
        let mut sys = System::new(model, &drives);
        let mut rows = vec![0.0; t_out.len() * n];
        let stats = ode::solve(&mut sys, method, t0, &x0, t_out, &bps, &ode_opts, &mut rows)
            .map_err(|e| match e {
                ode::OdeError::NonFinite { t, component } => model.non_finite_state(component, t),
                other => BondError::Ode(other),
            })?;
        let columns = (0..n)
            .map(|i| (0..t_out.len()).map(|k| rows[k * n + i]).collect())
            .collect();
        (columns, stats)
    };
    // Outputs and applied inputs at the output times, column by column.
    let m = model.n_inputs();
    let len = t_out.len();
    let inputs: Vec<Vec<f64>> = drives
        .iter()
        .map(|d| match d {
            Drive::Constant(v) => vec![*v; len],
            _ => {
                let mut cursor = 0;
                t_out.iter().map(|&t| d.value(t, &mut cursor)).collect()
            }
        })
        .collect();
    let outputs: Vec<Vec<f64>> = if model.is_lti {
        // y = C x + D u + e, column by column.
        let aff = crate::exact::Affine::of(model);
        (0..p)
            .map(|i| {
                let c = &aff.cy[i * n..(i + 1) * n];
                let d = &aff.dy[i * m..(i + 1) * m];
                let mut y = vec![aff.ey[i]; len];
                for (j, &dj) in d.iter().enumerate() {
                    if dj != 0.0 {
                        for (yk, uk) in y.iter_mut().zip(&inputs[j]) {
                            *yk += dj * uk;
                        }
                    }
                }
                for (j, &cj) in c.iter().enumerate() {
                    if cj != 0.0 {
                        for (yk, xk) in y.iter_mut().zip(&states[j]) {
                            *yk += cj * xk;
                        }
                    }
                }
                y
            })
            .collect()
    } else {
        let mut scratch = model.scratch();
        let mut x = vec![0.0; n];
        let mut u = vec![0.0; m];
        let mut y = vec![0.0; p];
        let mut out = vec![Vec::with_capacity(len); p];
        for (k, &t) in t_out.iter().enumerate() {
            for (uj, column) in u.iter_mut().zip(&inputs) {
                *uj = column[k];
            }
            for (xi, column) in x.iter_mut().zip(&states) {
                *xi = column[k];
            }
            model.eval(t, &x, &u, &mut scratch);
            model.read_outputs(&scratch, &mut y);
            for (column, &v) in out.iter_mut().zip(&y) {
                column.push(v);
            }
        }
        out
    };
    for (i, column) in outputs.iter().enumerate() {
        if let Some(k) = column.iter().position(|v| !v.is_finite()) {
            // Name the law that is not finite there, if one is.
            let x: Vec<f64> = states.iter().map(|c| c[k]).collect();
            let u: Vec<f64> = inputs.iter().map(|c| c[k]).collect();
            model.check_finite(t_out[k], &x, &u, false)?;
            return Err(BondError::NonFiniteOutput {
                output: model.output_names[i].clone(),
                t: t_out[k],
            });
        }
    }
    let run = Run {
        t: t_out.to_vec(),
        state_names: model.state_names.clone(),
        states,
        input_names: model.input_names.clone(),
        inputs,
        output_names: model.output_names.clone(),
        outputs,
        stats,
    };
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
