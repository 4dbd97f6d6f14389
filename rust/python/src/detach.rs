//! The one way long core calls run: without the GIL, with core errors converted.

use crate::errors::to_py;
use pyo3::prelude::*;
use pyo3::{PyErr, PyResult, Python};
use rhoprop_core::ensemble::Progress;
use rhoprop_core::CoreError;
use std::sync::atomic::Ordering;
use std::time::Duration;

/// Runs `f` with the GIL released and converts its error.
pub fn detached<T, F>(py: Python<'_>, f: F) -> PyResult<T>
where
    T: Send,
    F: FnOnce() -> Result<T, CoreError> + Send,
{
    py.detach(f).map_err(to_py)
}

/// Runs a long core call on a worker thread with the GIL released, while this (the
/// calling) thread wakes every 50 ms to honour Ctrl-C (`check_signals`) and to report the
/// members done to `callback(done)`. An exception from either cancels the run and is
/// raised; a cancelled run raises KeyboardInterrupt.
pub fn detached_with_progress<T, F>(
    py: Python<'_>,
    callback: Option<Py<PyAny>>,
    f: F,
) -> PyResult<T>
where
    T: Send,
    F: FnOnce(&Progress) -> Result<T, CoreError> + Send,
{
    let progress = Progress::default();
    let mut raised: Option<PyErr> = None;
    let result = py.detach(|| {
        std::thread::scope(|scope| {
            let worker = scope.spawn(|| f(&progress));
            while !worker.is_finished() {
                std::thread::sleep(Duration::from_millis(50));
                if raised.is_some() {
                    continue;
                }
                Python::attach(|py| {
                    let done = progress.done.load(Ordering::Relaxed);
                    let outcome = py.check_signals().and_then(|()| match &callback {
                        Some(cb) => cb.bind(py).call1((done,)).map(|_| ()),
                        None => Ok(()),
                    });
                    if let Err(e) = outcome {
                        raised = Some(e);
                        progress.cancel.store(true, Ordering::Relaxed);
                    }
                });
            }
            worker.join().expect("the core worker thread panicked")
        })
    });
    if let Some(e) = raised {
        return Err(e);
    }
    result.map_err(to_py)
}
