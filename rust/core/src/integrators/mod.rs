//! Integrators for batch ODEs ([`crate::dynamics::BatchRhs`]): fixed-step RK4 and RK8 (the
//! 8th-order Dormand-Prince DOP853 tableau) for stochastic runs, where kappa nodes must be
//! step boundaries, and adaptive DOP853 with 7th-order dense output for deterministic runs.
//! Workspaces are allocated once per integration; nothing allocates inside the step loop.
//!
//! Every fixed-step run (`propagate` with rk4/rk8, Monte Carlo batches, CCSP sigma points)
//! goes through the one loop [`drive`] over a [`StepPlan`]; callers add behaviour through
//! [`StepHooks`], which the adaptive integrator accepts too.

mod adaptive;
pub mod dop853_tableau;
mod fixed;

pub use adaptive::{integrate_adaptive, AdaptiveOptions};
pub use fixed::{drive, FixedMethod, FixedStepper, StepPlan, MAX_STEPS};

use crate::dynamics::State;
use crate::error::CoreError;

/// What the caller wants after a step.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Control {
    Continue,
    /// Stop the integration here; later outputs are not produced (e.g. a decayed orbit).
    Stop,
    /// Stop stepping and hand the current state to every remaining output, each at its
    /// own time (e.g. every member of a batch has decayed and is frozen).
    Hold,
}

/// Observers and actions around the steps of an integration. Every method defaults to
/// doing nothing, so `()` observes nothing. `R` is the right-hand side being integrated.
pub trait StepHooks<const W: usize, R: ?Sized> {
    /// Before the fixed step that starts at step boundary `boundary` (0 = the start) at
    /// time `t`; `grid` is the boundary's index on the uniform grid of a
    /// [`StepPlan::grid`] plan. Not called by the adaptive integrator.
    #[inline(always)]
    fn before_step(&mut self, boundary: usize, t: f64, grid: Option<usize>, rhs: &mut R) {
        let _ = (boundary, t, grid, rhs);
    }

    /// After every (accepted) step, ending at `t` in state `y`.
    #[inline(always)]
    fn after_step(&mut self, t: f64, y: &mut State<W>, rhs: &mut R) -> Result<Control, CoreError> {
        let _ = (t, y, rhs);
        Ok(Control::Continue)
    }

    /// The state `y` at output `i`, time `t`.
    #[inline(always)]
    fn on_output(&mut self, i: usize, t: f64, y: &State<W>, rhs: &R) -> Result<(), CoreError> {
        let _ = (i, t, y, rhs);
        Ok(())
    }
}

impl<const W: usize, R: ?Sized> StepHooks<W, R> for () {}

/// Runge-Kutta stage arithmetic: out = y + h * sum_j coef[j] * k[j], skipping zero
/// coefficients (the tableaus are sparse). Each component's sum runs in a local
/// accumulator over the nonzero coefficients in order, so that it stays in registers:
/// summing into `out` pass by pass made every pass wait for the previous one's store
/// (with 8 lanes that chain cost a third of an exponential-atmosphere Monte Carlo). Same
/// additions in the same order either way, so the same bits.
#[inline(always)]
pub(crate) fn combine<const W: usize>(
    out: &mut State<W>,
    y: &State<W>,
    h: f64,
    coef: &[f64],
    k: &[State<W>],
) {
    const MAX: usize = 16;
    assert!(coef.len() <= MAX && coef.len() <= k.len());
    let (mut js, mut has, mut n) = ([0usize; MAX], [0.0; MAX], 0);
    for (j, &a) in coef.iter().enumerate() {
        if a != 0.0 {
            (js[n], has[n]) = (j, h * a);
            n += 1;
        }
    }
    for c in 0..6 {
        let mut acc = y[c];
        for q in 0..n {
            let (kj, ha) = (&k[js[q]][c], has[q]);
            for l in 0..W {
                acc[l] += ha * kj[l];
            }
        }
        out[c] = acc;
    }
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
