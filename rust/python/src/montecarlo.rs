//! `monte_carlo`: the ensemble run.

use crate::density::{with_atmosphere, AtmosphereRef};
use crate::long_call::long_call;
use crate::records::{MonteCarloOut, PyMonteCarloRun};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use rhoprop_core::montecarlo::monte_carlo as core_mc;

/// Most worker threads a run may ask for (each costs a stack; more than cores only adds
/// switching).
const MAX_THREADS: usize = 1024;

/// Runs a Monte Carlo ensemble (`run`, a `MonteCarloRun`) on `threads` workers (None:
/// the core's pool), `progress(done)` called about every 50 ms; see `rhoprop.monte_carlo`
/// for the documented API.
#[pyfunction]
#[pyo3(signature = (atmosphere, run, threads = None, progress = None))]
pub fn monte_carlo<'py>(
    py: Python<'py>,
    atmosphere: &Bound<'py, PyAny>,
    run: &Bound<'py, PyMonteCarloRun>,
    threads: Option<usize>,
    progress: Option<Py<PyAny>>,
) -> PyResult<MonteCarloOut> {
    let atm = AtmosphereRef::extract(atmosphere)?;
    let cfg = &run.get().cfg;
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
        let go = || with_atmosphere!(&atm, |a| core_mc(a, cfg, p));
        match &pool {
            Some(pool) => pool.install(go),
            None => go(),
        }
    })?;
    Ok(MonteCarloOut::new(
        py,
        out,
        cfg.members,
        cfg.output_times.len(),
    ))
}
