//! The `[design]` table (docs/scene-format.md "[design]"): which physical parameters a fatigue
//! design (`chainbeam design`, [`crate::design`]) may change, their bounds, and the optimiser's
//! iteration limit and tolerance. Read into a [`DesignTable`]; every value is checked against the
//! scene it belongs to ([`Scene::check_design`]), an error naming its key.

use serde::{Deserialize, Serialize};

use super::{Scene, SceneError, SceneErrorKind};
use crate::design::{DesignParameter, DesignTable, FreeParameter, Role};

/// The file's `[design]` table.
#[derive(Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RawDesign {
    #[serde(default, skip_serializing_if = "Option::is_none")]
    max_iterations: Option<i64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    tolerance: Option<f64>,
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    parameter: Vec<RawDesignParameter>,
}

/// One `[[design.parameter]]` entry.
#[derive(Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct RawDesignParameter {
    name: String,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    role: Option<String>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    lower: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    upper: Option<f64>,
}

impl RawDesign {
    pub(super) fn from_table(t: &DesignTable) -> Self {
        RawDesign {
            max_iterations: Some(t.max_iterations as i64),
            tolerance: Some(t.tolerance),
            parameter: t
                .parameters
                .iter()
                .map(|p| RawDesignParameter {
                    name: p.parameter.name().to_string(),
                    role: Some(p.role.name().to_string()),
                    lower: p.bounds.map(|b| b.0),
                    upper: p.bounds.map(|b| b.1),
                })
                .collect(),
        }
    }

    /// The table; names, roles, counts and the presence of bounds are checked here, the values
    /// against the scene by [`Scene::check_design`].
    pub(super) fn into_table(self) -> Result<DesignTable, SceneError> {
        let max_iterations = match self.max_iterations {
            None => DesignTable::DEFAULT_MAX_ITERATIONS,
            Some(m) if (1..=DesignTable::MAX_ITERATIONS as i64).contains(&m) => m as usize,
            Some(m) => {
                return Err(SceneError::invalid(
                    "design.max_iterations",
                    format!("must be 1 to {}, got {m}", DesignTable::MAX_ITERATIONS),
                ))
            }
        };
        let mut parameters = Vec::with_capacity(self.parameter.len());
        for (i, p) in self.parameter.into_iter().enumerate() {
            let key = |k: &str| format!("design.parameter[{i}].{k}");
            let parameter = DesignParameter::from_name(&p.name).ok_or_else(|| {
                SceneError::invalid(
                    key("name"),
                    format!(
                        "unknown design parameter {:?}; expected one of {}",
                        p.name,
                        DesignParameter::names()
                    ),
                )
            })?;
            if parameters
                .iter()
                .any(|q: &FreeParameter| q.parameter == parameter)
            {
                return Err(SceneError::invalid(
                    key("name"),
                    format!("{} is named twice", p.name),
                ));
            }
            let role = match p.role.as_deref() {
                None => parameter.default_role(),
                Some(r) => Role::from_name(r).ok_or_else(|| {
                    SceneError::invalid(
                        key("role"),
                        format!("unknown role {r:?}; expected \"design\" or \"uncertainty\""),
                    )
                })?,
            };
            let bounds = match (role, p.lower, p.upper) {
                (Role::Design, Some(lo), Some(hi)) => Some((lo, hi)),
                (Role::Design, lo, _) => {
                    let missing = if lo.is_none() { "lower" } else { "upper" };
                    return Err(SceneError::new(SceneErrorKind::MissingKey {
                        key: key(missing),
                        note: Some(format!(
                            "a design parameter ({}) needs both bounds, lower < upper, in {}",
                            p.name,
                            parameter.unit()
                        )),
                    }));
                }
                (Role::Uncertainty, None, None) => None,
                (Role::Uncertainty, lo, _) => {
                    let given = if lo.is_some() { "lower" } else { "upper" };
                    return Err(SceneError::invalid(
                        key(given),
                        "an uncertainty (role = \"uncertainty\") is not optimised and takes no \
                         bounds: only its sensitivity is reported",
                    ));
                }
            };
            parameters.push(FreeParameter {
                parameter,
                role,
                bounds,
            });
        }
        Ok(DesignTable {
            parameters,
            max_iterations,
            tolerance: self.tolerance.unwrap_or(DesignTable::DEFAULT_TOLERANCE),
        })
    }
}

impl Scene {
    /// Checks the `[design]` table against the scene: the tolerance is positive and finite;
    /// every parameter is one this scene's model has (`beam.base_stiffness` needs a base spring,
    /// `beam.tip_stiffness` a tip spring, `loads.tension` a tension T > 0, `soil.modulus` a
    /// `[soil]` table); bounds are finite with 0 < lower < upper, and the scene's own value lies
    /// within them (the optimiser starts there).
    ///
    /// # Errors
    /// [`SceneErrorKind::InvalidValue`] naming `design.tolerance` or
    /// `design.parameter[i].name`, `.lower` or `.upper`.
    pub fn check_design(&self) -> Result<(), SceneError> {
        let Some(d) = &self.design else {
            return Ok(());
        };
        if !(d.tolerance.is_finite() && d.tolerance > 0.0) {
            return Err(SceneError::invalid(
                "design.tolerance",
                format!("must be positive and finite, got {}", d.tolerance),
            ));
        }
        for (i, p) in d.parameters.iter().enumerate() {
            let key = |k: &str| format!("design.parameter[{i}].{k}");
            let value = p.parameter.value(self).map_err(|reason| {
                SceneError::invalid(key("name"), format!("{}: {reason}", p.parameter.name()))
            })?;
            let Some((lo, hi)) = p.bounds else {
                continue;
            };
            for (k, v) in [("lower", lo), ("upper", hi)] {
                if !(v.is_finite() && v > 0.0) {
                    return Err(SceneError::invalid(
                        key(k),
                        format!(
                            "must be positive and finite ({}), got {v}",
                            p.parameter.unit()
                        ),
                    ));
                }
            }
            if lo >= hi {
                return Err(SceneError::invalid(
                    key("upper"),
                    format!("must be above lower = {lo}, got {hi}"),
                ));
            }
            if !(lo..=hi).contains(&value) {
                let k = if value < lo { "lower" } else { "upper" };
                return Err(SceneError::invalid(
                    key(k),
                    format!(
                        "the scene's own {} = {value} {} lies outside [{lo}, {hi}]: the design \
                         starts there",
                        p.parameter.name(),
                        p.parameter.unit()
                    ),
                ));
            }
        }
        Ok(())
    }
}
