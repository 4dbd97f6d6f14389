//! Monte Carlo ensembles: members with their own kappa process and (optionally) sampled
//! initial states, integrated in batches of `LANES` members stepping together
//! (structure of arrays), batches in parallel with rayon. Memory grows with members x
//! output times, never with steps.

use crate::constants::R_EARTH;
use crate::density::Atmosphere;
use crate::dynamics::{Dynamics, Perturbation, State};
use crate::error::{finite, positive, CoreError};
use crate::integrators::{FixedMethod, FixedStepper};
use crate::kappa::{KappaLanes, KappaProcess};
use crate::propagate::{altitude, check_state};
use crate::rng::MemberStream;
use rayon::prelude::*;
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};

/// Members per batch (SIMD-friendly lane count).
pub const LANES: usize = 4;

/// Shared progress counter and cancellation flag of a run.
#[derive(Debug, Default)]
pub struct Progress {
    /// Members finished.
    pub done: AtomicUsize,
    /// Set to stop the run; it then returns [`CoreError::Cancelled`].
    pub cancel: AtomicBool,
}

/// What to run.
#[derive(Debug, Clone)]
pub struct MonteCarloConfig {
    /// Epoch, seconds since J2000.
    pub epoch: f64,
    /// Mean initial state (m, m/s).
    pub y0: [f64; 6],
    /// Drag parameter Cd*A/m, m^2/kg.
    pub drag: f64,
    /// Factor L with L L^T = initial covariance (row-major), or None for a fixed state.
    pub initial_factor: Option<[[f64; 6]; 6]>,
    pub kappa: KappaProcess,
    pub perturbation: Perturbation,
    pub method: FixedMethod,
    /// Largest integration step, s; the step used divides the kappa node spacing.
    pub max_step: f64,
    /// Output times, s from the epoch: increasing, each a multiple of the step or the end.
    pub output_times: Vec<f64>,
    pub members: usize,
    pub seed: u64,
    pub floor_altitude: f64,
    /// Also return the density each member sees at the output times.
    pub record_density: bool,
}

/// Results, row-major: member, output time, component.
#[derive(Debug, Clone, PartialEq)]
pub struct MonteCarloOutput {
    /// Positions (members x times x 3), m.
    pub positions: Vec<f64>,
    /// Velocities (members x times x 3), m/s.
    pub velocities: Vec<f64>,
    /// Densities seen (members x times), kg/m^3, when recorded.
    pub densities: Option<Vec<f64>>,
    /// Density evaluations clipped at zero, per member.
    pub clipped: Vec<u64>,
    /// Decay time per member (s from the epoch), infinite when it did not decay.
    pub decay_times: Vec<f64>,
    /// Integration step used, s.
    pub step: f64,
}

struct BatchOut {
    positions: Vec<f64>,
    velocities: Vec<f64>,
    densities: Vec<f64>,
    clipped: [u64; LANES],
    decay: [f64; LANES],
}

/// Step boundaries of a run: the uniform grid k h (kappa nodes fall on it) up to the last
/// output, plus every output time, so outputs need not be multiples of the step.
#[derive(Debug, Clone, PartialEq)]
struct Schedule {
    times: Vec<f64>,
    /// The grid index k of a boundary that lies on the uniform grid.
    grid: Vec<Option<usize>>,
    /// Boundary index of each output.
    outputs: Vec<usize>,
}

fn schedule(outputs: &[f64], h: f64) -> Schedule {
    let end = *outputs.last().expect("checked non-empty");
    let n = ((end / h) * (1.0 - 1e-12)).ceil().max(0.0) as usize;
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
    let outputs = outputs
        .iter()
        .map(|&t| {
            let j = times.partition_point(|&b| b < t - tol);
            j.min(times.len() - 1)
        })
        .collect();
    Schedule {
        times,
        grid,
        outputs,
    }
}

/// Runs the ensemble. `progress.done` counts finished members; setting `progress.cancel`
/// stops the run at the next batch.
pub fn monte_carlo<A: Atmosphere + ?Sized>(
    atmosphere: &A,
    cfg: &MonteCarloConfig,
    progress: &Progress,
) -> Result<MonteCarloOutput, CoreError> {
    finite("epoch", cfg.epoch)?;
    positive("drag parameter Cd*A/m", cfg.drag)?;
    positive("step", cfg.max_step)?;
    cfg.kappa.check()?;
    check_state(cfg.epoch, &cfg.y0, cfg.floor_altitude)?;
    crate::integrators::check_times("output times", 0.0, &cfg.output_times)?;
    if cfg.members == 0 {
        return Err(CoreError::invalid("members", 0.0, "must be >= 1"));
    }
    let h = cfg.kappa.integration_step(cfg.max_step);
    let plan = schedule(&cfg.output_times, h);
    let nt = cfg.output_times.len();
    let batches = cfg.members.div_ceil(LANES);

    let results: Vec<BatchOut> = (0..batches)
        .into_par_iter()
        .map(|b| {
            if progress.cancel.load(Ordering::Relaxed) {
                return Err(CoreError::Cancelled);
            }
            let first = b * LANES;
            let lanes = LANES.min(cfg.members - first);
            let out = run_batch_dispatch(atmosphere, cfg, h, &plan, first, lanes)?;
            progress.done.fetch_add(lanes, Ordering::Relaxed);
            Ok(out)
        })
        .collect::<Result<_, _>>()?;

    let n = cfg.members;
    let mut positions = Vec::with_capacity(n * nt * 3);
    let mut velocities = Vec::with_capacity(n * nt * 3);
    let mut densities = Vec::with_capacity(if cfg.record_density { n * nt } else { 0 });
    let mut clipped = Vec::with_capacity(n);
    let mut decay_times = Vec::with_capacity(n);
    for (b, r) in results.into_iter().enumerate() {
        let lanes = LANES.min(n - b * LANES);
        positions.extend_from_slice(&r.positions[..lanes * nt * 3]);
        velocities.extend_from_slice(&r.velocities[..lanes * nt * 3]);
        if cfg.record_density {
            densities.extend_from_slice(&r.densities[..lanes * nt]);
        }
        clipped.extend_from_slice(&r.clipped[..lanes]);
        decay_times.extend_from_slice(&r.decay[..lanes]);
    }
    Ok(MonteCarloOutput {
        positions,
        velocities,
        densities: cfg.record_density.then_some(densities),
        clipped,
        decay_times,
        step: h,
    })
}

/// Runs a batch with the widest instruction set the CPU offers (runtime dispatch keeps the
/// wheel portable): AVX2 + FMA when available, else the baseline build.
fn run_batch_dispatch<A: Atmosphere + ?Sized>(
    atmosphere: &A,
    cfg: &MonteCarloConfig,
    h: f64,
    plan: &Schedule,
    first: usize,
    lanes: usize,
) -> Result<BatchOut, CoreError> {
    #[cfg(target_arch = "x86_64")]
    {
        if std::arch::is_x86_feature_detected!("avx2") && std::arch::is_x86_feature_detected!("fma")
        {
            // SAFETY: the CPU supports AVX2 and FMA, checked just above.
            return unsafe { run_batch_avx2(atmosphere, cfg, h, plan, first, lanes) };
        }
    }
    run_batch(atmosphere, cfg, h, plan, first, lanes)
}

/// `run_batch` compiled for AVX2 + FMA (the step, RHS and stage arithmetic inline into it).
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,fma")]
unsafe fn run_batch_avx2<A: Atmosphere + ?Sized>(
    atmosphere: &A,
    cfg: &MonteCarloConfig,
    h: f64,
    plan: &Schedule,
    first: usize,
    lanes: usize,
) -> Result<BatchOut, CoreError> {
    run_batch(atmosphere, cfg, h, plan, first, lanes)
}

/// Integrates members `first .. first + lanes` as one batch (unused lanes repeat the
/// first member and are discarded).
#[inline(always)]
fn run_batch<A: Atmosphere + ?Sized>(
    atmosphere: &A,
    cfg: &MonteCarloConfig,
    h: f64,
    plan: &Schedule,
    first: usize,
    lanes: usize,
) -> Result<BatchOut, CoreError> {
    let nt = plan.outputs.len();
    let mut streams: [MemberStream; LANES] =
        std::array::from_fn(|l| MemberStream::new(cfg.seed, (first + l.min(lanes - 1)) as u64));
    let mut y: State<LANES> = [[0.0; LANES]; 6];
    for l in 0..LANES {
        let mut s = cfg.y0;
        if let Some(f) = &cfg.initial_factor {
            let z: [f64; 6] = std::array::from_fn(|_| streams[l].normal());
            for (i, si) in s.iter_mut().enumerate() {
                *si += (0..6).map(|j| f[i][j] * z[j]).sum::<f64>();
            }
        }
        for c in 0..6 {
            y[c][l] = s[c];
        }
    }
    for l in 0..lanes {
        let s: [f64; 6] = std::array::from_fn(|c| y[c][l]);
        check_state(cfg.epoch, &s, cfg.floor_altitude).map_err(|e| {
            CoreError::invalid(
                format!("sampled initial state of member {}", first + l),
                0.0,
                format!("{e}; the initial covariance reaches below the floor"),
            )
        })?;
    }

    let mut dynamics = Dynamics::<A, LANES>::new(atmosphere, cfg.epoch, [cfg.drag; LANES]);
    dynamics.perturbation = cfg.perturbation;
    let spacing = cfg.kappa.node_spacing(h);
    let per_node = spacing.map_or(usize::MAX, |d| ((d / h).round() as usize).max(1));
    let mut kappa = KappaLanes::<LANES> {
        t0: 0.0,
        t1: spacing.unwrap_or(f64::INFINITY),
        k0: [0.0; LANES],
        k1: [0.0; LANES],
        linear: cfg.kappa.is_linear(),
    };
    for l in 0..LANES {
        kappa.k0[l] = cfg.kappa.first(&mut streams[l]);
        if kappa.linear {
            kappa.k1[l] = cfg
                .kappa
                .next(kappa.k0[l], spacing.unwrap_or(h), &mut streams[l]);
        }
    }
    dynamics.kappa = kappa;

    let mut out = BatchOut {
        positions: vec![0.0; LANES * nt * 3],
        velocities: vec![0.0; LANES * nt * 3],
        densities: vec![0.0; if cfg.record_density { LANES * nt } else { 0 }],
        clipped: [0; LANES],
        decay: [f64::INFINITY; LANES],
    };
    let mut frozen: [Option<[f64; 6]>; LANES] = [None; LANES];
    let record = |k: usize,
                  t: f64,
                  y: &State<LANES>,
                  dynamics: &Dynamics<A, LANES>,
                  frozen: &[Option<[f64; 6]>; LANES],
                  out: &mut BatchOut|
     -> Result<(), CoreError> {
        for (i, _) in plan.outputs.iter().enumerate().filter(|(_, &s)| s == k) {
            for l in 0..LANES {
                let s: [f64; 6] = frozen[l].unwrap_or_else(|| std::array::from_fn(|c| y[c][l]));
                let o = (l * nt + i) * 3;
                out.positions[o..o + 3].copy_from_slice(&s[..3]);
                out.velocities[o..o + 3].copy_from_slice(&s[3..]);
                if cfg.record_density {
                    out.densities[l * nt + i] = if frozen[l].is_some() {
                        0.0
                    } else {
                        dynamics.density(t, y, l)?
                    };
                }
            }
        }
        Ok(())
    };
    record(0, 0.0, &y, &dynamics, &frozen, &mut out)?;

    let mut stepper = FixedStepper::<LANES>::default();
    for j in 0..plan.times.len() - 1 {
        let (t, t_next) = (plan.times[j], plan.times[j + 1]);
        if matches!(plan.grid[j], Some(k) if k > 0 && k % per_node == 0) {
            // A new kappa node segment starts at this step.
            let kl = &mut dynamics.kappa;
            let d = spacing.expect("nodes exist when per_node is finite");
            kl.t0 = t;
            kl.t1 = t + d;
            for l in 0..LANES {
                if kl.linear {
                    kl.k0[l] = kl.k1[l];
                    kl.k1[l] = cfg.kappa.next(kl.k0[l], d, &mut streams[l]);
                } else {
                    kl.k0[l] = cfg.kappa.next(kl.k0[l], d, &mut streams[l]);
                }
            }
        }
        stepper.step(cfg.method, &mut dynamics, t, t_next - t, &mut y)?;
        for l in 0..LANES {
            // Geodetic altitude >= |r| - Re, so only orbits dipping below Re + floor need
            // the full geodetic conversion.
            let r = (y[0][l] * y[0][l] + y[1][l] * y[1][l] + y[2][l] * y[2][l]).sqrt();
            if frozen[l].is_none()
                && r < R_EARTH + cfg.floor_altitude
                && altitude(cfg.epoch + t_next, [y[0][l], y[1][l], y[2][l]]) < cfg.floor_altitude
            {
                frozen[l] = Some(std::array::from_fn(|c| y[c][l]));
                out.decay[l] = t_next;
                // A decayed lane keeps stepping harmlessly without drag; its outputs stay
                // frozen at the decay state.
                dynamics.drag[l] = 0.0;
            }
        }
        record(j + 1, t_next, &y, &dynamics, &frozen, &mut out)?;
        if frozen[..lanes].iter().all(Option::is_some) {
            for jj in j + 2..plan.times.len() {
                record(jj, plan.times[jj], &y, &dynamics, &frozen, &mut out)?;
            }
            break;
        }
    }
    out.clipped = dynamics.clipped;
    Ok(out)
}

/// A factor L with L L^T = `cov` for a symmetric positive semi-definite 6x6 matrix
/// (row-major), from its eigendecomposition; an error when it is not symmetric or has a
/// clearly negative eigenvalue.
pub fn covariance_factor(cov: &[[f64; 6]; 6]) -> Result<[[f64; 6]; 6], CoreError> {
    use nalgebra::{Matrix6, SymmetricEigen};
    let m = Matrix6::from_fn(|i, j| cov[i][j]);
    let scale = m.abs().max();
    if !scale.is_finite() {
        return Err(CoreError::invalid(
            "initial covariance",
            scale,
            "must be finite",
        ));
    }
    for i in 0..6 {
        for j in 0..i {
            if (m[(i, j)] - m[(j, i)]).abs() > 1e-12 * scale.max(f64::MIN_POSITIVE) {
                return Err(CoreError::invalid(
                    format!("initial covariance[{i}][{j}]"),
                    m[(i, j)],
                    format!(
                        "must equal covariance[{j}][{i}] = {} (symmetric)",
                        m[(j, i)]
                    ),
                ));
            }
        }
    }
    let eig = SymmetricEigen::new(m);
    let mut factor = [[0.0; 6]; 6];
    for k in 0..6 {
        let lambda = eig.eigenvalues[k];
        if lambda < -1e-10 * scale {
            return Err(CoreError::invalid(
                "initial covariance eigenvalue",
                lambda,
                "must be >= 0 (the matrix must be positive semi-definite)",
            ));
        }
        let s = lambda.max(0.0).sqrt();
        for i in 0..6 {
            factor[i][k] = eig.eigenvectors[(i, k)] * s;
        }
    }
    Ok(factor)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::density::Exponential;
    use crate::propagate::{propagate, Method};

    const PAPER: [f64; 6] = [
        3782900.7032,
        -5441600.6779,
        -1420075.1327,
        -606.6600,
        1539.2559,
        -7488.3946,
    ];

    fn config(members: usize, kappa: KappaProcess) -> MonteCarloConfig {
        MonteCarloConfig {
            epoch: 8.4e7,
            y0: PAPER,
            drag: 3.0912 * 0.0015,
            initial_factor: None,
            kappa,
            perturbation: Perturbation::Additive,
            method: FixedMethod::Rk8,
            max_step: 180.0,
            output_times: vec![0.0, 3600.0, 7200.0],
            members,
            seed: 5,
            floor_altitude: 120e3,
            record_density: true,
        }
    }

    #[test]
    fn zero_sigma_reproduces_the_deterministic_orbit_exactly() {
        let atm = Exponential::new(3.725e-12, 400e3, 58.515e3, 0.0).unwrap();
        let cfg = config(5, KappaProcess::GaussMarkov { half_life: 1080.0 });
        let out = monte_carlo(&atm, &cfg, &Progress::default()).unwrap();
        let det = propagate(
            &atm,
            cfg.epoch,
            PAPER,
            cfg.drag,
            &cfg.output_times,
            Method::Rk8 { step: 180.0 },
            120e3,
        )
        .unwrap();
        for m in 0..5 {
            for (i, s) in det.states.iter().enumerate() {
                for c in 0..3 {
                    assert_eq!(out.positions[(m * 3 + i) * 3 + c], s[c]);
                }
            }
        }
    }

    #[test]
    fn members_do_not_depend_on_batching() {
        let atm = Exponential::new(3.725e-12, 400e3, 58.515e3, 0.3).unwrap();
        let all = monte_carlo(
            &atm,
            &config(7, KappaProcess::White { step: 60.0 }),
            &Progress::default(),
        )
        .unwrap();
        let few = monte_carlo(
            &atm,
            &config(3, KappaProcess::White { step: 60.0 }),
            &Progress::default(),
        )
        .unwrap();
        assert_eq!(&all.positions[..few.positions.len()], &few.positions[..]);
        assert_eq!(
            &all.densities.as_ref().unwrap()[..9],
            &few.densities.as_ref().unwrap()[..]
        );
        // Member 2 and member 3 at the last output differ.
        assert_ne!(
            all.positions[(2 * 3 + 2) * 3],
            all.positions[(3 * 3 + 2) * 3]
        );
    }

    #[test]
    fn covariance_factor_reproduces_the_matrix() {
        let mut cov = [[0.0; 6]; 6];
        for i in 0..6 {
            for j in 0..6 {
                cov[i][j] = if i == j {
                    4.0 + i as f64
                } else {
                    0.5 / (1.0 + (i + j) as f64)
                };
            }
        }
        let f = covariance_factor(&cov).unwrap();
        for i in 0..6 {
            for j in 0..6 {
                let s: f64 = (0..6).map(|k| f[i][k] * f[j][k]).sum();
                assert!((s - cov[i][j]).abs() < 1e-12, "{i}{j}");
            }
        }
        let mut bad = cov;
        bad[0][1] += 0.1;
        assert!(covariance_factor(&bad)
            .unwrap_err()
            .to_string()
            .contains("symmetric"));
        let mut neg = [[0.0; 6]; 6];
        neg[2][2] = -1.0;
        assert!(covariance_factor(&neg)
            .unwrap_err()
            .to_string()
            .contains("semi-definite"));
    }

    #[test]
    fn outputs_off_the_step_grid_are_step_boundaries() {
        // Outputs between kappa nodes: with zero sigma the members follow the deterministic
        // orbit there (to the integrator's accuracy: different step partitions).
        let atm = Exponential::new(3.725e-12, 400e3, 58.515e3, 0.0).unwrap();
        let mut cfg = config(2, KappaProcess::Interpolated { interval: 1080.0 });
        cfg.output_times = vec![100.0, 3650.0, 7000.0];
        let out = monte_carlo(&atm, &cfg, &Progress::default()).unwrap();
        let det = propagate(
            &atm,
            cfg.epoch,
            PAPER,
            cfg.drag,
            &cfg.output_times,
            Method::Rk8 { step: 60.0 },
            120e3,
        )
        .unwrap();
        for (i, s) in det.states.iter().enumerate() {
            let d: f64 = (0..3)
                .map(|c| (out.positions[i * 3 + c] - s[c]).powi(2))
                .sum::<f64>()
                .sqrt();
            assert!(d < 1e-3, "output {i}: {d} m");
        }
        let plan = schedule(&[100.0, 360.0, 400.0], 180.0);
        assert_eq!(plan.times, vec![0.0, 100.0, 180.0, 360.0, 400.0]);
        assert_eq!(plan.grid, vec![Some(0), None, Some(1), Some(2), Some(3)]);
        assert_eq!(plan.outputs, vec![1, 3, 4]);
    }

    #[test]
    fn cancel_stops_the_run() {
        let atm = Exponential::new(3.725e-12, 400e3, 58.515e3, 0.3).unwrap();
        let p = Progress::default();
        p.cancel.store(true, Ordering::Relaxed);
        let e = monte_carlo(&atm, &config(9, KappaProcess::Constant), &p).unwrap_err();
        assert_eq!(e, CoreError::Cancelled);
    }
}
