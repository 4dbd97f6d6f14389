//! The counting step of the Pc over an encounter interval (the Python
//! `rhoprop.conjunction.encounter.pc_interval`, which draws the relative states): each
//! relative state at TCA is flown by the Clohessy-Wiltshire equations about a circular
//! orbit of mean motion n over [-span/2, span/2], and counted when its distance falls
//! within the hard-body radius.
//!
//! Per state, a coarse pass on `coarse_points` even times sets it aside when it cannot
//! come within the radius: between two points the distance dips at most half the chord
//! (the arcs over 1/200 of an orbit are straight to 1e-4), taken 10 % wider, so a state
//! is kept when min |rho| - 0.55 max chord <= HBR. A kept state's squared distance is
//! evaluated on `grid_points` even times and its minimum refined by the parabola through
//! the grid minimum and its neighbours (exact for straight motion). The CW coefficients
//! of each time are computed once for all states.

use crate::error::CoreError;
use crate::progress::Progress;
use rayon::prelude::*;

/// States per parallel task (the hit count does not depend on the split).
const STATES_PER_TASK: usize = 1024;

/// The CW state-transition coefficients of one time t (nt = n t): position at t from
/// the LVLH position (x radial, y along-track, z cross-track) and velocity at 0.
struct Cw {
    xx: f64,
    xu: f64,
    xv: f64,
    yx: f64,
    yu: f64,
    yv: f64,
    zz: f64,
    zw: f64,
}

impl Cw {
    fn new(n: f64, t: f64) -> Self {
        let nt = n * t;
        let (s, c) = nt.sin_cos();
        Cw {
            xx: 4.0 - 3.0 * c,
            xu: s / n,
            xv: 2.0 / n * (1.0 - c),
            yx: 6.0 * (s - nt),
            yu: -(2.0 / n * (1.0 - c)),
            yv: (4.0 * s - 3.0 * nt) / n,
            zz: c,
            zw: s / n,
        }
    }

    /// The position at this time of the relative state `q` (x, y, z, u, v, w).
    fn at(&self, q: &[f64; 6]) -> [f64; 3] {
        [
            self.xx * q[0] + self.xu * q[3] + self.xv * q[4],
            self.yx * q[0] + q[1] + self.yu * q[3] + self.yv * q[4],
            self.zz * q[2] + self.zw * q[5],
        ]
    }
}

/// `count` even times over [-span/2, span/2] (both ends included).
fn grid(n: f64, span: f64, count: usize) -> Vec<Cw> {
    let step = span / (count - 1) as f64;
    (0..count)
        .map(|i| {
            let t = if i + 1 == count {
                span / 2.0
            } else {
                -span / 2.0 + i as f64 * step
            };
            Cw::new(n, t)
        })
        .collect()
}

fn norm2(p: &[f64; 3]) -> f64 {
    p[0] * p[0] + p[1] * p[1] + p[2] * p[2]
}

/// The minimum of squared distances on an even grid, refined by the parabola through
/// the grid minimum and its neighbours (at the ends: the end value), at least 0.
fn refined_minimum(d2: &[f64]) -> f64 {
    let mut k = 0;
    for (i, &d) in d2.iter().enumerate() {
        if d < d2[k] {
            k = i;
        }
    }
    let b = d2[k];
    let mut low = b;
    if k > 0 && k + 1 < d2.len() {
        let (a, c) = (d2[k - 1], d2[k + 1]);
        let curve = a - 2.0 * b + c;
        if curve > 0.0 {
            low = (b - (c - a) * (c - a) / (8.0 * curve)).min(b);
        }
    }
    low.max(0.0)
}

/// Whether relative state `q` comes within `hbr` m on the grids (`d2`: scratch of the
/// fine grid's length).
fn hits(q: &[f64; 6], coarse: &[Cw], fine: &[Cw], hbr: f64, d2: &mut [f64]) -> bool {
    let mut last = coarse[0].at(q);
    let mut closest = norm2(&last).sqrt();
    let mut chord = 0.0f64;
    for cw in &coarse[1..] {
        let p = cw.at(q);
        let d = [p[0] - last[0], p[1] - last[1], p[2] - last[2]];
        chord = chord.max(norm2(&d).sqrt());
        closest = closest.min(norm2(&p).sqrt());
        last = p;
    }
    if closest - 0.55 * chord > hbr {
        return false;
    }
    for (out, cw) in d2.iter_mut().zip(fine) {
        *out = norm2(&cw.at(q));
    }
    refined_minimum(d2) <= hbr * hbr
}

/// How many of `states` (LVLH relative position m and velocity m/s at TCA, rows x y z
/// u v w, velocities relative to the rotating frame) come within `hard_body_radius` m
/// over [-span/2, span/2] s of CW motion about a circular orbit of mean motion `n`
/// rad/s, on `coarse_points` and `grid_points` even times (see the module docs).
/// Parallel over states; the count does not depend on the thread count.
pub fn interval_hits(
    states: &[[f64; 6]],
    n: f64,
    span: f64,
    hard_body_radius: f64,
    coarse_points: usize,
    grid_points: usize,
    progress: &Progress,
) -> Result<u64, CoreError> {
    for (name, value) in [
        ("mean_motion", n),
        ("span", span),
        ("hard_body_radius", hard_body_radius),
    ] {
        if !(value.is_finite() && value > 0.0) {
            return Err(CoreError::Invalid {
                name: name.into(),
                value,
                reason: "must be a positive finite number".into(),
            });
        }
    }
    for (name, count) in [
        ("coarse_points", coarse_points),
        ("grid_points", grid_points),
    ] {
        if count < 2 {
            return Err(CoreError::Invalid {
                name: name.into(),
                value: count as f64,
                reason: "needs at least 2 points".into(),
            });
        }
    }
    if let Some(row) = states.iter().position(|q| !q.iter().all(|x| x.is_finite())) {
        return Err(CoreError::Rejected {
            name: "states".into(),
            reason: format!("row {row} holds a non-finite value"),
        });
    }
    let coarse = grid(n, span, coarse_points);
    let fine = grid(n, span, grid_points);
    let counts = states
        .par_chunks(STATES_PER_TASK)
        .map(|chunk| {
            progress.check()?;
            let mut d2 = vec![0.0; grid_points];
            let c = chunk
                .iter()
                .filter(|q| hits(q, &coarse, &fine, hard_body_radius, &mut d2))
                .count() as u64;
            progress.add(chunk.len());
            Ok(c)
        })
        .collect::<Result<Vec<u64>, CoreError>>()?;
    Ok(counts.iter().sum())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A state on a straight line (n -> 0 is not allowed; a tiny n is straight to 1e-12
    /// over the span) passing at `miss` m from the origin at t = 0.
    fn passing(miss: f64, speed: f64) -> [f64; 6] {
        [miss, 0.0, 0.0, 0.0, speed, 0.0]
    }

    #[test]
    fn a_straight_pass_counts_against_its_miss_distance() {
        // Along-track motion at 10 m/s passing 9.9 m / 10.1 m radially off: the minimum
        // is exactly the miss distance (grid minimum refined by the parabola).
        let n = 1e-9;
        let p = Progress::default();
        let states = [
            passing(9.9, 10.0),
            passing(10.1, 10.0),
            passing(-9.99, 10.0),
        ];
        let hits = interval_hits(&states, n, 100.0, 10.0, 101, 801, &p).unwrap();
        assert_eq!(hits, 2);
    }

    #[test]
    fn the_cw_motion_is_the_closed_form_of_a_bounded_relative_orbit() {
        // A radial offset x0 with along-track velocity -2 n x0 is the CW relative orbit
        // without drift, the 2:1 ellipse x = x0 cos(nt), y = -2 x0 sin(nt): closest (x0)
        // at t = 0.
        let n = 0.0011;
        let x0 = 50.0;
        let q = [x0, 0.0, 0.0, 0.0, -2.0 * n * x0, 0.0];
        for t in [-1000.0, -10.0, 0.0, 333.0, 2000.0] {
            let p = Cw::new(n, t).at(&q);
            let (s, c) = (n * t).sin_cos();
            assert!((p[0] - x0 * c).abs() < 1e-9, "{t}: {p:?}");
            assert!(
                (p[1] + 2.0 * x0 * s).abs() < 1e-9 && p[2] == 0.0,
                "{t}: {p:?}"
            );
        }
        let states = [q];
        let pr = Progress::default();
        assert_eq!(
            interval_hits(&states, n, 4000.0, 50.5, 101, 801, &pr).unwrap(),
            1
        );
        assert_eq!(
            interval_hits(&states, n, 4000.0, 49.5, 101, 801, &pr).unwrap(),
            0
        );
    }

    #[test]
    fn bad_inputs_are_errors() {
        let p = Progress::default();
        let q = [passing(1.0, 1.0)];
        assert!(interval_hits(&q, 0.0, 1.0, 1.0, 101, 801, &p).is_err());
        assert!(interval_hits(&q, 1e-3, f64::NAN, 1.0, 101, 801, &p).is_err());
        assert!(interval_hits(&q, 1e-3, 1.0, -1.0, 101, 801, &p).is_err());
        assert!(interval_hits(&q, 1e-3, 1.0, 1.0, 1, 801, &p).is_err());
        let bad = [[0.0, f64::NAN, 0.0, 0.0, 0.0, 0.0]];
        let err = interval_hits(&bad, 1e-3, 1.0, 1.0, 101, 801, &p).unwrap_err();
        assert!(err.to_string().contains("row 0"));
    }
}
