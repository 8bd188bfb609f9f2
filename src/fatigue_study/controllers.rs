//! The controllers a study runs on one cell and record: whether one can act on the scene, the
//! closed loop of each kind (none, PD, constant, MPC) and the settings each derives from the
//! scene (the PD law, the best constant at the hot spot, the control bound, the training scene).

use super::*;
use crate::mpc::{pd, running_mean};
use crate::scene::{MomentAbout, SceneInput};

/// The scene's support as the scene file writes it.
fn support_name(s: Support) -> &'static str {
    s.name()
}

/// Refuses a feedback controller whose force acts at a node the supports lock (the tip of a
/// fixed-fixed or pinned-pinned beam without the reaction-force tip).
///
/// # Errors
/// [`StudyError::ControlCannotAct`].
pub fn check_control_can_act(scene: &Scene, kind: ControllerKind) -> Result<(), StudyError> {
    if !kind.is_feedback() {
        return Ok(());
    }
    let n = scene.n();
    let node = scene.control.as_ref().map_or(n, |c| c.node);
    // The vessel's thrust moves the top the vessel holds: it can act.
    let locked =
        scene.beam.support.holds_tip() && !scene.beam.reaction_force && scene.thrust().is_none();
    if locked && node == n {
        return Err(StudyError::ControlCannotAct {
            controller: kind.name(),
            node,
            support: support_name(scene.beam.support),
        });
    }
    Ok(())
}

/// Runs one controller on `scene` and records M₀ (module docs, "The controllers").
///
/// # Errors
/// The library's errors of the run (a planar-only controller on a spatial scene:
/// [`crate::Error::NeedsSpatialModel`]; a failed step or solve; an interval that does not fit).
pub fn run_controller<S: SceneInput + ?Sized>(
    scene: &S,
    kind: ControllerKind,
    settings: &ControlSettings,
) -> crate::Result<ControlledRecord> {
    let valid = scene.checked()?;
    let scene = valid.scene();
    let (interval, effort) = (settings.interval, settings.mpc.effort);
    let bound = control_bound(scene, settings);
    let thrust_scene = scene.thrust().is_some();
    // The study's controllers and records are planar (M₀ and a force in the plane).
    if kind.is_feedback() {
        if let Some(key) = scene.spatial_key() {
            return Err(crate::Error::NeedsSpatialModel { key });
        }
    }
    let closed = |c: &mut dyn Controller, force, gains| {
        let r = run_closed_loop(scene, interval, c)?;
        Ok(ControlledRecord {
            thrust: thrust_scene.then(|| thrust_stats(&r.control)),
            duration_s: r.summary.simulated_seconds,
            moment: r.moment,
            moment_x: None,
            force,
            gains,
            decisions: Some(r.decisions.iter().map(|d| d.control).collect()),
        })
    };
    match kind {
        ControllerKind::Scene | ControllerKind::None => {
            let free;
            let run = if kind == ControllerKind::None {
                free = valid.without_control();
                free.proof()
            } else {
                valid
            };
            let history = moment_history(&run)?;
            // The thrust of `scene` is its `[control]` per step (none: zero).
            let thrust = match (thrust_scene, kind) {
                (false, _) => None,
                (true, ControllerKind::None) => Some([0.0; 2]),
                (true, _) => Some(thrust_stats(&scene_controls(&run)?)),
            };
            Ok(ControlledRecord {
                thrust,
                duration_s: history.duration(),
                moment: history.moment,
                moment_x: history.moment_x,
                force: None,
                gains: None,
                decisions: None,
            })
        }
        ControllerKind::Constant => {
            let training = training_scene(scene, settings)?;
            let mut c = if let Some(spot) = settings.mpc.hotspot.as_ref() {
                best_constant_at_hot_spot(&training, spot, bound, effort)?
            } else if scene.thrust().is_some() {
                ConstantForce::best_thrust(&training, bound, effort)?.0
            } else {
                ConstantForce::best(&training, bound, effort)?.0
            };
            let force = c.u.z;
            closed(&mut c, Some(force), None)
        }
        ControllerKind::Pd => {
            let mut pd = pd_law(scene, settings)?;
            let gains = [pd.bias.z, pd.kp, pd.kd];
            match hot_spot_objective(scene, settings)? {
                Some(spot) => {
                    let mut law = HotSpotPd::new(pd, spot, interval);
                    closed(&mut law, None, Some(gains))
                }
                None => closed(&mut pd, None, Some(gains)),
            }
        }
        ControllerKind::Mpc => {
            let mut mpc = Mpc::new(scene, interval, settings.mpc.clone())?;
            closed(&mut mpc, None, None)
        }
    }
}

/// The moment of the hot spot the controllers act on ([`MpcOptions::hotspot`]) as
/// [`HotSpotObjective`] on `scene` (its exponent the S-N curve's first slope, the effort
/// `settings`'), `None` without one.
///
/// # Errors
/// [`HotSpotObjective::new`]'s; the hot spot's S-N curve's.
fn hot_spot_objective(
    scene: &Scene,
    settings: &ControlSettings,
) -> crate::Result<Option<HotSpotObjective>> {
    let Some(spot) = settings.mpc.hotspot.as_ref() else {
        if settings.mpc.moment_about == MomentAbout::Mean {
            return Err(MpcError::MomentAboutNeedsHotSpot.into());
        }
        return Ok(None);
    };
    let exponent =
        WellheadDamage::new(&spot.spec, crate::fatigue::MomentMeasure::Wellhead)?.exponent();
    Ok(Some(
        HotSpotObjective::new(scene, spot.elevation, exponent, settings.mpc.effort)?
            .with_about(settings.mpc.moment_about),
    ))
}

/// The PD law on the moment M at a hot spot (module docs, "The moment the controllers act
/// on"): u = clamp(u_b − K_p M − K_d Ṁ, ±u_max) with M read from the observed attitudes
/// ([`HotSpotObjective::moment_of_attitudes`]) and Ṁ the difference over the last step,
/// (M(t_k) − M(t_{k−1}))/h (0 at k = 0); about the mean ([`HotSpotObjective::about`]),
/// u = clamp(u_b − K_p (M − M̄) − K_d Ṁ) with M̄ the running mean of the decisions' moments
/// ([`crate::mpc::running_mean`]): the loop its gains were tuned on
/// ([`crate::mpc::pd_closed_loop_cost_at`]).
struct HotSpotPd {
    law: PdLaw,
    spot: HotSpotObjective,
    /// The decisions' interval Δt \[s\] (the running mean's sample time).
    interval: f64,
    /// The running mean M̄ of the decisions so far (about the mean only).
    mean: Option<f64>,
}

impl HotSpotPd {
    fn new(law: PdLaw, spot: HotSpotObjective, interval: f64) -> Self {
        HotSpotPd {
            law,
            spot,
            interval,
            mean: None,
        }
    }
}

impl Controller for HotSpotPd {
    fn name(&self) -> String {
        "pd".into()
    }
    fn control(&mut self, obs: &crate::mpc::Observation<'_>) -> crate::Result<Force2> {
        let obs = obs.in_model::<2>()?;
        let m = self.spot.moment_of_attitudes(&obs.state.q);
        let rate = match obs.previous_state {
            Some(prev) => (m - self.spot.moment_of_attitudes(&prev.q)) / obs.h,
            None => 0.0,
        };
        let about = if self.spot.about == MomentAbout::Mean {
            let mean = running_mean(self.mean, m, self.interval);
            self.mean = Some(mean);
            mean
        } else {
            0.0
        };
        let gains = [self.law.bias.z, self.law.kp, self.law.kd];
        Ok(Force2::z(pd(&gains, m - about, rate, self.law.bound)))
    }
}

/// The best constant force (or thrust) for a hot spot's moment on `scene` (the training
/// window): min_u h Σ_k |M(t_k)|^m + ρ h Σ_k u², |u| ≤ `bound`, M the hot spot's moment and m
/// its S-N curve's first slope ([`HotSpotObjective`]), by [`minimize`] on the adjoint gradient
/// from u = 0 (the structured solvers need the base moment's Gauss-Newton form).
///
/// # Errors
/// The objective's ([`HotSpotObjective::new`]), the problem's and the optimiser's errors.
pub fn best_constant_at_hot_spot(
    scene: &Scene,
    spot: &crate::hotspots::HotSpotSpec,
    bound: f64,
    effort: f64,
) -> crate::Result<ConstantForce> {
    let exponent =
        WellheadDamage::new(&spot.spec, crate::fatigue::MomentMeasure::Wellhead)?.exponent();
    let objective = HotSpotObjective::new(scene, spot.elevation, exponent, effort)?;
    let steps = scene.time.steps;
    let map = crate::adjoint::PiecewiseControl { steps, pieces: 1 };
    let problem = crate::adjoint::ControlProblem::builder(scene)
        .map(map)
        .objective(objective)
        .build_in::<2>()?;
    let options = OptimOptions {
        bounds: Some(Bounds::symmetric(bound)?),
        first_step: 0.01 * bound,
        trust_radius: 0.1 * bound,
        max_trust_radius: bound,
        ..OptimOptions::default()
    };
    let r = minimize(&problem, &[0.0], &options)?;
    Ok(ConstantForce {
        u: Force2::z(r.theta[0]),
        spatial: false,
    })
}

/// The per-step controls u_0..u_N a scene's `[control]` applies (none: zeros).
///
/// # Errors
/// The scene's model errors.
pub(super) fn scene_controls(scene: &Scene) -> crate::Result<Vec<f64>> {
    use crate::adjoint::ControlMap;
    let steps = scene.time.steps;
    let Some(c) = scene.control.as_ref() else {
        return Ok(vec![0.0; steps + 1]);
    };
    let mut u = vec![0.0; steps + 1];
    match c.kind {
        crate::scene::ControlKind::Constant => u.fill(c.values[0]),
        crate::scene::ControlKind::PerStep => u.copy_from_slice(&c.values),
        crate::scene::ControlKind::Piecewise => {
            let map = crate::adjoint::PiecewiseControl {
                steps,
                pieces: c.values.len(),
            };
            map.controls(&c.values, &mut u);
        }
    }
    Ok(u)
}

/// The bound of the closed-loop controllers' control on `scene`: the vessel's `thrust_bound`
/// when the control is the thrust on the vessel, else [`ControlSettings::bound`].
pub fn control_bound(scene: &Scene, settings: &ControlSettings) -> f64 {
    scene.thrust().map_or(settings.bound(), |t| t.bound)
}

/// The PD law of a cell ([`ControlSettings::pd_gains`], or tuned on the first
/// [`ControlSettings::pd_training`] seconds of `scene`'s record in the scaled, bounded
/// parameters of [`pd::ScaledPdTuning`] from [`pd::PD_START`]: positive loop gains only).
///
/// # Errors
/// The tuning's errors ([`PdTuning::new`], [`pd::PdScales::of`], [`minimize`]);
/// [`crate::error::ValueError`] naming `pd_training` for a window that is not positive.
pub fn pd_law(scene: &Scene, settings: &ControlSettings) -> crate::Result<PdLaw> {
    let (interval, effort) = (settings.interval, settings.mpc.effort);
    let bound = control_bound(scene, settings);
    if let Some([bias, kp, kd]) = settings.pd_gains {
        return Ok(PdLaw {
            bias: Force2::z(bias),
            kp,
            kd,
            bound,
            spatial: false,
        });
    }
    let training = training_scene(scene, settings)?;
    let spot = hot_spot_objective(scene, settings)?;
    let mut tuning = PdTuning::new(&training, interval, bound, effort)?;
    if let Some(spot) = spot.clone() {
        tuning = tuning.at_hot_spot(spot);
    }
    let scaled = pd::ScaledPdTuning {
        tuning,
        scales: pd::PdScales::of_at(&training, bound, spot.as_ref())?,
    };
    let opts = OptimOptions {
        max_iters: settings.pd_max_iters,
        first_step: 0.1,
        bounds: Some(Bounds::symmetric(pd::PD_BOX)?),
        ..OptimOptions::default()
    };
    let r = minimize(&scaled, &pd::PD_START, &opts)?;
    let [bias, kp, kd] = scaled.scales.gains(&r.theta);
    Ok(PdLaw {
        bias: Force2::z(bias),
        kp,
        kd,
        bound,
        spatial: false,
    })
}

/// The scene cut to its training window: the first [`ControlSettings::pd_training`] seconds
/// (whole control intervals, at least one), or the whole scene without one.
///
/// # Errors
/// [`crate::error::ValueError`] naming `pd_training` for a window that is not positive;
/// [`MpcError::IntervalNotMultiple`].
pub fn training_scene(scene: &Scene, settings: &ControlSettings) -> crate::Result<Scene> {
    let mut training = scene.clone();
    if let Some(seconds) = settings.pd_training {
        Requirement::PositiveFinite
            .check("pd_training", seconds)
            .map_err(MpcError::from)?;
        let interval = settings.interval;
        let m = interval_steps(interval, scene.time.step)?;
        let intervals = ((seconds / interval).round() as usize).max(1);
        training.time.steps = (intervals * m).min(scene.time.steps);
    }
    Ok(training)
}
