//! The plan's models of the receding-horizon controller, built once by [`Mpc::build`]: the hot
//! spot's objective, the thrust plan at a coarser step and the reduced planning model with its
//! map from the plant (code moved out of `receding.rs`, unchanged).

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
    /// scene with fewer pendulums is refused by [`Mpc::build`]).
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
        let r = (hp / h).round();
        if !(hp.is_finite() && r >= 1.0) || (r * h - hp).abs() > 1e-9 * hp {
            return Err(MpcError::ThrustStep {
                model: hp,
                plant: h,
            }
            .into());
        }
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
