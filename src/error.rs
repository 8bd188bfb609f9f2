//! Typed errors. Each algorithm reports what went wrong with the data needed to act on it
//! (the step, the residual, the joint), never a sentinel value or a bare string.

use thiserror::Error;

pub use crate::scene::SceneError;

/// Errors from simulation, differentiation and optimisation.
#[derive(Debug, Error, Clone, PartialEq)]
#[non_exhaustive]
pub enum Error {
    /// The scene is invalid (names the key and the reason).
    #[error(transparent)]
    Scene(#[from] SceneError),
    /// The Newton iteration for the RATTLE multipliers λ did not converge.
    #[error(
        "RATTLE Newton solve did not converge at step {step} (t = {time} s): constraint residual \
         {residual:.3e} after {iterations} iterations (the step size may be too large for the \
         stiffness, or the beam is folding)"
    )]
    NewtonNotConverged {
        /// Step index k of the step q_k → q_{k+1}.
        step: usize,
        /// Time t_k.
        time: f64,
        /// Max-norm of the constraint residual at the last iterate.
        residual: f64,
        /// Newton iterations performed.
        iterations: usize,
    },
    /// A joint angle reached the fold limit (θ → π): the chain has folded over itself and the
    /// spring force θ/sin θ is unbounded (thesis §2.2.2, after eq. 2.2.1).
    #[error(
        "the beam folds over at step {step}: joint {joint} has angle {angle_deg:.2}° \
         (limit {limit_deg:.2}°)"
    )]
    Folded {
        /// Step index at which the folded configuration was met.
        step: usize,
        /// Joint index i (the spring between q_{i−1} and q_i), 1..=n+1.
        joint: usize,
        /// The joint angle in degrees.
        angle_deg: f64,
        /// The configured fold limit in degrees.
        limit_deg: f64,
    },
    /// A pivot of a tridiagonal constraint system vanished.
    #[error("singular constraint system at step {step} (pivot {index} is {pivot:.3e})")]
    SingularSystem {
        /// Step index.
        step: usize,
        /// Zero-based pivot index.
        index: usize,
        /// The pivot value.
        pivot: f64,
    },
    /// The state became non-finite (NaN or infinity).
    #[error("non-finite state at step {step}")]
    NonFinite {
        /// Step index.
        step: usize,
    },
    /// The static-equilibrium Newton solve ([`crate::statics`]) did not converge.
    #[error(
        "static equilibrium: Newton did not converge in {iterations} iterations (residual \
         {residual:.3e}); the loads may buckle or fold the beam"
    )]
    StaticNotConverged {
        /// Iterations performed.
        iterations: usize,
        /// Final scaled gradient residual.
        residual: f64,
    },
    /// The static Newton matrix was singular.
    #[error("static equilibrium: singular Newton matrix at iteration {iteration}")]
    StaticSingular {
        /// The Newton iteration.
        iteration: usize,
    },
    /// An argument passed to the API is inconsistent with the scene.
    #[error("invalid argument `{name}`: {reason}")]
    InvalidArgument {
        /// The argument's name.
        name: &'static str,
        /// What is wrong with it.
        reason: String,
    },
}

/// Result alias for chainbeam.
pub type Result<T, E = Error> = std::result::Result<T, E>;
