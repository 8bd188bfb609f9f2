//! Local minimisation of a differentiable objective J(θ) ([`OptimProblem`]; a
//! [`ControlProblem`](crate::ControlProblem) is one) with [argmin]: L-BFGS with the More-Thuente
//! line search, a trust region with Steihaug's truncated conjugate gradients, and Newton-CG, all
//! driven by exact gradients (the discrete adjoint, for a control problem) and exact
//! Hessian-vector products (forward-over-adjoint; the Hessian is never formed).
//!
//! ```
//! use chainbeam::optimize::{minimize, OptimOptions, Termination};
//! use chainbeam::{catalogue, BendingObjective, ControlProblem, Parametrisation};
//!
//! // Thesis Table 3.2, load at node 7: constant control, c_sum (eq. 3.3.4).
//! let problem = ControlProblem::builder(&catalogue::riser(7))
//!     .map(Parametrisation::Constant)
//!     .objective(BendingObjective::summed_moment())
//!     .build()?;
//! let r = minimize(&problem, &[0.0], &OptimOptions::default())?;
//! assert!(r.converged, "{}", r.termination);
//! assert!(matches!(r.termination, Termination::RelativeGradientTolerance { .. }));
//! assert!((r.objective - 4.9376e-2).abs() < 5e-7); // the thesis's c_sum to its 5 digits
//! assert_eq!(r.controls, vec![r.theta[0]; 11]); // u_0..u_10
//! # Ok::<(), chainbeam::Error>(())
//! ```
//!
//! # Layout
//! - [`problem`]: the [`OptimProblem`] and [`HessianVec`] traits, their implementation for the
//!   control problem, the resolved force range and the no-effect test;
//! - [`adapter`]: the problem as an argmin problem ([`ArgminAdapter`], [`HessianOperator`]);
//! - [`supervisor`]: our stopping rules around argmin's solvers, the restarts, [`Termination`];
//! - [`bounds`]: the sine reparametrisation of force bounds ([`Bounds`]) and the KKT measure;
//! - [`polish`]: the gradient polish;
//! - [`observers`]: user observers ([`Minimizer::add_observer`], [`History`]).
//!
//! # The argmin problem
//! [`ArgminAdapter`] is the problem as an argmin problem: it implements [`CostFunction`],
//! [`Gradient`] and [`Hessian`] over `Vec<f64>`. One evaluation (an adjoint sweep) gives the
//! objective *and* the gradient, so the adapter caches the last point: the solvers' usual
//! cost-then-gradient calls at one point cost one sweep, not two. Its [`Hessian`] is a
//! [`HessianOperator`] (the point and the problem), which implements
//! [`ArgminDot<Vec<f64>, Vec<f64>>`](argmin_math::ArgminDot) by [`HessianVec::hessian_vec`];
//! argmin-math's blanket `ArgminWeightedDot` for `Vec<f64>` (`p·(H v)`) then serves Steihaug and
//! the trust region. `ArgminDot` cannot fail, so an HVP error is stored in the adapter's shared
//! state, the operator answers zeros from then on, every later cost or gradient request fails,
//! and [`minimize`] returns the stored, typed error after the run (a NaN never reaches a
//! solver). The trust region and Newton-CG need [`OptimProblem::hessian`]; without it only
//! L-BFGS runs and there is no polish.
//!
//! [`CostFunction`]: argmin::core::CostFunction
//! [`Gradient`]: argmin::core::Gradient
//! [`Hessian`]: argmin::core::Hessian
//!
//! **Scaling.** [`minimize`] hands argmin s·J with s = 1/‖∇J(θ₀)‖ (L-BFGS: s =
//! [`first_step`](OptimOptions::first_step)/‖∇J(θ₀)‖): the first L-BFGS trial step −s g₀ is then
//! 1 N (`first_step`) long whatever the objective's size (the thesis's objectives span 10⁻¹⁶ to
//! 10² N²m²); L-BFGS's later steps do not depend on s (its curvature pairs scale with it); and
//! argmin's Steihaug, whose tolerance (10⁻⁹) is also an *absolute* test (it returns a zero step
//! once ‖g‖ < 10⁻⁹, and the trust region then stalls on ρ = 0/0), acts relative to ‖g₀‖.
//! Results, tolerances, termination and observers are in J's own units.
//!
//! # Checks at the start
//! - θ₀ has n finite entries, lies within the force bound, and passes
//!   [`OptimProblem::check_range`]: for a control problem every force within
//!   [`resolved_control_limit`] = π m l / h², beyond which the time grid does not resolve the
//!   motion ([`Error::ControlOutOfRange`]). A trial point outside that range later in the run
//!   fails like a trial point whose simulation failed, so no result lies outside it.
//! - Parameters without effect ([`ineffective_params`]): a parameter that moving across its
//!   whole range changes J by round-off only (a control at a node the supports lock, such as
//!   the tip of a fixed-fixed beam) would send the solver chasing round-off to absurd values
//!   (once u = −1.46·10³² N, reported as J = 0, converged). [`minimize`] refuses such a start
//!   with [`Error::NoEffect`] when no parameter acts, or when one without effect has a nonzero
//!   (round-off) gradient. Parameters whose gradient and Hessian column are exactly zero while
//!   others act (u_N of a per-step control, thesis §3.3.1) are allowed: no step moves them.
//!
//! # Bounded controls: a sine reparametrisation
//! argmin has no bound-constrained quasi-Newton method (no L-BFGS-B). With a force box
//! L ≤ θ_i ≤ U ([`OptimOptions::bounds`], a [`Bounds`]; the symmetric `bound = Some(b)` is the
//! box [−b, b]) the solvers work in unconstrained variables φ with, componentwise (the variable
//! transformation of MINUIT), centre c = (L + U)/2 and half-width r = (U − L)/2,
//! ```text
//! θ = c + r sin((φ − c)/r),   dθ/dφ = cos((φ − c)/r) =: J,   d²θ/dφ² = −(θ − c)/r²,
//! g_φ = J ⊙ g_θ,    H_φ v = J ⊙ H_θ (J ⊙ v) + (g_θ ⊙ d²θ/dφ²) ⊙ v     (exact chain rule).
//! ```
//! For the symmetric box (c = 0, r = b) this is θ = b sin(φ/b). A one-sided limit (L or U
//! infinite) has no such map and is refused ([`Bounds::new`]): give a finite far side, e.g.
//! the [`resolved_control_limit`], beyond which forces are refused anyway.
//! Why this and not the alternatives:
//! - *Projection* breaks the curvature pairs of L-BFGS and the quadratic model of the trust
//!   region (argmin's solvers would need rewriting as L-BFGS-B / projected trust region).
//! - *tanh* (θ = b tanh(φ/b)) reaches the bound only as φ → ∞: an active bound is approached with
//!   exponentially vanishing gradients and no finite minimiser, so solvers stall instead of
//!   converging.
//! - *sine* reaches the bound at the finite φ = c ± rπ/2, where g_φ = 0 and, if the bound is
//!   active (g_θ pushes outward), H_φ has the positive entry |g_θ|/r: the bounded optimum is a
//!   regular local minimum in φ, found at the solvers' usual (superlinear) rates. L ≤ θ ≤ U holds
//!   exactly in floating point (|sin| ≤ 1, and θ is clamped into the box against the rounding of
//!   c ± r). Near θ = c, φ ≈ θ, so tolerances and trust radii keep their units (N).
//!
//! The price: every bound point is a stationary point in φ. Where g_θ points *inward* it is a
//! saddle or maximum in φ, which descent methods leave; but a start exactly on the bound would
//! not move, so a θ₀ closer than 10⁻⁴·r to a bound is moved that far inside. For the built-in
//! parametrisations ([`Parametrisation`](crate::Parametrisation)) θ are the forces themselves (or
//! copies of them), so L ≤ θ ≤ U bounds every u_k; for another [`ControlMap`](crate::ControlMap)
//! the bounds still act on θ, and [`minimize`] checks L ≤ u_k ≤ U at the end (an error if the
//! map broke it).
//!
//! # Stopping
//! Whichever comes first (each is checked after every iteration, in the solver's variables φ; φ =
//! θ without a bound); [`OptimResult::termination`] says which ([`Termination`]), and
//! [`OptimResult::converged`] is [`Termination::is_converged`]:
//! - gradient: ‖g‖ ≤ `grad_tol` or ‖g‖ ≤ `rel_grad_tol`·‖g₀‖ (converged);
//! - cost: an accepted step changed J by at most `cost_rel_tol`·max(|J_old|, |J_new|)
//!   (converged; argmin's own L-BFGS `tol_cost` is *absolute*, so it is switched off and this
//!   relative test is used instead);
//! - `target_cost`: argmin's test best J ≤ target (converged);
//! - `max_iters` iterations in total (not converged);
//! - no progress: the line search returned its start point or failed, or the trust region
//!   rejected 20 steps in a row (its radius has then shrunk by 4²⁰ ≈ 10¹²; not converged).
//!
//! A line search that failed because a trial point's evaluation failed (argmin's L-BFGS turns
//! any line-search error into a normal exit) restarts the solver from the best point, at most
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
//! otherwise p/2 and p/4 are tried. If the polish reaches the gradient tolerance, the run is
//! converged by that test (whatever stopped the solver before: argmin's messages then do not
//! appear in the termination). The polish is a refinement: if one of its HVPs fails, it stops,
//! the point reached so far is returned and [`OptimResult::polish_error`] holds the error.
//!
//! # Observers
//! [`Minimizer::add_observer`] takes any argmin [`Observe`] on [`ObservedState`] (θ, J, ∇_θJ)
//! with an [`ObserverMode`]; every solver calls them, the argmin ones through each executor's
//! [`add_observer`](argmin::core::Executor::add_observer) and the structured ones
//! ([`Method::Riccati`], [`Method::Condensed`]) after each of their accepted iterations
//! (module [`observers`]). [`History`] records the iterates. The library prints nothing: what a
//! run did is in its [`OptimResult`] (with [`Method::Auto`], [`OptimResult::choice`] says which
//! method ran and why) and in what its observers saw; a program decides what to show.
//!
//! # Reference
//! J. Nocedal, S. J. Wright, *Numerical Optimization*, 2nd ed., Springer 2006: L-BFGS (Alg. 7.5),
//! More-Thuente line search (§3.5), trust region with Steihaug CG (Alg. 4.1, 7.2), Newton-CG
//! (Alg. 7.1). F. James, M. Roos, MINUIT, CERN (the sine transformation for bounded parameters).

pub mod adapter;
pub mod any;
pub mod bounds;
mod choice;
pub mod observers;
mod point;
pub mod polish;
pub mod problem;
mod riccati;
pub mod supervisor;

use std::fmt;
use std::str::FromStr;
use std::time::Instant;

/// The argmin crate this module is built on (to write observers against the same version).
pub use argmin;
use argmin::core::observers::Observers;
pub use argmin::core::observers::{Observe, ObserverMode};
use argmin::core::KV;

pub use adapter::{ArgminAdapter, EvalCounts, HessianOperator};
pub use any::{scene_start, Values, RICCATI_PLANAR};
pub use bounds::{Bounds, ACTIVE_BOUND_TOL};
pub use choice::{choose_method, condensed_max_params, Fallback, MethodChoice};
pub use observers::{History, ObservedState, Record};
pub use polish::POLISH_COST_TOL;
pub use problem::{
    ineffective_params, resolved_control_limit, HessianVec, NoEffectCheck, OptimProblem,
    ProblemShape, NO_EFFECT_TOL,
};
pub use riccati::ocp_options as riccati_options;
pub use supervisor::{Termination, MAX_REJECTIONS};

pub use crate::error::OptimizeError;
use crate::error::{Error, Requirement, Result, ValueError};

type ArgminError = argmin::core::Error;

/// ‖v‖₂.
pub(crate) fn norm(v: &[f64]) -> f64 {
    v.iter().map(|x| x * x).sum::<f64>().sqrt()
}

/// The local solver.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum Method {
    /// The default: the method is chosen from the problem's shape by [`choose_method`] —
    /// [`Method::Condensed`] for a structured control problem with few parameters,
    /// [`Method::Riccati`] for one with many, [`Method::Lbfgs`] for everything else — run
    /// behind an L-BFGS fallback when the structured solver fails or does not converge
    /// ([`Fallback`]); a converged condensed run is followed by the Riccati solver from the same
    /// start and the lower converged objective is kept (module `choice`); the result's
    /// [`OptimResult::method`] and [`OptimResult::choice`] say which ran, why, and whether the
    /// fallback did.
    #[default]
    Auto,
    /// L-BFGS (memory [`OptimOptions::lbfgs_memory`]) with the More-Thuente line search: one
    /// adjoint sweep per line-search trial, no HVPs.
    Lbfgs,
    /// Trust region (Nocedal-Wright Alg. 4.1) with Steihaug's truncated CG on exact HVPs; handles
    /// indefinite Hessians and rejects trial points where the simulation fails.
    TrustRegion,
    /// Newton-CG with the More-Thuente line search on exact HVPs. argmin's version compares the
    /// *squared* CG residual with the forcing term min(½, √‖g‖)‖g‖, so once ‖g‖ < 1 its inner
    /// solves stop early and it slows to gradient-descent-like steps; prefer the trust region.
    NewtonCg,
    /// The structured Gauss-Newton solver of [`crate::ocp`] (Riccati backward passes, box bounds
    /// handled exactly by interior-point QPs): O(N) per iteration for per-step, piecewise and
    /// constant controls of a bending-moment objective; other problems are refused with
    /// [`OptimizeError::NotStructured`]. The argmin options do not apply (module
    /// `riccati`). If its Gauss-Newton model stalls short of the tolerance (it cannot see
    /// negative curvature: no effort penalty, a chain near folding), the trust region finishes
    /// from its point and the result's `method` says [`Method::TrustRegion`].
    Riccati,
    /// The condensed Gauss-Newton solver [`crate::ocp::Condensed`] on the same problems as
    /// [`Method::Riccati`]: the sensitivities of the bending moments to θ by forward dual
    /// numbers and a dense box QP, with NL2SOL's structured secant term for the residual
    /// curvature. Its cost per iteration grows with N times the number of parameters, so it is
    /// the faster choice for few parameters (thesis Table 3.4's eleven per-step forces: about
    /// half the Riccati solver's time, `docs/benchmarks.md`), not for long per-step horizons.
    /// The two may end in different local minima of a nonconvex problem, which is why
    /// [`Method::Auto`] runs both when it picks this one. A stalled run is finished by the trust
    /// region as for `riccati`.
    Condensed,
}

impl Method {
    /// The name used on the command line: `auto`, `lbfgs`, `trust-region`, `newton-cg`,
    /// `riccati` or `condensed`.
    pub fn name(self) -> &'static str {
        match self {
            Method::Auto => "auto",
            Method::Lbfgs => "lbfgs",
            Method::TrustRegion => "trust-region",
            Method::NewtonCg => "newton-cg",
            Method::Riccati => "riccati",
            Method::Condensed => "condensed",
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
            "auto" => Ok(Method::Auto),
            "lbfgs" | "l-bfgs" => Ok(Method::Lbfgs),
            "trust-region" | "trustregion" => Ok(Method::TrustRegion),
            "newton-cg" | "newtoncg" => Ok(Method::NewtonCg),
            "riccati" => Ok(Method::Riccati),
            "condensed" => Ok(Method::Condensed),
            _ => Err(OptimizeError::UnknownMethod {
                given: s.into(),
                expected: "auto, lbfgs, trust-region, newton-cg, riccati or condensed",
            }
            .into()),
        }
    }
}

/// Options of [`minimize`]. Build with struct update syntax:
/// `OptimOptions { method: Method::TrustRegion, ..Default::default() }`.
#[derive(Clone, Debug, PartialEq)]
pub struct OptimOptions {
    /// The solver. Default [`Method::Auto`]: chosen from the problem's shape
    /// ([`choose_method`]).
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
    /// short the slow phase of a flat landscape (docs/conventions.md: c_sum is very flat near its minimum).
    pub cost_rel_tol: f64,
    /// argmin's target: stop when J ≤ `target_cost`. Default −∞ (off).
    pub target_cost: f64,
    /// Symmetric force limit |θ_i| ≤ u_max (see the module docs): the box [−u_max, u_max].
    /// Default `None`. Set this or [`bounds`](Self::bounds), not both.
    pub bound: Option<f64>,
    /// Force box L ≤ θ_i ≤ U, possibly asymmetric ([`Bounds`]; module docs). Default `None`.
    /// Set this or [`bound`](Self::bound), not both.
    pub bounds: Option<Bounds>,
    /// L-BFGS memory m. Default 10 (more pairs than the thesis problems have parameters).
    pub lbfgs_memory: usize,
    /// L-BFGS: the length of the first trial step −first_step·g₀/‖g₀‖, in the units of θ
    /// (module docs, "Scaling"). Default 1: 1 N for forces, a small fraction of the thesis's
    /// optimal forces (1-300 N). Shorten it for parameters where a unit step is large, e.g. 0.1
    /// for log-parameters (a factor e^0.1).
    pub first_step: f64,
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
    /// The second-order model of [`Method::Riccati`] ([`crate::ocp::Curvature`]; ignored by
    /// the other methods). Default [`Curvature::Auto`](crate::ocp::Curvature::Auto):
    /// Gauss-Newton, then the exact Hessian from the first step Gauss-Newton predicts poorly.
    pub curvature: crate::ocp::Curvature,
}

impl Default for OptimOptions {
    fn default() -> Self {
        OptimOptions {
            method: Method::Auto,
            max_iters: 1000,
            grad_tol: 0.0,
            rel_grad_tol: 1e-8,
            cost_rel_tol: 4.0 * f64::EPSILON,
            target_cost: f64::NEG_INFINITY,
            bound: None,
            bounds: None,
            lbfgs_memory: 10,
            first_step: 1.0,
            trust_radius: 10.0,
            max_trust_radius: 1e4,
            cg_max_iters: None,
            max_restarts: 3,
            polish_steps: 5,
            curvature: crate::ocp::Curvature::Auto,
        }
    }
}

impl OptimOptions {
    /// The box the parameters are kept in: [`bounds`](Self::bounds), or [−b, b] for
    /// [`bound`](Self::bound) = b, or `None`.
    ///
    /// # Errors
    /// [`ValueError::OutOfRange`] (`bound`) for a bound that is not positive and finite,
    /// [`OptimizeError::BoundAndBox`] when both `bound` and `bounds` are set.
    pub fn force_bounds(&self) -> Result<Option<Bounds>> {
        match (self.bound, self.bounds) {
            (Some(_), Some(_)) => Err(OptimizeError::BoundAndBox.into()),
            (Some(b), None) => Bounds::symmetric(b).map(Some),
            (None, bounds) => Ok(bounds),
        }
    }

    /// Checks every field (an [`OptimizeError`] naming it).
    pub fn validate(&self) -> Result<()> {
        let finite = Requirement::FiniteNonNegative;
        let positive = Requirement::PositiveFinite;
        for (name, requirement, value) in [
            ("grad_tol", finite, self.grad_tol),
            ("rel_grad_tol", finite, self.rel_grad_tol),
            ("cost_rel_tol", finite, self.cost_rel_tol),
        ] {
            check(name, requirement, value)?;
        }
        if self.target_cost.is_nan() {
            return Err(OptimizeError::TargetCostNan.into());
        }
        self.force_bounds()?;
        ValueError::check_count("lbfgs_memory", self.lbfgs_memory).map_err(OptimizeError::from)?;
        check("first_step", positive, self.first_step)?;
        check("trust_radius", positive, self.trust_radius)?;
        if !(self.max_trust_radius.is_finite() && self.max_trust_radius >= self.trust_radius) {
            return Err(OptimizeError::MaxTrustRadius {
                trust_radius: self.trust_radius,
                max_trust_radius: self.max_trust_radius,
            }
            .into());
        }
        if let Some(count) = self.cg_max_iters {
            ValueError::check_count("cg_max_iters", count).map_err(OptimizeError::from)?;
        }
        Ok(())
    }
}

/// [`Error::NoEffect`] when parameters cannot act on the objective at the start point
/// ([`ineffective_params`]); the Hessian-vector products of the check are counted.
fn refuse_ineffective<Q: OptimProblem + ?Sized>(
    problem: &Q,
    adapter: &ArgminAdapter<'_, Q>,
    start: &point::Point,
) -> Result<()> {
    let check = ineffective_params(problem, &start.theta, start.value, &start.grad_theta)?;
    adapter.shared.bump(|c| c.hvps += check.hvps);
    if check.refuses(&start.grad_theta) {
        return Err(Error::NoEffect {
            params: check.params,
            objective: start.value,
            relative_change: check.relative_change,
        });
    }
    Ok(())
}

/// [`ValueError::OutOfRange`] naming the option `name` unless `value` meets `requirement`.
fn check(name: &'static str, requirement: Requirement, value: f64) -> Result<()> {
    Ok(requirement
        .check(name, value)
        .map_err(OptimizeError::from)?)
}

/// The outcome of [`minimize`].
#[derive(Clone, Debug, PartialEq)]
pub struct OptimResult {
    /// J(θ) at the result.
    pub objective: f64,
    /// The parameters θ.
    pub theta: Vec<f64>,
    /// The forces u_0..u_N of θ (within the bound, if one was given) for a control problem
    /// ([`OptimProblem::controls`]); empty for a problem without controls.
    pub controls: Vec<f64>,
    /// ‖∇_θ J‖ of the original problem at θ (not zero at an active bound).
    pub gradient_norm: f64,
    /// ‖∇_θ J‖ at the start θ₀ (moved inside the bound if it was on it).
    pub initial_gradient_norm: f64,
    /// The projected-gradient (first-order KKT) measure: ‖∇_θ J‖ with the components removed
    /// whose bound is active and blocks descent. Equals `gradient_norm` without a bound.
    pub projected_gradient_norm: f64,
    /// Indices i with θ_i within [`ACTIVE_BOUND_TOL`]·r of a bound (r the half-width of the
    /// box; for |θ| ≤ u_max: |θ_i| ≥ (1 − [`ACTIVE_BOUND_TOL`])·u_max).
    pub active_bounds: Vec<usize>,
    /// Iterations, over all restarts (L-BFGS / Newton-CG: line searches; trust region:
    /// subproblem solves, accepted or rejected).
    pub iterations: usize,
    /// Objective values requested by the solvers (answered from the one-point cache when the
    /// point was already evaluated).
    pub cost_evals: usize,
    /// Evaluations of J and ∇J run (adjoint sweeps for a control problem, so also the number of
    /// simulations).
    pub gradient_evals: usize,
    /// Hessian-vector products run (forward-over-adjoint sweeps in dual numbers), including
    /// those of the no-effect test at the start.
    pub hvp_evals: usize,
    /// Trial points whose evaluation failed (trust region: treated as J = +∞; line searches:
    /// ended the search).
    pub failed_evals: usize,
    /// Restarts after failed line searches.
    pub restarts: usize,
    /// Accepted Newton steps of the gradient polish.
    pub polish_steps: usize,
    /// The error that stopped the gradient polish early, if one did.
    pub polish_error: Option<Error>,
    /// Wall-clock time of [`minimize`] in seconds.
    pub seconds: f64,
    /// Whether a convergence test (gradient, cost change or target) stopped the run:
    /// `termination.is_converged()`.
    pub converged: bool,
    /// Why the run stopped.
    pub termination: Termination,
    /// The solver used (never [`Method::Auto`]: the method it chose).
    pub method: Method,
    /// With [`Method::Auto`]: what [`choose_method`] chose and why; `None` for a method given.
    pub choice: Option<MethodChoice>,
}

/// [`minimize`] with observers: argmin's builder style. Every solver shows its iterations to
/// the observers: L-BFGS, the trust region and Newton-CG through argmin, the Riccati and
/// condensed solvers after each accepted iteration (module [`observers`]). When one call runs
/// several solvers one after the other ([`Method::Auto`]'s fallback or its Riccati companion
/// run, a structured run finished by the trust region), each is shown as a run of its own:
/// `observe_init` with its name, its iterations, `observe_final`.
///
/// ```
/// use chainbeam::optimize::{History, Method, Minimizer, ObserverMode, OptimOptions};
/// use chainbeam::{catalogue, BendingObjective, ControlProblem, Parametrisation};
///
/// let problem = ControlProblem::builder(&catalogue::riser(5))
///     .map(Parametrisation::Constant)
///     .objective(BendingObjective::summed_moment())
///     .build()?;
/// let history = History::default();
/// let lbfgs = OptimOptions { method: Method::Lbfgs, ..OptimOptions::default() };
/// let r = Minimizer::new(&problem, lbfgs)
///     .add_observer(history.clone(), ObserverMode::Always)
///     .run(&[0.0])?;
/// let costs: Vec<f64> = history.records().iter().map(|x| x.objective).collect();
/// assert_eq!(costs.last(), Some(&r.objective));
/// assert!(costs.windows(2).all(|w| w[1] <= w[0] * (1.0 + 1e-10))); // descent (to round-off)
/// # Ok::<(), chainbeam::Error>(())
/// ```
pub struct Minimizer<'p, Q: ?Sized> {
    problem: &'p Q,
    opts: OptimOptions,
    observers: Observers<ObservedState>,
}

impl<'p, Q: OptimProblem + ?Sized> Minimizer<'p, Q> {
    /// A minimiser of `problem` with options `opts` and no observers.
    pub fn new(problem: &'p Q, opts: OptimOptions) -> Self {
        Minimizer {
            problem,
            opts,
            observers: Observers::new(),
        }
    }

    /// Adds an observer, called as `mode` says (module [`observers`]).
    #[must_use]
    pub fn add_observer<O: Observe<ObservedState> + 'static>(
        mut self,
        observer: O,
        mode: ObserverMode,
    ) -> Self {
        self.observers.push(observer, mode);
        self
    }

    /// The options.
    pub fn options(&self) -> &OptimOptions {
        &self.opts
    }

    /// Minimises J from θ₀ (module docs: checks, solvers, bound, stopping, polish).
    ///
    /// # Errors
    /// [`OptimizeError`] for invalid options, a θ₀ outside the bound
    /// ([`OptimizeError::InfeasibleStart`]) or a method that needs Hessian-vector products the
    /// problem lacks ([`OptimizeError::NoHessian`]); [`Error::WrongLength`] or
    /// [`Error::NotFinite`] (`theta0`) for a θ₀ of the wrong length or non-finite; the problem's
    /// range error for a θ₀ outside its resolved range ([`Error::ControlOutOfRange`]);
    /// [`Error::NoEffect`] for parameters without effect; the problem's error if J cannot be
    /// evaluated at θ₀; the typed error of a failed Hessian-vector product;
    /// [`OptimizeError::ControlOutsideBound`] if the control map turned bounded θ into forces
    /// beyond the bound.
    pub fn run(&self, theta0: &[f64]) -> Result<OptimResult> {
        if self.opts.method != Method::Auto {
            return self.run_with(&self.opts, theta0);
        }
        choice::run_auto(self, theta0)
    }

    /// [`Minimizer::run`] with `opts` (a method other than [`Method::Auto`]).
    fn run_with(&self, opts: &OptimOptions, theta0: &[f64]) -> Result<OptimResult> {
        let clock = Instant::now();
        let problem = self.problem;
        opts.validate()?;
        check_start(problem, theta0)?;
        if matches!(opts.method, Method::Riccati | Method::Condensed) {
            riccati::check_start_point(problem, theta0, opts)?;
            return riccati::run(self, theta0, opts);
        }
        if opts.method != Method::Lbfgs && problem.hessian().is_none() {
            return Err(adapter::no_hessian());
        }
        let bounds = opts.force_bounds()?;
        let adapter = ArgminAdapter::with_bounds(problem, bounds);
        let phi0 = adapter.to_phi(theta0)?;
        problem.check_range(&adapter.to_theta(&phi0))?;
        let start = adapter.evaluate(&phi0)?;
        refuse_ineffective(problem, &adapter, &start)?;
        let initial_gradient_norm = norm(&start.grad_theta);
        let gnorm0 = norm(&start.grad_phi);
        // L-BFGS's first step is −s g₀; its later steps do not depend on s (the curvature
        // pairs scale with it), so `first_step` sets exactly the first step.
        let first = if opts.method == Method::Lbfgs {
            opts.first_step
        } else {
            1.0
        };
        let scale = if gnorm0 > 0.0 { first / gnorm0 } else { 1.0 };
        let adapter = adapter.with_scale(scale);
        if !self.observers.is_empty() {
            let mut relay = observers::Relay::new(
                self.observers.clone(),
                opts.max_iters as u64,
                opts.target_cost,
            );
            if let Err(e) = relay.init(opts.method.name(), &start) {
                *adapter.shared.observer_stop.borrow_mut() = Some(e.to_string());
            }
            *adapter.shared.relay.borrow_mut() = Some(relay);
            *adapter.shared.current.borrow_mut() = Some(start.clone());
        }
        let run = supervisor::supervise(&adapter, start, opts, gnorm0)?;
        let mut polish = Polish {
            point: run.point,
            termination: run.termination,
            steps: 0,
            error: None,
        };
        if run.polish && problem.hessian().is_some() {
            polish.run(&adapter, opts, gnorm0);
        }
        let Polish {
            point,
            mut termination,
            steps: polished,
            error: polish_error,
        } = polish;
        if let Some(e) = adapter.take_error() {
            return Err(e);
        }
        let theta = point.theta.clone();
        let controls = checked_controls(problem, &theta, bounds)?;
        if let Some(relay) = adapter.shared.relay.borrow_mut().as_mut() {
            if let Err(e) = relay.finish(&point, &termination) {
                termination = Termination::Observer {
                    message: e.to_string(),
                };
            }
        }
        let (projected_gradient_norm, active_bounds) =
            bounds::kkt(&theta, &point.grad_theta, bounds);
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
            restarts: run.restarts,
            polish_steps: polished,
            polish_error,
            seconds: clock.elapsed().as_secs_f64(),
            converged: termination.is_converged(),
            termination,
            method: opts.method,
            choice: None,
        })
    }
}

/// The gradient polish after the supervised run (module docs, "Gradient polish"): up to
/// `polish_steps` Newton steps on ∇J = 0 while the gradient test is unmet, each shown to the
/// observers.
struct Polish {
    point: point::Point,
    termination: Termination,
    /// Accepted polish steps.
    steps: usize,
    /// The error that stopped the polish early.
    error: Option<Error>,
}

impl Polish {
    fn run<Q: OptimProblem + ?Sized>(
        &mut self,
        adapter: &ArgminAdapter<'_, Q>,
        opts: &OptimOptions,
        gnorm0: f64,
    ) {
        let grad_test =
            |p: &point::Point| supervisor::gradient_test(opts, gnorm0, norm(&p.grad_phi));
        if !(grad_test(&self.point).is_none() && opts.target_cost < self.point.value) {
            return;
        }
        let cap = opts.cg_max_iters.unwrap_or(2 * self.point.phi.len().max(1));
        while self.steps < opts.polish_steps {
            match polish::polish_step(adapter, &self.point, cap) {
                Ok(Some(next)) => {
                    self.point = next;
                    self.steps += 1;
                }
                Ok(None) => break,
                Err(e) => {
                    self.error = Some(e);
                    break;
                }
            }
            if let Some(message) = relay_iter(adapter, &self.point) {
                self.termination = Termination::Observer { message };
                break;
            }
            if grad_test(&self.point).is_some() {
                break;
            }
        }
        if let (false, Some(t)) = (
            matches!(self.termination, Termination::Observer { .. }),
            grad_test(&self.point),
        ) {
            self.termination = t;
        }
    }
}

/// The forces u(θ) of a control problem (empty for other problems), checked against the box:
/// [`OptimizeError::ControlOutsideBound`] if the control map turned bounded θ into forces beyond
/// it.
fn checked_controls<Q: OptimProblem + ?Sized>(
    problem: &Q,
    theta: &[f64],
    bounds: Option<Bounds>,
) -> Result<Vec<f64>> {
    let controls = match problem.controls(theta) {
        Some(c) => c?,
        None => Vec::new(),
    };
    if let Some(b) = bounds {
        if let Some(k) = controls.iter().position(|&u| !b.contains(u)) {
            return Err(OptimizeError::ControlOutsideBound {
                index: k,
                value: controls[k],
                lower: b.lower(),
                upper: b.upper(),
            }
            .into());
        }
    }
    Ok(controls)
}

/// Shows an accepted polish step to the observers; the message of an observer that stopped.
fn relay_iter<Q: OptimProblem + ?Sized>(
    adapter: &ArgminAdapter<'_, Q>,
    point: &point::Point,
) -> Option<String> {
    let mut relay = adapter.shared.relay.borrow_mut();
    let relay = relay.as_mut()?;
    let mut kv = KV::new();
    kv.insert("polish", argmin::core::KvValue::Bool(true));
    relay.iter(point, &kv).err().map(|e| e.to_string())
}

/// θ₀ has n finite entries and, for a control problem, valid controls (errors name `theta0`).
pub(super) fn check_start<Q: OptimProblem + ?Sized>(problem: &Q, theta0: &[f64]) -> Result<()> {
    let n = problem.n_params();
    if theta0.len() != n {
        return Err(Error::WrongLength {
            name: "theta0",
            expected: n,
            got: theta0.len(),
        });
    }
    if let Some(i) = theta0.iter().position(|x| !x.is_finite()) {
        return Err(Error::NotFinite {
            name: "theta0",
            index: i,
        });
    }
    match problem.controls(theta0) {
        Some(Err(e)) => Err(e),
        _ => Ok(()),
    }
}

/// Minimises J(θ) of `problem` from `theta0` (module docs: checks, solvers, bound, stopping):
/// [`Minimizer::run`] without observers.
///
/// # Errors
/// As [`Minimizer::run`].
pub fn minimize<Q: OptimProblem + ?Sized>(
    problem: &Q,
    theta0: &[f64],
    opts: &OptimOptions,
) -> Result<OptimResult> {
    Minimizer::new(problem, opts.clone()).run(theta0)
}
