//! The reduced planning model of [`Mpc`](super::Mpc): the same pipe as a coarser chain with a
//! larger step, on which the controller plans while the plant runs at full resolution
//! ([`MpcOptions::plan_pendulums`](super::MpcOptions::plan_pendulums),
//! [`MpcOptions::plan_step`](super::MpcOptions::plan_step)).
//!
//! A re-plan of the full chain costs a few rollouts and one pass of sensitivities of the whole
//! horizon on n pendulums at the plant's step h; a planning model of n_p < n pendulums at a step
//! h_p > h costs about (n_p/n)·(h/h_p) of it. The planning model is what practice does ("model
//! no more than the control needs"): the lowest modes of a tensioned riser, which the wave and
//! the platform's force excite, are resolved by a few tens of pendulums, and the fastest
//! (zig-zag) mode that limits h (ω_max ≈ 4√(EI/(μ l⁴)), examples/scenes/riser_300m.toml) is
//! 16× slower at a quarter of the pendulums, so the step can grow with l².
//!
//! # The model ([`planning_scene`])
//! The scene's `[pipe]` rebuilt with n_p pendulums ([`crate::scene::Pipe::beam`]: lᵢ = L/n_p, the lumped
//! masses, k = EI/l, the clamped ends' 2EI/l; a flex joint's given end spring is kept), at the
//! step h_p; every load per unit length or by depth (tension, axial weight, current, waves,
//! gravity) as the scene gives it; the momentum drag constant D scaled by n_p/n, because the
//! scene's D matches the Morison load of a uniform flow on the base pendulum,
//! D = ½ ρ_w C_d D_o/(l μ² L) ∝ 1/l (docs/conventions.md "Drag in a current"), and each of the
//! planning chain's pendulums weighted by the factors wᵢ = l₁S₁/(lᵢSᵢ) of *its* lengths and masses
//! ([`Scene::drag_weights`], which the planning scene, still a `[pipe]` scene, gives its model:
//! docs/conventions.md "Equivalent drag constant"), so that plant and plan give every pendulum the
//! same share of Morison's load; the control node
//! and point loads at node j moved to the node at the same height, round(j n_p/n) (at least 1).
//!
//! # A stack-up ([`planning_scene`] of a `[stackup]` scene)
//! The stack-up rebuilt with n_p pendulums by its own rule ([`crate::scene::Stackup::beam`]):
//! every segment and body kept as a piece, each piece's pendulums allotted in proportion to its
//! length, the foot, the soil, the flex joints and the bodies as the scene gives them, the
//! nodes' Morison coefficients (or the momentum drag's D and weights) of the rebuilt layout; a
//! point load or the control at the node of the nearest height. The fewest pendulums is the
//! stack-up's number of pieces (fewer: the stack-up's error naming `beam.pendulums`).
//!
//! # The tip held by the vessel
//! With `support = "vessel"` the top's z is held by the constraint Σ lᵢ qᵢ,z = Z(t) (and its
//! rate). The sampled chords of the map below put the model's top node where the plant's is but
//! their sum falls short of it by the chords' sag, Σ (l_{p,J} − |X_J − X_{J−1}|) Q_J,z; the map
//! therefore shifts every chord by one α toward z (Newton, to round-off) and every Q̇_J by one
//! β Π_J e_z so that the model's state satisfies both, and copies the vessel's own state
//! (Z, Ż: the `tip_target` of a thrust scene) one to one.
//!
//! # The objective
//! The model's M₀ = 2k₁z₁/l₁² = (2/l₁) M_w, with M_w = k₁ θ₁ the wellhead moment of the base
//! spring, so the same M_w weighs (l/l_p)² less in the model, and a sum over steps weighs h/h_p
//! less: Σ_k M₀(t_k)² ≈ (4/(l² h)) ∫ M_w² dt. The plan therefore minimises the plant's objective
//! in the model's units: with r = l/l_p and p the objective's exponent (2 for c and c_sum),
//! ```text
//! ρ_p = ρ r^p h/h_p,   σ_p = σ r^p   (the rate penalty (σ/h) Σ Δu²),   ρ_p = ρ r² for c = M₀(t_N)².
//! ```
//!
//! # The state ([`StateMap`])
//! The chain is a polyline of its nodes. The planning chain's node J sits at the arc length
//! s_J = Σ_{I≤J} l_{p,I} of the plant's polyline: its position X_J and velocity W_J are those of
//! the point at that arc length on the plant's chain (exact on the polyline: linear along the
//! pendulum that holds it, node velocities wᵢ = Σ_{j≤i} l_j q̇_j with q̇ = M⁻¹p). Then
//! ```text
//! Q_J = (X_J − X_{J−1}) / |X_J − X_{J−1}|,   Q̇_J = Π_J (W_J − W_{J−1}) / l_{p,J},   P = M_p Q̇,
//! ```
//! Π_J = I − Q_J Q_Jᵀ, so the model's state satisfies its constraints |Q_J| = 1 and its hidden
//! constraints Q_J·Q̇_J = 0 exactly. With n_p = n and h_p = h the map is the identity up to
//! round-off, and the planner is the full-model one.

use super::ModelObservation;
use crate::error::{MpcError, Requirement, Result};
use crate::hotspots::joint_elevations;
use crate::model::{Chain, TipCondition};
use crate::scene::{DragModel, ObjectiveKind, Scene, SceneErrorKind, Support};
use crate::steppers::rattle::State;

/// The planning model of `scene` with `pendulums` pendulums at step `step` (module docs): the
/// `[pipe]` or the `[stackup]` rebuilt with n_p pendulums.
///
/// # Errors
/// [`MpcError::PlanWithoutPipe`] for a scene with neither `[pipe]` nor `[stackup]`;
/// [`MpcError::PlanPendulums`] for `pendulums` not in 1..=n; [`MpcError::PlanSupport`] for a
/// beam whose tip is locked (fixed-fixed, pinned-pinned) or a reaction-force tip (the map keeps
/// only the vessel's constraint); [`crate::error::ValueError::OutOfRange`] naming `plan_step`
/// for a step that is not positive and finite; a `beam.joint_damping` of a stack-up (not
/// rebuilt); the rebuilt scene's errors (a stack-up's fewer pendulums than pieces: naming
/// `beam.pendulums`).
pub fn planning_scene(scene: &Scene, pendulums: usize, step: f64) -> Result<Scene> {
    if scene.pipe.is_none() && scene.stackup.is_none() {
        return Err(MpcError::PlanWithoutPipe.into());
    }
    let n = scene.n();
    if pendulums == 0 || pendulums > n {
        return Err(MpcError::PlanPendulums { pendulums, n }.into());
    }
    // A vessel's prescribed (or thrust-driven) top is kept by the map (`StateMap`, "The tip
    // held by the vessel"); a locked or reaction-force tip is not.
    let support = scene.beam.support;
    let locked = support.holds_tip() && support != Support::Vessel;
    if locked || scene.beam.reaction_force {
        return Err(MpcError::PlanSupport.into());
    }
    Requirement::PositiveFinite
        .check("plan_step", step)
        .map_err(MpcError::from)?;
    let mut out = scene.clone();
    match (scene.pipe, scene.stackup.as_ref()) {
        (Some(pipe), _) => {
            // A clamped end's spring is 2EI/l, which the coarser chain recomputes; a flex
            // joint's given stiffness is a property of the joint and is kept.
            let clamped = 2.0 * pipe.bending_stiffness() / scene.beam.lengths[0];
            let given = |k: f64| ((k - clamped).abs() > 1e-12 * clamped).then_some(k);
            let end_springs = (
                given(scene.beam.base_stiffness),
                given(scene.beam.tip_stiffness),
            );
            out.beam = pipe.beam(pendulums, support, scene.water.density, end_springs)?;
            // D ∝ 1/l; the per-pendulum weights follow from the rebuilt beam
            // (`Scene::drag_weights`).
            out.loads.drag *= pendulums as f64 / n as f64;
        }
        (None, Some(stackup)) => {
            if scene.beam.joint_damping.iter().any(|&c| c != 0.0) {
                return Err(crate::scene::SceneError::new(SceneErrorKind::InvalidValue {
                    key: "beam.joint_damping".into(),
                    reason: "a reduced planning model of a stack-up does not rebuild the joint \
                             damping; plan on the full model (plan_pendulums = n)"
                        .into(),
                })
                .into());
            }
            // The stack-up's own chain of n_p pendulums (module docs, "A stack-up").
            let mut stackup = stackup.clone();
            let mudline = scene.soil.as_ref().map_or(0.0, |s| s.mudline);
            out.beam = stackup.beam(pendulums, support, scene.water.density, mudline)?;
            if stackup.drag_model == DragModel::Momentum {
                out.loads.drag = stackup
                    .drag_constants(&out.beam.lengths, &out.beam.masses, mudline)
                    .0;
            }
            out.stackup = Some(stackup);
        }
        (None, None) => return Err(MpcError::PlanWithoutPipe.into()),
    }
    out.time.step = step;
    // A wave record every r steps of the plant: as close on the model's grid, not longer.
    if let Some(w) = out.loads.waves.as_mut() {
        w.fit_record_step(step);
    }
    let node: Box<dyn Fn(usize) -> usize> = if scene.stackup.is_some() {
        // The node at the nearest height of the stack-up's uneven chain.
        let plant = joint_elevations(&scene.beam.lengths);
        let model = joint_elevations(&out.beam.lengths);
        Box::new(move |j: usize| nearest_joint_of(&model, plant[j.min(n)]).max(1))
    } else {
        Box::new(|j: usize| ((j * pendulums) as f64 / n as f64).round().max(1.0) as usize)
    };
    for load in &mut out.loads.points {
        load.node = node(load.node);
    }
    if let Some(c) = out.control.as_mut() {
        c.node = node(c.node);
    }
    out.validate()?;
    Ok(out)
}

/// The index of the elevation in `s` nearest `e` (the lower one on a tie).
fn nearest_joint_of(s: &[f64], e: f64) -> usize {
    let mut best = 0;
    for (i, sj) in s.iter().enumerate() {
        if (sj - e).abs() < (s[best] - e).abs() {
            best = i;
        }
    }
    best
}

/// The factor c by which the planning model's objective is the plant's (module docs, "The
/// objective"): ρ_p = c ρ; the rate penalty's σ_p = c σ h_p/h.
pub fn objective_scale(kind: ObjectiveKind, length_ratio: f64, step_ratio: f64) -> f64 {
    match kind {
        ObjectiveKind::Final => length_ratio * length_ratio,
        ObjectiveKind::Sum => length_ratio * length_ratio * step_ratio,
        ObjectiveKind::Power { exponent } => length_ratio.powf(exponent) * step_ratio,
        // The rainflow damage (the plans take its power proxy, never D itself: the structured
        // solvers refuse it) counts cycles, not samples: Σ Δσ^m scales as the moment's ratio^m.
        ObjectiveKind::Fatigue(d) => length_ratio.powf(d.exponent()),
    }
}

/// The map of a plant's state onto the planning chain (module docs, "The state"), with its
/// scratch memory: [`StateMap::map`] does not allocate.
#[derive(Clone, Debug)]
pub struct StateMap<const DIM: usize> {
    plant: Chain<f64, DIM>,
    model: Chain<f64, DIM>,
    /// q̇ of the plant.
    qdot: Vec<[f64; DIM]>,
    /// X_J and W_J, J = 0..=n_p.
    x: Vec<[f64; DIM]>,
    w: Vec<[f64; DIM]>,
    /// Q̇ of the model.
    model_qdot: Vec<[f64; DIM]>,
}

impl<const DIM: usize> StateMap<DIM> {
    /// The map from the chain of `plant` to the chain of `model` (two scenes of the same pipe).
    ///
    /// # Errors
    /// The chains' errors.
    pub fn new(plant: &Scene, model: &Scene) -> Result<Self> {
        let plant = Chain::<f64, DIM>::from_scene(plant)?;
        let model = Chain::<f64, DIM>::from_scene(model)?;
        let (n, np) = (plant.n(), model.n());
        Ok(StateMap {
            plant,
            model,
            qdot: vec![[0.0; DIM]; n],
            x: vec![[0.0; DIM]; np + 1],
            w: vec![[0.0; DIM]; np + 1],
            model_qdot: vec![[0.0; DIM]; np],
        })
    }

    /// The plant's number of pendulums.
    pub fn plant_pendulums(&self) -> usize {
        self.plant.n()
    }

    /// Writes the model's state of the plant's `state` into `out` (its q and p; no multipliers:
    /// the model's first step starts Newton from the consistent multiplier).
    ///
    /// # Errors
    /// [`MpcError::ModelSize`] when `state` is not of the plant's size.
    pub fn map(&mut self, state: &State<f64, DIM>, out: &mut State<f64, DIM>) -> Result<()> {
        let (n, np) = (self.plant.n(), self.model.n());
        if state.q.len() != n || state.p.len() != n {
            return Err(MpcError::ModelSize {
                model: n,
                plant: state.q.len(),
            }
            .into());
        }
        self.plant.apply_inverse_mass(&state.p, &mut self.qdot);
        self.sample_nodes(&state.q);
        out.q.resize(np, [0.0; DIM]);
        out.p.resize(np, [0.0; DIM]);
        for j in 0..np {
            let mut chord = [0.0; DIM];
            for d in 0..DIM {
                chord[d] = self.x[j + 1][d] - self.x[j][d];
            }
            let len = chord.iter().map(|c| c * c).sum::<f64>().sqrt();
            let lp = self.model.lengths()[j];
            let mut v = [0.0; DIM];
            for d in 0..DIM {
                chord[d] /= len;
                v[d] = (self.w[j + 1][d] - self.w[j][d]) / lp;
            }
            let along: f64 = (0..DIM).map(|d| v[d] * chord[d]).sum();
            for d in 0..DIM {
                v[d] -= along * chord[d];
            }
            out.q[j] = chord;
            self.model_qdot[j] = v;
        }
        if self.model.tip_condition() == TipCondition::Prescribed {
            self.hold_top(&mut out.q);
        }
        self.model.apply_mass(&self.model_qdot, &mut out.p);
        out.multipliers = None;
        // The vessel's state (Z, Ż) of a thrust scene, one to one (zero in other scenes).
        out.tip_target = state.tip_target;
        Ok(())
    }

    /// Puts the model's top where the plant's is (module docs, "The tip held by the vessel"):
    /// Σ l_J Q_J,z = X_{n_p,z} by Newton on a common shift α of the chords toward z,
    /// Q_J = (C_J + α e_z)/|C_J + α e_z|, then Σ l_J Q̇_J,z = W_{n_p,z} by the common
    /// Q̇_J += β Π_J e_z, β = (W_z − Σ l_J Q̇_J,z)/Σ l_J (1 − Q_J,z²), after projecting Q̇_J
    /// onto the tangent of the corrected Q_J.
    fn hold_top(&mut self, q: &mut [[f64; DIM]]) {
        let z = DIM - 1;
        let np = self.model.n();
        let (top, top_rate) = (self.x[np][z], self.w[np][z]);
        let lengths = self.model.lengths();
        // The chords C_J (unit) stay in `q`; α is applied to copies.
        let mut alpha = 0.0;
        for _ in 0..4 {
            let (mut f, mut df) = (-top, 0.0);
            for (c, &l) in q.iter().zip(lengths) {
                let mut v = *c;
                v[z] += alpha;
                let norm = v.iter().map(|x| x * x).sum::<f64>().sqrt();
                let qz = v[z] / norm;
                f += l * qz;
                df += l * (1.0 - qz * qz) / norm;
            }
            if df <= 0.0 || f == 0.0 {
                break;
            }
            alpha -= f / df;
        }
        for c in q.iter_mut() {
            c[z] += alpha;
            let norm = c.iter().map(|x| x * x).sum::<f64>().sqrt();
            c.iter_mut().for_each(|x| *x /= norm);
        }
        let (mut rate, mut weight) = (0.0, 0.0);
        for ((c, v), &l) in q.iter().zip(self.model_qdot.iter_mut()).zip(lengths) {
            let along: f64 = (0..DIM).map(|d| v[d] * c[d]).sum();
            for d in 0..DIM {
                v[d] -= along * c[d];
            }
            rate += l * v[z];
            weight += l * (1.0 - c[z] * c[z]);
        }
        if weight > 0.0 {
            let beta = (top_rate - rate) / weight;
            for (c, v) in q.iter().zip(self.model_qdot.iter_mut()) {
                for d in 0..DIM {
                    let e = if d == z { 1.0 } else { 0.0 };
                    v[d] += beta * (e - c[d] * c[z]);
                }
            }
        }
    }

    /// X_J and W_J at the model's node arc lengths on the plant's polyline.
    fn sample_nodes(&mut self, q: &[[f64; DIM]]) {
        let n = self.plant.n();
        let lengths = self.plant.lengths();
        // The plant's node i (position r, velocity v, arc length s) and the next model node.
        let (mut r, mut v, mut s) = ([0.0; DIM], [0.0; DIM], 0.0);
        self.x[0] = r;
        self.w[0] = v;
        let mut target = 0.0;
        let mut i = 0;
        for big_j in 1..=self.model.n() {
            target += self.model.lengths()[big_j - 1];
            // Advance to the plant's pendulum that holds the arc length `target`.
            while i + 1 < n && s + lengths[i] < target {
                for d in 0..DIM {
                    r[d] += lengths[i] * q[i][d];
                    v[d] += lengths[i] * self.qdot[i][d];
                }
                s += lengths[i];
                i += 1;
            }
            let f = ((target - s) / lengths[i]).clamp(0.0, 1.0) * lengths[i];
            for d in 0..DIM {
                self.x[big_j][d] = r[d] + f * q[i][d];
                self.w[big_j][d] = v[d] + f * self.qdot[i][d];
            }
        }
    }
}

/// The observation's state in the planning model: (q, p̂) before the control's half-kick when
/// the plant gives it, else (q, p) (module docs of [`crate::mpc`], "The start of a horizon").
/// Returns whether the kick is pending.
///
/// # Errors
/// See [`StateMap::map`].
pub(super) fn map_observation<const DIM: usize>(
    map: &mut StateMap<DIM>,
    obs: &ModelObservation<'_, DIM>,
    out: &mut State<f64, DIM>,
) -> Result<bool> {
    match obs.state_before_kick {
        Some(hat) => map.map(hat, out).map(|()| true),
        None => map.map(obs.state, out).map(|()| false),
    }
}
