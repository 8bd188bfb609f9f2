//! What a number of an option or an argument must be ([`Requirement`]), shared by the per-area
//! errors' `OutOfRange` variants.

use std::fmt;

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
