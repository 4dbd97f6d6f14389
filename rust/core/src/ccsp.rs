//! The consider-covariance sigma-point (CCSP) filter of the paper (section 4), in the
//! form of DESIGN.md section 6: the augmented state is [r, v, kappa] with kappa the
//! normalised density offset (unit variance), which makes the units of the printed
//! block-Cholesky factor consistent (the paper's B has units of state in the density row;
//! we use the transposed off-diagonal block).
//!
//! Each sigma point carries its own kappa, held over an update interval, while the mean
//! and sigma of density follow its position and time. Because the cross-covariance enters
//! the factor unscaled while the state block is scaled by lambda1 + n, the carried
//! cross-covariance shrinks by 1 / (lambda2 + p) per update: the filter is the linearised
//! covariance of a kappa piecewise constant over each interval with correlation
//! 1 / (lambda2 + p) between consecutive intervals.

use crate::decay::{crossing, lane_step, may_cross_lanes};
use crate::density::Atmosphere;
use crate::dynamics::{Dynamics, Perturbation, State};
use crate::error::{finite, positive, CoreError};
use crate::integrators::{drive, Control, FixedMethod, StepHooks, StepPlan};
use crate::kappa::KappaLanes;
use crate::problem::Problem;
use crate::progress::Progress;
use crate::simd::{dispatch_on, Kernel, SimdPath};
use nalgebra::{Cholesky, Matrix6, SMatrix, Vector6};
use rayon::prelude::*;

/// Settings of a CCSP run.
#[derive(Debug, Clone)]
pub struct CcspConfig {
    /// Epoch, initial mean state, drag parameter and decay floor.
    pub problem: Problem,
    /// Initial 6x6 state covariance (row-major), positive definite.
    pub p0: [[f64; 6]; 6],
    /// Update times, s from the epoch: increasing, > 0; the last is the end.
    pub update_times: Vec<f64>,
    /// (lambda1 + n, lambda2 + p), both > 0; the paper uses (3, 3).
    pub scaling: (f64, f64),
    pub perturbation: Perturbation,
    pub method: FixedMethod,
    /// Largest integration step, s.
    pub max_step: f64,
}

/// Mean, covariance and state-kappa cross-covariance at every update time.
#[derive(Debug, Clone, PartialEq)]
pub struct CcspOutput {
    pub times: Vec<f64>,
    pub means: Vec<[f64; 6]>,
    pub covariances: Vec<[[f64; 6]; 6]>,
    pub cross: Vec<[f64; 6]>,
    /// When a sigma point first went below the floor altitude (s from the epoch): the
    /// filter stopped there and the outputs end at the last update before it.
    pub decayed_at: Option<f64>,
}

const N: usize = 6;
/// Sigma points: 2n + 1 state points, then 2p + 1 consider points (p = 1).
const POINTS: usize = 2 * N + 1 + 3;

type Matrix7 = SMatrix<f64, 7, 7>;

/// The scaled block factor S = [[Chol(A), B^T], [0, sqrt(l2)]] of DESIGN.md section 6, with
/// B = C^T / sqrt(l2) and A = l1 P - B^T B, for state covariance `p` (already including
/// C C^T) and cross-covariance `c` (kappa has unit variance). `t` names the epoch in errors.
pub fn factor(
    p: &Matrix6<f64>,
    c: &Vector6<f64>,
    l1: f64,
    l2: f64,
    t: f64,
) -> Result<Matrix7, CoreError> {
    let bt = c / l2.sqrt();
    let a = p * l1 - bt * bt.transpose();
    let a = (a + a.transpose()) * 0.5;
    let chol = Cholesky::new(a).ok_or_else(|| {
        CoreError::invalid(
            format!("CCSP covariance at t = {t} s"),
            a.symmetric_eigenvalues().min(),
            "is not positive definite (value: smallest eigenvalue of (lambda1+n) P - B^T B)",
        )
    })?;
    let mut s = Matrix7::zeros();
    s.fixed_view_mut::<6, 6>(0, 0).copy_from(&chol.l());
    s.fixed_view_mut::<6, 1>(0, 6).copy_from(&bt);
    s[(6, 6)] = l2.sqrt();
    Ok(s)
}

/// Runs the filter. `progress.done` counts the updates done; setting `progress.cancel`
/// stops the run at the next update or batch of sigma points.
pub fn ccsp<A: Atmosphere + ?Sized>(
    atmosphere: &A,
    cfg: &CcspConfig,
    progress: &Progress,
) -> Result<CcspOutput, CoreError> {
    cfg.problem.validate()?;
    crate::integrators::check_times("update times", 0.0, &cfg.update_times)?;
    if cfg.update_times.windows(2).any(|w| w[1] <= w[0]) || cfg.update_times[0] <= 0.0 {
        return Err(CoreError::invalid(
            "update times",
            cfg.update_times[0],
            "must increase strictly from > 0",
        ));
    }
    positive("step", cfg.max_step)?;
    positive("scaling[0] (lambda1 + n)", cfg.scaling.0)?;
    positive("scaling[1] (lambda2 + p)", cfg.scaling.1)?;
    let (l1, l2) = cfg.scaling;
    // UKF weights: w0 = lambda / (n + lambda), wi = 1 / (2 (n + lambda)).
    let (w0, wi) = ((l1 - N as f64) / l1, 0.5 / l1);
    let (v0, vi) = ((l2 - 1.0) / l2, 0.5 / l2);

    let p0 = Matrix6::from_fn(|i, j| cfg.p0[i][j]);
    for i in 0..N {
        for j in 0..N {
            finite(&format!("initial covariance[{i}][{j}]"), p0[(i, j)])?;
        }
    }
    if (p0 - p0.transpose()).abs().max() > 1e-12 * p0.abs().max() {
        return Err(CoreError::rejected(
            "initial covariance",
            "must be symmetric",
        ));
    }
    let y0 = cfg.problem.y0;
    let mut mean = Vector6::from_column_slice(&y0);
    let mut p = p0;
    let mut c = Vector6::zeros();
    let mut out = CcspOutput {
        times: vec![0.0],
        means: vec![y0],
        covariances: vec![cfg.p0],
        cross: vec![[0.0; 6]],
        decayed_at: None,
    };
    let mut t = 0.0;
    for &t1 in &cfg.update_times {
        progress.check()?;
        let s = factor(&p, &c, l1, l2, t)?;
        // Sigma points [state; kappa] around the mean (kappa mean 0).
        let mut points = [[0.0f64; 7]; POINTS];
        for (k, pt) in points.iter_mut().enumerate() {
            let (col, sign) = match k {
                0 | 13 => (None, 0.0),
                1..=6 => (Some(k - 1), 1.0),
                7..=12 => (Some(k - 7), -1.0),
                14 => (Some(6), 1.0),
                _ => (Some(6), -1.0),
            };
            for i in 0..7 {
                let base = if i < N { mean[i] } else { 0.0 };
                pt[i] = base + col.map_or(0.0, |j| sign * s[(i, j)]);
            }
        }
        let (ends, decayed_at) = propagate_points(atmosphere, cfg, &points, t, t1, progress)?;
        if decayed_at.is_some() {
            out.decayed_at = decayed_at;
            break;
        }
        // Set 1 (state points): mean and covariance.
        let m1: Vector6<f64> = (0..13).map(|k| weight(k, w0, wi) * ends[k]).sum();
        let mut p1 = Matrix6::zeros();
        for (k, e) in ends.iter().enumerate().take(13) {
            let d = e - m1;
            p1 += weight(k, w0, wi) * d * d.transpose();
        }
        // Set 2 (consider points): cross-covariance between state and kappa.
        let m2: Vector6<f64> = (0..3).map(|k| weight(k, v0, vi) * ends[13 + k]).sum();
        let mut cross = Vector6::zeros();
        for k in 0..3 {
            let kappa = points[13 + k][6];
            cross += weight(k, v0, vi) * (ends[13 + k] - m2) * kappa;
        }
        mean = m1;
        c = cross;
        p = p1 + c * c.transpose();
        p = (p + p.transpose()) * 0.5;
        if Cholesky::new(p).is_none() {
            return Err(CoreError::invalid(
                format!("CCSP covariance at t = {t1} s"),
                p.symmetric_eigenvalues().min(),
                "is not positive definite (value: smallest eigenvalue); try a larger initial \
                 covariance or scaling",
            ));
        }
        t = t1;
        out.times.push(t);
        out.means.push(std::array::from_fn(|i| mean[i]));
        out.covariances
            .push(std::array::from_fn(|i| std::array::from_fn(|j| p[(i, j)])));
        out.cross.push(std::array::from_fn(|i| c[i]));
        progress.add(1);
    }
    Ok(out)
}

fn weight(k: usize, w0: f64, wi: f64) -> f64 {
    if k == 0 {
        w0
    } else {
        wi
    }
}

/// The sigma points at t1, and the earliest floor crossing of any of them.
type PointEnds = (Vec<Vector6<f64>>, Option<f64>);

/// Propagates the sigma points from t0 to t1, each with its kappa held, in parallel
/// batches of the SIMD path's lane count; stops a batch where a point crosses the floor.
fn propagate_points<A: Atmosphere + ?Sized>(
    atmosphere: &A,
    cfg: &CcspConfig,
    points: &[[f64; 7]; POINTS],
    t0: f64,
    t1: f64,
    progress: &Progress,
) -> Result<PointEnds, CoreError> {
    let path = SimdPath::detect();
    match path.lanes() {
        8 => propagate_points_in::<A, 8>(path, atmosphere, cfg, points, t0, t1, progress),
        _ => propagate_points_in::<A, 4>(path, atmosphere, cfg, points, t0, t1, progress),
    }
}

fn propagate_points_in<A: Atmosphere + ?Sized, const W: usize>(
    path: SimdPath,
    atmosphere: &A,
    cfg: &CcspConfig,
    points: &[[f64; 7]; POINTS],
    t0: f64,
    t1: f64,
    progress: &Progress,
) -> Result<PointEnds, CoreError> {
    let plan = StepPlan::equal_steps(t0, &[t1], cfg.max_step)?;
    let batches: Vec<PointEnds> = points
        .par_chunks(W)
        .map(|chunk| {
            progress.check()?;
            dispatch_on(
                path,
                SigmaBatch::<A, W> {
                    atmosphere,
                    cfg,
                    chunk,
                    plan: &plan,
                },
            )
        })
        .collect::<Result<_, CoreError>>()?;
    let decayed_at = batches
        .iter()
        .filter_map(|b| b.1)
        .min_by(|a, b| a.total_cmp(b));
    Ok((batches.into_iter().flat_map(|b| b.0).collect(), decayed_at))
}

/// Locates the first floor crossing of the real lanes of a sigma-point batch.
struct FloorWatch<const W: usize> {
    epoch: f64,
    floor: f64,
    lanes: usize,
    last: (f64, State<W>),
    decayed_at: Option<f64>,
}

impl<R, const W: usize> StepHooks<W, R> for FloorWatch<W> {
    #[inline(always)]
    fn after_step(&mut self, t: f64, y: &mut State<W>, _: &mut R) -> Result<Control, CoreError> {
        let (t0, prev) = self.last;
        let candidates = may_cross_lanes(t0, &prev, t, y, self.floor);
        for l in 0..self.lanes {
            if !candidates[l] {
                continue;
            }
            let step = lane_step(t0, &prev, t, y, l);
            if let Some(tc) = crossing(self.epoch, &step, self.floor) {
                self.decayed_at = Some(self.decayed_at.map_or(tc, |d: f64| d.min(tc)));
            }
        }
        self.last = (t, *y);
        Ok(if self.decayed_at.is_some() {
            Control::Stop
        } else {
            Control::Continue
        })
    }
}

/// Up to `W` sigma points [state; kappa] stepped together through `plan` (unused lanes
/// repeat the last point and are discarded).
struct SigmaBatch<'a, A: ?Sized, const W: usize> {
    atmosphere: &'a A,
    cfg: &'a CcspConfig,
    chunk: &'a [[f64; 7]],
    plan: &'a StepPlan,
}

impl<A: Atmosphere + ?Sized, const W: usize> Kernel for SigmaBatch<'_, A, W> {
    type Output = Result<PointEnds, CoreError>;

    #[inline(always)]
    fn run(self) -> Self::Output {
        let SigmaBatch {
            atmosphere,
            cfg,
            chunk,
            plan,
        } = self;
        let lanes = chunk.len();
        let mut y: State<W> = [[0.0; W]; 6];
        let mut kappa = KappaLanes::<W>::zero();
        for l in 0..W {
            let pt = chunk[l.min(lanes - 1)];
            for c in 0..6 {
                y[c][l] = pt[c];
            }
            kappa.k0[l] = pt[6];
        }
        let problem = &cfg.problem;
        let mut dynamics = Dynamics::<A, W>::new(atmosphere, problem.epoch, [problem.drag; W]);
        dynamics.zonal_degree = problem.zonal_degree;
        dynamics.perturbation = cfg.perturbation;
        dynamics.kappa = kappa;
        let mut watch = FloorWatch {
            epoch: problem.epoch,
            floor: problem.floor_altitude,
            lanes,
            last: (plan.start(), y),
            decayed_at: None,
        };
        drive(cfg.method, &mut dynamics, &mut y, plan, &mut watch)?;
        Ok((
            (0..lanes)
                .map(|l| Vector6::from_fn(|c, _| y[c][l]))
                .collect(),
            watch.decayed_at,
        ))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    proptest! {
        #[test]
        fn factor_reproduces_the_documented_product(
            diag in proptest::collection::vec(1.0f64..100.0, 6),
            c in proptest::collection::vec(-1.0f64..1.0, 6),
        ) {
            // S S^T = [[l1 P, C], [C^T, l2]] (DESIGN.md section 6: the cross block unscaled).
            let mut p = Matrix6::from_diagonal(&Vector6::from_column_slice(&diag));
            let c = Vector6::from_column_slice(&c);
            p += c * c.transpose();
            let s = factor(&p, &c, 3.0, 3.0, 0.0).unwrap();
            let sst = s * s.transpose();
            let tl = sst.fixed_view::<6, 6>(0, 0) - p * 3.0;
            prop_assert!(tl.abs().max() < 1e-9 * p.abs().max());
            prop_assert!((sst.fixed_view::<6, 1>(0, 6) - c).abs().max() < 1e-12);
            prop_assert!((sst[(6, 6)] - 3.0).abs() < 1e-12);
            // Lower block-triangular: zeros below the state block.
            prop_assert!(s.fixed_view::<1, 6>(6, 0).abs().max() == 0.0);
        }
    }

    #[test]
    fn non_positive_definite_is_an_error_naming_the_epoch() {
        let p = Matrix6::from_diagonal(&Vector6::new(1.0, 1.0, 1.0, 1.0, 1.0, -1.0));
        let e = factor(&p, &Vector6::zeros(), 3.0, 3.0, 7200.0).unwrap_err();
        assert!(e.to_string().contains("t = 7200 s"), "{e}");
    }

    #[test]
    fn decay_stops_the_filter_cleanly_where_a_point_crosses_the_floor() {
        use crate::constants::{MU, R_EARTH};
        use crate::density::Exponential;
        use crate::propagate::{propagate, Method};
        // From 600 km apogee down to a 90 km perigee: every sigma point crosses the floor
        // on the first perigee pass, ~45 min in.
        let atm = Exponential::new(3.725e-12, 400e3, 58.515e3, 0.2).unwrap();
        let (ra, rp) = (R_EARTH + 600e3, R_EARTH + 90e3);
        let va = (MU * (2.0 / ra - 2.0 / (ra + rp))).sqrt();
        let problem = Problem {
            epoch: 0.0,
            y0: [ra, 0.0, 0.0, 0.0, va, 0.0],
            drag: 3.0912 * 0.0015,
            floor_altitude: 120e3,
            zonal_degree: 2,
        };
        let mut p0 = [[0.0; 6]; 6];
        for i in 0..6 {
            p0[i][i] = if i < 3 { 1.0 } else { 1e-6 };
        }
        let cfg = CcspConfig {
            problem,
            p0,
            update_times: vec![600.0, 1200.0, 3600.0, 7200.0],
            scaling: (3.0, 3.0),
            perturbation: Perturbation::Additive,
            method: FixedMethod::Rk8,
            max_step: 180.0,
        };
        let out = ccsp(&atm, &cfg, &Progress::default()).unwrap();
        let mean = propagate(
            &atm,
            &problem,
            &[7200.0],
            Method::Rk8 { step: 10.0 },
            &Progress::default(),
        )
        .unwrap()
        .decayed_at
        .unwrap();
        let td = out.decayed_at.expect("decays");
        // Sigma points 1 m / 1 mm/s apart cross within a fraction of a second of the mean.
        assert!((td - mean).abs() < 2.0, "{td} s vs {mean} s");
        assert_eq!(out.times, vec![0.0, 600.0, 1200.0]);
    }

    #[test]
    fn cancel_stops_the_run() {
        use crate::density::Exponential;
        use std::sync::atomic::Ordering;
        let atm = Exponential::new(3.725e-12, 400e3, 58.515e3, 0.2).unwrap();
        let mut p0 = [[0.0; 6]; 6];
        for i in 0..6 {
            p0[i][i] = if i < 3 { 1e-6 } else { 1e-12 };
        }
        let cfg = CcspConfig {
            problem: Problem {
                epoch: 8.4e7,
                y0: [
                    3782900.7032,
                    -5441600.6779,
                    -1420075.1327,
                    -606.6600,
                    1539.2559,
                    -7488.3946,
                ],
                drag: 3.0912 * 0.0015,
                floor_altitude: 120e3,
                zonal_degree: 2,
            },
            p0,
            update_times: vec![3600.0, 7200.0],
            scaling: (3.0, 3.0),
            perturbation: Perturbation::Additive,
            method: FixedMethod::Rk8,
            max_step: 180.0,
        };
        let p = Progress::default();
        p.cancel.store(true, Ordering::Relaxed);
        assert_eq!(ccsp(&atm, &cfg, &p).unwrap_err(), CoreError::Cancelled);
        // Not cancelled: every update is counted.
        let p = Progress::default();
        let out = ccsp(&atm, &cfg, &p).unwrap();
        assert_eq!(out.times, vec![0.0, 3600.0, 7200.0]);
        assert_eq!(p.done.load(Ordering::Relaxed), 2);
    }
}
