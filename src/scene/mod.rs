//! Scenes: the beam, its support, loads, time grid, control and objective.
//!
//! A [`Scene`] is plain data. It is built in code with [`SceneBuilder`] ([`Scene::builder`]), read
//! from a TOML scene file with [`Scene::from_file`] / [`Scene::from_toml_str`] (or `str::parse`),
//! written with [`Scene::to_toml_string`], and checked by [`Scene::validate`], which rejects bad
//! values with a [`SceneError`] naming the offending key. Ready-made thesis scenes are in
//! [`crate::catalogue`]. The valid ranges are the constants [`LENGTH_RANGE`], [`MASS_RANGE`],
//! [`STIFFNESS_RANGE`], [`FORCE_RANGE`], [`GRAVITY_RANGE`], [`DRAG_RANGE`], [`STEP_RANGE`],
//! [`PERIOD_RANGE`] and
//! [`MAX_STEP_NUMBER`]; the size limits are [`MAX_PENDULUMS`] and [`MAX_STEPS`], and a run that
//! stores the trajectory checks [`MAX_TRAJECTORY_BYTES`] ([`Scene::check_stored_trajectory`]).
//!
//! The rest of this page is the repository's `docs/scene-format.md`; the conventions it refers to
//! (coordinates, signs, M₀, time grid) are in `docs/conventions.md`, which is also part of the
//! [crate documentation](crate#conventions).
//!
#![doc = include_str!("../../docs/scene-format.md")]

mod builder;
mod current;
mod design;
mod error;
mod fatigue;
mod limits;
mod mpc;
mod objective;
mod pipe;
mod ranges;
mod raw;
pub(crate) mod series;
mod soil;
mod stackup;
mod toml_errors;
mod valid;
mod validate;
mod values;
mod vessel;
mod waves;

use std::path::Path;

use serde::{Deserialize, Serialize};

pub use crate::input::{
    human_bytes, read_text_file, read_text_file_limited, ReadError, ReadErrorKind, MAX_INPUT_BYTES,
};
pub use builder::SceneBuilder;
pub use current::{
    current_velocity, direction_of_angle, Current, CurrentProfile, DEFAULT_POWER_EXPONENT,
    MAX_POWER_EXPONENT,
};
pub use design::{DesignParameter, DesignTable, FreeParameter, Role};
pub use error::{SceneError, SceneErrorKind};
pub use fatigue::{HotSpotSpec, MAX_HOTSPOT_NAME};
pub use limits::{
    max_trajectory_steps, trajectory_bytes, MAX_PENDULUMS, MAX_STEPS, MAX_STEP_NUMBER,
    MAX_TRAJECTORY_BYTES,
};
pub use mpc::{
    check_forecast_error, Forecast, MomentAbout, MpcPlanObjective, MpcSettings, MpcTable, Observe,
    MPC_KEYS,
};
pub use pipe::{
    drag_weights, DragModel, Pipe, Water, SEA_WATER_DENSITY, STEEL_DENSITY, STEEL_YOUNGS_MODULUS,
};
pub use ranges::{
    stackup_range_of, ValueRange, AXIAL_WEIGHT_RANGE, CURRENT_SPEED_RANGE, DRAG_RANGE, FORCE_RANGE,
    GRAVITY_RANGE, JOINT_DAMPING_RANGE, LENGTH_RANGE, MASS_RANGE, PERIOD_RANGE,
    SOIL_GRADIENT_RANGE, SOIL_MODULUS_RANGE, SOIL_MUDLINE_RANGE, STEP_RANGE, STIFFNESS_RANGE,
};
pub use series::{LoadSeries, MAX_SERIES_BYTES};
pub use soil::{water_height, Soil, SoilLumping};
pub use stackup::{
    Body, FlexJoint, Foot, Layout, NodeTangents, Segment, Stackup, STANDARD_GRAVITY,
};
pub(crate) use valid::{sealed::Validate, Checked};
pub use valid::{SceneInput, ValidScene};
pub use vessel::{
    Rao, Thrust, Vessel, DEFAULT_THRUST_BOUND, DEFAULT_THRUST_RATE_BOUND,
    DEFAULT_VESSEL_ADDED_MASS, DEFAULT_VESSEL_DAMPING, DEFAULT_VESSEL_MASS, DEFAULT_VESSEL_RAMP,
    MAX_RAO_ROWS,
};
pub use waves::{sea_error, WaveLumping, WaveSpectrum, Waves, DEFAULT_GAMMA};

use raw::RawScene;

/// How the beam is held at its two ends (thesis §2.4.1, §3.1).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Support {
    /// Base spring k₁, free tip (k_{n+1} = 0), eq. 2.2.3.
    Cantilever,
    /// Cantilever plus a tip spring k_{n+1}; the tip stays free (§3.1, the marine riser).
    Riser,
    /// Base and tip springs, tip z locked by the constraint l(q) = 0 (eq. 2.4.1/2.4.2).
    FixedFixed,
    /// No end springs, tip z locked by l(q) = 0 (eq. 2.4.3).
    PinnedPinned,
    /// Base and tip springs (the lower and upper flex joints), the tip's z held by the vessel:
    /// l(q) = Z(t), the vessel's position ([`Vessel`], `[vessel]`); planar scenes only.
    Vessel,
}

impl Support {
    /// Whether the support has a base spring k₁ and a tip spring k_{n+1} (docs/conventions.md):
    /// the base except for pinned-pinned, the tip for riser, fixed-fixed and vessel.
    pub fn end_springs(self) -> (bool, bool) {
        match self {
            Support::Cantilever => (true, false),
            Support::Riser | Support::FixedFixed | Support::Vessel => (true, true),
            Support::PinnedPinned => (false, false),
        }
    }

    /// Whether the tip's z is held by a constraint (fixed-fixed, pinned-pinned: at 0; vessel: at
    /// the vessel's position).
    pub fn holds_tip(self) -> bool {
        matches!(
            self,
            Support::FixedFixed | Support::PinnedPinned | Support::Vessel
        )
    }

    /// The name the scene file writes (`support = "pinned-pinned"`).
    pub fn name(self) -> &'static str {
        match self {
            Support::Cantilever => "cantilever",
            Support::Riser => "riser",
            Support::FixedFixed => "fixed-fixed",
            Support::PinnedPinned => "pinned-pinned",
            Support::Vessel => "vessel",
        }
    }
}

/// The chain of pendulums: geometry, masses and spring constants (thesis §2.2.2).
#[derive(Clone, Debug, PartialEq)]
pub struct Beam {
    /// Pendulum lengths l₁..lₙ \[m\]; `lengths.len()` is n.
    pub lengths: Vec<f64>,
    /// Point masses m₁..mₙ \[kg\] at the pendulum ends.
    pub masses: Vec<f64>,
    /// Interior spring constants k₂..kₙ \[Nm/rad\] (n − 1 values).
    pub stiffness: Vec<f64>,
    /// Base spring k₁ \[Nm/rad\] (ignored by pinned-pinned).
    pub base_stiffness: f64,
    /// Tip spring k_{n+1} \[Nm/rad\] (used by riser and fixed-fixed only).
    pub tip_stiffness: f64,
    /// End conditions.
    pub support: Support,
    /// Reaction-force variant (thesis §3.2, eq. 3.2.1/3.2.2): the tip constraint of a fixed-fixed or
    /// pinned-pinned beam is replaced by the reaction force, so a control at the tip can move it.
    pub reaction_force: bool,
    /// Joint dampers c₁..c_{n+1} \[N·m·s/rad\] (`[beam] joint_damping`; empty: none), laid out
    /// like the model's springs k₁..k_{n+1}: joint 1 at the base, n + 1 at the tip, zero where the
    /// support has no spring. The torque −c_j θ̇_j (docs/conventions.md "Joint damping").
    pub joint_damping: Vec<f64>,
}

/// A point load at node `node` (eq. 2.2.2, extended to the transverse plane and to time-varying
/// forces): at time t it is the vector F(t) = (F_x, F_z)(t) with
///
/// F(t) = w(t) · ρ(t) · [ (`force_x`, `force`) + d · Σⱼ Aⱼ sin(2π t/Tⱼ + φⱼ) + S(t) ],
///
/// w the window [`start`, `end`), ρ the ramp-in ([`PointLoad::ramp`]), d the unit
/// [`direction`](PointLoad::direction) of the [`harmonics`](PointLoad::harmonics) and S the
/// linearly interpolated [`series`](PointLoad::series). Thesis sign, for x as for z: the load
/// enters H as +F·r (F_x·x + F_z·z of the node), so F_z > 0 pushes toward −z and F_x > 0 toward
/// −x. A scene with any x component is spatial ([`Scene::is_spatial`]).
#[derive(Clone, Debug, PartialEq)]
pub struct PointLoad {
    /// Node index 1..=n.
    pub node: usize,
    /// The constant force's z component F_z \[N\] (the thesis's F; `force = F` in a file).
    pub force: f64,
    /// The constant force's x component F_x \[N\] (`force = [F_x, F_z]` in a file; default 0).
    pub force_x: f64,
    /// The load acts for t_k ≥ `start` (default 0).
    pub start: f64,
    /// The load acts for t_k < `end` (default: forever).
    pub end: Option<f64>,
    /// Ramp-in time T_r \[s\] (0: none): the whole load is multiplied by
    /// ρ = ½(1 − cos(π (t − start)/T_r)) for start ≤ t < start + T_r, so it rises smoothly from 0.
    pub ramp: f64,
    /// Direction (d_x, d_z) of the harmonics in the transverse plane, normalised by the model
    /// (default (0, 1): along z; must not have zero length).
    pub direction: [f64; 2],
    /// Harmonic components Aⱼ sin(2π t/Tⱼ + φⱼ) along `direction` (a sum of harmonics).
    pub harmonics: Vec<Harmonic>,
    /// A time series (t, F_x, F_z) read from a CSV file, linearly interpolated.
    pub series: Option<LoadSeries>,
}

impl PointLoad {
    /// A constant load F along z at `node` (thesis eq. 2.2.2), acting for all t.
    pub fn new(node: usize, force: f64) -> Self {
        PointLoad {
            node,
            force,
            force_x: 0.0,
            start: 0.0,
            end: None,
            ramp: 0.0,
            direction: [0.0, 1.0],
            harmonics: Vec::new(),
            series: None,
        }
    }

    /// A constant load (F_x, F_z) at `node`.
    pub fn vector(node: usize, force: [f64; 2]) -> Self {
        PointLoad {
            force_x: force[0],
            ..PointLoad::new(node, force[1])
        }
    }

    /// A sum of harmonics along `direction` (d_x, d_z) at `node`, with no constant part.
    pub fn harmonic(node: usize, direction: [f64; 2], harmonics: Vec<Harmonic>) -> Self {
        PointLoad {
            direction,
            harmonics,
            ..PointLoad::new(node, 0.0)
        }
    }

    /// A time series at `node`, with no constant part.
    pub fn series(node: usize, series: LoadSeries) -> Self {
        PointLoad {
            series: Some(series),
            ..PointLoad::new(node, 0.0)
        }
    }

    /// The same load acting for `start` ≤ t_k < `end`.
    pub fn window(mut self, start: f64, end: Option<f64>) -> Self {
        self.start = start;
        self.end = end;
        self
    }

    /// The same load with a ramp-in time T_r (see [`PointLoad::ramp`]).
    pub fn ramped(mut self, ramp: f64) -> Self {
        self.ramp = ramp;
        self
    }

    /// Whether the load has a component along x at any time (it then needs the spatial model).
    pub fn is_spatial(&self) -> bool {
        self.force_x != 0.0
            || (!self.harmonics.is_empty() && self.direction[0] != 0.0)
            || self
                .series
                .as_ref()
                .is_some_and(|s| s.samples.iter().any(|r| r[1] != 0.0))
    }

    /// An upper bound of |F(t)| over all t: |(F_x, F_z)| + Σ|Aⱼ| + max |S| (for the load number of
    /// the step check, docs/scene-format.md).
    pub fn max_magnitude(&self) -> f64 {
        self.force_x.hypot(self.force)
            + self
                .harmonics
                .iter()
                .map(|h| h.amplitude.abs())
                .sum::<f64>()
            + self.series.as_ref().map_or(0.0, |s| {
                s.samples
                    .iter()
                    .fold(0.0f64, |m, r| m.max(r[1].hypot(r[2])))
            })
    }
}

/// One harmonic component A sin(2π t/T + φ) of a point load (a regular wave's force at a node).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Harmonic {
    /// Amplitude A \[N\] (thesis sign along the load's direction).
    pub amplitude: f64,
    /// Period T \[s\] (> 0).
    pub period: f64,
    /// Phase φ \[rad\] at t = 0.
    pub phase: f64,
}

/// External loads.
#[derive(Clone, Debug, PartialEq, Default)]
pub struct Loads {
    /// Gravitational acceleration g \[m/s²\] (§2.2.2); 0 means no gravity term is computed.
    pub gravity: f64,
    /// Drag constant D \[kg/m\] of F_D(p) = −D p ⊙ |p| (eq. 2.4.4; in the spatial model the
    /// transverse part is −D |p_⊥| p_⊥, docs/conventions.md); 0 means no drag is computed.
    pub drag: f64,
    /// Top tension T \[N\] along +y at the tip (`tension`; docs/conventions.md "Axial loads");
    /// 0 means no tension term is computed.
    pub tension: f64,
    /// Axial (submerged) weight w \[N/m\] along −y on every node (`axial_weight`, lumped as the
    /// masses: half a cell at the tip); 0 means no axial-weight term is computed.
    pub axial_weight: f64,
    /// Point loads.
    pub points: Vec<PointLoad>,
    /// A steady current along the depth (`[loads.current]`); with it the drag acts on the
    /// velocity relative to the water.
    pub current: Option<Current>,
    /// An irregular sea state (`[loads.waves]`): the water velocity is the current's plus the
    /// waves' particle velocity, and the waves add their inertia load.
    pub waves: Option<Waves>,
}

/// The time grid t_k = k h, k = 0..=N, and the state the run starts from at t₀ = 0.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TimeGrid {
    /// Step h \[s\].
    pub step: f64,
    /// Number of steps N.
    pub steps: usize,
    /// The initial state (`[time] initial`, default [`Initial::Rest`]).
    pub initial: Initial,
}

/// The state a run starts from at t₀ = 0 (`[time] initial`; docs/conventions.md "The start of
/// a run").
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Initial {
    /// The straight beam at rest: qⱼ = e₂, p = 0 (the thesis's start).
    #[default]
    Rest,
    /// At rest (p = 0) in the static equilibrium of the steady loads at t = 0, ∇U(q₀) = F(0)
    /// ([`crate::statics::static_start`]): gravity and buoyancy, the tension, the springs and
    /// the soil, the current's drag at rest and the vessel's mean offset Z₀ in full, without the
    /// waves and with the control 0. The vessel's offset is then not ramped:
    /// Z(t) = Z₀ + ρ(t) d_z X_w(t).
    Static,
}

impl Initial {
    /// Whether this is the default [`Initial::Rest`].
    pub fn is_rest(&self) -> bool {
        *self == Initial::Rest
    }
}

/// How the control force is parametrised in a scene file.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum ControlKind {
    /// One value u for all k.
    Constant,
    /// One value u_k per time t_k, k = 0..=N.
    PerStep,
    /// P values, piece j acting on the steps k with ⌊k·P/N⌋ = j (k = 0..N−1; u_N takes the last
    /// piece): the N steps split evenly, longer pieces first
    /// ([`crate::simulate::piece_index`], docs/conventions.md). 1 ≤ P ≤ N.
    Piecewise,
}

/// The control force u at node `node` (eq. 3.1.1 with eq. 2.2.2's load form; thesis sign).
#[derive(Clone, Debug, PartialEq)]
pub struct Control {
    /// Node index 1..=n (default n, the tip).
    pub node: usize,
    /// Constant or per-step.
    pub kind: ControlKind,
    /// 1 value (constant), N + 1 values (per-step) or P values (piecewise, 1 ≤ P ≤ N) \[N\]:
    /// applied, or an optimiser's initial guess. The z components u_z of a 2-axis control.
    pub values: Vec<f64>,
    /// The x components u_x of a 2-axis control (as many as `values`; the scene file writes the
    /// pairs [u_x, u_z]), `None` for a control along z. A 2-axis control selects the spatial
    /// model (docs/conventions.md "Two-axis controls").
    pub values_x: Option<Vec<f64>>,
}

/// Which bending-moment objective a scene asks for (thesis §3.3; `[objective]`,
/// docs/scene-format.md).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum ObjectiveKind {
    /// c = M₀(t_N)² (eq. 3.3.2).
    Final,
    /// c_sum = Σ_{k=0}^{N} M₀(t_k)² (eq. 3.3.4).
    Sum,
    /// Σ_{k=0}^{N} |M₀(t_k)|^p, p ≥ 2 ([`crate::PowerObjective`]; p = 2 is c_sum bit for bit).
    Power {
        /// The exponent p (finite, ≥ 2: [`ObjectiveKind::check`]).
        exponent: f64,
    },
    /// The rainflow Miner damage D of the wellhead stress ([`crate::FatigueObjective`],
    /// docs/fatigue.md): `kind = "fatigue"`, resolved when the scene is read from its `[fatigue]` table
    /// and l₁ (a scene file writes it back as `kind = "fatigue"`; not serialised otherwise).
    #[serde(skip)]
    Fatigue(crate::fatigue::WellheadDamage),
}

/// A complete simulation / optimal-control scene.
#[derive(Clone, Debug, PartialEq)]
pub struct Scene {
    /// The beam.
    pub beam: Beam,
    /// External loads.
    pub loads: Loads,
    /// The beam described as a pipe (`[pipe]`), from which `beam`'s lengths, masses and spring
    /// constants were derived; `None` when they were given directly.
    pub pipe: Option<Pipe>,
    /// The beam described as a riser system from the bottom up (`[stackup]`: segments, bodies,
    /// flex joints), from which `beam` was derived; `None` otherwise.
    pub stackup: Option<Stackup>,
    /// The water (`[water]`): depth and density.
    pub water: Water,
    /// The seabed and the soil below it (`[soil]`): the mudline's height on the chain and the
    /// lateral p-y modulus; `None`: the foot is at the seabed and no node is in the soil.
    pub soil: Option<Soil>,
    /// Time grid.
    pub time: TimeGrid,
    /// Optional control.
    pub control: Option<Control>,
    /// Optional objective.
    pub objective: Option<ObjectiveKind>,
    /// Optional `[fatigue]` table: the wellhead's section and S-N curve (`chainbeam fatigue`).
    pub fatigue: Option<crate::fatigue::FatigueSpec>,
    /// The hot spots of `[[fatigue.hotspot]]` (empty: none; `chainbeam fatigue` then assesses
    /// the wellhead alone, [`Scene::hot_spots`]).
    pub hotspots: Vec<HotSpotSpec>,
    /// Optional `[mpc]` table: the closed-loop controllers' settings (`chainbeam fatigue`'s
    /// flags, which override it).
    pub mpc: Option<MpcTable>,
    /// The vessel that holds the top (`[vessel]`), with `support = "vessel"` only (which
    /// defaults it: a vessel that holds the top still over the wellhead).
    pub vessel: Option<Vessel>,
    /// Optional `[design]` table: the parameters a fatigue design may change and their bounds
    /// (`chainbeam design`, [`crate::design`]).
    pub design: Option<DesignTable>,
}

impl Scene {
    /// Number of pendulums n.
    pub fn n(&self) -> usize {
        self.beam.lengths.len()
    }

    /// Whether the scene needs the spatial model (qᵢ ∈ S², `Chain<_, 3>`): some load has a
    /// component along x ([`PointLoad::is_spatial`], or a current with an x component). Otherwise every force lies in the yz-plane
    /// and the planar model (`Chain<_, 2>`) computes the same motion with fewer components.
    pub fn is_spatial(&self) -> bool {
        self.loads.points.iter().any(PointLoad::is_spatial)
            || self
                .loads
                .current
                .as_ref()
                .is_some_and(|c| c.spatial_key().is_some())
            || self.has_two_axis_control()
            || self
                .loads
                .waves
                .is_some_and(|w| w.unit_direction()[0] != 0.0)
    }

    /// The water depth d \[m\] of the waves (and the current), from the mudline: `[water]
    /// depth`, else the current's `surface`, else the beam's length above the mudline (its top at
    /// the mean surface).
    pub fn wave_depth(&self) -> f64 {
        self.water
            .depth
            .or_else(|| self.loads.current.as_ref().and_then(|c| c.surface))
            .unwrap_or_else(|| self.beam.lengths.iter().sum::<f64>() - self.mudline())
    }

    /// The mudline's height above the chain's foot \[m\] (`[soil] mudline`; 0 without `[soil]`):
    /// heights on the chain are mapped to the water by [`water_height`].
    pub fn mudline(&self) -> f64 {
        self.soil.map_or(0.0, |s| s.mudline)
    }

    /// Whether the scene's control is 2-axis (`values` written as pairs [u_x, u_z]).
    pub fn has_two_axis_control(&self) -> bool {
        self.control.as_ref().is_some_and(|c| c.values_x.is_some())
    }

    /// The first key that makes the scene spatial (for messages), e.g. `loads.point[1].force`.
    pub fn spatial_key(&self) -> Option<String> {
        if self.has_two_axis_control() {
            return Some("control.values".to_string());
        }
        let points = self.loads.points.iter().enumerate().find_map(|(i, p)| {
            let key = if p.force_x != 0.0 {
                "force"
            } else if !p.harmonics.is_empty() && p.direction[0] != 0.0 {
                "direction"
            } else if p.is_spatial() {
                "series"
            } else {
                return None;
            };
            Some(format!("loads.point[{i}].{key}"))
        });
        let current = self.loads.current.as_ref().and_then(Current::spatial_key);
        let waves = self
            .loads
            .waves
            .is_some_and(|w| w.unit_direction()[0] != 0.0)
            .then_some("loads.waves.direction");
        points.or_else(|| current.or(waves).map(String::from))
    }
}

// ---------------------------------------------------------------------------------------------
// Scene: reading and writing
// ---------------------------------------------------------------------------------------------

impl Scene {
    /// A [`SceneBuilder`] for `n` pendulums with the builder's defaults.
    pub fn builder(n: usize) -> SceneBuilder {
        SceneBuilder::new(n)
    }

    /// Parses and validates a scene file's text (the format, defaults and limits are in the
    /// [module documentation](self)).
    ///
    /// A load's `series` file is read relative to the current directory; use
    /// [`Scene::from_toml_str_in_dir`] or [`Scene::from_file`] to read it relative to a scene's
    /// directory.
    pub fn from_toml_str(text: &str) -> Result<Scene, SceneError> {
        Self::parse_in(text, None)
    }

    /// As [`Scene::from_toml_str`], with relative `series` file names taken relative to `dir`
    /// (what [`Scene::from_file`] does with the scene file's directory).
    pub fn from_toml_str_in_dir(text: &str, dir: impl AsRef<Path>) -> Result<Scene, SceneError> {
        Self::parse_in(text, Some(dir.as_ref()))
    }

    fn parse_in(text: &str, dir: Option<&Path>) -> Result<Scene, SceneError> {
        let raw = raw::parse(text)?;
        let scene = raw.into_scene(dir)?;
        scene.validate()?;
        Ok(scene)
    }

    /// Reads, parses and validates a scene file; errors name the file. A load's `series` file
    /// name is relative to the scene file's directory. The file is read by the bounded
    /// [`read_text_file`] (at most [`MAX_INPUT_BYTES`], UTF-8 text; a FIFO blocks until a writer
    /// comes).
    pub fn from_file(path: impl AsRef<Path>) -> Result<Scene, SceneError> {
        let path = path.as_ref();
        let text = read_text_file(path).map_err(|e| {
            let kind = match e.kind {
                ReadErrorKind::Io { message, .. } => SceneErrorKind::Io { message },
                reason => SceneErrorKind::Read { reason },
            };
            SceneError::new(kind).with_file(path)
        })?;
        let dir = path.parent().unwrap_or(Path::new(""));
        Self::parse_in(&text, Some(dir)).map_err(|e| e.with_file(path))
    }

    /// The scene as a scene file, with every value explicit (end springs, loads,
    /// control node). Per-pendulum values are written as one number when they are all equal.
    /// For a valid scene, `Scene::from_toml_str(&s.to_toml_string()) == Ok(s)`; a scene with a
    /// load `series` refers to its file by the name it was given
    /// ([`LoadSeries::file`]), so the text reads back from the directory that name is relative to
    /// ([`Scene::from_toml_str_in_dir`]).
    pub fn to_toml_string(&self) -> String {
        toml::to_string(&RawScene::from_scene(self))
            .expect("serialising plain tables of numbers, strings and arrays cannot fail")
    }
}

impl std::str::FromStr for Scene {
    type Err = SceneError;

    /// Same as [`Scene::from_toml_str`].
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        Self::from_toml_str(s)
    }
}
