//! The core's thread pool of this process. rayon's global pool cannot be used: a child
//! forked after the parent ran parallel work (`multiprocessing`'s default on Linux)
//! inherits the pool's state but none of its threads, and waits for them for ever. This
//! pool remembers the process it was made in and is made again in a child; it also
//! follows `$RAYON_NUM_THREADS` (set by `rhoprop.parallel.set_threads`) when it changes.

use pyo3::exceptions::PyValueError;
use pyo3::PyResult;
use rayon::{ThreadPool, ThreadPoolBuilder};
use std::sync::{Arc, Mutex};

/// (process id, `$RAYON_NUM_THREADS` when made, the pool).
type Made = (u32, Option<String>, Arc<ThreadPool>);

static POOL: Mutex<Option<Made>> = Mutex::new(None);

/// The pool for a core call of this process. Call with the GIL held (the environment is
/// read, and Python changes it only under the GIL).
pub fn current() -> PyResult<Arc<ThreadPool>> {
    let pid = std::process::id();
    let threads = std::env::var("RAYON_NUM_THREADS").ok();
    // A panic elsewhere cannot leave the Option half-written: take it as it is.
    let mut made = POOL.lock().unwrap_or_else(|e| e.into_inner());
    if let Some((p, t, pool)) = made.as_ref() {
        if *p == pid && *t == threads {
            return Ok(Arc::clone(pool));
        }
    }
    if let Some((p, _, old)) = made.take() {
        if p != pid {
            // Its threads live in the parent: dropping it here would signal threads this
            // process does not have. Leak the few bytes instead.
            std::mem::forget(old);
        }
    }
    // num_threads unset: rayon takes $RAYON_NUM_THREADS, else the number of CPUs.
    let pool = Arc::new(
        ThreadPoolBuilder::new()
            .build()
            .map_err(|e| PyValueError::new_err(format!("cannot start the core's threads: {e}")))?,
    );
    *made = Some((pid, threads, Arc::clone(&pool)));
    Ok(pool)
}
