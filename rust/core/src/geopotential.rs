//! The Earth's tesseral and sectoral harmonics (order m >= 1) up to degree
//! [`MAX_TESSERAL_DEGREE`], for deep-space orbits: the resonances that SDP4 carries (the
//! one-day ones of geostationary orbits, J22, J31, J33; the half-day ones of GPS and
//! Molniya orbits, J22, J32, J44, J52, J54) and the rest of the field to degree 8. The
//! zonals stay in [`crate::dynamics`] (J2 always, J3..J6 on request).
//!
//! Cunningham's recursion of the solid harmonics V_nm, W_nm and their gradient
//! (Montenbruck & Gill, Satellite Orbits, 2000, eqs. 3.29-3.33), with the unnormalised
//! coefficients of the fully normalised EGM2008 ones (tide-free), in Earth-fixed
//! coordinates, lane by lane so that the loops vectorise.

use std::sync::LazyLock;

use crate::constants::{MU, R_EARTH};

/// Highest degree of the tesseral field.
pub const MAX_TESSERAL_DEGREE: usize = 8;

/// Degree used by the dynamics of deep-space orbits: the whole table. Its cost is about
/// that of a density lookup per lane and stage, and degree 8 is (Re / r)^6 ~ 2e-4 of the
/// degree-2 pull at GPS radius.
pub const DEEP_SPACE_TESSERAL_DEGREE: usize = MAX_TESSERAL_DEGREE;

/// V and W up to degree and order MAX + 1 (the gradient of degree n needs n + 1).
const TOP: usize = MAX_TESSERAL_DEGREE + 1;
const ENTRIES: usize = (TOP + 1) * (TOP + 2) / 2;

#[inline(always)]
const fn idx(n: usize, m: usize) -> usize {
    n * (n + 1) / 2 + m
}

/// Fully normalised EGM2008 coefficients (n, m, C, S), 2 <= n <= 8, 1 <= m <= n, as in
/// the ICGEM file EGM2008.gfc (Pavlis et al. 2012, tide-free).
#[rustfmt::skip]
const EGM2008: [(usize, usize, f64, f64); 35] = [
    (2, 1, -0.206615509074176e-09, 0.138441389137979e-08),
    (2, 2, 0.243938357328313e-05, -0.140027370385934e-05),
    (3, 1, 0.203046201047864e-05, 0.248200415856872e-06),
    (3, 2, 0.904787894809528e-06, -0.619005475177618e-06),
    (3, 3, 0.721321757121568e-06, 0.141434926192941e-05),
    (4, 1, -0.536157389388867e-06, -0.473567346518086e-06),
    (4, 2, 0.350501623962649e-06, 0.662480026275829e-06),
    (4, 3, 0.990856766672321e-06, -0.200956723567452e-06),
    (4, 4, -0.188519633023033e-06, 0.308803882149194e-06),
    (5, 1, -0.629211923042529e-07, -0.943698073395769e-07),
    (5, 2, 0.652078043176164e-06, -0.323353192540522e-06),
    (5, 3, -0.451847152328843e-06, -0.214955408306046e-06),
    (5, 4, -0.295328761175629e-06, 0.498070550102351e-07),
    (5, 5, 0.174811795496002e-06, -0.669379935180165e-06),
    (6, 1, -0.759210081892527e-07, 0.265122593213647e-07),
    (6, 2, 0.486488924604690e-07, -0.373789324523752e-06),
    (6, 3, 0.572451611175653e-07, 0.895201130010730e-08),
    (6, 4, -0.860237937191611e-07, -0.471425573429095e-06),
    (6, 5, -0.267166423703038e-06, -0.536493151500206e-06),
    (6, 6, 0.947068749756882e-08, -0.237382353351005e-06),
    (7, 1, 0.280887555776673e-06, 0.951259362869275e-07),
    (7, 2, 0.330407993702235e-06, 0.929969290624092e-07),
    (7, 3, 0.250458409225729e-06, -0.217118287729610e-06),
    (7, 4, -0.274993935591631e-06, -0.124058403514343e-06),
    (7, 5, 0.164773255934658e-08, 0.179281782751438e-07),
    (7, 6, -0.358798423464889e-06, 0.151798257443669e-06),
    (7, 7, 0.150746472872675e-08, 0.241068767286303e-07),
    (8, 1, 0.231607991248329e-07, 0.588974540927606e-07),
    (8, 2, 0.800143604736599e-07, 0.652805043667369e-07),
    (8, 3, -0.193745381715290e-07, -0.859639339125694e-07),
    (8, 4, -0.244360480007096e-06, 0.698072508472777e-07),
    (8, 5, -0.257011477267991e-07, 0.892034891745881e-07),
    (8, 6, -0.659648680031408e-07, 0.308946730783065e-06),
    (8, 7, 0.672569751771483e-07, 0.748686063738231e-07),
    (8, 8, -0.124022771917136e-06, 0.120551889384997e-06),
];

/// Normalisation factor of degree n, order m >= 1: sqrt(2 (2n + 1) (n - m)! / (n + m)!).
pub fn normalisation(n: usize, m: usize) -> f64 {
    let ratio: f64 = ((n - m + 1)..=(n + m)).map(|k| 1.0 / k as f64).product();
    (2.0 * (2 * n + 1) as f64 * ratio).sqrt()
}

/// Unnormalised (C, S) by [`idx`] (zero for m = 0 and n < 2).
static UNNORMALISED: LazyLock<[[f64; 2]; ENTRIES]> = LazyLock::new(|| {
    let mut cs = [[0.0; 2]; ENTRIES];
    for &(n, m, c, s) in &EGM2008 {
        let k = normalisation(n, m);
        cs[idx(n, m)] = [c * k, s * k];
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
    let degree = degree.min(MAX_TESSERAL_DEGREE);
    let top = degree + 1;
    let cs = &*UNNORMALISED;
    let mut v = [[0.0; W]; ENTRIES];
    let mut w = [[0.0; W]; ENTRIES];
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

#[cfg(test)]
mod tests {
    use super::*;

    /// The potential of the orders >= 1 in spherical coordinates, from the fully
    /// normalised coefficients and Legendre functions by the angular recursion (not the
    /// Cartesian solid harmonics of the code under test).
    fn potential(p: [f64; 3], degree: usize) -> f64 {
        let r = (p[0] * p[0] + p[1] * p[1] + p[2] * p[2]).sqrt();
        let t = p[2] / r;
        let u = (1.0 - t * t).sqrt();
        let lon = p[1].atan2(p[0]);
        let mut sum = 0.0;
        for &(n, m, c, s) in &EGM2008 {
            if n > degree {
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
            for degree in [2, 4, MAX_TESSERAL_DEGREE] {
                let a = tesseral(p, degree);
                let size = a.iter().map(|v| v.abs()).fold(0.0, f64::max);
                for i in 0..3 {
                    let h = 10.0;
                    let (mut qp, mut qm) = (p, p);
                    qp[i] += h;
                    qm[i] -= h;
                    let g = (potential(qp, degree) - potential(qm, degree)) / (2.0 * h);
                    assert!(
                        (a[i] - g).abs() < 1e-6 * size,
                        "{p:?} {degree} {i}: {} vs {g}",
                        a[i]
                    );
                }
            }
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
            worst_full = worst_full.max((east(MAX_TESSERAL_DEGREE, lon) * 1e9 - want).abs());
            worst_two = worst_two.max((east(2, lon) * 1e9 - want).abs());
        }
        assert!(worst_full < 1.5, "degree 8: worst {worst_full} e-9 m/s^2");
        assert!(worst_two > 7.0, "degree 2: worst {worst_two} e-9 m/s^2");
    }
}
