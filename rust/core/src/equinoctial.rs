//! Equinoctial orbital elements (a, h, k, p, q, lambda): the coordinates in which the CCSP
//! draws its sigma points and carries its covariance (docs/conventions.md, "CCSP
//! coordinates"). An along-track spread is a spread of the mean longitude lambda, so a
//! Gaussian there stays on the orbit for weeks, where a Cartesian one is a straight line
//! that leaves it (Junkins, Akella & Alfriend 1996; Horwood & Poore 2011).
//!
//! Definitions (Broucke & Cefola 1972, prograde factor +1): a the semi-major axis (m);
//! k + i h = e exp(i (omega + Omega)); q + i p = tan(i / 2) exp(i Omega), i.e.
//! p = tan(i/2) sin(Omega), q = tan(i/2) cos(Omega); lambda = M + omega + Omega (rad).
//! They are singular only for retrograde equatorial orbits (i = 180 deg): a state whose
//! angular momentum points south is converted in axes turned 180 deg about x
//! ([`Axes::Flipped`]), chosen once per run so lambda stays continuous.

use crate::constants::{J2, MU, R_EARTH};
use crate::error::CoreError;
use nalgebra::{Matrix6, Vector3, Vector6};

/// The axes the elements are taken in.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Axes {
    /// The inertial axes of the state.
    Direct,
    /// Turned 180 deg about x (y -> -y, z -> -z): a retrograde orbit becomes prograde.
    Flipped,
}

impl Axes {
    /// The axes in which the orbit of `state` is prograde (angular momentum z >= 0).
    pub fn for_state(state: &Vector6<f64>) -> Self {
        let r = Vector3::new(state[0], state[1], state[2]);
        let v = Vector3::new(state[3], state[4], state[5]);
        if r.cross(&v).z >= 0.0 {
            Axes::Direct
        } else {
            Axes::Flipped
        }
    }

    fn apply(self, s: &Vector6<f64>) -> Vector6<f64> {
        match self {
            Axes::Direct => *s,
            Axes::Flipped => Vector6::new(s[0], -s[1], -s[2], s[3], -s[4], -s[5]),
        }
    }
}

/// What the first element, a, is.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum SemiMajor {
    /// The osculating (two-body) semi-major axis, -mu / (2 (v^2 / 2 - mu / r)).
    Osculating,
    /// The energy semi-major axis, -mu / (2 epsilon) with epsilon the orbit's energy in the
    /// J2 field, v^2 / 2 - mu / r + mu J2 R^2 (3 z^2 / r^2 - 1) / (2 r^3): constant along
    /// an orbit under J2 (the field is axisymmetric), where the osculating a swings by
    /// about 2 J2 R^2 / a (13 km at 400 km) twice a revolution. The CCSP's coordinate: its
    /// sigma points spread degrees along the orbit, and with the osculating a each was
    /// re-drawn with the centre's phase of that swing, a spurious spread of mean motion
    /// that fed on itself (3x a Monte Carlo's along-track sigma by 30 days at 400 km for
    /// a 4-day density term, docs/mc-vs-ccsp.md).
    Energy,
}

/// The J2 part of the potential energy per unit mass at `r`, m^2/s^2.
fn j2_energy(r: &Vector3<f64>) -> f64 {
    let r2 = r.norm_squared();
    let rn = r2.sqrt();
    MU * J2 * R_EARTH * R_EARTH * (3.0 * r.z * r.z / r2 - 1.0) / (2.0 * r2 * rn)
}

/// The equinoctial frame's in-plane unit vectors f and g of (p, q).
fn frame(p: f64, q: f64) -> (Vector3<f64>, Vector3<f64>) {
    let s = 1.0 + p * p + q * q;
    let f = Vector3::new(1.0 - p * p + q * q, 2.0 * p * q, -2.0 * p) / s;
    let g = Vector3::new(2.0 * p * q, 1.0 + p * p - q * q, 2.0 * q) / s;
    (f, g)
}

/// Cartesian state (m, m/s) -> equinoctial elements with a of kind `semi`.
pub fn from_cartesian_with(
    state: &Vector6<f64>,
    axes: Axes,
    semi: SemiMajor,
    what: &str,
) -> Result<Vector6<f64>, CoreError> {
    let mut el = from_cartesian(state, axes, what)?;
    if semi == SemiMajor::Energy {
        let r = Vector3::new(state[0], state[1], state[2]);
        let inv = 1.0 / el[0] - 2.0 * j2_energy(&r) / MU;
        if !(inv.is_finite() && inv > 0.0) {
            return Err(CoreError::rejected(
                what,
                "is not on a bound orbit in the J2 field",
            ));
        }
        el[0] = 1.0 / inv;
    }
    Ok(el)
}

/// Equinoctial elements with a of kind `semi` -> Cartesian state (m, m/s). For the energy
/// a, the osculating one solves 1 / a_osc = 1 / a + 2 U_J2(r) / mu. With h, k, p, q and
/// lambda held, the eccentric longitude does not depend on a: the position scales as
/// a_osc and the velocity as a_osc^(-1/2), and z / r is fixed, so one Kepler solution at
/// a gives r / a and z / r and the equation is scalar, solved by fixed-point iteration
/// (each step shrinks the error by about 3 J2 (R / r)^2; six steps from a_osc = a leave
/// 1e-18 of it, a fixed count keeps the map smooth for the Jacobian's differences).
pub fn to_cartesian_with(el: &Vector6<f64>, axes: Axes, semi: SemiMajor) -> Vector6<f64> {
    let x = to_cartesian(el, axes);
    if semi == SemiMajor::Osculating {
        return x;
    }
    let a = el[0];
    let r = Vector3::new(x[0], x[1], x[2]);
    let (rho, s2) = (r.norm() / a, r.z * r.z / r.norm_squared());
    let c = J2 * R_EARTH * R_EARTH * (3.0 * s2 - 1.0) / rho.powi(3);
    let mut a_osc = a;
    for _ in 0..6 {
        a_osc = 1.0 / (1.0 / a + c / a_osc.powi(3));
    }
    let (fr, fv) = (a_osc / a, (a / a_osc).sqrt());
    Vector6::new(
        x[0] * fr,
        x[1] * fr,
        x[2] * fr,
        x[3] * fv,
        x[4] * fv,
        x[5] * fv,
    )
}

/// Cartesian state (m, m/s) -> equinoctial elements (a m, h, k, p, q, lambda rad in
/// (-pi, pi]), a osculating. An orbit that is not elliptic (a <= 0 or e >= 1) or has no
/// angular momentum has no such elements: an error naming `what`.
pub fn from_cartesian(
    state: &Vector6<f64>,
    axes: Axes,
    what: &str,
) -> Result<Vector6<f64>, CoreError> {
    let s = axes.apply(state);
    let r = Vector3::new(s[0], s[1], s[2]);
    let v = Vector3::new(s[3], s[4], s[5]);
    let rn = r.norm();
    let inv_a = 2.0 / rn - v.norm_squared() / MU;
    let hvec = r.cross(&v);
    let hn = hvec.norm();
    if !inv_a.is_finite() || inv_a <= 0.0 || hn.is_nan() || hn <= 0.0 {
        return Err(CoreError::rejected(
            what,
            "is not on an elliptic orbit (equinoctial elements need a > 0 and e < 1; \
             use Cartesian coordinates)",
        ));
    }
    let a = 1.0 / inv_a;
    let w = hvec / hn;
    if w.z <= -1.0 + 1e-12 {
        return Err(CoreError::rejected(
            what,
            "is a retrograde equatorial orbit in these axes (equinoctial elements are \
             singular there)",
        ));
    }
    let p = w.x / (1.0 + w.z);
    let q = -w.y / (1.0 + w.z);
    let (f, g) = frame(p, q);
    let evec = (r * (v.norm_squared() - MU / rn) - v * r.dot(&v)) / MU;
    let (k, h) = (evec.dot(&f), evec.dot(&g));
    let e2 = h * h + k * k;
    if e2 >= 1.0 {
        return Err(CoreError::rejected(
            what,
            "is not on an elliptic orbit (e >= 1; use Cartesian coordinates)",
        ));
    }
    // Eccentric longitude F from the in-plane position (X1, Y1): a linear system in
    // (cos F, sin F) of determinant sqrt(1 - e^2).
    let beta = 1.0 / (1.0 + (1.0 - e2).sqrt());
    let (x1, y1) = (r.dot(&f) / a + k, r.dot(&g) / a + h);
    let (m11, m12, m22) = (1.0 - h * h * beta, h * k * beta, 1.0 - k * k * beta);
    let det = m11 * m22 - m12 * m12;
    let cos_f = (m22 * x1 - m12 * y1) / det;
    let sin_f = (m11 * y1 - m12 * x1) / det;
    let big_f = sin_f.atan2(cos_f);
    let lambda = big_f + h * big_f.cos() - k * big_f.sin();
    Ok(Vector6::new(a, h, k, p, q, wrap(lambda)))
}

/// Equinoctial elements -> Cartesian state (m, m/s), solving the generalised Kepler
/// equation lambda = F + h cos F - k sin F by Newton's method.
pub fn to_cartesian(el: &Vector6<f64>, axes: Axes) -> Vector6<f64> {
    let (a, h, k, p, q, lambda) = (el[0], el[1], el[2], el[3], el[4], el[5]);
    let mut big_f = lambda;
    for _ in 0..30 {
        let (sf, cf) = big_f.sin_cos();
        let step = (big_f + h * cf - k * sf - lambda) / (1.0 - h * sf - k * cf);
        big_f -= step;
        if step.abs() < 1e-15 {
            break;
        }
    }
    let (sf, cf) = big_f.sin_cos();
    let beta = 1.0 / (1.0 + (1.0 - h * h - k * k).sqrt());
    let n = (MU / (a * a * a)).sqrt();
    let rn = a * (1.0 - k * cf - h * sf);
    let x1 = a * ((1.0 - h * h * beta) * cf + h * k * beta * sf - k);
    let y1 = a * (h * k * beta * cf + (1.0 - k * k * beta) * sf - h);
    let vx1 = a * a * n / rn * (h * k * beta * cf - (1.0 - h * h * beta) * sf);
    let vy1 = a * a * n / rn * ((1.0 - k * k * beta) * cf - h * k * beta * sf);
    let (f, g) = frame(p, q);
    let r = f * x1 + g * y1;
    let v = f * vx1 + g * vy1;
    axes.apply(&Vector6::new(r.x, r.y, r.z, v.x, v.y, v.z))
}

/// An angle in (-pi, pi].
pub fn wrap(x: f64) -> f64 {
    let t = std::f64::consts::TAU;
    let y = x - t * (x / t).round();
    if y <= -std::f64::consts::PI {
        y + t
    } else {
        y
    }
}

/// `el` with lambda moved by whole turns to within pi of `near`'s (so differences of
/// lambda between sigma points never jump by 2 pi).
pub fn unwrap_near(el: &Vector6<f64>, near: f64) -> Vector6<f64> {
    let mut out = *el;
    out[5] = near + wrap(el[5] - near);
    out
}

/// Cartesian mean and covariance of the Gaussian (`mean`, `cov`) in elements by the
/// unscented transform with lambda + n = `l1` (points mean +- sqrt(l1) columns of the
/// Cholesky factor, weights (l1 - 6) / l1 and 1 / (2 l1)); None when `cov` is not
/// positive definite or a point is not an elliptic orbit.
///
/// The factor is taken with lambda first, so that one pair of points carries the whole
/// lambda spread: the arc's sag (a radial offset quadratic in lambda) then gets its full
/// variance, 2 (a sigma_lambda^2 / 2)^2. With lambda last, its spread was shared among the
/// columns of a and the consider directions, and the transform, which sees no products
/// of two columns, put a fraction of it in the radial variance (the storm case of
/// `benches/ccsp_long.py` at 14 days: 0.6 km radial against the members' 3.4 km).
pub fn cartesian_moments(
    mean: &Vector6<f64>,
    cov: &Matrix6<f64>,
    axes: Axes,
    semi: SemiMajor,
    l1: f64,
) -> Option<(Vector6<f64>, Matrix6<f64>)> {
    // Element order [lambda, a, h, k, p, q] for the factor, back to [a .. lambda] after.
    const ORDER: [usize; 6] = [5, 0, 1, 2, 3, 4];
    let permuted = Matrix6::from_fn(|i, j| cov[(ORDER[i], ORDER[j])]);
    let lp = nalgebra::Cholesky::new(permuted)?.l();
    let l = Matrix6::from_fn(|i, j| {
        let row = ORDER.iter().position(|&o| o == i).unwrap_or(i);
        lp[(row, j)]
    }) * l1.sqrt();
    let (w0, wi) = ((l1 - 6.0) / l1, 0.5 / l1);
    let mut points = vec![to_cartesian_with(mean, axes, semi)];
    for j in 0..6 {
        for sign in [1.0, -1.0] {
            let el = mean + l.column(j) * sign;
            if el[0].is_nan() || el[0] <= 0.0 || el[1] * el[1] + el[2] * el[2] >= 1.0 {
                return None;
            }
            points.push(to_cartesian_with(&el, axes, semi));
        }
    }
    let w = |k: usize| if k == 0 { w0 } else { wi };
    let m: Vector6<f64> = points.iter().enumerate().map(|(k, x)| x * w(k)).sum();
    let mut p = Matrix6::zeros();
    for (k, x) in points.iter().enumerate() {
        let dx = x - m;
        p += dx * dx.transpose() * w(k);
    }
    Some((m, p))
}

/// d(Cartesian)/d(elements) at `el` (6x6), by central differences: steps of 1e-6 in a
/// relative, 1e-8 in h, k, p, q and lambda, so that truncation (O(step^2)) and rounding
/// (eps / step) both stay below about 1e-8 relative.
pub fn jacobian(el: &Vector6<f64>, axes: Axes, semi: SemiMajor) -> Matrix6<f64> {
    let steps = [el[0] * 1e-6, 1e-8, 1e-8, 1e-8, 1e-8, 1e-8];
    let mut jac = Matrix6::zeros();
    for (j, &dx) in steps.iter().enumerate() {
        let mut plus = *el;
        let mut minus = *el;
        plus[j] += dx;
        minus[j] -= dx;
        let col = (to_cartesian_with(&plus, axes, semi) - to_cartesian_with(&minus, axes, semi))
            / (2.0 * dx);
        jac.set_column(j, &col);
    }
    jac
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::constants::R_EARTH;
    use proptest::prelude::*;

    /// A Cartesian state from classical elements (a, e, i, Omega, omega, M), written
    /// with perifocal rotations, independently of the equinoctial formulas.
    fn classical(a: f64, e: f64, i: f64, raan: f64, argp: f64, m: f64) -> Vector6<f64> {
        let mut big_e = m;
        for _ in 0..50 {
            big_e -= (big_e - e * big_e.sin() - m) / (1.0 - e * big_e.cos());
        }
        let (se, ce) = big_e.sin_cos();
        let b = a * (1.0 - e * e).sqrt();
        let rn = a * (1.0 - e * ce);
        let n = (MU / a.powi(3)).sqrt();
        let (xp, yp) = (a * (ce - e), b * se);
        let (vxp, vyp) = (-a * a * n / rn * se, a * b * n / rn * ce);
        let rot = nalgebra::Rotation3::from_axis_angle(&Vector3::z_axis(), raan)
            * nalgebra::Rotation3::from_axis_angle(&Vector3::x_axis(), i)
            * nalgebra::Rotation3::from_axis_angle(&Vector3::z_axis(), argp);
        let r = rot * Vector3::new(xp, yp, 0.0);
        let v = rot * Vector3::new(vxp, vyp, 0.0);
        Vector6::new(r.x, r.y, r.z, v.x, v.y, v.z)
    }

    #[test]
    fn elements_of_a_classical_orbit_are_the_definitions() {
        let (a, e, i, raan, argp, m) = (7.0e6, 0.05, 0.9, 1.2, 2.0, 0.4);
        let s = classical(a, e, i, raan, argp, m);
        let el = from_cartesian(&s, Axes::for_state(&s), "state").unwrap();
        let tol = 1e-10;
        assert!((el[0] - a).abs() < 1e-6, "a {}", el[0]);
        assert!((el[1] - e * (argp + raan).sin()).abs() < tol, "h");
        assert!((el[2] - e * (argp + raan).cos()).abs() < tol, "k");
        assert!((el[3] - (i / 2.0).tan() * raan.sin()).abs() < tol, "p");
        assert!((el[4] - (i / 2.0).tan() * raan.cos()).abs() < tol, "q");
        assert!((el[5] - wrap(m + argp + raan)).abs() < tol, "lambda");
    }

    proptest! {
        #[test]
        fn round_trip_is_exact_to_rounding(
            alt in 150e3f64..40000e3,
            e in 0.0f64..0.8,
            i in 0.0f64..3.1,
            raan in -3.1f64..3.1,
            argp in -3.1f64..3.1,
            m in -3.1f64..3.1,
        ) {
            let a = (R_EARTH + alt) / (1.0 - e).max(0.2);
            let s = classical(a, e, i, raan, argp, m);
            let axes = Axes::for_state(&s);
            let el = from_cartesian(&s, axes, "state").unwrap();
            let back = to_cartesian(&el, axes);
            let rscale = s.fixed_rows::<3>(0).norm();
            let vscale = s.fixed_rows::<3>(3).norm();
            prop_assert!((back - s).fixed_rows::<3>(0).norm() < 1e-9 * rscale);
            prop_assert!((back - s).fixed_rows::<3>(3).norm() < 1e-9 * vscale);
        }
    }

    #[test]
    fn retrograde_equatorial_orbits_convert_in_flipped_axes() {
        let s = classical(7.0e6, 0.01, std::f64::consts::PI, 0.3, 0.2, 0.1);
        let axes = Axes::for_state(&s);
        assert_eq!(axes, Axes::Flipped);
        let el = from_cartesian(&s, axes, "state").unwrap();
        assert!((to_cartesian(&el, axes) - s).norm() < 1e-6);
        assert!(from_cartesian(&s, Axes::Direct, "state").is_err());
    }

    #[test]
    fn hyperbolic_states_are_an_error_naming_the_state() {
        let s = Vector6::new(7.0e6, 0.0, 0.0, 0.0, 12e3, 0.0);
        let e = from_cartesian(&s, Axes::Direct, "sigma point 3").unwrap_err();
        assert!(e.to_string().contains("sigma point 3"), "{e}");
    }

    #[test]
    fn jacobian_matches_a_second_difference_scheme_and_inverts() {
        let s = classical(6.8e6, 0.002, 1.7, 0.5, 1.0, 2.0);
        let axes = Axes::for_state(&s);
        for semi in [SemiMajor::Osculating, SemiMajor::Energy] {
            let el = from_cartesian_with(&s, axes, semi, "state").unwrap();
            assert!(
                (to_cartesian_with(&el, axes, semi) - s)
                    .fixed_rows::<3>(0)
                    .norm()
                    < 1e-6
            );
            let jac = jacobian(&el, axes, semi);
            // Forward differences with other steps: agree to their O(step) error.
            for j in 0..6 {
                let dx = if j == 0 { 1e-2 } else { 1e-9 };
                let mut plus = el;
                plus[j] += dx;
                let fwd = (to_cartesian_with(&plus, axes, semi) - s) / dx;
                let err = (fwd - jac.column(j)).norm() / jac.column(j).norm();
                assert!(err < 1e-5, "{semi:?} column {j}: {err}");
            }
            // d(elements)/d(Cartesian) by differences of from_cartesian is its inverse.
            let mut inv = Matrix6::zeros();
            for j in 0..6 {
                let dx = if j < 3 { 1e-1 } else { 1e-4 };
                let mut plus = s;
                let mut minus = s;
                plus[j] += dx;
                minus[j] -= dx;
                let col = (from_cartesian_with(&plus, axes, semi, "s").unwrap()
                    - from_cartesian_with(&minus, axes, semi, "s").unwrap())
                    / (2.0 * dx);
                inv.set_column(j, &col);
            }
            // Compared in units of the orbit (position / |r|, velocity / |v|).
            let (rn, vn) = (s.fixed_rows::<3>(0).norm(), s.fixed_rows::<3>(3).norm());
            let scale = Vector6::new(rn, rn, rn, vn, vn, vn);
            let id = Matrix6::from_fn(|i, j| (jac * inv)[(i, j)] * scale[j] / scale[i]);
            assert!(
                (id - Matrix6::identity()).abs().max() < 1e-6,
                "{semi:?} {id}"
            );
        }
    }

    #[test]
    fn the_energy_semi_major_axis_holds_still_along_a_j2_orbit() {
        // A day of a 400 km orbit at 51.6 deg under J2 alone (no drag): the osculating a
        // swings by kilometres twice a revolution, the energy a by the integrator's error.
        use crate::density::Exponential;
        use crate::problem::Problem;
        use crate::progress::Progress;
        use crate::propagate::{propagate, Method};
        let s0 = classical(R_EARTH + 400e3, 0.001, 0.9, 0.3, 0.2, 0.1);
        let axes = Axes::for_state(&s0);
        let problem = Problem {
            epoch: 0.0,
            y0: std::array::from_fn(|i| s0[i]),
            drag: 1e-12, // m^2/kg: no drag to speak of (it must be > 0)
            floor_altitude: 100e3,
            zonal_degree: 2,
            forces: crate::problem::Forces::AUTO,
        };
        let atm = Exponential::new(3.725e-12, 400e3, 58.515e3, 0.0).unwrap();
        let times: Vec<f64> = (1..=288).map(|i| i as f64 * 300.0).collect();
        let tr = propagate(
            &atm,
            &problem,
            &times,
            Method::Rk8 { step: 30.0 },
            &Progress::default(),
        )
        .unwrap();
        let spread = |semi| {
            let a: Vec<f64> = tr
                .states
                .iter()
                .map(|x| {
                    from_cartesian_with(&Vector6::from_column_slice(x), axes, semi, "s").unwrap()[0]
                })
                .collect();
            let (lo, hi) = a
                .iter()
                .fold((f64::MAX, f64::MIN), |(l, h), &v| (l.min(v), h.max(v)));
            hi - lo
        };
        let (osc, energy) = (spread(SemiMajor::Osculating), spread(SemiMajor::Energy));
        assert!(osc > 5e3, "osculating a swings {osc} m");
        assert!(energy < 0.05, "energy a moves {energy} m");
    }

    #[test]
    fn wrap_and_unwrap() {
        assert!((wrap(3.0 * std::f64::consts::PI) - std::f64::consts::PI).abs() < 1e-12);
        let el = Vector6::new(7e6, 0.0, 0.0, 0.0, 0.0, -3.1);
        assert!((unwrap_near(&el, 3.1)[5] - (std::f64::consts::TAU - 3.1)).abs() < 1e-12);
    }
}
