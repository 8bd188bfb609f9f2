//! Our stopping rules wrapped around any argmin solver, one executor run, the choice of solver,
//! the restarts after failed line searches, and how a run ended ([`Termination`]). Module docs
//! of [`optimize`](super), "Stopping".

use std::fmt;
use std::rc::Rc;

use argmin::core::observers::{Observe, ObserverMode};
use argmin::core::{
    Executor, IterState, LineSearch, Problem, Solver, State, TerminationReason, TerminationStatus,
    KV,
};
use argmin::solver::linesearch::MoreThuenteLineSearch;
use argmin::solver::newton::NewtonCG;
use argmin::solver::quasinewton::LBFGS;
use argmin::solver::trustregion::{Steihaug, TrustRegion};

use super::adapter::{ArgminAdapter, Shared};
use super::point::{same_bits, Point};
use super::problem::OptimProblem;
use super::{norm, ArgminError, Method, OptimOptions};
use crate::error::{Error, OptimizeError, Result};

/// Consecutive rejected trust-region steps after which the run stops for lack of progress (the
/// radius has then shrunk by at least 4²⁰ ≈ 10¹²).
pub const MAX_REJECTIONS: usize = 20;

/// How a [`minimize`](super::minimize) run ended. The first five variants are convergence
/// ([`is_converged`](Self::is_converged)); the others say why the run stopped short. Gradient
/// norms are those the test was made on: of J in the solver variables (∇_φJ; = ∇_θJ without a
/// bound).
#[derive(Clone, Debug, PartialEq)]
#[non_exhaustive]
pub enum Termination {
    /// ‖∇J‖ ≤ [`grad_tol`](OptimOptions::grad_tol).
    GradientTolerance {
        /// ‖∇J‖ at the result.
        gradient_norm: f64,
        /// The tolerance.
        tolerance: f64,
    },
    /// ‖∇J‖ ≤ [`rel_grad_tol`](OptimOptions::rel_grad_tol)·‖∇J(θ₀)‖.
    RelativeGradientTolerance {
        /// ‖∇J‖ at the result.
        gradient_norm: f64,
        /// ‖∇J(θ₀)‖.
        initial: f64,
        /// The relative tolerance.
        tolerance: f64,
    },
    /// An accepted step changed J by at most [`cost_rel_tol`](OptimOptions::cost_rel_tol)
    /// relative to max(|J_old|, |J_new|).
    CostChange {
        /// The relative change of that step.
        relative_change: f64,
        /// The tolerance.
        tolerance: f64,
    },
    /// J ≤ [`target_cost`](OptimOptions::target_cost).
    TargetReached {
        /// The target.
        target: f64,
    },
    /// The argmin solver's own convergence test (Newton-CG: J did not change at all).
    SolverConverged {
        /// The solver's name.
        solver: String,
    },
    /// [`max_iters`](OptimOptions::max_iters) iterations were used.
    MaxIterations {
        /// The limit.
        max_iters: usize,
    },
    /// The line search returned its start point: no decrease along the search direction that
    /// J's round-off lets it see.
    LineSearchStalled,
    /// The trust region rejected this many consecutive steps ([`MAX_REJECTIONS`]).
    TrustRegionStalled {
        /// Consecutive rejections.
        rejections: usize,
    },
    /// argmin's line search stopped with an error of its own (its message).
    LineSearchFailed {
        /// argmin's message.
        message: String,
    },
    /// The argmin solver failed (its message).
    SolverError {
        /// argmin's message.
        message: String,
    },
    /// The run stopped (`stop`) after trial points failed to evaluate (a simulation failed or
    /// left the resolved range) and no restart was left.
    EvaluationFailures {
        /// Why the last solver run stopped.
        stop: Box<Termination>,
        /// Failed evaluations in the whole run.
        failures: usize,
        /// Restarts made.
        restarts: usize,
        /// The last failure.
        last: Error,
    },
    /// A user observer returned an error (its message).
    Observer {
        /// The observer's message.
        message: String,
    },
}

impl Termination {
    /// Whether a convergence test (gradient, cost change, target, the solver's own) ended the
    /// run.
    pub fn is_converged(&self) -> bool {
        matches!(
            self,
            Termination::GradientTolerance { .. }
                | Termination::RelativeGradientTolerance { .. }
                | Termination::CostChange { .. }
                | Termination::TargetReached { .. }
                | Termination::SolverConverged { .. }
        )
    }
}

impl fmt::Display for Termination {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Termination::GradientTolerance {
                gradient_norm,
                tolerance,
            } => write!(
                f,
                "converged: gradient norm {gradient_norm:.3e} <= grad_tol {tolerance:.3e}"
            ),
            Termination::RelativeGradientTolerance {
                gradient_norm,
                initial,
                tolerance,
            } => write!(
                f,
                "converged: gradient norm {gradient_norm:.3e} <= rel_grad_tol {tolerance:.1e} x \
                 initial {initial:.3e}"
            ),
            Termination::CostChange {
                relative_change,
                tolerance,
            } => write!(
                f,
                "converged: relative cost change {relative_change:.3e} <= cost_rel_tol \
                 {tolerance:.1e}"
            ),
            Termination::TargetReached { target } => {
                write!(f, "converged: target cost {target:e} reached")
            }
            Termination::SolverConverged { solver } => {
                write!(f, "converged: {solver}'s own convergence test")
            }
            Termination::MaxIterations { max_iters } => {
                write!(f, "not converged: maximum iterations ({max_iters}) reached")
            }
            Termination::LineSearchStalled => write!(
                f,
                "not converged: no progress, the line search returned its start point"
            ),
            Termination::TrustRegionStalled { rejections } => write!(
                f,
                "not converged: no progress, the trust region rejected {rejections} consecutive \
                 steps"
            ),
            Termination::LineSearchFailed { message } => {
                write!(f, "not converged: the line search failed: {message}")
            }
            Termination::SolverError { message } => {
                write!(f, "not converged: solver error: {message}")
            }
            Termination::EvaluationFailures {
                stop,
                failures,
                restarts,
                last,
            } => {
                // argmin's line-search message repeats the failure given below.
                let stop = match stop.as_ref() {
                    Termination::LineSearchFailed { .. } => "the line search failed".to_string(),
                    t => t.to_string(),
                };
                let stop = stop.strip_prefix("not converged: ").unwrap_or(&stop);
                write!(
                    f,
                    "not converged: {stop}, after {failures} failed evaluation(s) and \
                     {restarts} restart(s); the last failure: {last}"
                )
            }
            Termination::Observer { message } => {
                write!(f, "not converged: stopped by an observer: {message}")
            }
        }
    }
}

/// The gradient test of [`OptimOptions`] on ‖g‖ = `gnorm` (`gnorm0` at the start).
pub(crate) fn gradient_test(opts: &OptimOptions, gnorm0: f64, gnorm: f64) -> Option<Termination> {
    if gnorm <= opts.grad_tol {
        Some(Termination::GradientTolerance {
            gradient_norm: gnorm,
            tolerance: opts.grad_tol,
        })
    } else if gnorm <= opts.rel_grad_tol * gnorm0 {
        Some(Termination::RelativeGradientTolerance {
            gradient_norm: gnorm,
            initial: gnorm0,
            tolerance: opts.rel_grad_tol,
        })
    } else {
        None
    }
}

// ---------------------------------------------------------------------------------------------
// The supervised solver
// ---------------------------------------------------------------------------------------------

/// Wraps an argmin solver with the stopping rules of [`OptimOptions`] (module docs) and keeps the
/// current iterate for the observers.
pub(crate) struct Supervised<'o, S> {
    inner: S,
    opts: &'o OptimOptions,
    gnorm0: f64,
    trust_region: bool,
    rejections: usize,
    stop: Option<Termination>,
    shared: Rc<Shared>,
    /// The adapter's scale s: argmin sees s·J, the tests use J.
    scale: f64,
}

pub(crate) type St<H> = IterState<Vec<f64>, Vec<f64>, (), H, (), f64>;

impl<'a, 'o, Q, H, S> Solver<ArgminAdapter<'a, Q>, St<H>> for Supervised<'o, S>
where
    Q: OptimProblem + ?Sized,
    S: Solver<ArgminAdapter<'a, Q>, St<H>>,
{
    fn name(&self) -> &str {
        self.inner.name()
    }

    fn init(
        &mut self,
        problem: &mut Problem<ArgminAdapter<'a, Q>>,
        state: St<H>,
    ) -> std::result::Result<(St<H>, Option<KV>), ArgminError> {
        let (state, kv) = self.inner.init(problem, state)?;
        if let Some(g) = state.get_gradient() {
            self.stop = gradient_test(self.opts, self.gnorm0, norm(g) / self.scale);
        }
        Ok((state, kv))
    }

    fn next_iter(
        &mut self,
        problem: &mut Problem<ArgminAdapter<'a, Q>>,
        state: St<H>,
    ) -> std::result::Result<(St<H>, Option<KV>), ArgminError> {
        let old_param = state.get_param().cloned();
        let old_cost = state.get_cost();
        let (mut state, kv) = self.inner.next_iter(problem, state)?;
        self.shared.bump(|c| c.iterations += 1);
        let kv = kv.unwrap_or_default();
        if state.terminated() {
            return Ok((state, Some(kv)));
        }
        let Some(param) = state.get_param().cloned() else {
            return Ok((state, Some(kv)));
        };
        let gnorm = match state.get_gradient() {
            Some(g) => norm(g),
            None => {
                let g = problem.gradient(&param)?;
                let n = norm(&g);
                state = state.gradient(g);
                n
            }
        } / self.scale;
        let moved = old_param.as_ref().is_none_or(|p| !same_bits(p, &param));
        if moved {
            self.rejections = 0;
            if self.shared.observing() {
                if let Some(adapter) = problem.problem.as_ref() {
                    if let Ok(p) = adapter.evaluate(&param) {
                        *self.shared.current.borrow_mut() = Some(p);
                    }
                }
            }
        } else {
            self.rejections += 1;
        }
        self.stop = gradient_test(self.opts, self.gnorm0, gnorm);
        if self.stop.is_some() {
            return Ok((state, Some(kv)));
        }
        let cost = state.get_cost();
        let tol = self.opts.cost_rel_tol;
        if moved {
            let scale = old_cost.abs().max(cost.abs());
            let change = (old_cost - cost).abs();
            if old_cost.is_finite() && change <= tol * scale {
                self.stop = Some(Termination::CostChange {
                    relative_change: if scale > 0.0 { change / scale } else { 0.0 },
                    tolerance: tol,
                });
            }
        } else if !self.trust_region {
            self.stop = Some(Termination::LineSearchStalled);
        } else if self.rejections >= MAX_REJECTIONS {
            self.stop = Some(Termination::TrustRegionStalled {
                rejections: self.rejections,
            });
        }
        Ok((state, Some(kv)))
    }

    fn terminate(&mut self, state: &St<H>) -> TerminationStatus {
        match &self.stop {
            Some(t) if t.is_converged() => {
                TerminationStatus::Terminated(TerminationReason::SolverConverged)
            }
            Some(t) => TerminationStatus::Terminated(TerminationReason::SolverExit(t.to_string())),
            None => self.inner.terminate(state),
        }
    }
}

// ---------------------------------------------------------------------------------------------
// One executor run
// ---------------------------------------------------------------------------------------------

/// Where one executor run ended and why.
pub(crate) struct RunOutcome {
    pub(crate) phi: Vec<f64>,
    pub(crate) end: Termination,
}

pub(crate) struct RunSetup<'o> {
    pub(crate) opts: &'o OptimOptions,
    pub(crate) gnorm0: f64,
    pub(crate) scale: f64,
    pub(crate) max_iters: usize,
    pub(crate) alpha: f64,
}

fn supervised<'o, S>(
    inner: S,
    setup: &RunSetup<'o>,
    shared: &Rc<Shared>,
    tr: bool,
) -> Supervised<'o, S> {
    Supervised {
        inner,
        opts: setup.opts,
        gnorm0: setup.gnorm0,
        trust_region: tr,
        rejections: 0,
        stop: None,
        shared: Rc::clone(shared),
        scale: setup.scale,
    }
}

/// Runs one executor from `start` and classifies the end.
fn execute<'a, Q, H, S>(
    adapter: ArgminAdapter<'a, Q>,
    solver: Supervised<'_, S>,
    start: &Point,
    setup: &RunSetup<'_>,
) -> Result<RunOutcome>
where
    Q: OptimProblem + ?Sized,
    S: Solver<ArgminAdapter<'a, Q>, St<H>>,
{
    let shared = Rc::clone(&adapter.shared);
    let mut exec = Executor::new(adapter, solver)
        .configure(|s: St<H>| {
            s.param(start.phi.clone())
                .cost(start.value * setup.scale)
                .gradient(start.grad_phi.iter().map(|g| g * setup.scale).collect())
                .max_iters(setup.max_iters as u64)
                .target_cost(setup.opts.target_cost * setup.scale)
        })
        .ctrlc(false);
    if shared.observing() {
        exec = exec.add_observer(
            Bridge {
                shared: Rc::clone(&shared),
            },
            ObserverMode::Always,
        );
    }
    let run = exec.run();
    if let Some(e) = shared.fatal() {
        return Err(e);
    }
    if let Some(message) = shared.observer_stop.borrow().clone() {
        let phi = shared
            .current
            .borrow()
            .as_ref()
            .map_or_else(|| start.phi.clone(), |p| p.phi.clone());
        return Ok(RunOutcome {
            phi,
            end: Termination::Observer { message },
        });
    }
    let res = match run {
        Ok(res) => res,
        Err(e) => {
            // argmin lost the state (e.g. a line-search error inside Newton-CG): continue from
            // the best point evaluated so far.
            let phi = shared
                .best
                .borrow()
                .as_ref()
                .map_or_else(|| start.phi.clone(), |p| p.phi.clone());
            return Ok(RunOutcome {
                phi,
                end: Termination::SolverError {
                    message: e.to_string(),
                },
            });
        }
    };
    let state = &res.state;
    // The current iterate is where the stopping tests were made; argmin's "best" compares costs
    // that may differ by round-off only. After a failed line search argmin's L-BFGS leaves no
    // current parameter: then the best one.
    let phi = state
        .get_param()
        .or(state.get_best_param())
        .cloned()
        .unwrap_or_else(|| start.phi.clone());
    let end = match (&res.solver.stop, state.get_termination_reason()) {
        (Some(t), _) => t.clone(),
        (None, Some(TerminationReason::TargetCostReached)) => Termination::TargetReached {
            target: setup.opts.target_cost,
        },
        (None, Some(TerminationReason::MaxItersReached)) => Termination::MaxIterations {
            max_iters: setup.opts.max_iters,
        },
        (None, Some(TerminationReason::SolverConverged)) => Termination::SolverConverged {
            solver: res.solver.inner.name().to_string(),
        },
        (None, Some(TerminationReason::SolverExit(s))) => {
            Termination::LineSearchFailed { message: s.clone() }
        }
        (None, Some(r)) => Termination::SolverError {
            message: r.text().to_string(),
        },
        (None, None) => Termination::SolverError {
            message: "stopped without a reason".into(),
        },
    };
    Ok(RunOutcome { phi, end })
}

/// Builds the solver of `setup.opts.method` and runs it once from `start`.
pub(crate) fn run_method<Q: OptimProblem + ?Sized>(
    adapter: &ArgminAdapter<'_, Q>,
    start: &Point,
    setup: &RunSetup<'_>,
) -> Result<RunOutcome> {
    let opts = setup.opts;
    let n = start.phi.len();
    let cg = opts.cg_max_iters.unwrap_or(2 * n.max(1));
    let config = |e: ArgminError| {
        Error::from(OptimizeError::SolverConfig {
            message: e.to_string(),
        })
    };
    match opts.method {
        Method::Lbfgs => {
            let mut ls = MoreThuenteLineSearch::new();
            ls.initial_step_length(setup.alpha).map_err(config)?;
            let inner = LBFGS::new(ls, opts.lbfgs_memory)
                .with_tolerance_grad(0.0)
                .map_err(config)?
                .with_tolerance_cost(0.0)
                .map_err(config)?;
            let solver = supervised(inner, setup, &adapter.shared, false);
            execute::<Q, (), _>(adapter.clone(), solver, start, setup)
        }
        Method::TrustRegion => {
            let sub = Steihaug::new().with_max_iters(cg as u64);
            let inner = TrustRegion::new(sub)
                .with_radius(opts.trust_radius)
                .map_err(config)?
                .with_max_radius(opts.max_trust_radius)
                .map_err(config)?;
            let solver = supervised(inner, setup, &adapter.shared, true);
            let a = adapter.clone().with_extended_value(true);
            execute(a, solver, start, setup)
        }
        Method::NewtonCg => {
            let mut ls = MoreThuenteLineSearch::new();
            ls.initial_step_length(setup.alpha).map_err(config)?;
            let inner = NewtonCG::new(ls)
                .with_tolerance(f64::MIN_POSITIVE)
                .map_err(config)?;
            let solver = supervised(inner, setup, &adapter.shared, false);
            let a = adapter.clone().with_hvp_cap(cg);
            execute(a, solver, start, setup)
        }
        // `minimize` hands this method to crate::ocp before any argmin solver is built.
        Method::Auto | Method::Riccati | Method::Condensed => {
            Err(super::riccati::unsupported(opts.method))
        }
    }
}

// ---------------------------------------------------------------------------------------------
// Restarts
// ---------------------------------------------------------------------------------------------

/// Where the solver runs ended.
pub(crate) struct Supervision {
    pub(crate) point: Point,
    pub(crate) termination: Termination,
    /// Whether the gradient polish may follow (not after the iteration limit or an observer's
    /// stop).
    pub(crate) polish: bool,
    pub(crate) restarts: usize,
}

/// Runs the solver from `start` until it converges, runs out of iterations, or stops for lack
/// of progress; restarts a line-search method whose trial points failed (module docs).
pub(crate) fn supervise<Q: OptimProblem + ?Sized>(
    adapter: &ArgminAdapter<'_, Q>,
    start: Point,
    opts: &OptimOptions,
    gnorm0: f64,
) -> Result<Supervision> {
    let scale = adapter.scale();
    let mut point = start;
    let mut restarts = 0;
    let mut alpha_first = 1.0;
    let max_iters = Termination::MaxIterations {
        max_iters: opts.max_iters,
    };
    let (termination, polish) = loop {
        if let Some(message) = adapter.shared.observer_stop.borrow().clone() {
            break (Termination::Observer { message }, false);
        }
        let used = adapter.counts().iterations;
        if used >= opts.max_iters {
            break (max_iters, false);
        }
        let first_only = alpha_first < 1.0;
        let setup = RunSetup {
            opts,
            gnorm0,
            scale,
            max_iters: if first_only { 1 } else { opts.max_iters - used },
            alpha: alpha_first,
        };
        let failures_before = adapter.counts().failures;
        let out = run_method(adapter, &point, &setup)?;
        point = adapter.evaluate(&out.phi)?;
        match out.end {
            t if t.is_converged() => break (t, true),
            Termination::Observer { message } => break (Termination::Observer { message }, false),
            Termination::MaxIterations { .. } if first_only => alpha_first = 1.0,
            Termination::MaxIterations { .. } => break (max_iters, false),
            stop => {
                let trial_failed = adapter.counts().failures > failures_before;
                // The trust region has no memory to reset and already shrinks its radius at
                // failed trial points: only the line-search methods restart.
                let restartable = opts.method != Method::TrustRegion;
                if !trial_failed || !restartable || restarts >= opts.max_restarts {
                    let last = adapter.shared.last_failure.borrow().clone();
                    let t = match (trial_failed, last) {
                        (true, Some(last)) => Termination::EvaluationFailures {
                            stop: Box::new(stop),
                            failures: adapter.counts().failures,
                            restarts,
                            last,
                        },
                        _ => stop,
                    };
                    break (t, true);
                }
                restarts += 1;
                alpha_first *= 0.1;
            }
        }
    };
    Ok(Supervision {
        point,
        termination,
        polish,
        restarts,
    })
}

/// The one observer [`minimize`](super::minimize) adds to each argmin executor: relays the
/// solver's iterations to the user's observers in θ and J (module docs). The point comes from
/// the supervisor, which keeps the current iterate in the shared state.
pub(crate) struct Bridge {
    pub(crate) shared: Rc<Shared>,
}

impl<G, J, H, R> Observe<IterState<Vec<f64>, G, J, H, R, f64>> for Bridge {
    fn observe_iter(
        &mut self,
        _state: &IterState<Vec<f64>, G, J, H, R, f64>,
        kv: &KV,
    ) -> Result<(), ArgminError> {
        let Some(p) = self.shared.current.borrow().clone() else {
            return Ok(());
        };
        let out = match self.shared.relay.borrow_mut().as_mut() {
            Some(relay) => relay.iter(&p, kv),
            None => Ok(()),
        };
        if let Err(e) = &out {
            self.shared
                .observer_stop
                .borrow_mut()
                .get_or_insert_with(|| e.to_string());
        }
        out
    }
}
