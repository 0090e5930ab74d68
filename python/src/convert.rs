//! Conversions between Python values and modelgap's: numpy arrays in and out, option
//! strings, noise-floor dicts, and the thread that runs long work while the caller's
//! thread watches for Ctrl-C and reports progress.

use std::collections::BTreeMap;
use std::sync::Arc;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::mpsc;
use std::time::Duration;

use modelgap::fit::Cancel;
use modelgap::math::Vector3;
use modelgap::{Recording, Signal};
use numpy::ndarray::Array2;
use numpy::{IntoPyArray as _, PyArray1, PyArray2, PyArrayDyn, PyArrayMethods as _};
use pyo3::prelude::*;

use crate::errors::{ModelgapError, data_error, to_py_err};

/// How often the caller's thread looks for Ctrl-C and progress while work runs.
const POLL_INTERVAL: Duration = Duration::from_millis(50);

/// Any array-like as a float64 numpy array (no copy when it already is one; strides kept).
fn as_float_array<'py>(obj: &Bound<'py, PyAny>) -> PyResult<Bound<'py, PyArrayDyn<f64>>> {
    let np = obj.py().import("numpy")?;
    let arr = np.call_method1("asarray", (obj, np.getattr("float64")?))?;
    Ok(arr.cast_into::<PyArrayDyn<f64>>()?)
}

/// A 1-D array-like of floats, copied into a `Vec` (`what` names it in errors).
pub fn vec_from_py(obj: &Bound<'_, PyAny>, what: &str) -> PyResult<Vec<f64>> {
    let arr = as_float_array(obj)?;
    let ro = arr.readonly();
    let view = ro.as_array();
    if view.ndim() != 1 {
        return Err(data_error(format!(
            "{what} must be one-dimensional (n_samples,), found shape {:?}",
            view.shape()
        )));
    }
    Ok(view.iter().copied().collect())
}

/// A `(n, 3)` array-like of floats (any strides, any real dtype) as 3-vectors; `what`
/// names it in errors ("positions must be (n, 3)").
pub fn points_from_py(obj: &Bound<'_, PyAny>, what: &str) -> PyResult<Vec<Vector3>> {
    let arr = as_float_array(obj)?;
    let ro = arr.readonly();
    let view = ro.as_array();
    match view.shape() {
        [_, 3] => Ok(view
            .outer_iter()
            .map(|row| Vector3::new(row[0], row[1], row[2]))
            .collect()),
        shape => Err(data_error(format!(
            "{what} must be (n, 3), found shape {shape:?}"
        ))),
    }
}

/// A 3-vector from any array-like of three finite floats (`what` names it in errors).
pub fn vec3_from_py(obj: &Bound<'_, PyAny>, what: &str) -> PyResult<Vector3> {
    let v = vec_from_py(obj, what).map_err(|_| shape_error3(obj, what))?;
    match v.as_slice() {
        [x, y, z] if v.iter().all(|c| c.is_finite()) => Ok(Vector3::new(*x, *y, *z)),
        [_, _, _] => Err(data_error(format!(
            "{what} must be three finite numbers, found {v:?}"
        ))),
        _ => Err(shape_error3(obj, what)),
    }
}

fn shape_error3(obj: &Bound<'_, PyAny>, what: &str) -> PyErr {
    let found = obj
        .repr()
        .map_or_else(|_| "an object".to_owned(), |r| r.to_string());
    data_error(format!(
        "{what} must be three numbers (x, y, z), found {found}"
    ))
}

/// An array-like of non-negative integers below 2³² (any strides, any integer dtype), with
/// its shape; `what` names it in errors. Floats are refused, even whole ones.
pub fn indices_from_py(obj: &Bound<'_, PyAny>, what: &str) -> PyResult<(Vec<usize>, Vec<u32>)> {
    let np = obj.py().import("numpy")?;
    let arr = np.call_method1("asarray", (obj,))?;
    let kind: String = arr.getattr("dtype")?.getattr("kind")?.extract()?;
    let size: usize = arr.getattr("size")?.extract()?;
    if !(kind == "i" || kind == "u" || size == 0) {
        return Err(data_error(format!(
            "{what} must hold integers (vertex indices), found dtype {}",
            arr.getattr("dtype")?.str()?
        )));
    }
    let arr = arr.call_method1("astype", (np.getattr("int64")?,))?;
    let arr = arr.cast_into::<PyArrayDyn<i64>>()?;
    let ro = arr.readonly();
    let view = ro.as_array();
    let mut out = Vec::with_capacity(view.len());
    for &i in view.iter() {
        match u32::try_from(i) {
            Ok(v) => out.push(v),
            Err(_) => {
                return Err(data_error(format!(
                    "{what} must be non-negative vertex indices below 2^32, found {i}"
                )));
            }
        }
    }
    Ok((view.shape().to_vec(), out))
}

/// An `(m, k)` integer array-like as rows of `K` indices (`what` names it in errors).
pub fn index_rows_from_py<const K: usize>(
    obj: &Bound<'_, PyAny>,
    what: &str,
) -> PyResult<Vec<[u32; K]>> {
    let (shape, flat) = indices_from_py(obj, what)?;
    let empty = flat.is_empty() && shape.len() == 1;
    if !(empty || (shape.len() == 2 && shape[1] == K)) {
        return Err(data_error(format!(
            "{what} must be (m, {K}), found shape {shape:?}"
        )));
    }
    Ok(flat
        .chunks_exact(K)
        .map(|c| {
            let mut row = [0; K];
            row.copy_from_slice(c);
            row
        })
        .collect())
}

/// A 1-D integer array-like (or list) of vertex indices (`what` names it in errors).
pub fn index_list_from_py(obj: &Bound<'_, PyAny>, what: &str) -> PyResult<Vec<u32>> {
    let (shape, flat) = indices_from_py(obj, what)?;
    if shape.len() != 1 {
        return Err(data_error(format!(
            "{what} must be one-dimensional (a list of vertex indices), found shape {shape:?}"
        )));
    }
    Ok(flat)
}

/// Rows of `K` values as a fresh `(n, K)` numpy array of `T`.
pub fn rows_to_array2<'py, T: numpy::Element + Copy, const K: usize>(
    py: Python<'py>,
    rows: &[[T; K]],
) -> Bound<'py, PyArray2<T>> {
    let a = Array2::from_shape_fn((rows.len(), K), |(i, j)| rows[i][j]);
    a.into_pyarray(py)
}

/// 3-vectors as a fresh `(n, 3)` float64 array.
pub fn points_to_array<'py>(py: Python<'py>, points: &[Vector3]) -> Bound<'py, PyArray2<f64>> {
    let a = Array2::from_shape_fn((points.len(), 3), |(i, j)| points[i][j]);
    a.into_pyarray(py)
}

/// A recording from a time axis, values shaped (n_samples, n_signals) and names.
pub fn recording_from_py(
    t: &Bound<'_, PyAny>,
    values: &Bound<'_, PyAny>,
    names: Vec<String>,
) -> PyResult<Recording> {
    let t = vec_from_py(t, "t")?;
    let arr = as_float_array(values)?;
    let ro = arr.readonly();
    let view = ro.as_array();
    let shape = view.shape().to_vec();
    let k = names.len();
    let ok = match shape.as_slice() {
        [n, m] => *n == t.len() && *m == k,
        // One signal may come as a 1-D array.
        [n] => k == 1 && *n == t.len(),
        _ => false,
    };
    if !ok {
        return Err(data_error(format!(
            "values must be (n_samples, n_signals) = ({}, {k}), one column per name, found shape {shape:?}",
            t.len()
        )));
    }
    let signals: Vec<Signal> = if shape.len() == 1 {
        vec![Signal::new(
            names[0].clone(),
            view.iter().copied().collect(),
        )]
    } else {
        names
            .into_iter()
            .enumerate()
            .map(|(j, name)| {
                let column = view.index_axis(numpy::ndarray::Axis(1), j);
                Signal::new(name, column.iter().copied().collect())
            })
            .collect()
    };
    Recording::new(t, signals).map_err(to_py_err)
}

/// A fresh float64 numpy array holding `v`.
pub fn array1<'py>(py: Python<'py>, v: &[f64]) -> Bound<'py, PyArray1<f64>> {
    PyArray1::from_slice(py, v)
}

/// Columns as a fresh (n_rows, n_columns) float64 array (each column `n_rows` long).
pub fn columns_to_array2<'py>(
    py: Python<'py>,
    n_rows: usize,
    columns: &[&[f64]],
) -> Bound<'py, PyArray2<f64>> {
    let n_cols = columns.len();
    let a = Array2::from_shape_fn((n_rows, n_cols), |(i, j)| {
        columns[j].get(i).copied().unwrap_or(f64::NAN)
    });
    a.into_pyarray(py)
}

/// Row-major matrix as a fresh 2-D float64 array.
pub fn matrix<'py>(py: Python<'py>, m: &modelgap::math::DMatrix) -> Bound<'py, PyArray2<f64>> {
    let a = Array2::from_shape_fn((m.nrows(), m.ncols()), |(i, j)| m[(i, j)]);
    a.into_pyarray(py)
}

/// Noise floors by output name from an optional `{name: sigma}` dict.
pub fn noise_map(noise: Option<BTreeMap<String, f64>>) -> PyResult<BTreeMap<String, f64>> {
    let noise = noise.unwrap_or_default();
    for (name, sigma) in &noise {
        if !(sigma.is_finite() && *sigma > 0.0) {
            return Err(data_error(format!(
                "the noise floor of `{name}` must be positive and finite, found {sigma}"
            )));
        }
    }
    Ok(noise)
}

/// What long work gets from [`run_watched`]: a cancel flag and a progress sink.
pub struct Watch {
    /// Set when the caller pressed Ctrl-C or the progress callback raised.
    pub cancel: Arc<Cancel>,
    /// Called by the work as `(done, total)`; forwarded to the Python callback.
    pub progress: Arc<dyn Fn(usize, usize) + Send + Sync>,
}

/// Runs `work` on a scoped thread with the GIL released, while the calling thread wakes
/// every [`POLL_INTERVAL`] to check for Ctrl-C (`check_signals`) and to call the user's
/// `progress(done, total)` when it changed. An exception from either sets the cancel flag;
/// it is raised once the work has stopped. A panic in the work becomes a `ModelgapError`
/// naming the bug, never a `PanicException`.
pub fn run_watched<T, F>(
    py: Python<'_>,
    progress: Option<&Bound<'_, PyAny>>,
    work: F,
) -> PyResult<T>
where
    T: Send,
    F: FnOnce(Watch) -> T + Send,
{
    let cancel = Arc::new(Cancel::new());
    let counts = Arc::new((AtomicUsize::new(0), AtomicUsize::new(0)));
    let sink = counts.clone();
    let watch = Watch {
        cancel: cancel.clone(),
        progress: Arc::new(move |done, total| {
            sink.1.store(total, Ordering::Relaxed);
            sink.0.fetch_max(done, Ordering::Relaxed);
        }),
    };
    let mut raised: Option<PyErr> = None;
    let mut reported = (0, 0);
    let mut report = |raised: &mut Option<PyErr>| {
        let now = (
            counts.0.load(Ordering::Relaxed),
            counts.1.load(Ordering::Relaxed),
        );
        if now != reported
            && raised.is_none()
            && let Some(cb) = progress
        {
            reported = now;
            if let Err(e) = cb.call1(now) {
                cancel.cancel();
                *raised = Some(e);
            }
        }
    };
    let outcome = std::thread::scope(|scope| {
        let (tx, rx) = mpsc::channel();
        scope.spawn(move || {
            let result = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| work(watch)));
            let _ = tx.send(result);
        });
        let mut rx = rx;
        loop {
            let (received, back) = py.detach(move || (rx.recv_timeout(POLL_INTERVAL), rx));
            rx = back;
            if raised.is_none()
                && let Err(e) = py.check_signals()
            {
                cancel.cancel();
                raised = Some(e);
            }
            report(&mut raised);
            match received {
                Ok(result) => break Some(result),
                Err(mpsc::RecvTimeoutError::Timeout) => {}
                Err(mpsc::RecvTimeoutError::Disconnected) => break None,
            }
        }
    });
    if let Some(e) = raised {
        return Err(e);
    }
    match outcome {
        Some(Ok(value)) => Ok(value),
        Some(Err(panic)) => Err(ModelgapError::new_err(format!(
            "internal error (a bug in modelgap, please report it): {}",
            panic_message(panic.as_ref())
        ))),
        None => Err(ModelgapError::new_err(
            "internal error (a bug in modelgap, please report it): the worker thread ended without a result",
        )),
    }
}

fn panic_message(panic: &(dyn std::any::Any + Send)) -> String {
    if let Some(s) = panic.downcast_ref::<&str>() {
        (*s).to_owned()
    } else if let Some(s) = panic.downcast_ref::<String>() {
        s.clone()
    } else {
        "a panic".to_owned()
    }
}

/// Runs `work` with the GIL released, turning a panic into a `ModelgapError`.
pub fn detached<T, F>(py: Python<'_>, work: F) -> PyResult<T>
where
    T: Send,
    F: FnOnce() -> T + Send,
{
    py.detach(|| std::panic::catch_unwind(std::panic::AssertUnwindSafe(work)))
        .map_err(|panic| {
            ModelgapError::new_err(format!(
                "internal error (a bug in modelgap, please report it): {}",
                panic_message(panic.as_ref())
            ))
        })
}
