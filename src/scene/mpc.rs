//! The `[mpc]` table: the settings of the closed-loop controllers (`constant`, `pd`, `mpc`) of
//! `chainbeam fatigue` and `chainbeam mpc`, with the flags' names in snake case
//! (docs/scene-format.md "[mpc]"). Every key is optional; a value given by the caller (a flag on
//! the command line, an argument in Python) overrides the table, and a key given in neither
//! takes the default ([`MpcTable::resolve`], the one precedence every caller uses).

use serde::{Deserialize, Serialize};

use super::ranges::FORCE_RANGE;
use super::{ObjectiveKind, Scene, SceneError};
use crate::fatigue::WellheadDamage;

/// What MPC plans on (`mpc.objective`, the flag `--mpc-objective`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum MpcPlanObjective {
    /// `"power"`: Σ|M₀|^m with m the S-N curve's first slope (the fatigue proxy).
    Power,
    /// `"sum"`: Σ M₀² (the thesis's c_sum, eq. 3.3.4).
    Sum,
}

impl MpcPlanObjective {
    /// The name in the scene file and on the command line.
    pub fn name(self) -> &'static str {
        match self {
            MpcPlanObjective::Power => "power",
            MpcPlanObjective::Sum => "sum",
        }
    }
}

/// What the plan knows of the sea ahead (`[mpc] forecast`, [`crate::mpc`] "What the plan
/// knows"). The plant always runs the true sea.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Forecast {
    /// The model scene's sea as it is: with a perfect model, the plant's own future waves.
    #[default]
    Perfect,
    /// No future waves: the plan runs on a calm sea (the model scene without `[loads.waves]`,
    /// so without the waves' loads and the vessel's wave-frequency motion; the current, the
    /// point loads and the mean offset kept), from the observed state, which carries the
    /// motion the waves have caused up to now.
    None,
    /// The model scene's sea with errors that grow with lead time ([`crate::mpc`], "What the
    /// plan knows"): at each re-plan every wave component's complex amplitude aⱼ e^{iφⱼ} is
    /// forecast as aⱼ e^{iφⱼ} (1 + σ(τ) wⱼ), wⱼ = ξⱼ + i ηⱼ with ξⱼ, ηⱼ independent standard
    /// normal draws (to first order a relative amplitude error σ ξⱼ and a phase error σ ηⱼ
    /// rad), σ(τ) = min(`forecast_error` · τ / T_p, 1/√2) at lead time τ, drawn afresh per
    /// re-plan from the seed `forecast_seed`.
    Noisy,
}

impl Forecast {
    /// The name in the scene file and on the command line.
    pub fn name(self) -> &'static str {
        match self {
            Forecast::Perfect => "perfect",
            Forecast::None => "none",
            Forecast::Noisy => "noisy",
        }
    }

    /// The forecast of a name ([`Forecast::name`]); `None` for another name.
    pub fn from_name(name: &str) -> Option<Self> {
        match name {
            "perfect" => Some(Forecast::Perfect),
            "none" => Some(Forecast::None),
            "noisy" => Some(Forecast::Noisy),
            _ => None,
        }
    }
}

/// What the hot spot's moment is measured from in the objective MPC plans on (`[mpc]
/// moment_about`, [`crate::mpc`] "The moment a controller acts on"): zero, J = h Σ_k |M_k|^m,
/// or the plan's own mean, J = h Σ_k |M_k − M̄|^m with M̄ = (1/(N+1)) Σ_{k=0}^{N} M_k over the
/// plan's horizon ([`crate::adjoint::HotSpotObjective`]). S-N damage counts ranges only, which
/// the mean does not change.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum MomentAbout {
    /// `"zero"`: |M_k|^m, the moment about zero (every number as without the key).
    #[default]
    Zero,
    /// `"mean"`: |M_k − M̄|^m, the moment's fluctuation about the plan's own mean.
    Mean,
}

impl MomentAbout {
    /// The name in the scene file and on the command line.
    pub fn name(self) -> &'static str {
        match self {
            MomentAbout::Zero => "zero",
            MomentAbout::Mean => "mean",
        }
    }

    /// The setting of a name ([`MomentAbout::name`]); `None` for another name.
    pub fn from_name(name: &str) -> Option<Self> {
        match name {
            "zero" => Some(MomentAbout::Zero),
            "mean" => Some(MomentAbout::Mean),
            _ => None,
        }
    }
}

/// What MPC's plan starts from (`[mpc] observe`, [`crate::mpc`] "What the controller sees"):
/// the plant's whole state, or an estimate of it from a named set of sensors.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Observe {
    /// The plant's state as it is (every angle and momentum, exactly).
    #[default]
    State,
    /// The sensors of a drilling riser (the vessel's position and velocity, the top and bottom
    /// flex joints' angles, the LMRP's inclination), each with its measurement noise, through a
    /// Kalman filter on the plan's linearised model ([`crate::mpc::observer`]).
    Sensors,
}

impl Observe {
    /// The name in the scene file and on the command line.
    pub fn name(self) -> &'static str {
        match self {
            Observe::State => "state",
            Observe::Sensors => "sensors",
        }
    }

    /// The setting of a name ([`Observe::name`]); `None` for another name.
    pub fn from_name(name: &str) -> Option<Self> {
        match name {
            "state" => Some(Observe::State),
            "sensors" => Some(Observe::Sensors),
            _ => None,
        }
    }
}

/// The `[mpc]` table (module docs): `None` for a key not given.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct MpcTable {
    /// `interval` \[s\]: the control interval (> 0).
    pub interval: Option<f64>,
    /// `horizon` \[s\]: MPC's horizon (> 0).
    pub horizon: Option<f64>,
    /// `iterations`: Gauss-Newton iterations per re-plan (≥ 1).
    pub iterations: Option<usize>,
    /// `bound` \[N\]: the force bound |u| ≤ U (> 0).
    pub bound: Option<f64>,
    /// `effort`: the effort weight ρ (finite, ≥ 0).
    pub effort: Option<f64>,
    /// `plan_pendulums`: pendulums of MPC's reduced planning model (≥ 1).
    pub plan_pendulums: Option<usize>,
    /// `plan_step` \[s\]: the planning model's step (> 0).
    pub plan_step: Option<f64>,
    /// `pd_training` \[s\]: the PD law's training window (> 0).
    pub pd_training: Option<f64>,
    /// `objective`: what MPC plans on (`"power"` or `"sum"`).
    pub objective: Option<MpcPlanObjective>,
    /// `forecast`: what MPC's plan knows of the sea ahead (`"perfect"`, `"none"` or
    /// `"noisy"`).
    pub forecast: Option<Forecast>,
    /// `forecast_error`: the growth e of the noisy forecast's error, σ(τ) = e τ / T_p (finite,
    /// 0 ≤ e ≤ [`MpcSettings::MAX_FORECAST_ERROR`]).
    pub forecast_error: Option<f64>,
    /// `forecast_seed`: the seed of the noisy forecast's errors (default: the sea's seed).
    pub forecast_seed: Option<u64>,
    /// `observe`: what MPC's plan starts from (`"state"` or `"sensors"`).
    pub observe: Option<Observe>,
    /// `hotspot`: the `name` of the `[[fatigue.hotspot]]` whose moment every controller acts
    /// on (not given: the chain's base moment).
    pub hotspot: Option<String>,
    /// `moment_about`: what the hot spot's moment is measured from in MPC's plan (`"zero"` or
    /// `"mean"`; needs `hotspot`).
    pub moment_about: Option<MomentAbout>,
}

/// The table's keys, in the order of docs/scene-format.md (section `[mpc]`).
pub const MPC_KEYS: [&str; 15] = [
    "interval",
    "horizon",
    "iterations",
    "bound",
    "effort",
    "plan_pendulums",
    "plan_step",
    "pd_training",
    "objective",
    "forecast",
    "forecast_error",
    "forecast_seed",
    "observe",
    "hotspot",
    "moment_about",
];

/// The closed-loop settings of a run after the precedence of [`MpcTable::resolve`]: the keys
/// with a default hold a value; the others stay optional (`None`: off, or the command's own
/// choice: `chainbeam fatigue` plans MPC on the fatigue proxy, `chainbeam mpc` on the model's
/// `[objective]`).
#[derive(Clone, Debug, PartialEq)]
pub struct MpcSettings {
    /// The control interval \[s\] (default [`MpcSettings::DEFAULT_INTERVAL`]).
    pub interval: f64,
    /// MPC's horizon \[s\] (default [`MpcSettings::DEFAULT_HORIZON`]).
    pub horizon: f64,
    /// Gauss-Newton iterations per re-plan (default [`MpcSettings::DEFAULT_ITERATIONS`]).
    pub iterations: usize,
    /// The force bound |u| ≤ U \[N\] (default [`MpcSettings::DEFAULT_BOUND`]).
    pub bound: f64,
    /// The effort weight ρ of ρ·h·Σ u² (default [`MpcSettings::DEFAULT_EFFORT`]).
    pub effort: f64,
    /// Pendulums of MPC's reduced planning model (default off).
    pub plan_pendulums: Option<usize>,
    /// The planning model's step \[s\] (default: the model's `time.step`).
    pub plan_step: Option<f64>,
    /// The PD law's training window \[s\] (default: the whole record).
    pub pd_training: Option<f64>,
    /// What MPC plans on (default: the command's own, see the type's docs).
    pub objective: Option<MpcPlanObjective>,
    /// What MPC's plan knows of the sea ahead (default [`Forecast::Perfect`]).
    pub forecast: Forecast,
    /// The noisy forecast's error growth e (default [`MpcSettings::DEFAULT_FORECAST_ERROR`];
    /// read with [`Forecast::Noisy`] only).
    pub forecast_error: f64,
    /// The seed of the noisy forecast's errors (default: the sea's seed, `None` here).
    pub forecast_seed: Option<u64>,
    /// What MPC's plan starts from (default [`Observe::State`]).
    pub observe: Observe,
    /// The hot spot every controller acts on, by name (default: none, the chain's base
    /// moment; [`MpcSettings::hotspot_spec`]).
    pub hotspot: Option<String>,
    /// What the hot spot's moment is measured from in MPC's plan (default
    /// [`MomentAbout::Zero`]; [`MomentAbout::Mean`] needs [`MpcSettings::hotspot`]).
    pub moment_about: MomentAbout,
}

impl MpcSettings {
    /// `interval`'s default \[s\] (the flag `--interval`'s).
    pub const DEFAULT_INTERVAL: f64 = 0.1;
    /// `horizon`'s default \[s\].
    pub const DEFAULT_HORIZON: f64 = 3.0;
    /// `iterations`' default.
    pub const DEFAULT_ITERATIONS: usize = 1;
    /// `bound`'s default \[N\].
    pub const DEFAULT_BOUND: f64 = 5.0;
    /// `effort`'s default.
    pub const DEFAULT_EFFORT: f64 = 0.01;
    /// `forecast_error`'s default: σ reaches 0.1 (10 % in amplitude, 0.1 rad in phase) one
    /// peak period ahead ([`crate::mpc`], "What the plan knows").
    pub const DEFAULT_FORECAST_ERROR: f64 = 0.1;
    /// The largest `forecast_error` accepted: σ then reaches its cap 1/√2 a hundredth of a peak
    /// period ahead, a forecast without skill beyond the first steps.
    pub const MAX_FORECAST_ERROR: f64 = 100.0;
}

impl MpcSettings {
    /// What MPC plans on (with the effort penalty ρ·h·Σ u²): `objective` when given —
    /// `"power"`, the fatigue proxy Σ|M₀(t_k)|^m with m the first slope of the S-N curve of
    /// `scene`'s `[fatigue]` table ([`WellheadDamage::exponent`]); `"sum"`, c_sum (thesis eq.
    /// 3.3.4) — else the `model` scene's `[objective]` when it is `"power"` (Σ|M₀(t_k)|^p), its
    /// smooth stand-in Σ|M₀|^m when it is `"fatigue"` (the structured solvers need a
    /// Gauss-Newton form, which the rainflow damage has not), otherwise c_sum (a receding
    /// horizon has no final time of its own). `chainbeam mpc`'s and the Python package's `mpc`.
    ///
    /// # Errors
    /// [`SceneError`] naming `mpc.objective` for `"power"` without a `[fatigue]` table (or with
    /// one whose S-N curve is invalid).
    pub fn plan_objective(
        &self,
        scene: &Scene,
        model: &Scene,
    ) -> Result<ObjectiveKind, SceneError> {
        match self.objective {
            Some(MpcPlanObjective::Sum) => return Ok(ObjectiveKind::Sum),
            Some(MpcPlanObjective::Power) => {
                let spec = scene.fatigue_spec().ok_or_else(|| {
                    SceneError::invalid(
                        "mpc.objective",
                        "\"power\" plans on Σ|M₀|^m with m the S-N curve's first slope: it needs \
                         a [fatigue] or a [pipe] table (docs/scene-format.md)",
                    )
                })?;
                let d = WellheadDamage::new(&spec, scene.moment_measure()).map_err(|e| {
                    SceneError::invalid("mpc.objective", format!("\"power\": [fatigue]: {e}"))
                })?;
                return Ok(ObjectiveKind::Power {
                    exponent: d.exponent(),
                });
            }
            None => {}
        }
        Ok(match model.objective {
            Some(kind @ ObjectiveKind::Power { .. }) => kind,
            Some(ObjectiveKind::Fatigue(d)) => ObjectiveKind::Power {
                exponent: d.exponent(),
            },
            _ => ObjectiveKind::Sum,
        })
    }
}

impl MpcTable {
    /// The settings of a run: each value of `self` (the caller's: the command line's flags,
    /// the Python arguments), else the scene's `table` (`[mpc]`), else the default
    /// ([`MpcSettings`]'s constants). The one precedence of `chainbeam fatigue`, `chainbeam mpc`
    /// and the Python package.
    pub fn resolve(&self, table: Option<&MpcTable>) -> MpcSettings {
        let t = table.cloned().unwrap_or_default();
        MpcSettings {
            interval: self
                .interval
                .or(t.interval)
                .unwrap_or(MpcSettings::DEFAULT_INTERVAL),
            horizon: self
                .horizon
                .or(t.horizon)
                .unwrap_or(MpcSettings::DEFAULT_HORIZON),
            iterations: self
                .iterations
                .or(t.iterations)
                .unwrap_or(MpcSettings::DEFAULT_ITERATIONS),
            bound: self.bound.or(t.bound).unwrap_or(MpcSettings::DEFAULT_BOUND),
            effort: self
                .effort
                .or(t.effort)
                .unwrap_or(MpcSettings::DEFAULT_EFFORT),
            plan_pendulums: self.plan_pendulums.or(t.plan_pendulums),
            plan_step: self.plan_step.or(t.plan_step),
            pd_training: self.pd_training.or(t.pd_training),
            objective: self.objective.or(t.objective),
            forecast: self.forecast.or(t.forecast).unwrap_or_default(),
            forecast_error: self
                .forecast_error
                .or(t.forecast_error)
                .unwrap_or(MpcSettings::DEFAULT_FORECAST_ERROR),
            forecast_seed: self.forecast_seed.or(t.forecast_seed),
            observe: self.observe.or(t.observe).unwrap_or_default(),
            hotspot: self.hotspot.clone().or(t.hotspot),
            moment_about: self.moment_about.or(t.moment_about).unwrap_or_default(),
        }
    }

    /// Whether the key `key` (one of [`MPC_KEYS`]) is given.
    pub fn has(&self, key: &str) -> bool {
        match key {
            "interval" => self.interval.is_some(),
            "horizon" => self.horizon.is_some(),
            "iterations" => self.iterations.is_some(),
            "bound" => self.bound.is_some(),
            "effort" => self.effort.is_some(),
            "plan_pendulums" => self.plan_pendulums.is_some(),
            "plan_step" => self.plan_step.is_some(),
            "pd_training" => self.pd_training.is_some(),
            "objective" => self.objective.is_some(),
            "forecast" => self.forecast.is_some(),
            "forecast_error" => self.forecast_error.is_some(),
            "forecast_seed" => self.forecast_seed.is_some(),
            "observe" => self.observe.is_some(),
            "hotspot" => self.hotspot.is_some(),
            "moment_about" => self.moment_about.is_some(),
            _ => false,
        }
    }

    /// Whether [`MpcTable::resolve`] takes `key` from the scene's `table`: `self` (the caller's
    /// values) does not give it and the table does. Errors about the value then name the
    /// table's key (`mpc.horizon`) rather than the caller's flag.
    pub fn defers_to(&self, table: Option<&MpcTable>, key: &str) -> bool {
        !self.has(key) && table.is_some_and(|t| t.has(key))
    }
}

#[derive(Serialize, Deserialize, Default)]
#[serde(deny_unknown_fields)]
pub(super) struct RawMpc {
    #[serde(default, skip_serializing_if = "Option::is_none")]
    interval: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    horizon: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    iterations: Option<i64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    bound: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    effort: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    plan_pendulums: Option<i64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    plan_step: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pd_training: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    objective: Option<String>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    forecast: Option<String>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    forecast_error: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    forecast_seed: Option<i64>,
    observe: Option<String>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    hotspot: Option<String>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    moment_about: Option<String>,
}

/// A positive finite number (`mpc.KEY`).
fn positive(key: &str, v: Option<f64>) -> Result<Option<f64>, SceneError> {
    match v {
        Some(x) if !(x.is_finite() && x > 0.0) => Err(SceneError::invalid(
            format!("mpc.{key}"),
            format!("must be a positive finite number, got {x}"),
        )),
        v => Ok(v),
    }
}

/// A count ≥ 1 (`mpc.KEY`).
fn count(key: &str, v: Option<i64>) -> Result<Option<usize>, SceneError> {
    v.map(|x| {
        usize::try_from(x).ok().filter(|&n| n >= 1).ok_or_else(|| {
            SceneError::invalid(format!("mpc.{key}"), format!("must be ≥ 1, got {x}"))
        })
    })
    .transpose()
}

impl RawMpc {
    pub(super) fn from_table(t: &MpcTable) -> Self {
        let int = |v: Option<usize>| v.map(|n| i64::try_from(n).unwrap_or(i64::MAX));
        RawMpc {
            interval: t.interval,
            horizon: t.horizon,
            iterations: int(t.iterations),
            bound: t.bound,
            effort: t.effort,
            plan_pendulums: int(t.plan_pendulums),
            plan_step: t.plan_step,
            pd_training: t.pd_training,
            objective: t.objective.map(|o| o.name().to_string()),
            forecast: t.forecast.map(|f| f.name().to_string()),
            forecast_error: t.forecast_error,
            forecast_seed: t
                .forecast_seed
                .map(|s| i64::try_from(s).unwrap_or(i64::MAX)),
            observe: t.observe.map(|o| o.name().to_string()),
            hotspot: t.hotspot.clone(),
            moment_about: t.moment_about.map(|m| m.name().to_string()),
        }
    }

    /// The validated table; an invalid value names its key (`mpc.horizon`).
    pub(super) fn into_table(self) -> Result<MpcTable, SceneError> {
        // A positive number of newtons; infinite (unbounded) or within the forces a scene may
        // have (the flag `--bound`'s check).
        let bound = match self.bound {
            Some(b) if b.is_nan() || b <= 0.0 => Err(SceneError::invalid(
                "mpc.bound",
                format!("must be a positive number of newtons, got {b}"),
            )),
            Some(b) if b.is_finite() && !FORCE_RANGE.contains(b) => Err(SceneError::invalid(
                "mpc.bound",
                format!(
                    "{b:e} N: outside the supported force range [{:e}, {:e}] N",
                    FORCE_RANGE.min, FORCE_RANGE.max
                ),
            )),
            b => Ok(b),
        }?;
        let effort = match self.effort {
            Some(e) if !(e.is_finite() && e >= 0.0) => Err(SceneError::invalid(
                "mpc.effort",
                format!("must be finite and ≥ 0, got {e}"),
            )),
            e => Ok(e),
        }?;
        let objective = one_of(
            "objective",
            self.objective.as_deref(),
            |o| match o {
                "power" => Some(MpcPlanObjective::Power),
                "sum" => Some(MpcPlanObjective::Sum),
                _ => None,
            },
            "power, sum",
        )?;
        let forecast = one_of(
            "forecast",
            self.forecast.as_deref(),
            Forecast::from_name,
            "perfect, none, noisy",
        )?;
        let forecast_error = self
            .forecast_error
            .map(|e| check_forecast_error("mpc.forecast_error", e))
            .transpose()?;
        let forecast_seed = self
            .forecast_seed
            .map(|s| {
                u64::try_from(s).map_err(|_| {
                    SceneError::invalid(
                        "mpc.forecast_seed",
                        format!("must be a non-negative integer, got {s}"),
                    )
                })
            })
            .transpose()?;
        let observe = one_of(
            "observe",
            self.observe.as_deref(),
            Observe::from_name,
            "state, sensors",
        )?;
        let moment_about = one_of(
            "moment_about",
            self.moment_about.as_deref(),
            MomentAbout::from_name,
            "zero, mean",
        )?;
        Ok(MpcTable {
            interval: positive("interval", self.interval)?,
            horizon: positive("horizon", self.horizon)?,
            iterations: count("iterations", self.iterations)?,
            bound,
            effort,
            plan_pendulums: count("plan_pendulums", self.plan_pendulums)?,
            plan_step: positive("plan_step", self.plan_step)?,
            pd_training: positive("pd_training", self.pd_training)?,
            objective,
            forecast,
            forecast_error,
            forecast_seed,
            observe,
            hotspot: self.hotspot,
            moment_about,
        })
    }
}

/// A named choice of `[mpc]`: absent, or one of `choices` (parsed by `parse`); any other name is
/// refused naming the key `mpc.<key>` and the choices.
fn one_of<T>(
    key: &str,
    name: Option<&str>,
    parse: impl Fn(&str) -> Option<T>,
    choices: &str,
) -> Result<Option<T>, SceneError> {
    name.map(|v| {
        parse(v).ok_or_else(|| {
            SceneError::invalid(
                format!("mpc.{key}"),
                format!("unknown {key} `{v}` (one of {choices})"),
            )
        })
    })
    .transpose()
}

/// `forecast_error` e checked: finite, 0 ≤ e ≤ [`MpcSettings::MAX_FORECAST_ERROR`].
///
/// # Errors
/// [`SceneError`] naming `key` (the scene's `mpc.forecast_error`, a flag's or an argument's
/// name) with the value and the range.
pub fn check_forecast_error(key: &str, e: f64) -> Result<f64, SceneError> {
    if e.is_finite() && (0.0..=MpcSettings::MAX_FORECAST_ERROR).contains(&e) {
        Ok(e)
    } else {
        Err(SceneError::invalid(
            key,
            format!(
                "must be a finite number in [0, {}] (σ(τ) = forecast_error · τ / T_p), got {e}",
                MpcSettings::MAX_FORECAST_ERROR
            ),
        ))
    }
}
