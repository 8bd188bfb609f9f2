//! Full condensing: Gauss-Newton on the decisions θ themselves, with the dense sensitivities
//! ∂M₀(t_k)/∂θ_j from forward dual numbers — for horizons with few decisions and many steps
//! (receding-horizon control: 30 pieces of 10 steps).
//!
//! # Why a second method
//! The Riccati solver ([`super::Solver`]) linearises every stage: 2n + 1 directions through
//! each of the N steps (the stage Jacobians A_k, B_k), then O(N n³) per Riccati pass, several
//! passes per QP. When the decisions are few (m ≪ 2n per piece of steps, m pieces), the
//! sensitivities of the residuals r_k = M₀(t_k) to θ cost less: direction j starts at its
//! piece's first stage s_j, so chunk c of 8 decisions runs through N − s_{8c} steps, and the
//! total is Σ_c (N − s_{8c}) dual steps of 8 directions against 3N for the stage Jacobians
//! (n = 10). The Gauss-Newton QP is then dense and tiny (m × m), solved exactly by a primal
//! active-set method (no Riccati pass at all). The cost grows as N·m (quadratic when m grows
//! with the horizon), so the Riccati solver stays the method for long horizons and per-step
//! controls; acados makes the same choice between full condensing and a Riccati-based QP
//! solver (Frison, Diehl et al., *Algorithms and methods for high-performance model predictive
//! control*, 2018).
//!
//! # The model
//! With S_kj = ∂M₀(t_k)/∂θ_j at the nominal and u_k = θ_{piece(k)},
//! ```text
//! J(θ + δ) ≈ Σ_k c_k (M₀_k + S_k δ)² + ρh Σ_k (u_k + δ_{piece(k)})² + (σ/h) Σ_{k≥1} (Δu_k + Δδ_k)²
//! g = 2 Σ_k c_k M₀_k S_kᵀ + (effort and rate terms, exact),   H = 2 Σ_k c_k S_kᵀ S_k + (…)
//! ```
//! the same Gauss-Newton model as the Riccati solver's (the dense Hessian of
//! [`super::Solver::dense_gauss_newton`]), so g is the exact gradient (tested against the adjoint
//! to 10⁻¹²) and the step the same Gauss-Newton step (tested against the Riccati step to
//! 10⁻¹⁰). The dual steps start at the nominal's converged multipliers: the Newton iteration
//! does one derivative-only update, the implicit function theorem (as for the stage
//! Jacobians, [`super::stage`]).
//!
//! # Curvature
//! Gauss-Newton converges linearly when the residuals M₀_k stay large at the optimum (no effort
//! penalty, Table 3.4): its model lacks 2 Σ_k c_k M₀_k ∇²M₀_k. The dense problem is small enough
//! to carry NL2SOL's structured secant approximation A of that term (Dennis, Gay, Welsch,
//! *An adaptive nonlinear least-squares algorithm*, ACM TOMS 1981): after each step
//! s = θ₊ − θ, with y = 2 Σ_k c_k M₀_k(θ₊) (S_k(θ₊) − S_k(θ)), A is sized by
//! min(1, |sᵀy|/|sᵀAs|) and updated by the symmetric Powell-Broyden formula to A s = y; the
//! next step's model adds A only when, on the step just taken, the model with A predicted the
//! change of J better than the one without (NL2SOL's adaptive choice). The first step of a
//! solve is always the Gauss-Newton step (A = 0), so a receding horizon's one-iteration
//! re-plans are unchanged. Measured on Table 3.4 (`cargo bench --bench ocp -- ocp_table_3_4`,
//! through `minimize` with [`Method::Condensed`](crate::optimize::Method::Condensed)): all ten
//! rows converge in 23 ms in total, against 58 ms without A and, when this was measured,
//! 192 ms for the Riccati solver (rows 2 and 3: 21 and 56 iterations against 72 and 125 of
//! plain Gauss-Newton); now 14–18 ms against the Riccati solver's 29–31 ms.
//!
//! # Globalisation and convergence
//! As the Riccati solver: a Levenberg weight μ·mean(diag H) on the QP, an open-loop line search
//! on rollouts of θ + αδ (α = 1 first, then the quadratic interpolation in [α/10, α/2],
//! accepted when J̄ − J(α) ≥ c·(−ΔJ(α))), and the projected gradient for convergence
//! ([`OcpOptions`] tolerances, [`Termination`]).

use std::time::Instant;

use faer::Mat;
use nalgebra::SVector;
use num_dual::Derivative;
#[cfg(feature = "parallel")]
use rayon::prelude::*;

use super::globalise::{backtrack, next_mu, raise_mu, Accepted, LineSearch, ModelChange, Progress};
use super::line_search::{Shooting, Simulator, Traj};
use super::riccati::StageCost;
use super::stage::{Dv, StageModel, Stepper, CHUNK};
use super::{
    available_threads, check_theta, IterationRecord, OcpOptions, OcpResult, Setup, Termination,
};
use crate::adjoint::{ControlMap, ControlProblem, Objective};
use crate::error::{Error, Result};

/// Gauss-Newton on the condensed problem (module docs), with its buffers.
#[derive(Clone, Debug)]
pub struct Condensed {
    model: StageModel,
    cost: StageCost,
    opts: OcpOptions,
    steps: usize,
    np: usize,
    piece: Vec<usize>,
    free: Vec<bool>,
    /// First stage of θ_j.
    theta_stage: Vec<usize>,
    nominal: Traj,
    trial: Traj,
    sim: Simulator,
    chunks: Vec<SensChunk>,
    threads: usize,
    /// H (np × np, row-major, lower triangle filled) and g at the nominal.
    hess: Vec<f64>,
    grad: Vec<f64>,
    /// The QP's step δ and its working set.
    qp: BoxQp,
    /// The structured secant approximation A ≈ 2 Σ_k c_k M₀_k ∇²M₀_k (np × np, full) and the
    /// sensitivities and θ of the previous linearisation (module docs, "Curvature").
    secant: Vec<f64>,
    prev_rows: Vec<f64>,
    prev_theta: Vec<f64>,
    has_prev: bool,
    /// Whether the model of the next step adds A (chosen after each step by which model
    /// predicted its decrease better).
    use_secant: bool,
    counts: (usize, usize),
}

/// The first nonzero relative Levenberg weight after a failed step with μ = 0. The dense
/// Gauss-Newton Hessian is often singular to round-off (controls with little effect, no effort
/// penalty): a shift at that level makes the QP convex without limiting the step. (From 10⁻⁶,
/// the Riccati solver's smallest weight, the steps along a flat valley stayed short: Table 3.4
/// row 9 took 46 iterations, with 10⁻¹² it takes 2.)
const MU_FIRST: f64 = 1e-12;

/// The sensitivities of the decisions θ_first … θ_{first+len−1} (one dual-number chunk).
#[derive(Clone, Debug)]
struct SensChunk {
    first: usize,
    len: usize,
    stepper: Stepper<Dv>,
    /// Row k: ∂M₀(t_k)/∂θ_{first+s} in slot s, k = 0..=N.
    rows: Vec<[f64; CHUNK]>,
}

impl Condensed {
    /// Builds the solver for `problem` (as [`super::Solver::new`]: a planar problem with a
    /// free tip, a bending-moment objective and per-step or piecewise-constant controls).
    ///
    /// # Errors
    /// [`Error::InvalidArgument`] naming the option, the objective, the control map or the tip.
    pub fn new<P: ControlMap, O: Objective>(
        problem: &ControlProblem<P, O>,
        options: &OcpOptions,
    ) -> Result<Self> {
        let Setup {
            model,
            cost,
            steps,
            n_params: np,
            piece,
            free,
            theta_stage,
        } = Setup::new(problem, options, "the condensed Gauss-Newton solver")?;
        check_memory(steps, np)?;
        let chunks = (0..np)
            .step_by(CHUNK)
            .map(|first| {
                Ok(SensChunk {
                    first,
                    len: CHUNK.min(np - first),
                    stepper: Stepper::new(&model)?,
                    rows: vec![[0.0; CHUNK]; steps + 1],
                })
            })
            .collect::<Result<Vec<_>>>()?;
        let chunks = balanced(chunks);
        let threads = if options.threads == 0 {
            available_threads()
        } else {
            options.threads
        };
        let n = model.n;
        Ok(Condensed {
            sim: Simulator::new(&model)?,
            nominal: Traj::new(n, steps),
            trial: Traj::new(n, steps),
            hess: vec![0.0; np * np],
            grad: vec![0.0; np],
            qp: BoxQp::new(np),
            secant: vec![0.0; np * np],
            prev_rows: vec![0.0; (steps + 1) * np],
            prev_theta: vec![0.0; np],
            has_prev: false,
            use_secant: false,
            model,
            cost,
            opts: options.clone(),
            steps,
            np,
            piece,
            free,
            theta_stage,
            chunks,
            threads,
            counts: (0, 0),
        })
    }

    /// Moves the solver to `problem`'s start (state, t₀, pending kick): the problem it was built
    /// for, from another state (a receding horizon re-plans with one solver).
    ///
    /// # Errors
    /// [`Error::InvalidArgument`] (`problem`) when the horizon, the step, the number of
    /// parameters or of pendulums differ from the solver's.
    pub fn restart<P: ControlMap, O: Objective>(
        &mut self,
        problem: &ControlProblem<P, O>,
    ) -> Result<()> {
        let (steps, h, np, n) = (self.steps, self.model.h, self.np, self.model.n);
        let other = (
            problem.steps(),
            problem.time_step(),
            problem.n_params(),
            problem.chain().n(),
        );
        if other != (steps, h, np, n) {
            return Err(Error::InvalidArgument {
                name: "problem",
                reason: format!(
                    "a restart needs the solver's horizon (N, h, parameters, pendulums) = \
                     {:?}, got {other:?}",
                    (steps, h, np, n)
                ),
            });
        }
        let start = problem.start();
        self.model.start = start.cloned();
        self.sim.stepper.set_start(start);
        for c in &mut self.chunks {
            c.stepper.set_start(start);
        }
        Ok(())
    }

    /// Changes the iteration limit [`OcpOptions::max_iters`] of later solves (at least 1).
    pub fn set_max_iters(&mut self, max_iters: usize) {
        self.opts.max_iters = max_iters.max(1);
    }

    /// θ of the nominal.
    pub fn theta(&self) -> Vec<f64> {
        self.theta_stage
            .iter()
            .map(|&k| self.nominal.u[k])
            .collect()
    }

    /// Simulates θ (projected onto the box) into `out` and returns J.
    fn simulate(&mut self, theta: &[f64], into_trial: bool) -> Result<f64> {
        let (lo, hi) = (self.opts.lower, self.opts.upper);
        let out = if into_trial {
            &mut self.trial
        } else {
            &mut self.nominal
        };
        for k in 0..=self.steps {
            out.u[k] = theta[self.piece[k]].clamp(lo, hi);
        }
        self.counts.0 += 1;
        let shooting = Shooting {
            model: &self.model,
            cost: &self.cost,
            free: &self.free,
            lower: lo,
            upper: hi,
        };
        self.sim.rollout(&shooting, None, out)?;
        Ok(out.cost)
    }

    /// Sets the nominal to θ (projected onto the box); returns J.
    ///
    /// # Errors
    /// [`Error::InvalidArgument`] (`theta`) for a wrong length or a non-finite entry; the
    /// simulation's errors.
    pub fn set_point(&mut self, theta: &[f64]) -> Result<f64> {
        check_theta(theta, self.np)?;
        self.simulate(theta, false)
    }

    /// The sensitivities S of every chunk at the nominal (in parallel over the chunks), then
    /// the Gauss-Newton Hessian and the exact gradient.
    fn linearise(&mut self) -> Result<()> {
        let (model, nominal) = (&self.model, &self.nominal);
        let (piece, stage) = (&self.piece[..], &self.theta_stage[..]);
        let work = |c: &mut SensChunk| c.sweep(model, nominal, piece, stage[c.first]);
        if self.threads > 1 {
            #[cfg(feature = "parallel")]
            self.chunks.par_iter_mut().try_for_each(work)?;
            #[cfg(not(feature = "parallel"))]
            self.chunks.iter_mut().try_for_each(work)?;
        } else {
            self.chunks.iter_mut().try_for_each(work)?;
        }
        self.counts.1 += 1;
        if self.has_prev {
            self.update_secant();
        }
        self.assemble();
        if self.use_secant {
            let np = self.np;
            for i in 0..np {
                for j in 0..=i {
                    self.hess[i * np + j] += self.secant[i * np + j];
                }
            }
        }
        self.snapshot();
        Ok(())
    }

    /// Keeps S and θ of this linearisation for the next secant update.
    fn snapshot(&mut self) {
        let np = self.np;
        for k in 0..=self.steps {
            sens_row(&self.chunks, k, &mut self.prev_rows[k * np..(k + 1) * np]);
        }
        self.prev_theta = self.theta();
        self.has_prev = true;
    }

    /// The structured secant update of A (Dennis, Gay, Welsch 1981, NL2SOL): with the step
    /// s = θ − θ_prev and y = 2 Σ_k c_k M₀_k (S_k − S_prev,k) (the change of the Jacobian applied
    /// to the new residuals), A is sized by min(1, |sᵀy|/|sᵀAs|) and updated by the symmetric
    /// Powell-Broyden formula so that A s = y.
    fn update_secant(&mut self) {
        let np = self.np;
        let theta = self.theta();
        let st: Vec<f64> = theta
            .iter()
            .zip(&self.prev_theta)
            .map(|(a, b)| a - b)
            .collect();
        let ss: f64 = st.iter().map(|x| x * x).sum();
        if ss == 0.0 {
            return;
        }
        let mut y = vec![0.0; np];
        let mut row = vec![0.0; np];
        for k in 0..=self.steps {
            let c = self.cost.weight(k);
            if c == 0.0 {
                continue;
            }
            sens_row(&self.chunks, k, &mut row);
            let r = self.nominal.moment[k];
            for j in 0..np {
                y[j] += 2.0 * c * r * (row[j] - self.prev_rows[k * np + j]);
            }
        }
        let a = &mut self.secant;
        let as_: Vec<f64> = (0..np)
            .map(|i| (0..np).map(|j| a[i * np + j] * st[j]).sum())
            .collect();
        let sas: f64 = st.iter().zip(&as_).map(|(x, y)| x * y).sum();
        let sy: f64 = st.iter().zip(&y).map(|(x, y)| x * y).sum();
        let tau = if sas != 0.0 {
            (sy.abs() / sas.abs()).min(1.0)
        } else {
            1.0
        };
        let w: Vec<f64> = (0..np).map(|i| y[i] - tau * as_[i]).collect();
        let ws: f64 = w.iter().zip(&st).map(|(x, y)| x * y).sum();
        for i in 0..np {
            for j in 0..=i {
                let v = tau * a[i * np + j] + (w[i] * st[j] + st[i] * w[j]) / ss
                    - ws * st[i] * st[j] / (ss * ss);
                a[i * np + j] = v;
                a[j * np + i] = v;
            }
        }
    }

    /// H and g of the module docs from the sensitivities (lower triangle of H).
    fn assemble(&mut self) {
        let np = self.np;
        self.hess.fill(0.0);
        self.grad.fill(0.0);
        let mut s = vec![0.0; np];
        for k in 0..=self.steps {
            let c = self.cost.weight(k);
            if c != 0.0 {
                sens_row(&self.chunks, k, &mut s);
                // Decisions after stage k do not act on M₀(t_k).
                let last = self.piece[k.saturating_sub(1)].min(np - 1) + 1;
                let r = self.nominal.moment[k];
                for i in 0..last {
                    self.grad[i] += 2.0 * c * r * s[i];
                    let row = &mut self.hess[i * np..i * np + i + 1];
                    let si = 2.0 * c * s[i];
                    for (h, sj) in row.iter_mut().zip(&s[..=i]) {
                        *h += si * sj;
                    }
                }
            }
            self.control_terms(k);
        }
    }

    /// The exact effort and rate terms of stage k in H and g.
    fn control_terms(&mut self, k: usize) {
        let np = self.np;
        let (p, u) = (self.piece[k], self.nominal.u[k]);
        self.grad[p] += 2.0 * self.cost.effort * u;
        self.hess[p * np + p] += 2.0 * self.cost.effort;
        self.rate_terms(k);
    }

    /// The rate penalty's terms of stage k in H and g.
    fn rate_terms(&mut self, k: usize) {
        let np = self.np;
        let (p, u) = (self.piece[k], self.nominal.u[k]);
        let r = self.cost.rate;
        if k > 0 && r > 0.0 && self.piece[k - 1] != p {
            let q = self.piece[k - 1];
            let du = u - self.nominal.u[k - 1];
            self.grad[p] += 2.0 * r * du;
            self.grad[q] -= 2.0 * r * du;
            self.hess[p * np + p] += 2.0 * r;
            self.hess[q * np + q] += 2.0 * r;
            // p = q + 1 > q: the lower triangle.
            self.hess[p * np + q] -= 2.0 * r;
        }
    }

    /// ‖θ − Π_box(θ − g)‖₂ at the nominal.
    fn projected_norm(&self) -> f64 {
        let (lo, hi) = (self.opts.lower, self.opts.upper);
        self.theta_stage
            .iter()
            .zip(&self.grad)
            .map(|(&k, g)| {
                let t = self.nominal.u[k];
                let d = super::boxqp::projected_component(t, *g, lo, hi);
                d * d
            })
            .sum::<f64>()
            .sqrt()
    }

    /// Runs the solver from θ₀ (projected onto the box): the iterations of the module docs.
    ///
    /// # Errors
    /// As [`Condensed::set_point`]; a failed simulation of the nominal.
    pub fn solve(&mut self, theta0: &[f64]) -> Result<OcpResult> {
        self.run(theta0)
    }

    fn run(&mut self, theta0: &[f64]) -> Result<OcpResult> {
        let t0 = Instant::now();
        self.counts = (0, 0);
        self.secant.fill(0.0);
        self.has_prev = false;
        self.use_secant = false;
        let mut pr = Progress::new(self.set_point(theta0)?);
        let termination = loop {
            if let Some(t) = self.iterate(&mut pr)? {
                break t;
            }
        };
        Ok(self.report(termination, pr, t0))
    }

    /// One iteration: linearisation, stopping tests, the QP step and its line search, the
    /// regularisation schedule. `Some` ends the run.
    fn iterate(&mut self, pr: &mut Progress) -> Result<Option<Termination>> {
        if pr.budget_spent(&self.opts) {
            return Ok(Some(Termination::Budget));
        }
        self.linearise()?;
        let pg = self.projected_norm();
        let (stop, _, _) = pr.stop_test(&self.opts, pg, &self.grad);
        if stop.is_some() {
            return Ok(stop);
        }
        let Some((acc, model)) = self.step(&mut pr.mu, pr.j0) else {
            return Ok(Some(Termination::RegularisationLimit));
        };
        self.choose_model(&acc, model);
        std::mem::swap(&mut self.nominal, &mut self.trial);
        pr.iterations += 1;
        pr.history.push(IterationRecord {
            objective: self.nominal.cost,
            projected_gradient_norm: pg,
            alpha: acc.alpha,
            regularisation: pr.mu,
        });
        if pr.roundoff.stalled(acc.roundoff, pg) {
            return Ok(Some(Termination::RoundOff));
        }
        pr.mu = next_mu(pr.mu, &acc);
        Ok(None)
    }

    /// The QP step and the line search, raising μ until a step is accepted (into `trial`), or
    /// `None` with μ beyond its limit.
    fn step(&mut self, mu: &mut f64, j0: f64) -> Option<(Accepted, ModelChange)> {
        let theta = self.theta();
        let (lo, hi) = (self.opts.lower, self.opts.upper);
        let np = self.np;
        let scale = (0..np).map(|i| self.hess[i * np + i]).sum::<f64>() / np as f64;
        let scale = if scale > 0.0 && scale.is_finite() {
            scale
        } else {
            1.0
        };
        loop {
            let qp = DenseQp {
                h: &self.hess,
                g: &self.grad,
                theta: &theta,
                lower: lo,
                upper: hi,
                lambda: *mu * scale,
            };
            if let Some(model) = self.qp.solve(&qp) {
                let search = LineSearch {
                    jbar: self.nominal.cost,
                    j0,
                    model,
                    armijo: self.opts.armijo,
                    tries: self.opts.backtracks,
                };
                let mut trial = theta.clone();
                let mut rollout = |alpha: f64| {
                    for ((t, th), d) in trial.iter_mut().zip(&theta).zip(&self.qp.delta) {
                        *t = th + alpha * d;
                    }
                    self.simulate(&trial, true).ok()
                };
                if let Some(acc) = backtrack(search, &mut rollout) {
                    return Some((acc, model));
                }
            }
            *mu = if *mu == 0.0 { MU_FIRST } else { raise_mu(*mu) };
            if *mu > self.opts.max_regularisation {
                return None;
            }
        }
    }

    /// NL2SOL's adaptive choice (Dennis, Gay, Welsch 1981): the next step's model adds the
    /// secant term A when, for the step just taken (`acc`, model change (d1, d2) of the model
    /// used), the model with A predicted the actual change of J better than the Gauss-Newton
    /// model without it.
    fn choose_model(&mut self, acc: &Accepted, model: ModelChange) {
        let (np, a) = (self.np, acc.alpha);
        let d = &self.qp.delta;
        let dad: f64 = (0..np)
            .map(|i| d[i] * (0..np).map(|j| self.secant[i * np + j] * d[j]).sum::<f64>())
            .sum();
        let qa = 0.5 * a * a * dad;
        let used = model.at(a);
        let gn = if self.use_secant { used - qa } else { used };
        let actual = self.trial.cost - self.nominal.cost;
        self.use_secant = (actual - (gn + qa)).abs() < (actual - gn).abs();
    }

    fn report(&self, termination: Termination, pr: Progress, t0: Instant) -> OcpResult {
        let theta = self.theta();
        let gn = self.grad.iter().map(|x| x * x).sum::<f64>().sqrt();
        let (lo, hi) = (self.opts.lower, self.opts.upper);
        OcpResult {
            objective: self.nominal.cost,
            initial_objective: pr.j0,
            controls: self.nominal.u.clone(),
            active_bounds: (0..self.np)
                .filter(|&i| theta[i] <= lo || theta[i] >= hi)
                .collect(),
            theta,
            gradient_norm: gn,
            projected_gradient_norm: pr.last_pg,
            initial_gradient_norm: pr.g0.unwrap_or(gn),
            iterations: pr.iterations,
            rollouts: self.counts.0,
            jacobian_passes: self.counts.1,
            backward_passes: 0,
            seconds: t0.elapsed().as_secs_f64(),
            converged: termination == Termination::Converged,
            termination,
            history: pr.history,
        }
    }

    /// The Gauss-Newton Hessian (full, symmetric) and the gradient at the nominal (for tests).
    ///
    /// # Errors
    /// A failed dual-number step.
    pub fn gauss_newton(&mut self) -> Result<(Mat<f64>, Vec<f64>)> {
        self.secant.fill(0.0);
        self.has_prev = false;
        self.linearise()?;
        let np = self.np;
        let h = Mat::from_fn(np, np, |i, j| self.hess[i.max(j) * np + i.min(j)]);
        Ok((h, self.grad.clone()))
    }
}

impl SensChunk {
    /// Rows S_k of this chunk's decisions: dual numbers seeded on u from the chunk's first
    /// stage s₀, real parts held at the nominal's and each step started at its converged
    /// multipliers (one derivative-only Newton update).
    fn sweep(&mut self, model: &StageModel, nom: &Traj, piece: &[usize], s0: usize) -> Result<()> {
        let n = model.n;
        let steps = self.rows.len() - 1;
        self.rows[..=s0].fill([0.0; CHUNK]);
        let st = &mut self.stepper.state;
        for (q, p) in st.q.iter_mut().zip(st.p.iter_mut()) {
            *q = [Dv::from_re(0.0); 2];
            *p = [Dv::from_re(0.0); 2];
        }
        for k in s0..steps {
            let st = &mut self.stepper.state;
            for (i, (q, p)) in st.q.iter_mut().zip(st.p.iter_mut()).enumerate() {
                for d in 0..2 {
                    q[d].re = nom.q(k)[i][d];
                    p[d].re = nom.p(k)[i][d];
                }
            }
            let m = st.multipliers_mut(n);
            for ((ml, mm), &v) in m.lambda.iter_mut().zip(m.mu.iter_mut()).zip(nom.lambda(k)) {
                (*ml, *mm) = (Dv::from_re(v), Dv::from_re(v));
            }
            st.tip_target = [Dv::from_re(0.0); 2];
            let mut seed = [0.0; CHUNK];
            let j = piece[k];
            if (self.first..self.first + self.len).contains(&j) {
                seed[j - self.first] = 1.0;
            }
            let u = Dv::new(nom.u[k], Derivative::some(SVector::from(seed)));
            self.stepper.advance(k, u)?;
            let z = &self.stepper.state.q[0][1];
            let row = &mut self.rows[k + 1];
            *row = [0.0; CHUNK];
            if let Some(e) = z.eps.0.as_ref() {
                for (r, v) in row.iter_mut().zip(e.iter()) {
                    *r = model.moment_scale * v;
                }
            }
        }
        Ok(())
    }
}

/// The solver's storage grows as N × (parameters): the sensitivities of every chunk, the
/// previous linearisation's (for the secant update) and the dense m × m matrices. Refused, before
/// anything of that size is allocated, beyond the library's memory budget
/// ([`MAX_TRAJECTORY_BYTES`](crate::scene::MAX_TRAJECTORY_BYTES)): such a problem (long per-step
/// horizons) is the Riccati solver's, whose storage is linear in N.
fn check_memory(steps: usize, np: usize) -> Result<()> {
    let (n1, m) = (steps as u128 + 1, np as u128);
    let chunks = m.div_ceil(CHUNK as u128);
    let bytes = 8 * (n1 * chunks * CHUNK as u128 + n1 * m + 2 * m * m);
    let budget = u128::from(crate::scene::MAX_TRAJECTORY_BYTES);
    if bytes > budget {
        return Err(Error::InvalidArgument {
            name: "method",
            reason: format!(
                "the condensed solver would store {} for N = {steps} steps and {np} parameters \
                 (over the memory limit of {}); use the Riccati solver for long per-step horizons",
                crate::scene::human_bytes(u64::try_from(bytes).unwrap_or(u64::MAX)),
                crate::scene::human_bytes(crate::scene::MAX_TRAJECTORY_BYTES)
            ),
        });
    }
    Ok(())
}

/// S_k, the sensitivities of M₀(t_k) to θ, gathered from the chunks into `out`.
fn sens_row(chunks: &[SensChunk], k: usize, out: &mut [f64]) {
    for ch in chunks {
        out[ch.first..ch.first + ch.len].copy_from_slice(&ch.rows[k][..ch.len]);
    }
}

/// The chunks ordered longest, shortest, second longest, second shortest, …: the chunk of
/// θ_first runs from θ_first's stage to N, so the recursive halving of rayon's parallel
/// iterator hands each thread about the same number of steps.
fn balanced(mut chunks: Vec<SensChunk>) -> Vec<SensChunk> {
    let mut out = Vec::with_capacity(chunks.len());
    let mut front = true;
    while !chunks.is_empty() {
        out.push(if front {
            chunks.remove(0)
        } else {
            chunks.pop().expect("not empty")
        });
        front = !front;
    }
    out
}

/// A dense convex box QP min ½ δᵀ(H + λI)δ + gᵀδ, lo ≤ δ ≤ hi (lo ≤ 0 ≤ hi), by a primal
/// active-set method from δ = 0 (Nocedal & Wright, *Numerical Optimization*, Alg. 16.3):
/// Newton steps on the free set (Cholesky of its block), a ratio test that fixes the first
/// blocking bound, and the release of the bound whose multiplier has the wrong sign.
/// A decision without effect (a zero row of H and a zero gradient: u_N of a per-step control
/// without effort penalty acts on nothing J sees) stays where it is, as the Riccati solver's
/// inert controls ([`super::boxqp`]).
const INERT: i8 = 2;

/// The data of one dense box QP: H (lower triangle, row-major), g, the shift λ, and the box
/// lower ≤ θ + δ ≤ upper about the point θ.
#[derive(Clone, Copy, Debug)]
struct DenseQp<'a> {
    h: &'a [f64],
    g: &'a [f64],
    theta: &'a [f64],
    lower: f64,
    upper: f64,
    lambda: f64,
}

#[derive(Clone, Debug)]
struct BoxQp {
    delta: Vec<f64>,
    /// 0 free, −1 at its lower bound, +1 at its upper bound, [`INERT`].
    fixed: Vec<i8>,
    free: Vec<usize>,
    resid: Vec<f64>,
}

impl BoxQp {
    fn new(np: usize) -> Self {
        BoxQp {
            delta: vec![0.0; np],
            fixed: vec![0; np],
            free: Vec::with_capacity(np),
            resid: vec![0.0; np],
        }
    }

    /// (H + λI)δ + g into `resid` (H: lower triangle, row-major).
    fn residual(&mut self, h: &[f64], g: &[f64], lambda: f64) {
        let np = g.len();
        for i in 0..np {
            let mut r = g[i] + lambda * self.delta[i];
            for j in 0..np {
                r += h[i.max(j) * np + i.min(j)] * self.delta[j];
            }
            self.resid[i] = r;
        }
    }

    /// Solves the QP with the box lo − θ ≤ δ ≤ hi − θ; returns the model change (gᵀδ, ½δᵀHδ)
    /// without λ, or `None` when H + λI is not positive definite on a free set.
    fn solve(&mut self, qp: &DenseQp<'_>) -> Option<ModelChange> {
        let DenseQp {
            h,
            g,
            theta,
            lower: lo,
            upper: hi,
            lambda,
        } = *qp;
        let np = g.len();
        let bounds = |i: usize| (lo - theta[i], hi - theta[i]);
        self.delta.fill(0.0);
        for i in 0..np {
            let inert = g[i] == 0.0 && (0..np).all(|j| h[i.max(j) * np + i.min(j)] == 0.0);
            let (l, u) = bounds(i);
            self.fixed[i] = if inert {
                INERT
            } else if l >= 0.0 && g[i] > 0.0 {
                -1
            } else if u <= 0.0 && g[i] < 0.0 {
                1
            } else {
                0
            };
        }
        for _ in 0..10 * np + 10 {
            let p = self.free_newton_step(h, g, lambda)?;
            // The first bound the full step crosses, if any, joins the working set.
            let (alpha, block) = self.ratio_test(&p, bounds);
            for (a, &i) in self.free.iter().enumerate() {
                self.delta[i] += alpha * p[(a, 0)];
            }
            if let Some((i, side, to)) = block {
                self.delta[i] = to;
                self.fixed[i] = side;
                continue;
            }
            // A minimiser on the working set: release the worst wrong-signed multiplier.
            self.residual(h, g, lambda);
            let worst = (0..np)
                .filter(|&i| self.fixed[i] == -1 || self.fixed[i] == 1)
                .map(|i| (i, -f64::from(self.fixed[i]) * self.resid[i]))
                .filter(|&(_, m)| m < 0.0)
                .min_by(|a, b| a.1.total_cmp(&b.1));
            match worst {
                Some((i, _)) => self.fixed[i] = 0,
                None => return Some(self.model_change(h, g)),
            }
        }
        None
    }

    /// The Newton step p on the free set (the others held): (H + λI)_FF p = −((H + λI)δ + g)_F,
    /// by faer's Cholesky; `None` when the free block is not positive definite.
    fn free_newton_step(&mut self, h: &[f64], g: &[f64], lambda: f64) -> Option<Mat<f64>> {
        let np = g.len();
        self.free.clear();
        self.free.extend((0..np).filter(|&i| self.fixed[i] == 0));
        self.residual(h, g, lambda);
        let nf = self.free.len();
        if nf == 0 {
            return Some(Mat::zeros(0, 1));
        }
        let hf = Mat::from_fn(nf, nf, |a, b| {
            let (i, j) = (self.free[a], self.free[b]);
            h[i.max(j) * np + i.min(j)] + if a == b { lambda } else { 0.0 }
        });
        let rhs = Mat::from_fn(nf, 1, |a, _| -self.resid[self.free[a]]);
        let llt = hf.llt(faer::Side::Lower).ok()?;
        Some(faer::linalg::solvers::Solve::solve(&llt, &rhs))
    }

    /// The largest α ≤ 1 that keeps δ + α p in the box (bounds of decision i: `bounds(i)`), and
    /// the bound that stops it (decision, side, value).
    fn ratio_test(
        &self,
        p: &Mat<f64>,
        bounds: impl Fn(usize) -> (f64, f64),
    ) -> (f64, Option<(usize, i8, f64)>) {
        let (mut alpha, mut block) = (1.0, None);
        for (a, &i) in self.free.iter().enumerate() {
            let (d, pi) = (self.delta[i], p[(a, 0)]);
            let (l, u) = bounds(i);
            let (to, side) = if pi < 0.0 { (l, -1) } else { (u, 1) };
            let crosses = (pi < 0.0 && d + pi < to) || (pi > 0.0 && d + pi > to);
            if crosses {
                let a_i = ((to - d) / pi).max(0.0);
                if a_i < alpha {
                    alpha = a_i;
                    block = Some((i, side, to));
                }
            }
        }
        (alpha, block)
    }

    /// (gᵀδ, ½δᵀHδ).
    fn model_change(&self, h: &[f64], g: &[f64]) -> ModelChange {
        let np = g.len();
        let mut quad = 0.0;
        for i in 0..np {
            for j in 0..np {
                quad += self.delta[i] * h[i.max(j) * np + i.min(j)] * self.delta[j];
            }
        }
        let lin = g.iter().zip(&self.delta).map(|(a, b)| a * b).sum();
        ModelChange {
            d1: lin,
            d2: 0.5 * quad,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{catalogue, BendingObjective, Parametrisation, PerStepControl};

    /// The structured secant update satisfies the secant equation A s = y (s = θ₂ − θ₁,
    /// y = 2 Σ c_k M₀_k(θ₂)(S_k(θ₂) − S_k(θ₁)), recomputed here from the two linearisations) to
    /// round-off, and keeps A symmetric (Powell-symmetric-Broyden, Dennis & Moré 1977).
    #[test]
    fn secant_update_satisfies_the_secant_equation() {
        let p = ControlProblem::new(
            &catalogue::riser(3),
            Parametrisation::PerStep(PerStepControl { steps: 10 }),
            BendingObjective::summed_moment(),
        )
        .unwrap();
        let mut c = Condensed::new(&p, &OcpOptions::default()).unwrap();
        let t1: Vec<f64> = (0..11).map(|k| (0.7 * k as f64).sin()).collect();
        let t2: Vec<f64> = t1.iter().map(|x| 1.3 * x + 0.2).collect();
        c.set_point(&t1).unwrap();
        c.linearise().unwrap();
        let s1 = c.prev_rows.clone();
        c.set_point(&t2).unwrap();
        c.linearise().unwrap();
        let s2 = &c.prev_rows;
        let np = 11;
        let mut y = vec![0.0; np];
        for k in 0..=10 {
            let m = c.nominal.moment[k];
            for j in 0..np {
                y[j] += 2.0 * m * (s2[k * np + j] - s1[k * np + j]);
            }
        }
        let s: Vec<f64> = t2.iter().zip(&t1).map(|(a, b)| a - b).collect();
        let ymax = y.iter().fold(0.0f64, |m, x| m.max(x.abs()));
        assert!(ymax > 0.0);
        for i in 0..np {
            let as_i: f64 = (0..np).map(|j| c.secant[i * np + j] * s[j]).sum();
            assert!(
                (as_i - y[i]).abs() <= 1e-12 * ymax,
                "row {i}: {as_i} vs {}",
                y[i]
            );
            for j in 0..np {
                assert_eq!(
                    c.secant[i * np + j].to_bits(),
                    c.secant[j * np + i].to_bits()
                );
            }
        }
    }
}
