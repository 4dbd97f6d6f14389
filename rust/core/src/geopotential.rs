//! The Earth's gravity field beyond the zonals of [`crate::dynamics`], from EGM2008
//! ([`crate::egm2008`]): for deep-space orbits the tesseral and sectoral harmonics (order
//! m >= 1) to degree 8, the resonances that SDP4 carries (the one-day ones of
//! geostationary orbits, J22, J31, J33; the half-day ones of GPS and Molniya orbits, J22,
//! J32, J44, J52, J54) and the rest of the field to degree 8; on request the whole field
//! to degree and order [`MAX_TESSERAL_DEGREE`], zonals above J6 included, which a
//! near-Earth orbit needs to follow a precise orbit (GRACE at 455 km over a day: 4-5 km
//! off without it, a few hundred metres with it).
//!
//! Cunningham's recursion of the solid harmonics V_nm, W_nm and their gradient
//! (Montenbruck & Gill, Satellite Orbits, 2000, eqs. 3.29-3.33), with the unnormalised
//! coefficients of the fully normalised EGM2008 ones (tide-free), in Earth-fixed
//! coordinates, lane by lane so that the loops vectorise.

use std::sync::LazyLock;

use crate::constants::{MU, R_EARTH};
use crate::egm2008::EGM2008;

/// Highest degree (and order) of the field.
pub const MAX_TESSERAL_DEGREE: usize = 40;

/// Degree of the tesseral field of deep-space orbits. Its cost is about that of a density
/// lookup per lane and stage, and degree 8 is (Re / r)^6 ~ 2e-4 of the degree-2 pull at
/// GPS radius.
pub const DEEP_SPACE_TESSERAL_DEGREE: usize = 8;

/// Entries of V and W up to degree and order `top`.
const fn entries(top: usize) -> usize {
    (top + 1) * (top + 2) / 2
}
/// V and W up to degree and order MAX + 1 (the gradient of degree n needs n + 1).
const ENTRIES: usize = entries(MAX_TESSERAL_DEGREE + 1);
/// The same for the deep-space degree, whose smaller arrays keep that path as fast as it
/// was before the table grew.
const DEEP_ENTRIES: usize = entries(DEEP_SPACE_TESSERAL_DEGREE + 1);

#[inline(always)]
const fn idx(n: usize, m: usize) -> usize {
    n * (n + 1) / 2 + m
}

/// Normalisation factor of degree n, order m: sqrt((2 - delta_m0) (2n + 1) (n - m)! /
/// (n + m)!).
pub fn normalisation(n: usize, m: usize) -> f64 {
    let ratio: f64 = ((n - m + 1)..=(n + m)).map(|k| 1.0 / k as f64).product();
    let two = if m == 0 { 1.0 } else { 2.0 };
    (two * (2 * n + 1) as f64 * ratio).sqrt()
}

/// Unnormalised (C, S) by [`idx`] (zero for n < 2).
static UNNORMALISED: LazyLock<Vec<[f64; 2]>> = LazyLock::new(|| {
    let mut cs = vec![[0.0; 2]; ENTRIES];
    for &(n, m, c, s) in &EGM2008 {
        if n <= MAX_TESSERAL_DEGREE {
            let k = normalisation(n, m);
            cs[idx(n, m)] = [c * k, s * k];
        }
    }
    cs
});

/// Acceleration (m/s^2, Earth-fixed) of the harmonics of order 1..=n, degree 2..=`degree`
/// (at most [`MAX_TESSERAL_DEGREE`]), at the Earth-fixed positions (m) of the lanes.
#[inline(always)]
pub fn tesseral_lanes<const W: usize>(
    x: &[f64; W],
    y: &[f64; W],
    z: &[f64; W],
    degree: usize,
) -> [[f64; W]; 3] {
    field_lanes(x, y, z, degree, usize::MAX)
}

/// Acceleration (m/s^2, Earth-fixed) of every harmonic of degree 2..=`degree` (at most
/// [`MAX_TESSERAL_DEGREE`]) of order m >= 1, and of the zonals (m = 0) of degree
/// `first_zonal`..=`degree`, at the Earth-fixed positions (m) of the lanes.
#[inline(always)]
pub fn field_lanes<const W: usize>(
    x: &[f64; W],
    y: &[f64; W],
    z: &[f64; W],
    degree: usize,
    first_zonal: usize,
) -> [[f64; W]; 3] {
    let degree = degree.min(MAX_TESSERAL_DEGREE);
    if degree <= DEEP_SPACE_TESSERAL_DEGREE {
        // The deep-space path: V and W on the stack, as small as degree 8 needs.
        let mut v = [[0.0; W]; DEEP_ENTRIES];
        let mut w = [[0.0; W]; DEEP_ENTRIES];
        field_into(x, y, z, degree, first_zonal, &mut v, &mut w)
    } else {
        // Up to 903 entries a lane: on the heap, sized to the degree asked for (a stack
        // array of the largest size overflowed the 2 MB test threads with 32 lanes).
        let n = entries(degree + 1);
        let (mut v, mut w) = (vec![[0.0; W]; n], vec![[0.0; W]; n]);
        field_into(x, y, z, degree, first_zonal, &mut v, &mut w)
    }
}

/// [`field_lanes`] with V and W in the given scratch (at least the entries of degree + 1).
#[inline(always)]
fn field_into<const W: usize>(
    x: &[f64; W],
    y: &[f64; W],
    z: &[f64; W],
    degree: usize,
    first_zonal: usize,
    v: &mut [[f64; W]],
    w: &mut [[f64; W]],
) -> [[f64; W]; 3] {
    let top = degree + 1;
    debug_assert!(entries(top) <= v.len() && entries(top) <= w.len());
    let cs = &*UNNORMALISED;
    let (mut xr, mut yr, mut zr, mut rr) = ([0.0; W], [0.0; W], [0.0; W], [0.0; W]);
    for l in 0..W {
        let r2 = x[l] * x[l] + y[l] * y[l] + z[l] * z[l];
        let k = R_EARTH / r2;
        (xr[l], yr[l], zr[l], rr[l]) = (x[l] * k, y[l] * k, z[l] * k, R_EARTH * k);
        v[0][l] = R_EARTH / r2.sqrt();
    }
    for m in 0..=top {
        if m > 0 {
            let (a, b, k) = (idx(m, m), idx(m - 1, m - 1), (2 * m - 1) as f64);
            for l in 0..W {
                v[a][l] = k * (xr[l] * v[b][l] - yr[l] * w[b][l]);
                w[a][l] = k * (xr[l] * w[b][l] + yr[l] * v[b][l]);
            }
        }
        if m < top {
            let (a, b, k) = (idx(m + 1, m), idx(m, m), (2 * m + 1) as f64);
            for l in 0..W {
                v[a][l] = k * zr[l] * v[b][l];
                w[a][l] = k * zr[l] * w[b][l];
            }
        }
        for n in (m + 2)..=top {
            let (a, b, c) = (idx(n, m), idx(n - 1, m), idx(n - 2, m));
            let k1 = (2 * n - 1) as f64 / (n - m) as f64;
            let k2 = (n + m - 1) as f64 / (n - m) as f64;
            for l in 0..W {
                v[a][l] = k1 * zr[l] * v[b][l] - k2 * rr[l] * v[c][l];
                w[a][l] = k1 * zr[l] * w[b][l] - k2 * rr[l] * w[c][l];
            }
        }
    }
    let mut acc = [[0.0; W]; 3];
    for n in 2..=degree {
        if n >= first_zonal {
            // Order 0 (M&G eq. 3.33): only C_n0.
            let c = cs[idx(n, 0)][0];
            let (p, o) = (idx(n + 1, 1), idx(n + 1, 0));
            let g = (n + 1) as f64;
            for l in 0..W {
                acc[0][l] -= c * v[p][l];
                acc[1][l] -= c * w[p][l];
                acc[2][l] -= g * c * v[o][l];
            }
        }
        for m in 1..=n {
            let [c, s] = cs[idx(n, m)];
            let (p, q, o) = (idx(n + 1, m + 1), idx(n + 1, m - 1), idx(n + 1, m));
            let f = ((n - m + 2) * (n - m + 1)) as f64;
            let g = (n - m + 1) as f64;
            for l in 0..W {
                acc[0][l] += 0.5 * ((-c * v[p][l] - s * w[p][l]) + f * (c * v[q][l] + s * w[q][l]));
                acc[1][l] +=
                    0.5 * ((-c * w[p][l] + s * v[p][l]) + f * (-c * w[q][l] + s * v[q][l]));
                acc[2][l] += g * (-c * v[o][l] - s * w[o][l]);
            }
        }
    }
    let scale = MU / (R_EARTH * R_EARTH);
    for a in &mut acc {
        for value in a.iter_mut() {
            *value *= scale;
        }
    }
    acc
}

/// [`tesseral_lanes`] at one Earth-fixed position `p` (m).
pub fn tesseral(p: [f64; 3], degree: usize) -> [f64; 3] {
    let a = tesseral_lanes::<1>(&[p[0]], &[p[1]], &[p[2]], degree);
    [a[0][0], a[1][0], a[2][0]]
}

/// [`field_lanes`] at one Earth-fixed position `p` (m).
pub fn field(p: [f64; 3], degree: usize, first_zonal: usize) -> [f64; 3] {
    let a = field_lanes::<1>(&[p[0]], &[p[1]], &[p[2]], degree, first_zonal);
    [a[0][0], a[1][0], a[2][0]]
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The potential of the orders >= 1 (and the zonals from `first_zonal`) in spherical
    /// coordinates, from the fully
    /// normalised coefficients and Legendre functions by the angular recursion (not the
    /// Cartesian solid harmonics of the code under test).
    fn potential(p: [f64; 3], degree: usize, first_zonal: usize) -> f64 {
        let r = (p[0] * p[0] + p[1] * p[1] + p[2] * p[2]).sqrt();
        let t = p[2] / r;
        let u = (1.0 - t * t).sqrt();
        let lon = p[1].atan2(p[0]);
        let mut sum = 0.0;
        for &(n, m, c, s) in &EGM2008 {
            if n > degree || (m == 0 && n < first_zonal) {
                continue;
            }
            // Unnormalised P_nm(t) without the Condon-Shortley phase.
            let mut pmm = 1.0;
            for k in 1..=m {
                pmm *= (2 * k - 1) as f64 * u;
            }
            let (mut p0, mut p1) = (pmm, t * (2 * m + 1) as f64 * pmm);
            let pnm = if n == m {
                pmm
            } else {
                for k in (m + 2)..=n {
                    let p2 =
                        ((2 * k - 1) as f64 * t * p1 - (k + m - 1) as f64 * p0) / (k - m) as f64;
                    (p0, p1) = (p1, p2);
                }
                p1
            };
            let norm = normalisation(n, m);
            sum += (R_EARTH / r).powi(n as i32)
                * pnm
                * norm
                * (c * (m as f64 * lon).cos() + s * (m as f64 * lon).sin());
        }
        MU / r * sum
    }

    #[test]
    fn acceleration_is_the_gradient_of_the_potential() {
        // Central differences of the spherical potential, 10 m steps: at GEO, GPS and
        // Molniya-perigee radii, off the equator and near a pole.
        for p in [
            [3.0e7, 2.9e7, 2.0e6],
            [-1.2e7, 2.1e7, 1.1e7],
            [4.0e6, -5.0e6, 2.5e6],
            [2.0e5, 1.0e5, 7.5e6],
        ] {
            for (degree, first_zonal) in [
                (2, usize::MAX),
                (4, usize::MAX),
                (DEEP_SPACE_TESSERAL_DEGREE, usize::MAX),
                (MAX_TESSERAL_DEGREE, usize::MAX),
                (MAX_TESSERAL_DEGREE, 7),
                (20, 3),
            ] {
                let a = field(p, degree, first_zonal);
                let size = a.iter().map(|v| v.abs()).fold(0.0, f64::max);
                for i in 0..3 {
                    let h = 10.0;
                    let (mut qp, mut qm) = (p, p);
                    qp[i] += h;
                    qm[i] -= h;
                    let g = (potential(qp, degree, first_zonal)
                        - potential(qm, degree, first_zonal))
                        / (2.0 * h);
                    assert!(
                        (a[i] - g).abs() < 1e-6 * size,
                        "{p:?} {degree} {i}: {} vs {g}",
                        a[i]
                    );
                }
            }
        }
        // The zonals of the table are rhoprop's J3..J6 (dynamics::zonal_acceleration) to
        // their digits: J_n = -sqrt(2n + 1) C_n0.
        for (n, j) in [
            (3, crate::constants::J3),
            (4, crate::constants::J4),
            (6, crate::constants::J6),
        ] {
            let c = EGM2008.iter().find(|e| e.0 == n && e.1 == 0).unwrap().2;
            let jn = -c * ((2 * n + 1) as f64).sqrt();
            assert!((jn - j).abs() < 1e-3 * j.abs(), "J{n}: {jn} vs {j}");
        }
    }

    #[test]
    fn normalisation_of_degree_two_order_two() {
        // N22^2 = 2 x 5 x 0! / 4! = 5 / 12.
        assert!((normalisation(2, 2).powi(2) - 5.0 / 12.0).abs() < 1e-15);
        // N31^2 = 2 x 7 x 2! / 4! = 7 / 6.
        assert!((normalisation(3, 1).powi(2) - 7.0 / 6.0).abs() < 1e-15);
    }

    /// East component (m/s^2) of the pull on the geostationary ring at `lon` (rad).
    fn east(degree: usize, lon: f64) -> f64 {
        let r = 42_164.2e3;
        let a = tesseral([r * lon.cos(), r * lon.sin(), 0.0], degree);
        -a[0] * lon.sin() + a[1] * lon.cos()
    }

    #[test]
    fn geo_drift_of_degree_two_matches_the_published_figure() {
        // C22/S22 alone (C21/S21 do not pull along the equator): at most 5.6e-8 m/s^2
        // along the ring, a longitude acceleration 3 a_T / r of 0.0017 deg/day^2 (Soop,
        // Handbook of Geostationary Orbits, 1994: 0.00168 deg/day^2 at 45 deg from the
        // stable points), stable points near 75 E and 105 W.
        let r = 42_164.2e3;
        let (mut peak, mut stable) = (0.0f64, Vec::new());
        for k in 0..3600 {
            let lon = (k as f64 / 10.0).to_radians();
            peak = peak.max(east(2, lon).abs());
            let next = ((k + 1) as f64 / 10.0).to_radians();
            // A westward pull lowers the orbit and speeds it up eastward (longitude
            // acceleration -3 a_T / r): stable where the pull turns from west to east.
            if east(2, lon) < 0.0 && east(2, next) >= 0.0 {
                stable.push(lon.to_degrees());
            }
        }
        let deg_per_day2 = 3.0 * peak / r * 86400.0f64.powi(2) * 180.0 / std::f64::consts::PI;
        assert!(
            (deg_per_day2 - 0.00168).abs() < 0.00005,
            "{deg_per_day2} deg/day^2"
        );
        assert_eq!(stable.len(), 2, "{stable:?}");
        assert!(
            (stable[0] - 75.1).abs() < 1.0 && (stable[1] - 255.1).abs() < 1.0,
            "{stable:?}"
        );
    }

    #[test]
    fn geo_pull_of_the_whole_field_matches_soops_table() {
        // East-west acceleration on the geostationary ring every 15 deg, 1e-9 m/s^2, east
        // positive (Soop, Handbook of Geostationary Orbits, table 2, as tabulated at
        // server-sky.com/Soop), from 0 E eastward. Degree 8 agrees within 0.96 (degrees 3
        // and 4 within 1.02); degree 2 alone is sinusoidal with a 55.9 amplitude and
        // misses by up to 10.6 (65.3 at 120 E): the degree-3 terms make the asymmetry.
        let soop = [
            -21.3, -45.5, -58.3, -54.3, -33.0, 0.0, 34.5, 58.9, 65.3, 52.3, 25.3, -6.6, -34.2,
            -50.8, -54.4, -43.0, -23.3, 0.3, 22.3, 38.7, 46.5, 43.5, 29.6, 6.3,
        ];
        let (mut worst_full, mut worst_two) = (0.0f64, 0.0f64);
        for (k, want) in soop.iter().enumerate() {
            let lon = (15.0 * k as f64).to_radians();
            worst_full = worst_full.max((east(DEEP_SPACE_TESSERAL_DEGREE, lon) * 1e9 - want).abs());
            worst_two = worst_two.max((east(2, lon) * 1e9 - want).abs());
        }
        assert!(worst_full < 1.5, "degree 8: worst {worst_full} e-9 m/s^2");
        assert!(worst_two > 7.0, "degree 2: worst {worst_two} e-9 m/s^2");
    }
}
