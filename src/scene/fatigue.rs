//! The `[fatigue]` table: the wellhead's pipe section, stress concentration, DNV-RP-C203 S-N
//! curve and design fatigue factor, read into a [`FatigueSpec`] (docs/scene-format.md).

use serde::{Deserialize, Serialize};

use crate::fatigue::{
    DnvClass, Environment, FatigueError, FatigueSpec, MomentMeasure, DEFAULT_CIRCUMFERENCE_POINTS,
    DNV_REFERENCE_THICKNESS_M,
};

use super::{Pipe, Scene, SceneError, SceneErrorKind};

impl Scene {
    /// The wellhead's fatigue assessment as the scene defines it: its `[fatigue]` table (whose
    /// `outer_diameter` and `wall_thickness` default to the `[pipe]`'s), else, for a scene with a
    /// `[pipe]` and no `[fatigue]` table, the pipe's section with every other value at its
    /// default ([`FatigueSpec::new`]: S-N curve D in sea water with cathodic protection, SCF 1,
    /// DFF 1). `None` for a scene with neither.
    pub fn fatigue_spec(&self) -> Option<FatigueSpec> {
        self.fatigue.or_else(|| {
            self.pipe
                .map(|p| FatigueSpec::new(p.outer_diameter, p.wall_thickness))
        })
    }

    /// What this scene's `moment` (M₀ = 2k₁z₁/l₁², thesis eq. 3.1.3) is in terms of the wellhead
    /// moment: [`MomentMeasure::ChainM0`] with l₁ = `beam.lengths[0]`, so that the fatigue
    /// assessment takes M_w = k₁z₁/l₁ = M₀ · l₁/2 (docs/conventions.md "The wellhead moment M_w").
    pub fn moment_measure(&self) -> MomentMeasure {
        MomentMeasure::ChainM0 {
            base_length: self.beam.lengths.first().copied().unwrap_or(f64::NAN),
        }
    }
}

#[derive(Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RawFatigue {
    #[serde(default, skip_serializing_if = "Option::is_none")]
    outer_diameter: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    wall_thickness: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    scf: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    curve: Option<String>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    environment: Option<String>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    thickness_exponent: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    reference_thickness: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    dff: Option<f64>,
}

/// A [`FatigueError`] of the table as a scene error naming `fatigue.<key>`.
pub(super) fn scene_error(e: FatigueError) -> SceneError {
    match e {
        FatigueError::InvalidSpec { key, value, reason } => {
            SceneError::invalid(format!("fatigue.{key}"), format!("{reason}, got {value}"))
        }
        FatigueError::UnknownCurve { .. } => SceneError::invalid("fatigue.curve", e.to_string()),
        FatigueError::UnknownEnvironment { .. } => {
            SceneError::invalid("fatigue.environment", e.to_string())
        }
        other => SceneError::invalid("fatigue", other.to_string()),
    }
}

impl RawFatigue {
    pub(super) fn from_spec(f: &FatigueSpec) -> Self {
        RawFatigue {
            outer_diameter: Some(f.outer_diameter),
            wall_thickness: Some(f.wall_thickness),
            scf: Some(f.scf),
            curve: Some(f.curve.name().to_string()),
            environment: Some(f.environment.name().to_string()),
            thickness_exponent: f.thickness_exponent,
            reference_thickness: Some(f.reference_thickness),
            dff: Some(f.dff),
        }
    }

    /// The validated spec; an invalid value names its key (`fatigue.wall_thickness`). The
    /// section (`outer_diameter`, `wall_thickness`) not given is the `pipe`'s; without a pipe it
    /// is required.
    pub(super) fn into_spec(self, pipe: Option<&Pipe>) -> Result<FatigueSpec, SceneError> {
        let section = |given: Option<f64>, key: &str, of_pipe: fn(&Pipe) -> f64| {
            given.or(pipe.map(of_pipe)).ok_or_else(|| {
                SceneError::new(SceneErrorKind::MissingKey {
                    key: format!("fatigue.{key}"),
                    note: Some(format!(
                        "the wellhead's section: give `{key}` [m], or a [pipe] table whose \
                         `{key}` it then takes"
                    )),
                })
            })
        };
        let outer_diameter = section(self.outer_diameter, "outer_diameter", |p| p.outer_diameter)?;
        let wall_thickness = section(self.wall_thickness, "wall_thickness", |p| p.wall_thickness)?;
        let curve = match self.curve {
            Some(name) => name.parse::<DnvClass>().map_err(scene_error)?,
            None => DnvClass::D,
        };
        let environment = match self.environment {
            Some(name) => name.parse::<Environment>().map_err(scene_error)?,
            None => Environment::SeawaterCp,
        };
        let spec = FatigueSpec {
            outer_diameter,
            wall_thickness,
            scf: self.scf.unwrap_or(1.0),
            curve,
            environment,
            thickness_exponent: self.thickness_exponent,
            reference_thickness: self
                .reference_thickness
                .unwrap_or(DNV_REFERENCE_THICKNESS_M),
            dff: self.dff.unwrap_or(1.0),
            circumference_points: DEFAULT_CIRCUMFERENCE_POINTS,
        };
        spec.validate().map_err(scene_error)?;
        Ok(spec)
    }
}
