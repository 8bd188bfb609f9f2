//! Local minimisation of a [`ControlProblem`] with [argmin]: L-BFGS with the More-Thuente line
//! search, a trust region with Steihaug's truncated conjugate gradients, and Newton-CG, all driven
//! by the exact discrete-adjoint gradient and exact Hessian-vector products (forward-over-adjoint;
//! the Hessian is never formed).
//!
//! # The argmin problem
//! [`ArgminAdapter`] is the control problem as an argmin problem: it implements
//! [`CostFunction`], [`Gradient`] and [`Hessian`] over `Vec<f64>`. One adjoint sweep gives the
//! objective *and* the gradient, so the adapter caches the last point: the solvers' usual
//! cost-then-gradient calls at one point cost one sweep, not two. Its [`Hessian`] is a
//! [`HessianOperator`] (the point and the problem), which implements
//! [`ArgminDot<Vec<f64>, Vec<f64>>`](ArgminDot) by [`ControlProblem::hessian_vec`]; argmin-math's
//! blanket `ArgminWeightedDot` for `Vec<f64>` (`p·(H v)`) then serves Steihaug and the trust
//! region. `ArgminDot` cannot fail, so an HVP error is stored in the adapter's shared state, the
//! operator answers zeros from then on, every later cost or gradient request fails, and
//! [`minimize`] returns the stored, typed error after the run (a NaN never reaches a solver).
//!
//! **Scaling.** [`minimize`] hands argmin s·J with s = 1/‖∇J(θ₀)‖: the first L-BFGS trial step
//! −s g₀ is then 1 N long whatever the objective's size (the thesis's objectives span 10⁻¹⁶ to
//! 10² N²m²), and argmin's Steihaug, whose tolerance (10⁻⁹) is also an *absolute* test (it returns
//! a zero step once ‖g‖ < 10⁻⁹, and the trust region then stalls on ρ = 0/0), acts relative to
//! ‖g₀‖. Results, tolerances and the progress output are in J's own units.
//!
//! # Bounded controls: a sine reparametrisation
//! argmin has no bound-constrained quasi-Newton method (no L-BFGS-B). With a force limit
//! `bound = Some(b)` the solvers work in unconstrained variables φ with, componentwise (the
//! variable transformation of MINUIT),
//! ```text
//! θ = b sin(φ/b),   dθ/dφ = cos(φ/b) =: J,   d²θ/dφ² = −sin(φ/b)/b = −θ/b²,
//! g_φ = J ⊙ g_θ,    H_φ v = J ⊙ H_θ (J ⊙ v) + (g_θ ⊙ d²θ/dφ²) ⊙ v     (exact chain rule).
//! ```
//! Why this and not the alternatives:
//! - *Projection* breaks the curvature pairs of L-BFGS and the quadratic model of the trust
//!   region (argmin's solvers would need rewriting as L-BFGS-B / projected trust region).
//! - *tanh* (θ = b tanh(φ/b)) reaches the bound only as φ → ∞: an active bound is approached with
//!   exponentially vanishing gradients and no finite minimiser, so solvers stall instead of
//!   converging.
//! - *sine* reaches the bound at the finite φ = ±bπ/2, where g_φ = 0 and, if the bound is active
//!   (g_θ pushes outward), H_φ has the positive entry |g_θ|/b: the bounded optimum is a regular
//!   local minimum in φ, found at the solvers' usual (superlinear) rates. |θ| ≤ b holds exactly in
//!   floating point (|sin| ≤ 1). Near θ = 0, φ ≈ θ, so tolerances and trust radii keep their
//!   units (N).
//!
//! The price: every bound point is a stationary point in φ. Where g_θ points *inward* it is a
//! saddle or maximum in φ, which descent methods leave; but a start exactly on the bound would
//! not move, so a θ₀ closer than 10⁻⁴·b to the bound is moved that far inside. For the built-in
//! parametrisations ([`Parametrisation`](crate::Parametrisation)) θ are the forces themselves (or
//! copies of them), so |θ| ≤ b bounds every u_k; for another [`ControlMap`] the bound still acts
//! on θ, and [`minimize`] checks |u_k| ≤ b at the end (an error if the map broke it).
//!
//! # Stopping
//! Whichever comes first (each is checked after every iteration, in the solver's variables φ; φ =
//! θ without a bound):
//! - gradient: ‖g‖ ≤ `grad_tol` or ‖g‖ ≤ `rel_grad_tol`·‖g₀‖ (converged);
//! - cost: an accepted step changed J by at most `cost_rel_tol`·max(|J_old|, |J_new|)
//!   (converged; argmin's own L-BFGS `tol_cost` is *absolute*, so it is switched off and this
//!   relative test is used instead);
//! - `target_cost`: argmin's test best J ≤ target (converged);
//! - `max_iters` iterations in total (not converged);
//! - no progress: the line search returned its start point or failed, or the trust region
//!   rejected 20 steps in a row (its radius has then shrunk by 4²⁰ ≈ 10¹²; not converged).
//!
//! A line search that failed because a trial point's simulation failed (argmin's L-BFGS turns any
//! line-search error into a normal exit) restarts the solver from the best point, at most
//! `max_restarts` times, with the restart's first step shortened tenfold each time. The trust
//! region treats a trial point whose simulation fails (e.g. a folded beam) as J = +∞: the step is
//! rejected and the radius shrinks, the textbook extended-value rule; such failures are counted.
//!
//! # Gradient polish
//! Near a flat minimum the objective's round-off hides the last digits from every cost-based
//! test. On the thesis riser (constant control, c_sum, load at node 5) J has round-off noise of
//! about 4·10⁻¹³ (2·10⁻¹³ relative) while ∇J is accurate to about 4·10⁻¹⁵: along u the true
//! change ½ J'' δ² falls below the noise for δ < 4·10⁻⁵ N, so the line search and the trust-region
//! ratio stall at ‖g‖/‖g₀‖ ≈ 10⁻⁷. When a run stops short of the gradient tolerance for lack of
//! progress (or by the cost-change test), [`minimize`] therefore takes up to `polish_steps`
//! Newton steps on ∇J = 0 with the gradient norm as merit: p solves H p = −g by CG on exact HVPs
//! (no step if CG meets non-positive curvature: then the point is not near a minimum), and φ + p
//! is accepted if it reduces ‖g‖ and raises J by at most [`POLISH_COST_TOL`]·|J| (round-off);
//! otherwise p/2 and p/4 are tried. The polish is a refinement: if one of its HVPs fails, it
//! stops, the point reached so far is returned and `termination` says why.
//!
//! # Reference
//! J. Nocedal, S. J. Wright, *Numerical Optimization*, 2nd ed., Springer 2006: L-BFGS (Alg. 7.5),
//! More-Thuente line search (§3.5), trust region with Steihaug CG (Alg. 4.1, 7.2), Newton-CG
//! (Alg. 7.1). F. James, M. Roos, MINUIT, CERN (the sine transformation for bounded parameters).

use std::cell::{Cell, RefCell};
use std::fmt;
use std::rc::Rc;
use std::str::FromStr;
use std::time::Instant;

use argmin::core::observers::{Observe, ObserverMode};
use argmin::core::{
    CostFunction, Executor, Gradient, Hessian, IterState, KvValue, LineSearch, Problem, Solver,
    State, TerminationReason, TerminationStatus, KV,
};
use argmin::solver::linesearch::MoreThuenteLineSearch;
use argmin::solver::newton::NewtonCG;
use argmin::solver::quasinewton::LBFGS;
use argmin::solver::trustregion::{Steihaug, TrustRegion};
use argmin_math::ArgminDot;

use crate::adjoint::{ControlMap, ControlProblem, Objective};
use crate::error::{Error, Result};

type ArgminError = argmin::core::Error;

/// A start closer than this fraction of the bound to ±b is moved this far inside (the bound is
/// a stationary point of the sine reparametrisation).
const BOUND_PULL_IN: f64 = 1e-4;
/// A component within this fraction of b of ±b counts as on the bound (for
/// [`OptimResult::active_bounds`] and the projected gradient).
pub const ACTIVE_BOUND_TOL: f64 = 1e-6;
/// Consecutive rejected trust-region steps after which the run stops for lack of progress (the
/// radius has then shrunk by at least 4²⁰ ≈ 10¹²).
const MAX_REJECTIONS: usize = 20;
/// The gradient polish accepts a step that raises J by at most this fraction of |J| (J's
/// round-off; measured 2·10⁻¹³ on the thesis riser, see the module docs).
pub const POLISH_COST_TOL: f64 = 1e-10;
/// Relative residual at which the polish's CG stops.
const POLISH_CG_TOL: f64 = 1e-10;
/// HVP products remembered by one [`HessianOperator`] (Steihaug asks for d·(H d) and then H d).
const HVP_CACHE: usize = 4;

/// The local solver.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum Method {
    /// L-BFGS (memory [`OptimOptions::lbfgs_memory`]) with the More-Thuente line search: one
    /// adjoint sweep per line-search trial, no HVPs. The default.
    #[default]
    Lbfgs,
    /// Trust region (Nocedal-Wright Alg. 4.1) with Steihaug's truncated CG on exact HVPs; handles
    /// indefinite Hessians and rejects trial points where the simulation fails.
    TrustRegion,
    /// Newton-CG with the More-Thuente line search on exact HVPs. argmin's version compares the
    /// *squared* CG residual with the forcing term min(½, √‖g‖)‖g‖, so once ‖g‖ < 1 its inner
    /// solves stop early and it slows to gradient-descent-like steps; prefer the trust region.
    NewtonCg,
}

impl Method {
    /// The name used on the command line: `lbfgs`, `trust-region` or `newton-cg`.
    pub fn name(self) -> &'static str {
        match self {
            Method::Lbfgs => "lbfgs",
            Method::TrustRegion => "trust-region",
            Method::NewtonCg => "newton-cg",
        }
    }
}

impl fmt::Display for Method {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

impl FromStr for Method {
    type Err = Error;
    fn from_str(s: &str) -> Result<Self> {
        match s {
            "lbfgs" | "l-bfgs" => Ok(Method::Lbfgs),
            "trust-region" | "trustregion" => Ok(Method::TrustRegion),
            "newton-cg" | "newtoncg" => Ok(Method::NewtonCg),
            _ => Err(Error::InvalidArgument {
                name: "method",
                reason: format!("unknown method `{s}` (expected lbfgs, trust-region or newton-cg)"),
            }),
        }
    }
}

/// Options of [`minimize`]. Build with struct update syntax:
/// `OptimOptions { method: Method::TrustRegion, ..Default::default() }`.
#[derive(Clone, Debug, PartialEq)]
pub struct OptimOptions {
    /// The solver. Default [`Method::Lbfgs`]: the cheapest per iteration (one adjoint sweep per
    /// line-search trial, no HVPs) and robust on the thesis problems.
    pub method: Method,
    /// Iterations in total over all restarts. Default 1000: the thesis problems have 1 to N + 1 =
    /// 11 parameters and converge in tens of iterations, an iteration costs about one
    /// simulation, so the limit only stops runs that cannot make progress.
    pub max_iters: usize,
    /// Absolute gradient tolerance: stop when ‖g‖ ≤ `grad_tol`. Default 0 (off): the thesis
    /// objectives range from 10⁻¹⁶ to 10² N²m², so no absolute value fits them all.
    pub grad_tol: f64,
    /// Relative gradient tolerance: stop when ‖g‖ ≤ `rel_grad_tol`·‖g₀‖ (g₀ at the start).
    /// Default 10⁻⁸: the adjoint gradient is exact to round-off, so eight orders of reduction are
    /// reachable, and with superlinear convergence the last order costs one or two iterations.
    pub rel_grad_tol: f64,
    /// Relative cost-change tolerance: stop when an accepted step changed J by at most
    /// `cost_rel_tol`·max(|J_old|, |J_new|). Default 4ε ≈ 8.9·10⁻¹⁶: steps below that only move
    /// round-off, so this ends runs whose gradient tolerance cannot be reached, without cutting
    /// short the slow phase of a flat landscape (SPEC §4: c_sum is very flat near its minimum).
    pub cost_rel_tol: f64,
    /// argmin's target: stop when J ≤ `target_cost`. Default −∞ (off).
    pub target_cost: f64,
    /// Force limit |θ_i| ≤ u_max (see the module docs). Default `None`.
    pub bound: Option<f64>,
    /// L-BFGS memory m. Default 10 (more pairs than the thesis problems have parameters).
    pub lbfgs_memory: usize,
    /// Initial trust radius, in the units of θ (N). Default 10 N: the thesis's optimal forces are
    /// 1-300 N, so the radius reaches them in a few doublings.
    pub trust_radius: f64,
    /// Largest trust radius (N). Default 10⁴ N, beyond any force the thesis's tables use.
    pub max_trust_radius: f64,
    /// Inner CG iterations per trust-region or Newton-CG step; `None` (default) means 2·n_params,
    /// twice what exact arithmetic needs.
    pub cg_max_iters: Option<usize>,
    /// Restarts after a line search that failed because a trial point's simulation failed
    /// (module docs). Default 3.
    pub max_restarts: usize,
    /// Newton steps of the gradient polish (module docs); 0 turns it off. Default 5: from where
    /// cost-based globalisation stalls one or two quadratically convergent steps suffice.
    pub polish_steps: usize,
    /// Print iteration, cost and ‖g‖ to stderr through an argmin observer. Default `false`.
    pub progress: bool,
}

impl Default for OptimOptions {
    fn default() -> Self {
        OptimOptions {
            method: Method::Lbfgs,
            max_iters: 1000,
            grad_tol: 0.0,
            rel_grad_tol: 1e-8,
            cost_rel_tol: 4.0 * f64::EPSILON,
            target_cost: f64::NEG_INFINITY,
            bound: None,
            lbfgs_memory: 10,
            trust_radius: 10.0,
            max_trust_radius: 1e4,
            cg_max_iters: None,
            max_restarts: 3,
            polish_steps: 5,
            progress: false,
        }
    }
}

impl OptimOptions {
    /// Checks every field (an [`Error::InvalidArgument`] naming it).
    pub fn validate(&self) -> Result<()> {
        let bad = |name: &'static str, reason: String| Err(Error::InvalidArgument { name, reason });
        let nonneg = |x: f64| x.is_finite() && x >= 0.0;
        if !nonneg(self.grad_tol) {
            return bad(
                "grad_tol",
                format!("must be finite and >= 0, got {}", self.grad_tol),
            );
        }
        if !nonneg(self.rel_grad_tol) {
            return bad(
                "rel_grad_tol",
                format!("must be finite and >= 0, got {}", self.rel_grad_tol),
            );
        }
        if !nonneg(self.cost_rel_tol) {
            return bad(
                "cost_rel_tol",
                format!("must be finite and >= 0, got {}", self.cost_rel_tol),
            );
        }
        if self.target_cost.is_nan() {
            return bad("target_cost", "must not be NaN".into());
        }
        if let Some(b) = self.bound {
            if !(b.is_finite() && b > 0.0) {
                return bad("bound", format!("must be positive and finite, got {b}"));
            }
        }
        if self.lbfgs_memory == 0 {
            return bad("lbfgs_memory", "must be at least 1".into());
        }
        if !(self.trust_radius.is_finite() && self.trust_radius > 0.0) {
            return bad(
                "trust_radius",
                format!("must be positive and finite, got {}", self.trust_radius),
            );
        }
        if !(self.max_trust_radius.is_finite() && self.max_trust_radius >= self.trust_radius) {
            return bad(
                "max_trust_radius",
                format!(
                    "must be finite and >= trust_radius = {}, got {}",
                    self.trust_radius, self.max_trust_radius
                ),
            );
        }
        if self.cg_max_iters == Some(0) {
            return bad("cg_max_iters", "must be at least 1".into());
        }
        Ok(())
    }
}

/// The outcome of [`minimize`].
#[derive(Clone, Debug, PartialEq)]
pub struct OptimResult {
    /// J(θ) at the result.
    pub objective: f64,
    /// The parameters θ.
    pub theta: Vec<f64>,
    /// The forces u_0..u_N of θ (within the bound, if one was given).
    pub controls: Vec<f64>,
    /// ‖∇_θ J‖ of the original problem at θ (not zero at an active bound).
    pub gradient_norm: f64,
    /// ‖∇_θ J‖ at the start θ₀ (moved inside the bound if it was on it).
    pub initial_gradient_norm: f64,
    /// The projected-gradient (first-order KKT) measure: ‖∇_θ J‖ with the components removed
    /// whose bound is active and blocks descent. Equals `gradient_norm` without a bound.
    pub projected_gradient_norm: f64,
    /// Indices i with |θ_i| ≥ (1 − [`ACTIVE_BOUND_TOL`])·u_max.
    pub active_bounds: Vec<usize>,
    /// Iterations, over all restarts (L-BFGS / Newton-CG: line searches; trust region:
    /// subproblem solves, accepted or rejected).
    pub iterations: usize,
    /// Objective values requested by the solvers (answered from the one-point cache when the
    /// point was already swept).
    pub cost_evals: usize,
    /// Adjoint sweeps run; each yields J and ∇J, so this is also the number of simulations.
    pub gradient_evals: usize,
    /// Hessian-vector products run (forward-over-adjoint sweeps in dual numbers).
    pub hvp_evals: usize,
    /// Trial points whose simulation failed (trust region: treated as J = +∞; line searches:
    /// ended the search).
    pub failed_evals: usize,
    /// Restarts after failed line searches.
    pub restarts: usize,
    /// Accepted Newton steps of the gradient polish.
    pub polish_steps: usize,
    /// Wall-clock time of [`minimize`] in seconds.
    pub seconds: f64,
    /// Whether a convergence test (gradient, cost change or target) stopped the run.
    pub converged: bool,
    /// Why the run stopped.
    pub termination: String,
    /// The solver used.
    pub method: Method,
}

// ---------------------------------------------------------------------------------------------
// Shared evaluation state
// ---------------------------------------------------------------------------------------------

/// One evaluated point.
#[derive(Clone, Debug)]
struct Point {
    phi: Vec<f64>,
    theta: Vec<f64>,
    value: f64,
    grad_theta: Vec<f64>,
    grad_phi: Vec<f64>,
}

/// Evaluation counts of an [`ArgminAdapter`] (shared with its Hessian operators).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct EvalCounts {
    /// Calls of [`CostFunction::cost`].
    pub cost_requests: usize,
    /// Calls of [`Gradient::gradient`].
    pub gradient_requests: usize,
    /// Adjoint sweeps run (cache misses).
    pub sweeps: usize,
    /// Hessian-vector products run.
    pub hvps: usize,
    /// Evaluations whose simulation failed.
    pub failures: usize,
    /// Iterations counted by [`minimize`]'s supervisor.
    pub iterations: usize,
}

#[derive(Default)]
struct Shared {
    cache: RefCell<Option<Point>>,
    best: RefCell<Option<Point>>,
    counts: Cell<EvalCounts>,
    last_failure: RefCell<Option<Error>>,
    fatal: RefCell<Option<Error>>,
}

impl Shared {
    fn bump(&self, f: impl FnOnce(&mut EvalCounts)) {
        let mut c = self.counts.get();
        f(&mut c);
        self.counts.set(c);
    }
    fn fatal(&self) -> Option<Error> {
        self.fatal.borrow().clone()
    }
}

fn same_bits(a: &[f64], b: &[f64]) -> bool {
    a.len() == b.len() && a.iter().zip(b).all(|(x, y)| x.to_bits() == y.to_bits())
}

fn norm(v: &[f64]) -> f64 {
    v.iter().map(|x| x * x).sum::<f64>().sqrt()
}

// ---------------------------------------------------------------------------------------------
// The argmin problem
// ---------------------------------------------------------------------------------------------

/// A [`ControlProblem`] as an argmin problem over `Vec<f64>`, in the solver variables φ (φ = θ
/// without a bound, θ = b sin(φ/b) with one; see the module docs).
///
/// Evaluations are cached by point (one adjoint sweep answers cost and gradient); the counts and
/// the first fatal error live in state shared with the [`HessianOperator`]s it hands out. Not
/// `Send` (the shared state is an `Rc`): build one per thread.
pub struct ArgminAdapter<'a, P, O> {
    problem: &'a ControlProblem<P, O>,
    bound: Option<f64>,
    scale: f64,
    extended_value: bool,
    cg_cap: usize,
    shared: Rc<Shared>,
}

impl<P, O> Clone for ArgminAdapter<'_, P, O> {
    fn clone(&self) -> Self {
        ArgminAdapter {
            problem: self.problem,
            bound: self.bound,
            scale: self.scale,
            extended_value: self.extended_value,
            cg_cap: self.cg_cap,
            shared: Rc::clone(&self.shared),
        }
    }
}

impl<'a, P: ControlMap, O: Objective> ArgminAdapter<'a, P, O> {
    /// The adapter for `problem` with an optional force bound |θ_i| ≤ b (b > 0, finite).
    pub fn new(problem: &'a ControlProblem<P, O>, bound: Option<f64>) -> Result<Self> {
        if let Some(b) = bound {
            if !(b.is_finite() && b > 0.0) {
                return Err(Error::InvalidArgument {
                    name: "bound",
                    reason: format!("must be positive and finite, got {b}"),
                });
            }
        }
        Ok(ArgminAdapter {
            problem,
            bound,
            scale: 1.0,
            extended_value: false,
            cg_cap: usize::MAX,
            shared: Rc::new(Shared::default()),
        })
    }

    /// Makes the argmin problem s·J (cost, gradient and Hessian products all scaled by s > 0,
    /// finite); [`minimize`] uses s = 1/‖∇J(θ₀)‖. Default 1.
    pub fn with_scale(mut self, s: f64) -> Self {
        if s.is_finite() && s > 0.0 {
            self.scale = s;
        }
        self
    }

    /// When `true`, a cost request whose simulation fails answers +∞ (for trust regions, which
    /// then reject the step) instead of an error. Default `false`.
    pub fn with_extended_value(mut self, on: bool) -> Self {
        self.extended_value = on;
        self
    }

    /// Distinct products one [`HessianOperator`] computes before it answers zeros (a truncation
    /// that makes a CG loop see zero curvature and stop; argmin's Newton-CG has no inner
    /// iteration limit). Default unlimited.
    pub fn with_hvp_cap(mut self, cap: usize) -> Self {
        self.cg_cap = cap.max(1);
        self
    }

    /// The control problem.
    pub fn problem(&self) -> &'a ControlProblem<P, O> {
        self.problem
    }

    /// θ of the solver variables φ.
    pub fn to_theta(&self, phi: &[f64]) -> Vec<f64> {
        match self.bound {
            None => phi.to_vec(),
            Some(b) => phi.iter().map(|&p| b * (p / b).sin()).collect(),
        }
    }

    /// φ of θ: an error if θ is not finite or outside the bound; components closer than
    /// 10⁻⁴·b to the bound are moved that far inside (the bound is stationary in φ).
    pub fn to_phi(&self, theta: &[f64]) -> Result<Vec<f64>> {
        if let Some(i) = theta.iter().position(|x| !x.is_finite()) {
            return Err(Error::InvalidArgument {
                name: "theta0",
                reason: format!("entry {i} is not finite"),
            });
        }
        match self.bound {
            None => Ok(theta.to_vec()),
            Some(b) => theta
                .iter()
                .enumerate()
                .map(|(i, &t)| {
                    if t.abs() > b {
                        return Err(Error::InvalidArgument {
                            name: "theta0",
                            reason: format!(
                                "entry {i} = {t} lies outside the force bound ±{b} (infeasible start)"
                            ),
                        });
                    }
                    let lim = b * (1.0 - BOUND_PULL_IN);
                    Ok(b * (t.clamp(-lim, lim) / b).asin())
                })
                .collect(),
        }
    }

    /// The counts so far.
    pub fn counts(&self) -> EvalCounts {
        self.shared.counts.get()
    }

    /// The fatal error (from an HVP) that stopped the run, if any; clears it.
    pub fn take_error(&self) -> Option<Error> {
        self.shared.fatal.borrow_mut().take()
    }

    /// J, ∇_θ J and ∇_φ J at φ by one adjoint sweep, or from the cache.
    fn evaluate(&self, phi: &[f64]) -> Result<Point> {
        if let Some(p) = self.shared.cache.borrow().as_ref() {
            if same_bits(&p.phi, phi) {
                return Ok(p.clone());
            }
        }
        if let Some(e) = self.shared.fatal() {
            return Err(e);
        }
        let theta = self.to_theta(phi);
        let (value, grad_theta) = self.problem.value_and_gradient(&theta)?;
        self.shared.bump(|c| c.sweeps += 1);
        if !value.is_finite() || grad_theta.iter().any(|g| !g.is_finite()) {
            return Err(Error::NonFinite {
                step: self.problem.steps(),
                quantity: "the objective or its gradient",
            });
        }
        let grad_phi = match self.bound {
            None => grad_theta.clone(),
            Some(b) => phi
                .iter()
                .zip(&grad_theta)
                .map(|(&p, &g)| (p / b).cos() * g)
                .collect(),
        };
        let point = Point {
            phi: phi.to_vec(),
            theta,
            value,
            grad_theta,
            grad_phi,
        };
        {
            let mut best = self.shared.best.borrow_mut();
            if best.as_ref().is_none_or(|b| point.value < b.value) {
                *best = Some(point.clone());
            }
        }
        *self.shared.cache.borrow_mut() = Some(point.clone());
        Ok(point)
    }

    fn failed(&self, e: Error) -> ArgminError {
        self.shared.bump(|c| c.failures += 1);
        *self.shared.last_failure.borrow_mut() = Some(e.clone());
        ArgminError::from(e)
    }
}

impl<P: ControlMap, O: Objective> CostFunction for ArgminAdapter<'_, P, O> {
    type Param = Vec<f64>;
    type Output = f64;

    fn cost(&self, phi: &Vec<f64>) -> std::result::Result<f64, ArgminError> {
        self.shared.bump(|c| c.cost_requests += 1);
        match self.evaluate(phi) {
            Ok(p) => Ok(p.value * self.scale),
            Err(e) if self.extended_value && self.shared.fatal().is_none() => {
                let _ = self.failed(e);
                Ok(f64::INFINITY)
            }
            Err(e) => Err(self.failed(e)),
        }
    }
}

impl<P: ControlMap, O: Objective> Gradient for ArgminAdapter<'_, P, O> {
    type Param = Vec<f64>;
    type Gradient = Vec<f64>;

    fn gradient(&self, phi: &Vec<f64>) -> std::result::Result<Vec<f64>, ArgminError> {
        self.shared.bump(|c| c.gradient_requests += 1);
        let s = self.scale;
        self.evaluate(phi)
            .map(|p| p.grad_phi.iter().map(|g| g * s).collect())
            .map_err(|e| self.failed(e))
    }
}

impl<'a, P: ControlMap, O: Objective> Hessian for ArgminAdapter<'a, P, O> {
    type Param = Vec<f64>;
    type Hessian = HessianOperator<'a, P, O>;

    fn hessian(&self, phi: &Vec<f64>) -> std::result::Result<Self::Hessian, ArgminError> {
        self.operator(phi).map_err(|e| self.failed(e))
    }
}

impl<'a, P: ControlMap, O: Objective> ArgminAdapter<'a, P, O> {
    /// The Hessian operator at φ (evaluates J and ∇J there, or takes them from the cache).
    pub fn operator(&self, phi: &[f64]) -> Result<HessianOperator<'a, P, O>> {
        let p = self.evaluate(phi)?;
        let (jac, curv) = match self.bound {
            None => (None, None),
            Some(b) => {
                let jac: Vec<f64> = phi.iter().map(|&x| (x / b).cos()).collect();
                let curv: Vec<f64> = p
                    .theta
                    .iter()
                    .zip(&p.grad_theta)
                    .map(|(&t, &g)| -g * t / (b * b))
                    .collect();
                (Some(jac), Some(curv))
            }
        };
        Ok(HessianOperator {
            problem: self.problem,
            theta: p.theta,
            scale: self.scale,
            jac,
            curv,
            cap: self.cg_cap,
            products: Cell::new(0),
            cache: RefCell::new(Vec::with_capacity(HVP_CACHE)),
            shared: Rc::clone(&self.shared),
        })
    }
}

/// ∇²J at one point as a linear operator v ↦ H v, by exact Hessian-vector products
/// ([`ControlProblem::hessian_vec`], chain-ruled to φ under a bound, times the adapter's scale
/// in the argmin product). Never forms H.
///
/// Implements [`ArgminDot<Vec<f64>, Vec<f64>>`](ArgminDot); `Vec<f64>`'s blanket
/// `ArgminWeightedDot` (p·(H v)) follows. A product that fails stores its error in the adapter's
/// shared state and answers zeros (as do all later products), and the adapter's next cost or
/// gradient request fails, so the run ends and [`minimize`] returns the error.
pub struct HessianOperator<'a, P, O> {
    problem: &'a ControlProblem<P, O>,
    theta: Vec<f64>,
    scale: f64,
    jac: Option<Vec<f64>>,
    curv: Option<Vec<f64>>,
    cap: usize,
    products: Cell<usize>,
    cache: RefCell<Vec<(Vec<f64>, Vec<f64>)>>,
    shared: Rc<Shared>,
}

impl<P, O> Clone for HessianOperator<'_, P, O> {
    fn clone(&self) -> Self {
        HessianOperator {
            problem: self.problem,
            theta: self.theta.clone(),
            scale: self.scale,
            jac: self.jac.clone(),
            curv: self.curv.clone(),
            cap: self.cap,
            products: self.products.clone(),
            cache: self.cache.clone(),
            shared: Rc::clone(&self.shared),
        }
    }
}

impl<P, O> fmt::Debug for HessianOperator<'_, P, O> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("HessianOperator")
            .field("theta", &self.theta)
            .field("bounded", &self.jac.is_some())
            .field("products", &self.products.get())
            .finish()
    }
}

impl<P: ControlMap, O: Objective> HessianOperator<'_, P, O> {
    /// θ at which the Hessian is taken.
    pub fn theta(&self) -> &[f64] {
        &self.theta
    }

    /// H v (of J itself, not scaled), or the HVP's error.
    pub fn apply(&self, v: &[f64]) -> Result<Vec<f64>> {
        if let Some(e) = self.shared.fatal() {
            return Err(e);
        }
        if v.iter().all(|x| x.to_bits() << 1 == 0) {
            return Ok(vec![0.0; v.len()]);
        }
        let w: Vec<f64> = match &self.jac {
            None => v.to_vec(),
            Some(j) => j.iter().zip(v).map(|(a, b)| a * b).collect(),
        };
        let hw = self.problem.hessian_vec(&self.theta, &w)?;
        self.shared.bump(|c| c.hvps += 1);
        let out: Vec<f64> = match (&self.jac, &self.curv) {
            (Some(j), Some(c)) => (0..v.len()).map(|i| j[i] * hw[i] + c[i] * v[i]).collect(),
            _ => hw,
        };
        if out.iter().any(|x| !x.is_finite()) {
            return Err(Error::NonFinite {
                step: self.problem.steps(),
                quantity: "the Hessian-vector product",
            });
        }
        Ok(out)
    }
}

impl<P: ControlMap, O: Objective> ArgminDot<Vec<f64>, Vec<f64>> for HessianOperator<'_, P, O> {
    fn dot(&self, v: &Vec<f64>) -> Vec<f64> {
        if let Some((_, hv)) = self.cache.borrow().iter().find(|(x, _)| same_bits(x, v)) {
            return hv.clone();
        }
        let zeros = || vec![0.0; v.len()];
        if self.shared.fatal().is_some() || self.products.get() >= self.cap {
            return zeros();
        }
        self.products.set(self.products.get() + 1);
        match self.apply(v) {
            Ok(mut hv) => {
                hv.iter_mut().for_each(|x| *x *= self.scale);
                let mut cache = self.cache.borrow_mut();
                if cache.len() == HVP_CACHE {
                    cache.remove(0);
                }
                cache.push((v.clone(), hv.clone()));
                hv
            }
            Err(e) => {
                self.shared.fatal.borrow_mut().get_or_insert(e);
                zeros()
            }
        }
    }
}

// ---------------------------------------------------------------------------------------------
// Supervisor: our stopping rules around any argmin solver
// ---------------------------------------------------------------------------------------------

/// How one executor run stopped.
#[derive(Clone, Debug, PartialEq)]
enum Stop {
    Converged(String),
    NoProgress(String),
}

/// Wraps an argmin solver with the stopping rules of [`OptimOptions`] (module docs) and reports
/// ‖g‖ to the observers under the key `grad_norm`.
struct Supervised<S> {
    inner: S,
    grad_tol: f64,
    rel_grad_tol: f64,
    gnorm0: f64,
    cost_rel_tol: f64,
    trust_region: bool,
    rejections: usize,
    stop: Option<Stop>,
    shared: Rc<Shared>,
    /// The adapter's scale s: argmin sees s·J, the tests use J.
    scale: f64,
}

impl<S> Supervised<S> {
    fn check_gradient(&mut self, gnorm: f64) {
        if gnorm <= self.grad_tol {
            self.stop = Some(Stop::Converged(format!(
                "gradient norm {gnorm:.3e} <= grad_tol {:.3e}",
                self.grad_tol
            )));
        } else if gnorm <= self.rel_grad_tol * self.gnorm0 {
            self.stop = Some(Stop::Converged(format!(
                "gradient norm {gnorm:.3e} <= rel_grad_tol {:.1e} x initial {:.3e}",
                self.rel_grad_tol, self.gnorm0
            )));
        }
    }
}

type St<H> = IterState<Vec<f64>, Vec<f64>, (), H, (), f64>;

impl<'a, P, O, H, S> Solver<ArgminAdapter<'a, P, O>, St<H>> for Supervised<S>
where
    P: ControlMap,
    O: Objective,
    S: Solver<ArgminAdapter<'a, P, O>, St<H>>,
{
    fn name(&self) -> &str {
        self.inner.name()
    }

    fn init(
        &mut self,
        problem: &mut Problem<ArgminAdapter<'a, P, O>>,
        state: St<H>,
    ) -> std::result::Result<(St<H>, Option<KV>), ArgminError> {
        let (state, kv) = self.inner.init(problem, state)?;
        if let Some(g) = state.get_gradient() {
            self.check_gradient(norm(g) / self.scale);
        }
        Ok((state, kv))
    }

    fn next_iter(
        &mut self,
        problem: &mut Problem<ArgminAdapter<'a, P, O>>,
        state: St<H>,
    ) -> std::result::Result<(St<H>, Option<KV>), ArgminError> {
        let old_param = state.get_param().cloned();
        let old_cost = state.get_cost();
        let (mut state, kv) = self.inner.next_iter(problem, state)?;
        self.shared.bump(|c| c.iterations += 1);
        let mut kv = kv.unwrap_or_default();
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
        kv.insert("grad_norm", KvValue::Float(gnorm));
        let moved = old_param.as_ref().is_none_or(|p| !same_bits(p, &param));
        if moved {
            self.rejections = 0;
        } else {
            self.rejections += 1;
        }
        self.check_gradient(gnorm);
        if self.stop.is_some() {
            return Ok((state, Some(kv)));
        }
        let cost = state.get_cost();
        if moved {
            let scale = old_cost.abs().max(cost.abs());
            let change = (old_cost - cost).abs();
            if old_cost.is_finite() && change <= self.cost_rel_tol * scale {
                self.stop = Some(Stop::Converged(format!(
                    "relative cost change {:.3e} <= cost_rel_tol {:.1e}",
                    if scale > 0.0 { change / scale } else { 0.0 },
                    self.cost_rel_tol
                )));
            }
        } else if !self.trust_region {
            self.stop = Some(Stop::NoProgress(
                "the line search returned its start point".into(),
            ));
        } else if self.rejections >= MAX_REJECTIONS {
            self.stop = Some(Stop::NoProgress(format!(
                "the trust region rejected {MAX_REJECTIONS} consecutive steps"
            )));
        }
        Ok((state, Some(kv)))
    }

    fn terminate(&mut self, state: &St<H>) -> TerminationStatus {
        match &self.stop {
            Some(Stop::Converged(_)) => {
                TerminationStatus::Terminated(TerminationReason::SolverConverged)
            }
            Some(Stop::NoProgress(s)) => {
                TerminationStatus::Terminated(TerminationReason::SolverExit(s.clone()))
            }
            None => self.inner.terminate(state),
        }
    }
}

/// Prints iteration, J and ‖∇J‖ to stderr (enabled by [`OptimOptions::progress`]); argmin's
/// costs are divided by `scale` (the adapter's [`ArgminAdapter::with_scale`]).
#[derive(Clone, Copy, Debug)]
pub struct ProgressObserver {
    /// The scale s of the argmin problem s·J.
    pub scale: f64,
}

impl<G, J, H, R> Observe<IterState<Vec<f64>, G, J, H, R, f64>> for ProgressObserver {
    fn observe_init(
        &mut self,
        name: &str,
        state: &IterState<Vec<f64>, G, J, H, R, f64>,
        _kv: &KV,
    ) -> std::result::Result<(), ArgminError> {
        eprintln!("{name}: start, cost {:.12e}", state.get_cost() / self.scale);
        Ok(())
    }

    fn observe_iter(
        &mut self,
        state: &IterState<Vec<f64>, G, J, H, R, f64>,
        kv: &KV,
    ) -> std::result::Result<(), ArgminError> {
        let g = kv
            .get("grad_norm")
            .and_then(KvValue::get_float)
            .map_or_else(|| "-".to_string(), |g| format!("{g:.3e}"));
        eprintln!(
            "iter {:>5}  cost {:.12e}  |g| {g}",
            state.get_iter() + 1,
            state.get_cost() / self.scale
        );
        Ok(())
    }
}

// ---------------------------------------------------------------------------------------------
// minimize
// ---------------------------------------------------------------------------------------------

/// How one executor run ended.
enum RunEnd {
    /// A convergence test (ours or argmin's target cost).
    Converged(String),
    /// The iteration budget.
    MaxIters,
    /// No progress, a failed line search or an argmin error: a restart may help.
    Failed(String),
}

struct RunOutcome {
    phi: Vec<f64>,
    end: RunEnd,
}

struct RunSetup<'o> {
    opts: &'o OptimOptions,
    gnorm0: f64,
    scale: f64,
    max_iters: usize,
    alpha: f64,
}

fn supervise<S>(inner: S, setup: &RunSetup<'_>, shared: &Rc<Shared>, tr: bool) -> Supervised<S> {
    Supervised {
        inner,
        grad_tol: setup.opts.grad_tol,
        rel_grad_tol: setup.opts.rel_grad_tol,
        gnorm0: setup.gnorm0,
        cost_rel_tol: setup.opts.cost_rel_tol,
        trust_region: tr,
        rejections: 0,
        stop: None,
        shared: Rc::clone(shared),
        scale: setup.scale,
    }
}

/// Runs one executor from `start` and classifies the end.
fn execute<'a, P, O, H, S>(
    adapter: ArgminAdapter<'a, P, O>,
    solver: Supervised<S>,
    start: &Point,
    setup: &RunSetup<'_>,
) -> Result<RunOutcome>
where
    P: ControlMap,
    O: Objective,
    S: Solver<ArgminAdapter<'a, P, O>, St<H>>,
    ProgressObserver: Observe<St<H>>,
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
    if setup.opts.progress {
        exec = exec.add_observer(
            ProgressObserver { scale: setup.scale },
            ObserverMode::Always,
        );
    }
    let run = exec.run();
    if let Some(e) = shared.fatal() {
        return Err(e);
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
                end: RunEnd::Failed(format!("solver error: {e}")),
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
        (Some(Stop::Converged(s)), _) => RunEnd::Converged(s.clone()),
        (Some(Stop::NoProgress(s)), _) => RunEnd::Failed(format!("no progress: {s}")),
        (None, Some(TerminationReason::TargetCostReached)) => {
            RunEnd::Converged(format!("target cost {:e} reached", setup.opts.target_cost))
        }
        (None, Some(TerminationReason::MaxItersReached)) => RunEnd::MaxIters,
        (None, Some(TerminationReason::SolverConverged)) => {
            RunEnd::Converged(format!("{} converged", res.solver.inner.name()))
        }
        (None, Some(r)) => RunEnd::Failed(r.text().to_string()),
        (None, None) => RunEnd::Failed("stopped without a reason".into()),
    };
    Ok(RunOutcome { phi, end })
}

fn run_method<P: ControlMap, O: Objective>(
    adapter: &ArgminAdapter<'_, P, O>,
    start: &Point,
    setup: &RunSetup<'_>,
) -> Result<RunOutcome> {
    let opts = setup.opts;
    let n = start.phi.len();
    let cg = opts.cg_max_iters.unwrap_or(2 * n.max(1));
    let config = |e: ArgminError| Error::InvalidArgument {
        name: "opts",
        reason: e.to_string(),
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
            let solver = supervise(inner, setup, &adapter.shared, false);
            execute::<P, O, (), _>(adapter.clone(), solver, start, setup)
        }
        Method::TrustRegion => {
            let sub = Steihaug::new().with_max_iters(cg as u64);
            let inner = TrustRegion::new(sub)
                .with_radius(opts.trust_radius)
                .map_err(config)?
                .with_max_radius(opts.max_trust_radius)
                .map_err(config)?;
            let solver = supervise(inner, setup, &adapter.shared, true);
            let a = adapter.clone().with_extended_value(true);
            execute(a, solver, start, setup)
        }
        Method::NewtonCg => {
            let mut ls = MoreThuenteLineSearch::new();
            ls.initial_step_length(setup.alpha).map_err(config)?;
            let inner = NewtonCG::new(ls)
                .with_tolerance(f64::MIN_POSITIVE)
                .map_err(config)?;
            let solver = supervise(inner, setup, &adapter.shared, false);
            let a = adapter.clone().with_hvp_cap(cg);
            execute(a, solver, start, setup)
        }
    }
}

/// Minimises J(θ) of `problem` from `theta0` (module docs: solvers, bound, stopping).
///
/// # Errors
/// [`Error::InvalidArgument`] for invalid options, a θ₀ of the wrong length, non-finite or
/// outside the bound (infeasible); the simulation's error if J cannot be evaluated at θ₀; the
/// typed error of a failed Hessian-vector product; [`Error::InvalidArgument`] (`bound`) if the
/// control map turned bounded θ into forces beyond the bound.
pub fn minimize<P: ControlMap, O: Objective>(
    problem: &ControlProblem<P, O>,
    theta0: &[f64],
    opts: &OptimOptions,
) -> Result<OptimResult> {
    let clock = Instant::now();
    opts.validate()?;
    problem.controls(theta0).map_err(|e| match e {
        Error::InvalidArgument { reason, .. } => Error::InvalidArgument {
            name: "theta0",
            reason,
        },
        Error::WrongLength { expected, got, .. } => Error::WrongLength {
            name: "theta0",
            expected,
            got,
        },
        Error::NotFinite { index, .. } => Error::NotFinite {
            name: "theta0",
            index,
        },
        e => e,
    })?;
    let adapter = ArgminAdapter::new(problem, opts.bound)?;
    let phi0 = adapter.to_phi(theta0)?;
    let start0 = adapter.evaluate(&phi0)?;
    let initial_gradient_norm = norm(&start0.grad_theta);
    let gnorm0 = norm(&start0.grad_phi);
    let scale = if gnorm0 > 0.0 { 1.0 / gnorm0 } else { 1.0 };
    let adapter = adapter.with_scale(scale);
    let mut point = start0;
    let mut restarts = 0;
    let mut alpha_first = 1.0;
    let grad_met = |gn: f64| gn <= opts.grad_tol || gn <= opts.rel_grad_tol * gnorm0;
    let (mut converged, mut termination, polish) = loop {
        let used = adapter.counts().iterations;
        if used >= opts.max_iters {
            break (
                false,
                format!("maximum iterations ({}) reached", opts.max_iters),
                false,
            );
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
        let out = run_method(&adapter, &point, &setup)?;
        point = adapter.evaluate(&out.phi)?;
        match out.end {
            RunEnd::Converged(s) => break (true, s, true),
            RunEnd::MaxIters if first_only => alpha_first = 1.0,
            RunEnd::MaxIters => {
                break (
                    false,
                    format!("maximum iterations ({}) reached", opts.max_iters),
                    false,
                );
            }
            RunEnd::Failed(s) => {
                let trial_failed = adapter.counts().failures > failures_before;
                // The trust region has no memory to reset and already shrinks its radius at
                // failed trial points: only the line-search methods restart.
                let restartable = opts.method != Method::TrustRegion;
                if !trial_failed || !restartable || restarts >= opts.max_restarts {
                    let why = match (trial_failed, adapter.shared.last_failure.borrow().as_ref()) {
                        (true, Some(e)) => format!("{s} (last failed trial point: {e})"),
                        _ => s,
                    };
                    break (false, why, true);
                }
                restarts += 1;
                alpha_first *= 0.1;
            }
        }
    };
    let mut polished = 0;
    if polish && !grad_met(norm(&point.grad_phi)) && opts.target_cost < point.value {
        let cap = opts.cg_max_iters.unwrap_or(2 * point.phi.len().max(1));
        let mut polish_error = None;
        while polished < opts.polish_steps {
            match polish_step(&adapter, &point, cap) {
                Ok(Some(next)) => {
                    point = next;
                    polished += 1;
                }
                Ok(None) => break,
                Err(e) => {
                    polish_error = Some(e);
                    break;
                }
            }
            if grad_met(norm(&point.grad_phi)) {
                break;
            }
        }
        let gn = norm(&point.grad_phi);
        if polished > 0 {
            termination =
                format!("{termination}; then {polished} polish step(s): gradient norm {gn:.3e}");
        }
        if let Some(e) = polish_error {
            termination = format!("{termination}; polish stopped: {e}");
        }
        if grad_met(gn) {
            converged = true;
        }
    }
    if let Some(e) = adapter.take_error() {
        return Err(e);
    }
    let theta = point.theta.clone();
    let controls = problem.controls(&theta)?;
    if let Some(b) = opts.bound {
        if let Some(k) = controls.iter().position(|u| u.abs() > b) {
            return Err(Error::InvalidArgument {
                name: "bound",
                reason: format!(
                    "the control map turned bounded parameters into u_{k} = {} beyond ±{b}",
                    controls[k]
                ),
            });
        }
    }
    let (projected_gradient_norm, active_bounds) = kkt(&theta, &point.grad_theta, opts.bound);
    let c = adapter.counts();
    Ok(OptimResult {
        objective: point.value,
        gradient_norm: norm(&point.grad_theta),
        initial_gradient_norm,
        projected_gradient_norm,
        active_bounds,
        theta,
        controls,
        iterations: c.iterations,
        cost_evals: c.cost_requests,
        gradient_evals: c.sweeps,
        hvp_evals: c.hvps,
        failed_evals: c.failures,
        restarts,
        polish_steps: polished,
        seconds: clock.elapsed().as_secs_f64(),
        converged,
        termination,
        method: opts.method,
    })
}

/// One Newton step of the gradient polish (module docs), tried at lengths 1, ½, ¼: `None` if CG
/// meets non-positive curvature first or no length reduces ‖g‖ within the cost allowance (a
/// trial point whose simulation fails counts as no reduction); an HVP's error otherwise (the
/// caller reports it and keeps the point it has).
fn polish_step<P: ControlMap, O: Objective>(
    adapter: &ArgminAdapter<'_, P, O>,
    at: &Point,
    max_cg: usize,
) -> Result<Option<Point>> {
    let op = adapter.operator(&at.phi)?;
    let g = &at.grad_phi;
    let gn = norm(g);
    let n = g.len();
    let mut x = vec![0.0; n];
    let mut r: Vec<f64> = g.iter().map(|v| -v).collect();
    let mut d = r.clone();
    let mut rr = gn * gn;
    for it in 0..max_cg {
        let hd = op.apply(&d)?;
        let dhd: f64 = d.iter().zip(&hd).map(|(a, b)| a * b).sum();
        if dhd <= 0.0 || !dhd.is_finite() {
            if it == 0 {
                return Ok(None);
            }
            break;
        }
        let alpha = rr / dhd;
        for i in 0..n {
            x[i] += alpha * d[i];
            r[i] -= alpha * hd[i];
        }
        let rr_new: f64 = r.iter().map(|v| v * v).sum();
        if rr_new.sqrt() <= POLISH_CG_TOL * gn {
            break;
        }
        let beta = rr_new / rr;
        for i in 0..n {
            d[i] = r[i] + beta * d[i];
        }
        rr = rr_new;
    }
    let allowed = at.value + POLISH_COST_TOL * at.value.abs();
    for alpha in [1.0, 0.5, 0.25] {
        let phi: Vec<f64> = at.phi.iter().zip(&x).map(|(a, b)| a + alpha * b).collect();
        if let Ok(next) = adapter.evaluate(&phi) {
            if norm(&next.grad_phi) < gn && next.value <= allowed {
                return Ok(Some(next));
            }
        }
    }
    Ok(None)
}

/// The projected gradient norm and the active bounds at θ.
fn kkt(theta: &[f64], g: &[f64], bound: Option<f64>) -> (f64, Vec<usize>) {
    let Some(b) = bound else {
        return (norm(g), Vec::new());
    };
    let lim = b * (1.0 - ACTIVE_BOUND_TOL);
    let mut active = Vec::new();
    let mut s = 0.0;
    for (i, (&t, &gi)) in theta.iter().zip(g).enumerate() {
        let upper = t >= lim;
        let lower = t <= -lim;
        if upper || lower {
            active.push(i);
        }
        // At the upper bound descent (−g) is blocked when g < 0; at the lower when g > 0.
        if !((upper && gi < 0.0) || (lower && gi > 0.0)) {
            s += gi * gi;
        }
    }
    (s.sqrt(), active)
}
