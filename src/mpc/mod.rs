//! Closed-loop control of the riser: a receding-horizon (model predictive) controller built on
//! the Gauss-Newton solvers of [`crate::ocp`] (condensed or Riccati), the baselines it is measured against, and the loop that
//! runs any of them against a plant that may differ from the controller's model.
//!
//! # The loop
//! The plant ([`Plant`]) is a scene simulated by RATTLE from its start (`[time] initial`). Time is
//! cut into control intervals of m steps (interval = m h); at the start t_{jm} of interval j the
//! controller observes the plant ([`Observation`]: the state (q, p), M₀, Ṁ₀, the tip) and
//! returns one force u_j ([`Force2`]; its z component in a planar scene), which the plant holds over the interval:
//! u_k = u_j for k = jm .. jm + m − 1 (zero-order hold; u_N repeats the last one). The applied
//! controls are a [`PiecewiseControl`](crate::PiecewiseControl) with one piece per interval, and
//! the plant's trajectory is exactly the open-loop RATTLE trajectory of them ([`Plant`] on the
//! switching step). [`run_closed_loop`] records t_k, M₀(t_k), u_k and the tip for k = 0..N and
//! the wall time of every decision, and summarises them ([`Summary`]):
//! ```text
//! c_sum = Σ_{k=0}^{N} M₀(t_k)²          (thesis eq. 3.3.4, the quantity every controller is judged by)
//! max |M₀(t_k)|,  max |u_k|,  effort h Σ_k u_k²
//! real-time factor = T / Σ_{j≥1} (wall time of decision j),   T = N h
//! ```
//! The first decision (at t = 0, from the beam at rest) is reported on its own: a receding-
//! horizon controller computes it cold, before the loads arrive; every later decision must fit
//! in the control interval for the loop to run in real time.
//!
//! # The controllers
//! - [`Mpc`]: receding horizon. At t_{jm} it solves
//!   min_θ Σ_{k=0}^{H} M₀(t_{jm+k})² + ρ h Σ u_k² (+ the rate penalty σ/h Σ (Δu)²), |θ| ≤ u_max,
//!   over a horizon of H steps of its *model* scene, starting from the observed state before
//!   the control's half-kick at the observed time (below, "The start of a horizon"),
//!   with one piece per control interval, by a Gauss-Newton solver ([`MpcSolver`]: the
//!   condensed one by default, or the Riccati one) warm-started from the previous plan shifted
//!   by one interval (the tail padded with its last value) and a fixed
//!   iteration budget (real-time iteration: 1-2 Gauss-Newton steps per re-plan), then applies
//!   θ₀. The model's forecast of the loads is the model scene's loads: the plant and the model
//!   may differ in any scene quantity (drag, load amplitude or phase, a current, the step).
//! - [`NoControl`]: u = 0.
//! - [`ConstantForce`]: the best constant force over the whole scene (the same solver on the
//!   one-piece problem of the *plant* scene: an offline optimum that knows the future).
//! - [`PdLaw`]: u = clamp(u_b − K_p M₀ − K_d Ṁ₀) on the measured base moment, sampled at the
//!   control interval, with (u_b, K_p, K_d) tuned by [`crate::optimize::minimize`] over the
//!   closed-loop c_sum of the plant scene, the gradient by dual numbers through the closed loop
//!   ([`pd_closed_loop_cost`]).
//!
//! # The start of a horizon
//! A RATTLE step k−1 → k takes u_k in its second half-kick, so the plant's p_k depends on the
//! force the controller is about to decide. After the projection onto the hidden constraint
//! that half-kick is affine in the force (b = ∂U_q/∂u, P(q) the projection,
//! [`Plant`] "The state before the control's half-kick"):
//! ```text
//! p_k = p̂_k − (h/2) u_k P(q_k) b,
//! ```
//! with p̂_k, the momentum of the step into t_k taken with zero control in its second
//! half-kick, independent of u_k. The plant exposes (q_k, p̂_k)
//! ([`ModelObservation::state_before_kick`]) and [`Mpc`] plans from it with the kick pending
//! ([`ControlProblem::starting_before_kick`](crate::ControlProblem::starting_before_kick)): the
//! plan's first force supplies the half-kick by the equation above, so it acts on both sides
//! of t_k exactly as the plant then applies it, and a re-plan is exactly the tail of the run
//! it continues (at k = 0 the beam is at rest, p_0 = 0 whatever u_0, and the plan starts from
//! it as it is). With a perfect model and the horizon to the end the closed loop reproduces
//! the open-loop optimum to the solver's tolerance (tests/mpc/mpc.rs: 6.2·10⁻¹⁰ in the forces,
//! 7.9·10⁻¹⁴ in J; a start that held the observed p_k fixed left the first force short by a
//! half-kick: 1.0 % and 1.8·10⁻³).
//!
//! # The spatial model
//! The plant, the observation and the loop are written once over the dimension
//! ([`Plant<D, DIM>`](Plant); [`Observation::in_model`] gives the states in the model's own
//! dimension), and one [`run_closed_loop`] runs either: a scene whose loads, current or control
//! have an x component (or a controller that plans in the spatial model,
//! [`Controller::spatial`]) runs the spatial plant, and every [`Controller`] decides a 2-axis
//! force [`Force2`] (u_x, u_z) per interval, u_x = 0 in a planar scene. The baselines are one
//! type each: [`NoControl`], [`ConstantForce`] (the best constant (u_x, u_z), by the condensed
//! solver in the scene's model, [`crate::ocp`] "The spatial model") and [`PdLaw`] (a PD law per
//! axis with common gains, tuned by [`PdTuning`] in the scene's model). The summary of a
//! spatial run judges by |M₀|² = M₀ₓ² + M₀_z² and |u|. A planar scene runs the planar code as
//! before, bit for bit.
//! The receding-horizon controller is written once over the dimension too ([`Mpc<DIM>`](Mpc)):
//! [`Mpc::spatial`] plans a 2-axis force on the vector moment, min Σ |M₀|² + ρ h Σ |u|² over
//! θ = (θ_x; θ_z), each component within the box, with the condensed or the Riccati solver in
//! the spatial model ([`crate::ocp`], "The spatial model"), from the observed state or its map
//! onto a reduced planning model ([`planning`], whose map is written over the dimension).
//! Tested in tests/ocp/ocp_spatial.rs: the closed loop of a scene turned by 45° about the beam's
//! axis is the planar closed loop turned (c_sum to 10⁻⁹, forces to 10⁻⁸ N), with either solver.
//!
//! # MPC through the vessel's thrust
//! In a scene whose control is the thrust F on the vessel ([`crate::scene::Thrust`]: the top
//! follows the vessel's surge, (m + m_a) ẍ_v = F − c ẋ_v) [`Mpc`] plans thrust *commands*, one
//! per control interval, and the plant applies them through its thrusters ([`Plant`], "The
//! vessel under thrust"): the command clipped to ±F_max, the thrust moved toward it by at most
//! Ḟ_max h per step. The structured Gauss-Newton solvers above cannot take this problem (their
//! minimal coordinates cannot hold a prescribed tip, [`crate::error::OcpError::UnsupportedTip`]),
//! so a re-plan is solved another way, exactly:
//! - **The plan models the thrusters** (src/mpc/thrust.rs): its per-step thrusts are the
//!   plant's clipping of the commands, F_i = F_{i−1} + clamp(clamp(θ_j, ±F_max) − F_{i−1},
//!   ±Ḟ_max h), so the rate bound is respected by the plant's clipping and the plan predicts
//!   that clipping exactly (no penalty keeps the plan inside; the commands are boxed to ±F_max).
//!   A command beyond what the rate lets the thrust reach within its interval changes no thrust
//!   when moved: a penalty σ Σ_j (θ_j − F_{end of j})², zero for a reached command, removes that
//!   flat direction without changing the optimal thrusts.
//! - **The gradient is exact**: the horizon's moment objective over the per-step thrusts is the
//!   library's generic control problem ([`ControlProblem`](crate::ControlProblem) with one
//!   control per step, the path the best constant thrust takes), its gradient by the discrete
//!   adjoint through RATTLE and the vessel's surge; the thrusters' map is transposed by hand
//!   (∂F_i/∂θ_j = 1 where the command is reached, ∂F_i/∂F_{i−1} = 1 where the rate clips).
//! - **The step is a bounded L-BFGS** ([`crate::optimize::minimize`], `Method::Lbfgs` with the
//!   box ±F_max) with a fixed budget per re-plan ([`MpcOptions::thrust_iterations`], default 5;
//!   the first plan [`MpcOptions::first_iterations`]), warm-started from the previous plan
//!   shifted by one interval: a real-time iteration in the sense above. (A Gauss-Newton step on
//!   dual-number sensitivities of the moments to the few commands would model the curvature
//!   better; it is not written.)
//! - **The start**: the plant re-takes the step into t_k with the thrust F_k the new command
//!   gives, and that thrust enters both the vessel's velocity and the riser's momentum at t_k.
//!   The plan therefore starts one step back, from the plant's state at t_{k−1}
//!   ([`ModelObservation::previous_state`]) with its thrust F_{k−1} fixed, and its first step is the
//!   plant's re-taken step: a re-plan is exactly the tail of the run it continues, and with a
//!   perfect model and the horizon to the end the closed loop reproduces the open-loop optimum
//!   (tests/mpc/mpc_vessel.rs).
//!
//! A thrust plan runs on the model scene in the planar model, at the plant's step h or at a
//! whole multiple r h of it (`plan_step`, with the model's own pendulums): such a coarser plan
//! starts at t_k from the observed state with the thrust applied there fixed (the plant's
//! re-taken step then moves that thrust by at most Ḟ_max h toward the new command, which the
//! plan does not see: its approximation), its thrusters clip per plan step (Ḟ_max r h), and its
//! effort weight is rescaled to its steps as a reduced plan's ([`planning::objective_scale`]);
//! `plan_step` = h is the full plan bit for bit (tests/mpc/thrust_plan_step.rs).
//!
//! With fewer pendulums (`plan_pendulums` = n_p < n, `plan_step` = h_p a whole multiple of h) it
//! plans on the reduced model of [`planning`] with the same vessel, from the state mapped by
//! [`planning::StateMap`] (the vessel's (Z, Ż) copied), from t_k if h_p > h (else t_{k−1}), its
//! thrusters clipped per plan step; a hot spot's h_p Σ|M|^m + ρ h_p Σ F² (M blended between the
//! plan's joints) keeps ρ, the base moment's is rescaled ([`planning`], "The objective"); with
//! `observe = "sensors"` the filter runs on the plant's chain and step and its estimate is mapped
//! (docs/mpc.md "The reduced thrust plan"; exact gradient: tests/mpc/thrust_reduced.rs).
//!
//! # What the plan knows
//! [`MpcOptions::forecast`] ([`Forecast`], `[mpc] forecast`, `--forecast`): `perfect` plans on
//! the model scene's sea as it is (with a perfect model, the plant's own future); `none` plans
//! on a calm sea, the model scene without `[loads.waves]`, from the observed state. Calm rather
//! than "the present kinematics frozen": a wave's water velocity reverses within half a period
//! (4 s at T_p = 8 s), so holding today's velocity over a 20 s horizon predicts a steady drag
//! the sea never applies, while the calm sea predicts none of the future load and keeps the
//! motion the waves have already caused (it is in the observed state). Without waves the
//! vessel's wave-frequency motion is gone from the plan too, and the plan's vessel starts from
//! the observed position and velocity. `noisy` plans on the model scene's sea with errors that
//! grow with lead time ([`forecast`]): at every re-plan each wave component's complex amplitude
//! aⱼ e^{iφⱼ} is forecast as aⱼ e^{iφⱼ} (1 + σ(τ) wⱼ), wⱼ a fresh pair of standard normal draws
//! (a relative amplitude error σ ξⱼ and a phase error σ ηⱼ rad to first order), with
//! σ(τ) = min(e τ / T_p, 1/√2) at lead time τ after the decision, e = `forecast_error`
//! ([`MpcOptions::forecast_error`], default 0.1: 10 % and 0.1 rad one peak period ahead), the
//! cap where the forecast's mean-square error reaches the sea's own (no better than `none`);
//! seeded by `forecast_seed` ([`MpcOptions::forecast_seed`], default the sea's seed, a
//! separate ChaCha20 stream), so a run is reproducible. The forecast changes the plan's wave
//! loads and the vessel's wave-frequency surge alike (both are linear in the amplitudes); with
//! e = 0 it is the perfect forecast bit for bit (tests/mpc/forecast_noisy.rs). The plant always
//! runs the true sea.
//!
//! # What the controller sees
//! [`MpcOptions::observe`] ([`Observe`], `[mpc] observe`, `--observe`): `state` plans from the
//! plant's whole state, as every section above says; `sensors` plans from the estimate of a
//! Kalman filter ([`observer`]) that reads only the sensors a drilling riser carries — the
//! vessel's position and velocity, the top and bottom flex joints' angles and the LMRP's
//! inclination, each with its measurement noise (seeded) — and predicts between readings with
//! the plan's own model and the forecast's sea. It is built for MPC through the vessel's thrust
//! on a `[stackup]` scene (refused elsewhere, naming `observe`): the filter's estimate at
//! t_{k−1} is the plan's start. The other controllers are unchanged by it (the PD law measures
//! M₀ as before).
//!
//! # Which solver re-plans ([`MpcSolver`])
//! A 3 s horizon is 300 steps but only 30 decisions. The Riccati solver linearises every step
//! (21 dual-number directions per step for n = 10, then several Riccati passes over 300
//! stages: cost linear in the horizon); the condensed solver
//! ([`ocp::Condensed`](crate::ocp::Condensed)) propagates one direction per decision from the
//! decision's first step on (about N·m/2 direction-steps for m decisions) and solves a dense
//! 30 × 30 box QP: fewer operations while m is a few tens, with the same Gauss-Newton model
//! and the same exact gradient. The Riccati solver remains the choice for long horizons and
//! per-step controls (its cost does not grow with m); the default, [`MpcSolver::Auto`], picks
//! the condensed solver up to 4(2n + 1) pieces (measured crossover on `mpc_riser`: between 80
//! and 100 pieces) and the Riccati solver beyond, so a horizon to the end of a long run starts
//! with the Riccati solver and finishes with the condensed one. The condensed solver is kept
//! between re-plans ([`ocp::Condensed::restart`](crate::ocp::Condensed::restart)).
//!
//! # Measured (`cargo run --release --example mpc`, `chainbeam mpc examples/scenes/mpc_riser.toml --baselines`)
//! The scene: n = 10, D = 10 kg/m, the irregular sea at node 5 and a sheared current along +z
//! (0.1 → 0.02 m/s, switched on at t = 0 on the straight beam); 60 s, interval 0.1 s, horizon
//! 3 s, 1 Gauss-Newton iteration per re-plan, |u| ≤ 5 N, ρ = 0.01, on the 2-core machine
//! (load average ≈ 1.5; its timings vary by about ±20 % from run to run):
//!
//! | controller | c_sum | max \|M₀\| (Nm) | max \|u\| (N) | mean / worst re-plan (ms) |
//! |---|---|---|---|---|
//! | none | 4797918.4 | 35.51 | 0 | |
//! | best constant force | 92936.4 | 9.14 | 2.93 | |
//! | tuned PD on M₀ (u_b = 2.80 N, K_p = −0.319 N/Nm, K_d = −0.031 Ns/Nm) | 54668.8 | 11.56 | 5.00 | |
//! | MPC, perfect model (condensed solver) | 9307.5 | 12.16 | 5.00 | 4.9 / 17.4 |
//! | MPC, drag −30 %, current +20 %, forecast without the 5.3 s component and −20 % on the 8 s wave | 14207.2 | 11.76 | 5.00 | 5.2 / 11.6 |
//! | MPC, perfect model, Riccati solver | 9292.1 | 12.04 | 5.00 | 9.9 / 16.6 |
//!
//! MPC's c_sum is 10.0 % of the best constant force's and 17.0 % of the tuned PD law's (wrong
//! model: 15.3 % and 26.0 %); the two solvers' loops differ by 0.2 % (the one-iteration
//! re-plans are not converged, and their line searches differ, open loop against Riccati
//! feedback; solved to the tolerance every plan gives the same optimum with either,
//! tests/cli/cli_mpc.rs). Such a loop amplifies round-off: making the stage derivatives' Newton
//! update use real-part matrices (commit 3b183b0, derivative parts changed at the 10⁻¹⁴ level)
//! moved the condensed loop's c_sum from 9256.7 to 9307.5 (0.5 %) and the 1 s horizon's (both
//! solvers) by 2–5 %: differences of that size between builds or solvers are not findings.
//! Its max |M₀| is
//! higher than the constant force's: the transient when the current switches on at t = 0
//! saturates every controller, and MPC trades that peak for the sum it minimises. Without the
//! current (the same sea alone, an earlier build: 9a0108d) MPC's c_sum was 1.82 against the
//! PD law's 61262: the current's
//! steady drag, which the force must cancel (≈ 2.9 N of the 5 N), is what leaves MPC a
//! residual.
//!
//! Re-plan cost: the condensed solver takes 2.0× less time than the Riccati solver on this
//! loop (mean 4.9 against 9.9 ms; worst 17.4 against 16.6 ms), real-time factor of the
//! controller 20.4 against 10.1: the worst re-plan fits the 100 ms interval with either, and the
//! mean ≤ 10 ms holds with the condensed solver. Measured on an earlier build (9a0108d),
//! `cargo bench --bench mpc` (one re-plan at
//! t = 10 s; the machine's timings vary by about ±20 % from run to run): 1.7 / 4.6 / 5.5 /
//! 8.5 ms for horizons of 1 / 2 / 3 / 4 s with the condensed solver, 5.0 / 12.1 / 14.9 /
//! 12.8 ms with the Riccati solver; the 10 s closed loop with the 3 s horizon: mean re-plan
//! 4.8 ms, worst 9.7 ms, controller real-time factor 21 (Riccati: 13.5 ms, 19.4 ms, 7.5), the
//! whole loop (plant included) 16× faster than real time (Riccati 6.7×).
//! A condensed re-plan is two or three rollouts (the nominal from the observed state, the line
//! search) and one pass of sensitivities (about 60 % of its time); the gradient pass that only
//! served a final convergence test is skipped
//! ([`OcpOptions::final_gradient`](crate::ocp::OcpOptions::final_gradient)).
//!
//! Tried and left out: reusing the previous re-plan's stage Jacobians shifted by one interval
//! (the multi-level real-time iteration, with the gradient kept exact by one adjoint sweep)
//! made a Riccati re-plan 18 % cheaper but the closed loop 2.4× worse (c_sum 22312 against
//! 9292 over 60 s): the Jacobians computed 3 s ahead differ from those at the nominal by 1–5 %,
//! and on this ill-conditioned problem (ρh = 10⁻⁴) that spoils the step; more line-search
//! rollouts ate most of the saving. A model with a coarser step (0.02 s) fails: the riser's
//! fastest mode needs h = 0.01 s (the RATTLE Newton iteration diverges).
//!
//! Horizon against cost (`cargo run --release -p paper_figures -- --only mpc_horizon`, 60 s):
//! c_sum 3302921 / 35592 / 9307 / 7592 / 7466 for horizons of 1 / 2 / 3 / 4 / 5 s at mean
//! re-plan times of 1.4 / 2.5 / 5.2 / 8.4 / 11.0 ms (condensed; Riccati: 3629881 / 38363 /
//! 9292 / 7592 / 7469 at 4.3 / 6.5 / 9.5 / 12.3 / 15.3 ms) ([`MpcOptions::horizon`]): 1 s is
//! 36× worse than the best constant force (myopic), 2 s beats the PD law by 1.5×, 3 s by 5.9×.
//!
//! # Example
//! ```
//! use chainbeam::mpc::{run_closed_loop, Horizon, Mpc, MpcOptions, NoControl};
//! use chainbeam::{catalogue, ocp::OcpOptions};
//! let mut scene = catalogue::wave_riser();
//! scene.time.steps = 100; // 1 s
//! let options = MpcOptions {
//!     horizon: Horizon::Seconds(0.5),
//!     ocp: OcpOptions::default().with_bound(5.0),
//!     ..MpcOptions::default()
//! };
//! let mut mpc = Mpc::new(&scene, 0.1, options)?;
//! let controlled = run_closed_loop(&scene, 0.1, &mut mpc)?;
//! let free = run_closed_loop(&scene, 0.1, &mut NoControl)?;
//! assert!(controlled.summary.c_sum < free.summary.c_sum);
//! assert!(controlled.summary.max_abs_control <= 5.0);
//! # Ok::<(), chainbeam::Error>(())
//! ```

mod baselines;
pub(crate) use baselines::pd;
pub mod forecast;
mod hotspot_setting;
pub mod observer;
pub mod planning;
mod plant;
pub mod prediction;
mod receding;
mod thrust;

pub use crate::scene::Forecast;
pub use crate::scene::MomentAbout;
pub use crate::scene::Observe;
pub use baselines::{
    pd_closed_loop_cost, pd_closed_loop_cost_at, pd_closed_loop_cost_spatial, running_mean,
    ConstantForce, NoControl, PdLaw, PdTuning, PD_MEAN_TIME,
};
pub use forecast::{forecast_sigma, NoisyForecast, SIGMA_CAP};
pub use observer::{Observer, ObserverOptions, SensorNoise, SensorSet};
pub use plant::Plant;
pub use receding::{Horizon, Mpc, MpcOptions, MpcSolver, PlannedThrust};

use std::any::Any;
use std::time::Instant;

use serde::Serialize;

pub use crate::error::MpcError;
use crate::error::Result;
use crate::scene::{Checked, SceneInput};
use crate::steppers::rattle::State;

/// A force at the control node in the two transverse axes (N): `z` in the plane of a planar
/// scene, `x` out of it (0 in a planar scene, whose plant refuses u_x ≠ 0 with
/// [`crate::Error::NeedsSpatialModel`]).
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
pub struct Force2 {
    /// u_x (N).
    pub x: f64,
    /// u_z (N).
    pub z: f64,
}

impl Force2 {
    /// (0, u_z): a force in the plane, the only force of a planar scene.
    pub const fn z(z: f64) -> Self {
        Force2 { x: 0.0, z }
    }
}

/// What a controller sees at the start t_k of a control interval, in either model: the
/// scalars below (the x components 0 in the planar model), and the plant's states in the
/// model's own dimension through [`Observation::in_model`].
#[derive(Clone, Copy)]
pub struct Observation<'a> {
    /// The step index k.
    pub k: usize,
    /// t_k = k h.
    pub t: f64,
    /// The plant's step h.
    pub h: f64,
    /// The plant's last step N (the run ends at t_N).
    pub steps: usize,
    /// The control interval (s).
    pub interval: f64,
    /// M₀(t_k) (Nm; its z component M₀_z in the spatial model).
    pub moment: f64,
    /// Ṁ₀(t_k) (Nm/s).
    pub moment_rate: f64,
    /// The tip displacement z_n (m).
    pub tip: f64,
    /// The control held so far (N; its z component in the spatial model).
    pub control: f64,
    /// M₀ₓ(t_k) (Nm; 0 in the planar model).
    pub moment_x: f64,
    /// Ṁ₀ₓ(t_k) (Nm/s; 0 in the planar model).
    pub moment_rate_x: f64,
    /// The x component of the control held so far (N; 0 in the planar model).
    pub control_x: f64,
    /// The control applied at t_{k−1} (N; 0 at k = 0): the thrust of the step into t_k's first
    /// half in a scene whose control is the thrust on the vessel.
    pub previous_control: f64,
    /// The plant's states, their dimension erased (read back by [`Observation::in_model`]).
    states: Erased<'a>,
}

/// The states of an [`Observation`] behind `Any`, with the model's dimension.
#[derive(Clone, Copy)]
struct Erased<'a> {
    dim: usize,
    state: &'a dyn Any,
    state_before_kick: Option<&'a dyn Any>,
    previous_state: Option<&'a dyn Any>,
}

impl<'a> Erased<'a> {
    fn of<const DIM: usize>(
        state: &'a State<f64, DIM>,
        state_before_kick: Option<&'a State<f64, DIM>>,
        previous_state: Option<&'a State<f64, DIM>>,
    ) -> Self {
        Erased {
            dim: DIM,
            state,
            state_before_kick: state_before_kick.map(|s| s as &dyn Any),
            previous_state: previous_state.map(|s| s as &dyn Any),
        }
    }
}

impl std::fmt::Debug for Observation<'_> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Observation")
            .field("k", &self.k)
            .field("t", &self.t)
            .field("spatial", &self.spatial())
            .field("moment", &self.moment)
            .field("moment_x", &self.moment_x)
            .field("control", &self.control)
            .field("control_x", &self.control_x)
            .finish_non_exhaustive()
    }
}

impl<'a> Observation<'a> {
    /// What the loop observes of `plant` at its present step, decisions every `interval`
    /// seconds (call [`Plant::update_state_before_kick`] first for the state before the
    /// control's half-kick).
    pub fn of_plant<const DIM: usize>(plant: &'a mut Plant<f64, DIM>, interval: f64) -> Self {
        let moment_rate = plant.moment_rate();
        let [moment_x, _] = plant.moment_vector();
        let [moment_rate_x, _] = plant.moment_vector_rate();
        let plant: &'a Plant<f64, DIM> = plant;
        Observation {
            k: plant.step_index(),
            t: plant.time(),
            h: plant.h(),
            steps: plant.steps(),
            interval,
            moment: plant.moment(),
            moment_rate,
            tip: plant.tip(),
            control: plant.control(),
            moment_x,
            moment_rate_x,
            control_x: plant.control_x(),
            previous_control: plant.previous_control(),
            states: Erased::of(
                plant.state(),
                plant.state_before_kick(),
                plant.previous_state(),
            ),
        }
    }

    /// Whether the plant runs in the spatial model (qᵢ ∈ S², its states `State<f64, 3>`).
    pub fn spatial(&self) -> bool {
        self.states.dim == 3
    }

    /// The observation with the plant's states in the model of dimension `DIM` (2: planar,
    /// 3: spatial), for a controller that plans in that model.
    ///
    /// # Errors
    /// [`MpcError::ControllerModel`] when the plant runs in the other model.
    pub fn in_model<const DIM: usize>(&self) -> Result<ModelObservation<'a, DIM>> {
        let cast = |s: &'a dyn Any| s.downcast_ref::<State<f64, DIM>>();
        let e = self.states;
        let name = |spatial: bool| if spatial { "spatial" } else { "planar" };
        let state = cast(e.state).ok_or(MpcError::ControllerModel {
            controller: name(DIM == 3),
            plant: name(self.spatial()),
        })?;
        Ok(ModelObservation {
            observation: *self,
            state,
            state_before_kick: e.state_before_kick.and_then(cast),
            previous_state: e.previous_state.and_then(cast),
        })
    }
}

/// An [`Observation`] with the plant's states in the model of dimension `DIM`
/// ([`Observation::in_model`]); it reads as the observation itself (`Deref`).
#[derive(Clone, Copy, Debug)]
pub struct ModelObservation<'a, const DIM: usize> {
    /// The observation's scalars.
    pub observation: Observation<'a>,
    /// The state (q_k, p_k), p_k with the held control u_{k−1} in the second half-kick of the
    /// step into t_k ([`Plant`]).
    pub state: &'a State<f64, DIM>,
    /// (q_k, p̂_k): the state before the control's half-kick at t_k, p̂_k the momentum of the
    /// step into t_k taken with zero control in its second half-kick, which the force decided
    /// now completes ([`Plant::state_before_kick`]); `None` at k = 0 (the beam at rest, no step
    /// into t₀) and for a reaction-force tip.
    pub state_before_kick: Option<&'a State<f64, DIM>>,
    /// The state at t_{k−1}, from which the plant re-takes the step into t_k with the control
    /// decided now ([`Plant::previous_state`]); `None` at k = 0.
    pub previous_state: Option<&'a State<f64, DIM>>,
}

impl<'a, const DIM: usize> ModelObservation<'a, DIM> {
    /// The observation `observation`'s scalars with the states replaced (a filter's estimate
    /// in place of the plant's).
    pub(crate) fn with_states(
        mut observation: Observation<'a>,
        state: &'a State<f64, DIM>,
        state_before_kick: Option<&'a State<f64, DIM>>,
        previous_state: Option<&'a State<f64, DIM>>,
    ) -> Self {
        observation.states = Erased::of(state, state_before_kick, previous_state);
        ModelObservation {
            observation,
            state,
            state_before_kick,
            previous_state,
        }
    }
}

impl<'a, const DIM: usize> std::ops::Deref for ModelObservation<'a, DIM> {
    type Target = Observation<'a>;
    fn deref(&self) -> &Observation<'a> {
        &self.observation
    }
}

/// A feedback law: one force per control interval from what it observes, in either model (a
/// planar scene's plant holds u_z with u_x = 0, a spatial scene's both).
pub trait Controller {
    /// A short name for tables, lower-case as the command line's controller names ("none",
    /// "constant", "pd", "mpc").
    fn name(&self) -> String;

    /// The force (u_x, u_z) for the interval starting at `obs.t` (u_x = 0 when the plant is
    /// planar, `obs.spatial()` false).
    ///
    /// # Errors
    /// The controller's failure (a failed solve, settings that do not fit the plant).
    fn control(&mut self, obs: &Observation<'_>) -> Result<Force2>;

    /// Iterations of the optimiser at the last decision (None: no optimiser).
    fn last_iterations(&self) -> Option<usize> {
        None
    }

    /// Simulations of the plan's model at the last decision (each a rollout of the horizon, with
    /// its adjoint sweep when the solver asked for the gradient; None: no optimiser). With
    /// [`Controller::last_iterations`] it says what a decision cost: a solver that backtracks
    /// runs more simulations per iteration.
    fn last_rollouts(&self) -> Option<usize> {
        None
    }

    /// Whether the controller plans in the spatial model: [`run_closed_loop`] then runs the
    /// plant in it even for a planar scene (false: the scene decides).
    fn spatial(&self) -> bool {
        false
    }
}

/// One decision of the loop.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct Decision {
    /// Its time t_k (s).
    pub t: f64,
    /// The force decided (N; its z component in the spatial model).
    pub control: f64,
    /// Wall-clock seconds the controller took.
    pub seconds: f64,
    /// Optimiser iterations, if any.
    pub iterations: Option<usize>,
    /// Simulations of the plan's model, if any ([`Controller::last_rollouts`]).
    pub rollouts: Option<usize>,
}

/// The numbers a closed-loop run is judged by (module docs).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Summary {
    /// [`Controller::name`].
    pub controller: String,
    /// c_sum = Σ_{k=0}^{N} M₀(t_k)² (N²m², eq. 3.3.4; |M₀|² = M₀ₓ² + M₀_z² in the spatial
    /// model).
    pub c_sum: f64,
    /// max_k |M₀(t_k)| (Nm).
    pub max_abs_moment: f64,
    /// max_k |u_k| (N; |u| = √(u_x² + u_z²) in the spatial model).
    pub max_abs_control: f64,
    /// h Σ_k |u_k|² (N²s).
    pub effort: f64,
    /// Simulated time T = N h (s).
    pub simulated_seconds: f64,
    /// Decisions taken (N / m).
    pub decisions: usize,
    /// Wall time of the first decision (at t = 0, s).
    pub initial_decision_seconds: f64,
    /// Mean wall time of the decisions after the first (s; 0 with a single decision).
    pub mean_replan_seconds: f64,
    /// Longest wall time of a decision after the first (s).
    pub worst_replan_seconds: f64,
    /// Mean optimiser iterations per decision after the first (None: no optimiser).
    pub mean_iterations: Option<f64>,
    /// Mean simulations of the plan's model per decision after the first, Σ_{k≥1} r_k / (N/m − 1)
    /// (None: no optimiser; [`Decision::rollouts`]).
    pub mean_rollouts: Option<f64>,
    /// T / Σ_{j≥1} (decision wall time): how much faster than real time the controller runs
    /// (the decisions after the first; capped at 10¹² for controllers that take no time).
    pub real_time_factor: f64,
    /// T / wall time of the whole loop (plant and controller, the first decision included).
    pub loop_real_time_factor: f64,
    /// In a scene whose control is the vessel's thrust: max_k |F_k − F_{k−1}| / h \[N/s\], the
    /// largest rate of the applied thrust, after the loop checked every step against the
    /// vessel's limits (|F_k| ≤ F_max, the rate ≤ Ḟ_max); `None` otherwise.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub thrust_rate_peak: Option<f64>,
}

/// A closed-loop run: the trajectory at every step, the decisions and the summary.
#[derive(Clone, Debug, PartialEq)]
pub struct ClosedLoopResult {
    /// t_k (s), k = 0..N.
    pub t: Vec<f64>,
    /// M₀(t_k) (Nm; M₀_z in the spatial model).
    pub moment: Vec<f64>,
    /// u_k (N; u_z in the spatial model).
    pub control: Vec<f64>,
    /// Tip displacement z_n(t_k) (m).
    pub tip: Vec<f64>,
    /// M₀ₓ(t_k) (Nm; spatial model, empty in the planar one).
    pub moment_x: Vec<f64>,
    /// u_{x,k} (N; spatial model, empty in the planar one).
    pub control_x: Vec<f64>,
    /// One record per control interval.
    pub decisions: Vec<Decision>,
    /// The summary.
    pub summary: Summary,
}

/// The number of steps m of a control interval: interval = m h exactly (to 10⁻⁹ relative).
///
/// # Errors
/// [`MpcError::IntervalNotMultiple`] when it is not a positive multiple of h.
pub fn interval_steps(interval: f64, h: f64) -> Result<usize> {
    let m = (interval / h).round();
    if !(interval.is_finite() && interval > 0.0 && m >= 1.0)
        || (m * h - interval).abs() > 1e-9 * interval
    {
        return Err(MpcError::IntervalNotMultiple { interval, h }.into());
    }
    Ok(m as usize)
}

/// Runs `controller` against the plant of `scene` (from rest at t = 0) with one decision every
/// `interval` seconds, to t_N (module docs). The plant runs in the spatial model when the scene
/// has a load, a current or a control with an x component ([`Scene::spatial_key`](crate::Scene::spatial_key)) or the
/// controller plans in it ([`Controller::spatial`]): the plant then holds (u_x, u_z) over each
/// interval and the summary judges by |M₀|² = M₀ₓ² + M₀_z² and |u|² = u_x² + u_z²; otherwise
/// in the planar model, holding u_z (u_x must be 0).
///
/// # Errors
/// [`MpcError::IntervalNotMultiple`] when the interval is not a multiple of h,
/// [`MpcError::RunNotWhole`] when it does not divide the run T = N h; the controller's and the
/// plant's errors (a failed step, a failed solve, u_x ≠ 0 in the planar model) end the run.
pub fn run_closed_loop<S: SceneInput + ?Sized>(
    scene: &S,
    interval: f64,
    controller: &mut dyn Controller,
) -> Result<ClosedLoopResult> {
    let scene = scene.checked()?;
    if scene.spatial_key().is_some() || controller.spatial() {
        closed_loop::<3>(scene, interval, controller)
    } else {
        closed_loop::<2>(scene, interval, controller)
    }
}

/// The loop of both models: observe, decide, hold, record.
fn closed_loop<const DIM: usize>(
    checked: Checked<'_>,
    interval: f64,
    controller: &mut dyn Controller,
) -> Result<ClosedLoopResult> {
    let start = Instant::now();
    let mut plant = Plant::<f64, DIM>::new(&checked)?;
    let m = interval_steps(interval, plant.h())?;
    let steps = plant.steps();
    if steps % m != 0 {
        return Err(MpcError::RunNotWhole {
            steps,
            interval_steps: m,
        }
        .into());
    }
    let mut rec = Recorder::with_capacity(steps + 1, DIM == 3);
    let mut decisions = Vec::with_capacity(steps / m);
    for _ in 0..steps / m {
        crate::cancel::check()?;
        plant.update_state_before_kick()?;
        let obs = Observation::of_plant(&mut plant, interval);
        let clock = Instant::now();
        let u = controller.control(&obs)?;
        let seconds = clock.elapsed().as_secs_f64();
        decisions.push(Decision {
            t: obs.t,
            control: u.z,
            seconds,
            iterations: controller.last_iterations(),
            rollouts: controller.last_rollouts(),
        });
        plant.set_controls([u.x, u.z])?;
        for _ in 0..m {
            rec.push(&plant);
            plant.advance()?;
        }
    }
    rec.push(&plant);
    let loop_seconds = start.elapsed().as_secs_f64();
    let mut summary = summarise(controller.name(), &rec, &decisions, plant.h(), loop_seconds);
    if let Some(limits) = plant.thrust_limits() {
        summary.thrust_rate_peak = Some(check_thrust_limits(&rec.control, limits, plant.h())?);
    }
    Ok(ClosedLoopResult {
        t: rec.t,
        moment: rec.moment,
        control: rec.control,
        tip: rec.tip,
        moment_x: rec.moment_x,
        control_x: rec.control_x,
        decisions,
        summary,
    })
}

/// Checks the applied thrusts F_0..F_N of a run against the vessel's limits at every step,
/// |F_k| ≤ F_max and |F_k − F_{k−1}| ≤ Ḟ_max h (F_{−1} = 0; the rate to a relative 10⁻⁹ for the
/// round-off of F_{k−1} ± Ḟ_max h), and returns the largest rate max_k |F_k − F_{k−1}|/h
/// \[N/s\]. The plant's clipping makes a violation impossible; the check is the headline's
/// assertion that no run exceeded them.
///
/// # Errors
/// [`MpcError::ThrustLimit`] at the first step that exceeds a limit.
fn check_thrust_limits(thrust: &[f64], (bound, change): (f64, f64), h: f64) -> Result<f64> {
    let mut prev = 0.0;
    let mut peak = 0.0f64;
    for (k, &f) in thrust.iter().enumerate() {
        let d = (f - prev).abs();
        if !(f.abs() <= bound && d <= change * (1.0 + 1e-9)) {
            return Err(MpcError::ThrustLimit {
                step: k,
                thrust: f,
                change: d,
                bound,
                max_change: change,
            }
            .into());
        }
        peak = peak.max(d);
        prev = f;
    }
    Ok(peak / h)
}

/// The per-step records of a run (the x components in the spatial model).
struct Recorder {
    t: Vec<f64>,
    moment: Vec<f64>,
    control: Vec<f64>,
    tip: Vec<f64>,
    moment_x: Vec<f64>,
    control_x: Vec<f64>,
    spatial: bool,
}

impl Recorder {
    fn with_capacity(n: usize, spatial: bool) -> Self {
        let x = if spatial { n } else { 0 };
        Recorder {
            t: Vec::with_capacity(n),
            moment: Vec::with_capacity(n),
            control: Vec::with_capacity(n),
            tip: Vec::with_capacity(n),
            moment_x: Vec::with_capacity(x),
            control_x: Vec::with_capacity(x),
            spatial,
        }
    }

    fn push<const DIM: usize>(&mut self, plant: &Plant<f64, DIM>) {
        self.t.push(plant.time());
        self.moment.push(plant.moment());
        self.control.push(plant.control());
        self.tip.push(plant.tip());
        if self.spatial {
            self.moment_x.push(plant.moment_vector()[0]);
            self.control_x.push(plant.control_x());
        }
    }
}

/// Largest real-time factor reported (a controller that takes no measurable time).
const MAX_REAL_TIME_FACTOR: f64 = 1e12;

/// The mean of a decision's count over `later` (the decisions after the first): Σ c_k / len
/// (None without such decisions or when a decision has no count).
fn per_decision(later: &[Decision], count: impl Fn(&Decision) -> Option<usize>) -> Option<f64> {
    let total: Option<usize> = later.iter().map(count).sum();
    total
        .filter(|_| !later.is_empty())
        .map(|t| t as f64 / later.len() as f64)
}

fn summarise(
    controller: String,
    rec: &Recorder,
    decisions: &[Decision],
    h: f64,
    loop_seconds: f64,
) -> Summary {
    let max_abs = |v: &[f64]| v.iter().fold(0.0f64, |a, x| a.max(x.abs()));
    let simulated = h * (rec.t.len() - 1) as f64;
    let later = decisions.get(1..).unwrap_or(&[]);
    let replan: f64 = later.iter().map(|d| d.seconds).sum();
    let count = later.len().max(1) as f64;
    let rtf = |s: f64| (simulated / s).min(MAX_REAL_TIME_FACTOR);
    let (c_sum, max_abs_moment, max_abs_control, effort) = if rec.spatial {
        let norms = |a: &[f64], b: &[f64]| -> Vec<f64> {
            a.iter().zip(b).map(|(x, z)| x.hypot(*z)).collect()
        };
        let sq = |a: &[f64], b: &[f64]| a.iter().zip(b).map(|(x, z)| x * x + z * z).sum::<f64>();
        (
            sq(&rec.moment_x, &rec.moment),
            max_abs(&norms(&rec.moment_x, &rec.moment)),
            max_abs(&norms(&rec.control_x, &rec.control)),
            h * sq(&rec.control_x, &rec.control),
        )
    } else {
        (
            rec.moment.iter().map(|m| m * m).sum(),
            max_abs(&rec.moment),
            max_abs(&rec.control),
            h * rec.control.iter().map(|u| u * u).sum::<f64>(),
        )
    };
    Summary {
        controller,
        c_sum,
        max_abs_moment,
        max_abs_control,
        effort,
        simulated_seconds: simulated,
        decisions: decisions.len(),
        initial_decision_seconds: decisions.first().map_or(0.0, |d| d.seconds),
        mean_replan_seconds: replan / count,
        worst_replan_seconds: later.iter().fold(0.0, |a, d| a.max(d.seconds)),
        mean_iterations: per_decision(later, |d| d.iterations),
        mean_rollouts: per_decision(later, |d| d.rollouts),
        real_time_factor: rtf(replan),
        loop_real_time_factor: rtf(loop_seconds),
        thrust_rate_peak: None,
    }
}
