//! Validation of a [`Scene`]: value ranges, counts, nodes, the step numbers and the size limits
//! (docs/scene-format.md, "Valid ranges" and "Size limits").

use super::values::{to_i64, NumOrArray};
use super::{Control, ControlKind, PointLoad, Scene, SceneError, SceneErrorKind, Support};
use crate::base::StepStats;
use crate::input::human_bytes;

/// Largest number of pendulums n a scene may have.
pub const MAX_PENDULUMS: usize = 1_000_000;
/// Largest number of time steps N a scene may have.
pub const MAX_STEPS: usize = 10_000_000;
/// Memory budget of a stored trajectory: 8 GiB, a third of a 24 GiB machine (the rest is left
/// for the operating system, the optimiser's vectors and the output). It is checked where a
/// trajectory is stored, not when a scene is read (a streamed run, [`crate::simulate_streaming`],
/// stores none): a scene whose planar `f64` trajectory ([`trajectory_bytes`]) needs more is
/// refused by [`Scene::check_stored_trajectory`] naming `time.steps`, which
/// [`crate::simulate()`] and [`crate::ControlProblem`] call, and
/// [`crate::simulate::simulate_chain`] checks every scalar type and dimension against the same
/// budget and allocates fallibly.
pub const MAX_TRAJECTORY_BYTES: u64 = 8 << 30;
/// Largest step number h²·k/(m·l²) (springs) and h²·F·l/(m·l²) (loads) a scene may have: the
/// dimensionless angle one step turns a pendulum through. RATTLE resolves the motion only when
/// it is well below 1 (its Newton solve fails long before 10¹²); the limit keeps every quantity
/// the step forms far inside the `f64` range, so a valid scene cannot overflow.
pub const MAX_STEP_NUMBER: f64 = 1e12;

/// A supported closed range of a physical value, with its unit.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ValueRange {
    /// Smallest allowed value.
    pub min: f64,
    /// Largest allowed value.
    pub max: f64,
    /// SI unit, for messages.
    pub unit: &'static str,
    /// What goes wrong outside the range, for messages.
    why: &'static str,
}

impl ValueRange {
    /// Whether `x` lies in [min, max] (NaN does not).
    pub fn contains(&self, x: f64) -> bool {
        self.min <= x && x <= self.max
    }
}

/// Pendulum lengths lᵢ \[m\]: 10⁻⁶ to 10⁶ m.
pub const LENGTH_RANGE: ValueRange = ValueRange {
    min: 1e-6,
    max: 1e6,
    unit: "m",
    why: "1/(m·l²) enters the inverse mass matrix and F·l the generalised force",
};
/// Point masses mᵢ \[kg\]: 10⁻¹² to 10¹² kg.
pub const MASS_RANGE: ValueRange = ValueRange {
    min: 1e-12,
    max: 1e12,
    unit: "kg",
    why: "1/(m·l²) enters the inverse mass matrix",
};
/// Spring constants kᵢ (interior, base, tip) \[N·m/rad\]: 0 to 10¹⁵.
pub const STIFFNESS_RANGE: ValueRange = ValueRange {
    min: 0.0,
    max: 1e15,
    unit: "N·m/rad",
    why: "h²·k/(m·l²) is the step's spring number",
};
/// Joint dampers c \[N·m·s/rad\] (`[beam] joint_damping`): 0 to 10¹⁵ N·m·s/rad.
pub const JOINT_DAMPING_RANGE: ValueRange = ValueRange {
    min: 0.0,
    max: 1e15,
    unit: "N·m·s/rad",
    why: "h·c/(m·l²) is the step's damping number",
};
/// Point loads F and control forces u \[N\]: |F| ≤ 10¹² N.
pub const FORCE_RANGE: ValueRange = ValueRange {
    min: -1e12,
    max: 1e12,
    unit: "N",
    why: "F·l enters the generalised force",
};
/// Gravitational acceleration g \[m/s²\]: |g| ≤ 10⁴ m/s² (a thousand times Earth's).
pub const GRAVITY_RANGE: ValueRange = ValueRange {
    min: -1e4,
    max: 1e4,
    unit: "m/s²",
    why: "g·m·l enters the generalised force",
};
/// Axial weight w \[N/m\] (`loads.axial_weight`): |w| ≤ 10¹² N/m.
pub const AXIAL_WEIGHT_RANGE: ValueRange = ValueRange {
    min: -1e12,
    max: 1e12,
    unit: "N/m",
    why: "w·l² enters the generalised force",
};
/// Drag constant D \[kg/m\]: 0 to 10¹².
pub const DRAG_RANGE: ValueRange = ValueRange {
    min: 0.0,
    max: 1e12,
    unit: "kg/m",
    why: "h·D·|p| enters the implicit half step",
};
/// Current speeds \[m/s\] (`[loads.current]`): 0 to 10³ m/s.
pub const CURRENT_SPEED_RANGE: ValueRange = ValueRange {
    min: 0.0,
    max: 1e3,
    unit: "m/s",
    why: "D·P² with P = l·Σm·U is the current's force in the implicit half step",
};
/// Period T of a harmonic load \[s\]: 10⁻¹² to 10¹² s.
pub const PERIOD_RANGE: ValueRange = ValueRange {
    min: 1e-12,
    max: 1e12,
    unit: "s",
    why: "2π·t/T is the harmonic's phase, and must stay finite",
};
/// Time step h \[s\]: 10⁻¹² to 10⁴ s.
pub const STEP_RANGE: ValueRange = ValueRange {
    min: 1e-12,
    max: 1e4,
    unit: "s",
    why: "h² multiplies every force in the step and 2/h gives the multipliers μ",
};

/// Height of the mudline above the chain's foot \[m\] (`soil.mudline`): 0 to 10⁶ m.
pub const SOIL_MUDLINE_RANGE: ValueRange = ValueRange {
    min: 0.0,
    max: 1e6,
    unit: "m",
    why: "the mudline is a height on the beam, whose pendulums are at most 10⁶ m long",
};
/// Lateral p-y modulus of the soil at the mudline E₀ \[N/m²\] (`soil.modulus`): 0 to 10¹² N/m²
/// (soft clays are 10⁵–10⁷, dense sands 10⁷–10⁸).
pub const SOIL_MODULUS_RANGE: ValueRange = ValueRange {
    min: 0.0,
    max: 1e12,
    unit: "N/m²",
    why: "h²·E_s·l/m is the step's soil number, and E_s·l the node's spring",
};
/// Increase of the p-y modulus with depth E₁ \[N/m³\] (`soil.gradient`): 0 to 10¹² N/m³.
pub const SOIL_GRADIENT_RANGE: ValueRange = ValueRange {
    min: 0.0,
    max: 1e12,
    unit: "N/m³",
    why: "E₁·d·l is the spring of a node at depth d",
};

/// The ranges of `soil.mudline`, `soil.modulus` and `soil.gradient`, in that order.
pub(super) fn soil_ranges() -> [ValueRange; 3] {
    [SOIL_MUDLINE_RANGE, SOIL_MODULUS_RANGE, SOIL_GRADIENT_RANGE]
}

/// The ranges of the stack-up's values (`[stackup]`, docs/scene-format.md), indexed by
/// [`StackupRange`].
const STACKUP_RANGES: [ValueRange; 14] = [
    ValueRange {
        min: 1e-6,
        max: 1e6,
        unit: "m",
        why: "lengths become the pendulums' lengths, within beam.length's range",
    },
    ValueRange {
        min: 0.0,
        max: 1e6,
        unit: "m",
        why: "an elevation is a height on the stack-up, from its foot",
    },
    ValueRange {
        min: 1e-6,
        max: 1e3,
        unit: "m",
        why: "diameters and walls give the sections' areas and second moments",
    },
    ValueRange {
        min: 1e3,
        max: 1e15,
        unit: "Pa",
        why: "E·I/l is a joint's spring, within beam.stiffness's range",
    },
    ValueRange {
        min: 0.0,
        max: 1e5,
        unit: "kg/m³",
        why: "densities give the masses and weights per length",
    },
    ValueRange {
        min: 0.0,
        max: 1e6,
        unit: "kg/m",
        why: "the lines' mass joins the pipe's mass per length",
    },
    ValueRange {
        min: 0.0,
        max: 1e4,
        unit: "m²",
        why: "areas give buoyancy and drag",
    },
    ValueRange {
        min: 0.0,
        max: 100.0,
        unit: "",
        why: "C_d and C_a scale the Morison loads and the added mass",
    },
    ValueRange {
        min: 1e-6,
        max: 1e10,
        unit: "kg",
        why: "a body's mass becomes node masses, within beam.mass's range",
    },
    ValueRange {
        min: 0.0,
        max: 1e10,
        unit: "kg",
        why: "the added mass joins the body's node masses",
    },
    ValueRange {
        min: -1e12,
        max: 1e12,
        unit: "N",
        why: "the weight enters the axial force, within the forces' range",
    },
    ValueRange {
        min: 1e-6,
        max: 1e18,
        unit: "N·m²",
        why: "E·I/l is a joint's spring, within beam.stiffness's range",
    },
    ValueRange {
        min: 0.0,
        max: 1e15,
        unit: "N·m/rad",
        why: "h²·k/(m·l²) is the step's spring number",
    },
    ValueRange {
        min: 1e-3,
        max: 1e3,
        unit: "",
        why: "a segment's share of the pendulums is its length times its refinement",
    },
];

/// Which of the stack-up's ranges ([`stackup_ranges`]).
#[derive(Clone, Copy, Debug)]
pub(super) enum StackupRange {
    /// Segment joint lengths and body heights.
    Length,
    /// Flex-joint elevations.
    Elevation,
    /// Diameters and wall thicknesses.
    Diameter,
    /// Young's moduli.
    Modulus,
    /// Steel, contents and buoyancy densities.
    Density,
    /// The auxiliary lines' mass per length.
    LineMass,
    /// The lines' displaced area and the bodies' drag areas.
    Area,
    /// C_d and C_a.
    Coefficient,
    /// A body's mass.
    BodyMass,
    /// A body's added mass.
    AddedMass,
    /// A body's submerged weight.
    BodyWeight,
    /// A body's bending stiffness.
    Ei,
    /// A flex joint's stiffness.
    Rotational,
    /// A segment's relative density of pendulums.
    Refinement,
}

/// The stack-up's ranges, indexed by [`StackupRange`] (each with its unit and why).
pub(super) fn stackup_ranges() -> [ValueRange; 14] {
    STACKUP_RANGES
}

/// The range of a stack-up key, for the documentation's check (tests/scene/docs_keys.rs).
pub fn stackup_range_of(key: &str) -> Option<ValueRange> {
    use StackupRange as R;
    let r = match key {
        "length" | "height" => R::Length,
        "elevation" => R::Elevation,
        "outer_diameter" | "wall_thickness" | "buoyancy_diameter" | "hydrodynamic_diameter" => {
            R::Diameter
        }
        "youngs_modulus" => R::Modulus,
        "steel_density" | "contents_density" | "buoyancy_density" => R::Density,
        "line_mass" => R::LineMass,
        "line_area" | "drag_area" => R::Area,
        "drag_coefficient" | "added_mass_coefficient" => R::Coefficient,
        "mass" => R::BodyMass,
        "added_mass" => R::AddedMass,
        "submerged_weight" => R::BodyWeight,
        "bending_stiffness" => R::Ei,
        "stiffness" => R::Rotational,
        "refinement" => R::Refinement,
        _ => return None,
    };
    Some(STACKUP_RANGES[r as usize])
}

/// Number of constraints of a planar chain with this support: one length constraint per pendulum,
/// plus the tip constraint of fixed-fixed and pinned-pinned beams (also in the reaction-force
/// variant, where it is the moving target).
fn n_constraints(n: usize, support: Support) -> usize {
    n + usize::from(support.holds_tip())
}

impl Scene {
    /// Checks the rules of docs/scene-format.md: counts and nodes, the value ranges
    /// ([`LENGTH_RANGE`], [`MASS_RANGE`], ...), the step numbers ([`MAX_STEP_NUMBER`]) and the size
    /// limits ([`MAX_PENDULUMS`], [`MAX_STEPS`], the wave record's). The error names the first
    /// offending key. The stored trajectory's budget ([`MAX_TRAJECTORY_BYTES`]) is not a rule of
    /// the scene but of a run that stores one: [`Scene::check_stored_trajectory`].
    pub fn validate(&self) -> Result<(), SceneError> {
        let n = self.n();
        check_size(n, self.time.steps)?;
        let b = &self.beam;
        if b.masses.len() != n {
            return Err(SceneError::count("beam.mass", n, b.masses.len()));
        }
        if b.stiffness.len() != n - 1 {
            return Err(SceneError::count(
                "beam.stiffness",
                n - 1,
                b.stiffness.len(),
            ));
        }
        check_all("beam.length", &b.lengths, check_positive)?;
        check_all("beam.length", &b.lengths, |k, x| {
            check_range(k, x, &LENGTH_RANGE)
        })?;
        check_all("beam.mass", &b.masses, check_positive)?;
        check_all("beam.mass", &b.masses, |k, x| {
            check_range(k, x, &MASS_RANGE)
        })?;
        check_all("beam.stiffness", &b.stiffness, check_spring)?;
        check_spring("beam.base_stiffness", b.base_stiffness)?;
        check_spring("beam.tip_stiffness", b.tip_stiffness)?;
        check_joint_damping(&b.joint_damping, n, b.support)?;
        if b.reaction_force && !matches!(b.support, Support::FixedFixed | Support::PinnedPinned) {
            return Err(SceneError::invalid(
                "beam.reaction_force",
                format!(
                    "the reaction-force variant needs support `fixed-fixed` or `pinned-pinned`, \
                     not `{}`",
                    support_name(b.support)
                ),
            ));
        }
        self.check_vessel()?;
        check_finite("loads.gravity", self.loads.gravity)?;
        check_range("loads.gravity", self.loads.gravity, &GRAVITY_RANGE)?;
        if let Some(pipe) = &self.pipe {
            pipe.check()?;
            if pipe.drag_model == super::DragModel::Morison && !self.beam.joint_damping.is_empty() {
                return Err(SceneError::invalid(
                    "beam.joint_damping",
                    "the joint damping and `pipe.drag_model = \"morison\"` are not combined yet \
                     (each couples the pendulums' half step in its own way)"
                        .to_string(),
                ));
            }
            if pipe.drag_model == super::DragModel::Morison && self.loads.drag != 0.0 {
                return Err(SceneError::invalid(
                    "loads.drag",
                    format!(
                        "is the momentum drag's constant D, which `pipe.drag_model = \"morison\"` \
                         does not use (its drag is ½ ρ_w C_d D_o per length from `[pipe]`): \
                         leave it out, got {}",
                        self.loads.drag
                    ),
                ));
            }
        }
        self.water.check()?;
        if let Some(soil) = &self.soil {
            soil.check(b.lengths.iter().sum())?;
        }
        if let Some(st) = &self.stackup {
            if st.drag_model == super::DragModel::Morison && !self.beam.joint_damping.is_empty() {
                return Err(SceneError::invalid(
                    "beam.joint_damping",
                    "the joint damping and `stackup.drag_model = \"morison\"` are not combined \
                     yet (each couples the pendulums' half step in its own way)"
                        .to_string(),
                ));
            }
            if st.drag_model == super::DragModel::Morison && self.loads.drag != 0.0 {
                return Err(SceneError::invalid(
                    "loads.drag",
                    format!(
                        "is the momentum drag's constant D, which `stackup.drag_model = \
                         \"morison\"` does not use (each node's drag comes from its segments \
                         and bodies): leave it 0, got {}",
                        self.loads.drag
                    ),
                ));
            }
            let l = &st.layout;
            let lens = [
                l.node_weights.len(),
                l.node_drag.len(),
                l.node_inertia.len(),
            ];
            if lens.iter().any(|&m| m != n) {
                return Err(SceneError::invalid(
                    "stackup",
                    format!(
                        "its layout on the chain has {} nodes for a beam of {n} pendulums: a \
                         stack-up's chain is built when the scene is read (`Scene::from_file`, \
                         `Scene::from_toml_str`)",
                        lens[0]
                    ),
                ));
            }
        }
        if let Some(objective) = &self.objective {
            objective.check()?;
        }
        self.check_design()?;
        check_finite("loads.tension", self.loads.tension)?;
        check_range("loads.tension", self.loads.tension, &FORCE_RANGE)?;
        check_finite("loads.axial_weight", self.loads.axial_weight)?;
        check_range(
            "loads.axial_weight",
            self.loads.axial_weight,
            &AXIAL_WEIGHT_RANGE,
        )?;
        check_nonnegative("loads.drag", self.loads.drag)?;
        check_range("loads.drag", self.loads.drag, &DRAG_RANGE)?;
        for (i, p) in self.loads.points.iter().enumerate() {
            check_point_load(i, p, n)?;
        }
        if let Some(c) = &self.loads.current {
            // Morison's node drag acts through the pipe's (the stack-up's) C_d, not D (then 0).
            let node_drag = self
                .pipe
                .is_some_and(|p| p.drag_model == super::DragModel::Morison)
                || self
                    .stackup
                    .as_ref()
                    .is_some_and(|st| st.drag_model == super::DragModel::Morison);
            c.check(if node_drag { 1.0 } else { self.loads.drag })?;
        }
        check_positive("time.step", self.time.step)?;
        check_range("time.step", self.time.step, &STEP_RANGE)?;
        if let Some(w) = &self.loads.waves {
            w.check(self)?;
        }
        let t_end = self.time.steps as f64 * self.time.step;
        for (i, p) in self.loads.points.iter().enumerate() {
            check_series_coverage(i, p, t_end)?;
        }
        if let Some(c) = &self.control {
            self.check_control(c)?;
        }
        if let Some(f) = &self.fatigue {
            f.validate().map_err(super::fatigue::scene_error)?;
        }
        self.check_hotspots()?;
        self.check_step_numbers()
    }

    /// The `[control]` table: the node (the tip with the reaction-force variant), the number of
    /// values for the kind, `values_x` as long as `values`, every value finite and in range.
    fn check_control(&self, c: &Control) -> Result<(), SceneError> {
        let (n, b) = (self.n(), &self.beam);
        node_index("control.node", to_i64(c.node), n)?;
        if b.reaction_force && c.node != n {
            return Err(SceneError::invalid(
                "control.node",
                format!(
                    "the reaction-force variant moves the tip: the control must act at node \
                     {n}, not {}",
                    c.node
                ),
            ));
        }
        check_control_count(c.kind, c.values.len(), self.time.steps)?;
        if let Some(thrust) = self.thrust() {
            self.check_thrust_control(c, &thrust)?;
        }
        if let Some(vx) = &c.values_x {
            if vx.len() != c.values.len() {
                return Err(SceneError::count(
                    "control.values_x",
                    c.values.len(),
                    vx.len(),
                ));
            }
        }
        let vx = c.values_x.iter().flatten();
        for (i, &u) in c.values.iter().chain(vx).enumerate() {
            let key = format!("control.values[{}]", i % c.values.len());
            check_finite(&key, u)?;
            check_range(&key, u, &FORCE_RANGE)?;
        }
        Ok(())
    }

    /// The step numbers of [`MAX_STEP_NUMBER`], with M̄⁻¹ᵢᵢ = (1/lᵢ²)(1/mᵢ + 1/mᵢ₋₁) the diagonal
    /// of the inverse mass matrix (docs/conventions.md): the spring number
    /// h²·(kᵢ + kᵢ₊₁)·M̄⁻¹ᵢᵢ ≈ (ω h)², ω the fastest local angular frequency, and the load number
    /// h²·(C·lᵢ + Dᵢ·|Pᵢ|²)·M̄⁻¹ᵢᵢ with C = Σ|F| + |g|·Σm + max|u| the largest load and Dᵢ·|Pᵢ|²
    /// the current's steady drag on pendulum i (if any; Dᵢ = D wᵢ on a pipe's chain,
    /// [`Scene::drag_weights`]), an upper bound
    /// of the angle one step from rest turns pendulum i through. Every factor is inside its
    /// range, so both are finite.
    fn check_step_numbers(&self) -> Result<(), SceneError> {
        let b = &self.beam;
        let n = self.n();
        let h = self.time.step;
        let (has_base, has_tip) = end_springs(b.support);
        let spring = |j: usize| -> f64 {
            // spring j = 0..=n couples pendulums j and j + 1 (1-based), k₁ = base, k_{n+1} = tip
            if j == 0 {
                if has_base {
                    b.base_stiffness
                } else {
                    0.0
                }
            } else if j == n {
                if has_tip {
                    b.tip_stiffness
                } else {
                    0.0
                }
            } else {
                b.stiffness[j - 1]
            }
        };
        let loads = &self.loads;
        let total_mass: f64 = b.masses.iter().sum();
        // A thrust on the vessel is not a load on the riser (it moves the top's constraint).
        let riser_control = self.control.as_ref().filter(|_| self.thrust().is_none());
        let max_u = riser_control.map_or(0.0, |c| {
            let vx = c.values_x.as_deref().unwrap_or(&[]);
            let ux = |i: usize| vx.get(i).copied().unwrap_or(0.0);
            let mag = c.values.iter().enumerate().map(|(i, u)| ux(i).hypot(*u));
            mag.fold(0.0f64, f64::max)
        });
        let load: f64 = loads
            .points
            .iter()
            .map(PointLoad::max_magnitude)
            .sum::<f64>()
            + loads.gravity.abs() * total_mass
            + max_u;
        let weights = self.drag_weights();
        let current = loads.current.as_ref().map_or_else(
            || vec![0.0; n],
            |c| {
                let chain = (&b.lengths[..], &b.masses[..]);
                c.steady_forces(loads.drag, weights.as_deref(), chain, self.mudline())
            },
        );
        let (mut worst_spring, mut at_spring) = (0.0f64, 0);
        let (mut worst_load, mut at_load) = (0.0f64, 0);
        for i in 0..n {
            let inv_l = 1.0 / b.lengths[i];
            let inv_m = 1.0 / b.masses[i] + if i > 0 { 1.0 / b.masses[i - 1] } else { 0.0 };
            let minv = inv_l * inv_l * inv_m;
            let s = h * h * (spring(i) + spring(i + 1)) * minv;
            if s > worst_spring {
                (worst_spring, at_spring) = (s, i + 1);
            }
            let f = h * h * (load * b.lengths[i] + current[i]) * minv;
            if f > worst_load {
                (worst_load, at_load) = (f, i + 1);
            }
        }
        let advice = |number: f64| {
            format!(
                "use a smaller `time.step` (below {:.3e} s)",
                h * (MAX_STEP_NUMBER / number).sqrt()
            )
        };
        if worst_spring > MAX_STEP_NUMBER {
            return Err(SceneError::invalid(
                "time.step",
                format!(
                    "the spring number h²·k/(m·l²) = {worst_spring:.3e} at pendulum {at_spring} \
                     exceeds {MAX_STEP_NUMBER:e}: one step of h = {h} s spans {:.1e} rad of its \
                     fastest oscillation; {} or check `beam.stiffness`, `beam.mass` and \
                     `beam.length`",
                    worst_spring.sqrt(),
                    advice(worst_spring)
                ),
            ));
        }
        if worst_load > MAX_STEP_NUMBER {
            return Err(SceneError::invalid(
                "time.step",
                format!(
                    "the load number h²·F·l/(m·l²) = {worst_load:.3e} at pendulum {at_load} \
                     exceeds {MAX_STEP_NUMBER:e}: one step of h = {h} s would turn it through \
                     {worst_load:.1e} rad; {} or check the forces (`loads`, `control.values`), \
                     `beam.mass` and `beam.length`",
                    advice(worst_load)
                ),
            ));
        }
        Ok(())
    }
}

/// The rules of one point load `loads.point[i]` (docs/scene-format.md, `[[loads.point]]`).
fn check_point_load(i: usize, p: &PointLoad, n: usize) -> Result<(), SceneError> {
    let key = |k: &str| format!("loads.point[{i}].{k}");
    node_index(&key("node"), to_i64(p.node), n)?;
    for f in [p.force_x, p.force] {
        check_finite(&key("force"), f)?;
        check_range(&key("force"), f, &FORCE_RANGE)?;
    }
    check_finite(&key("start"), p.start)?;
    if let Some(end) = p.end {
        check_finite(&key("end"), end)?;
        if end <= p.start {
            return Err(SceneError::invalid(
                key("end"),
                format!("must be greater than start = {}, got {end}", p.start),
            ));
        }
    }
    check_nonnegative(&key("ramp"), p.ramp)?;
    let [dx, dz] = p.direction;
    let norm = dx.hypot(dz);
    if !(dx.is_finite() && dz.is_finite() && norm > 0.0 && norm.is_finite()) {
        return Err(SceneError::invalid(
            key("direction"),
            format!(
                "must be a finite vector [dx, dz] of non-zero length, got [{dx}, {dz}]{}",
                if norm == 0.0 {
                    " (zero length: no direction)"
                } else {
                    ""
                }
            ),
        ));
    }
    for (j, h) in p.harmonics.iter().enumerate() {
        let hkey = |k: &str| format!("loads.point[{i}].harmonic[{j}].{k}");
        check_finite(&hkey("amplitude"), h.amplitude)?;
        check_range(&hkey("amplitude"), h.amplitude, &FORCE_RANGE)?;
        check_positive(&hkey("period"), h.period)?;
        check_range(&hkey("period"), h.period, &PERIOD_RANGE)?;
        check_finite(&hkey("phase"), h.phase)?;
    }
    if let Some(series) = &p.series {
        series.check(&key("series"))?;
    }
    Ok(())
}

/// A time series must cover the times t_k ∈ [0, t_N] at which its load acts (t_N = `t_end`).
fn check_series_coverage(i: usize, p: &PointLoad, t_end: f64) -> Result<(), SceneError> {
    let key = |k: &str| format!("loads.point[{i}].{k}");
    if let Some(series) = &p.series {
        // The rows must cover the times t_k ∈ [0, t_N] at which the load acts.
        let from = p.start.max(0.0);
        let to = p.end.map_or(t_end, |e| e.min(t_end));
        let (a, b) = series.span();
        let tol = 1e-9 * t_end.max(1.0);
        if from <= to && (a > from + tol || b < to - tol) {
            return Err(SceneErrorKind::SeriesFile {
                key: key("series"),
                file: series.file.clone(),
                line: None,
                reason: format!(
                    "its rows cover t ∈ [{a}, {b}] s but the load acts for t ∈ [{from}, {to}] s \
                     (the grid ends at t_N = N·h = {t_end} s); extend the series, or set `start`/`end` \
                     or `time.steps`"
                ),
            }
            .into());
        }
    }
    Ok(())
}

/// The number of `control.values` a control kind needs with N steps.
pub(super) fn check_control_count(
    kind: ControlKind,
    count: usize,
    steps: usize,
) -> Result<(), SceneError> {
    let expected = match kind {
        ControlKind::Constant => 1,
        ControlKind::PerStep => steps + 1,
        ControlKind::Piecewise if (1..=steps).contains(&count) => return Ok(()),
        ControlKind::Piecewise => {
            return Err(SceneError::invalid(
                "control.values",
                format!(
                    "a piecewise control has 1 to N = {steps} pieces (one value each), got {count} \
                     values{}",
                    if count > steps {
                        "; use kind = \"per-step\" for one value per time t_k"
                    } else {
                        ""
                    }
                ),
            ))
        }
    };
    if count != expected {
        return Err(SceneError::count("control.values", expected, count));
    }
    Ok(())
}

/// A count that must be ≥ 1 (the upper limits are checked by [`check_size`]).
pub(super) fn positive_count(key: &str, v: i64) -> Result<usize, SceneError> {
    match usize::try_from(v) {
        Ok(x) if x >= 1 => Ok(x),
        _ => Err(SceneError::invalid(
            key,
            format!("must be at least 1, got {v}"),
        )),
    }
}

/// A node index in 1..=n.
pub(super) fn node_index(key: &str, node: i64, n: usize) -> Result<usize, SceneError> {
    match usize::try_from(node) {
        Ok(x) if (1..=n).contains(&x) => Ok(x),
        _ => Err(SceneErrorKind::NodeOutOfRange {
            key: key.to_string(),
            node,
            n,
        }
        .into()),
    }
}

/// The size limits ([`MAX_PENDULUMS`], [`MAX_STEPS`]), checked before anything of size n or N is
/// allocated. The stored trajectory's budget is [`check_trajectory_budget`]'s, for runs that store
/// one.
pub(super) fn check_size(n: usize, steps: usize) -> Result<(), SceneError> {
    if n == 0 {
        return Err(SceneError::invalid(
            "beam.pendulums",
            "must be at least 1, got 0",
        ));
    }
    if n > MAX_PENDULUMS {
        return Err(SceneError::invalid(
            "beam.pendulums",
            format!("at most {MAX_PENDULUMS} pendulums are supported, got {n}"),
        ));
    }
    if steps == 0 {
        return Err(SceneError::invalid(
            "time.steps",
            "must be at least 1, got 0",
        ));
    }
    if steps > MAX_STEPS {
        return Err(SceneError::invalid(
            "time.steps",
            format!("at most {MAX_STEPS} steps are supported, got {steps}"),
        ));
    }
    Ok(())
}

/// The stored trajectory's budget: the planar `f64` trajectory of N = `steps` steps of n
/// pendulums ([`trajectory_bytes`]) must fit [`MAX_TRAJECTORY_BYTES`], else an error naming
/// `time.steps`, the bytes, the limit and the largest N that fits.
pub(super) fn check_trajectory_budget(
    n: usize,
    steps: usize,
    support: Support,
) -> Result<(), SceneError> {
    let nc = n_constraints(n, support);
    let bytes = trajectory_bytes::<f64, 2>(n, nc, steps);
    if bytes > MAX_TRAJECTORY_BYTES {
        let max_steps = max_trajectory_steps::<f64, 2>(n, nc);
        return Err(SceneError::invalid(
            "time.steps",
            format!(
                "the trajectory of N = {steps} steps of n = {n} pendulums needs {} (q, p, λ, μ \
                 per node and time), over the memory limit of {}; reduce `time.steps` (at most \
                 {max_steps} for this beam) or `beam.pendulums`",
                human_bytes(bytes),
                human_bytes(MAX_TRAJECTORY_BYTES)
            ),
        ));
    }
    Ok(())
}

impl Scene {
    /// Whether a run that stores this scene's trajectory may: its planar `f64` trajectory
    /// ([`trajectory_bytes`]: q, p, λ, μ per node and time, (N + 1)(6n + 4)·8 bytes and more)
    /// fits [`MAX_TRAJECTORY_BYTES`]. [`crate::simulate()`] and its variants and
    /// [`crate::ControlProblem`] (the adjoint and the optimisers) check it before anything of
    /// size N is allocated; a streamed run ([`crate::simulate_streaming`],
    /// [`crate::moment_history`], `chainbeam simulate`) stores no trajectory and does not.
    ///
    /// # Errors
    /// [`SceneErrorKind::InvalidValue`] naming `time.steps`, with the bytes needed, the limit and
    /// the largest N that fits this beam.
    pub fn check_stored_trajectory(&self) -> Result<(), SceneError> {
        check_trajectory_budget(self.n(), self.time.steps, self.beam.support)
    }
}

impl Scene {
    /// The vessel's thrust actuator ([`crate::scene::Thrust`]) of a `support = "vessel"` scene
    /// whose `[vessel]` gives a thrust key; `None` otherwise.
    pub fn thrust(&self) -> Option<crate::scene::Thrust> {
        if self.beam.support != Support::Vessel {
            return None;
        }
        self.vessel.as_ref().and_then(|v| v.thrust())
    }

    /// A `[control]` of a thrust scene is the thrust on the vessel: it acts at the top (node n,
    /// where the vessel holds the riser), within ±`thrust_bound`, and a per-step or piecewise
    /// thrust changes by at most `thrust_rate_bound`·h from one time t_k to the next.
    fn check_thrust_control(
        &self,
        c: &Control,
        thrust: &crate::scene::Thrust,
    ) -> Result<(), SceneError> {
        let n = self.n();
        if c.node != n {
            return Err(SceneError::invalid(
                "control.node",
                format!(
                    "with the vessel's thrust keys the control is the thrust on the vessel, which \
                     holds the top: it acts at node {n}, not {}",
                    c.node
                ),
            ));
        }
        for (i, &u) in c.values.iter().enumerate() {
            if u.abs() > thrust.bound {
                return Err(SceneError::invalid(
                    format!("control.values[{i}]"),
                    format!(
                        "a thrust of {u} N exceeds vessel.thrust_bound = {} N",
                        thrust.bound
                    ),
                ));
            }
        }
        let max_change = thrust.rate_bound * self.time.step;
        if c.kind != crate::scene::ControlKind::Constant {
            for (i, w) in c.values.windows(2).enumerate() {
                let change = (w[1] - w[0]).abs();
                if change > max_change * (1.0 + 1e-12) {
                    return Err(SceneError::invalid(
                        format!("control.values[{}]", i + 1),
                        format!(
                            "the thrust changes by {change} N in one step of {} s, more than \
                             vessel.thrust_rate_bound · h = {max_change} N",
                            self.time.step
                        ),
                    ));
                }
            }
        }
        Ok(())
    }

    /// `[vessel]` belongs to `support = "vessel"` and its values are valid; the vessel holds the
    /// tip's z only, so its scenes are planar.
    fn check_vessel(&self) -> Result<(), SceneError> {
        let vessel_support = self.beam.support == Support::Vessel;
        match &self.vessel {
            Some(_) if !vessel_support => Err(SceneError::invalid(
                "vessel",
                format!(
                    "a `[vessel]` table needs `beam.support = \"vessel\"`, not `{}`",
                    self.beam.support.name()
                ),
            )),
            Some(v) => {
                v.check()?;
                match self.spatial_key() {
                    Some(key) => Err(SceneError::invalid(
                        "beam.support",
                        format!(
                            "`vessel` holds the top along z only, and `{key}` makes the scene \
                             spatial (a load, current, wave or control along x)"
                        ),
                    )),
                    None => Ok(()),
                }
            }
            None => Ok(()),
        }
    }
}

/// Whether the support has a base spring k₁ / a tip spring k_{n+1}.
pub(super) fn end_springs(support: Support) -> (bool, bool) {
    support.end_springs()
}

pub(super) fn support_name(support: Support) -> &'static str {
    support.name()
}

pub(super) fn check_positive(key: &str, x: f64) -> Result<(), SceneError> {
    if x.is_finite() && x > 0.0 {
        Ok(())
    } else {
        Err(SceneError::invalid(
            key,
            format!("must be positive and finite, got {x}"),
        ))
    }
}

fn check_nonnegative(key: &str, x: f64) -> Result<(), SceneError> {
    if x.is_finite() && x >= 0.0 {
        Ok(())
    } else {
        Err(SceneError::invalid(
            key,
            format!("must be finite and non-negative, got {x}"),
        ))
    }
}

/// The joints 0..=n (0-based) that carry a spring for this support (docs/conventions.md):
/// the interior joints always, the base except for pinned-pinned, the tip for riser and
/// fixed-fixed.
fn has_spring(support: Support, n: usize, j: usize) -> bool {
    match j {
        0 => support != Support::PinnedPinned,
        j if j == n => support.end_springs().1,
        _ => true,
    }
}

/// `[beam] joint_damping` as n + 1 dampers c₁..c_{n+1}: one number is the damper of every joint
/// with a spring (0 elsewhere); an array must have n + 1 values ([`SceneErrorKind::WrongCount`]
/// naming `beam.joint_damping`).
pub(super) fn joint_damping_layout(
    c: NumOrArray,
    n: usize,
    support: Support,
) -> Result<Vec<f64>, SceneError> {
    match c {
        NumOrArray::Number(x) => Ok((0..=n)
            .map(|j| if has_spring(support, n, j) { x } else { 0.0 })
            .collect()),
        NumOrArray::Array(v) => NumOrArray::Array(v).expand("beam.joint_damping", n + 1),
    }
}

/// The joint dampers (empty: none): n + 1 values, each finite and non-negative, zero at the
/// joints without a spring (a free tip, a pinned end).
fn check_joint_damping(c: &[f64], n: usize, support: Support) -> Result<(), SceneError> {
    const KEY: &str = "beam.joint_damping";
    if c.is_empty() {
        return Ok(());
    }
    if c.len() != n + 1 {
        return Err(SceneError::count(KEY, n + 1, c.len()));
    }
    check_all(KEY, c, check_nonnegative)?;
    check_all(KEY, c, |k, x| check_range(k, x, &JOINT_DAMPING_RANGE))?;
    for (j, &x) in c.iter().enumerate() {
        if x != 0.0 && !has_spring(support, n, j) {
            return Err(SceneError::invalid(
                format!("{KEY}[{j}]"),
                format!(
                    "joint {} has no spring with support `{}`, so it has no damper (give 0)",
                    j + 1,
                    support_name(support)
                ),
            ));
        }
    }
    Ok(())
}

pub(super) fn check_spring(key: &str, x: f64) -> Result<(), SceneError> {
    check_nonnegative(key, x)?;
    check_range(key, x, &STIFFNESS_RANGE)
}

pub(super) fn check_finite(key: &str, x: f64) -> Result<(), SceneError> {
    if x.is_finite() {
        Ok(())
    } else {
        Err(SceneError::invalid(key, format!("must be finite, got {x}")))
    }
}

/// `x` inside `range` (NaN is outside every range).
pub(super) fn check_range(key: &str, x: f64, range: &ValueRange) -> Result<(), SceneError> {
    if range.contains(x) {
        return Ok(());
    }
    let unit = range.unit;
    let (lo, hi) = (short(range.min), short(range.max));
    let bound = if x < range.min {
        format!("at least {lo} {unit}")
    } else {
        format!("at most {hi} {unit}")
    };
    Err(SceneError::invalid(
        key,
        format!(
            "must be {bound}, got {} (the supported range is [{lo}, {hi}] {unit}: {})",
            short(x),
            range.why
        ),
    ))
}

/// `x` as written in a file: `0`, `2.5`, `1e-300`, `-1e12` (the shorter of the two forms).
fn short(x: f64) -> String {
    let plain = format!("{x}");
    let sci = format!("{x:e}");
    if plain.len() <= sci.len() {
        plain
    } else {
        sci
    }
}

/// Checks every value of a per-pendulum array; the key has an index unless all values are equal
/// (then the file form is a single number, see [`NumOrArray::compact`]).
fn check_all(
    key: &str,
    values: &[f64],
    check: impl Fn(&str, f64) -> Result<(), SceneError>,
) -> Result<(), SceneError> {
    let uniform = matches!(NumOrArray::compact(values), NumOrArray::Number(_));
    for (i, &x) in values.iter().enumerate() {
        if uniform {
            check(key, x)?;
        } else {
            check(&format!("{key}[{i}]"), x)?;
        }
    }
    Ok(())
}

/// Bytes [`crate::simulate::simulate_chain`] stores for a trajectory of N = `steps` steps of n pendulums with
/// `n_constraints` multipliers in scalar `D` and dimension `DIM`: per time t_k (N + 1 of them) q
/// and p (2·n·DIM scalars), λ and μ (2·n_c scalars), energy, moment, control and tip target
/// (4 scalars; 6 in the spatial model, with M₀ₓ and u_x); per step its [`StepStats`]; plus the n lengths. Saturates at `u64::MAX`.
pub fn trajectory_bytes<D, const DIM: usize>(n: usize, n_constraints: usize, steps: usize) -> u64 {
    let per_time = per_time_bytes::<D, DIM>(n, n_constraints);
    let total = (steps as u128 + 1) * per_time
        + steps as u128 * std::mem::size_of::<StepStats>() as u128
        + n as u128 * std::mem::size_of::<f64>() as u128;
    u64::try_from(total).unwrap_or(u64::MAX)
}

fn per_time_bytes<D, const DIM: usize>(n: usize, n_constraints: usize) -> u128 {
    let d = std::mem::size_of::<D>() as u128;
    let extra = if DIM == 3 { 2 } else { 0 };
    (2 * n as u128 * DIM as u128 + 2 * n_constraints as u128 + 4 + extra) * d
}

/// The largest N whose trajectory ([`trajectory_bytes`]) fits [`MAX_TRAJECTORY_BYTES`].
pub fn max_trajectory_steps<D, const DIM: usize>(n: usize, n_constraints: usize) -> usize {
    let per_step =
        per_time_bytes::<D, DIM>(n, n_constraints) + std::mem::size_of::<StepStats>() as u128;
    let fixed = per_time_bytes::<D, DIM>(n, n_constraints) + 8 * n as u128;
    let budget = MAX_TRAJECTORY_BYTES as u128;
    if budget < fixed {
        return 0;
    }
    usize::try_from((budget - fixed) / per_step).unwrap_or(usize::MAX)
}
