//! Equations of motion: two-body + J2 (optionally the zonals up to J6) + drag with a
//! co-rotating atmosphere, evaluated for a batch of `W` members at once, held
//! structure-of-arrays (`state[component][lane]`).
//! One trajectory is a batch of one. This is the one RHS that every integrator, member and
//! sigma point uses.

use crate::constants::{J2, J3, J4, J5, J6, MU, OMEGA_EARTH, R_EARTH, WGS84_F};
use crate::density::{Atmosphere, LaneMemory};
use crate::ephemeris::ThirdBodies;
use crate::error::CoreError;
use crate::frames::{EarthRotation, RotationCache};
use crate::geopotential::{field_lanes, DEEP_SPACE_TESSERAL_DEGREE};
use crate::kappa::KappaLanes;
use crate::problem::{Forces, Problem};
use crate::radiation;

/// Batch state: `[x, y, z, vx, vy, vz][lane]`, m and m/s, inertial.
pub type State<const W: usize> = [[f64; W]; 6];

/// Right-hand side of a batch ODE.
pub trait BatchRhs<const W: usize> {
    /// Writes dy/dt at `t` (seconds from the epoch) into `dy`.
    fn eval(&mut self, t: f64, y: &State<W>, dy: &mut State<W>) -> Result<(), CoreError>;

    /// Changes whenever the right-hand side changes discontinuously (a new kappa node),
    /// so that a multistep method restarts instead of differencing across it.
    fn generation(&self) -> u64 {
        0
    }

    /// Which side of a switch in the right-hand side each lane is on at (`t`, `y`): the
    /// Earth's shadow under radiation pressure (lit, penumbra, umbra). An adaptive step
    /// whose stages see a change is retaken shorter, down to [`BatchRhs::switch_step`]:
    /// an error estimate from stages that skip a narrow penumbra misses it (a 1,500-km
    /// orbit of high area-to-mass was 6 % off its radiation displacement in a day).
    /// Default: no switches.
    fn sides(&self, _t: f64, _y: &State<W>) -> u64 {
        0
    }

    /// Longest adaptive step (s) that may cross a change of [`BatchRhs::sides`]; infinite:
    /// none watched.
    fn switch_step(&self) -> f64 {
        f64::INFINITY
    }
}

/// How the normalised offset kappa perturbs the density (docs/conventions.md, "The kappa processes").
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Perturbation {
    /// rho = mean + kappa * sigma, clipped at 0 (the paper's form); clips are counted.
    Additive,
    /// rho = mean * exp(kappa s - s^2 / 2), s^2 = ln(1 + (sigma/mean)^2): same mean and
    /// variance, never negative.
    Lognormal,
}

impl Perturbation {
    /// The names of the forms, as the binding and Python spell them.
    pub const NAMES: [&'static str; 2] = ["additive", "lognormal"];

    /// The form named `name` (one of [`Perturbation::NAMES`]).
    pub fn from_name(name: &str) -> Result<Self, CoreError> {
        match name {
            "additive" => Ok(Self::Additive),
            "lognormal" => Ok(Self::Lognormal),
            other => Err(CoreError::UnknownName {
                what: "perturbation",
                name: other.to_string(),
                expected: &Self::NAMES,
            }),
        }
    }
}

/// Orbital period (s) from which an orbit is "deep space" and feels the Sun and the Moon
/// ([`Dynamics::third_body`]): 225 minutes, SGP4's own switch to SDP4 (Hoots & Roehrich,
/// Spacetrack Report No. 3).
pub const DEEP_SPACE_PERIOD: f64 = 225.0 * 60.0;

/// Whether the two-body orbit of `y0` (inertial position m, velocity m/s) has a period of
/// at least [`DEEP_SPACE_PERIOD`] (an unbound orbit counts as deep space).
pub fn deep_space(y0: &[f64; 6]) -> bool {
    let r = (y0[0] * y0[0] + y0[1] * y0[1] + y0[2] * y0[2]).sqrt();
    let v2 = y0[3] * y0[3] + y0[4] * y0[4] + y0[5] * y0[5];
    let inv_a = 2.0 / r - v2 / MU;
    inv_a <= 0.0 || 2.0 * std::f64::consts::PI * (inv_a.powi(-3) / MU).sqrt() >= DEEP_SPACE_PERIOD
}

/// Highest zonal degree the dynamics can include (J2..J6).
pub const MAX_ZONAL_DEGREE: u8 = 6;
/// Unnormalised zonal coefficients by degree (0 and 1 unused).
const ZONALS: [f64; 7] = [0.0, 0.0, J2, J3, J4, J5, J6];

/// How far below the decay floor a stage position must be to lose its drag, m: above the
/// error of the first-order altitude r - a (1 - f sin^2 psi) the test uses (< 100 m), so a
/// position at or above the floor always keeps it.
pub const FLOOR_MARGIN: f64 = 1_000.0;

/// Two-body + J2 (+ J3..J6 on request) + drag for a batch of members sharing one epoch
/// and atmosphere.
///
/// Lane arrays come first and the struct is aligned to a cache line, so that with 8, 16 or
/// 32 lanes every lane array starts on a 64-byte boundary and vector loads never split a
/// cache line (a misplaced `drag` cost 10 % on the AVX-512 path).
#[repr(C, align(64))]
pub struct Dynamics<'a, A: Atmosphere + ?Sized, const W: usize> {
    /// Drag parameter Cd * A / m per lane, m^2/kg (0 switches drag off in that lane).
    pub drag: [f64; W],
    /// Number of density evaluations clipped at zero, per lane.
    pub clipped: [u64; W],
    /// Normalised density offset per lane on the current node segment (0 = mean density).
    pub kappa: KappaLanes<W>,
    atmosphere: &'a A,
    /// Epoch of t = 0, seconds since J2000 (UT1).
    epoch: f64,
    /// Highest zonal harmonic in the gravity field: 2 (J2 only, the paper's model and the
    /// default) up to [`MAX_ZONAL_DEGREE`]; validated in [`crate::problem::Problem`].
    pub zonal_degree: u8,
    /// Whether the Sun's and the Moon's pull ([`crate::ephemeris`]) is included: on for
    /// deep-space orbits ([`deep_space`]), as SGP4 switches to SDP4, or on request
    /// ([`crate::problem::Forces`]).
    pub third_body: bool,
    /// Highest degree of the EGM2008 field of order >= 1 ([`crate::geopotential`]; 0:
    /// none): degree 8 for deep-space orbits, or as requested.
    pub field_degree: usize,
    /// Whether the field also carries the zonals above `zonal_degree` (when requested:
    /// the whole field to `field_degree`), not only the orders m >= 1.
    pub field_zonals: bool,
    /// Radiation parameter Cr A / m (m^2/kg) of every lane; 0: no radiation pressure
    /// ([`crate::radiation`]).
    pub radiation: f64,
    pub perturbation: Perturbation,
    /// Number of batch RHS evaluations.
    pub evaluations: u64,
    /// The run's decay floor, m of geodetic altitude (`-inf`: none). A stage position more
    /// than [`FLOOR_MARGIN`] below it sees no drag: the object is down there, and only the
    /// step that crosses the floor evaluates such points (its crossing is then located
    /// on the step's ends). With the real density a light object's stage 50 km down
    /// decelerates by 1e6 m/s^2, the step's later stages fly off to infinity and the
    /// run stops on a NaN position instead of dating its decay.
    pub floor_altitude: f64,
    /// Bumped by whoever changes `kappa` or `drag` discontinuously (see
    /// [`BatchRhs::generation`]).
    pub generation: u64,
    /// Earth rotation of the stages, one trig call per 10 minutes.
    rotation: RotationCache,
    /// What the atmosphere keeps between evaluations of this batch (boxed: it is large,
    /// and the exponential atmosphere never reads it).
    memory: Box<LaneMemory<W>>,
}

impl<'a, A: Atmosphere + ?Sized, const W: usize> Dynamics<'a, A, W> {
    /// Dynamics at the mean density (kappa = 0) with the given drag parameters.
    pub fn new(atmosphere: &'a A, epoch: f64, drag: [f64; W]) -> Self {
        Self {
            atmosphere,
            epoch,
            zonal_degree: 2,
            third_body: false,
            field_degree: 0,
            field_zonals: false,
            radiation: 0.0,
            drag,
            kappa: KappaLanes::zero(),
            perturbation: Perturbation::Additive,
            clipped: [0; W],
            evaluations: 0,
            floor_altitude: f64::NEG_INFINITY,
            generation: 0,
            rotation: RotationCache::default(),
            memory: Box::default(),
        }
    }

    /// The dynamics of a run of `problem` with the given drag parameters: its epoch, decay
    /// floor and zonal degree, and the deep-space terms when its initial state calls for
    /// them. Every propagator builds its dynamics here, so none forgets the floor.
    pub fn for_problem(atmosphere: &'a A, problem: &Problem, drag: [f64; W]) -> Self {
        let mut dynamics = Self::new(atmosphere, problem.epoch, drag);
        dynamics.floor_altitude = problem.floor_altitude;
        dynamics.zonal_degree = problem.zonal_degree;
        dynamics.set_forces(problem.forces, &problem.y0);
        dynamics
    }

    /// Switches the third bodies, the field and radiation pressure on as `forces` asks,
    /// and where it leaves the first two automatic, as the regime of the orbit `y0` calls
    /// for.
    pub fn set_forces(&mut self, forces: Forces, y0: &[f64; 6]) {
        let deep = deep_space(y0);
        self.third_body = forces.third_bodies.unwrap_or(deep);
        self.radiation = forces.radiation;
        (self.field_degree, self.field_zonals) = match forces.field_degree {
            Some(d) => (usize::from(d), true),
            None if deep => (DEEP_SPACE_TESSERAL_DEGREE, false),
            None => (0, false),
        };
    }
}

impl<A: Atmosphere + ?Sized, const W: usize> Dynamics<'_, A, W> {
    /// Density (kg/m^3) that lane `l` sees at `t` s from the epoch in state `y`.
    pub fn density(&self, t: f64, y: &State<W>, l: usize) -> Result<f64, CoreError> {
        let ut1 = self.epoch + t;
        // The rotation the stages see (bucketed GMST), not GMST directly.
        let rot = RotationCache::default().at(ut1);
        let (mean, sigma) = self
            .atmosphere
            .mean_sigma(ut1, [y[0][l], y[1][l], y[2][l]], &rot)?;
        Ok(perturb(mean, sigma, self.kappa.at(l, t), self.perturbation).0)
    }
}

/// Acceleration (m/s^2) of the zonal harmonics of degree 3..=`degree` (at most
/// [`MAX_ZONAL_DEGREE`]) at inertial position (x, y, z), m; see [`zonal_lanes`].
pub fn zonal_acceleration(x: f64, y: f64, z: f64, degree: u8) -> [f64; 3] {
    zonal_lanes::<1>(degree, &[x], &[y], &[z]).map(|c| c[0])
}

/// Zonal accelerations of degree 3..=`degree` (at most [`MAX_ZONAL_DEGREE`]) for `W`
/// positions at once, `[component][lane]`: the gradient of
/// -mu/r sum_n J_n (Re/r)^n P_n(s), s = z/r, which is
/// a = mu/r^2 sum_n J_n (Re/r)^n [P'_{n+1}(s) (x, y, z)/r - P'_n(s) e_z],
/// with P_n and its derivative by the Legendre recursions (lanes innermost, so the
/// arithmetic vectorises across members).
#[inline(always)]
pub fn zonal_lanes<const W: usize>(
    degree: u8,
    x: &[f64; W],
    y: &[f64; W],
    z: &[f64; W],
) -> [[f64; W]; 3] {
    let (mut inv_r, mut s, mut q) = ([0.0; W], [0.0; W], [0.0; W]);
    for l in 0..W {
        inv_r[l] = 1.0 / (x[l] * x[l] + y[l] * y[l] + z[l] * z[l]).sqrt();
        s[l] = z[l] * inv_r[l];
        q[l] = R_EARTH * inv_r[l];
    }
    // P_{n-1}, P_n and P'_n, starting at n = 2; (Re/r)^n.
    let mut p_prev = s;
    let mut p = s.map(|s| 1.5 * s * s - 0.5);
    let mut dp = s.map(|s| 3.0 * s);
    let mut qn: [f64; W] = std::array::from_fn(|l| q[l] * q[l]);
    let (mut radial, mut polar) = ([0.0; W], [0.0; W]);
    for n in 3..=usize::from(degree.min(MAX_ZONAL_DEGREE)) {
        let nf = n as f64;
        let (a, b) = ((2.0 * nf - 1.0) / nf, (nf - 1.0) / nf);
        for l in 0..W {
            // P'_n = s P'_{n-1} + n P_{n-1}; P_n = ((2n - 1) s P_{n-1} - (n - 1) P_{n-2}) / n.
            dp[l] = s[l] * dp[l] + nf * p[l];
            let p_next = a * s[l] * p[l] - b * p_prev[l];
            p_prev[l] = p[l];
            p[l] = p_next;
            qn[l] *= q[l];
            let dp_next = s[l] * dp[l] + (nf + 1.0) * p[l];
            radial[l] += ZONALS[n] * qn[l] * dp_next;
            polar[l] += ZONALS[n] * qn[l] * dp[l];
        }
    }
    let mut out = [[0.0; W]; 3];
    for l in 0..W {
        let k = MU * inv_r[l] * inv_r[l];
        let kr = k * radial[l] * inv_r[l];
        out[0][l] = kr * x[l];
        out[1][l] = kr * y[l];
        out[2][l] = kr * z[l] - k * polar[l];
    }
    out
}

/// Density from mean, sigma and kappa; the flag tells whether it was clipped at zero.
#[inline(always)]
pub fn perturb(mean: f64, sigma: f64, kappa: f64, perturbation: Perturbation) -> (f64, bool) {
    match perturbation {
        Perturbation::Additive => {
            let rho = mean + kappa * sigma;
            if rho < 0.0 {
                (0.0, true)
            } else {
                (rho, false)
            }
        }
        Perturbation::Lognormal => {
            if sigma == 0.0 {
                (mean, false)
            } else {
                let rel = sigma / mean;
                let s2 = (rel * rel).ln_1p();
                (mean * (kappa * s2.sqrt() - 0.5 * s2).exp(), false)
            }
        }
    }
}

impl<A: Atmosphere + ?Sized, const W: usize> BatchRhs<W> for Dynamics<'_, A, W> {
    #[inline(always)]
    fn generation(&self) -> u64 {
        self.generation
    }

    fn sides(&self, t: f64, y: &State<W>) -> u64 {
        if self.radiation <= 0.0 {
            return 0;
        }
        let sun = crate::ephemeris::sun_of_date(self.epoch + t);
        (0..W).fold(0, |acc, l| {
            let side = radiation::shadow_side([y[0][l], y[1][l], y[2][l]], sun);
            acc | (u64::from(side) << (2 * (l % 32)))
        })
    }

    fn switch_step(&self) -> f64 {
        if self.radiation > 0.0 {
            radiation::SHADOW_STEP
        } else {
            f64::INFINITY
        }
    }

    #[inline(always)]
    fn eval(&mut self, t: f64, y: &State<W>, dy: &mut State<W>) -> Result<(), CoreError> {
        self.evaluations += 1;
        let ut1 = self.epoch + t;
        // One Earth-rotation angle per stage, shared by all lanes (skipped when neither the
        // atmosphere nor the deep-space tesseral field needs it).
        let rot = if self.atmosphere.uses_earth_rotation() || self.field_degree > 0 {
            self.rotation.at(ut1)
        } else {
            EarthRotation::IDENTITY
        };
        let kj2 = -1.5 * J2 * MU * R_EARTH * R_EARTH;
        // Per lane: its Cd*A/m where drag applies (0 more than FLOOR_MARGIN below the
        // floor, by the first-order geodetic altitude), so that the density lookup neither
        // needs nor checks a point the object cannot be alive at.
        let mut live = [0.0; W];
        let (af, lowest) = (R_EARTH * WGS84_F, self.floor_altitude - FLOOR_MARGIN);
        for l in 0..W {
            let (x, yy, z) = (y[0][l], y[1][l], y[2][l]);
            let r2 = x * x + yy * yy + z * z;
            let r = r2.sqrt();
            let inv_r2 = 1.0 / r2;
            let inv_r3 = inv_r2 / r;
            let zz = 5.0 * z * z * inv_r2;
            let height = r - R_EARTH + af * (z * z * inv_r2);
            live[l] = if height >= lowest { self.drag[l] } else { 0.0 };
            let j2f = kj2 * inv_r3 * inv_r2;
            dy[0][l] = y[3][l];
            dy[1][l] = y[4][l];
            dy[2][l] = y[5][l];
            dy[3][l] = -MU * x * inv_r3 + j2f * x * (1.0 - zz);
            dy[4][l] = -MU * yy * inv_r3 + j2f * yy * (1.0 - zz);
            dy[5][l] = -MU * z * inv_r3 + j2f * z * (3.0 - zz);
        }
        // Density per lane first (the only fallible, branchy part), then the drag
        // arithmetic in a straight loop over lanes that the compiler vectorises.
        let (mut mean, mut sigma) = ([0.0; W], [0.0; W]);
        self.atmosphere.mean_sigma_lanes(
            ut1,
            &y[0],
            &y[1],
            &y[2],
            &live,
            &rot,
            &mut mean,
            &mut sigma,
            &mut self.memory,
        )?;
        let mut rho = [0.0; W];
        let w = self.kappa.weight(t);
        match self.perturbation {
            Perturbation::Additive => {
                // Straight-line so that it vectorises: clip at zero and count the clips.
                for l in 0..W {
                    let value = mean[l] + self.kappa.at_weight(l, w) * sigma[l];
                    let active = live[l] != 0.0;
                    let clipped = value < 0.0 && active;
                    rho[l] = if value < 0.0 || !active { 0.0 } else { value };
                    self.clipped[l] += u64::from(clipped);
                }
            }
            Perturbation::Lognormal => {
                for l in 0..W {
                    if live[l] != 0.0 {
                        let kappa = self.kappa.at_weight(l, w);
                        rho[l] = perturb(mean[l], sigma[l], kappa, self.perturbation).0;
                    }
                }
            }
        }
        for l in 0..W {
            // v_rel = v - omega x r with omega = (0, 0, OMEGA_EARTH).
            let vr = [
                y[3][l] + OMEGA_EARTH * y[1][l],
                y[4][l] - OMEGA_EARTH * y[0][l],
                y[5][l],
            ];
            let vn = (vr[0] * vr[0] + vr[1] * vr[1] + vr[2] * vr[2]).sqrt();
            let f = -0.5 * rho[l] * live[l] * vn;
            dy[3][l] += f * vr[0];
            dy[4][l] += f * vr[1];
            dy[5][l] += f * vr[2];
        }
        // Deep-space orbits (and others on request): the Sun's and the Moon's pull (both
        // bodies once per evaluation) and the Earth's tesseral field to degree 8
        // (crate::geopotential), whose longitude-dependent pull drifts a geostationary
        // orbit along-track by tens of km a week and resonates with 12-hour orbits
        // (SDP4's resonance terms).
        if self.third_body || self.field_degree > 0 {
            let mut t = [[0.0; W]; 3];
            if self.field_degree > 0 {
                let (mut fx, mut fy) = ([0.0; W], [0.0; W]);
                for l in 0..W {
                    [fx[l], fy[l], _] = rot.to_fixed([y[0][l], y[1][l], y[2][l]]);
                }
                let first_zonal = if self.field_zonals {
                    usize::from(self.zonal_degree) + 1
                } else {
                    usize::MAX
                };
                t = field_lanes(&fx, &fy, &y[2], self.field_degree, first_zonal);
            }
            let bodies = self.third_body.then(|| ThirdBodies::at(ut1));
            for l in 0..W {
                let a = bodies
                    .as_ref()
                    .map_or([0.0; 3], |b| b.acceleration([y[0][l], y[1][l], y[2][l]]));
                let s = rot.to_inertial([t[0][l], t[1][l], t[2][l]]);
                for c in 0..3 {
                    dy[3 + c][l] += a[c] + s[c];
                }
            }
        }
        // Solar radiation pressure where the object has a radiation parameter, after the
        // rest, so that runs without it are unchanged to the bit.
        if self.radiation > 0.0 {
            let sun = crate::ephemeris::sun_of_date(ut1);
            for l in 0..W {
                let a = radiation::acceleration([y[0][l], y[1][l], y[2][l]], sun, self.radiation);
                for c in 0..3 {
                    dy[3 + c][l] += a[c];
                }
            }
        }
        // Higher zonals only on request, decided once per call after the rest, so that the
        // J2-only path is unchanged.
        if self.zonal_degree > 2 {
            let a = zonal_lanes(self.zonal_degree, &y[0], &y[1], &y[2]);
            for c in 0..3 {
                for l in 0..W {
                    dy[3 + c][l] += a[c][l];
                }
            }
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::density::Exponential;

    fn one(state: [f64; 6]) -> State<1> {
        state.map(|c| [c])
    }

    #[test]
    fn two_body_and_j2_match_the_potential_gradient() {
        // Without drag the acceleration is the gradient of
        // U = mu/r - mu J2 Re^2 (3 z^2 / r^2 - 1) / (2 r^3); check by central differences.
        let atm = Exponential::new(1e-12, 400e3, 60e3, 0.0).unwrap();
        let mut dynm = Dynamics::new(&atm, 0.0, [0.0]);
        let p = [3782900.7, -5441600.6, -1420075.1];
        let mut dy = [[0.0]; 6];
        dynm.eval(0.0, &one([p[0], p[1], p[2], 1.0, 2.0, 3.0]), &mut dy)
            .unwrap();
        let u = |q: [f64; 3]| {
            let r = (q[0] * q[0] + q[1] * q[1] + q[2] * q[2]).sqrt();
            MU / r
                - MU * J2 * R_EARTH * R_EARTH * (3.0 * q[2] * q[2] / (r * r) - 1.0)
                    / (2.0 * r * r * r)
        };
        for i in 0..3 {
            let h = 1.0;
            let mut qp = p;
            let mut qm = p;
            qp[i] += h;
            qm[i] -= h;
            let grad = (u(qp) - u(qm)) / (2.0 * h);
            assert!(
                (dy[3 + i][0] - grad).abs() < 1e-9 * grad.abs().max(1.0),
                "axis {i}"
            );
        }
        assert_eq!(dy[0][0], 1.0);
    }

    /// Legendre polynomial P_n(s) written out for n <= 6 (independent of the recursion).
    fn legendre(n: usize, s: f64) -> f64 {
        let s2 = s * s;
        match n {
            2 => (3.0 * s2 - 1.0) / 2.0,
            3 => (5.0 * s2 - 3.0) * s / 2.0,
            4 => ((35.0 * s2 - 30.0) * s2 + 3.0) / 8.0,
            5 => ((63.0 * s2 - 70.0) * s2 + 15.0) * s / 8.0,
            6 => (((231.0 * s2 - 315.0) * s2 + 105.0) * s2 - 5.0) / 16.0,
            _ => unreachable!(),
        }
    }

    #[test]
    fn zonals_match_the_potential_gradient() {
        // U = mu/r [1 - sum_{n=2}^{N} J_n (Re/r)^n P_n(z/r)]; the acceleration of degree N
        // minus that of degree 2 is the gradient of the J3..JN terms (central differences).
        let atm = Exponential::new(1e-12, 400e3, 60e3, 0.0).unwrap();
        let points = [
            [3782900.7, -5441600.6, -1420075.1],
            [-2.0e6, 3.0e6, 5.9e6],
            [6.9e6, 1.0e5, 1.0e3],
            [1.0e6, -1.5e6, -6.8e6],
            [4.0e6, 4.0e6, 3.0e6],
        ];
        for degree in 3..=MAX_ZONAL_DEGREE {
            let u = |q: [f64; 3]| {
                let r = (q[0] * q[0] + q[1] * q[1] + q[2] * q[2]).sqrt();
                let s = q[2] / r;
                (3..=usize::from(degree))
                    .map(|n| -MU / r * ZONALS[n] * (R_EARTH / r).powi(n as i32) * legendre(n, s))
                    .sum::<f64>()
            };
            for p in points {
                let y = one([p[0], p[1], p[2], 0.0, 0.0, 0.0]);
                let (mut with, mut j2) = ([[0.0]; 6], [[0.0]; 6]);
                let mut dynm = Dynamics::new(&atm, 0.0, [0.0]);
                dynm.eval(0.0, &y, &mut j2).unwrap();
                dynm.zonal_degree = degree;
                dynm.eval(0.0, &y, &mut with).unwrap();
                let a = zonal_acceleration(p[0], p[1], p[2], degree);
                let norm = (a[0] * a[0] + a[1] * a[1] + a[2] * a[2]).sqrt();
                assert!(norm > 1e-7, "degree {degree}: {norm}");
                for i in 0..3 {
                    let h = 10.0;
                    let (mut qp, mut qm) = (p, p);
                    qp[i] += h;
                    qm[i] -= h;
                    let grad = (u(qp) - u(qm)) / (2.0 * h);
                    assert!(
                        (a[i] - grad).abs() < 1e-8 * norm,
                        "degree {degree} axis {i}: {} vs {grad}",
                        a[i]
                    );
                    let added = with[3 + i][0] - j2[3 + i][0];
                    assert!((added - a[i]).abs() < 1e-12 * j2[3 + i][0].abs().max(1.0));
                }
            }
        }
        // Degree 2 adds nothing.
        assert_eq!(zonal_acceleration(7e6, 1e5, 2e5, 2), [0.0; 3]);
    }

    #[test]
    fn drag_opposes_relative_velocity_with_the_right_magnitude() {
        let atm = Exponential::new(3.725e-12, 400e3, 58.515e3, 0.2).unwrap();
        let r = R_EARTH + 400e3;
        let state = [r, 0.0, 0.0, 0.0, 7700.0, 0.0];
        let mut with = Dynamics::new(&atm, 0.0, [3.0912 * 0.0015]);
        let mut without = Dynamics::new(&atm, 0.0, [0.0]);
        let (mut a, mut b) = ([[0.0]; 6], [[0.0]; 6]);
        with.eval(0.0, &one(state), &mut a).unwrap();
        without.eval(0.0, &one(state), &mut b).unwrap();
        let vrel = 7700.0 - OMEGA_EARTH * r;
        let expect = -0.5 * 3.725e-12 * 3.0912 * 0.0015 * vrel * vrel;
        assert!((a[4][0] - b[4][0] - expect).abs() < 1e-12 * expect.abs());
        assert_eq!(a[3][0], b[3][0]);

        // kappa = -10 with 20 % sigma makes the additive density negative: clipped to 0.
        with.kappa.k0 = [-10.0];
        with.eval(0.0, &one(state), &mut a).unwrap();
        assert_eq!(a[4][0], b[4][0]);
        assert_eq!(with.clipped, [1]);
        // Lognormal keeps it positive: mean * exp(-10 s - s^2/2).
        with.perturbation = Perturbation::Lognormal;
        with.eval(0.0, &one(state), &mut a).unwrap();
        let s2 = (1.0f64 + 0.04).ln();
        let rho = 3.725e-12 * (-10.0 * s2.sqrt() - 0.5 * s2).exp();
        let expect = -0.5 * rho * 3.0912 * 0.0015 * vrel * vrel;
        assert!((a[4][0] - b[4][0] - expect).abs() < 1e-10 * expect.abs());
    }

    #[test]
    fn lanes_are_independent() {
        let atm = Exponential::new(3.725e-12, 400e3, 58.515e3, 0.2).unwrap();
        let s0 = crate::constants::PAPER_STATE;
        let s1 = [7.0e6, 1.0e5, 2.0e5, 10.0, 7500.0, 100.0];
        let mut batch = Dynamics::new(&atm, 5e8, [0.004, 0.01]);
        batch.kappa.k0 = [0.5, -1.0];
        let y: State<2> = std::array::from_fn(|c| [s0[c], s1[c]]);
        let mut dy = [[0.0; 2]; 6];
        batch.eval(30.0, &y, &mut dy).unwrap();
        for (lane, (s, d, k)) in [(s0, 0.004, 0.5), (s1, 0.01, -1.0)].into_iter().enumerate() {
            let mut single = Dynamics::new(&atm, 5e8, [d]);
            single.kappa.k0 = [k];
            let mut d1 = [[0.0]; 6];
            single.eval(30.0, &one(s), &mut d1).unwrap();
            for c in 0..6 {
                assert_eq!(d1[c][0], dy[c][lane]);
            }
        }
    }

    #[test]
    fn the_field_and_the_third_bodies_act_as_requested_in_any_regime() {
        // A near-Earth orbit gets neither by default; asked for, each adds exactly its own
        // pull (the tesseral field of crate::geopotential rotated from the Earth-fixed
        // axes of the stage, the Sun's and the Moon's tidal pull), and a deep-space orbit
        // gets both automatically.
        let atm = Exponential::new(1e-12, 400e3, 60e3, 0.0).unwrap();
        let (epoch, t) = (7.5e8, 1234.0);
        let accel = |forces: Forces, s: [f64; 6]| {
            let mut d = Dynamics::new(&atm, epoch, [0.0]);
            d.set_forces(forces, &s);
            let mut dy = [[0.0]; 6];
            d.eval(t, &one(s), &mut dy).unwrap();
            [dy[3][0], dy[4][0], dy[5][0]]
        };
        let leo = crate::constants::PAPER_STATE;
        let p = [leo[0], leo[1], leo[2]];
        let base = accel(Forces::AUTO, leo);
        let rot = RotationCache::default().at(epoch + t);
        // Dynamics::new has zonal degree 2: the field brings J3..J8 too.
        let field = rot.to_inertial(crate::geopotential::field(rot.to_fixed(p), 8, 3));
        let with_field = Forces {
            field_degree: Some(8),
            third_bodies: None,
            radiation: 0.0,
        };
        let moved = accel(with_field, leo);
        let sun_moon = ThirdBodies::at(epoch + t).acceleration(p);
        let with_bodies = Forces {
            field_degree: None,
            third_bodies: Some(true),
            radiation: 0.0,
        };
        let pulled = accel(with_bodies, leo);
        for c in 0..3 {
            assert!(
                (moved[c] - base[c] - field[c]).abs() < 1e-12,
                "field, axis {c}"
            );
            assert!(
                (pulled[c] - base[c] - sun_moon[c]).abs() < 1e-12,
                "bodies, axis {c}"
            );
        }
        // At 460 km the field is ~1e-4 m/s^2 and the Sun and Moon ~1e-6 m/s^2: both on.
        let size = |a: [f64; 3]| (a[0] * a[0] + a[1] * a[1] + a[2] * a[2]).sqrt();
        assert!((1e-5..1e-3).contains(&size(field)), "{}", size(field));
        assert!((1e-7..1e-5).contains(&size(sun_moon)), "{}", size(sun_moon));
        // Radiation pressure adds the cannonball push of crate::radiation, nothing else.
        let lit = Forces {
            radiation: 0.02,
            ..Forces::AUTO
        };
        let pushed = accel(lit, leo);
        let sun = crate::ephemeris::sun_of_date(epoch + t);
        let push = crate::radiation::acceleration(p, sun, 0.02);
        for c in 0..3 {
            assert!(
                (pushed[c] - base[c] - push[c]).abs() < 1e-14,
                "radiation, axis {c}"
            );
        }
        // Deep space: automatically the Sun, the Moon and the orders m >= 1 to degree 8.
        let geo = [42_164e3, 0.0, 0.0, 0.0, 3_074.7, 0.0];
        let none = Forces {
            field_degree: Some(0),
            third_bodies: Some(false),
            radiation: 0.0,
        };
        let g = [geo[0], geo[1], geo[2]];
        let tess = rot.to_inertial(crate::geopotential::tesseral(rot.to_fixed(g), 8));
        let bodies = ThirdBodies::at(epoch + t).acceleration(g);
        let (auto, bare) = (accel(Forces::AUTO, geo), accel(none, geo));
        for c in 0..3 {
            let want = tess[c] + bodies[c];
            assert!(
                (auto[c] - bare[c] - want).abs() < 1e-15,
                "deep space, axis {c}"
            );
        }
    }
}
