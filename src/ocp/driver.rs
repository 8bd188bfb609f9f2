//! The iteration: start, Gauss-Newton QP, closed-loop line search, regularisation schedule,
//! convergence and failure reports (module docs, "Globalisation", "Convergence").

use super::*;

impl Solver {
    /// Runs the solver from θ₀ (projected onto the box): Gauss-Newton SQP iterations whose
    /// box-constrained QP is solved by Riccati-based projected Newton, globalised by closed-loop
    /// rollouts with backtracking and a proximal (Levenberg) weight (module docs).
    pub fn solve(&mut self, theta0: &[f64]) -> Result<OcpResult> {
        let t0 = Instant::now();
        self.counts = (0, 0, 0);
        let j0 = self.set_point(theta0)?;
        let opts = self.opts.clone();
        let (lo, hi) = (opts.lower, opts.upper);
        let in_memory = self.block >= self.steps;
        let width = if (hi - lo).is_finite() { hi - lo } else { 1.0 };
        let mut mu = 0.0;
        let mut iterations = 0;
        let mut roundoff_steps = 0;
        let mut roundoff_pg = f64::INFINITY;
        let mut history = Vec::new();
        let mut g0 = None;
        let mut last_pg = f64::INFINITY;
        let termination = 'outer: loop {
            if iterations > 0 && iterations >= opts.max_iters && !opts.final_gradient {
                break Termination::Budget;
            }
            // The exact gradient at the nominal (costate sweep) and the convergence test.
            self.costate()?;
            let pg = self.projected_norm();
            last_pg = pg;
            let gref = *g0
                .get_or_insert_with(|| self.riccati.grad.iter().map(|g| g * g).sum::<f64>().sqrt());
            if pg <= opts.grad_tol.max(opts.rel_grad_tol * gref) {
                break Termination::Converged;
            }
            if iterations >= opts.max_iters {
                break Termination::MaxIterations;
            }
            self.gtrue.copy_from_slice(&self.riccati.grad);
            // The step: the box-constrained QP of the Gauss-Newton model, solved to a relative
            // accuracy η = min(0.1, √(‖pg‖/‖g₀‖)) (inexact Newton with a vanishing forcing
            // term); without every Jacobian in memory, one Riccati pass on the ε-active set.
            let jbar = self.nominal.cost;
            let (d1, d2) = loop {
                self.prox = mu * self.quu_scale;
                if in_memory {
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
                        break (a, (q - jbar) - a);
                    }
                } else {
                    self.set_active((1e-3 * width).min(pg));
                    if self.sweep(true)? {
                        self.ff_out.copy_from_slice(&self.riccati.ff);
                        break (self.riccati.d1, self.riccati.d2);
                    }
                }
                mu = (mu * 10.0).max(MU_MIN);
                if mu > opts.max_regularisation {
                    break 'outer Termination::RegularisationLimit;
                }
            };
            // Line search on closed-loop rollouts of the simulator: α = 1 first, then the
            // minimiser of the quadratic through J̄, the slope d1 and J(α), kept in [α/10, α/2].
            let jscale = jbar.abs().max(1e-6 * j0.abs());
            let tiny = ROUNDOFF * jscale;
            let mut accepted = None;
            let mut alpha = 1.0;
            for _ in 0..opts.backtracks {
                let dj = alpha * d1 + alpha * alpha * d2;
                let fb = Feedback {
                    nominal: &self.nominal,
                    gain: &self.riccati.gain,
                    ff: &self.ff_out,
                    alpha,
                    nz: self.nz,
                };
                self.counts.0 += 1;
                let ok = rollout(
                    (&self.model, &self.cost),
                    &mut self.stepper,
                    &self.free,
                    (lo, hi),
                    Some(&fb),
                    &mut self.trial,
                    &mut self.scratch,
                )
                .is_ok();
                let mut next = 0.5 * alpha;
                if ok {
                    let jt = self.trial.cost;
                    if -dj <= tiny {
                        // Round-off regime: the model's decrease is not resolvable in J; take
                        // the step unless J rises beyond its round-off.
                        if jt <= jbar + NOISE * jscale {
                            accepted = Some((alpha, true, 1.0));
                            break;
                        }
                    } else {
                        let ratio = (jbar - jt) / (-dj);
                        if ratio >= opts.armijo {
                            accepted = Some((alpha, false, ratio));
                            break;
                        }
                        let b = (jt - jbar - alpha * d1) / (alpha * alpha);
                        if b > 0.0 && d1 < 0.0 {
                            next = (-d1 / (2.0 * b)).clamp(0.1 * alpha, 0.5 * alpha);
                        }
                    }
                }
                alpha = next;
            }
            match accepted {
                Some((alpha, roundoff, ratio)) => {
                    std::mem::swap(&mut self.nominal, &mut self.trial);
                    self.jac_range = None;
                    iterations += 1;
                    history.push(IterationRecord {
                        objective: self.nominal.cost,
                        projected_gradient_norm: pg,
                        alpha,
                        regularisation: mu,
                    });
                    if roundoff {
                        // Below J's resolution only the projected gradient shows progress: stop
                        // when it has not fallen by 10 % over several such steps.
                        if roundoff_steps == 0 || pg < 0.9 * roundoff_pg {
                            roundoff_steps = 0;
                            roundoff_pg = pg;
                        }
                        roundoff_steps += 1;
                        if roundoff_steps > MAX_ROUNDOFF_STEPS {
                            self.costate()?;
                            let pg = self.projected_norm();
                            if pg <= opts.grad_tol.max(opts.rel_grad_tol * gref) {
                                break Termination::Converged;
                            }
                            break Termination::RoundOff;
                        }
                    } else {
                        roundoff_steps = 0;
                    }
                    // Levenberg-Marquardt schedule on the agreement of J with its model.
                    if alpha >= 1.0 && ratio > 0.75 {
                        mu = if mu * 0.25 < MU_MIN { 0.0 } else { mu * 0.25 };
                    } else if alpha < 1.0 || ratio < 0.25 {
                        mu = (mu * 4.0).max(MU_MIN);
                    }
                }
                None => {
                    mu = (mu * 10.0).max(MU_MIN);
                    if mu > opts.max_regularisation {
                        break Termination::RegularisationLimit;
                    }
                }
            }
        };
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
            last_pg
        } else {
            self.projected_norm()
        };
        let active_bounds = theta
            .iter()
            .enumerate()
            .filter(|(_, &t)| t <= lo || t >= hi)
            .map(|(i, _)| i)
            .collect();
        Ok(OcpResult {
            objective: self.nominal.cost,
            initial_objective: j0,
            controls: self.nominal.u.clone(),
            theta,
            gradient_norm: gn,
            projected_gradient_norm: pg,
            initial_gradient_norm: g0.unwrap_or(gn),
            active_bounds,
            iterations,
            rollouts: self.counts.0,
            jacobian_passes: self.counts.1,
            backward_passes: self.counts.2,
            seconds: t0.elapsed().as_secs_f64(),
            converged: termination == Termination::Converged,
            termination,
            history,
        })
    }
}
