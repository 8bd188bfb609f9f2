//! Errors of the structured optimal-control solvers (Riccati and condensed, [`crate::ocp`]).

use super::requirement::ValueError;
use crate::base::TipCondition;
use thiserror::Error;

/// An option, a problem or an argument the structured solvers of [`crate::ocp`] refuse. `Display`
/// says what is wrong; [`OcpError::argument`] names the option or argument, and the crate's
/// [`Error::Ocp`](super::Error::Ocp) puts both together (e.g. "invalid argument `backtracks`:
/// must be at least 1").
#[derive(Debug, Error, Clone, PartialEq)]
#[non_exhaustive]
pub enum OcpError {
    /// The box [lower, upper] of [`OcpOptions`](crate::ocp::OcpOptions) holds no number: NaN
    /// ends, lower ≥ upper, lower = +∞ or upper = −∞.
    #[error("need lower < upper (not NaN) and a box that is not empty, got [{lower}, {upper}]")]
    EmptyBox {
        /// The lower bound.
        lower: f64,
        /// The upper bound.
        upper: f64,
    },
    /// A number of [`OcpOptions`](crate::ocp::OcpOptions) (`rate_penalty`, `rel_grad_tol`,
    /// `grad_tol`, `armijo`, `max_regularisation`) outside its range, or a count (`backtracks`)
    /// of zero.
    #[error(transparent)]
    Value(#[from] ValueError),
    /// The objective has no Gauss-Newton form ½ w_k r_k(M₀)² + e_k u_k²
    /// ([`Objective::gauss_newton`](crate::Objective::gauss_newton)), which the structured
    /// solvers exploit.
    #[error(
        "{solver} needs an objective in Gauss-Newton form ½ w_k r_k(M₀)² + e_k u_k² (c, c_sum or \
         power, with effort); use lbfgs or trust-region"
    )]
    NoGaussNewtonForm {
        /// The solver, e.g. `the Riccati solver`.
        solver: &'static str,
    },
    /// The objective is the rainflow damage (`[objective] kind = "fatigue"`), a function of the
    /// whole moment history with no Gauss-Newton form: the structured solvers take its smooth
    /// stand-in Σ|M₀|^m instead ([`Objective::power_proxy`](crate::Objective::power_proxy)).
    #[error(
        "{solver} cannot take the rainflow damage ([objective] kind = \"fatigue\", a function of \
         the whole moment history without a Gauss-Newton form): use its smooth stand-in \
         [objective] kind = \"power\", exponent = {exponent} (the S-N curve's slope m) with this \
         method, or --method lbfgs (or trust-region, or auto) for the damage itself"
    )]
    NeedsPowerProxy {
        /// The solver, e.g. `the Riccati solver`.
        solver: &'static str,
        /// The exponent p = m of the proxy.
        exponent: f64,
    },
    /// The objective's Gauss-Newton form has a negative or non-finite weight w_k or effort e_k.
    #[error(
        "{solver}: the objective's Gauss-Newton form has weight {weight} and effort {effort} at \
         stage {stage} (both must be finite and ≥ 0)"
    )]
    InvalidGaussNewtonForm {
        /// The solver.
        solver: &'static str,
        /// The stage k.
        stage: usize,
        /// w_k.
        weight: f64,
        /// e_k.
        effort: f64,
    },
    /// The controls are not per-step or piecewise constant in time on consecutive pieces.
    #[error(
        "the Riccati solver needs controls that are per-step or piecewise constant in time \
         (u_k = θ_j on consecutive pieces j = 0, 1, …)"
    )]
    NotPiecewise,
    /// A tip other than free: a locked or reaction-force tip removes a dimension from the state
    /// manifold that the solvers' tangent coordinates do not.
    #[error(
        "the Riccati solver supports free tips (cantilever, riser) only, got {tip:?}: a locked \
         or reaction-force tip removes a dimension from the state manifold that its tangent \
         coordinates do not"
    )]
    UnsupportedTip {
        /// The problem's tip.
        tip: TipCondition,
    },
    /// The problem has no control node.
    #[error("the problem has no control node")]
    NoControlNode,
    /// A structured solver in the spatial model with an objective that is not a function of the
    /// moment's magnitude |M₀| alone (its stage cost differs for M₀ along x and along z, or it
    /// reads the node positions): the spatial solvers take the vector residual
    /// r_k(|M₀|) M₀/|M₀| of the objective's Gauss-Newton form.
    #[error(
        "{solver} in the spatial model needs an objective of |M₀| alone (c, c_sum or power):          the stage cost at M₀ = {moment} N m along x and along z differs ({along_x} against          {along_z}); use lbfgs or trust-region"
    )]
    AnisotropicObjective {
        /// The solver, e.g. `the condensed Gauss-Newton solver`.
        solver: &'static str,
        /// The magnitude of the moment tried.
        moment: f64,
        /// The stage cost with M₀ along x (NaN for an objective of the positions).
        along_x: f64,
        /// The stage cost with M₀ along z (NaN for an objective of the positions).
        along_z: f64,
    },
    /// A restart ([`Condensed::restart`](crate::ocp::Condensed::restart)) with a problem of
    /// another horizon.
    #[error("a restart needs the solver's horizon {expected}, got {got}")]
    RestartMismatch {
        /// The solver's (N, h, parameters, pendulums).
        expected: HorizonShape,
        /// The problem's.
        got: HorizonShape,
    },
    /// The condensed solver's storage (linear in N × parameters) is over the memory budget
    /// [`MAX_TRAJECTORY_BYTES`](crate::scene::MAX_TRAJECTORY_BYTES).
    #[error(
        "the condensed solver would store {} for N = {steps} steps and {params} parameters \
         (over the memory limit of {}); use the Riccati solver for long per-step horizons",
        crate::scene::human_bytes(*bytes),
        crate::scene::human_bytes(crate::scene::MAX_TRAJECTORY_BYTES)
    )]
    CondensedTooLarge {
        /// The horizon's N.
        steps: usize,
        /// The number of parameters.
        params: usize,
        /// The bytes it would store (saturated at `u64::MAX`).
        bytes: u64,
    },
    /// A stage index k ≥ N.
    #[error("must be below N = {steps}, got {stage}")]
    StageOutOfRange {
        /// The stage given.
        stage: usize,
        /// The horizon's N.
        steps: usize,
    },
    /// A stage QP is unbounded below with the proximal weight μ given.
    #[error("a stage QP is unbounded below with mu = {mu}")]
    UnboundedStage {
        /// The proximal weight μ.
        mu: f64,
    },
    /// The exact second-order model ([`Curvature::Exact`](crate::ocp::Curvature::Exact)) needs
    /// per-step controls without rate penalty and a curvature other than Gauss-Newton.
    #[error(
        "the exact model needs per-step controls without rate penalty and a curvature other \
         than GaussNewton"
    )]
    NoExactModel,
    /// The costate sweep by reverse stage steps needs per-step controls without rate penalty.
    #[error("the costate sweep by reverse steps needs per-step controls without rate penalty")]
    NoReverseSweep,
    /// The linearised rollout needs every stage Jacobian in memory, which the solver did not
    /// keep.
    #[error("the linearised rollout needs every stage Jacobian in memory ({bytes} bytes)")]
    JacobiansNotInMemory {
        /// The bytes they would take.
        bytes: usize,
    },
}

/// A horizon's shape (N, h, parameters, pendulums), compared by a restart.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct HorizonShape {
    /// The number of steps N.
    pub steps: usize,
    /// The step h \[s\].
    pub h: f64,
    /// The number of parameters.
    pub params: usize,
    /// The number of pendulums n.
    pub pendulums: usize,
}

impl std::fmt::Display for HorizonShape {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "(N = {}, h = {} s, {} parameters, {} pendulums)",
            self.steps, self.h, self.params, self.pendulums
        )
    }
}

impl OcpError {
    /// The option or argument at fault: `bounds`, an option's name, `objective`, `control map`,
    /// `tip`, `control node`, `problem`, `method`, `stage`, `mu`, `curvature` or
    /// `jacobian_memory`.
    pub fn argument(&self) -> &'static str {
        match self {
            OcpError::EmptyBox { .. } => "bounds",
            OcpError::Value(v) => v.argument(),
            OcpError::NoGaussNewtonForm { .. }
            | OcpError::InvalidGaussNewtonForm { .. }
            | OcpError::NeedsPowerProxy { .. }
            | OcpError::AnisotropicObjective { .. } => "objective",
            OcpError::NotPiecewise => "control map",
            OcpError::UnsupportedTip { .. } => "tip",
            OcpError::NoControlNode => "control node",
            OcpError::RestartMismatch { .. } => "problem",
            OcpError::CondensedTooLarge { .. } => "method",
            OcpError::StageOutOfRange { .. } => "stage",
            OcpError::UnboundedStage { .. } => "mu",
            OcpError::NoExactModel | OcpError::NoReverseSweep => "curvature",
            OcpError::JacobiansNotInMemory { .. } => "jacobian_memory",
        }
    }
}
