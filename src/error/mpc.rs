//! Errors of the model-predictive controller and its closed loop ([`crate::mpc`]).

use super::requirement::ValueError;
use thiserror::Error;

/// An argument of [`crate::mpc`] a caller can correct. `Display` says what is wrong;
/// [`MpcError::argument`] names the argument, and the crate's [`Error::Mpc`](super::Error::Mpc)
/// puts both together (e.g. "invalid argument `horizon`: must be a positive whole number of
/// control intervals of 0.1 s, got 0.05 s"), so a command line can name its flag instead.
#[derive(Debug, Error, Clone, PartialEq)]
#[non_exhaustive]
pub enum MpcError {
    /// The control interval is not a positive whole multiple m h of the scene's step
    /// (to 10⁻⁹ relative; [`crate::mpc::interval_steps`]).
    #[error(
        "the control interval must be a positive multiple of the step h = {h} s, got {interval} s"
    )]
    IntervalNotMultiple {
        /// The interval given \[s\].
        interval: f64,
        /// The scene's step h \[s\].
        h: f64,
    },
    /// The run of N steps is not a whole number of control intervals of m steps
    /// ([`crate::mpc::run_closed_loop`]).
    #[error(
        "the run of N = {steps} steps is not a whole number of control intervals of \
         {interval_steps} steps"
    )]
    RunNotWhole {
        /// The run's N.
        steps: usize,
        /// The steps m of one interval.
        interval_steps: usize,
    },
    /// The closed loop's interval is not the one the controller plans with.
    #[error("the controller plans with intervals of {controller} s, the loop runs {run} s")]
    IntervalMismatch {
        /// The controller's interval \[s\].
        controller: f64,
        /// The loop's interval \[s\].
        run: f64,
    },
    /// The controller plans in one model (planar or spatial) and the loop observes the plant in
    /// the other (a planar [`crate::mpc::Mpc`] on a spatial scene: build it on a spatial model
    /// scene, and the loop runs the spatial plant).
    #[error("the controller plans in the {controller} model, the plant runs in the {plant} model")]
    ControllerModel {
        /// The controller's model ("planar" or "spatial").
        controller: &'static str,
        /// The plant's model ("planar" or "spatial").
        plant: &'static str,
    },
    /// A fixed horizon that is not a positive whole number of control intervals.
    #[error(
        "must be a positive whole number of control intervals of {interval} s, got {horizon} s"
    )]
    HorizonNotWhole {
        /// The horizon given \[s\].
        horizon: f64,
        /// The control interval \[s\].
        interval: f64,
    },
    /// The controller's model has another number of pendulums than the plant it observes.
    #[error("the model has {model} pendulums, the plant {plant}")]
    ModelSize {
        /// The model's n.
        model: usize,
        /// The plant's n.
        plant: usize,
    },
    /// The plant was advanced past its last step t_N ([`crate::mpc::Plant::advance`]).
    #[error("the plant is at its last step N = {steps}")]
    PastEnd {
        /// The plant's N.
        steps: usize,
    },
    /// A reduced planning model ([`crate::mpc::MpcOptions::plan_pendulums`]) of a scene with
    /// neither `[pipe]` nor `[stackup]`: the coarser chain is rebuilt from their description.
    #[error(
        "a reduced planning model needs a scene with a [pipe] or [stackup] table, from which the \
         coarser chain is built"
    )]
    PlanWithoutPipe,
    /// A planning model's number of pendulums outside 1..=n.
    #[error("must be between 1 and the plant's {n} pendulums, got {pendulums}")]
    PlanPendulums {
        /// The number asked for.
        pendulums: usize,
        /// The plant's n.
        n: usize,
    },
    /// A reduced planning model of a beam whose tip is locked by a constraint (fixed-fixed,
    /// pinned-pinned, a reaction-force tip), which the state map does not keep (a tip held by the
    /// vessel it keeps).
    #[error(
        "a reduced planning model needs a free tip, a tip spring or a tip held by the vessel \
         (support cantilever, riser or vessel)"
    )]
    PlanSupport,
    /// The Riccati solver asked for in the spatial model, where only the condensed one plans.
    #[error(
        "the Riccati solver is planar only; a spatial scene (loads, current or control along x) \
         plans with the condensed solver (solver condensed or auto)"
    )]
    RiccatiPlanar,
    /// MPC through the vessel's thrust in the spatial model: the thrust drives the vessel's
    /// surge along z, and its plan is written in the planar model.
    #[error(
        "MPC through the vessel's thrust plans in the planar model only (loads, current and \
         waves along z)"
    )]
    ThrustSpatial,
    /// A plan through the vessel's thrust on a model whose step (or `plan_step`) is not a whole
    /// multiple of the plant's.
    #[error("MPC through the vessel's thrust plans at the plant's step h = {plant} s or a whole multiple of it, the model's is {model} s")]
    ThrustStep {
        /// The model's step \[s\].
        model: f64,
        /// The plant's step \[s\].
        plant: f64,
    },
    /// `forecast = "none"` on a scene without `[loads.waves]`: there is no sea to leave out.
    #[error("forecast \"none\" leaves the waves out of the plan: the scene has no [loads.waves]")]
    ForecastWithoutSea,
    /// A noisy forecast's error growth (`forecast_error`) not finite and ≥ 0.
    #[error("forecast_error must be a finite number ≥ 0, got {value}")]
    ForecastError {
        /// The value given.
        value: f64,
    },
    /// A noisy forecast for plan times outside the model's record of the sea (the record covers
    /// the run and a horizon beyond it).
    #[error("the noisy forecast of the plan over t = {start} .. {end} s is outside the model's record of the sea")]
    ForecastWindow {
        /// The plan's first time \[s\].
        start: f64,
        /// The plan's last time \[s\].
        end: f64,
    },
    /// A closed loop's applied thrust beyond the vessel's limits at a step (the plant's clipping
    /// makes it impossible; the loop asserts it at every step).
    #[error("the applied thrust {thrust} N at step {step} (change {change} N) exceeds the vessel's limits (|F| ≤ {bound} N, change ≤ {max_change} N per step)")]
    ThrustLimit {
        /// The step k.
        step: usize,
        /// F_k \[N\].
        thrust: f64,
        /// |F_k − F_{k−1}| \[N\].
        change: f64,
        /// F_max \[N\].
        bound: f64,
        /// Ḟ_max h \[N\].
        max_change: f64,
    },
    /// `observe = "sensors"` on a scene whose control is not the vessel's thrust (or in the
    /// spatial model): the sensor set reads the vessel under thrust ([`crate::mpc::observer`]).
    #[error(
        "observe \"sensors\" reads the vessel's position and velocity, the flex joints and the \
         LMRP of a riser held by a vessel under thrust: the scene's control is not the vessel's \
         thrust (give [vessel] thrust keys) or it runs in the spatial model"
    )]
    ObserveNeedsThrust,
    /// `observe = "sensors"` on a scene that lacks one of the sensors' places.
    #[error(
        "observe \"sensors\" needs {missing} (the flex joints and the LMRP carry the sensors; \
         docs/mpc.md \"What the controller sees\")"
    )]
    ObserveSensors {
        /// What the scene lacks.
        missing: &'static str,
    },
    /// The steady-state Kalman filter of `observe = "sensors"` has no solution: its Riccati
    /// equation did not converge (the sensors do not see an unstable motion of the model).
    #[error(
        "observe \"sensors\": the Kalman filter's Riccati equation did not converge (the \
         sensors do not see a growing motion of the model)"
    )]
    ObserverNotConverged,
    /// `hotspot` names no `[[fatigue.hotspot]]` of the scene.
    #[error("hotspot `{name}` is not a [[fatigue.hotspot]] of the scene (its hot spots: {known})")]
    HotSpotUnknown {
        /// The name given.
        name: String,
        /// The scene's hot spots' names, comma-separated (empty: none).
        known: String,
    },
    /// `hotspot` in the spatial model: the moment at a hot spot is planned in the planar model
    /// only (the spatial joint torque has two components).
    #[error("hotspot: the controllers act on a hot spot's moment in the planar model only")]
    HotSpotSpatial,
    /// `hotspot` for MPC on a scene whose control is not the vessel's thrust: the structured
    /// solvers of a force control plan on the base moment's Gauss-Newton form, which the hot
    /// spot's moment has not.
    #[error(
        "hotspot: MPC plans on a hot spot's moment through the vessel's thrust only (a scene \
         with [vessel] thrust keys); a force control plans on the base moment"
    )]
    HotSpotNeedsThrust,
    /// The hot spot objective's exponent (its S-N slope) not finite and ≥ 2.
    #[error("hotspot: the exponent of Σ|M|^p h must be finite and ≥ 2, got {exponent}")]
    HotSpotExponent {
        /// The exponent.
        exponent: f64,
    },
    /// `moment_about = "mean"` without `hotspot`: the moment about its mean (MPC's plan's
    /// mean, the PD law's running mean) is a hot spot's moment only (the chain's base moment is
    /// measured from zero).
    #[error(
        "moment_about \"mean\": MPC and the PD law act on a moment's fluctuation about its mean \
         at a hot spot only; name one with hotspot (the chain's base moment is measured from zero)"
    )]
    MomentAboutNeedsHotSpot,
    /// A count (`iterations`, `first_iterations`) of zero, or a number (`effort`, `bound`)
    /// outside its range.
    #[error(transparent)]
    Value(#[from] ValueError),
}

impl MpcError {
    /// The argument at fault: `interval`, `horizon`, `model`, `steps`, `plan_pendulums`, or the
    /// name of a count or a number (`iterations`, `first_iterations`, `effort`, `bound`,
    /// `plan_step`).
    pub fn argument(&self) -> &'static str {
        match self {
            MpcError::IntervalNotMultiple { .. }
            | MpcError::RunNotWhole { .. }
            | MpcError::IntervalMismatch { .. } => "interval",
            MpcError::HorizonNotWhole { .. } => "horizon",
            MpcError::ModelSize { .. } | MpcError::ControllerModel { .. } => "model",
            MpcError::PlanWithoutPipe | MpcError::PlanPendulums { .. } | MpcError::PlanSupport => {
                "plan_pendulums"
            }
            MpcError::PastEnd { .. } => "steps",
            MpcError::Value(v) => v.argument(),
            MpcError::RiccatiPlanar => "solver",
            MpcError::ThrustSpatial | MpcError::ThrustStep { .. } => "model",
            MpcError::ForecastWithoutSea => "forecast",
            MpcError::ForecastError { .. } => "forecast_error",
            MpcError::ForecastWindow { .. } => "forecast",
            MpcError::ThrustLimit { .. } => "model",
            MpcError::ObserveNeedsThrust
            | MpcError::ObserveSensors { .. }
            | MpcError::ObserverNotConverged => "observe",
            MpcError::HotSpotUnknown { .. }
            | MpcError::HotSpotSpatial
            | MpcError::HotSpotNeedsThrust
            | MpcError::HotSpotExponent { .. } => "hotspot",
            MpcError::MomentAboutNeedsHotSpot => "moment_about",
        }
    }
}
