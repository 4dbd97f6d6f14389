//! Deterministic propagation of one trajectory (a batch of one) to requested output times,
//! with any integrator, stopping cleanly when the object decays below the floor altitude.

use crate::decay::{crossing, StepEnds};
use crate::density::Atmosphere;
use crate::dynamics::{Dynamics, State};
use crate::integrators::{
    drive, integrate_adaptive, AdaptiveOptions, Control, FixedMethod, Outcome, StepHooks, StepPlan,
};
use crate::problem::Problem;
use crate::progress::Progress;
use crate::simd::{dispatch, Kernel};
use crate::CoreError;

/// Integration method of a propagation.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Method {
    /// Fixed-step RK4 with the given largest step, s.
    Rk4 { step: f64 },
    /// Fixed-step 8th-order Dormand-Prince with the given largest step, s.
    Rk8 { step: f64 },
    /// Fixed-step Adams-Bashforth-Moulton (started with RK8) with the given largest step, s.
    Abm { step: f64 },
    /// Adaptive DOP853 with dense output.
    Dop853(AdaptiveOptions),
}

impl Method {
    /// The names of the integrators, as the binding and Python spell them.
    pub const NAMES: [&'static str; 4] = ["dop853", "rk8", "rk4", "abm"];

    /// The integrator named `name` (one of [`Method::NAMES`]): a fixed-step scheme needs
    /// `step` (s); DOP853 takes `rtol` (default [`AdaptiveOptions`]'s) and `step` as its
    /// largest step.
    pub fn from_name(name: &str, step: Option<f64>, rtol: Option<f64>) -> Result<Self, CoreError> {
        if name == "dop853" {
            return Ok(Self::Dop853(AdaptiveOptions {
                rtol: rtol.unwrap_or(AdaptiveOptions::default().rtol),
                max_step: step.unwrap_or(f64::INFINITY),
                ..Default::default()
            }));
        }
        let scheme = FixedMethod::from_name(name).map_err(|_| CoreError::UnknownName {
            what: "integrator",
            name: name.to_string(),
            expected: &Self::NAMES,
        })?;
        let step = step.ok_or_else(|| {
            CoreError::rejected("step", format!("integrator {name:?} needs a step"))
        })?;
        Ok(match scheme {
            FixedMethod::Rk4 => Self::Rk4 { step },
            FixedMethod::Rk8 => Self::Rk8 { step },
            FixedMethod::Abm => Self::Abm { step },
        })
    }
}

/// A propagated trajectory: states at the output times reached.
#[derive(Debug, Clone, PartialEq)]
pub struct Trajectory {
    /// Output times reached, seconds from the epoch.
    pub times: Vec<f64>,
    /// Inertial states [x, y, z, vx, vy, vz] (m, m/s) at `times`.
    pub states: Vec<[f64; 6]>,
    /// Time at which the orbit first went below the floor altitude (located within the
    /// step to a millisecond), if the object decayed; outputs stop before it.
    pub decayed_at: Option<f64>,
    /// Number of RHS evaluations.
    pub evaluations: u64,
    /// Number of density evaluations clipped at zero.
    pub clipped: u64,
}

/// Collects the states, stops where the orbit crosses the floor (located within the
/// step), honours cancellation.
struct Observer<'p> {
    epoch: f64,
    floor: f64,
    progress: &'p Progress,
    states: Vec<[f64; 6]>,
    /// The previous step end (time, state).
    last: (f64, [f64; 6]),
    /// Where the orbit crossed the floor.
    decayed_at: Option<f64>,
}

impl<R> StepHooks<1, R> for Observer<'_> {
    fn after_step(&mut self, t: f64, y: &mut State<1>, _: &mut R) -> Result<Control, CoreError> {
        self.progress.check()?;
        let end = y.map(|c| c[0]);
        let step = StepEnds {
            t0: self.last.0,
            y0: self.last.1,
            t1: t,
            y1: end,
        };
        self.last = (t, end);
        self.decayed_at = crossing(self.epoch, &step, self.floor);
        Ok(if self.decayed_at.is_some() {
            Control::Stop
        } else {
            Control::Continue
        })
    }

    fn on_output(&mut self, _: usize, _: f64, y: &State<1>, _: &R) -> Result<(), CoreError> {
        self.states.push(y.map(|c| c[0]));
        self.progress.add(1);
        Ok(())
    }
}

/// One fixed-step propagation, run through the SIMD dispatch.
struct FixedRun<'r, 'a, 'p, A: Atmosphere + ?Sized> {
    scheme: FixedMethod,
    dynamics: &'r mut Dynamics<'a, A, 1>,
    y: &'r mut State<1>,
    plan: &'r StepPlan,
    observer: &'r mut Observer<'p>,
}

impl<A: Atmosphere + ?Sized> Kernel for FixedRun<'_, '_, '_, A> {
    type Output = Result<Outcome, CoreError>;

    #[inline(always)]
    fn run(self) -> Self::Output {
        drive(self.scheme, self.dynamics, self.y, self.plan, self.observer)
    }
}

/// Propagates `problem` through the increasing `output_times` (s from the epoch, >= 0; or
/// all <= 0 to go backwards with a fixed-step method). `progress.done` counts the output
/// times reached; setting `progress.cancel` stops the run after the current step.
pub fn propagate<A: Atmosphere + ?Sized>(
    atmosphere: &A,
    problem: &Problem,
    output_times: &[f64],
    method: Method,
    progress: &Progress,
) -> Result<Trajectory, CoreError> {
    problem.validate()?;
    let mut dynamics = Dynamics::<A, 1>::for_problem(atmosphere, problem, [problem.drag]);
    let mut y: State<1> = problem.y0.map(|c| [c]);
    let mut observer = Observer {
        epoch: problem.epoch,
        floor: problem.floor_altitude,
        progress,
        states: Vec::with_capacity(output_times.len()),
        last: (0.0, problem.y0),
        decayed_at: None,
    };
    let outcome = match method {
        Method::Rk4 { step } | Method::Rk8 { step } | Method::Abm { step } => {
            let scheme = match method {
                Method::Rk4 { .. } => FixedMethod::Rk4,
                Method::Rk8 { .. } => FixedMethod::Rk8,
                _ => FixedMethod::Abm,
            };
            let plan = StepPlan::equal_steps(0.0, output_times, step)?;
            // Compiled for the CPU's instruction set like the batch kernels (inline
            // floor, FMA-free arithmetic: bit-identical on every path).
            dispatch(FixedRun {
                scheme,
                dynamics: &mut dynamics,
                y: &mut y,
                plan: &plan,
                observer: &mut observer,
            })?
        }
        Method::Dop853(opts) => {
            integrate_adaptive(&mut dynamics, 0.0, &y, output_times, opts, &mut observer)?
        }
    };
    debug_assert!(matches!(outcome, Outcome::Completed) || observer.decayed_at.is_some());
    let decayed_at = observer.decayed_at;
    let mut states = observer.states;
    if let Some(td) = decayed_at {
        // The adaptive integrator hands out the outputs of a step before the step's decay
        // check: drop those after the crossing.
        let forward = output_times.last().is_some_and(|&t| t >= 0.0);
        let kept = output_times[..states.len()]
            .iter()
            .take_while(|&&t| if forward { t < td } else { t > td })
            .count();
        states.truncate(kept);
    }
    let times = output_times[..states.len()].to_vec();
    Ok(Trajectory {
        times,
        states,
        decayed_at,
        evaluations: dynamics.evaluations,
        clipped: dynamics.clipped[0],
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::constants::{J2, MU, R_EARTH};
    use crate::density::Exponential;
    use crate::problem::DEFAULT_FLOOR_ALTITUDE;
    use std::sync::atomic::Ordering;

    /// `propagate` with the problem spelled out and no cancellation.
    fn run(
        atm: &Exponential,
        epoch: f64,
        y0: [f64; 6],
        drag: f64,
        times: &[f64],
        method: Method,
        floor_altitude: f64,
    ) -> Result<Trajectory, CoreError> {
        let problem = Problem {
            epoch,
            y0,
            drag,
            floor_altitude,
            zonal_degree: 2,
            forces: crate::problem::Forces::AUTO,
        };
        propagate(atm, &problem, times, method, &Progress::default())
    }

    /// The paper's initial state (docs/paper-study.md).
    const PAPER: [f64; 6] = crate::constants::PAPER_STATE;
    const DRAG: f64 = 3.0912 * 0.0015;

    fn paper_atmosphere() -> Exponential {
        Exponential::new(3.725e-12, 400e3, 58.515e3, 0.0).unwrap()
    }

    fn end_position(method: Method, atm: &Exponential, drag: f64) -> [f64; 3] {
        let tr = run(
            atm,
            0.0,
            PAPER,
            drag,
            &[259200.0],
            method,
            DEFAULT_FLOOR_ALTITUDE,
        )
        .unwrap();
        let s = tr.states[0];
        [s[0], s[1], s[2]]
    }

    fn distance(a: [f64; 3], b: [f64; 3]) -> f64 {
        ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2) + (a[2] - b[2]).powi(2)).sqrt()
    }

    #[test]
    fn fixed_rk8_and_adaptive_agree_over_three_days() {
        // Reference: adaptive DOP853 at rtol 1e-13. The independent scipy reference lives
        // in the Python tests; here the two integrators check each other.
        let atm = paper_atmosphere();
        let reference = end_position(
            Method::Dop853(AdaptiveOptions {
                rtol: 1e-13,
                ..Default::default()
            }),
            &atm,
            DRAG,
        );
        let rk8 = distance(
            end_position(Method::Rk8 { step: 180.0 }, &atm, DRAG),
            reference,
        );
        assert!(rk8 < 1.0, "rk8 180 s: {rk8} m");
        let rk4 = distance(
            end_position(Method::Rk4 { step: 5.0 }, &atm, DRAG),
            reference,
        );
        assert!(rk4 < 1.0, "rk4 5 s: {rk4} m");
        let adaptive = distance(
            end_position(Method::Dop853(AdaptiveOptions::default()), &atm, DRAG),
            reference,
        );
        assert!(adaptive < 1.0, "dop853 default rtol: {adaptive} m");
    }

    #[test]
    fn energy_and_polar_angular_momentum_are_conserved_without_drag() {
        // Without drag the J2 field is axisymmetric and static in the inertial frame:
        // E = v^2/2 - mu/r + mu J2 Re^2 (3 z^2/r^2 - 1) / (2 r^3) and h_z are constants.
        let atm = paper_atmosphere();
        let times: Vec<f64> = (0..=72).map(|i| i as f64 * 3600.0).collect();
        let tr = run(
            &atm,
            0.0,
            PAPER,
            1e-300,
            &times,
            Method::Dop853(AdaptiveOptions {
                rtol: 1e-12,
                ..Default::default()
            }),
            DEFAULT_FLOOR_ALTITUDE,
        )
        .unwrap();
        let energy = |s: &[f64; 6]| {
            let r = (s[0] * s[0] + s[1] * s[1] + s[2] * s[2]).sqrt();
            let v2 = s[3] * s[3] + s[4] * s[4] + s[5] * s[5];
            0.5 * v2 - MU / r
                + MU * J2 * R_EARTH * R_EARTH * (3.0 * s[2] * s[2] / (r * r) - 1.0)
                    / (2.0 * r * r * r)
        };
        let hz = |s: &[f64; 6]| s[0] * s[4] - s[1] * s[3];
        let (e0, h0) = (energy(&tr.states[0]), hz(&tr.states[0]));
        for s in &tr.states {
            // Relative 1e-10 of |E| ~ 3e7 J/kg is 3e-3 J/kg, i.e. ~0.1 mm of semi-major axis.
            assert!(
                ((energy(s) - e0) / e0).abs() < 1e-10,
                "{}",
                (energy(s) - e0) / e0
            );
            assert!(((hz(s) - h0) / h0).abs() < 1e-10);
        }
    }

    #[test]
    fn decay_below_the_floor_stops_cleanly() {
        // A very dense atmosphere brings the object down within hours.
        let atm = Exponential::new(1e-9, 400e3, 58.515e3, 0.0).unwrap();
        let times: Vec<f64> = (0..=72).map(|i| i as f64 * 3600.0).collect();
        let tr = run(
            &atm,
            0.0,
            PAPER,
            DRAG,
            &times,
            Method::Rk8 { step: 60.0 },
            DEFAULT_FLOOR_ALTITUDE,
        )
        .unwrap();
        let t = tr.decayed_at.expect("must decay");
        assert!(t < 259200.0);
        assert!(tr.states.len() < times.len());
        assert!(tr.states.iter().flatten().all(|x| x.is_finite()));
    }

    #[test]
    fn a_light_object_plunging_through_a_long_step_is_dated_not_lost() {
        // 60 m^2/kg (an MLI fragment, as real ones of the 2022 reentries) at 130 km
        // through an atmosphere with a 7 km scale height: a 180-s RK8 step's later stages
        // dive tens of km below the 120 km floor, where the real density (1e-3 kg/m^3 at
        // 50 km) decelerated them by 1e6 m/s^2 and the step ended on a NaN. Stage points
        // more than FLOOR_MARGIN below the floor see no drag: the decay is dated, within
        // 2 s of RK8 at 1 s (whose stages stay within metres of the floor).
        let atm = Exponential::new(2.5e-8, 120e3, 7e3, 0.0).unwrap();
        let r = R_EARTH + 130e3;
        let y0 = [r, 0.0, 0.0, 0.0, (MU / r).sqrt(), 0.0];
        let at = |step| {
            let tr = run(&atm, 0.0, y0, 60.0, &[3600.0], Method::Rk8 { step }, 120e3);
            tr.unwrap().decayed_at.expect("decays")
        };
        let (t, reference) = (at(180.0), at(1.0));
        assert!(
            t.is_finite() && (t - reference).abs() < 2.0,
            "{t} s vs {reference} s"
        );
    }

    #[test]
    fn decay_is_located_within_the_step_for_every_integrator() {
        // An ellipse from 600 km apogee (on the x axis) down to a 90 km perigee: the first
        // perigee pass crosses the 120 km floor between step ends of the adaptive
        // integrator. Reference: RK8 at 1 s, the first step end below the floor.
        let atm = paper_atmosphere();
        let (ra, rp) = (R_EARTH + 600e3, R_EARTH + 90e3);
        let a = 0.5 * (ra + rp);
        let va = (MU * (2.0 / ra - 1.0 / a)).sqrt();
        let y0 = [ra, 0.0, 0.0, 0.0, va, 0.0];
        let times = [10_000.0];
        let at = |method| {
            run(&atm, 0.0, y0, DRAG, &times, method, 120e3)
                .unwrap()
                .decayed_at
                .expect("decays")
        };
        let reference = at(Method::Rk8 { step: 1.0 });
        for method in [
            Method::Dop853(AdaptiveOptions::default()),
            Method::Rk8 { step: 180.0 },
            Method::Rk4 { step: 5.0 },
        ] {
            let t = at(method);
            assert!(
                (t - reference).abs() < 1.5,
                "{method:?}: {t} s vs {reference} s"
            );
        }
        let tr = run(
            &atm,
            0.0,
            y0,
            DRAG,
            &[600.0, 1200.0, 10_000.0],
            Method::Dop853(AdaptiveOptions::default()),
            120e3,
        )
        .unwrap();
        // Only outputs before the crossing are returned.
        assert!(tr.times.iter().all(|&t| t < reference), "{:?}", tr.times);
    }

    #[test]
    fn absurd_step_counts_are_refused_before_allocating() {
        let e = run(
            &paper_atmosphere(),
            0.0,
            PAPER,
            DRAG,
            &[86400.0],
            Method::Rk4 { step: 1e-6 },
            120e3,
        )
        .unwrap_err();
        assert!(e.to_string().contains("steps over the span"), "{e}");
    }

    #[test]
    fn backward_propagation_retraces_the_forward_orbit() {
        // Forward 8 h with drag, then from there back to t = 0 (epoch shifted): the start
        // state comes back within a centimetre (RK8 at 180 s: ~1 mm each way).
        let atm = paper_atmosphere();
        let m = Method::Rk8 { step: 180.0 };
        let fwd = run(&atm, 0.0, PAPER, DRAG, &[28800.0], m, 120e3).unwrap();
        let back = run(&atm, 28800.0, fwd.states[0], DRAG, &[-28800.0], m, 120e3).unwrap();
        let d = distance(
            [back.states[0][0], back.states[0][1], back.states[0][2]],
            [PAPER[0], PAPER[1], PAPER[2]],
        );
        assert!(d < 1e-2, "{d} m");
    }

    #[test]
    fn bad_inputs_are_errors() {
        let atm = paper_atmosphere();
        let m = Method::Rk8 { step: 180.0 };
        let mut nan = PAPER;
        nan[4] = f64::NAN;
        let e = run(&atm, 0.0, nan, DRAG, &[10.0], m, 120e3).unwrap_err();
        assert!(e.to_string().contains("velocity[1]"), "{e}");
        let e = run(
            &atm,
            0.0,
            [1e6, 0.0, 0.0, 0.0, 7e3, 0.0],
            DRAG,
            &[10.0],
            m,
            120e3,
        )
        .unwrap_err();
        assert!(e.to_string().contains("below the Earth's surface"), "{e}");
        assert!(run(&atm, 0.0, PAPER, 0.0, &[10.0], m, 120e3).is_err());
        assert!(run(&atm, 0.0, PAPER, DRAG, &[-10.0, 5.0], m, 120e3).is_err());
        assert!(run(
            &atm,
            0.0,
            PAPER,
            DRAG,
            &[10.0],
            Method::Rk4 { step: -1.0 },
            120e3
        )
        .is_err());
    }

    #[test]
    fn cancel_stops_the_run() {
        let atm = paper_atmosphere();
        let problem = Problem {
            epoch: 0.0,
            y0: PAPER,
            drag: DRAG,
            floor_altitude: DEFAULT_FLOOR_ALTITUDE,
            zonal_degree: 2,
            forces: crate::problem::Forces::AUTO,
        };
        let p = Progress::default();
        p.cancel.store(true, Ordering::Relaxed);
        for m in [
            Method::Rk8 { step: 180.0 },
            Method::Dop853(AdaptiveOptions::default()),
        ] {
            let e = propagate(&atm, &problem, &[0.0, 3600.0], m, &p).unwrap_err();
            assert_eq!(e, CoreError::Cancelled);
        }
        // Not cancelled: every output reached is counted.
        let p = Progress::default();
        propagate(
            &atm,
            &problem,
            &[0.0, 3600.0, 7200.0],
            Method::Rk8 { step: 180.0 },
            &p,
        )
        .unwrap();
        assert_eq!(p.done.load(Ordering::Relaxed), 3);
    }

    #[test]
    fn integrators_are_parsed_by_name() {
        assert_eq!(
            Method::from_name("rk8", Some(180.0), None).unwrap(),
            Method::Rk8 { step: 180.0 }
        );
        assert_eq!(
            Method::from_name("abm", Some(80.0), None).unwrap(),
            Method::Abm { step: 80.0 }
        );
        let Method::Dop853(o) = Method::from_name("dop853", None, Some(1e-9)).unwrap() else {
            panic!("dop853")
        };
        assert_eq!((o.rtol, o.max_step), (1e-9, f64::INFINITY));
        let e = Method::from_name("euler", Some(1.0), None).unwrap_err();
        assert!(
            e.to_string().contains("unknown integrator \"euler\""),
            "{e}"
        );
        let e = Method::from_name("rk4", None, None).unwrap_err();
        assert!(e.to_string().contains("needs a step"), "{e}");
        assert!(crate::dynamics::Perturbation::from_name("additive").is_ok());
        assert!(FixedMethod::from_name("dop853").is_err());
    }
}
