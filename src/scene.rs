//! Scenes: the beam, its support, loads, time grid, control and objective (SPEC §5).
//!
//! A [`Scene`] is plain data. It is built in code with [`SceneBuilder`] ([`Scene::builder`]), read
//! from the TOML format of SPEC §5 with [`Scene::from_toml_str`] / [`Scene::from_file`] (or
//! `str::parse`), written with [`Scene::to_toml_string`], and checked by [`Scene::validate`], which
//! rejects bad values with a [`SceneError`] naming the offending key. Ready-made thesis scenes are
//! in [`crate::catalogue`].
//!
//! # The TOML format (SPEC §5)
//! ```toml
//! [beam]
//! pendulums = 10            # n ≥ 1
//! length = 1.0              # l_i: a number, or an array of n numbers
//! mass = 1.0                # m_i: a number, or an array of n numbers
//! stiffness = 1000.0        # interior springs k_2..k_n: a number, or an array of n-1
//! support = "riser"         # "cantilever" | "riser" | "fixed-fixed" | "pinned-pinned"
//! base_stiffness = 2000.0   # k_1 (optional)
//! tip_stiffness = 2000.0    # k_{n+1} (optional)
//! reaction_force = false    # optional, extension (see below)
//!
//! [loads]                   # optional
//! gravity = 0.0             # g in m/s^2 (default 0)
//! drag = 0.0                # D in kg/m (default 0)
//! [[loads.point]]           # zero or more
//! node = 5                  # 1..n
//! force = 2.0               # thesis sign: +F z in H
//! start = 0.0               # optional, extension (see below)
//! end = 5.0                 # optional, extension (see below)
//!
//! [time]
//! step = 0.01               # h > 0
//! steps = 10                # N ≥ 1
//!
//! [control]                 # optional
//! node = 10                 # default: n
//! kind = "constant"         # "constant" | "per-step"
//! values = [0.0]            # 1 value (constant) or N+1 values (per-step)
//!
//! [objective]               # optional
//! kind = "final"            # "final" (eq. 3.3.2) | "sum" (eq. 3.3.4)
//! ```
//! Required: `[beam]` with `pendulums`, `length`, `mass`, `stiffness`, `support`; `[time]` with
//! `step`, `steps`; inside an optional `[control]`, `kind` and `values`; inside an optional
//! `[objective]`, `kind`. Integers are accepted wherever a number is expected (`length = 1`), but
//! counts and nodes (`pendulums`, `steps`, `node`) must be integers. Every other key, at any level,
//! is an error naming it.
//!
//! **Defaults.** `base_stiffness` and `tip_stiffness` default to `stiffness` when `stiffness` is a
//! number. When `stiffness` is an array there is no single value to copy, so `base_stiffness` is
//! then *required* if the support has a base spring (all but pinned-pinned) and `tip_stiffness` is
//! required if it has a tip spring (riser, fixed-fixed); an unused end spring that is not given is
//! stored as 0. `gravity` and `drag` default to 0, `[loads]` to no loads, `control.node` to n.
//!
//! **Extensions beyond SPEC §5** (both optional, so every SPEC file reads unchanged):
//! - `beam.reaction_force = true` selects the reaction-force variant of thesis §3.2
//!   (eq. 3.2.1/3.2.2, [`Beam::reaction_force`]); only allowed with `fixed-fixed` or
//!   `pinned-pinned`. Default `false`.
//! - `start` and `end` on a point load \[s\]: the load acts at the times t_k with
//!   `start ≤ t_k < end` (default `start = 0`, no end). Both must be finite and `start < end`.
//!
//! # Validation
//! [`Scene::validate`] (run by every constructor here) requires: n ≥ 1; every length, mass and the
//! step h positive and finite; spring constants (interior, base, tip) and the drag D finite and
//! ≥ 0; gravity finite; array lengths n (length, mass) and n − 1 (stiffness); N ≥ 1 and t_N = N h
//! finite; point-load and control nodes in 1..=n; load forces and times finite with start < end;
//! 1 control value for `constant`, N + 1 for `per-step`, all finite; `reaction_force` only for
//! fixed-fixed and pinned-pinned.
//!
//! **Size limits**, so that a mistyped file fails with a clear error instead of exhausting memory:
//! n ≤ [`MAX_PENDULUMS`] (10⁶), N ≤ [`MAX_STEPS`] (10⁷) and (N + 1)·n ≤ [`MAX_STORED_STATES`]
//! (2·10⁸ stored node states; a trajectory stores q, p, λ and μ per node and step, about 48 bytes
//! per node state in planar `f64`, so the limit is ≈ 10 GB; dual numbers need more).
//!
//! # Errors
//! A [`SceneError`] carries the file (when read with [`Scene::from_file`]) and a
//! [`SceneErrorKind`] naming the key in TOML notation, with array indices where they matter
//! (`beam.length[3]`, `loads.point[0].node`, `control.values`). A number given as a scalar is
//! named without index (`beam.mass`); so is an array whose entries are all equal. For example:
//! ``scene.toml: key `beam.mass`: must be positive and finite, got -1``.

use std::fmt;
use std::ops::Range;
use std::path::{Path, PathBuf};

use serde::de::{SeqAccess, Visitor};
use serde::{Deserialize, Deserializer, Serialize, Serializer};
use toml::de::{DeTable, DeValue};
use toml::Spanned;

/// Largest number of pendulums n a scene may have.
pub const MAX_PENDULUMS: usize = 1_000_000;
/// Largest number of time steps N a scene may have.
pub const MAX_STEPS: usize = 10_000_000;
/// Largest number of stored node states (N + 1)·n a scene may need (about 48 bytes each for a
/// planar `f64` trajectory, so ≈ 10 GB at the limit).
pub const MAX_STORED_STATES: usize = 200_000_000;

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
}

/// The control force u at node `node` (eq. 3.1.1 with eq. 2.2.2's load form; thesis sign).
#[derive(Clone, Debug, PartialEq)]
pub struct Control {
    /// Node index 1..=n (default n, the tip).
    pub node: usize,
    /// Constant or per-step.
    pub kind: ControlKind,
    /// 1 value (constant) or N + 1 values (per-step) \[N\]: applied, or an optimiser's initial guess.
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
// Errors
// ---------------------------------------------------------------------------------------------

/// What is wrong with a scene. Every variant except [`Syntax`](Self::Syntax) and
/// [`Io`](Self::Io) names the offending key in TOML notation (`beam.length[3]`,
/// `loads.point[0].node`, `control.values`).
#[derive(Clone, Debug, PartialEq)]
#[non_exhaustive]
pub enum SceneErrorKind {
    /// The text is not valid TOML.
    Syntax {
        /// 1-based line of the error, when known.
        line: Option<usize>,
        /// 1-based column (in characters) of the error, when known.
        column: Option<usize>,
        /// The parser's description.
        message: String,
    },
    /// A key that the format does not have.
    UnknownKey {
        /// The full key, e.g. `beam.lenght`.
        key: String,
        /// The keys allowed at that place.
        expected: Vec<String>,
    },
    /// A required key is absent.
    MissingKey {
        /// The full key, e.g. `time.step`.
        key: String,
        /// Why it is required, when that depends on other keys.
        note: Option<String>,
    },
    /// A value of the wrong TOML type (a string for a number, a float for a count, ...).
    WrongType {
        /// The full key.
        key: String,
        /// What the key takes, e.g. `a number or an array of numbers`.
        expected: String,
        /// What was found, e.g. `string "abc"`.
        found: String,
    },
    /// A value of the right type but not allowed: non-finite, out of range, unknown name, over a
    /// size limit.
    InvalidValue {
        /// The full key.
        key: String,
        /// What is wrong, e.g. `must be positive and finite, got -1`.
        reason: String,
    },
    /// A node index outside 1..=n.
    NodeOutOfRange {
        /// The full key, e.g. `loads.point[0].node`.
        key: String,
        /// The node given.
        node: i64,
        /// The number of pendulums n.
        n: usize,
    },
    /// An array with the wrong number of values.
    WrongCount {
        /// The full key, e.g. `control.values`.
        key: String,
        /// The number of values required.
        expected: usize,
        /// The number of values given.
        found: usize,
    },
    /// The scene file could not be read.
    Io {
        /// The operating system's message.
        message: String,
    },
}

impl SceneErrorKind {
    /// The offending key, if the error has one.
    pub fn key(&self) -> Option<&str> {
        match self {
            Self::UnknownKey { key, .. }
            | Self::MissingKey { key, .. }
            | Self::WrongType { key, .. }
            | Self::InvalidValue { key, .. }
            | Self::NodeOutOfRange { key, .. }
            | Self::WrongCount { key, .. } => Some(key),
            Self::Syntax { .. } | Self::Io { .. } => None,
        }
    }
}

/// `key` for display: the document itself when empty.
fn show_key(key: &str) -> &str {
    if key.is_empty() {
        "<document>"
    } else {
        key
    }
}

impl fmt::Display for SceneErrorKind {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::Syntax {
                line,
                column,
                message,
            } => match (line, column) {
                (Some(l), Some(c)) => write!(f, "syntax error at line {l}, column {c}: {message}"),
                (Some(l), None) => write!(f, "syntax error at line {l}: {message}"),
                _ => write!(f, "syntax error: {message}"),
            },
            Self::UnknownKey { key, expected } => {
                write!(f, "key `{}`: unknown key", show_key(key))?;
                if !expected.is_empty() {
                    let list: Vec<String> = expected.iter().map(|k| format!("`{k}`")).collect();
                    write!(f, " (expected one of {})", list.join(", "))?;
                }
                Ok(())
            }
            Self::MissingKey { key, note } => {
                write!(f, "key `{}`: missing required key", show_key(key))?;
                if let Some(note) = note {
                    write!(f, " ({note})")?;
                }
                Ok(())
            }
            Self::WrongType {
                key,
                expected,
                found,
            } => write!(
                f,
                "key `{}`: wrong type: expected {expected}, got {found}",
                show_key(key)
            ),
            Self::InvalidValue { key, reason } => write!(f, "key `{}`: {reason}", show_key(key)),
            Self::NodeOutOfRange { key, node, n } => write!(
                f,
                "key `{}`: node {node} is out of range (nodes are 1..={n})",
                show_key(key)
            ),
            Self::WrongCount {
                key,
                expected,
                found,
            } => write!(
                f,
                "key `{}`: expected {expected} value{}, got {found}",
                show_key(key),
                if *expected == 1 { "" } else { "s" }
            ),
            Self::Io { message } => write!(f, "cannot read scene file: {message}"),
        }
    }
}

/// `"<file>: "` or `"invalid scene: "`.
fn file_prefix(file: &Option<PathBuf>) -> String {
    match file {
        Some(p) => format!("{}: ", p.display()),
        None => "invalid scene: ".to_string(),
    }
}

/// A problem with a scene: the file it came from (if any) and what is wrong
/// ([`SceneErrorKind`], which names the key). Displayed as
/// ``scene.toml: key `beam.mass`: must be positive and finite, got -1``.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
#[error("{}{kind}", file_prefix(.file))]
pub struct SceneError {
    /// The scene file, when the scene was read with [`Scene::from_file`].
    pub file: Option<PathBuf>,
    /// What is wrong.
    pub kind: SceneErrorKind,
}

impl SceneError {
    /// An error without a file.
    pub fn new(kind: SceneErrorKind) -> Self {
        Self { file: None, kind }
    }

    /// The same error, attributed to `file`.
    pub fn with_file(mut self, file: impl AsRef<Path>) -> Self {
        self.file = Some(file.as_ref().to_path_buf());
        self
    }

    /// The offending key, if the error has one (see [`SceneErrorKind::key`]).
    pub fn key(&self) -> Option<&str> {
        self.kind.key()
    }

    fn invalid(key: impl Into<String>, reason: impl Into<String>) -> Self {
        Self::new(SceneErrorKind::InvalidValue {
            key: key.into(),
            reason: reason.into(),
        })
    }

    fn count(key: impl Into<String>, expected: usize, found: usize) -> Self {
        Self::new(SceneErrorKind::WrongCount {
            key: key.into(),
            expected,
            found,
        })
    }
}

impl From<SceneErrorKind> for SceneError {
    fn from(kind: SceneErrorKind) -> Self {
        Self::new(kind)
    }
}

// ---------------------------------------------------------------------------------------------
// Raw (file-shaped) structures
// ---------------------------------------------------------------------------------------------

/// A number, or an array of numbers (`length`, `mass`, `stiffness`).
#[derive(Clone, Debug, PartialEq)]
enum NumOrArray {
    Number(f64),
    Array(Vec<f64>),
}

impl<'de> Deserialize<'de> for NumOrArray {
    // Hand-written rather than `#[serde(untagged)]`: a bad element of an array is then reported at
    // its own index, and a bad value says what the key takes.
    fn deserialize<D: Deserializer<'de>>(deserializer: D) -> Result<Self, D::Error> {
        struct NumOrArrayVisitor;
        impl<'de> Visitor<'de> for NumOrArrayVisitor {
            type Value = NumOrArray;
            fn expecting(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
                f.write_str("a number or an array of numbers")
            }
            fn visit_f64<E: serde::de::Error>(self, v: f64) -> Result<NumOrArray, E> {
                Ok(NumOrArray::Number(v))
            }
            fn visit_i64<E: serde::de::Error>(self, v: i64) -> Result<NumOrArray, E> {
                Ok(NumOrArray::Number(v as f64))
            }
            fn visit_u64<E: serde::de::Error>(self, v: u64) -> Result<NumOrArray, E> {
                Ok(NumOrArray::Number(v as f64))
            }
            fn visit_seq<A: SeqAccess<'de>>(self, mut seq: A) -> Result<NumOrArray, A::Error> {
                let mut values = Vec::new();
                while let Some(v) = seq.next_element::<f64>()? {
                    values.push(v);
                }
                Ok(NumOrArray::Array(values))
            }
        }
        deserializer.deserialize_any(NumOrArrayVisitor)
    }
}

impl Serialize for NumOrArray {
    fn serialize<S: Serializer>(&self, serializer: S) -> Result<S::Ok, S::Error> {
        match self {
            Self::Number(x) => serializer.serialize_f64(*x),
            Self::Array(v) => serializer.collect_seq(v),
        }
    }
}

impl NumOrArray {
    /// A number if all values are bitwise equal (and there is at least one), else an array.
    fn compact(values: &[f64]) -> Self {
        match values.first() {
            Some(first) if values.iter().all(|v| v.to_bits() == first.to_bits()) => {
                Self::Number(*first)
            }
            _ => Self::Array(values.to_vec()),
        }
    }

    /// `count` values: the number repeated, or the array if it has exactly `count` values.
    fn expand(self, key: &str, count: usize) -> Result<Vec<f64>, SceneError> {
        match self {
            Self::Number(x) => Ok(vec![x; count]),
            Self::Array(v) if v.len() == count => Ok(v),
            Self::Array(v) => Err(SceneError::count(key, count, v.len())),
        }
    }
}

fn is_false(b: &bool) -> bool {
    !*b
}

fn is_positive_zero(x: &f64) -> bool {
    x.to_bits() == 0
}

#[derive(Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct RawScene {
    beam: RawBeam,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    loads: Option<RawLoads>,
    time: RawTime,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    control: Option<RawControl>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    objective: Option<RawObjective>,
}

#[derive(Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct RawBeam {
    pendulums: i64,
    length: NumOrArray,
    mass: NumOrArray,
    stiffness: NumOrArray,
    support: Support,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    base_stiffness: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    tip_stiffness: Option<f64>,
    #[serde(default, skip_serializing_if = "is_false")]
    reaction_force: bool,
}

#[derive(Serialize, Deserialize, Default)]
#[serde(deny_unknown_fields)]
struct RawLoads {
    #[serde(default)]
    gravity: f64,
    #[serde(default)]
    drag: f64,
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    point: Vec<RawPoint>,
}

#[derive(Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct RawPoint {
    node: i64,
    force: f64,
    #[serde(default, skip_serializing_if = "is_positive_zero")]
    start: f64,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    end: Option<f64>,
}

#[derive(Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct RawTime {
    step: f64,
    steps: i64,
}

#[derive(Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct RawControl {
    #[serde(default, skip_serializing_if = "Option::is_none")]
    node: Option<i64>,
    kind: ControlKind,
    values: Vec<f64>,
}

#[derive(Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct RawObjective {
    kind: ObjectiveKind,
}

fn to_i64(x: usize) -> i64 {
    i64::try_from(x).unwrap_or(i64::MAX)
}

impl RawScene {
    fn from_scene(s: &Scene) -> Self {
        let b = &s.beam;
        RawScene {
            beam: RawBeam {
                pendulums: to_i64(s.n()),
                length: NumOrArray::compact(&b.lengths),
                mass: NumOrArray::compact(&b.masses),
                stiffness: NumOrArray::compact(&b.stiffness),
                support: b.support,
                base_stiffness: Some(b.base_stiffness),
                tip_stiffness: Some(b.tip_stiffness),
                reaction_force: b.reaction_force,
            },
            loads: Some(RawLoads {
                gravity: s.loads.gravity,
                drag: s.loads.drag,
                point: s
                    .loads
                    .points
                    .iter()
                    .map(|p| RawPoint {
                        node: to_i64(p.node),
                        force: p.force,
                        start: p.start,
                        end: p.end,
                    })
                    .collect(),
            }),
            time: RawTime {
                step: s.time.step,
                steps: to_i64(s.time.steps),
            },
            control: s.control.as_ref().map(|c| RawControl {
                node: Some(to_i64(c.node)),
                kind: c.kind,
                values: c.values.clone(),
            }),
            objective: s.objective.map(|kind| RawObjective { kind }),
        }
    }

    fn into_scene(self) -> Result<Scene, SceneError> {
        let n = positive_count("beam.pendulums", self.beam.pendulums)?;
        let steps = positive_count("time.steps", self.time.steps)?;
        check_size(n, steps)?;
        let b = self.beam;
        let beam = assemble_beam(
            n,
            b.length,
            b.mass,
            b.stiffness,
            b.base_stiffness,
            b.tip_stiffness,
            b.support,
            b.reaction_force,
        )?;
        let raw_loads = self.loads.unwrap_or_default();
        let mut points = Vec::with_capacity(raw_loads.point.len());
        for (i, p) in raw_loads.point.into_iter().enumerate() {
            points.push(PointLoad {
                node: node_index(&format!("loads.point[{i}].node"), p.node, n)?,
                force: p.force,
                start: p.start,
                end: p.end,
            });
        }
        let control = match self.control {
            None => None,
            Some(c) => Some(Control {
                node: match c.node {
                    Some(node) => node_index("control.node", node, n)?,
                    None => n,
                },
                kind: c.kind,
                values: c.values,
            }),
        };
        Ok(Scene {
            beam,
            loads: Loads {
                gravity: raw_loads.gravity,
                drag: raw_loads.drag,
                points,
            },
            time: TimeGrid {
                step: self.time.step,
                steps,
            },
            control,
            objective: self.objective.map(|o| o.kind),
        })
    }
}

/// A count that must be ≥ 1 (the upper limits are checked by [`check_size`]).
fn positive_count(key: &str, v: i64) -> Result<usize, SceneError> {
    match usize::try_from(v) {
        Ok(x) if x >= 1 => Ok(x),
        _ => Err(SceneError::invalid(
            key,
            format!("must be at least 1, got {v}"),
        )),
    }
}

/// A node index in 1..=n.
fn node_index(key: &str, node: i64, n: usize) -> Result<usize, SceneError> {
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

/// The size limits of the module documentation, checked before anything of size n or N is
/// allocated.
fn check_size(n: usize, steps: usize) -> Result<(), SceneError> {
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
    // n ≤ 10⁶ and steps ≤ 10⁷, so this cannot overflow.
    let states = (steps + 1) * n;
    if states > MAX_STORED_STATES {
        return Err(SceneError::invalid(
            "time.steps",
            format!(
                "(N + 1)·n = {states} stored node states for N = {steps}, n = {n} exceeds the \
                 limit of {MAX_STORED_STATES}"
            ),
        ));
    }
    Ok(())
}

/// Whether the support has a base spring k₁ / a tip spring k_{n+1}.
fn end_springs(support: Support) -> (bool, bool) {
    match support {
        Support::Cantilever => (true, false),
        Support::Riser | Support::FixedFixed => (true, true),
        Support::PinnedPinned => (false, false),
    }
}

/// Builds the beam from file-shaped values, applying the defaults of the module documentation.
/// `n` must have passed [`check_size`].
#[allow(clippy::too_many_arguments)]
fn assemble_beam(
    n: usize,
    length: NumOrArray,
    mass: NumOrArray,
    stiffness: NumOrArray,
    base_stiffness: Option<f64>,
    tip_stiffness: Option<f64>,
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
    })
}

fn support_name(support: Support) -> &'static str {
    match support {
        Support::Cantilever => "cantilever",
        Support::Riser => "riser",
        Support::FixedFixed => "fixed-fixed",
        Support::PinnedPinned => "pinned-pinned",
    }
}

fn check_positive(key: &str, x: f64) -> Result<(), SceneError> {
    if x.is_finite() && x > 0.0 {
        Ok(())
    } else {
        Err(SceneError::invalid(
            key,
            format!("must be positive and finite, got {x}"),
        ))
    }
}

fn check_spring(key: &str, x: f64) -> Result<(), SceneError> {
    if x.is_finite() && x >= 0.0 {
        Ok(())
    } else {
        Err(SceneError::invalid(
            key,
            format!("must be finite and non-negative, got {x}"),
        ))
    }
}

fn check_finite(key: &str, x: f64) -> Result<(), SceneError> {
    if x.is_finite() {
        Ok(())
    } else {
        Err(SceneError::invalid(key, format!("must be finite, got {x}")))
    }
}

/// Checks every value of a per-pendulum array; the key has an index unless all values are equal
/// (then the file form is a single number, see [`NumOrArray::compact`]).
fn check_all(
    key: &str,
    values: &[f64],
    check: fn(&str, f64) -> Result<(), SceneError>,
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

// ---------------------------------------------------------------------------------------------
// Locating serde errors in the document
// ---------------------------------------------------------------------------------------------

/// 1-based line and column (in characters) of a byte offset.
fn line_column(text: &str, offset: usize) -> (usize, usize) {
    let mut offset = offset.min(text.len());
    while !text.is_char_boundary(offset) {
        offset -= 1;
    }
    let before = &text[..offset];
    let line = before.matches('\n').count() + 1;
    let column = before.rsplit('\n').next().map_or(0, |s| s.chars().count()) + 1;
    (line, column)
}

fn one_line(message: &str) -> String {
    message.split_whitespace().collect::<Vec<_>>().join(" ")
}

fn syntax_error(text: &str, err: &toml::de::Error) -> SceneError {
    let (line, column) = match err.span() {
        Some(span) => {
            let (l, c) = line_column(text, span.start);
            (Some(l), Some(c))
        }
        None => (None, None),
    };
    SceneErrorKind::Syntax {
        line,
        column,
        message: one_line(err.message()),
    }
    .into()
}

/// A key as a path segment: bare if it may be written bare in TOML, else quoted.
fn segment(key: &str) -> String {
    if !key.is_empty()
        && key
            .chars()
            .all(|c| c.is_ascii_alphanumeric() || c == '_' || c == '-')
    {
        key.to_string()
    } else {
        format!("{key:?}")
    }
}

fn join(prefix: &str, key: &str) -> String {
    if prefix.is_empty() {
        key.to_string()
    } else {
        format!("{prefix}.{key}")
    }
}

/// Where a serde error points: the key path and the TOML type of the value there.
struct Location {
    exact: bool,
    depth: usize,
    path: String,
    type_name: Option<&'static str>,
}

/// Keeps the better of `best` and a new candidate: exact span matches beat containing values,
/// deeper beats shallower.
fn consider(
    best: &mut Option<Location>,
    exact: bool,
    depth: usize,
    path: &str,
    type_name: Option<&'static str>,
) {
    let better = match best {
        None => true,
        Some(b) => (exact, depth) > (b.exact, b.depth),
    };
    if better {
        *best = Some(Location {
            exact,
            depth,
            path: path.to_string(),
            type_name,
        });
    }
}

fn contains(outer: &Range<usize>, inner: &Range<usize>) -> bool {
    outer.start < outer.end && outer.start <= inner.start && inner.end <= outer.end
}

fn walk_table(
    table: &DeTable<'_>,
    prefix: &str,
    depth: usize,
    target: &Range<usize>,
    best: &mut Option<Location>,
) {
    for (key, value) in table.iter() {
        let path = join(prefix, &segment(key.get_ref()));
        if key.span() == *target {
            consider(best, true, depth, &path, None);
        }
        walk_value(value, &path, depth, target, best);
    }
}

fn walk_value(
    value: &Spanned<DeValue<'_>>,
    path: &str,
    depth: usize,
    target: &Range<usize>,
    best: &mut Option<Location>,
) {
    let span = value.span();
    let type_name = Some(value.get_ref().type_str());
    if span == *target {
        consider(best, true, depth, path, type_name);
    } else if contains(&span, target) {
        consider(best, false, depth, path, type_name);
    }
    match value.get_ref() {
        DeValue::Table(t) => walk_table(t, path, depth + 1, target, best),
        DeValue::Array(a) => {
            for (i, item) in a.iter().enumerate() {
                walk_value(item, &format!("{path}[{i}]"), depth + 1, target, best);
            }
        }
        _ => {}
    }
}

/// The key or value at `span`: the deepest exact match, else (unless `exact_only`) the deepest
/// value containing it, else the document itself (empty path).
fn locate(doc: &Spanned<DeTable<'_>>, span: &Range<usize>, exact_only: bool) -> Location {
    let mut best = None;
    walk_table(doc.get_ref(), "", 1, span, &mut best);
    match best {
        Some(b) if b.exact || !exact_only => b,
        _ => Location {
            exact: false,
            depth: 0,
            path: String::new(),
            type_name: None,
        },
    }
}

/// The names between backticks in `s`.
fn backticked(s: &str) -> Vec<String> {
    s.split('`')
        .skip(1)
        .step_by(2)
        .map(str::to_string)
        .collect()
}

fn pretty_expected(s: &str) -> String {
    let s = s.trim();
    match s {
        "f64" => "a number".to_string(),
        "i64" => "an integer".to_string(),
        "a sequence" => "an array".to_string(),
        "a boolean" => "a boolean (true or false)".to_string(),
        _ if s.starts_with("struct ") => "a table".to_string(),
        _ if s.starts_with("enum ") => "a string".to_string(),
        _ => s.to_string(),
    }
}

fn pretty_found(s: &str) -> String {
    let s = s.trim();
    match s {
        "sequence" => "an array".to_string(),
        "map" => "a table".to_string(),
        _ => s.replacen("floating point", "float", 1),
    }
}

/// Turns a serde error of the raw structures into a keyed [`SceneError`].
fn classify(err: &toml::de::Error, doc: &Spanned<DeTable<'_>>) -> SceneError {
    let message = one_line(err.message());
    // A missing field points at its table (a header, or the document start): only an exact match
    // is that table, anything merely containing the span is not.
    let exact_only = message.starts_with("missing field ");
    let (path, type_name) = match err.span() {
        Some(span) => {
            let at = locate(doc, &span, exact_only);
            (at.path, at.type_name)
        }
        None => (String::new(), None),
    };
    let kind = if let Some(rest) = message.strip_prefix("unknown field ") {
        let names = backticked(rest);
        let field = names.first().cloned().unwrap_or_default();
        let last = path.rsplit('.').next().unwrap_or("");
        let key = if last == segment(&field) {
            path
        } else {
            join(&path, &segment(&field))
        };
        SceneErrorKind::UnknownKey {
            key,
            expected: names.into_iter().skip(1).collect(),
        }
    } else if let Some(rest) = message.strip_prefix("missing field ") {
        let field = backticked(rest).into_iter().next().unwrap_or_default();
        SceneErrorKind::MissingKey {
            key: join(&path, &segment(&field)),
            note: None,
        }
    } else if let Some(rest) = message.strip_prefix("invalid type: ") {
        let (found, expected) = rest.rsplit_once(", expected ").unwrap_or((rest, "?"));
        SceneErrorKind::WrongType {
            key: path,
            expected: pretty_expected(expected),
            found: pretty_found(found),
        }
    } else if let Some(rest) = message.strip_prefix("invalid value: ") {
        let (found, expected) = rest.rsplit_once(", expected ").unwrap_or((rest, "?"));
        SceneErrorKind::InvalidValue {
            key: path,
            reason: format!(
                "expected {}, got {}",
                pretty_expected(expected),
                found.trim()
            ),
        }
    } else if let Some(rest) = message.strip_prefix("unknown variant ") {
        SceneErrorKind::InvalidValue {
            key: path,
            reason: format!("unknown value {rest}"),
        }
    } else if message == "wanted string or table" {
        // toml's message for an enum (support, kind) given as another type
        SceneErrorKind::WrongType {
            key: path,
            expected: "a string".to_string(),
            found: type_name.unwrap_or("another type").to_string(),
        }
    } else {
        SceneErrorKind::InvalidValue {
            key: path,
            reason: message,
        }
    };
    kind.into()
}

// ---------------------------------------------------------------------------------------------
// Scene: reading, writing, validating
// ---------------------------------------------------------------------------------------------

impl Scene {
    /// A [`SceneBuilder`] for `n` pendulums with the builder's defaults.
    pub fn builder(n: usize) -> SceneBuilder {
        SceneBuilder::new(n)
    }

    /// Parses and validates a scene in the TOML format of SPEC §5 (see the
    /// [module documentation](self) for defaults, extensions and limits).
    pub fn from_toml_str(text: &str) -> Result<Scene, SceneError> {
        let doc = DeTable::parse(text).map_err(|e| syntax_error(text, &e))?;
        let raw: RawScene = toml::from_str(text).map_err(|e| classify(&e, &doc))?;
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

    /// The scene in the TOML format of SPEC §5, with every value explicit (end springs, loads,
    /// control node). Per-pendulum values are written as one number when they are all equal.
    /// For a valid scene, `Scene::from_toml_str(&s.to_toml_string()) == Ok(s)`.
    pub fn to_toml_string(&self) -> String {
        toml::to_string(&RawScene::from_scene(self))
            .expect("serialising plain tables of numbers, strings and arrays cannot fail")
    }

    /// Checks the rules of the [module documentation](self) (and the size limits); the error names
    /// the first offending key.
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
        check_all("beam.mass", &b.masses, check_positive)?;
        check_all("beam.stiffness", &b.stiffness, check_spring)?;
        check_spring("beam.base_stiffness", b.base_stiffness)?;
        check_spring("beam.tip_stiffness", b.tip_stiffness)?;
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
        check_finite("loads.gravity", self.loads.gravity)?;
        check_spring("loads.drag", self.loads.drag)?;
        for (i, p) in self.loads.points.iter().enumerate() {
            let key = |k: &str| format!("loads.point[{i}].{k}");
            node_index(&key("node"), to_i64(p.node), n)?;
            check_finite(&key("force"), p.force)?;
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
        }
        check_positive("time.step", self.time.step)?;
        let t_end = self.time.step * self.time.steps as f64;
        if !t_end.is_finite() {
            return Err(SceneError::invalid(
                "time.step",
                format!("the final time N·h = {t_end} must be finite"),
            ));
        }
        if let Some(c) = &self.control {
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
            let expected = match c.kind {
                ControlKind::Constant => 1,
                ControlKind::PerStep => self.time.steps + 1,
            };
            if c.values.len() != expected {
                return Err(SceneError::count(
                    "control.values",
                    expected,
                    c.values.len(),
                ));
            }
            for (i, &u) in c.values.iter().enumerate() {
                check_finite(&format!("control.values[{i}]"), u)?;
            }
        }
        Ok(())
    }
}

impl std::str::FromStr for Scene {
    type Err = SceneError;

    /// Same as [`Scene::from_toml_str`].
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        Self::from_toml_str(s)
    }
}

// ---------------------------------------------------------------------------------------------
// Builder
// ---------------------------------------------------------------------------------------------

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
    loads: Loads,
    time: TimeGrid,
    control: Option<Control>,
    objective: Option<ObjectiveKind>,
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
            loads: Loads::default(),
            time: TimeGrid {
                step: 0.01,
                steps: 10,
            },
            control: None,
            objective: None,
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

    /// Drag constant D \[kg/m\].
    pub fn drag(mut self, d: f64) -> Self {
        self.loads.drag = d;
        self
    }

    /// Adds a point load `force` \[N\] at `node` (1..=n), acting for all t.
    pub fn point_load(mut self, node: usize, force: f64) -> Self {
        self.loads.points.push(PointLoad {
            node,
            force,
            start: 0.0,
            end: None,
        });
        self
    }

    /// Adds a point load `force` at `node` acting for `start ≤ t_k < end` \[s\].
    pub fn point_load_window(mut self, node: usize, force: f64, start: f64, end: f64) -> Self {
        self.loads.points.push(PointLoad {
            node,
            force,
            start,
            end: Some(end),
        });
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

    /// A constant control `u` \[N\] at `node`.
    pub fn control_constant(mut self, node: usize, u: f64) -> Self {
        self.control = Some(Control {
            node,
            kind: ControlKind::Constant,
            values: vec![u],
        });
        self
    }

    /// A per-step control u_0..u_N (N + 1 values) at `node`.
    pub fn control_per_step(mut self, node: usize, values: Vec<f64>) -> Self {
        self.control = Some(Control {
            node,
            kind: ControlKind::PerStep,
            values,
        });
        self
    }

    /// The objective.
    pub fn objective(mut self, kind: ObjectiveKind) -> Self {
        self.objective = Some(kind);
        self
    }

    /// The validated scene.
    pub fn build(self) -> Result<Scene, SceneError> {
        check_size(self.n, self.time.steps)?;
        let beam = assemble_beam(
            self.n,
            self.length,
            self.mass,
            self.stiffness,
            self.base_stiffness,
            self.tip_stiffness,
            self.support,
            self.reaction_force,
        )?;
        let scene = Scene {
            beam,
            loads: self.loads,
            time: self.time,
            control: self.control,
            objective: self.objective,
        };
        scene.validate()?;
        Ok(scene)
    }
}
