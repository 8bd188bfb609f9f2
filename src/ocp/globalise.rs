//! The outer iteration the Riccati solver ([`super::Solver`]) and the condensed solver
//! ([`super::Condensed`]) share ([`run`], module docs "Globalisation" and "Convergence"), and
//! what turns a model step into an accepted one: the backtracking rule on actual against
//! predicted decrease (with J's round-off), the Levenberg schedule, and the stall test for
//! steps below J's resolution. Each solver supplies its own linearisation, model step and
//! trial (a closed-loop rollout with Riccati feedback, or an open-loop rollout of θ + αδ)
//! through [`Outer`].

use std::time::Instant;

use super::options::{
    IterationObserver, IterationRecord, IterationReport, OcpOptions, OcpResult, OcpTermination,
};
use crate::error::Result;

/// Consecutive round-off steps without a 10 % decrease of the projected gradient after which
/// the run stops ([`OcpTermination::RoundOff`]).
const MAX_ROUNDOFF_STEPS: usize = 10;
/// Predicted decreases below this fraction of max(|J|, 10⁻⁶ J₀) are not resolved by J: J's
/// noise is its floating-point round-off (2·10⁻¹³ relative on the thesis riser, see
/// [`crate::optimize`]) and the RATTLE Newton tolerance (10⁻¹⁴ on the constraints, ~4·10⁻¹¹ in
/// M₀ = 4000 z₁; about 10⁻¹⁰ relative at J ≈ 6·10⁻⁴, Table 3.4 row 8). Such steps are taken
/// unless J rises by more than [`NOISE`] of it, and the projected gradient alone decides
/// convergence.
const ROUNDOFF: f64 = 1e-10;
/// The rise of J (relative to max(|J|, 10⁻⁶ J₀)) tolerated for a step below J's resolution.
const NOISE: f64 = 1e-11;
/// Smallest nonzero relative regularisation.
const MU_MIN: f64 = 1e-6;

/// What a solver's step ended with.
#[derive(Clone, Copy, Debug)]
pub(crate) enum Step {
    /// The line search accepted a trial (in the horizon's trial trajectory).
    Accepted(Accepted),
    /// The line search failed: μ rises for the next iteration.
    Rejected,
    /// No solvable model below μ's limit.
    NoModel,
}

/// A solver the shared outer iteration ([`run`]) drives: the Riccati solver and the condensed
/// one differ in how they linearise, model and try a step, not in the iteration around it.
pub(crate) trait Outer {
    /// Resets the counters (and whatever else a run starts from).
    fn begin(&mut self);
    /// The solver's options.
    fn options(&self) -> &OcpOptions;
    /// J of the nominal.
    fn nominal_cost(&self) -> f64;
    /// θ of the nominal.
    fn theta(&self) -> Vec<f64>;
    /// Makes θ (projected onto the box) the nominal; J.
    fn set_point(&mut self, theta: &[f64]) -> Result<f64>;
    /// The exact gradient at the nominal; returns the projected gradient norm.
    fn linearise(&mut self) -> Result<f64>;
    /// The gradient of the last [`Outer::linearise`] (its norm is ‖g₀‖ at the first).
    fn gradient(&self) -> &[f64];
    /// The model's step and its line search from the nominal (projected gradient `pg`,
    /// ‖g₀‖ = `gref`), raising `pr.mu` as the model needs.
    fn step(&mut self, pr: &mut Progress, pg: f64, gref: f64) -> Result<Step>;
    /// The accepted trial becomes the nominal.
    fn take_step(&mut self);
    /// How a run ends whose steps below J's round-off stopped lowering the projected gradient
    /// (tolerance `target`).
    fn stalled(&mut self, target: f64) -> Result<OcpTermination>;
    /// The result at the final nominal.
    fn report(&mut self, termination: OcpTermination, pr: Progress, t0: Instant) -> OcpResult;
}

/// Runs a solver from θ₀ (projected onto the box): iterations of linearisation, stopping tests,
/// the model's step with its line search and the Levenberg schedule until one ends the run.
/// `observer`, if any, sees every accepted iteration and may stop the run.
pub(crate) fn run<S: Outer>(
    solver: &mut S,
    theta0: &[f64],
    mut observer: Option<IterationObserver<'_>>,
) -> Result<OcpResult> {
    let t0 = Instant::now();
    solver.begin();
    let mut pr = Progress::new(solver.set_point(theta0)?);
    let termination = loop {
        if let Some(t) = iterate(solver, &mut pr, &mut observer)? {
            break t;
        }
    };
    Ok(solver.report(termination, pr, t0))
}

/// One iteration: the exact gradient and the stopping tests, the model's step and its line
/// search, the history and the regularisation schedule. `Some` ends the run.
fn iterate<S: Outer>(
    solver: &mut S,
    pr: &mut Progress,
    observer: &mut Option<IterationObserver<'_>>,
) -> Result<Option<OcpTermination>> {
    let opts = solver.options().clone();
    if pr.budget_spent(&opts) {
        return Ok(Some(OcpTermination::Budget));
    }
    let pg = solver.linearise()?;
    let (stop, target, gref) = pr.stop_test(&opts, pg, solver.gradient());
    if stop.is_some() {
        return Ok(stop);
    }
    let acc = match solver.step(pr, pg, gref)? {
        Step::Accepted(acc) => acc,
        Step::Rejected => {
            pr.mu = raise_mu(pr.mu);
            let limit = pr.mu > opts.max_regularisation;
            return Ok(limit.then_some(OcpTermination::RegularisationLimit));
        }
        Step::NoModel => return Ok(Some(OcpTermination::RegularisationLimit)),
    };
    solver.take_step();
    pr.iterations += 1;
    pr.history.push(IterationRecord {
        objective: solver.nominal_cost(),
        projected_gradient_norm: pg,
        alpha: acc.alpha,
        regularisation: pr.mu,
    });
    if let (Some(watch), Some(record)) = (observer.as_mut(), pr.history.last()) {
        let theta = solver.theta();
        let report = IterationReport {
            iteration: pr.iterations,
            theta: &theta,
            record,
        };
        if watch(&report).is_break() {
            return Ok(Some(OcpTermination::Stopped));
        }
    }
    // Below J's resolution only the projected gradient shows progress: stop when it has not
    // fallen by 10 % over several such steps.
    if pr.roundoff.stalled(acc.roundoff, pg) {
        return solver.stalled(target).map(Some);
    }
    pr.mu = next_mu(pr.mu, &acc);
    Ok(None)
}

/// The step the line search accepted.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Accepted {
    pub alpha: f64,
    /// Taken in the round-off regime (the model's decrease below J's resolution).
    pub roundoff: bool,
    /// Actual over predicted decrease.
    pub ratio: f64,
}

/// The change of J a model predicts along its step: ΔJ(α) = α d1 + α² d2.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct ModelChange {
    /// The slope at α = 0 (gᵀδ).
    pub d1: f64,
    /// The curvature term (½ δᵀHδ).
    pub d2: f64,
}

impl ModelChange {
    /// ΔJ(α).
    #[inline]
    pub(super) fn at(&self, alpha: f64) -> f64 {
        alpha * self.d1 + alpha * alpha * self.d2
    }
}

/// One line search: from J̄ = `jbar` (J₀ = `j0` at the start of the run) along a step whose
/// model predicts `model`, with the acceptance fraction `armijo` and at most `tries` trials.
#[derive(Clone, Copy, Debug)]
pub(crate) struct LineSearch {
    pub jbar: f64,
    pub j0: f64,
    pub model: ModelChange,
    pub armijo: f64,
    pub tries: usize,
}

/// Backtracking on J(α) = `trial(α)` (`None`: the trial failed) from J̄ with the predicted
/// change ΔJ(α) = α d1 + α² d2: α = 1 first, then the minimiser of the quadratic through J̄,
/// d1 and J(α), kept in [α/10, α/2]; accepted when J̄ − J(α) ≥ c·(−ΔJ(α)) (c = `armijo`), or,
/// where −ΔJ is below J's round-off (relative to max(|J̄|, 10⁻⁶ |J₀|)), when J does not rise
/// beyond it. At most `tries` trials.
pub(crate) fn backtrack(
    search: LineSearch,
    mut trial: impl FnMut(f64) -> Option<f64>,
) -> Option<Accepted> {
    let LineSearch {
        jbar,
        j0,
        model,
        armijo,
        tries,
    } = search;
    let d1 = model.d1;
    let jscale = jbar.abs().max(1e-6 * j0.abs());
    let tiny = ROUNDOFF * jscale;
    let mut alpha = 1.0;
    for _ in 0..tries {
        let dj = model.at(alpha);
        let mut next = 0.5 * alpha;
        if let Some(jt) = trial(alpha) {
            if -dj <= tiny {
                if jt <= jbar + NOISE * jscale {
                    return Some(Accepted {
                        alpha,
                        roundoff: true,
                        ratio: 1.0,
                    });
                }
            } else {
                let ratio = (jbar - jt) / (-dj);
                if ratio >= armijo {
                    return Some(Accepted {
                        alpha,
                        roundoff: false,
                        ratio,
                    });
                }
                let b = (jt - jbar - alpha * d1) / (alpha * alpha);
                if b > 0.0 && d1 < 0.0 {
                    next = (-d1 / (2.0 * b)).clamp(0.1 * alpha, 0.5 * alpha);
                }
            }
        }
        alpha = next;
    }
    None
}

/// The Levenberg weight after an accepted step: lowered (to 0 below [`MU_MIN`]) after a full
/// step whose decrease matched the model, raised after a short step or a poor match: ×4, and
/// by a further 1/α after a step the line search shortened to α, since the model was then
/// trusted about 1/α times too far (a proximal term ½ μ δv² shortens a Newton step by
/// λ/(λ + μ) along a direction of curvature λ). With ×4 alone a run of α = 0.1 steps took six
/// iterations to lift μ from 10⁻⁶ to where full steps passed, and Gauss-Newton stalled at J's
/// round-off on Table 3.4 rows 1 and 3 (tests/scene/tables.rs now converges on all ten).
pub(crate) fn next_mu(mu: f64, acc: &Accepted) -> f64 {
    if acc.alpha >= 1.0 && acc.ratio > 0.75 {
        if mu * 0.25 < MU_MIN {
            0.0
        } else {
            mu * 0.25
        }
    } else if acc.alpha < 1.0 || acc.ratio < 0.25 {
        (mu * 4.0).max(MU_MIN) / acc.alpha
    } else {
        mu
    }
}

/// The Levenberg weight after a failed model step or line search.
pub(crate) fn raise_mu(mu: f64) -> f64 {
    (mu * 10.0).max(MU_MIN)
}

/// Consecutive accepted steps below J's round-off, and the projected gradient they are measured
/// against: below J's resolution only the projected gradient shows progress.
#[derive(Clone, Copy, Debug)]
pub(crate) struct RoundoffWatch {
    steps: usize,
    pg: f64,
}

impl Default for RoundoffWatch {
    fn default() -> Self {
        RoundoffWatch {
            steps: 0,
            pg: f64::INFINITY,
        }
    }
}

impl RoundoffWatch {
    /// Records an accepted step (`roundoff`: taken below J's resolution) at projected gradient
    /// `pg`; true when more than [`MAX_ROUNDOFF_STEPS`] such steps in a row have not lowered
    /// the projected gradient by 10 %.
    pub(super) fn stalled(&mut self, roundoff: bool, pg: f64) -> bool {
        if !roundoff {
            self.steps = 0;
            return false;
        }
        if self.steps == 0 || pg < 0.9 * self.pg {
            self.steps = 0;
            self.pg = pg;
        }
        self.steps += 1;
        self.steps > MAX_ROUNDOFF_STEPS
    }
}

/// The running state of one solve (either solver).
pub(crate) struct Progress {
    /// J at the (projected) start.
    pub j0: f64,
    /// Relative Levenberg weight.
    pub mu: f64,
    /// Accepted steps.
    pub iterations: usize,
    /// Steps below J's round-off.
    pub roundoff: RoundoffWatch,
    pub history: Vec<IterationRecord>,
    /// ‖∇J(θ₀)‖ (set by the first gradient).
    pub g0: Option<f64>,
    /// The projected gradient of the last evaluation.
    pub last_pg: f64,
}

impl Progress {
    /// The state at the start, J(θ₀) = `j0`.
    pub(super) fn new(j0: f64) -> Self {
        Progress {
            j0,
            mu: 0.0,
            iterations: 0,
            roundoff: RoundoffWatch::default(),
            history: Vec::new(),
            g0: None,
            last_pg: f64::INFINITY,
        }
    }

    /// Whether a real-time budget is spent (no final gradient wanted:
    /// [`OcpOptions::final_gradient`]); tested before the next linearisation.
    pub(super) fn budget_spent(&self, opts: &OcpOptions) -> bool {
        self.iterations > 0 && self.iterations >= opts.max_iters && !opts.final_gradient
    }

    /// The stopping tests on the projected gradient `pg` (the gradient `grad` sets ‖∇J(θ₀)‖ at
    /// the first call): [`OcpTermination::Converged`] at max(grad_tol, rel_grad_tol ‖g₀‖),
    /// [`OcpTermination::MaxIterations`] at the limit. Returns the tolerance as well, and
    /// ‖g₀‖.
    pub(super) fn stop_test(
        &mut self,
        opts: &OcpOptions,
        pg: f64,
        grad: &[f64],
    ) -> (Option<OcpTermination>, f64, f64) {
        self.last_pg = pg;
        let gref = *self
            .g0
            .get_or_insert_with(|| grad.iter().map(|g| g * g).sum::<f64>().sqrt());
        let target = opts.grad_tol.max(opts.rel_grad_tol * gref);
        let stop = if pg <= target {
            Some(OcpTermination::Converged)
        } else if self.iterations >= opts.max_iters {
            Some(OcpTermination::MaxIterations)
        } else {
            None
        };
        (stop, target, gref)
    }
}
