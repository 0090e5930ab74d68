//! The loop's models from Python: the built-in kinds (`BondModel`, `ClothModel`), models
//! loaded by name or file (`load_model`), and models written in Python — any object with
//! `outputs`, `predict(recording, effects)` and `candidates()` — behind the one seam
//! (`modelgap::Model`) that compare, explain and fix take.
//!
//! A Python model is called with the GIL taken for that call only: the loop itself runs
//! with the GIL released, on as many threads as it likes, and each prediction waits its turn
//! for the interpreter. An exception of the user's code that is a `modelgap.ModelError`
//! means "the model cannot simulate at these values" (a fit steps away from it); any other
//! exception is a bug in the user's model: it stops the loop and comes back to the caller
//! as itself, traceback included.

use std::collections::BTreeMap;
use std::path::PathBuf;
use std::sync::{Arc, Mutex};

use modelgap::fit::Cancel;
use modelgap::{
    Candidate, CoreError, Effect, EffectKind, EffectParam, Model, Prediction, Recording,
};
use pyo3::exceptions::PyTypeError;
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList};

use crate::bond::PyBondModel;
use crate::cloth::PyClothModel;
use crate::convert::{detached, vec_from_py};
use crate::core_api::{PyEffect, PyRecording};
use crate::errors::{ModelError, data_error, to_py_err};

/// Registers the classes and functions of this module.
pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<PyEffectParam>()?;
    m.add_class::<PyCandidate>()?;
    m.add_function(wrap_pyfunction!(load_model, m)?)?;
    m.add_function(wrap_pyfunction!(load_recording, m)?)?;
    Ok(())
}

/// A parameter of a candidate effect: its name, unit, start value, bounds and typical size
/// (the fit's scale, which also sets its finite-difference steps: give it even when the
/// start value is 0).
///
/// ``EffectParam(name, *, lower, upper, initial=None, scale=None, unit="", prior=None)``:
/// finite bounds with ``lower < upper`` (in ``unit``), ``initial`` within them (default their
/// midpoint), ``scale`` positive (default a tenth of ``upper - lower``), ``prior`` a Gaussian
/// ``(mean, std)`` that calibration weighs against the data (a model's free parameters only).
/// Raises ``DataError`` for values that break these rules.
#[pyclass(name = "EffectParam", module = "modelgap", frozen, get_all)]
#[derive(Clone)]
pub struct PyEffectParam {
    /// Name (``R_leak``).
    name: String,
    /// Unit (``Ohm``; ``""`` or ``"1"`` for none).
    unit: String,
    /// Where the fit starts.
    initial: f64,
    /// Lower bound.
    lower: f64,
    /// Upper bound.
    upper: f64,
    /// A typical size of the parameter.
    scale: f64,
    /// A Gaussian prior ``(mean, std)``, or ``None``.
    prior: Option<(f64, f64)>,
}

#[pymethods]
impl PyEffectParam {
    #[new]
    #[pyo3(signature = (name, *, lower, upper, initial = None, scale = None, unit = "", prior = None))]
    fn new(
        name: String,
        lower: f64,
        upper: f64,
        initial: Option<f64>,
        scale: Option<f64>,
        unit: &str,
        prior: Option<(f64, f64)>,
    ) -> PyResult<Self> {
        if let Some((mean, std)) = prior
            && modelgap::Prior::new(mean, std).is_none()
        {
            return Err(data_error(format!(
                "parameter {name}: prior (mean, std) needs a finite mean and a positive finite \
                 std, found ({mean}, {std})"
            )));
        }
        if !(lower.is_finite() && upper.is_finite() && lower < upper) {
            return Err(data_error(format!(
                "parameter {name}: bounds must be finite with lower < upper, found [{lower}, {upper}]"
            )));
        }
        let initial = initial.unwrap_or(0.5 * (lower + upper));
        if !(initial >= lower && initial <= upper) {
            return Err(data_error(format!(
                "parameter {name}: initial value {initial} is outside [{lower}, {upper}]"
            )));
        }
        let scale = scale.unwrap_or(0.1 * (upper - lower));
        if !(scale.is_finite() && scale > 0.0) {
            return Err(data_error(format!(
                "parameter {name}: scale must be positive and finite, found {scale}"
            )));
        }
        Ok(Self {
            name,
            unit: unit.to_owned(),
            initial,
            lower,
            upper,
            scale,
            prior,
        })
    }

    fn __repr__(&self) -> String {
        format!(
            "<EffectParam {} in [{}, {}] {} from {}>",
            self.name, self.lower, self.upper, self.unit, self.initial
        )
    }
}

impl From<&PyEffectParam> for EffectParam {
    fn from(p: &PyEffectParam) -> EffectParam {
        EffectParam {
            name: p.name.clone(),
            unit: p.unit.clone(),
            initial: p.initial,
            lower: p.lower,
            upper: p.upper,
            scale: p.scale,
            grid: 0,
            log_grid: false,
            step: 0.0,
            prior: p
                .prior
                .and_then(|(mean, std)| modelgap::Prior::new(mean, std)),
        }
    }
}

/// An effect a model may be missing: a stable ``id``, a plain ``name``, its ``kind``
/// (``missing-element``, ``parameter-deviation`` or ``abrupt-change``), where it acts and
/// its parameters (``EffectParam``).
///
/// ``Candidate(id, name, params, *, kind="missing-element", acts_on="")``, with at least
/// one parameter; what a Python model's ``candidates()`` lists. Raises ``DataError`` for
/// another ``kind`` or no parameter.
#[pyclass(name = "Candidate", module = "modelgap", frozen)]
#[derive(Clone)]
pub struct PyCandidate {
    pub(crate) inner: Candidate,
}

#[pymethods]
impl PyCandidate {
    #[new]
    #[pyo3(signature = (id, name, params, *, kind = "missing-element", acts_on = ""))]
    fn new(
        id: String,
        name: String,
        params: Vec<PyRef<'_, PyEffectParam>>,
        kind: &str,
        acts_on: &str,
    ) -> PyResult<Self> {
        let kind = match kind {
            "missing-element" => EffectKind::MissingElement,
            "parameter-deviation" => EffectKind::ParameterDeviation,
            "calibration" => EffectKind::Calibration,
            "abrupt-change" => EffectKind::AbruptChange,
            other => {
                return Err(data_error(format!(
                    "candidate {id}: kind must be missing-element, parameter-deviation or \
                     abrupt-change, found `{other}`"
                )));
            }
        };
        if params.is_empty() {
            return Err(data_error(format!(
                "candidate {id}: it needs at least one parameter to fit"
            )));
        }
        Ok(Self {
            inner: Candidate {
                id,
                name,
                kind,
                acts_on: acts_on.to_owned(),
                params: params.iter().map(|p| EffectParam::from(&**p)).collect(),
            },
        })
    }

    /// The stable id.
    #[getter]
    fn id(&self) -> &str {
        &self.inner.id
    }
    /// The plain name.
    #[getter]
    fn name(&self) -> &str {
        &self.inner.name
    }
    /// The parameters' names.
    #[getter]
    fn params(&self) -> Vec<String> {
        self.inner.params.iter().map(|p| p.name.clone()).collect()
    }
    /// The effect at ``values`` (parameter name to value, every parameter given), as the
    /// loop passes it to ``predict``: to try a model's effect by hand, or make a recording
    /// with it.
    fn effect(&self, values: BTreeMap<String, f64>) -> PyResult<PyEffect> {
        let mut ordered = Vec::with_capacity(self.inner.params.len());
        for p in &self.inner.params {
            let v = values.get(&p.name).ok_or_else(|| {
                data_error(format!(
                    "candidate {}: no value for parameter {} (its parameters: {})",
                    self.inner.id,
                    p.name,
                    self.params().join(", ")
                ))
            })?;
            ordered.push(*v);
        }
        if let Some(extra) = values
            .keys()
            .find(|k| !self.inner.params.iter().any(|p| &p.name == *k))
        {
            return Err(data_error(format!(
                "candidate {} has no parameter {extra} (its parameters: {})",
                self.inner.id,
                self.params().join(", ")
            )));
        }
        Ok(PyEffect {
            inner: Effect {
                candidate: self.inner.clone(),
                values: ordered,
            },
        })
    }
    fn __repr__(&self) -> String {
        format!("<Candidate {} ({})>", self.inner.id, self.inner.name)
    }
}

/// A model written in Python, behind the loop's seam (see the module docs).
pub struct PythonModel {
    object: Py<PyAny>,
    name: String,
    outputs: Vec<String>,
    inputs: Vec<String>,
    units: BTreeMap<String, String>,
    candidates: Vec<Candidate>,
    /// The model's own unknowns (`free_parameters()`), as one calibration candidate.
    free: Option<Candidate>,
    /// Effects built in (by `with_effects`), passed before the loop's own to `predict`.
    built_in: Vec<Effect>,
    /// The first exception of the user's code that is not a `ModelError`: raised again
    /// when the loop returns.
    raised: Arc<Mutex<Option<PyErr>>>,
    /// Set when such an exception is caught, to stop the loop early.
    stop: Arc<Mutex<Option<Arc<Cancel>>>>,
}

impl PythonModel {
    /// Wraps a Python object that has `outputs`, `predict(recording, effects)` and
    /// `candidates()` (and, optionally, `name`, `inputs`, `unit(output)` and
    /// `free_parameters()`, the model's own unknowns as `EffectParam`s: `fit` calibrates
    /// them, passing `predict` an effect of id `calibration` with their values, and explain
    /// fits every candidate jointly with them).
    ///
    /// # Errors
    /// `TypeError` naming what the object lacks; the exceptions of its `outputs` and
    /// `candidates()`.
    pub fn wrap(obj: &Bound<'_, PyAny>) -> PyResult<PythonModel> {
        let type_name = obj.get_type().name()?.to_string();
        for needed in ["outputs", "predict", "candidates"] {
            if !obj.hasattr(needed)? {
                return Err(PyTypeError::new_err(format!(
                    "a model must be a modelgap.bond.BondModel, a modelgap.cloth.ClothModel or an \
                     object with `outputs`, `predict(recording, effects)` and `candidates()`; \
                     {type_name} has no `{needed}`"
                )));
            }
        }
        let outputs: Vec<String> = obj.getattr("outputs")?.extract()?;
        // Any iterable of names (a list, or a dict of defaults).
        let mut inputs = Vec::new();
        if obj.hasattr("inputs")? {
            for name in obj.getattr("inputs")?.try_iter()? {
                inputs.push(name?.extract::<String>()?);
            }
        }
        let name: String = if obj.hasattr("name")? {
            obj.getattr("name")?.extract()?
        } else {
            type_name
        };
        let mut units = BTreeMap::new();
        if obj.hasattr("unit")? {
            for o in &outputs {
                let u: String = obj.call_method1("unit", (o.as_str(),))?.extract()?;
                units.insert(o.clone(), u);
            }
        }
        let listed = obj.call_method0("candidates")?;
        let mut candidates = Vec::new();
        for item in listed.try_iter()? {
            let item = item?;
            let c = item.cast::<PyCandidate>().map_err(|_| {
                PyTypeError::new_err(format!(
                    "{name}.candidates() must give modelgap.Candidate objects, found {}",
                    item.get_type()
                        .name()
                        .map_or_else(|_| "?".into(), |n| n.to_string())
                ))
            })?;
            candidates.push(c.get().inner.clone());
        }
        let free = if obj.hasattr("free_parameters")? {
            let listed = obj.call_method0("free_parameters")?;
            let mut params = Vec::new();
            for item in listed.try_iter()? {
                let item = item?;
                let p = item.cast::<PyEffectParam>().map_err(|_| {
                    PyTypeError::new_err(format!(
                        "{name}.free_parameters() must give modelgap.EffectParam objects, found {}",
                        item.get_type()
                            .name()
                            .map_or_else(|_| "?".into(), |n| n.to_string())
                    ))
                })?;
                params.push(EffectParam::from(p.get()));
            }
            (!params.is_empty()).then(|| Candidate {
                id: "calibration".to_string(),
                name: format!("calibration of {name}"),
                kind: EffectKind::Calibration,
                acts_on: name.clone(),
                params,
            })
        } else {
            None
        };
        Ok(PythonModel {
            object: obj.clone().unbind(),
            name,
            outputs,
            inputs,
            units,
            candidates,
            free,
            built_in: Vec::new(),
            raised: Arc::new(Mutex::new(None)),
            stop: Arc::new(Mutex::new(None)),
        })
    }

    /// The exception of the user's code that stopped the last loop, if one did (taken).
    pub fn take_raised(&self) -> Option<PyErr> {
        self.raised.lock().ok().and_then(|mut r| r.take())
    }

    /// The flag the loop stops on when the user's code raises.
    pub fn stop_with(&self, cancel: Arc<Cancel>) {
        if let Ok(mut s) = self.stop.lock() {
            *s = Some(cancel);
        }
    }

    /// Calls `predict`, converting what it returns.
    fn call_predict(
        &self,
        py: Python<'_>,
        rec: &Recording,
        effects: &[(&Candidate, &[f64])],
    ) -> PyResult<Prediction> {
        let list = PyList::empty(py);
        for e in &self.built_in {
            list.append(PyEffect { inner: e.clone() })?;
        }
        for (c, v) in effects {
            list.append(PyEffect {
                inner: Effect {
                    candidate: (*c).clone(),
                    values: v.to_vec(),
                },
            })?;
        }
        let result = self
            .object
            .bind(py)
            .call_method1("predict", (PyRecording::from(rec.clone()), list))?;
        let n = rec.len();
        let mut names = Vec::new();
        let mut values = Vec::new();
        let mapping = result.cast::<PyDict>().map_err(|_| {
            PyTypeError::new_err(format!(
                "{}.predict must return a dict of output name to an array of one value per \
                 sample, found {}",
                self.name,
                result
                    .get_type()
                    .name()
                    .map_or_else(|_| "?".into(), |n| n.to_string())
            ))
        })?;
        for (k, v) in mapping.iter() {
            let name: String = k.extract()?;
            let series = vec_from_py(&v, &format!("{}.predict()[{name:?}]", self.name))?;
            if series.len() != n {
                return Err(data_error(format!(
                    "{}.predict()[{name:?}] has {} values, expected {n} (one per sample of the \
                     recording)",
                    self.name,
                    series.len()
                )));
            }
            names.push(name);
            values.push(series);
        }
        Ok(Prediction { names, values })
    }
}

impl Model for PythonModel {
    fn name(&self) -> String {
        self.name.clone()
    }

    fn outputs(&self) -> Vec<String> {
        self.outputs.clone()
    }

    fn inputs(&self) -> Vec<String> {
        self.inputs.clone()
    }

    fn unit(&self, output: &str) -> String {
        self.units.get(output).cloned().unwrap_or_default()
    }

    fn predict_with(
        &self,
        rec: &Recording,
        effects: &[(&Candidate, &[f64])],
    ) -> Result<Prediction, CoreError> {
        Python::attach(|py| {
            self.call_predict(py, rec, effects).map_err(|err| {
                let message = format!("{} could not predict: {err}", self.name);
                // A ModelError is the model's own "not at these values"; anything else is a
                // bug in its code: keep it, and stop the loop.
                if !err.is_instance_of::<ModelError>(py) {
                    if let Ok(mut slot) = self.raised.lock()
                        && slot.is_none()
                    {
                        *slot = Some(err);
                    }
                    if let Ok(stop) = self.stop.lock()
                        && let Some(c) = stop.as_ref()
                    {
                        c.cancel();
                    }
                }
                CoreError::model(message)
            })
        })
    }

    fn candidates(&self) -> Vec<Candidate> {
        self.candidates.clone()
    }

    /// The unknowns `free_parameters()` listed, starting where the last calibration built
    /// in put them (a calibrated model is calibrated again from its own values).
    fn free_parameters(&self) -> Option<Candidate> {
        let mut free = self.free.clone()?;
        if let Some(cal) = (self.built_in.iter().rev()).find(|e| e.candidate.id == free.id) {
            for p in &mut free.params {
                if let Some(i) = cal.candidate.params.iter().position(|q| q.name == p.name) {
                    p.initial = cal.values[i].clamp(p.lower, p.upper);
                }
            }
        }
        Some(free)
    }

    fn with_effects(&self, effects: &[Effect]) -> Result<Box<dyn Model>, CoreError> {
        let object = Python::attach(|py| self.object.clone_ref(py));
        let mut built_in = self.built_in.clone();
        built_in.extend_from_slice(effects);
        Ok(Box::new(PythonModel {
            object,
            name: self.name.clone(),
            outputs: self.outputs.clone(),
            inputs: self.inputs.clone(),
            units: self.units.clone(),
            candidates: self.candidates.clone(),
            free: self.free.clone(),
            built_in,
            raised: Arc::new(Mutex::new(None)),
            stop: Arc::new(Mutex::new(None)),
        }))
    }
}

/// The loop's model behind a Python object: the model of a `BondModel` or `ClothModel`, or
/// a model written in Python (then also returned on its own, to raise its exceptions).
pub enum LoopModel {
    /// A built-in kind.
    Rust(Arc<dyn Model>),
    /// A model written in Python.
    Python(Arc<PythonModel>),
}

impl LoopModel {
    /// The model behind the seam.
    pub fn model(&self) -> Arc<dyn Model> {
        match self {
            LoopModel::Rust(m) => m.clone(),
            LoopModel::Python(m) => m.clone(),
        }
    }

    /// Turns the loop's result into Python's: a bug raised in a Python model comes back
    /// as itself (traceback included), whatever the loop made of it.
    pub fn finish<T>(&self, result: Result<T, CoreError>) -> PyResult<T> {
        if let LoopModel::Python(m) = self
            && let Some(err) = m.take_raised()
        {
            return Err(err);
        }
        result.map_err(to_py_err)
    }
}

/// The loop's model behind a Python model object.
///
/// # Errors
/// `TypeError` for an object that is none of a `BondModel`, a `ClothModel` or a model
/// written in Python (naming what it lacks).
pub fn model_of(obj: &Bound<'_, PyAny>) -> PyResult<LoopModel> {
    if let Ok(m) = obj.cast::<PyBondModel>() {
        return Ok(LoopModel::Rust(m.borrow().loop_model()));
    }
    if let Ok(m) = obj.cast::<PyClothModel>() {
        return Ok(LoopModel::Rust(m.get().model()));
    }
    Ok(LoopModel::Python(Arc::new(PythonModel::wrap(obj)?)))
}

/// The loop's model behind a Python model object, meeting `rec`: a `BondModel` whose hold
/// is `"auto"` holds each input as chosen on `rec` ([`PyBondModel::loop_model_for`]).
///
/// # Errors
/// As [`model_of`]; the model's errors when it cannot be built.
pub fn model_for(obj: &Bound<'_, PyAny>, rec: &modelgap::Recording) -> PyResult<LoopModel> {
    if let Ok(m) = obj.cast::<PyBondModel>() {
        return Ok(LoopModel::Rust(m.borrow().loop_model_for(rec)?.0));
    }
    model_of(obj)
}

/// Loads a model by file or built-in name: a ``BondModel`` for a bond-graph model file or
/// ``dc-motor``/``buck-motor``, a ``ClothModel`` for a scene file (a ``[cloth]`` table) or
/// ``corner``/``two-corners``/``drape``. ``set`` changes bond-graph parameters or input
/// defaults first; ``steady_start`` and ``hold`` (``"zoh"`` or ``"linear"``) are how a
/// bond-graph model meets a recording. Raises ``DataError`` naming the file, line and
/// element, or the option a model's kind does not take.
#[pyfunction]
#[pyo3(signature = (model, *, set = None, steady_start = false, hold = "auto"))]
fn load_model(
    py: Python<'_>,
    model: &str,
    set: Option<BTreeMap<String, f64>>,
    steady_start: bool,
    hold: &str,
) -> PyResult<Py<PyAny>> {
    let hold_kind = crate::bond::parse_model_hold(hold)?;
    let opts = modelgap::LoadOptions {
        set: set.unwrap_or_default().into_iter().collect(),
        steady_start,
        hold: hold_kind,
        free: Vec::new(),
    };
    let name = model.to_owned();
    let loaded = detached(py, move || {
        modelgap::load::load(&name, &opts).map_err(Box::new)
    })?
    .map_err(|e| to_py_err(*e))?;
    match loaded {
        modelgap::load::AnyModel::BondGraph(m) => {
            Ok(Py::new(py, PyBondModel::from_model(&m, hold_kind)?)?.into_any())
        }
        modelgap::load::AnyModel::ClothScene(m) => {
            Ok(Py::new(py, PyClothModel::from_model(*m)?)?.into_any())
        }
    }
}

/// Reads a recording for ``model``: a signals file (``.csv``, ``.mcap``, ``.parquet``) for a
/// bond-graph model or a model written in Python, a marker file (``t,id,x,y,z`` CSV or ``/markers``
/// MCAP, every id checked against the grid) for a ``ClothModel``.
#[pyfunction]
fn load_recording(
    py: Python<'_>,
    path: PathBuf,
    model: &Bound<'_, PyAny>,
) -> PyResult<PyRecording> {
    let loop_model = model_of(model)?;
    let m = loop_model.model();
    let rec = detached(py, move || {
        modelgap::load_recording(&path, m.as_ref()).map_err(Box::new)
    })?
    .map_err(|e| to_py_err(*e))?;
    Ok(PyRecording::from(rec))
}
