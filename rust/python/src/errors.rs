//! Core errors -> Python exceptions, mapped once. Each core variant has its own class in
//! `rhoprop.errors` (all `RhopropError`, itself a `ValueError`), raised with the variant's
//! values as attributes, so Python never parses a message.

use pyo3::exceptions::{PyKeyboardInterrupt, PyRuntimeError};
use pyo3::prelude::*;
use pyo3::types::PyTuple;
use pyo3::PyErr;
use rhoprop_core::CoreError;
use std::sync::Mutex;

/// An instance of `rhoprop.errors.<class>` with message `msg` and attributes `attrs`.
fn raise(py: Python<'_>, class: &str, msg: String, attrs: &[(&str, Py<PyAny>)]) -> PyErr {
    let made = (|| -> PyResult<PyErr> {
        let cls = py.import("rhoprop.errors")?.getattr(class)?;
        let instance = cls.call1((msg.clone(),))?;
        for (name, value) in attrs {
            instance.setattr(*name, value.bind(py))?;
        }
        Ok(PyErr::from_value(instance))
    })();
    // The tree is part of the package; if it cannot be imported, still say what failed.
    made.unwrap_or_else(|e| PyRuntimeError::new_err(format!("{msg} (and rhoprop.errors: {e})")))
}

/// The exception a Python tile source raised in a run (the core carries only its text).
static SOURCE_ERROR: Mutex<Option<PyErr>> = Mutex::new(None);

/// Keeps the exception of a Python tile source, raised by [`to_py`] as itself.
pub fn keep_source_error(e: PyErr) {
    *SOURCE_ERROR.lock().unwrap_or_else(|p| p.into_inner()) = Some(e);
}

/// Converts a core error to the matching Python exception.
pub fn to_py(e: CoreError) -> PyErr {
    if e == CoreError::Cancelled {
        return PyKeyboardInterrupt::new_err("rhoprop run interrupted");
    }
    if let CoreError::Rejected { name, .. } = &e {
        if name.starts_with("density tile ") {
            if let Some(kept) = SOURCE_ERROR
                .lock()
                .unwrap_or_else(|p| p.into_inner())
                .take()
            {
                return kept;
            }
        }
    }
    let msg = e.to_string();
    Python::attach(|py| {
        let v = |x: f64| x.into_pyobject(py).unwrap().into_any().unbind();
        let s = |x: &str| x.into_pyobject(py).unwrap().into_any().unbind();
        match e {
            CoreError::NonFinite { name, value } => raise(
                py,
                "NonFiniteError",
                msg,
                &[("name", s(&name)), ("value", v(value))],
            ),
            CoreError::Invalid {
                name,
                value,
                reason,
            } => raise(
                py,
                "InvalidValueError",
                msg,
                &[
                    ("name", s(&name)),
                    ("value", v(value)),
                    ("reason", s(&reason)),
                ],
            ),
            CoreError::Rejected { name, reason } => raise(
                py,
                "RejectedInputError",
                msg,
                &[("name", s(&name)), ("reason", s(&reason))],
            ),
            CoreError::UnknownName {
                what,
                name,
                expected,
            } => {
                let known = PyTuple::new(py, expected.iter().copied())
                    .map(|t| t.into_any().unbind())
                    .unwrap_or_else(|_| py.None());
                raise(
                    py,
                    "UnknownNameError",
                    msg,
                    &[("what", s(what)), ("name", s(&name)), ("expected", known)],
                )
            }
            CoreError::Shape { name, reason } => raise(
                py,
                "ShapeError",
                msg,
                &[("name", s(&name)), ("reason", s(&reason))],
            ),
            CoreError::OutsideField {
                axis,
                value,
                min,
                max,
                t,
            } => raise(
                py,
                "DensityFieldError",
                msg,
                &[
                    ("axis", s(axis)),
                    ("value", v(value)),
                    ("min", v(min)),
                    ("max", v(max)),
                    ("time", v(t)),
                ],
            ),
            CoreError::NotPositiveDefinite {
                t, min_eigenvalue, ..
            } => raise(
                py,
                "CovarianceError",
                msg,
                &[("time", v(t)), ("min_eigenvalue", v(min_eigenvalue))],
            ),
            CoreError::StepUnderflow { t, h } => raise(
                py,
                "StepUnderflowError",
                msg,
                &[("time", v(t)), ("step", v(h))],
            ),
            CoreError::TooManySteps { max_steps, t, end } => {
                let n = max_steps.into_pyobject(py).unwrap().into_any().unbind();
                raise(
                    py,
                    "TooManyStepsError",
                    msg,
                    &[("max_steps", n), ("time", v(t)), ("end", v(end))],
                )
            }
            CoreError::Cancelled => unreachable!("handled above"),
        }
    })
}
