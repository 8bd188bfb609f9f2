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
//! c_k = [k = N] (c, eq. 3.3.2), ρ the effort weight of [`BendingObjective::effort`](crate::BendingObjective::effort), σ ≥ 0 the
//! optional rate penalty [`OcpOptions::rate_penalty`] (σh Σ ((u_k − u_{k−1})/h)²: real thrusters
//! cannot jump), u_k = θ_{piece(k)} (per-step: θ = u; piecewise: the pieces of
//! [`PiecewiseControl`](crate::PiecewiseControl)), and the box lower ≤ θ ≤ upper. The costs are
//! those of [`ControlProblem::value`]; without the rate penalty J is exactly that function.
//!
//! # The method (choices, measured on the long-horizon scene)
//! - **Stage structure** ([`stage`]): one control per stage through the shifted state
//!   x̂_k = (q_k, p̂_k), tangent coordinates ξ = (φ, ω) (2n per stage instead of 4n), Jacobians
//!   A_k, B_k by `DualSVec64<8>` through the one generic RATTLE step (its derivative-only Newton
//!   update is the implicit function theorem, exact to round-off), computed in parallel
//!   (rayon, one workspace per thread: stages are independent given the trajectory).
//! - **Second-order model** ([`Curvature`]): Gauss-Newton first — the bending residual
//!   r_k = M₀(q_k) linearised (l_xx = 2∇r∇rᵀ), the dynamics' second derivatives dropped (iLQR):
//!   positive semidefinite, fast from far away. From the first step whose decrease the
//!   Gauss-Newton model did not predict (not taken in full, or actual < ½ predicted:
//!   [`Curvature::Auto`], the default), the exact Hessian of J: each stage adds
//!   H_k = ∇²_{(ξ,u)}(ν_{k+1}·F̃_k), the curvature of its stage map in the tangent chart weighted
//!   by the nominal's costates, and the moment's own curvature 2c M₀ ∂²M₀/∂φ₁² = −2c M₀².
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
//!   1/α rise it converges on all ten rows, as the default does (tests/tables.rs).
//!   In an exact iteration the costates come first, by one reverse step per stage in f64
//!   (the same code as H_k's, `hessian::stage_vjp`: 3 ms at N = 10³ against 22.7 ms for the
//!   Jacobian sweep), then one parallel pass of forward and reverse dual steps gives A_k, B_k
//!   and H_k together: about twice a Gauss-Newton iteration's Jacobian pass.
//! - **Measured and dropped.** Mehrotra's predictor-corrector for the interior point (the
//!   affine direction by a factor pass, the corrector by a solve-only pass: the recursion's
//!   vectors with the gains and Q_uu kept, O(n_z²) per stage): 48 → 31 factor passes at
//!   N = 10³, but its QP solutions, as inexact as allowed, led the outer iteration elsewhere:
//!   12 iterations instead of 10 (farm-bench wall ratio 1.04), 18 instead of 12 with
//!   ρ = 0.001 (ratio 1.29; away from the optimum the exact model's QP is not convex and the
//!   affine step, τ = 0, aims badly), 16 instead of 18 at N = 3000, |u| ≤ 5 → 4 (ratio 0.70).
//!   Not a clear gain; the plain path-following (σ = 0.1, 0.01 after long steps) stays. So
//!   did it against the step-length form of Mehrotra's centering rule, σ = (1 − α)³ in
//!   [0.001, 0.1] (α the shorter of the primal and dual steps): 11 % fewer Riccati passes and
//!   10 % less time summed over 14 variants of the long-horizon scene (`--umax`, `--rho`,
//!   `--rate`, `--steps`, `--pieces`, `--curvature`), N = 10³ 38 passes instead of 48, but
//!   N = 10⁴ one iteration more (3.39 s against 2.98 s) and N = 10⁵ no faster. A
//!   hand-written f64 tangent step instead of the dual numbers would save little: the dual
//!   step costs about 1.3 f64 steps per direction (10 per chunk of 8), near the floor of one
//!   linearised step per direction that any forward-mode Jacobian of 2n + 1 directions pays.
//!   What the dual steps did spend beyond arithmetic was removed instead, each change
//!   keeping every real part bit for bit: the spring function and the tridiagonal solves of
//!   first-order duals from their real parts (`spring_s` lifted by its slope; [`crate::tridiag`]
//!   by the implicit function theorem on the real factors), the drag's slope in closed form
//!   (no nested duals in the reverse step), and two tiny helpers inlined (out-of-line calls
//!   with AVX-512 state transitions): Jacobians 13.4 → 11.4 ms, the exact model's pass
//!   32.5 → 23.3 ms at N = 10³ (`ocp_parts`), the solve at N = 10⁴ and 10⁵ 0.90 of the time
//!   (farm-bench). A dynamic split of the stages over the threads (16 chunks per thread
//!   instead of one half each, whose H_k times differed by 4–10 %) and fusing the Riccati
//!   stage's three products with Ãᵀ into one hand-written loop measured no faster (as extra
//!   columns of the faer product they are: one pass 1.75 → 1.65 ms at N = 10³, unchanged
//!   beyond the caches). Splitting each Riccati stage's products over the two threads (half
//!   of the columns each, one spin barrier per stage) ran at 0.8–0.9× the single thread's
//!   speed in a microbenchmark of the pass's products: every stage hands half of S to the
//!   other core, which costs more than the halved product saves, so the interior point's
//!   passes stay on one thread. Nor was reusing the previous
//!   iteration's H_k (A_k, B_k and the gradient recomputed exactly, half the H pass's cost)
//!   after a full warm-face step the model predicted within 10 % adopted: neutral at
//!   N = 10³–5·10³, 10 iterations instead of 11 at 10⁵ (its 10th step happened to end below
//!   the tolerance), but 39 iterations instead of 34 with [`Curvature::Exact`], where it also
//!   fired far from the optimum.
//! - **Start**: a horizon may start from a given state at t₀
//!   ([`ControlProblem::starting_from`]): the rollouts start there and the loads see
//!   t₀ + k h, as in the adjoint. With the control's half-kick pending
//!   ([`ControlProblem::starting_before_kick`], the given momentum is p̂₀) stage 0 applies
//!   p₀ = p̂₀ − (h/2) u₀ P(q₀) b like every later stage ([`stage`]), so B₀ and the costate
//!   gradient carry it (tests/start.rs: equal to the adjoint's to 10⁻¹⁴).
//!
//! # Measured (2-core machine, `examples/long_horizon.rs`, `benches/ocp.rs`)
//! Long-horizon scene, |u| ≤ 5 N, ρ = 0.01, from u = 0, to ‖pg‖ ≤ 10⁻⁸‖g₀‖, wall time of the
//! release build (fat LTO, `target-cpu=native`: README); the trust-region row at N = 10³ is
//! CPU seconds of an earlier build on a loaded machine.
//!
//! | N | method | time | iterations | J | Σ M₀² | note |
//! |---|---|---|---|---|---|---|
//! | 10³ | this solver (default: Gauss-Newton, then exact) | 0.29–0.36 s (criterion 289 ms) | 11 (7 + 4) | 1507.481361068 | 1507.2286 | the trust region's optimum; pg/‖g₀‖ = 1.5·10⁻⁹ |
//! | 10³ | this solver, Gauss-Newton throughout | 0.54 s | 23 | 1507.481362441 | 1507.2287 | the same optimum at the tolerance; 4.5·10⁻⁹ |
//! | 10³ | L-BFGS | 9.1 s | 5000 (limit) | 1507.489974383 | 1507.2448 | not converged, pg/‖g₀‖ = 1.0·10⁻⁵ |
//! | 10³ | trust region (exact HVPs) | 243.5 s | 119 | 1507.481361068 | 1507.2286 | converged (1.4·10⁻⁹); 50333 HVPs |
//! | 10⁴ | this solver | 2.83–2.91 s | 11 | 1509.506385425 | 1507.2286 | 3.7·10⁻⁹ (Gauss-Newton: 3.2 s, 14 iterations) |
//! | 10⁴ | L-BFGS | 102.5 s | 5000 (limit) | 1509.698222128 | 1507.4462 | not converged, 1.6·10⁻⁴ |
//! | 10⁵ | this solver | 26.4–30.2 s | 11 | 1529.756629004 | 1507.2286 | 9.2·10⁻¹⁰; 31.6 s wall at 30.2 s, 900 MB peak (Gauss-Newton, an earlier build: 222.7 s, 15) |
//! | 10⁵ | L-BFGS | 1164 s | 5000 (limit) | 1532.922287883 | 1510.4200 | not converged, 2.0·10⁻³; 132 MB peak |
//!
//! The times are those `long_horizon` prints (the solve alone; the machine's speed drifts by
//! 10–30 % over minutes, which the ranges include: N = 10⁵ printed 26.4, 30.1, 30.2 and, in a
//! slow phase, 38.2 s; `farm-bench` pairs against the uniform interior-point start of the
//! previous build gave wall ratios 0.94, 1.00 and 0.86 at N = 10³, 10⁴, 10⁵, and
//! `cargo bench --bench ocp -- ocp_solve/riccati/1000` a median of 289 ms for both). Time per
//! iteration 26 ms, 0.26 s and 2.7 s: linear in N within 1.05× (the passes over the stored
//! Jacobians prefetch them; without, 10⁴ and 10⁵ cost 1.1× and 1.35× of linear). The parts
//! at N = 10³ (`cargo bench --bench ocp -- ocp_parts`): forward simulation 0.65 ms; rollout +
//! stage Jacobians + costate sweep 11.4 ms (17.5 simulations, two threads); one Riccati pass
//! with its linearised rollout 1.65 ms (2.5 simulations; 19.5 ms at N = 10⁴, 3.0 simulations
//! of 6.49 ms: beyond the caches the pass streams 3.2 kB of A_k per stage, twice per
//! interior-point iteration, and huge pages for them did not help, `GLIBC_TUNABLES=
//! glibc.malloc.hugetlb=1` at N = 10⁵: farm-bench wall ratio 1.00); the exact model's extra —
//! costate sweep, A_k, B_k and H_k of every stage (a forward and a reverse dual step per
//! chunk) and a Riccati pass with them — 23.3 ms (36 simulations; 246 ms at N = 10⁴). A
//! Gauss-Newton iteration thus costs about 22–35 simulations (one pass on the warm face, or
//! 2–7 interior-point iterations, each a Riccati pass and a linearised rollout), an exact one
//! about 40–70; the default run averages 40 of these simulations at N = 10³ (36 Riccati
//! passes in 11 iterations; a sinusoidal control, `ocp_parts/forward`). Against a simulation
//! at the optimum, where the beam rests in the middle of the horizon and RATTLE's Newton
//! needs one iteration per step (0.50 ms at N = 10³, 4.1 ms at 10⁴), the ratio
//! `long_horizon` prints is 46, 62–65 and 69 at N = 10³, 10⁴, 10⁵. Of the issue's targets,
//! 3 s at N = 10⁴, ≤ 30 iterations, the linear scaling and Table 3.4's time are met; 0.3 s at
//! N = 10³ and 30 s at 10⁵ are met in the machine's fast phases and missed by up to 20 % and
//! 27 % in its slow ones; ≤ 20 simulations per iteration is not met: the cheapest iteration
//! this design has (Gauss-Newton, one pass on the warm face, one rollout) is ≈ 22 of them,
//! and it reaches the time targets by spending more per iteration (interior-point passes
//! while the active set settles, the exact model near the end) on fewer iterations. The
//! yardstick is cheap (0.65 µs per step at n = 10): the Jacobians alone are 2n + 1 = 21
//! linearised steps per stage, about 10 simulations on two threads at the floor of forward
//! mode, before any QP pass (≈ 3 simulations each). N = 10⁵ needs an 11th iteration because
//! its 10th ends just above the tolerance (projected gradient 2.1·10⁻³ against
//! 10⁻⁸‖g₀‖ = 1.0·10⁻³): near the optimum the exact Newton steps on the warm face (model
//! gradient solved to 10⁻¹³, decrease predicted to 1.000000 of the actual one) reduce the
//! true projected gradient slowly where J is curved by ρh = 10⁻⁴ alone, spread evenly over
//! the ~10⁵ controls of the horizon's static middle, where the beam is at rest against the
//! constant load.
//!
//! Table 3.4 (per-step, N = 10, no effort penalty, each row bounded by the thesis's largest
//! |u_k|): all ten rows converge; against the trust region the objectives are equal on rows
//! 1–7, lower on row 8 (1.5·10⁻⁹ relative), both at J ≈ 0 on row 10 (3·10⁻¹³ against
//! 5·10⁻²¹), and higher on row 9 (6.0236·10⁻⁶ against 6.0208·10⁻⁶, another local minimum,
//! which the exact Hessian from the start avoids). Which local minimum a row ends in follows
//! the solver's path: before the interior point started centred ([`Solver`]'s QP) rows 3 and
//! 6 ended above the trust region's minima and row 2 below (30.09 against 32.89).
//! 29–31 ms for the ten rows through `minimize` (four criterion runs; trust region 101 ms,
//! L-BFGS 126 ms; [`Condensed`], `Method::Condensed`: 14–18 ms, against this solver higher
//! objectives on rows 3, 6 and 8 and lower ones on rows 1 (22.93) and 9;
//! `cargo bench --bench ocp -- ocp_table_3_4`).
//!
//! Supported: the planar model (`DIM = 2`) with a free tip (cantilever, riser), objectives
//! [`BendingObjective`](crate::BendingObjective) (c or c_sum, with effort), controls that are per-step or piecewise
//! constant in time. Locked and reaction-force tips are refused with
//! [`Error::InvalidArgument`] (their tip constraint removes a dimension of the state manifold that
//! the tangent coordinates do not).
//!
//! # Example
//! ```
//! use chainbeam::ocp::{solve, OcpOptions};
//! use chainbeam::{catalogue, BendingObjective, ControlProblem, Parametrisation, PerStepControl};
//! let scene = catalogue::riser(5); // thesis Table 3.4 scene, N = 10
//! let map = Parametrisation::PerStep(PerStepControl { steps: 10 });
//! let problem = ControlProblem::new(&scene, map, BendingObjective::summed_moment().with_effort(0.01))?;
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
mod diagnostics;
mod driver;
mod globalise;
mod hessian;
pub mod line_search;
mod options;
mod qp;
pub mod riccati;
pub mod stage;

pub use condensed::Condensed;
pub use options::{Curvature, IterationRecord, OcpOptions, OcpResult, Termination};

use std::time::Instant;

use faer::Mat;
#[cfg(feature = "parallel")]
use rayon::prelude::*;

use crate::adjoint::{ControlMap, ControlProblem, Objective};
use crate::error::{Error, Result};
use crate::model::Chain;
use crate::scene::ObjectiveKind;
use hessian::{
    gradient_entry, stage_vjp, HessianWorkspace, Reverse, SecondOrderMut, VjpStage, VjpWorkspace,
};
use line_search::{Feedback, Shooting, Simulator, Traj};
use riccati::{Riccati, StageCost, StageInput, StageJacobians};
use stage::{tangent, Dv, JacobiansMut, StageAt, StageModel, StagePoint};

/// Consecutive round-off steps without a 10 % decrease of the projected gradient after which
/// the run stops ([`Termination::RoundOff`]).
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
/// How [`Solver::linear_rollout`] moves the controls.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Arc {
    /// Closed loop with the Riccati gains, clamped to the box.
    ClosedLoop,
    /// Closed loop, unclamped, recording the direction Δv in `dir`.
    Direction,
    /// Open loop to the clamped controls u + α dir.
    Projected,
}

/// How many stages ahead of the current one the passes over the stored Jacobians prefetch
/// ([`riccati::prefetch`]).
const PREFETCH_AHEAD: usize = 4;

/// Prefetches A_k (in store slot `i`) and, when given, H_k of stage `k`.
fn prefetch_stage(a_store: &[f64], h_store: Option<&[f64]>, nxi: usize, i: usize, k: usize) {
    let per = nxi * nxi;
    riccati::prefetch(&a_store[i * per..(i + 1) * per]);
    if let Some(h) = h_store {
        let nd = (nxi + 1) * (nxi + 1);
        riccati::prefetch(&h[k * nd..(k + 1) * nd]);
    }
}

/// Interior-point iterations of one QP solve.
const MAX_QP_ITERS: usize = 40;

/// The second-order terms of the stages, as the backward pass reads them.
struct SecondOrder<'a> {
    on: bool,
    steps: usize,
    nz: usize,
    h: &'a [f64],
    curv: &'a [f64],
    dz: &'a [f64],
}

impl<'a> SecondOrder<'a> {
    /// ½ δᵀH_kδ + ½ curv_k δφ₁² at the model point δ = (δz_k, δv_k): stage k's second-order
    /// terms in the model's value.
    fn value(&self, k: usize, dz: &[f64], dv: f64) -> f64 {
        let (nz, nd) = (self.nz, self.nz + 1);
        let mut v = 0.5 * self.curv[k] * dz[0] * dz[0];
        if k < self.steps {
            let h = &self.h[k * nd * nd..(k + 1) * nd * nd];
            let hx = |j: usize| {
                let c = &h[j * nd..(j + 1) * nd];
                riccati::dot(&c[..nz], dz) + c[nz] * dv
            };
            v += 0.5 * ((0..nz).map(|j| dz[j] * hx(j)).sum::<f64>() + dv * hx(nz));
        }
        v
    }

    /// Attaches stage k's terms to its input (nothing for Gauss-Newton).
    fn attach(&self, inp: &mut StageInput<'a>) {
        if !self.on {
            return;
        }
        let (k, nz) = (inp.k, self.nz);
        let nd = nz + 1;
        inp.curv = self.curv[k];
        inp.dz = &self.dz[k * nz..(k + 1) * nz];
        if k < self.steps {
            inp.hess = Some(&self.h[k * nd * nd..(k + 1) * nd * nd]);
        }
    }
}

/// Minimises J of a [`ControlProblem`] with per-step or piecewise-constant controls from θ₀
/// (projected onto the box) by the structured Gauss-Newton method of the module docs.
pub fn solve<P: ControlMap, O: Objective>(
    problem: &ControlProblem<P, O>,
    theta0: &[f64],
    options: &OcpOptions,
) -> Result<OcpResult> {
    Solver::new(problem, options)?.solve(theta0)
}

/// The solver with all its buffers, reusable for several starts (and the linearisation
/// diagnostics the tests use).
#[derive(Clone, Debug)]
pub struct Solver {
    model: StageModel,
    cost: StageCost,
    opts: OcpOptions,
    steps: usize,
    n: usize,
    nxi: usize,
    nz: usize,
    n_params: usize,
    /// Whether stage k has a decision (first step of a piece).
    free: Vec<bool>,
    /// θ index of stage k.
    piece: Vec<usize>,
    /// Stage of θ_j.
    theta_stage: Vec<usize>,
    nominal: Traj,
    trial: Traj,
    sim: Simulator,
    jws: Vec<HessianWorkspace>,
    a_store: Vec<f64>,
    b_store: Vec<f64>,
    block: usize,
    /// Stages [lo, hi) whose Jacobians at the nominal are in the store.
    jac_range: Option<(usize, usize)>,
    riccati: Riccati,
    /// The ε-active set of the current iteration: stage k's control moves to its bound
    /// (step `fixed[k]`) without feedback.
    active: Vec<bool>,
    fixed: Vec<f64>,

    /// The model point δ of the QP iterations (δv per stage, δz per stage) and its trial.
    dv: Vec<f64>,
    dz: Vec<f64>,
    dv_t: Vec<f64>,
    dz_t: Vec<f64>,
    lin_dz: Vec<f64>,
    lin_next: Vec<f64>,
    dir: Vec<f64>,
    /// Interior-point multipliers of the lower and upper bounds, their steps, and the barrier
    /// terms of the Riccati pass (used when `barrier`).
    zl: Vec<f64>,
    zh: Vec<f64>,
    dzl: Vec<f64>,
    dzh: Vec<f64>,
    ip_quu: Vec<f64>,
    ip_lu: Vec<f64>,
    barrier: bool,
    /// The exact gradient at the nominal (per stage).
    gtrue: Vec<f64>,
    /// Feedforward of the closed-loop rollout about the nominal.
    ff_out: Vec<f64>,
    /// Proximal weight μ (absolute) of the current model.
    prox: f64,
    quu_scale: f64,
    counts: (usize, usize, usize),
    /// The second-order terms (`hessian`): the dual chain of the reverse steps, H_k per stage
    /// and the cost's extra curvature per stage; `exact` when the current model uses them.
    chain_dv: Chain<Dv, 2>,
    /// The stage map and buffers of the costate sweep by reverse steps, and its costates ν_k
    /// (n_z per stage): the multipliers of the second-order terms.
    vjp: VjpWorkspace<f64>,
    nu_store: Vec<f64>,
    h_store: Vec<f64>,
    curv: Vec<f64>,
    exact: bool,
    /// Whether the iterations from now on use the exact model ([`Curvature`]).
    second_order_on: bool,
    /// Whether `h_store` holds H_k at the current nominal (a failed line search keeps it).
    h_valid: bool,
    /// Whether the exact model is available: per-step controls without rate penalty (no
    /// augmented state), H_k and the Jacobians of every stage within `jacobian_memory`, and a
    /// curvature other than Gauss-Newton. Its storage is allocated at its first use.
    second_order_possible: bool,
}

impl Solver {
    /// Builds the solver for `problem` (validates the options, the model, the objective — a
    /// [`BendingObjective`](crate::BendingObjective) — and the control map).
    pub fn new<P: ControlMap, O: Objective>(
        problem: &ControlProblem<P, O>,
        options: &OcpOptions,
    ) -> Result<Self> {
        let Setup {
            model,
            cost,
            steps,
            n_params,
            piece,
            free,
            theta_stage,
        } = Setup::new(problem, options, "the Riccati solver")?;
        let n = model.n;
        let nxi = model.nx();
        let aug = usize::from(options.rate_penalty > 0.0 || free.iter().any(|f| !f));
        let nz = nxi + aug;
        let threads = if options.threads == 0 {
            available_threads()
        } else {
            options.threads
        }
        .clamp(1, steps.max(1));
        let jws = (0..threads)
            .map(|_| HessianWorkspace::new(&model))
            .collect::<Result<Vec<_>>>()?;
        let stage_bytes = 8 * (nxi * nxi + nxi);
        let block = (options.jacobian_memory / stage_bytes).clamp(1, steps.max(1));
        // The exact model keeps H_k beside every A_k, B_k: both within `jacobian_memory`.
        let exact_bytes = stage_bytes + 8 * (nxi + 1) * (nxi + 1);
        let second_order_possible = aug == 0
            && options.jacobian_memory / exact_bytes >= steps
            && options.curvature != Curvature::GaussNewton;
        let riccati = Riccati::new(nxi, aug, steps);
        Ok(Solver {
            chain_dv: model.chain.lift::<Dv>(),
            vjp: VjpWorkspace::new(&model)?,
            nu_store: Vec::new(),
            h_store: Vec::new(),
            second_order_possible,
            curv: vec![0.0; steps + 1],
            exact: false,
            second_order_on: false,
            h_valid: false,
            sim: Simulator::new(&model)?,
            nominal: Traj::new(n, steps),
            trial: Traj::new(n, steps),
            a_store: vec![0.0; block * nxi * nxi],
            b_store: vec![0.0; block * nxi],
            riccati,
            active: vec![false; steps + 1],
            fixed: vec![0.0; steps + 1],
            dv: vec![0.0; steps + 1],
            dz: vec![0.0; (steps + 1) * nz],
            dv_t: vec![0.0; steps + 1],
            dz_t: vec![0.0; (steps + 1) * nz],
            lin_dz: vec![0.0; nz],
            dir: vec![0.0; steps + 1],
            zl: vec![0.0; steps + 1],
            zh: vec![0.0; steps + 1],
            dzl: vec![0.0; steps + 1],
            dzh: vec![0.0; steps + 1],
            ip_quu: vec![0.0; steps + 1],
            ip_lu: vec![0.0; steps + 1],
            barrier: false,
            lin_next: vec![0.0; nz],
            gtrue: vec![0.0; steps + 1],
            ff_out: vec![0.0; steps + 1],
            prox: 0.0,
            model,
            cost,
            opts: options.clone(),
            steps,
            n,
            nxi,
            nz,
            n_params,
            free,
            piece,
            theta_stage,
            jws,
            block,
            jac_range: None,
            quu_scale: 1.0,
            counts: (0, 0, 0),
        })
    }

    /// Number of parameters θ.
    pub fn n_params(&self) -> usize {
        self.n_params
    }

    /// Simulates θ (projected onto the box) as the new nominal trajectory and returns J.
    pub fn set_point(&mut self, theta: &[f64]) -> Result<f64> {
        check_theta(theta, self.n_params)?;
        let (lo, hi) = (self.opts.lower, self.opts.upper);
        for k in 0..=self.steps {
            self.nominal.u[k] = theta[self.piece[k]].clamp(lo, hi);
        }
        self.jac_range = None;
        self.h_valid = false;
        self.counts.0 += 1;
        let shooting = Shooting {
            model: &self.model,
            cost: &self.cost,
            free: &self.free,
            lower: lo,
            upper: hi,
        };
        self.sim.rollout(&shooting, None, &mut self.nominal)?;
        Ok(self.nominal.cost)
    }

    /// θ of the nominal trajectory.
    pub fn theta(&self) -> Vec<f64> {
        self.theta_stage
            .iter()
            .map(|&k| self.nominal.u[k])
            .collect()
    }

    /// J of the nominal trajectory.
    pub fn objective(&self) -> f64 {
        self.nominal.cost
    }

    /// The stage Jacobians of stages [lo, hi) at the nominal into the store, in parallel.
    fn jacobians(&mut self, lo: usize, hi: usize) -> Result<()> {
        if self.jac_range == Some((lo, hi)) {
            return Ok(());
        }
        let (nxi, count) = (self.nxi, hi - lo);
        let per_a = nxi * nxi;
        let chunk = count.div_ceil(self.jws.len()).max(1);
        let (model, nom) = (&self.model, &self.nominal);
        let work = |c: usize, a: &mut [f64], b: &mut [f64], ws: &mut HessianWorkspace| {
            for (i, (ai, bi)) in a.chunks_mut(per_a).zip(b.chunks_mut(nxi)).enumerate() {
                let k = lo + c * chunk + i;
                let x = StagePoint {
                    q: nom.q(k),
                    p: nom.p(k),
                    omega: nom.omega(k),
                    mu: nom.lambda(k),
                };
                let at = StageAt {
                    model,
                    k,
                    x,
                    u: nom.u[k],
                };
                ws.jac.jacobians(at, JacobiansMut { a: ai, b: bi })?;
            }
            Ok::<(), Error>(())
        };
        let a = &mut self.a_store[..count * per_a];
        let b = &mut self.b_store[..count * nxi];
        #[cfg(feature = "parallel")]
        if self.jws.len() > 1 {
            a.par_chunks_mut(chunk * per_a)
                .zip(b.par_chunks_mut(chunk * nxi))
                .zip(self.jws.par_iter_mut())
                .enumerate()
                .try_for_each(|(c, ((a, b), ws))| work(c, a, b, ws))?;
        } else {
            work(0, a, b, &mut self.jws[0])?;
        }
        #[cfg(not(feature = "parallel"))]
        for (c, ((a, b), ws)) in a
            .chunks_mut(chunk * per_a)
            .zip(b.chunks_mut(chunk * nxi))
            .zip(self.jws.iter_mut())
            .enumerate()
        {
            work(c, a, b, ws)?;
        }
        self.jac_range = Some((lo, hi));
        self.counts.1 += 1;
        Ok(())
    }

    /// What the backward pass needs of stage k at the model point δ (the current inner
    /// iterate: `dv`, `dz`; δ = 0 is the nominal) without its Jacobians: the linearised moment
    /// M₀ + ∂M₀/∂φ₁ δφ₁, the shifted controls, the box relative to them and the proximal
    /// gradient. With `with_active`, a control of the ε-active set gets its fixed step.
    fn stage_input(&self, k: usize, with_active: bool) -> StageInput<'static> {
        let nom = &self.nominal;
        let d = nom.dmoment(k, self.model.moment_scale);
        let u = nom.u[k] + self.dv[k];
        let (lo, hi) = if self.barrier {
            (f64::NEG_INFINITY, f64::INFINITY)
        } else if with_active && self.active[k] {
            (self.fixed[k], self.fixed[k])
        } else {
            (self.opts.lower - u, self.opts.upper - u)
        };
        let (qs, ls) = if self.barrier && self.free[k] {
            (self.ip_quu[k], self.ip_lu[k])
        } else {
            (0.0, 0.0)
        };
        StageInput {
            k,
            free: self.free[k],
            moment: nom.moment[k] + d * self.dz[k * self.nz],
            dmoment: d,
            u,
            w: if k > 0 {
                nom.u[k - 1] + self.dv[k - 1]
            } else {
                0.0
            },
            lo,
            hi,
            lu_shift: if self.free[k] {
                self.prox * self.dv[k] + ls
            } else {
                0.0
            },
            quu_shift: qs,
            jac: None,
            hess: None,
            curv: 0.0,
            dz: &[],
            dv: self.dv[k],
        }
    }

    /// One sweep k = N … 0 over the stages, with the Jacobians computed block by block ahead
    /// of it: the Riccati recursion (`riccati = true`, proximal weight `self.prox`; returns
    /// whether every stage QP was bounded) or the costate sweep alone (the gradient into
    /// `riccati.grad`).
    fn sweep(&mut self, riccati: bool) -> Result<bool> {
        let (steps, nxi, mu) = (self.steps, self.nxi, self.prox);
        self.riccati.begin();
        let mut last = self.stage_input(steps, true);
        let so = SecondOrder {
            on: self.exact,
            steps,
            nz: self.nz,
            h: &self.h_store,
            curv: &self.curv,
            dz: &self.dz,
        };
        so.attach(&mut last);
        let mut bounded = if riccati {
            self.counts.2 += 1;
            self.riccati.stage(&last, &self.cost, mu)
        } else {
            self.riccati.costate(&last, &self.cost);
            true
        };
        let mut top = steps;
        while top > 0 {
            let bottom = top.saturating_sub(self.block);
            self.jacobians(bottom, top)?;
            let h_store = self.exact.then_some(&self.h_store[..]);
            for k in (bottom..top).rev() {
                let i = k - bottom;
                if i >= PREFETCH_AHEAD {
                    let (slot, ahead) = (i - PREFETCH_AHEAD, k - PREFETCH_AHEAD);
                    prefetch_stage(&self.a_store, h_store, nxi, slot, ahead);
                }
                let mut inp = self.stage_input(k, true);
                inp.jac = Some(StageJacobians {
                    a: &self.a_store[i * nxi * nxi..(i + 1) * nxi * nxi],
                    b: &self.b_store[i * nxi..(i + 1) * nxi],
                });
                let so = SecondOrder {
                    on: self.exact,
                    steps,
                    nz: self.nz,
                    h: &self.h_store,
                    curv: &self.curv,
                    dz: &self.dz,
                };
                so.attach(&mut inp);
                if riccati {
                    bounded &= self.riccati.stage(&inp, &self.cost, mu);
                } else {
                    self.riccati.costate(&inp, &self.cost);
                }
            }
            top = bottom;
        }
        if riccati && self.riccati.quu_count > 0 {
            let m = self.riccati.quu_sum / self.riccati.quu_count as f64;
            self.quu_scale = if m > 0.0 && m.is_finite() { m } else { 1.0 };
        }
        Ok(bounded)
    }

    /// The exact gradient at the nominal (δ = 0, no active set): the costate sweep.
    fn costate(&mut self) -> Result<()> {
        self.dv.fill(0.0);
        self.dz.fill(0.0);
        self.active.fill(false);
        self.sweep(false).map(|_| ())
    }

    /// Allocates the exact model's storage (H_k per stage, the costates) at its first use.
    fn second_order_storage(&mut self) {
        let nd = self.nxi + 1;
        if self.h_store.is_empty() {
            self.h_store = vec![0.0; self.steps * nd * nd];
            self.nu_store = vec![0.0; (self.steps + 1) * self.nz];
        }
    }

    /// H_k = ∇²(ν_{k+1}·F̃_k) and the Jacobians A_k, B_k of every stage at the nominal, in
    /// one parallel pass of forward and reverse dual steps (`hessian`), and the cost's
    /// curvature −2c_k M₀(t_k)²; needs the costates ν of [`Solver::costate_by_reverse_steps`].
    fn hessians(&mut self) -> Result<()> {
        let (steps, nxi) = (self.steps, self.nxi);
        let nd = nxi + 1;
        let per = nd * nd;
        let chunk = steps.div_ceil(self.jws.len()).max(1);
        let (model, nom, chain) = (&self.model, &self.nominal, &self.chain_dv);
        let nu = &self.nu_store;
        let work =
            |c: usize, hs: &mut [f64], a: &mut [f64], b: &mut [f64], ws: &mut HessianWorkspace| {
                let mut rev = Reverse::new(chain, model, steps);
                let mut grad = vec![0.0; nd];
                let stages = hs
                    .chunks_mut(per)
                    .zip(a.chunks_mut(nxi * nxi).zip(b.chunks_mut(nxi)));
                for (i, (h, (ai, bi))) in stages.enumerate() {
                    let k = c * chunk + i;
                    let x = StagePoint {
                        q: nom.q(k),
                        p: nom.p(k),
                        omega: nom.omega(k),
                        mu: nom.lambda(k),
                    };
                    let nu1 = &nu[(k + 1) * nxi..(k + 2) * nxi];
                    let at = StageAt {
                        model,
                        k,
                        x,
                        u: nom.u[k],
                    };
                    let out = SecondOrderMut {
                        hess: h,
                        grad: &mut grad[..],
                        jac: JacobiansMut { a: ai, b: bi },
                    };
                    ws.second_order(at, nu1, &mut rev, out)?;
                }
                Ok::<(), Error>(())
            };
        let hs = &mut self.h_store[..steps * per];
        let a = &mut self.a_store[..steps * nxi * nxi];
        let b = &mut self.b_store[..steps * nxi];
        #[cfg(feature = "parallel")]
        if self.jws.len() > 1 {
            hs.par_chunks_mut(chunk * per)
                .zip(a.par_chunks_mut(chunk * nxi * nxi))
                .zip(b.par_chunks_mut(chunk * nxi))
                .zip(self.jws.par_iter_mut())
                .enumerate()
                .try_for_each(|(c, (((h, a), b), ws))| work(c, h, a, b, ws))?;
        } else {
            work(0, hs, a, b, &mut self.jws[0])?;
        }
        #[cfg(not(feature = "parallel"))]
        for (c, (((h, a), b), ws)) in hs
            .chunks_mut(chunk * per)
            .zip(a.chunks_mut(chunk * nxi * nxi))
            .zip(b.chunks_mut(chunk * nxi))
            .zip(self.jws.iter_mut())
            .enumerate()
        {
            work(c, h, a, b, ws)?;
        }
        self.jac_range = Some((0, steps));
        self.counts.1 += 1;
        for k in 0..=steps {
            let m = self.nominal.moment[k];
            self.curv[k] = -2.0 * self.cost.weight(k) * m * m;
        }
        self.h_valid = true;
        Ok(())
    }

    /// The exact gradient and the costates ν_k at the nominal without the stage Jacobians:
    /// ν_N = l_x, then ν_k = l_x + A_kᵀν_{k+1} and g_k = l_u + B_kᵀν_{k+1} as one reverse step
    /// of each stage in f64 (`hessian::stage_vjp`: the stage recomputed from the stored x̂_k,
    /// then the adjoint's reverse step), O(N) sequential, about two simulations. For the exact
    /// model (no augmented state), whose H_k pass then computes A_k and B_k as well.
    fn costate_by_reverse_steps(&mut self) -> Result<()> {
        let (steps, nxi) = (self.steps, self.nxi);
        self.dv.fill(0.0);
        self.dz.fill(0.0);
        self.active.fill(false);
        self.second_order_storage();
        let mut rev = Reverse::new(&self.model.chain, &self.model, steps);
        let scale = self.model.moment_scale;
        for k in (0..=steps).rev() {
            let nom = &self.nominal;
            let (c, u) = (self.cost.weight(k), nom.u[k]);
            let lx0 = 2.0 * c * nom.moment[k] * nom.dmoment(k, scale);
            let lu = 2.0 * self.cost.effort * u;
            let (done, rest) = self.nu_store.split_at_mut((k + 1) * nxi);
            let nu_k = &mut done[k * nxi..];
            nu_k.fill(0.0);
            nu_k[0] = lx0;
            self.riccati.grad[k] = lu;
            if k == steps {
                continue;
            }
            let st = &mut self.vjp.stepper.state;
            st.q.copy_from_slice(nom.q(k));
            st.p.copy_from_slice(nom.p(k));
            let m = st.multipliers_mut(nom.lambda(k).len());
            m.lambda.copy_from_slice(nom.lambda(k));
            m.mu.copy_from_slice(nom.lambda(k));
            st.tip_target = [0.0; 2];
            self.vjp.bufs.omega0.copy_from_slice(nom.omega(k));
            let stage = VjpStage {
                model: &self.model,
                k,
                u,
                nu: &rest[..nxi],
            };
            stage_vjp(&mut self.vjp.stepper, &mut self.vjp.bufs, stage, &mut rev)?;
            for (r, v) in nu_k.iter_mut().enumerate() {
                *v += gradient_entry(&self.vjp.bufs, &rev, k, r);
            }
            self.riccati.grad[k] += gradient_entry(&self.vjp.bufs, &rev, k, nxi);
        }
        Ok(())
    }

    /// Bertsekas's ε-active set at the model point from the gradient of the last costate
    /// sweep: a control within ε of a bound whose gradient pushes it outward moves to that
    /// bound and is fixed there (no feedback); every other control is free in the Newton step.
    fn set_active(&mut self, eps: f64) {
        let (lo, hi) = (self.opts.lower, self.opts.upper);
        for k in 0..=self.steps {
            let (u, g) = (self.nominal.u[k] + self.dv[k], self.riccati.grad[k]);
            self.active[k] = false;
            if !self.free[k] {
                continue;
            }
            if u <= lo + eps && g > 0.0 {
                self.active[k] = true;
                self.fixed[k] = lo - u;
            } else if u >= hi - eps && g < 0.0 {
                self.active[k] = true;
                self.fixed[k] = hi - u;
            }
        }
    }

    fn theta_gradient(&self) -> Vec<f64> {
        self.theta_stage
            .iter()
            .map(|&k| self.riccati.grad[k])
            .collect()
    }

    /// ‖θ − Π_box(θ − g)‖₂ at the model point with the gradient of the last costate sweep.
    fn projected_norm(&self) -> f64 {
        let (lo, hi) = (self.opts.lower, self.opts.upper);
        self.theta_stage
            .iter()
            .map(|&k| {
                let (t, g) = (self.nominal.u[k] + self.dv[k], self.riccati.grad[k]);
                let d = boxqp::projected_component(t, g, lo, hi);
                d * d
            })
            .sum::<f64>()
            .sqrt()
    }
}

/// What both solvers read off a problem: the stage model from its start, the stage costs,
/// and the control structure u_k = θ_{piece(k)}.
struct Setup {
    model: StageModel,
    cost: StageCost,
    steps: usize,
    n_params: usize,
    piece: Vec<usize>,
    /// Whether stage k starts a piece (has a decision).
    free: Vec<bool>,
    /// The first stage of θ_j.
    theta_stage: Vec<usize>,
}

impl Setup {
    /// Validates the options, the model (planar, free tip, a control node), the objective (a
    /// [`BendingObjective`](crate::BendingObjective)) and the control map (per-step or piecewise
    /// constant); `solver` names the solver in the objective's error.
    fn new<P: ControlMap, O: Objective>(
        problem: &ControlProblem<P, O>,
        options: &OcpOptions,
        solver: &str,
    ) -> Result<Self> {
        options.validate()?;
        let obj = problem
            .objective()
            .bending()
            .ok_or_else(|| Error::InvalidArgument {
                name: "objective",
                reason: format!(
                    "{solver} needs a bending-moment objective (c or c_sum, with effort): it \
                     exploits their Gauss-Newton form"
                ),
            })?;
        let steps = problem.steps();
        let h = problem.time_step();
        let model = StageModel::new(problem.chain(), h)?.with_start(problem.start());
        let cost = StageCost {
            effort: obj.effort * h,
            rate: options.rate_penalty / h,
            final_only: obj.kind == ObjectiveKind::Final,
            steps,
        };
        let n_params = problem.n_params();
        let (piece, free) = control_structure(&problem.controls(&ids(n_params))?, n_params)?;
        let theta_stage = (0..=steps).filter(|&k| free[k]).collect();
        Ok(Setup {
            model,
            cost,
            steps,
            n_params,
            piece,
            free,
            theta_stage,
        })
    }
}

/// θ has `n_params` finite entries ([`Error::InvalidArgument`] naming `theta` otherwise).
fn check_theta(theta: &[f64], n_params: usize) -> Result<()> {
    if theta.len() != n_params {
        return Err(Error::InvalidArgument {
            name: "theta",
            reason: format!("expected {n_params} values, got {}", theta.len()),
        });
    }
    if let Some(i) = theta.iter().position(|x| !x.is_finite()) {
        return Err(Error::InvalidArgument {
            name: "theta",
            reason: format!("entry {i} is not finite"),
        });
    }
    Ok(())
}

/// θ_j = j, to read the control structure off the control map.
fn ids(n_params: usize) -> Vec<f64> {
    (0..n_params).map(|j| j as f64).collect()
}

/// The control structure u_k = θ_{piece(k)} of the controls `u` of θ_j = j: contiguous pieces
/// 0, 1, …, n_params − 1 (per-step, piecewise or constant); `free[k]` when stage k starts a
/// piece (has a decision).
fn control_structure(u: &[f64], n_params: usize) -> Result<(Vec<usize>, Vec<bool>)> {
    let not_piecewise = || Error::InvalidArgument {
        name: "control map",
        reason: "the Riccati solver needs controls that are per-step or piecewise constant in \
                 time (u_k = θ_j on consecutive pieces j = 0, 1, …)"
            .into(),
    };
    let (mut piece, mut free) = (Vec::with_capacity(u.len()), Vec::with_capacity(u.len()));
    for (k, &x) in u.iter().enumerate() {
        let j = x as usize;
        let prev = if k > 0 { piece[k - 1] } else { 0 };
        let ok = if k == 0 {
            j == 0
        } else {
            j == prev || j == prev + 1
        };
        if (j as f64 - x).abs() > 0.0 || !ok {
            return Err(not_piecewise());
        }
        free.push(k == 0 || j != prev);
        piece.push(j);
    }
    if piece.last().map(|p| p + 1) != Some(n_params) {
        return Err(not_piecewise());
    }
    Ok((piece, free))
}

/// Threads for the stage Jacobians when `OcpOptions::threads` is 0: rayon's pool with the
/// `parallel` feature, else 1.
fn available_threads() -> usize {
    #[cfg(feature = "parallel")]
    {
        rayon::current_num_threads()
    }
    #[cfg(not(feature = "parallel"))]
    {
        1
    }
}
