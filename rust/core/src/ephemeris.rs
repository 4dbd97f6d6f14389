//! Low-precision Sun and Moon positions and their point-mass pull on an Earth satellite
//! (lunisolar third-body perturbation), for orbits where it matters: over a week it moves a
//! geostationary object by tens of kilometres, a LEO object by metres.
//!
//! The series are those of Montenbruck & Gill, "Satellite Orbits" (Springer 2000),
//! section 3.3.2: the Sun from its mean anomaly (about 0.1 % in distance, 1 arcmin in
//! direction, with the perigee's slow advance added), the Moon from the leading terms of Brown's theory (a few arcmin, about
//! 500 km). Positions are geocentric, in the mean equator and equinox of J2000 (EME2000),
//! checked against an independent ephemeris (ERFA's through astropy) in the tests below.
//! The pulls ([`ThirdBodies`]) rotate them to the mean equator and equinox of date (IAU
//! 1976 precession, [`precession`]): the frame of rhoprop's states, TEME of date from
//! element sets, to within nutation (under 0.01 deg), and the frame its J2 and Earth
//! rotation assume. Left in J2000 they were 0.31-0.36 deg off in 2023-2026.

use crate::constants::SECONDS_PER_DAY;

/// Gravitational parameter of the Sun, m^3/s^2 (IAU 2009 / DE430).
pub const GM_SUN: f64 = 1.327_124_400_18e20;
/// Gravitational parameter of the Moon, m^3/s^2 (DE430).
pub const GM_MOON: f64 = 4.902_800_066e12;
/// TT - UT1 in 2020-2025, s (32.184 s + 37 leap seconds, UT1 - UTC within 0.1 s); the
/// series take TT, and a minute of error moves the Moon by 0.01 deg.
const TT_MINUS_UT1: f64 = 69.184;
/// Obliquity of the ecliptic at J2000, rad (23.43929111 deg).
const OBLIQUITY: f64 = 23.439_291_11 * std::f64::consts::PI / 180.0;
const ARCSEC: f64 = std::f64::consts::PI / (180.0 * 3600.0);
const DEG: f64 = std::f64::consts::PI / 180.0;

/// Julian centuries of TT since J2000 for `ut1` seconds since J2000 (UT1).
fn centuries(ut1: f64) -> f64 {
    (ut1 + TT_MINUS_UT1) / (36_525.0 * SECONDS_PER_DAY)
}

/// The IAU 1976 precession matrix (Lieske et al. 1977), J2000 mean equator and equinox to
/// those of date, `t` Julian centuries of TT since J2000: R3(-z) R2(theta) R3(-zeta).
pub fn precession(t: f64) -> [[f64; 3]; 3] {
    let zeta = (2306.2181 * t + 0.30188 * t * t + 0.017998 * t * t * t) * ARCSEC;
    let z = (2306.2181 * t + 1.09468 * t * t + 0.018203 * t * t * t) * ARCSEC;
    let theta = (2004.3109 * t - 0.42665 * t * t - 0.041833 * t * t * t) * ARCSEC;
    let (sz, cz) = zeta.sin_cos();
    let (sza, cza) = z.sin_cos();
    let (st, ct) = theta.sin_cos();
    [
        [
            cza * ct * cz - sza * sz,
            -cza * ct * sz - sza * cz,
            -cza * st,
        ],
        [
            sza * ct * cz + cza * sz,
            -sza * ct * sz + cza * cz,
            -sza * st,
        ],
        [st * cz, -st * sz, ct],
    ]
}

/// `m v` for a 3x3 matrix and a vector.
fn rotate(m: &[[f64; 3]; 3], v: [f64; 3]) -> [f64; 3] {
    std::array::from_fn(|i| m[i][0] * v[0] + m[i][1] * v[1] + m[i][2] * v[2])
}

/// Ecliptic (longitude, latitude, distance m) to EME2000 Cartesian, m.
fn equatorial(lon: f64, lat: f64, r: f64) -> [f64; 3] {
    let (sl, cl) = lon.sin_cos();
    let (sb, cb) = lat.sin_cos();
    let (se, ce) = OBLIQUITY.sin_cos();
    let (x, y, z) = (r * cl * cb, r * sl * cb, r * sb);
    [x, ce * y - se * z, se * y + ce * z]
}

/// Geocentric position of the Sun, m, EME2000, at `ut1` s since J2000.
pub fn sun(ut1: f64) -> [f64; 3] {
    let t = centuries(ut1);
    let m = (357.5256 + 35_999.049 * t) * DEG;
    // Longitude of perigee 282.94 deg (Montenbruck & Gill) advancing 0.3225 deg/century
    // against the J2000 equinox (1.7195 deg/century of date, Meeus, less the 1.3970 of
    // precession): without it the Sun was 0.07 deg behind by 2023.
    let perigee = (282.94 + 0.3225 * t) * DEG;
    let lon = perigee + m + (6_892.0 * m.sin() + 72.0 * (2.0 * m).sin()) * ARCSEC;
    let r = (149.619 - 2.499 * m.cos() - 0.021 * (2.0 * m).cos()) * 1e9;
    equatorial(lon, 0.0, r)
}

/// Geocentric position of the Sun, m, in the mean equator and equinox of the date `ut1`
/// (s since J2000): [`ThirdBodies::sun`] without the Moon's series.
pub fn sun_of_date(ut1: f64) -> [f64; 3] {
    rotate(&precession(centuries(ut1)), sun(ut1))
}

/// Geocentric position of the Moon, m, EME2000, at `ut1` s since J2000.
pub fn moon(ut1: f64) -> [f64; 3] {
    let t = centuries(ut1);
    // Mean longitude (referred to the J2000 equinox), mean anomalies of Moon and Sun,
    // argument of latitude and elongation.
    let l0 = (218.316_17 + 481_267.880_88 * t - 1.3972 * t) * DEG;
    let l = (134.962_92 + 477_198.867_53 * t) * DEG;
    let lp = (357.525_43 + 35_999.049_44 * t) * DEG;
    let f = (93.272_83 + 483_202.018_73 * t) * DEG;
    let d = (297.850_27 + 445_267.111_35 * t) * DEG;
    let lon = l0
        + (22_640.0 * l.sin() + 769.0 * (2.0 * l).sin() - 4_586.0 * (l - 2.0 * d).sin()
            + 2_370.0 * (2.0 * d).sin()
            - 668.0 * lp.sin()
            - 412.0 * (2.0 * f).sin()
            - 212.0 * (2.0 * l - 2.0 * d).sin()
            - 206.0 * (l + lp - 2.0 * d).sin()
            + 192.0 * (l + 2.0 * d).sin()
            - 165.0 * (lp - 2.0 * d).sin()
            + 148.0 * (l - lp).sin()
            - 125.0 * d.sin()
            - 110.0 * (l + lp).sin()
            - 55.0 * (2.0 * f - 2.0 * d).sin())
            * ARCSEC;
    let lat = (18_520.0
        * (f + lon - l0 + (412.0 * (2.0 * f).sin() + 541.0 * lp.sin()) * ARCSEC).sin()
        - 526.0 * (f - 2.0 * d).sin()
        + 44.0 * (l + f - 2.0 * d).sin()
        - 31.0 * (-l + f - 2.0 * d).sin()
        - 25.0 * (-2.0 * l + f).sin()
        - 23.0 * (lp + f - 2.0 * d).sin()
        + 21.0 * (-l + f).sin()
        + 11.0 * (-lp + f - 2.0 * d).sin())
        * ARCSEC;
    let r = (385_000.0
        - 20_905.0 * l.cos()
        - 3_699.0 * (2.0 * d - l).cos()
        - 2_956.0 * (2.0 * d).cos()
        - 570.0 * (2.0 * l).cos()
        + 246.0 * (2.0 * l - 2.0 * d).cos()
        - 205.0 * (lp - 2.0 * d).cos()
        - 171.0 * (l + 2.0 * d).cos()
        - 152.0 * (l + lp - 2.0 * d).cos())
        * 1e3;
    equatorial(lon, lat, r)
}

/// The pulls of the Sun and the Moon at one instant: each body's position and
/// gravitational parameter, and its direct pull on the Earth (mu s / |s|^3), which the
/// geocentric frame subtracts.
#[derive(Debug, Clone, Copy)]
pub struct ThirdBodies {
    bodies: [([f64; 3], f64, [f64; 3]); 2],
}

impl ThirdBodies {
    /// The Sun and the Moon at `ut1` s since J2000, in the mean equator and equinox of
    /// that date.
    pub fn at(ut1: f64) -> Self {
        let of_date = precession(centuries(ut1));
        let body = |s: [f64; 3], mu: f64| {
            let s = rotate(&of_date, s);
            let d = (s[0] * s[0] + s[1] * s[1] + s[2] * s[2]).sqrt();
            let k = mu / (d * d * d);
            (s, mu, [k * s[0], k * s[1], k * s[2]])
        };
        Self {
            bodies: [body(sun(ut1), GM_SUN), body(moon(ut1), GM_MOON)],
        }
    }

    /// Perturbing acceleration (m/s^2) at geocentric position `r` (m):
    /// sum over bodies of mu ((s - r) / |s - r|^3 - s / |s|^3).
    #[inline(always)]
    pub fn acceleration(&self, r: [f64; 3]) -> [f64; 3] {
        let mut a = [0.0; 3];
        for (s, mu, direct) in &self.bodies {
            let d = [s[0] - r[0], s[1] - r[1], s[2] - r[2]];
            let n2 = d[0] * d[0] + d[1] * d[1] + d[2] * d[2];
            let k = mu / (n2 * n2.sqrt());
            for c in 0..3 {
                a[c] += k * d[c] - direct[c];
            }
        }
        a
    }
}

#[cfg(test)]
mod tests {
    #[test]
    fn precession_equals_erfa_pmat76() {
        // ERFA's pmat76 (through pyerfa) at 2024-06-17T00:00 UTC: TT JD 2460478.50080074.
        let erfa = [
            [
                0.999_982_216_856_306_1,
                -0.005_469_734_936_745_44,
                -0.002_376_545_995_649_408_7,
            ],
            [
                0.005_469_734_936_096_066,
                0.999_985_040_866_852_5,
                -6.499_869_364_404_125e-6,
            ],
            [
                0.002_376_545_997_143_975,
                -6.499_322_883_349_552e-6,
                0.999_997_175_989_453_6,
            ],
        ];
        let t = (2_460_478.500_800_74 - 2_451_545.0) / 36_525.0;
        let p = super::precession(t);
        for i in 0..3 {
            for j in 0..3 {
                assert!((p[i][j] - erfa[i][j]).abs() < 2e-11, "{i} {j}: {}", p[i][j]);
            }
        }
    }

    use super::*;
    use crate::frames::{dot, norm};

    /// Seconds since J2000 (2000-01-01T12:00) of a UTC calendar instant, UT1 taken as UTC.
    fn since_j2000(days_from_j2000: f64) -> f64 {
        days_from_j2000 * SECONDS_PER_DAY
    }

    fn angle(a: [f64; 3], b: [f64; 3]) -> f64 {
        (dot(a, b) / (norm(a) * norm(b))).clamp(-1.0, 1.0).acos()
    }

    // Reference: astropy 8.0.2 `get_body(name, Time(..., scale="utc"),
    // ephemeris="builtin")` (ERFA epv00 for the Sun, ERFA moon98 for the Moon), GCRS
    // Cartesian, m; an independent implementation of independent theories. Days from
    // J2000 (UTC): 2023-11-13T00:00 = 8716.5, 2023-08-07T12:00 = 8619, 2022-02-01T06:00 =
    // 8066.75, 2002-09-07T01:00 = 979.541667.
    const REFERENCE: [(f64, [f64; 3], [f64; 3]); 4] = [
        (8716.5, SUN_2023_11_13, MOON_2023_11_13),
        (8619.0, SUN_2023_08_07, MOON_2023_08_07),
        (8066.75, SUN_2022_02_01, MOON_2022_02_01),
        (979.541_666_666_666_6, SUN_2002_09_07, MOON_2002_09_07),
    ];
    include!("ephemeris_reference.rs");

    #[test]
    fn sun_and_moon_agree_with_an_independent_ephemeris() {
        // Montenbruck & Gill's accuracy: Sun about 1 arcmin and 0.1 % in distance, Moon a
        // few arcmin and about 500 km. Tolerances: 0.05 deg / 0.2 % and 0.3 deg / 0.3 %.
        for (days, sun_ref, moon_ref) in REFERENCE {
            let t = since_j2000(days);
            let (s, m) = (sun(t), moon(t));
            assert!(
                angle(s, sun_ref).to_degrees() < 0.05,
                "sun {days}: {}",
                angle(s, sun_ref).to_degrees()
            );
            assert!(
                (norm(s) / norm(sun_ref) - 1.0).abs() < 2e-3,
                "sun distance {days}"
            );
            assert!(
                angle(m, moon_ref).to_degrees() < 0.3,
                "moon {days}: {}",
                angle(m, moon_ref).to_degrees()
            );
            assert!(
                (norm(m) / norm(moon_ref) - 1.0).abs() < 3e-3,
                "moon distance {days}"
            );
        }
    }

    #[test]
    fn the_pull_is_the_tidal_one() {
        // At the geocentre the perturbation vanishes; along the Earth-Moon line at
        // distance r it is the tidal 2 mu r / d^3 (to first order in r / d), towards the
        // Moon on the near side.
        let t = since_j2000(8716.5);
        let bodies = ThirdBodies::at(t);
        let a0 = bodies.acceleration([0.0; 3]);
        assert!(norm(a0) < 1e-18, "{a0:?}");
        let m = moon(t);
        let d = norm(m);
        let r = 42_164e3;
        let u = [m[0] / d, m[1] / d, m[2] / d];
        let moon_only = ThirdBodies {
            bodies: [bodies.bodies[1], ([1e30, 0.0, 0.0], 0.0, [0.0; 3])],
        };
        let a = moon_only.acceleration([r * u[0], r * u[1], r * u[2]]);
        let along = a[0] * u[0] + a[1] * u[1] + a[2] * u[2];
        let tidal = 2.0 * GM_MOON * r / (d * d * d);
        assert!((along / tidal - 1.0).abs() < 0.2, "{along} vs {tidal}");
        assert!(along > 0.0);
    }
}
