//! What a number or a count of an option or an argument must be: [`Requirement`] (the range a
//! number must lie in) and [`ValueError`], the one refusal of a value out of its range that the
//! per-area errors ([`OcpError`](super::OcpError), [`OptimizeError`](super::OptimizeError),
//! [`MpcError`](super::MpcError)) wrap with `#[from]`.

use std::fmt;
use thiserror::Error;

/// The range a number must lie in; its `Display` completes "must be …".
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[non_exhaustive]
pub enum Requirement {
    /// Finite and ≥ 0 (a tolerance, a weight).
    FiniteNonNegative,
    /// Positive and finite (a step, a radius).
    PositiveFinite,
    /// Positive; +∞ allowed (a bound where ∞ means none).
    Positive,
    /// In the open interval (0, 1) (a sufficient-decrease constant).
    OpenUnitInterval,
}

impl Requirement {
    /// Whether `x` meets the requirement (NaN never does).
    pub fn holds(self, x: f64) -> bool {
        match self {
            Requirement::FiniteNonNegative => x.is_finite() && x >= 0.0,
            Requirement::PositiveFinite => x.is_finite() && x > 0.0,
            Requirement::Positive => x > 0.0,
            Requirement::OpenUnitInterval => x > 0.0 && x < 1.0,
        }
    }

    /// `Ok` if `value` meets the requirement, else [`ValueError::OutOfRange`] naming `name`.
    ///
    /// # Errors
    /// [`ValueError::OutOfRange`] when [`Requirement::holds`] is false.
    pub fn check(self, name: &'static str, value: f64) -> Result<(), ValueError> {
        if self.holds(value) {
            Ok(())
        } else {
            Err(ValueError::OutOfRange {
                name,
                requirement: self,
                value,
            })
        }
    }
}

impl fmt::Display for Requirement {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            Requirement::FiniteNonNegative => "finite and >= 0",
            Requirement::PositiveFinite => "positive and finite",
            Requirement::Positive => "positive",
            Requirement::OpenUnitInterval => "in (0, 1)",
        })
    }
}

/// A number or a count of an option or argument out of its range. `Display` says what is wrong
/// ("must be finite and >= 0, got -1"); [`ValueError::argument`] names the option, and the
/// per-area error that wraps it (e.g. [`OcpError::Value`](super::OcpError::Value)) is named by
/// the crate's error ("invalid argument `grad_tol`: must be finite and >= 0, got -1").
#[derive(Debug, Error, Clone, Copy, PartialEq)]
#[non_exhaustive]
pub enum ValueError {
    /// A number outside its range.
    #[error("must be {requirement}, got {value}")]
    OutOfRange {
        /// The option or argument, e.g. `grad_tol`.
        name: &'static str,
        /// What it must be.
        requirement: Requirement,
        /// The value given.
        value: f64,
    },
    /// A count that must be at least 1 (iterations, a memory, backtracks) of zero.
    #[error("must be at least 1")]
    Zero {
        /// The option or argument, e.g. `iterations`.
        name: &'static str,
    },
}

impl ValueError {
    /// The option or argument at fault.
    pub fn argument(&self) -> &'static str {
        match self {
            ValueError::OutOfRange { name, .. } | ValueError::Zero { name } => name,
        }
    }

    /// `Ok` unless the count is zero.
    ///
    /// # Errors
    /// [`ValueError::Zero`] naming `name` when `count` = 0.
    pub fn check_count(name: &'static str, count: usize) -> Result<(), ValueError> {
        if count == 0 {
            Err(ValueError::Zero { name })
        } else {
            Ok(())
        }
    }
}
