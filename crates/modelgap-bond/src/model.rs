//! [`BondModel`]: a bond graph as a [`modelgap_core::Model`], the seam the
//! measurement loop (compare, explain, add an effect) works through.
//!
//! The model drives its inputs from a recording, simulates at the
//! recording's times and predicts every output; it offers the candidate
//! effects of [`crate::effects`], builds fitted effects into a new model and
//! writes that model as a bond-graph TOML file; and it says whether the
//! paper's qualitative diagnosis (fault trees) points at a candidate.
//!
//! ```
//! use modelgap_bond::{BondModel, library};
//! use modelgap_bond::simulate::{Inputs, SimOptions, simulate, time_grid};
//! use modelgap_core::Model as _;
//!
//! let motor = BondModel::new(library::dc_motor());
//! // A recording of the motor: here simply the model's own run.
//! let run = simulate(motor.graph(), &Inputs::new(), &time_grid(0.2, 1000.0), &SimOptions::default())?;
//! let rec = run.to_recording(false)?;
//! let coulomb = motor.candidates().into_iter().find(|c| c.id == "coulomb@1m").unwrap();
//! let with_friction = motor.predict_with(&rec, &[(&coulomb, &[0.01])])?;
//! let nominal = motor.predict(&rec)?;
//! assert!(with_friction.get("omega").unwrap()[200] < nominal.get("omega").unwrap()[200]);
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

use std::borrow::Cow;
use std::collections::BTreeMap;
use std::fmt::Write as _;

use modelgap_core::explain::estimate::MissingSignal;
use modelgap_core::residual::Threshold;
use modelgap_core::{Candidate, CoreError, Effect, Model, Prediction, QualitativeCheck, Recording};

use crate::compiled::CompiledModel;
use crate::diagnosis::{DiagnosisOptions, diagnose};
use crate::effects::QualTarget;
use crate::effects::{self, BondEffect};
use crate::element::{ElementKind, Law, Scheduled, ScheduledChange};
use crate::error::{BondError, Result};
use crate::fault_tree::{FaultTree, Hypothesis, first_hypothesis_set};
use crate::file::write_model;
use crate::graph::BondGraph;
use crate::qual::Qual;
use crate::simulate::{
    Hold, Inputs, ParamChange, Run, SimOptions, Solver, simulate, simulate_compiled,
};

/// Relative tolerance of the adaptive solvers in [`BondModel`]'s predictions.
pub const RTOL: f64 = 1e-8;

/// Absolute tolerance of the adaptive solvers in [`BondModel`]'s predictions
/// (in state units: V s, N m s, C; well below the states of the built-ins).
pub const ATOL: f64 = 1e-10;

/// How far (RMS, relative to the output's spread about its mean) the model's
/// fixed-step run may lie from its reference run for [`Model::for_fitting`] to
/// take that step.
pub const FIXED_STEP_TOLERANCE: f64 = 1e-4;

/// Fixed steps [`Model::for_fitting`] tries, in sample intervals, longest first (a step
/// never crosses a breakpoint of the inputs, so a recording whose inputs move at every
/// sample takes at least one step per sample whatever this says).
const FIXED_STEPS: [f64; 11] = [
    16.0, 8.0, 4.0, 2.0, 1.0, 0.5, 0.25, 0.125, 0.0625, 0.03125, 0.015625,
];

/// Newton iterations of the steady start before giving up.
const STEADY_MAX_ITERATIONS: usize = 100;

/// Relative Newton step under which the steady start has converged.
const STEADY_STEP_TOLERANCE: f64 = 1e-12;

/// Where a prediction starts.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Start {
    /// The model's initial states (its file's `[initial]`; all zero, at
    /// rest and uncharged, when it gives none).
    #[default]
    Rest,
    /// The steady state under the recording's first input values (Newton).
    /// A periodic, position-dependent element (cogging) has no steady state
    /// of its own: its position is held at 0 and the other states solved.
    SteadyState,
}

/// A bond graph that the measurement loop can hold against a recording.
///
/// Holds the graph, the abrupt parameter changes found by explain (they
/// happen during every prediction) and where predictions start.
#[derive(Clone, Debug, PartialEq)]
pub struct BondModel {
    graph: BondGraph,
    changes: Vec<ParamChange>,
    start: Start,
    /// Plain descriptions of the effects built in, for the file's header.
    added: Vec<String>,
    /// How recorded inputs are held between samples.
    hold: Hold,
    /// Inputs held otherwise than `hold` ([`BondModel::settle_holds`]).
    input_holds: BTreeMap<String, Hold>,
    /// A fixed integration step (s) for a model the exact discretisation does
    /// not cover, chosen for one recording by [`Model::for_fitting`]; `None`:
    /// adaptive steps at [`RTOL`] and [`ATOL`].
    fixed_step: Option<f64>,
}

impl BondModel {
    /// A model of `graph`, starting at rest, with no abrupt changes.
    pub fn new(graph: BondGraph) -> BondModel {
        BondModel {
            graph,
            changes: Vec::new(),
            start: Start::Rest,
            added: Vec::new(),
            hold: Hold::Zero,
            input_holds: BTreeMap::new(),
            fixed_step: None,
        }
    }

    /// The same model with recorded inputs held as `hold` between samples.
    /// Default: zero-order hold, right for commanded inputs (a voltage set
    /// by a controller changes at a sample and stays); use linear hold for
    /// a sampled analog input.
    #[must_use]
    pub fn with_hold(mut self, hold: Hold) -> BondModel {
        self.hold = hold;
        self.input_holds.clear();
        self
    }

    /// The same model with the recorded input `input` held as `hold` (the others as
    /// [`BondModel::hold`]).
    #[must_use]
    pub fn with_input_hold(mut self, input: &str, hold: Hold) -> BondModel {
        self.set_input_hold(input, hold);
        self
    }

    /// Holds the recorded input `input` as `hold` from now on.
    pub fn set_input_hold(&mut self, input: &str, hold: Hold) {
        self.input_holds.insert(input.to_owned(), hold);
    }

    /// How the recorded input `input` is held between samples.
    pub fn hold_of(&self, input: &str) -> Hold {
        self.input_holds.get(input).copied().unwrap_or(self.hold)
    }

    /// The model's inputs that `rec` records, each held as [`BondModel::hold_of`] says.
    pub fn recorded_inputs(&self, rec: &Recording) -> Inputs {
        self.inputs_of(&self.graph, rec)
    }

    /// The inputs of `graph` (this model's, or an edit of it) that `rec` records, each
    /// held as [`BondModel::hold_of`] says.
    pub(crate) fn inputs_of(&self, graph: &BondGraph, rec: &Recording) -> Inputs {
        Inputs::from_recording_held(rec, graph.inputs().keys(), |name| self.hold_of(name))
    }

    /// The same model with predictions starting at `start`.
    #[must_use]
    pub fn with_start(mut self, start: Start) -> BondModel {
        self.start = start;
        self
    }

    /// The bond graph (with every effect built in so far).
    pub fn graph(&self) -> &BondGraph {
        &self.graph
    }

    /// The abrupt parameter changes made during every prediction.
    pub fn changes(&self) -> &[ParamChange] {
        &self.changes
    }

    /// How the recording's inputs are held between samples (unless
    /// [`BondModel::hold_of`] says otherwise for one of them).
    pub fn hold(&self) -> Hold {
        self.hold
    }

    /// The fixed integration step (s) of a copy made for fitting
    /// ([`Model::for_fitting`]); `None` for adaptive steps.
    pub fn fixed_step(&self) -> Option<f64> {
        self.fixed_step
    }

    /// How runs start: at rest or at the steady state under the first inputs.
    pub fn start(&self) -> Start {
        self.start
    }

    /// The graph with effects applied in turn, and the parameter changes of
    /// the model followed by those of the effects.
    ///
    /// Each candidate is read into its kind ([`BondEffect::from_candidate`])
    /// against the graph as edited so far.
    ///
    /// # Errors
    /// [`BondError::BadEffect`] for an effect the graph does not offer or
    /// values outside the candidate's bounds (see [`effects::apply`]).
    pub fn edited(
        &self,
        effects: &[(&Candidate, &[f64])],
    ) -> Result<(BondGraph, Vec<ParamChange>)> {
        let mut graph = self.graph.clone();
        let mut changes = self.changes.clone();
        for (candidate, values) in effects {
            let (g, ch) =
                BondEffect::from_candidate(candidate, &graph)?.apply(&graph, candidate, values)?;
            graph = g;
            changes.extend(ch);
        }
        Ok((graph, changes))
    }

    /// Simulates the model with effects applied, driven by the recording's
    /// inputs (those it holds; the others at their defaults), at the
    /// recording's times.
    ///
    /// # Errors
    /// As [`BondModel::edited`]; causality, equation and solver errors of the
    /// edited graph (see [`simulate`]); [`BondError::LawNotFinite`] for a law
    /// that is NaN where the steady start's search begins;
    /// [`BondError::BadOptions`] when [`Start::SteadyState`] finds no steady state.
    pub fn run(&self, rec: &Recording, effects: &[(&Candidate, &[f64])]) -> Result<Run> {
        let (graph, changes): (Cow<'_, BondGraph>, Vec<ParamChange>) = if effects.is_empty() {
            (Cow::Borrowed(&self.graph), self.changes.clone())
        } else {
            let (g, ch) = self.edited(effects)?;
            (Cow::Owned(g), ch)
        };
        let model = CompiledModel::new(&graph)?;
        let inputs = self.inputs_of(&graph, rec);
        let initial_state = match self.start {
            Start::Rest => None,
            Start::SteadyState => {
                let base = (!effects.is_empty()).then_some(&self.graph);
                Some(steady_start(&graph, &model, rec, base)?)
            }
        };
        // A contact that closes and opens is followed by adaptive steps, even in the copy
        // for fitting (its fixed step was checked on the model without it).
        let adaptive = (effects.iter()).any(|(c, _)| crate::effects::needs_adaptive_steps(c));
        let opts = SimOptions {
            rtol: RTOL,
            atol: ATOL,
            fixed_step: self.fixed_step.filter(|_| !adaptive),
            initial_state,
            changes,
            ..SimOptions::default()
        };
        if opts.changes.is_empty() && graph.schedule().is_empty() {
            simulate_compiled(&model, &inputs, rec.t(), &opts)
        } else {
            simulate(&graph, &inputs, rec.t(), &opts)
        }
    }
}

impl From<BondGraph> for BondModel {
    fn from(graph: BondGraph) -> BondModel {
        BondModel::new(graph)
    }
}

/// The loop's error for a failed prediction or edit, naming the effects.
fn model_error(effects: &[(&Candidate, &[f64])], e: BondError) -> CoreError {
    let context = match e {
        // Already names the candidate and the parameter.
        BondError::BadEffect { .. } => None,
        _ if effects.is_empty() => None,
        _ => Some(format!(
            "with {}",
            effects
                .iter()
                .map(|(c, v)| format!("{} at {v:?}", c.id))
                .collect::<Vec<_>>()
                .join(", ")
        )),
    };
    CoreError::from_model(context, e)
}

/// The first value of each model input in the recording (its default when
/// the recording lacks it).
fn first_inputs(model: &CompiledModel, rec: &Recording) -> Vec<f64> {
    model
        .input_names
        .iter()
        .zip(&model.input_defaults)
        .map(|(n, d)| rec.signal(n).map_or(*d, |s| s.values[0]))
        .collect()
}

/// Indices of the states of periodic position-dependent C elements (cogging):
/// held at 0 by the steady start.
fn held_states(g: &BondGraph, model: &CompiledModel) -> Vec<usize> {
    let mut held = Vec::new();
    for id in g.element_ids() {
        let el = g.element(id);
        if el.kind != ElementKind::C {
            continue;
        }
        let Law::Nonlinear {
            effort: Some(e), ..
        } = &el.law
        else {
            continue;
        };
        if !effects::is_periodic(e) {
            continue;
        }
        if let Some(&(bond, _)) = g.ports(id).first() {
            let name = format!("q{}", bond.number());
            if let Some(i) = model.state_names.iter().position(|n| *n == name) {
                held.push(i);
            }
        }
    }
    held
}

/// The steady state of `graph` under the recording's first inputs, from the
/// steady state of `base` (the graph before the effects, mapped by state
/// name) when given.
fn steady_start(
    graph: &BondGraph,
    model: &CompiledModel,
    rec: &Recording,
    base: Option<&BondGraph>,
) -> Result<Vec<f64>> {
    let mut guess = vec![0.0; model.n_states()];
    if let Some(base) = base {
        let bm = CompiledModel::new(base)?;
        let bu = first_inputs(&bm, rec);
        if let Ok(bx) = newton(&bm, &bu, &vec![0.0; bm.n_states()], &held_states(base, &bm)) {
            for (name, v) in bm.state_names.iter().zip(bx) {
                if let Some(i) = model.state_names.iter().position(|n| n == name) {
                    guess[i] = v;
                }
            }
        }
    }
    let u0 = first_inputs(model, rec);
    // A law that is NaN where Newton starts is named, not reported as "no convergence".
    model.check_finite(0.0, &guess, &u0, true)?;
    newton(model, &u0, &guess, &held_states(graph, model))
}

/// Damped Newton for `f(x, u) = 0` over the states not in `held` (those stay 0).
fn newton(model: &CompiledModel, u: &[f64], x0: &[f64], held: &[usize]) -> Result<Vec<f64>> {
    let n = model.n_states();
    let free: Vec<usize> = (0..n).filter(|i| !held.contains(i)).collect();
    let m = free.len();
    let mut x = x0.to_vec();
    for &i in held {
        x[i] = 0.0;
    }
    if m == 0 {
        return Ok(x);
    }
    let mut scratch = model.scratch();
    let mut dx_all = vec![0.0; n];
    let mut residual = |x: &[f64], out: &mut [f64]| {
        model.eval(0.0, x, u, &mut scratch);
        model.read_derivatives(&scratch, &mut dx_all);
        for (o, &i) in out.iter_mut().zip(&free) {
            *o = dx_all[i];
        }
    };
    let norm = |r: &[f64]| r.iter().map(|v| v * v).sum::<f64>().sqrt();
    let mut r = vec![0.0; m];
    let mut r2 = vec![0.0; m];
    let mut jac = nalgebra::DMatrix::zeros(m, m);
    for _ in 0..STEADY_MAX_ITERATIONS {
        residual(&x, &mut r);
        let r_norm = norm(&r);
        if r_norm == 0.0 {
            return Ok(x);
        }
        let scale = x.iter().fold(1e-12_f64, |a, v| a.max(v.abs()));
        for (col, &j) in free.iter().enumerate() {
            let h = 1e-7 * x[j].abs().max(1e-6 * scale).max(1e-4);
            let keep = x[j];
            x[j] = keep + h;
            residual(&x, &mut r2);
            x[j] = keep;
            for row in 0..m {
                jac[(row, col)] = (r2[row] - r[row]) / h;
            }
        }
        let rhs = nalgebra::DVector::from_iterator(m, r.iter().map(|v| -v));
        let step = jac
            .clone()
            .lu()
            .solve(&rhs)
            .ok_or_else(|| BondError::NoSteadyState {
                reason: "the Jacobian is singular".to_string(),
            })?;
        let rel = free
            .iter()
            .zip(step.iter())
            .map(|(&i, d)| d.abs() / x[i].abs().max(1e-9 * scale.max(1.0)))
            .fold(0.0, f64::max);
        // Backtracking: the largest of 1, 1/2, … 1/1024 that lowers the residual.
        let mut lambda = 1.0;
        let mut trial = x.clone();
        loop {
            for (&i, d) in free.iter().zip(step.iter()) {
                trial[i] = x[i] + lambda * d;
            }
            residual(&trial, &mut r2);
            if norm(&r2) < r_norm || lambda < 1e-3 {
                break;
            }
            lambda *= 0.5;
        }
        x.copy_from_slice(&trial);
        if x.iter().any(|v| !v.is_finite()) {
            break;
        }
        if rel < STEADY_STEP_TOLERANCE {
            return Ok(x);
        }
    }
    Err(BondError::NoSteadyState {
        reason: "Newton's method did not converge".to_string(),
    })
}

impl Model for BondModel {
    fn name(&self) -> String {
        self.graph.name.clone()
    }

    fn outputs(&self) -> Vec<String> {
        self.graph
            .outputs()
            .iter()
            .map(|o| o.name.clone())
            .collect()
    }

    fn unit(&self, output: &str) -> String {
        self.graph
            .outputs()
            .iter()
            .find(|o| o.name == output)
            .map(|o| o.unit.clone())
            .unwrap_or_default()
    }

    fn inputs(&self) -> Vec<String> {
        self.graph.inputs().keys().cloned().collect()
    }

    /// A fixed-step copy of the model for fits on `rec` (RODAS4 with no error
    /// control, [`SimOptions::fixed_step`]): the longest step of 16, 8, … 1/64
    /// sample intervals at which the model as given (its
    /// nonlinear laws, or its linear ones on the same fixed-step path) stays
    /// within [`FIXED_STEP_TOLERANCE`] of its reference run (the exact
    /// discretisation, or adaptive steps at [`RTOL`]) on every output,
    /// relative to that output's spread. `None` when no step is good enough or
    /// the recording is too short to judge.
    fn for_fitting(&self, rec: &Recording) -> Option<Box<dyn Model>> {
        if self.fixed_step.is_some() || rec.len() < 3 {
            return None;
        }
        let reference = self.run(rec, &[]).ok()?;
        let spread: Vec<f64> = (reference.outputs.iter())
            .map(|y| {
                let mean = y.iter().sum::<f64>() / y.len().max(1) as f64;
                (y.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / y.len().max(1) as f64).sqrt()
            })
            .collect();
        let t = rec.t();
        let dt = (t[t.len() - 1] - t[0]) / (t.len() - 1) as f64;
        if !(dt.is_finite() && dt > 0.0) {
            return None;
        }
        let model = CompiledModel::new(&self.graph).ok()?;
        let inputs = self.recorded_inputs(rec);
        let initial_state = match self.start {
            Start::Rest => None,
            Start::SteadyState => Some(steady_start(&self.graph, &model, rec, None).ok()?),
        };
        for steps in FIXED_STEPS {
            let h = dt * steps;
            let opts = SimOptions {
                solver: Solver::Rosenbrock,
                fixed_step: Some(h),
                initial_state: initial_state.clone(),
                changes: self.changes.clone(),
                ..SimOptions::default()
            };
            let run = if opts.changes.is_empty() && self.graph.schedule().is_empty() {
                simulate_compiled(&model, &inputs, t, &opts)
            } else {
                simulate(&self.graph, &inputs, t, &opts)
            };
            let Ok(run) = run else { continue };
            let close =
                (reference.outputs.iter().zip(&run.outputs).zip(&spread)).all(|((a, b), s)| {
                    let d = (a.iter().zip(b)).map(|(x, y)| (x - y).powi(2)).sum::<f64>()
                        / a.len().max(1) as f64;
                    d.sqrt() <= FIXED_STEP_TOLERANCE * s.max(f64::MIN_POSITIVE)
                });
            if close {
                let mut fitting = self.clone();
                fitting.fixed_step = Some(h);
                return Some(Box::new(fitting));
            }
        }
        None
    }

    /// `1 / |λ|` of every mode of the model linearised where predictions
    /// start (at rest, or at the steady state), under the recording's first
    /// inputs; pure integrators (λ = 0) and modes the linearisation cannot
    /// evaluate are left out.
    fn time_constants(&self, rec: &Recording) -> Vec<f64> {
        let Ok(model) = CompiledModel::new(&self.graph) else {
            return Vec::new();
        };
        let u0 = first_inputs(&model, rec);
        let x0 = match self.start {
            Start::Rest => model.initial_state.clone(),
            Start::SteadyState => match steady_start(&self.graph, &model, rec, None) {
                Ok(x) => x,
                Err(_) => return Vec::new(),
            },
        };
        let ss = crate::state_space::StateSpace::of_compiled(&model, Some(&x0), Some(&u0));
        if ss.a.iter().any(|v| !v.is_finite()) {
            return Vec::new();
        }
        ss.modes()
            .iter()
            .map(|m| m.eigenvalue.norm())
            .filter(|l| l.is_finite() && *l > 1e-12)
            .map(|l| 1.0 / l)
            .collect()
    }

    fn predict_with(
        &self,
        rec: &Recording,
        effects: &[(&Candidate, &[f64])],
    ) -> modelgap_core::Result<Prediction> {
        let run = self
            .run(rec, effects)
            .map_err(|e| model_error(effects, e))?;
        Ok(Prediction {
            names: run.output_names,
            values: run.outputs,
        })
    }

    fn candidates(&self) -> Vec<Candidate> {
        effects::candidates(&self.graph)
    }

    /// The menu with its scales from a run driven by the recording's inputs
    /// ([`effects::Scales::of_run`]); the defaults' scales when the model
    /// cannot simulate the recording.
    fn candidates_for(&self, rec: &Recording) -> Vec<Candidate> {
        match self.run(rec, &[]) {
            Ok(run) => {
                effects::candidates_with(&self.graph, &effects::Scales::of_run(&self.graph, &run))
            }
            Err(_) => self.candidates(),
        }
    }

    /// The outputs the recording does not measure, and the junctions whose
    /// physics the menu cannot name: a storage node (0-junction with a C)
    /// or a 1-junction with an I that has neither a unit to read nor a
    /// declared `domain` gets only the generic candidates.
    fn notes(&self, rec: &Recording) -> Vec<String> {
        let mut out: Vec<String> = (self.graph.outputs().iter())
            .filter(|o| rec.signal(&o.name).is_none())
            .map(|o| {
                format!(
                    "the recording does not measure output `{}`: it is left out",
                    o.name
                )
            })
            .collect();
        let g = &self.graph;
        for id in g.element_ids() {
            let el = g.element(id);
            let generic_node = effects::Node::of(g, id)
                .is_some_and(|n| n.kind == effects::NodeKind::Generic && el.domain.is_none());
            let has_inertia = el.kind == ElementKind::One
                && (g.ports(id).iter())
                    .any(|(b, _)| g.element(g.other_end(*b, id)).kind == ElementKind::I);
            let unknown_junction =
                has_inertia && el.domain.is_none() && effects::Junction::of(g, id).is_none();
            if generic_node || unknown_junction {
                out.push(format!(
                    "junction `{}` has no unit to read and declares no domain: the menu tries only \
                     generic effects there; give its storage parameter a unit or write \
                     `domain = \"hydraulic\"` (electrical, rotational, translational, pneumatic, \
                     thermal, magnetic) on it for that domain's physics",
                    el.name
                ));
            }
        }
        out
    }

    /// The parameters and initial states marked free in the graph (see
    /// [`effects::Calibration`]).
    fn missing_signals(
        &self,
        rec: &Recording,
        effects: &[(&Candidate, &[f64])],
        outputs: &[String],
        sigma: &[f64],
    ) -> modelgap_core::Result<Vec<MissingSignal>> {
        crate::estimate::missing_signals(self, rec, effects, outputs, sigma)
            .map_err(|e| model_error(effects, e))
    }

    fn measurement_noise(
        &self,
        rec: &Recording,
        effects: &[(&Candidate, &[f64])],
        outputs: &[String],
        sigma: &[f64],
    ) -> modelgap_core::Result<Vec<(String, f64)>> {
        crate::estimate::measurement_noise(self, rec, effects, outputs, sigma)
            .map_err(|e| model_error(effects, e))
    }

    /// Where the edit leaves the graph and its changes as they are (a
    /// parameter at its current value). Not merely at the values at which its
    /// kind does nothing: a saturation of 0 still makes the inductor's law
    /// nonlinear, and a linear graph is simulated another way (exactly), so
    /// the two predictions differ at the solver's tolerance — which a
    /// finite difference divides by its step.
    fn vanishes(&self, c: &Candidate, values: &[f64]) -> bool {
        self.edited(&[(c, values)])
            .is_ok_and(|(g, changes)| g == self.graph && changes == self.changes)
    }

    fn law_candidate(&self, law: &modelgap_core::explain::screen::Law) -> Option<Candidate> {
        crate::effects::law_candidate(&self.graph, law)
    }

    fn free_parameters(&self) -> Option<Candidate> {
        effects::Calibration::of(&self.graph)
    }

    fn with_effects(&self, effects: &[Effect]) -> modelgap_core::Result<Box<dyn Model>> {
        let pairs: Vec<(&Candidate, &[f64])> = effects
            .iter()
            .map(|e| (&e.candidate, e.values.as_slice()))
            .collect();
        let (graph, changes) = self.edited(&pairs).map_err(|e| model_error(&pairs, e))?;
        let mut added = self.added.clone();
        added.extend(effects.iter().map(|e| {
            if e.candidate.kind == modelgap_core::EffectKind::Calibration {
                format!("free parameters fitted: {e}")
            } else {
                format!("added by explain: {e}")
            }
        }));
        Ok(Box::new(BondModel {
            graph,
            changes,
            start: self.start,
            added,
            hold: self.hold,
            input_holds: self.input_holds.clone(),
            fixed_step: self.fixed_step,
        }))
    }

    /// The graph as a model file, headed by a comment line per effect built
    /// in; the abrupt changes explain found are written as `[[changes]]`,
    /// so a model read back from the file makes them too.
    fn to_file_text(&self) -> Option<String> {
        let mut s = String::new();
        for a in &self.added {
            let _ = writeln!(s, "# {a}");
        }
        let mut graph = self.graph.clone();
        for c in &self.changes {
            let change = ScheduledChange {
                at: c.at,
                what: Scheduled::Parameter(c.name.clone()),
                value: c.value,
                description: "abrupt change found by explain".to_string(),
            };
            if graph.add_scheduled(change).is_err() {
                // Not a parameter of the graph (cannot happen for changes
                // made by effects): keep it visible as a comment.
                let _ = writeln!(
                    s,
                    "# fault: {} becomes {} at t = {} s (abrupt change found by explain)",
                    c.name, c.value, c.at
                );
            }
        }
        s.push_str(&write_model(&graph));
        Some(s)
    }

    fn file_extension(&self) -> &'static str {
        "toml"
    }

    /// Runs the paper's diagnosis ([`diagnose`], a band of 5 noise sigmas,
    /// persistence 3, the model's start) and says whether the parameter a
    /// candidate acts through is in the first hypothesis set of the fault
    /// trees at the final stage. Deviations and abrupt changes look for
    /// their parameter (either sign); missing elements for the nearest
    /// parameter effect: viscous friction and a brush drop for the
    /// junction's R increasing, Coulomb friction and a load for the
    /// junction's load input or R increasing, extra inertia for the
    /// junction's inertia (either sign). `None` for the others, when the
    /// diagnosis cannot run, or when it detects nothing.
    fn qualitative_agreement(&self, rec: &Recording, candidate: &Candidate) -> Option<bool> {
        self.qualitative_check(rec, candidate).map(|c| c.agrees)
    }

    /// [`qualitative_agreement`](Model::qualitative_agreement) with its
    /// reason: which outputs left their bands first and which way, the
    /// parameter deviations their fault trees share, and the deviation the
    /// candidate would show as.
    fn qualitative_check(
        &self,
        rec: &Recording,
        candidate: &Candidate,
    ) -> Option<QualitativeCheck> {
        let targets = BondEffect::from_candidate(candidate, &self.graph)
            .ok()?
            .qualitative_signature(&self.graph)?;
        let opts = DiagnosisOptions {
            threshold: Threshold::Noise { sigmas: 5.0 },
            persistence: 3,
            steady_start: self.start == Start::SteadyState,
            sim: SimOptions {
                rtol: RTOL,
                atol: ATOL,
                ..SimOptions::default()
            },
            ..DiagnosisOptions::default()
        };
        let d = diagnose(&self.graph, rec, &opts).ok()?;
        let detected_at = d.detected_at?;
        let set = first_hypothesis_set(&d.trees);
        let agrees = targets.iter().any(|(param, sign)| {
            set.iter()
                .any(|h| h.param == *param && sign.is_none_or(|s| h.deviation == s))
        });
        Some(QualitativeCheck {
            agrees,
            reason: qualitative_reason(&d.trees, &set, &targets, detected_at, agrees),
        })
    }
}

/// The plain-words reason of a qualitative check: "measured i above the model
/// and omega below it first (from 0.13 s); their fault trees point at R+, k-;
/// this effect would show as beta+, which is not among them".
fn qualitative_reason(
    trees: &[FaultTree],
    set: &std::collections::BTreeSet<Hypothesis>,
    targets: &[QualTarget],
    detected_at: f64,
    agrees: bool,
) -> String {
    // The residual is measured − model: + means the measurement ran above the model.
    let moved: Vec<String> = trees
        .iter()
        .filter(|t| t.qual != Qual::Zero)
        .enumerate()
        .map(|(k, t)| {
            let way = if t.qual == Qual::Plus {
                "above"
            } else {
                "below"
            };
            let what = if k == 0 { "the model" } else { "it" };
            format!("{} {way} {what}", t.output)
        })
        .collect();
    let moved = match moved.as_slice() {
        [] => "no output deviated clearly".to_owned(),
        [one] => format!("measured {one}"),
        [rest @ .., last] => format!("measured {} and {last}", rest.join(", ")),
    };
    let shows_as: Vec<String> = targets
        .iter()
        .map(|(p, sign)| match sign {
            Some(s) => format!("{p}{s}"),
            None => format!("{p}+ or {p}-"),
        })
        .collect();
    let shows_as = shows_as.join(" or ");
    let pointed = if set.is_empty() {
        "their fault trees share no parameter deviation".to_owned()
    } else {
        let names: Vec<String> = set.iter().map(ToString::to_string).collect();
        format!("their fault trees point at {}", names.join(", "))
    };
    let verdict = if agrees {
        "which is among them"
    } else {
        "which is not among them"
    };
    format!(
        "{moved} first (from {} s); {pointed}; this effect would show as {shows_as}, {verdict}",
        modelgap_core::report::format_number(detected_at)
    )
}
