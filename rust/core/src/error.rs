//! Errors of the core. Every message says what was wrong and where, so the binding can
//! pass it to the user unchanged.

use thiserror::Error;

/// Everything that can go wrong in the core.
#[derive(Debug, Clone, PartialEq, Error)]
pub enum CoreError {
    /// An input value is NaN or infinite.
    #[error("{name} must be finite, got {value}")]
    NonFinite { name: String, value: f64 },
    /// An input value is outside its valid range.
    #[error("{name} = {value} is invalid: {reason}")]
    Invalid {
        name: String,
        value: f64,
        reason: String,
    },
    /// An input that is wrong as a whole (no single value to show).
    #[error("{name} is invalid: {reason}")]
    Rejected { name: String, reason: String },
    /// A name that is not one of the known choices.
    #[error("unknown {what} {name:?}; expected one of {}", .expected.join(", "))]
    UnknownName {
        what: &'static str,
        name: String,
        expected: &'static [&'static str],
    },
    /// An array has the wrong length or shape.
    #[error("{name} has the wrong shape: {reason}")]
    Shape { name: String, reason: String },
    /// A density lookup fell outside the sampled field.
    #[error(
        "density field does not cover {axis} = {value} (field covers {min} to {max}) \
         at t = {t} s from the epoch (a sampled model's atlas starts at the model's lowest \
         altitude and covers the drivers' span; a user grid covers what it was given)"
    )]
    OutsideField {
        axis: &'static str,
        value: f64,
        min: f64,
        max: f64,
        t: f64,
    },
    /// A CCSP covariance is not positive definite (near decay, or a bad initial one).
    #[error(
        "{what} at t = {t} s is not positive definite (smallest eigenvalue \
         {min_eigenvalue}){hint}"
    )]
    NotPositiveDefinite {
        what: &'static str,
        t: f64,
        min_eigenvalue: f64,
        hint: &'static str,
    },
    /// The adaptive integrator could not meet its tolerance.
    #[error("adaptive integrator: step size underflow at t = {t} s (h = {h} s)")]
    StepUnderflow { t: f64, h: f64 },
    /// The adaptive integrator needed more steps than allowed.
    #[error(
        "adaptive integrator: more than {max_steps} steps before t = {t} s of a run to \
         {end} s (the limit: 1,000,000 or one per 10 s of the run; steps that small mean \
         the orbit or the field needs them, e.g. an object near decay or a density jump)"
    )]
    TooManySteps { max_steps: usize, t: f64, end: f64 },
    /// The run was cancelled by the caller (e.g. Ctrl-C).
    #[error("cancelled")]
    Cancelled,
}

impl CoreError {
    /// Error for a value that must be finite.
    pub fn non_finite(name: impl Into<String>, value: f64) -> Self {
        CoreError::NonFinite {
            name: name.into(),
            value,
        }
    }

    /// Error for a value outside its valid range.
    pub fn invalid(name: impl Into<String>, value: f64, reason: impl Into<String>) -> Self {
        CoreError::Invalid {
            name: name.into(),
            value,
            reason: reason.into(),
        }
    }

    /// Error for an input that is wrong as a whole, with no one value to quote.
    pub fn rejected(name: impl Into<String>, reason: impl Into<String>) -> Self {
        CoreError::Rejected {
            name: name.into(),
            reason: reason.into(),
        }
    }

    /// Error for an array of the wrong shape.
    pub fn shape(name: impl Into<String>, reason: impl Into<String>) -> Self {
        CoreError::Shape {
            name: name.into(),
            reason: reason.into(),
        }
    }
}

/// Checks that `value` is finite.
pub fn finite(name: &str, value: f64) -> Result<f64, CoreError> {
    if value.is_finite() {
        Ok(value)
    } else {
        Err(CoreError::non_finite(name, value))
    }
}

/// Checks that `value` is finite and strictly positive.
pub fn positive(name: &str, value: f64) -> Result<f64, CoreError> {
    finite(name, value)?;
    if value > 0.0 {
        Ok(value)
    } else {
        Err(CoreError::invalid(name, value, "must be > 0"))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn messages_name_the_value() {
        let e = positive("cd", -1.0).unwrap_err();
        assert_eq!(e.to_string(), "cd = -1 is invalid: must be > 0");
        let e = finite("position[0]", f64::NAN).unwrap_err();
        assert_eq!(e.to_string(), "position[0] must be finite, got NaN");
    }
}
