//! Hot spots along the riser: the fatigue of named sections at given elevations (the wellhead
//! datum, the conductor below the mudline, a casing connector, a riser joint's weld …), each from
//! the chain's joint torques interpolated in elevation between the two joints around it
//! (docs/conventions.md "Hot spots: the joint torque M_j").
//!
//! # The moment at a hot spot
//! Joint j (j = 1..n+1) links pendulum j−1 to pendulum j (pendulum 0 and pendulum n+1 are the
//! vertical e₂ of the supports); its spring k_j carries the torque M_j = k_j θ_j, θ_j = ∠(q_{j−1},
//! q_j) the angle whose energy ½k_jθ_j² the model integrates (`model::terms::spring`). Its
//! elevation is the straight chain's, s_j = Σ_{i<j} l_i above the chain's base (joint 1 at 0, joint
//! n+1 at the top). A hot spot at elevation e reads the moment interpolated linearly in elevation
//! between the two joints around it ([`interpolation_joints`]):
//!
//! M(e) = (1 − w) M_a + w M_b,   w = (e − s_a)/(s_b − s_a),   s_a ≤ e < s_b,
//!
//! per component; a hot spot within 10⁻⁹ of the chain's length of a joint (a flex joint, a part's
//! end, the wellhead datum) reads that joint alone, w = 0. Why not the nearest joint: a joint's
//! torque approximates the bending moment at its own elevation, and as n changes the joint
//! nearest a fixed elevation jumps along the riser, so the nearest joint's moment does not
//! converge in n where the moment varies over a few pendulum lengths (the conductor below the
//! mudline); the interpolant reads the moment at the hot spot's own elevation and converges with
//! the joint torques.
//!
//! As a vector in the transverse axes (x, z), with the sign convention of the wellhead moment
//! (each component the moment that bends the pipe toward that axis):
//!
//! (M_x, M_z) = k_j · (θ_j/‖a×b‖) · (−(a×b)_z, (a×b)_x),   a = q_{j−1}, b = q_j,
//!
//! ([`joint_moment`]). In a planar chain a×b is along x and this is k_j times the signed angle,
//! M_z = k_j·atan2(a_y b_z − a_z b_y, a·b). The factor θ/‖a×b‖ = θ/sin θ is evaluated by its series
//! in y = ‖a×b‖² near θ = 0 (the series of the spring's own angle,
//! `model::geometry::joint_angle_squared`), so the moment is exact, and finite, at θ = 0. The
//! component (a×b)_y (a twist of the joint about the vertical) is not a bending of the section and
//! is not counted; it vanishes when both pendulums lie in one vertical plane.
//!
//! **Joint 1 is the wellhead.** With a = e₂ (the clamp), a×b = (b_z, 0, −b_x) and
//! (M_x, M_z) = k₁ (θ₁/sin θ₁) (x₁, z₁)/l₁: the wellhead moment M_w = k₁ (x₁, z₁)/l₁ = M₀ l₁/2 of
//! `fatigue::MomentMeasure::ChainM0` times θ₁/sin θ₁ = 1 + θ₁²/6 + … (docs/conventions.md "The
//! wellhead moment M_w": M_w is the torque linearised at the straight beam, sin θ₁ for θ₁). The two
//! are the same function of the state up to that factor, sample by sample; tests/fatigue/hotspots.rs
//! checks the identity to 10⁻¹² and the two damages at elevation 0 against the bound the factor
//! implies.
//!
//! # The assessment
//! Each hot spot's moment history (N·m, [`crate::fatigue::MomentMeasure::Wellhead`]) goes through
//! [`crate::fatigue::assess`] with the hot spot's own section, SCF, S-N curve and DFF; the critical hot
//! spot is the shortest-lived ([`critical`]).

use crate::error::{Error, Result};
use crate::fatigue::{assess, Assessment, FatigueError, MomentHistory, MomentMeasure};
use crate::model::Chain;
use crate::scene::{Scene, SceneInput};
use crate::simulate::{simulate_streaming, StepObserver, StepView, StreamControls, StreamError};

pub use crate::scene::HotSpotSpec;

/// The elevations s_j = Σ_{i<j} l_i of the joints j = 1..n+1 of a straight chain with pendulum
/// lengths `lengths` (n + 1 values: 0 first, the chain's length last).
pub fn joint_elevations(lengths: &[f64]) -> Vec<f64> {
    let mut s = Vec::with_capacity(lengths.len() + 1);
    let mut sum = 0.0;
    s.push(sum);
    for l in lengths {
        sum += l;
        s.push(sum);
    }
    s
}

/// The 0-based index i = j − 1 of the joint nearest `elevation`: the least |s_j − e|, the lower
/// joint on a tie (the hot spots read [`interpolation_joints`] instead, module docs).
pub fn nearest_joint(lengths: &[f64], elevation: f64) -> usize {
    let s = joint_elevations(lengths);
    let mut best = 0;
    for (i, sj) in s.iter().enumerate() {
        if (sj - elevation).abs() < (s[best] - elevation).abs() {
            best = i;
        }
    }
    best
}

/// The joints a hot spot at `elevation` reads (module docs): the lower joint a (0-based i = j − 1)
/// with s_a ≤ e, the upper one b = a + 1, and the upper one's weight w = (e − s_a)/(s_b − s_a);
/// `upper == lower` and w = 0 when e lies within 10⁻⁹ of the chain's length of a joint (or at or
/// beyond the chain's ends).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct JointInterpolation {
    /// The joint at or below the elevation (0-based).
    pub lower: usize,
    /// The joint above it (0-based; `lower` when the elevation is a joint's).
    pub upper: usize,
    /// The upper joint's weight w in [0, 1).
    pub weight: f64,
}

impl JointInterpolation {
    /// (1 − w) a + w b, and a itself (bit for bit) when w = 0.
    #[inline]
    pub fn blend(&self, a: f64, b: f64) -> f64 {
        if self.weight == 0.0 {
            a
        } else {
            (1.0 - self.weight) * a + self.weight * b
        }
    }
}

/// The two joints around `elevation` and the upper one's weight ([`JointInterpolation`], module
/// docs) on a straight chain with pendulum lengths `lengths`.
pub fn interpolation_joints(lengths: &[f64], elevation: f64) -> JointInterpolation {
    let s = joint_elevations(lengths);
    let top = s.len() - 1;
    let tol = 1e-9 * s[top].abs().max(1.0);
    let at = |j: usize| JointInterpolation {
        lower: j,
        upper: j,
        weight: 0.0,
    };
    if let Some(j) = (0..=top).find(|&j| (s[j] - elevation).abs() <= tol) {
        return at(j);
    }
    if elevation <= s[0] {
        return at(0);
    }
    if elevation >= s[top] {
        return at(top);
    }
    // s[a] < e < s[a + 1]: the last joint below e.
    let a = s.partition_point(|&y| y < elevation) - 1;
    JointInterpolation {
        lower: a,
        upper: a + 1,
        weight: (elevation - s[a]) / (s[a + 1] - s[a]),
    }
}

/// The joints whose torques the hot spots read, two per hot spot in their order (lower, upper of
/// [`interpolation_joints`]): what [`joint_moment_history`] records for [`assess_histories`].
pub fn hot_spot_joints(lengths: &[f64], hotspots: &[HotSpotSpec]) -> Vec<usize> {
    hotspots
        .iter()
        .flat_map(|h| {
            let w = interpolation_joints(lengths, h.elevation);
            [w.lower, w.upper]
        })
        .collect()
}

/// θ/sin θ from y = sin²θ = ‖a×b‖² and x = cos θ = a·b: the series of arcsin(√y)/√y near y = 0
/// (coefficients a_k = a_{k−1}(2k−1)²/(2k(2k+1)), as `joint_angle_squared`), atan2 elsewhere;
/// 1 at θ = 0 exactly.
fn angle_over_sine(x: f64, y: f64) -> f64 {
    if x > 0.0 && y <= 0.01 {
        const A: [f64; 10] = [
            1.0,
            1.0 / 6.0,
            3.0 / 40.0,
            5.0 / 112.0,
            35.0 / 1152.0,
            63.0 / 2816.0,
            231.0 / 13312.0,
            143.0 / 10240.0,
            6435.0 / 557056.0,
            12155.0 / 1245184.0,
        ];
        A.iter().rev().fold(0.0, |s, &c| s * y + c)
    } else {
        let r = y.sqrt();
        if r > 0.0 {
            r.atan2(x) / r
        } else {
            // Antiparallel (θ = π): no bending plane; the model refuses such a fold before.
            0.0
        }
    }
}

/// The torque (M_x, M_z) \[N·m\] of a joint of stiffness k between the attitudes a = q_{j−1} and
/// b = q_j (module docs): k·(θ/‖a×b‖)·(−(a×b)_z, (a×b)_x); in a planar chain (DIM = 2, components
/// (y, z)) M_x = 0 and M_z = k·atan2(a_y b_z − a_z b_y, a·b). Exact and finite at θ = 0.
pub fn joint_moment<const DIM: usize>(a: &[f64; DIM], b: &[f64; DIM], k: f64) -> [f64; 2] {
    if DIM == 2 {
        let cross = a[0] * b[1] - a[1] * b[0];
        let dot = a[0] * b[0] + a[1] * b[1];
        return [0.0, k * cross.atan2(dot)];
    }
    let cx = a[1] * b[2] - a[2] * b[1];
    let cy = a[2] * b[0] - a[0] * b[2];
    let cz = a[0] * b[1] - a[1] * b[0];
    let dot = a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
    let f = k * angle_over_sine(dot, cx * cx + cy * cy + cz * cz);
    [-f * cz, f * cx]
}

/// The joint-torque histories of a run at some joints.
#[derive(Clone, Debug, PartialEq)]
pub struct JointMoments {
    /// The step h \[s\].
    pub h: f64,
    /// The joints (0-based i = j − 1), in the order asked.
    pub joints: Vec<usize>,
    /// M_z(t_k) \[N·m\] per joint, N + 1 values each.
    pub moment: Vec<Vec<f64>>,
    /// M_x(t_k) per joint in the spatial model, `None` in the planar one.
    pub moment_x: Option<Vec<Vec<f64>>>,
    /// The same run's base moment M₀(t_k) = 2k₁z₁/l₁² (thesis eq. 3.1.3, what
    /// [`crate::moment_history`] gives, bit for bit), so that the wellhead's assessment of
    /// [`crate::fatigue::MomentMeasure::ChainM0`] needs no second run.
    pub base_moment: Vec<f64>,
    /// M₀ₓ(t_k) of the spatial model, `None` in the planar one.
    pub base_moment_x: Option<Vec<f64>>,
}

impl JointMoments {
    /// The simulated duration N h \[s\].
    pub fn duration(&self) -> f64 {
        self.moment
            .first()
            .map_or(0.0, |m| m.len().saturating_sub(1) as f64 * self.h)
    }
}

/// Collects the joint torques of a streamed run.
struct JointSink {
    joints: Vec<usize>,
    moment: Vec<Vec<f64>>,
    moment_x: Vec<Vec<f64>>,
    base: Vec<Vec<f64>>,
}

impl StepObserver for JointSink {
    type Error = std::convert::Infallible;
    fn observe<const DIM: usize>(
        &mut self,
        step: &mut StepView<'_, DIM>,
    ) -> std::result::Result<(), Self::Error> {
        let [m0x, m0] = step.moment_vector();
        self.base[0].push(m0);
        if DIM == 3 {
            self.base[1].push(m0x);
        }
        push_joint_moments(
            step.chain(),
            step.q(),
            &self.joints,
            &mut self.moment,
            &mut self.moment_x,
        );
        Ok(())
    }
}

/// Appends the torques of `joints` (0-based) at the attitudes `q` of `chain` ([`joint_moment`]
/// with the chain's springs, 0 where the support has none): M_z to `moment[s]`, and in the
/// spatial model M_x to `moment_x[s]`, s the joint's place in `joints`.
pub fn push_joint_moments<const DIM: usize>(
    chain: &Chain<f64, DIM>,
    q: &[[f64; DIM]],
    joints: &[usize],
    moment: &mut [Vec<f64>],
    moment_x: &mut [Vec<f64>],
) {
    let n = q.len();
    let mut e2 = [0.0; DIM];
    e2[DIM - 2] = 1.0;
    for (s, &i) in joints.iter().enumerate() {
        let k = if chain.has_spring(i) {
            chain.springs()[i]
        } else {
            0.0
        };
        let a = if i == 0 { &e2 } else { &q[i - 1] };
        let b = if i == n { &e2 } else { &q[i] };
        let [mx, mz] = joint_moment(a, b, k);
        moment[s].push(mz);
        if DIM == 3 {
            moment_x[s].push(mx);
        }
    }
}

/// The torques M_j(t_k) at `joints` (0-based, each ≤ n) of `scene` run with its own controls
/// (the states of [`crate::simulate()`] bit for bit, streamed: O(n) memory besides the
/// (N + 1)·joints values kept).
///
/// # Errors
/// As [`crate::simulate()`]; [`Error::TrajectoryTooLarge`] if the allocator refuses the values;
/// [`Error::Fatigue`] naming `joint` for an index above n.
pub fn joint_moment_history<S: SceneInput + ?Sized>(
    scene: &S,
    joints: &[usize],
) -> Result<JointMoments> {
    let checked = scene.checked()?;
    let scene = checked.scene();
    let n = scene.n();
    if let Some(&bad) = joints.iter().find(|&&i| i > n) {
        return Err(FatigueError::InvalidSpec {
            key: "joint",
            value: bad as f64,
            reason: "must be a joint of the chain (0-based, at most n)",
        }
        .into());
    }
    let steps = scene.time.steps;
    let spatial = scene.is_spatial();
    let per = if spatial { 2 } else { 1 };
    let too_large = || Error::TrajectoryTooLarge {
        n,
        steps,
        bytes: 8 * ((steps + 1) * per * (joints.len() + 1)) as u64,
        max_steps: crate::scene::MAX_STEPS,
        refused: true,
    };
    let reserve = |count: usize| -> Result<Vec<Vec<f64>>> {
        let mut out = Vec::with_capacity(count);
        for _ in 0..count {
            let mut v = Vec::new();
            v.try_reserve_exact(steps + 1).map_err(|_| too_large())?;
            out.push(v);
        }
        Ok(out)
    };
    let mut sink = JointSink {
        joints: joints.to_vec(),
        moment: reserve(joints.len())?,
        moment_x: reserve(if spatial { joints.len() } else { 0 })?,
        base: reserve(per)?,
    };
    match simulate_streaming(&checked, StreamControls::Scene, &mut sink) {
        Ok(_) => {}
        Err(StreamError::Simulation(e)) => return Err(e),
        Err(StreamError::Observer(never)) => match never {},
    }
    Ok(JointMoments {
        h: scene.time.step,
        joints: joints.to_vec(),
        moment: sink.moment,
        moment_x: spatial.then_some(sink.moment_x),
        base_moment: std::mem::take(&mut sink.base[0]),
        base_moment_x: spatial.then(|| std::mem::take(&mut sink.base[1])),
    })
}

/// One hot spot's assessment.
#[derive(Clone, Debug, PartialEq)]
pub struct HotSpotAssessment {
    /// The hot spot's name.
    pub name: String,
    /// Its elevation \[m\] (as given).
    pub elevation: f64,
    /// The joint at or below its elevation (0-based i = j − 1; joint j of the module docs): the
    /// joint it reads when it lies on one, else the lower of the two it interpolates between.
    pub joint: usize,
    /// That joint's elevation s_j \[m\].
    pub joint_elevation: f64,
    /// The two joints and the weight its moment is interpolated with (module docs).
    pub interpolation: JointInterpolation,
    /// The assessment of its moment history (damage, damage per year, life, cycles).
    pub assessment: Assessment,
}

/// The index of the critical (shortest-lived) hot spot: the greatest DFF·D_y (the least life
/// 1/(DFF·D_y), also when every life is infinite: then the first); the first on a tie.
pub fn critical(lives: impl IntoIterator<Item = (f64, f64)>) -> Option<usize> {
    let mut best: Option<(usize, f64)> = None;
    for (i, (damage_per_year, dff)) in lives.into_iter().enumerate() {
        let d = dff * damage_per_year;
        if best.is_none_or(|(_, b)| d > b) {
            best = Some((i, d));
        }
    }
    best.map(|(i, _)| i)
}

/// Every hot spot of `hotspots` on `scene` run with its own controls, the first `skip` steps
/// left out of the count (the spin-up): one streamed run, then each hot spot's moment history
/// (interpolated in elevation between its two joints, module docs) through [`assess`] with the
/// hot spot's spec.
///
/// # Errors
/// The run's ([`joint_moment_history`]); a hot spot's [`FatigueError`] (its spec, a non-finite
/// moment) as [`Error::Fatigue`]; `skip` leaving fewer than two samples is
/// [`FatigueError::InvalidSpec`] naming `spin_up`.
pub fn assess_hot_spots(
    scene: &Scene,
    hotspots: &[HotSpotSpec],
    skip: usize,
) -> Result<Vec<HotSpotAssessment>> {
    let joints = hot_spot_joints(&scene.beam.lengths, hotspots);
    let history = joint_moment_history(scene, &joints)?;
    assess_histories(scene, hotspots, &history, skip)
}

/// The hot spots' assessments of a run's joint torques ([`joint_moment_history`] at the joints
/// [`hot_spot_joints`] gives for `hotspots`: two per hot spot, in their order), the first `skip`
/// steps left out; each hot spot's moment is interpolated between its two joints (module docs).
///
/// # Errors
/// As [`assess_hot_spots`]; [`FatigueError::InvalidSpec`] naming `joint` when `history` does
/// not hold the joints of [`hot_spot_joints`].
pub fn assess_histories(
    scene: &Scene,
    hotspots: &[HotSpotSpec],
    history: &JointMoments,
    skip: usize,
) -> Result<Vec<HotSpotAssessment>> {
    let lengths = &scene.beam.lengths;
    let elevations = joint_elevations(lengths);
    let expected = hot_spot_joints(lengths, hotspots);
    if history.joints != expected {
        return Err(FatigueError::InvalidSpec {
            key: "joint",
            value: history.joints.len() as f64,
            reason: "the joint-torque history must hold the hot spots' joints \
                     (hotspots::hot_spot_joints: two per hot spot)",
        }
        .into());
    }
    let mut out = Vec::with_capacity(hotspots.len());
    for (s, h) in hotspots.iter().enumerate() {
        let w = interpolation_joints(lengths, h.elevation);
        let blend = |m: &[Vec<f64>]| -> Option<Vec<f64>> {
            (w.weight != 0.0).then(|| {
                let (a, b) = (&m[2 * s], &m[2 * s + 1]);
                a.iter().zip(b).map(|(&a, &b)| w.blend(a, b)).collect()
            })
        };
        let blended = blend(&history.moment);
        let blended_x = history.moment_x.as_deref().and_then(blend);
        let moment = blended
            .as_deref()
            .unwrap_or(history.moment[2 * s].as_slice());
        let moment_x = history
            .moment_x
            .as_deref()
            .map(|m| blended_x.as_deref().unwrap_or(m[2 * s].as_slice()));
        if skip + 2 > moment.len() {
            return Err(FatigueError::InvalidSpec {
                key: "spin_up",
                value: skip as f64 * history.h,
                reason: "must leave at least two samples of the record",
            }
            .into());
        }
        let assessment = assess(
            &h.spec,
            MomentHistory {
                duration_s: history.duration() - skip as f64 * history.h,
                moment: &moment[skip..],
                moment_x: moment_x.map(|m| &m[skip..]),
                measure: MomentMeasure::Wellhead,
            },
        )?;
        out.push(HotSpotAssessment {
            name: h.name.clone(),
            elevation: h.elevation,
            joint: w.lower,
            joint_elevation: elevations[w.lower],
            interpolation: w,
            assessment,
        });
    }
    Ok(out)
}

/// β_p = asin q_{p,z}, pendulum p's angle from the vertical read from the node displacements
/// z₁..zₙ (q_{p,z} = (z_p − z_{p−1})/l_p, z₀ = 0 at the base), 0 for p outside 0..n (the
/// supports' vertical), planar, every pendulum pointing upward: the joint angle
/// θ_j = β_j − β_{j−1} is then [`joint_moment`]'s atan2 angle exactly. The stage costs of the
/// hot-spot objectives read it (`adjoint::HotSpotObjective`, the design's hot spot).
pub fn pendulum_inclination<D: crate::base::Scalar>(
    lengths: &[f64],
    p: Option<usize>,
    z: &[D],
) -> D {
    match p {
        Some(p) if p < lengths.len() => {
            let below = if p == 0 { D::zero() } else { z[p - 1] };
            ((z[p] - below) / lengths[p]).asin()
        }
        _ => D::zero(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// θ/sin θ of the series against the closed form away from 0, and exactly 1 at θ = 0.
    #[test]
    fn angle_over_sine_series_and_closed_form() {
        assert_eq!(angle_over_sine(1.0, 0.0).to_bits(), 1.0f64.to_bits());
        for deg in [0.01, 0.5, 3.0, 5.7, 5.8, 20.0, 90.0, 120.0] {
            let t = f64::to_radians(deg);
            let (s, c) = t.sin_cos();
            let got = angle_over_sine(c, s * s);
            assert!(
                (got - t / s).abs() <= 1e-14 * (t / s),
                "{deg}°: {got} vs {}",
                t / s
            );
        }
    }

    /// The spatial torque of a joint in the yz-plane is the planar signed one, and at the base
    /// (a = e₂) it is k θ/sin θ times the wellhead's k(x₁, z₁)/l₁ direction.
    #[test]
    fn spatial_torque_reduces_to_planar_and_to_the_wellhead() {
        let k = 2.5e6;
        let t: f64 = -0.03;
        let a2 = [1.0, 0.0];
        let b2 = [t.cos(), t.sin()];
        let [mx2, mz2] = joint_moment(&a2, &b2, k);
        assert_eq!(mx2.to_bits(), 0.0f64.to_bits());
        assert!((mz2 - k * t).abs() <= 1e-15 * k);
        let a3 = [0.0, 1.0, 0.0];
        let b3 = [0.0, t.cos(), t.sin()];
        let [mx3, mz3] = joint_moment(&a3, &b3, k);
        assert!(mx3.abs() <= 1e-20 && (mz3 - mz2).abs() <= 1e-12 * k * t.abs());
        // Bending toward x by θ: (M_x, M_z) = k θ (1, 0).
        let b = [t.sin(), t.cos(), 0.0];
        let [mx, mz] = joint_moment(&a3, &b, k);
        assert!((mx - k * t).abs() <= 1e-12 * k * t.abs() && mz.abs() <= 1e-20);
        // θ = 0: exactly zero, no NaN.
        let zero = joint_moment(&a3, &a3, k).map(f64::to_bits);
        assert_eq!(zero, [(-0.0f64).to_bits(), 0.0f64.to_bits()]);
        assert_eq!(joint_moment(&a2, &a2, k)[1].to_bits(), 0.0f64.to_bits());
    }

    /// The nearest joint, the lower on a tie; the critical hot spot is the least life.
    #[test]
    fn nearest_joint_and_critical() {
        let l = [2.0, 2.0, 2.0];
        assert_eq!(joint_elevations(&l), vec![0.0, 2.0, 4.0, 6.0]);
        assert_eq!(nearest_joint(&l, 0.0), 0);
        assert_eq!(nearest_joint(&l, 2.9), 1);
        assert_eq!(nearest_joint(&l, 3.0), 1);
        assert_eq!(nearest_joint(&l, 3.1), 2);
        assert_eq!(nearest_joint(&l, 6.0), 3);
        assert_eq!(critical([(1e-3, 1.0), (1e-4, 10.0), (2e-3, 1.0)]), Some(2));
        assert_eq!(critical([(1e-3, 3.0), (3e-3, 1.0)]), Some(0));
        assert_eq!(critical([(0.0, 1.0), (0.0, 1.0)]), Some(0));
        assert_eq!(critical(std::iter::empty()), None);
    }

    /// The joints around an elevation and the upper one's weight: (e − s_a)/(s_b − s_a) between
    /// joints, the joint alone (w = 0) at a joint, within the 10⁻⁹ tolerance and at the ends;
    /// the blend is linear and returns the lower value's bits at w = 0.
    #[test]
    // 0.25 and 8·0.75 + 4·0.25 = 7 are exact in binary: the comparisons are meant to be exact.
    #[allow(clippy::float_cmp)]
    fn interpolation_between_the_joints_around_an_elevation() {
        let l = [2.0, 4.0, 2.0];
        let at = |e: f64| interpolation_joints(&l, e);
        let w = at(3.0);
        assert_eq!((w.lower, w.upper), (1, 2));
        assert_eq!(w.weight, 0.25);
        assert_eq!(w.blend(8.0, 4.0), 7.0);
        for (e, j) in [
            (0.0, 0),
            (2.0, 1),
            (6.0 + 1e-10, 2),
            (8.0, 3),
            (-1.0, 0),
            (9.0, 3),
        ] {
            assert_eq!(
                at(e),
                JointInterpolation {
                    lower: j,
                    upper: j,
                    weight: 0.0
                },
                "{e}"
            );
        }
        let third = 0.1f64 / 3.0;
        assert_eq!(at(0.0).blend(third, f64::NAN).to_bits(), third.to_bits());
        let w = at(7.5);
        assert_eq!((w.lower, w.upper, w.weight), (2, 3, 0.75));
    }
}
