//! Errors of a horizon's start ([`crate::adjoint::Start`]).

use thiserror::Error;

/// A start state S₀ that a horizon cannot begin from.
#[derive(Debug, Error, Clone, PartialEq)]
#[non_exhaustive]
pub enum StartError {
    /// A pending control half-kick ([`crate::adjoint::StartKick::Pending`]) applies the control as
    /// a force term, which the reaction-force tip's control is not (it drives the tip target,
    /// eq. 3.2.1).
    #[error(
        "invalid argument `start kick`: a pending control half-kick needs the control as a force \
         term; the reaction-force tip's control drives the tip target (eq. 3.2.1)"
    )]
    PendingKickWithReactionTip,
    /// The state is off the constraint manifold: ĝ(q) = 0 and Ĝ(q) M⁻¹ p = 0 fail by more than
    /// the tolerance ([`crate::adjoint::START_TOLERANCE`]).
    #[error(
        "invalid argument `initial state`: not on the constraint manifold: position residual \
         {position:.3e}, velocity residual {velocity:.3e} (relative), tolerance {tolerance:e}"
    )]
    OffManifold {
        /// The max-norm of the position constraints ĝ(q) (the lengths and a held tip).
        position: f64,
        /// The hidden constraints' residual relative to 1 + maxᵢ‖vᵢ‖.
        velocity: f64,
        /// The tolerance both had to meet.
        tolerance: f64,
    },
}
