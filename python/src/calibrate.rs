//! `modelgap.fit`: calibration of a model's free parameters and initial states
//! ([`modelgap::calibrate`]), and its result class `Calibration`.

use std::collections::BTreeMap;

use modelgap::{CalibrationOptions, calibrate};
use pyo3::prelude::*;

use crate::convert::run_watched;
use crate::core_api::{PyEffect, PyRecording};
use crate::model::model_for;

/// Registers `fit` and `Calibration`.
pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<PyCalibration>()?;
    m.add_function(wrap_pyfunction!(py_fit, m)?)?;
    Ok(())
}

/// What ``fit`` found: each unknown fitted, the error before and after, and the effect
/// that builds the fitted values into the model (``model.with_effects([cal.effect])``).
#[pyclass(name = "Calibration", module = "modelgap", frozen)]
pub struct PyCalibration {
    inner: modelgap::Calibration,
}

#[pymethods]
impl PyCalibration {
    /// One dict per unknown, in fit order: ``name``, ``unit``, ``start``, ``value``,
    /// ``std_error`` (``None`` when the data do not determine it), ``at_bound``
    /// (``"lower"``, ``"upper"`` or ``None``), ``bounds`` (``(lower, upper)``) and ``prior``
    /// (``(mean, std)`` or ``None``).
    #[getter]
    fn values(&self, py: Python<'_>) -> PyResult<Vec<Py<PyAny>>> {
        self.inner
            .values
            .iter()
            .map(|v| {
                let d = pyo3::types::PyDict::new(py);
                d.set_item("name", &v.name)?;
                d.set_item("unit", &v.unit)?;
                d.set_item("start", v.start)?;
                d.set_item("value", v.value)?;
                d.set_item("std_error", v.std_error)?;
                d.set_item("at_bound", v.at_bound)?;
                d.set_item("bounds", v.bounds)?;
                d.set_item("prior", v.prior.map(|p| (p.mean, p.std)))?;
                Ok(d.into_any().unbind())
            })
            .collect()
    }

    /// Correlation matrix of the unknowns, rows and columns in the order of ``values``.
    #[getter]
    fn correlation(&self) -> Vec<Vec<f64>> {
        self.inner.correlation.clone()
    }

    /// RMS of measured − predicted per output with the model's own values.
    #[getter]
    fn rms_before(&self) -> BTreeMap<String, f64> {
        self.inner.rms_before.iter().cloned().collect()
    }

    /// RMS of measured − predicted per output with the fitted values.
    #[getter]
    fn rms_after(&self) -> BTreeMap<String, f64> {
        self.inner.rms_after.iter().cloned().collect()
    }

    /// Why the fit stopped: ``"converged"``, ``"max-iterations"``, ``"stalled"`` or
    /// ``"cancelled"``.
    #[getter]
    fn termination(&self) -> String {
        self.inner.termination.to_string()
    }

    /// The fitted values as an ``Effect`` (kind ``calibration``), for
    /// ``model.with_effects([cal.effect])``.
    #[getter]
    fn effect(&self) -> PyEffect {
        PyEffect {
            inner: self.inner.effect.clone(),
        }
    }

    /// The calibrated model as a model file's text (``None`` for a model that is not
    /// file-based).
    fn to_file_text(&self) -> Option<String> {
        self.inner.model.to_file_text()
    }

    fn __repr__(&self) -> String {
        let parts: Vec<String> = (self.inner.values.iter())
            .map(|v| format!("{}={:.6}", v.name, v.value))
            .collect();
        format!("Calibration({})", parts.join(", "))
    }
}

/// Calibrates the model's unknowns — parameters marked ``free`` (in its file, or with
/// ``BondModel.free``) and free initial states — jointly, by simulation error on ``rec``.
///
/// Each output's residual is divided by the standard deviation of its measurement, so
/// outputs in different units weigh alike. Standard errors are widened for the residual's
/// correlation in time; a value that ends on one of its bounds is marked (``at_bound``) and
/// has no standard error. The GIL is released during the fit; Ctrl-C stops it.
///
/// Args:
///     model: a ``BondModel`` (or any model whose ``free_parameters`` the loop knows).
///     rec: a ``Recording`` of the model's inputs and some of its outputs.
///
/// Returns:
///     A ``Calibration``.
///
/// Raises:
///     ModelError: the model has nothing free, the recording holds none of its outputs or
///         an output is constant, or the model cannot be simulated.
///     ConvergenceError: the model's start cannot be found (a steady start).
///     KeyboardInterrupt: on Ctrl-C.
#[pyfunction(name = "fit")]
fn py_fit(
    py: Python<'_>,
    model: &Bound<'_, PyAny>,
    rec: &Bound<'_, PyRecording>,
) -> PyResult<PyCalibration> {
    let loop_model = model_for(model, &rec.get().inner)?;
    let model = loop_model.model();
    let rec = &rec.get().inner;
    let result = run_watched(py, None, move |watch| {
        calibrate(
            model.as_ref(),
            rec,
            &CalibrationOptions {
                cancel: Some(watch.cancel),
                ..CalibrationOptions::default()
            },
        )
    })?;
    Ok(PyCalibration {
        inner: loop_model.finish(result)?,
    })
}
