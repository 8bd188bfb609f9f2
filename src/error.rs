//! Typed errors. Each algorithm reports what went wrong with the data needed to act on it
//! (the step, the residual, the joint), never a sentinel value or a bare string.

use thiserror::Error;

mod model;
mod mpc;
mod multistart;
mod ocp;
mod optimize;
mod requirement;
mod start;
mod stepper;

pub use crate::euler_bernoulli::EulerBernoulliError;
pub use crate::scene::SceneError;
pub use model::ModelError;
pub use mpc::MpcError;
pub use multistart::MultistartError;
pub use ocp::{HorizonShape, OcpError};
pub use optimize::OptimizeError;
pub(crate) use optimize::PLANAR_ONLY;
pub use requirement::{Requirement, ValueError};
pub use start::StartError;
pub use stepper::StepperError;

/// Errors from simulation, differentiation and optimisation.
#[derive(Debug, Error, Clone, PartialEq)]
#[non_exhaustive]
pub enum Error {
    /// The scene is invalid (names the key and the reason).
    #[error(transparent)]
    Scene(#[from] SceneError),
    /// A chain's configuration the model cannot take (the control node, the fold limit).
    #[error(transparent)]
    Model(#[from] ModelError),
    /// An input a stepper or a comparison integrator refuses (the step, the state, the tip).
    #[error(transparent)]
    Stepper(#[from] StepperError),
    /// A horizon's start state the adjoint cannot begin from.
    #[error(transparent)]
    Start(#[from] StartError),
    /// An input of the multistart, the certificate or a landscape out of its range.
    #[error(transparent)]
    Multistart(#[from] MultistartError),
    /// An argument of the Euler-Bernoulli reference beam out of its range.
    #[error(transparent)]
    EulerBernoulli(#[from] EulerBernoulliError),
    /// An argument of the model-predictive controller or its closed loop (the interval, the
    /// horizon, a count or weight); [`MpcError::argument`] names it.
    #[error("invalid argument `{}`: {}", .0.argument(), .0)]
    Mpc(#[from] MpcError),
    /// An option, problem or argument the structured optimal-control solvers refuse (the box,
    /// a tolerance, the objective, the tip, a restart, the memory); [`OcpError::argument`] names
    /// it.
    #[error("invalid argument `{}`: {}", .0.argument(), .0)]
    Ocp(#[from] OcpError),
    /// An option, start or problem the general-purpose optimiser refuses (a tolerance, the
    /// method, the bounds, an infeasible θ₀); [`OptimizeError::argument`] names it.
    #[error("invalid argument `{}`: {}", .0.argument(), .0)]
    Optimize(#[from] OptimizeError),
    /// The fatigue assessment of an objective (`[objective] kind = "fatigue"`) failed: a
    /// non-finite stress, histories of different lengths.
    #[error("fatigue objective: {0}")]
    Fatigue(#[from] crate::fatigue::FatigueError),
    /// The Newton iteration for the constraint multipliers λ of one step (RATTLE's implicit first
    /// half step, eq. 1.6.1; SHAKE's position step) did not reach its tolerance. Almost always the
    /// time step is too large for the stiffness or the loads (the thesis's cantilever fails at
    /// h = 0.02 s, thesis §2.2.4), or the beam is folding: the message says so and names `time.step`.
    #[error(
        "the RATTLE Newton solve for the constraint multipliers failed at step {step} (t = {time} s): \
         the constraint residual {residual:.2e} did not reach the tolerance {tolerance:.0e} in \
         {iterations} iterations; {}",
        newton_advice(*h)
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
        /// The tolerance the residual had to reach ([`crate::steppers::rattle::RattleOptions::tolerance`]).
        tolerance: f64,
        /// The time step h \[s\] of the failing step (`None` for a solve without a time step).
        h: Option<f64>,
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
    /// A pivot of a tridiagonal constraint system vanished (or overflowed): the constraint
    /// gradients of a pendulum before and after the step are (nearly) perpendicular.
    #[error(
        "singular constraint system at step {step} (pivot {index} is {pivot:.3e}): the \
         constraint directions of pendulum {} before and after the step are (nearly) \
         perpendicular, usually because the time step is too large (`time.step`)",
        index + 1
    )]
    SingularSystem {
        /// Step index.
        step: usize,
        /// Zero-based pivot index.
        index: usize,
        /// The pivot value.
        pivot: f64,
    },
    /// A value became non-finite (NaN or infinity). Valid scenes keep every quantity the step
    /// forms finite (docs/scene-format.md, "Valid ranges"), so this means a divergent iteration
    /// or values set past the scene's validation (parameters, controls).
    #[error("non-finite value at step {step}: {quantity} overflowed (NaN or infinity)")]
    NonFinite {
        /// Step index.
        step: usize,
        /// What became non-finite, e.g. `the positions q_{k+1} of the Newton iterate`.
        quantity: &'static str,
    },
    /// A simulation's stored trajectory does not fit in memory: it exceeds the budget
    /// [`crate::scene::MAX_TRAJECTORY_BYTES`], or the allocator refused it.
    #[error(
        "cannot store the trajectory of {steps} steps of {n} pendulums: it needs {} ({bytes} \
         bytes), {}; reduce `time.steps` (at most {max_steps} fit the budget for this beam) or \
         `beam.pendulums`",
        crate::scene::human_bytes(*bytes),
        if *refused {
            "and the allocator refused it (out of memory)".to_string()
        } else {
            format!(
                "over the memory limit of {}",
                crate::scene::human_bytes(crate::scene::MAX_TRAJECTORY_BYTES)
            )
        }
    )]
    TrajectoryTooLarge {
        /// Number of pendulums n.
        n: usize,
        /// Number of steps N.
        steps: usize,
        /// Bytes the trajectory needs.
        bytes: u64,
        /// The largest N whose trajectory fits the budget for this n.
        max_steps: usize,
        /// `true` when under the budget but the allocator refused the memory.
        refused: bool,
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
    /// A static Newton iterate folded the beam (a joint at the fold limit θ → π, thesis §2.2.2):
    /// the loads may be more than the springs can hold, or the iteration left the equilibrium's
    /// basin. (A simulation reports the same event as [`Error::Folded`] with its step.)
    #[error(
        "static equilibrium: the Newton iterate of iteration {iteration} folds the beam: joint \
         {joint} has angle {angle_deg:.2}° (limit {limit_deg:.2}°); the loads may exceed what \
         the springs hold"
    )]
    StaticFolded {
        /// The Newton iteration.
        iteration: usize,
        /// Joint index i (the spring between q_{i−1} and q_i), 1..=n+1.
        joint: usize,
        /// The joint angle in degrees.
        angle_deg: f64,
        /// The configured fold limit in degrees.
        limit_deg: f64,
    },
    /// The spatial statics ([`crate::statics::static_equilibrium_spatial`]) of a beam without end
    /// springs (pinned-pinned): the spatial model locks only the tip's z, so the beam turns
    /// freely about the z axis through its base and has no isolated equilibrium (its Newton
    /// matrix is singular). A planar scene's pinned-pinned statics is solved in the planar model.
    #[error(
        "static equilibrium in the spatial model: a {} beam ({tip:?} tip: only the tip's z is \
         held) has no end springs, so it turns freely about the z axis through its base and has \
         no isolated equilibrium; only a planar scene's {} statics is solved",
        support_name(*support),
        support_name(*support)
    )]
    StaticNotIsolated {
        /// The scene's support.
        support: crate::scene::Support,
        /// How the model holds the tip.
        tip: crate::base::TipCondition,
    },
    /// `[time] initial = "static"`: the static equilibrium the run starts from
    /// ([`crate::statics::static_start`]) was not found (its statics' error).
    #[error(
        "key `time.initial` = \"static\": the static equilibrium of the steady loads at t = 0, \
         the run's start, was not found ({source}); start from `initial = \"rest\"` instead"
    )]
    StaticStart {
        /// The statics' error.
        source: Box<Error>,
    },
    /// `[time] initial = "static"` on a path that cannot start there: a chain built without its
    /// static start ([`crate::statics::set_static_start`]), or a derivative the start's own
    /// dependence would enter.
    #[error("key `time.initial` = \"static\": {reason}")]
    StaticStartRefused {
        /// What cannot start from the static equilibrium, and why.
        reason: &'static str,
    },
    /// The planar model (`Chain<_, 2>`) was asked for a scene with a load out of the yz-plane,
    /// which needs the spatial model (`Chain<_, 3>`; [`crate::simulate()`] chooses it itself).
    #[error(
        "`{key}` has an x component, so the scene needs the spatial model (qᵢ ∈ S², \
         Chain<_, 3>), but this operation uses the planar model: MPC and the Riccati solver are \
         planar for now (simulation, statics, and gradients and optimisation through \
         `ControlProblem::builder` or the command line's gradient, optimize and explore, run \
         spatial scenes)"
    )]
    NeedsSpatialModel {
        /// The first key with an x component, e.g. `loads.point[0].force`.
        key: String,
    },
    /// An input has the wrong number of values.
    #[error("`{name}`: expected {expected} values, got {got}")]
    WrongLength {
        /// The input's name.
        name: &'static str,
        /// The number of values expected.
        expected: usize,
        /// The number given.
        got: usize,
    },
    /// An input value is NaN or infinite.
    #[error("`{name}`: entry {index} is not finite")]
    NotFinite {
        /// The input's name.
        name: &'static str,
        /// Zero-based index of the first non-finite entry.
        index: usize,
    },
    /// A derivative was requested with respect to a parameter the model does not have.
    #[error("{parameter:?} is not a parameter of this scene: {reason}")]
    NoSuchParameter {
        /// The parameter.
        parameter: crate::base::Parameter,
        /// Why (e.g. "the support has no base spring").
        reason: &'static str,
    },
    /// The time step is not positive and finite.
    #[error("the time step must be positive and finite, got h = {h}")]
    InvalidStep {
        /// The step given.
        h: f64,
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
    /// The computation was cancelled through the thread's [`crate::cancel::CancelToken`]
    /// (a front end's Ctrl-C); nothing was returned.
    #[error("the computation was cancelled")]
    Cancelled,
}

impl Error {
    /// The argument, option or input a caller passed wrongly, for the errors that name one
    /// ([`Error::Mpc`], [`Error::Ocp`], [`Error::Optimize`], [`Error::WrongLength`],
    /// [`Error::NotFinite`]); `None`
    /// for the others (a scene's key is [`SceneError::key`]).
    pub fn argument(&self) -> Option<&'static str> {
        match self {
            Error::Mpc(e) => Some(e.argument()),
            Error::Ocp(e) => Some(e.argument()),
            Error::Optimize(e) => Some(e.argument()),
            Error::WrongLength { name, .. } | Error::NotFinite { name, .. } => Some(name),
            _ => None,
        }
    }

    /// For an argument error that names its argument ([`Error::Mpc`], [`Error::Ocp`],
    /// [`Error::Optimize`]): the argument and what is wrong with it, without the "invalid
    /// argument" prefix, so a front end can name its own flag instead (`--interval: …`).
    pub fn argument_fault(&self) -> Option<(&'static str, String)> {
        match self {
            Error::Mpc(e) => Some((e.argument(), e.to_string())),
            Error::Ocp(e) => Some((e.argument(), e.to_string())),
            Error::Optimize(e) => Some((e.argument(), e.to_string())),
            _ => None,
        }
    }
}

/// The advice of [`Error::NewtonNotConverged`].
fn newton_advice(h: Option<f64>) -> String {
    match h {
        Some(h) => format!(
            "try a smaller time step (`time.step` = {h} s now; the step may be too large for the \
             stiffness or the loads), or the beam is folding"
        ),
        None => "the loads may be too large for an equilibrium, or the beam is folding".to_string(),
    }
}

/// The scene-file name of a support (`support = "pinned-pinned"`).
fn support_name(support: crate::scene::Support) -> &'static str {
    support.name()
}

/// Result alias for chainbeam.
pub type Result<T, E = Error> = std::result::Result<T, E>;
