//! Adaptive DOP853 (Hairer, Norsett & Wanner) with its 7th-order dense output, for a
//! batch sharing one step size. The error norm is scaled per lane by the position and
//! velocity vector norms (`rtol * |r|`, `rtol * |v|`), which is rotation invariant and
//! never divides by a component that crosses zero.

use super::dop853_tableau as tab;
use super::{check_times, combine, Control, Outcome, StepHooks};
use crate::dynamics::{BatchRhs, State};
use crate::error::{positive, CoreError};

/// Settings of the adaptive integrator.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct AdaptiveOptions {
    /// Relative tolerance on |r| and |v| per step.
    pub rtol: f64,
    /// Largest step, s.
    pub max_step: f64,
    /// Largest number of attempted steps before giving up (a run may take more: see
    /// `steps_per_day`).
    pub max_steps: usize,
    /// Attempted steps a run may take per day of its span when that allows more than
    /// `max_steps`: a 10-year lifetime run of a LEO object needs about 2 million steps, and
    /// the guard is against steps that shrink without end, not against long runs.
    pub steps_per_day: f64,
}

impl Default for AdaptiveOptions {
    fn default() -> Self {
        Self {
            rtol: 1e-10,
            max_step: f64::INFINITY,
            max_steps: 1_000_000,
            // One per 10 s on average.
            steps_per_day: 8640.0,
        }
    }
}

fn zero<const W: usize>() -> State<W> {
    [[0.0; W]; 6]
}

/// Per-component error scales of a batch: rtol * max(|r_old|, |r_new|) on positions and
/// the same with velocities.
fn scales<const W: usize>(rtol: f64, a: &State<W>, b: &State<W>) -> State<W> {
    let mut s = zero::<W>();
    for l in 0..W {
        let n = |y: &State<W>, o: usize| {
            (y[o][l] * y[o][l] + y[o + 1][l] * y[o + 1][l] + y[o + 2][l] * y[o + 2][l]).sqrt()
        };
        let sr = rtol * n(a, 0).max(n(b, 0));
        let sv = rtol * n(a, 3).max(n(b, 3));
        for c in 0..3 {
            s[c][l] = sr.max(f64::MIN_POSITIVE);
            s[c + 3][l] = sv.max(f64::MIN_POSITIVE);
        }
    }
    s
}

/// RMS of x / scale over all components and lanes.
fn rms<const W: usize>(x: &State<W>, scale: &State<W>) -> f64 {
    let mut sum = 0.0;
    for c in 0..6 {
        for l in 0..W {
            let q = x[c][l] / scale[c][l];
            sum += q * q;
        }
    }
    (sum / (6 * W) as f64).sqrt()
}

/// Integrates `y0` from `t0` through the increasing `outputs`; `hooks.on_output` gets the
/// dense-output state at each output, `hooks.after_step` is called after every accepted
/// step and may stop or hold the run (it must not change `y` or the RHS here: the next
/// step reuses f(t, y)). `before_step` is not called: there are no planned boundaries.
pub fn integrate_adaptive<const W: usize, R: BatchRhs<W>, H: StepHooks<W, R>>(
    rhs: &mut R,
    t0: f64,
    y0: &State<W>,
    outputs: &[f64],
    opts: AdaptiveOptions,
    hooks: &mut H,
) -> Result<Outcome, CoreError> {
    positive("rtol", opts.rtol)?;
    if opts.rtol >= 1.0 {
        return Err(CoreError::invalid("rtol", opts.rtol, "must be < 1"));
    }
    if opts.max_step.is_nan() || opts.max_step <= 0.0 {
        return Err(CoreError::invalid("max_step", opts.max_step, "must be > 0"));
    }
    check_times("output times", t0, outputs)?;
    let t_end = *outputs.last().expect("checked non-empty");
    let span_days = (t_end - t0).abs() / 86400.0;
    let max_steps = opts
        .max_steps
        .max((opts.steps_per_day * span_days) as usize);

    let mut k: [State<W>; 16] = [zero::<W>(); 16];
    let mut tmp = zero::<W>();
    let mut y = *y0;
    let mut t = t0;
    let mut next_out = 0;
    while next_out < outputs.len() && outputs[next_out] <= t0 {
        hooks.on_output(next_out, outputs[next_out], &y, rhs)?;
        next_out += 1;
    }
    if next_out == outputs.len() {
        return Ok(Outcome::Completed);
    }

    rhs.eval(t, &y, &mut k[0])?;
    let mut h = initial_step(rhs, t, &y, &k[0], opts.rtol, &mut tmp)?.min(opts.max_step);
    let mut last_rejected = false;
    let mut attempts = 0usize;
    let watch = rhs.switch_step().is_finite();

    while t < t_end {
        attempts += 1;
        if attempts > max_steps {
            return Err(CoreError::TooManySteps {
                max_steps,
                t,
                end: t_end,
            });
        }
        // The last step lands on t_end exactly (below): t + (t_end - t) can round to just
        // short of t_end when t < t_end / 2, which left a step of 1e-13 s that underflowed
        // (a GEO object whose epoch lay 858.740832 s before the screening start).
        let last = t + h > t_end || t_end - (t + h) < 1e-12 * t_end.abs().max(1.0);
        if last {
            h = t_end - t;
        }
        if h <= 1e-12 * t.abs().max(1.0) {
            return Err(CoreError::StepUnderflow { t, h });
        }
        // Stages 1..11 (k[0] holds f(t, y) already).
        let side = if watch { rhs.sides(t, &y) } else { 0 };
        let mut switched = false;
        for s in 1..12 {
            combine(&mut tmp, &y, h, &tab::A[s][..s], &k[..s]);
            rhs.eval(t + tab::C[s] * h, &tmp, &mut k[s])?;
            switched |= watch && rhs.sides(t + tab::C[s] * h, &tmp) != side;
        }
        // 8th-order solution.
        let mut y_new = y;
        combine(&mut y_new, &y, h, &tab::B, &k[..12]);
        switched |= watch && rhs.sides(t + h, &y_new) != side;
        if switched && h > rhs.switch_step() {
            // A switch inside the step: retake it shorter, down to the switch step.
            h = (0.25 * h).max(rhs.switch_step());
            last_rejected = true;
            continue;
        }
        // Error estimate (Hairer's combination of the 5th and 3rd order estimators).
        let sc = scales(opts.rtol, &y, &y_new);
        let (mut e5, mut e3) = (zero::<W>(), zero::<W>());
        for c in 0..6 {
            for l in 0..W {
                for j in 0..12 {
                    e5[c][l] += tab::E5[j] * k[j][c][l];
                    e3[c][l] += tab::E3[j] * k[j][c][l];
                }
            }
        }
        let n5 = rms(&e5, &sc);
        let n3 = rms(&e3, &sc);
        let err = if n5 == 0.0 && n3 == 0.0 {
            0.0
        } else {
            h * n5 * n5 / (n5 * n5 + 0.01 * n3 * n3).sqrt()
        };
        if !err.is_finite() {
            return Err(CoreError::StepUnderflow { t, h });
        }
        if err > 1.0 {
            h *= (0.9 * err.powf(-1.0 / 8.0)).max(0.2);
            last_rejected = true;
            continue;
        }

        // Accepted: FSAL stage f(t + h, y_new) goes to k[12].
        let t_new = if last { t_end } else { t + h };
        rhs.eval(t_new, &y_new, &mut k[12])?;
        if next_out < outputs.len() && outputs[next_out] <= t_new {
            // Three extra stages for the dense output.
            for s in 13..16 {
                combine(&mut tmp, &y, h, &tab::A[s][..s], &k[..s]);
                rhs.eval(t + tab::C[s] * h, &tmp, &mut k[s])?;
            }
            let dense = DenseStep::new(&y, &y_new, h, &k);
            while next_out < outputs.len() && outputs[next_out] <= t_new {
                let x = (outputs[next_out] - t) / h;
                let yo = if outputs[next_out] == t_new {
                    y_new
                } else {
                    dense.eval(x)
                };
                hooks.on_output(next_out, outputs[next_out], &yo, rhs)?;
                next_out += 1;
            }
        }
        t = t_new;
        y = y_new;
        k[0] = k[12];
        match hooks.after_step(t, &mut y, rhs)? {
            Control::Continue => {}
            Control::Stop => return Ok(Outcome::Stopped { t }),
            Control::Hold => {
                for (i, &to) in outputs.iter().enumerate().skip(next_out) {
                    hooks.on_output(i, to, &y, rhs)?;
                }
                return Ok(Outcome::Stopped { t });
            }
        }
        let mut fac = if err == 0.0 {
            6.0
        } else {
            (0.9 * err.powf(-1.0 / 8.0)).clamp(0.333, 6.0)
        };
        if last_rejected {
            fac = fac.min(1.0);
        }
        last_rejected = false;
        h = (h * fac).min(opts.max_step);
    }
    Ok(Outcome::Completed)
}

/// Starting step from Hairer's heuristic (as in `dop853`'s `hinit`), for 8th order.
fn initial_step<const W: usize, R: BatchRhs<W>>(
    rhs: &mut R,
    t: f64,
    y: &State<W>,
    f0: &State<W>,
    rtol: f64,
    tmp: &mut State<W>,
) -> Result<f64, CoreError> {
    let sc = scales(rtol, y, y);
    let d0 = rms(y, &sc);
    let d1 = rms(f0, &sc);
    let h0 = if d0 < 1e-5 || d1 < 1e-5 {
        1e-6
    } else {
        0.01 * d0 / d1
    };
    let mut y1 = *y;
    for c in 0..6 {
        for l in 0..W {
            y1[c][l] += h0 * f0[c][l];
        }
    }
    rhs.eval(t + h0, &y1, tmp)?;
    let mut diff = zero::<W>();
    for c in 0..6 {
        for l in 0..W {
            diff[c][l] = tmp[c][l] - f0[c][l];
        }
    }
    let d2 = rms(&diff, &sc) / h0;
    let h1 = if d1.max(d2) <= 1e-15 {
        (h0 * 1e-3).max(1e-6)
    } else {
        (0.01 / d1.max(d2)).powf(1.0 / 8.0)
    };
    Ok((100.0 * h0).min(h1))
}

/// The 7th-order interpolant of one accepted step.
struct DenseStep<const W: usize> {
    y0: State<W>,
    f: [State<W>; 7],
}

impl<const W: usize> DenseStep<W> {
    fn new(y0: &State<W>, y1: &State<W>, h: f64, k: &[State<W>; 16]) -> Self {
        let mut f = [zero::<W>(); 7];
        for c in 0..6 {
            for l in 0..W {
                let dy = y1[c][l] - y0[c][l];
                let bspl = h * k[0][c][l] - dy;
                f[0][c][l] = dy;
                f[1][c][l] = bspl;
                f[2][c][l] = dy - h * k[12][c][l] - bspl;
                for (r, d) in tab::D.iter().enumerate() {
                    let mut s = 0.0;
                    for j in 0..16 {
                        s += d[j] * k[j][c][l];
                    }
                    f[3 + r][c][l] = h * s;
                }
            }
        }
        Self { y0: *y0, f }
    }

    /// State at the fraction `x` in [0, 1] of the step.
    fn eval(&self, x: f64) -> State<W> {
        let x1 = 1.0 - x;
        let mut out = zero::<W>();
        for c in 0..6 {
            for l in 0..W {
                let f = |i: usize| self.f[i][c][l];
                let p = f(3) + x * (f(4) + x1 * (f(5) + x * f(6)));
                out[c][l] = self.y0[c][l] + x * (f(0) + x1 * (f(1) + x * (f(2) + x1 * p)));
            }
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::constants::MU;

    /// Hooks from two closures: the output observer and the step observer.
    struct Observe<O, A>(O, A);
    impl<R, O: FnMut(usize, &State<1>), A: FnMut()> StepHooks<1, R> for Observe<O, A> {
        fn after_step(
            &mut self,
            _: f64,
            _: &mut State<1>,
            _: &mut R,
        ) -> Result<Control, CoreError> {
            (self.1)();
            Ok(Control::Continue)
        }
        fn on_output(&mut self, i: usize, _: f64, y: &State<1>, _: &R) -> Result<(), CoreError> {
            (self.0)(i, y);
            Ok(())
        }
    }

    /// Pure two-body RHS for analytic comparison.
    struct Kepler;
    impl BatchRhs<1> for Kepler {
        fn eval(&mut self, _t: f64, y: &State<1>, dy: &mut State<1>) -> Result<(), CoreError> {
            let r3 = (y[0][0] * y[0][0] + y[1][0] * y[1][0] + y[2][0] * y[2][0]).powf(1.5);
            for c in 0..3 {
                dy[c][0] = y[c + 3][0];
                dy[c + 3][0] = -MU * y[c][0] / r3;
            }
            Ok(())
        }
    }

    /// Circular equatorial orbit of radius a: position at time t.
    fn circular(a: f64, t: f64) -> [f64; 2] {
        let n = (MU / (a * a * a)).sqrt();
        [a * (n * t).cos(), a * (n * t).sin()]
    }

    #[test]
    fn kepler_circular_orbit_and_dense_output() {
        let a = 6_778_137.0;
        let v = (MU / a).sqrt();
        let y0: State<1> = [[a], [0.0], [0.0], [0.0], [v], [0.0]];
        let outputs: Vec<f64> = (0..=72)
            .map(|i| i as f64 * 3600.0 + 0.37 * i as f64)
            .collect();
        let mut worst: f64 = 0.0;
        let mut steps = 0;
        integrate_adaptive(
            &mut Kepler,
            0.0,
            &y0,
            &outputs,
            AdaptiveOptions {
                rtol: 1e-12,
                ..Default::default()
            },
            &mut Observe(
                |i, y: &State<1>| {
                    let p = circular(a, outputs[i]);
                    worst = worst.max(((y[0][0] - p[0]).powi(2) + (y[1][0] - p[1]).powi(2)).sqrt());
                },
                || steps += 1,
            ),
        )
        .unwrap();
        // Three days (~45 revolutions) at rtol 1e-12: dense output within 5 mm of the
        // analytic orbit (the global error of ~2000 steps of local error ~1e-12 |r|).
        assert!(
            worst < 5e-3,
            "worst dense-output error {worst} m over {steps} steps"
        );
    }

    #[test]
    fn tighter_tolerance_is_more_accurate() {
        let a = 7_000_000.0;
        let v = (MU / a).sqrt() * 1.1; // eccentric
        let y0: State<1> = [[a], [0.0], [0.0], [0.0], [v * 0.8], [v * 0.6]];
        let run = |rtol: f64| {
            let mut end = zero::<1>();
            integrate_adaptive(
                &mut Kepler,
                0.0,
                &y0,
                &[86400.0],
                AdaptiveOptions {
                    rtol,
                    ..Default::default()
                },
                &mut Observe(|_, y: &State<1>| end = *y, || {}),
            )
            .unwrap();
            end
        };
        let reference = run(1e-14);
        let err = |rtol: f64| {
            let e = run(rtol);
            ((e[0][0] - reference[0][0]).powi(2)
                + (e[1][0] - reference[1][0]).powi(2)
                + (e[2][0] - reference[2][0]).powi(2))
            .sqrt()
        };
        let (e8, e11) = (err(1e-8), err(1e-11));
        assert!(e11 < e8 / 50.0, "{e8} {e11}");
        assert!(e11 < 0.2, "{e11}");
    }

    #[test]
    fn rejects_bad_options() {
        let y0: State<1> = [[7e6], [0.0], [0.0], [0.0], [7.5e3], [0.0]];
        let run = |opts: AdaptiveOptions, out: &[f64]| {
            integrate_adaptive(&mut Kepler, 0.0, &y0, out, opts, &mut ())
        };
        assert!(run(
            AdaptiveOptions {
                rtol: 0.0,
                ..Default::default()
            },
            &[1.0]
        )
        .is_err());
        assert!(run(
            AdaptiveOptions {
                rtol: 2.0,
                ..Default::default()
            },
            &[1.0]
        )
        .is_err());
        let e = run(
            AdaptiveOptions {
                max_steps: 3,
                steps_per_day: 0.0,
                ..Default::default()
            },
            &[86400.0],
        )
        .unwrap_err();
        assert!(matches!(e, CoreError::TooManySteps { .. }));
    }
}
