//! Exponential atmosphere: a standard analytic benchmark.

use super::Atmosphere;
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
        self.rho0 * (-(h - self.h0) / self.scale_height).exp()
    }
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

    fn uses_earth_rotation(&self) -> bool {
        false
    }
}

#[cfg(test)]
mod tests {
    use super::*;

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
