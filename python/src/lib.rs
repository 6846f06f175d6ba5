//! The native module `paracosm._native` of the Python package (`python/paracosm/`): thin
//! pyo3 bindings over the workspace's crates. The Python modules `paracosm.qmc`,
//! `paracosm.covering` and `paracosm.scenario` validate arguments, choose scipy's names and
//! defaults and build result objects; this module converts arrays and releases the GIL for
//! every computation that can take long.
//!
//! Arrays cross without copies where numpy allows: inputs are read as C-contiguous `float64`
//! (`n × d`, row-major) or `int64` views, outputs are handed to numpy as the vectors they were
//! computed in.
#![warn(missing_docs)]

use pyo3::exceptions::{PyRuntimeError, PyValueError};
use pyo3::prelude::*;

mod covering;
mod falsify;
mod qmc;
mod scenario;

/// `ValueError(message)`: what the Python side raises for input it cannot honour.
pub(crate) fn value_error(message: impl std::fmt::Display) -> PyErr {
    PyValueError::new_err(message.to_string())
}

/// `RuntimeError(message)`: a defect or a failure that is not the input's.
pub(crate) fn runtime_error(message: impl std::fmt::Display) -> PyErr {
    PyRuntimeError::new_err(message.to_string())
}

/// The module: its functions and classes, and the package's version.
#[pymodule]
fn _native(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    m.add("RENDER", cfg!(feature = "render"))?;
    qmc::register(m)?;
    covering::register(m)?;
    falsify::register(m)?;
    scenario::register(m)?;
    Ok(())
}
