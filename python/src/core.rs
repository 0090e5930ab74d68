//! Wrappers of modelgap-core: [`Recording`], compare and its [`Comparison`], explain and its
//! [`Explanation`], fitted [`Effect`]s, and the HTML report.

use std::collections::BTreeMap;
use std::path::PathBuf;

use modelgap::residual::FailureWindow;
use modelgap::story::{build_report, comparison_text, explanation_text, write_report_dir};
use modelgap::{
    CompareOptions, Comparison, Effect, ExplainOptions, Explanation, OutputComparison,
    RankedCandidate, Recording, compare, explain,
};
use numpy::{PyArray1, PyArray2};
use pyo3::prelude::*;
use pyo3::types::{PyTuple, PyType};

use crate::convert::{
    array1, columns_to_array2, detached, noise_map, recording_from_py, run_watched,
};
use crate::errors::{data_error, to_py_err};
use crate::model::model_for;

/// Registers the core classes and functions.
pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<PyRecording>()?;
    m.add_class::<PyOutputComparison>()?;
    m.add_class::<PyComparison>()?;
    m.add_class::<PyEffect>()?;
    m.add_class::<PyFittedParam>()?;
    m.add_class::<PyRankedCandidate>()?;
    m.add_class::<PyOutputSummary>()?;
    m.add_class::<PyExplanation>()?;
    m.add_function(wrap_pyfunction!(py_compare, m)?)?;
    m.add_function(wrap_pyfunction!(py_explain, m)?)?;
    m.add_function(wrap_pyfunction!(py_write_report, m)?)?;
    Ok(())
}

/// What pickling stores of a result: TOML text, which (unlike JSON) keeps infinite
/// standard errors and scores, and NaN, exactly as they are.
fn to_state<T: serde::Serialize>(value: &T) -> PyResult<String> {
    toml::to_string(value).map_err(|e| {
        crate::errors::ModelgapError::new_err(format!(
            "internal error (a bug in modelgap, please report it): cannot store the result: {e}"
        ))
    })
}

/// A result back from the text of [`to_state`] (`what` names it in errors).
fn from_state<T: serde::de::DeserializeOwned>(state: &str, what: &str) -> PyResult<T> {
    toml::from_str(state).map_err(|e| data_error(format!("not the stored state of {what}: {e}")))
}

/// Failure windows as `(start, end, peak)` tuples (s, s, signal unit).
/// A floor kind as Python and JSON name it (`quiet-band`).
fn floor_kind_name(kind: modelgap::compare::FloorKind) -> String {
    serde_json::to_value(kind)
        .ok()
        .and_then(|v| v.as_str().map(str::to_owned))
        .unwrap_or_default()
}

fn windows(w: &[FailureWindow]) -> Vec<(f64, f64, f64)> {
    w.iter().map(|w| (w.start, w.end, w.peak)).collect()
}

/// Sampled signals on one strictly increasing time axis (s), checked when built or read.
///
/// Build one with ``Recording(t, values, names)`` (``values`` shaped
/// ``(n_samples, n_signals)``), ``Recording.from_numpy`` (the same) or
/// ``Recording.load(path)`` (``.csv`` or ``.mcap``). Every array read from it is a fresh
/// float64 copy.
#[pyclass(name = "Recording", module = "modelgap", frozen)]
#[derive(Clone)]
pub struct PyRecording {
    pub(crate) inner: Recording,
}

impl From<Recording> for PyRecording {
    fn from(inner: Recording) -> Self {
        Self { inner }
    }
}

#[pymethods]
impl PyRecording {
    #[new]
    fn new(
        t: &Bound<'_, PyAny>,
        values: &Bound<'_, PyAny>,
        names: Vec<String>,
    ) -> PyResult<PyRecording> {
        Ok(recording_from_py(t, values, names)?.into())
    }

    /// A recording from numpy arrays: ``t`` (n_samples,), ``values`` (n_samples, n_signals)
    /// and one name per column. Raises ``DataError`` for a bad shape, non-finite values or
    /// time that does not strictly increase.
    #[staticmethod]
    fn from_numpy(
        t: &Bound<'_, PyAny>,
        values: &Bound<'_, PyAny>,
        names: Vec<String>,
    ) -> PyResult<PyRecording> {
        Self::new(t, values, names)
    }

    /// Reads a ``.csv`` file, the ``/signals`` topic of an ``.mcap`` file, or a ``.parquet``
    /// (``.pq``) file.
    ///
    /// CSV files as pandas, R or a spreadsheet export them read as they are: quoted cells, a
    /// row-index first column (left out), the time column ``t`` or ``time`` anywhere (with a
    /// unit such as ``time [ms]``, converted to seconds), ``;`` or tabs with decimal commas,
    /// ``name [unit]`` headers or a unit row. Parquet files as pandas (``to_parquet()``) and
    /// Polars (``write_parquet()``) write them read with the same column rules (the pandas
    /// index left out, timestamps in seconds from the first sample); nulls and text columns
    /// are refused with the column and row. ``time`` names another time column (CSV and
    /// Parquet), ``delimiter`` (one character) and ``decimal_comma`` declare what detection
    /// cannot tell in CSV; none of them applies to an ``.mcap`` file.
    #[staticmethod]
    #[pyo3(signature = (path, *, time = None, delimiter = None, decimal_comma = None))]
    fn load(
        py: Python<'_>,
        path: PathBuf,
        time: Option<String>,
        delimiter: Option<String>,
        decimal_comma: Option<bool>,
    ) -> PyResult<PyRecording> {
        let delimiter = match delimiter.as_deref() {
            None => None,
            Some(d) if d.len() == 1 && d.is_ascii() => Some(d.as_bytes()[0]),
            Some(d) => {
                return Err(data_error(format!(
                    "delimiter must be one character, such as \";\" or \"\\t\", found {d:?}"
                )));
            }
        };
        let options = modelgap::io::csv::CsvOptions {
            time,
            delimiter,
            decimal_comma,
        };
        let read = detached(py, move || {
            modelgap::io::read_recording_path_with(&path, &options)
        })?;
        Ok(read.map_err(to_py_err)?.0.into())
    }

    /// Writes the recording as ``.csv`` or ``.mcap`` (chosen by the extension); Parquet is
    /// read, not written.
    fn save(&self, py: Python<'_>, path: PathBuf) -> PyResult<()> {
        let rec = &self.inner;
        detached(py, move || modelgap::io::write_recording_path(&path, rec))?.map_err(to_py_err)
    }

    /// ``(t, values, names)``: times (n_samples,), values (n_samples, n_signals), names.
    fn to_numpy<'py>(
        &self,
        py: Python<'py>,
    ) -> (
        Bound<'py, PyArray1<f64>>,
        Bound<'py, PyArray2<f64>>,
        Vec<String>,
    ) {
        let columns: Vec<&[f64]> = self
            .inner
            .signals()
            .iter()
            .map(|s| s.values.as_slice())
            .collect();
        (
            array1(py, self.inner.t()),
            columns_to_array2(py, self.inner.len(), &columns),
            self.names(),
        )
    }

    /// The time axis (s), a fresh float64 array.
    #[getter]
    fn t<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        array1(py, self.inner.t())
    }

    /// The signal names, in order.
    #[getter]
    fn names(&self) -> Vec<String> {
        self.inner.names().into_iter().map(str::to_owned).collect()
    }

    /// The time from the first to the last sample (s).
    #[getter]
    fn duration(&self) -> f64 {
        self.inner.duration()
    }

    /// The values of one signal, a fresh float64 array. Raises ``DataError`` naming the
    /// available signals when there is no such signal.
    fn signal<'py>(&self, py: Python<'py>, name: &str) -> PyResult<Bound<'py, PyArray1<f64>>> {
        let v = self.inner.values(name).map_err(to_py_err)?;
        Ok(array1(py, v))
    }

    fn __len__(&self) -> usize {
        self.inner.len()
    }

    fn __contains__(&self, name: &str) -> bool {
        self.inner.signal(name).is_some()
    }

    fn __eq__(&self, other: &Bound<'_, PyAny>) -> bool {
        other
            .cast::<PyRecording>()
            .is_ok_and(|o| o.get().inner == self.inner)
    }

    fn __repr__(&self) -> String {
        format!(
            "<Recording n_samples={} duration={} s signals=[{}]>",
            self.inner.len(),
            self.inner.duration(),
            self.inner.names().join(", ")
        )
    }

    fn __reduce__<'py>(
        slf: &Bound<'py, Self>,
    ) -> PyResult<(Bound<'py, PyType>, Bound<'py, PyTuple>)> {
        let py = slf.py();
        let (t, values, names) = slf.get().to_numpy(py);
        let args = PyTuple::new(
            py,
            [
                t.into_any(),
                values.into_any(),
                names.into_pyobject(py)?.into_any(),
            ],
        )?;
        Ok((slf.get_type(), args))
    }
}

/// One measured output held against the model's prediction.
#[pyclass(name = "OutputComparison", module = "modelgap", frozen)]
pub struct PyOutputComparison {
    inner: OutputComparison,
}

#[pymethods]
impl PyOutputComparison {
    /// Output name.
    #[getter]
    fn name(&self) -> &str {
        &self.inner.name
    }
    /// Its unit.
    #[getter]
    fn unit(&self) -> &str {
        &self.inner.unit
    }
    /// RMS of the residual, in the output's unit.
    #[getter]
    fn rms(&self) -> f64 {
        self.inner.stats.rms
    }
    /// RMS over the RMS of the measurement.
    #[getter]
    fn nrms(&self) -> f64 {
        self.inner.stats.nrms
    }
    /// Largest absolute residual.
    #[getter]
    fn max_abs(&self) -> f64 {
        self.inner.stats.max_abs
    }
    /// Mean residual (bias).
    #[getter]
    fn mean(&self) -> f64 {
        self.inner.stats.mean
    }
    /// The noise floor (σ): what a perfect model would leave.
    #[getter]
    fn noise_floor(&self) -> f64 {
        self.inner.noise_floor
    }
    /// True when the noise floor was given, false when estimated.
    #[getter]
    fn noise_given(&self) -> bool {
        self.inner.noise_given
    }
    /// How the noise floor was found and how far to trust it: ``"given"``, ``"white"``,
    /// ``"quantised"``, ``"coloured"`` (likely too low), ``"signal-content"`` (likely too
    /// high) or ``"unchecked"``.
    #[getter]
    fn noise_method(&self) -> String {
        floor_kind_name(self.inner.noise_method)
    }
    /// RMS over the noise floor: about 1 for a right model.
    #[getter]
    fn rms_over_floor(&self) -> f64 {
        self.inner.rms_over_floor()
    }
    /// Half-width of the band the residual must leave to count as failure.
    #[getter]
    fn band(&self) -> f64 {
        self.inner.band
    }
    /// Where the residual leaves its band: ``(start, end, peak)`` tuples.
    #[getter]
    fn windows(&self) -> Vec<(f64, f64, f64)> {
        windows(&self.inner.windows)
    }
    /// Effective number of independent samples of the residual.
    #[getter]
    fn effective_samples(&self) -> f64 {
        self.inner.effective_samples
    }
    /// The measurement's quantisation step when it lies on a lattice (its rounding error is
    /// part of the floor), else ``None``.
    #[getter]
    fn quantum(&self) -> Option<f64> {
        self.inner.quantum
    }
    /// Why this output cannot be judged (a dead sensor that reads a constant), else ``None``.
    #[getter]
    fn finding(&self) -> Option<String> {
        self.inner.finding.clone()
    }
    /// measured − predicted, a fresh float64 array.
    #[getter]
    fn residual<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        array1(py, &self.inner.residual)
    }
    /// The model's prediction, a fresh float64 array.
    #[getter]
    fn predicted<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        array1(py, &self.inner.predicted)
    }
    /// The measurement, a fresh float64 array.
    #[getter]
    fn measured<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        array1(py, &self.inner.measured)
    }

    fn __repr__(&self) -> String {
        format!(
            "<OutputComparison {} rms={:.4e} {} noise_floor={:.4e} windows={}>",
            self.inner.name,
            self.inner.stats.rms,
            self.inner.unit,
            self.inner.noise_floor,
            self.inner.windows.len()
        )
    }
}

/// The result of ``compare``: per output, residual statistics, noise floor and the windows
/// where the model fails.
#[pyclass(name = "Comparison", module = "modelgap", frozen)]
pub struct PyComparison {
    pub(crate) inner: Comparison,
}

#[pymethods]
impl PyComparison {
    /// Model name.
    #[getter]
    fn model(&self) -> &str {
        &self.inner.model
    }
    /// Sample times (s), a fresh float64 array.
    #[getter]
    fn t<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        array1(py, &self.inner.t)
    }
    /// One ``OutputComparison`` per output the model predicts and the recording measures.
    #[getter]
    fn outputs(&self) -> Vec<PyOutputComparison> {
        self.inner
            .outputs
            .iter()
            .map(|o| PyOutputComparison { inner: o.clone() })
            .collect()
    }
    /// What keeps the recording, or an output of it, from being judged: too few samples, a
    /// dead sensor, a time base that hides the model's time constants.
    #[getter]
    fn warnings(&self) -> Vec<String> {
        self.inner.warnings.clone()
    }
    /// The comparison of one output. Raises ``DataError`` for an output not compared.
    fn output(&self, name: &str) -> PyResult<PyOutputComparison> {
        self.inner
            .output(name)
            .map(|o| PyOutputComparison { inner: o.clone() })
            .ok_or_else(|| {
                data_error(format!(
                    "no output `{name}` in the comparison; compared: {}",
                    self.inner
                        .outputs
                        .iter()
                        .map(|o| o.name.as_str())
                        .collect::<Vec<_>>()
                        .join(", ")
                ))
            })
    }
    /// Where the model fails, output by output, as text.
    fn text(&self) -> String {
        comparison_text(&self.inner)
    }

    /// Restores a pickled comparison (see ``__reduce__``).
    #[staticmethod]
    fn _from_state(state: &str) -> PyResult<PyComparison> {
        Ok(PyComparison {
            inner: from_state(state, "a comparison")?,
        })
    }

    fn __reduce__<'py>(slf: &Bound<'py, Self>) -> PyResult<(Bound<'py, PyAny>, (String,))> {
        let restore = slf.get_type().getattr("_from_state")?;
        Ok((restore, (to_state(&slf.get().inner)?,)))
    }

    fn __eq__(&self, other: &Bound<'_, PyAny>) -> bool {
        other
            .cast::<PyComparison>()
            .is_ok_and(|o| o.get().inner == self.inner)
    }

    fn __repr__(&self) -> String {
        let parts: Vec<String> = self
            .inner
            .outputs
            .iter()
            .map(|o| {
                format!(
                    "{}: rms={:.4e} windows={}",
                    o.name,
                    o.stats.rms,
                    o.windows.len()
                )
            })
            .collect();
        format!("<Comparison {} {}>", self.inner.model, parts.join(", "))
    }
}

/// A fitted effect: a candidate with parameter values, ready for ``model.with_effects``.
#[pyclass(name = "Effect", module = "modelgap", frozen)]
#[derive(Clone)]
pub struct PyEffect {
    pub(crate) inner: Effect,
}

#[pymethods]
impl PyEffect {
    /// The candidate's stable id (``coulomb@1m``, ``deviation:R``).
    #[getter]
    fn id(&self) -> &str {
        &self.inner.candidate.id
    }
    /// Its plain name.
    #[getter]
    fn name(&self) -> &str {
        &self.inner.candidate.name
    }
    /// ``parameter-deviation``, ``abrupt-change`` or ``missing-element``.
    #[getter]
    fn kind(&self) -> String {
        self.inner.candidate.kind.to_string()
    }
    /// Where it acts.
    #[getter]
    fn acts_on(&self) -> &str {
        &self.inner.candidate.acts_on
    }
    /// Parameter values by name.
    #[getter]
    fn values(&self) -> BTreeMap<String, f64> {
        self.inner
            .candidate
            .params
            .iter()
            .zip(&self.inner.values)
            .map(|(p, v)| (p.name.clone(), *v))
            .collect()
    }
    /// The effect as JSON (what pickling stores).
    fn to_json(&self) -> PyResult<String> {
        serde_json::to_string(&self.inner).map_err(|e| data_error(e.to_string()))
    }
    /// An effect from the JSON of ``to_json``.
    #[staticmethod]
    fn from_json(text: &str) -> PyResult<PyEffect> {
        let inner: Effect = serde_json::from_str(text)
            .map_err(|e| data_error(format!("not the JSON of an effect: {e}")))?;
        Ok(PyEffect { inner })
    }
    fn __str__(&self) -> String {
        self.inner.to_string()
    }
    fn __repr__(&self) -> String {
        format!("<Effect {}>", self.inner)
    }
    fn __eq__(&self, other: &Bound<'_, PyAny>) -> bool {
        other
            .cast::<PyEffect>()
            .is_ok_and(|o| o.get().inner == self.inner)
    }
    fn __reduce__<'py>(slf: &Bound<'py, Self>) -> PyResult<(Bound<'py, PyAny>, (String,))> {
        let restore = slf.get_type().getattr("from_json")?;
        Ok((restore, (slf.get().to_json()?,)))
    }
}

/// One fitted parameter of a candidate.
#[pyclass(name = "FittedParam", module = "modelgap", frozen, get_all)]
pub struct PyFittedParam {
    /// Name.
    name: String,
    /// Unit.
    unit: String,
    /// Fitted value.
    value: f64,
    /// Standard error (infinite when the parameter sits at a bound).
    std_error: f64,
    /// ``"lower"`` or ``"upper"`` when the fit ended on that bound, else ``None``.
    at_bound: Option<String>,
}

#[pymethods]
impl PyFittedParam {
    fn __repr__(&self) -> String {
        match &self.at_bound {
            Some(side) => format!(
                "<FittedParam {}={:.4e} {} (at its {side} bound)>",
                self.name, self.value, self.unit
            ),
            None => format!(
                "<FittedParam {}={:.4e} ± {:.2e} {}>",
                self.name, self.value, self.std_error, self.unit
            ),
        }
    }
}

/// A candidate effect after its fit, with its evidence.
#[pyclass(name = "RankedCandidate", module = "modelgap", frozen)]
pub struct PyRankedCandidate {
    inner: RankedCandidate,
}

#[pymethods]
impl PyRankedCandidate {
    /// Stable id.
    #[getter]
    fn id(&self) -> &str {
        &self.inner.candidate.id
    }
    /// Plain name.
    #[getter]
    fn name(&self) -> &str {
        &self.inner.candidate.name
    }
    /// Kind of change.
    #[getter]
    fn kind(&self) -> String {
        self.inner.candidate.kind.to_string()
    }
    /// Where it acts.
    #[getter]
    fn acts_on(&self) -> &str {
        &self.inner.candidate.acts_on
    }
    /// Fitted parameters.
    #[getter]
    fn params(&self) -> Vec<PyFittedParam> {
        self.inner
            .params
            .iter()
            .map(|p| PyFittedParam {
                name: p.name.clone(),
                unit: p.unit.clone(),
                value: p.value,
                std_error: p.std_error,
                at_bound: p.at_bound.clone(),
            })
            .collect()
    }
    /// RMS per output after the effect, in the order of ``Explanation.outputs``.
    #[getter]
    fn rms_after(&self) -> Vec<f64> {
        self.inner.rms_after.clone()
    }
    /// The evidence (a BIC difference); higher is better.
    #[getter]
    fn score(&self) -> f64 {
        self.inner.score
    }
    /// Weighted cost after the fit.
    #[getter]
    fn cost(&self) -> f64 {
        self.inner.cost
    }
    /// How the fit ended.
    #[getter]
    fn termination(&self) -> String {
        self.inner.termination.to_string()
    }
    /// Whether the qualitative diagnosis agrees (None when it has no opinion).
    #[getter]
    fn qualitative(&self) -> Option<bool> {
        self.inner.qualitative
    }
    /// Why the qualitative diagnosis agrees or disagrees, in plain words ("" when it gives
    /// no reason).
    #[getter]
    fn qualitative_reason(&self) -> &str {
        &self.inner.qualitative_reason
    }
    /// Plain names of other physics this recording cannot tell from this effect.
    #[getter]
    fn indistinct(&self) -> Vec<String> {
        self.inner.indistinct.clone()
    }
    /// Why the fit failed, if it did.
    #[getter]
    fn error(&self) -> Option<String> {
        self.inner.error.clone()
    }
    /// Ids of candidates that explain the recording exactly as well.
    #[getter]
    fn equivalent(&self) -> Vec<String> {
        self.inner.equivalent.clone()
    }
    /// The fitted effect.
    #[getter]
    fn effect(&self) -> PyEffect {
        PyEffect {
            inner: self.inner.effect(),
        }
    }
    fn __repr__(&self) -> String {
        format!(
            "<RankedCandidate {} score={:.1} params=[{}]>",
            self.inner.candidate.id,
            self.inner.score,
            self.inner
                .params
                .iter()
                .map(|p| format!("{}={:.4e}", p.name, p.value))
                .collect::<Vec<_>>()
                .join(", ")
        )
    }
}

/// One output before and after the chosen effects.
#[pyclass(name = "OutputSummary", module = "modelgap", frozen)]
pub struct PyOutputSummary {
    inner: modelgap::explain::OutputSummary,
}

#[pymethods]
impl PyOutputSummary {
    /// Output name.
    #[getter]
    fn name(&self) -> &str {
        &self.inner.name
    }
    /// Unit.
    #[getter]
    fn unit(&self) -> &str {
        &self.inner.unit
    }
    /// Noise floor (σ).
    #[getter]
    fn noise_floor(&self) -> f64 {
        self.inner.noise_floor
    }
    /// How the noise floor was found: as ``Output.noise_method``, or ``"smoother"`` (the white
    /// noise the model leaves with a free effort at the place that explains most).
    #[getter]
    fn noise_method(&self) -> String {
        floor_kind_name(self.inner.noise_method)
    }
    /// RMS of the model as given.
    #[getter]
    fn rms_before(&self) -> f64 {
        self.inner.rms_before
    }
    /// RMS after the chosen effects.
    #[getter]
    fn rms_after(&self) -> f64 {
        self.inner.rms_after
    }
    /// Where the residual after the effects still leaves a 4σ band: ``(start, end, peak)``.
    #[getter]
    fn remaining_windows(&self) -> Vec<(f64, f64, f64)> {
        windows(&self.inner.remaining_windows)
    }
    /// Whether the residual after the effects is what noise leaves: at its floor (or taken for
    /// coloured noise), no failure window, uncorrelated with the inputs, unbiased; ``None``
    /// when the recording could not be judged.
    #[getter]
    fn at_floor(&self) -> Option<bool> {
        self.inner.judgement.as_ref().map(|j| j.at_floor)
    }
    /// σ of the noise the residual was taken for (the floor, or the level of coloured noise),
    /// in the output's unit; ``None`` when not judged.
    #[getter]
    fn noise_sigma(&self) -> Option<f64> {
        self.inner.judgement.as_ref().map(|j| j.noise_sigma)
    }
    /// The AR(1) coefficient of the noise model the scores whiten this output's residual with;
    /// at its cap of 0.999 the residual is mostly model error. ``None`` when nothing was scored.
    #[getter]
    fn noise_rho(&self) -> Option<f64> {
        self.inner.noise_rho
    }
    /// Why the residual is not what noise leaves (empty when it is, or when not judged).
    #[getter]
    fn reasons(&self) -> Vec<String> {
        self.inner
            .judgement
            .as_ref()
            .map(|j| j.reasons.clone())
            .unwrap_or_default()
    }
    fn __repr__(&self) -> String {
        format!(
            "<OutputSummary {} rms {:.4e} -> {:.4e} {} (noise floor {:.4e})>",
            self.inner.name,
            self.inner.rms_before,
            self.inner.rms_after,
            self.inner.unit,
            self.inner.noise_floor
        )
    }
}

/// The result of ``explain``: the verdict, the ranked candidates and the chosen effects.
#[pyclass(name = "Explanation", module = "modelgap", frozen)]
pub struct PyExplanation {
    pub(crate) inner: Explanation,
}

#[pymethods]
impl PyExplanation {
    /// Model name.
    #[getter]
    fn model(&self) -> &str {
        &self.inner.model
    }
    /// ``nothing-missing``, ``effect-found``, ``two-effects``, ``partial``, ``unexplained``,
    /// ``cannot-judge`` or ``interrupted``.
    #[getter]
    fn verdict(&self) -> String {
        self.inner.verdict.to_string()
    }
    /// Why the verdict is what it is when it is not a complete answer: what keeps the
    /// recording from being judged, which output's residual is not noise and how, or how far
    /// an interrupted run got.
    #[getter]
    fn reasons(&self) -> Vec<String> {
        self.inner.reasons.clone()
    }
    /// Per output: noise floor, RMS before and after.
    #[getter]
    fn outputs(&self) -> Vec<PyOutputSummary> {
        self.inner
            .outputs
            .iter()
            .map(|o| PyOutputSummary { inner: o.clone() })
            .collect()
    }
    /// Every candidate, best first.
    #[getter]
    fn ranked(&self) -> Vec<PyRankedCandidate> {
        self.inner
            .ranked
            .iter()
            .map(|r| PyRankedCandidate { inner: r.clone() })
            .collect()
    }
    /// The chosen candidates (none, one or two).
    #[getter]
    fn chosen(&self) -> Vec<PyRankedCandidate> {
        self.inner
            .chosen
            .iter()
            .map(|r| PyRankedCandidate { inner: r.clone() })
            .collect()
    }
    /// The chosen effects, ready for ``model.with_effects``.
    #[getter]
    fn effects(&self) -> Vec<PyEffect> {
        self.inner
            .effects()
            .into_iter()
            .map(|inner| PyEffect { inner })
            .collect()
    }
    /// Score of the best minus that of the runner-up.
    #[getter]
    fn margin(&self) -> f64 {
        self.inner.margin
    }
    /// Effective sample size used for the scores.
    #[getter]
    fn effective_samples(&self) -> f64 {
        self.inner.effective_samples
    }
    /// Non-fatal findings.
    #[getter]
    fn warnings(&self) -> Vec<String> {
        self.inner.warnings.clone()
    }
    /// The places discovery looked at, most explaining first, as dicts.
    #[getter]
    fn places<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let v: Vec<serde_json::Value> = self
            .inner
            .places
            .iter()
            .map(modelgap::json::place_json)
            .collect();
        let text = serde_json::to_string(&v).map_err(|e| data_error(e.to_string()))?;
        py.import("json")?.call_method1("loads", (text,))
    }

    /// The missing effort (or flow) estimated at a place, as arrays ``(t, value, band)``.
    #[allow(clippy::type_complexity)]
    fn missing<'py>(
        &self,
        py: Python<'py>,
        location: &str,
    ) -> PyResult<(
        Bound<'py, PyArray1<f64>>,
        Bound<'py, PyArray1<f64>>,
        Bound<'py, PyArray1<f64>>,
    )> {
        let m = (self.inner.missing.iter())
            .find(|m| m.location == location)
            .ok_or_else(|| {
                let known: Vec<&str> = self
                    .inner
                    .missing
                    .iter()
                    .map(|m| m.location.as_str())
                    .collect();
                data_error(format!(
                    "no missing effort was estimated at '{location}' (places: {})",
                    if known.is_empty() {
                        "none".to_string()
                    } else {
                        known.join(", ")
                    }
                ))
            })?;
        Ok((
            PyArray1::from_slice(py, &m.t),
            PyArray1::from_slice(py, &m.value),
            PyArray1::from_slice(py, &m.band),
        ))
    }

    /// How long each stage took: ``(stage, wall_s, cpu_s)`` in the order run (``cpu_s`` is the
    /// whole process's CPU time over the stage, every thread; ``None`` where not measured).
    #[getter]
    fn timings(&self) -> Vec<(String, f64, Option<f64>)> {
        (self.inner.timings.iter())
            .map(|t| (t.stage.clone(), t.wall_s, t.cpu_s))
            .collect()
    }

    /// The ranking (the ``top`` best) and the verdict as text.
    #[pyo3(signature = (top = 5))]
    fn text(&self, top: usize) -> String {
        explanation_text(&self.inner, top)
    }

    /// Restores a pickled explanation (see ``__reduce__``).
    #[staticmethod]
    fn _from_state(state: &str) -> PyResult<PyExplanation> {
        Ok(PyExplanation {
            inner: from_state(state, "an explanation")?,
        })
    }

    fn __reduce__<'py>(slf: &Bound<'py, Self>) -> PyResult<(Bound<'py, PyAny>, (String,))> {
        let restore = slf.get_type().getattr("_from_state")?;
        Ok((restore, (to_state(&slf.get().inner)?,)))
    }

    /// Equal when everything a pickle keeps is equal (the missing-effort series are not kept),
    /// the stage timings aside: two runs that say the same thing are the same explanation.
    fn __eq__(&self, other: &Bound<'_, PyAny>) -> bool {
        let said = |e: &modelgap::Explanation| {
            let mut e = e.clone();
            e.timings.clear();
            to_state(&e)
        };
        other.cast::<PyExplanation>().is_ok_and(|o| {
            matches!(
                (said(&o.get().inner), said(&self.inner)),
                (Ok(a), Ok(b)) if a == b
            )
        })
    }
    fn __repr__(&self) -> String {
        format!(
            "<Explanation {} verdict={} chosen=[{}] candidates={}>",
            self.inner.model,
            self.inner.verdict,
            self.inner
                .chosen
                .iter()
                .map(|c| c.candidate.id.as_str())
                .collect::<Vec<_>>()
                .join(", "),
            self.inner.ranked.len()
        )
    }
}

/// Simulates the model on the recording's inputs and holds it against its outputs.
///
/// ``model`` is a ``BondModel``, a ``ClothModel`` or a model written in Python
/// (``modelgap.ModelLike``); ``rec`` a ``Recording`` of its inputs and measured outputs.
/// Every output both share is compared: residual statistics, the noise floor and the
/// windows where the residual leaves its band. Returns a ``Comparison``. The GIL is
/// released while the model runs.
///
/// - ``noise``: known noise floors, output name to σ in the output's unit (positive and
///   finite); the others are estimated from the measurement's high-frequency part, and
///   names that are not compared outputs are ignored.
/// - ``band_sigmas``: the half-width of the failure band in noise floors (positive).
/// - ``band_fraction``: instead, the paper's band: this fraction of the magnitude of the
///   prediction's steady state (the mean of its last 10 %).
/// - ``min_window``: the shortest failure window (s); excursions closer than it merge and
///   shorter ones are dropped. Default five mean sample periods.
/// - ``predictability``: widens the failure band by the model's own predictability band
///   where it has one (a cloth model near a snap), so only failures beyond it count.
///
/// Raises ``DataError`` for a bad option or a recording that measures none of the model's
/// outputs, ``ModelError`` or ``ConvergenceError`` when the model cannot be simulated,
/// ``TypeError`` for an object that is not a model; an exception other than ``ModelError``
/// raised by a Python model's ``predict`` comes back as itself.
#[pyfunction(name = "compare")]
#[pyo3(signature = (model, rec, *, noise = None, band_sigmas = 4.0, band_fraction = None, min_window = None, predictability = true))]
#[allow(clippy::too_many_arguments)] // keyword-only options of the Python API
fn py_compare(
    py: Python<'_>,
    model: &Bound<'_, PyAny>,
    rec: &Bound<'_, PyRecording>,
    noise: Option<BTreeMap<String, f64>>,
    band_sigmas: f64,
    band_fraction: Option<f64>,
    min_window: Option<f64>,
    predictability: bool,
) -> PyResult<PyComparison> {
    let loop_model = model_for(model, &rec.get().inner)?;
    let model = loop_model.model();
    let opts = CompareOptions {
        noise: noise_map(noise)?,
        band_sigmas,
        band_fraction,
        min_window,
        predictability,
    };
    let rec = &rec.get().inner;
    let result = detached(py, move || compare(model.as_ref(), rec, &opts))?;
    Ok(PyComparison {
        inner: loop_model.finish(result)?,
    })
}

/// Fits every candidate effect the model offers to the recording and says which is missing.
///
/// ``model`` is a ``BondModel``, a ``ClothModel`` or a model written in Python
/// (``modelgap.ModelLike``); ``rec`` a ``Recording`` of its inputs and measured outputs.
/// Every candidate is fitted (in parallel, with the GIL released) to the residual weighted
/// by the noise floors and scored by the error it removes, penalised by its number of
/// parameters (a BIC difference). The best is chosen when its score beats
/// ``significance``; when it leaves the residual above the noise floor (RMS above 1.3 × the
/// floor, or not noise-like), a second effect is fitted jointly on top of it. Returns an
/// ``Explanation``; a candidate whose fit fails is ranked last with its error, not raised.
///
/// - ``noise``: known noise floors, output name to σ in the output's unit (positive and
///   finite); they weight the fits and are what the verdict judges against. The others are
///   estimated; names that are not outputs of the model are ignored.
/// - ``significance``: the score the best candidate must beat to be chosen, the gain a
///   second effect must add, and the margin by which a candidate with more parameters must
///   beat a simpler one to rank above it. Default 10 ("very strong evidence").
/// - ``max_effects``: with 2 (the default) a second effect may be chosen, with 1 at most
///   one; other values raise ``DataError``.
/// - ``only``: the candidate ids to fit (for the second effect too); ``None`` or an empty
///   list fits all; an id not on the model's menu raises ``DataError``.
/// - ``progress``: ``progress(done, total)`` with the candidate fits finished and the
///   number to fit, called on the calling thread when the counts changed (polled every
///   50 ms, so some counts are skipped); second-effect fits are not counted. An exception
///   it raises stops the fits and is raised once they have stopped.
///
/// Raises ``DataError`` for a bad option or a recording that measures none of the model's
/// outputs, ``ModelError`` or ``ConvergenceError`` when the model as given cannot be
/// simulated, ``KeyboardInterrupt`` on Ctrl-C (the fits stop; no explanation is returned),
/// ``TypeError`` for an object that is not a model; an exception other than ``ModelError``
/// raised by a Python model's ``predict`` comes back as itself.
#[pyfunction(name = "explain")]
#[pyo3(signature = (model, rec, *, noise = None, significance = 10.0, max_effects = 2, only = None, progress = None))]
#[allow(clippy::too_many_arguments)] // keyword-only options of the Python API
fn py_explain(
    py: Python<'_>,
    model: &Bound<'_, PyAny>,
    rec: &Bound<'_, PyRecording>,
    noise: Option<BTreeMap<String, f64>>,
    significance: f64,
    max_effects: usize,
    only: Option<Vec<String>>,
    progress: Option<&Bound<'_, PyAny>>,
) -> PyResult<PyExplanation> {
    let loop_model = model_for(model, &rec.get().inner)?;
    let model = loop_model.model();
    let noise = noise_map(noise)?;
    let rec = &rec.get().inner;
    let python_model = match &loop_model {
        crate::model::LoopModel::Python(m) => Some(m.clone()),
        crate::model::LoopModel::Rust(_) => None,
    };
    let result = run_watched(py, progress, move |watch| {
        if let Some(m) = &python_model {
            m.stop_with(watch.cancel.clone());
        }
        let opts = ExplainOptions {
            noise,
            significance,
            max_effects,
            only: only.unwrap_or_default(),
            progress: Some(watch.progress),
            cancel: Some(watch.cancel),
            ..ExplainOptions::default()
        };
        explain(model.as_ref(), rec, &opts)
    })?;
    Ok(PyExplanation {
        inner: loop_model.finish(result)?,
    })
}

/// Writes ``report.html`` and ``comparison.mcap`` into ``dir``; returns the page's path.
///
/// ``dir`` is created when missing. ``before`` is the comparison of the model as given,
/// ``explanation`` (optional) the explanation of the same recording and ``after``
/// (optional) the comparison of the fixed model. ``comparison.mcap`` holds the measured and
/// predicted signals for Foxglove, time shifted to start at 0. Raises ``DataError`` when a
/// file cannot be written. The GIL is released.
#[pyfunction(name = "write_report")]
#[pyo3(signature = (dir, before, explanation = None, after = None))]
fn py_write_report(
    py: Python<'_>,
    dir: PathBuf,
    before: &Bound<'_, PyComparison>,
    explanation: Option<&Bound<'_, PyExplanation>>,
    after: Option<&Bound<'_, PyComparison>>,
) -> PyResult<PathBuf> {
    let before = &before.get().inner;
    let explanation = explanation.map(|e| &e.get().inner);
    let after = after.map(|a| &a.get().inner);
    detached(py, move || {
        let report = build_report(before, explanation, after);
        write_report_dir(&dir, &report, before, after).map(|()| dir.join("report.html"))
    })?
    .map_err(to_py_err)
}
