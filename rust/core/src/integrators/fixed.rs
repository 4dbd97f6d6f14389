//! Fixed-step explicit Runge-Kutta: classic RK4 and the 8th-order DOP853 tableau.

use super::dop853_tableau as tab;
use super::{check_times, Control, Outcome};
use crate::dynamics::{BatchRhs, State};
use crate::error::{positive, CoreError};

/// Fixed-step scheme.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum FixedMethod {
    /// Classic 4th-order Runge-Kutta, 4 RHS evaluations per step.
    Rk4,
    /// 8th-order Dormand-Prince (DOP853 tableau without its error estimate), 12 RHS
    /// evaluations per step.
    Rk8,
}

/// Stage workspace for one batch, reused for every step.
pub struct FixedStepper<const W: usize> {
    k: [State<W>; 12],
    tmp: State<W>,
}

impl<const W: usize> Default for FixedStepper<W> {
    fn default() -> Self {
        Self {
            k: [[[0.0; W]; 6]; 12],
            tmp: [[0.0; W]; 6],
        }
    }
}

/// tmp = y + h * sum_j coef[j] * k[j] over the stages whose coefficient is not zero.
#[inline(always)]
fn combine<const W: usize>(tmp: &mut State<W>, y: &State<W>, h: f64, coef: &[f64], k: &[State<W>]) {
    *tmp = *y;
    for (j, &a) in coef.iter().enumerate() {
        if a != 0.0 {
            let ha = h * a;
            for c in 0..6 {
                for l in 0..W {
                    tmp[c][l] += ha * k[j][c][l];
                }
            }
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
                for s in 1..12 {
                    combine(&mut self.tmp, y, h, &tab::A[s][..s], &self.k[..s]);
                    rhs.eval(t + tab::C[s] * h, &self.tmp, &mut self.k[s])?;
                }
                combine(&mut self.tmp, y, h, &tab::B, &self.k[..12]);
            }
        }
        *y = self.tmp;
        Ok(())
    }
}

/// Integrates from `t0` through the increasing `stops`, never with a step longer than
/// `max_step`, and with every stop a step boundary: each interval between stops is cut
/// into the fewest equal steps no longer than `max_step`. `on_stop(i, y)` receives the
/// state at `stops[i]`; `after_step(t, y)` is called after every step and may stop the run.
#[allow(clippy::too_many_arguments)]
pub fn integrate_fixed<const W: usize, R: BatchRhs<W>>(
    method: FixedMethod,
    rhs: &mut R,
    t0: f64,
    y: &mut State<W>,
    max_step: f64,
    stops: &[f64],
    mut on_stop: impl FnMut(usize, &State<W>),
    mut after_step: impl FnMut(f64, &State<W>) -> Control,
) -> Result<Outcome, CoreError> {
    positive("step", max_step)?;
    // Backward integration when the stops run backwards from t0 (e.g. drag-coefficient
    // debiasing over a window before the epoch).
    let backward = stops.last().is_some_and(|&s| s < t0);
    if backward {
        let mirrored: Vec<f64> = stops.iter().map(|s| -s).collect();
        check_times("stop times (backward)", -t0, &mirrored)?;
    } else {
        check_times("stop times", t0, stops)?;
    }
    let mut stepper = FixedStepper::<W>::default();
    let mut t = t0;
    for (i, &t1) in stops.iter().enumerate() {
        let span = t1 - t;
        if span != 0.0 {
            // Relative slack so that a span of exactly k steps is not cut into k + 1.
            let n = ((span.abs() / max_step) * (1.0 - 1e-12)).ceil().max(1.0) as usize;
            let h = span / n as f64;
            for j in 0..n {
                let ts = t + j as f64 * h;
                stepper.step(method, rhs, ts, h, y)?;
                let te = if j + 1 == n {
                    t1
                } else {
                    t + (j + 1) as f64 * h
                };
                if after_step(te, y) == Control::Stop {
                    return Ok(Outcome::Stopped { t: te });
                }
            }
            t = t1;
        }
        on_stop(i, y);
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

    fn error_after(method: FixedMethod, h: f64) -> f64 {
        let mut y: State<1> = [[1.0], [0.0], [0.0], [0.0], [0.0], [0.0]];
        integrate_fixed(
            method,
            &mut Oscillator,
            0.0,
            &mut y,
            h,
            &[10.0],
            |_, _| {},
            |_, _| Control::Continue,
        )
        .unwrap();
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
        let mut seen = Vec::new();
        integrate_fixed(
            FixedMethod::Rk8,
            &mut Oscillator,
            0.0,
            &mut y,
            0.1,
            &[-1.0, -3.0],
            |_, y| seen.push(y[0][0]),
            |_, _| Control::Continue,
        )
        .unwrap();
        assert!((seen[0] - 1f64.cos()).abs() < 1e-12 && (seen[1] - 3f64.cos()).abs() < 1e-12);
        assert!((y[3][0] - 3f64.sin()).abs() < 1e-12); // v(-3) = -sin(-3)
    }

    #[test]
    fn stops_are_step_boundaries() {
        let mut seen = Vec::new();
        let mut y: State<1> = [[1.0], [0.0], [0.0], [0.0], [0.0], [0.0]];
        let mut steps = Vec::new();
        integrate_fixed(
            FixedMethod::Rk8,
            &mut Oscillator,
            0.0,
            &mut y,
            0.4,
            &[0.0, 1.0, 1.0, 2.2],
            |i, y| seen.push((i, y[0][0])),
            |t, _| {
                steps.push(t);
                Control::Continue
            },
        )
        .unwrap();
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
            integrate_fixed(
                FixedMethod::Rk4,
                &mut Oscillator,
                0.0,
                y,
                h,
                stops,
                |_, _| {},
                |_, _| Control::Continue,
            )
        };
        assert!(run(&mut y, 0.0, &[1.0]).is_err());
        assert!(run(&mut y, 0.1, &[1.0, 0.5]).is_err());
        assert!(run(&mut y, 0.1, &[-1.0, -0.5]).is_err());
        assert!(run(&mut y, 0.1, &[f64::NAN]).is_err());
        assert!(run(&mut y, 0.1, &[]).is_err());
    }
}
