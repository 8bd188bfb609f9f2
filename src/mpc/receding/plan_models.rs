//! The plan's models of the receding-horizon controller, built once by [`Mpc::build`]: the hot
//! spot's objective, the thrust plan at a coarser step, the reduced planning model with its
//! map from the plant, and the filter's scene under a plan whose model is not the plant's.

use super::*;

impl<const DIM: usize> Mpc<DIM> {
    /// The hot spot's objective the plan weighs ([`MpcOptions::hotspot`]: h Σ|M − M̄|^m or
    /// h Σ|M|^m at its elevation, m the S-N curve's first slope, ρ = `effort`), `None` for the
    /// base moment; refused about the mean without a hot spot, in the spatial model, or
    /// without the vessel's thrust.
    pub(super) fn hot_spot_of(
        model: &Scene,
        options: &MpcOptions,
        thrust: bool,
        effort: f64,
    ) -> Result<Option<HotSpotObjective>> {
        Ok(match &options.hotspot {
            None if options.moment_about == MomentAbout::Mean => {
                return Err(MpcError::MomentAboutNeedsHotSpot.into())
            }
            None => None,
            Some(_) if DIM == 3 => return Err(MpcError::HotSpotSpatial.into()),
            Some(_) if !thrust => return Err(MpcError::HotSpotNeedsThrust.into()),
            Some(spot) => {
                let exponent = WellheadDamage::new(&spot.spec, MomentMeasure::Wellhead)?.exponent();
                Some(
                    HotSpotObjective::new(model, spot.elevation, exponent, effort)?
                        .with_about(options.moment_about),
                )
            }
        })
    }

    /// The plan through the vessel's thrust at a coarser step ([`crate::mpc`], "MPC through the
    /// vessel's thrust"): with `plan_step` = r h (r ≥ 1 a whole number) and the model's own
    /// pendulums (`plan_pendulums` not given or n), the model scene at the step r h, the effort
    /// weight rescaled to its units as a reduced planning model's
    /// ([`super::planning::objective_scale`]); `None` for any other scene or setting (a thrust
    /// scene with fewer pendulums plans on the reduced model of [`Mpc::planning_model`]).
    ///
    /// # Errors
    /// [`MpcError::ThrustStep`] when `plan_step` is not a whole multiple of the model's step.
    pub(super) fn coarse_thrust_model(
        model: &Scene,
        options: &mut MpcOptions,
    ) -> Result<Option<Scene>> {
        let h = model.time.step;
        let (Some(_), Some(hp)) = (model.thrust(), options.plan_step) else {
            return Ok(None);
        };
        if options.plan_pendulums.is_some_and(|n| n != model.n()) || DIM == 3 {
            return Ok(None);
        }
        let r = super::thrust_plan::plan_step_ratio(hp, h)?;
        let mut plan = model.clone();
        plan.time.step = r * h;
        plan.time.steps = (model.time.steps / r as usize).max(1);
        options.effort *= objective_scale(options.objective, 1.0, h / plan.time.step);
        options.plan_pendulums = None;
        options.plan_step = None;
        Ok(Some(plan))
    }

    /// The reduced planning model of `options` ([`MpcOptions::plan_pendulums`],
    /// [`MpcOptions::plan_step`]) and the map onto it, with the effort weight and the rate
    /// penalty rescaled to its units; `(None, None)` without one.
    #[allow(clippy::type_complexity)]
    pub(super) fn planning_model(
        model: &Scene,
        options: &mut MpcOptions,
    ) -> Result<(Option<Scene>, Option<(StateMap<DIM>, State<f64, DIM>)>)> {
        if options.plan_pendulums.is_none() && options.plan_step.is_none() {
            return Ok((None, None));
        }
        let np = options.plan_pendulums.unwrap_or(model.n());
        let hp = options.plan_step.unwrap_or(model.time.step);
        let plan = planning_scene(model, np, hp)?;
        let map = StateMap::new(model, &plan)?;
        let r = model.beam.lengths[0] / plan.beam.lengths[0];
        let c = objective_scale(options.objective, r, model.time.step / hp);
        options.effort *= c;
        options.ocp.rate_penalty *= c * hp / model.time.step;
        let start = State::straight(np);
        Ok((Some(plan), Some((map, start))))
    }
}

/// The plan's control on `scene`: a constant zero force at the scene's control node (the top's,
/// n, unless the scene names one). The plans set their own controls; the filter of
/// [`Observe::Sensors`] applies the thrusts the thrusters gave.
pub(super) fn zero_control(scene: &mut Scene) {
    let node = scene.control.as_ref().map_or(scene.n(), |c| c.node);
    scene.control = Some(Control {
        node,
        kind: ControlKind::Constant,
        values: vec![0.0],
        values_x: None,
    });
}

/// The scene the filter of [`Observe::Sensors`] runs on under a plan whose model is not the
/// plant's (a reduced stack-up or a coarser step): the model scene `model` itself, the plant's
/// n pendulums at its step h, with the forecast's sea (calm for [`Forecast::None`]) and
/// [`zero_control`]. The filter predicts between readings on the plant's grid t_{k−1} (its
/// readings are taken on the plant's state), so it needs the plant's step and chain; its estimate
/// is then mapped onto the plan by the plan's [`StateMap`] as the plant's state is. Its cost per
/// interval is one simulation of the interval on the plant's chain, against a re-plan's few
/// simulations and adjoint sweeps of a whole horizon on the plan's chain.
pub(super) fn observer_model(model: &Scene, forecast: Forecast) -> Scene {
    let mut scene = model.clone();
    if forecast == Forecast::None {
        scene.loads.waves = None;
    }
    zero_control(&mut scene);
    scene
}
