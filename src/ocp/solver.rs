//! The Riccati solver (module docs): its parts — the horizon and its trajectories, the Jacobian
//! store, the second-order model, the QP iterate, the interior point and the backward pass —
//! and the steps of the outer iteration it runs ([`super::globalise::Outer`]).

use std::time::Instant;

use super::boxqp;
use super::globalise::{backtrack, raise_mu, LineSearch, ModelChange, Outer, Progress, Step};
use super::horizon::ControlHorizon;
use super::interior::InteriorPoint;
use super::iterate::QpIterate;
use super::jacobians::{JacobianStore, PREFETCH_AHEAD};
use super::options::{IterationObserver, OcpOptions, OcpResult, OcpTermination};
use super::riccati::{Riccati, RiccatiShape, StageInput};
use super::second_order::SecondOrderModel;
use crate::adjoint::{ControlMap, ControlProblem, Objective};
use crate::error::Result;
use std::any::Any;

/// The solver with all its buffers, reusable for several starts (and the linearisation
/// diagnostics the tests use), in the planar (`DIM = 2`) or the spatial (`DIM = 3`) model
/// (module docs, "The spatial model").
#[derive(Clone, Debug)]
pub struct Solver<const DIM: usize = 2> {
    pub(super) horizon: ControlHorizon<DIM>,
    pub(super) store: JacobianStore<DIM>,
    pub(super) second: SecondOrderModel,
    pub(super) qp: QpIterate,
    pub(super) ip: InteriorPoint,
    pub(super) riccati: Riccati,
    /// The exact gradient at the nominal (per decision).
    gtrue: Vec<f64>,
    /// Proximal weight μ (absolute) of the current model, and the mean Q_uu it is relative to.
    pub(super) prox: f64,
    pub(super) quu_scale: f64,
    /// Riccati passes run.
    backward_passes: usize,
    pub(super) nxi: usize,
    pub(super) nz: usize,
    /// Controls per stage m (1, or 2 for a 2-axis control).
    pub(super) ncu: usize,
}

impl<const DIM: usize> Solver<DIM> {
    /// Builds the solver for `problem` (validates the options, the model, the objective — one
    /// in Gauss-Newton form, in the spatial model of |M₀| alone — and the control map).
    pub fn new<P: ControlMap, O: Objective>(
        problem: &ControlProblem<P, O, DIM>,
        options: &OcpOptions,
    ) -> Result<Self> {
        let horizon = ControlHorizon::new(problem, options, "the Riccati solver", |_, _| Ok(()))?;
        let (model, steps) = (&horizon.model, horizon.steps);
        let (nxi, ncu) = (model.nx(), horizon.axes);
        let held = options.rate_penalty > 0.0 || horizon.free.iter().any(|f| !f);
        let aug = if held { ncu } else { 0 };
        let nz = nxi + aug;
        let store = JacobianStore::new(model, options, steps)?;
        let second = SecondOrderModel::new(model, options, steps, aug)?;
        let shape = RiccatiShape {
            nxi,
            aug,
            controls: ncu,
            residuals: DIM - 1,
        };
        Ok(Solver {
            store,
            second,
            qp: QpIterate::new(steps, nz, ncu),
            ip: InteriorPoint::new((steps + 1) * ncu),
            riccati: Riccati::new(shape, steps),
            gtrue: vec![0.0; (steps + 1) * ncu],
            prox: 0.0,
            quu_scale: 1.0,
            backward_passes: 0,
            nxi,
            nz,
            ncu,
            horizon,
        })
    }

    /// The planar horizon, store and second-order model (the exact model's reverse steps are
    /// planar): `None` in the spatial model, by a checked downcast.
    fn planar_parts(
        &mut self,
    ) -> Option<(
        &ControlHorizon<2>,
        &mut JacobianStore<2>,
        &mut SecondOrderModel,
    )> {
        let hz = (&self.horizon as &dyn Any).downcast_ref::<ControlHorizon<2>>()?;
        let store = (&mut self.store as &mut dyn Any).downcast_mut::<JacobianStore<2>>()?;
        Some((hz, store, &mut self.second))
    }

    /// Number of parameters θ.
    pub fn n_params(&self) -> usize {
        self.horizon.n_params
    }

    /// Simulates θ (projected onto the box) as the new nominal trajectory and returns J.
    pub fn set_point(&mut self, theta: &[f64]) -> Result<f64> {
        let j = self.horizon.set_point(theta);
        self.store.invalidate();
        self.second.valid = false;
        j
    }

    /// θ of the nominal trajectory.
    pub fn theta(&self) -> Vec<f64> {
        self.horizon.theta()
    }

    /// J of the nominal trajectory.
    pub fn objective(&self) -> f64 {
        self.horizon.nominal.cost
    }

    /// Runs the solver from θ₀ (projected onto the box): Gauss-Newton SQP iterations whose
    /// box-constrained QP is solved by Riccati-based projected Newton, globalised by closed-loop
    /// rollouts with backtracking and a proximal (Levenberg) weight (module docs).
    pub fn solve(&mut self, theta0: &[f64]) -> Result<OcpResult> {
        super::globalise::run(self, theta0, None)
    }

    /// [`Solver::solve`] with an observer called after every accepted iteration (θ, J and the
    /// record of the step); it may stop the run ([`OcpTermination::Stopped`]).
    ///
    /// # Errors
    /// As [`Solver::solve`].
    pub fn solve_observed(
        &mut self,
        theta0: &[f64],
        observer: IterationObserver<'_>,
    ) -> Result<OcpResult> {
        super::globalise::run(self, theta0, Some(observer))
    }

    /// What the backward pass needs of stage k at the model point δ (the current inner
    /// iterate: `dv`, `dz`; δ = 0 is the nominal) without its Jacobians: the linearised
    /// residual R + ∂R/∂φ₁ δφ₁, the shifted controls, the box relative to them and the proximal
    /// gradient, per control. With `with_active`, a control of the ε-active set gets its fixed
    /// step.
    fn stage_input(&self, k: usize, with_active: bool) -> StageInput<'static> {
        // A planar control is along z alone (a 2-axis control is spatial, `StageModel::with_axes`):
        // m = 1 as a constant lets the planar instance drop the loop over the axes below.
        let m = if DIM == 2 { 1 } else { self.ncu };
        let (hz, qp) = (&self.horizon, &self.qp);
        let nom = &hz.nominal;
        let (r, d) = nom.residual_model(k, hz.model.moment_scale);
        let dz = &qp.dz[k * self.nz..];
        let mut residual = [r[0] + d[0][0] * dz[0], 0.0];
        if DIM == 3 {
            for (c, x) in residual.iter_mut().enumerate() {
                *x = r[c] + d[c][0] * dz[0] + d[c][1] * dz[1];
            }
        }
        let mut inp = StageInput {
            k,
            free: hz.free[k],
            residual,
            dresidual: d,
            u: [0.0; 2],
            w: [0.0; 2],
            lo: [0.0; 2],
            hi: [0.0; 2],
            lu_shift: [0.0; 2],
            quu_shift: [0.0; 2],
            jac: None,
            hess: None,
            curv: 0.0,
            dz: &[],
            dv: qp.dv[k * m],
        };
        for a in 0..m {
            let i = k * m + a;
            let u = nom.control(k, a) + qp.dv[i];
            (inp.lo[a], inp.hi[a]) = if self.ip.on {
                (f64::NEG_INFINITY, f64::INFINITY)
            } else if with_active && qp.active[i] {
                (qp.fixed[i], qp.fixed[i])
            } else {
                (hz.opts.lower - u, hz.opts.upper - u)
            };
            let (qs, ls) = if self.ip.on && hz.free[k] {
                (self.ip.quu[i], self.ip.lu[i])
            } else {
                (0.0, 0.0)
            };
            inp.u[a] = u;
            if k > 0 {
                inp.w[a] = nom.control(k - 1, a) + qp.dv[i - m];
            }
            if hz.free[k] {
                inp.lu_shift[a] = self.prox * qp.dv[i] + ls;
            }
            inp.quu_shift[a] = qs;
        }
        inp
    }

    /// One sweep k = N … 0 over the stages, with the Jacobians computed block by block ahead
    /// of it: the Riccati recursion (`riccati = true`, proximal weight `self.prox`; returns
    /// whether every stage QP was bounded) or the costate sweep alone (the gradient into
    /// `riccati.grad`).
    pub(super) fn sweep(&mut self, riccati: bool) -> Result<bool> {
        let (steps, nz, mu) = (self.horizon.steps, self.nz, self.prox);
        self.riccati.begin();
        let mut last = self.stage_input(steps, true);
        self.second.view(&self.qp.dz, steps, nz).attach(&mut last);
        let cost = &self.horizon.cost;
        let mut bounded = if riccati {
            self.backward_passes += 1;
            self.riccati.stage(&last, cost, mu)
        } else {
            self.riccati.costate(&last, cost);
            true
        };
        let mut top = steps;
        while top > 0 {
            let bottom = top.saturating_sub(self.store.block);
            let hz = &self.horizon;
            self.store.fill(&hz.model, &hz.nominal, bottom..top)?;
            let h_store = self.second.exact.then_some(&self.second.h[..]);
            for k in (bottom..top).rev() {
                let i = k - bottom;
                if i >= PREFETCH_AHEAD {
                    self.store
                        .prefetch(i - PREFETCH_AHEAD, h_store, k - PREFETCH_AHEAD);
                }
                let mut inp = self.stage_input(k, true);
                inp.jac = Some(self.store.stage(i));
                self.second.view(&self.qp.dz, steps, nz).attach(&mut inp);
                if riccati {
                    bounded &= self.riccati.stage(&inp, &self.horizon.cost, mu);
                } else {
                    self.riccati.costate(&inp, &self.horizon.cost);
                }
            }
            top = bottom;
        }
        if riccati && self.riccati.quu_count > 0 {
            let m = self.riccati.quu_sum / self.riccati.quu_count as f64;
            self.quu_scale = if m > 0.0 && m.is_finite() { m } else { 1.0 };
        }
        Ok(bounded)
    }

    /// The exact gradient at the nominal (δ = 0, no active set): the costate sweep.
    pub(super) fn costate(&mut self) -> Result<()> {
        self.qp.at_nominal();
        self.qp.active.fill(false);
        self.sweep(false).map(|_| ())
    }

    /// The exact gradient and the costates ν_k at the nominal by one reverse step per stage
    /// ([`SecondOrderModel::costates`]), for the exact model (planar only: the spatial model
    /// never turns it on, and would get the costate sweep).
    pub(super) fn costate_by_reverse_steps(&mut self) -> Result<()> {
        self.qp.at_nominal();
        self.qp.active.fill(false);
        match (&self.horizon as &dyn Any).downcast_ref::<ControlHorizon<2>>() {
            Some(hz) => self.second.costates(hz, &mut self.riccati.grad),
            None => self.costate(),
        }
    }

    /// H_k and the Jacobians of every stage at the nominal, and the cost's curvature
    /// ([`SecondOrderModel::compute`]); needs the costates of
    /// [`Solver::costate_by_reverse_steps`]. Planar only ([`OcpError::NoExactModel`]
    /// otherwise; the spatial model never turns the exact model on).
    ///
    /// [`OcpError::NoExactModel`]: crate::error::OcpError::NoExactModel
    pub(super) fn hessians(&mut self) -> Result<()> {
        match self.planar_parts() {
            Some((hz, store, second)) => second.compute(hz, store),
            None => Err(crate::error::OcpError::NoExactModel.into()),
        }
    }

    /// ∂J/∂θ from the per-decision gradient of the last costate sweep.
    pub(super) fn theta_gradient(&self) -> Vec<f64> {
        let hz = &self.horizon;
        (0..hz.n_params)
            .map(|i| {
                let (k, a) = hz.decision(i);
                self.riccati.grad[k * self.ncu + a]
            })
            .collect()
    }

    /// ‖θ − Π_box(θ − g)‖₂ at the model point with the gradient of the last costate sweep.
    pub(super) fn projected_norm(&self) -> f64 {
        let hz = &self.horizon;
        let (lo, hi) = (hz.opts.lower, hz.opts.upper);
        (0..hz.n_params)
            .map(|i| {
                let (k, a) = hz.decision(i);
                let j = k * self.ncu + a;
                let (t, g) = (
                    hz.nominal.control(k, a) + self.qp.dv[j],
                    self.riccati.grad[j],
                );
                let d = boxqp::projected_component(t, g, lo, hi);
                d * d
            })
            .sum::<f64>()
            .sqrt()
    }

    /// The step: the box-constrained QP of the Gauss-Newton model, solved to a relative
    /// accuracy η = min(0.1, √(‖pg‖/‖g₀‖)) (inexact Newton with a vanishing forcing term);
    /// without every Jacobian in memory, one Riccati pass on the ε-active set. Raises μ until
    /// the model is solvable; returns the predicted change ΔJ(α), or `None` with μ beyond its
    /// limit.
    fn model_step(&mut self, pr: &mut Progress, pg: f64, gref: f64) -> Result<Option<ModelChange>> {
        let opts = self.horizon.opts.clone();
        let (lo, hi) = (opts.lower, opts.upper);
        let width = if (hi - lo).is_finite() { hi - lo } else { 1.0 };
        let jbar = self.horizon.nominal.cost;
        let steps = self.horizon.steps;
        loop {
            self.prox = pr.mu * self.quu_scale;
            if self.store.holds_all(steps) {
                let eta = (pg / gref).sqrt().min(0.1);
                let target = opts.grad_tol.max(opts.rel_grad_tol * gref);
                let tol = (eta * pg).max(0.1 * target);
                let q = match self.warm_qp(tol)? {
                    Some(q) => Some(q),
                    None => self.solve_qp(tol)?,
                };
                if let Some(q) = q {
                    let m = self.ncu;
                    let a: f64 = (0..(steps + 1) * m)
                        .filter(|&i| self.horizon.free[i / m])
                        .map(|i| self.gtrue[i] * self.qp.dv[i])
                        .sum();
                    return Ok(Some(ModelChange {
                        d1: a,
                        d2: (q - jbar) - a,
                    }));
                }
            } else {
                let eps = (1e-3 * width).min(pg);
                self.qp.set_active(&self.horizon, &self.riccati.grad, eps);
                if self.sweep(true)? {
                    self.qp.ff.copy_from_slice(&self.riccati.ff);
                    return Ok(Some(ModelChange {
                        d1: self.riccati.d1,
                        d2: self.riccati.d2,
                    }));
                }
            }
            pr.mu = raise_mu(pr.mu);
            if pr.mu > opts.max_regularisation {
                return Ok(None);
            }
        }
    }
}

impl<const DIM: usize> Outer for Solver<DIM> {
    fn begin(&mut self) {
        self.horizon.rollouts = 0;
        self.store.passes = 0;
        self.backward_passes = 0;
        self.second.begin(self.horizon.opts.curvature);
    }

    fn options(&self) -> &OcpOptions {
        &self.horizon.opts
    }

    fn nominal_cost(&self) -> f64 {
        self.horizon.nominal.cost
    }

    fn theta(&self) -> Vec<f64> {
        Solver::theta(self)
    }

    fn set_point(&mut self, theta: &[f64]) -> Result<f64> {
        Solver::set_point(self, theta)
    }

    /// The exact gradient at the nominal (costate sweep); with the exact model by reverse
    /// steps, whose H_k pass then computes the Jacobians too.
    fn linearise(&mut self) -> Result<f64> {
        if self.second.on {
            self.costate_by_reverse_steps()?;
        } else {
            self.costate()?;
        }
        Ok(self.projected_norm())
    }

    fn gradient(&self) -> &[f64] {
        &self.riccati.grad
    }

    /// The model step and its closed-loop line search; the curvature of the next iterations
    /// follows how well the model predicted this one.
    fn step(&mut self, pr: &mut Progress, pg: f64, gref: f64) -> Result<Step> {
        self.gtrue.copy_from_slice(&self.riccati.grad);
        self.second.exact = self.second.on;
        if self.second.exact && !self.second.valid {
            self.hessians()?;
        }
        let jbar = self.horizon.nominal.cost;
        let Some(model) = self.model_step(pr, pg, gref)? else {
            return Ok(Step::NoModel);
        };
        let opts = &self.horizon.opts;
        let curvature = opts.curvature;
        let search = LineSearch {
            jbar,
            j0: pr.j0,
            model,
            armijo: opts.armijo,
            tries: opts.backtracks,
        };
        let (hz, gain, ff, nz) = (&mut self.horizon, &self.riccati.gain, &self.qp.ff, self.nz);
        let trial = |alpha| {
            hz.closed_loop_trial(gain, ff, alpha, nz)
                .then_some(hz.trial.cost)
        };
        Ok(match backtrack(search, trial) {
            Some(acc) => {
                self.second
                    .switch(curvature, acc.alpha >= 1.0 && acc.ratio >= 0.5);
                Step::Accepted(acc)
            }
            None => {
                self.second.switch(curvature, false);
                Step::Rejected
            }
        })
    }

    fn take_step(&mut self) {
        self.horizon.take_trial();
        self.store.invalidate();
        self.second.valid = false;
    }

    /// Steps below J's round-off stopped lowering the projected gradient: converged if the
    /// swept gradient meets the tolerance.
    fn stalled(&mut self, target: f64) -> Result<OcpTermination> {
        self.costate()?;
        Ok(if self.projected_norm() <= target {
            OcpTermination::Converged
        } else {
            OcpTermination::RoundOff
        })
    }

    /// The result at the final nominal.
    fn report(&mut self, termination: OcpTermination, pr: Progress, t0: Instant) -> OcpResult {
        // The true gradient at the final nominal (the QP iterations overwrite the costates).
        let stale = matches!(
            termination,
            OcpTermination::Budget | OcpTermination::Stopped
        );
        if termination == OcpTermination::RegularisationLimit || stale {
            self.riccati.grad.copy_from_slice(&self.gtrue);
        }
        self.qp.at_nominal();
        let theta = self.theta();
        let g = self.theta_gradient();
        let gn = g.iter().map(|x| x * x).sum::<f64>().sqrt();
        // With the budget spent (no final gradient), the measure of the last evaluation.
        let pg = if stale {
            pr.last_pg
        } else {
            self.projected_norm()
        };
        let hz = &self.horizon;
        let (lo, hi) = (hz.opts.lower, hz.opts.upper);
        let active_bounds = theta
            .iter()
            .enumerate()
            .filter(|(_, &t)| t <= lo || t >= hi)
            .map(|(i, _)| i)
            .collect();
        OcpResult {
            objective: hz.nominal.cost,
            initial_objective: pr.j0,
            controls: hz.nominal.u.clone(),
            controls_x: hz.nominal.ux.clone(),
            theta,
            gradient_norm: gn,
            projected_gradient_norm: pg,
            initial_gradient_norm: pr.g0.unwrap_or(gn),
            active_bounds,
            iterations: pr.iterations,
            rollouts: hz.rollouts,
            jacobian_passes: self.store.passes,
            backward_passes: self.backward_passes,
            seconds: t0.elapsed().as_secs_f64(),
            converged: termination == OcpTermination::Converged,
            termination,
            history: pr.history,
        }
    }
}
