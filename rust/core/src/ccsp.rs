//! The consider-covariance sigma-point (CCSP) filter of the paper (section 4), in the
//! form of docs/conventions.md, "CCSP filter": the augmented state is [r, v, kappa] with kappa the
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
//!
//! With `drag_sigma` > 0 a second consider parameter joins: c, the normalised error of
//! Cd*A/m (unit variance; the sigma point flies with Cd*A/m exp(drag_sigma c)). Unlike
//! kappa it is a constant of the object, so its cross-covariance D with the state is
//! carried in full from update to update (never shrunk): the augmented state is
//! [r, v, kappa, c], p = 2, and the factor is
//! S = [[Chol(A), C / sqrt(l2), alpha sqrt(l2) D], [0, sqrt(l2), 0], [0, 0, alpha sqrt(l2)]]
//! with A = l1 (P - D D^T) - C C^T / l2 and alpha = [`DRAG_ALPHA`] (docs/conventions.md
//! derives it).
//!
//! A slow density term ([`SlowKappa`], the 4-day term of a two-scale kappa) is a third
//! consider parameter s, added to kappa in the density (kappa_scale kappa + scale s),
//! held over each update like kappa but correlated rho = 2^(-dt / half_life) from one
//! update to the next: its cross-covariance E is carried times rho, and the state set
//! holds P - D D^T - rho^2 E E^T - C C^T / l2^2. One more one-sided point, like c.

use crate::decay::{crossing, lane_step, may_cross_lanes};
use crate::density::Atmosphere;
use crate::dynamics::{Dynamics, Perturbation, State};
use crate::equinoctial;
use crate::error::{finite, positive, CoreError};
use crate::integrators::{drive, Control, FixedMethod, StepHooks, StepPlan};
use crate::kappa::KappaLanes;
use crate::problem::{check_drag_sigma, drag_factor, Problem};
use crate::progress::Progress;
use crate::simd::{dispatch_on, Aligned, Kernel, SimdPath};
use nalgebra::{Cholesky, Matrix6, SMatrix, Vector6};

type Matrix9 = SMatrix<f64, 9, 9>;
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
    /// Further output times, s from the epoch (increasing, within (0, end); empty: the
    /// updates only): the moments of the sigma points in flight, without re-drawing them.
    /// Re-drawn in Cartesian coordinates near the perigee of an eccentric orbit, where the
    /// spread bends along the orbit within minutes, the points leave the orbit's energy
    /// and the covariance grows tenfold over a few revolutions (docs/catalog-realism.md,
    /// "Eccentric orbits"); such runs update once per revolution and output here.
    pub output_times: Vec<f64>,
    /// (lambda1 + n, lambda2 + p), both > 0; the paper uses (3, 3).
    pub scaling: (f64, f64),
    /// Standard deviation of the density consider parameter kappa (1 in the paper's
    /// filter): a sigma point's kappa is this times its drawn value, so the density
    /// term of the covariance scales with its square. Less than 1 when only part of the
    /// density error is carried by the per-update kappa (the fast term of a two-scale
    /// process; its slow term goes into `drag_sigma`).
    pub kappa_scale: f64,
    pub perturbation: Perturbation,
    pub method: FixedMethod,
    /// Largest integration step, s.
    pub max_step: f64,
    /// Relative 1-sigma of Cd*A/m (log-normal, [`drag_factor`]), carried as the second
    /// consider parameter c; 0 (the paper's filter) leaves it out.
    pub drag_sigma: f64,
    /// Coordinates in which the sigma points are drawn and their moments taken.
    pub coordinates: Coordinates,
    /// The slow density term of a two-scale kappa, carried as its own consider
    /// parameter ([`SlowKappa`]); None: kappa alone.
    pub slow: Option<SlowKappa>,
}

/// A slow density term: a unit-variance process s that adds `scale` s to kappa in the
/// density (rho (1 + sigma (kappa_scale kappa + scale s))), held over each update and
/// correlated 2^(-dt / `half_life`) between updates dt apart: the piecewise-constant
/// form of a Gauss-Markov term with that half-life, whose correlation time it matches to
/// 1e-5 at hourly updates and a 4-day half-life. `half_life` infinite: a density scale
/// constant over the run (the `Constant` kappa).
///
/// Why its own parameter: folded into the constant c (before 2026-12-05), it tied the
/// along-track drift to the semi-major axis for the whole run, where the members' slow
/// density decorrelates over days and spreads them across that line: 57 % of 2,000
/// members inside the filter's 95 % region of (a, lambda) at 14 days.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SlowKappa {
    /// Weight of s in kappa (sqrt(w) of a two-scale process), >= 0.
    pub scale: f64,
    /// Half-life of s, s (> 0; infinite: constant).
    pub half_life: f64,
}

impl SlowKappa {
    /// The correlation of s between updates `dt` s apart.
    fn correlation(&self, dt: f64) -> f64 {
        (-dt / self.half_life).exp2()
    }

    fn check(&self) -> Result<(), CoreError> {
        if !(self.scale.is_finite() && self.scale >= 0.0) {
            return Err(CoreError::invalid(
                "slow.scale",
                self.scale,
                "must be finite and >= 0",
            ));
        }
        if self.half_life.is_nan() || self.half_life <= 0.0 {
            return Err(CoreError::invalid(
                "slow.half_life",
                self.half_life,
                "must be > 0 (infinite: a constant term)",
            ));
        }
        Ok(())
    }
}

/// Coordinates of the filter's mean and covariance (docs/conventions.md, "CCSP
/// coordinates").
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Coordinates {
    /// Inertial position and velocity: the paper's filter. Points drawn on a straight
    /// line leave the curved orbit: once the along-track spread reaches tens of km (about
    /// 5 days at 400 km) both points of a pair gain the same energy, and the spurious
    /// drift feeds the covariance faster than the density does (8.6x a Monte Carlo's
    /// along-track sigma by 19 days).
    Cartesian,
    /// Equinoctial elements (a, h, k, p, q, lambda) ([`crate::equinoctial`]): an
    /// along-track spread is a spread of lambda, points stay on their orbits, and the
    /// Gaussian holds for weeks. Outputs are mapped to Cartesian by the Jacobian at the
    /// mean; the element moments are returned too.
    Equinoctial,
}

/// Mean, covariance and state-kappa cross-covariance at every update time.
#[derive(Debug, Clone, PartialEq)]
pub struct CcspOutput {
    pub times: Vec<f64>,
    pub means: Vec<[f64; 6]>,
    pub covariances: Vec<[[f64; 6]; 6]>,
    pub cross: Vec<[f64; 6]>,
    /// Cross-covariance of the state with the normalised ballistic-coefficient error c
    /// (zero when `drag_sigma` is 0).
    pub drag_cross: Vec<[f64; 6]>,
    /// When a sigma point first went below the floor altitude (s from the epoch): the
    /// filter stopped there and the outputs end at the last update before it.
    pub decayed_at: Option<f64>,
    /// With [`Coordinates::Equinoctial`], the mean (a m, h, k, p, q, lambda rad) and
    /// covariance in equinoctial elements at every output (the filter's own Gaussian;
    /// the Cartesian one is its linear map); empty with Cartesian coordinates.
    pub element_means: Vec<[f64; 6]>,
    pub element_covariances: Vec<[[f64; 6]; 6]>,
}

const N: usize = 6;
/// Sigma points: 2n + 1 state points, then the consider points kappa + and -, and (with a
/// ballistic-coefficient sigma) c +, one-sided ([`DRAG_ALPHA`]). The consider set's centre
/// (state at the mean, kappa = c = 0) is the state set's point 0, so it is not flown
/// twice. 15 or 16 points, one batch of [`LANES`] either way.
/// A slow density term ([`SlowKappa`]) adds one more one-sided point, s +.
const POINTS_KAPPA: usize = 2 * N + 1 + 2;
/// Lanes of a whole-object batch: a multiple of the SIMD width. An odd count costs far
/// more than its share (measured through the NRLMSIS field, AVX-512, one thread: 15 lanes
/// 0.76 s, 16 lanes 0.51 s, 17 lanes 0.62 s, 18 lanes 0.67 s for the same 100 objects),
/// so the kappa-only filter pads its 15 points with one discarded lane.
const LANES: usize = 16;
/// Lanes of a batch of 17 points (c and s both carried).
const LANES_SLOW: usize = 17;
/// Index of the first kappa point.
const KAPPA: usize = 2 * N + 1;
/// Scaling alpha of the c point (the tangent-linear limit of the scaled unscented
/// transform, Julier 2002, for the ballistic-coefficient set alone): it probes
/// alpha sqrt(l2) in c and the state alpha sqrt(l2) D, and D' = (x_c - x_0) / (alpha
/// sqrt(l2)) is a one-sided difference, exact to O(alpha drag_sigma) (2.6e-4 relative at
/// drag_sigma 0.3; rounding ~1e-7): one lane instead of the pair +-, which with the
/// consider centre no longer flown twice fits the filter in 16 lanes. At
/// alpha = 1 (points +-sqrt(3) sigma) the points lay on a straight line in Cartesian space
/// while the spread is curved along the orbit (kilometres along-track): re-drawn there
/// every update, they lost 24 % of the along-track sigma by 3 days at drag_sigma = 0.3
/// against finite differences and a Monte Carlo (docs/conventions.md).
pub const DRAG_ALPHA: f64 = 1e-3;
/// A sigma point: [state (6), kappa, c, s].
type Point = [f64; 9];

/// The scaled block factor of docs/conventions.md, "CCSP filter" generalised to the two consider
/// parameters [kappa, c]:
/// S = [[Chol(A), B^T], [0, diag(sqrt(l2), alpha sqrt(l2))]] with
/// B^T = [C / sqrt(l2), alpha sqrt(l2) D] and A = l1 (`pc` - C C^T / l2^2), where
/// `pc` = P - D D^T is the state covariance without the part explained by c (it includes
/// C C^T), `c` the cross-covariance with kappa and `d` the cross-covariance with c (both
/// of unit variance), `alpha` the scaling of the c points ([`DRAG_ALPHA`]). Hence
/// S S^T = [[l1 pc - (l1 / l2 - 1) C C^T / l2 + a^2 l2 D D^T, C, a^2 l2 D], [C^T, l2, 0],
/// [a^2 l2 D^T, 0, a^2 l2]] (a = alpha): kappa's cross block unscaled as in
/// docs/conventions.md, "CCSP filter" (the 1 / l2 forgetting per update), c's scaled like
/// its variance (carried in full). With the weights 1 / (2 l1) of the state points and
/// 1 / (2 l2) of the kappa points, the points hold the state covariance pc + D D^T whatever
/// l1 and l2; the paper's A = l1 pc - C C^T / l2 held it only at l1 = l2 (its (3, 3), where
/// both forms are the same bits), and at l2 = 1.17 (correlation 0.85) inflated the
/// along-track sigma 1.7x over the Monte Carlo of its process. With D = 0 the first seven
/// rows and columns are the p = 1 factor exactly.
///
/// The slow term s ([`SlowKappa`]): `e` is the cross-covariance with s before the update
/// and `rho` its correlation across it, so the state's cross-covariance with the new s is
/// rho E; the state set holds pc + (1 - rho^2) E E^T - C C^T / l2^2 (pc then excludes
/// E E^T as it excludes D D^T), and the s point probes alpha sqrt(l2) rho E, s =
/// alpha sqrt(l2) (row and column 8). With E = 0 the first eight rows and columns are the
/// factor without s, bit for bit. `t` names the epoch in errors.
#[allow(clippy::too_many_arguments)]
pub fn factor(
    pc: &Matrix6<f64>,
    c: &Vector6<f64>,
    d: &Vector6<f64>,
    e: &Vector6<f64>,
    rho: f64,
    l1: f64,
    l2: f64,
    alpha: f64,
    t: f64,
) -> Result<Matrix9, CoreError> {
    let bt = c / l2.sqrt();
    let mut a = pc * l1 - bt * bt.transpose() * (l1 / l2);
    if *e != Vector6::zeros() {
        a += e * e.transpose() * (l1 * (1.0 - rho * rho));
    }
    let a = (a + a.transpose()) * 0.5;
    let chol = Cholesky::new(a).ok_or_else(|| CoreError::NotPositiveDefinite {
        what: "CCSP covariance ((lambda1+n) P - B^T B)",
        t,
        min_eigenvalue: a.symmetric_eigenvalues().min(),
        hint: "",
    })?;
    let mut s = Matrix9::zeros();
    s.fixed_view_mut::<6, 6>(0, 0).copy_from(&chol.l());
    s.fixed_view_mut::<6, 1>(0, 6).copy_from(&bt);
    s.fixed_view_mut::<6, 1>(0, 7)
        .copy_from(&(d * (alpha * l2.sqrt())));
    s.fixed_view_mut::<6, 1>(0, 8)
        .copy_from(&(e * (alpha * l2.sqrt() * rho)));
    s[(6, 6)] = l2.sqrt();
    s[(7, 7)] = alpha * l2.sqrt();
    s[(8, 8)] = alpha * l2.sqrt();
    Ok(s)
}

/// Runs the filter. `progress.done` counts the updates done; setting `progress.cancel`
/// stops the run at the next update. The sigma points of an update step together in one
/// batch of 16 lanes on the calling thread: per-update
/// parallel work over lane-width batches cost more in thread wake-ups than it gained
/// (one paper CCSP over 3 days: 4.6 ms on rayon over 2 cores, 2.3 ms in one batch).
pub fn ccsp<A: Atmosphere + ?Sized>(
    atmosphere: &A,
    cfg: &CcspConfig,
    progress: &Progress,
) -> Result<CcspOutput, CoreError> {
    run(atmosphere, cfg, progress, Grouping::Whole)
}

/// Runs the filter for several objects (a catalog chunk) through one atmosphere: objects
/// in parallel, each object's sigma points stepping together in one batch of
/// 16 lanes ([`LANES`]: the lane loops fill whole SIMD registers and the
/// time-dependent parts of a stage, Earth rotation and the field's time cell, are
/// computed once per object). Each object's result is bit-identical to [`ccsp`] of its
/// config alone (lanes never mix, whatever the batching), and independent of the thread
/// count. Per object: its output or its error; a cancelled run is an error of the call.
pub fn ccsp_many<A: Atmosphere + ?Sized>(
    atmosphere: &A,
    cfgs: &[CcspConfig],
    progress: &Progress,
) -> Result<Vec<Result<CcspOutput, CoreError>>, CoreError> {
    let out: Vec<Result<CcspOutput, CoreError>> = cfgs
        .par_iter()
        .with_max_len(1)
        .map(|cfg| run(atmosphere, cfg, progress, Grouping::Whole))
        .collect();
    if out.iter().any(|r| matches!(r, Err(CoreError::Cancelled))) {
        return Err(CoreError::Cancelled);
    }
    Ok(out)
}

/// How the sigma points of one update are batched.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Grouping {
    /// Batches of 8 lanes, run in parallel (the layout before issue
    /// 14; kept for the test that every batching gives the same bits).
    #[cfg_attr(not(test), allow(dead_code))]
    Lanes,
    /// One batch of all points, on the calling thread (objects already in parallel).
    Whole,
}

fn run<A: Atmosphere + ?Sized>(
    atmosphere: &A,
    cfg: &CcspConfig,
    progress: &Progress,
    grouping: Grouping,
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
    let end = cfg.update_times[cfg.update_times.len() - 1];
    if !cfg.output_times.is_empty() {
        crate::integrators::check_times("output times", 0.0, &cfg.output_times)?;
        let last = cfg.output_times[cfg.output_times.len() - 1];
        if cfg.output_times[0] <= 0.0 || last >= end {
            return Err(CoreError::invalid(
                "output times",
                if last >= end {
                    last
                } else {
                    cfg.output_times[0]
                },
                "must lie within (0, the last update time)",
            ));
        }
    }
    positive("step", cfg.max_step)?;
    positive("scaling[0] (lambda1 + n)", cfg.scaling.0)?;
    positive("scaling[1] (lambda2 + p)", cfg.scaling.1)?;
    if !(cfg.kappa_scale.is_finite() && cfg.kappa_scale >= 0.0) {
        return Err(CoreError::invalid(
            "kappa_scale",
            cfg.kappa_scale,
            "must be finite and >= 0",
        ));
    }
    let drag_on = check_drag_sigma(cfg.drag_sigma)? > 0.0;
    if let Some(slow) = cfg.slow {
        slow.check()?;
    }
    let slow = cfg.slow.filter(|s| s.scale > 0.0);
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
    let coords = Frame::new(cfg.coordinates, &Vector6::from_column_slice(&y0), l1);
    // Mean and covariances in the filter's coordinates.
    let (mut mean, p0) = coords.initial(&Vector6::from_column_slice(&y0), &p0)?;
    // The state covariance without the parts explained by c and s: P = pc + D D^T + E E^T.
    let mut pc = p0;
    let mut c = Vector6::zeros();
    let mut d = Vector6::zeros();
    let mut e = Vector6::zeros();
    let mut out = CcspOutput {
        times: Vec::new(),
        means: Vec::new(),
        covariances: Vec::new(),
        cross: Vec::new(),
        drag_cross: Vec::new(),
        decayed_at: None,
        element_means: Vec::new(),
        element_covariances: Vec::new(),
    };
    out.push(&coords, 0.0, &mean, &p0, &c, &d);
    out.means[0] = y0;
    out.covariances[0] = cfg.p0;
    if cfg.output_times.windows(2).any(|w| w[1] <= w[0]) {
        return Err(CoreError::rejected(
            "output times",
            "must increase strictly",
        ));
    }
    // The one-sided points after the kappa pair: c (column 7), then s (column 8).
    let one_sided: Vec<usize> = [(drag_on, 7), (slow.is_some(), 8)]
        .iter()
        .filter_map(|&(on, col)| on.then_some(col))
        .collect();
    let npoints = POINTS_KAPPA + one_sided.len();
    let weights = Weights { w0, wi, v0, vi };
    let mut t = 0.0;
    let mut next_output = 0;
    for &t1 in &cfg.update_times {
        progress.check()?;
        let rho = slow.map_or(1.0, |s| s.correlation(t1 - t));
        let s = factor(&pc, &c, &d, &e, rho, l1, l2, DRAG_ALPHA, t)?;
        // Sigma points [state; kappa; c; s] around the mean (kappa, c and s of mean 0).
        let mut points = vec![[0.0f64; 9]; npoints];
        for (k, pt) in points.iter_mut().enumerate() {
            let (col, sign) = match k {
                0 => (None, 0.0),
                1..=6 => (Some(k - 1), 1.0),
                7..=12 => (Some(k - 7), -1.0),
                13 => (Some(6), 1.0),
                14 => (Some(6), -1.0),
                _ => (Some(one_sided[k - POINTS_KAPPA]), 1.0),
            };
            for i in 0..9 {
                let base = if i < N { mean[i] } else { 0.0 };
                pt[i] = base + col.map_or(0.0, |j| sign * s[(i, j)]);
            }
        }
        let flown = coords.flown(&points, t)?;
        // The output times inside this update's interval, then the update itself.
        let mut stops = Vec::new();
        while next_output < cfg.output_times.len() && cfg.output_times[next_output] <= t1 {
            let to = cfg.output_times[next_output];
            if to > t && to < t1 {
                stops.push(to);
            }
            next_output += 1;
        }
        stops.push(t1);
        let (ends_at, decayed_at) =
            propagate_points(atmosphere, cfg, &flown, t, &stops, progress, grouping)?;
        let ends_at = coords.ends(ends_at, &stops)?;
        // The outputs in flight (before any floor crossing): the points' moments.
        for (k, ends) in ends_at.iter().enumerate().take(stops.len() - 1) {
            if decayed_at.is_some_and(|td| stops[k] >= td) {
                break;
            }
            let (mean_k, pc_k, c_k) = state_moments(&points, ends, weights);
            let d_k = one_sided_cross(&points, ends, 7).unwrap_or(d);
            let mut p_k = pc_k + d_k * d_k.transpose();
            if let Some(e_k) = one_sided_cross(&points, ends, 8) {
                p_k += e_k * e_k.transpose();
            }
            let p_k = positive_definite((p_k + p_k.transpose()) * 0.5);
            out.push(&coords, stops[k], &mean_k, &p_k, &c_k, &d_k);
        }
        if decayed_at.is_some() {
            out.decayed_at = decayed_at;
            break;
        }
        let ends = &ends_at[stops.len() - 1];
        let (m1, pc1, cross) = state_moments(&points, ends, weights);
        mean = m1;
        c = cross;
        pc = (pc1 + pc1.transpose()) * 0.5;
        if coords.axes.is_some() && Cholesky::new(pc).is_none() {
            pc = rounding_repaired(pc, &mean).unwrap_or(pc);
        }
        if Cholesky::new(pc).is_none() {
            return Err(CoreError::NotPositiveDefinite {
                what: "CCSP covariance",
                t: t1,
                min_eigenvalue: pc.symmetric_eigenvalues().min(),
                hint: "; try a larger initial covariance or scaling",
            });
        }
        let mut p = pc;
        if let Some(d1) = one_sided_cross(&points, ends, 7) {
            d = d1;
            p += d * d.transpose();
        }
        if let Some(e1) = one_sided_cross(&points, ends, 8) {
            e = e1;
            p += e * e.transpose();
        }
        if drag_on || slow.is_some() {
            p = (p + p.transpose()) * 0.5;
        }
        t = t1;
        out.push(&coords, t, &mean, &p, &c, &d);
        progress.add(1);
    }
    Ok(out)
}

impl CcspOutput {
    /// Records the moments (in the filter's coordinates) at `t`. From equinoctial
    /// elements the Cartesian mean and covariance are the unscented transform of the
    /// element Gaussian (its points are on their orbits, so the mean sits inside the arc
    /// and the radial variance holds the arc's sag, as a Monte Carlo's sample moments
    /// do); the cross-covariances are mapped by the Jacobian at the mean.
    fn push(
        &mut self,
        coords: &Frame,
        t: f64,
        mean: &Vector6<f64>,
        p: &Matrix6<f64>,
        c: &Vector6<f64>,
        d: &Vector6<f64>,
    ) {
        let arr = |v: &Vector6<f64>| -> [f64; 6] { std::array::from_fn(|i| v[i]) };
        let mat = |m: &Matrix6<f64>| -> [[f64; 6]; 6] {
            std::array::from_fn(|i| std::array::from_fn(|j| m[(i, j)]))
        };
        self.times.push(t);
        match coords.axes {
            None => {
                self.means.push(arr(mean));
                self.covariances.push(mat(p));
                self.cross.push(arr(c));
                self.drag_cross.push(arr(d));
            }
            Some(axes) => {
                let jac = equinoctial::jacobian(mean, axes, SEMI);
                let (mx, px) = equinoctial::cartesian_moments(mean, p, axes, SEMI, coords.l1)
                    .unwrap_or_else(|| {
                        (
                            equinoctial::to_cartesian_with(mean, axes, SEMI),
                            jac * p * jac.transpose(),
                        )
                    });
                self.means.push(arr(&mx));
                self.covariances
                    .push(mat(&positive_definite((px + px.transpose()) * 0.5)));
                self.cross.push(arr(&(jac * c)));
                self.drag_cross.push(arr(&(jac * d)));
                let mut m = *mean;
                m[5] = equinoctial::wrap(m[5]);
                self.element_means.push(arr(&m));
                self.element_covariances.push(mat(p));
            }
        }
    }
}

/// The semi-major axis of the filter's equinoctial elements: the energy one, free of the
/// J2 swing ([`equinoctial::SemiMajor::Energy`]).
pub const SEMI: equinoctial::SemiMajor = equinoctial::SemiMajor::Energy;

/// The filter's coordinates: the identity for Cartesian ones, else the axes in which the
/// equinoctial elements are taken.
struct Frame {
    axes: Option<equinoctial::Axes>,
    /// lambda1 + n of the unscented transform that maps the element Gaussian to Cartesian
    /// moments.
    l1: f64,
}

impl Frame {
    fn new(coordinates: Coordinates, y0: &Vector6<f64>, l1: f64) -> Self {
        Frame {
            l1,
            axes: match coordinates {
                Coordinates::Cartesian => None,
                Coordinates::Equinoctial => Some(equinoctial::Axes::for_state(y0)),
            },
        }
    }

    /// The initial mean and covariance in these coordinates: P_el = K P K^T with K the
    /// inverse of d(Cartesian)/d(elements) at the mean.
    fn initial(
        &self,
        y0: &Vector6<f64>,
        p0: &Matrix6<f64>,
    ) -> Result<(Vector6<f64>, Matrix6<f64>), CoreError> {
        let Some(axes) = self.axes else {
            return Ok((*y0, *p0));
        };
        let el = equinoctial::from_cartesian_with(y0, axes, SEMI, "initial state")?;
        let k = equinoctial::jacobian(&el, axes, SEMI)
            .try_inverse()
            .ok_or_else(|| {
                CoreError::rejected(
                    "initial state",
                    "gives a singular equinoctial Jacobian; use Cartesian coordinates",
                )
            })?;
        let p = k * p0 * k.transpose();
        Ok((el, (p + p.transpose()) * 0.5))
    }

    /// The sigma points with their state part in Cartesian coordinates, to fly.
    fn flown(&self, points: &[Point], t: f64) -> Result<Vec<Point>, CoreError> {
        let Some(axes) = self.axes else {
            return Ok(points.to_vec());
        };
        points
            .iter()
            .map(|pt| {
                let el = Vector6::from_column_slice(&pt[..N]);
                let e2 = el[1] * el[1] + el[2] * el[2];
                if el[0].is_nan() || el[0] <= 0.0 || e2.is_nan() || e2 >= 1.0 {
                    return Err(CoreError::invalid(
                        "CCSP sigma point semi-major axis",
                        el[0],
                        format!(
                            "at t = {t} s the equinoctial spread reaches a non-elliptic \
                             orbit (e^2 = {:.3}); use Cartesian coordinates",
                            e2
                        ),
                    ));
                }
                let x = equinoctial::to_cartesian_with(&el, axes, SEMI);
                let mut out = *pt;
                out[..N].copy_from_slice(x.as_slice());
                Ok(out)
            })
            .collect()
    }

    /// The flown points' states at each stop in these coordinates, lambda unwrapped next
    /// to the centre point's so that a spread across +-pi stays one spread.
    fn ends(
        &self,
        ends: Vec<Vec<Vector6<f64>>>,
        stops: &[f64],
    ) -> Result<Vec<Vec<Vector6<f64>>>, CoreError> {
        let Some(axes) = self.axes else {
            return Ok(ends);
        };
        ends.into_iter()
            .zip(stops)
            .map(|(at, &ts)| {
                let what = format!("a CCSP sigma point at t = {ts} s");
                let centre = equinoctial::from_cartesian_with(&at[0], axes, SEMI, &what)?;
                at.iter()
                    .map(|x| {
                        let el = equinoctial::from_cartesian_with(x, axes, SEMI, &what)?;
                        Ok(equinoctial::unwrap_near(&el, centre[5]))
                    })
                    .collect()
            })
            .collect()
    }
}

/// UKF weights of the state set (w0, wi) and of the consider set (v0, vi).
#[derive(Debug, Clone, Copy)]
struct Weights {
    w0: f64,
    wi: f64,
    v0: f64,
    vi: f64,
}

/// The state set's mean and covariance with kappa's part, P + C C^T, and the
/// cross-covariance C with kappa from the consider set (centred on point 0), of the
/// sigma points `points` flown to `ends`.
fn state_moments(
    points: &[Point],
    ends: &[Vector6<f64>],
    w: Weights,
) -> (Vector6<f64>, Matrix6<f64>, Vector6<f64>) {
    // Set 1 (state points): mean and covariance.
    let m1: Vector6<f64> = (0..KAPPA).map(|k| weight(k, w.w0, w.wi) * ends[k]).sum();
    let mut p1 = Matrix6::zeros();
    for (k, e) in ends.iter().enumerate().take(KAPPA) {
        let d = e - m1;
        p1 += weight(k, w.w0, w.wi) * d * d.transpose();
    }
    // Set 2 (consider points, centred on point 0): cross-covariance between state and
    // kappa. Summed in the order of the layout that flew the centre twice (same bits).
    let consider = [0, KAPPA, KAPPA + 1];
    let m2: Vector6<f64> = (0..3)
        .map(|k| weight(k, w.v0, w.vi) * ends[consider[k]])
        .sum();
    let mut cross = Vector6::zeros();
    for k in 0..3 {
        let kappa = points[consider[k]][6];
        cross += weight(k, w.v0, w.vi) * (ends[consider[k]] - m2) * kappa;
    }
    (m1, p1 + cross * cross.transpose(), cross)
}

/// `p`, or where it is not positive definite its eigenvalues raised to 1e-12 of the
/// largest. Only outputs between updates need it: their moments come from the points in
/// flight with the unscented weights, the centre's negative (1 - n / l1 = -1 at the
/// paper's l1 = 3), and over an eccentric orbit's perigee pass the covariance is so
/// elongated that this left eigenvalues of -1e-4 m^2 (-7e-7 of the correlation matrix)
/// in a few outputs a revolution; a covariance to sample or factor must be positive
/// definite, and the change is of that size. At updates an indefinite covariance stops
/// the run as before (a sign of decay).
fn positive_definite(p: Matrix6<f64>) -> Matrix6<f64> {
    if Cholesky::new(p).is_some() {
        return p;
    }
    let eig = p.symmetric_eigen();
    let floor = 1e-12 * eig.eigenvalues.max().max(0.0);
    let lifted = eig.eigenvalues.map(|l| l.max(floor));
    let q = eig.eigenvectors * Matrix6::from_diagonal(&lifted) * eig.eigenvectors.transpose();
    (q + q.transpose()) * 0.5
}

/// `p` with the rounding noise of its thinnest directions lifted, or None when its
/// indefiniteness is more than rounding. Element covariances span 30 orders of magnitude
/// (a in m^2, p and q near 1e-20 from a mm-level initial covariance), so an eigenvalue
/// check relative to the largest is meaningless; in the correlation matrix
/// D^-1/2 p D^-1/2 the rounding of each element, eps max(|mean|, 1), over its sigma
/// bounds what rounding can do (the energy a of a 7,000 km orbit rounds at 1e-9 m, 3e-7
/// of a 3 mm sigma: -6e-9 seen after 36 daily updates with a certain density). An
/// eigenvalue above -10 times the largest such ratio (at least -1e-9) is rounding, and
/// is raised to 1e-12.
fn rounding_repaired(p: Matrix6<f64>, mean: &Vector6<f64>) -> Option<Matrix6<f64>> {
    let d = p.diagonal();
    if d.iter().any(|&x| x.is_nan() || x <= 0.0) {
        return None;
    }
    let s = d.map(|x| x.sqrt());
    let corr = Matrix6::from_fn(|i, j| p[(i, j)] / (s[i] * s[j]));
    let eig = corr.symmetric_eigen();
    let rounding = (0..N)
        .map(|i| f64::EPSILON * mean[i].abs().max(1.0) / s[i])
        .fold(1e-10, f64::max);
    if eig.eigenvalues.min() < -10.0 * rounding {
        return None;
    }
    let lifted = eig.eigenvalues.map(|l| l.max(1e-12));
    let c = eig.eigenvectors * Matrix6::from_diagonal(&lifted) * eig.eigenvectors.transpose();
    let q = Matrix6::from_fn(|i, j| c[(i, j)] * s[i] * s[j]);
    Some((q + q.transpose()) * 0.5)
}

/// Set 2, the one-sided point of consider parameter `col` (7: c, 8: s), if flown: the
/// cross-covariance with it, a one-sided difference from the centre (point 0) at
/// alpha sqrt(l2).
fn one_sided_cross(points: &[Point], ends: &[Vector6<f64>], col: usize) -> Option<Vector6<f64>> {
    let k = (POINTS_KAPPA..points.len()).find(|&k| points[k][col] != 0.0)?;
    Some((ends[k] - ends[0]) / points[k][col])
}

fn weight(k: usize, w0: f64, wi: f64) -> f64 {
    if k == 0 {
        w0
    } else {
        wi
    }
}

/// The sigma points at each stop reached, and the earliest floor crossing of any of them.
type PointEnds = (Vec<Vec<Vector6<f64>>>, Option<f64>);

/// Propagates the sigma points from t0 to t1, each with its kappa held, in parallel
/// batches of the SIMD path's lane count (or, [`Grouping::Whole`], in one batch of all
/// points); stops a batch where a point crosses the floor.
fn propagate_points<A: Atmosphere + ?Sized>(
    atmosphere: &A,
    cfg: &CcspConfig,
    points: &[Point],
    t0: f64,
    stops: &[f64],
    progress: &Progress,
    grouping: Grouping,
) -> Result<PointEnds, CoreError> {
    let path = SimdPath::detect();
    if grouping == Grouping::Whole {
        progress.check()?;
        let plan = StepPlan::equal_steps(t0, stops, cfg.max_step)?;
        return if points.len() <= LANES {
            whole_batch::<A, LANES>(path, atmosphere, cfg, points, &plan)
        } else {
            whole_batch::<A, LANES_SLOW>(path, atmosphere, cfg, points, &plan)
        };
    }
    propagate_points_in::<A, 8>(path, atmosphere, cfg, points, t0, stops, progress)
}

fn propagate_points_in<A: Atmosphere + ?Sized, const W: usize>(
    path: SimdPath,
    atmosphere: &A,
    cfg: &CcspConfig,
    points: &[Point],
    t0: f64,
    stops: &[f64],
    progress: &Progress,
) -> Result<PointEnds, CoreError> {
    let plan = StepPlan::equal_steps(t0, stops, cfg.max_step)?;
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
    // Per stop, the points of every batch in order (as far as every batch got).
    let reached = batches.iter().map(|b| b.0.len()).min().unwrap_or(0);
    let ends = (0..reached)
        .map(|k| {
            batches
                .iter()
                .flat_map(|b| b.0[k].iter().copied())
                .collect()
        })
        .collect();
    Ok((ends, decayed_at))
}

/// All sigma points in one batch of `W` lanes (`W` = their count).
fn whole_batch<A: Atmosphere + ?Sized, const W: usize>(
    path: SimdPath,
    atmosphere: &A,
    cfg: &CcspConfig,
    points: &[Point],
    plan: &StepPlan,
) -> Result<PointEnds, CoreError> {
    dispatch_on(
        path,
        SigmaBatch::<A, W> {
            atmosphere,
            cfg,
            chunk: points,
            plan,
        },
    )
}

/// Locates the first floor crossing of the real lanes of a sigma-point batch.
struct FloorWatch<const W: usize> {
    epoch: f64,
    floor: f64,
    lanes: usize,
    last: (f64, State<W>),
    decayed_at: Option<f64>,
    /// The batch's state at each stop of the plan reached.
    at_stops: Vec<State<W>>,
}

impl<R, const W: usize> StepHooks<W, R> for FloorWatch<W> {
    #[inline(always)]
    fn on_output(&mut self, _: usize, _: f64, y: &State<W>, _: &R) -> Result<(), CoreError> {
        self.at_stops.push(*y);
        Ok(())
    }

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

/// Up to `W` sigma points [state; kappa; c] stepped together through `plan` (unused lanes
/// repeat the last point and are discarded).
struct SigmaBatch<'a, A: ?Sized, const W: usize> {
    atmosphere: &'a A,
    cfg: &'a CcspConfig,
    chunk: &'a [Point],
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
        let mut state = Aligned::<State<W>>([[0.0; W]; 6]);
        let y = &mut state.0;
        let mut kappa = KappaLanes::<W>::zero();
        let mut drag = [0.0; W];
        let problem = &cfg.problem;
        let slow_scale = cfg.slow.map_or(0.0, |s| s.scale);
        for l in 0..W {
            let pt = chunk[l.min(lanes - 1)];
            for c in 0..6 {
                y[c][l] = pt[c];
            }
            kappa.k0[l] = pt[6] * cfg.kappa_scale + pt[8] * slow_scale;
            drag[l] = problem.drag * drag_factor(cfg.drag_sigma, pt[7]);
        }
        let mut dynamics = Dynamics::<A, W>::for_problem(atmosphere, problem, drag);
        dynamics.perturbation = cfg.perturbation;
        dynamics.kappa = kappa;
        let mut watch = FloorWatch {
            epoch: problem.epoch,
            floor: problem.floor_altitude,
            lanes,
            last: (plan.start(), *y),
            decayed_at: None,
            at_stops: Vec::new(),
        };
        drive(cfg.method, &mut dynamics, y, plan, &mut watch)?;
        Ok((
            watch
                .at_stops
                .iter()
                .map(|ys| {
                    (0..lanes)
                        .map(|l| Vector6::from_fn(|c, _| ys[c][l]))
                        .collect()
                })
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
            d in proptest::collection::vec(-10.0f64..10.0, 6),
            l1 in 1.0f64..5.0,
            l2 in 1.0f64..5.0,
            alpha in 0.01f64..1.0,
        ) {
            // S S^T = [[l1 pc + a^2 l2 D D^T, C, a^2 l2 D], [C^T, l2, 0], [a^2 l2 D^T, 0,
            // a^2 l2]]: kappa's cross block unscaled (docs/conventions.md, "CCSP filter"), c's scaled like
            // its variance (a = alpha).
            let mut pc = Matrix6::from_diagonal(&Vector6::from_column_slice(&diag));
            let c = Vector6::from_column_slice(&c);
            let d = Vector6::from_column_slice(&d);
            pc += c * c.transpose();
            let s = factor(&pc, &c, &d, &Vector6::zeros(), 1.0, l1, l2, alpha, 0.0).unwrap();
            let sst = s * s.transpose();
            let a2 = alpha * alpha;
            let scale = (pc * l1 + d * d.transpose() * (a2 * l2)).abs().max();
            let held = pc * l1 - c * c.transpose() * ((l1 / l2 - 1.0) / l2);
            let tl = sst.fixed_view::<6, 6>(0, 0) - held - d * d.transpose() * (a2 * l2);
            prop_assert!(tl.abs().max() < 1e-9 * scale);
            prop_assert!((sst.fixed_view::<6, 1>(0, 6) - c).abs().max() < 1e-12);
            let cross = sst.fixed_view::<6, 1>(0, 7) - d * (a2 * l2);
            prop_assert!(cross.abs().max() < 1e-12 * scale);
            prop_assert!((sst[(6, 6)] - l2).abs() < 1e-12);
            prop_assert!((sst[(7, 7)] - a2 * l2).abs() < 1e-12);
            prop_assert!(sst[(6, 7)] == 0.0);
            // Lower block-triangular: zeros below the state block.
            prop_assert!(s.fixed_view::<2, 6>(6, 0).abs().max() == 0.0);
            // With D = 0 the p = 1 factor of docs/conventions.md, "CCSP filter", bit for bit.
            let s0 = factor(&pc, &c, &Vector6::zeros(), &Vector6::zeros(), 1.0, l1, l2, alpha, 0.0)
                .unwrap();
            prop_assert!(s0.fixed_view::<7, 7>(0, 0) == s.fixed_view::<7, 7>(0, 0));
            prop_assert!(s0.fixed_view::<6, 1>(0, 7).abs().max() == 0.0);
        }

        #[test]
        fn factor_carries_the_slow_term_times_its_correlation(
            diag in proptest::collection::vec(1.0f64..100.0, 6),
            e in proptest::collection::vec(-3.0f64..3.0, 6),
            rho in 0.0f64..1.0,
            l1 in 1.0f64..5.0,
            l2 in 1.0f64..5.0,
        ) {
            // The s block: cross a^2 l2 rho E, variance a^2 l2; the state block holds
            // l1 (pc + (1 - rho^2) E E^T) besides the s point's a^2 l2 rho^2 E E^T.
            let pc = Matrix6::from_diagonal(&Vector6::from_column_slice(&diag));
            let e = Vector6::from_column_slice(&e);
            let z = Vector6::zeros();
            let a = 0.1;
            let s = factor(&pc, &z, &z, &e, rho, l1, l2, a, 0.0).unwrap();
            let sst = s * s.transpose();
            let a2l2 = a * a * l2;
            let scale = (pc * l1 + e * e.transpose() * l1).abs().max();
            let held = (pc + e * e.transpose() * (1.0 - rho * rho)) * l1
                + e * e.transpose() * (a2l2 * rho * rho);
            prop_assert!((sst.fixed_view::<6, 6>(0, 0) - held).abs().max() < 1e-9 * scale);
            let cross = sst.fixed_view::<6, 1>(0, 8) - e * (a2l2 * rho);
            prop_assert!(cross.abs().max() < 1e-12 * scale);
            prop_assert!((sst[(8, 8)] - a2l2).abs() < 1e-12);
            prop_assert!(sst[(6, 8)] == 0.0 && sst[(7, 8)] == 0.0);
        }
    }

    #[test]
    fn non_positive_definite_is_an_error_naming_the_epoch() {
        let p = Matrix6::from_diagonal(&Vector6::new(1.0, 1.0, 1.0, 1.0, 1.0, -1.0));
        let z = Vector6::zeros();
        let e = factor(&p, &z, &z, &z, 1.0, 3.0, 3.0, DRAG_ALPHA, 7200.0).unwrap_err();
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
            forces: crate::problem::Forces::AUTO,
        };
        let mut p0 = [[0.0; 6]; 6];
        for i in 0..6 {
            p0[i][i] = if i < 3 { 1.0 } else { 1e-6 };
        }
        let cfg = CcspConfig {
            problem,
            p0,
            update_times: vec![600.0, 1200.0, 3600.0, 7200.0],
            output_times: vec![],
            scaling: (3.0, 3.0),
            kappa_scale: 1.0,
            perturbation: Perturbation::Additive,
            method: FixedMethod::Rk8,
            max_step: 180.0,
            drag_sigma: 0.0,
            coordinates: Coordinates::Equinoctial,
            slow: None,
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
    fn outputs_between_updates_are_the_moments_of_the_points_in_flight() {
        use crate::density::Exponential;
        let atm = Exponential::new(3.725e-12, 400e3, 58.515e3, 0.2).unwrap();
        // One update at 2 h with outputs at 1 h and 1.5 h: the 1-hour output is the first
        // update of a run that updates at 1 h (same points, same 180-s steps: same bits),
        // and the 2-hour output is that of a run without the extra outputs.
        let mut cfg = paper_config(vec![7200.0], 0.3);
        cfg.output_times = vec![3600.0, 5400.0];
        let out = ccsp(&atm, &cfg, &Progress::default()).unwrap();
        assert_eq!(out.times, vec![0.0, 3600.0, 5400.0, 7200.0]);
        let hourly = ccsp(&atm, &paper_config(vec![3600.0], 0.3), &Progress::default()).unwrap();
        assert_eq!(out.means[1], hourly.means[1]);
        assert_eq!(out.covariances[1], hourly.covariances[1]);
        assert_eq!(out.drag_cross[1], hourly.drag_cross[1]);
        let plain = ccsp(&atm, &paper_config(vec![7200.0], 0.3), &Progress::default()).unwrap();
        assert_eq!(out.means[3], plain.means[1]);
        assert_eq!(out.covariances[3], plain.covariances[1]);
        // An output time on an update is that update's; outside (0, end) an error.
        cfg.output_times = vec![3600.0, 7200.0];
        assert!(ccsp(&atm, &cfg, &Progress::default()).is_err());
        let mut two = paper_config(vec![3600.0, 7200.0], 0.0);
        two.output_times = vec![3600.0];
        let out = ccsp(&atm, &two, &Progress::default()).unwrap();
        assert_eq!(out.times, vec![0.0, 3600.0, 7200.0]);
        two.output_times = vec![1800.0, 1800.0];
        assert!(ccsp(&atm, &two, &Progress::default()).is_err());
    }

    #[test]
    fn a_certain_density_runs_for_a_year_on_daily_updates() {
        // The covariance stays at millimetres and a and lambda correlate to 1 - 6e-8: the
        // energy a's rounding (1e-9 m) is then 3e-7 of its sigma, which the rounding
        // repair must recognise (it stopped the run at 36 days with a fixed 1e-9 bound).
        use crate::density::Exponential;
        let atm = Exponential::new(3.725e-12, 400e3, 58.515e3, 0.0).unwrap();
        let cfg = paper_config((1..=400).map(|i| i as f64 * 86400.0).collect(), 0.0);
        let out = ccsp(&atm, &cfg, &Progress::default()).unwrap();
        assert_eq!((out.times.len(), out.decayed_at), (401, None));
    }

    #[test]
    fn cancel_stops_the_run() {
        use crate::density::Exponential;
        use std::sync::atomic::Ordering;
        let atm = Exponential::new(3.725e-12, 400e3, 58.515e3, 0.2).unwrap();
        let cfg = paper_config(vec![3600.0, 7200.0], 0.0);
        let p = Progress::default();
        p.cancel.store(true, Ordering::Relaxed);
        assert_eq!(ccsp(&atm, &cfg, &p).unwrap_err(), CoreError::Cancelled);
        // Not cancelled: every update is counted.
        let p = Progress::default();
        let out = ccsp(&atm, &cfg, &p).unwrap();
        assert_eq!(out.times, vec![0.0, 3600.0, 7200.0]);
        assert_eq!(p.done.load(Ordering::Relaxed), 2);
    }

    #[test]
    fn kappa_scale_scales_the_density_covariance_by_its_square() {
        // The density term of the covariance is linear in kappa's variance to first order:
        // with kappa at half scale the position variance (grown from 1 mm^2 to ~(2 km)^2
        // in 3 days) is a quarter, up to the sigma points' nonlinearity (< 1 %).
        use crate::density::Exponential;
        let atm = Exponential::new(3.725e-12, 400e3, 58.515e3, 0.2).unwrap();
        let hours: Vec<f64> = (1..=72).map(|h| h as f64 * 3600.0).collect();
        let trace = |scale: f64| {
            let cfg = CcspConfig {
                kappa_scale: scale,
                ..paper_config(hours.clone(), 0.0)
            };
            let out = ccsp(&atm, &cfg, &Progress::default()).unwrap();
            let p = out.covariances.last().unwrap();
            (0..3).map(|i| p[i][i]).sum::<f64>()
        };
        let (full, half) = (trace(1.0), trace(0.5));
        assert!(full > 1e6, "{full}");
        assert!((half / full - 0.25).abs() < 0.0025, "{}", half / full);
        let bad = CcspConfig {
            kappa_scale: -1.0,
            ..paper_config(hours.clone(), 0.0)
        };
        assert!(ccsp(&atm, &bad, &Progress::default()).is_err());
    }

    /// Along-track 1-sigma (m) of `positions` (members x 3) about their mean, in the RTN
    /// frame of the mean state `mean`.
    fn along_track_spread(positions: &[[f64; 3]], mean: &[f64; 6]) -> f64 {
        let basis =
            crate::frames::rtn_basis([mean[0], mean[1], mean[2]], [mean[3], mean[4], mean[5]]);
        let n = positions.len() as f64;
        let m: [f64; 3] = std::array::from_fn(|i| positions.iter().map(|p| p[i]).sum::<f64>() / n);
        let t: Vec<f64> = positions
            .iter()
            .map(|p| (0..3).map(|i| (p[i] - m[i]) * basis[1][i]).sum())
            .collect();
        let tm = t.iter().sum::<f64>() / n;
        (t.iter().map(|x| (x - tm) * (x - tm)).sum::<f64>() / (n - 1.0)).sqrt()
    }

    /// The filter's along-track 1-sigma (m) at output `k`, in the RTN frame of its mean,
    /// and that mean.
    fn along_track_sigma(out: &CcspOutput, k: usize) -> (f64, [f64; 6]) {
        let m = out.means[k];
        let basis = crate::frames::rtn_basis([m[0], m[1], m[2]], [m[3], m[4], m[5]]);
        let p = out.covariances[k];
        let tt: f64 = (0..3)
            .flat_map(|i| (0..3).map(move |j| (i, j)))
            .map(|(i, j)| basis[1][i] * p[i][j] * basis[1][j])
            .sum();
        (tt.sqrt(), m)
    }

    #[test]
    fn along_track_sigma_matches_the_monte_carlo_of_its_process_to_30_days() {
        // The process the filter linearises (docs/conventions.md, "CCSP filter"): kappa
        // piecewise constant over the hourly update interval, correlation 1 / l2 = 1/3,
        // with a 10 % Cd*A/m sigma, through the exponential atmosphere with a 20 % sigma.
        // 400 members: the sample sigma's own 1-sigma is 1 / sqrt(2 * 400) = 3.5 %, so 10 %
        // is a 3-sigma bound. In Cartesian coordinates the filter grew 1.2x at 7 days,
        // 3x at 14 and 9x at 19 (its points gain energy in pairs); that must stay visible.
        use crate::density::Exponential;
        use crate::kappa::KappaProcess;
        use crate::montecarlo::{monte_carlo, MonteCarloConfig};
        let atm = Exponential::new(3.725e-12, 400e3, 58.515e3, 0.2).unwrap();
        let days = [1.0, 3.0, 7.0, 14.0, 21.0, 30.0];
        let hours: Vec<f64> = (1..=30 * 24).map(|h| h as f64 * 3600.0).collect();
        let cfg = paper_config(hours.clone(), 0.1);
        let eq = ccsp(&atm, &cfg, &Progress::default()).unwrap();
        let cart_cfg = CcspConfig {
            coordinates: Coordinates::Cartesian,
            update_times: hours[..14 * 24].to_vec(),
            ..cfg.clone()
        };
        let cart = ccsp(&atm, &cart_cfg, &Progress::default()).unwrap();
        let outputs: Vec<f64> = days.iter().map(|d| d * 86400.0).collect();
        let mc = monte_carlo(
            &atm,
            &MonteCarloConfig {
                problem: cfg.problem,
                initial_factor: None,
                kappa: KappaProcess::PiecewiseConstant {
                    interval: 3600.0,
                    correlation: 1.0 / 3.0,
                },
                perturbation: Perturbation::Additive,
                method: FixedMethod::Rk8,
                max_step: 180.0,
                output_times: outputs.clone(),
                members: 400,
                seed: 7,
                record_density: false,
                drag_sigma: 0.1,
            },
            &Progress::default(),
        )
        .unwrap();
        let nt = outputs.len();
        let sigma_of = |out: &CcspOutput, t: f64| {
            along_track_sigma(out, out.times.iter().position(|&x| x == t).unwrap())
        };
        for (j, &t) in outputs.iter().enumerate() {
            let members: Vec<[f64; 3]> = (0..400)
                .map(|m| std::array::from_fn(|i| mc.positions[(m * nt + j) * 3 + i]))
                .collect();
            let (sigma, mean) = sigma_of(&eq, t);
            let ratio = sigma / along_track_spread(&members, &mean);
            assert!((ratio - 1.0).abs() < 0.10, "day {}: ratio {ratio}", days[j]);
            if days[j] == 14.0 {
                let (cs, cm) = sigma_of(&cart, t);
                let cr = cs / along_track_spread(&members, &cm);
                assert!(cr > 2.0, "Cartesian at 14 days: ratio {cr}");
            }
        }
    }

    /// The paper's orbit and craft with the paper's near-zero initial covariance.
    fn paper_config(update_times: Vec<f64>, drag_sigma: f64) -> CcspConfig {
        let mut p0 = [[0.0; 6]; 6];
        for i in 0..6 {
            p0[i][i] = if i < 3 { 1e-6 } else { 1e-12 };
        }
        CcspConfig {
            problem: Problem {
                epoch: 8.4e7,
                y0: crate::constants::PAPER_STATE,
                drag: 3.0912 * 0.0015,
                floor_altitude: 120e3,
                zonal_degree: 2,
                forces: crate::problem::Forces::AUTO,
            },
            p0,
            update_times,
            output_times: vec![],
            scaling: (3.0, 3.0),
            kappa_scale: 1.0,
            perturbation: Perturbation::Additive,
            method: FixedMethod::Rk8,
            max_step: 180.0,
            drag_sigma,
            coordinates: Coordinates::Equinoctial,
            slow: None,
        }
    }

    /// Position at `t` of the paper's orbit with Cd*A/m times `factor`.
    fn position_with_drag(
        atm: &crate::density::Exponential,
        cfg: &CcspConfig,
        factor: f64,
        t: f64,
    ) -> Vector6<f64> {
        use crate::propagate::{propagate, Method};
        let mut problem = cfg.problem;
        problem.drag *= factor;
        let tr = propagate(
            atm,
            &problem,
            &[t],
            Method::Rk8 { step: 180.0 },
            &Progress::default(),
        )
        .unwrap();
        Vector6::from_column_slice(&tr.states[0])
    }

    #[test]
    fn drag_consider_parameter_is_the_linearised_sensitivity_and_is_never_forgotten() {
        use crate::density::Exponential;
        // Certain density: the covariance growth comes from Cd*A/m alone. Its
        // cross-covariance must equal drag_sigma * dx/d(ln Cd*A/m) (central differences of
        // two deterministic runs), whatever the update interval (c is a constant of the
        // object, unlike kappa).
        // Also at 30 % over 3 days, where along-track spreads of 10 km make Cartesian
        // sigma points at sqrt(3) sigma fail (DRAG_ALPHA).
        let atm = Exponential::new(3.725e-12, 400e3, 58.515e3, 0.0).unwrap();
        for (sigma, days, tol) in [(0.02, 1, 1e-4), (0.3, 3, 1e-3)] {
            let end = days as f64 * 86400.0;
            let hourly = paper_config((1..=24 * days).map(|i| i as f64 * 3600.0).collect(), sigma);
            let six_hourly =
                paper_config((1..=4 * days).map(|i| i as f64 * 21600.0).collect(), sigma);
            let eps: f64 = 1e-3;
            let sens = (position_with_drag(&atm, &hourly, eps.exp(), end)
                - position_with_drag(&atm, &hourly, (-eps).exp(), end))
                / (2.0 * eps)
                * sigma;
            // Hundreds of metres at 2 % after a day, tens of km at 30 % after 3 days.
            assert!(sens.fixed_rows::<3>(0).norm() > 50.0, "{}", sens.norm());
            for cfg in [&hourly, &six_hourly] {
                let out = ccsp(&atm, cfg, &Progress::default()).unwrap();
                let d = Vector6::from_column_slice(out.drag_cross.last().unwrap());
                let rel = (d - sens).fixed_rows::<3>(0).norm() / sens.fixed_rows::<3>(0).norm();
                assert!(rel < tol, "D vs finite differences at {sigma}: {rel}");
                // The position variance along D is D D^T plus the tiny initial covariance.
                let p = Matrix6::from_fn(|i, j| out.covariances.last().unwrap()[i][j]);
                let u = sens.fixed_rows::<3>(0).normalize();
                let var = (u.transpose() * p.fixed_view::<3, 3>(0, 0) * u)[(0, 0)];
                let expect = sens.fixed_rows::<3>(0).norm_squared();
                assert!((var / expect - 1.0).abs() < 2.0 * tol, "{var} vs {expect}");
                assert!(out.cross.iter().all(|c| c.iter().all(|&v| v == 0.0)));
            }
        }
    }

    #[test]
    fn many_objects_in_one_call_equal_each_alone_bit_for_bit() {
        use crate::density::Exponential;
        // 15 and 16 sigma points in one batch each, different epochs, update grids and
        // drag sigmas: every object's output is that of `ccsp` alone (lanes never mix).
        let atm = Exponential::new(3.725e-12, 400e3, 58.515e3, 0.2).unwrap();
        let cfgs: Vec<CcspConfig> = (0..5)
            .map(|k| {
                let dt = 1800.0 + 700.0 * k as f64;
                let mut cfg = paper_config(
                    (1..=4 + k).map(|i| i as f64 * dt).collect(),
                    [0.0, 0.1, 0.3][k % 3],
                );
                cfg.problem.epoch += 977.0 * k as f64;
                cfg
            })
            .collect();
        let together = ccsp_many(&atm, &cfgs, &Progress::default()).unwrap();
        for (cfg, got) in cfgs.iter().zip(together) {
            assert_eq!(got.unwrap(), ccsp(&atm, cfg, &Progress::default()).unwrap());
        }
        // An object's error stays its own; cancelling stops the call.
        let mut bad = cfgs.clone();
        bad[1].p0[0][0] = -1.0;
        let out = ccsp_many(&atm, &bad, &Progress::default()).unwrap();
        assert!(out[0].is_ok() && out[1].is_err() && out[2].is_ok());
        let p = Progress::default();
        p.cancel.store(true, std::sync::atomic::Ordering::Relaxed);
        assert_eq!(
            ccsp_many(&atm, &cfgs, &p).unwrap_err(),
            CoreError::Cancelled
        );
    }

    #[test]
    fn lane_width_batches_in_parallel_give_the_same_bits_as_one_batch() {
        use crate::density::Exponential;
        let atm = Exponential::new(3.725e-12, 400e3, 58.515e3, 0.2).unwrap();
        for sigma in [0.0, 0.2] {
            let cfg = paper_config((1..=8).map(|i| i as f64 * 2700.0).collect(), sigma);
            let p = Progress::default();
            assert_eq!(
                run(&atm, &cfg, &p, Grouping::Lanes).unwrap(),
                run(&atm, &cfg, &p, Grouping::Whole).unwrap()
            );
        }
    }

    #[test]
    fn zero_drag_sigma_is_the_paper_filter() {
        use crate::density::Exponential;
        // drag_sigma = 0: no c points, D stays zero, and the result does not depend on
        // anything of the second consider parameter.
        let atm = Exponential::new(3.725e-12, 400e3, 58.515e3, 0.2).unwrap();
        let cfg = paper_config((1..=6).map(|i| i as f64 * 3600.0).collect(), 0.0);
        let out = ccsp(&atm, &cfg, &Progress::default()).unwrap();
        assert!(out.drag_cross.iter().all(|d| d.iter().all(|&v| v == 0.0)));
        let with = ccsp(
            &atm,
            &paper_config(cfg.update_times.clone(), 0.1),
            &Progress::default(),
        )
        .unwrap();
        // The kappa part (the filter's own mean, kappa cross-covariance) is the same with
        // the c points. (The Cartesian mean is the unscented transform of the whole
        // element Gaussian, c's part included.)
        assert_eq!(out.element_means, with.element_means);
        assert_eq!(out.cross, with.cross);
        assert!(with.covariances.last().unwrap()[0][0] > out.covariances.last().unwrap()[0][0]);
        let mut bad = cfg.clone();
        bad.drag_sigma = -0.1;
        assert!(ccsp(&atm, &bad, &Progress::default())
            .unwrap_err()
            .to_string()
            .starts_with("drag_sigma = -0.1 is invalid"));
    }
    #[test]
    fn a_slow_term_that_never_decorrelates_is_the_drag_parameter_of_its_sigma() {
        // Through the exponential atmosphere (sigma 0.2 everywhere) a constant density
        // scale s of weight 1 moves the orbit as a Cd*A/m sigma of 0.2 does, to first
        // order: the one-sided probes differ by exp(0.2 x) - 1 - 0.2 x at x = 1.7e-3.
        use crate::density::Exponential;
        let atm = Exponential::new(3.725e-12, 400e3, 58.515e3, 0.2).unwrap();
        let hours: Vec<f64> = (1..=72).map(|h| h as f64 * 3600.0).collect();
        let drag = CcspConfig {
            kappa_scale: 0.0,
            ..paper_config(hours.clone(), 0.2)
        };
        let slow = CcspConfig {
            kappa_scale: 0.0,
            slow: Some(SlowKappa {
                scale: 1.0,
                half_life: f64::INFINITY,
            }),
            ..paper_config(hours.clone(), 0.0)
        };
        let (a, b) = (
            ccsp(&atm, &drag, &Progress::default()).unwrap(),
            ccsp(&atm, &slow, &Progress::default()).unwrap(),
        );
        let (pa, pb) = (a.covariances.last().unwrap(), b.covariances.last().unwrap());
        // Kilometres along-track after 3 days: a real test of the sensitivity.
        assert!(pa[0][0] + pa[1][1] + pa[2][2] > 1e6);
        for i in 0..6 {
            for j in 0..6 {
                let scale = (pa[i][i] * pa[j][j]).sqrt();
                assert!((pa[i][j] - pb[i][j]).abs() < 1e-3 * scale, "{i} {j}");
            }
        }
        // Weight 0 is no slow term at all, bit for bit (no extra point is flown).
        let none = CcspConfig {
            slow: Some(SlowKappa {
                scale: 0.0,
                half_life: 86400.0,
            }),
            ..paper_config(hours.clone(), 0.1)
        };
        assert_eq!(
            ccsp(&atm, &none, &Progress::default()).unwrap(),
            ccsp(
                &atm,
                &paper_config(hours.clone(), 0.1),
                &Progress::default()
            )
            .unwrap()
        );
        for bad in [
            SlowKappa {
                scale: -1.0,
                half_life: 1.0,
            },
            SlowKappa {
                scale: 1.0,
                half_life: 0.0,
            },
            SlowKappa {
                scale: f64::NAN,
                half_life: 1.0,
            },
        ] {
            let cfg = CcspConfig {
                slow: Some(bad),
                ..paper_config(hours.clone(), 0.1)
            };
            let err = ccsp(&atm, &cfg, &Progress::default()).unwrap_err();
            assert!(err.to_string().contains("slow."), "{err}");
        }
    }

    #[test]
    fn the_two_scale_process_keeps_its_a_lambda_shape_to_two_weeks() {
        // The default density error (a 4.4-hour term and a 4.1-day one, 45 % of the
        // variance in the slow term) through the exponential atmosphere at 400 km with a
        // 10 % Cd*A/m sigma, against 2,000 members of that process. The slow term as its
        // own decorrelating parameter keeps the members inside the filter's 95 % region of
        // (a, lambda): with it constant (half-life infinite, as when it was folded into c
        // before 2026-12-05) 78 % and 65 % at 7 and 14 days. 2,000 members: the binomial
        // 1-sigma of a 95 % share is 0.5 %, so 92 % is a 6-sigma bound; the sample
        // along-track sigma's 1-sigma is 1.6 % (6 %: almost 4).
        use crate::density::Exponential;
        use crate::kappa::KappaProcess;
        use crate::montecarlo::{monte_carlo, MonteCarloConfig};
        let atm = Exponential::new(3.725e-12, 400e3, 58.515e3, 0.2).unwrap();
        let (half_life, slow_half_life, w): (f64, f64, f64) = (15840.0, 4.1 * 86400.0, 0.45);
        let hours: Vec<f64> = (1..=14 * 24).map(|h| h as f64 * 3600.0).collect();
        let cfg = CcspConfig {
            scaling: (3.0, 1.0 / (-3600.0f64 / half_life).exp2()),
            kappa_scale: (1.0 - w).sqrt(),
            slow: Some(SlowKappa {
                scale: w.sqrt(),
                half_life: slow_half_life,
            }),
            ..paper_config(hours, 0.1)
        };
        let out = ccsp(&atm, &cfg, &Progress::default()).unwrap();
        let days = [1.0, 7.0, 14.0];
        let outputs: Vec<f64> = days.iter().map(|d| d * 86400.0).collect();
        let members = 2000;
        let mc = monte_carlo(
            &atm,
            &MonteCarloConfig {
                problem: cfg.problem,
                initial_factor: None,
                kappa: KappaProcess::TwoScale {
                    half_life,
                    slow_half_life,
                    slow_fraction: w,
                    interval: 180.0,
                },
                perturbation: Perturbation::Additive,
                method: FixedMethod::Rk8,
                max_step: 180.0,
                output_times: outputs.clone(),
                members,
                seed: 11,
                record_density: false,
                drag_sigma: 0.1,
            },
            &Progress::default(),
        )
        .unwrap();
        let axes = equinoctial::Axes::for_state(&Vector6::from_column_slice(&cfg.problem.y0));
        let nt = outputs.len();
        for (j, &t) in outputs.iter().enumerate() {
            let k = out.times.iter().position(|&x| x == t).unwrap();
            let (em, ec) = (out.element_means[k], out.element_covariances[k]);
            let sub = nalgebra::Matrix2::new(ec[0][0], ec[0][5], ec[5][0], ec[5][5]);
            let inv = sub.try_inverse().unwrap();
            let mut inside = 0;
            let mut at = Vec::new();
            for m in 0..members {
                let x = Vector6::from_fn(|i, _| {
                    let base = (m * nt + j) * 3;
                    if i < 3 {
                        mc.positions[base + i]
                    } else {
                        mc.velocities[base + i - 3]
                    }
                });
                let el = equinoctial::from_cartesian_with(&x, axes, SEMI, "member").unwrap();
                let el = equinoctial::unwrap_near(&el, em[5]);
                let dv = nalgebra::Vector2::new(el[0] - em[0], el[5] - em[5]);
                if (dv.transpose() * inv * dv)[(0, 0)] <= 5.991464547107979 {
                    inside += 1;
                }
                at.push([x[0], x[1], x[2]]);
            }
            let share = inside as f64 / members as f64;
            assert!(share > 0.92, "day {}: {share} inside (a, lambda)", days[j]);
            let (sigma, m) = along_track_sigma(&out, k);
            let ratio = sigma / along_track_spread(&at, &m);
            assert!((ratio - 1.0).abs() < 0.06, "day {}: ratio {ratio}", days[j]);
        }
    }
}
