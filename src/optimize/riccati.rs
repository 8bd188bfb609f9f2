//! [`Method::Riccati`]: [`minimize`](super::minimize) hands per-step, piecewise and constant
//! control problems with a bending-moment objective to the structured Gauss-Newton solver of
//! [`crate::ocp`] and reports its result as an [`OptimResult`].
//!
//! The options carry over as: `bound = Some(b)` → the box −b ≤ θ ≤ b, `bounds` → the box
//! L ≤ θ ≤ U (handled exactly by the solver's interior-point QPs, no reparametrisation), `max_iters`, `grad_tol` and
//! `rel_grad_tol` on the *projected* gradient. The argmin-specific options (L-BFGS memory,
//! trust radius, CG, restarts, polish, cost-change and target tests) do not apply; observers are
//! not called (with `progress` the iteration history is printed to stderr at the end).

use super::{Method, OptimOptions, OptimProblem, OptimResult, Termination};
use crate::error::{Error, Result};
use crate::ocp::{self, OcpOptions, OcpResult};

/// The Riccati solver's options for [`OptimOptions`].
pub(crate) fn ocp_options(opts: &OptimOptions) -> Result<OcpOptions> {
    let (lower, upper) = match opts.force_bounds()? {
        Some(b) => (b.lower(), b.upper()),
        None => (f64::NEG_INFINITY, f64::INFINITY),
    };
    Ok(OcpOptions {
        lower,
        upper,
        max_iters: opts.max_iters,
        grad_tol: opts.grad_tol,
        rel_grad_tol: opts.rel_grad_tol,
        ..OcpOptions::default()
    })
}

/// The error for a problem the Riccati solver does not cover.
pub(crate) fn unsupported() -> Error {
    Error::InvalidArgument {
        name: "method",
        reason: "riccati needs a control problem (per-step, piecewise or constant controls) \
                 with a bending-moment objective (c or c_sum, with effort); use lbfgs or \
                 trust-region"
            .into(),
    }
}

/// Runs the Riccati solver on `problem` from θ₀.
pub(crate) fn run<Q: OptimProblem + ?Sized>(
    problem: &Q,
    theta0: &[f64],
    opts: &OptimOptions,
) -> Result<OptimResult> {
    let r = problem
        .riccati(theta0, &ocp_options(opts)?)
        .ok_or_else(unsupported)??;
    if opts.progress {
        for (i, h) in r.history.iter().enumerate() {
            eprintln!(
                "riccati {i:4}  J = {:.12e}  |pg| = {:.3e}  alpha = {:.3}",
                h.objective, h.projected_gradient_norm, h.alpha
            );
        }
    }
    Ok(result(r, opts))
}

/// The [`OptimResult`] of an [`OcpResult`].
fn result(r: OcpResult, opts: &OptimOptions) -> OptimResult {
    let tolerance_met = r.projected_gradient_norm <= opts.grad_tol;
    let termination = match r.termination {
        ocp::Termination::Converged if tolerance_met => Termination::GradientTolerance {
            gradient_norm: r.projected_gradient_norm,
            tolerance: opts.grad_tol,
        },
        ocp::Termination::Converged => Termination::RelativeGradientTolerance {
            gradient_norm: r.projected_gradient_norm,
            initial: r.initial_gradient_norm,
            tolerance: opts.rel_grad_tol,
        },
        // `minimize` keeps `final_gradient` on; a budget is an iteration limit all the same.
        ocp::Termination::MaxIterations | ocp::Termination::Budget => Termination::MaxIterations {
            max_iters: opts.max_iters,
        },
        // No accepted decrease (regularisation at its limit, or below J's round-off).
        ocp::Termination::RegularisationLimit | ocp::Termination::RoundOff => {
            Termination::LineSearchStalled
        }
    };
    OptimResult {
        objective: r.objective,
        controls: r.controls,
        gradient_norm: r.gradient_norm,
        initial_gradient_norm: r.initial_gradient_norm,
        projected_gradient_norm: r.projected_gradient_norm,
        active_bounds: r.active_bounds,
        theta: r.theta,
        iterations: r.iterations,
        cost_evals: r.rollouts,
        gradient_evals: r.jacobian_passes,
        hvp_evals: 0,
        failed_evals: 0,
        restarts: 0,
        polish_steps: 0,
        polish_error: None,
        seconds: r.seconds,
        converged: termination.is_converged(),
        termination,
        method: Method::Riccati,
    }
}
