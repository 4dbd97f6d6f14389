//! Physical constants of the design contract (DESIGN.md section 3). Use exactly these.

/// Earth's gravitational parameter, m^3/s^2.
pub const MU: f64 = 3.986004418e14;
/// Earth's equatorial radius (WGS-84 semi-major axis), m.
pub const R_EARTH: f64 = 6378137.0;
/// Second zonal harmonic, unnormalised.
pub const J2: f64 = 1.08262668e-3;
/// WGS-84 flattening.
pub const WGS84_F: f64 = 1.0 / 298.257223563;
/// WGS-84 polar radius (semi-minor axis), m.
pub const R_POLE: f64 = R_EARTH * (1.0 - WGS84_F);
/// Earth rotation rate used for the co-rotating atmosphere, rad/s.
pub const OMEGA_EARTH: f64 = 7.292115e-5;
/// Seconds per day.
pub const SECONDS_PER_DAY: f64 = 86400.0;

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn values_match_design_contract() {
        assert_eq!(MU, 3.986004418e14);
        assert_eq!(R_EARTH, 6_378_137.0);
        assert_eq!(J2, 1.08262668e-3);
        assert_eq!(1.0 / WGS84_F, 298.257223563);
        assert_eq!(OMEGA_EARTH, 7.292115e-5);
        assert!((R_POLE - 6_356_752.314245).abs() < 1e-6);
    }
}
