//! Validation of a [`Scene`]: value ranges, counts, nodes and the size limits.

use super::raw::{to_i64, NumOrArray};
use super::{ControlKind, Scene, SceneError, SceneErrorKind, Support};

/// Largest number of pendulums n a scene may have.
pub const MAX_PENDULUMS: usize = 1_000_000;
/// Largest number of time steps N a scene may have.
pub const MAX_STEPS: usize = 10_000_000;
/// Largest number of stored node states (N + 1)·n a scene may need (about 48 bytes each for a
/// planar `f64` trajectory, so ≈ 10 GB at the limit).
pub const MAX_STORED_STATES: usize = 200_000_000;

impl Scene {
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

/// The size limits of the module documentation, checked before anything of size n or N is
/// allocated.
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

pub(super) fn support_name(support: Support) -> &'static str {
    match support {
        Support::Cantilever => "cantilever",
        Support::Riser => "riser",
        Support::FixedFixed => "fixed-fixed",
        Support::PinnedPinned => "pinned-pinned",
    }
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

pub(super) fn check_spring(key: &str, x: f64) -> Result<(), SceneError> {
    if x.is_finite() && x >= 0.0 {
        Ok(())
    } else {
        Err(SceneError::invalid(
            key,
            format!("must be finite and non-negative, got {x}"),
        ))
    }
}

pub(super) fn check_finite(key: &str, x: f64) -> Result<(), SceneError> {
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
