//! `propagate`: one deterministic trajectory.

use crate::arrays::vector;
use crate::density::{with_atmosphere, AtmosphereRef};
use crate::errors::to_py;
use crate::long_call::long_call;
use crate::records::{Propagated, PyProblem};
use numpy::PyReadonlyArray1;
use pyo3::prelude::*;
use rhoprop_core::propagate::{propagate as core_propagate, Method, Trajectory};

/// Propagates one `problem` to `output_times` (s) with `method` ("dop853", "rk8", "rk4",
/// "abm"), its largest `step` (s) and DOP853's `rtol`; see `rhoprop.propagate` for the
/// documented Python API.
#[pyfunction]
#[pyo3(signature = (atmosphere, problem, output_times, method, step = None, rtol = None))]
pub fn propagate<'py>(
    py: Python<'py>,
    atmosphere: &Bound<'py, PyAny>,
    problem: &Bound<'py, PyProblem>,
    output_times: PyReadonlyArray1<'py, f64>,
    method: &str,
    step: Option<f64>,
    rtol: Option<f64>,
) -> PyResult<Propagated> {
    let atm = AtmosphereRef::extract(atmosphere)?;
    let problem = problem.get().inner;
    let outputs = vector("output_times", &output_times)?.to_vec();
    let method = Method::from_name(method, step, rtol).map_err(to_py)?;
    let tr: Trajectory = long_call(py, None, |progress| {
        with_atmosphere!(&atm, |a| core_propagate(
            a, &problem, &outputs, method, progress
        ))
    })?;
    Ok(Propagated::new(py, tr))
}
