//! The `[design]` table (docs/scene-format.md "[design]"): which physical parameters a fatigue
//! design (`chainbeam design`, [`crate::design`]) may change, their bounds, and the optimiser's
//! iteration limit and tolerance. Read into a [`DesignTable`]; every value is checked against the
//! scene it belongs to ([`Scene::check_design`]), an error naming its key.

use serde::{Deserialize, Serialize};

use super::{Scene, SceneError, SceneErrorKind, Support};
use crate::base::Parameter;

/// The file's `[design]` table.
#[derive(Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RawDesign {
    #[serde(default, skip_serializing_if = "Option::is_none")]
    max_iterations: Option<i64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    tolerance: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    hotspot: Option<String>,
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
            hotspot: t.hotspot.clone(),
            parameter: t
                .parameters
                .iter()
                .map(|p| RawDesignParameter {
                    name: p.parameter.name(),
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
            hotspot: self.hotspot,
        })
    }
}

impl Scene {
    /// Checks the `[design]` table against the scene: the tolerance is positive and finite; the
    /// `hotspot`, when given, names a `[[fatigue.hotspot]]` of a planar scene;
    /// every parameter is one this scene's model has (`beam.base_stiffness` needs a base spring,
    /// `beam.tip_stiffness` a tip spring, `loads.tension` a tension T > 0, `soil.modulus` a
    /// `[soil]` table, `vessel.offset` `support = "vessel"` with a positive `vessel.ramp`,
    /// `stackup.segment.<name>.buoyancy_diameter` a segment of that name with buoyancy modules);
    /// bounds are finite with 0 < lower < upper (lower < upper for the signed `vessel.offset`;
    /// a buoyancy diameter's lower bound at least the segment's pipe outer diameter and its
    /// upper one within the stack-up's diameters' range), and the scene's own value lies
    /// within them (the optimiser starts there).
    ///
    /// # Errors
    /// [`SceneErrorKind::InvalidValue`] naming `design.tolerance`, `design.hotspot` or
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
        if let Some(name) = &d.hotspot {
            self.check_design_hotspot(name)?;
        }
        for (i, p) in d.parameters.iter().enumerate() {
            self.check_design_parameter(i, p)?;
        }
        Ok(())
    }

    /// `[design] hotspot`: a `[[fatigue.hotspot]]` of the scene, in a planar scene.
    fn check_design_hotspot(&self, name: &str) -> Result<(), SceneError> {
        if !self.hotspots.iter().any(|h| h.name == name) {
            let names: Vec<String> = self
                .hotspots
                .iter()
                .map(|h| format!("{:?}", h.name))
                .collect();
            return Err(SceneError::invalid(
                "design.hotspot",
                format!(
                    "no [[fatigue.hotspot]] is named {name:?} (the scene's: {})",
                    if names.is_empty() {
                        "none".to_string()
                    } else {
                        names.join(", ")
                    }
                ),
            ));
        }
        if self.is_spatial() {
            return Err(SceneError::invalid(
                "design.hotspot",
                format!(
                    "the objective at the hot spot {name:?} needs a planar scene (no load, \
                     current, wave direction or control along x)"
                ),
            ));
        }
        Ok(())
    }

    /// `[[design.parameter]]` number `i`: a parameter of the scene, bounds that are finite
    /// (positive for an unsigned one), ordered, within the stack-up's diameters for a buoyancy
    /// diameter, and around the scene's own value.
    fn check_design_parameter(&self, i: usize, p: &FreeParameter) -> Result<(), SceneError> {
        let key = |k: &str| format!("design.parameter[{i}].{k}");
        let value = p.parameter.value(self).map_err(|reason| {
            SceneError::invalid(key("name"), format!("{}: {reason}", p.parameter.name()))
        })?;
        let Some((lo, hi)) = p.bounds else {
            return Ok(());
        };
        for (k, v) in [("lower", lo), ("upper", hi)] {
            let signed = p.parameter.is_signed();
            if signed && !v.is_finite() {
                return Err(SceneError::invalid(
                    key(k),
                    format!("must be finite ({}), got {v}", p.parameter.unit()),
                ));
            }
            if !(signed || v.is_finite() && v > 0.0) {
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
        if let Some(floor) = p.parameter.floor(self) {
            if lo < floor {
                return Err(SceneError::invalid(
                    key("lower"),
                    format!(
                        "must be at least the segment's pipe outer diameter {floor} m \
                         (buoyancy modules are no thinner than the pipe), got {lo}"
                    ),
                ));
            }
            let range = super::stackup_range_of("buoyancy_diameter");
            if let Some(r) = range.filter(|r| hi > r.max) {
                return Err(SceneError::invalid(
                    key("upper"),
                    format!(
                        "must be at most {} {} (the stack-up's diameters), got {hi}",
                        r.max, r.unit
                    ),
                ));
            }
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
        Ok(())
    }
}

/// A physical parameter a fatigue design may change or test (module docs), named by its scene
/// key.
#[derive(Clone, Debug, PartialEq, Eq, Hash)]
pub enum DesignParameter {
    /// The top tension T \[N\] (`loads.tension`; [`Parameter::Tension`]).
    Tension,
    /// The lower flex joint's rotational stiffness, the base spring k₁ \[N·m/rad\]
    /// (`beam.base_stiffness`; [`Parameter::BaseStiffness`]).
    BaseStiffness,
    /// The upper flex joint's rotational stiffness, the tip spring k_{n+1} \[N·m/rad\]
    /// (`beam.tip_stiffness`; [`Parameter::TipStiffness`]).
    TipStiffness,
    /// The soil's p-y modulus at the mudline E₀ \[N/m²\] (`soil.modulus`;
    /// [`Parameter::SoilModulus`]): an uncertainty by default.
    SoilModulus,
    /// The rotational stiffness \[N·m/rad\] of the stack-up's flex joint of this name
    /// (`[[stackup.flex_joint]]` `name`), named `stackup.flex_joint.<name>.stiffness` (e.g.
    /// `stackup.flex_joint.lower flex joint.stiffness`). Its spring is the chain's joint
    /// spring where the flex joint sits ([`crate::scene::Layout::flex_joints`]): the base spring
    /// ([`Parameter::BaseStiffness`]), the tip spring ([`Parameter::TipStiffness`]) or an
    /// interior one ([`Parameter::JointStiffness`]).
    FlexJoint(String),
    /// The vessel's mean offset Z₀ \[m\] (`vessel.offset`, `support = "vessel"`;
    /// [`Parameter::VesselOffset`]): the top's prescribed Z(t) = ρ(t)(Z₀ + d_z X_w(t)). A signed
    /// parameter (Z₀ may be 0 or negative): its bounds may be any finite lower < upper, and
    /// the optimiser scales it affinely, u = (Z₀ − lower)/(upper − lower)
    /// ([`DesignParameter::is_signed`]).
    VesselOffset,
    /// The outer diameter D_b \[m\] of the buoyancy modules of the stack-up's segment of this
    /// name (`[[stackup.segment]]` `name`, a segment with `buoyancy_diameter` and
    /// `buoyancy_density`), named `stackup.segment.<name>.buoyancy_diameter` (e.g.
    /// `stackup.segment.riser_buoyant.buoyancy_diameter`). It sets the segment's
    /// `buoyancy_diameter` and the chain is laid out again ([`Scene::relayout_stackup`]): the
    /// foam's mass per length ρ_f π (D_b² − D_o²)/4, the displaced area π D_b²/4 (the submerged
    /// weight per length, hence the nodes' weights and the effective tension), and, unless the
    /// segment gives `hydrodynamic_diameter` explicitly, the Morison diameter D_h = D_b (the
    /// added mass C_a ρ_w π D_h²/4 per length, the drag ½ ρ_w C_d D_h and the waves' inertia
    /// ρ_w (1 + C_a) π D_h²/4). No library [`Parameter`] carries these per-node quantities
    /// ([`DesignParameter::is_node_quantity`]): its gradient comes from the same adjoint sweep
    /// as the others', through the node tangents of the chain
    /// ([`crate::adjoint::adjoint_gradient_with_nodes`]; the node quantities' exact
    /// derivatives [`crate::scene::Stackup::buoyancy_tangents`]).
    BuoyancyDiameter(String),
}

/// The prefix and suffix of a flex joint's design parameter name.
const FLEX_PREFIX: &str = "stackup.flex_joint.";
const FLEX_SUFFIX: &str = ".stiffness";
/// The prefix and suffix of a segment's buoyancy diameter's design parameter name.
const SEGMENT_PREFIX: &str = "stackup.segment.";
const BUOYANCY_SUFFIX: &str = ".buoyancy_diameter";

impl DesignParameter {
    /// Every design parameter but the stack-up's flex joints (which a scene names), in the
    /// order of the module docs.
    pub const ALL: [DesignParameter; 5] = [
        DesignParameter::Tension,
        DesignParameter::BaseStiffness,
        DesignParameter::TipStiffness,
        DesignParameter::SoilModulus,
        DesignParameter::VesselOffset,
    ];

    /// The scene key that names it (`loads.tension`, `beam.base_stiffness`,
    /// `beam.tip_stiffness`, `soil.modulus`, `vessel.offset`,
    /// `stackup.flex_joint.<name>.stiffness`, `stackup.segment.<name>.buoyancy_diameter`): its
    /// name in `[design]` and in the JSON.
    pub fn name(&self) -> String {
        match self {
            DesignParameter::Tension => "loads.tension".into(),
            DesignParameter::BaseStiffness => "beam.base_stiffness".into(),
            DesignParameter::TipStiffness => "beam.tip_stiffness".into(),
            DesignParameter::SoilModulus => "soil.modulus".into(),
            DesignParameter::VesselOffset => "vessel.offset".into(),
            DesignParameter::FlexJoint(name) => format!("{FLEX_PREFIX}{name}{FLEX_SUFFIX}"),
            DesignParameter::BuoyancyDiameter(name) => {
                format!("{SEGMENT_PREFIX}{name}{BUOYANCY_SUFFIX}")
            }
        }
    }

    /// The parameter of that name (a flex joint's or a segment's whatever its name: the scene it
    /// is used with must have it, [`DesignParameter::value`]).
    pub fn from_name(name: &str) -> Option<Self> {
        if let Some(joint) = name
            .strip_prefix(FLEX_PREFIX)
            .and_then(|r| r.strip_suffix(FLEX_SUFFIX))
        {
            return (!joint.is_empty()).then(|| DesignParameter::FlexJoint(joint.to_string()));
        }
        if let Some(segment) = name
            .strip_prefix(SEGMENT_PREFIX)
            .and_then(|r| r.strip_suffix(BUOYANCY_SUFFIX))
        {
            return (!segment.is_empty())
                .then(|| DesignParameter::BuoyancyDiameter(segment.to_string()));
        }
        Self::ALL.into_iter().find(|p| p.name() == name)
    }

    /// The names, quoted and comma-separated (for an error naming an unknown one).
    pub fn names() -> String {
        Self::ALL
            .iter()
            .map(|p| format!("\"{}\"", p.name()))
            .chain([
                format!("\"{FLEX_PREFIX}<name>{FLEX_SUFFIX}\""),
                format!("\"{SEGMENT_PREFIX}<name>{BUOYANCY_SUFFIX}\""),
            ])
            .collect::<Vec<_>>()
            .join(", ")
    }

    /// Its unit.
    pub fn unit(&self) -> &'static str {
        match self {
            DesignParameter::Tension => "N",
            DesignParameter::BaseStiffness
            | DesignParameter::TipStiffness
            | DesignParameter::FlexJoint(_) => "N·m/rad",
            DesignParameter::SoilModulus => "N/m²",
            DesignParameter::VesselOffset | DesignParameter::BuoyancyDiameter(_) => "m",
        }
    }

    /// Whether the parameter is signed (its value may be 0 or negative: the vessel's offset),
    /// scaled affinely to the optimiser's unit box, u = (θ − lower)/(upper − lower), where the
    /// others (positive) are scaled by the logarithms of their bounds ([`crate::design`], "The
    /// optimiser").
    pub fn is_signed(&self) -> bool {
        matches!(self, DesignParameter::VesselOffset)
    }

    /// Whether it moves the chain's per-node quantities rather than a library [`Parameter`]:
    /// a segment's buoyancy diameter ([`DesignParameter::BuoyancyDiameter`]), whose adjoint
    /// gradient the sweep takes through the node tangents
    /// ([`crate::adjoint::adjoint_gradient_with_nodes`], [`crate::design`] "The parameters").
    pub fn is_node_quantity(&self) -> bool {
        matches!(self, DesignParameter::BuoyancyDiameter(_))
    }

    /// The library's parameter of the scene's model, whose adjoint gradient this is (`None`:
    /// the scene has no flex joint of that name, or the parameter has no library parameter, a
    /// segment's buoyancy diameter: [`DesignParameter::is_node_quantity`]).
    pub fn parameter(&self, scene: &Scene) -> Option<Parameter> {
        Some(match self {
            DesignParameter::BuoyancyDiameter(_) => return None,
            DesignParameter::Tension => Parameter::Tension,
            DesignParameter::BaseStiffness => Parameter::BaseStiffness,
            DesignParameter::TipStiffness => Parameter::TipStiffness,
            DesignParameter::SoilModulus => Parameter::SoilModulus,
            DesignParameter::VesselOffset => Parameter::VesselOffset,
            DesignParameter::FlexJoint(_) => {
                let j = self.flex_joint(scene)?.1;
                match j {
                    0 => Parameter::BaseStiffness,
                    j if j == scene.beam.lengths.len() => Parameter::TipStiffness,
                    j => Parameter::JointStiffness(j),
                }
            }
        })
    }

    /// The index in `[[stackup.flex_joint]]` and the chain's joint of a flex joint's parameter.
    fn flex_joint(&self, scene: &Scene) -> Option<(usize, usize)> {
        let DesignParameter::FlexJoint(name) = self else {
            return None;
        };
        let st = scene.stackup.as_ref()?;
        let i = st.flex_joints.iter().position(|f| &f.name == name)?;
        Some((i, *st.layout.flex_joints.get(i)?))
    }

    /// The index in `[[stackup.segment]]` of a buoyancy diameter's segment (`None`: another
    /// parameter, or no segment of that name).
    pub fn segment(&self, scene: &Scene) -> Option<usize> {
        let DesignParameter::BuoyancyDiameter(name) = self else {
            return None;
        };
        let st = scene.stackup.as_ref()?;
        st.segments.iter().position(|s| &s.name == name)
    }

    /// The smallest value the parameter may take on the scene (its lower bound's floor): a
    /// segment's pipe outer diameter D_o for its buoyancy modules' diameter (modules thinner
    /// than the pipe are no modules); `None` for the others (positive, or any finite value for
    /// the signed ones).
    pub fn floor(&self, scene: &Scene) -> Option<f64> {
        let i = self.segment(scene)?;
        scene
            .stackup
            .as_ref()
            .map(|st| st.segments[i].outer_diameter)
    }

    /// The role it has when `[design]` does not say: the soil modulus is an uncertainty, the
    /// others are design choices.
    pub fn default_role(&self) -> Role {
        match self {
            DesignParameter::SoilModulus => Role::Uncertainty,
            _ => Role::Design,
        }
    }

    /// The scene's value of the parameter.
    ///
    /// # Errors
    /// Why the scene's model does not have it (no base or tip spring for its support, no
    /// tension, no `[soil]`).
    pub fn value(&self, scene: &Scene) -> Result<f64, &'static str> {
        let (base, tip) = scene.beam.support.end_springs();
        match self {
            DesignParameter::Tension if scene.loads.tension > 0.0 => Ok(scene.loads.tension),
            DesignParameter::Tension => Err("the scene has no top tension (loads.tension = 0)"),
            DesignParameter::BaseStiffness if base => Ok(scene.beam.base_stiffness),
            DesignParameter::TipStiffness if tip => Ok(scene.beam.tip_stiffness),
            DesignParameter::BaseStiffness | DesignParameter::TipStiffness => {
                Err("the support has no spring at that end")
            }
            DesignParameter::SoilModulus => scene
                .soil
                .map(|s| s.modulus)
                .ok_or("the scene has no [soil] table"),
            DesignParameter::VesselOffset if scene.beam.support != Support::Vessel => {
                Err("the top is not held by a vessel (beam.support = \"vessel\")")
            }
            DesignParameter::VesselOffset => {
                let v = scene.vessel.clone().unwrap_or_default();
                if v.ramp > 0.0 {
                    Ok(v.offset)
                } else {
                    Err(
                        "vessel.ramp = 0: a run starts from rest with the top at 0, so an offset \
                         needs a positive ramp to grow in over",
                    )
                }
            }
            DesignParameter::FlexJoint(_) => match self.flex_joint(scene) {
                Some((i, _)) => Ok(scene
                    .stackup
                    .as_ref()
                    .map_or(f64::NAN, |st| st.flex_joints[i].stiffness)),
                None => Err("the scene has no [[stackup.flex_joint]] of that name"),
            },
            DesignParameter::BuoyancyDiameter(_) => {
                let segment = self
                    .segment(scene)
                    .and_then(|i| scene.stackup.as_ref().map(|st| &st.segments[i]))
                    .ok_or("the scene has no [[stackup.segment]] of that name")?;
                match (segment.buoyancy_diameter, segment.buoyancy_density) {
                    (Some(d), Some(_)) => Ok(d),
                    _ => Err(
                        "the segment has no buoyancy modules (buoyancy_diameter and \
                         buoyancy_density): there is no module diameter to change",
                    ),
                }
            }
        }
    }

    /// Sets the parameter's value on the scene (the scene's model then has it: the chain is
    /// built from these fields; a flex joint's both in `[[stackup.flex_joint]]` and in the
    /// beam's spring at its joint; a segment's buoyancy diameter in the segment, the chain then
    /// laid out again, [`Scene::relayout_stackup`]). The value is not checked here
    /// ([`Scene::validate`] does) but for a buoyancy diameter, which the stack-up checks.
    ///
    /// # Errors
    /// A buoyancy diameter the stack-up refuses (smaller than the pipe's outer diameter, out of
    /// the diameters' range: [`SceneErrorKind::InvalidValue`] naming
    /// `stackup.segment[i].buoyancy_diameter`).
    pub fn set(&self, scene: &mut Scene, value: f64) -> Result<(), SceneError> {
        if let Some(i) = self.segment(scene) {
            if let Some(st) = scene.stackup.as_mut() {
                st.segments[i].buoyancy_diameter = Some(value);
            }
            return scene.relayout_stackup();
        }
        if let Some((i, j)) = self.flex_joint(scene) {
            if let Some(st) = scene.stackup.as_mut() {
                st.flex_joints[i].stiffness = value;
            }
            let n = scene.beam.lengths.len();
            match j {
                0 => scene.beam.base_stiffness = value,
                j if j == n => scene.beam.tip_stiffness = value,
                j => scene.beam.stiffness[j - 1] = value,
            }
            return Ok(());
        }
        match self {
            DesignParameter::Tension => scene.loads.tension = value,
            DesignParameter::BaseStiffness => scene.beam.base_stiffness = value,
            DesignParameter::TipStiffness => scene.beam.tip_stiffness = value,
            DesignParameter::SoilModulus => {
                if let Some(s) = scene.soil.as_mut() {
                    s.modulus = value;
                }
            }
            DesignParameter::VesselOffset => {
                scene.vessel.get_or_insert_with(Default::default).offset = value;
            }
            DesignParameter::FlexJoint(_) | DesignParameter::BuoyancyDiameter(_) => {}
        }
        Ok(())
    }
}

/// What a parameter of `[design]` is: optimised within its bounds, or an uncertainty whose
/// sensitivity alone is reported.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Role {
    /// A design choice: optimised within its bounds.
    Design,
    /// An uncertain property of the site (the soil): not optimised, its sensitivity reported.
    Uncertainty,
}

impl Role {
    /// `design` or `uncertainty`.
    pub fn name(self) -> &'static str {
        match self {
            Role::Design => "design",
            Role::Uncertainty => "uncertainty",
        }
    }

    /// The role of that name.
    pub fn from_name(name: &str) -> Option<Self> {
        [Role::Design, Role::Uncertainty]
            .into_iter()
            .find(|r| r.name() == name)
    }
}

/// One `[[design.parameter]]`: the parameter, its role, and its bounds (lower, upper) in its
/// unit for a design choice (`None` for an uncertainty).
#[derive(Clone, Debug, PartialEq)]
pub struct FreeParameter {
    /// The parameter.
    pub parameter: DesignParameter,
    /// Design choice or uncertainty.
    pub role: Role,
    /// (lower, upper), 0 < lower < upper, for a design choice.
    pub bounds: Option<(f64, f64)>,
}

/// The `[design]` table (docs/scene-format.md "\[design\]").
#[derive(Clone, Debug, PartialEq)]
pub struct DesignTable {
    /// The parameters, in the file's order.
    pub parameters: Vec<FreeParameter>,
    /// The optimiser's iteration limit (`max_iterations`, default
    /// [`DesignTable::DEFAULT_MAX_ITERATIONS`]).
    pub max_iterations: usize,
    /// Stop when the projected gradient's norm ‖P(u − ∇_u ln D_y) − u‖_∞ ≤ `tolerance`, u the
    /// parameters scaled to the unit box by the logarithms of their bounds ([`crate::design`],
    /// "The optimiser"; default [`DesignTable::DEFAULT_TOLERANCE`]).
    pub tolerance: f64,
    /// The `[[fatigue.hotspot]]` whose damage is the objective (`hotspot`, its `name`); `None`
    /// (the default): the chain's base, the wellhead moment of the adjoint's history term.
    pub hotspot: Option<String>,
}

impl DesignTable {
    /// The default iteration limit: each iteration costs a line search of one or a few
    /// scatter-diagram evaluations, and a handful of parameters converge in tens.
    pub const DEFAULT_MAX_ITERATIONS: usize = 30;
    /// The largest iteration limit.
    pub const MAX_ITERATIONS: usize = 1000;
    /// The default tolerance on the projected gradient's norm in the log-scaled unit box: a move
    /// of a free parameter across its whole range changes the life by less than about 0.01 %.
    pub const DEFAULT_TOLERANCE: f64 = 1e-4;

    /// The design choices (role [`Role::Design`]) with their bounds.
    pub fn design_choices(&self) -> Vec<(DesignParameter, (f64, f64))> {
        self.parameters
            .iter()
            .filter_map(|p| p.bounds.map(|b| (p.parameter.clone(), b)))
            .collect()
    }
}
