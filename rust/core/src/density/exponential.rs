//! Exponential atmosphere: a standard analytic benchmark.

use super::sigma_factor;
use super::{Atmosphere, LaneMemory};
use crate::constants::R_EARTH;
use crate::error::{finite, positive, CoreError};
use crate::frames::{norm, EarthRotation};

/// rho = rho0 * exp(-(h - h0) / H) with h = |r| - Re the spherical altitude, and a
/// standard deviation `rel_sigma * rho` for stochastic use.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Exponential {
    rho0: f64,
    h0: f64,
    scale_height: f64,
    rel_sigma: f64,
}

impl Exponential {
    /// This atmosphere with its sigma times `factor` (finite, >= 0).
    pub fn with_sigma_scale(&self, factor: f64) -> Result<Self, CoreError> {
        let factor = sigma_factor(factor)?;
        Self::new(
            self.rho0,
            self.h0,
            self.scale_height,
            self.rel_sigma * factor,
        )
    }

    /// `rho0` kg/m^3 at altitude `h0` m, scale height `scale_height` m, relative sigma
    /// (dimensionless, >= 0).
    pub fn new(rho0: f64, h0: f64, scale_height: f64, rel_sigma: f64) -> Result<Self, CoreError> {
        positive("rho0", rho0)?;
        finite("h0", h0)?;
        positive("scale_height", scale_height)?;
        finite("rel_sigma", rel_sigma)?;
        if rel_sigma < 0.0 {
            return Err(CoreError::invalid("rel_sigma", rel_sigma, "must be >= 0"));
        }
        Ok(Self {
            rho0,
            h0,
            scale_height,
            rel_sigma,
        })
    }

    /// Mean density at spherical altitude `h` m.
    #[inline(always)]
    pub fn at_altitude(&self, h: f64) -> f64 {
        self.rho0 * exp(-(h - self.h0) / self.scale_height)
    }
}

/// e^x to within 2 ulp, branch-free so that lane loops vectorise (the C library's `exp`
/// is a call per lane): x = k ln2 + r with |r| <= ln2 / 2, e^r by its Taylor series to
/// degree 13 (truncation < 1e-17 relative), times 2^k built in the exponent bits.
/// Arguments are clamped to [-708, 709], where e^x is a normal finite number.
#[inline(always)]
pub fn exp(x: f64) -> f64 {
    const LN2_HI: f64 = 6.931_471_803_691_238e-1;
    const LN2_LO: f64 = 1.908_214_929_270_587_7e-10;
    const INV_LN2: f64 = std::f64::consts::LOG2_E;
    // Adding and subtracting 1.5 * 2^52 rounds to the nearest integer without a branch.
    const ROUND: f64 = 6_755_399_441_055_744.0;
    let x = x.clamp(-708.0, 709.0);
    let k = (x * INV_LN2 + ROUND) - ROUND;
    let r = (x - k * LN2_HI) - k * LN2_LO;
    let mut p = 1.0 / 6_227_020_800.0; // 1/13!
    for d in [
        479_001_600.0, // 12!
        39_916_800.0,
        3_628_800.0,
        362_880.0,
        40_320.0,
        5_040.0,
        720.0,
        120.0,
        24.0,
        6.0,
        2.0,
        1.0,
        1.0,
    ] {
        p = p * r + 1.0 / d;
    }
    // 2^k: k + 1023 sits in the low mantissa bits of (k + 1023 + 2^52); shifted into the
    // exponent field it is the power of two.
    let two_k = f64::from_bits((k + 1023.0 + 4_503_599_627_370_496.0).to_bits() << 52);
    p * two_k
}

impl Atmosphere for Exponential {
    #[inline(always)]
    fn mean_sigma(
        &self,
        _ut1: f64,
        r: [f64; 3],
        _rot: &EarthRotation,
    ) -> Result<(f64, f64), CoreError> {
        let mean = self.at_altitude(norm(r) - R_EARTH);
        Ok((mean, self.rel_sigma * mean))
    }

    #[inline(always)]
    fn mean_sigma_lanes<const W: usize>(
        &self,
        _ut1: f64,
        x: &[f64; W],
        y: &[f64; W],
        z: &[f64; W],
        _active: &[f64; W],
        _rot: &EarthRotation,
        mean: &mut [f64; W],
        sigma: &mut [f64; W],
        _memory: &mut LaneMemory<W>,
    ) -> Result<(), CoreError> {
        // Every lane, active or not: the arithmetic cannot fail and stays finite (exp
        // clamps), and a straight loop vectorises.
        for l in 0..W {
            let r = (x[l] * x[l] + y[l] * y[l] + z[l] * z[l]).sqrt();
            mean[l] = self.at_altitude(r - R_EARTH);
            sigma[l] = self.rel_sigma * mean[l];
        }
        Ok(())
    }

    fn uses_earth_rotation(&self) -> bool {
        false
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn lane_exp_matches_the_library_exp() {
        // Within 2 ulp over the range densities use, and exact at 0.
        let mut worst = 0.0f64;
        for i in 0..=200_000 {
            let x = -700.0 + 1400.0 * i as f64 / 200_000.0;
            let (a, b) = (exp(x), x.exp());
            worst = worst.max(((a - b) / b).abs() / f64::EPSILON);
        }
        assert!(worst <= 2.0, "{worst} ulp");
        assert_eq!(exp(0.0), 1.0);
        assert!(exp(-1e6) > 0.0 && exp(1e6).is_finite());
    }

    #[test]
    fn values_and_scale_height() {
        let e = Exponential::new(3.725e-12, 400e3, 58.515e3, 0.2).unwrap();
        let rot = EarthRotation::new(0.3);
        let (m, s) = e
            .mean_sigma(0.0, [R_EARTH + 400e3, 0.0, 0.0], &rot)
            .unwrap();
        assert_eq!(m, 3.725e-12);
        assert!((s - 0.2 * 3.725e-12).abs() < 1e-27);
        let (m2, _) = e
            .mean_sigma(0.0, [0.0, 0.0, R_EARTH + 400e3 + 58.515e3], &rot)
            .unwrap();
        assert!((m2 / m - (-1.0f64).exp()).abs() < 1e-15);
    }

    #[test]
    fn rejects_bad_parameters() {
        assert!(Exponential::new(0.0, 400e3, 58e3, 0.0).is_err());
        assert!(Exponential::new(1e-12, 400e3, -1.0, 0.0).is_err());
        assert!(Exponential::new(1e-12, f64::NAN, 58e3, 0.0).is_err());
        assert!(Exponential::new(1e-12, 400e3, 58e3, -0.1).is_err());
    }
}
