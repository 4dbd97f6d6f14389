//! All-on-all screening's sieve: which pairs of objects, in which intervals of a common
//! time grid, can come within a distance of each other.
//!
//! Every object is sampled (position and velocity) on the same times t_0 < t_1 < ...
//! For each grid interval [t_k, t_k+1] three tests run, each a necessary condition for
//! a distance <= D somewhere in the interval, so no such approach is lost:
//!
//! 1. **Spatial grid.** Over the interval the object stays inside the ball centred on the
//!    chord's midpoint c = (r_k + r_k+1)/2 of radius R = |r_k+1 - r_k|/2 + A h^2/8 (the
//!    path leaves its chord by at most A h^2/8 when |r''| <= A). Two objects can meet
//!    within D only if |c_i - c_j| <= R_i + R_j + D. Centres are hashed into cubes of side
//!    2 max(R) + D, so only the 27 neighbouring cubes are searched (the uniform-grid
//!    broad phase of collision detection, e.g. Ericson, "Real-Time Collision Detection",
//!    7.1; used for catalog screening by Budianto-Ho et al. 2014).
//! 2. **Coarse bound.** (d_k + d_k+1)/2 - (V + A h) h/2 <= D, with V the larger relative
//!    speed at the ends (the bound of one-primary screening).
//! 3. **Interpolated bound.** The same bound on `hermite_samples` sub-intervals of the
//!    cubic Hermite interpolant of the relative motion, against D plus an interpolation
//!    margin 10 h^4/384 (f_i + f_j) + 100 m, f the objects' (v/r)^4 r.
//!
//! Intervals run in parallel; the result is sorted by (i, j, k) whatever the thread count.
//!
//! [`approaches`] then finds the minima of the distance in the candidate intervals on
//! the quintic Hermite interpolant of each object's samples (positions, velocities and
//! the gravity acceleration two-body + J2..Jn at both ends): its error over a 60 s
//! interval in LEO is h^6/46080 |r^(6)| ~ 1e-5 m, and the drag acceleration it leaves
//! out moves it by ~|a_drag| h^2/64 (millimetres; centimetres just before decay), so no
//! re-propagation is needed. The minima are the sign changes from - to + of
//! f = r_rel . v_rel on 32 sub-intervals, bisected to 1e-12 of the interval. At the
//! window's own ends the distance has a minimum where it grows from the start (f >= 0)
//! or still falls at the end (f < 0): those are minima too, marked as [`Edge`]s (the
//! closest approach may lie outside the window).

use crate::constants::{J2, MU, R_EARTH};
use crate::dynamics::{zonal_acceleration, MAX_ZONAL_DEGREE};
use crate::error::{finite, positive, CoreError};
use crate::progress::Progress;
use rayon::prelude::*;

/// Objects sampled on a common time grid.
pub struct Tracks<'a> {
    /// Grid times (nt,), s, increasing.
    pub times: &'a [f64],
    /// Positions, object-major: sample k of object i at `i * nt + k`, m.
    pub positions: &'a [[f64; 3]],
    /// Velocities, same layout, m/s.
    pub velocities: &'a [[f64; 3]],
    /// Samples each object has (a decayed object stops early; 0: none), <= nt.
    pub samples: &'a [usize],
    /// Each object's interpolation coefficient f = max (v/r)^4 r, 1/s^4 x m.
    pub fourth: &'a [f64],
}

/// What the sieve looks for.
#[derive(Debug, Clone, Copy)]
pub struct SieveSettings {
    /// Screening distance D, m.
    pub distance: f64,
    /// Bound on either object's acceleration A, m/s^2.
    pub max_acceleration: f64,
    /// Sub-intervals of the interpolated bound.
    pub hermite_samples: usize,
}

/// Pair-intervals that passed each test.
#[derive(Debug, Default, Clone, Copy, PartialEq, Eq)]
pub struct SieveCounts {
    /// Passed the spatial grid's ball test.
    pub spatial: u64,
    /// Passed the coarse bound too.
    pub coarse: u64,
    /// Passed the interpolated bound too (the candidates).
    pub interpolated: u64,
}

/// Candidate intervals: object pairs i < j and interval k, sorted by (i, j, k).
#[derive(Debug, Default, Clone, PartialEq, Eq)]
pub struct Candidates {
    pub i: Vec<u32>,
    pub j: Vec<u32>,
    pub k: Vec<u32>,
    pub counts: SieveCounts,
}

fn sub(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

fn norm(a: [f64; 3]) -> f64 {
    (a[0] * a[0] + a[1] * a[1] + a[2] * a[2]).sqrt()
}

/// Cubic Hermite value and derivative at fraction s of an interval of length h.
fn hermite(r0: [f64; 3], v0: [f64; 3], r1: [f64; 3], v1: [f64; 3], h: f64, s: f64) -> [f64; 6] {
    let (s2, s3) = (s * s, s * s * s);
    let (a, b, c, d) = (
        2.0 * s3 - 3.0 * s2 + 1.0,
        (s3 - 2.0 * s2 + s) * h,
        -2.0 * s3 + 3.0 * s2,
        (s3 - s2) * h,
    );
    let (da, db, dc, dd) = (
        (6.0 * s2 - 6.0 * s) / h,
        3.0 * s2 - 4.0 * s + 1.0,
        (-6.0 * s2 + 6.0 * s) / h,
        3.0 * s2 - 2.0 * s,
    );
    std::array::from_fn(|m| {
        let q = m % 3;
        if m < 3 {
            a * r0[q] + b * v0[q] + c * r1[q] + d * v1[q]
        } else {
            da * r0[q] + db * v0[q] + dc * r1[q] + dd * v1[q]
        }
    })
}

/// The tracks' layout: positions and velocities of every object at every grid time, no
/// object with more samples than the grid has.
fn check_layout(tracks: &Tracks<'_>) -> Result<(), CoreError> {
    let nt = tracks.times.len();
    let n = tracks.samples.len();
    if tracks.positions.len() != n * nt || tracks.velocities.len() != n * nt {
        return Err(CoreError::shape(
            "positions",
            "positions and velocities must hold objects x times samples",
        ));
    }
    for &s in tracks.samples {
        if s > nt {
            return Err(CoreError::invalid("samples", s as f64, "exceeds the grid"));
        }
    }
    Ok(())
}

fn check(tracks: &Tracks<'_>, settings: &SieveSettings) -> Result<usize, CoreError> {
    let nt = tracks.times.len();
    let n = tracks.samples.len();
    check_layout(tracks)?;
    if tracks.fourth.len() != n {
        return Err(CoreError::shape("fourth", "must hold one value per object"));
    }
    if n > u32::MAX as usize || nt > u32::MAX as usize {
        return Err(CoreError::rejected(
            "objects",
            "too many to index with 32 bits",
        ));
    }
    for w in tracks.times.windows(2) {
        if w[1].partial_cmp(&w[0]) != Some(std::cmp::Ordering::Greater) {
            return Err(CoreError::invalid("times", w[1], "must increase"));
        }
    }
    for (i, &f) in tracks.fourth.iter().enumerate() {
        if !(f.is_finite() && f >= 0.0) {
            return Err(CoreError::invalid(
                "fourth",
                f,
                format!("of object {i} must be >= 0"),
            ));
        }
    }
    for (p, v) in tracks.positions.iter().zip(tracks.velocities) {
        for x in p.iter().chain(v) {
            finite("track sample", *x)?;
        }
    }
    positive("distance", settings.distance)?;
    positive("max_acceleration", settings.max_acceleration)?;
    if settings.hermite_samples == 0 {
        return Err(CoreError::invalid("hermite_samples", 0.0, "must be >= 1"));
    }
    Ok(nt)
}

/// The candidate intervals of every pair (see the module docs). Progress counts grid
/// intervals done; cancellation stops between intervals.
pub fn candidates(
    tracks: &Tracks<'_>,
    settings: &SieveSettings,
    progress: &Progress,
) -> Result<Candidates, CoreError> {
    let nt = check(tracks, settings)?;
    if nt < 2 {
        return Ok(Candidates::default());
    }
    let per_interval: Vec<(Vec<(u32, u32)>, SieveCounts)> = (0..nt - 1)
        .into_par_iter()
        .map(|k| {
            progress.check()?;
            let out = interval(tracks, settings, k);
            progress.add(1);
            Ok(out)
        })
        .collect::<Result<_, CoreError>>()?;
    let mut triples: Vec<(u32, u32, u32)> = Vec::new();
    let mut counts = SieveCounts::default();
    for (k, (pairs, c)) in per_interval.into_iter().enumerate() {
        counts.spatial += c.spatial;
        counts.coarse += c.coarse;
        counts.interpolated += c.interpolated;
        triples.extend(pairs.into_iter().map(|(i, j)| (i, j, k as u32)));
    }
    triples.sort_unstable();
    Ok(Candidates {
        i: triples.iter().map(|t| t.0).collect(),
        j: triples.iter().map(|t| t.1).collect(),
        k: triples.iter().map(|t| t.2).collect(),
        counts,
    })
}

/// One interval's candidate pairs (i < j) and counts.
fn interval(tracks: &Tracks<'_>, s: &SieveSettings, k: usize) -> (Vec<(u32, u32)>, SieveCounts) {
    let nt = tracks.times.len();
    let h = tracks.times[k + 1] - tracks.times[k];
    let sag = s.max_acceleration * h * h / 8.0;
    let active: Vec<usize> = (0..tracks.samples.len())
        .filter(|&i| tracks.samples[i] > k + 1)
        .collect();
    let centre = |i: usize| {
        let (a, b) = (
            tracks.positions[i * nt + k],
            tracks.positions[i * nt + k + 1],
        );
        [
            0.5 * (a[0] + b[0]),
            0.5 * (a[1] + b[1]),
            0.5 * (a[2] + b[2]),
        ]
    };
    let radius = |i: usize| {
        0.5 * norm(sub(
            tracks.positions[i * nt + k + 1],
            tracks.positions[i * nt + k],
        )) + sag
    };
    let centres: Vec<[f64; 3]> = active.iter().map(|&i| centre(i)).collect();
    let radii: Vec<f64> = active.iter().map(|&i| radius(i)).collect();
    let biggest = radii.iter().cloned().fold(0.0, f64::max);
    let cell = 2.0 * biggest + s.distance;
    let key = |c: [f64; 3]| -> [i64; 3] { std::array::from_fn(|q| (c[q] / cell).floor() as i64) };
    // Active objects sorted by cell (then index): each cell is a contiguous run.
    let mut order: Vec<([i64; 3], usize)> = centres
        .iter()
        .enumerate()
        .map(|(a, &c)| (key(c), a))
        .collect();
    order.sort_unstable();
    let mut pairs = Vec::new();
    let mut counts = SieveCounts::default();
    for &(own, a) in &order {
        for dx in -1..=1 {
            for dy in -1..=1 {
                for dz in -1..=1 {
                    let cell_key = [own[0] + dx, own[1] + dy, own[2] + dz];
                    let lo = order.partition_point(|e| e.0 < cell_key);
                    for &(kb, b) in &order[lo..] {
                        if kb != cell_key {
                            break;
                        }
                        let (i, j) = (active[a], active[b]);
                        if j <= i {
                            continue;
                        }
                        let gap = norm(sub(centres[a], centres[b]));
                        if gap > radii[a] + radii[b] + s.distance {
                            continue;
                        }
                        counts.spatial += 1;
                        if !coarse_pass(tracks, s, i, j, k) {
                            continue;
                        }
                        counts.coarse += 1;
                        if !interpolated_pass(tracks, s, i, j, k) {
                            continue;
                        }
                        counts.interpolated += 1;
                        pairs.push((i as u32, j as u32));
                    }
                }
            }
        }
    }
    pairs.sort_unstable();
    (pairs, counts)
}

/// Relative position and velocity of j from i at sample m.
fn relative(tracks: &Tracks<'_>, i: usize, j: usize, m: usize) -> ([f64; 3], [f64; 3]) {
    let nt = tracks.times.len();
    (
        sub(tracks.positions[j * nt + m], tracks.positions[i * nt + m]),
        sub(tracks.velocities[j * nt + m], tracks.velocities[i * nt + m]),
    )
}

fn coarse_pass(tracks: &Tracks<'_>, s: &SieveSettings, i: usize, j: usize, k: usize) -> bool {
    let h = tracks.times[k + 1] - tracks.times[k];
    let (r0, v0) = relative(tracks, i, j, k);
    let (r1, v1) = relative(tracks, i, j, k + 1);
    let speed = norm(v0).max(norm(v1)) + s.max_acceleration * h;
    0.5 * (norm(r0) + norm(r1)) - 0.5 * speed * h <= s.distance
}

fn interpolated_pass(tracks: &Tracks<'_>, s: &SieveSettings, i: usize, j: usize, k: usize) -> bool {
    let h = tracks.times[k + 1] - tracks.times[k];
    let (r0, v0) = relative(tracks, i, j, k);
    let (r1, v1) = relative(tracks, i, j, k + 1);
    let margin = 10.0 * h.powi(4) / 384.0 * (tracks.fourth[i] + tracks.fourth[j]) + 100.0;
    let n = s.hermite_samples;
    let dh = h / n as f64;
    let at = |m: usize| {
        let x = hermite(r0, v0, r1, v1, h, m as f64 / n as f64);
        (norm([x[0], x[1], x[2]]), norm([x[3], x[4], x[5]]))
    };
    let mut prev = at(0);
    for m in 1..=n {
        let next = at(m);
        let speed = prev.1.max(next.1) + s.max_acceleration * dh;
        if 0.5 * (prev.0 + next.0) - 0.5 * speed * dh <= s.distance + margin {
            return true;
        }
        prev = next;
    }
    false
}

/// A minimum of the distance of objects i < j at time `t` (s, on the grid's scale),
/// with both states [x, y, z, vx, vy, vz] (m, m/s) there.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Approach {
    pub i: u32,
    pub j: u32,
    pub t: f64,
    pub state_i: [f64; 6],
    pub state_j: [f64; 6],
    pub edge: Edge,
}

/// Where a minimum lies: inside the window (r . v changes sign from - to +), or at one of
/// its ends, where the distance grows from the start or still falls at the end.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Edge {
    Interior = 0,
    Start = 1,
    End = 2,
}

/// Which ends of the tracks' grid are the screening window's own (a chunk of a longer
/// window has neither or one), where a minimum at the end is reported as an [`Edge`].
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct WindowEnds {
    pub start: bool,
    pub end: bool,
}

/// Gravity acceleration (m/s^2) at inertial position `p` (m): two-body, J2 and the zonal
/// harmonics 3..=`degree`, as the dynamics has them.
pub fn gravity(p: [f64; 3], degree: u8) -> [f64; 3] {
    let r2 = p[0] * p[0] + p[1] * p[1] + p[2] * p[2];
    let inv_r2 = 1.0 / r2;
    let inv_r3 = inv_r2 / r2.sqrt();
    let zz = 5.0 * p[2] * p[2] * inv_r2;
    let j2f = -1.5 * J2 * MU * R_EARTH * R_EARTH * inv_r3 * inv_r2;
    let high = if degree > 2 {
        zonal_acceleration(p[0], p[1], p[2], degree)
    } else {
        [0.0; 3]
    };
    [
        -MU * p[0] * inv_r3 + j2f * p[0] * (1.0 - zz) + high[0],
        -MU * p[1] * inv_r3 + j2f * p[1] * (1.0 - zz) + high[1],
        -MU * p[2] * inv_r3 + j2f * p[2] * (3.0 - zz) + high[2],
    ]
}

/// One object's end values on an interval of length h: position, velocity, acceleration.
type Ends = ([f64; 3], [f64; 3], [f64; 3]);

/// Quintic Hermite state [position, velocity] at fraction s of an interval of length h.
fn quintic(a: &Ends, b: &Ends, h: f64, s: f64) -> [f64; 6] {
    let (s2, s3, s4, s5) = (s * s, s * s * s, s * s * s * s, s * s * s * s * s);
    let w = [
        1.0 - 10.0 * s3 + 15.0 * s4 - 6.0 * s5,
        (s - 6.0 * s3 + 8.0 * s4 - 3.0 * s5) * h,
        (0.5 * s2 - 1.5 * s3 + 1.5 * s4 - 0.5 * s5) * h * h,
        (0.5 * s3 - s4 + 0.5 * s5) * h * h,
        (-4.0 * s3 + 7.0 * s4 - 3.0 * s5) * h,
        10.0 * s3 - 15.0 * s4 + 6.0 * s5,
    ];
    let d = [
        (-30.0 * s2 + 60.0 * s3 - 30.0 * s4) / h,
        1.0 - 18.0 * s2 + 32.0 * s3 - 15.0 * s4,
        (s - 4.5 * s2 + 6.0 * s3 - 2.5 * s4) * h,
        (1.5 * s2 - 4.0 * s3 + 2.5 * s4) * h,
        -12.0 * s2 + 28.0 * s3 - 15.0 * s4,
        (30.0 * s2 - 60.0 * s3 + 30.0 * s4) / h,
    ];
    std::array::from_fn(|m| {
        let q = m % 3;
        let c = if m < 3 { &w } else { &d };
        c[0] * a.0[q]
            + c[1] * a.1[q]
            + c[2] * a.2[q]
            + c[3] * b.2[q]
            + c[4] * b.1[q]
            + c[5] * b.0[q]
    })
}

/// Sub-intervals searched for sign changes of r . v in each candidate interval.
const ROOT_SAMPLES: usize = 32;

/// The minima of the distance within `distance` in the candidate intervals (i[m], j[m],
/// k[m]) (see the module docs), in the candidates' order; `degree` is the zonal degree
/// of the gravity acceleration. Progress counts candidates done.
pub fn approaches(
    tracks: &Tracks<'_>,
    cand: (&[u32], &[u32], &[u32]),
    degree: u8,
    distance: f64,
    ends: WindowEnds,
    progress: &Progress,
) -> Result<Vec<Approach>, CoreError> {
    let (ci, cj, ck) = cand;
    if ci.len() != cj.len() || ci.len() != ck.len() {
        return Err(CoreError::shape(
            "candidates",
            "i, j and k must have one length",
        ));
    }
    if !(2..=MAX_ZONAL_DEGREE).contains(&degree) {
        return Err(CoreError::invalid(
            "zonal_degree",
            degree as f64,
            "must be 2 to 6",
        ));
    }
    positive("distance", distance)?;
    minima(
        tracks,
        cand,
        &|p| gravity(p, degree),
        distance,
        ends,
        progress,
    )
}

/// [`approaches`] with the acceleration at the samples given by `accel`.
fn minima(
    tracks: &Tracks<'_>,
    cand: (&[u32], &[u32], &[u32]),
    accel: &(dyn Fn([f64; 3]) -> [f64; 3] + Sync),
    distance: f64,
    window: WindowEnds,
    progress: &Progress,
) -> Result<Vec<Approach>, CoreError> {
    let nt = tracks.times.len();
    let (ci, cj, ck) = cand;
    let n = tracks.samples.len();
    for m in 0..ci.len() {
        let (i, j, k) = (ci[m] as usize, cj[m] as usize, ck[m] as usize);
        if i >= n || j >= n || k + 1 >= tracks.samples[i].min(tracks.samples[j]) {
            return Err(CoreError::invalid(
                "candidate",
                m as f64,
                format!("({i}, {j}, {k}) is not an interval both objects have"),
            ));
        }
    }
    let found: Vec<Vec<Approach>> = (0..ci.len())
        .into_par_iter()
        .map(|m| {
            if m % 256 == 0 {
                progress.check()?;
            }
            let (i, j, k) = (ci[m] as usize, cj[m] as usize, ck[m] as usize);
            let ends = |o: usize, q: usize| -> Ends {
                let p = tracks.positions[o * nt + q];
                (p, tracks.velocities[o * nt + q], accel(p))
            };
            let (a0, a1, b0, b1) = (ends(i, k), ends(i, k + 1), ends(j, k), ends(j, k + 1));
            let t0 = tracks.times[k];
            let h = tracks.times[k + 1] - t0;
            let state = |s: f64| (quintic(&a0, &a1, h, s), quintic(&b0, &b1, h, s));
            let f = |s: f64| {
                let (x, y) = state(s);
                (0..3)
                    .map(|q| (y[q] - x[q]) * (y[q + 3] - x[q + 3]))
                    .sum::<f64>()
            };
            let mut out = Vec::new();
            let at = |s: f64, edge: Edge| {
                let (x, y) = state(s);
                let miss = norm(sub([y[0], y[1], y[2]], [x[0], x[1], x[2]]));
                (miss <= distance).then_some(Approach {
                    i: i as u32,
                    j: j as u32,
                    t: t0 + s * h,
                    state_i: x,
                    state_j: y,
                    edge,
                })
            };
            let mut prev = f(0.0);
            if window.start && k == 0 && prev >= 0.0 {
                out.extend(at(0.0, Edge::Start));
            }
            for m in 1..=ROOT_SAMPLES {
                let (lo0, hi0) = ((m - 1) as f64, m as f64);
                let next = f(hi0 / ROOT_SAMPLES as f64);
                if prev < 0.0 && next >= 0.0 {
                    let (mut lo, mut hi) = (lo0 / ROOT_SAMPLES as f64, hi0 / ROOT_SAMPLES as f64);
                    while hi - lo > 1e-12 {
                        let mid = 0.5 * (lo + hi);
                        if f(mid) < 0.0 {
                            lo = mid;
                        } else {
                            hi = mid;
                        }
                    }
                    out.extend(at(0.5 * (lo + hi), Edge::Interior));
                }
                prev = next;
            }
            if window.end && k + 2 == nt && prev < 0.0 {
                out.extend(at(1.0, Edge::End));
            }
            progress.add(1);
            Ok(out)
        })
        .collect::<Result<_, CoreError>>()?;
    Ok(found.into_iter().flatten().collect())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::constants::MU;

    /// A circular two-body orbit of radius `a` (inclination, node, argument of latitude
    /// at t = 0, rad), rotated by `rot`.
    #[derive(Clone, Copy)]
    struct Orbit {
        a: f64,
        inc: f64,
        raan: f64,
        u0: f64,
        rot: [[f64; 3]; 3],
    }

    const IDENTITY: [[f64; 3]; 3] = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];

    fn apply(m: &[[f64; 3]; 3], x: [f64; 3]) -> [f64; 3] {
        std::array::from_fn(|r| m[r][0] * x[0] + m[r][1] * x[1] + m[r][2] * x[2])
    }

    /// Rotation by `angle` about the unit vector along `axis` (Rodrigues).
    fn rotation(axis: [f64; 3], angle: f64) -> [[f64; 3]; 3] {
        let n = norm(axis);
        let k = [axis[0] / n, axis[1] / n, axis[2] / n];
        let (c, s) = (angle.cos(), angle.sin());
        std::array::from_fn(|r| {
            std::array::from_fn(|q| {
                let cross = [[0.0, -k[2], k[1]], [k[2], 0.0, -k[0]], [-k[1], k[0], 0.0]][r][q];
                c * IDENTITY[r][q] + s * cross + (1.0 - c) * k[r] * k[q]
            })
        })
    }

    impl Orbit {
        fn circle(a: f64, inc: f64, raan: f64, u0: f64) -> Self {
            Orbit {
                a,
                inc,
                raan,
                u0,
                rot: IDENTITY,
            }
        }

        fn at(&self, t: f64) -> ([f64; 3], [f64; 3]) {
            let n = (MU / self.a.powi(3)).sqrt();
            let speed = n * self.a;
            let u = self.u0 + n * t;
            let (cu, su) = (u.cos(), u.sin());
            let (ci, si) = (self.inc.cos(), self.inc.sin());
            let (co, so) = (self.raan.cos(), self.raan.sin());
            let p = [
                self.a * (co * cu - so * su * ci),
                self.a * (so * cu + co * su * ci),
                self.a * su * si,
            ];
            let v = [
                speed * (-co * su - so * cu * ci),
                speed * (-so * su + co * cu * ci),
                speed * cu * si,
            ];
            (apply(&self.rot, p), apply(&self.rot, v))
        }

        /// The same orbit turned by `angle` about its position at `t`, raised by `miss`
        /// m and phased to pass there at `t`: a Kepler circle meeting this one `miss` m
        /// apart (radially) at `t`.
        fn partner(&self, t: f64, angle: f64, miss: f64) -> Self {
            let (p, _) = self.at(t);
            let r = rotation(p, angle);
            let rot = std::array::from_fn(|i| {
                std::array::from_fn(|j| (0..3).map(|m| r[i][m] * self.rot[m][j]).sum())
            });
            let a = self.a + miss;
            let (n0, n1) = ((MU / self.a.powi(3)).sqrt(), (MU / a.powi(3)).sqrt());
            Orbit {
                a,
                rot,
                u0: self.u0 + (n0 - n1) * t,
                ..*self
            }
        }
    }

    fn sample(orbits: &[Orbit], times: &[f64]) -> Vec<Vec<([f64; 3], [f64; 3])>> {
        orbits
            .iter()
            .map(|o| times.iter().map(|&t| o.at(t)).collect())
            .collect()
    }

    struct Owned {
        times: Vec<f64>,
        pos: Vec<[f64; 3]>,
        vel: Vec<[f64; 3]>,
        samples: Vec<usize>,
        fourth: Vec<f64>,
    }

    impl Owned {
        fn new(times: Vec<f64>, objects: &[Vec<([f64; 3], [f64; 3])>]) -> Self {
            let mut pos = Vec::new();
            let mut vel = Vec::new();
            let mut fourth = Vec::new();
            for o in objects {
                let mut f: f64 = 0.0;
                for (p, v) in o {
                    pos.push(*p);
                    vel.push(*v);
                    f = f.max((norm(*v) / norm(*p)).powi(4) * norm(*p));
                }
                fourth.push(f);
            }
            let samples = vec![times.len(); objects.len()];
            Owned {
                times,
                pos,
                vel,
                samples,
                fourth,
            }
        }
        fn tracks(&self) -> Tracks<'_> {
            Tracks {
                times: &self.times,
                positions: &self.pos,
                velocities: &self.vel,
                samples: &self.samples,
                fourth: &self.fourth,
            }
        }
    }

    fn settings(distance: f64) -> SieveSettings {
        SieveSettings {
            distance,
            max_acceleration: 1.01 * MU / 6_356_752.0f64.powi(2),
            hermite_samples: 64,
        }
    }

    /// Brute force: the least distance of each pair on each grid interval, from 1-s
    /// samples of the exact orbits.
    fn brute_minima(orbits: &[Orbit], t_end: f64, step: f64) -> Vec<(usize, usize, usize, f64)> {
        let fine: Vec<f64> = (0..=(t_end as usize)).map(|s| s as f64).collect();
        let tracks = sample(orbits, &fine);
        let per = step as usize;
        let mut out = Vec::new();
        for i in 0..orbits.len() {
            for j in i + 1..orbits.len() {
                for k in 0..(t_end / step) as usize {
                    let d = (k * per..=(k + 1) * per)
                        .map(|m| norm(sub(tracks[j][m].0, tracks[i][m].0)))
                        .fold(f64::INFINITY, f64::min);
                    out.push((i, j, k, d));
                }
            }
        }
        out
    }

    /// Twelve LEO and two higher orbits, each LEO one with partners that meet it at
    /// chosen times and miss distances (0 to 40 km), at crossing angles 3 to 170 degrees.
    fn encounters(t_end: f64) -> Vec<Orbit> {
        let mut orbits = Vec::new();
        for m in 0..12 {
            let x = m as f64;
            let base = Orbit::circle(6.75e6 + 40e3 * x, 0.3 + 0.11 * x, 0.7 * x, 0.37 * x);
            orbits.push(base);
            for (q, (angle, miss)) in [(0.05, 0.0), (1.2, 4e3), (2.9, 15e3), (0.6, 40e3)]
                .iter()
                .enumerate()
            {
                let t = (0.13 + 0.21 * q as f64 + 0.017 * x) * t_end;
                orbits.push(base.partner(t, *angle, *miss));
            }
        }
        orbits.push(Orbit::circle(26.5e6, 0.96, 1.0, 0.0));
        orbits.push(Orbit::circle(42.164e6, 0.001, 0.0, 2.0));
        orbits
    }

    #[test]
    fn every_interval_within_the_distance_is_a_candidate_and_far_ones_are_not() {
        let (step, t_end) = (60.0, 6000.0);
        let orbits = encounters(t_end);
        let times: Vec<f64> = (0..=(t_end / step) as usize)
            .map(|k| k as f64 * step)
            .collect();
        let owned = Owned::new(times.clone(), &sample(&orbits, &times));
        let distance = 20e3;
        let got = candidates(&owned.tracks(), &settings(distance), &Progress::default()).unwrap();
        let set: std::collections::HashSet<(u32, u32, u32)> = (0..got.i.len())
            .map(|m| (got.i[m], got.j[m], got.k[m]))
            .collect();
        let brute = brute_minima(&orbits, t_end, step);
        let near: Vec<_> = brute.iter().filter(|x| x.3 <= distance).collect();
        assert!(
            near.len() >= 36,
            "the geometry holds 36 approaches: {}",
            near.len()
        );
        for &&(i, j, k, d) in &near {
            assert!(
                set.contains(&(i as u32, j as u32, k as u32)),
                "lost ({i}, {j}, {k}) at {d} m"
            );
        }
        // The sieve is sharp: nothing farther than 60 km all through an interval is kept,
        // except slow pairs (a 3-degree crossing) whose bounds are wide.
        for &(i, j, k, d) in &brute {
            if set.contains(&(i as u32, j as u32, k as u32)) {
                assert!(d < 100e3, "({i}, {j}, {k}) kept at {d} m");
            }
        }
        assert!(got.counts.spatial > got.counts.coarse);
        assert!(got.counts.coarse >= got.counts.interpolated);
        assert_eq!(got.counts.interpolated as usize, got.i.len());
    }

    fn owned_times(t_end: f64, step: f64) -> Vec<f64> {
        (0..=(t_end / step) as usize)
            .map(|k| k as f64 * step)
            .collect()
    }

    #[test]
    fn the_result_does_not_depend_on_the_thread_count() {
        let orbits = encounters(12000.0);
        let times = owned_times(12000.0, 60.0);
        let owned = Owned::new(times.clone(), &sample(&orbits, &times));
        let run = |threads| {
            rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap()
                .install(|| candidates(&owned.tracks(), &settings(10e3), &Progress::default()))
                .unwrap()
        };
        let one = run(1);
        assert!(one.i.len() > 20);
        assert_eq!(one, run(3));
    }

    #[test]
    fn a_decayed_object_is_screened_up_to_its_last_sample() {
        let orbits = encounters(6000.0);
        let times = owned_times(6000.0, 60.0);
        let mut owned = Owned::new(times.clone(), &sample(&orbits, &times));
        let all = candidates(&owned.tracks(), &settings(20e3), &Progress::default()).unwrap();
        owned.samples[0] = 30;
        let cut = candidates(&owned.tracks(), &settings(20e3), &Progress::default()).unwrap();
        for m in 0..all.i.len() {
            let kept = (0..cut.i.len())
                .any(|q| (cut.i[q], cut.j[q], cut.k[q]) == (all.i[m], all.j[m], all.k[m]));
            assert_eq!(
                kept,
                all.i[m] != 0 || all.k[m] < 29,
                "({}, {})",
                all.i[m],
                all.k[m]
            );
        }
    }

    #[test]
    fn the_quintic_interpolant_follows_a_two_body_orbit_to_a_millimetre() {
        // Two-body only: the exact orbit's acceleration is -mu r/r^3 (J2 adds 0.1 %; the
        // test takes the gravity without it by comparing against a Kepler circle).
        let o = Orbit::circle(6.8e6, 0.9, 0.3, 0.2);
        let (h, t0) = (60.0, 1234.0);
        let kepler = |t: f64| -> Ends {
            let (p, v) = o.at(t);
            let r3 = norm(p).powi(3);
            (p, v, p.map(|x| -MU * x / r3))
        };
        let (a, b) = (kepler(t0), kepler(t0 + h));
        for m in 0..=20 {
            let s = m as f64 / 20.0;
            let got = quintic(&a, &b, h, s);
            let (p, v) = o.at(t0 + s * h);
            assert!(
                norm(sub([got[0], got[1], got[2]], p)) < 1e-3,
                "position at s = {s}"
            );
            assert!(
                norm(sub([got[3], got[4], got[5]], v)) < 1e-6,
                "velocity at s = {s}"
            );
        }
    }

    #[test]
    fn gravity_is_the_gradient_of_the_potential() {
        // Central differences of U = -mu/r (1 - sum J_n (Re/r)^n P_n(z/r)) for n = 2..4.
        let u = |p: [f64; 3]| {
            let r = norm(p);
            let s = p[2] / r;
            let p2 = 0.5 * (3.0 * s * s - 1.0);
            let p3 = 0.5 * (5.0 * s * s * s - 3.0 * s);
            let p4 = (35.0 * s.powi(4) - 30.0 * s * s + 3.0) / 8.0;
            let q = R_EARTH / r;
            let (j3, j4) = (crate::constants::J3, crate::constants::J4);
            MU / r * (1.0 - J2 * q * q * p2 - j3 * q.powi(3) * p3 - j4 * q.powi(4) * p4)
        };
        let p = [3.1e6, -4.2e6, 4.4e6];
        let g = gravity(p, 4);
        for c in 0..3 {
            let mut hi = p;
            let mut lo = p;
            hi[c] += 1.0;
            lo[c] -= 1.0;
            let fd = (u(hi) - u(lo)) / 2.0;
            assert!(
                (g[c] - fd).abs() < 1e-8 * norm(g),
                "component {c}: {} vs {fd}",
                g[c]
            );
        }
    }

    /// Two-body acceleration at `p`, the exact orbits' own (m/s^2).
    fn kepler(p: [f64; 3]) -> [f64; 3] {
        let r3 = norm(p).powi(3);
        p.map(|x| -MU * x / r3)
    }

    #[test]
    fn approaches_are_the_minima_of_the_exact_orbits() {
        // Pairs built to meet (Orbit::partner) at known times and miss distances, sampled
        // from Kepler circles, with the two-body acceleration: the minima agree with a
        // golden-section search on the exact orbits to 1 mm and 1e-5 s (the search itself
        // resolves a minimum of the distance to ~1e-6 s only).
        let (step, t_end) = (60.0, 6000.0);
        let orbits = encounters(t_end);
        let times = owned_times(t_end, step);
        let owned = Owned::new(times.clone(), &sample(&orbits, &times));
        let tracks = owned.tracks();
        let p = Progress::default();
        let c = candidates(&tracks, &settings(20e3), &p).unwrap();
        let found = minima(
            &tracks,
            (&c.i, &c.j, &c.k),
            &kepler,
            20e3,
            WindowEnds::default(),
            &p,
        )
        .unwrap();
        assert!(found.len() >= 36, "{}", found.len());
        for a in &found {
            let (oi, oj) = (orbits[a.i as usize], orbits[a.j as usize]);
            let d = |t: f64| norm(sub(oj.at(t).0, oi.at(t).0));
            let (mut lo, mut hi) = (a.t - 1.0, a.t + 1.0);
            let g = 0.5 * (5f64.sqrt() - 1.0);
            while hi - lo > 1e-9 {
                let (x1, x2) = (hi - g * (hi - lo), lo + g * (hi - lo));
                if d(x1) < d(x2) {
                    hi = x2;
                } else {
                    lo = x1;
                }
            }
            let tb = 0.5 * (lo + hi);
            let best = d(tb);
            let miss = norm(sub(
                [a.state_j[0], a.state_j[1], a.state_j[2]],
                [a.state_i[0], a.state_i[1], a.state_i[2]],
            ));
            assert!((miss - best).abs() < 1e-3, "miss {miss} vs {best}");
            assert!((a.t - tb).abs() < 1e-5, "tca {} vs {tb}", a.t);
        }
    }

    #[test]
    fn minima_at_the_window_ends_are_reported_as_edges() {
        // Two pairs that stay within the distance all window: 50 m apart radially and 100 m
        // along-track at the start, drifting apart (the closest approach is the start), and a
        // pair closing along-track to the end. Inside the window r . v never changes sign,
        // so neither had an event; as the window's ends they are Edge::Start / Edge::End.
        let (step, t_end) = (60.0, 6000.0);
        let a = 7e6;
        let gap = 1000.0 / (a + 50.0);
        let orbits = [
            Orbit::circle(a, 0.9, 0.3, 0.1),
            Orbit::circle(a + 50.0, 0.9, 0.3, 0.1 - 100.0 / (a + 50.0)),
            Orbit::circle(a, 1.2, 2.0, 0.5),
            Orbit::circle(a + 50.0, 1.2, 2.0, 0.5 + gap),
        ];
        let times = owned_times(t_end, step);
        let owned = Owned::new(times.clone(), &sample(&orbits, &times));
        let tracks = owned.tracks();
        let p = Progress::default();
        let c = candidates(&tracks, &settings(20e3), &p).unwrap();
        let cand = (c.i.as_slice(), c.j.as_slice(), c.k.as_slice());
        let run = |ends| minima(&tracks, cand, &kepler, 20e3, ends, &p).unwrap();
        let inner = run(WindowEnds::default());
        assert!(inner.is_empty(), "{inner:?}");
        let found = run(WindowEnds {
            start: true,
            end: true,
        });
        assert_eq!(found.len(), 2, "{found:?}");
        let d = |o: usize, q: usize, t: f64| norm(sub(orbits[q].at(t).0, orbits[o].at(t).0));
        let miss = |x: &Approach| {
            norm(sub(
                [x.state_j[0], x.state_j[1], x.state_j[2]],
                [x.state_i[0], x.state_i[1], x.state_i[2]],
            ))
        };
        let (first, last) = (&found[0], &found[1]);
        assert_eq!(
            (first.i, first.j, first.edge, first.t),
            (0, 1, Edge::Start, 0.0)
        );
        assert!((miss(first) - d(0, 1, 0.0)).abs() < 1e-6, "{}", miss(first));
        assert!(d(0, 1, 0.0) < 112.0 && d(0, 1, step) > d(0, 1, 0.0));
        assert_eq!(
            (last.i, last.j, last.edge, last.t),
            (2, 3, Edge::End, t_end)
        );
        assert!((miss(last) - d(2, 3, t_end)).abs() < 1e-3, "{}", miss(last));
        assert!(d(2, 3, t_end) < d(2, 3, t_end - step));
    }

    #[test]
    fn bad_input_is_an_error_not_a_panic() {
        let owned = Owned::new(
            vec![0.0, 60.0],
            &sample(&[Orbit::circle(7e6, 1.0, 0.0, 0.0)], &[0.0, 60.0]),
        );
        let mut t = owned.tracks();
        let p = Progress::default();
        assert!(candidates(&t, &settings(-1.0), &p).is_err());
        let backwards = [60.0, 0.0];
        t.times = &backwards;
        assert!(candidates(&t, &settings(1.0), &p).is_err());
        let mut nan = owned.pos.clone();
        nan[0][0] = f64::NAN;
        let t = Tracks {
            positions: &nan,
            ..owned.tracks()
        };
        assert!(candidates(&t, &settings(1.0), &p).is_err());
        let too_many = [5usize];
        let t = Tracks {
            samples: &too_many,
            ..owned.tracks()
        };
        assert!(candidates(&t, &settings(1.0), &p).is_err());
    }
}

/// Points per grid interval at which [`stretches`] checks the distance.
pub const WITHIN_POINTS: usize = 8;
/// Bisection steps of a stretch's end (1e-12 of a 60-s interval: below 1 ms).
const WITHIN_BISECTIONS: usize = 40;

/// For each minimum (i[m], j[m] at time t[m], s on the grid's scale), the (first, last)
/// times between which the two objects stay within `distance` m around it: the cubic
/// Hermite interpolant of their relative state between the samples, checked at
/// [`WITHIN_POINTS`] points per interval walking away from t, each end's crossing by
/// bisection; held within the samples both objects have (a stretch reaching the grid's
/// ends stops there). Parallel over minima; progress counts minima done.
pub fn stretches(
    tracks: &Tracks<'_>,
    i: &[u32],
    j: &[u32],
    t: &[f64],
    distance: f64,
    progress: &Progress,
) -> Result<Vec<(f64, f64)>, CoreError> {
    if i.len() != j.len() || i.len() != t.len() {
        return Err(CoreError::shape(
            "minima",
            "i, j and t must have one length",
        ));
    }
    positive("distance", distance)?;
    check_layout(tracks)?;
    let n = tracks.samples.len();
    for m in 0..i.len() {
        finite("t", t[m])?;
        if i[m] as usize >= n || j[m] as usize >= n {
            return Err(CoreError::invalid(
                "minimum",
                m as f64,
                format!("objects ({}, {}) are not among the {n} tracks", i[m], j[m]),
            ));
        }
    }
    (0..i.len())
        .into_par_iter()
        .map(|m| {
            if m % 256 == 0 {
                progress.check()?;
            }
            let out = stretch(tracks, i[m] as usize, j[m] as usize, t[m], distance);
            progress.add(1);
            Ok(out)
        })
        .collect()
}

/// One minimum's stretch (see [`stretches`]).
fn stretch(tracks: &Tracks<'_>, i: usize, j: usize, tca: f64, limit: f64) -> (f64, f64) {
    let nt = tracks.times.len();
    let k = tracks.samples[i].min(tracks.samples[j]);
    if k < 2 {
        return (tca, tca);
    }
    let times = &tracks.times[..k];
    let rel = |q: usize| {
        let (a, b) = (i * nt + q, j * nt + q);
        (
            sub(tracks.positions[b], tracks.positions[a]),
            sub(tracks.velocities[b], tracks.velocities[a]),
        )
    };
    let dist = |q: usize, s: f64| {
        let ((r0, v0), (r1, v1)) = (rel(q), rel(q + 1));
        let x = hermite(r0, v0, r1, v1, times[q + 1] - times[q], s);
        norm([x[0], x[1], x[2]])
    };
    let crossing = |q: usize, mut inside: f64, mut outside: f64| {
        for _ in 0..WITHIN_BISECTIONS {
            let mid = 0.5 * (inside + outside);
            if dist(q, mid) <= limit {
                inside = mid;
            } else {
                outside = mid;
            }
        }
        times[q] + 0.5 * (inside + outside) * (times[q + 1] - times[q])
    };
    // The check points of an interval, fractions 0, 1/8, ..., 1 (exact in binary).
    let point = |p: usize| p as f64 / WITHIN_POINTS as f64;
    // The interval holding tca: the last sample at or before it, within [0, k - 2].
    let at = times
        .partition_point(|&x| x <= tca)
        .saturating_sub(1)
        .min(k - 2);
    let s_tca = ((tca - times[at]) / (times[at + 1] - times[at])).clamp(0.0, 1.0);
    // Backward from tca, then forward; each end the grid's if no crossing.
    let mut first = times[0];
    let (mut q, mut frac) = (at as isize, s_tca);
    'back: while q >= 0 {
        let qu = q as usize;
        let mut inside = frac;
        for p in (0..=WITHIN_POINTS).rev().map(point).filter(|&p| p < frac) {
            if dist(qu, p) > limit {
                first = crossing(qu, inside, p);
                break 'back;
            }
            inside = p;
        }
        q -= 1;
        frac = 1.0;
    }
    let mut last = times[k - 1];
    let (mut q, mut frac) = (at, s_tca);
    'forward: while q + 2 <= k {
        let mut inside = frac;
        for p in (0..=WITHIN_POINTS).map(point).filter(|&p| p > frac) {
            if dist(q, p) > limit {
                last = crossing(q, inside, p);
                break 'forward;
            }
            inside = p;
        }
        q += 1;
        frac = 0.0;
    }
    (first, last)
}

#[cfg(test)]
mod stretch_tests {
    use super::*;

    /// Two objects on straight lines: object 1 at rest at the origin, object 2 passing
    /// at `miss` m with speed `u` m/s along x, at x = 0 when t = 0; sampled every 60 s.
    #[test]
    fn a_straight_pass_stays_within_the_distance_for_its_chord() {
        let (miss, u, limit) = (300.0, 2.0, 1000.0);
        let times: Vec<f64> = (0..=60).map(|k| -1800.0 + 60.0 * k as f64).collect();
        let nt = times.len();
        let mut pos = vec![[0.0; 3]; 2 * nt];
        let mut vel = vec![[0.0; 3]; 2 * nt];
        for (k, &t) in times.iter().enumerate() {
            pos[nt + k] = [u * t, miss, 0.0];
            vel[nt + k] = [u, 0.0, 0.0];
        }
        let samples = [nt, nt];
        let fourth = [0.0, 0.0];
        let tracks = Tracks {
            times: &times,
            positions: &pos,
            velocities: &vel,
            samples: &samples,
            fourth: &fourth,
        };
        let p = Progress::default();
        let out = stretches(&tracks, &[0], &[1], &[0.0], limit, &p).unwrap();
        // |x| <= sqrt(limit^2 - miss^2) / u either side of 0 (the Hermite cubic is exact
        // for straight motion).
        let half = (limit * limit - miss * miss).sqrt() / u;
        assert!((out[0].0 + half).abs() < 1e-6 && (out[0].1 - half).abs() < 1e-6);
        // A limit the pass never leaves: the grid's ends.
        let all = stretches(&tracks, &[0], &[1], &[0.0], 1e5, &p).unwrap();
        assert_eq!(all[0], (times[0], times[nt - 1]));
        assert!(stretches(&tracks, &[0], &[2], &[0.0], limit, &p).is_err());
        assert!(stretches(&tracks, &[0], &[1], &[f64::NAN], limit, &p).is_err());
        let too_many = [nt + 1, nt];
        let bad = Tracks {
            samples: &too_many,
            ..tracks
        };
        assert!(stretches(&bad, &[0], &[1], &[0.0], limit, &p).is_err());
    }
}
