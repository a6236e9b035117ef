//! Errors of the control layer.

use thiserror::Error;

/// A controller or actuator parameter that cannot work, with its name and the rule.
#[derive(Debug, Clone, PartialEq, Error)]
#[non_exhaustive]
pub enum ControlError {
    /// A parameter out of its range.
    #[error("{name} = {value}: {rule}")]
    InvalidParameter {
        /// The parameter's key (`kp`, `lead`, ...).
        name: &'static str,
        /// Its value.
        value: f64,
        /// What it must be.
        rule: &'static str,
    },
    /// A law's computation failed at a sample (a law in another language raised, or
    /// returned a command that is not a number).
    #[error("at the sample t = {t} s the control law failed: {message}")]
    LawFailed {
        /// The sample time (s).
        t: f64,
        /// What went wrong (for a Python law, its traceback).
        message: String,
    },
}

/// `value` if it is finite and at least `min` (strictly above when `strict`), else the error.
/// `value` when it is at most `max`; else the parameter `name` with its `rule` (the upper
/// bound of a parameter whose lower bound [`check`] tested).
pub(crate) fn at_most(
    name: &'static str,
    value: f64,
    max: f64,
    rule: &'static str,
) -> Result<f64, ControlError> {
    if value > max {
        Err(ControlError::InvalidParameter { name, value, rule })
    } else {
        Ok(value)
    }
}

pub(crate) fn check(
    name: &'static str,
    value: f64,
    min: f64,
    strict: bool,
    rule: &'static str,
) -> Result<f64, ControlError> {
    let ok = value.is_finite() && if strict { value > min } else { value >= min };
    if ok {
        Ok(value)
    } else {
        Err(ControlError::InvalidParameter { name, value, rule })
    }
}
