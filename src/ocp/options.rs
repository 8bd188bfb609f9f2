//! Options and results of the Riccati solver.

use crate::error::{OcpError, Requirement, Result, ValueError};

/// Options of [`solve`](super::solve). Build with struct update syntax or [`OcpOptions::with_bound`].
#[derive(Clone, Debug, PartialEq)]
pub struct OcpOptions {
    /// Lower bound on every θ (force, N). Default −∞.
    pub lower: f64,
    /// Upper bound on every θ. Default +∞.
    pub upper: f64,
    /// σ ≥ 0 of the rate penalty (σ/h) Σ (u_k − u_{k−1})² = σh Σ ((u_k − u_{k−1})/h)². Default 0.
    pub rate_penalty: f64,
    /// Iterations (accepted steps). Default 200.
    pub max_iters: usize,
    /// Stop when the projected gradient ≤ `rel_grad_tol`·‖g₀‖. Default 10⁻⁸.
    pub rel_grad_tol: f64,
    /// Stop when the projected gradient ≤ `grad_tol`. Default 0 (off).
    pub grad_tol: f64,
    /// c of the acceptance test J̄ − J(α) ≥ c·(−ΔJ(α)). Default 0.1.
    pub armijo: f64,
    /// Step lengths tried per step (α = 1, then quadratic interpolation within [α/10, α/2]).
    /// Default 10.
    pub backtracks: usize,
    /// Largest relative proximal weight μ/mean(Q_uu) before giving up. Default 10¹⁰.
    pub max_regularisation: f64,
    /// Bytes the stage Jacobians may occupy; beyond it they are recomputed per block in every
    /// backward pass. Default 1 GiB.
    pub jacobian_memory: usize,
    /// Threads for the stage Jacobians; 0 = rayon's pool size. Default 0.
    pub threads: usize,
    /// Whether a run that spends its [`max_iters`](Self::max_iters) evaluates the gradient at
    /// its last iterate (one more pass of stage Jacobians and costates) to report it. Default
    /// `true`. `false` is the real-time iteration of a receding-horizon controller, which only
    /// needs the step: the run then ends with [`OcpTermination::Budget`], and the result's
    /// gradient norms are those at the start of the last iteration (the last point where the
    /// gradient was evaluated). Measured on `mpc_riser` with one iteration per re-plan, this
    /// halves the Jacobian passes (2 → 1 per re-plan).
    pub final_gradient: bool,
    /// The curvature of the step's model ([`Curvature`]). Default [`Curvature::Auto`].
    pub curvature: Curvature,
}

/// The second-order model of the Riccati solver's step.
///
/// Gauss-Newton keeps from the Hessian of J only what the linearised trajectory gives
/// (Σ 2c ∇M₀∇M₀ᵀ + effort and rate terms): always positive semidefinite, fast from far away,
/// but only linearly convergent where the residual M₀ stays large at the optimum (the long
/// riser: 16 of 23 iterations for the last 10⁻⁵ of J). The exact model adds the stage maps'
/// curvature weighted by the costates and the moment's own curvature (`ocp::hessian`): the
/// Newton step of J(u), quadratically convergent near a minimum, computed by forward-over-
/// reverse dual numbers through the same step (about the cost of the stage Jacobians again).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Curvature {
    /// Gauss-Newton throughout.
    GaussNewton,
    /// The exact Hessian of J throughout (Newton).
    Exact,
    /// Gauss-Newton while its steps are taken in full and predicted well (actual over
    /// predicted decrease ≥ 0.5), the exact Hessian from the first step that is not.
    #[default]
    Auto,
}

impl Default for OcpOptions {
    fn default() -> Self {
        OcpOptions {
            lower: f64::NEG_INFINITY,
            upper: f64::INFINITY,
            rate_penalty: 0.0,
            max_iters: 200,
            rel_grad_tol: 1e-8,
            grad_tol: 0.0,
            armijo: 0.1,
            backtracks: 10,
            max_regularisation: 1e10,
            jacobian_memory: 1 << 30,
            threads: 0,
            final_gradient: true,
            curvature: Curvature::Auto,
        }
    }
}

impl OcpOptions {
    /// The symmetric box |θ| ≤ `b`.
    pub fn with_bound(mut self, b: f64) -> Self {
        self.lower = -b;
        self.upper = b;
        self
    }

    /// Checks every field ([`OcpError`] naming it: [`OcpError::EmptyBox`],
    /// [`ValueError::OutOfRange`], [`ValueError::Zero`] in [`OcpError::Value`]).
    pub fn validate(&self) -> Result<()> {
        let (lower, upper) = (self.lower, self.upper);
        if lower.is_nan() || upper.is_nan() || lower >= upper {
            return Err(OcpError::EmptyBox { lower, upper }.into());
        }
        if lower == f64::INFINITY || upper == f64::NEG_INFINITY {
            return Err(OcpError::EmptyBox { lower, upper }.into());
        }
        for (name, requirement, value) in [
            (
                "rate_penalty",
                Requirement::FiniteNonNegative,
                self.rate_penalty,
            ),
            (
                "rel_grad_tol",
                Requirement::FiniteNonNegative,
                self.rel_grad_tol,
            ),
            ("grad_tol", Requirement::FiniteNonNegative, self.grad_tol),
            ("armijo", Requirement::OpenUnitInterval, self.armijo),
        ] {
            requirement.check(name, value).map_err(OcpError::from)?;
        }
        ValueError::check_count("backtracks", self.backtracks).map_err(OcpError::from)?;
        Requirement::PositiveFinite
            .check("max_regularisation", self.max_regularisation)
            .map_err(OcpError::from)?;
        Ok(())
    }
}

/// Why a run stopped.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum OcpTermination {
    /// The projected gradient met the tolerance.
    Converged,
    /// [`OcpOptions::max_iters`] accepted steps without convergence.
    MaxIterations,
    /// [`OcpOptions::max_iters`] accepted steps with [`OcpOptions::final_gradient`] off: a
    /// real-time iteration's budget, spent as asked; whether the last iterate is stationary was
    /// not evaluated (not converged).
    Budget,
    /// No step length was accepted even with the regularisation at its limit.
    RegularisationLimit,
    /// Several steps in a row predicted a decrease below J's round-off while the gradient
    /// stayed above the tolerance.
    RoundOff,
    /// The iteration observer asked to stop
    /// ([`Solver::solve_observed`](super::Solver::solve_observed),
    /// [`Condensed::solve_observed`](super::Condensed::solve_observed)); the gradient norms of
    /// the result are those of the last evaluation, before the last step (not converged).
    Stopped,
}

impl std::fmt::Display for OcpTermination {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            OcpTermination::Converged => "converged (projected gradient below the tolerance)",
            OcpTermination::MaxIterations => "iteration limit reached",
            OcpTermination::Budget => {
                "iteration budget spent (final gradient not evaluated: real-time iteration)"
            }
            OcpTermination::RegularisationLimit => {
                "no descent step found with the regularisation at its limit"
            }
            OcpTermination::RoundOff => "predicted decrease below the round-off of J",
            OcpTermination::Stopped => "stopped by the iteration observer",
        })
    }
}

/// One accepted iteration.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct IterationRecord {
    /// J after the step.
    pub objective: f64,
    /// Projected gradient before the step.
    pub projected_gradient_norm: f64,
    /// The accepted step length.
    pub alpha: f64,
    /// Relative proximal weight μ/mean(Q_uu) of the accepted step.
    pub regularisation: f64,
}

/// One accepted iteration as an observer of
/// [`Solver::solve_observed`](super::Solver::solve_observed) or
/// [`Condensed::solve_observed`](super::Condensed::solve_observed) sees it, after the step.
#[derive(Clone, Copy, Debug)]
pub struct IterationReport<'a> {
    /// The iteration's number, from 1.
    pub iteration: usize,
    /// θ after the step (the new nominal).
    pub theta: &'a [f64],
    /// J after the step, the projected gradient before it, the step length and the
    /// regularisation (the record the result's history keeps).
    pub record: &'a IterationRecord,
}

/// The observer of a structured solve: called after every accepted iteration;
/// [`ControlFlow::Break`](std::ops::ControlFlow::Break) ends the run with
/// [`OcpTermination::Stopped`] at the point reached.
pub type IterationObserver<'a> =
    &'a mut dyn FnMut(&IterationReport<'_>) -> std::ops::ControlFlow<()>;

/// The outcome of [`solve`](super::solve).
#[derive(Clone, Debug, PartialEq)]
pub struct OcpResult {
    /// J at the result (including the rate penalty, if any).
    pub objective: f64,
    /// J at the (projected) start.
    pub initial_objective: f64,
    /// The parameters θ.
    pub theta: Vec<f64>,
    /// The forces u_0..u_N (their z components for a 2-axis control).
    pub controls: Vec<f64>,
    /// The x components u_{x,0..N} of a 2-axis control (spatial model; empty otherwise).
    pub controls_x: Vec<f64>,
    /// ‖∇J(θ)‖₂ at the result (not zero at active bounds); after [`OcpTermination::Budget`], at
    /// the start of the last iteration.
    pub gradient_norm: f64,
    /// ‖θ − Π_box(θ − ∇J)‖₂ at the result: the first-order optimality measure; after
    /// [`OcpTermination::Budget`], at the start of the last iteration.
    pub projected_gradient_norm: f64,
    /// ‖∇J(θ₀)‖₂ at the start.
    pub initial_gradient_norm: f64,
    /// Indices of θ on a bound.
    pub active_bounds: Vec<usize>,
    /// Accepted iterations.
    pub iterations: usize,
    /// Rollouts (forward simulations of the whole horizon, line-search trials included).
    pub rollouts: usize,
    /// Passes computing the stage Jacobians of the whole horizon.
    pub jacobian_passes: usize,
    /// Riccati passes (interior-point iterations of the QPs, and fallback passes).
    pub backward_passes: usize,
    /// Wall-clock seconds.
    pub seconds: f64,
    /// Whether the projected-gradient test stopped the run.
    pub converged: bool,
    /// Why the run stopped.
    pub termination: OcpTermination,
    /// One record per accepted iteration.
    pub history: Vec<IterationRecord>,
}
