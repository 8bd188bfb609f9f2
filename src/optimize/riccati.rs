//! [`Method::Riccati`] and [`Method::Condensed`]: [`minimize`](super::minimize) hands per-step,
//! piecewise and constant control problems with an objective in Gauss-Newton form
//! ([`Objective::gauss_newton`](crate::Objective::gauss_newton)) to the structured
//! Gauss-Newton solvers of [`crate::ocp`] (the Riccati solver, or the condensed one) and
//! reports their result as an [`OptimResult`].
//!
//! The options carry over as: `bound = Some(b)` → the box −b ≤ θ ≤ b, `bounds` → the box
//! L ≤ θ ≤ U (handled exactly by the solver's interior-point QPs, no reparametrisation), `max_iters`, `grad_tol` and
//! `rel_grad_tol` on the *projected* gradient. The argmin-specific options (L-BFGS memory,
//! trust radius, CG, restarts, polish, cost-change and target tests) do not apply; observers are
//! not called (with `progress` the iteration history is printed to stderr at the end). A run
//! that stalls short of the tolerance is finished by the trust region
//! ([`finish_by_trust_region`]).

use super::{
    ineffective_params, ArgminAdapter, Method, OptimOptions, OptimProblem, OptimResult, Termination,
};
use crate::error::{Error, OptimizeError, Result};
use crate::ocp::{self, OcpOptions, OcpResult};

/// The options of [`crate::ocp::solve`] that [`minimize`](super::minimize) derives from
/// [`OptimOptions`] for [`Method::Riccati`] (the box, `max_iters`, the gradient tolerances,
/// the curvature);
/// re-exported as `optimize::riccati_options`.
///
/// # Errors
/// [`OptimizeError`](crate::error::OptimizeError) for an invalid bound.
pub fn ocp_options(opts: &OptimOptions) -> Result<OcpOptions> {
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
        curvature: opts.curvature,
        ..OcpOptions::default()
    })
}

/// The error for a problem the structured solvers (`method`: riccati or condensed) do not
/// cover.
pub(crate) fn unsupported(method: Method) -> Error {
    OptimizeError::NotStructured {
        method: method.name(),
    }
    .into()
}

/// The start checks of the argmin methods (module docs of [`super`], "Checks at the start") for
/// the structured solvers, which would not make them otherwise: θ₀ within the force box
/// ([`OptimizeError::InfeasibleStart`]), within the problem's resolved range
/// ([`OptimProblem::check_range`]), and some parameter with an effect ([`Error::NoEffect`]).
/// One evaluation of J and ∇J at θ₀ (and Hessian-vector products for parameters with a zero
/// gradient).
pub(crate) fn check_start_point<Q: OptimProblem + ?Sized>(
    problem: &Q,
    theta0: &[f64],
    opts: &OptimOptions,
) -> Result<()> {
    let adapter = ArgminAdapter::with_bounds(problem, opts.force_bounds()?);
    let phi0 = adapter.to_phi(theta0)?;
    let theta = adapter.to_theta(&phi0);
    problem.check_range(&theta)?;
    let (value, gradient) = problem.value_and_gradient(&theta)?;
    let check = ineffective_params(problem, &theta, value, &gradient)?;
    if check.refuses(&gradient) {
        return Err(Error::NoEffect {
            params: check.params,
            objective: value,
            relative_change: check.relative_change,
        });
    }
    Ok(())
}

/// Runs the Riccati solver (or, with [`Method::Condensed`], the condensed one) on `problem`
/// from θ₀. The result's objective is J(θ) evaluated by `problem` itself (one simulation), so it
/// is the number `gradient` reports for the same controls, bit for bit (the solver's own value
/// comes from its rollouts and may differ in the last bits); if that simulation fails (the
/// beam folds, RATTLE fails), so does the run, with that error.
pub(crate) fn run<Q: OptimProblem + ?Sized>(
    problem: &Q,
    theta0: &[f64],
    opts: &OptimOptions,
) -> Result<OptimResult> {
    let options = ocp_options(opts)?;
    let r = match opts.method {
        Method::Condensed => problem.condensed(theta0, &options),
        _ => problem.riccati(theta0, &options),
    }
    .ok_or_else(|| unsupported(opts.method))??;
    if opts.progress {
        for (i, h) in r.history.iter().enumerate() {
            eprintln!(
                "{} {i:4}  J = {:.12e}  |pg| = {:.3e}  alpha = {:.3}",
                opts.method, h.objective, h.projected_gradient_norm, h.alpha
            );
        }
    }
    let mut res = result(r, opts);
    // Also the check that the result is a simulation at all: a run that ends where the beam folds
    // or RATTLE fails (the structured solvers' line searches can end there when they do not
    // converge) is that error, not a result.
    res.objective = problem.value(&res.theta)?;
    if res.converged || res.termination != Termination::LineSearchStalled {
        return Ok(res);
    }
    finish_by_trust_region(problem, res, opts)
}

/// The hand-over when the Gauss-Newton iteration stalls short of the tolerance (no accepted
/// decrease with the regularisation at its limit, or decreases below J's round-off): its
/// positive semi-definite model misses negative curvature of J (no effort penalty, or a chain
/// near folding; Table 3.4 rows 1 and 3 with Gauss-Newton throughout stalled until the
/// regularisation learnt to rise with shortened steps, `ocp::globalise`), or the tolerance is
/// below what floating point resolves (`tests/tables.rs` forces the hand-over so). [`minimize`](super::minimize) then continues from
/// its point with the trust region on exact Hessian-vector products (which sees that
/// curvature) and returns *that* result: `method` is [`Method::TrustRegion`], the counts and
/// the time add both phases. Without Hessian-vector products, or if the trust region fails to
/// start, the stalled result is returned as it is (not converged).
fn finish_by_trust_region<Q: OptimProblem + ?Sized>(
    problem: &Q,
    stalled: OptimResult,
    opts: &OptimOptions,
) -> Result<OptimResult> {
    if problem.hessian().is_none() {
        return Ok(stalled);
    }
    let tr = OptimOptions {
        method: Method::TrustRegion,
        ..opts.clone()
    };
    let Ok(mut t) = super::minimize(problem, &stalled.theta, &tr) else {
        return Ok(stalled);
    };
    t.iterations += stalled.iterations;
    t.cost_evals += stalled.cost_evals;
    t.gradient_evals += stalled.gradient_evals;
    t.seconds += stalled.seconds;
    t.initial_gradient_norm = stalled.initial_gradient_norm;
    Ok(t)
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
        method: opts.method,
        choice: None,
    }
}
