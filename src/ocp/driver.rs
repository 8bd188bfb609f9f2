//! The iteration: start, Gauss-Newton QP, closed-loop line search, regularisation schedule,
//! convergence and failure reports (module docs, "Globalisation", "Convergence").

use super::globalise::{backtrack, next_mu, raise_mu, Accepted, LineSearch, ModelChange, Progress};
use super::*;

impl Solver {
    /// Runs the solver from θ₀ (projected onto the box): Gauss-Newton SQP iterations whose
    /// box-constrained QP is solved by Riccati-based projected Newton, globalised by closed-loop
    /// rollouts with backtracking and a proximal (Levenberg) weight (module docs).
    pub fn solve(&mut self, theta0: &[f64]) -> Result<OcpResult> {
        let t0 = Instant::now();
        self.counts = (0, 0, 0);
        self.second_order_on =
            self.opts.curvature == Curvature::Exact && self.second_order_possible;
        let mut pr = Progress::new(self.set_point(theta0)?);
        let termination = loop {
            if let Some(t) = self.iterate(&mut pr)? {
                break t;
            }
        };
        Ok(self.report(termination, pr, t0))
    }

    /// One iteration: the exact gradient and the stopping tests, the step of the Gauss-Newton
    /// model, the line search and the regularisation schedule. `Some` ends the run.
    fn iterate(&mut self, pr: &mut Progress) -> Result<Option<Termination>> {
        let opts = self.opts.clone();
        if pr.budget_spent(&opts) {
            return Ok(Some(Termination::Budget));
        }
        // The exact gradient at the nominal (costate sweep) and the convergence test; with the
        // exact model by reverse steps, whose H_k pass then computes the Jacobians too.
        if self.second_order_on {
            self.costate_by_reverse_steps()?;
        } else {
            self.costate()?;
        }
        let pg = self.projected_norm();
        let (stop, target, gref) = pr.stop_test(&opts, pg, &self.riccati.grad);
        if stop.is_some() {
            return Ok(stop);
        }
        self.gtrue.copy_from_slice(&self.riccati.grad);
        self.exact = self.second_order_on;
        if self.exact && !self.h_valid {
            self.hessians()?;
        }
        let jbar = self.nominal.cost;
        let Some(model) = self.model_step(pr, pg, gref)? else {
            return Ok(Some(Termination::RegularisationLimit));
        };
        let search = LineSearch {
            jbar,
            j0: pr.j0,
            model,
            armijo: opts.armijo,
            tries: opts.backtracks,
        };
        let trial = |alpha| self.trial_rollout(alpha).then_some(self.trial.cost);
        match backtrack(search, trial) {
            Some(acc) => {
                self.switch_curvature(acc.alpha >= 1.0 && acc.ratio >= 0.5);
                self.accept(pr, acc, pg, target)
            }
            None => {
                self.switch_curvature(false);
                pr.mu = raise_mu(pr.mu);
                Ok((pr.mu > opts.max_regularisation).then_some(Termination::RegularisationLimit))
            }
        }
    }

    /// The step: the box-constrained QP of the Gauss-Newton model, solved to a relative
    /// accuracy η = min(0.1, √(‖pg‖/‖g₀‖)) (inexact Newton with a vanishing forcing term);
    /// without every Jacobian in memory, one Riccati pass on the ε-active set. Raises μ until
    /// the model is solvable; returns the predicted change ΔJ(α) = α d1 + α² d2 as (d1, d2), or
    /// `None` with μ beyond its limit.
    fn model_step(&mut self, pr: &mut Progress, pg: f64, gref: f64) -> Result<Option<ModelChange>> {
        let opts = self.opts.clone();
        let (lo, hi) = (opts.lower, opts.upper);
        let width = if (hi - lo).is_finite() { hi - lo } else { 1.0 };
        let jbar = self.nominal.cost;
        loop {
            self.prox = pr.mu * self.quu_scale;
            if self.block >= self.steps {
                let eta = (pg / gref).sqrt().min(0.1);
                let target = opts.grad_tol.max(opts.rel_grad_tol * gref);
                let tol = (eta * pg).max(0.1 * target);
                let q = match self.warm_qp(tol)? {
                    Some(q) => Some(q),
                    None => self.solve_qp(tol)?,
                };
                if let Some(q) = q {
                    let a: f64 = (0..=self.steps)
                        .filter(|&k| self.free[k])
                        .map(|k| self.gtrue[k] * self.dv[k])
                        .sum();
                    return Ok(Some(ModelChange {
                        d1: a,
                        d2: (q - jbar) - a,
                    }));
                }
            } else {
                self.set_active((1e-3 * width).min(pg));
                if self.sweep(true)? {
                    self.ff_out.copy_from_slice(&self.riccati.ff);
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

    /// [`Curvature::Auto`]: the exact model from the first step the Gauss-Newton model did not
    /// predict well (`good`: taken in full with actual ≥ ½ predicted decrease) on.
    fn switch_curvature(&mut self, good: bool) {
        if self.opts.curvature == Curvature::Auto && !good && self.second_order_possible {
            self.second_order_on = true;
        }
    }

    /// The closed-loop rollout u_k = clamp(ū_k + α k_k + K_k δz_k) into `self.trial`; `false`
    /// if the simulation failed.
    fn trial_rollout(&mut self, alpha: f64) -> bool {
        let fb = Feedback {
            nominal: &self.nominal,
            gain: &self.riccati.gain,
            ff: &self.ff_out,
            alpha,
            nz: self.nz,
        };
        let shooting = Shooting {
            model: &self.model,
            cost: &self.cost,
            free: &self.free,
            lower: self.opts.lower,
            upper: self.opts.upper,
        };
        self.counts.0 += 1;
        self.sim
            .rollout(&shooting, Some(&fb), &mut self.trial)
            .is_ok()
    }

    /// Takes the accepted step: the trial becomes the nominal, the history grows, the
    /// round-off stop is checked and μ follows the Levenberg-Marquardt schedule on the agreement
    /// of J with its model. `Some` ends the run.
    fn accept(
        &mut self,
        pr: &mut Progress,
        acc: Accepted,
        pg: f64,
        target: f64,
    ) -> Result<Option<Termination>> {
        std::mem::swap(&mut self.nominal, &mut self.trial);
        self.jac_range = None;
        self.h_valid = false;
        pr.iterations += 1;
        pr.history.push(IterationRecord {
            objective: self.nominal.cost,
            projected_gradient_norm: pg,
            alpha: acc.alpha,
            regularisation: pr.mu,
        });
        // Below J's resolution only the projected gradient shows progress: stop when it has
        // not fallen by 10 % over several such steps.
        if pr.roundoff.stalled(acc.roundoff, pg) {
            self.costate()?;
            return Ok(Some(if self.projected_norm() <= target {
                Termination::Converged
            } else {
                Termination::RoundOff
            }));
        }
        pr.mu = next_mu(pr.mu, &acc);
        Ok(None)
    }

    /// The result at the final nominal.
    fn report(&mut self, termination: Termination, pr: Progress, t0: Instant) -> OcpResult {
        // The true gradient at the final nominal (the QP iterations overwrite the costates).
        let stale = termination == Termination::Budget;
        if termination == Termination::RegularisationLimit || stale {
            self.riccati.grad.copy_from_slice(&self.gtrue);
        }
        self.dv.fill(0.0);
        self.dz.fill(0.0);
        let theta = self.theta();
        let g = self.theta_gradient();
        let gn = g.iter().map(|x| x * x).sum::<f64>().sqrt();
        // With the budget spent (no final gradient), the measure of the last evaluation.
        let pg = if stale {
            pr.last_pg
        } else {
            self.projected_norm()
        };
        let (lo, hi) = (self.opts.lower, self.opts.upper);
        let active_bounds = theta
            .iter()
            .enumerate()
            .filter(|(_, &t)| t <= lo || t >= hi)
            .map(|(i, _)| i)
            .collect();
        OcpResult {
            objective: self.nominal.cost,
            initial_objective: pr.j0,
            controls: self.nominal.u.clone(),
            theta,
            gradient_norm: gn,
            projected_gradient_norm: pg,
            initial_gradient_norm: pr.g0.unwrap_or(gn),
            active_bounds,
            iterations: pr.iterations,
            rollouts: self.counts.0,
            jacobian_passes: self.counts.1,
            backward_passes: self.counts.2,
            seconds: t0.elapsed().as_secs_f64(),
            converged: termination == Termination::Converged,
            termination,
            history: pr.history,
        }
    }
}
