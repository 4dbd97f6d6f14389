//! The fixed-step schemes, classic RK4, the 8th-order DOP853 tableau (RK8) and
//! Adams-Bashforth-Moulton (ABM, started and restarted with RK8 steps), and the one
//! fixed-step loop of the crate: [`drive`] over a [`StepPlan`], shared by propagate, the
//! Monte Carlo and the CCSP. The schemes are arms of one `match` in the stepping loop so
//! that each batch's stage sums stay in registers (same additions, same order on every
//! SIMD path).

use super::dop853_tableau as tab;
use super::{check_times, combine, Control, Outcome, StepHooks};
use crate::dynamics::{BatchRhs, State};
use crate::error::{positive, CoreError};
use std::ops::Range;

/// Fixed-step scheme.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum FixedMethod {
    /// Classic 4th-order Runge-Kutta, 4 RHS evaluations per step.
    Rk4,
    /// 8th-order Dormand-Prince (DOP853 tableau without its error estimate), 12 RHS
    /// evaluations per step.
    Rk8,
    /// Adams-Bashforth-Moulton predict-evaluate-correct-evaluate with [`ABM_STEPS`]
    /// back values (Adams-Bashforth of that order predicts, Adams-Moulton one order higher
    /// corrects): 2 RHS evaluations per step. It starts, and restarts wherever the step
    /// size changes or the right-hand side jumps (a kappa node), with RK8 steps; so it pays
    /// where the force is smooth over many steps (deterministic ensembles, held kappa).
    Abm,
}

impl FixedMethod {
    /// The names of the fixed-step schemes, as the binding and Python spell them.
    pub const NAMES: [&'static str; 3] = ["rk8", "rk4", "abm"];

    /// The scheme named `name` (one of [`FixedMethod::NAMES`]).
    pub fn from_name(name: &str) -> Result<Self, CoreError> {
        match name {
            "rk8" => Ok(Self::Rk8),
            "rk4" => Ok(Self::Rk4),
            "abm" => Ok(Self::Abm),
            other => Err(CoreError::UnknownName {
                what: "fixed-step integrator",
                name: other.to_string(),
                expected: &Self::NAMES,
            }),
        }
    }
}

/// Back values of the multistep method.
pub const ABM_STEPS: usize = 10;

/// Adams-Bashforth (`ab`, weights of f_n, f_{n-1}, ...) and Adams-Moulton (`am`, weights of
/// f_{n+1}, f_n, ...) coefficients from the backward-difference series (Hairer, Norsett &
/// Wanner I, III.1): gamma_i = 1 - sum_j gamma_j / (i + 1 - j), gamma*_i = -sum_j
/// gamma*_j / (i + 1 - j), beta_j = (-1)^j sum_{i >= j} gamma_i C(i, j).
fn adams_coefficients() -> ([f64; ABM_STEPS], [f64; ABM_STEPS + 1]) {
    let k = ABM_STEPS;
    let mut g = vec![0.0; k + 1];
    let mut gs = vec![0.0; k + 1];
    for i in 0..=k {
        let (mut a, mut b) = (0.0, 0.0);
        for j in 0..i {
            a += g[j] / (i + 1 - j) as f64;
            b += gs[j] / (i + 1 - j) as f64;
        }
        g[i] = 1.0 - a;
        gs[i] = if i == 0 { 1.0 } else { -b };
    }
    let binom = |n: usize, r: usize| (0..r).fold(1.0, |c, q| c * (n - q) as f64 / (q + 1) as f64);
    let sign = |j: usize| if j.is_multiple_of(2) { 1.0 } else { -1.0 };
    let ab = std::array::from_fn(|j| sign(j) * (j..k).map(|i| g[i] * binom(i, j)).sum::<f64>());
    let am = std::array::from_fn(|j| sign(j) * (j..=k).map(|i| gs[i] * binom(i, j)).sum::<f64>());
    (ab, am)
}

/// Back values of f for the multistep method, a ring: [`History::back`] `(j)` is the value
/// `j` steps back (a ring, not a shifted array: shifting moved nine batch states a step).
struct History<const W: usize> {
    f: [State<W>; ABM_STEPS],
    /// Slot of the newest value.
    head: usize,
    /// Values held.
    len: usize,
    /// Where the next step must start, its size and the RHS generation for the values
    /// to be usable.
    t_next: f64,
    h: f64,
    generation: u64,
    ab: [f64; ABM_STEPS],
    am: [f64; ABM_STEPS + 1],
}

impl<const W: usize> History<W> {
    fn push(&mut self, f: &State<W>) {
        self.head = (self.head + ABM_STEPS - 1) % ABM_STEPS;
        self.f[self.head] = *f;
        self.len = (self.len + 1).min(ABM_STEPS);
    }

    /// The value `j` steps back (0: the newest).
    #[inline(always)]
    fn back(&self, j: usize) -> &State<W> {
        &self.f[(self.head + j) % ABM_STEPS]
    }
}

/// Stage workspace for one batch, reused for every step; cache-line aligned with the
/// stage arrays first (see [`crate::dynamics::Dynamics`]).
#[repr(C, align(64))]
pub struct FixedStepper<const W: usize> {
    k: [State<W>; 12],
    tmp: State<W>,
    /// Back values of the multistep method (allocated on its first use).
    history: Option<Box<History<W>>>,
}

impl<const W: usize> Default for FixedStepper<W> {
    fn default() -> Self {
        Self {
            k: [[[0.0; W]; 6]; 12],
            tmp: [[0.0; W]; 6],
            history: None,
        }
    }
}

impl<const W: usize> FixedStepper<W> {
    /// Advances `y` from `t` by one step `h`.
    #[inline(always)]
    pub fn step<R: BatchRhs<W>>(
        &mut self,
        method: FixedMethod,
        rhs: &mut R,
        t: f64,
        h: f64,
        y: &mut State<W>,
    ) -> Result<(), CoreError> {
        match method {
            FixedMethod::Rk4 => {
                const A: [f64; 4] = [0.0, 0.5, 0.5, 1.0];
                const B: [f64; 4] = [1.0 / 6.0, 1.0 / 3.0, 1.0 / 3.0, 1.0 / 6.0];
                rhs.eval(t, y, &mut self.k[0])?;
                for s in 1..4 {
                    let mut coef = [0.0; 3];
                    coef[s - 1] = A[s];
                    combine(&mut self.tmp, y, h, &coef[..s], &self.k[..s]);
                    rhs.eval(t + A[s] * h, &self.tmp, &mut self.k[s])?;
                }
                combine(&mut self.tmp, y, h, &B, &self.k[..4]);
            }
            FixedMethod::Rk8 => {
                rhs.eval(t, y, &mut self.k[0])?;
                self.rk8_stages(rhs, t, h, y)?;
            }
            FixedMethod::Abm => return self.abm_step(rhs, t, h, y),
        }
        *y = self.tmp;
        Ok(())
    }

    /// RK8 stages 2..12 and the combination into `tmp`, with k[0] = f(t, y) given.
    #[inline(always)]
    fn rk8_stages<R: BatchRhs<W>>(
        &mut self,
        rhs: &mut R,
        t: f64,
        h: f64,
        y: &State<W>,
    ) -> Result<(), CoreError> {
        for s in 1..12 {
            combine(&mut self.tmp, y, h, &tab::A[s][..s], &self.k[..s]);
            rhs.eval(t + tab::C[s] * h, &self.tmp, &mut self.k[s])?;
        }
        combine(&mut self.tmp, y, h, &tab::B, &self.k[..12]);
        Ok(())
    }

    /// One Adams-Bashforth-Moulton PECE step, or an RK8 starting step while fewer than
    /// [`ABM_STEPS`] back values are valid for this step size and right-hand side.
    #[inline(always)]
    fn abm_step<R: BatchRhs<W>>(
        &mut self,
        rhs: &mut R,
        t: f64,
        h: f64,
        y: &mut State<W>,
    ) -> Result<(), CoreError> {
        let hist = self.history.get_or_insert_with(|| {
            let (ab, am) = adams_coefficients();
            Box::new(History {
                f: [[[0.0; W]; 6]; ABM_STEPS],
                head: 0,
                len: 0,
                t_next: f64::NAN,
                h: f64::NAN,
                generation: 0,
                ab,
                am,
            })
        });
        let tol = 1e-9 * h.abs().max(t.abs()).max(1.0);
        if !((t - hist.t_next).abs() <= tol && h == hist.h && rhs.generation() == hist.generation) {
            hist.len = 0;
        }
        if hist.len == 0 {
            rhs.eval(t, y, &mut self.k[0])?;
            hist.push(&self.k[0]);
        }
        if hist.len < ABM_STEPS {
            // Start-up: an RK8 step whose first stage is the newest back value.
            self.k[0] = *hist.back(0);
            self.rk8_stages(rhs, t, h, y)?;
            *y = self.tmp;
            rhs.eval(t + h, y, &mut self.k[0])?;
        } else {
            // Predict (Adams-Bashforth), evaluate, correct (Adams-Moulton), evaluate.
            // Each component's sum in a local accumulator, in the same order as a pass
            // per coefficient would add (see `combine`).
            let (ab, am) = (hist.ab, hist.am);
            let mut pred = *y;
            for c in 0..6 {
                let mut acc = y[c];
                for (j, &b) in ab.iter().enumerate() {
                    let (hb, fj) = (h * b, &hist.back(j)[c]);
                    for l in 0..W {
                        acc[l] += hb * fj[l];
                    }
                }
                pred[c] = acc;
            }
            rhs.eval(t + h, &pred, &mut self.k[1])?;
            let mut corr = *y;
            for c in 0..6 {
                let mut acc = y[c];
                for l in 0..W {
                    acc[l] += h * am[0] * self.k[1][c][l];
                }
                for (j, &b) in am[1..].iter().enumerate() {
                    let (hb, fj) = (h * b, &hist.back(j)[c]);
                    for l in 0..W {
                        acc[l] += hb * fj[l];
                    }
                }
                corr[c] = acc;
            }
            *y = corr;
            rhs.eval(t + h, y, &mut self.k[0])?;
        }
        let hist = self.history.as_mut().expect("set above");
        hist.push(&self.k[0]);
        hist.t_next = t + h;
        hist.h = h;
        hist.generation = rhs.generation();
        Ok(())
    }
}

/// Most steps one run may take: beyond it a step is far too small for the span (a plan of
/// grid steps also holds one entry per step, so this bounds its memory to ~0.6 GB).
pub const MAX_STEPS: usize = 10_000_000;

/// An error for a run of `steps` steps, over [`MAX_STEPS`].
fn too_many_steps(steps: f64, step: f64) -> CoreError {
    CoreError::invalid(
        "step",
        step,
        format!(
            "gives {steps:.3e} steps over the span, more than the {MAX_STEPS} a run may take; \
             use a larger step (or kappa node spacing)"
        ),
    )
}

/// `n` equal steps of `h` from `start`, the last ending exactly at `end`.
#[derive(Debug, Clone, PartialEq)]
struct Segment {
    start: f64,
    end: f64,
    n: usize,
    h: f64,
    /// Grid index of the boundary at `start` ([`StepPlan::grid`] plans).
    grid: Option<usize>,
    /// The outputs that fall on `end`.
    outputs: Range<usize>,
}

/// The step boundaries of a fixed-step run and the outputs that fall on them. Outputs are
/// always step boundaries; each knows its contiguous range of outputs, so recording costs
/// O(outputs) in all. Stored as segments of equal steps, so memory grows with the outputs
/// (and, for grid plans, with the grid steps), never with the steps of an interval.
#[derive(Debug, Clone, PartialEq)]
pub struct StepPlan {
    t0: f64,
    /// Outputs at `t0`.
    initial: Range<usize>,
    segments: Vec<Segment>,
    /// Grid index of the last boundary.
    last_grid: Option<usize>,
}

impl StepPlan {
    /// From `t0` through the `stops` (the outputs), never with a step longer than
    /// `max_step`: each interval between stops is cut into the fewest equal steps no longer
    /// than `max_step`. Stops running backwards from `t0` integrate backwards (e.g.
    /// drag-coefficient debiasing over a window before the epoch).
    pub fn equal_steps(t0: f64, stops: &[f64], max_step: f64) -> Result<Self, CoreError> {
        positive("step", max_step)?;
        let backward = stops.last().is_some_and(|&s| s < t0);
        if backward {
            let mirrored: Vec<f64> = stops.iter().map(|s| -s).collect();
            check_times("stop times (backward)", -t0, &mirrored)?;
        } else {
            check_times("stop times", t0, stops)?;
        }
        let mut plan = Self {
            t0,
            initial: 0..0,
            segments: Vec::with_capacity(stops.len()),
            last_grid: None,
        };
        let total = (stops.last().map_or(0.0, |&s| (s - t0).abs()) / max_step).ceil();
        if total + stops.len() as f64 > MAX_STEPS as f64 {
            return Err(too_many_steps(total, max_step));
        }
        let mut t = t0;
        for (i, &t1) in stops.iter().enumerate() {
            let span = t1 - t;
            if span != 0.0 {
                // Relative slack so that a span of exactly k steps is not cut into k + 1.
                let n = ((span.abs() / max_step) * (1.0 - 1e-12)).ceil().max(1.0) as usize;
                plan.segments.push(Segment {
                    start: t,
                    end: t1,
                    n,
                    h: span / n as f64,
                    grid: None,
                    outputs: i..i + 1,
                });
                t = t1;
            } else {
                plan.last_outputs().end = i + 1;
            }
        }
        Ok(plan)
    }

    /// From 0 through the increasing `outputs` (s, checked here) on the uniform grid k h
    /// (where kappa nodes fall) plus every output time, so outputs need not be multiples of
    /// the step. Boundaries closer than 1e-9 max(h, 1) merge, keeping the grid time.
    pub fn grid(outputs: &[f64], h: f64) -> Result<Self, CoreError> {
        check_times("output times", 0.0, outputs)?;
        positive("step", h)?;
        let end = *outputs.last().expect("checked non-empty");
        let steps = ((end / h) * (1.0 - 1e-12)).ceil().max(0.0);
        if steps + outputs.len() as f64 > MAX_STEPS as f64 {
            return Err(too_many_steps(steps, h));
        }
        let n = steps as usize;
        let mut points: Vec<(f64, Option<usize>)> = (0..=n)
            .map(|k| (if k == n { end } else { k as f64 * h }, Some(k)))
            .collect();
        points.extend(outputs.iter().map(|&t| (t, None)));
        points.sort_by(|a, b| a.0.total_cmp(&b.0));
        let tol = 1e-9 * h.max(1.0);
        let mut times: Vec<f64> = Vec::with_capacity(points.len());
        let mut grid: Vec<Option<usize>> = Vec::with_capacity(points.len());
        for (t, k) in points {
            match times.last() {
                Some(&last) if (t - last).abs() <= tol => {
                    let g = grid.last_mut().expect("same length");
                    if g.is_none() {
                        *g = k;
                        if k.is_some() {
                            *times.last_mut().expect("same length") = t;
                        }
                    }
                }
                _ => {
                    times.push(t);
                    grid.push(k);
                }
            }
        }
        let mut plan = Self {
            t0: times[0],
            initial: 0..0,
            segments: (1..times.len())
                .map(|j| Segment {
                    start: times[j - 1],
                    end: times[j],
                    n: 1,
                    h: times[j] - times[j - 1],
                    grid: grid[j - 1],
                    outputs: 0..0,
                })
                .collect(),
            last_grid: grid[times.len() - 1],
        };
        // Boundary of each output: non-decreasing, so each boundary's outputs are a range.
        for (i, &t) in outputs.iter().enumerate() {
            let b = times.partition_point(|&x| x < t - tol).min(times.len() - 1);
            let range = if b == 0 {
                &mut plan.initial
            } else {
                &mut plan.segments[b - 1].outputs
            };
            if range.start == range.end {
                *range = i..i;
            }
            range.end = i + 1;
        }
        Ok(plan)
    }

    /// The time the plan starts at.
    pub fn start(&self) -> f64 {
        self.t0
    }

    /// The outputs on the last boundary so far.
    fn last_outputs(&mut self) -> &mut Range<usize> {
        match self.segments.last_mut() {
            Some(s) => &mut s.outputs,
            None => &mut self.initial,
        }
    }

    /// Boundary times, their grid indices and the boundary of each output, one entry per
    /// step boundary (for inspection in tests).
    #[cfg(test)]
    fn boundaries(&self) -> (Vec<f64>, Vec<Option<usize>>, Vec<usize>) {
        let mut times = vec![self.t0];
        let mut grid = Vec::new();
        let mut outputs = vec![0; self.initial.len()];
        for s in &self.segments {
            for j in 0..s.n {
                grid.push(if j == 0 { s.grid } else { None });
                times.push(if j + 1 == s.n {
                    s.end
                } else {
                    s.start + (j + 1) as f64 * s.h
                });
            }
            outputs.extend(s.outputs.clone().map(|_| times.len() - 1));
        }
        grid.push(self.last_grid);
        (times, grid, outputs)
    }
}

/// The one fixed-step loop: integrates `y` through `plan` with `method`. Per step it calls
/// `hooks.before_step`, takes the step, then `hooks.after_step` (which may stop or hold
/// the run), then `hooks.on_output` for the outputs on the boundary reached. The step
/// arithmetic (start t + j h, length h, last end exactly the interval end) is fixed here
/// so that every caller gets bit-identical steps.
#[inline(always)]
pub fn drive<const W: usize, R: BatchRhs<W>, H: StepHooks<W, R>>(
    method: FixedMethod,
    rhs: &mut R,
    y: &mut State<W>,
    plan: &StepPlan,
    hooks: &mut H,
) -> Result<Outcome, CoreError> {
    let mut stepper = FixedStepper::<W>::default();
    for i in plan.initial.clone() {
        hooks.on_output(i, plan.t0, y, rhs)?;
    }
    let mut boundary = 0;
    for (s, seg) in plan.segments.iter().enumerate() {
        for j in 0..seg.n {
            let ts = seg.start + j as f64 * seg.h;
            hooks.before_step(boundary, ts, if j == 0 { seg.grid } else { None }, rhs);
            stepper.step(method, rhs, ts, seg.h, y)?;
            boundary += 1;
            let te = if j + 1 == seg.n {
                seg.end
            } else {
                seg.start + (j + 1) as f64 * seg.h
            };
            match hooks.after_step(te, y, rhs)? {
                Control::Continue => {}
                Control::Stop => return Ok(Outcome::Stopped { t: te }),
                Control::Hold => {
                    for later in &plan.segments[s..] {
                        for i in later.outputs.clone() {
                            hooks.on_output(i, later.end, y, rhs)?;
                        }
                    }
                    return Ok(Outcome::Stopped { t: te });
                }
            }
        }
        for i in seg.outputs.clone() {
            hooks.on_output(i, seg.end, y, rhs)?;
        }
    }
    Ok(Outcome::Completed)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Harmonic oscillator x'' = -x in lanes: y = (x, 0, 0, v, 0, 0).
    struct Oscillator;
    impl<const W: usize> BatchRhs<W> for Oscillator {
        fn eval(&mut self, _t: f64, y: &State<W>, dy: &mut State<W>) -> Result<(), CoreError> {
            for l in 0..W {
                dy[0][l] = y[3][l];
                dy[3][l] = -y[0][l];
                for c in [1, 2, 4, 5] {
                    dy[c][l] = 0.0;
                }
            }
            Ok(())
        }
    }

    /// Records the outputs (index, x) and the step end times.
    #[derive(Default)]
    struct Seen {
        outputs: Vec<(usize, f64)>,
        steps: Vec<f64>,
    }
    impl<R> StepHooks<1, R> for Seen {
        fn after_step(
            &mut self,
            t: f64,
            _: &mut State<1>,
            _: &mut R,
        ) -> Result<Control, CoreError> {
            self.steps.push(t);
            Ok(Control::Continue)
        }
        fn on_output(&mut self, i: usize, _: f64, y: &State<1>, _: &R) -> Result<(), CoreError> {
            self.outputs.push((i, y[0][0]));
            Ok(())
        }
    }

    fn integrate(
        method: FixedMethod,
        y: &mut State<1>,
        h: f64,
        stops: &[f64],
        hooks: &mut impl StepHooks<1, Oscillator>,
    ) -> Result<Outcome, CoreError> {
        let plan = StepPlan::equal_steps(0.0, stops, h)?;
        drive(method, &mut Oscillator, y, &plan, hooks)
    }

    fn error_after(method: FixedMethod, h: f64) -> f64 {
        let mut y: State<1> = [[1.0], [0.0], [0.0], [0.0], [0.0], [0.0]];
        integrate(method, &mut y, h, &[10.0], &mut ()).unwrap();
        ((y[0][0] - 10f64.cos()).powi(2) + (y[3][0] + 10f64.sin()).powi(2)).sqrt()
    }

    #[test]
    fn rk4_is_fourth_order() {
        let ratio = error_after(FixedMethod::Rk4, 0.1) / error_after(FixedMethod::Rk4, 0.05);
        assert!(
            (ratio.log2() - 4.0).abs() < 0.1,
            "observed order {}",
            ratio.log2()
        );
    }

    #[test]
    fn rk8_is_eighth_order() {
        let ratio = error_after(FixedMethod::Rk8, 1.0) / error_after(FixedMethod::Rk8, 0.5);
        assert!(
            (ratio.log2() - 8.0).abs() < 0.3,
            "observed order {}",
            ratio.log2()
        );
        assert!(error_after(FixedMethod::Rk8, 0.25) < 1e-9);
    }

    #[test]
    fn adams_coefficients_are_the_textbook_ones() {
        // Each family's weights sum to 1 (exact for f = const); AB2 = (3/2, -1/2) and
        // AM with two points is the trapezoid, from the same recursion at lower order.
        let (ab, am) = adams_coefficients();
        assert!((ab.iter().sum::<f64>() - 1.0).abs() < 1e-12);
        assert!((am.iter().sum::<f64>() - 1.0).abs() < 1e-12);
        // Exact for polynomials up to degree ABM_STEPS - 1 (AB) and ABM_STEPS (AM):
        // integrate f(t) = t^q over [0, 1] from nodes 0, -1, -2, ... (and 1 for AM).
        for q in 0..ABM_STEPS as i32 {
            let exact = 1.0 / (q + 1) as f64;
            // Tolerance: rounding of sums whose terms reach ~10^q.
            let scale: f64 = (0..=ABM_STEPS).map(|j| (j as f64).powi(q)).sum::<f64>() * 1e-13;
            let b: f64 = (0..ABM_STEPS).map(|j| ab[j] * (-(j as f64)).powi(q)).sum();
            assert!((b - exact).abs() < scale.max(1e-13), "AB q = {q}: {b}");
            let m: f64 = (0..=ABM_STEPS)
                .map(|j| am[j] * (1.0 - j as f64).powi(q))
                .sum();
            assert!((m - exact).abs() < scale.max(1e-13), "AM q = {q}: {m}");
        }
    }

    #[test]
    fn abm_converges_at_high_order_and_restarts_on_jumps() {
        let e1 = error_after(FixedMethod::Abm, 0.2);
        let e2 = error_after(FixedMethod::Abm, 0.1);
        let order = (e1 / e2).log2();
        assert!(order > 9.0, "observed order {order} ({e1}, {e2})");
        assert!(e2 < 1e-10, "{e2}");
    }

    #[test]
    fn tableau_order_conditions() {
        // Row sums equal the nodes, and the weights satisfy sum b c^(q-1) = 1/q, q <= 8.
        for s in 0..16 {
            let row: f64 = tab::A[s].iter().sum();
            assert!((row - tab::C[s]).abs() < 1e-13, "row {s}");
        }
        for q in 1..=8 {
            let sum: f64 = (0..12).map(|i| tab::B[i] * tab::C[i].powi(q - 1)).sum();
            assert!((sum - 1.0 / q as f64).abs() < 1e-13, "q = {q}: {sum}");
        }
    }

    #[test]
    fn backward_integration_retraces_the_solution() {
        let mut y: State<1> = [[1.0], [0.0], [0.0], [0.0], [0.0], [0.0]];
        let mut hooks = Seen::default();
        integrate(FixedMethod::Rk8, &mut y, 0.1, &[-1.0, -3.0], &mut hooks).unwrap();
        let seen: Vec<f64> = hooks.outputs.iter().map(|o| o.1).collect();
        assert!((seen[0] - 1f64.cos()).abs() < 1e-12 && (seen[1] - 3f64.cos()).abs() < 1e-12);
        assert!((y[3][0] - 3f64.sin()).abs() < 1e-12); // v(-3) = -sin(-3)
    }

    #[test]
    fn stops_are_step_boundaries() {
        let mut y: State<1> = [[1.0], [0.0], [0.0], [0.0], [0.0], [0.0]];
        let mut hooks = Seen::default();
        integrate(
            FixedMethod::Rk8,
            &mut y,
            0.4,
            &[0.0, 1.0, 1.0, 2.2],
            &mut hooks,
        )
        .unwrap();
        let Seen {
            outputs: seen,
            steps,
        } = hooks;
        // 0 -> 1 in 3 steps of 1/3, 1 -> 2.2 in 3 steps of 0.4.
        assert_eq!(steps.len(), 6);
        assert_eq!(steps[2], 1.0);
        assert_eq!(steps[5], 2.2);
        assert_eq!(seen.len(), 4);
        assert!((seen[3].1 - 2.2f64.cos()).abs() < 1e-9);
        assert_eq!(seen[1].1, seen[2].1);
    }

    #[test]
    fn bad_times_are_rejected() {
        let mut y: State<1> = [[1.0], [0.0], [0.0], [0.0], [0.0], [0.0]];
        let run = |y: &mut State<1>, h: f64, stops: &[f64]| {
            integrate(FixedMethod::Rk4, y, h, stops, &mut ())
        };
        assert!(run(&mut y, 0.0, &[1.0]).is_err());
        assert!(run(&mut y, 0.1, &[1.0, 0.5]).is_err());
        assert!(run(&mut y, 0.1, &[-1.0, -0.5]).is_err());
        assert!(run(&mut y, 0.1, &[f64::NAN]).is_err());
        assert!(run(&mut y, 0.1, &[]).is_err());
    }

    #[test]
    fn grid_plan_merges_outputs_into_the_grid() {
        let plan = StepPlan::grid(&[100.0, 360.0, 400.0], 180.0).unwrap();
        let (times, grid, outputs) = plan.boundaries();
        assert_eq!(times, vec![0.0, 100.0, 180.0, 360.0, 400.0]);
        assert_eq!(grid, vec![Some(0), None, Some(1), Some(2), Some(3)]);
        assert_eq!(outputs, vec![1, 3, 4]);
        // Repeated outputs share their boundary; one on the start is recorded first.
        let plan = StepPlan::grid(&[0.0, 0.0, 180.0, 180.0, 1000.0], 180.0).unwrap();
        let (times, _, outputs) = plan.boundaries();
        assert_eq!(times.len(), 7);
        assert_eq!(outputs, vec![0, 0, 1, 1, 6]);
    }

    #[test]
    fn hold_hands_the_state_to_every_remaining_output() {
        struct HoldAfter(usize, Vec<(usize, f64, f64)>);
        impl<R> StepHooks<1, R> for HoldAfter {
            fn after_step(
                &mut self,
                _: f64,
                _: &mut State<1>,
                _: &mut R,
            ) -> Result<Control, CoreError> {
                self.0 -= 1;
                Ok(if self.0 == 0 {
                    Control::Hold
                } else {
                    Control::Continue
                })
            }
            fn on_output(
                &mut self,
                i: usize,
                t: f64,
                y: &State<1>,
                _: &R,
            ) -> Result<(), CoreError> {
                self.1.push((i, t, y[0][0]));
                Ok(())
            }
        }
        let mut y: State<1> = [[1.0], [0.0], [0.0], [0.0], [0.0], [0.0]];
        let mut hooks = HoldAfter(4, Vec::new());
        let out = integrate(FixedMethod::Rk4, &mut y, 0.5, &[1.0, 1.7, 3.0], &mut hooks).unwrap();
        // Steps end at 0.5, 1.0, 1.35, 1.7: held after the step onto 1.7.
        assert_eq!(out, Outcome::Stopped { t: 1.7 });
        let times: Vec<f64> = hooks.1.iter().map(|o| o.1).collect();
        assert_eq!(times, vec![1.0, 1.7, 3.0]);
        assert_eq!(hooks.1[1].2, hooks.1[2].2);
        assert_eq!(hooks.1[2].2, y[0][0]);
    }
}
