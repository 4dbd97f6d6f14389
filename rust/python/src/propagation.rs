//! `propagate`: one deterministic trajectory.

use crate::arrays::{from_rows, from_vec, vector};
use crate::density::{with_atmosphere, AtmosphereRef};
use crate::errors::to_py;
use crate::long_call::long_call;
use numpy::{IntoPyArray, PyArray1, PyArray2, PyReadonlyArray1};
use pyo3::prelude::*;
use rhoprop_core::propagate::{propagate as core_propagate, Method, Trajectory};

/// Result tuple: (times (n,), states (n, 6), decayed_at or None, rhs evaluations, clipped).
type PropagateOut<'py> = (
    Bound<'py, PyArray1<f64>>,
    Bound<'py, PyArray2<f64>>,
    Option<f64>,
    u64,
    u64,
);

/// Propagates one state; see `rhoprop.propagate` for the documented Python API.
#[pyfunction]
#[pyo3(signature = (atmosphere, epoch, state, drag, output_times, method, step, rtol, floor_altitude,
    zonal_degree = 2, forces = (None, None, 0.0)))]
#[allow(clippy::too_many_arguments)]
pub fn propagate<'py>(
    py: Python<'py>,
    atmosphere: &Bound<'py, PyAny>,
    epoch: f64,
    state: PyReadonlyArray1<'py, f64>,
    drag: f64,
    output_times: PyReadonlyArray1<'py, f64>,
    method: &str,
    step: Option<f64>,
    rtol: Option<f64>,
    floor_altitude: f64,
    zonal_degree: u8,
    forces: (Option<u8>, Option<bool>, f64),
) -> PyResult<PropagateOut<'py>> {
    let atm = AtmosphereRef::extract(atmosphere)?;
    let problem =
        crate::arrays::problem(epoch, &state, drag, floor_altitude, zonal_degree, forces)?;
    let outputs = vector("output_times", &output_times)?.to_vec();
    let method = Method::from_name(method, step, rtol).map_err(to_py)?;
    let tr: Trajectory = long_call(py, None, |progress| {
        with_atmosphere!(&atm, |a| core_propagate(
            a, &problem, &outputs, method, progress
        ))
    })?;
    Ok((
        from_vec(tr.times).into_pyarray(py),
        from_rows(&tr.states).into_pyarray(py),
        tr.decayed_at,
        tr.evaluations,
        tr.clipped,
    ))
}
