//! `fit_orbits`: least-squares fits of state and Cd*A/m, many objects per call.

use crate::arrays::{fixed, from_rows, rows};
use crate::density::{with_atmosphere, AtmosphereRef};
use crate::long_call::long_call;
use numpy::ndarray::Array2;
use numpy::{IntoPyArray, PyReadonlyArray1, PyReadonlyArray2};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use pyo3::types::{PyList, PyTuple};
use rhoprop_core::fit::{fit_many, FitJob, FitSettings};

/// One job: (epoch UT1 s, p0 (7,), prior, prior_sigma, spacing, back, forward,
/// rows (k,), observed (k, 3), weights (k, 9) row-major 3x3).
type JobArgs<'py> = (
    f64,
    PyReadonlyArray1<'py, f64>,
    f64,
    f64,
    f64,
    usize,
    usize,
    PyReadonlyArray1<'py, i64>,
    PyReadonlyArray2<'py, f64>,
    PyReadonlyArray2<'py, f64>,
);

fn job(args: &JobArgs<'_>) -> PyResult<FitJob> {
    let (epoch, p0, prior, prior_sigma, spacing, back, forward, grid_rows, observed, weights) =
        args;
    let observed = rows("observed", observed, 3)?;
    let weights = rows("weights", weights, 9)?;
    let grid_rows = grid_rows
        .as_array()
        .iter()
        .map(|&r| {
            usize::try_from(r)
                .map_err(|_| PyValueError::new_err(format!("observation row {r} is negative")))
        })
        .collect::<PyResult<Vec<usize>>>()?;
    Ok(FitJob {
        epoch: *epoch,
        p0: fixed::<7>("p0", p0)?,
        prior: *prior,
        prior_sigma: *prior_sigma,
        spacing: *spacing,
        back: *back,
        forward: *forward,
        rows: grid_rows,
        observed: observed
            .rows()
            .into_iter()
            .map(|r| [r[0], r[1], r[2]])
            .collect(),
        weights: weights
            .rows()
            .into_iter()
            .map(|r| std::array::from_fn(|i| std::array::from_fn(|j| r[3 * i + j])))
            .collect(),
    })
}

/// Fits several objects through one atmosphere in one call, objects in parallel with
/// the GIL released (each trial's nominal and 7 perturbed orbits in one 8-lane batch); see
/// `rhoprop.catalog.fit` for the documented API. Returns a list with, per job, the tuple
/// (p (7,), grid states (n, 6), J^T J (7, 7), iterations, converged) or the exception of
/// that job (not raised here).
#[pyfunction]
#[pyo3(signature = (atmosphere, jobs, step, zonal_degree, floor_altitude, max_iterations,
    min_drag, progress = None))]
#[allow(clippy::too_many_arguments)]
pub fn fit_orbits<'py>(
    py: Python<'py>,
    atmosphere: &Bound<'py, PyAny>,
    jobs: Vec<JobArgs<'py>>,
    step: f64,
    zonal_degree: u8,
    floor_altitude: f64,
    max_iterations: usize,
    min_drag: f64,
    progress: Option<Py<PyAny>>,
) -> PyResult<Bound<'py, PyList>> {
    let atm = AtmosphereRef::extract(atmosphere)?;
    let jobs = jobs.iter().map(job).collect::<PyResult<Vec<_>>>()?;
    let settings = FitSettings {
        step,
        zonal_degree,
        floor_altitude,
        max_iterations,
        min_drag,
    };
    let outs = long_call(py, progress, |progress| {
        with_atmosphere!(&atm, |a| fit_many(a, &jobs, &settings, progress))
    })?;
    let list = PyList::empty(py);
    for out in outs {
        match out {
            Ok(o) => {
                let normal = Array2::from_shape_fn((7, 7), |(i, j)| o.normal[i][j]);
                let item = PyTuple::new(
                    py,
                    [
                        o.p.to_vec().into_pyarray(py).into_any(),
                        from_rows(&o.states).into_pyarray(py).into_any(),
                        normal.into_pyarray(py).into_any(),
                        o.iterations.into_pyobject(py)?.into_any(),
                        pyo3::types::PyBool::new(py, o.converged)
                            .to_owned()
                            .into_any(),
                    ],
                )?;
                list.append(item)?;
            }
            Err(err) => list.append(crate::errors::to_py(err).into_value(py))?,
        }
    }
    Ok(list)
}
