//! The design's objective at a named hot spot (`[design] hotspot`, module docs of
//! [`crate::design`], "The hot spot"): the rainflow damage of a `[[fatigue.hotspot]]`'s moment,
//! interpolated in elevation between the two joints around it ([`crate::hotspots`]), and its
//! exact design gradient by an adjoint sweep of the damage linearised at the run's pairing.
//!
//! # The gradient
//! The hot spot's moment is M(t_k) = (1 − w) k_a θ_a(t_k) + w k_b θ_b(t_k) (joints a and b
//! around its elevation, w the upper one's weight, k the joints' springs, θ their angles), and
//! its damage D = D(M(t_skip), …, M(t_N)) is piecewise smooth: at the rainflow pairing of θ,
//! ```text
//! dD/dθ_i = Σ_k g_k · dM(t_k)/dθ_i,     g_k = ∂D/∂M(t_k)   (0 on the spin-up's samples),
//! ```
//! which is the gradient of the linear functional J = Σ_k g_k M(t_k) with g held at its value.
//! So a forward run gives M(t_k), D and g ([`WellheadDamage::value_and_gradient`], the hot
//! spot's section, S-N curve and SCF on the moment in N·m), and one adjoint sweep of J gives
//! every dD/dθ_i: J is a sum of stage costs ℓ_k = g_k M(t_k), its seed at t_k the blend
//! (1 − w) g_k k_a ∂θ_a/∂q + w g_k k_b ∂θ_b/∂q of the two joints' seeds. A parameter that is
//! one of the two joints' springs also enters M directly: ∂M(t_k)/∂k_a = (1 − w) θ_a(t_k)
//! (and w θ_b(t_k) for k_b), added to the adjoint's. A segment's buoyancy diameter D_b (a
//! per-node quantity) enters the chain alone, not M (the springs and lengths do not move with
//! it): dD/dD_b = Σ_k g_k dM(t_k)/dD_b is the same sweep's node-tangent share
//! ([`crate::adjoint::adjoint_gradient_with_nodes`], module docs of [`crate::adjoint`]
//! "Per-node quantities"), with no further run.
//!
//! The stage cost reads the joint angles from the nodes' transverse displacements z_i, which
//! the adjoint's stage costs see ([`crate::adjoint::Stage::z`]): pendulum p's attitude has
//! q_{p,z} = (z_p − z_{p−1})/l_p (z₀ = 0 at the base), and, in the planar model with every
//! pendulum pointing upward (q_{p,y} > 0, which a riser's tension keeps), its angle from the
//! vertical is β_p = asin q_{p,z}, so θ_j = β_j − β_{j−1} (β = 0 for the supports' vertical
//! beyond either end): the angle atan2(a × b, a · b) of [`crate::hotspots::joint_moment`]
//! exactly. The forward run checks that the pendulums around the hot spot point upward at every
//! step; the spatial model (whose joint torques have two components) is refused.
//!
//! # The cost
//! A value is one forward run per cell; a value with the gradient is a forward run and an
//! adjoint sweep (a forward and a reverse pass) per cell
//! ([`super::DesignStudy::runs_per_evaluation`]).

use std::sync::Arc;

use super::tangents::node_tangents;
use super::DesignError;
use crate::adjoint::{ControlProblem, Objective, Stage};
use crate::base::Scalar;
use crate::fatigue::{DamageGradient, MomentMeasure, WellheadDamage};
use crate::fatigue_study::StudyError;
use crate::hotspots::{
    interpolation_joints, joint_moment, pendulum_inclination, HotSpotSpec, JointInterpolation,
};
use crate::optimize::any::scene_start;
use crate::scene::ValidScene;
use crate::simulate::{simulate_streaming, StepObserver, StepView, StreamControls, StreamError};
use crate::Parameter;

/// The linearised hot-spot damage J = Σ_k g_k M(t_k) as stage costs (module docs).
#[derive(Clone, Debug)]
struct LinearisedHotSpot {
    /// g_k = ∂D/∂M(t_k), k = 0..=N.
    weights: Arc<[f64]>,
    /// The pendulums' lengths l_p.
    lengths: Arc<[f64]>,
    /// The joints read and their coefficients (joint i, c_i): M = Σ c_i θ_i, c_i the weight
    /// times the spring.
    terms: [(usize, f64); 2],
}

impl LinearisedHotSpot {
    /// β_p = asin q_{p,z} of pendulum p (0 for p outside 0..n, the supports' vertical).
    fn beta<D: Scalar>(&self, p: Option<usize>, z: &[D]) -> D {
        pendulum_inclination(&self.lengths, p, z)
    }

    /// θ_i = β_i − β_{i−1} of joint i (0-based: joint i links pendulums i − 1 and i).
    fn angle<D: Scalar>(&self, i: usize, z: &[D]) -> D {
        self.beta(Some(i), z) - self.beta(i.checked_sub(1), z)
    }
}

impl Objective for LinearisedHotSpot {
    /// ℓ_k = g_k · Σ c_i θ_i(z(t_k)).
    fn stage<D: Scalar>(&self, s: Stage<'_, D>) -> D {
        let g = self.weights.get(s.k).copied().unwrap_or(0.0);
        if g == 0.0 {
            return D::zero();
        }
        let mut m = D::zero();
        for &(i, c) in &self.terms {
            if c != 0.0 {
                m += self.angle(i, s.z) * c;
            }
        }
        m * g
    }
    fn uses_positions(&self) -> bool {
        true
    }
}

/// Records a run's angles at the two joints of a hot spot and checks that the pendulums around
/// them point upward.
struct AngleSink {
    joints: JointInterpolation,
    angles: [Vec<f64>; 2],
    /// The first step at which a pendulum around the hot spot did not point upward.
    folded: Option<usize>,
}

impl StepObserver for AngleSink {
    type Error = std::convert::Infallible;
    fn observe<const DIM: usize>(
        &mut self,
        step: &mut StepView<'_, DIM>,
    ) -> Result<(), Self::Error> {
        let q = step.q();
        let n = q.len();
        let mut e2 = [0.0; DIM];
        e2[DIM - 2] = 1.0;
        let (lo, hi) = (self.joints.lower, self.joints.upper);
        for (slot, i) in [lo, hi].into_iter().enumerate() {
            let a = if i == 0 { &e2 } else { &q[i - 1] };
            let b = if i == n { &e2 } else { &q[i] };
            // The joint's angle: its torque with a unit spring.
            self.angles[slot].push(joint_moment(a, b, 1.0)[1]);
        }
        let around = lo.saturating_sub(1)..(hi + 1).min(n);
        if self.folded.is_none() && q[around].iter().any(|p| p[DIM - 2] <= 0.0) {
            self.folded = Some(step.k());
        }
        Ok(())
    }
}

/// One cell's hot-spot damage D and, with `params`, dD/dθ (module docs) on `scene` (the cell's,
/// its record set), the first `skip` samples left out of the count: (D, dD/d`params`, dD/dD_b
/// for the buoyancy diameter of each of the stack-up's segments `segments`), the last two from
/// the one adjoint sweep (empty without `params`).
pub(super) fn hot_spot_sweep(
    scene: &ValidScene,
    hot_spot: &HotSpotSpec,
    skip: usize,
    params: Option<&[Parameter]>,
    segments: &[usize],
) -> Result<(f64, Vec<f64>, Vec<f64>), HotSpotError> {
    if scene.is_spatial() {
        return Err(HotSpotError::Spatial);
    }
    let w = interpolation_joints(&scene.beam.lengths, hot_spot.elevation);
    let mut sink = AngleSink {
        joints: w,
        angles: [Vec::new(), Vec::new()],
        folded: None,
    };
    match simulate_streaming(scene, StreamControls::Scene, &mut sink) {
        Ok(_) => {}
        Err(StreamError::Simulation(e)) => return Err(HotSpotError::Run(e)),
        Err(StreamError::Observer(never)) => match never {},
    }
    if let Some(step) = sink.folded {
        return Err(HotSpotError::Folded { step });
    }
    let chain = crate::Chain::<f64, 2>::from_scene(scene).map_err(HotSpotError::Run)?;
    let spring = |i: usize| {
        if chain.has_spring(i) {
            chain.springs()[i]
        } else {
            0.0
        }
    };
    let (ka, kb) = (spring(w.lower), spring(w.upper));
    // M(t_k) as the hot spots' assessment reads it (`hotspots::assess_histories`): the lower
    // joint's torque alone at w = 0, else the blend.
    let moment: Vec<f64> = sink.angles[0]
        .iter()
        .zip(&sink.angles[1])
        .map(|(&a, &b)| w.blend(ka * a, kb * b))
        .collect();
    if skip + 2 > moment.len() {
        return Err(HotSpotError::Study(
            crate::fatigue::FatigueError::InvalidSpec {
                key: "spin_up",
                value: skip as f64 * scene.time.step,
                reason: "must leave at least two samples of the record",
            }
            .into(),
        ));
    }
    let damage = WellheadDamage::new(&hot_spot.spec, MomentMeasure::Wellhead)
        .map_err(|e| HotSpotError::Study(e.into()))?;
    let mut g = vec![0.0; moment.len()];
    let d = damage
        .value_and_gradient(
            &moment[skip..],
            None,
            DamageGradient {
                grad: &mut g[skip..],
                grad_x: &mut [],
            },
        )
        .map_err(|e| HotSpotError::Study(e.into()))?;
    let Some(params) = params else {
        return Ok((d, Vec::new(), Vec::new()));
    };
    let (ca, cb) = if w.weight == 0.0 {
        (ka, 0.0)
    } else {
        ((1.0 - w.weight) * ka, w.weight * kb)
    };
    let objective = LinearisedHotSpot {
        weights: g.clone().into(),
        lengths: scene.beam.lengths.clone().into(),
        terms: [(w.lower, ca), (w.upper, cb)],
    };
    let (map, theta0) = scene_start(scene).map_err(HotSpotError::Run)?;
    let problem = ControlProblem::builder(scene)
        .map(map)
        .objective(objective)
        .two_axis(false)
        .build_in::<2>()
        .map_err(HotSpotError::Run)?;
    // The buoyancy diameters' node tangents ride the same sweep: the stage cost reads the
    // nodes' positions alone, so ∂ℓ_k/∂D_b = 0 at fixed state and their share is the chain's.
    let nodes = node_tangents::<2>(scene, segments).map_err(HotSpotError::Run)?;
    let (r, buoyancy) = problem
        .adjoint_with_nodes(&theta0, params, nodes)
        .map_err(HotSpotError::Run)?;
    let mut gradient = r.parameter_gradient;
    let n = scene.beam.lengths.len();
    for (p, dp) in params.iter().zip(gradient.iter_mut()) {
        *dp += spring_direct_term(*p, n, w, &g, &sink.angles);
    }
    Ok((d, gradient, buoyancy))
}

/// The direct term of a parameter that is one of the hot spot's two joints' springs (`joints`,
/// their angles θ(t_k) in `angles`, g_k = ∂D/∂M(t_k) in `g`; n pendulums):
/// Σ_k g_k ∂M(t_k)/∂k_i with ∂M(t_k)/∂k_i = (weight of joint i) · θ_i(t_k); 0 for any other
/// parameter.
fn spring_direct_term(
    p: Parameter,
    n: usize,
    joints: JointInterpolation,
    g: &[f64],
    angles: &[Vec<f64>; 2],
) -> f64 {
    let joint = match p {
        Parameter::BaseStiffness => 0,
        Parameter::TipStiffness => n,
        Parameter::JointStiffness(j) => j,
        _ => return 0.0,
    };
    let lower = if joints.weight == 0.0 {
        1.0
    } else {
        1.0 - joints.weight
    };
    let mut term = 0.0;
    for (slot, (joint_i, weight)) in [(joints.lower, lower), (joints.upper, joints.weight)]
        .into_iter()
        .enumerate()
    {
        if joint_i == joint && weight != 0.0 {
            let direct: f64 = g.iter().zip(&angles[slot]).map(|(gk, th)| gk * th).sum();
            term += weight * direct;
        }
    }
    term
}

/// Why a hot spot's cell failed (mapped to [`DesignError`] with the cell and the hot spot).
#[derive(Debug)]
pub(super) enum HotSpotError {
    /// The scene is spatial.
    Spatial,
    /// A pendulum around the hot spot did not point upward at this step.
    Folded { step: usize },
    /// The run or the adjoint failed.
    Run(crate::Error),
    /// The damage's spec or the record.
    Study(StudyError),
}

impl HotSpotError {
    /// The design's error for cell `cell` and hot spot `name`.
    pub(super) fn into_design(self, cell: usize, name: &str) -> DesignError {
        match self {
            HotSpotError::Spatial => DesignError::HotSpotSpatial {
                name: name.to_string(),
            },
            HotSpotError::Folded { step } => DesignError::HotSpotFolded {
                name: name.to_string(),
                cell,
                step,
            },
            HotSpotError::Run(e) => DesignError::Run {
                cell,
                source: Box::new(e),
            },
            HotSpotError::Study(e) => DesignError::Study(e),
        }
    }
}
