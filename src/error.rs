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
    /// Optimisation parameters that cannot act on the objective (e.g. a control force at a node
    /// the supports lock): moving them across their whole range changes J by round-off only, so
    /// an optimiser would chase round-off to absurd values (see
    /// `optimize::problem::ineffective_params`).
    #[error(
        "parameter(s) {params:?} have no effect on the objective J = {objective:.6e}: across the \
         resolved range they change J by at most {relative_change:.1e} of itself (round-off); is \
         the control at a node the supports lock (e.g. the tip of a fixed-fixed beam)?"
    )]
    NoEffect {
        /// Indices of the parameters without effect.
        params: Vec<usize>,
        /// J at the start point.
        objective: f64,
        /// The largest first- plus second-order relative change of J they predict.
        relative_change: f64,
    },
    /// A control force beyond what the time grid resolves (see
    /// `optimize::problem::resolved_control_limit`: π m l / h², the force that turns the control
    /// node's link half a turn per step).
    #[error(
        "control u_{index} = {value:.6e} N is outside the range the time step resolves, \
         |u| <= {limit:.4e} N (pi m l / h^2 at the control node); use smaller forces or a \
         smaller step"
    )]
    ControlOutOfRange {
        /// Step index k of the force u_k.
        index: usize,
        /// The force.
        value: f64,
        /// The resolved limit.
        limit: f64,
    },
    /// An objective, gradient or Hessian-vector product handed to the optimiser is NaN or
    /// infinite.
    #[error("the optimiser was handed a non-finite {quantity} (NaN or infinity)")]
    NonFiniteObjective {
        /// Which quantity: "objective", "gradient" or "Hessian-vector product".
        quantity: &'static str,
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
