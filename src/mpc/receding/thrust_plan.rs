//! The receding-horizon controller through the vessel's thrust ([`crate::mpc`], "MPC through
//! the vessel's thrust"): what it keeps between re-plans and one re-plan, the commands of the
//! horizon by the bounded L-BFGS on the exact adjoint gradient.

use super::*;

/// The last plan through the vessel's thrust ([`Mpc::last_thrust_plan`]).
#[derive(Clone, Debug, PartialEq)]
pub struct PlannedThrust {
    /// The per-step thrusts u_0..u_{N_p} of the plan's horizon \[N\] (from the plan's start).
    pub thrusts: Vec<f64>,
    /// The plan's moment objective J_u at those thrusts, with its effort term, without the
    /// command penalty of the plan's solver ([`crate::mpc`], "MPC through the vessel's thrust").
    pub objective: f64,
    /// The plan's start time \[s\].
    pub start: f64,
}

/// What a controller through the vessel's thrust keeps between re-plans.
#[derive(Clone, Debug)]
pub(super) struct ThrustState {
    pub(super) actuator: Actuator,
    /// The per-step problem of the last horizon length (in steps), cloned and started from
    /// each observation.
    pub(super) template: Option<(usize, ControlProblem<PerStepControl, PlanObjective>)>,
    /// The last re-plan's result.
    pub(super) last: Option<crate::optimize::OptimResult>,
    /// The last plan's thrusts and objective.
    pub(super) planned: Option<PlannedThrust>,
}

impl Mpc {
    /// A re-plan through the vessel's thrust ([`crate::mpc`], "MPC through the vessel's
    /// thrust"): the commands of the horizon by the bounded L-BFGS on the exact adjoint
    /// gradient, from the previous plan shifted by one interval, within the iteration budget.
    pub(super) fn replan_thrust(&mut self, obs: &ModelObservation<'_, 2>) -> Result<()> {
        let pieces = self.horizon_pieces(obs)?;
        let hp = self.model.time.step;
        let r = plan_step_ratio(hp, obs.h)?;
        // From t_{k−1} with its thrust fixed (the plant re-takes the step into t_k with the
        // command decided now), or from rest at t = 0. A plan at a coarser step r h starts at
        // t_k from the observed state with the thrust applied there fixed (the plant's re-taken
        // step then moves that thrust by at most Ḟ_max h toward the new command: the plan's
        // approximation, [`crate::mpc`] "MPC through the vessel's thrust").
        let coarse = r > 1.0;
        let (lead, start, t_start, before) = match obs.previous_state {
            _ if coarse && obs.k > 0 => (1, Some(obs.state), obs.t, obs.control),
            Some(prev) if obs.k > 0 => (
                1,
                Some(prev),
                (obs.k - 1) as f64 * obs.h,
                obs.previous_control,
            ),
            _ => (0, None, 0.0, obs.previous_control),
        };
        let steps = lead + pieces * self.model_steps;
        let record = self.record_chain(obs, pieces + 1)?;
        let state = self.thrust.as_mut().expect("a thrust controller");
        if state.template.as_ref().map(|t| t.0) != Some(steps) {
            let objective = match &self.hotspot {
                Some(o) => PlanObjective::HotSpot(o.clone()),
                None => PlanObjective::Base(BendingObjective {
                    kind: self.options.objective,
                    effort: self.options.effort,
                }),
            };
            let problem = thrust_template(&self.model, steps, objective, record)?;
            state.template = Some((steps, problem));
        }
        if let Some(noisy) = self.noisy.as_mut() {
            // A new forecast from the decision at t_k for the plan from t_{k−1}.
            let record = self.record.as_ref().expect("built above");
            let end = t_start + steps as f64 * hp;
            let chain = noisy.forecast_chain(record, obs.t, (t_start, end))?;
            let t = state.template.take().expect("set above");
            state.template = Some((t.0, t.1.with_chain(chain)));
        }
        let template = &state.template.as_ref().expect("set above").1;
        if self.planning.is_none() {
            super::check_model_size(template.chain().n(), obs.state.q.len())?;
        }
        // A reduced plan starts from the plant's state mapped onto its chain (the vessel's
        // (Z, Ż) copied), as a force plan's does ([`super::planning`]).
        let start = match (start, self.planning.as_mut()) {
            (Some(plant), Some((map, mapped))) => {
                map.map(plant, mapped)?;
                Some(&*mapped)
            }
            (start, _) => start,
        };
        let problem = match start {
            Some(prev) => template.clone().starting_from(prev.clone(), t_start)?,
            None => template.clone(),
        };
        // The water's momenta of the horizon's steps once for the re-plan's dozen sweeps (the
        // same values bit for bit: Chain::tabulate_water).
        let problem = {
            let mut chain = problem.chain().clone();
            let t0 = if start.is_some() { t_start } else { 0.0 };
            chain.tabulate_water(t0, hp, steps);
            problem.with_chain(chain)
        };
        let actuator = state.actuator;
        self.warm_start(pieces);
        for w in &mut self.warm {
            *w = w.clamp(-actuator.bound, actuator.bound);
        }
        let mut plan = ThrustPlan {
            problem: &problem,
            actuator,
            m: self.model_steps,
            lead,
            before,
            pieces,
            sigma: 0.0,
        };
        // σ: the penalty of a command a whole F_max away from its thrust weighs 10⁻³ of the
        // warm start's moment objective (any σ > 0 leaves the optimal thrusts as they are).
        let (u0, _) = plan.thrusts(&self.warm);
        let j0 = problem.value(&u0)?;
        plan.sigma = 1e-3 * j0.abs() / (pieces as f64 * actuator.bound * actuator.bound);
        let max_iters = if self.decisions == 0 {
            self.options.first_iterations
        } else {
            self.options.thrust_iterations
        };
        let opts = thrust_search(actuator, max_iters)?;
        let r = minimize(&plan, &self.warm, &opts)?;
        self.plan.clone_from(&r.theta);
        let (thrusts, _) = plan.thrusts(&r.theta);
        let planned = PlannedThrust {
            objective: r.objective - plan.penalty(&r.theta, &thrusts),
            thrusts,
            start: t_start,
        };
        let state = self.thrust.as_mut().expect("a thrust controller");
        state.last = Some(r);
        state.planned = Some(planned);
        self.decisions += 1;
        Ok(())
    }

    /// A decision from the sensors ([`Observe::Sensors`]): the filter's update at this decision,
    /// then the thrust plan from its estimate instead of the plant's state.
    pub(super) fn control_observed(&mut self, obs: &ModelObservation<'_, 2>) -> Result<f64> {
        let mut observer = match self.observer.take() {
            Some(o) => o,
            None => {
                let scene = self.observer_model.as_ref().unwrap_or(&self.model);
                Observer::new(scene, obs.steps, self.interval, self.options.observer)?
            }
        };
        observer.observe(obs)?;
        let planned = self.replan_thrust(&observer.observation(obs));
        let command = self.plan.first().copied().unwrap_or(0.0);
        observer.commanded(obs.k, command);
        self.observer = Some(observer);
        planned.map(|()| command)
    }

    /// The Kalman filter of [`Observe::Sensors`] (after the first decision).
    pub fn observer(&self) -> Option<&Observer> {
        self.observer.as_ref()
    }

    /// The last plan through the vessel's thrust: its per-step thrusts and its moment objective
    /// (`None` for a force control or before the first decision).
    pub fn last_thrust_plan(&self) -> Option<&PlannedThrust> {
        self.thrust.as_ref().and_then(|t| t.planned.as_ref())
    }

    /// The last re-plan's result through the vessel's thrust (`None` for a force control).
    pub fn last_thrust_result(&self) -> Option<&crate::optimize::OptimResult> {
        self.thrust.as_ref().and_then(|t| t.last.as_ref())
    }
}

/// The ratio r = h_plan / h of the plan's step to the plant's, refused unless a whole number
/// ≥ 1 (to 1e-9) of a finite step: [`MpcError::ThrustStep`] otherwise. Shared by the coarser
/// plan on the plant's pendulums and the reduced plan.
pub(super) fn plan_step_ratio(hp: f64, h: f64) -> Result<f64> {
    let r = (hp / h).round();
    if !(hp.is_finite() && r >= 1.0) || (r * h - hp).abs() > 1e-9 * hp {
        return Err(MpcError::ThrustStep {
            model: hp,
            plant: h,
        }
        .into());
    }
    Ok(r)
}

/// The horizon's problem of `steps` per-step thrusts on the plan's `model` (its load series
/// held past their end), on the chain `record` whose loads are realised over the run.
fn thrust_template(
    model: &Scene,
    steps: usize,
    objective: PlanObjective,
    record: Chain<f64, 2>,
) -> Result<ControlProblem<PerStepControl, PlanObjective>> {
    let mut scene = model.clone();
    scene.time.steps = steps;
    hold_series_past_end(&mut scene);
    Ok(ControlProblem::builder(&scene)
        .map(PerStepControl { steps })
        .objective(objective)
        .build_in::<2>()?
        .with_chain(record))
}

/// The bounded L-BFGS of a thrust re-plan: |F| ≤ F_max, `max_iters` iterations, steps scaled
/// to F_max, no polishing.
fn thrust_search(actuator: Actuator, max_iters: usize) -> Result<OptimOptions> {
    Ok(OptimOptions {
        method: Method::Lbfgs,
        max_iters,
        bounds: Some(Bounds::symmetric(actuator.bound)?),
        first_step: 0.01 * actuator.bound,
        trust_radius: 0.1 * actuator.bound,
        max_trust_radius: actuator.bound,
        polish_steps: 0,
        ..OptimOptions::default()
    })
}
