//! `propagate`: one deterministic trajectory.

use crate::arrays::{fixed, from_rows, from_vec, vector};
use crate::density::{with_atmosphere, AtmosphereRef};
use crate::long_call::long_call;
use numpy::{IntoPyArray, PyArray1, PyArray2, PyReadonlyArray1};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use rhoprop_core::integrators::AdaptiveOptions;
use rhoprop_core::problem::Problem;
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
    zonal_degree = 2))]
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
) -> PyResult<PropagateOut<'py>> {
    let atm = AtmosphereRef::extract(atmosphere)?;
    let problem = Problem {
        epoch,
        y0: fixed::<6>("state", &state)?,
        drag,
        floor_altitude,
        zonal_degree,
    };
    let outputs = vector("output_times", &output_times)?.to_vec();
    let need_step =
        || step.ok_or_else(|| PyValueError::new_err(format!("method {method:?} needs a step")));
    let method = match method {
        "rk4" => Method::Rk4 { step: need_step()? },
        "rk8" => Method::Rk8 { step: need_step()? },
        "abm" => Method::Abm { step: need_step()? },
        "dop853" => Method::Dop853(AdaptiveOptions {
            rtol: rtol.unwrap_or(AdaptiveOptions::default().rtol),
            max_step: step.unwrap_or(f64::INFINITY),
            ..Default::default()
        }),
        other => {
            return Err(PyValueError::new_err(format!(
                "unknown method {other:?}; expected one of 'dop853', 'rk8', 'rk4', 'abm'"
            )))
        }
    };
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
