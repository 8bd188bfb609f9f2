//! A riser system described from the bottom up (`[stackup]`, docs/scene-format.md "[stackup]";
//! docs/conventions.md "The stack-up"): segments of pipe (conductor, wellhead, riser joints with
//! auxiliary lines and buoyancy), rigid lumped bodies (BOP, LMRP) and rotational springs at named
//! places (flex joints), turned into the chain's lengths, masses and spring constants and into the
//! per-node loads the model's terms read (submerged weight, Morison drag and inertia
//! coefficients).
//!
//! The chain runs from the foot of the lowest segment (node 0, y = 0) upward. Pendulum ends fall
//! on every segment's end, every body's ends, every flex joint and the mudline (`[soil] mudline`);
//! between them the pipe pieces share the rest of `beam.pendulums` in proportion to their length
//! times their segment's `refinement` (default 1; largest remainders, at least one each). A body is one pendulum: rigid within itself, its mass,
//! weight and drag split half to each end node.

use serde::{Deserialize, Serialize};
use std::f64::consts::PI;

use super::error::{SceneError, SceneErrorKind};
use super::ranges::{check_range, stackup_ranges, StackupRange};
use super::{Beam, DragModel, Support};

mod buoyancy;
mod pieces;

pub use buoyancy::NodeTangents;
use pieces::{allocate, nearest, split, Piece};

/// Standard gravity g \[m/s²\] of the stack-up's weights (ISO 80000-3).
pub const STANDARD_GRAVITY: f64 = 9.80665;

/// How the chain's foot (node 0, the lowest segment's bottom) is held.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Foot {
    /// Held in place and in direction: the base spring is 2 EI/l of the first pendulum (a pile
    /// fixed at a fixity depth).
    #[default]
    Clamped,
    /// Held in place, free to turn (no base spring): with soil springs all the way down, a pile
    /// whose foot lies deep enough to carry no moment.
    Pinned,
}

fn steel_e() -> f64 {
    super::STEEL_YOUNGS_MODULUS
}
fn steel_rho() -> f64 {
    super::STEEL_DENSITY
}
fn one() -> f64 {
    1.0
}
fn one_joint() -> u32 {
    1
}
fn is_zero(x: &f64) -> bool {
    x.to_bits() == 0
}
fn is_one(x: &f64) -> bool {
    x.to_bits() == 1f64.to_bits()
}
fn is_one_joint(x: &u32) -> bool {
    *x == 1
}

/// A run of identical pipe joints (`[[stackup.segment]]`), from the bottom up in file order.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Segment {
    /// The segment's name (unique in the stack-up; bodies and flex joints refer to it).
    pub name: String,
    /// Length of one joint \[m\].
    pub length: f64,
    /// Number of identical joints (default 1): the segment is `joints` × `length` long.
    #[serde(default = "one_joint", skip_serializing_if = "is_one_joint")]
    pub joints: u32,
    /// Outer diameter of the steel pipe D_o \[m\].
    pub outer_diameter: f64,
    /// Wall thickness t \[m\] (0 < t ≤ D_o/2).
    pub wall_thickness: f64,
    /// Young's modulus E \[Pa\] (default 207 GPa).
    #[serde(default = "steel_e")]
    pub youngs_modulus: f64,
    /// Density of the steel ρ_s \[kg/m³\] (default 7850).
    #[serde(default = "steel_rho")]
    pub steel_density: f64,
    /// Density of the contents ρ_c \[kg/m³\] (mud, sea water, cement; default 0).
    #[serde(default, skip_serializing_if = "is_zero")]
    pub contents_density: f64,
    /// Mass of the auxiliary lines (choke, kill, booster, hydraulic) per length, in air, with
    /// their contents \[kg/m\] (default 0).
    #[serde(default, skip_serializing_if = "is_zero")]
    pub line_mass: f64,
    /// The auxiliary lines' displaced cross-section (their outer areas) \[m²\] (default 0).
    #[serde(default, skip_serializing_if = "is_zero")]
    pub line_area: f64,
    /// Outer diameter of the buoyancy modules \[m\] (with `buoyancy_density`; none by default).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub buoyancy_diameter: Option<f64>,
    /// Density of the buoyancy modules' foam \[kg/m³\] (with `buoyancy_diameter`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub buoyancy_density: Option<f64>,
    /// Diameter of the Morison drag and inertia loads \[m\] (default: the buoyancy's if any, else
    /// D_o).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub hydrodynamic_diameter: Option<f64>,
    /// Morison drag coefficient C_d (default 1.0).
    #[serde(default = "one", skip_serializing_if = "is_one")]
    pub drag_coefficient: f64,
    /// Added-mass coefficient C_a (default 1.0).
    #[serde(default = "one", skip_serializing_if = "is_one")]
    pub added_mass_coefficient: f64,
    /// Relative density of pendulums r (default 1): the pipe pieces share `beam.pendulums` in
    /// proportion to length × r, so a segment with r = 2 gets pendulums half as long as one with
    /// r = 1 (shorter pendulums where the moment varies fast, longer ones in uniform joints).
    #[serde(default = "one", skip_serializing_if = "is_one")]
    pub refinement: f64,
}

/// A rigid lumped body (`[[stackup.body]]`): BOP, LMRP, a wellhead housing modelled as a mass.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Body {
    /// The body's name (unique in the stack-up).
    pub name: String,
    /// The segment it stands on (bodies naming the same segment stack in file order).
    pub above: String,
    /// Mass in air \[kg\].
    pub mass: f64,
    /// Submerged weight \[N\] (its weight less its buoyancy, downward positive).
    pub submerged_weight: f64,
    /// Height \[m\]: the body's pendulum length.
    pub height: f64,
    /// Drag area C_d A \[m²\] against a flow across it (default 0).
    #[serde(default, skip_serializing_if = "is_zero")]
    pub drag_area: f64,
    /// Hydrodynamic added mass \[kg\] (default 0).
    #[serde(default, skip_serializing_if = "is_zero")]
    pub added_mass: f64,
    /// Bending stiffness EI \[N·m²\] of the body's half-lengths in the springs at its ends
    /// (default: 10 × the stiffest segment's EI: rigid against the pipe).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub bending_stiffness: Option<f64>,
}

/// A rotational spring at a named place (`[[stackup.flex_joint]]`): the lower or upper flex
/// joint, a ball joint. Its stiffness replaces the joint spring the pipe would give there.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct FlexJoint {
    /// The flex joint's name.
    pub name: String,
    /// Rotational stiffness \[N·m/rad\].
    pub stiffness: f64,
    /// The segment or body on whose top it sits (or give `elevation`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub above: Option<String>,
    /// Its height above the chain's foot \[m\] (or give `above`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub elevation: Option<f64>,
}

/// The stack-up (`[stackup]`): its description as written, and the layout on the chain computed
/// from it ([`Layout`]).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Stackup {
    /// How the foot is held (default clamped).
    #[serde(default)]
    pub foot: Foot,
    /// How the water's drag acts (`[stackup] drag_model`, default [`DragModel::Momentum`]):
    /// the momentum drag per pendulum from the segments' coefficients, or Morison's drag node by
    /// node with each node's own ½ ρ_w C_d D_h over its wet cell and the bodies' ½ ρ_w C_dA.
    #[serde(default, skip_serializing_if = "DragModel::is_momentum")]
    pub drag_model: DragModel,
    /// The segments, from the bottom up.
    #[serde(rename = "segment")]
    pub segments: Vec<Segment>,
    /// The bodies.
    #[serde(default, rename = "body", skip_serializing_if = "Vec::is_empty")]
    pub bodies: Vec<Body>,
    /// The flex joints.
    #[serde(default, rename = "flex_joint", skip_serializing_if = "Vec::is_empty")]
    pub flex_joints: Vec<FlexJoint>,
    /// The layout on the chain (computed, not written).
    #[serde(skip)]
    pub layout: Layout,
}

/// The stack-up on the chain: per node (1..=n as 0..n) the loads the model's terms read, and per
/// pendulum the part it belongs to.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Layout {
    /// The name of the segment or body of each pendulum.
    pub parts: Vec<String>,
    /// Submerged weight carried by each node \[N\] (half of each adjacent pendulum's).
    pub node_weights: Vec<f64>,
    /// Morison drag coefficient of each node, ½ ρ_w C_d D_h over its wet cell (pipes) and
    /// ½ ρ_w C_d A / 2 (each end of a body) \[kg/m\]: a flow U across it loads it with F U².
    pub node_drag: Vec<f64>,
    /// Inertia coefficient of each node, ρ_w (1 + C_a) π D_h²/4 over its wet cell \[kg\] (bodies:
    /// none).
    pub node_inertia: Vec<f64>,
    /// The bending stiffness EI of each pendulum \[N·m²\].
    pub bending_stiffness: Vec<f64>,
    /// The joint of each flex joint, in `[[stackup.flex_joint]]`'s order: 0 the base spring,
    /// n the tip spring, 1..n − 1 the spring between pendulums j and j + 1 (the beam's
    /// `stiffness[j − 1]`).
    pub flex_joints: Vec<usize>,
}

impl Segment {
    fn key(i: usize, k: &str) -> String {
        format!("stackup.segment[{i}].{k}")
    }

    fn inner_diameter(&self) -> f64 {
        self.outer_diameter - 2.0 * self.wall_thickness
    }

    /// Bending stiffness E π/64 (D_o⁴ − D_i⁴) \[N·m²\].
    pub fn bending_stiffness(&self) -> f64 {
        let (o, i) = (self.outer_diameter, self.inner_diameter());
        self.youngs_modulus * PI / 64.0 * (o.powi(4) - i.powi(4))
    }

    /// Mass per length in air \[kg/m\]: steel, contents, buoyancy foam and auxiliary lines.
    pub fn mass_in_air(&self) -> f64 {
        let (o, i) = (self.outer_diameter, self.inner_diameter());
        let foam = match (self.buoyancy_diameter, self.buoyancy_density) {
            (Some(b), Some(rho)) => rho * PI / 4.0 * (b * b - o * o),
            _ => 0.0,
        };
        self.steel_density * PI / 4.0 * (o * o - i * i)
            + self.contents_density * PI / 4.0 * i * i
            + foam
            + self.line_mass
    }

    /// The displaced cross-section \[m²\]: the pipe's (or the buoyancy's) outer area and the
    /// lines'.
    pub fn displaced_area(&self) -> f64 {
        let d = self
            .buoyancy_diameter
            .unwrap_or(0.0)
            .max(self.outer_diameter);
        PI / 4.0 * d * d + self.line_area
    }

    /// The diameter of the Morison loads \[m\].
    pub fn hydrodynamic(&self) -> f64 {
        self.hydrodynamic_diameter
            .or(self.buoyancy_diameter)
            .unwrap_or(self.outer_diameter)
    }

    /// Submerged weight per length g (m_air − ρ_w A_displaced) \[N/m\].
    pub fn submerged_weight(&self, water_density: f64) -> f64 {
        STANDARD_GRAVITY * (self.mass_in_air() - water_density * self.displaced_area())
    }

    /// Checks the segment's values (key `stackup.segment[i].…`).
    fn check(&self, i: usize) -> Result<(), SceneError> {
        let r = stackup_ranges();
        let key = |k: &str| Self::key(i, k);
        if self.name.is_empty() {
            return Err(SceneError::invalid(key("name"), "must not be empty"));
        }
        check_range(
            &key("length"),
            self.length,
            &r[StackupRange::Length as usize],
        )?;
        if !(1..=1_000_000).contains(&self.joints) {
            return Err(SceneError::invalid(
                key("joints"),
                format!("must be 1 to 1000000, got {}", self.joints),
            ));
        }
        let dia = &r[StackupRange::Diameter as usize];
        check_range(&key("outer_diameter"), self.outer_diameter, dia)?;
        check_range(&key("wall_thickness"), self.wall_thickness, dia)?;
        if self.wall_thickness > 0.5 * self.outer_diameter {
            return Err(SceneError::invalid(
                key("wall_thickness"),
                format!(
                    "must be at most half the outer diameter ({} m), got {}",
                    0.5 * self.outer_diameter,
                    self.wall_thickness
                ),
            ));
        }
        let modulus = &r[StackupRange::Modulus as usize];
        check_range(&key("youngs_modulus"), self.youngs_modulus, modulus)?;
        let density = &r[StackupRange::Density as usize];
        check_range(&key("steel_density"), self.steel_density, density)?;
        check_range(&key("contents_density"), self.contents_density, density)?;
        let line = &r[StackupRange::LineMass as usize];
        check_range(&key("line_mass"), self.line_mass, line)?;
        let area = &r[StackupRange::Area as usize];
        check_range(&key("line_area"), self.line_area, area)?;
        match (self.buoyancy_diameter, self.buoyancy_density) {
            (Some(b), Some(rho)) => {
                check_range(&key("buoyancy_diameter"), b, dia)?;
                check_range(&key("buoyancy_density"), rho, density)?;
                if b < self.outer_diameter {
                    return Err(SceneError::invalid(
                        key("buoyancy_diameter"),
                        format!(
                            "the modules' outer diameter {b} m is smaller than the pipe's {} m",
                            self.outer_diameter
                        ),
                    ));
                }
            }
            (None, None) => {}
            (Some(_), None) => return Err(missing(key("buoyancy_density"), "buoyancy_diameter")),
            (None, Some(_)) => return Err(missing(key("buoyancy_diameter"), "buoyancy_density")),
        }
        if let Some(d) = self.hydrodynamic_diameter {
            check_range(&key("hydrodynamic_diameter"), d, dia)?;
        }
        let coefficient = &r[StackupRange::Coefficient as usize];
        check_range(&key("drag_coefficient"), self.drag_coefficient, coefficient)?;
        check_range(
            &key("added_mass_coefficient"),
            self.added_mass_coefficient,
            coefficient,
        )?;
        check_range(
            &key("refinement"),
            self.refinement,
            &r[StackupRange::Refinement as usize],
        )
    }
}

fn missing(key: String, with: &str) -> SceneError {
    SceneErrorKind::MissingKey {
        key,
        note: Some(format!("required with `{with}`")),
    }
    .into()
}

impl Body {
    fn check(&self, i: usize) -> Result<(), SceneError> {
        let r = stackup_ranges();
        let key = |k: &str| format!("stackup.body[{i}].{k}");
        if self.name.is_empty() {
            return Err(SceneError::invalid(key("name"), "must not be empty"));
        }
        check_range(&key("mass"), self.mass, &r[StackupRange::BodyMass as usize])?;
        let added = &r[StackupRange::AddedMass as usize];
        check_range(&key("added_mass"), self.added_mass, added)?;
        let weight = &r[StackupRange::BodyWeight as usize];
        check_range(&key("submerged_weight"), self.submerged_weight, weight)?;
        check_range(
            &key("height"),
            self.height,
            &r[StackupRange::Length as usize],
        )?;
        check_range(
            &key("drag_area"),
            self.drag_area,
            &r[StackupRange::Area as usize],
        )?;
        if let Some(ei) = self.bending_stiffness {
            check_range(&key("bending_stiffness"), ei, &r[StackupRange::Ei as usize])?;
        }
        Ok(())
    }
}

impl Stackup {
    /// The parts from the bottom up: each segment followed by the bodies standing on it, as
    /// (name, index into segments or bodies, is a body).
    fn order(&self) -> Result<Vec<(usize, bool)>, SceneError> {
        let mut names = std::collections::HashSet::new();
        for (i, s) in self.segments.iter().enumerate() {
            if !names.insert(s.name.as_str()) {
                let key = format!("stackup.segment[{i}].name");
                return Err(duplicate(key, &s.name));
            }
        }
        for (i, b) in self.bodies.iter().enumerate() {
            if !names.insert(b.name.as_str()) {
                return Err(duplicate(format!("stackup.body[{i}].name"), &b.name));
            }
            if !self.segments.iter().any(|s| s.name == b.above) {
                return Err(SceneError::invalid(
                    format!("stackup.body[{i}].above"),
                    format!("names no segment: `{}`", b.above),
                ));
            }
        }
        let mut order = Vec::new();
        for (i, s) in self.segments.iter().enumerate() {
            order.push((i, false));
            for (j, b) in self.bodies.iter().enumerate() {
                if b.above == s.name {
                    order.push((j, true));
                }
            }
        }
        Ok(order)
    }

    /// The chain of `n` pendulums of this stack-up (module docs) for the support, the water's
    /// density and the mudline's height; fills [`Stackup::layout`].
    ///
    /// # Errors
    /// [`SceneError`] naming the `stackup.*` key, `beam.support` (riser, vessel or cantilever) or
    /// `beam.pendulums` (fewer than the stack-up's pieces).
    pub fn beam(
        &mut self,
        n: usize,
        support: Support,
        water_density: f64,
        mudline: f64,
    ) -> Result<Beam, SceneError> {
        if !matches!(
            support,
            Support::Riser | Support::Cantilever | Support::Vessel
        ) {
            return Err(SceneError::invalid(
                "beam.support",
                "a stack-up stands on its foot: support `riser` (held at the top by a spring), \
                 `vessel` (the top held by the vessel, through the upper flex joint) or \
                 `cantilever` (free top)",
            ));
        }
        if self.segments.is_empty() {
            return Err(SceneErrorKind::MissingKey {
                key: "stackup.segment".into(),
                note: Some("a stack-up has at least one segment".into()),
            }
            .into());
        }
        self.segments
            .iter()
            .enumerate()
            .try_for_each(|(i, s)| s.check(i))?;
        self.bodies
            .iter()
            .enumerate()
            .try_for_each(|(i, b)| b.check(i))?;
        let order = self.order()?;
        let stiffest = self
            .segments
            .iter()
            .map(Segment::bending_stiffness)
            .fold(0.0, f64::max);
        let mut parts = Vec::new();
        for &(i, body) in &order {
            parts.push(self.part(i, body, water_density, stiffest));
        }
        let total: f64 = parts.iter().map(|p| p.length).sum();
        let (cuts, springs) = self.cuts(&parts, total, mudline)?;
        let pieces = split(&parts, &cuts)?;
        let counts = allocate(n, &pieces)?;
        Ok(self.assemble(&pieces, &counts, &springs, support, mudline))
    }

    fn part(&self, i: usize, body: bool, rho_w: f64, stiffest: f64) -> Piece {
        if body {
            let b = &self.bodies[i];
            let m = b.mass + b.added_mass;
            return Piece {
                part: self.segments.len() + i,
                refinement: 1.0,
                length: b.height,
                mu: m / b.height,
                w: b.submerged_weight / b.height,
                drag: 0.5 * rho_w * b.drag_area / b.height,
                inertia: 0.0,
                ei: b.bending_stiffness.unwrap_or(10.0 * stiffest),
                body: true,
            };
        }
        let s = &self.segments[i];
        let dh = s.hydrodynamic();
        let area = PI / 4.0 * dh * dh;
        Piece {
            part: i,
            refinement: s.refinement,
            length: s.length * f64::from(s.joints),
            mu: s.mass_in_air() + s.added_mass_coefficient * rho_w * area,
            w: s.submerged_weight(rho_w),
            drag: 0.5 * rho_w * s.drag_coefficient * dh,
            inertia: rho_w * (1.0 + s.added_mass_coefficient) * area,
            ei: s.bending_stiffness(),
            body: false,
        }
    }

    fn part_name(&self, part: usize) -> &str {
        match part.checked_sub(self.segments.len()) {
            Some(j) => &self.bodies[j].name,
            None => &self.segments[part].name,
        }
    }

    /// The heights where pendulum ends are forced (part ends, flex joints, the mudline), sorted,
    /// and the flex joints' springs as (height, stiffness).
    #[allow(clippy::type_complexity)]
    fn cuts(
        &self,
        parts: &[Piece],
        total: f64,
        mudline: f64,
    ) -> Result<(Vec<f64>, Vec<(f64, f64)>), SceneError> {
        let mut tops = Vec::with_capacity(parts.len());
        let mut y = 0.0;
        for p in parts {
            y += p.length;
            tops.push(y);
        }
        let mut cuts = tops.clone();
        if mudline > 0.0 && mudline < total {
            cuts.push(mudline);
        }
        let mut springs = Vec::new();
        let r = stackup_ranges();
        for (i, f) in self.flex_joints.iter().enumerate() {
            let key = |k: &str| format!("stackup.flex_joint[{i}].{k}");
            check_range(
                &key("stiffness"),
                f.stiffness,
                &r[StackupRange::Rotational as usize],
            )?;
            let at = match (&f.above, f.elevation) {
                (Some(name), None) => {
                    let k = parts.iter().position(|p| self.part_name(p.part) == name);
                    match k {
                        Some(k) => tops[k],
                        None => {
                            return Err(SceneError::invalid(
                                key("above"),
                                format!("names no segment or body: `{name}`"),
                            ))
                        }
                    }
                }
                (None, Some(e)) => {
                    check_range(&key("elevation"), e, &r[StackupRange::Elevation as usize])?;
                    if e > total * (1.0 + 1e-12) {
                        return Err(SceneError::invalid(
                            key("elevation"),
                            format!("lies above the stack-up's top ({total} m), got {e}"),
                        ));
                    }
                    e
                }
                (Some(_), Some(_)) => {
                    return Err(SceneErrorKind::ExclusiveKeys {
                        key: key("elevation"),
                        other: key("above"),
                        note: "place the flex joint by one of them".into(),
                    }
                    .into())
                }
                (None, None) => {
                    return Err(SceneErrorKind::MissingKey {
                        key: key("above"),
                        note: Some("or `elevation`: where the flex joint sits".into()),
                    }
                    .into())
                }
            };
            cuts.push(at);
            springs.push((at, f.stiffness));
        }
        cuts.sort_by(f64::total_cmp);
        cuts.dedup_by(|a, b| (*a - *b).abs() <= 1e-9 * total.max(1.0));
        Ok((cuts, springs))
    }

    /// The chain from the pieces and their pendulum counts; fills the layout.
    fn assemble(
        &mut self,
        pieces: &[Piece],
        counts: &[usize],
        springs: &[(f64, f64)],
        support: Support,
        mudline: f64,
    ) -> Beam {
        let mut pend: Vec<&Piece> = Vec::new();
        let mut lengths = Vec::new();
        for (p, &c) in pieces.iter().zip(counts) {
            for _ in 0..c {
                pend.push(p);
                lengths.push(p.length / c as f64);
            }
        }
        let n = lengths.len();
        // Node i (0-based, the end of pendulum i) takes half of pendulum i and half of i + 1.
        let mut masses = vec![0.0; n];
        let mut layout = Layout {
            parts: pend
                .iter()
                .map(|p| self.part_name(p.part).to_string())
                .collect(),
            node_weights: vec![0.0; n],
            node_drag: vec![0.0; n],
            node_inertia: vec![0.0; n],
            bending_stiffness: pend.iter().map(|p| p.ei).collect(),
            flex_joints: Vec::with_capacity(springs.len()),
        };
        let mut y = 0.0;
        for (j, (p, &l)) in pend.iter().zip(&lengths).enumerate() {
            let wet = y + 0.5 * l > mudline;
            y += l;
            for node in [j.checked_sub(1), Some(j)].into_iter().flatten() {
                masses[node] += 0.5 * p.mu * l;
                layout.node_weights[node] += 0.5 * p.w * l;
                if wet {
                    layout.node_drag[node] += 0.5 * p.drag * l;
                    layout.node_inertia[node] += 0.5 * p.inertia * l;
                }
            }
        }
        // Joint j (0..=n, between pendulums j and j + 1): the two half-pendulums in series, or
        // a flex joint's spring.
        let half = |j: usize| lengths[j] / (2.0 * pend[j].ei);
        let mut stiffness: Vec<f64> = (1..n).map(|j| 1.0 / (half(j - 1) + half(j))).collect();
        let mut base = match self.foot {
            Foot::Clamped => 1.0 / half(0),
            Foot::Pinned => 0.0,
        };
        let mut tip = match support {
            Support::Riser | Support::Vessel => 1.0 / half(n - 1),
            _ => 0.0,
        };
        let mut y = 0.0;
        let mut joint_heights = vec![0.0];
        for l in &lengths {
            y += l;
            joint_heights.push(y);
        }
        for &(at, k) in springs {
            let j = nearest(&joint_heights, at);
            layout.flex_joints.push(j);
            match j {
                0 => base = k,
                j if j == n => tip = k,
                j => stiffness[j - 1] = k,
            }
        }
        self.layout = layout;
        Beam {
            lengths,
            masses,
            stiffness,
            base_stiffness: base,
            tip_stiffness: tip,
            support,
            reaction_force: false,
            joint_damping: Vec::new(),
        }
    }

    /// The per-pendulum factors wᵢ = Dᵢ/D₁ of the momentum drag (docs/conventions.md "The
    /// stack-up's drag"): Dᵢ = Σ_{k≥i} F_k / (lᵢ Sᵢ²) with F_k the node drag coefficients and
    /// Sᵢ the mass of the wet nodes beyond joint i, so that a uniform flow U gives pendulum i the
    /// Morison load lᵢ Σ_{k≥i} F_k U²; and D₁ itself.
    pub fn drag_constants(&self, lengths: &[f64], masses: &[f64], mudline: f64) -> (f64, Vec<f64>) {
        let n = lengths.len();
        let mut y: Vec<f64> = Vec::with_capacity(n);
        let mut acc = 0.0;
        for l in lengths {
            acc += l;
            y.push(acc);
        }
        let mut d = vec![0.0; n];
        let (mut f, mut s) = (0.0, 0.0);
        for i in (0..n).rev() {
            // A layout not computed for this chain (a scene assembled in code) has no drag.
            f += self.layout.node_drag.get(i).copied().unwrap_or(0.0);
            if super::soil::water_height(mudline, y[i]).is_some() {
                s += masses[i];
            }
            d[i] = if s > 0.0 {
                f / (lengths[i] * s * s)
            } else {
                0.0
            };
        }
        let d1 = d[0];
        let w = d
            .iter()
            .map(|&x| if d1 > 0.0 { x / d1 } else { 1.0 })
            .collect();
        (d1, w)
    }
}

fn duplicate(key: String, name: &str) -> SceneError {
    SceneError::invalid(
        key,
        format!("the name `{name}` is given twice in the stack-up"),
    )
}

impl super::pipe::BeamKeys {
    /// The beam of a scene with `[stackup]` ([`Stackup::beam`]); the keys that would give the
    /// same quantities another way are refused: `[pipe]`, `beam.length`, `beam.mass`,
    /// `beam.stiffness`, `beam.base_stiffness`, `beam.tip_stiffness` (the foot and the flex
    /// joints give the end springs), `beam.reaction_force`, and a nonzero `loads.drag` or
    /// `loads.axial_weight` (`loads` = (drag, axial weight): the stack-up's coefficients and
    /// weights give them).
    ///
    /// # Errors
    /// [`SceneErrorKind::ExclusiveKeys`] naming the key; [`Stackup::beam`]'s errors.
    pub(super) fn into_stackup_beam(
        self,
        stackup: &mut Stackup,
        pipe: bool,
        (drag, axial_weight): (f64, f64),
        water: &super::Water,
        mudline: f64,
    ) -> Result<Beam, SceneError> {
        let given = [
            ("pipe", pipe),
            ("beam.length", self.length.is_some()),
            ("beam.mass", self.mass.is_some()),
            ("beam.stiffness", self.stiffness.is_some()),
            ("beam.base_stiffness", self.end_springs.0.is_some()),
            ("beam.tip_stiffness", self.end_springs.1.is_some()),
            ("beam.reaction_force", self.reaction_force),
            ("loads.drag", drag != 0.0),
            ("loads.axial_weight", axial_weight != 0.0),
        ];
        if let Some((key, _)) = given.iter().find(|(_, g)| *g) {
            return Err(SceneErrorKind::ExclusiveKeys {
                key: (*key).to_string(),
                other: "stackup".to_string(),
                note: "the stack-up gives the lengths, masses, spring constants (the foot and \
                       the flex joints the end springs), the submerged weight and the drag; \
                       give either `[stackup]` or the beam's own keys"
                    .to_string(),
            }
            .into());
        }
        water.check()?;
        stackup.beam(self.n, self.support, water.density, mudline)
    }
}
