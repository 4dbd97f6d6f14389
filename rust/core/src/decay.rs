//! Where an orbit crosses the decay floor within a step. Checking only step ends misses a
//! perigee pass below the floor between them and dates a decay up to a step late; instead
//! each step is interpolated by the cubic Hermite polynomial of its end positions and
//! velocities (error O(h^4): tens of metres for a 3-minute step at a low perigee, so the
//! crossing time is good to about a second) and the crossing is located on it to
//! [`TIME_TOLERANCE`]. Cheap: the full search runs only when the radius can come
//! near the floor.

use crate::constants::{MU, R_EARTH};
use crate::dynamics::State;
use crate::frames::altitude;

/// Accuracy of a located crossing time, s.
pub const TIME_TOLERANCE: f64 = 1e-3;

/// One lane's state at both ends of a step.
#[derive(Debug, Clone, Copy)]
pub struct StepEnds {
    pub t0: f64,
    pub y0: [f64; 6],
    pub t1: f64,
    pub y1: [f64; 6],
}

impl StepEnds {
    /// The Hermite-interpolated state at time `t` in [t0, t1].
    pub fn state_at(&self, t: f64) -> [f64; 6] {
        let h = self.t1 - self.t0;
        if h == 0.0 {
            return self.y1;
        }
        let s = (t - self.t0) / h;
        let (s2, s3) = (s * s, s * s * s);
        let (h00, h10, h01, h11) = (
            2.0 * s3 - 3.0 * s2 + 1.0,
            s3 - 2.0 * s2 + s,
            -2.0 * s3 + 3.0 * s2,
            s3 - s2,
        );
        let (d00, d10, d01, d11) = (
            6.0 * s2 - 6.0 * s,
            3.0 * s2 - 4.0 * s + 1.0,
            -6.0 * s2 + 6.0 * s,
            3.0 * s2 - 2.0 * s,
        );
        let (a, b) = (&self.y0, &self.y1);
        let mut out = [0.0; 6];
        for c in 0..3 {
            out[c] = h00 * a[c] + h10 * h * a[c + 3] + h01 * b[c] + h11 * h * b[c + 3];
            out[c + 3] = (d00 * a[c] + d01 * b[c]) / h + d10 * a[c + 3] + d11 * b[c + 3];
        }
        out
    }

    fn radius_at(&self, t: f64) -> f64 {
        let s = self.state_at(t);
        (s[0] * s[0] + s[1] * s[1] + s[2] * s[2]).sqrt()
    }
}

fn norm(v: &[f64]) -> f64 {
    (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt()
}

fn dot(a: &[f64], b: &[f64]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

/// Whether each lane of a batch step from `prev` (at `t0`) to `y` (at `t1`) may cross the
/// floor: it ends below Re + floor or passes a periapsis (radial velocity from falling to
/// rising). The cheap test every lane takes every step, on the structure-of-arrays states
/// so that it vectorises; [`crossing`] does the rest only where it holds.
#[inline(always)]
pub fn may_cross_lanes<const W: usize>(
    t0: f64,
    prev: &State<W>,
    t1: f64,
    y: &State<W>,
    floor: f64,
) -> [bool; W] {
    let threshold = R_EARTH + floor;
    let forward = t1 >= t0;
    let mut out = [false; W];
    for l in 0..W {
        let rv0 = prev[0][l] * prev[3][l] + prev[1][l] * prev[4][l] + prev[2][l] * prev[5][l];
        let rv1 = y[0][l] * y[3][l] + y[1][l] * y[4][l] + y[2][l] * y[5][l];
        let r1 = y[0][l] * y[0][l] + y[1][l] * y[1][l] + y[2][l] * y[2][l];
        let periapsis = if forward {
            rv0 < 0.0 && rv1 > 0.0
        } else {
            rv0 > 0.0 && rv1 < 0.0
        };
        out[l] = periapsis || r1 < threshold * threshold;
    }
    out
}

/// Lanes bound at `prev` (specific energy v^2/2 - mu/r < 0) and unbound (energy >= 0)
/// or non-finite at `y`, one step later: neither drag nor the rest of the field (J2..Jn,
/// the Sun and Moon, the tesseral terms) unbinds an orbit in a step, so such a lane was
/// not integrated (a drag far too strong for the step flings it out). A fixed step's
/// ordinary energy error (a HEO's perigee pass at 180 s) never gets there.
pub fn unbound_lanes<const W: usize>(prev: &State<W>, y: &State<W>) -> [bool; W] {
    let energy = |s: &State<W>, l: usize| {
        let r = (s[0][l] * s[0][l] + s[1][l] * s[1][l] + s[2][l] * s[2][l]).sqrt();
        0.5 * (s[3][l] * s[3][l] + s[4][l] * s[4][l] + s[5][l] * s[5][l]) - MU / r
    };
    std::array::from_fn(|l| {
        let (e0, e1) = (energy(prev, l), energy(y, l));
        e0 < 0.0 && (e1 >= 0.0 || e1.is_nan())
    })
}

/// The lane `l` of a batch step as [`StepEnds`].
#[inline(always)]
pub fn lane_step<const W: usize>(
    t0: f64,
    prev: &State<W>,
    t1: f64,
    y: &State<W>,
    l: usize,
) -> StepEnds {
    StepEnds {
        t0,
        y0: std::array::from_fn(|c| prev[c][l]),
        t1,
        y1: std::array::from_fn(|c| y[c][l]),
    }
}

/// The first time in (t0, t1] at which the geodetic altitude falls below `floor` (m), if
/// it does, for a step that started above the floor. `epoch` is the UT1 of t = 0 (s since
/// J2000). Works for forward and backward steps.
#[inline(never)]
pub fn crossing(epoch: f64, step: &StepEnds, floor: f64) -> Option<f64> {
    // The geodetic altitude is at least |r| - Re (the ellipsoid lies inside that sphere),
    // so a step whose radius stays above Re + floor cannot cross.
    let threshold = R_EARTH + floor;
    let (p0, v0) = (&step.y0[..3], &step.y0[3..]);
    let (p1, v1) = (&step.y1[..3], &step.y1[3..]);
    let r1 = norm(p1);
    let h = step.t1 - step.t0;
    // A periapsis inside the step: the radial velocity changes sign from falling to rising.
    let (rv0, rv1) = (dot(p0, v0), dot(p1, v1));
    let periapsis = if h >= 0.0 {
        rv0 < 0.0 && rv1 > 0.0
    } else {
        rv0 > 0.0 && rv1 < 0.0
    };
    if !periapsis && r1 >= threshold {
        return None;
    }
    let r0 = norm(p0);
    // Bound on how far below its ends the radius can sag within the step.
    let speed = norm(v0).max(norm(v1));
    let sag = (speed * h).powi(2) / (2.0 * r0.min(r1)) + 1e4;
    let below = |t: f64| {
        altitude(epoch + t, {
            let s = step.state_at(t);
            [s[0], s[1], s[2]]
        }) < floor
    };
    let mut start = step.t0;
    let mut negative = None;
    if periapsis && r0.min(r1) - sag < threshold {
        let tm = golden_minimum(step);
        if step.radius_at(tm) < threshold && below(tm) {
            negative = Some(tm);
        } else {
            start = tm;
        }
    }
    if negative.is_none() && r1 < threshold && below(step.t1) {
        negative = Some(step.t1);
    }
    let (mut a, mut b) = (start, negative?);
    // Bisection: above the floor at a, below at b.
    while (b - a).abs() > TIME_TOLERANCE {
        let m = 0.5 * (a + b);
        if below(m) {
            b = m;
        } else {
            a = m;
        }
    }
    Some(b)
}

/// Time of the smallest radius of the interpolated step (golden-section search).
fn golden_minimum(step: &StepEnds) -> f64 {
    const G: f64 = 0.618_033_988_749_894_8;
    let (mut a, mut b) = (step.t0, step.t1);
    let mut c = b - G * (b - a);
    let mut d = a + G * (b - a);
    let (mut fc, mut fd) = (step.radius_at(c), step.radius_at(d));
    while (b - a).abs() > TIME_TOLERANCE {
        if fc < fd {
            b = d;
            d = c;
            fd = fc;
            c = b - G * (b - a);
            fc = step.radius_at(c);
        } else {
            a = c;
            c = d;
            fc = fd;
            d = a + G * (b - a);
            fd = step.radius_at(d);
        }
    }
    0.5 * (a + b)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::constants::MU;

    /// A Keplerian ellipse with perigee radius `rp` and apogee radius `ra` in the equatorial
    /// plane, perigee on the x axis at t = 0: state at time `t` by Kepler's equation.
    fn kepler(rp: f64, ra: f64, t: f64) -> [f64; 6] {
        let a = 0.5 * (rp + ra);
        let e = (ra - rp) / (ra + rp);
        let n = (MU / a.powi(3)).sqrt();
        let m = n * t;
        let mut ea = m;
        for _ in 0..50 {
            ea -= (ea - e * ea.sin() - m) / (1.0 - e * ea.cos());
        }
        let (c, s) = (ea.cos(), ea.sin());
        let b = a * (1.0 - e * e).sqrt();
        let rdot = n * a / (1.0 - e * c);
        [
            a * (c - e),
            b * s,
            0.0,
            -a * s * rdot / a,
            b * c * rdot / a,
            0.0,
        ]
    }

    #[test]
    fn hermite_reproduces_the_ends_and_is_fourth_order() {
        let (rp, ra) = (R_EARTH + 130e3, R_EARTH + 900e3);
        let at = |t0: f64, t1: f64| StepEnds {
            t0,
            y0: kepler(rp, ra, t0),
            t1,
            y1: kepler(rp, ra, t1),
        };
        let step = at(-300.0, 300.0);
        assert_eq!(step.state_at(-300.0)[0], step.y0[0]);
        let err = |h: f64| {
            let s = at(-h, h);
            let (x, y) = (s.state_at(0.1 * h), kepler(rp, ra, 0.1 * h));
            ((x[0] - y[0]).powi(2) + (x[1] - y[1]).powi(2)).sqrt()
        };
        let order = (err(200.0) / err(100.0)).log2();
        assert!((order - 4.0).abs() < 0.3, "order {order}");
        // A 180 s step next to the perigee of a 130 x 900 km ellipse: tens of metres.
        assert!(err(90.0) < 50.0, "{} m", err(90.0));
    }

    #[test]
    fn finds_a_perigee_dip_between_step_ends() {
        // Perigee 100 km (equatorial: geodetic altitude = radius - Re), floor 120 km: the
        // orbit is below the floor only near perigee, inside a step whose ends are above.
        let (rp, ra) = (R_EARTH + 100e3, R_EARTH + 900e3);
        let step = StepEnds {
            t0: -300.0,
            y0: kepler(rp, ra, -300.0),
            t1: 350.0,
            y1: kepler(rp, ra, 350.0),
        };
        // Both ends above the floor.
        assert!(norm(&step.y0[..3]) - R_EARTH > 121e3 && norm(&step.y1[..3]) - R_EARTH > 121e3);
        let t = crossing(0.0, &step, 120e3).expect("crosses");
        // Reference: where the exact ellipse reaches 120 km, by bisection on Kepler.
        let (mut a, mut b) = (-300.0, 0.0);
        for _ in 0..60 {
            let m = 0.5 * (a + b);
            if norm(&kepler(rp, ra, m)[..3]) - R_EARTH < 120e3 {
                b = m;
            } else {
                a = m;
            }
        }
        // A 650 s step across the perigee: the interpolant is ~100 m off there.
        assert!((t - b).abs() < 2.0, "located {t} s, exact {b} s");
        // A floor below the perigee is never crossed.
        assert_eq!(crossing(0.0, &step, 90e3), None);
    }

    #[test]
    fn a_step_far_above_the_floor_is_skipped() {
        let (rp, ra) = (R_EARTH + 400e3, R_EARTH + 420e3);
        let step = StepEnds {
            t0: 0.0,
            y0: kepler(rp, ra, 0.0),
            t1: 180.0,
            y1: kepler(rp, ra, 180.0),
        };
        assert_eq!(crossing(0.0, &step, 120e3), None);
    }
}
