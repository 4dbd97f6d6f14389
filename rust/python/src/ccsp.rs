//! `ccsp`: the consider-covariance sigma-point filter.

use crate::arrays::fixed;
use crate::density::{with_atmosphere, AtmosphereRef};
use crate::long_call::long_call;
use numpy::ndarray::{Array1, Array2, Array3};
use numpy::{IntoPyArray, PyReadonlyArray1, PyReadonlyArray2};
use pyo3::prelude::*;
use pyo3::types::PyDict;
use rhoprop_core::ccsp::{ccsp as core_ccsp, CcspConfig};
use rhoprop_core::integrators::FixedMethod;
use rhoprop_core::problem::Problem;

/// Runs the CCSP filter; see `rhoprop.ccsp` for the documented API. Returns a dict:
/// decayed_at (s, or None: when a sigma point crossed the floor; the outputs end before it),
/// times (nt,), means (nt, 6), covariances (nt, 6, 6), cross (nt, 6), drag_cross (nt, 6),
/// nt = updates + 1.
#[pyfunction]
#[pyo3(signature = (atmosphere, epoch, state, drag, initial_covariance, update_times,
    scaling, perturbation, step, floor_altitude, zonal_degree = 2, drag_sigma = 0.0))]
#[allow(clippy::too_many_arguments)]
pub fn ccsp<'py>(
    py: Python<'py>,
    atmosphere: &Bound<'py, PyAny>,
    epoch: f64,
    state: PyReadonlyArray1<'py, f64>,
    drag: f64,
    initial_covariance: PyReadonlyArray2<'py, f64>,
    update_times: PyReadonlyArray1<'py, f64>,
    scaling: (f64, f64),
    perturbation: &str,
    step: f64,
    floor_altitude: f64,
    zonal_degree: u8,
    drag_sigma: f64,
) -> PyResult<Bound<'py, PyDict>> {
    let atm = AtmosphereRef::extract(atmosphere)?;
    let perturbation = crate::arrays::perturbation(perturbation)?;
    let p0 = crate::arrays::matrix6("initial_covariance", &initial_covariance)?;
    let cfg = CcspConfig {
        problem: Problem {
            epoch,
            y0: fixed::<6>("state", &state)?,
            drag,
            floor_altitude,
            zonal_degree,
        },
        p0,
        update_times: crate::arrays::vector("update_times", &update_times)?.to_vec(),
        scaling,
        perturbation,
        method: FixedMethod::Rk8,
        max_step: step,
        drag_sigma,
    };
    let out = long_call(py, None, |progress| {
        with_atmosphere!(&atm, |a| core_ccsp(a, &cfg, progress))
    })?;
    let nt = out.times.len();
    let dict = PyDict::new(py);
    dict.set_item("decayed_at", out.decayed_at)?;
    dict.set_item("times", Array1::from_vec(out.times).into_pyarray(py))?;
    dict.set_item(
        "means",
        Array2::from_shape_fn((nt, 6), |(i, j)| out.means[i][j]).into_pyarray(py),
    )?;
    dict.set_item(
        "covariances",
        Array3::from_shape_fn((nt, 6, 6), |(i, j, k)| out.covariances[i][j][k]).into_pyarray(py),
    )?;
    dict.set_item(
        "cross",
        Array2::from_shape_fn((nt, 6), |(i, j)| out.cross[i][j]).into_pyarray(py),
    )?;
    dict.set_item(
        "drag_cross",
        Array2::from_shape_fn((nt, 6), |(i, j)| out.drag_cross[i][j]).into_pyarray(py),
    )?;
    Ok(dict)
}
