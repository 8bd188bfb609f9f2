//! A riser described as a pipe (`[pipe]`, `[water]`; docs/ocean.md "From a pipe to a chain",
//! docs/scene-format.md): the
//! chain's lengths, masses and spring constants from the pipe's section and materials.

use serde::{Deserialize, Serialize};
use std::f64::consts::PI;

use super::builder::assemble_beam;
use super::error::{SceneError, SceneErrorKind};
use super::validate::check_positive;
use super::values::NumOrArray;
use super::{Beam, Current, Support};

/// Default Young's modulus of steel E \[Pa\].
pub const STEEL_YOUNGS_MODULUS: f64 = 207e9;
/// Default density of steel ρ_s \[kg/m³\].
pub const STEEL_DENSITY: f64 = 7850.0;
/// Default density of sea water ρ_w \[kg/m³\].
pub const SEA_WATER_DENSITY: f64 = 1025.0;

/// A circular steel pipe (`[pipe]`): the physical description of a riser.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Pipe {
    /// Total length L \[m\] (the n pendulums have lᵢ = L/n).
    pub length: f64,
    /// Outer diameter D_o \[m\].
    pub outer_diameter: f64,
    /// Wall thickness t \[m\] (0 < t ≤ D_o/2; D_i = D_o − 2t).
    pub wall_thickness: f64,
    /// Young's modulus E \[Pa\] (default 207 GPa).
    #[serde(default = "default_e")]
    pub youngs_modulus: f64,
    /// Density of the pipe's steel ρ_s \[kg/m³\] (default 7850).
    #[serde(default = "default_steel")]
    pub steel_density: f64,
    /// Density of the contents ρ_c \[kg/m³\] (mud, oil, sea water; default 0: empty).
    #[serde(default)]
    pub contents_density: f64,
    /// Morison drag coefficient C_d (default 1.0), for the drag per unit length ½ ρ_w C_d D_o.
    #[serde(default = "default_one")]
    pub drag_coefficient: f64,
    /// Added-mass coefficient C_a (default 1.0): C_a ρ_w A_o joins the mass per unit length.
    #[serde(default = "default_one")]
    pub added_mass_coefficient: f64,
    /// How the water's drag acts on the chain (default [`DragModel::Momentum`]).
    #[serde(default, skip_serializing_if = "DragModel::is_momentum")]
    pub drag_model: DragModel,
}

/// How the water's drag acts on a pipe's chain (`[pipe] drag_model`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum DragModel {
    /// The thesis's momentum drag −Dᵢ|pᵢ − Pᵢ|(pᵢ − Pᵢ) per pendulum, with `[loads] drag` = D and
    /// the per-pendulum weights (docs/conventions.md "Drag in a current").
    #[default]
    Momentum,
    /// Morison's drag node by node, −½ ρ_w C_d D_o cₖ |v_r⊥| v_r⊥ on each node's velocity relative
    /// to the water over its cell (docs/conventions.md "Morison's drag node by node"); `[loads]
    /// drag` is not used (and must be 0).
    Morison,
}

impl DragModel {
    pub(super) fn is_momentum(&self) -> bool {
        *self == DragModel::Momentum
    }
}

fn default_e() -> f64 {
    STEEL_YOUNGS_MODULUS
}
fn default_steel() -> f64 {
    STEEL_DENSITY
}
fn default_one() -> f64 {
    1.0
}
fn default_water() -> f64 {
    SEA_WATER_DENSITY
}

/// The water around the beam (`[water]`): one depth for the current and the waves.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Water {
    /// Depth d \[m\]: the mean surface is at height y = d above the base (the seabed). `None`:
    /// not given (a current's surface then defaults to the beam's top).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub depth: Option<f64>,
    /// Density ρ_w \[kg/m³\] (default 1025, sea water).
    #[serde(default = "default_water")]
    pub density: f64,
}

impl Default for Water {
    fn default() -> Self {
        Water {
            depth: None,
            density: SEA_WATER_DENSITY,
        }
    }
}

impl Water {
    /// Whether this is the default (nothing to write in a scene file).
    pub fn is_default(&self) -> bool {
        *self == Water::default()
    }

    /// Checks `water.depth` and `water.density` (positive and finite).
    ///
    /// # Errors
    /// [`SceneError`] naming the key.
    pub fn check(&self) -> Result<(), SceneError> {
        if let Some(d) = self.depth {
            check_positive("water.depth", d)?;
        }
        check_positive("water.density", self.density)
    }
}

impl Pipe {
    /// A pipe of the given length, outer diameter and wall thickness, with the defaults above.
    pub fn new(length: f64, outer_diameter: f64, wall_thickness: f64) -> Self {
        Pipe {
            length,
            outer_diameter,
            wall_thickness,
            youngs_modulus: STEEL_YOUNGS_MODULUS,
            steel_density: STEEL_DENSITY,
            contents_density: 0.0,
            drag_coefficient: 1.0,
            added_mass_coefficient: 1.0,
            drag_model: DragModel::Momentum,
        }
    }

    /// Inner diameter D_i = D_o − 2t \[m\].
    pub fn inner_diameter(&self) -> f64 {
        self.outer_diameter - 2.0 * self.wall_thickness
    }

    /// Steel area A_s = π/4 (D_o² − D_i²) \[m²\].
    pub fn steel_area(&self) -> f64 {
        let (o, i) = (self.outer_diameter, self.inner_diameter());
        PI / 4.0 * (o * o - i * i)
    }

    /// Inner (contents) area A_i = π D_i²/4 \[m²\].
    pub fn inner_area(&self) -> f64 {
        let i = self.inner_diameter();
        PI / 4.0 * i * i
    }

    /// Outer (displaced) area A_o = π D_o²/4 \[m²\].
    pub fn outer_area(&self) -> f64 {
        PI / 4.0 * self.outer_diameter * self.outer_diameter
    }

    /// Second moment of area I = π/64 (D_o⁴ − D_i⁴) \[m⁴\].
    pub fn second_moment(&self) -> f64 {
        let (o, i) = (self.outer_diameter, self.inner_diameter());
        PI / 64.0 * (o * o * o * o - i * i * i * i)
    }

    /// Bending stiffness EI \[N m²\].
    pub fn bending_stiffness(&self) -> f64 {
        self.youngs_modulus * self.second_moment()
    }

    /// Mass per unit length with added mass, μ = ρ_s A_s + ρ_c A_i + C_a ρ_w A_o \[kg/m\].
    pub fn mass_per_length(&self, water_density: f64) -> f64 {
        self.steel_density * self.steel_area()
            + self.contents_density * self.inner_area()
            + self.added_mass_coefficient * water_density * self.outer_area()
    }

    /// Submerged weight per unit length w = g (ρ_s A_s + ρ_c A_i − ρ_w A_o) \[N/m\] (the value
    /// for `[loads] axial_weight`; docs/ocean.md "From a pipe to a chain").
    pub fn submerged_weight(&self, water_density: f64, g: f64) -> f64 {
        g * (self.steel_density * self.steel_area() + self.contents_density * self.inner_area()
            - water_density * self.outer_area())
    }

    /// Morison drag per unit length ½ ρ_w C_d D_o \[kg/m²\]: a node of cell length l moving at
    /// v relative to the water feels −½ ρ_w C_d D_o l |v| v (Morison's drag, docs/ocean.md).
    pub fn drag_per_length(&self, water_density: f64) -> f64 {
        0.5 * water_density * self.drag_coefficient * self.outer_diameter
    }

    /// Checks every value (positive and finite; 0 < t ≤ D_o/2; densities and coefficients
    /// non-negative).
    ///
    /// # Errors
    /// [`SceneError`] naming the `pipe.*` key.
    pub fn check(&self) -> Result<(), SceneError> {
        check_positive("pipe.length", self.length)?;
        check_positive("pipe.outer_diameter", self.outer_diameter)?;
        check_positive("pipe.wall_thickness", self.wall_thickness)?;
        if self.wall_thickness > 0.5 * self.outer_diameter {
            return Err(SceneError::invalid(
                "pipe.wall_thickness",
                format!(
                    "must be at most half the outer diameter ({} m), got {}",
                    0.5 * self.outer_diameter,
                    self.wall_thickness
                ),
            ));
        }
        check_positive("pipe.youngs_modulus", self.youngs_modulus)?;
        check_positive("pipe.steel_density", self.steel_density)?;
        for (key, v) in [
            ("pipe.contents_density", self.contents_density),
            ("pipe.drag_coefficient", self.drag_coefficient),
            ("pipe.added_mass_coefficient", self.added_mass_coefficient),
        ] {
            if !(v.is_finite() && v >= 0.0) {
                return Err(SceneError::invalid(
                    key,
                    format!("must be non-negative and finite, got {v}"),
                ));
            }
        }
        Ok(())
    }

    /// The chain of n pendulums of this pipe (docs/ocean.md "From a pipe to a chain"): lᵢ = L/n;
    /// node masses mᵢ = μ l and
    /// half a cell, μ l/2, at the tip (the lumping whose first frequency converges at order 2 in
    /// n, tests/model/pipe.rs); interior springs k = EI/l; a clamped end (the base of a cantilever,
    /// riser or fixed-fixed beam, the tip of a riser or fixed-fixed beam) 2EI/l unless
    /// `end_springs` = (base, tip) gives it (a flex joint).
    ///
    /// # Errors
    /// [`Pipe::check`]'s errors.
    pub fn beam(
        &self,
        n: usize,
        support: Support,
        water_density: f64,
        end_springs: (Option<f64>, Option<f64>),
    ) -> Result<Beam, SceneError> {
        self.check()?;
        let l = self.length / n as f64;
        let mu = self.mass_per_length(water_density);
        let k = self.bending_stiffness() / l;
        let mut masses = vec![mu * l; n];
        masses[n - 1] = 0.5 * mu * l;
        let clamp = |given: Option<f64>, clamped: bool| {
            given.unwrap_or(if clamped { 2.0 * k } else { 0.0 })
        };
        let (base, tip) = support.end_springs();
        Ok(Beam {
            lengths: vec![l; n],
            masses,
            stiffness: vec![k; n - 1],
            base_stiffness: clamp(end_springs.0, base),
            tip_stiffness: clamp(end_springs.1, tip),
            support,
            reaction_force: false,
            joint_damping: Vec::new(),
        })
    }
}

/// The per-pendulum factors of the momentum drag constant of a pipe's chain (docs/conventions.md
/// "Equivalent drag constant"): wᵢ = l₁S₁/(lᵢSᵢ) with Sᵢ = Σ_{k≥i} m_k the mass beyond joint i,
/// so that Dᵢ = D wᵢ. Under a uniform relative flow U, Morison's load on pendulum i (the
/// generalised force lᵢ Σ_{k≥i} ½ ρ_w C_d D_o c_k U² of the node loads on their cells
/// c_k = m_k/μ) is lᵢ ½ ρ_w C_d D_o (Sᵢ/μ) U², and the momentum drag Dᵢ (lᵢ Sᵢ U)² is
/// D l₁S₁ · lᵢSᵢ U²: the same share of it, D l₁S₁ μ/(½ ρ_w C_d D_o), on every pendulum. w₁ = 1
/// exactly. The weights depend on the discretisation only (lᵢ, mᵢ), not on D, which stays the one
/// parameter (∂Dᵢ/∂D = wᵢ).
pub fn drag_weights(lengths: &[f64], masses: &[f64]) -> Vec<f64> {
    let mut beyond = vec![0.0; masses.len()];
    let mut s = 0.0;
    for i in (0..masses.len()).rev() {
        s += masses[i];
        beyond[i] = lengths[i] * s;
    }
    let base = beyond.first().copied().unwrap_or(1.0);
    beyond.iter().map(|b| base / b).collect()
}

impl super::Scene {
    /// The per-pendulum factors wᵢ of the drag constant ([`drag_weights`]) for a scene built
    /// from `[pipe]` (from `[stackup]`: [`super::Stackup::drag_constants`]), `None` for a scene whose beam is given by its lengths and masses (one D on
    /// every pendulum, the thesis's eq. 2.4.4). Every reader of D (the model's drag terms, the
    /// statics through them, the scene check's load number, MPC's planning chain) takes them
    /// from here.
    pub fn drag_weights(&self) -> Option<Vec<f64>> {
        if let Some(st) = &self.stackup {
            let b = &self.beam;
            return Some(st.drag_constants(&b.lengths, &b.masses, self.mudline()).1);
        }
        self.pipe
            .map(|_| drag_weights(&self.beam.lengths, &self.beam.masses))
    }
}

/// The beam of a scene file: from `[pipe]`, or from `beam.length`, `beam.mass` and
/// `beam.stiffness` — one or the other, never both ([`SceneErrorKind::ExclusiveKeys`]).
pub(super) struct BeamKeys {
    pub n: usize,
    pub length: Option<NumOrArray>,
    pub mass: Option<NumOrArray>,
    pub stiffness: Option<NumOrArray>,
    pub end_springs: (Option<f64>, Option<f64>),
    pub support: Support,
    pub reaction_force: bool,
}

impl BeamKeys {
    /// Builds the beam (see [`BeamKeys`]).
    pub(super) fn into_beam(self, pipe: Option<&Pipe>, water: &Water) -> Result<Beam, SceneError> {
        let given = [
            ("beam.length", self.length.is_some()),
            ("beam.mass", self.mass.is_some()),
            ("beam.stiffness", self.stiffness.is_some()),
        ];
        if let Some(pipe) = pipe {
            if let Some((key, _)) = given.iter().find(|(_, g)| *g) {
                return Err(SceneError::new(SceneErrorKind::ExclusiveKeys {
                    key: (*key).to_string(),
                    other: "pipe".to_string(),
                    note: "the pipe's description gives the lengths, masses and spring \
                           constants; give either `[pipe]` or `beam.length`, `beam.mass` and \
                           `beam.stiffness`"
                        .to_string(),
                }));
            }
            water.check()?;
            let mut beam = pipe.beam(self.n, self.support, water.density, self.end_springs)?;
            beam.reaction_force = self.reaction_force;
            return Ok(beam);
        }
        match (self.length, self.mass, self.stiffness) {
            (Some(l), Some(m), Some(k)) => assemble_beam(
                self.n,
                l,
                m,
                k,
                self.end_springs,
                self.support,
                self.reaction_force,
            ),
            _ => {
                let (key, _) = given.iter().find(|(_, g)| !*g).expect("one is missing");
                Err(SceneError::new(SceneErrorKind::MissingKey {
                    key: (*key).to_string(),
                    note: Some("or describe the beam as a pipe in `[pipe]`".to_string()),
                }))
            }
        }
    }
}

/// One water depth for the current and the waves: a current without a `surface` takes
/// `water.depth`; a current whose `surface` differs from it is refused.
///
/// # Errors
/// [`SceneErrorKind::ExclusiveKeys`] naming `loads.current.surface`.
pub(super) fn reconcile_surface(
    water: &Water,
    current: Option<&mut Current>,
) -> Result<(), SceneError> {
    let (Some(depth), Some(c)) = (water.depth, current) else {
        return Ok(());
    };
    match c.surface {
        None => c.surface = Some(depth),
        Some(s) if s.to_bits() != depth.to_bits() => {
            return Err(SceneError::new(SceneErrorKind::ExclusiveKeys {
                key: "loads.current.surface".to_string(),
                other: "water.depth".to_string(),
                note: format!(
                    "the surface at {s} m disagrees with the water depth {depth} m; the current \
                     and the waves share one depth: give it once, as `[water] depth`"
                ),
            }))
        }
        Some(_) => {}
    }
    Ok(())
}
