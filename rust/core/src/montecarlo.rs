//! The Monte Carlo engine: members with their own kappa process and (optionally) sampled
//! initial states, integrated in batches of W members (one per SIMD lane: 4, or 8 with
//! AVX-512) stepping together
//! (structure of arrays), batches in parallel with rayon, each batch run through the SIMD
//! [`dispatch`]. Memory grows with members x output times, never with steps.

use crate::constants::R_EARTH;
use crate::decay::{crossing, lane_step, may_cross_lanes, unbound_lanes};
use crate::density::Atmosphere;
use crate::dynamics::{Dynamics, Perturbation, State};
use crate::error::{positive, CoreError};
use crate::integrators::{drive, Control, FixedMethod, StepHooks, StepPlan};
use crate::kappa::{KappaLanes, KappaNode, KappaProcess};
use crate::problem::{check_drag_sigma, check_state, drag_factor, Problem};
use crate::progress::Progress;
use crate::rng::MemberStream;
use crate::simd::{batch_width, dispatch_on, Aligned, Kernel, SimdPath, BATCH_WIDTHS};
use rayon::prelude::*;

/// What to run.
#[derive(Debug, Clone)]
pub struct MonteCarloConfig {
    /// Epoch, mean initial state, drag parameter and decay floor.
    pub problem: Problem,
    /// Factor L with L L^T = initial covariance (row-major), or None for a fixed state.
    pub initial_factor: Option<[[f64; 6]; 6]>,
    pub kappa: KappaProcess,
    pub perturbation: Perturbation,
    pub method: FixedMethod,
    /// Largest integration step, s; the step used divides the kappa node spacing.
    pub max_step: f64,
    /// Output times, s from the epoch: increasing (any value; each becomes a step boundary).
    pub output_times: Vec<f64>,
    pub members: usize,
    pub seed: u64,
    /// Also return the density each member sees at the output times.
    pub record_density: bool,
    /// Relative 1-sigma of Cd*A/m (log-normal, see [`drag_factor`]): each member flies
    /// with Cd*A/m times exp(drag_sigma c), c ~ N(0, 1) drawn from its own stream
    /// ([`DRAG_DOMAIN`]); 0 gives every member the nominal value.
    pub drag_sigma: f64,
}

/// Stream domain of the members' ballistic-coefficient draws ([`MemberStream::with_domain`]):
/// apart from their kappa streams, so that turning `drag_sigma` on leaves each member's
/// density path unchanged.
pub const DRAG_DOMAIN: u64 = 1;

/// Factor on Cd*A/m of `member` for `seed` and `drag_sigma` (1 when it is 0): depends
/// only on these, never on the thread count or batch layout.
pub fn member_drag_factor(seed: u64, member: u64, drag_sigma: f64) -> f64 {
    if drag_sigma == 0.0 {
        return 1.0;
    }
    let c = MemberStream::with_domain(seed, member, DRAG_DOMAIN).normal();
    drag_factor(drag_sigma, c)
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
    /// Factor on Cd*A/m of each member (all 1 when `drag_sigma` is 0).
    pub drag_factors: Vec<f64>,
}

struct BatchOut<const W: usize> {
    positions: Vec<f64>,
    velocities: Vec<f64>,
    densities: Vec<f64>,
    clipped: [u64; W],
    decay: [f64; W],
}

/// Runs the ensemble. `progress.done` counts finished members; setting `progress.cancel`
/// stops the run at the next batch.
pub fn monte_carlo<A: Atmosphere + ?Sized>(
    atmosphere: &A,
    cfg: &MonteCarloConfig,
    progress: &Progress,
) -> Result<MonteCarloOutput, CoreError> {
    monte_carlo_on(SimdPath::detect(), atmosphere, cfg, progress)
}

/// [`monte_carlo`] on a given instruction-set path, in batches of
/// [`batch_width`] members. Every path and width gives bit-identical results: members
/// draw from their own streams and lanes never mix.
pub fn monte_carlo_on<A: Atmosphere + ?Sized>(
    path: SimdPath,
    atmosphere: &A,
    cfg: &MonteCarloConfig,
    progress: &Progress,
) -> Result<MonteCarloOutput, CoreError> {
    let width = batch_width(cfg.members, rayon::current_num_threads());
    monte_carlo_in(path, width, atmosphere, cfg, progress)
}

/// [`monte_carlo_on`] in batches of `width` members (one of [`BATCH_WIDTHS`]).
pub fn monte_carlo_in<A: Atmosphere + ?Sized>(
    path: SimdPath,
    width: usize,
    atmosphere: &A,
    cfg: &MonteCarloConfig,
    progress: &Progress,
) -> Result<MonteCarloOutput, CoreError> {
    match width {
        32 => run::<A, 32>(path, atmosphere, cfg, progress),
        16 => run::<A, 16>(path, atmosphere, cfg, progress),
        8 => run::<A, 8>(path, atmosphere, cfg, progress),
        _ => Err(CoreError::invalid(
            "batch width",
            width as f64,
            format!("must be one of {BATCH_WIDTHS:?}"),
        )),
    }
}

fn run<A: Atmosphere + ?Sized, const W: usize>(
    path: SimdPath,
    atmosphere: &A,
    cfg: &MonteCarloConfig,
    progress: &Progress,
) -> Result<MonteCarloOutput, CoreError> {
    cfg.problem.validate()?;
    positive("step", cfg.max_step)?;
    cfg.kappa.check()?;
    check_drag_sigma(cfg.drag_sigma)?;
    let h = cfg.kappa.integration_step(cfg.max_step);
    let plan = StepPlan::grid(&cfg.output_times, h)?;
    if cfg.members == 0 {
        return Err(CoreError::invalid("members", 0.0, "must be >= 1"));
    }
    let nt = cfg.output_times.len();
    let batches = cfg.members.div_ceil(W);
    // Reserved before the run, so that a run too large for memory fails at once.
    let n = cfg.members;
    let mut positions = output_buffer(n, nt * 3)?;
    let mut velocities = output_buffer(n, nt * 3)?;
    let mut densities = output_buffer(if cfg.record_density { n } else { 0 }, nt)?;
    let drag_factors: Vec<f64> = (0..n as u64)
        .map(|m| member_drag_factor(cfg.seed, m, cfg.drag_sigma))
        .collect();

    // Each batch writes its members' rows into its own slice of the output, as it
    // finishes: no second copy of the ensemble is ever held (the peak is the output).
    positions.resize(n * nt * 3, 0.0);
    velocities.resize(n * nt * 3, 0.0);
    densities.resize(if cfg.record_density { n * nt } else { 0 }, 0.0);
    let density_rows: Vec<&mut [f64]> = if cfg.record_density {
        densities.chunks_mut(W * nt).collect()
    } else {
        (0..batches).map(|_| <&mut [f64]>::default()).collect()
    };
    let slots: Vec<_> = positions
        .chunks_mut(W * nt * 3)
        .zip(velocities.chunks_mut(W * nt * 3))
        .zip(density_rows)
        .collect();
    let tails: Vec<([u64; W], [f64; W])> = slots
        .into_par_iter()
        .enumerate()
        .map(|(b, ((pos, vel), dens))| {
            progress.check()?;
            let first = b * W;
            let lanes = W.min(cfg.members - first);
            let out = dispatch_on(
                path,
                Batch::<A, W> {
                    atmosphere,
                    cfg,
                    h,
                    plan: &plan,
                    first,
                    lanes,
                    drag_factors: &drag_factors[first..first + lanes],
                },
            )?;
            pos.copy_from_slice(&out.positions[..lanes * nt * 3]);
            vel.copy_from_slice(&out.velocities[..lanes * nt * 3]);
            dens.copy_from_slice(&out.densities[..dens.len()]);
            progress.add(lanes);
            Ok((out.clipped, out.decay))
        })
        .collect::<Result<_, _>>()?;

    let mut clipped = Vec::with_capacity(n);
    let mut decay_times = Vec::with_capacity(n);
    for (b, (c, d)) in tails.into_iter().enumerate() {
        let lanes = W.min(n - b * W);
        clipped.extend_from_slice(&c[..lanes]);
        decay_times.extend_from_slice(&d[..lanes]);
    }
    Ok(MonteCarloOutput {
        positions,
        velocities,
        densities: cfg.record_density.then_some(densities),
        clipped,
        decay_times,
        step: h,
        drag_factors,
    })
}

/// An empty buffer with room for `members` x `per_member` values, or an error naming the
/// size when the memory cannot be had (instead of aborting the process).
fn output_buffer(members: usize, per_member: usize) -> Result<Vec<f64>, CoreError> {
    let len = members.checked_mul(per_member);
    let mut v = Vec::new();
    match len.map(|len| v.try_reserve_exact(len)) {
        Some(Ok(())) => Ok(v),
        _ => Err(CoreError::invalid(
            "members x output times",
            members as f64 * per_member as f64 * 8.0,
            "needs more memory than is available (value: bytes); use fewer members or \
             output times",
        )),
    }
}

/// Members `first .. first + lanes` as one batch (unused lanes repeat the last member and
/// are discarded).
struct Batch<'a, A: ?Sized, const W: usize> {
    atmosphere: &'a A,
    cfg: &'a MonteCarloConfig,
    /// Integration step, s.
    h: f64,
    plan: &'a StepPlan,
    first: usize,
    lanes: usize,
    /// Factor on Cd*A/m of each real lane.
    drag_factors: &'a [f64],
}

impl<A: Atmosphere + ?Sized, const W: usize> Kernel for Batch<'_, A, W> {
    type Output = Result<BatchOut<W>, CoreError>;

    #[inline(always)]
    fn run(self) -> Self::Output {
        let Batch {
            atmosphere,
            cfg,
            h,
            plan,
            first,
            lanes,
            drag_factors,
        } = self;
        let nt = cfg.output_times.len();
        let y0 = cfg.problem.y0;
        let mut streams: [MemberStream; W] =
            std::array::from_fn(|l| MemberStream::new(cfg.seed, (first + l.min(lanes - 1)) as u64));
        let mut state = Aligned::<State<W>>([[0.0; W]; 6]);
        let y = &mut state.0;
        for l in 0..W {
            let mut s = y0;
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
            check_state(cfg.problem.epoch, &s, cfg.problem.floor_altitude).map_err(|e| {
                CoreError::rejected(
                    format!("sampled initial state of member {}", first + l),
                    format!("{e}; the initial covariance reaches below the floor"),
                )
            })?;
        }

        let drag: [f64; W] =
            std::array::from_fn(|l| cfg.problem.drag * drag_factors[l.min(lanes - 1)]);
        let mut dynamics = Dynamics::<A, W>::for_problem(atmosphere, &cfg.problem, drag);
        dynamics.perturbation = cfg.perturbation;
        let spacing = cfg.kappa.node_spacing();
        let mut kappa = KappaLanes::<W> {
            t0: 0.0,
            t1: spacing.unwrap_or(f64::INFINITY),
            k0: [0.0; W],
            k1: [0.0; W],
            linear: cfg.kappa.is_linear(),
        };
        // The newest node of each lane (k1 when kappa is linear, k0 when held).
        let mut nodes = [KappaNode::default(); W];
        for l in 0..W {
            nodes[l] = cfg.kappa.first(&mut streams[l]);
            kappa.k0[l] = cfg.kappa.value(&nodes[l]);
            if kappa.linear {
                nodes[l] = cfg
                    .kappa
                    .next(&nodes[l], spacing.unwrap_or(h), &mut streams[l]);
                kappa.k1[l] = cfg.kappa.value(&nodes[l]);
            }
        }
        dynamics.kappa = kappa;

        let mut members = Members {
            cfg,
            first,
            h,
            lanes,
            nt,
            streams,
            nodes,
            spacing,
            per_node: spacing.map_or(usize::MAX, |d| ((d / h).round() as usize).max(1)),
            frozen: [None; W],
            last: (0.0, *y),
            out: BatchOut {
                positions: vec![0.0; W * nt * 3],
                velocities: vec![0.0; W * nt * 3],
                densities: vec![0.0; if cfg.record_density { W * nt } else { 0 }],
                clipped: [0; W],
                decay: [f64::INFINITY; W],
            },
        };
        drive(cfg.method, &mut dynamics, y, plan, &mut members)?;
        members.out.clipped = dynamics.clipped;
        Ok(members.out)
    }
}

/// Altitude (m, over the equatorial radius) below which a member whose step failed (its
/// orbit came out unbound) is counted decayed at the step's start: the drag that breaks a 180-s step
/// there ends the orbit within minutes anyway.
pub const RUNAWAY_DECAY_ALTITUDE: f64 = 200e3;

/// The members' side of a batch run: kappa nodes before steps, decay after them, the
/// record at outputs.
struct Members<'a, const W: usize> {
    cfg: &'a MonteCarloConfig,
    /// Index of the batch's first member, and the integration step, s (for errors).
    first: usize,
    h: f64,
    /// Lanes that hold real members.
    lanes: usize,
    /// Output times.
    nt: usize,
    streams: [MemberStream; W],
    /// The newest kappa node of each lane.
    nodes: [KappaNode; W],
    /// Kappa node spacing, s (None: no nodes after t = 0).
    spacing: Option<f64>,
    /// Grid steps per kappa node.
    per_node: usize,
    /// State of each decayed lane at its decay.
    frozen: [Option<[f64; 6]>; W],
    /// The previous step end (time, states), to locate decays within a step.
    last: (f64, State<W>),
    out: BatchOut<W>,
}

impl<A: Atmosphere + ?Sized, const W: usize> StepHooks<W, Dynamics<'_, A, W>> for Members<'_, W> {
    /// A new kappa node segment starts at a grid boundary that is a node.
    #[inline(always)]
    fn before_step(
        &mut self,
        _: usize,
        t: f64,
        grid: Option<usize>,
        dynamics: &mut Dynamics<'_, A, W>,
    ) {
        if matches!(grid, Some(k) if k > 0 && k % self.per_node == 0) {
            // A new segment is a jump in the right-hand side (or in its slope).
            dynamics.generation += 1;
            let kl = &mut dynamics.kappa;
            let d = self.spacing.expect("nodes exist when per_node is finite");
            kl.t0 = t;
            kl.t1 = t + d;
            for l in 0..W {
                let process = &self.cfg.kappa;
                self.nodes[l] = process.next(&self.nodes[l], d, &mut self.streams[l]);
                if kl.linear {
                    kl.k0[l] = kl.k1[l];
                    kl.k1[l] = process.value(&self.nodes[l]);
                } else {
                    kl.k0[l] = process.value(&self.nodes[l]);
                }
            }
        }
    }

    /// Freezes lanes that fell below the floor; holds once every member has.
    #[inline(always)]
    fn after_step(
        &mut self,
        t: f64,
        y: &mut State<W>,
        dynamics: &mut Dynamics<'_, A, W>,
    ) -> Result<Control, CoreError> {
        let (floor, epoch) = (self.cfg.problem.floor_altitude, self.cfg.problem.epoch);
        let (t0, prev) = self.last;
        let candidates = may_cross_lanes(t0, &prev, t, y, floor);
        for l in 0..W {
            if !candidates[l] || self.frozen[l].is_some() {
                continue;
            }
            let step = lane_step(t0, &prev, t, y, l);
            if let Some(tc) = crossing(epoch, &step, floor) {
                self.frozen[l] = Some(step.state_at(tc));
                self.out.decay[l] = tc;
                // A decayed lane keeps stepping harmlessly without drag; its outputs stay
                // frozen at the decay state.
                dynamics.drag[l] = 0.0;
                dynamics.generation += 1;
            }
        }
        // A live lane whose bound orbit came out unbound from a step was not integrated (a
        // drag too strong for the fixed step flung it out; it was counted a survivor 5e10 m
        // away). Below RUNAWAY_DECAY_ALTITUDE its reentry is at hand: it decays at the
        // step's start. Higher up the drag is absurd for the step: an error.
        let flung = unbound_lanes(&prev, y);
        for l in 0..self.lanes {
            if !flung[l] || self.frozen[l].is_some() {
                continue;
            }
            let start: [f64; 6] = std::array::from_fn(|c| prev[c][l]);
            let radius = (start[0] * start[0] + start[1] * start[1] + start[2] * start[2]).sqrt();
            if radius - R_EARTH < RUNAWAY_DECAY_ALTITUDE {
                self.frozen[l] = Some(start);
                self.out.decay[l] = t0;
                dynamics.drag[l] = 0.0;
                dynamics.generation += 1;
                continue;
            }
            return Err(CoreError::rejected(
                format!("member {}", self.first + l),
                format!(
                    "its orbit came out unbound from the step ending at t = {t} s, {:.0} km \
                     up, which drag cannot do: its drag (Cd*A/m = {:.3e} m^2/kg) is too \
                     strong for the fixed step of {} s; lower Cd*A/m or drag_sigma, or the \
                     step",
                    (radius - R_EARTH) / 1e3,
                    dynamics.drag[l],
                    self.h
                ),
            ));
        }
        self.last = (t, *y);
        Ok(if self.frozen[..self.lanes].iter().all(Option::is_some) {
            Control::Hold
        } else {
            Control::Continue
        })
    }

    #[inline(always)]
    fn on_output(
        &mut self,
        i: usize,
        t: f64,
        y: &State<W>,
        dynamics: &Dynamics<'_, A, W>,
    ) -> Result<(), CoreError> {
        let nt = self.nt;
        for l in 0..W {
            let frozen = self.frozen[l];
            let s: [f64; 6] = frozen.unwrap_or_else(|| std::array::from_fn(|c| y[c][l]));
            let o = (l * nt + i) * 3;
            self.out.positions[o..o + 3].copy_from_slice(&s[..3]);
            self.out.velocities[o..o + 3].copy_from_slice(&s[3..]);
            if self.cfg.record_density {
                self.out.densities[l * nt + i] = if frozen.is_some() {
                    0.0
                } else {
                    dynamics.density(t, y, l)?
                };
            }
        }
        Ok(())
    }
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
    use std::sync::atomic::Ordering;

    const PAPER: [f64; 6] = crate::constants::PAPER_STATE;

    fn config(members: usize, kappa: KappaProcess) -> MonteCarloConfig {
        MonteCarloConfig {
            problem: Problem {
                epoch: 8.4e7,
                y0: PAPER,
                drag: 3.0912 * 0.0015,
                floor_altitude: 120e3,
                zonal_degree: 2,
                forces: crate::problem::Forces::AUTO,
            },
            initial_factor: None,
            kappa,
            perturbation: Perturbation::Additive,
            method: FixedMethod::Rk8,
            max_step: 180.0,
            output_times: vec![0.0, 3600.0, 7200.0],
            members,
            seed: 5,
            record_density: true,
            drag_sigma: 0.0,
        }
    }

    #[test]
    fn a_member_the_step_cannot_carry_is_an_error_not_a_survivor() {
        // Cd*A/m = 1e8 m^2/kg: a drag acceleration of ~1e4 m/s^2 at 400 km, which the
        // 180-s RK8 step flung out to ~1e10 m, counted "not decayed". Its orbit comes out
        // unbound from a step, which drag cannot do: an error naming the member.
        let atm = Exponential::new(3.725e-12, 400e3, 58.515e3, 0.0).unwrap();
        let mut cfg = config(4, KappaProcess::Constant);
        cfg.problem.drag = 1e8;
        let e = monte_carlo(&atm, &cfg, &Progress::default()).unwrap_err();
        assert!(
            e.to_string()
                .starts_with("member 0 is invalid: its orbit came out unbound"),
            "{e}"
        );
        // A plausible drag runs as before.
        cfg.problem.drag = 3.0912 * 0.0015;
        assert!(monte_carlo(&atm, &cfg, &Progress::default()).is_ok());
    }

    #[test]
    fn every_simd_path_and_batch_width_gives_the_same_bits() {
        // AVX-512, AVX2 and portable code, in batches of 8, 16 and 32: same members, same
        // numbers, including batches only partly filled (45 members) and decays.
        let atm = Exponential::new(3.725e-12, 400e3, 58.515e3, 0.3).unwrap();
        let mut cfg = config(
            45,
            KappaProcess::GaussMarkov {
                half_life: 1080.0,
                interval: 180.0,
            },
        );
        cfg.output_times = vec![0.0, 1000.0, 7200.0];
        let mut runs = Vec::new();
        for p in SimdPath::available() {
            for w in BATCH_WIDTHS {
                runs.push(monte_carlo_in(p, w, &atm, &cfg, &Progress::default()).unwrap());
            }
        }
        for r in &runs[1..] {
            assert_eq!(r, &runs[0]);
        }
        assert!(monte_carlo_in(SimdPath::Portable, 4, &atm, &cfg, &Progress::default()).is_err());
    }

    #[test]
    fn decay_times_are_located_within_the_step() {
        use crate::constants::{MU, R_EARTH};
        // From 600 km apogee down to a 90 km perigee, zero sigma: every member crosses the
        // floor where a 1 s RK8 propagation does, to about a second, and is frozen there.
        let atm = Exponential::new(3.725e-12, 400e3, 58.515e3, 0.0).unwrap();
        let (ra, rp) = (R_EARTH + 600e3, R_EARTH + 90e3);
        let va = (MU * (2.0 / ra - 2.0 / (ra + rp))).sqrt();
        let mut cfg = config(
            5,
            KappaProcess::GaussMarkov {
                half_life: 1080.0,
                interval: 180.0,
            },
        );
        cfg.problem.y0 = [ra, 0.0, 0.0, 0.0, va, 0.0];
        cfg.problem.epoch = 0.0;
        let out = monte_carlo(&atm, &cfg, &Progress::default()).unwrap();
        let reference = propagate(
            &atm,
            &cfg.problem,
            &[7200.0],
            Method::Rk8 { step: 1.0 },
            &Progress::default(),
        )
        .unwrap()
        .decayed_at
        .unwrap();
        for &t in &out.decay_times {
            assert!((t - reference).abs() < 1.5, "{t} s vs {reference} s");
        }
        // The frozen state is at the floor: 120 km above the equator.
        let r = (out.positions[3].powi(2) + out.positions[4].powi(2)).sqrt();
        assert!((r - R_EARTH - 120e3).abs() < 50.0, "{} m", r - R_EARTH);
    }

    #[test]
    fn zero_sigma_reproduces_the_deterministic_orbit_exactly() {
        let atm = Exponential::new(3.725e-12, 400e3, 58.515e3, 0.0).unwrap();
        let cfg = config(
            5,
            KappaProcess::GaussMarkov {
                half_life: 1080.0,
                interval: 180.0,
            },
        );
        let out = monte_carlo(&atm, &cfg, &Progress::default()).unwrap();
        let det = propagate(
            &atm,
            &cfg.problem,
            &cfg.output_times,
            Method::Rk8 { step: 180.0 },
            &Progress::default(),
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
            &cfg.problem,
            &cfg.output_times,
            Method::Rk8 { step: 60.0 },
            &Progress::default(),
        )
        .unwrap();
        for (i, s) in det.states.iter().enumerate() {
            let d: f64 = (0..3)
                .map(|c| (out.positions[i * 3 + c] - s[c]).powi(2))
                .sum::<f64>()
                .sqrt();
            assert!(d < 1e-3, "output {i}: {d} m");
        }
        // The step plan itself: integrators::fixed, grid_plan_merges_outputs_into_the_grid.
    }

    #[test]
    fn cancel_stops_the_run() {
        let atm = Exponential::new(3.725e-12, 400e3, 58.515e3, 0.3).unwrap();
        let p = Progress::default();
        p.cancel.store(true, Ordering::Relaxed);
        let e = monte_carlo(&atm, &config(9, KappaProcess::Constant), &p).unwrap_err();
        assert_eq!(e, CoreError::Cancelled);
    }

    #[test]
    fn members_fly_with_their_own_drag_factor() {
        // Certain density: each member is the deterministic orbit with Cd*A/m times its
        // factor, bit for bit, on every SIMD path; the factors depend only on seed and
        // member index.
        let atm = Exponential::new(3.725e-12, 400e3, 58.515e3, 0.0).unwrap();
        let mut cfg = config(
            11,
            KappaProcess::GaussMarkov {
                half_life: 1080.0,
                interval: 180.0,
            },
        );
        cfg.drag_sigma = 0.2;
        let runs: Vec<_> = SimdPath::available()
            .into_iter()
            .map(|p| monte_carlo_on(p, &atm, &cfg, &Progress::default()).unwrap())
            .collect();
        for r in &runs[1..] {
            assert_eq!(r, &runs[0]);
        }
        let out = &runs[0];
        for m in [0, 5, 10] {
            let f = out.drag_factors[m];
            assert_eq!(f, member_drag_factor(cfg.seed, m as u64, 0.2));
            let mut problem = cfg.problem;
            problem.drag *= f;
            let det = propagate(
                &atm,
                &problem,
                &cfg.output_times,
                Method::Rk8 { step: 180.0 },
                &Progress::default(),
            )
            .unwrap();
            for (i, s) in det.states.iter().enumerate() {
                for c in 0..3 {
                    assert_eq!(out.positions[(m * 3 + i) * 3 + c], s[c], "member {m}");
                }
            }
        }
        let few = {
            let mut c = cfg.clone();
            c.members = 3;
            monte_carlo(&atm, &c, &Progress::default()).unwrap()
        };
        assert_eq!(&few.drag_factors[..], &out.drag_factors[..3]);
        // Zero sigma: every factor is exactly 1.
        cfg.drag_sigma = 0.0;
        let zero = monte_carlo(&atm, &cfg, &Progress::default()).unwrap();
        assert!(zero.drag_factors.iter().all(|&f| f == 1.0));
        cfg.drag_sigma = f64::INFINITY;
        assert!(monte_carlo(&atm, &cfg, &Progress::default()).is_err());
    }

    #[test]
    fn drag_factors_are_log_normal_and_leave_kappa_alone() {
        // ln(factor) / sigma over 100k members: mean 0 and variance 1 within ~4.5 standard
        // errors (0.0032 and 0.0045).
        let n = 100_000u64;
        let z: Vec<f64> = (0..n)
            .map(|m| member_drag_factor(9, m, 0.3).ln() / 0.3)
            .collect();
        let mean = z.iter().sum::<f64>() / n as f64;
        let var = z.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / n as f64;
        assert!(mean.abs() < 0.015, "{mean}");
        assert!((var - 1.0).abs() < 0.02, "{var}");
        // The drag draws come from their own stream: a member's kappa path is unchanged.
        let atm = Exponential::new(3.725e-12, 400e3, 58.515e3, 0.3).unwrap();
        let mut cfg = config(3, KappaProcess::Constant);
        let without = monte_carlo(&atm, &cfg, &Progress::default()).unwrap();
        cfg.drag_sigma = 0.1;
        let with = monte_carlo(&atm, &cfg, &Progress::default()).unwrap();
        // At t = 0 the density seen is mean + kappa sigma, the same with or without.
        let (a, b) = (without.densities.unwrap(), with.densities.unwrap());
        for m in 0..3 {
            assert_eq!(a[m * 3], b[m * 3]);
        }
        assert_ne!(without.positions, with.positions);
    }
}
