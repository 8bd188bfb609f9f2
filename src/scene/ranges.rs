//! The supported range of every physical value of a scene, with its unit and what goes wrong
//! outside it (docs/scene-format.md, "Valid ranges"), and the check that names the key when a
//! value leaves its range.

use super::SceneError;

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
