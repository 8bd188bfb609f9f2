//! The receding-horizon controller: real-time iterations of a Gauss-Newton solver (condensed or
//! Riccati) from the observed state, warm-started from the previous plan.

use super::forecast::NoisyForecast;
use super::observer::{Observer, ObserverOptions, SensorSet};
use super::planning::{map_observation, objective_scale, planning_scene, StateMap};
use super::thrust::{Actuator, ThrustPlan};
use super::{interval_steps, Controller, Force2, ModelObservation, Observation};
use crate::adjoint::{
    BendingObjective, ControlProblem, GaussNewton, History, HotSpotObjective, MomentStage,
    Objective, PerStepControl, PiecewiseControl, Stage,
};
use crate::base::Scalar;
use crate::error::{MpcError, Requirement, Result, ValueError};
use crate::fatigue::{MomentMeasure, WellheadDamage};
use crate::hotspots::HotSpotSpec;
use crate::model::Chain;
use crate::ocp::{self, OcpOptions, OcpResult};
use crate::optimize::{minimize, Bounds, Method, OptimOptions};
use crate::scene::{Control, ControlKind, Forecast, MomentAbout, ObjectiveKind, Observe, Scene};
use crate::steppers::rattle::State;

mod plan_models;
mod thrust_plan;

use plan_models::{observer_model, zero_control};
pub use thrust_plan::PlannedThrust;
use thrust_plan::ThrustState;

/// How far a plan looks ahead.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Horizon {
    /// A fixed horizon (s), a whole number of control intervals.
    Seconds(f64),
    /// To the end of the run t_N (the horizon shrinks by one interval per decision): with a
    /// perfect model this reproduces the open-loop optimum (principle of optimality; to the
    /// solver's tolerance, since each re-plan starts before the control's half-kick and is
    /// exactly the tail of the run, [`crate::mpc`] "The start of a horizon").
    ToEnd,
}

/// The optimal-control solver of each re-plan.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum MpcSolver {
    /// [`MpcSolver::Condensed`] for plans of at most 4(2n + 1) pieces (n pendulums), else
    /// [`MpcSolver::Riccati`] ([`MpcSolver::resolve`]): the condensed cost grows with steps ×
    /// pieces, the Riccati one with steps alone. Measured on `mpc_riser` (n = 10, pieces of
    /// 10 steps; `chainbeam mpc examples/scenes/mpc_riser.toml --horizon H --solver S
    /// --summary s.json`, mean re-plan over 60 s): condensed / Riccati 31.7 / 38.5 ms with 80
    /// pieces (H = 8 s), 53.8 / 51.1 ms with 100 (H = 10 s) — the crossover between the two,
    /// near 4(2n + 1) = 84.
    #[default]
    Auto,
    /// Full condensing ([`ocp::Condensed`]): sensitivities of the bending moments to the
    /// horizon's pieces by forward dual numbers, a dense box QP. The cheaper choice for the
    /// horizons of a few seconds of receding-horizon control (measured on `mpc_riser`, 3 s:
    /// module docs of [`crate::mpc`]).
    Condensed,
    /// The Riccati solver ([`ocp::Solver`]): stage Jacobians and Riccati passes, linear in the
    /// horizon whatever the number of pieces — the choice for long horizons.
    Riccati,
}

impl MpcSolver {
    /// The solver for a plan of `pieces` pieces of a chain of `n` pendulums
    /// ([`MpcSolver::Auto`]'s rule; the others are themselves).
    pub fn resolve(self, pieces: usize, n: usize) -> MpcSolver {
        match self {
            MpcSolver::Auto if pieces <= 4 * (2 * n + 1) => MpcSolver::Condensed,
            MpcSolver::Auto => MpcSolver::Riccati,
            s => s,
        }
    }
}

/// Settings of [`Mpc`].
#[derive(Clone, Debug, PartialEq)]
pub struct MpcOptions {
    /// The horizon. Default 3 s. Measured on `mpc_riser` (its current's steady drag bends the
    /// riser slowly, through the drag's long time constant; the `mpc_horizon` figure of
    /// `paper_figures`): closed-loop c_sum 35592 with 2 s, 9307 with 3 s, 7592 with 4 s, 7466
    /// with 5 s, at mean re-plan times of 2.5, 5.2, 8.4 and 11.0 ms with the condensed solver
    /// (2-core machine); 2 s is myopic there (below the best constant force only by 2.6×,
    /// 3 s by 10×), beyond 3 s the gain is small.
    pub horizon: Horizon,
    /// Gauss-Newton iterations per re-plan (the real-time iteration budget). Default 1: from
    /// the shifted plan one iteration is as good as two on `mpc_riser` at half the cost (its
    /// first 10 s, `chainbeam mpc` with `steps = 1000` and `--iterations 1|2`: c_sum 7683 and
    /// 7687 with the condensed solver, 7707 and 7674 with the Riccati solver; mean re-plan
    /// 5.1 against 8.4 ms and 9.1 against 16.7 ms).
    pub iterations: usize,
    /// Iterations of the first plan (cold, at t = 0 from the beam at rest). Default 50.
    pub first_iterations: usize,
    /// Start each re-plan from the previous plan shifted by one interval (tail padded with its
    /// last value); `false` starts from θ = 0. Default `true`.
    pub warm_start: bool,
    /// The solver of each re-plan. Default [`MpcSolver::Auto`].
    pub solver: MpcSolver,
    /// Effort weight ρ of ρ h Σ u_k² ([`BendingObjective::effort`]). Default 0.01.
    pub effort: f64,
    /// The objective each plan minimises (with the effort penalty): the scene kinds of
    /// [`BendingObjective`], any with a Gauss-Newton form. Default [`ObjectiveKind::Sum`]
    /// (c_sum); [`ObjectiveKind::Power`] plans on Σ|M₀(t_k)|^p.
    pub objective: ObjectiveKind,
    /// The solver's options: the bounds on u (default |u| ≤ 5 N), the rate penalty and the
    /// tolerances; `max_iters` is replaced by the budgets above.
    pub ocp: OcpOptions,
    /// Pendulums n_p of a reduced planning model: the model scene's `[pipe]` or `[stackup]`
    /// rebuilt as a chain of n_p pendulums ([`super::planning`]; through the vessel's thrust with
    /// the same vessel), onto which each observed state is mapped; the plant keeps its n. `None`
    /// (default): plan on the model scene as it is.
    pub plan_pendulums: Option<usize>,
    /// The planning model's step h_p \[s\] (the control interval must be a multiple of it).
    /// `None` (default): the model scene's step. With either `plan_*` option set, the effort
    /// weight and the rate penalty are rescaled so that the plan minimises the plant's
    /// objective in the model's units ([`super::planning`], "The objective").
    pub plan_step: Option<f64>,
    /// What the plan knows of the sea ahead. Default [`Forecast::Perfect`].
    pub forecast: Forecast,
    /// Iterations of the bounded L-BFGS of a re-plan through the vessel's thrust (a scene whose
    /// control is the thrust: [`crate::mpc`], "MPC through the vessel's thrust"; each costs
    /// about one simulation and one adjoint sweep of the horizon, more when its line search
    /// backtracks). Default 5; the first plan takes [`MpcOptions::first_iterations`].
    pub thrust_iterations: usize,
    /// The noisy forecast's error growth e, σ(τ) = min(e τ / T_p, 1/√2) ([`Forecast::Noisy`];
    /// [`super::forecast`]). Default [`crate::scene::MpcSettings::DEFAULT_FORECAST_ERROR`].
    pub forecast_error: f64,
    /// The seed of the noisy forecast's errors; `None` (default): the model's sea's seed.
    pub forecast_seed: Option<u64>,
    /// What the plan starts from: the plant's state, or the estimate of a Kalman filter from a
    /// named set of sensors ([`super::observer`]). Default [`Observe::State`].
    pub observe: Observe,
    /// The filter's settings with [`Observe::Sensors`] (the sensors' noise, the process noise,
    /// the seed).
    pub observer: ObserverOptions,
    /// The hot spot whose moment the plan acts on (`[mpc] hotspot`, [`crate::mpc`] "The moment
    /// a controller acts on"): each plan minimises h Σ_k |M(t_k)|^m + ρ h Σ_k u_k²
    /// ([`HotSpotObjective`]), M the moment at the hot spot's elevation and m its S-N curve's
    /// first slope, instead of [`MpcOptions::objective`] on the base moment. Through the
    /// vessel's thrust and in the planar model only ([`MpcError::HotSpotNeedsThrust`],
    /// [`MpcError::HotSpotSpatial`]). Default `None`: the base moment.
    pub hotspot: Option<HotSpotSpec>,
    /// What the hot spot's moment is measured from in each plan (`[mpc] moment_about`): zero
    /// (default), or the plan's own mean over its horizon ([`HotSpotObjective`], "About the
    /// plan's mean"). [`MomentAbout::Mean`] needs [`MpcOptions::hotspot`]
    /// ([`MpcError::MomentAboutNeedsHotSpot`]).
    pub moment_about: MomentAbout,
}

impl Default for MpcOptions {
    fn default() -> Self {
        MpcOptions {
            horizon: Horizon::Seconds(3.0),
            iterations: 1,
            first_iterations: 50,
            warm_start: true,
            solver: MpcSolver::default(),
            effort: 0.01,
            objective: ObjectiveKind::Sum,
            ocp: OcpOptions::default().with_bound(5.0),
            plan_pendulums: None,
            plan_step: None,
            forecast: Forecast::Perfect,
            thrust_iterations: 5,
            forecast_error: crate::scene::MpcSettings::DEFAULT_FORECAST_ERROR,
            forecast_seed: None,
            observe: Observe::State,
            observer: ObserverOptions::default(),
            hotspot: None,
            moment_about: MomentAbout::Zero,
        }
    }
}

/// A receding-horizon controller on a model scene (module docs of [`crate::mpc`]), in the planar
/// (`DIM = 2`, [`Mpc::new`]) or the spatial model (`DIM = 3`, [`Mpc::spatial`], planning a
/// 2-axis force (u_x, u_z) per interval on the vector moment:
/// θ = (θ_x; θ_z), min Σ |M₀|² + ρ h Σ |u|², each component within the box).
#[derive(Clone, Debug)]
pub struct Mpc<const DIM: usize = 2> {
    model: Scene,
    options: MpcOptions,
    interval: f64,
    /// Model steps per control interval.
    model_steps: usize,
    /// Pieces of a fixed horizon.
    pieces: Option<usize>,
    /// The problem of the last horizon length (cloned and started from each observation).
    template: Option<(
        usize,
        ControlProblem<PiecewiseControl, BendingObjective, DIM>,
    )>,
    /// The condensed solver of the last horizon length, kept between re-plans.
    condensed: Option<(usize, ocp::Condensed<DIM>)>,
    plan: Vec<f64>,
    warm: Vec<f64>,
    last: Option<OcpResult>,
    decisions: usize,
    /// The map of the plant's state onto a reduced planning model, and the mapped state.
    planning: Option<(StateMap<DIM>, State<f64, DIM>)>,
    /// The model's chain with its loads realised over the whole run and one horizon beyond
    /// (built at the first decision, [`Mpc::record_chain`]).
    record: Option<Chain<f64, DIM>>,
    /// Whether only the iteration budget stops a re-plan (`rel_grad_tol` = 0), set once the
    /// solver's relative test stopped a plan at a capped projected gradient
    /// ([`capped_convergence`]).
    budget_only: bool,
    /// The plan through the vessel's thrust (a thrust scene), `None` otherwise.
    thrust: Option<ThrustState>,
    /// The noisy forecast ([`Forecast::Noisy`]), `None` otherwise.
    noisy: Option<NoisyForecast>,
    /// The Kalman filter of [`Observe::Sensors`] (built at the first decision, which knows the
    /// run's length).
    observer: Option<Observer>,
    /// The objective at [`MpcOptions::hotspot`] on the plan's model, `None` without one.
    hotspot: Option<HotSpotObjective>,
    /// The scene the filter of [`Observe::Sensors`] runs on when the plan's model is not the
    /// plant's (a reduced or coarser plan: [`observer_model`]); `None`: the plan's model.
    observer_model: Option<Scene>,
}

/// What a plan through the vessel's thrust minimises: the base-moment objective of
/// [`MpcOptions::objective`] (every value and derivative [`BendingObjective`]'s, bit for bit) or
/// the hot spot's ([`MpcOptions::hotspot`]).
#[derive(Clone, Debug, PartialEq)]
pub(crate) enum PlanObjective {
    /// On the base moment.
    Base(BendingObjective),
    /// On a hot spot's moment.
    HotSpot(HotSpotObjective),
}

impl Objective for PlanObjective {
    fn stage<D: Scalar>(&self, s: Stage<'_, D>) -> D {
        match self {
            PlanObjective::Base(o) => o.stage(s),
            PlanObjective::HotSpot(o) => o.stage(s),
        }
    }
    fn uses_positions(&self) -> bool {
        match self {
            PlanObjective::Base(o) => o.uses_positions(),
            PlanObjective::HotSpot(o) => o.uses_positions(),
        }
    }
    fn gauss_newton<D: Scalar>(&self, s: MomentStage<D>) -> Option<GaussNewton<D>> {
        match self {
            PlanObjective::Base(o) => o.gauss_newton(s),
            PlanObjective::HotSpot(o) => o.gauss_newton(s),
        }
    }
    fn has_history(&self) -> bool {
        match self {
            PlanObjective::Base(o) => o.has_history(),
            PlanObjective::HotSpot(o) => o.has_history(),
        }
    }
    fn history<D: Scalar>(&self, h: History<'_, D>) -> Result<D> {
        match self {
            PlanObjective::Base(o) => o.history(h),
            PlanObjective::HotSpot(o) => o.history(h),
        }
    }
    fn history_signal<D: Scalar>(&self, s: Stage<'_, D>) -> Option<D> {
        match self {
            PlanObjective::Base(o) => o.history_signal(s),
            PlanObjective::HotSpot(o) => o.history_signal(s),
        }
    }
    fn power_proxy(&self) -> Option<f64> {
        match self {
            PlanObjective::Base(o) => o.power_proxy(),
            PlanObjective::HotSpot(o) => o.power_proxy(),
        }
    }
}

impl Mpc {
    /// A controller that plans on `model` (its beam, loads as the forecast, step, control node;
    /// its `[time]` length and `[control]` values are not used) with decisions every `interval`
    /// seconds, in the planar model.
    ///
    /// # Errors
    /// As [`Mpc::spatial`].
    pub fn new(model: &Scene, interval: f64, options: MpcOptions) -> Result<Self> {
        Self::build(model, interval, options)
    }
}

impl Mpc<3> {
    /// The controller of [`Mpc::new`] in the spatial model: a 2-axis force (u_x, u_z) per
    /// interval, planned on the vector moment (the scene's loads and current may have x
    /// components; [`crate::ocp`] "The spatial model").
    ///
    /// # Errors
    /// As [`Mpc::build`].
    pub fn spatial(model: &Scene, interval: f64, options: MpcOptions) -> Result<Self> {
        Self::build(model, interval, options)
    }
}

/// The plan's model and the plant have the same number of pendulums (a plan's state is the
/// plant's, [`MpcError::ModelSize`] otherwise).
fn check_model_size(model: usize, plant: usize) -> Result<()> {
    if model != plant {
        return Err(MpcError::ModelSize { model, plant }.into());
    }
    Ok(())
}

/// The horizon's number of control intervals: `None` to the end of the run, else
/// s / interval, refused unless a positive whole number.
fn horizon_pieces(horizon: Horizon, interval: f64) -> Result<Option<usize>> {
    Ok(match horizon {
        Horizon::ToEnd => None,
        Horizon::Seconds(s) => {
            let p = (s / interval).round();
            if !(s.is_finite() && p >= 1.0) || (p * interval - s).abs() > 1e-9 * s {
                return Err(MpcError::HorizonNotWhole {
                    horizon: s,
                    interval,
                }
                .into());
            }
            Some(p as usize)
        }
    })
}

/// The options' iteration counts (each ≥ 1), effort weight (finite, ≥ 0) and objective.
fn check_counts_and_effort(options: &MpcOptions) -> Result<()> {
    for (name, v) in [
        ("iterations", options.iterations),
        ("first_iterations", options.first_iterations),
        ("thrust_iterations", options.thrust_iterations),
    ] {
        ValueError::check_count(name, v).map_err(MpcError::from)?;
    }
    Requirement::FiniteNonNegative
        .check("effort", options.effort)
        .map_err(MpcError::from)?;
    options.objective.check()?;
    Ok(())
}

impl<const DIM: usize> Mpc<DIM> {
    /// The controller of [`Mpc::new`] in the model `DIM`.
    ///
    /// # Errors
    /// [`MpcError`]: the `interval` not a multiple of the model's step, the `horizon` not a
    /// positive whole number of intervals, zero `iterations` or `first_iterations`, an `effort`
    /// not finite and ≥ 0; [`OcpError`](crate::error::OcpError) naming the solver option at
    /// fault; [`Error::Scene`](crate::Error::Scene) naming `objective.exponent` for a power objective's invalid
    /// exponent; [`MpcError::ThrustStep`] for a reduced plan through the vessel's thrust whose
    /// `plan_step` is not a whole multiple of the model's step; the model's errors.
    pub fn build(model: &Scene, interval: f64, mut options: MpcOptions) -> Result<Self> {
        // The hot spot's objective carries h in both its terms: the effort weight is the same
        // at any planning step (not rescaled as the base moment's is, below).
        let hotspot_effort = options.effort;
        let (plan_model, planning) = match Self::coarse_thrust_model(model, &mut options)? {
            Some(coarse) => (Some(coarse), None),
            None => Self::planning_model(model, &mut options)?,
        };
        let plant = model;
        let model = plan_model.as_ref().unwrap_or(model);
        let model_steps = interval_steps(interval, model.time.step)?;
        options.ocp.validate()?;
        let pieces = horizon_pieces(options.horizon, interval)?;
        check_counts_and_effort(&options)?;
        let mut model = model.clone();
        if options.forecast == Forecast::None {
            if model.loads.waves.is_none() {
                return Err(MpcError::ForecastWithoutSea.into());
            }
            model.loads.waves = None;
        }
        let noisy = match options.forecast {
            Forecast::Noisy => Some(NoisyForecast::new(
                &model,
                options.forecast_error,
                options.forecast_seed,
            )?),
            _ => None,
        };
        let thrust = match model.thrust() {
            Some(_) if DIM == 3 => return Err(MpcError::ThrustSpatial.into()),
            Some(t) => Some(ThrustState {
                actuator: Actuator {
                    bound: t.bound,
                    change: t.rate_bound * model.time.step,
                },
                template: None,
                last: None,
                planned: None,
            }),
            None => None,
        };
        let hotspot = Self::hot_spot_of(&model, &options, thrust.is_some(), hotspot_effort)?;
        if options.observe == Observe::Sensors {
            // The sensors read the vessel under thrust (refused with the key named otherwise).
            if DIM == 3 || thrust.is_none() {
                return Err(MpcError::ObserveNeedsThrust.into());
            }
            SensorSet::of(&model)?;
        }
        if thrust.is_some() && planning.is_some() {
            thrust_plan::plan_step_ratio(model.time.step, plant.time.step)?;
        }
        let observer_model = (options.observe == Observe::Sensors && plan_model.is_some())
            .then(|| observer_model(plant, options.forecast));
        zero_control(&mut model);
        Ok(Mpc {
            model,
            options,
            interval,
            model_steps,
            pieces,
            template: None,
            condensed: None,
            plan: Vec::new(),
            warm: Vec::new(),
            last: None,
            decisions: 0,
            planning,
            record: None,
            budget_only: false,
            thrust,
            noisy,
            observer: None,
            observer_model,
            hotspot,
        })
    }

    /// The solver's result of the last decision.
    pub fn last_result(&self) -> Option<&OcpResult> {
        self.last.as_ref()
    }

    /// The current plan θ (one force per interval of the last horizon; in the spatial model
    /// θ = (θ_x; θ_z), the x components first).
    pub fn plan(&self) -> &[f64] {
        &self.plan
    }

    /// Control axes of a plan: 1 (along z, planar) or 2 ((u_x, u_z), spatial).
    fn axes() -> usize {
        if DIM == 3 {
            2
        } else {
            1
        }
    }

    /// The problem of a horizon of `pieces` intervals from `obs`.
    fn problem(
        &mut self,
        pieces: usize,
        obs: &ModelObservation<'_, DIM>,
    ) -> Result<ControlProblem<PiecewiseControl, BendingObjective, DIM>> {
        if self.template.as_ref().map(|t| t.0) != Some(pieces) {
            let mut scene = self.model.clone();
            scene.time.steps = pieces * self.model_steps;
            hold_series_past_end(&mut scene);
            let map = PiecewiseControl {
                steps: scene.time.steps,
                pieces,
            };
            let objective = BendingObjective {
                kind: self.options.objective,
                effort: self.options.effort,
            };
            // A noisy forecast's window reaches a step or two past the horizon.
            let margin = usize::from(self.noisy.is_some());
            let record = self.record_chain(obs, pieces + margin)?;
            let two_axis = DIM == 3;
            let problem = ControlProblem::builder(&scene)
                .map(map)
                .objective(objective)
                .two_axis(two_axis)
                .build_in()?
                .with_chain(record);
            self.template = Some((pieces, problem));
        }
        if let Some(noisy) = self.noisy.as_mut() {
            let record = self.record.as_ref().expect("built with the template");
            let end = obs.t + pieces as f64 * self.interval;
            let chain = noisy.forecast_chain(record, obs.t, (obs.t, end))?;
            let t = self.template.take().expect("set above");
            self.template = Some((t.0, t.1.with_chain(chain)));
            // The kept condensed solver holds the last forecast's model: rebuilt on this one.
            self.condensed = None;
        }
        let template = &self.template.as_ref().expect("set above").1;
        if let Some((map, start)) = self.planning.as_mut() {
            return if map_observation(map, obs, start)? {
                template.clone().starting_before_kick(start.clone(), obs.t)
            } else {
                template.clone().starting_from(start.clone(), obs.t)
            };
        }
        check_model_size(template.chain().n(), obs.state.q.len())?;
        // The force decided now completes the half-kick of the step into t_k: plan from the
        // state before it (exact: the plan's θ₀ acts on both sides of t_k as in the plant).
        match obs.state_before_kick {
            Some(hat) => template.clone().starting_before_kick(hat.clone(), obs.t),
            None => template.clone().starting_from(obs.state.clone(), obs.t),
        }
    }

    /// The model's chain (with its start) and its loads realised from t = 0 to the end of the
    /// run plus a horizon of `pieces` intervals (built once): a scene's wave kinematics are
    /// tabulated over its record only (`time.steps`, `WaveField`) and summed component by
    /// component beyond it, so a chain built from the horizon's scene alone would sum thousands
    /// of components per pendulum and step at every re-plan after the first horizon (measured
    /// on riser_300m.toml: 97 % of a re-plan's time in that sum).
    fn record_chain(
        &mut self,
        obs: &ModelObservation<'_, DIM>,
        pieces: usize,
    ) -> Result<Chain<f64, DIM>> {
        if let Some(chain) = &self.record {
            return Ok(chain.clone());
        }
        let mut scene = self.model.clone();
        let end = obs.steps as f64 * obs.h + pieces as f64 * self.interval;
        scene.time.steps = (end / scene.time.step).ceil() as usize + 1;
        hold_series_past_end(&mut scene);
        let chain = super::plant::plant_chain::<DIM>(&scene)?;
        self.record = Some(chain.clone());
        Ok(chain)
    }

    /// The condensed solver for a horizon of `pieces`, moved to `problem`'s start (built on the
    /// first call and whenever the horizon's length changes).
    fn condensed(
        &mut self,
        pieces: usize,
        problem: &ControlProblem<PiecewiseControl, BendingObjective, DIM>,
        opts: &OcpOptions,
    ) -> Result<&mut ocp::Condensed<DIM>> {
        match &mut self.condensed {
            Some((p, solver)) if *p == pieces => {
                solver.restart(problem)?;
                solver.set_max_iters(opts.max_iters);
            }
            slot => *slot = Some((pieces, ocp::Condensed::new(problem, opts)?)),
        }
        Ok(&mut self.condensed.as_mut().expect("set above").1)
    }

    /// The pieces of the horizon at `obs`.
    fn horizon_pieces(&self, obs: &ModelObservation<'_, DIM>) -> Result<usize> {
        if (obs.interval - self.interval).abs() > 1e-12 * self.interval {
            return Err(MpcError::IntervalMismatch {
                controller: self.interval,
                run: obs.interval,
            }
            .into());
        }
        Ok(match self.pieces {
            Some(p) => p,
            None => {
                let remaining = (obs.steps - obs.k) as f64 * obs.h;
                ((remaining / self.interval).round() as usize).max(1)
            }
        })
    }

    /// The start θ₀ of a plan of `pieces` intervals: the previous plan shifted by one
    /// interval, the tail padded with its last value (zeros without a plan or warm start);
    /// each axis of a 2-axis plan (θ_x; θ_z) alike.
    fn warm_start(&mut self, pieces: usize) {
        self.warm.clear();
        let axes = Self::axes();
        if self.options.warm_start && !self.plan.is_empty() {
            let m = self.plan.len() / axes;
            for axis in self.plan.chunks(m) {
                let last = m - 1;
                self.warm
                    .extend((0..pieces).map(|i| axis[(i + 1).min(last)]));
            }
        } else {
            self.warm.resize(pieces * axes, 0.0);
        }
    }

    /// A re-plan from `obs` (the real-time iteration of the module docs): the new plan θ.
    fn replan(&mut self, obs: &ModelObservation<'_, DIM>) -> Result<()> {
        let pieces = self.horizon_pieces(obs)?;
        let problem = self.problem(pieces, obs)?;
        self.warm_start(pieces);
        let mut opts = self.options.ocp.clone();
        opts.max_iters = if self.decisions == 0 {
            self.options.first_iterations
        } else {
            self.options.iterations
        };
        // Real-time iteration: the step is all a decision needs (OcpOptions::final_gradient).
        opts.final_gradient = false;
        let n = obs.state.q.len();
        if self.budget_only {
            opts.rel_grad_tol = 0.0;
        }
        let mut r = self.solve(pieces, &problem, &opts, n)?;
        if capped_convergence(&r, &opts) {
            // From now on only the iteration budget stops a re-plan (`capped_convergence`); the
            // kept condensed solver holds its options, so it is rebuilt with these.
            self.budget_only = true;
            opts.rel_grad_tol = 0.0;
            self.condensed = None;
            r = self.solve(pieces, &problem, &opts, n)?;
        }
        self.plan.clone_from(&r.theta);
        self.last = Some(r);
        self.decisions += 1;
        Ok(())
    }
}

impl<const DIM: usize> Mpc<DIM> {
    /// One solve of a re-plan's problem from the warm start, by the solver
    /// [`MpcOptions::solver`] picks for it (the condensed one kept between re-plans).
    fn solve(
        &mut self,
        pieces: usize,
        problem: &ControlProblem<PiecewiseControl, BendingObjective, DIM>,
        opts: &OcpOptions,
        n: usize,
    ) -> Result<OcpResult> {
        match self.options.solver.resolve(pieces * Self::axes(), n) {
            MpcSolver::Condensed | MpcSolver::Auto => {
                let warm = std::mem::take(&mut self.warm);
                let r = self.condensed(pieces, problem, opts)?.solve(&warm);
                self.warm = warm;
                r
            }
            MpcSolver::Riccati => ocp::solve(problem, &self.warm, opts),
        }
    }
}

/// The share of the box's width u_max − u_min above which a projected-gradient step
/// ‖θ − Π(θ − ∇J)‖ means that θ is not a solution ([`capped_convergence`]).
const CAPPED_STEP: f64 = 1e-6;

/// Whether the solver's relative stopping test, ‖θ − Π(θ − ∇J)‖ ≤ `rel_grad_tol`·‖∇J(θ₀)‖
/// ([`OcpOptions::rel_grad_tol`]), stopped a re-plan at its warm start (no iteration) while the
/// projected-gradient step still moves θ by more than [`CAPPED_STEP`] of the box's width. The
/// projection caps that step at the distance to the box, √P·(u_max − u_min) for P pieces, while
/// ‖∇J(θ₀)‖ is not capped: on an objective large in its units (Σ|M₀|³ of the 300 m riser in
/// the plant's own units, J ≈ 10¹⁹, ‖∇J‖ ≈ 3·10¹⁴ N·m³ per N) every warm start passes the
/// test, and the controller replays its previous plan (from rest: u = 0 throughout) reporting
/// convergence. Measured on examples/scenes/riser_300m.toml planned at n_p = n = 80 with
/// |u| ≤ 200 kN: every decision "converged" after 0 iterations with ‖θ − Π(θ − ∇J)‖ =
/// √20 · 2·10⁵ N, u = 0 for 120 s (README, "Headline"). A warm start that is a solution has
/// that step at zero on its active bounds and at most `rel_grad_tol`·‖∇J‖ elsewhere (should that
/// exceed the share, the guard costs the budget's iterations from a solution, no more). Once it
/// fires, the controller's re-plans stop on their budget alone (`rel_grad_tol` = 0).
fn capped_convergence(r: &OcpResult, opts: &OcpOptions) -> bool {
    let width = opts.upper - opts.lower;
    r.iterations == 0
        && r.converged
        && width.is_finite()
        && r.projected_gradient_norm > CAPPED_STEP * width
}

impl Controller for Mpc {
    fn name(&self) -> String {
        "mpc".into()
    }

    fn control(&mut self, obs: &Observation<'_>) -> Result<Force2> {
        let obs = obs.in_model::<2>()?;
        if self.options.observe == Observe::Sensors {
            return self.control_observed(&obs).map(Force2::z);
        }
        if self.thrust.is_some() {
            self.replan_thrust(&obs)?;
        } else {
            self.replan(&obs)?;
        }
        Ok(Force2::z(self.plan[0]))
    }

    fn last_iterations(&self) -> Option<usize> {
        match &self.thrust {
            Some(t) => t.last.as_ref().map(|r| r.iterations),
            None => self.last.as_ref().map(|r| r.iterations),
        }
    }

    fn last_rollouts(&self) -> Option<usize> {
        match &self.thrust {
            Some(t) => t.last.as_ref().map(|r| r.gradient_evals),
            None => self.last.as_ref().map(|r| r.rollouts),
        }
    }
}

impl Controller for Mpc<3> {
    fn name(&self) -> String {
        "mpc".into()
    }

    /// The first interval's (u_x, u_z) of the new plan θ = (θ_x; θ_z).
    fn control(&mut self, obs: &Observation<'_>) -> Result<Force2> {
        self.replan(&obs.in_model::<3>()?)?;
        let m = self.plan.len() / 2;
        Ok(Force2 {
            x: self.plan[0],
            z: self.plan[m],
        })
    }

    fn last_iterations(&self) -> Option<usize> {
        self.last.as_ref().map(|r| r.iterations)
    }

    fn last_rollouts(&self) -> Option<usize> {
        self.last.as_ref().map(|r| r.rollouts)
    }

    fn spatial(&self) -> bool {
        true
    }
}

/// What a plan sees of a load's time series past the run's end: its last value, held. The
/// plans of the last decisions look up to a horizon beyond t_N, where the plant never runs and
/// the series (which need only cover the run) has no rows; a [`crate::scene::LoadSeries`] holds
/// its last row outside its rows already, so a row (t_end, last F) appended at the planning
/// scene's end t_end = N h changes nothing inside the series and makes the hold explicit for
/// the scene's coverage rule (the planning scene is then valid, as the plant's is). The
/// alternative, a horizon cut at t_N, would change every plan of every scene near the end,
/// series or not; holding the last value changes no scene that ran before.
fn hold_series_past_end(scene: &mut Scene) {
    let t_end = scene.time.steps as f64 * scene.time.step;
    for load in &mut scene.loads.points {
        if let Some(series) = load.series.as_mut() {
            if let Some(&[t, fx, fz]) = series.samples.last() {
                if t < t_end {
                    series.samples.push([t_end, fx, fz]);
                }
            }
        }
    }
}
