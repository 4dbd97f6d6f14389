//! Time: epochs are seconds since J2000 (2000-01-01T12:00:00 UTC), taken as UT1
//! (UT1 = UTC is acceptable per the design contract). The core otherwise works in
//! seconds from the initial epoch.

use crate::constants::SECONDS_PER_DAY;
use std::f64::consts::TAU;

/// Seconds per Julian century.
const SECONDS_PER_CENTURY: f64 = 36525.0 * SECONDS_PER_DAY;

/// Greenwich mean sidereal time (IAU-82, Aoki et al. 1982 as in Vallado eq. 3-45), rad
/// in [0, 2 pi), for `ut1` seconds since J2000.
pub fn gmst(ut1: f64) -> f64 {
    // Split whole days so that the large linear term keeps full precision.
    let days = (ut1 / SECONDS_PER_DAY).floor();
    let frac = ut1 - days * SECONDS_PER_DAY;
    let t = ut1 / SECONDS_PER_CENTURY;
    // GMST in seconds of time: 67310.54841 + (876600 h + 8640184.812866) T + 0.093104 T^2
    // - 6.2e-6 T^3. The 876600 h T term equals one sidereal-free turn per UT1 day plus
    // the fractional day, which we add exactly.
    let poly = 67310.54841 + 8640184.812866 * t + 0.093104 * t * t - 6.2e-6 * t * t * t;
    // 876600 h * T = days + frac/86400 days = (whole days -> whole turns) + frac seconds.
    let seconds = (poly + frac).rem_euclid(SECONDS_PER_DAY);
    (seconds / SECONDS_PER_DAY * TAU).rem_euclid(TAU)
}

/// Rate of [`gmst`], rad/s, at `ut1` seconds since J2000: one turn per UT1 day plus the
/// derivative of the polynomial part.
pub fn gmst_rate(ut1: f64) -> f64 {
    let t = ut1 / SECONDS_PER_CENTURY;
    let poly_rate =
        (8640184.812866 + 2.0 * 0.093104 * t - 3.0 * 6.2e-6 * t * t) / SECONDS_PER_CENTURY;
    (1.0 + poly_rate) * TAU / SECONDS_PER_DAY
}

/// Seconds since J2000 of a Julian date (UT1).
pub fn seconds_since_j2000_from_jd(jd: f64) -> f64 {
    (jd - 2451545.0) * SECONDS_PER_DAY
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn gmst_rate_matches_the_difference_of_gmst() {
        // Central difference over +-5000 s (wide enough that gmst's own rounding, ~2e-14
        // rad at these epochs, stays below 1e-12 relative).
        for ut1 in [-4.0e8, 0.0, 7.8e8, 1.5e9] {
            let mut d = gmst(ut1 + 5000.0) - gmst(ut1 - 5000.0);
            if d < 0.0 {
                d += TAU;
            }
            let fd = d / 10000.0;
            let rate = gmst_rate(ut1);
            assert!((rate - fd).abs() < 1e-12 * rate, "{ut1}: {rate} vs {fd}");
        }
    }

    #[test]
    fn gmst_vallado_example_3_5() {
        // Vallado, Fundamentals of Astrodynamics (4th ed.), Example 3-5:
        // 1992 August 20, 12:14:00 UT1 -> GMST = 152.578787810 deg.
        let jd = 2448854.5 + (12.0 + 14.0 / 60.0) / 24.0;
        let g = gmst(seconds_since_j2000_from_jd(jd)).to_degrees();
        assert!((g - 152.578787810).abs() < 1e-6, "gmst = {g}");
    }

    #[test]
    fn gmst_at_j2000() {
        // At J2000 (T = 0): 67310.54841 s = 280.46061837 deg (Vallado eq. 3-45).
        let g = gmst(0.0).to_degrees();
        assert!((g - 280.460618375).abs() < 1e-8, "gmst = {g}");
    }

    #[test]
    fn gmst_rate_is_sidereal() {
        // One UT1 day later GMST has advanced by 360 deg plus 8640184.812866 / 36525 s of
        // sidereal time (the linear term of the IAU-82 polynomial).
        let g0 = gmst(1.0e8);
        let g1 = gmst(1.0e8 + SECONDS_PER_DAY);
        let adv = (g1 - g0).rem_euclid(TAU).to_degrees();
        assert!(
            (adv - 8640184.812866 / 36525.0 / 240.0).abs() < 1e-9,
            "advance = {adv}"
        );
    }
}
