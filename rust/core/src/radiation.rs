//! Solar radiation pressure on a cannonball: the Sun's light pushing an object of
//! radiation parameter Cr A / m (m^2/kg) away from the Sun, dimmed by the Earth's shadow
//! (a conical umbra and penumbra). Over a week it drives the eccentricity of a
//! geostationary orbit by 1e-5 and more (kilometres of daily oscillation), of high
//! area-to-mass debris far more (Montenbruck & Gill, Satellite Orbits, 2000, section 3.4).

use crate::constants::R_EARTH;

/// Solar radiation pressure at one astronomical unit, N/m^2 (the solar constant
/// 1367 W/m^2 over the speed of light; Montenbruck & Gill eq. 3.69).
pub const SOLAR_PRESSURE: f64 = 4.560e-6;
/// Astronomical unit, m (IAU 2012).
pub const AU: f64 = 1.495_978_707e11;
/// Radius of the Sun, m (Montenbruck & Gill, table 3.3's 696,000 km).
pub const R_SUN: f64 = 6.96e8;

/// Longest adaptive step (s) across an edge of the shadow: a penumbra takes 8-20 s to
/// cross in low orbit, minutes in GEO.
pub const SHADOW_STEP: f64 = 5.0;

fn dot(a: [f64; 3], b: [f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

/// The apparent radii of the Sun and the Earth seen from `r` with the Sun at `sun`, and
/// their separation, rad (`None` inside the Earth).
fn discs(r: [f64; 3], sun: [f64; 3]) -> Option<(f64, f64, f64)> {
    let d = [sun[0] - r[0], sun[1] - r[1], sun[2] - r[2]];
    let (rn, dn) = (dot(r, r).sqrt(), dot(d, d).sqrt());
    if rn <= R_EARTH {
        return None;
    }
    let a = (R_SUN / dn).asin();
    let b = (R_EARTH / rn).asin();
    let c = (-dot(r, d) / (rn * dn)).clamp(-1.0, 1.0).acos();
    Some((a, b, c))
}

/// 0 in full sunlight, 1 in the penumbra (or an annular shadow), 2 in the umbra.
pub fn shadow_side(r: [f64; 3], sun: [f64; 3]) -> u8 {
    match discs(r, sun) {
        None => 2,
        Some((a, b, c)) if c >= a + b => 0,
        Some((a, b, c)) if c <= b - a => 2,
        Some(_) => 1,
    }
}

/// Fraction of the Sun's disc seen from geocentric position `r` (m) with the Sun at `sun`
/// (m): 1 in sunlight, 0 in the umbra, between in the penumbra (the area of overlap of
/// the two apparent discs; Montenbruck & Gill section 3.4.2).
pub fn sunlit_fraction(r: [f64; 3], sun: [f64; 3]) -> f64 {
    let Some((a, b, c)) = discs(r, sun) else {
        return 0.0;
    };
    if c >= a + b {
        1.0
    } else if c <= b - a {
        0.0
    } else if c <= a - b {
        1.0 - (b * b) / (a * a) // the Earth's disc wholly inside the Sun's
    } else {
        let x = (c * c + a * a - b * b) / (2.0 * c);
        let y = (a * a - x * x).max(0.0).sqrt();
        let overlap = a * a * (x / a).clamp(-1.0, 1.0).acos()
            + b * b * ((c - x) / b).clamp(-1.0, 1.0).acos()
            - c * y;
        (1.0 - overlap / (std::f64::consts::PI * a * a)).clamp(0.0, 1.0)
    }
}

/// Acceleration (m/s^2) of an object of radiation parameter `cr_area_mass` (Cr A / m,
/// m^2/kg) at geocentric position `r` (m), the Sun at `sun` (m, same axes): away from
/// the Sun, P (AU / d)^2 Cr A / m times the sunlit fraction.
pub fn acceleration(r: [f64; 3], sun: [f64; 3], cr_area_mass: f64) -> [f64; 3] {
    let d = [r[0] - sun[0], r[1] - sun[1], r[2] - sun[2]];
    let dn = dot(d, d).sqrt();
    let k = sunlit_fraction(r, sun) * SOLAR_PRESSURE * cr_area_mass * (AU / dn).powi(2) / dn;
    [k * d[0], k * d[1], k * d[2]]
}

#[cfg(test)]
mod tests {
    use super::*;

    const SUN: [f64; 3] = [AU, 0.0, 0.0];

    #[test]
    fn full_sunlight_pushes_away_from_the_sun_by_p_over_the_distance_squared() {
        // At GEO on the Sun's side: |a| = P Cr A/m (AU / (AU - r))^2, along -x.
        let r = [42_164e3, 0.0, 0.0];
        let a = acceleration(r, SUN, 0.02);
        let want = SOLAR_PRESSURE * 0.02 * (AU / (AU - 42_164e3)).powi(2);
        assert!(
            (-a[0] - want).abs() < 1e-15 * want.max(1.0) + 1e-22,
            "{a:?} vs {want}"
        );
        assert_eq!((a[1], a[2]), (0.0, 0.0));
        assert!((want - 9.12e-8).abs() < 0.01e-8); // ~1e-7 m/s^2 for a GEO satellite
    }

    #[test]
    fn the_earths_shadow_has_an_umbra_and_a_penumbra() {
        // Behind the Earth on the Sun-Earth line at LEO and GEO radii: umbra (the umbra
        // reaches 1.38e6 km behind the Earth). Off the line by the Earth's radius plus a
        // little: partly lit, more lit further out, fully lit beyond the penumbra.
        for radius in [6_778e3, 42_164e3] {
            assert_eq!(sunlit_fraction([-radius, 0.0, 0.0], SUN), 0.0);
            assert_eq!(sunlit_fraction([radius, 0.0, 0.0], SUN), 1.0);
            assert_eq!(sunlit_fraction([0.0, radius, 0.0], SUN), 1.0);
        }
        // At GEO radius the penumbra is about R_sun / AU x 42,164 km ~ 196 km wide on
        // either side of the shadow cylinder's edge (plus the cone's small taper).
        let x = -42_164e3;
        let lit = |y: f64| sunlit_fraction([x, y, 0.0], SUN);
        assert_eq!(lit(R_EARTH - 250e3), 0.0);
        let (p1, p2) = (lit(R_EARTH - 50e3), lit(R_EARTH + 50e3));
        assert!(0.0 < p1 && p1 < p2 && p2 < 1.0, "{p1} {p2}");
        assert!((lit(R_EARTH) - 0.5).abs() < 0.05, "{}", lit(R_EARTH));
        assert_eq!(lit(R_EARTH + 250e3), 1.0);
        // The sides the adaptive integrator watches agree with the fraction.
        let side = |y: f64| shadow_side([x, y, 0.0], SUN);
        assert_eq!(
            (side(R_EARTH - 250e3), side(R_EARTH), side(R_EARTH + 250e3)),
            (2, 1, 0)
        );
        assert_eq!(shadow_side([0.0, 0.0, 1e3], SUN), 2); // inside the Earth
                                                          // Continuous across the penumbra (no jump an integrator would stumble on).
        let mut last = 0.0;
        for k in 0..=1000 {
            let f = lit(R_EARTH - 300e3 + 600.0 * k as f64);
            assert!(f >= last && f - last < 0.01, "step {k}: {last} -> {f}");
            last = f;
        }
    }
}
