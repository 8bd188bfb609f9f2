//! The `[objective]` table: `kind` (`"final"`, `"sum"`, `"power"` or `"fatigue"`) and, for
//! `"power"`, the `exponent` p ≥ 2, read into an [`ObjectiveKind`] (docs/scene-format.md).
//! `"fatigue"` takes the scene's `[fatigue]` table and l₁ ([`Scene::moment_measure`]).

use serde::{Deserialize, Serialize};

#[cfg(doc)]
use super::Scene;
use super::{ObjectiveKind, SceneError, SceneErrorKind};
use crate::fatigue::{FatigueSpec, MomentMeasure, WellheadDamage};

/// The file's names of the objective kinds.
#[derive(Clone, Copy, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
enum RawKind {
    Final,
    Sum,
    Power,
    Fatigue,
}

#[derive(Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RawObjective {
    kind: RawKind,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    exponent: Option<f64>,
}

impl RawObjective {
    pub(super) fn from_kind(kind: ObjectiveKind) -> Self {
        let (kind, exponent) = match kind {
            ObjectiveKind::Final => (RawKind::Final, None),
            ObjectiveKind::Sum => (RawKind::Sum, None),
            ObjectiveKind::Power { exponent } => (RawKind::Power, Some(exponent)),
            ObjectiveKind::Fatigue(_) => (RawKind::Fatigue, None),
        };
        RawObjective { kind, exponent }
    }

    /// The kind; `objective.exponent` is required with `"power"` and refused otherwise (its
    /// range is checked by [`ObjectiveKind::check`], as for a built scene). `"fatigue"` needs the
    /// scene's `[fatigue]` table (`fatigue`, else an error naming the key `fatigue`) and the
    /// base pendulum's length l₁ (`base_length`).
    pub(super) fn into_kind(
        self,
        fatigue: Option<&FatigueSpec>,
        base_length: f64,
    ) -> Result<ObjectiveKind, SceneError> {
        match (self.kind, self.exponent) {
            (RawKind::Power, Some(exponent)) => Ok(ObjectiveKind::Power { exponent }),
            (RawKind::Power, None) => Err(SceneError::new(SceneErrorKind::MissingKey {
                key: EXPONENT_KEY.into(),
                note: Some("kind = \"power\" (Σ|M₀(t_k)|^p) needs the exponent p ≥ 2".into()),
            })),
            (_, Some(_)) => Err(SceneError::invalid(
                EXPONENT_KEY,
                "only kind = \"power\" takes an exponent",
            )),
            (RawKind::Fatigue, None) => {
                let spec = fatigue.ok_or_else(|| {
                    SceneError::new(SceneErrorKind::MissingKey {
                        key: "fatigue".into(),
                        note: Some(
                            "[objective] kind = \"fatigue\" (the rainflow damage of the wellhead \
                             stress) needs the [fatigue] table: outer_diameter, wall_thickness \
                             and the S-N curve"
                                .into(),
                        ),
                    })
                })?;
                let damage = WellheadDamage::new(spec, MomentMeasure::ChainM0 { base_length })
                    .map_err(super::fatigue::scene_error)?;
                Ok(ObjectiveKind::Fatigue(damage))
            }
            (RawKind::Final, None) => Ok(ObjectiveKind::Final),
            (RawKind::Sum, None) => Ok(ObjectiveKind::Sum),
        }
    }
}

/// The key of the power objective's exponent.
const EXPONENT_KEY: &str = "objective.exponent";

impl ObjectiveKind {
    /// Checks the power objective's exponent: finite and p ≥ 2 (then |M₀|^p is twice
    /// continuously differentiable, as the Hessian-vector products and the structured solvers'
    /// Newton steps need, and p = 2 is c_sum). Otherwise [`SceneErrorKind::InvalidValue`]
    /// naming `objective.exponent`.
    pub fn check(&self) -> Result<(), SceneError> {
        match *self {
            ObjectiveKind::Power { exponent } if !(exponent.is_finite() && exponent >= 2.0) => {
                Err(SceneError::invalid(
                    EXPONENT_KEY,
                    format!(
                        "the exponent p of Σ|M₀(t_k)|^p must be finite and at least 2, got \
                         {exponent}"
                    ),
                ))
            }
            _ => Ok(()),
        }
    }

    /// The name a scene file gives the kind: `final`, `sum`, `power` or `fatigue`.
    pub fn name(&self) -> &'static str {
        match self {
            ObjectiveKind::Final => "final",
            ObjectiveKind::Sum => "sum",
            ObjectiveKind::Power { .. } => "power",
            ObjectiveKind::Fatigue(_) => "fatigue",
        }
    }
}
