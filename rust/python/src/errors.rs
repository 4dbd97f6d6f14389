//! Core errors -> Python exceptions, mapped once. Every rhoprop error is a
//! `RhopropError`, itself a `ValueError`, so `except ValueError` catches bad input.

use pyo3::create_exception;
use pyo3::exceptions::{PyKeyboardInterrupt, PyValueError};
use pyo3::PyErr;
use rhoprop_core::CoreError;

create_exception!(
    rhoprop._core,
    RhopropError,
    PyValueError,
    "Base of all rhoprop errors (a ValueError)."
);
create_exception!(
    rhoprop._core,
    DensityFieldError,
    RhopropError,
    "A density lookup fell outside the sampled field."
);
create_exception!(
    rhoprop._core,
    IntegrationError,
    RhopropError,
    "The integrator could not complete (step underflow, too many steps)."
);

/// Converts a core error to the matching Python exception.
pub fn to_py(e: CoreError) -> PyErr {
    let msg = e.to_string();
    match e {
        CoreError::OutsideField { .. } => DensityFieldError::new_err(msg),
        CoreError::StepUnderflow { .. } | CoreError::TooManySteps { .. } => {
            IntegrationError::new_err(msg)
        }
        CoreError::Cancelled => PyKeyboardInterrupt::new_err("rhoprop run interrupted"),
        _ => RhopropError::new_err(msg),
    }
}
