//! The `modelgap._modelgap` extension module: Python bindings of modelgap.
//!
//! This file only registers; the wrappers live in `core.rs` (recordings, compare, explain,
//! the report), `bond.rs` (bond-graph models) and `cloth.rs` (cloth meshes, worlds, scenes,
//! marker recordings), errors in `errors.rs`, numpy and argument conversions in `convert.rs`.
//! No algorithm lives here.

use pyo3::prelude::*;

mod bond;
mod calibrate;
mod cloth;
mod convert;
// The file is `core.rs` (STYLE §1); the module may not be called `core`, which would
// shadow the `core` crate.
#[path = "core.rs"]
mod core_api;
mod errors;
mod model;

/// Python bindings of modelgap: recordings, compare, explain, bond-graph models, cloth.
#[pymodule]
fn _modelgap(m: &Bound<'_, PyModule>) -> PyResult<()> {
    errors::register(m)?;
    core_api::register(m)?;
    bond::register(m)?;
    cloth::register(m)?;
    model::register(m)?;
    calibrate::register(m)?;
    Ok(())
}
