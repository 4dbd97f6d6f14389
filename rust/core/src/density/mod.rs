//! Density sources. Every source answers the mean density and its standard deviation
//! (kg/m^3) at a time and inertial position; the stochastic perturbation by kappa is
//! applied by the dynamics, so any source serves every member and sigma point.

mod exponential;
mod gridded;
pub mod jacchia_roberts;
pub mod jb2008;
mod streamed;

pub use exponential::Exponential;
pub use gridded::{FieldTile, GriddedField};
pub use streamed::{StreamedField, TileSource};

use crate::error::CoreError;
use crate::frames::EarthRotation;
use std::sync::Arc;

/// A factor on a source's sigma, checked: finite and >= 0.
pub(crate) fn sigma_factor(factor: f64) -> Result<f64, CoreError> {
    if factor.is_finite() && factor >= 0.0 {
        Ok(factor)
    } else {
        Err(CoreError::invalid(
            "sigma scale",
            factor,
            "must be finite and >= 0",
        ))
    }
}

/// What one batch keeps between its right-hand-side evaluations for an atmosphere that
/// can reuse work from the previous stage: a field's cell corners per lane (consecutive
/// stages of a step mostly fall in the same cell, so its 16 table reads are skipped).
/// One per batch; it changes speed only, never a value.
#[derive(Debug, Clone)]
pub struct LaneMemory<const W: usize> {
    /// Per lane: first table index of the cell whose corners are held (NaN: none).
    pub(crate) cell: [f64; W],
    /// The cell's corners per (time node, value) pair and corner (4 altitude bit + 2
    /// latitude bit + longitude bit), per lane: at an even index the corner's value, at the
    /// odd one after it the step to its longitude neighbour.
    pub(crate) corners: [[f64; W]; 32],
    /// The field's time cell of the previous evaluation (a hint).
    pub(crate) time_cell: usize,
    /// A streamed field's tile the batch is in, and its one-tile field (kept alive while
    /// the batch is in it).
    pub(crate) tile: Option<(usize, Arc<GriddedField>)>,
}

impl<const W: usize> Default for LaneMemory<W> {
    fn default() -> Self {
        Self {
            cell: [f64::NAN; W],
            corners: [[0.0; W]; 32],
            time_cell: 0,
            tile: None,
        }
    }
}

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

    /// Mean and sigma for every lane of a batch at once (positions `x`, `y`, `z` per lane,
    /// m), written to `mean` and `sigma`. Lanes whose `active` entry is 0 (drag off, e.g.
    /// a decayed member) may be skipped and keep what they held. `memory` is the batch's
    /// own (see [`LaneMemory`]). The default asks [`Atmosphere::mean_sigma`] lane by
    /// lane; analytic sources override it with straight-line lane arithmetic that the
    /// compiler vectorises.
    #[allow(clippy::too_many_arguments)]
    #[inline(always)]
    fn mean_sigma_lanes<const W: usize>(
        &self,
        ut1: f64,
        x: &[f64; W],
        y: &[f64; W],
        z: &[f64; W],
        active: &[f64; W],
        rot: &EarthRotation,
        mean: &mut [f64; W],
        sigma: &mut [f64; W],
        _memory: &mut LaneMemory<W>,
    ) -> Result<(), CoreError> {
        for l in 0..W {
            if active[l] != 0.0 {
                (mean[l], sigma[l]) = self.mean_sigma(ut1, [x[l], y[l], z[l]], rot)?;
            }
        }
        Ok(())
    }

    /// Whether `mean_sigma` reads the Earth rotation; when false the caller may skip
    /// computing GMST (an analytic atmosphere of |r| alone).
    fn uses_earth_rotation(&self) -> bool {
        true
    }
}
