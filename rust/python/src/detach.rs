//! The one way long core calls run: without the GIL, with core errors converted.

use crate::errors::to_py;
use pyo3::{PyResult, Python};
use rhoprop_core::CoreError;

/// Runs `f` with the GIL released and converts its error.
pub fn detached<T, F>(py: Python<'_>, f: F) -> PyResult<T>
where
    T: Send,
    F: FnOnce() -> Result<T, CoreError> + Send,
{
    py.detach(f).map_err(to_py)
}
