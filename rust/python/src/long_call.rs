//! The one way every long core call (propagate, monte_carlo, ccsp) runs: on a worker
//! thread with the GIL released, while the calling thread wakes every 50 ms to honour
//! Ctrl-C and report progress, cancels the core through its `Progress` on any Python
//! exception, and converts core errors. Parallel work runs on `pool::current()` (made
//! again after a fork).

use crate::errors::to_py;
use pyo3::prelude::*;
use pyo3::{PyErr, PyResult, Python};
use rhoprop_core::progress::Progress;
use rhoprop_core::CoreError;
use std::sync::atomic::Ordering;
use std::sync::mpsc::{sync_channel, RecvTimeoutError};
use std::time::Duration;

/// How often the calling thread checks for Ctrl-C and reports progress.
const POLL: Duration = Duration::from_millis(50);

/// Runs `f` on a worker thread with the GIL released. Every 50 ms this thread calls
/// `py.check_signals()` and `callback(done)` (units done so far, see `Progress`); an
/// exception from either cancels the run and is raised. A run cancelled otherwise raises
/// KeyboardInterrupt; core errors map through `errors::to_py`. Returns as soon as the
/// worker finishes, not at the next poll.
pub fn long_call<T, F>(py: Python<'_>, callback: Option<Py<PyAny>>, f: F) -> PyResult<T>
where
    T: Send,
    F: FnOnce(&Progress) -> Result<T, CoreError> + Send,
{
    let pool = crate::pool::current()?;
    let progress = Progress::default();
    let mut raised: Option<PyErr> = None;
    let result = py.detach(|| {
        std::thread::scope(|scope| {
            let (finished, wait) = sync_channel::<()>(1);
            let progress = &progress;
            let pool = &pool;
            let worker = scope.spawn(move || {
                let out = pool.install(|| f(progress));
                // The receiver lives until the worker is joined; a failed send is harmless.
                let _ = finished.send(());
                out
            });
            loop {
                match wait.recv_timeout(POLL) {
                    Ok(()) | Err(RecvTimeoutError::Disconnected) => break,
                    Err(RecvTimeoutError::Timeout) => {}
                }
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
            worker
                .join()
                .unwrap_or_else(|panic| std::panic::resume_unwind(panic))
        })
    });
    if let Some(e) = raised {
        return Err(e);
    }
    result.map_err(to_py)
}
