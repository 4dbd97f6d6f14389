//! What every run starts from: epoch, initial state, drag parameter, decay floor and
//! zonal degree,
//! validated once here for `propagate`, the Monte Carlo engine and the CCSP filter alike.

use crate::dynamics::MAX_ZONAL_DEGREE;
use crate::error::{finite, positive, CoreError};
use crate::frames::altitude;
use crate::geopotential::MAX_TESSERAL_DEGREE;

/// Default floor altitude below which an object counts as decayed, m.
pub const DEFAULT_FLOOR_ALTITUDE: f64 = 120e3;

/// The initial-value problem shared by every run.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Problem {
    /// Epoch of t = 0, seconds since J2000 (UT1).
    pub epoch: f64,
    /// Initial inertial state [x, y, z, vx, vy, vz], m and m/s.
    pub y0: [f64; 6],
    /// Drag parameter Cd*A/m, m^2/kg.
    pub drag: f64,
    /// Geodetic altitude below which the object counts as decayed, m.
    pub floor_altitude: f64,
    /// Highest zonal harmonic of the gravity field: 2 (J2 only, the paper's model) up to
    /// [`MAX_ZONAL_DEGREE`] (J2..J6).
    pub zonal_degree: u8,
    /// What acts beside the zonals and drag: the field, the Sun and the Moon, the Sun's
    /// light.
    pub forces: Forces,
}

/// The terms of the dynamics beyond the zonals and drag. For the field and the third
/// bodies `None` is automatic: both on for deep-space orbits
/// ([`crate::dynamics::deep_space`]), both off near the Earth, as SGP4 switches to SDP4
/// (the tesseral field to degree 8); a precise near-Earth prediction asks for them (over
/// a day a 455-km orbit without the field is 4-5 km off its precise orbit). Radiation
/// pressure acts where the object has a radiation parameter.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Forces {
    /// Degree and order of the EGM2008 field beyond the run's zonals: every harmonic of
    /// order m >= 1 and the zonals above the zonal degree, up to this degree; 0 (none)
    /// or 2 to [`MAX_TESSERAL_DEGREE`].
    pub field_degree: Option<u8>,
    /// Whether the Sun's and the Moon's pull act.
    pub third_bodies: Option<bool>,
    /// Radiation parameter Cr A / m, m^2/kg, of solar radiation pressure
    /// ([`crate::radiation`]); 0: none.
    pub radiation: f64,
}

impl Forces {
    /// Automatic: what the orbit's regime calls for, and no radiation pressure.
    pub const AUTO: Forces = Forces {
        field_degree: None,
        third_bodies: None,
        radiation: 0.0,
    };

    /// Checks the field degree (0 or 2..=[`MAX_TESSERAL_DEGREE`]) and the radiation
    /// parameter (finite, >= 0).
    pub fn validate(&self) -> Result<(), CoreError> {
        finite("radiation parameter Cr*A/m", self.radiation)?;
        if self.radiation < 0.0 {
            return Err(CoreError::invalid(
                "radiation parameter Cr*A/m",
                self.radiation,
                "it must be >= 0 (0: no radiation pressure)",
            ));
        }
        match self.field_degree {
            Some(d) if d == 1 || usize::from(d) > MAX_TESSERAL_DEGREE => Err(CoreError::invalid(
                "field_degree",
                f64::from(d),
                format!("it must be 0 (none) or 2 to {MAX_TESSERAL_DEGREE}"),
            )),
            _ => Ok(()),
        }
    }
}

impl Problem {
    /// Checks a finite epoch, a positive drag parameter, a finite floor and an initial
    /// state that is finite and above both the surface and the floor, and a zonal degree
    /// in 2..=[`MAX_ZONAL_DEGREE`].
    pub fn validate(&self) -> Result<(), CoreError> {
        finite("epoch", self.epoch)?;
        positive("drag parameter Cd*A/m", self.drag)?;
        finite("floor_altitude", self.floor_altitude)?;
        if !(2..=MAX_ZONAL_DEGREE).contains(&self.zonal_degree) {
            return Err(CoreError::invalid(
                "zonal_degree",
                f64::from(self.zonal_degree),
                format!("it must be 2 (J2 only) to {MAX_ZONAL_DEGREE} (J2..J{MAX_ZONAL_DEGREE})"),
            ));
        }
        self.forces.validate()?;
        check_state(self.epoch, &self.y0, self.floor_altitude)
    }
}

/// Largest accepted relative 1-sigma (log-sigma) of the drag parameter: e^3 = 20x per
/// sigma is far past any physical uncertainty of Cd*A/m.
pub const MAX_DRAG_SIGMA: f64 = 3.0;

/// Checks the relative 1-sigma of the drag parameter (`drag_sigma` of the Monte Carlo
/// and the CCSP): finite, >= 0 and at most [`MAX_DRAG_SIGMA`].
pub fn check_drag_sigma(drag_sigma: f64) -> Result<f64, CoreError> {
    finite("drag_sigma", drag_sigma)?;
    if !(0.0..=MAX_DRAG_SIGMA).contains(&drag_sigma) {
        return Err(CoreError::invalid(
            "drag_sigma",
            drag_sigma,
            format!(
                "it is the relative 1-sigma of Cd*A/m (log-normal; 0.1 = 10 %) and must be \
                 0 to {MAX_DRAG_SIGMA}"
            ),
        ));
    }
    Ok(drag_sigma)
}

/// The factor on Cd*A/m of a draw `c` ~ N(0, 1) of the ballistic-coefficient error:
/// exp(`drag_sigma` c), a log-normal with median 1 (so Cd*A/m stays positive, and
/// c = 0 is the nominal value exactly). For small `drag_sigma` it is 1 + drag_sigma c.
#[inline]
pub fn drag_factor(drag_sigma: f64, c: f64) -> f64 {
    if drag_sigma == 0.0 || c == 0.0 {
        1.0
    } else {
        (drag_sigma * c).exp()
    }
}

/// Checks a state at `epoch` (s since J2000): finite, and above the surface and the floor
/// altitude `floor` (m). Also used for the sampled initial states of Monte Carlo members.
pub fn check_state(epoch: f64, y0: &[f64; 6], floor: f64) -> Result<(), CoreError> {
    const NAMES: [&str; 6] = [
        "position[0]",
        "position[1]",
        "position[2]",
        "velocity[0]",
        "velocity[1]",
        "velocity[2]",
    ];
    for (name, &v) in NAMES.iter().zip(y0) {
        finite(name, v)?;
    }
    let alt = altitude(epoch, [y0[0], y0[1], y0[2]]);
    if alt < 0.0 {
        return Err(CoreError::invalid(
            "initial geodetic altitude (m)",
            alt,
            "the position is below the Earth's surface",
        ));
    }
    if alt < floor {
        return Err(CoreError::invalid(
            "initial geodetic altitude (m)",
            alt,
            format!("the position is below the decay floor altitude of {floor} m"),
        ));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    const PAPER: Problem = Problem {
        epoch: 8.4e7,
        y0: crate::constants::PAPER_STATE,
        drag: 3.0912 * 0.0015,
        floor_altitude: DEFAULT_FLOOR_ALTITUDE,
        zonal_degree: 2,
        forces: Forces::AUTO,
    };

    #[test]
    fn each_check_names_its_input() {
        assert!(PAPER.validate().is_ok());
        let bad = |f: fn(&mut Problem)| {
            let mut p = PAPER;
            f(&mut p);
            p.validate().unwrap_err().to_string()
        };
        assert!(bad(|p| p.epoch = f64::NAN).starts_with("epoch must be finite"));
        assert!(bad(|p| p.drag = 0.0).starts_with("drag parameter Cd*A/m = 0 is invalid"));
        assert!(bad(|p| p.floor_altitude = f64::INFINITY).starts_with("floor_altitude"));
        assert!(bad(|p| p.y0[4] = f64::NAN).contains("velocity[1]"));
        assert!(
            bad(|p| p.y0 = [1e6, 0.0, 0.0, 0.0, 7e3, 0.0]).contains("below the Earth's surface")
        );
        assert!(bad(|p| p.floor_altitude = 450e3).contains("decay floor altitude of 450000 m"));
        assert!(bad(|p| p.zonal_degree = 7).starts_with("zonal_degree = 7 is invalid"));
        assert!(bad(|p| p.zonal_degree = 1).contains("2 (J2 only) to 6"));
        assert!(bad(|p| p.forces.field_degree = Some(41))
            .starts_with("field_degree = 41 is invalid: it must be 0 (none) or 2 to 40"));
        assert!(bad(|p| p.forces.field_degree = Some(1)).starts_with("field_degree = 1"));
        assert!(bad(|p| p.forces.radiation = -0.01)
            .starts_with("radiation parameter Cr*A/m = -0.01 is invalid: it must be >= 0"));
        assert!(bad(|p| p.forces.radiation = f64::NAN).contains("must be finite"));
        assert_eq!(check_drag_sigma(0.0), Ok(0.0));
        assert_eq!(check_drag_sigma(0.15), Ok(0.15));
        assert!(check_drag_sigma(-0.1)
            .unwrap_err()
            .to_string()
            .starts_with("drag_sigma = -0.1 is invalid"));
        assert!(check_drag_sigma(f64::NAN).is_err());
        assert!(check_drag_sigma(4.0).is_err());
        assert_eq!(drag_factor(0.0, 1.3), 1.0);
        assert_eq!(drag_factor(0.2, 0.0), 1.0);
        assert!((drag_factor(0.2, -1.0) - (-0.2f64).exp()).abs() < 1e-16);
        let mut j6 = PAPER;
        j6.zonal_degree = 6;
        assert!(j6.validate().is_ok());
    }
}
