//! The Python exceptions of modelgap and the one mapping from Rust errors to them.
//!
//! `ModelgapError` is the base; `DataError` (also a `ValueError`) is for recordings, files
//! and arguments; `ModelError` for models that cannot be built, derived or simulated;
//! `ConvergenceError` for fits and steady states that do not converge.

use modelgap::bond::BondError;
use modelgap::cloth::ClothError;
use modelgap::{CoreError, Error};
use pyo3::exceptions::{PyException, PyKeyboardInterrupt, PyValueError};
use pyo3::prelude::*;

pyo3::create_exception!(
    modelgap,
    ModelgapError,
    PyException,
    "Base class of every error modelgap raises."
);

// `create_exception!` takes one base; DataError is built at registration with two.
pyo3::create_exception!(
    modelgap,
    ModelError,
    ModelgapError,
    "A model cannot be read, built, derived or simulated."
);
pyo3::create_exception!(
    modelgap,
    ConvergenceError,
    ModelgapError,
    "A fit or a steady-state solve did not converge."
);

/// `DataError(ModelgapError, ValueError)`, created once at registration.
static DATA_ERROR: pyo3::sync::PyOnceLock<Py<pyo3::types::PyType>> = pyo3::sync::PyOnceLock::new();

fn data_error_type(py: Python<'_>) -> PyResult<&Bound<'_, pyo3::types::PyType>> {
    DATA_ERROR
        .get_or_try_init(py, || {
            let builtins = py.import("builtins")?;
            let type_fn = builtins.getattr("type")?;
            let bases = (
                py.get_type::<ModelgapError>(),
                py.get_type::<PyValueError>(),
            );
            let dict = pyo3::types::PyDict::new(py);
            dict.set_item("__module__", "modelgap")?;
            dict.set_item(
                "__doc__",
                "Bad input data: a recording, a file, an argument. Also a ValueError.",
            )?;
            let t = type_fn.call1(("DataError", bases, dict))?;
            Ok(t.cast_into::<pyo3::types::PyType>()?.unbind())
        })
        .map(|t| t.bind(py))
}

/// Registers the exception classes on the module.
pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    let py = m.py();
    m.add("ModelgapError", py.get_type::<ModelgapError>())?;
    m.add("DataError", data_error_type(py)?)?;
    m.add("ModelError", py.get_type::<ModelError>())?;
    m.add("ConvergenceError", py.get_type::<ConvergenceError>())?;
    Ok(())
}

/// Which Python class an error maps to.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Kind {
    Data,
    Model,
    Convergence,
    /// A run stopped by its cancel flag: `KeyboardInterrupt`.
    Interrupt,
}

fn cloth_kind(e: &ClothError) -> Kind {
    match e {
        ClothError::Core(c) => core_kind(c),
        ClothError::Diverged { .. } => Kind::Model,
        ClothError::Cancelled { .. } => Kind::Interrupt,
        _ => Kind::Data,
    }
}

fn core_kind(e: &CoreError) -> Kind {
    // A model's own error through the loop's seam keeps its crate's class.
    if let Some(domain) = e.model_error() {
        if let Some(b) = domain.downcast_ref::<BondError>() {
            return bond_kind(b);
        }
        if let Some(c) = domain.downcast_ref::<ClothError>() {
            return cloth_kind(c);
        }
    }
    match e {
        CoreError::Model { .. } => Kind::Model,
        CoreError::Fit { .. } => Kind::Convergence,
        _ => Kind::Data,
    }
}

fn bond_kind(e: &BondError) -> Kind {
    match e {
        BondError::Core(c) => core_kind(c),
        BondError::Io { .. }
        | BondError::File { .. }
        | BondError::BadInput { .. }
        | BondError::BadOptions(_)
        | BondError::BadParameter { .. }
        | BondError::BadRange { .. }
        | BondError::UnphysicalParameter { .. }
        | BondError::TooLarge { .. }
        | BondError::UnknownParameter { .. }
        | BondError::UnknownModel { .. } => Kind::Data,
        BondError::Ode(_) | BondError::NoSteadyState { .. } => Kind::Convergence,
        // A law that is NaN at the start and a state that runs away are the model's own:
        // ModelError, as for every other model that cannot be simulated.
        _ => Kind::Model,
    }
}

/// Converts any modelgap error into its Python exception, with the Rust message unchanged.
pub fn to_py_err(e: impl Into<Error>) -> PyErr {
    let e: Error = e.into();
    let kind = match &e {
        Error::Core(c) => core_kind(c),
        Error::Bond(b) => bond_kind(b),
        Error::Cloth(c) => cloth_kind(c),
        Error::Set { source, .. } => bond_kind(source),
        Error::Input(_) => Kind::Data,
        _ => Kind::Model,
    };
    raise(kind, e.to_string())
}

/// The exception of `kind` with `message`.
fn raise(kind: Kind, message: String) -> PyErr {
    match kind {
        Kind::Model => ModelError::new_err(message),
        Kind::Convergence => ConvergenceError::new_err(message),
        Kind::Interrupt => PyKeyboardInterrupt::new_err(message),
        Kind::Data => data_error(message),
    }
}

/// Converts a cloth error into its Python exception, with the Rust message unchanged.
///
/// Cloth errors are about their input (a mesh, a parameter, a limit, a file, a state set
/// from Python), so they are `DataError`s, except a simulation that diverged (a
/// `ModelError`: the model cannot be simulated), a cancelled run (`KeyboardInterrupt`), and
/// core errors, which map as `to_py_err` maps them.
pub fn cloth_err(e: ClothError) -> PyErr {
    to_py_err(e)
}

/// A `DataError` with a message of the bindings' own (a bad argument).
pub fn data_error(message: impl Into<String>) -> PyErr {
    let message = message.into();
    Python::attach(|py| match data_error_type(py) {
        Ok(t) => PyErr::from_type(t.clone(), message),
        Err(err) => err,
    })
}
