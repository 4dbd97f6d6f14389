//! Density sources. Every source answers the mean density and its standard deviation
//! (kg/m^3) at a time and inertial position; the stochastic perturbation by kappa is
//! applied by the dynamics, so any source serves every member and sigma point.

mod exponential;
mod gridded;

pub use exponential::Exponential;
pub use gridded::GriddedField;

use crate::error::CoreError;
use crate::frames::EarthRotation;

/// A thermospheric density source: mean and 1-sigma density.
pub trait Atmosphere: Sync {
    /// Mean density and its standard deviation, kg/m^3, at `ut1` seconds since J2000 and
    /// the inertial position `r` (m). `rot` is the inertial -> Earth-fixed rotation at that
    /// instant, computed once per integrator stage by the caller.
    fn mean_sigma(
        &self,
        ut1: f64,
        r: [f64; 3],
        rot: &EarthRotation,
    ) -> Result<(f64, f64), CoreError>;

    /// Whether `mean_sigma` reads the Earth rotation; when false the caller may skip
    /// computing GMST (an analytic atmosphere of |r| alone).
    fn uses_earth_rotation(&self) -> bool {
        true
    }
}
