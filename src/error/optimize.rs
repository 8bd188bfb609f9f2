//! Errors of the general-purpose optimiser's options, starts and problems
//! ([`crate::optimize`]).

use super::requirement::ValueError;
use thiserror::Error;

/// The refusal of a structured solver (riccati, condensed) on a spatial problem.
pub(crate) const PLANAR_ONLY: &str = "the Riccati solver is planar only (its tangent coordinates \
                                      are those of the yz-plane); use --method condensed (which \
                                      takes the spatial model), auto (the default), lbfgs or \
                                      trust-region";

/// An option, a start or a problem [`crate::optimize`] refuses. `Display` says what is wrong;
/// [`OptimizeError::argument`] names the option or argument, and the crate's
/// [`Error::Optimize`](super::Error::Optimize) puts both together (e.g. "invalid argument
/// `grad_tol`: must be finite and >= 0, got -1").
#[derive(Debug, Error, Clone, PartialEq)]
#[non_exhaustive]
pub enum OptimizeError {
    /// A method name that is not one of the methods (`Method::from_str`).
    #[error("unknown method `{given}` (expected {expected})")]
    UnknownMethod {
        /// The name given.
        given: String,
        /// The names accepted, e.g. `lbfgs, trust-region, newton-cg, riccati or condensed`.
        expected: &'static str,
    },
    /// A number of [`OptimOptions`](crate::optimize::OptimOptions) (`grad_tol`, `rel_grad_tol`,
    /// `cost_rel_tol`, `first_step`, `trust_radius`, `bound`) outside its range, or a count
    /// (`lbfgs_memory`, `cg_max_iters`) of zero.
    #[error(transparent)]
    Value(#[from] ValueError),
    /// `target_cost` is NaN.
    #[error("must not be NaN")]
    TargetCostNan,
    /// `max_trust_radius` below `trust_radius` or not finite.
    #[error("must be finite and >= trust_radius = {trust_radius}, got {max_trust_radius}")]
    MaxTrustRadius {
        /// The initial trust radius.
        trust_radius: f64,
        /// The maximum given.
        max_trust_radius: f64,
    },
    /// Both a symmetric `bound` and a box `bounds` were set.
    #[error("set either `bound` (symmetric) or `bounds` (a box), not both")]
    BoundAndBox,
    /// A box ([`Bounds::new`](crate::optimize::Bounds::new)) without finite lower < upper (and a
    /// finite width).
    #[error("need finite lower < upper, got lower = {lower}, upper = {upper}")]
    EmptyBox {
        /// The lower bound.
        lower: f64,
        /// The upper bound.
        upper: f64,
    },
    /// An entry of θ₀ outside the force bounds (an infeasible start).
    #[error(
        "entry {index} = {value} lies outside the force bounds {} (infeasible start)",
        describe(*lower, *upper)
    )]
    InfeasibleStart {
        /// The entry's index.
        index: usize,
        /// Its value.
        value: f64,
        /// The box's lower bound.
        lower: f64,
        /// The box's upper bound.
        upper: f64,
    },
    /// The control map turned bounded parameters into a force beyond the bound.
    #[error(
        "the control map turned bounded parameters into u_{index} = {value} outside {}",
        describe(*lower, *upper)
    )]
    ControlOutsideBound {
        /// The step k of the force u_k.
        index: usize,
        /// The force.
        value: f64,
        /// The box's lower bound.
        lower: f64,
        /// The box's upper bound.
        upper: f64,
    },
    /// The problem's `value_and_gradient` returned a gradient of another length than θ.
    #[error("value_and_gradient returned {got} gradient entries for {expected} parameters")]
    GradientLength {
        /// The gradient's length.
        got: usize,
        /// The number of parameters.
        expected: usize,
    },
    /// A method that needs Hessian-vector products on a problem without them.
    #[error(
        "this solver needs Hessian-vector products, which the problem does not provide \
         (OptimProblem::hessian is None); use lbfgs"
    )]
    NoHessian,
    /// A structured method (riccati, condensed) on a problem that is not a control problem with
    /// per-step, piecewise or constant controls and a bending-moment objective.
    #[error(
        "{method} needs a control problem (per-step, piecewise or constant controls) with an \
         objective in Gauss-Newton form (c, c_sum or power, with effort); use lbfgs or \
         trust-region"
    )]
    NotStructured {
        /// The method's name, e.g. `riccati`.
        method: &'static str,
    },
    /// A structured method (riccati, condensed) on a spatial problem.
    #[error("{}", PLANAR_ONLY)]
    PlanarOnly,
    /// argmin refused the solver's configuration (its message).
    #[error("{message}")]
    SolverConfig {
        /// What argmin reported.
        message: String,
    },
}

impl OptimizeError {
    /// The option or argument at fault: `method`, an option's name, `target_cost`,
    /// `max_trust_radius`, `bound`, `bounds`, `theta0`, `problem` or `opts`.
    pub fn argument(&self) -> &'static str {
        match self {
            OptimizeError::UnknownMethod { .. }
            | OptimizeError::NoHessian
            | OptimizeError::NotStructured { .. }
            | OptimizeError::PlanarOnly => "method",
            OptimizeError::Value(v) => v.argument(),
            OptimizeError::TargetCostNan => "target_cost",
            OptimizeError::MaxTrustRadius { .. } => "max_trust_radius",
            OptimizeError::BoundAndBox | OptimizeError::ControlOutsideBound { .. } => "bound",
            OptimizeError::EmptyBox { .. } => "bounds",
            OptimizeError::InfeasibleStart { .. } => "theta0",
            OptimizeError::GradientLength { .. } => "problem",
            OptimizeError::SolverConfig { .. } => "opts",
        }
    }
}

/// A box as the messages show it: `±b` when symmetric, else `[lower, upper]`.
fn describe(lower: f64, upper: f64) -> String {
    if lower.to_bits() == (-upper).to_bits() {
        format!("±{upper}")
    } else {
        format!("[{lower}, {upper}]")
    }
}
