//! `chainbeam optimize`, report: the result checked finite and written as JSON, and the exit
//! status (3 when the optimiser did not converge).

use serde::Serialize;

use chainbeam::optimize::{OptimOptions, OptimResult};

use super::solve::{Setup, Solved};
use super::OptimizeArgs;
use crate::output::Output;
use crate::problem::{ProblemReport, Values};
use crate::{check_finite, to_json, CliError};

/// The force limits of a run as reported in the JSON: `bound` for --bound, `lower` and `upper`
/// for any limit.
#[derive(Serialize)]
pub(super) struct LimitsReport {
    #[serde(skip_serializing_if = "Option::is_none")]
    bound: Option<f64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    lower: Option<f64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    upper: Option<f64>,
}

impl LimitsReport {
    pub(super) fn of(opts: &OptimOptions) -> Self {
        let b = opts.force_bounds().ok().flatten();
        LimitsReport {
            bound: opts.bound,
            lower: b.map(|b| b.lower()),
            upper: b.map(|b| b.upper()),
        }
    }
}

/// ‖∇c‖/‖∇c(start)‖ of a result (projected on active bounds), or `None` at a zero start gradient.
fn relative_gradient(r: &OptimResult) -> Option<f64> {
    (r.initial_gradient_norm > 0.0).then(|| r.projected_gradient_norm / r.initial_gradient_norm)
}

/// "…, N iterations, relative gradient …" for a stderr line.
pub(super) fn why(r: &OptimResult) -> String {
    let rel = match relative_gradient(r) {
        Some(g) => format!("relative gradient ‖∇c‖/‖∇c(start)‖ = {g:.3e}"),
        None => "the gradient was zero at the start".into(),
    };
    let its = r.iterations;
    format!(
        "{}; after {its} iteration{}, {rel}",
        r.termination,
        if its == 1 { "" } else { "s" }
    )
}

#[derive(Serialize)]
struct OptimizeReport {
    objective: f64,
    controls: Values,
    gradient_norm: f64,
    iterations: usize,
    seconds: f64,
    converged: bool,
    termination: String,
    #[serde(skip_serializing_if = "Option::is_none")]
    relative_gradient_norm: Option<f64>,
    method: &'static str,
    #[serde(skip_serializing_if = "Option::is_none")]
    method_choice: Option<ChoiceReport>,
    starts: usize,
    #[serde(skip_serializing_if = "Option::is_none")]
    seed: Option<u64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    minima_found: Option<usize>,
    #[serde(skip_serializing_if = "Option::is_none")]
    failed_starts: Option<usize>,
    initial_objective: f64,
    initial_controls: Values,
    projected_gradient_norm: f64,
    active_bounds: Vec<usize>,
    #[serde(flatten)]
    limits: LimitsReport,
    gradient_evals: usize,
    hvp_evals: usize,
    #[serde(flatten)]
    problem: ProblemReport,
}

/// Checks the result finite, writes the JSON report to `out` and ends with
/// [`CliError::NotConverged`] (exit status 3) when the optimiser did not converge.
pub fn write(
    a: &OptimizeArgs,
    setup: &Setup,
    solved: &Solved,
    out: Output,
) -> Result<(), CliError> {
    let best = &solved.best;
    check_finite(&a.scene, "objective", &[best.objective])?;
    check_finite(&a.scene, "controls", &best.theta)?;
    check_finite(&a.scene, "gradient_norm", &[best.gradient_norm])?;
    check_finite(
        &a.scene,
        "projected_gradient_norm",
        &[best.projected_gradient_norm],
    )?;
    out.write_all(&to_json(&report(a, setup, solved))?)?;
    if best.converged {
        Ok(())
    } else {
        Err(CliError::NotConverged(format!(
            "{}: the optimiser did not converge: {}; the result was written with \"converged\": \
             false",
            a.scene.display(),
            why(best)
        )))
    }
}

/// The JSON of a run.
fn report(a: &OptimizeArgs, setup: &Setup, solved: &Solved) -> OptimizeReport {
    let (sp, best) = (&setup.sp, &solved.best);
    let starts = a.starts as usize;
    let multi = starts > 1;
    OptimizeReport {
        objective: best.objective,
        controls: sp.problem.layout(&best.theta),
        gradient_norm: best.gradient_norm,
        iterations: best.iterations,
        seconds: setup.clock.elapsed().as_secs_f64(),
        converged: best.converged,
        termination: best.termination.to_string(),
        relative_gradient_norm: relative_gradient(best),
        method: best.method.name(),
        method_choice: best.choice.as_ref().map(ChoiceReport::of),
        starts,
        seed: multi.then_some(a.parallel.seed),
        minima_found: multi.then_some(solved.minima_found),
        failed_starts: multi.then_some(solved.failed_starts),
        initial_objective: setup.initial_objective,
        initial_controls: sp.problem.layout(&sp.theta0),
        projected_gradient_norm: best.projected_gradient_norm,
        active_bounds: best.active_bounds.clone(),
        limits: LimitsReport::of(&setup.opts),
        gradient_evals: best.gradient_evals,
        hvp_evals: best.hvp_evals,
        problem: ProblemReport::of(sp),
    }
}

/// The JSON's `method_choice` (with `--method auto`): the method the automatic choice took, why,
/// and the L-BFGS fallback that followed a structured run that did not converge
/// (`chainbeam::optimize::MethodChoice`).
#[derive(Serialize)]
struct ChoiceReport {
    chosen: &'static str,
    reason: String,
    #[serde(skip_serializing_if = "Option::is_none")]
    fallback: Option<FallbackReport>,
}

/// `method_choice.fallback`: what the structured run came to, and whose result was kept.
#[derive(Serialize)]
struct FallbackReport {
    method: &'static str,
    why: String,
    kept: &'static str,
}

impl ChoiceReport {
    fn of(c: &chainbeam::optimize::MethodChoice) -> Self {
        ChoiceReport {
            chosen: c.method.name(),
            reason: c.reason.clone(),
            fallback: c.fallback.as_ref().map(|f| FallbackReport {
                method: "lbfgs",
                why: f.why.clone(),
                kept: f.kept.name(),
            }),
        }
    }
}
