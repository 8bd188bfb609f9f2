//! [`Method::Riccati`] and [`Method::Condensed`]: [`minimize`](super::minimize) hands per-step,
//! piecewise and constant control problems with an objective in Gauss-Newton form
//! ([`Objective::gauss_newton`](crate::Objective::gauss_newton)) to the structured
//! Gauss-Newton solvers of [`crate::ocp`] (the Riccati solver, or the condensed one) and
//! reports their result as an [`OptimResult`].
//!
//! The options carry over as: `bound = Some(b)` → the box −b ≤ θ ≤ b, `bounds` → the box
//! L ≤ θ ≤ U (handled exactly by the solver's interior-point QPs, no reparametrisation), `max_iters`, `grad_tol` and
//! `rel_grad_tol` on the *projected* gradient. The argmin-specific options (L-BFGS memory,
//! trust radius, CG, restarts, polish, cost-change and target tests) do not apply. A run
//! that stalls short of the tolerance is finished by the trust region
//! ([`finish_by_trust_region`]).
//!
//! The observers of the [`Minimizer`] see the structured run as they see an argmin one
//! (module [`observers`](super::observers)): `observe_init` at θ₀ with the method's name,
//! `observe_iter` after every accepted iteration of the solver, `observe_final` at the result;
//! each shown point carries θ, J(θ) and ∇_θJ(θ) evaluated by the problem itself (one adjoint
//! sweep per iteration, spent only when there are observers; the solver's own arithmetic is
//! untouched), and the iteration's log holds the solver's `alpha` (step length),
//! `regularisation` (relative Levenberg weight) and `projected_grad_norm` (before the step). An
//! observer that returns an error stops the solver at the point reached
//! ([`Termination::Observer`]).

use std::ops::ControlFlow;

use argmin::core::{KvValue, KV};

use super::observers::{Relay, Seen};
use super::point::same_bits;
use super::{
    bounds, ineffective_params, norm, ArgminAdapter, Method, Minimizer, OptimOptions, OptimProblem,
    OptimResult, Termination,
};
use crate::error::{Error, OptimizeError, Result};
use crate::ocp::{self, IterationReport, OcpOptions, OcpResult};

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

/// Runs the Riccati solver (or, with [`Method::Condensed`], the condensed one) on the
/// minimiser's problem from θ₀, shown to its observers (module docs). The result's objective is
/// J(θ) evaluated by the problem itself (one simulation), so it is the number `gradient`
/// reports for the same controls, bit for bit (the solver's own value comes from its rollouts
/// and may differ in the last bits); if that simulation fails (the beam folds, RATTLE fails),
/// so does the run, with that error.
pub(crate) fn run<Q: OptimProblem + ?Sized>(
    m: &Minimizer<'_, Q>,
    theta0: &[f64],
    opts: &OptimOptions,
) -> Result<OptimResult> {
    let problem = m.problem;
    let options = ocp_options(opts)?;
    let mut watch = Watch::new(m, theta0, opts)?;
    let observed = watch.relay.is_some();
    let r = {
        let mut observe = |it: &IterationReport<'_>| watch.iteration(problem, it);
        let observer: Option<ocp::IterationObserver<'_>> = match observed {
            true => Some(&mut observe),
            false => None,
        };
        match opts.method {
            Method::Condensed => problem.condensed(theta0, &options, observer),
            _ => problem.riccati(theta0, &options, observer),
        }
    }
    .ok_or_else(|| unsupported(opts.method))??;
    if let Some(e) = watch.failed.take() {
        return Err(e);
    }
    let mut res = result(r, opts, watch.stop.take());
    // Also the check that the result is a simulation at all: a run that ends where the beam folds
    // or RATTLE fails (the structured solvers' line searches can end there when they do not
    // converge) is that error, not a result.
    res.objective = problem.value(&res.theta)?;
    if observed {
        watch.finish(problem, &mut res, opts)?;
    }
    if res.converged || res.termination != Termination::LineSearchStalled {
        return Ok(res);
    }
    finish_by_trust_region(m, res, opts)
}

/// The observers' side of a structured run: the relay to the minimiser's observers, the last
/// point shown (θ, J, ∇_θJ), and what stopped the run (an observer's message, a failed
/// evaluation).
struct Watch {
    relay: Option<Relay>,
    last: Option<(Vec<f64>, f64, Vec<f64>)>,
    stop: Option<String>,
    failed: Option<Error>,
}

impl Watch {
    /// The relay for `m`'s observers (none without observers), shown the start θ₀.
    fn new<Q: OptimProblem + ?Sized>(
        m: &Minimizer<'_, Q>,
        theta0: &[f64],
        opts: &OptimOptions,
    ) -> Result<Self> {
        let mut w = Watch {
            relay: None,
            last: None,
            stop: None,
            failed: None,
        };
        if m.observers.is_empty() {
            return Ok(w);
        }
        let mut relay = Relay::new(
            m.observers.clone(),
            opts.max_iters as u64,
            f64::NEG_INFINITY,
        );
        let (value, gradient) = m.problem.value_and_gradient(theta0)?;
        let at = Seen {
            theta: theta0,
            value,
            gradient: &gradient,
        };
        if let Err(e) = relay.init_at(opts.method.name(), at) {
            w.stop = Some(e.to_string());
        }
        w.relay = Some(relay);
        w.last = Some((theta0.to_vec(), value, gradient));
        Ok(w)
    }

    /// One accepted iteration of the solver, shown to the observers; `Break` stops the solver.
    fn iteration<Q: OptimProblem + ?Sized>(
        &mut self,
        problem: &Q,
        it: &IterationReport<'_>,
    ) -> ControlFlow<()> {
        let Some(relay) = self.relay.as_mut() else {
            return ControlFlow::Continue(());
        };
        if self.stop.is_some() || self.failed.is_some() {
            return ControlFlow::Break(());
        }
        let (value, gradient) = match problem.value_and_gradient(it.theta) {
            Ok(vg) => vg,
            Err(e) => {
                self.failed = Some(e);
                return ControlFlow::Break(());
            }
        };
        let mut kv = KV::new();
        kv.insert("alpha", KvValue::Float(it.record.alpha));
        kv.insert("regularisation", KvValue::Float(it.record.regularisation));
        kv.insert(
            "projected_grad_norm",
            KvValue::Float(it.record.projected_gradient_norm),
        );
        let at = Seen {
            theta: it.theta,
            value,
            gradient: &gradient,
        };
        let out = relay.iter_at(at, &kv);
        self.last = Some((it.theta.to_vec(), value, gradient));
        match out {
            Ok(()) => ControlFlow::Continue(()),
            Err(e) => {
                self.stop = Some(e.to_string());
                ControlFlow::Break(())
            }
        }
    }

    /// The end of the run, shown to the observers at the result (whose gradient norms, after a
    /// stop, are those of the last point shown, which is the result). An observer's error here
    /// makes the termination [`Termination::Observer`].
    fn finish<Q: OptimProblem + ?Sized>(
        &mut self,
        problem: &Q,
        res: &mut OptimResult,
        opts: &OptimOptions,
    ) -> Result<()> {
        let gradient = match self.last.take() {
            Some((theta, _, g)) if same_bits(&theta, &res.theta) => g,
            _ => problem.value_and_gradient(&res.theta)?.1,
        };
        if matches!(res.termination, Termination::Observer { .. }) {
            let (pg, _) = bounds::kkt(&res.theta, &gradient, opts.force_bounds()?);
            res.gradient_norm = norm(&gradient);
            res.projected_gradient_norm = pg;
        }
        let at = Seen {
            theta: &res.theta,
            value: res.objective,
            gradient: &gradient,
        };
        if let Some(relay) = self.relay.as_mut() {
            if let Err(e) = relay.finish_at(at, &res.termination) {
                res.termination = Termination::Observer {
                    message: e.to_string(),
                };
                res.converged = false;
            }
        }
        Ok(())
    }
}

/// The hand-over when the Gauss-Newton iteration stalls short of the tolerance (no accepted
/// decrease with the regularisation at its limit, or decreases below J's round-off): its
/// positive semi-definite model misses negative curvature of J (no effort penalty, or a chain
/// near folding; Table 3.4 rows 1 and 3 with Gauss-Newton throughout stalled until the
/// regularisation learnt to rise with shortened steps, `ocp::globalise`), or the tolerance is
/// below what floating point resolves (`tests/scene/tables.rs` forces the hand-over so). [`minimize`](super::minimize) then continues from
/// its point with the trust region on exact Hessian-vector products (which sees that
/// curvature) and returns *that* result: `method` is [`Method::TrustRegion`], the counts and
/// the time add both phases. Without Hessian-vector products, or if the trust region fails to
/// start, the stalled result is returned as it is (not converged).
fn finish_by_trust_region<Q: OptimProblem + ?Sized>(
    m: &Minimizer<'_, Q>,
    stalled: OptimResult,
    opts: &OptimOptions,
) -> Result<OptimResult> {
    if m.problem.hessian().is_none() {
        return Ok(stalled);
    }
    let tr = OptimOptions {
        method: Method::TrustRegion,
        ..opts.clone()
    };
    let finisher = Minimizer {
        problem: m.problem,
        opts: tr,
        observers: m.observers.clone(),
    };
    let Ok(mut t) = finisher.run(&stalled.theta) else {
        return Ok(stalled);
    };
    t.iterations += stalled.iterations;
    t.cost_evals += stalled.cost_evals;
    t.gradient_evals += stalled.gradient_evals;
    t.seconds += stalled.seconds;
    t.initial_gradient_norm = stalled.initial_gradient_norm;
    Ok(t)
}

/// The [`OptimResult`] of an [`OcpResult`]; `stop` is the message of the observer that stopped
/// the run, if one did.
fn result(r: OcpResult, opts: &OptimOptions, stop: Option<String>) -> OptimResult {
    let tolerance_met = r.projected_gradient_norm <= opts.grad_tol;
    let termination = match r.termination {
        ocp::OcpTermination::Converged if tolerance_met => Termination::GradientTolerance {
            gradient_norm: r.projected_gradient_norm,
            tolerance: opts.grad_tol,
        },
        ocp::OcpTermination::Converged => Termination::RelativeGradientTolerance {
            gradient_norm: r.projected_gradient_norm,
            initial: r.initial_gradient_norm,
            tolerance: opts.rel_grad_tol,
        },
        // `minimize` keeps `final_gradient` on; a budget is an iteration limit all the same.
        ocp::OcpTermination::MaxIterations | ocp::OcpTermination::Budget => {
            Termination::MaxIterations {
                max_iters: opts.max_iters,
            }
        }
        // No accepted decrease (regularisation at its limit, or below J's round-off).
        ocp::OcpTermination::RegularisationLimit | ocp::OcpTermination::RoundOff => {
            Termination::LineSearchStalled
        }
        ocp::OcpTermination::Stopped => Termination::Observer {
            message: stop.unwrap_or_default(),
        },
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

#[cfg(test)]
mod tests {
    use std::sync::{Arc, Mutex};

    use argmin::core::{Error as ArgminError, State, KV};

    use super::*;
    use crate::optimize::{History, Observe, ObservedState, ObserverMode};
    use crate::{catalogue, BendingObjective, ControlProblem, Parametrisation, PerStepControl};

    /// What an observer was called with: the runs' names, then per run the iterations seen and
    /// whether `observe_final` came.
    #[derive(Clone, Default)]
    struct Calls(Arc<Mutex<Vec<(String, usize, bool)>>>);

    impl Calls {
        fn runs(&self) -> Vec<(String, usize, bool)> {
            self.0.lock().unwrap().clone()
        }
    }

    impl Observe<ObservedState> for Calls {
        fn observe_init(
            &mut self,
            name: &str,
            _state: &ObservedState,
            _kv: &KV,
        ) -> std::result::Result<(), ArgminError> {
            self.0.lock().unwrap().push((name.to_string(), 0, false));
            Ok(())
        }
        fn observe_iter(
            &mut self,
            state: &ObservedState,
            kv: &KV,
        ) -> std::result::Result<(), ArgminError> {
            let mut runs = self.0.lock().unwrap();
            let run = runs.last_mut().expect("observe_init came first");
            assert!(!run.2, "an iteration after observe_final");
            // Numbered from 0 within the run, one call per iteration.
            assert_eq!(state.get_iter(), run.1 as u64);
            for key in [
                "alpha",
                "regularisation",
                "projected_grad_norm",
                "grad_norm",
            ] {
                assert!(kv.get(key).is_some(), "{key} missing from the log");
            }
            run.1 += 1;
            Ok(())
        }
        fn observe_final(
            &mut self,
            _state: &ObservedState,
        ) -> std::result::Result<(), ArgminError> {
            let mut runs = self.0.lock().unwrap();
            runs.last_mut().expect("observe_init came first").2 = true;
            Ok(())
        }
    }

    /// Stops the run after `after` iterations.
    struct StopAfter(usize);

    impl Observe<ObservedState> for StopAfter {
        fn observe_iter(
            &mut self,
            state: &ObservedState,
            _kv: &KV,
        ) -> std::result::Result<(), ArgminError> {
            if state.get_iter() + 1 >= self.0 as u64 {
                return Err(ArgminError::msg("seen enough"));
            }
            Ok(())
        }
    }

    /// Thesis Table 3.4's per-step control on the n = 5 riser (N = 10, 11 parameters), with an
    /// effort penalty and a bound so that both structured solvers converge from u = 0 without
    /// the trust-region hand-over (the `ocp` module's example problem).
    fn table_problem() -> ControlProblem {
        let map = Parametrisation::PerStep(PerStepControl { steps: 10 });
        let objective = BendingObjective::summed_moment().with_effort(0.01);
        ControlProblem::builder(&catalogue::riser(5))
            .map(map)
            .objective(objective)
            .build_in::<2>()
            .unwrap()
    }

    fn opts(method: Method) -> OptimOptions {
        OptimOptions {
            method,
            bound: Some(100.0),
            ..OptimOptions::default()
        }
    }

    /// Each structured solver calls the observers once at the start, once per accepted
    /// iteration (as many as the result's `iterations`, which the solver counts itself) and
    /// once at the end; the points shown are the solver's iterates (the last is the result,
    /// bit for bit), each with J and ∇J of the problem; and observing does not change the run:
    /// the result is bit for bit that of the same call without observers.
    #[test]
    fn observers_see_every_iteration_of_the_structured_solvers() {
        let problem = table_problem();
        let theta0 = vec![0.0; 11];
        for method in [Method::Riccati, Method::Condensed] {
            let calls = Calls::default();
            let history = History::default();
            let r = Minimizer::new(&problem, opts(method))
                .add_observer(calls.clone(), ObserverMode::Always)
                .add_observer(history.clone(), ObserverMode::Always)
                .run(&theta0)
                .unwrap();
            assert!(r.converged, "{method}: {}", r.termination);
            assert_eq!(r.method, method, "no trust-region hand-over here");
            assert!(r.iterations >= 2, "{method}: {} iterations", r.iterations);
            assert_eq!(
                calls.runs(),
                vec![(method.name().to_string(), r.iterations, true)]
            );
            let h = history.records();
            assert_eq!(h.len(), 1 + r.iterations);
            assert_eq!(h[0].theta, theta0);
            let last = h.last().unwrap();
            assert_eq!(last.theta, r.theta);
            assert_eq!(last.objective.to_bits(), r.objective.to_bits());
            for rec in &h {
                let (j, g) = problem.value_and_gradient(&rec.theta).unwrap();
                assert_eq!(rec.objective.to_bits(), j.to_bits());
                assert_eq!(rec.gradient_norm.to_bits(), norm(&g).to_bits());
            }
            let plain = crate::optimize::minimize(&problem, &theta0, &opts(method)).unwrap();
            assert_eq!(plain.theta, r.theta, "{method}: observing changed the run");
            assert_eq!(plain.iterations, r.iterations);
            assert_eq!(plain.objective.to_bits(), r.objective.to_bits());
        }
    }

    /// An observer's error stops a structured solver where it is (after that iteration), as it
    /// stops an argmin one, and under `auto` it ends the call: no fallback, no companion run.
    #[test]
    fn an_observer_stops_a_structured_solver() {
        let problem = table_problem();
        let theta0 = vec![0.0; 11];
        for method in [Method::Riccati, Method::Condensed, Method::Auto] {
            let calls = Calls::default();
            let r = Minimizer::new(&problem, opts(method))
                .add_observer(calls.clone(), ObserverMode::Always)
                .add_observer(StopAfter(2), ObserverMode::Always)
                .run(&theta0)
                .unwrap();
            let stopped = matches!(
                &r.termination,
                Termination::Observer { message } if message.contains("seen enough")
            );
            assert!(stopped, "{method}: {}", r.termination);
            assert!(!r.converged);
            assert_eq!(r.iterations, 2, "{method}");
            let runs = calls.runs();
            assert_eq!(runs.len(), 1, "{method}: {runs:?}");
            assert_eq!(runs[0].1, 2);
            let (j, g) = problem.value_and_gradient(&r.theta).unwrap();
            assert_eq!(r.objective.to_bits(), j.to_bits());
            assert_eq!(r.gradient_norm.to_bits(), norm(&g).to_bits());
        }
    }
}
