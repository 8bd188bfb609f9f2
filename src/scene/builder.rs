//! [`SceneBuilder`]: scenes in code, with the file format's defaults and validation.

use super::limits::check_size;
use super::validate::{check_spring, end_springs, support_name};
use super::values::NumOrArray;
use super::{
    Beam, Control, ControlKind, Current, Initial, Loads, ObjectiveKind, PointLoad, Scene,
    SceneError, SceneErrorKind, Support, TimeGrid,
};

/// Builds a [`Scene`] in code with the same defaults and validation as the file format.
///
/// Defaults: l = 1 m, m = 1 kg, k = 1000 Nm/rad for the interior springs and the end springs
/// (base = tip = k unless set; with [`stiffnesses`](Self::stiffnesses) the end springs the support
/// uses must be set, as in files), cantilever, no gravity, no drag, no loads, h = 0.01 s, N = 10,
/// no control, no objective.
///
/// ```
/// use chainbeam::scene::{Scene, Support};
/// let scene = Scene::builder(10)
///     .support(Support::Riser)
///     .base_stiffness(2000.0)
///     .tip_stiffness(2000.0)
///     .point_load(5, 2.0)
///     .control_constant(10, 0.0)
///     .build()
///     .unwrap();
/// assert_eq!(scene.n(), 10);
/// ```
#[derive(Clone, Debug)]
#[must_use]
pub struct SceneBuilder {
    n: usize,
    length: NumOrArray,
    mass: NumOrArray,
    stiffness: NumOrArray,
    base_stiffness: Option<f64>,
    tip_stiffness: Option<f64>,
    support: Support,
    reaction_force: bool,
    joint_damping: Option<NumOrArray>,
    loads: Loads,
    time: TimeGrid,
    control: Option<Control>,
    objective: Option<ObjectiveKind>,
    soil: Option<super::Soil>,
}

impl SceneBuilder {
    /// A builder for `n` pendulums with the defaults above.
    pub fn new(n: usize) -> Self {
        Self {
            n,
            length: NumOrArray::Number(1.0),
            mass: NumOrArray::Number(1.0),
            stiffness: NumOrArray::Number(1000.0),
            base_stiffness: None,
            tip_stiffness: None,
            support: Support::Cantilever,
            reaction_force: false,
            joint_damping: None,
            loads: Loads::default(),
            time: TimeGrid {
                step: 0.01,
                steps: 10,
                initial: Initial::Rest,
            },
            control: None,
            objective: None,
            soil: None,
        }
    }

    /// Every pendulum length lᵢ = `l` \[m\].
    pub fn length(mut self, l: f64) -> Self {
        self.length = NumOrArray::Number(l);
        self
    }

    /// The pendulum lengths l₁..lₙ (n values).
    pub fn lengths(mut self, l: Vec<f64>) -> Self {
        self.length = NumOrArray::Array(l);
        self
    }

    /// Every mass mᵢ = `m` \[kg\].
    pub fn mass(mut self, m: f64) -> Self {
        self.mass = NumOrArray::Number(m);
        self
    }

    /// The masses m₁..mₙ (n values).
    pub fn masses(mut self, m: Vec<f64>) -> Self {
        self.mass = NumOrArray::Array(m);
        self
    }

    /// Every interior spring k₂..kₙ = `k` \[Nm/rad\] (and the end springs, unless set).
    pub fn stiffness(mut self, k: f64) -> Self {
        self.stiffness = NumOrArray::Number(k);
        self
    }

    /// The interior springs k₂..kₙ (n − 1 values).
    pub fn stiffnesses(mut self, k: Vec<f64>) -> Self {
        self.stiffness = NumOrArray::Array(k);
        self
    }

    /// The base spring k₁.
    pub fn base_stiffness(mut self, k: f64) -> Self {
        self.base_stiffness = Some(k);
        self
    }

    /// The tip spring k_{n+1}.
    pub fn tip_stiffness(mut self, k: f64) -> Self {
        self.tip_stiffness = Some(k);
        self
    }

    /// Structural damping `[beam] joint_damping = c` \[N·m·s/rad\]: a damper c at every joint
    /// with a spring (docs/conventions.md "Joint damping").
    pub fn joint_damping(mut self, c: f64) -> Self {
        self.joint_damping = Some(NumOrArray::Number(c));
        self
    }

    /// The joint dampers c₁..c_{n+1} one by one (n + 1 values, 0 where the support has no
    /// spring), laid out like the model's springs k₁..k_{n+1}.
    pub fn joint_dampers(mut self, c: Vec<f64>) -> Self {
        self.joint_damping = Some(NumOrArray::Array(c));
        self
    }

    /// The support.
    pub fn support(mut self, support: Support) -> Self {
        self.support = support;
        self
    }

    /// The reaction-force variant (fixed-fixed and pinned-pinned only).
    pub fn reaction_force(mut self, on: bool) -> Self {
        self.reaction_force = on;
        self
    }

    /// Gravitational acceleration g \[m/s²\].
    pub fn gravity(mut self, g: f64) -> Self {
        self.loads.gravity = g;
        self
    }

    /// Top tension T \[N\] along +y at the tip (`[loads] tension`).
    pub fn tension(mut self, t: f64) -> Self {
        self.loads.tension = t;
        self
    }

    /// Axial weight w \[N/m\] along −y on every node (`[loads] axial_weight`).
    pub fn axial_weight(mut self, w: f64) -> Self {
        self.loads.axial_weight = w;
        self
    }

    /// Drag constant D \[kg/m\].
    pub fn drag(mut self, d: f64) -> Self {
        self.loads.drag = d;
        self
    }

    /// A steady current along the depth (see [`Current`]; needs a drag D > 0).
    pub fn current(mut self, current: Current) -> Self {
        self.loads.current = Some(current);
        self
    }

    /// Adds a point load `force` \[N\] along z at `node` (1..=n), acting for all t.
    pub fn point_load(self, node: usize, force: f64) -> Self {
        self.load(PointLoad::new(node, force))
    }

    /// Adds a point load `force` at `node` acting for `start ≤ t_k < end` \[s\].
    pub fn point_load_window(self, node: usize, force: f64, start: f64, end: f64) -> Self {
        self.load(PointLoad::new(node, force).window(start, Some(end)))
    }

    /// Adds a constant point load (F_x, F_z) \[N\] at `node` (an x component makes the scene
    /// spatial).
    pub fn point_load_vector(self, node: usize, force: [f64; 2]) -> Self {
        self.load(PointLoad::vector(node, force))
    }

    /// Adds any point load (constant, vector, harmonic, time series; see [`PointLoad`]).
    pub fn load(mut self, load: PointLoad) -> Self {
        self.loads.points.push(load);
        self
    }

    /// The time step h \[s\].
    pub fn step(mut self, h: f64) -> Self {
        self.time.step = h;
        self
    }

    /// The number of steps N.
    pub fn steps(mut self, steps: usize) -> Self {
        self.time.steps = steps;
        self
    }

    /// The state the run starts from (`[time] initial`, [`Initial`]).
    pub fn initial(mut self, initial: Initial) -> Self {
        self.time.initial = initial;
        self
    }

    /// A constant control `u` \[N\] at `node`.
    pub fn control_constant(mut self, node: usize, u: f64) -> Self {
        self.control = Some(Control {
            node,
            kind: ControlKind::Constant,
            values: vec![u],
            values_x: None,
        });
        self
    }

    /// A per-step control u_0..u_N (N + 1 values) at `node`.
    pub fn control_per_step(mut self, node: usize, values: Vec<f64>) -> Self {
        self.control = Some(Control {
            node,
            kind: ControlKind::PerStep,
            values,
            values_x: None,
        });
        self
    }

    /// A piecewise-constant control at `node` with P = `values.len()` pieces (1 ≤ P ≤ N): piece j
    /// acts on the steps k with ⌊k·P/N⌋ = j ([`crate::simulate::piece_index`]).
    pub fn control_piecewise(mut self, node: usize, values: Vec<f64>) -> Self {
        self.control = Some(Control {
            node,
            kind: ControlKind::Piecewise,
            values,
            values_x: None,
        });
        self
    }

    /// A 2-axis control at `node` (docs/conventions.md "Two-axis controls"): `values` are the
    /// pairs [u_x, u_z] of a control of kind `kind` (1, N + 1 or P pairs). Selects the spatial
    /// model.
    pub fn control_two_axis(mut self, node: usize, kind: ControlKind, values: &[[f64; 2]]) -> Self {
        self.control = Some(Control {
            node,
            kind,
            values: values.iter().map(|v| v[1]).collect(),
            values_x: Some(values.iter().map(|v| v[0]).collect()),
        });
        self
    }

    /// The objective.
    pub fn objective(mut self, kind: ObjectiveKind) -> Self {
        self.objective = Some(kind);
        self
    }

    /// The soil below the mudline (`[soil]`: lateral p-y springs on the nodes in it).
    pub fn soil(mut self, soil: super::Soil) -> Self {
        self.soil = Some(soil);
        self
    }

    /// The validated scene.
    pub fn build(self) -> Result<Scene, SceneError> {
        check_size(self.n, self.time.steps)?;
        let mut beam = assemble_beam(
            self.n,
            self.length,
            self.mass,
            self.stiffness,
            (self.base_stiffness, self.tip_stiffness),
            self.support,
            self.reaction_force,
        )?;
        if let Some(c) = self.joint_damping {
            beam.joint_damping = super::validate::joint_damping_layout(c, self.n, self.support)?;
        }
        let scene = Scene {
            beam,
            pipe: None,
            stackup: None,
            water: super::Water::default(),
            soil: self.soil,
            loads: self.loads,
            time: self.time,
            control: self.control,
            objective: self.objective,
            fatigue: None,
            hotspots: Vec::new(),
            mpc: None,
            vessel: (self.support == Support::Vessel).then(super::Vessel::default),
            design: None,
        };
        scene.validate()?;
        Ok(scene)
    }
}

/// Builds the beam from file-shaped values, applying the defaults of the module documentation;
/// `end_springs` = (`beam.base_stiffness`, `beam.tip_stiffness`). `n` must have passed
/// [`check_size`].
pub(super) fn assemble_beam(
    n: usize,
    length: NumOrArray,
    mass: NumOrArray,
    stiffness: NumOrArray,
    (base_stiffness, tip_stiffness): (Option<f64>, Option<f64>),
    support: Support,
    reaction_force: bool,
) -> Result<Beam, SceneError> {
    let lengths = length.expand("beam.length", n)?;
    let masses = mass.expand("beam.mass", n)?;
    let (has_base, has_tip) = end_springs(support);
    let default_spring = |given: Option<f64>, used: bool, key: &str| match (given, &stiffness) {
        (Some(v), _) => Ok(v),
        (None, NumOrArray::Number(k)) => Ok(*k),
        (None, NumOrArray::Array(_)) if used => Err(SceneError::new(SceneErrorKind::MissingKey {
            key: key.to_string(),
            note: Some(format!(
                "required with support `{}` when `beam.stiffness` is an array",
                support_name(support)
            )),
        })),
        (None, NumOrArray::Array(_)) => Ok(0.0),
    };
    if let NumOrArray::Number(k) = stiffness {
        // Checked here as well as in `validate`: with n = 1 the number is not stored.
        check_spring("beam.stiffness", k)?;
    }
    if let NumOrArray::Array(v) = &stiffness {
        // A wrong count is reported before a missing end spring.
        if v.len() != n - 1 {
            return Err(SceneError::count("beam.stiffness", n - 1, v.len()));
        }
    }
    let base_stiffness = default_spring(base_stiffness, has_base, "beam.base_stiffness")?;
    let tip_stiffness = default_spring(tip_stiffness, has_tip, "beam.tip_stiffness")?;
    let stiffness = stiffness.expand("beam.stiffness", n - 1)?;
    Ok(Beam {
        lengths,
        masses,
        stiffness,
        base_stiffness,
        tip_stiffness,
        support,
        reaction_force,
        joint_damping: Vec::new(),
    })
}
