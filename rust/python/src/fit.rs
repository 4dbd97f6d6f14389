//! `fit_orbits`: least-squares fits of state and Cd*A/m, many objects per call.

use crate::density::{with_atmosphere, AtmosphereRef};
use crate::long_call::long_call;
use crate::records::{FitOut, PyFitConfig, PyFitJob};
use pyo3::prelude::*;
use pyo3::types::PyList;
use rhoprop_core::fit::fit_many;

/// Fits several objects (`jobs`, one `FitJob` each, sharing `config`, a `FitConfig`)
/// through one atmosphere in one call, objects in parallel with the GIL released (each
/// trial's nominal and 7 perturbed orbits in one 8-lane batch); see
/// `rhoprop.catalog.fit` for the documented API. Returns a list with, per job, its
/// `FitOutput` or the exception of that job (not raised here).
#[pyfunction]
#[pyo3(signature = (atmosphere, jobs, config, progress = None))]
pub fn fit_orbits<'py>(
    py: Python<'py>,
    atmosphere: &Bound<'py, PyAny>,
    jobs: Vec<Bound<'py, PyFitJob>>,
    config: &Bound<'py, PyFitConfig>,
    progress: Option<Py<PyAny>>,
) -> PyResult<Bound<'py, PyList>> {
    let atm = AtmosphereRef::extract(atmosphere)?;
    let jobs: Vec<_> = jobs.iter().map(|j| j.get().job.clone()).collect();
    let settings = config.get().settings;
    let outs = long_call(py, progress, |progress| {
        with_atmosphere!(&atm, |a| fit_many(a, &jobs, &settings, progress))
    })?;
    let list = PyList::empty(py);
    for out in outs {
        match out {
            Ok(o) => list.append(FitOut::new(py, o))?,
            Err(err) => list.append(crate::errors::to_py(err).into_value(py))?,
        }
    }
    Ok(list)
}
