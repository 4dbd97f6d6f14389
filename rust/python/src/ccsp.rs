//! `ccsp`: the consider-covariance sigma-point filter.

use crate::density::{with_atmosphere, AtmosphereRef};
use crate::long_call::long_call;
use crate::records::{CcspOut, PyCcspRun};
use pyo3::prelude::*;
use pyo3::types::PyList;
use rhoprop_core::ccsp::{ccsp as core_ccsp, ccsp_many as core_ccsp_many};

/// Runs the CCSP filter (`run`, a `CcspRun`); see `rhoprop.ccsp` for the documented API.
#[pyfunction]
pub fn ccsp<'py>(
    py: Python<'py>,
    atmosphere: &Bound<'py, PyAny>,
    run: &Bound<'py, PyCcspRun>,
) -> PyResult<CcspOut> {
    let atm = AtmosphereRef::extract(atmosphere)?;
    let cfg = &run.get().cfg;
    let out = long_call(py, None, |progress| {
        with_atmosphere!(&atm, |a| core_ccsp(a, cfg, progress))
    })?;
    Ok(CcspOut::new(py, out))
}

/// Runs the CCSP filter of several objects (`runs`, one `CcspRun` each) through one
/// atmosphere in one call, objects in parallel with the GIL released (each object's
/// sigma points in one batch); every result equals `ccsp` of that object alone. Returns a
/// list with, per object, its `CcspOutput` or the exception its run raised (not raised
/// here). `progress(done)` is called about every 50 ms with the updates done over all
/// objects; an exception from it (or Ctrl-C) stops the call and is raised.
#[pyfunction]
#[pyo3(signature = (atmosphere, runs, progress = None))]
pub fn ccsp_many<'py>(
    py: Python<'py>,
    atmosphere: &Bound<'py, PyAny>,
    runs: Vec<Bound<'py, PyCcspRun>>,
    progress: Option<Py<PyAny>>,
) -> PyResult<Bound<'py, PyList>> {
    let atm = AtmosphereRef::extract(atmosphere)?;
    let cfgs: Vec<_> = runs.iter().map(|r| r.get().cfg.clone()).collect();
    let outs = long_call(py, progress, |progress| {
        with_atmosphere!(&atm, |a| core_ccsp_many(a, &cfgs, progress))
    })?;
    let list = PyList::empty(py);
    for out in outs {
        match out {
            Ok(out) => list.append(CcspOut::new(py, out))?,
            Err(err) => list.append(crate::errors::to_py(err).into_value(py))?,
        }
    }
    Ok(list)
}
