//! Progress and cancellation shared between a long core call and its caller (the binding
//! polls it from another thread to report progress and to honour Ctrl-C).

use crate::error::CoreError;
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};

/// Shared progress counter and cancellation flag of a run.
#[derive(Debug, Default)]
pub struct Progress {
    /// Units of work finished: members (Monte Carlo), updates (CCSP), output times
    /// reached (propagate).
    pub done: AtomicUsize,
    /// Set to stop the run; it then returns [`CoreError::Cancelled`].
    pub cancel: AtomicBool,
}

impl Progress {
    /// Counts `n` more units of work done.
    #[inline]
    pub fn add(&self, n: usize) {
        self.done.fetch_add(n, Ordering::Relaxed);
    }

    /// [`CoreError::Cancelled`] once the caller has asked to stop.
    #[inline]
    pub fn check(&self) -> Result<(), CoreError> {
        if self.cancel.load(Ordering::Relaxed) {
            Err(CoreError::Cancelled)
        } else {
            Ok(())
        }
    }
}
