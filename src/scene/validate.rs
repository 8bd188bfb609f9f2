//! Validation of a [`Scene`]: counts, nodes, loads, controls and the step numbers, each value
//! against its range ([`super::ranges`]) and the scene against the size limits
//! ([`super::limits`]), docs/scene-format.md's "Valid ranges" and "Size limits".

use super::limits::{check_size, MAX_STEP_NUMBER};
use super::ranges::{
    check_range, AXIAL_WEIGHT_RANGE, DRAG_RANGE, FORCE_RANGE, GRAVITY_RANGE, JOINT_DAMPING_RANGE,
    LENGTH_RANGE, MASS_RANGE, PERIOD_RANGE, STEP_RANGE, STIFFNESS_RANGE,
};
use super::values::{to_i64, NumOrArray};
use super::{Control, ControlKind, PointLoad, Scene, SceneError, SceneErrorKind, Support};

impl Scene {
    /// Checks the rules of docs/scene-format.md: counts and nodes, the value ranges
    /// ([`LENGTH_RANGE`], [`MASS_RANGE`], ...), the step numbers ([`MAX_STEP_NUMBER`]) and the size
    /// limits ([`MAX_PENDULUMS`](super::MAX_PENDULUMS), [`MAX_STEPS`](super::MAX_STEPS), the wave record's). The error names the first
    /// offending key. The stored trajectory's budget ([`MAX_TRAJECTORY_BYTES`](super::MAX_TRAJECTORY_BYTES)) is not a rule of
    /// the scene but of a run that stores one: [`Scene::check_stored_trajectory`].
    pub fn validate(&self) -> Result<(), SceneError> {
        let n = self.n();
        check_size(n, self.time.steps)?;
        self.check_beam()?;
        self.check_vessel()?;
        check_finite("loads.gravity", self.loads.gravity)?;
        check_range("loads.gravity", self.loads.gravity, &GRAVITY_RANGE)?;
        self.check_pipe_water_soil_stackup()?;
        if let Some(objective) = &self.objective {
            objective.check()?;
        }
        self.check_design()?;
        self.check_loads()?;
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

    /// The `[beam]` table: one mass per pendulum and one stiffness per inner joint, lengths and
    /// masses positive and in range, springs and joint damping valid, the reaction-force variant
    /// only on a beam held at both ends.
    fn check_beam(&self) -> Result<(), SceneError> {
        let n = self.n();
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
        Ok(())
    }

    /// The `[pipe]`, `[water]`, `[soil]` and `[stackup]` tables, in that order; Morison's node
    /// drag ([`Self::check_node_drag`]) in a pipe or a stack-up; a stack-up's layout one entry
    /// per pendulum.
    fn check_pipe_water_soil_stackup(&self) -> Result<(), SceneError> {
        let n = self.n();
        if let Some(pipe) = &self.pipe {
            pipe.check()?;
            self.check_node_drag("pipe", pipe.drag_model)?;
        }
        self.water.check()?;
        if let Some(soil) = &self.soil {
            soil.check(self.beam.lengths.iter().sum())?;
        }
        if let Some(st) = &self.stackup {
            self.check_node_drag("stackup", st.drag_model)?;
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
        Ok(())
    }

    /// Morison's node drag (`<table>.drag_model = "morison"`, `table` = `pipe` or `stackup`) is
    /// not combined with the joint damping (each couples the pendulums' half step in its own way)
    /// and does not use the momentum drag's constant D (`loads.drag` must stay 0).
    fn check_node_drag(&self, table: &str, model: super::DragModel) -> Result<(), SceneError> {
        if model != super::DragModel::Morison {
            return Ok(());
        }
        if !self.beam.joint_damping.is_empty() {
            return Err(SceneError::invalid(
                "beam.joint_damping",
                format!(
                    "the joint damping and `{table}.drag_model = \"morison\"` are not combined \
                     yet (each couples the pendulums' half step in its own way)"
                ),
            ));
        }
        if self.loads.drag != 0.0 {
            let (whence, advice) = if table == "pipe" {
                ("its drag is ½ ρ_w C_d D_o per length from `[pipe]`", "out")
            } else {
                ("each node's drag comes from its segments and bodies", "0")
            };
            return Err(SceneError::invalid(
                "loads.drag",
                format!(
                    "is the momentum drag's constant D, which `{table}.drag_model = \"morison\"` \
                     does not use ({whence}): leave it {advice}, got {}",
                    self.loads.drag
                ),
            ));
        }
        Ok(())
    }

    /// The `[loads]` table's tension, axial weight, momentum drag, point loads and current.
    fn check_loads(&self) -> Result<(), SceneError> {
        let n = self.n();
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
        Ok(())
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
                v.check_for(self.time.initial)?;
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
