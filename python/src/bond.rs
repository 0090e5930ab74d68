//! Wrappers of modelgap-bond: [`PyBondModel`] (a bond graph as the measurement loop's
//! model, with its equations, simulation and diagnosis), [`PyDiagnosis`], Table 7 and the
//! hidden-effect recordings.

use std::collections::BTreeMap;
use std::path::PathBuf;
use std::sync::Arc;

use modelgap::bond::BondModel;
use modelgap::bond::causal_graph::CausalGraph;
use modelgap::bond::compiled::CompiledModel;
use modelgap::bond::diagnosis::{Diagnosis, DiagnosisOptions, diagnose, set_text};
use modelgap::bond::fault_tree::fault_tree;
use modelgap::bond::file::{read_model, read_model_path};
use modelgap::bond::model::Start;
use modelgap::bond::notation::{equations_latex, equations_text};
use modelgap::bond::qual::Qual;
use modelgap::bond::simulate::{Drive, Hold, Inputs, ParamChange, SimOptions, Solver, simulate};
use modelgap::bond::{BondError, BondGraph, Equations, StateSpace, assign_causality, library};
use modelgap::{Effect, Model, Threshold};
use numpy::{Complex64, PyArray1};
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyTuple};

use crate::convert::{array1, detached, matrix, vec_from_py};
use crate::core_api::{PyEffect, PyRecording};
use crate::errors::{data_error, to_py_err};

/// Registers the bond classes and functions (re-exported by `modelgap.bond`).
pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<PyBondModel>()?;
    m.add_class::<PyDiagnosis>()?;
    m.add_function(wrap_pyfunction!(table7, m)?)?;
    m.add_function(wrap_pyfunction!(hidden_recording, m)?)?;
    m.add_function(wrap_pyfunction!(hidden_cases, m)?)?;
    Ok(())
}

/// Candidates as dicts with ``id``, ``name``, ``kind``, ``acts_on`` and ``params`` (names).
pub fn candidate_dicts<'py>(
    py: Python<'py>,
    candidates: &[modelgap::Candidate],
) -> PyResult<Vec<Bound<'py, PyDict>>> {
    candidates
        .iter()
        .map(|c| {
            let d = PyDict::new(py);
            d.set_item("id", &c.id)?;
            d.set_item("name", &c.name)?;
            d.set_item("kind", c.kind.to_string())?;
            d.set_item("acts_on", &c.acts_on)?;
            d.set_item(
                "params",
                c.params.iter().map(|p| p.name.clone()).collect::<Vec<_>>(),
            )?;
            Ok(d)
        })
        .collect()
}

fn start_name(s: Start) -> &'static str {
    match s {
        Start::Rest => "rest",
        Start::SteadyState => "steady",
    }
}

fn parse_start(s: &str) -> PyResult<Start> {
    match s {
        "rest" => Ok(Start::Rest),
        "steady" | "steady-state" | "steady_state" => Ok(Start::SteadyState),
        _ => Err(data_error(format!(
            "start must be \"rest\" or \"steady\", found \"{s}\""
        ))),
    }
}

fn hold_name(h: Hold) -> &'static str {
    match h {
        Hold::Zero => "zoh",
        Hold::Linear => "linear",
        Hold::Cubic => "cubic",
    }
}

/// A model's hold: `None` is `"auto"` (chosen per input from each recording).
fn model_hold_name(h: Option<Hold>) -> &'static str {
    h.map_or("auto", hold_name)
}

/// A model's hold: `"auto"`, `"zoh"` or `"linear"`.
pub fn parse_model_hold(s: &str) -> PyResult<Option<Hold>> {
    match s {
        "auto" => Ok(None),
        "zoh" | "zero" => Ok(Some(Hold::Zero)),
        "linear" => Ok(Some(Hold::Linear)),
        "cubic" => Ok(Some(Hold::Cubic)),
        _ => Err(data_error(format!(
            "hold must be \"auto\", \"zoh\", \"linear\" or \"cubic\", found \"{s}\""
        ))),
    }
}

fn parse_hold(s: &str) -> PyResult<Hold> {
    match s {
        "zoh" | "zero" => Ok(Hold::Zero),
        "linear" => Ok(Hold::Linear),
        "cubic" => Ok(Hold::Cubic),
        _ => Err(data_error(format!(
            "hold must be \"zoh\", \"linear\" or \"cubic\", found \"{s}\""
        ))),
    }
}

fn parse_solver(s: &str) -> PyResult<Solver> {
    match s {
        "auto" => Ok(Solver::Auto),
        "exact" => Ok(Solver::Exact),
        "dopri5" => Ok(Solver::Dopri5),
        "rosenbrock" => Ok(Solver::Rosenbrock),
        _ => Err(data_error(format!(
            "solver must be \"auto\", \"exact\", \"dopri5\" or \"rosenbrock\", found \"{s}\""
        ))),
    }
}

/// One input's drive from Python: a number, `(t, values)` arrays, or `("pwm", duty, freq)`
/// (optionally `("pwm", duty, freq, high, low)`).
fn drive_from_py(name: &str, obj: &Bound<'_, PyAny>, hold: Hold) -> PyResult<Drive> {
    if let Ok(v) = obj.extract::<f64>() {
        return Ok(Drive::Constant(v));
    }
    if let Ok(tuple) = obj.cast::<PyTuple>() {
        let first_is_pwm = tuple
            .get_item(0)
            .ok()
            .and_then(|x| x.extract::<String>().ok())
            .is_some_and(|s| s == "pwm");
        if first_is_pwm {
            let number = |i: usize, default: f64| -> PyResult<f64> {
                match tuple.get_item(i) {
                    Ok(x) => x.extract::<f64>(),
                    Err(_) => Ok(default),
                }
            };
            if !(3..=5).contains(&tuple.len()) {
                return Err(data_error(format!(
                    "input `{name}`: a PWM drive is (\"pwm\", duty, frequency_hz[, high, low]), found {} items",
                    tuple.len()
                )));
            }
            return Ok(Drive::Pwm {
                duty: number(1, 0.0)?,
                frequency_hz: number(2, 0.0)?,
                high: number(3, 1.0)?,
                low: number(4, 0.0)?,
            });
        }
        if tuple.len() == 2 {
            let t = vec_from_py(&tuple.get_item(0)?, &format!("the times of input `{name}`"))?;
            let values = vec_from_py(
                &tuple.get_item(1)?,
                &format!("the values of input `{name}`"),
            )?;
            return Ok(Drive::Sampled { t, values, hold });
        }
    }
    Err(data_error(format!(
        "input `{name}`: expected a number, (t, values) arrays or (\"pwm\", duty, frequency_hz), found {}",
        obj.repr()?
    )))
}

fn value_at_start(drive: &Drive) -> f64 {
    match drive {
        Drive::Constant(v) => *v,
        Drive::Sampled { values, .. } => values.first().copied().unwrap_or(0.0),
        Drive::Pwm {
            duty, high, low, ..
        } => low + duty * (high - low),
    }
}

/// What pickling stores of a model: its file text (as loaded), start, hold and the
/// effects built in (JSON).
type ModelState = (String, String, String, String);

/// A bond-graph model: what ``compare`` and ``explain`` hold against a recording.
///
/// Make one with ``BondModel.load(path)`` (a model file), ``BondModel.from_toml(text)``,
/// ``BondModel.dc_motor()``, ``BondModel.buck_motor()`` or ``BondModel.builtin(name)``.
/// Effects found by ``explain`` are added with ``with_effects``, which returns a new model.
#[pyclass(name = "BondModel", module = "modelgap.bond")]
pub struct PyBondModel {
    /// The model as loaded (and `set`), with its start and input hold.
    base: BondModel,
    /// How recorded inputs are held: `None` chosen per input from each recording
    /// ([`BondModel::settle_holds`]), else as given (mirrored in `base`).
    hold: Option<Hold>,
    /// Effects built in on top of `base`, in order.
    effects: Vec<Effect>,
    /// `base` with `effects`: what the loop works on.
    model: Arc<dyn Model>,
    /// The graph with `effects` built in.
    graph: BondGraph,
    /// The abrupt parameter changes of `effects`.
    changes: Vec<ParamChange>,
}

impl PyBondModel {
    fn build(
        graph: BondGraph,
        start: Start,
        hold: Option<Hold>,
        effects: Vec<Effect>,
    ) -> PyResult<Self> {
        let base = (BondModel::new(graph).with_start(start)).with_hold(hold.unwrap_or(Hold::Zero));
        let pairs: Vec<(&modelgap::Candidate, &[f64])> = effects
            .iter()
            .map(|e| (&e.candidate, e.values.as_slice()))
            .collect();
        let (graph, changes) = base.edited(&pairs).map_err(to_py_err)?;
        let model: Arc<dyn Model> = if effects.is_empty() {
            Arc::new(base.clone())
        } else {
            Arc::from(base.with_effects(&effects).map_err(to_py_err)?)
        };
        Ok(PyBondModel {
            base,
            hold,
            effects,
            model,
            graph,
            changes,
        })
    }

    fn from_graph(g: BondGraph) -> PyResult<Self> {
        Self::build(g, Start::Rest, None, Vec::new())
    }

    /// The class of a model loaded by the library ([`modelgap::load::load`]), holding
    /// recorded inputs as `hold` (`None`: chosen per input from each recording).
    pub fn from_model(m: &BondModel, hold: Option<Hold>) -> PyResult<Self> {
        Self::build(m.graph().clone(), m.start(), hold, Vec::new())
    }

    /// The loop's model: the graph with its effects, its start and input hold.
    pub fn loop_model(&self) -> Arc<dyn Model> {
        self.model.clone()
    }

    /// The loop's model for `rec`: with the hold `"auto"`, each input held as
    /// [`BondModel::settle_holds`] chooses on `rec`; also the notes saying how and why.
    pub fn loop_model_for(
        &self,
        rec: &modelgap::Recording,
    ) -> PyResult<(Arc<dyn Model>, Vec<String>)> {
        if self.hold.is_some() {
            return Ok((self.model.clone(), Vec::new()));
        }
        let mut base = self.base.clone();
        let notes = base
            .settle_holds(rec)
            .iter()
            .map(ToString::to_string)
            .collect();
        let model: Arc<dyn Model> = if self.effects.is_empty() {
            Arc::new(base)
        } else {
            Arc::from(base.with_effects(&self.effects).map_err(to_py_err)?)
        };
        Ok((model, notes))
    }

    fn rebuilt(&self, start: Start, hold: Option<Hold>, effects: Vec<Effect>) -> PyResult<Self> {
        Self::build(self.base.graph().clone(), start, hold, effects)
    }

    fn equations_of(&self) -> PyResult<Equations> {
        let g = &self.graph;
        let c = assign_causality(g).map_err(to_py_err)?;
        Equations::derive(g, &c).map_err(to_py_err)
    }

    fn causal_graph(&self) -> PyResult<CausalGraph> {
        let eqs = self.equations_of()?;
        CausalGraph::from_graph(&self.graph, &eqs).map_err(to_py_err)
    }

    /// The linear state space at the default inputs: as is for an LTI model, else
    /// linearised at the steady state (or at zero when there is none).
    fn linear(&self) -> PyResult<StateSpace> {
        let model = CompiledModel::new(&self.graph).map_err(to_py_err)?;
        let u0 = model.input_defaults.clone();
        if model.is_lti {
            Ok(StateSpace::of_compiled(&model, None, Some(&u0)))
        } else {
            let x0 = model
                .steady_state(&u0, None)
                .unwrap_or_else(|_| vec![0.0; model.n_states()]);
            Ok(StateSpace::of_compiled(&model, Some(&x0), Some(&u0)))
        }
    }
}

#[pymethods]
impl PyBondModel {
    /// Reads a bond-graph model file (TOML). Raises ``DataError`` naming the line and column.
    #[staticmethod]
    fn load(py: Python<'_>, path: PathBuf) -> PyResult<Self> {
        let g = detached(py, move || read_model_path(&path))?.map_err(to_py_err)?;
        Self::from_graph(g)
    }

    /// A model from the text of a model file.
    #[staticmethod]
    fn from_toml(text: &str) -> PyResult<Self> {
        Self::from_graph(read_model(text).map_err(to_py_err)?)
    }

    /// The DC motor of the diagnosis paper (12 V, permanent magnet).
    #[staticmethod]
    fn dc_motor() -> PyResult<Self> {
        Self::from_graph(library::dc_motor())
    }

    /// The buck converter feeding the DC motor (section 5 of the paper).
    #[staticmethod]
    fn buck_motor() -> PyResult<Self> {
        Self::from_graph(library::buck_motor())
    }

    /// A built-in model by name: ``dc-motor`` or ``buck-motor``.
    #[staticmethod]
    fn builtin(name: &str) -> PyResult<Self> {
        Self::from_graph(library::builtin(name).map_err(to_py_err)?)
    }

    /// The names of the built-in models.
    #[staticmethod]
    fn builtins() -> Vec<&'static str> {
        library::BUILTINS.iter().map(|(n, _)| *n).collect()
    }

    /// The same model with predictions starting at ``"rest"`` or ``"steady"`` (the steady
    /// state under the recording's first input values).
    fn with_start(&self, start: &str) -> PyResult<Self> {
        self.rebuilt(parse_start(start)?, self.hold, self.effects.clone())
    }

    /// The same model with recorded inputs held ``"auto"`` (the default: each input that
    /// steps held at its samples' values, any other the way the model predicts the recording
    /// better), ``"zoh"`` or ``"linear"``.
    fn with_hold(&self, hold: &str) -> PyResult<Self> {
        self.rebuilt(
            self.base.start(),
            parse_model_hold(hold)?,
            self.effects.clone(),
        )
    }

    /// How ``"auto"`` holds each input ``rec`` records, and why: one sentence per input
    /// that is not constant (the notes ``modelgap explain`` prints); empty for a model with
    /// its hold given.
    fn hold_notes(&self, rec: &Bound<'_, crate::core_api::PyRecording>) -> PyResult<Vec<String>> {
        Ok(self.loop_model_for(&rec.get().inner)?.1)
    }

    /// A new model with the effects (from ``Explanation.effects``) built in.
    fn with_effects(&self, effects: Vec<PyRef<'_, PyEffect>>) -> PyResult<Self> {
        let mut all = self.effects.clone();
        all.extend(effects.iter().map(|e| e.inner.clone()));
        self.rebuilt(self.base.start(), self.hold, all)
    }

    /// Sets a parameter (or an input's default) of the model as loaded.
    fn set(&mut self, name: &str, value: f64) -> PyResult<()> {
        let mut g = self.base.graph().clone();
        g.set_param(name, value).map_err(to_py_err)?;
        *self = Self::build(g, self.base.start(), self.hold, self.effects.clone())?;
        Ok(())
    }

    /// Marks a parameter unknown, for ``modelgap.fit`` to calibrate within ``bounds``
    /// (``(lower, upper)``; ``None``: from 0 to 1000 times its value, its sign kept).
    ///
    /// Raises ``DataError`` for an unknown parameter, bounds that are not finite and
    /// ordered or leave out its value, or no bounds for a value of 0.
    #[pyo3(signature = (name, bounds = None))]
    fn free(&mut self, name: &str, bounds: Option<(f64, f64)>) -> PyResult<()> {
        use modelgap::bond::element::Range;
        let mut g = self.base.graph().clone();
        let value = g.param(name).map_err(to_py_err)?;
        let range = match bounds {
            Some((lower, upper)) => Range { lower, upper },
            None => Range::around(value, None, None).ok_or_else(|| {
                crate::errors::data_error(format!(
                    "{name} is 0, which gives no default bounds: pass bounds=(lower, upper)"
                ))
            })?,
        };
        g.set_free(name, Some(range)).map_err(to_py_err)?;
        *self = Self::build(g, self.base.start(), self.hold, self.effects.clone())?;
        Ok(())
    }

    /// The model's name.
    #[getter]
    fn name(&self) -> String {
        self.graph.name.clone()
    }

    /// Where predictions start: ``"rest"`` or ``"steady"``.
    #[getter]
    fn start(&self) -> &'static str {
        start_name(self.base.start())
    }

    /// How recorded inputs are held: ``"auto"``, ``"zoh"`` or ``"linear"``.
    #[getter]
    fn hold(&self) -> &'static str {
        model_hold_name(self.hold)
    }

    /// Parameter values by name (SI units), effects included; a fresh dict.
    #[getter]
    fn params(&self) -> BTreeMap<String, f64> {
        self.graph
            .params()
            .iter()
            .map(|(n, p)| (n.clone(), p.value))
            .collect()
    }

    /// Parameter units by name.
    #[getter]
    fn units(&self) -> BTreeMap<String, String> {
        self.graph
            .params()
            .iter()
            .map(|(n, p)| (n.clone(), p.unit.clone()))
            .collect()
    }

    /// Input defaults by name.
    #[getter]
    fn inputs(&self) -> BTreeMap<String, f64> {
        self.graph
            .inputs()
            .iter()
            .map(|(n, i)| (n.clone(), i.default))
            .collect()
    }

    /// The measured outputs, in order.
    #[getter]
    fn outputs(&self) -> Vec<String> {
        self.model.outputs()
    }

    /// The effects built in so far.
    #[getter]
    fn effects(&self) -> Vec<PyEffect> {
        self.effects
            .iter()
            .map(|e| PyEffect { inner: e.clone() })
            .collect()
    }

    /// The candidate effects explain fits: dicts with ``id``, ``name``, ``kind``,
    /// ``acts_on`` and ``params`` (names).
    fn candidates<'py>(&self, py: Python<'py>) -> PyResult<Vec<Bound<'py, PyDict>>> {
        candidate_dicts(py, &self.model.candidates())
    }

    /// The causal equations (and the state equations) in the paper's notation; LaTeX
    /// (an ``align*`` environment) with ``latex=True``.
    #[pyo3(signature = (latex = false))]
    fn equations(&self, latex: bool) -> PyResult<String> {
        let eqs = self.equations_of()?;
        Ok(if latex {
            equations_latex(&self.graph, &eqs)
        } else {
            equations_text(&self.graph, &eqs)
        })
    }

    fn _repr_latex_(&self) -> PyResult<String> {
        self.equations(true)
    }

    /// The linear state space at the default inputs (linearised at the steady state for a
    /// model that is not LTI): a dict of ``A``, ``B``, ``C``, ``D`` (fresh float64 arrays)
    /// and ``states``, ``inputs``, ``outputs`` names.
    fn state_space<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let ss = self.linear()?;
        let d = PyDict::new(py);
        d.set_item("A", matrix(py, &ss.a))?;
        d.set_item("B", matrix(py, &ss.b))?;
        d.set_item("C", matrix(py, &ss.c))?;
        d.set_item("D", matrix(py, &ss.d))?;
        d.set_item("states", ss.states.clone())?;
        d.set_item("inputs", ss.inputs.clone())?;
        d.set_item("outputs", ss.outputs.clone())?;
        Ok(d)
    }

    /// The eigenvalues of ``A`` (1/s), a complex array.
    fn eigenvalues<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray1<Complex64>>> {
        let ss = self.linear()?;
        let v: Vec<Complex64> = ss
            .modes()
            .iter()
            .map(|m| Complex64::new(m.eigenvalue.re, m.eigenvalue.im))
            .collect();
        Ok(PyArray1::from_vec(py, v))
    }

    /// The steady state under the given input values (defaults for the others): a dict of
    /// states and outputs by name. Raises ``ConvergenceError`` when there is none.
    #[pyo3(signature = (inputs = None))]
    fn steady_state(
        &self,
        inputs: Option<BTreeMap<String, f64>>,
    ) -> PyResult<BTreeMap<String, f64>> {
        let model = CompiledModel::new(&self.graph).map_err(to_py_err)?;
        let inputs = inputs.unwrap_or_default();
        for name in inputs.keys() {
            if !model.input_names.contains(name) {
                return Err(data_error(format!(
                    "unknown input `{name}`; inputs: {}",
                    model.input_names.join(", ")
                )));
            }
        }
        let u: Vec<f64> = model
            .input_names
            .iter()
            .zip(&model.input_defaults)
            .map(|(n, d)| inputs.get(n).copied().unwrap_or(*d))
            .collect();
        let x = model.steady_state(&u, None).map_err(to_py_err)?;
        let mut scratch = model.scratch();
        model.eval(0.0, &x, &u, &mut scratch);
        let mut y = vec![0.0; model.n_outputs()];
        model.read_outputs(&scratch, &mut y);
        let mut out: BTreeMap<String, f64> = model.state_names.iter().cloned().zip(x).collect();
        out.extend(model.output_names.iter().cloned().zip(y));
        Ok(out)
    }

    /// Simulates the model at times ``t`` (s) and returns a ``Recording`` of its inputs and
    /// outputs (and states with ``states=True``).
    ///
    /// ``inputs`` maps an input name to a number, ``(t, values)`` arrays (held ``hold``
    /// between samples) or ``("pwm", duty, frequency_hz)``; the others keep their defaults.
    /// ``faults`` are ``(parameter, new_value, at_s)`` abrupt changes. The GIL is released.
    #[pyo3(signature = (t, inputs = None, *, solver = "auto", faults = None, steady_start = false, hold = "linear", states = false))]
    #[allow(clippy::too_many_arguments)] // keyword-only options of the Python API
    fn simulate(
        &self,
        py: Python<'_>,
        t: &Bound<'_, PyAny>,
        inputs: Option<&Bound<'_, PyDict>>,
        solver: &str,
        faults: Option<Vec<(String, f64, f64)>>,
        steady_start: bool,
        hold: &str,
        states: bool,
    ) -> PyResult<PyRecording> {
        let t = vec_from_py(t, "t")?;
        let hold = parse_hold(hold)?;
        let mut drives = Inputs::new();
        let mut start_values = BTreeMap::new();
        if let Some(inputs) = inputs {
            for (k, v) in inputs.iter() {
                let name: String = k.extract()?;
                if !self.graph.inputs().contains_key(&name) {
                    return Err(data_error(format!(
                        "model {} has no input `{name}`; inputs: {}",
                        self.graph.name,
                        self.graph
                            .inputs()
                            .keys()
                            .cloned()
                            .collect::<Vec<_>>()
                            .join(", ")
                    )));
                }
                let drive = drive_from_py(&name, &v, hold)?;
                start_values.insert(name.clone(), value_at_start(&drive));
                drives.set(&name, drive);
            }
        }
        let mut changes = self.changes.clone();
        for (name, value, at) in faults.unwrap_or_default() {
            if !self.graph.params().contains_key(&name) && !self.graph.inputs().contains_key(&name)
            {
                return Err(data_error(format!(
                    "fault on `{name}`: model {} has no such parameter; parameters: {}",
                    self.graph.name,
                    self.graph
                        .params()
                        .keys()
                        .cloned()
                        .collect::<Vec<_>>()
                        .join(", ")
                )));
            }
            changes.push(ParamChange { at, name, value });
        }
        let opts = SimOptions {
            solver: parse_solver(solver)?,
            changes,
            ..SimOptions::default()
        };
        let g = &self.graph;
        let run = detached(py, move || -> Result<_, BondError> {
            let mut opts = opts;
            if steady_start {
                let model = CompiledModel::new(g)?;
                let u0: Vec<f64> = model
                    .input_names
                    .iter()
                    .zip(&model.input_defaults)
                    .map(|(n, d)| start_values.get(n).copied().unwrap_or(*d))
                    .collect();
                opts.initial_state = Some(model.steady_state(&u0, None)?);
            }
            simulate(g, &drives, &t, &opts)?.to_recording(states)
        })?
        .map_err(to_py_err)?;
        Ok(run.into())
    }

    /// The causal graph as Graphviz DOT.
    fn causal_graph_dot(&self) -> PyResult<String> {
        Ok(self.causal_graph()?.to_dot())
    }

    /// The causal graph's antecedents/consequents table, as text.
    fn causal_table(&self) -> PyResult<String> {
        Ok(self.causal_graph()?.table())
    }

    /// The fault tree of a measured output with a qualitative value ``"+"``, ``"-"`` or
    /// ``"0"``, as text.
    fn fault_tree(&self, output: &str, qual: &str) -> PyResult<String> {
        let q = Qual::parse(qual).ok_or_else(|| {
            data_error(format!(
                "qual must be \"+\", \"-\" or \"0\", found \"{qual}\""
            ))
        })?;
        let cg = self.causal_graph()?;
        Ok(fault_tree(&cg, output, q).map_err(to_py_err)?.to_text())
    }

    /// The paper's diagnosis of a recording: residuals from a parallel model, detection
    /// against a band (``threshold``: a fraction of the steady state, the paper's 2 %; or
    /// ``noise_sigmas`` noise floors), fault trees and temporal signatures.
    #[pyo3(signature = (rec, *, threshold = 0.02, noise_sigmas = None, persistence = 3, steady_start = false))]
    fn diagnose(
        &self,
        py: Python<'_>,
        rec: &Bound<'_, PyRecording>,
        threshold: f64,
        noise_sigmas: Option<f64>,
        persistence: usize,
        steady_start: bool,
    ) -> PyResult<PyDiagnosis> {
        let threshold = match noise_sigmas {
            Some(sigmas) => Threshold::Noise { sigmas },
            None => Threshold::FractionOfSteadyState {
                fraction: threshold,
            },
        };
        let g = &self.graph;
        let rec = &rec.get().inner;
        let d = detached(py, move || -> Result<Diagnosis, BondError> {
            let mut opts = DiagnosisOptions {
                threshold,
                persistence,
                steady_start,
                ..DiagnosisOptions::default()
            };
            if steady_start {
                let model = CompiledModel::new(g)?;
                let u0: Vec<f64> = model
                    .input_names
                    .iter()
                    .zip(&model.input_defaults)
                    .map(|(n, d)| rec.signal(n).map_or(*d, |s| s.values[0]))
                    .collect();
                opts.sim.initial_state = Some(model.steady_state(&u0, None)?);
            }
            diagnose(g, rec, &opts)
        })?
        .map_err(to_py_err)?;
        Ok(PyDiagnosis { inner: d })
    }

    /// Analytical redundancy relations, the fault signature matrix, detectability and
    /// isolability, as text.
    fn arrs(&self) -> PyResult<String> {
        let eqs = self.equations_of()?;
        let a = modelgap::bond::arr::derive_arrs(&self.graph, &eqs).map_err(to_py_err)?;
        Ok(a.to_text())
    }

    /// The model as a model file (TOML), headed by a comment per effect built in.
    fn to_toml(&self) -> String {
        self.model
            .to_file_text()
            .unwrap_or_else(|| modelgap::bond::file::write_model(&self.graph))
    }

    /// Writes ``to_toml()`` to a file.
    fn save(&self, py: Python<'_>, path: PathBuf) -> PyResult<()> {
        let text = self.to_toml();
        detached(py, move || {
            modelgap::io::atomic::write_atomic(&path, text.as_bytes())
        })?
        .map_err(to_py_err)
    }

    /// Restores a pickled model (see ``__reduce__``).
    #[staticmethod]
    fn _from_state(text: &str, start: &str, hold: &str, effects: &str) -> PyResult<Self> {
        let g = read_model(text).map_err(to_py_err)?;
        let effects: Vec<Effect> = serde_json::from_str(effects)
            .map_err(|e| data_error(format!("not the JSON of a list of effects: {e}")))?;
        Self::build(g, parse_start(start)?, parse_model_hold(hold)?, effects)
    }

    fn __reduce__<'py>(slf: &Bound<'py, Self>) -> PyResult<(Bound<'py, PyAny>, ModelState)> {
        let me = slf.borrow();
        let effects = serde_json::to_string(&me.effects).map_err(|e| data_error(e.to_string()))?;
        let restore = slf.get_type().getattr("_from_state")?;
        Ok((
            restore,
            (
                modelgap::bond::file::write_model(me.base.graph()),
                start_name(me.base.start()).to_owned(),
                model_hold_name(me.hold).to_owned(),
                effects,
            ),
        ))
    }

    fn __repr__(&self) -> String {
        format!(
            "<BondModel {} states={} params={} effects={} start={} hold={}>",
            self.graph.name,
            self.graph
                .elements()
                .iter()
                .filter(|e| e.kind.is_storage())
                .count(),
            self.graph.params().len(),
            self.effects.len(),
            start_name(self.base.start()),
            model_hold_name(self.hold)
        )
    }
}

/// The result of ``BondModel.diagnose``: detection, fault trees, signatures and the
/// hypothesis sets.
#[pyclass(name = "Diagnosis", module = "modelgap.bond", frozen)]
pub struct PyDiagnosis {
    inner: Diagnosis,
}

#[pymethods]
impl PyDiagnosis {
    /// The final hypothesis set, each as parameter and deviation (``R+``).
    #[getter]
    fn hypotheses(&self) -> Vec<String> {
        self.inner
            .hypotheses
            .iter()
            .map(ToString::to_string)
            .collect()
    }
    /// The parameters of the final hypothesis set, sorted.
    #[getter]
    fn parameters(&self) -> Vec<String> {
        self.inner.parameters()
    }
    /// When the first residual left its band (s), if one did.
    #[getter]
    fn detected_at(&self) -> Option<f64> {
        self.inner.detected_at
    }
    /// ``zero``, ``transitory`` or ``permanent``.
    #[getter]
    fn behaviour(&self) -> String {
        self.inner.behaviour().to_string()
    }
    /// Per output: a dict of ``output``, ``band``, ``detected_at``, ``first_deviation``,
    /// ``behaviour`` and ``residual`` (a fresh float64 array).
    #[getter]
    fn residuals<'py>(&self, py: Python<'py>) -> PyResult<Vec<Bound<'py, PyDict>>> {
        self.inner
            .residuals
            .iter()
            .map(|r| {
                let d = PyDict::new(py);
                d.set_item("output", &r.output)?;
                d.set_item("band", r.band)?;
                d.set_item("detected_at", r.detected_at)?;
                d.set_item("first_deviation", r.first_deviation.to_string())?;
                d.set_item("behaviour", r.behaviour.to_string())?;
                d.set_item("residual", array1(py, &r.residual))?;
                Ok(d)
            })
            .collect()
    }
    /// The hypothesis sets as the measurements left their bands: ``(at_s, from_trees,
    /// after_signatures)`` with the sets as text.
    #[getter]
    fn stages(&self) -> Vec<(f64, String, String)> {
        self.inner
            .stages
            .iter()
            .map(|s| (s.at, set_text(&s.from_trees), set_text(&s.after_signatures)))
            .collect()
    }
    /// Non-fatal findings.
    #[getter]
    fn warnings(&self) -> Vec<String> {
        self.inner.warnings.clone()
    }
    /// The diagnosis as a report, as text.
    fn report(&self) -> String {
        self.inner.report()
    }
    fn __repr__(&self) -> String {
        format!(
            "<Diagnosis detected_at={} hypotheses={{{}}} behaviour={}>",
            self.inner
                .detected_at
                .map_or_else(|| "None".to_owned(), |t| format!("{t}")),
            self.hypotheses().join(", "),
            self.inner.behaviour()
        )
    }
}

/// The paper's Table 7: each ±20 % fault of the buck converter + motor simulated and
/// diagnosed, as a list of dicts (``fault``, ``detected_at``, ``deviations``,
/// ``hypotheses``, ``parameters``, ``behaviour``, ``paper_parameters``,
/// ``paper_behaviour``, ``contains_fault``, ``same_set``, ``same_behaviour``, ``stages``).
#[pyfunction]
fn table7<'py>(py: Python<'py>) -> PyResult<Vec<Bound<'py, PyDict>>> {
    let rows = detached(py, || {
        modelgap::bond::table7::table7(&modelgap::bond::table7::Table7Options::default())
    })?
    .map_err(to_py_err)?;
    rows.iter()
        .map(|r| {
            let d = PyDict::new(py);
            d.set_item("fault", &r.fault)?;
            d.set_item("detected_at", r.detected_at)?;
            d.set_item("deviations", r.deviations.clone())?;
            d.set_item("hypotheses", r.hypotheses.clone())?;
            d.set_item("parameters", r.parameters.clone())?;
            d.set_item("behaviour", &r.behaviour)?;
            d.set_item("paper_parameters", r.paper_parameters.clone())?;
            d.set_item("paper_behaviour", &r.paper_behaviour)?;
            d.set_item("contains_fault", r.contains_fault)?;
            d.set_item("same_set", r.same_set)?;
            d.set_item("same_behaviour", r.same_behaviour)?;
            d.set_item("stages", r.stages.clone())?;
            Ok(d)
        })
        .collect()
}

/// The names of the hidden-effect cases (``coulomb``, ``load``, …, ``nothing``).
#[pyfunction]
fn hidden_cases() -> Vec<String> {
    modelgap::bond::hidden::cases()
        .into_iter()
        .map(|c| c.name)
        .collect()
}

/// A recording of a built-in motor with a hidden effect (or none, for ``nothing``):
/// sensor lag and white plus coloured noise included, seeded.
///
/// ``case`` is a name of ``hidden_cases()``, ``seed`` the noise seed (non-negative) and
/// ``duration`` the length (s, positive); samples at 1 kHz. Raises ``DataError`` for an
/// unknown case or a duration that is not positive. The GIL is released.
#[pyfunction]
#[pyo3(signature = (case, seed = 1, duration = 4.0))]
fn hidden_recording(py: Python<'_>, case: &str, seed: u64, duration: f64) -> PyResult<PyRecording> {
    let cases = modelgap::bond::hidden::cases();
    let Some(c) = cases.into_iter().find(|c| c.name == case) else {
        return Err(data_error(format!(
            "unknown hidden-effect case `{case}`; cases: {}",
            hidden_cases().join(", ")
        )));
    };
    if !(duration.is_finite() && duration > 0.0) {
        return Err(data_error(format!(
            "duration must be positive, found {duration} s"
        )));
    }
    let opts = modelgap::bond::hidden::RecordingOptions {
        seed,
        duration,
        ..Default::default()
    };
    let rec =
        detached(py, move || modelgap::bond::hidden::record(&c, &opts))?.map_err(to_py_err)?;
    Ok(rec.into())
}
