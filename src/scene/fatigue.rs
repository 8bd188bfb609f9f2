//! The `[fatigue]` table: the wellhead's pipe section, stress concentration, DNV-RP-C203 S-N
//! curve and design fatigue factor, read into a [`FatigueSpec`] (docs/scene-format.md).

use serde::{Deserialize, Serialize};

use crate::fatigue::{
    DnvClass, Environment, FatigueError, FatigueSpec, MomentMeasure, DEFAULT_CIRCUMFERENCE_POINTS,
    DNV_REFERENCE_THICKNESS_M,
};

use super::{Pipe, Scene, SceneError, SceneErrorKind};

/// A hot spot of the scene (`[[fatigue.hotspot]]`, docs/scene-format.md).
#[derive(Clone, Debug, PartialEq)]
pub struct HotSpotSpec {
    /// Its name (`name`, unique in the scene), as the report names it.
    pub name: String,
    /// Elevation e above the chain's base \[m\] (`elevation`, 0 ≤ e ≤ the chain's length).
    pub elevation: f64,
    /// The section, SCF, S-N curve, environment and DFF of the hot spot (every key the
    /// `[fatigue]` table has, defaulting to the table's value).
    pub spec: FatigueSpec,
}

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
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    hotspot: Vec<RawHotSpot>,
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
            hotspot: Vec::new(),
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

/// One `[[fatigue.hotspot]]` entry as the file writes it: `name` and `elevation` required, every
/// other key optional, defaulting to the `[fatigue]` table's value.
#[derive(Serialize, Deserialize, Clone)]
#[serde(deny_unknown_fields)]
pub(super) struct RawHotSpot {
    name: String,
    elevation: f64,
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

/// A [`FatigueError`] of hot spot `index` as a scene error naming
/// `fatigue.hotspot[index].<key>`.
fn hotspot_error(index: usize, e: FatigueError) -> SceneError {
    let key = |k: &str| format!("fatigue.hotspot[{index}].{k}");
    match e {
        FatigueError::InvalidSpec {
            key: k,
            value,
            reason,
        } => SceneError::invalid(key(k), format!("{reason}, got {value}")),
        FatigueError::UnknownCurve { .. } => SceneError::invalid(key("curve"), e.to_string()),
        FatigueError::UnknownEnvironment { .. } => {
            SceneError::invalid(key("environment"), e.to_string())
        }
        other => SceneError::invalid(format!("fatigue.hotspot[{index}]"), other.to_string()),
    }
}

impl RawFatigue {
    /// The table without its `[[fatigue.hotspot]]` entries, and the entries.
    pub(super) fn split_hotspots(mut self) -> (Self, Vec<RawHotSpot>) {
        let hotspots = std::mem::take(&mut self.hotspot);
        (self, hotspots)
    }

    /// The table with `hotspots` written as its `[[fatigue.hotspot]]` entries (every key
    /// explicit).
    pub(super) fn with_hotspots(mut self, hotspots: &[HotSpotSpec]) -> Self {
        self.hotspot = hotspots.iter().map(RawHotSpot::from_spec).collect();
        self
    }
}

impl RawHotSpot {
    fn from_spec(h: &HotSpotSpec) -> Self {
        let f = &h.spec;
        RawHotSpot {
            name: h.name.clone(),
            elevation: h.elevation,
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

    /// The hot spot `index` with the table's spec `table` as its defaults; an invalid value
    /// names `fatigue.hotspot[index].<key>` (the elevation and the name are checked against the
    /// chain by [`Scene::check_hotspots`]).
    fn into_spec(self, index: usize, table: &FatigueSpec) -> Result<HotSpotSpec, SceneError> {
        let err = |e| hotspot_error(index, e);
        let curve = match self.curve {
            Some(name) => name.parse::<DnvClass>().map_err(err)?,
            None => table.curve,
        };
        let environment = match self.environment {
            Some(name) => name.parse::<Environment>().map_err(err)?,
            None => table.environment,
        };
        let spec = FatigueSpec {
            outer_diameter: self.outer_diameter.unwrap_or(table.outer_diameter),
            wall_thickness: self.wall_thickness.unwrap_or(table.wall_thickness),
            scf: self.scf.unwrap_or(table.scf),
            curve,
            environment,
            thickness_exponent: self.thickness_exponent.or(table.thickness_exponent),
            reference_thickness: self
                .reference_thickness
                .unwrap_or(table.reference_thickness),
            dff: self.dff.unwrap_or(table.dff),
            circumference_points: table.circumference_points,
        };
        spec.validate().map_err(err)?;
        Ok(HotSpotSpec {
            name: self.name,
            elevation: self.elevation,
            spec,
        })
    }
}

/// The hot spots of the entries, defaulting to the table's spec (none without a table).
pub(super) fn hotspots_of(
    raw: Vec<RawHotSpot>,
    table: Option<&FatigueSpec>,
) -> Result<Vec<HotSpotSpec>, SceneError> {
    let Some(table) = table else {
        return Ok(Vec::new());
    };
    raw.into_iter()
        .enumerate()
        .map(|(i, h)| h.into_spec(i, table))
        .collect()
}

/// The longest hot-spot name (characters).
pub const MAX_HOTSPOT_NAME: usize = 64;

impl Scene {
    /// The hot spots `chainbeam fatigue` assesses: the scene's `[[fatigue.hotspot]]` entries, or,
    /// without any, the wellhead alone (named `wellhead`, at elevation 0, the scene's
    /// [`Scene::fatigue_spec`]: the `[fatigue]` table, else the `[pipe]`'s section); none for a
    /// scene with neither. At elevation 0 the moment is joint 1's
    /// torque k₁θ₁, the wellhead moment M_w times θ₁/sin θ₁ (`crate::hotspots`).
    pub fn hot_spots(&self) -> Vec<HotSpotSpec> {
        match (self.fatigue_spec(), self.hotspots.is_empty()) {
            (_, false) => self.hotspots.clone(),
            (Some(spec), true) => vec![HotSpotSpec {
                name: "wellhead".to_string(),
                elevation: 0.0,
                spec,
            }],
            (None, true) => Vec::new(),
        }
    }

    /// The hot spots against the chain: each name non-empty, at most [`MAX_HOTSPOT_NAME`]
    /// characters and unique; each elevation finite and within [0, L] (L = Σ lᵢ, the chain's
    /// length); each spec valid. Errors name `fatigue.hotspot[i].<key>`.
    pub(super) fn check_hotspots(&self) -> Result<(), SceneError> {
        let length: f64 = self.beam.lengths.iter().sum();
        for (i, h) in self.hotspots.iter().enumerate() {
            let key = |k: &str| format!("fatigue.hotspot[{i}].{k}");
            if h.name.trim().is_empty() || h.name.chars().count() > MAX_HOTSPOT_NAME {
                return Err(SceneError::invalid(
                    key("name"),
                    format!("must be 1 to {MAX_HOTSPOT_NAME} characters, not blank"),
                ));
            }
            if self.hotspots[..i].iter().any(|o| o.name == h.name) {
                return Err(SceneError::invalid(
                    key("name"),
                    format!("`{}` names two hot spots", h.name),
                ));
            }
            if !(h.elevation.is_finite() && (0.0..=length).contains(&h.elevation)) {
                return Err(SceneError::invalid(
                    key("elevation"),
                    format!(
                        "must be within [0, {length}] m (above the chain's base, at most its \
                         length), got {}",
                        h.elevation
                    ),
                ));
            }
            h.spec.validate().map_err(|e| hotspot_error(i, e))?;
        }
        if !self.hotspots.is_empty() && self.fatigue.is_none() {
            return Err(SceneError::invalid(
                "fatigue.hotspot",
                "hot spots need the [fatigue] table they default to",
            ));
        }
        Ok(())
    }
}
