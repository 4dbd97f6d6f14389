//! Physical constants of the design contract (docs/conventions.md, "Frames and dynamics"). Use exactly these.

/// Earth's gravitational parameter, m^3/s^2.
pub const MU: f64 = 3.986004418e14;
/// Earth's equatorial radius (WGS-84 semi-major axis), m.
pub const R_EARTH: f64 = 6378137.0;
/// Second zonal harmonic, unnormalised.
pub const J2: f64 = 1.08262668e-3;
/// Zonal harmonics J3..J6 (unnormalised), used only when a run asks for a zonal degree
/// above 2 (the paper's model is J2 only). EGM2008 tide-free fully normalised
/// coefficients (Pavlis et al. 2012, NGA file `EGM2008_to2190_TideFree`):
/// C30 = 0.957161207093473e-06, C40 = 0.539965866638991e-06,
/// C50 = 0.686702913736681e-07, C60 = -0.149953927978527e-06, unnormalised by
/// J_n = -sqrt(2n + 1) C_n0.
pub const J3: f64 = -2.532_410_518_567_722_5e-6;
/// Fourth zonal harmonic, unnormalised (EGM2008, see [`J3`]).
pub const J4: f64 = -1.619_897_599_916_973_1e-6;
/// Fifth zonal harmonic, unnormalised (EGM2008, see [`J3`]).
pub const J5: f64 = -2.277_535_907_308_361_8e-7;
/// Sixth zonal harmonic, unnormalised (EGM2008, see [`J3`]).
pub const J6: f64 = 5.406_665_762_838_132e-7;
/// WGS-84 flattening.
pub const WGS84_F: f64 = 1.0 / 298.257223563;
/// WGS-84 polar radius (semi-minor axis), m.
pub const R_POLE: f64 = R_EARTH * (1.0 - WGS84_F);
/// Earth rotation rate used for the co-rotating atmosphere, rad/s.
pub const OMEGA_EARTH: f64 = 7.292115e-5;
/// Seconds per day.
pub const SECONDS_PER_DAY: f64 = 86400.0;

/// The paper's initial state [x, y, z (m), vx, vy, vz (m/s)] (docs/paper-study.md): the
/// orbit the tests and benchmarks fly.
pub const PAPER_STATE: [f64; 6] = [
    3782900.7032,
    -5441600.6779,
    -1420075.1327,
    -606.6600,
    1539.2559,
    -7488.3946,
];

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
        // J_n = -sqrt(2n + 1) C_n0 from the EGM2008 normalised coefficients.
        let c = [
            (3, 0.957161207093473e-06, J3),
            (4, 0.539965866638991e-06, J4),
            (5, 0.686702913736681e-07, J5),
            (6, -0.149953927978527e-06, J6),
        ];
        for (n, cn0, jn) in c {
            let expect = -f64::from(2 * n + 1).sqrt() * cn0;
            assert!((jn - expect).abs() < 1e-15 * expect.abs(), "J{n}");
        }
    }
}
