//! Scenes: the beam, its support, loads, time grid, control and objective.
//!
//! A [`Scene`] is plain data. It is built in code with [`SceneBuilder`] ([`Scene::builder`]), read
//! from a TOML scene file with [`Scene::from_file`] / [`Scene::from_toml_str`] (or `str::parse`),
//! written with [`Scene::to_toml_string`], and checked by [`Scene::validate`], which rejects bad
//! values with a [`SceneError`] naming the offending key. Ready-made thesis scenes are in
//! [`crate::catalogue`]. The valid ranges are the constants [`LENGTH_RANGE`], [`MASS_RANGE`],
//! [`STIFFNESS_RANGE`], [`FORCE_RANGE`], [`GRAVITY_RANGE`], [`DRAG_RANGE`], [`STEP_RANGE`] and
//! [`MAX_STEP_NUMBER`]; the size limits are [`MAX_PENDULUMS`], [`MAX_STEPS`] and
//! [`MAX_TRAJECTORY_BYTES`].
//!
//! The rest of this page is the repository's `docs/scene-format.md`; the conventions it refers to
//! (coordinates, signs, M₀, time grid) are in `docs/conventions.md`, which is also part of the
//! [crate documentation](crate#conventions).
//!
#![doc = include_str!("../../docs/scene-format.md")]

mod builder;
mod error;
mod raw;
mod validate;

use std::path::Path;

use serde::{Deserialize, Serialize};

pub use builder::SceneBuilder;
pub use error::{SceneError, SceneErrorKind};
pub use validate::{
    human_bytes, ValueRange, DRAG_RANGE, FORCE_RANGE, GRAVITY_RANGE, LENGTH_RANGE, MASS_RANGE,
    MAX_PENDULUMS, MAX_STEPS, MAX_STEP_NUMBER, MAX_TRAJECTORY_BYTES, STEP_RANGE, STIFFNESS_RANGE,
};

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
}

/// A point load F at node `node` (eq. 2.2.2); thesis sign: it enters H as +F z, so F > 0 pushes
/// toward −z.
#[derive(Clone, Debug, PartialEq)]
pub struct PointLoad {
    /// Node index 1..=n.
    pub node: usize,
    /// Force F \[N\].
    pub force: f64,
    /// The load acts for t_k ≥ `start` (default 0).
    pub start: f64,
    /// The load acts for t_k < `end` (default: forever).
    pub end: Option<f64>,
}

/// External loads.
#[derive(Clone, Debug, PartialEq, Default)]
pub struct Loads {
    /// Gravitational acceleration g \[m/s²\] (§2.2.2); 0 means no gravity term is computed.
    pub gravity: f64,
    /// Drag constant D \[kg/m\] of F_D(p) = −D p ⊙ |p| (eq. 2.4.4); 0 means no drag is computed.
    pub drag: f64,
    /// Point loads.
    pub points: Vec<PointLoad>,
}

/// The time grid t_k = k h, k = 0..=N.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TimeGrid {
    /// Step h \[s\].
    pub step: f64,
    /// Number of steps N.
    pub steps: usize,
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
    /// applied, or an optimiser's initial guess.
    pub values: Vec<f64>,
}

/// Which bending-moment objective a scene asks for (thesis §3.3).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum ObjectiveKind {
    /// c = M₀(t_N)² (eq. 3.3.2).
    Final,
    /// c_sum = Σ_{k=0}^{N} M₀(t_k)² (eq. 3.3.4).
    Sum,
}

/// A complete simulation / optimal-control scene.
#[derive(Clone, Debug, PartialEq)]
pub struct Scene {
    /// The beam.
    pub beam: Beam,
    /// External loads.
    pub loads: Loads,
    /// Time grid.
    pub time: TimeGrid,
    /// Optional control.
    pub control: Option<Control>,
    /// Optional objective.
    pub objective: Option<ObjectiveKind>,
}

impl Scene {
    /// Number of pendulums n.
    pub fn n(&self) -> usize {
        self.beam.lengths.len()
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
    pub fn from_toml_str(text: &str) -> Result<Scene, SceneError> {
        let raw = raw::parse(text)?;
        let scene = raw.into_scene()?;
        scene.validate()?;
        Ok(scene)
    }

    /// Reads, parses and validates a scene file; errors name the file.
    pub fn from_file(path: impl AsRef<Path>) -> Result<Scene, SceneError> {
        let path = path.as_ref();
        let text = std::fs::read_to_string(path).map_err(|e| {
            SceneError::new(SceneErrorKind::Io {
                message: e.to_string(),
            })
            .with_file(path)
        })?;
        Self::from_toml_str(&text).map_err(|e| e.with_file(path))
    }

    /// The scene as a scene file, with every value explicit (end springs, loads,
    /// control node). Per-pendulum values are written as one number when they are all equal.
    /// For a valid scene, `Scene::from_toml_str(&s.to_toml_string()) == Ok(s)`.
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
