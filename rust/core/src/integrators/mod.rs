//! Integrators for batch ODEs ([`crate::dynamics::BatchRhs`]): fixed-step RK4 and RK8 (the
//! 8th-order Dormand-Prince DOP853 tableau) for stochastic runs, where kappa nodes must be
//! step boundaries, and adaptive DOP853 with 7th-order dense output for deterministic runs.
//! Workspaces are allocated once per integration; nothing allocates inside the step loop.

mod adaptive;
pub mod dop853_tableau;
mod fixed;

pub use adaptive::{integrate_adaptive, AdaptiveOptions};
pub use fixed::{integrate_fixed, FixedMethod, FixedStepper};

/// What the caller's step observer wants after each accepted step.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Control {
    Continue,
    /// Stop the integration here (e.g. every member has decayed).
    Stop,
}

/// How an integration ended.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Outcome {
    /// Reached the last output time.
    Completed,
    /// The observer stopped it after the step ending at `t`.
    Stopped { t: f64 },
}

/// Checks that output/stop times are finite, start at or after `t0` and never decrease.
pub fn check_times(name: &str, t0: f64, times: &[f64]) -> Result<(), crate::CoreError> {
    use crate::CoreError;
    if times.is_empty() {
        return Err(CoreError::shape(name, "needs at least one time"));
    }
    let mut prev = t0;
    for (i, &t) in times.iter().enumerate() {
        if !t.is_finite() {
            return Err(CoreError::non_finite(format!("{name}[{i}]"), t));
        }
        if t < prev {
            return Err(CoreError::invalid(
                format!("{name}[{i}]"),
                t,
                format!("times must not decrease and must be >= {t0} (previous {prev})"),
            ));
        }
        prev = t;
    }
    Ok(())
}
