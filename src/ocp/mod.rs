//! A structure-exploiting second-order optimal-control solver for per-step and piecewise-constant
//! controls: box-constrained iLQR (Gauss-Newton DDP) on the RATTLE map, with a Riccati backward
//! pass in faer. One iteration costs O(N) (a rollout, the stage Jacobians, one backward pass),
//! whatever the number of controls, where a Hessian-vector product of a trust-region method costs
//! a whole forward-over-adjoint sweep and a Newton step needs many of them.
//!
//! A second method on the same problem and the same Gauss-Newton model, [`Condensed`] (full
//! condensing: the sensitivities of the bending moments to θ by forward dual numbers and a
//! dense box QP), is cheaper when the decisions are few over many steps (the receding horizons
//! of [`crate::mpc`]: 30 pieces of 10 steps); its cost grows with N times the number of
//! decisions, this solver's with N alone ([`condensed`] "Why a second method").
//!
//! # The problem
//! J(θ) = Σ_{k=0}^{N} [c_k M₀(t_k)² + ρh u_k²] + (σ/h) Σ_{k=1}^{N} (u_k − u_{k−1})²
//! over the RATTLE trajectory from the straight beam at rest, with c_k = 1 (c_sum, eq. 3.3.4) or
//! c_k = [k = N] (c, eq. 3.3.2) — in general Σ_k [½ w_k r_k(M₀(t_k))² + e_k u_k²], the
//! objective's Gauss-Newton form (Supported, below) — ρ the effort weight of [`BendingObjective::effort`](crate::BendingObjective::effort), σ ≥ 0 the
//! optional rate penalty [`OcpOptions::rate_penalty`] (σh Σ ((u_k − u_{k−1})/h)²: real thrusters
//! cannot jump), u_k = θ_{piece(k)} (per-step: θ = u; piecewise: the pieces of
//! [`PiecewiseControl`](crate::PiecewiseControl)), and the box lower ≤ θ ≤ upper. The costs are
//! those of [`ControlProblem::value`]; without the rate penalty J is exactly that function.
//!
//! # The method
//! - **Stage structure** ([`stage`]): one control per stage through the shifted state
//!   x̂_k = (q_k, p̂_k), tangent coordinates ξ = (φ, ω) (2n per stage instead of 4n), Jacobians
//!   A_k, B_k by `DualSVec64<8>` through the one generic RATTLE step (its derivative-only Newton
//!   update is the implicit function theorem, exact to round-off), computed in parallel
//!   (rayon, one workspace per thread: stages are independent given the trajectory).
//! - **Second-order model** ([`Curvature`]): Gauss-Newton first — the bending residual
//!   r_k = M₀(q_k) linearised (l_xx = 2∇r∇rᵀ; an objective's residual r_k(M₀) in general,
//!   l_xx = w_k∇r∇rᵀ), the dynamics' second derivatives dropped (iLQR):
//!   positive semidefinite, fast from far away. From the first step whose decrease the
//!   Gauss-Newton model did not predict (not taken in full, or actual < ½ predicted:
//!   [`Curvature::Auto`], the default), the exact Hessian of J: each stage adds
//!   H_k = ∇²_{(ξ,u)}(ν_{k+1}·F̃_k), the curvature of its stage map in the tangent chart weighted
//!   by the nominal's costates, and the cost's own curvature 2c M₀ ∂²M₀/∂φ₁² = −2c M₀²
//!   (in general w r (r″ (∂M₀/∂φ₁)² + r′ ∂²M₀/∂φ₁²)).
//!   With these terms the Riccati recursion solves the Newton system of J(θ) itself (the
//!   reduced Hessian of the multiple-shooting Lagrangian with the adjoint costates as
//!   multipliers, Dunn and Bertsekas 1989). H_k comes from the one model as well: the discrete
//!   adjoint's reverse RATTLE step, run in the same `DualSVec64<8>` as the forward step of the
//!   Jacobians (forward over reverse, `ocp/hessian.rs`; tested against central differences of
//!   [A_k B_k]ᵀν to 5·10⁻⁹, and the resulting Newton step against the dense solve with the
//!   whole-horizon Hessian of `ControlProblem::hessian_vec` to 10⁻¹⁴). Where the exact model
//!   is indefinite some stage's Q_uu is not positive (Q_uu > 0 at every stage is the Riccati
//!   form of a positive definite reduced Hessian) and the Levenberg weight below rises until it
//!   is. Per-step controls without rate penalty, with H_k and every Jacobian within
//!   [`OcpOptions::jacobian_memory`]; otherwise Gauss-Newton throughout.
//! - **Exact gradient** ([`riccati`]): a costate sweep ν_k = l_x + A_kᵀν_{k+1} on the same
//!   Jacobians; it equals the discrete adjoint [`ControlProblem::gradient`] to round-off (tested
//!   to 1e-12) and drives the convergence test.
//! - **The step: an SQP subproblem solved exactly, bounds included.** Stage-wise clamping
//!   (box-DDP, Tassa et al. 2014) and Riccati-based projected Newton (Bertsekas 1982) were tried
//!   first and measured: with |u| ≤ 5 N about 40 % of the 1001 controls of the long-horizon
//!   problem sit on a bound and the Gauss-Newton Hessian is very ill-conditioned (ρh = 10⁻⁴),
//!   so both changed the active set a few controls at a time (box-DDP: 164 iterations; projected
//!   Newton: 50 inner iterations without converging on the drag-free problem). Instead the
//!   box-constrained Gauss-Newton QP is solved by a primal-dual interior-point method whose
//!   Newton systems are Riccati passes (the scheme of HPIPM/acados: barrier curvature z/s added
//!   to Q_uu), 5–15 passes per QP, to a relative accuracy η = min(0.1, √(‖pg‖/‖g₀‖)) of the
//!   projected gradient (an inexact Newton method with a vanishing forcing term). An
//!   interior-point iteration costs one Riccati pass and one linearised rollout (the
//!   direction): the new iterate, its model value and its model gradient follow from the
//!   Newton step itself (the barrier-augmented gradient vanishes at the full step and the
//!   model's gradient is affine along it), so neither a costate sweep nor a second rollout
//!   through the stored Jacobians is needed; a solution is confirmed on a swept gradient.
//!   These passes stream the stored A_k (and H_k) and prefetch them four stages ahead, so
//!   their cost per stage does not grow once the store outgrows the caches (N ≥ 10⁴).
//!   On the drag-free long-horizon problem (where the model is nearly exact) this converges in 3
//!   iterations. The QP's iterates stay inside the box and every rollout clamps: no iterate
//!   leaves the box, and no reparametrisation is used.
//! - **Globalisation** ([`line_search`]): closed-loop rollouts u_k = clamp(ū_k + α k_k + K_k δz_k)
//!   with the last Riccati gains (K ≈ 0 on active bounds: their barrier curvature is large),
//!   which reproduce the QP's step for α = 1 on the linear model; α = 1 first, then the
//!   minimiser of the quadratic through J̄, its slope and J(α); accepted when
//!   J̄ − J(α) ≥ c·(−ΔJ(α)) (c = [`OcpOptions::armijo`]). A Levenberg-Marquardt proximal weight
//!   ½ μ Σ δv² (μ relative to the mean Q_uu) is lowered after full steps whose actual decrease
//!   matched the model and raised otherwise: ×4, and by a further 1/α after a step the line
//!   search shortened to α (the model was trusted about 1/α times too far; with ×4 alone a
//!   run of α = 0.1 steps needed six iterations to lift μ from 10⁻⁶ to where full steps pass).
//! - **Rate penalty and pieces**: the state is augmented with w_k = u_{k−1}; inside a piece the
//!   control is held (u_k = w_k, no decision), so one recursion serves per-step, piecewise and
//!   rate-penalised problems.
//! - **Convergence**: the projected gradient ‖θ − Π_box(θ − g)‖₂ (the first-order KKT measure;
//!   equal to ‖g‖ without active bounds) at most `max(grad_tol, rel_grad_tol·‖g₀‖)`. Otherwise
//!   the run ends *not converged* with the reason: the iteration limit, μ beyond its limit (no
//!   descent found), or steps whose predicted decrease stays below J's round-off.
//! - **Where it is slow**: Gauss-Newton alone converges linearly where the residual stays
//!   large: with drag (D = 10) it misses the costate-weighted curvature of the quadratic drag
//!   p|p|, and takes 23 iterations on the long-horizon scene (16 of them for the last 10⁻⁵ of J,
//!   many with backtracking or a raised μ); the exact model finishes the same run in 4 Newton
//!   iterations after 7 Gauss-Newton ones (projected gradient 0.52, 4.8·10⁻³, 2.2·10⁻²,
//!   2.5·10⁻⁴, then 2·10⁻⁶). Without an effort penalty (ρ = 0) and near folding (Table 3.4 rows 1 and 3)
//!   Gauss-Newton alone stalled at J's round-off while μ rose ×4 per shortened step; with the
//!   1/α rise it converges on all ten rows, as the default does (tests/scene/tables.rs).
//!   In an exact iteration the costates come first, by one reverse step per stage in f64
//!   (the same code as H_k's, `hessian::stage_vjp`: 3 ms at N = 10³ against 22.7 ms for the
//!   Jacobian sweep), then one parallel pass of forward and reverse dual steps gives A_k, B_k
//!   and H_k together: about twice a Gauss-Newton iteration's Jacobian pass.
//! - **Start**: a horizon may start from a given state at t₀
//!   ([`ControlProblem::starting_from`]): the rollouts start there and the loads see
//!   t₀ + k h, as in the adjoint. With the control's half-kick pending
//!   ([`ControlProblem::starting_before_kick`], the given momentum is p̂₀) stage 0 applies
//!   p₀ = p̂₀ − (h/2) u₀ P(q₀) b like every later stage ([`stage`]), so B₀ and the costate
//!   gradient carry it (tests/steppers/start.rs: equal to the adjoint's to 10⁻¹⁴).
//!
//! # Performance
//! One iteration costs a rollout, the stage Jacobians (in parallel over the stages) and a few
//! Riccati passes: O(N) in the horizon, about 22–70 forward simulations of the same horizon per
//! iteration. On the long-horizon scene (N = 10³ per-step controls, a force box, a small effort
//! penalty) the default converges in about 11 iterations and a third of a second, where L-BFGS
//! does not converge in 5000 iterations and the trust region needs minutes; the time per
//! iteration stays linear in N up to 10⁵. For a handful of decisions over a horizon
//! ([`crate::mpc`]'s pieces, thesis Table 3.4) prefer [`Condensed`]. The measurements, with the
//! commands that give them and the designs tried and dropped, are in `docs/benchmarks.md`;
//! the design itself is explained in `docs/riccati.md`.
//!
//! # Observing a run
//! [`Solver::solve_observed`] and [`Condensed::solve_observed`] call an
//! [`IterationObserver`] after every accepted iteration with θ and the iteration's
//! [`IterationRecord`]; it may stop the run ([`OcpTermination::Stopped`]). Nothing is printed:
//! [`OcpResult::history`] keeps the records of a run that was not observed.
//!
//! # Supported problems
//! The planar model (`DIM = 2`) and the spatial model (`DIM = 3`, below),
//! with a free tip (cantilever, riser), every objective
//! with a Gauss-Newton form ℓ_k = ½ w_k r_k(M₀)² + e_k u_k²
//! ([`Objective::gauss_newton`], `ocp/cost.rs`: c and c_sum of
//! [`BendingObjective`](crate::BendingObjective) with r_k = M₀, Σ|M₀|^p of
//! [`PowerObjective`](crate::PowerObjective) with r_k = sgn(M₀)|M₀|^{p/2}), controls that are
//! per-step or piecewise constant in time. Locked and reaction-force tips are refused with
//! [`OcpError::UnsupportedTip`] (their tip constraint removes a dimension of the state manifold that
//! the tangent coordinates do not).
//!
//! # The spatial model
//! [`Condensed`] is written once over the dimension (`Condensed<DIM>`; the stage map
//! `stage::Stepper<D, DIM>`, the trajectories and rollouts with it): in the spatial model
//! (`DIM = 3`, [`ProblemBuilder::build_in`](crate::adjoint::ProblemBuilder::build_in)) the decisions are those of a control along z or of a
//! 2-axis control u_k = (u_{x,k}, u_{z,k}) (θ = (θ_x; θ_z), the stage map's half-kick
//! p_k = p̂_k − (h/2) P(q_k)(u_k b + u_{x,k} b_x)), the sensitivities are those of both moment
//! components (M₀_z, M₀ₓ), and the objective's Gauss-Newton residual is the vector
//! R_k = r_k(|M₀|) M₀/|M₀| with ∂R_k/∂M₀ = g I + (r_k′ − g) û ûᵀ (g = r_k/|M₀|, û = M₀/|M₀|;
//! `cost.rs`), so ½ w_k |R_k|² is the stage cost of the vector moment: M₀ₓ² + M₀_z² for c and
//! c_sum, |M₀|^p for the power objective. This needs an objective of |M₀| alone, checked at
//! construction ([`OcpError::AnisotropicObjective`]). The box holds each component. A planar
//! problem runs the planar code (`DIM = 2`) bit for bit as before (`tables --json` identical).
//! The Riccati solver ([`Solver`], [`solve`]) is written once over the dimension too
//! (`Solver<DIM>`): its stage Jacobians A_k (4n × 4n) and B_k (4n × m, m = 1 or 2 controls
//! per stage) come from the same dual-number stage map in the spatial chart of [`stage`]
//! (δφ_{i,a} = e_a·δqᵢ, δω_{i,a} = e_a·(M⁻¹δp)ᵢ in the basis e_a(qᵢ) of the tangent plane, the
//! chart the closed-loop rollouts measure their deviations in, so the costate gradient is the
//! adjoint's: tests/ocp/ocp_spatial.rs, to 10⁻¹²); the residual's gradient and Gauss-Newton
//! curvature act on both angles of pendulum 1 (l_x = w J_Rᵀ R, l_xx = w J_RᵀJ_R with
//! J_R = ∂R/∂M₀ ∂M₀/∂φ₁); the recursion carries m controls per stage (Q_uu m × m, K m × n_z;
//! with m = 1 the planar scalar code, bit for bit), the interior point one pair of bound
//! multipliers per control, the augmented state w_k = u_{k−1} both components, and the stage
//! box-QP with two controls is solved exactly ([`boxqp`]'s `solve_pair`). The exact model
//! (H_k by forward-over-reverse steps, `hessian.rs`) is planar: in the spatial model the
//! iteration is Gauss-Newton throughout ([`Curvature`] is ignored there), so where the residual
//! stays large it converges linearly and may end at J's round-off
//! ([`OcpTermination::RoundOff`]) rather than at the gradient tolerance, as the planar
//! Gauss-Newton run does on the same problem (tests/ocp/ocp_spatial.rs: per-step, ρ = 0.1, the
//! objective within 10⁻⁹ of the planar exact model's). A planar problem runs `Solver<2>`,
//! whose arithmetic is that of the planar solver before (`tables --json` identical).
//!
//! # Example
//! ```
//! use chainbeam::ocp::{solve, OcpOptions};
//! use chainbeam::{catalogue, BendingObjective, ControlProblem, Parametrisation, PerStepControl};
//! let scene = catalogue::riser(5); // thesis Table 3.4 scene, N = 10
//! let map = Parametrisation::PerStep(PerStepControl { steps: 10 });
//! let problem = ControlProblem::builder(&scene).map(map).objective(BendingObjective::summed_moment().with_effort(0.01)).build_in::<2>()?;
//! let r = solve(&problem, &[0.0; 11], &OcpOptions::default().with_bound(100.0))?;
//! assert!(r.converged);
//! assert!(r.projected_gradient_norm <= 1e-8 * r.initial_gradient_norm);
//! assert!(r.theta.iter().all(|u| u.abs() <= 100.0));
//! # Ok::<(), chainbeam::Error>(())
//! ```
//!
//! # References
//! 1. Y. Tassa, T. Erez, E. Todorov, Synthesis and stabilization of complex behaviors through
//!    online trajectory optimization, IROS 2012 (iLQR/DDP, regularisation, line search).
//! 2. Y. Tassa, N. Mansard, E. Todorov, Control-limited differential dynamic programming,
//!    ICRA 2014 (box-QP, clamped gains).
//! 3. C. Mastalli et al., Crocoddyl, ICRA 2020 (acceptance test, regularisation schedule).
//! 4. C. V. Rao, S. J. Wright, J. B. Rawlings, Application of interior-point methods to model
//!    predictive control, JOTA 1998 (the Riccati recursion as a structured KKT solve).

pub mod boxqp;
pub mod condensed;
mod cost;
mod dense_qp;
mod diagnostics;
mod globalise;
mod hessian;
mod horizon;
mod interior;
mod iterate;
mod jacobians;
pub mod line_search;
mod options;
mod qp;
pub mod riccati;
mod second_order;
mod sensitivities;
mod solver;
pub mod stage;

pub use crate::error::{HorizonShape, OcpError};
pub use condensed::Condensed;
pub use options::{
    Curvature, IterationObserver, IterationRecord, IterationReport, OcpOptions, OcpResult,
    OcpTermination,
};
pub use solver::Solver;

use crate::adjoint::{ControlMap, ControlProblem, Objective};
use crate::error::Result;

/// Minimises J of a [`ControlProblem`] with per-step or piecewise-constant controls from θ₀
/// (projected onto the box) by the structured Gauss-Newton method of the module docs, in the
/// planar or the spatial model.
pub fn solve<P: ControlMap, O: Objective, const DIM: usize>(
    problem: &ControlProblem<P, O, DIM>,
    theta0: &[f64],
    options: &OcpOptions,
) -> Result<OcpResult> {
    Solver::new(problem, options)?.solve(theta0)
}
