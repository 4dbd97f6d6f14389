//! `ccsp`: the consider-covariance sigma-point filter.

use crate::density::{with_atmosphere, AtmosphereRef};
use crate::long_call::long_call;
use numpy::ndarray::{Array1, Array2, Array3};
use numpy::{IntoPyArray, PyReadonlyArray1, PyReadonlyArray2};
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList};
use rhoprop_core::ccsp::{
    ccsp as core_ccsp, ccsp_many as core_ccsp_many, CcspConfig, CcspOutput, Coordinates, SlowKappa,
};
use rhoprop_core::integrators::FixedMethod;

/// Runs the CCSP filter; see `rhoprop.ccsp` for the documented API. Returns a dict:
/// decayed_at (s, or None: when a sigma point crossed the floor; the outputs end before it),
/// times (nt,), means (nt, 6), covariances (nt, 6, 6), cross (nt, 6), drag_cross (nt, 6),
/// nt = 1 + the updates + the output times between them; with `coordinates`
/// "equinoctial" also element_means (nt, 6) and element_covariances (nt, 6, 6).
#[pyfunction]
#[pyo3(signature = (atmosphere, epoch, state, drag, initial_covariance, update_times,
    scaling, perturbation, step, floor_altitude, zonal_degree = 2, drag_sigma = 0.0,
    output_times = None, coordinates = "equinoctial", kappa_scale = 1.0, slow = None,
    forces = (None, None, 0.0)))]
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
    output_times: Option<PyReadonlyArray1<'py, f64>>,
    coordinates: &str,
    kappa_scale: f64,
    slow: Option<(f64, f64)>,
    forces: (Option<u8>, Option<bool>, f64),
) -> PyResult<Bound<'py, PyDict>> {
    let coordinates = coordinates_arg(coordinates)?;
    let atm = AtmosphereRef::extract(atmosphere)?;
    let perturbation = crate::arrays::perturbation(perturbation)?;
    let p0 = crate::arrays::matrix6("initial_covariance", &initial_covariance)?;
    let cfg = CcspConfig {
        problem: crate::arrays::problem(epoch, &state, drag, floor_altitude, zonal_degree, forces)?,
        p0,
        update_times: crate::arrays::vector("update_times", &update_times)?.to_vec(),
        output_times: match &output_times {
            Some(times) => crate::arrays::vector("output_times", times)?.to_vec(),
            None => Vec::new(),
        },
        scaling,
        kappa_scale,
        perturbation,
        method: FixedMethod::Rk8,
        max_step: step,
        drag_sigma,
        coordinates,
        slow: slow.map(slow_arg),
    };
    let out = long_call(py, None, |progress| {
        with_atmosphere!(&atm, |a| core_ccsp(a, &cfg, progress))
    })?;
    output_dict(py, out)
}

/// One object of `ccsp_many`: (epoch, state (6,), drag, initial_covariance (6, 6),
/// update_times (k,), step, drag_sigma, output_times (m,), empty for none).
type ObjectArgs<'py> = (
    f64,
    PyReadonlyArray1<'py, f64>,
    f64,
    PyReadonlyArray2<'py, f64>,
    PyReadonlyArray1<'py, f64>,
    f64,
    f64,
    PyReadonlyArray1<'py, f64>,
);

/// The core's [`SlowKappa`] from (scale, half_life s; infinite: constant).
fn slow_arg((scale, half_life): (f64, f64)) -> SlowKappa {
    SlowKappa { scale, half_life }
}

/// Runs the CCSP filter of several objects through one atmosphere in one call, objects in
/// parallel with the GIL released (each object's sigma points in one batch); every
/// result equals `ccsp` of that object alone. `objects` holds one tuple per object
/// (epoch, state, drag, initial_covariance, update_times, step, drag_sigma,
/// output_times);
/// the other
/// settings are shared. Returns a list with, per object, the dict of `ccsp` or the
/// exception its run raised (not raised here). `progress(done)` is called about every
/// 50 ms with the updates done over all objects; an exception from it (or Ctrl-C) stops
/// the call and is raised.
#[pyfunction]
#[pyo3(signature = (atmosphere, objects, scaling, perturbation, floor_altitude,
    zonal_degree = 2, progress = None, coordinates = "equinoctial", kappa_scale = 1.0,
    slow = None))]
#[allow(clippy::too_many_arguments)]
pub fn ccsp_many<'py>(
    py: Python<'py>,
    atmosphere: &Bound<'py, PyAny>,
    objects: Vec<ObjectArgs<'py>>,
    scaling: (f64, f64),
    perturbation: &str,
    floor_altitude: f64,
    zonal_degree: u8,
    progress: Option<Py<PyAny>>,
    coordinates: &str,
    kappa_scale: f64,
    slow: Option<(f64, f64)>,
) -> PyResult<Bound<'py, PyList>> {
    let coordinates = coordinates_arg(coordinates)?;
    let atm = AtmosphereRef::extract(atmosphere)?;
    let perturbation = crate::arrays::perturbation(perturbation)?;
    let cfgs = objects
        .iter()
        .map(
            |(epoch, state, drag, p0, times, step, drag_sigma, outputs)| {
                Ok(CcspConfig {
                    problem: crate::arrays::problem(
                        *epoch,
                        state,
                        *drag,
                        floor_altitude,
                        zonal_degree,
                        (None, None, 0.0),
                    )?,
                    p0: crate::arrays::matrix6("initial_covariance", p0)?,
                    update_times: crate::arrays::vector("update_times", times)?.to_vec(),
                    output_times: if outputs.as_array().is_empty() {
                        Vec::new()
                    } else {
                        crate::arrays::vector("output_times", outputs)?.to_vec()
                    },
                    scaling,
                    kappa_scale,
                    perturbation,
                    method: FixedMethod::Rk8,
                    max_step: *step,
                    drag_sigma: *drag_sigma,
                    coordinates,
                    slow: slow.map(slow_arg),
                })
            },
        )
        .collect::<PyResult<Vec<_>>>()?;
    let outs = long_call(py, progress, |progress| {
        with_atmosphere!(&atm, |a| core_ccsp_many(a, &cfgs, progress))
    })?;
    let list = PyList::empty(py);
    for out in outs {
        match out {
            Ok(out) => list.append(output_dict(py, out)?)?,
            Err(err) => list.append(crate::errors::to_py(err).into_value(py))?,
        }
    }
    Ok(list)
}

/// The filter's coordinates from their name.
fn coordinates_arg(name: &str) -> PyResult<Coordinates> {
    match name {
        "equinoctial" => Ok(Coordinates::Equinoctial),
        "cartesian" => Ok(Coordinates::Cartesian),
        _ => Err(pyo3::exceptions::PyValueError::new_err(format!(
            "coordinates must be 'equinoctial' or 'cartesian', got {name:?}"
        ))),
    }
}

/// The dict `ccsp` returns.
fn output_dict(py: Python<'_>, out: CcspOutput) -> PyResult<Bound<'_, PyDict>> {
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
    if !out.element_means.is_empty() {
        dict.set_item(
            "element_means",
            Array2::from_shape_fn((nt, 6), |(i, j)| out.element_means[i][j]).into_pyarray(py),
        )?;
        dict.set_item(
            "element_covariances",
            Array3::from_shape_fn((nt, 6, 6), |(i, j, k)| out.element_covariances[i][j][k])
                .into_pyarray(py),
        )?;
    }
    Ok(dict)
}
