//! `monte_carlo`: the ensemble run.

use crate::arrays::vector;
use crate::density::{with_atmosphere, AtmosphereRef};
use crate::errors::to_py;
use crate::long_call::long_call;
use numpy::ndarray::{Array1, Array2, Array3};
use numpy::{IntoPyArray, PyArray1, PyArray2, PyArray3, PyReadonlyArray1, PyReadonlyArray2};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use pyo3::types::PyDict;
use rhoprop_core::integrators::FixedMethod;
use rhoprop_core::kappa::KappaProcess;
use rhoprop_core::montecarlo::{covariance_factor, monte_carlo as core_mc, MonteCarloConfig};

/// Most worker threads a run may ask for (each costs a stack; more than cores only adds
/// switching).
const MAX_THREADS: usize = 1024;

/// Runs a Monte Carlo ensemble; see `rhoprop.monte_carlo` for the documented API.
/// Returns a dict of arrays: positions/velocities (n, nt, 3), densities (n, nt) or None,
/// clipped (n,), decay_times (n,), step, drag_factors (n,).
#[pyfunction]
#[pyo3(signature = (atmosphere, epoch, state, drag, output_times, kappa, perturbation, method,
    step, members, seed, initial_covariance, floor_altitude, record_density, threads, progress,
    zonal_degree = 2, drag_sigma = 0.0, forces = (None, None, 0.0)))]
#[allow(clippy::too_many_arguments)]
pub fn monte_carlo<'py>(
    py: Python<'py>,
    atmosphere: &Bound<'py, PyAny>,
    epoch: f64,
    state: PyReadonlyArray1<'py, f64>,
    drag: f64,
    output_times: PyReadonlyArray1<'py, f64>,
    kappa: (String, Vec<f64>),
    perturbation: &str,
    method: &str,
    step: f64,
    members: usize,
    seed: u64,
    initial_covariance: Option<PyReadonlyArray2<'py, f64>>,
    floor_altitude: f64,
    record_density: bool,
    threads: Option<usize>,
    progress: Option<Py<PyAny>>,
    zonal_degree: u8,
    drag_sigma: f64,
    forces: (Option<u8>, Option<bool>, f64),
) -> PyResult<Bound<'py, PyDict>> {
    let atm = AtmosphereRef::extract(atmosphere)?;
    let perturbation = crate::arrays::perturbation(perturbation)?;
    let method = FixedMethod::from_name(method).map_err(to_py)?;
    let initial_factor = match initial_covariance {
        None => None,
        Some(c) => Some(
            covariance_factor(&crate::arrays::matrix6("initial_covariance", &c)?).map_err(to_py)?,
        ),
    };
    let cfg = MonteCarloConfig {
        problem: crate::arrays::problem(epoch, &state, drag, floor_altitude, zonal_degree, forces)?,
        initial_factor,
        kappa: KappaProcess::from_spec(&kappa.0, &kappa.1).map_err(to_py)?,
        perturbation,
        method,
        max_step: step,
        output_times: vector("output_times", &output_times)?.to_vec(),
        members,
        seed,
        record_density,
        drag_sigma,
    };
    let pool = match threads {
        Some(0) => return Err(PyValueError::new_err("threads must be >= 1")),
        Some(n) if n > MAX_THREADS => {
            return Err(PyValueError::new_err(format!(
                "threads = {n} is more than rhoprop starts ({MAX_THREADS}); use at most the \
                 number of cores"
            )))
        }
        Some(n) => Some(
            rayon::ThreadPoolBuilder::new()
                .num_threads(n)
                .build()
                .map_err(|e| PyValueError::new_err(format!("cannot start {n} threads: {e}")))?,
        ),
        None => None,
    };
    let out = long_call(py, progress, |p| {
        let run = || with_atmosphere!(&atm, |a| core_mc(a, &cfg, p));
        match &pool {
            Some(pool) => pool.install(run),
            None => run(),
        }
    })?;
    let nt = cfg.output_times.len();
    let n = cfg.members;
    let shape3 = |v: Vec<f64>| {
        Array3::from_shape_vec((n, nt, 3), v).expect("core returns members x times x 3")
    };
    let dict = PyDict::new(py);
    let positions: Bound<'py, PyArray3<f64>> = shape3(out.positions).into_pyarray(py);
    let velocities: Bound<'py, PyArray3<f64>> = shape3(out.velocities).into_pyarray(py);
    dict.set_item("positions", positions)?;
    dict.set_item("velocities", velocities)?;
    let densities: Option<Bound<'py, PyArray2<f64>>> = out.densities.map(|d| {
        Array2::from_shape_vec((n, nt), d)
            .expect("core returns members x times")
            .into_pyarray(py)
    });
    dict.set_item("densities", densities)?;
    let clipped: Bound<'py, PyArray1<u64>> = Array1::from_vec(out.clipped).into_pyarray(py);
    dict.set_item("clipped", clipped)?;
    dict.set_item(
        "decay_times",
        Array1::from_vec(out.decay_times).into_pyarray(py),
    )?;
    dict.set_item("step", out.step)?;
    dict.set_item(
        "drag_factors",
        Array1::from_vec(out.drag_factors).into_pyarray(py),
    )?;
    Ok(dict)
}
