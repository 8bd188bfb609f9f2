//! The `[mpc]` table: the settings of the closed-loop controllers (`constant`, `pd`, `mpc`) that
//! were only flags of `chainbeam fatigue`, with the flags' names in snake case
//! (docs/scene-format.md "[mpc]"). Every key is optional; a flag given on the command line
//! overrides the table, and a key given in neither takes the flag's default.

use serde::{Deserialize, Serialize};

use super::SceneError;

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

/// The `[mpc]` table (module docs): `None` for a key not given.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
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
        }
    }

    /// The validated table; an invalid value names its key (`mpc.horizon`).
    pub(super) fn into_table(self) -> Result<MpcTable, SceneError> {
        let bound = match self.bound {
            Some(b) if b.is_nan() || b <= 0.0 => Err(SceneError::invalid(
                "mpc.bound",
                format!("must be a positive number of newtons, got {b}"),
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
        let objective = match self.objective.as_deref() {
            None => None,
            Some("power") => Some(MpcPlanObjective::Power),
            Some("sum") => Some(MpcPlanObjective::Sum),
            Some(other) => {
                return Err(SceneError::invalid(
                    "mpc.objective",
                    format!("unknown objective `{other}` (one of power, sum)"),
                ))
            }
        };
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
        })
    }
}
