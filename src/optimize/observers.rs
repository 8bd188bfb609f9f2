//! Observers of a [`minimize`](super::minimize) run: argmin's [`Observe`] trait on the state in
//! the problem's own terms ([`ObservedState`]), added with
//! [`Minimizer::add_observer`](super::Minimizer::add_observer).
//!
//! # What an observer sees
//! argmin's solvers run on s·J in the solver variables φ (scaled, and sine-reparametrised under
//! a force bound; module docs of [`optimize`](super)). Observers would have to undo both, and a
//! run may span several argmin executors (restarts) plus the gradient polish. So the run's own
//! [`Executor::add_observer`](argmin::core::Executor::add_observer) receives one bridge, which
//! turns every argmin iteration into an [`ObservedState`] holding θ, J(θ) and ∇_θJ(θ), numbered
//! over the whole run, and hands it, with argmin's key-value log of that iteration (plus
//! `grad_norm` = ‖∇_θJ‖), to the user's observers under their [`ObserverMode`](super::ObserverMode)s (argmin's own
//! [`Observers`] container does the filtering, so `NewBest` and `Every(k)` mean what they mean
//! in argmin). Then:
//! - `observe_init` once, at the start θ₀ (iteration 0), with the solver's name;
//! - `observe_iter` after each iteration of every executor run (restarts included; a restart's
//!   own initialisation is not an iteration and is not reported) and after each accepted polish
//!   step (key `polish` = true);
//! - `observe_final` once, at the result, with argmin's `SolverConverged` as the termination
//!   reason of a converged run and `SolverExit(why)` otherwise.
//!
//! The structured solvers ([`Method::Riccati`](super::Method::Riccati),
//! [`Method::Condensed`](super::Method::Condensed)) are shown the same way: `observe_init` at
//! θ₀, `observe_iter` after each accepted iteration (log keys `alpha`, `regularisation`,
//! `projected_grad_norm` before the step), `observe_final` at the result, with θ, J and ∇_θJ
//! evaluated by the problem itself.
//!
//! An observer that returns an error stops the run: [`minimize`](super::minimize) returns the
//! point reached with [`Termination::Observer`].

use std::sync::{Arc, Mutex};

use argmin::core::observers::{Observe, Observers};
use argmin::core::{IterState, KvValue, State, TerminationReason, KV};

use super::point::Point;
use super::{norm, ArgminError, Termination};

/// The state observers see: parameter θ, cost J(θ), gradient ∇_θJ(θ), iteration number over
/// the whole run (not the solver's scaled or reparametrised variables).
pub type ObservedState = IterState<Vec<f64>, Vec<f64>, (), (), (), f64>;

/// The user's observers and the state they are shown.
pub(crate) struct Relay {
    observers: Observers<ObservedState>,
    state: Option<ObservedState>,
}

impl Relay {
    pub(crate) fn new(observers: Observers<ObservedState>, max_iters: u64, target: f64) -> Self {
        Relay {
            observers,
            state: Some(
                ObservedState::new()
                    .max_iters(max_iters)
                    .target_cost(target),
            ),
        }
    }

    fn show(&mut self, at: Seen<'_>) -> ObservedState {
        let mut s = self
            .state
            .take()
            .unwrap_or_default()
            .param(at.theta.to_vec())
            .cost(at.value)
            .gradient(at.gradient.to_vec());
        s.update();
        s
    }

    /// Iteration 0: the start.
    pub(crate) fn init(&mut self, name: &str, p: &Point) -> Result<(), ArgminError> {
        self.init_at(name, Seen::of(p))
    }

    /// Iteration 0 at `at`.
    pub(crate) fn init_at(&mut self, name: &str, at: Seen<'_>) -> Result<(), ArgminError> {
        let s = self.show(at);
        let kv = KV::new().merge(grad_kv(at.gradient));
        let out = self.observers.observe_init(name, &s, &kv);
        self.state = Some(s);
        out
    }

    /// One iteration ending at `p`, with the solver's log `kv`.
    pub(crate) fn iter(&mut self, p: &Point, kv: &KV) -> Result<(), ArgminError> {
        self.iter_at(Seen::of(p), kv)
    }

    /// One iteration ending at `at`, with the solver's log `kv`.
    pub(crate) fn iter_at(&mut self, at: Seen<'_>, kv: &KV) -> Result<(), ArgminError> {
        let mut s = self.show(at);
        let kv = kv.clone().merge(grad_kv(at.gradient));
        let out = self.observers.observe_iter(&s, &kv);
        s.increment_iter();
        self.state = Some(s);
        out
    }

    /// The end of the run at `p`.
    pub(crate) fn finish(&mut self, p: &Point, t: &Termination) -> Result<(), ArgminError> {
        self.finish_at(Seen::of(p), t)
    }

    /// The end of the run at `at`.
    pub(crate) fn finish_at(&mut self, at: Seen<'_>, t: &Termination) -> Result<(), ArgminError> {
        let s = self.show(at).terminate_with(if t.is_converged() {
            TerminationReason::SolverConverged
        } else {
            TerminationReason::SolverExit(t.to_string())
        });
        let out = self.observers.observe_final(&s);
        self.state = Some(s);
        out
    }
}

/// A point as the observers are shown it: θ, J(θ) and ∇_θJ(θ).
#[derive(Clone, Copy, Debug)]
pub(crate) struct Seen<'a> {
    pub(crate) theta: &'a [f64],
    pub(crate) value: f64,
    pub(crate) gradient: &'a [f64],
}

impl<'a> Seen<'a> {
    fn of(p: &'a Point) -> Self {
        Seen {
            theta: &p.theta,
            value: p.value,
            gradient: &p.grad_theta,
        }
    }
}

fn grad_kv(gradient: &[f64]) -> KV {
    let mut kv = KV::new();
    kv.insert("grad_norm", KvValue::Float(norm(gradient)));
    kv
}

/// One entry of a [`History`].
#[derive(Clone, Debug, PartialEq)]
pub struct Record {
    /// 0 for the start, then the iteration after which the point was reached.
    pub iteration: u64,
    /// θ.
    pub theta: Vec<f64>,
    /// J(θ).
    pub objective: f64,
    /// ‖∇_θJ(θ)‖.
    pub gradient_norm: f64,
    /// Whether a gradient-polish step (not a solver iteration) reached it.
    pub polish: bool,
}

/// Records the start and every observed iteration: the iteration history of a run without
/// re-running it (of an argmin solver: L-BFGS here). Clones share one record list, so keep a
/// clone and read it after the run:
/// ```
/// use chainbeam::optimize::{History, Method, Minimizer, ObserverMode, OptimOptions};
/// use chainbeam::{catalogue, BendingObjective, ControlProblem, Parametrisation};
///
/// let problem = ControlProblem::builder(&catalogue::riser(10))
///     .map(Parametrisation::Constant)
///     .objective(BendingObjective::final_moment())
///     .build()?;
/// let history = History::default();
/// let lbfgs = OptimOptions { method: Method::Lbfgs, ..OptimOptions::default() };
/// let r = Minimizer::new(&problem, lbfgs)
///     .add_observer(history.clone(), ObserverMode::Always)
///     .run(&[0.0])?;
/// let h = history.records();
/// assert_eq!(h[0].theta, vec![0.0]); // the start
/// assert_eq!(h.last().unwrap().theta, r.theta); // the result
/// assert_eq!(h.len(), 1 + r.iterations + r.polish_steps);
/// # Ok::<(), chainbeam::Error>(())
/// ```
#[derive(Clone, Debug, Default)]
pub struct History {
    records: Arc<Mutex<Vec<Record>>>,
}

impl History {
    /// A copy of the records so far.
    pub fn records(&self) -> Vec<Record> {
        self.records
            .lock()
            .map(|r| r.clone())
            .unwrap_or_else(|e| e.into_inner().clone())
    }

    fn push(&self, state: &ObservedState, kv: &KV) {
        let theta = state.get_param().cloned().unwrap_or_default();
        let gradient_norm = state.get_gradient().map_or(f64::NAN, |g| norm(g));
        let polish = kv
            .get("polish")
            .and_then(KvValue::get_bool)
            .unwrap_or(false);
        let rec = Record {
            iteration: state.get_iter(),
            theta,
            objective: state.get_cost(),
            gradient_norm,
            polish,
        };
        match self.records.lock() {
            Ok(mut r) => r.push(rec),
            Err(e) => e.into_inner().push(rec),
        }
    }
}

impl Observe<ObservedState> for History {
    fn observe_init(
        &mut self,
        _name: &str,
        state: &ObservedState,
        kv: &KV,
    ) -> Result<(), ArgminError> {
        self.push(state, kv);
        Ok(())
    }

    fn observe_iter(&mut self, state: &ObservedState, kv: &KV) -> Result<(), ArgminError> {
        let mut s = state.clone();
        s.increment_iter();
        self.push(&s, kv);
        Ok(())
    }
}
