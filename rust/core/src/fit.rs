//! Least-squares fits of an orbit's state and drag parameter p = [r, v, Cd*A/m] to
//! position pseudo-observations (the SGP4 positions of element sets, prepared in Python):
//! Gauss-Newton with a prior on Cd*A/m, the Jacobian by forward differences. The nominal
//! orbit and its seven perturbed neighbours fly as the eight lanes of one batch, so each
//! trial of an iteration is one SIMD batch run backwards and one forwards over the
//! observation grid, and an accepted trial already holds the next iteration's Jacobian.
//! Jobs run in parallel; each job's result is independent of the thread count.

use crate::decay::{crossing, lane_step, may_cross_lanes};
use crate::density::Atmosphere;
use crate::dynamics::{Dynamics, State};
use crate::error::{finite, positive, CoreError};
use crate::integrators::{drive, Control, FixedMethod, StepHooks, StepPlan};
use crate::problem::{check_state, Forces, Problem};
use crate::progress::Progress;
use crate::simd::{dispatch, Aligned, Kernel};
use nalgebra::{DMatrix, DVector};
use rayon::prelude::*;

/// Lanes of a trial: the nominal parameters and one forward difference per parameter.
const LANES: usize = 8;
/// Parameters fitted: position (3), velocity (3), Cd*A/m.
const NP: usize = 7;
/// Forward-difference steps of position (m) and velocity (m/s); Cd*A/m's is
/// [`DRAG_STEP`] of its value.
const STEPS: [f64; 6] = [1.0, 1.0, 1.0, 1e-3, 1e-3, 1e-3];
/// Relative forward-difference step of Cd*A/m.
const DRAG_STEP: f64 = 0.01;
/// Halvings of a Gauss-Newton step that raises the cost before the fit stops.
const HALVINGS: usize = 5;

/// One object's fit: where it starts, its prior and its observations on the grid
/// t = g spacing s from the epoch, g = -back..=forward.
#[derive(Debug, Clone)]
pub struct FitJob {
    /// Epoch of t = 0 (the state's epoch), seconds since J2000 (UT1).
    pub epoch: f64,
    /// Starting parameters [x, y, z (m), vx, vy, vz (m/s), Cd*A/m (m^2/kg)].
    pub p0: [f64; NP],
    /// Prior on Cd*A/m and its 1-sigma, m^2/kg.
    pub prior: f64,
    pub prior_sigma: f64,
    /// Grid spacing, s; grid steps before and after the epoch.
    pub spacing: f64,
    pub back: usize,
    pub forward: usize,
    /// Grid row (g + back) of each observation.
    pub rows: Vec<usize>,
    /// Observed inertial positions, m.
    pub observed: Vec<[f64; 3]>,
    /// Weight matrix of each observation (its RTN rows over the 1-sigmas, 1/m): the
    /// weighted residual is `weights * (observed - model)`.
    pub weights: Vec<[[f64; 3]; 3]>,
}

/// Settings shared by the jobs of a call.
#[derive(Debug, Clone, Copy)]
pub struct FitSettings {
    /// Largest RK8 step, s (each grid interval is cut into equal steps).
    pub step: f64,
    pub zonal_degree: u8,
    /// Decay floor, m: a trial whose orbit crosses it is rejected.
    pub floor_altitude: f64,
    pub max_iterations: usize,
    /// Smallest Cd*A/m a trial may take, m^2/kg.
    pub min_drag: f64,
}

/// Where a fit ended.
#[derive(Debug, Clone, PartialEq)]
pub struct FitOutput {
    /// Fitted parameters (as [`FitJob::p0`]).
    pub p: [f64; NP],
    /// The fitted orbit's states on the grid, rows g + back.
    pub states: Vec<[f64; 6]>,
    /// J^T J of the weighted Jacobian at `p` (prior excluded).
    pub normal: [[f64; NP]; NP],
    pub iterations: usize,
    /// Whether the last update (taken, or computed and found too small to take) was
    /// below 1 cm in position and 1e-4 relative in Cd*A/m.
    pub converged: bool,
}

/// Fits every job through one atmosphere, jobs in parallel. Per job: its output or its
/// error (a job that cannot start: bad input, the orbit decays within the span, the
/// field does not cover it); a cancelled run is an error of the call.
/// `progress.done` counts finished jobs.
pub fn fit_many<A: Atmosphere + ?Sized>(
    atmosphere: &A,
    jobs: &[FitJob],
    settings: &FitSettings,
    progress: &Progress,
) -> Result<Vec<Result<FitOutput, CoreError>>, CoreError> {
    positive("step", settings.step)?;
    positive("min_drag", settings.min_drag)?;
    let out: Vec<Result<FitOutput, CoreError>> = jobs
        .par_iter()
        .with_max_len(1)
        .map(|job| {
            progress.check()?;
            let r = fit_one(atmosphere, job, settings, progress);
            progress.add(1);
            r
        })
        .collect();
    if out.iter().any(|r| matches!(r, Err(CoreError::Cancelled))) {
        return Err(CoreError::Cancelled);
    }
    Ok(out)
}

/// Checks a job's shapes and values.
fn check_job(job: &FitJob) -> Result<(), CoreError> {
    let k = job.rows.len();
    if k == 0 || job.observed.len() != k || job.weights.len() != k {
        return Err(CoreError::shape(
            "observations",
            format!(
                "rows, observed and weights must have one entry per observation and at least \
                 one (got {k}, {}, {})",
                job.observed.len(),
                job.weights.len()
            ),
        ));
    }
    let n = job.back + job.forward + 1;
    if let Some(&r) = job.rows.iter().find(|&&r| r >= n) {
        return Err(CoreError::invalid(
            "observation row",
            r as f64,
            format!("the grid has {n} rows"),
        ));
    }
    positive("spacing", job.spacing)?;
    positive("prior", job.prior)?;
    positive("prior_sigma", job.prior_sigma)?;
    for v in job.observed.iter().flatten() {
        finite("observed position", *v)?;
    }
    for v in job.weights.iter().flatten().flatten() {
        finite("observation weight", *v)?;
    }
    Ok(())
}

/// The states of the 8 lanes on the grid: rows g + back, each row all lanes.
type Grid = Vec<[[f64; 6]; LANES]>;

/// Gauss-Newton of one job (the module doc).
fn fit_one<A: Atmosphere + ?Sized>(
    atmosphere: &A,
    job: &FitJob,
    s: &FitSettings,
    progress: &Progress,
) -> Result<FitOutput, CoreError> {
    check_job(job)?;
    let mut p = job.p0;
    Problem {
        epoch: job.epoch,
        y0: std::array::from_fn(|i| p[i]),
        drag: p[6],
        floor_altitude: s.floor_altitude,
        zonal_degree: s.zonal_degree,
        forces: crate::problem::Forces::AUTO,
    }
    .validate()?;
    let mut grid = trial(atmosphere, job, s, &p, progress).map_err(|e| match e {
        Trial::Decayed => CoreError::rejected(
            "fit span",
            "the orbit decays within the fit span; shorten span",
        ),
        Trial::Failed(e) => e,
    })?;
    let (mut jac, mut res) = linearise(job, &grid, &p);
    let mut converged = false;
    let mut iterations = 0;
    for it in 1..=s.max_iterations {
        iterations = it;
        let before = cost(&res, job, p[6]);
        let mut dp = solve(&jac, &res, job, p[6])?;
        if small(&dp, p[6]) {
            // Converged: the update would move the orbit by under a centimetre, so the
            // trial that would confirm it (a quarter of a fit's runs) is skipped.
            converged = true;
            break;
        }
        let mut accepted = None;
        for _ in 0..HALVINGS {
            let mut q: [f64; NP] = std::array::from_fn(|i| p[i] + dp[i]);
            q[6] = q[6].max(s.min_drag);
            match trial(atmosphere, job, s, &q, progress) {
                Ok(g) => {
                    let (jq, rq) = linearise(job, &g, &q);
                    if cost(&rq, job, q[6]) <= before * (1.0 + 1e-9) {
                        accepted = Some((q, g, jq, rq));
                        break;
                    }
                }
                Err(Trial::Failed(CoreError::Cancelled)) => return Err(CoreError::Cancelled),
                Err(_) => {} // the step took the orbit into the ground or off the field
            }
            dp.iter_mut().for_each(|d| *d /= 2.0);
        }
        let Some((q, g, jq, rq)) = accepted else {
            break;
        };
        let moved: [f64; NP] = std::array::from_fn(|i| q[i] - p[i]);
        (p, grid, jac, res) = (q, g, jq, rq);
        if small(&moved, p[6]) {
            converged = true;
            break;
        }
    }
    let mut normal = [[0.0; NP]; NP];
    for row in &jac {
        for i in 0..NP {
            for j in 0..NP {
                normal[i][j] += row[i] * row[j];
            }
        }
    }
    Ok(FitOutput {
        p,
        states: grid.iter().map(|row| row[0]).collect(),
        normal,
        iterations,
        converged,
    })
}

/// Whether an update `dp` is below 1 cm in position and 1e-4 relative in Cd*A/m.
fn small(dp: &[f64; NP], drag: f64) -> bool {
    (dp[0] * dp[0] + dp[1] * dp[1] + dp[2] * dp[2]).sqrt() < 0.01 && dp[6].abs() < 1e-4 * drag
}

/// Forward-difference steps at `p`.
fn steps(p: &[f64; NP]) -> [f64; NP] {
    std::array::from_fn(|j| if j < 6 { STEPS[j] } else { DRAG_STEP * p[6] })
}

/// Weighted Jacobian rows (3 per observation) and weighted residuals at `p`.
fn linearise(job: &FitJob, grid: &Grid, p: &[f64; NP]) -> (Vec<[f64; NP]>, Vec<f64>) {
    let h = steps(p);
    let k = job.rows.len();
    let mut jac = vec![[0.0; NP]; 3 * k];
    let mut res = vec![0.0; 3 * k];
    for (o, (&r, w)) in job.rows.iter().zip(&job.weights).enumerate() {
        let lanes = &grid[r];
        let x0 = &lanes[0];
        for i in 0..3 {
            let wi = &w[i];
            res[3 * o + i] = (0..3).map(|c| wi[c] * (job.observed[o][c] - x0[c])).sum();
            for j in 0..NP {
                let xj = &lanes[j + 1];
                jac[3 * o + i][j] = (0..3).map(|c| wi[c] * (xj[c] - x0[c])).sum::<f64>() / h[j];
            }
        }
    }
    (jac, res)
}

/// Weighted sum of squares plus the prior's term.
fn cost(res: &[f64], job: &FitJob, drag: f64) -> f64 {
    let prior = (job.prior - drag) / job.prior_sigma;
    res.iter().map(|r| r * r).sum::<f64>() + prior * prior
}

/// The Gauss-Newton step: least squares of [J; prior row] dp = [res; prior residual],
/// columns scaled to unit norm, by SVD (singular values below eps * rows * largest cut).
fn solve(jac: &[[f64; NP]], res: &[f64], job: &FitJob, drag: f64) -> Result<[f64; NP], CoreError> {
    let m = jac.len() + 1;
    let a = DMatrix::from_fn(m, NP, |i, j| {
        if i < jac.len() {
            jac[i][j]
        } else if j == 6 {
            1.0 / job.prior_sigma
        } else {
            0.0
        }
    });
    let b = DVector::from_fn(m, |i, _| {
        if i < res.len() {
            res[i]
        } else {
            (job.prior - drag) / job.prior_sigma
        }
    });
    let scale: Vec<f64> = (0..NP)
        .map(|j| a.column(j).norm())
        .map(|n| if n > 0.0 { n } else { 1.0 })
        .collect();
    let scaled = DMatrix::from_fn(m, NP, |i, j| a[(i, j)] / scale[j]);
    let svd = scaled.svd(true, true);
    let eps = f64::EPSILON * m as f64 * svd.singular_values.max();
    let x = svd
        .solve(&b, eps)
        .map_err(|e| CoreError::rejected("fit", format!("least-squares step failed: {e}")))?;
    let dp: [f64; NP] = std::array::from_fn(|j| x[j] / scale[j]);
    if dp.iter().all(|d| d.is_finite()) {
        Ok(dp)
    } else {
        Err(CoreError::rejected(
            "fit",
            "the least-squares step is not finite (observations or weights degenerate)",
        ))
    }
}

/// Why a trial gave no grid.
enum Trial {
    /// A lane crossed the decay floor.
    Decayed,
    Failed(CoreError),
}

/// The 8 lanes (p and p plus each forward-difference step) on the grid.
fn trial<A: Atmosphere + ?Sized>(
    atmosphere: &A,
    job: &FitJob,
    s: &FitSettings,
    p: &[f64; NP],
    progress: &Progress,
) -> Result<Grid, Trial> {
    let h = steps(p);
    let lanes: [[f64; NP]; LANES] = std::array::from_fn(|l| {
        let mut q = *p;
        if l > 0 {
            q[l - 1] += h[l - 1];
        }
        q
    });
    for q in &lanes {
        check_state(job.epoch, &std::array::from_fn(|i| q[i]), s.floor_altitude)
            .map_err(|_| Trial::Decayed)?;
    }
    let n = job.back + job.forward + 1;
    let mut grid: Grid = vec![[[0.0; 6]; LANES]; n];
    for (count, sign) in [(job.back, -1.0), (job.forward, 1.0)] {
        if count == 0 && sign < 0.0 {
            continue; // the forward run writes row `back` (t = 0)
        }
        let stops: Vec<f64> = (0..=count).map(|g| sign * job.spacing * g as f64).collect();
        let plan = StepPlan::equal_steps(0.0, &stops, s.step).map_err(Trial::Failed)?;
        let mut dynamics =
            Dynamics::<A, LANES>::new(atmosphere, job.epoch, std::array::from_fn(|l| lanes[l][6]));
        dynamics.zonal_degree = s.zonal_degree;
        dynamics.set_forces(Forces::AUTO, &std::array::from_fn(|i| job.p0[i]));
        // As every propagator (`Dynamics::for_problem`): stage points far below the floor
        // see no drag, so a trial step across it ends on a position, not on a NaN, and the
        // trial is rejected as decayed.
        dynamics.floor_altitude = s.floor_altitude;
        let mut y = Aligned::<State<LANES>>(std::array::from_fn(|c| {
            std::array::from_fn(|l| lanes[l][c])
        }));
        let mut recorder = Recorder {
            epoch: job.epoch,
            floor: s.floor_altitude,
            progress,
            last: (0.0, y.0),
            decayed: false,
            grid: &mut grid,
            origin: job.back,
            sign: if sign < 0.0 { -1 } else { 1 },
        };
        dispatch(LaneRun {
            dynamics: &mut dynamics,
            y: &mut y.0,
            plan: &plan,
            recorder: &mut recorder,
        })
        .map_err(Trial::Failed)?;
        if recorder.decayed {
            return Err(Trial::Decayed);
        }
    }
    Ok(grid)
}

/// Writes the lanes' states into the grid, stops when a lane crosses the floor.
struct Recorder<'g, 'p> {
    epoch: f64,
    floor: f64,
    progress: &'p Progress,
    last: (f64, State<LANES>),
    decayed: bool,
    grid: &'g mut Grid,
    /// Row of t = 0 and the direction of the run (output i is row origin + sign i).
    origin: usize,
    sign: isize,
}

impl<R> StepHooks<LANES, R> for Recorder<'_, '_> {
    #[inline(always)]
    fn after_step(
        &mut self,
        t: f64,
        y: &mut State<LANES>,
        _: &mut R,
    ) -> Result<Control, CoreError> {
        self.progress.check()?;
        let (t0, prev) = self.last;
        let candidates = may_cross_lanes(t0, &prev, t, y, self.floor);
        for l in 0..LANES {
            if candidates[l]
                && crossing(self.epoch, &lane_step(t0, &prev, t, y, l), self.floor).is_some()
            {
                self.decayed = true;
                return Ok(Control::Stop);
            }
        }
        self.last = (t, *y);
        Ok(Control::Continue)
    }

    #[inline(always)]
    fn on_output(&mut self, i: usize, _: f64, y: &State<LANES>, _: &R) -> Result<(), CoreError> {
        let row = (self.origin as isize + self.sign * i as isize) as usize;
        for l in 0..LANES {
            self.grid[row][l] = std::array::from_fn(|c| y[c][l]);
        }
        Ok(())
    }
}

/// One direction of a trial, compiled per instruction set.
struct LaneRun<'r, 'a, 'g, 'p, A: Atmosphere + ?Sized> {
    dynamics: &'r mut Dynamics<'a, A, LANES>,
    y: &'r mut State<LANES>,
    plan: &'r StepPlan,
    recorder: &'r mut Recorder<'g, 'p>,
}

impl<A: Atmosphere + ?Sized> Kernel for LaneRun<'_, '_, '_, '_, A> {
    type Output = Result<(), CoreError>;

    #[inline(always)]
    fn run(self) -> Self::Output {
        drive(
            FixedMethod::Rk8,
            self.dynamics,
            self.y,
            self.plan,
            self.recorder,
        )
        .map(|_| ())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::density::Exponential;
    use crate::propagate::{propagate, Method};

    /// The paper's initial state (docs/paper-study.md) and a drag parameter.
    const Y0: [f64; 6] = crate::constants::PAPER_STATE;
    const DRAG: f64 = 0.0046;

    fn atmosphere() -> Exponential {
        Exponential::new(3.725e-12, 400e3, 58.515e3, 0.0).unwrap()
    }

    fn settings() -> FitSettings {
        FitSettings {
            step: 180.0,
            zonal_degree: 4,
            floor_altitude: 120e3,
            max_iterations: 10,
            min_drag: 1e-4,
        }
    }

    /// A job observing `truth`'s orbit (propagated by `propagate`, the one-lane path)
    /// every 600 s over -1..+1 day, started from `p0`; weights 1 / (10 m).
    fn job(truth: [f64; NP], p0: [f64; NP], prior: f64) -> FitJob {
        let (back, forward, spacing) = (144usize, 144usize, 600.0);
        let states = reference(truth, back, forward, spacing);
        let rows: Vec<usize> = (0..states.len()).collect();
        let w = 0.1;
        FitJob {
            epoch: 7e8,
            p0,
            prior,
            prior_sigma: 0.5 * prior,
            spacing,
            back,
            forward,
            observed: states.iter().map(|s| [s[0], s[1], s[2]]).collect(),
            weights: vec![[[w, 0.0, 0.0], [0.0, w, 0.0], [0.0, 0.0, w]]; rows.len()],
            rows,
        }
    }

    /// States on the grid by the single-trajectory propagator (backwards and forwards).
    fn reference(p: [f64; NP], back: usize, forward: usize, spacing: f64) -> Vec<[f64; 6]> {
        let problem = Problem {
            epoch: 7e8,
            y0: std::array::from_fn(|i| p[i]),
            drag: p[6],
            floor_altitude: 120e3,
            zonal_degree: 4,
            forces: crate::problem::Forces::AUTO,
        };
        let run = |sign: f64, n: usize| {
            let times: Vec<f64> = (0..=n).map(|g| sign * spacing * g as f64).collect();
            propagate(
                &atmosphere(),
                &problem,
                &times,
                Method::Rk8 { step: 180.0 },
                &Progress::default(),
            )
            .unwrap()
            .states
        };
        let mut out: Vec<[f64; 6]> = run(-1.0, back).into_iter().rev().collect();
        out.extend(run(1.0, forward).into_iter().skip(1));
        out
    }

    #[test]
    fn the_nominal_lane_is_the_single_trajectory_propagation() {
        let p: [f64; NP] = std::array::from_fn(|i| if i < 6 { Y0[i] } else { DRAG });
        let j = job(p, p, DRAG);
        let grid = trial(&atmosphere(), &j, &settings(), &p, &Progress::default())
            .unwrap_or_else(|_| panic!("trial failed"));
        let want = reference(p, j.back, j.forward, j.spacing);
        for (row, w) in grid.iter().zip(&want) {
            for c in 0..6 {
                assert_eq!(row[0][c].to_bits(), w[c].to_bits());
            }
        }
    }

    #[test]
    fn a_fit_recovers_the_state_and_drag_it_observes() {
        let truth: [f64; NP] = std::array::from_fn(|i| if i < 6 { Y0[i] } else { DRAG });
        // Start 2 km and 1 m/s off, with Cd*A/m 40 % high (and the prior there too).
        let mut p0 = truth;
        p0[0] += 2000.0;
        p0[4] -= 1.0;
        p0[6] *= 1.4;
        let out = fit_many(
            &atmosphere(),
            &[job(truth, p0, p0[6])],
            &settings(),
            &Progress::default(),
        )
        .unwrap()
        .remove(0)
        .unwrap();
        assert!(out.converged, "{out:?}");
        for i in 0..3 {
            assert!(
                (out.p[i] - truth[i]).abs() < 0.05,
                "position {i}: {:?}",
                out.p
            );
            assert!((out.p[i + 3] - truth[i + 3]).abs() < 5e-5, "velocity {i}");
        }
        // The prior (40 % high, sigma 50 %) pulls by (0.4/0.5)^2 against 870 residuals of
        // an orbit that sees drag: the fitted value is the truth to well under 1 %.
        assert!(
            (out.p[6] / truth[6] - 1.0).abs() < 0.005,
            "drag {}",
            out.p[6]
        );
        assert_eq!(out.states.len(), 289);
    }

    #[test]
    fn bad_jobs_and_decaying_orbits_are_errors_of_their_job() {
        let p: [f64; NP] = std::array::from_fn(|i| if i < 6 { Y0[i] } else { DRAG });
        let mut bad = job(p, p, DRAG);
        bad.rows[3] = 10_000;
        let mut low = job(p, p, DRAG);
        // Drag 3000 times higher: the orbit comes down within the day.
        low.p0[6] = DRAG * 3000.0;
        let outs = fit_many(
            &atmosphere(),
            &[bad, low],
            &settings(),
            &Progress::default(),
        )
        .unwrap();
        let e0 = outs[0].as_ref().unwrap_err().to_string();
        assert!(e0.contains("observation row"), "{e0}");
        let e1 = outs[1].as_ref().unwrap_err().to_string();
        assert!(e1.contains("decays within the fit span"), "{e1}");
    }
}
