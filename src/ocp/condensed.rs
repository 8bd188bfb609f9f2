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
//! With S_kj = ∂M₀(t_k)/∂θ_j at the nominal, u_k = θ_{piece(k)} and the objective's
//! Gauss-Newton form ℓ_k = ½ w_k r_k(M₀)² + e_k u_k² (`ocp/cost.rs`; c_sum: w_k = 2,
//! r_k = M₀, e_k = ρh), whose residual moves by ∇r_k = r_k′ S_k,
//! ```text
//! J(θ + δ) ≈ Σ_k ½ w_k (r_k + r_k′ S_k δ)² + Σ_k e_k (u_k + δ_{piece(k)})² + (σ/h) Σ_{k≥1} (Δu_k + Δδ_k)²
//! g = Σ_k w_k r_k r_k′ S_kᵀ + (effort and rate terms, exact),   H = Σ_k w_k r_k′² S_kᵀ S_k + (…)
//! ```
//! the same Gauss-Newton model as the Riccati solver's (the dense Hessian of
//! [`super::Solver::dense_gauss_newton`]), so g is the exact gradient (tested against the adjoint
//! to 10⁻¹²) and the step the same Gauss-Newton step (tested against the Riccati step to
//! 10⁻¹⁰). The dual steps start at the nominal's converged multipliers: the Newton iteration
//! does one derivative-only update, the implicit function theorem (as for the stage
//! Jacobians, [`super::stage`]).
//!
//! # Curvature
//! Gauss-Newton converges linearly when the residuals r_k stay large at the optimum (no effort
//! penalty, Table 3.4): its model lacks Σ_k w_k r_k ∇²r_k (c_sum: 2 Σ_k M₀_k ∇²M₀_k). The dense problem is small enough
//! to carry NL2SOL's structured secant approximation A of that term (Dennis, Gay, Welsch,
//! *An adaptive nonlinear least-squares algorithm*, ACM TOMS 1981): after each step
//! s = θ₊ − θ, with y = Σ_k w_k r_k(θ₊) (∇r_k(θ₊) − ∇r_k(θ)), A is sized by
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
//! # The spatial model
//! `Condensed<3>` (module docs of [`crate::ocp`], "The spatial model"): the sensitivities S_{k,c}
//! of both moment components c = z, x to θ = (θ_x; θ_z) by the same dual steps (a 2-axis
//! decision seeds u_x through the stage map's x schedule), ∇R_{k,c} = Σ_d ∂R_c/∂M₀_d S_{k,d},
//! g = Σ_k w_k Σ_c R_{k,c}∇R_{k,c} + (…), H = Σ_k w_k Σ_c ∇R_{k,c}∇R_{k,c}ᵀ + (…), and the secant
//! term's y from the same gradients. Tested against the adjoint (gradient and J to 10⁻¹²) and,
//! on a planar scene turned about the beam's axis, against the planar optimum (J to 10⁻⁹,
//! turned controls), in tests/ocp/ocp_spatial.rs.
//!
//! # Globalisation and convergence
//! As the Riccati solver: a Levenberg weight μ·mean(diag H) on the QP, an open-loop line search
//! on rollouts of θ + αδ (α = 1 first, then the quadratic interpolation in [α/10, α/2],
//! accepted when J̄ − J(α) ≥ c·(−ΔJ(α))), and the projected gradient for convergence
//! ([`OcpOptions`] tolerances, [`OcpTermination`]).

use std::time::Instant;

use faer::Mat;
#[cfg(feature = "parallel")]
use rayon::prelude::*;

use super::dense_qp::{BoxQp, DenseQp};
use super::globalise::{
    backtrack, raise_mu, Accepted, LineSearch, ModelChange, Outer, Progress, Step,
};
use super::horizon::{available_threads, ControlHorizon};
use super::line_search::Traj;
use super::options::{IterationObserver, OcpOptions, OcpResult, OcpTermination};
use super::sensitivities::{balanced, residual_gradients, sens_row, SensChunk};
use super::stage::{Stepper, CHUNK};
use crate::adjoint::{ControlMap, ControlProblem, Objective};
use crate::error::{HorizonShape, OcpError, Result};

/// Gauss-Newton on the condensed problem (module docs), with its buffers.
#[derive(Clone, Debug)]
pub struct Condensed<const DIM: usize = 2> {
    /// The problem, its structure and trajectories.
    horizon: ControlHorizon<DIM>,
    /// N and the number of decisions.
    steps: usize,
    np: usize,
    chunks: Vec<SensChunk<DIM>>,
    threads: usize,
    /// H (np × np, row-major, lower triangle filled) and g at the nominal.
    hess: Vec<f64>,
    grad: Vec<f64>,
    /// The QP's step δ and its working set.
    qp: BoxQp,
    /// The structured secant approximation A ≈ Σ_k w_k r_k ∇²r_k (np × np, full) and the
    /// residuals' gradients ∇r_k (DIM − 1 components each) and θ of the previous linearisation
    /// (module docs, "Curvature").
    secant: Vec<f64>,
    prev_rows: Vec<f64>,
    prev_theta: Vec<f64>,
    has_prev: bool,
    /// Whether the model of the next step adds A (chosen after each step by which model
    /// predicted its decrease better).
    use_secant: bool,
    /// Linearisations run (sensitivity passes).
    linearisations: usize,
}

/// The first nonzero relative Levenberg weight after a failed step with μ = 0. The dense
/// Gauss-Newton Hessian is often singular to round-off (controls with little effect, no effort
/// penalty): a shift at that level makes the QP convex without limiting the step. (From 10⁻⁶,
/// the Riccati solver's smallest weight, the steps along a flat valley stayed short: Table 3.4
/// row 9 took 46 iterations, with 10⁻¹² it takes 2.)
const MU_FIRST: f64 = 1e-12;

impl<const DIM: usize> Condensed<DIM> {
    /// Builds the solver for `problem` (as [`super::Solver::new`]: a planar problem with a
    /// free tip, a bending-moment objective and per-step or piecewise-constant controls).
    ///
    /// # Errors
    /// [`OcpError`] naming the option, the objective, the control map or
    /// the tip; [`OcpError::CondensedTooLarge`] over the memory budget.
    pub fn new<P: ControlMap, O: Objective>(
        problem: &ControlProblem<P, O, DIM>,
        options: &OcpOptions,
    ) -> Result<Self> {
        let solver = "the condensed Gauss-Newton solver";
        let horizon = ControlHorizon::new(problem, options, solver, check_memory)?;
        let (model, steps, np) = (&horizon.model, horizon.steps, horizon.n_params);
        let m = horizon.pieces();
        let chunks = (0..np)
            .step_by(CHUNK)
            .map(|first| {
                let len = CHUNK.min(np - first);
                Ok(SensChunk {
                    first,
                    len,
                    start: (first..first + len)
                        .map(|j| horizon.theta_stage[j % m])
                        .min()
                        .unwrap_or(0),
                    stepper: Stepper::new(model)?,
                    rows: vec![[0.0; CHUNK]; (steps + 1) * (DIM - 1)],
                })
            })
            .collect::<Result<Vec<_>>>()?;
        let chunks = balanced(chunks);
        let threads = if options.threads == 0 {
            available_threads()
        } else {
            options.threads
        };
        Ok(Condensed {
            hess: vec![0.0; np * np],
            grad: vec![0.0; np],
            qp: BoxQp::new(np),
            secant: vec![0.0; np * np],
            prev_rows: vec![0.0; (steps + 1) * (DIM - 1) * np],
            prev_theta: vec![0.0; np],
            has_prev: false,
            use_secant: false,
            horizon,
            steps,
            np,
            chunks,
            threads,
            linearisations: 0,
        })
    }

    /// Moves the solver to `problem`'s start (state, t₀, pending kick): the problem it was built
    /// for, from another state (a receding horizon re-plans with one solver).
    ///
    /// # Errors
    /// [`OcpError::RestartMismatch`] when the horizon, the step, the number of parameters or of
    /// pendulums differ from the solver's.
    pub fn restart<P: ControlMap, O: Objective>(
        &mut self,
        problem: &ControlProblem<P, O, DIM>,
    ) -> Result<()> {
        let model = &self.horizon.model;
        let expected = HorizonShape {
            steps: self.steps,
            h: model.h,
            params: self.np,
            pendulums: model.n,
        };
        let got = HorizonShape {
            steps: problem.steps(),
            h: problem.time_step(),
            params: problem.n_params(),
            pendulums: problem.chain().n(),
        };
        if got != expected {
            return Err(OcpError::RestartMismatch { expected, got }.into());
        }
        let start = problem.start();
        self.horizon.set_start(start);
        for c in &mut self.chunks {
            c.stepper.set_start(start);
        }
        Ok(())
    }

    /// Changes the iteration limit [`OcpOptions::max_iters`] of later solves (at least 1).
    pub fn set_max_iters(&mut self, max_iters: usize) {
        self.horizon.opts.max_iters = max_iters.max(1);
    }

    /// θ of the nominal.
    pub fn theta(&self) -> Vec<f64> {
        self.horizon.theta()
    }

    /// Sets the nominal to θ (projected onto the box); returns J.
    ///
    /// # Errors
    /// [`Error::WrongLength`](crate::Error::WrongLength) or
    /// [`Error::NotFinite`](crate::Error::NotFinite) (`theta`) for a wrong length or a
    /// non-finite entry; the simulation's errors.
    pub fn set_point(&mut self, theta: &[f64]) -> Result<f64> {
        self.horizon.set_point(theta)
    }

    /// The sensitivities S of every chunk at the nominal (in parallel over the chunks), then
    /// the Gauss-Newton Hessian and the exact gradient.
    fn linearise(&mut self) -> Result<()> {
        let hz = &self.horizon;
        let work = |c: &mut SensChunk<DIM>| c.sweep(hz);
        if self.threads > 1 {
            #[cfg(feature = "parallel")]
            self.chunks.par_iter_mut().try_for_each(work)?;
            #[cfg(not(feature = "parallel"))]
            self.chunks.iter_mut().try_for_each(work)?;
        } else {
            self.chunks.iter_mut().try_for_each(work)?;
        }
        self.linearisations += 1;
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

    /// Keeps ∇r_k = r_k′ S_k and θ of this linearisation for the next secant update.
    fn snapshot(&mut self) {
        let np = self.np;
        if DIM == 3 {
            for k in 0..=self.steps {
                let rows = &mut self.prev_rows[2 * k * np..2 * (k + 1) * np];
                let (g0, g1) = rows.split_at_mut(np);
                residual_gradients(
                    &self.chunks,
                    &self.horizon.nominal.residual_vec[k],
                    k,
                    [g0, g1],
                );
            }
            self.prev_theta = self.theta();
            self.has_prev = true;
            return;
        }
        for k in 0..=self.steps {
            let row = &mut self.prev_rows[k * np..(k + 1) * np];
            sens_row(&self.chunks, k, 0, row);
            let dr = self.horizon.nominal.dresidual_dm[k];
            row.iter_mut().for_each(|x| *x *= dr);
        }
        self.prev_theta = self.theta();
        self.has_prev = true;
    }

    /// The structured secant update of A (Dennis, Gay, Welsch 1981, NL2SOL): with the step
    /// s = θ − θ_prev and y = Σ_k w_k r_k (∇r_k − ∇r_prev,k) (the change of the Jacobian applied
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
        if DIM == 3 {
            self.secant_change_spatial(&mut y);
        }
        for k in 0..=self.steps {
            let w = self.horizon.cost.weight(k);
            if w == 0.0 || DIM == 3 {
                continue;
            }
            sens_row(&self.chunks, k, 0, &mut row);
            let nom = &self.horizon.nominal;
            let (r, dr) = (nom.residual[k], nom.dresidual_dm[k]);
            for j in 0..np {
                y[j] += w * r * (dr * row[j] - self.prev_rows[k * np + j]);
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

    /// The spatial y = Σ_k w_k Σ_c R_{k,c} (∇R_{k,c} − ∇R_{k,c}^prev) of the secant update.
    fn secant_change_spatial(&self, y: &mut [f64]) {
        let np = self.np;
        let (mut g0, mut g1) = (vec![0.0; np], vec![0.0; np]);
        for k in 0..=self.steps {
            let w = self.horizon.cost.weight(k);
            if w == 0.0 {
                continue;
            }
            let rv = &self.horizon.nominal.residual_vec[k];
            residual_gradients(&self.chunks, rv, k, [&mut g0, &mut g1]);
            let prev = &self.prev_rows[2 * k * np..2 * (k + 1) * np];
            for j in 0..np {
                y[j] += w * (rv.r[0] * (g0[j] - prev[j]) + rv.r[1] * (g1[j] - prev[np + j]));
            }
        }
    }

    /// H and g of the spatial model: ∇R_{k,c} = Σ_d (∂R_c/∂M₀_d) S_{k,d} for the vector
    /// residual R_k ([`StageCost::residual_vector`](super::cost::StageCost::residual_vector)),
    /// g = Σ_k w_k Σ_c R_{k,c} ∇R_{k,c} + (effort, rate), H = Σ_k w_k Σ_c ∇R_{k,c}∇R_{k,c}ᵀ + (…)
    /// (lower triangle).
    fn assemble_spatial(&mut self) {
        let np = self.np;
        self.hess.fill(0.0);
        self.grad.fill(0.0);
        let (mut g0, mut g1) = (vec![0.0; np], vec![0.0; np]);
        for k in 0..=self.steps {
            let w = self.horizon.cost.weight(k);
            if w != 0.0 {
                let rv = self.horizon.nominal.residual_vec[k];
                residual_gradients(&self.chunks, &rv, k, [&mut g0, &mut g1]);
                for i in 0..np {
                    self.grad[i] += w * (rv.r[0] * g0[i] + rv.r[1] * g1[i]);
                    let row = &mut self.hess[i * np..i * np + i + 1];
                    let (a, b) = (w * g0[i], w * g1[i]);
                    for (h, (x, y)) in row.iter_mut().zip(g0.iter().zip(&g1)) {
                        *h += a * x + b * y;
                    }
                }
            }
            self.control_terms(k);
        }
    }

    /// H and g of the module docs from the sensitivities (lower triangle of H).
    fn assemble(&mut self) {
        if DIM == 3 {
            self.assemble_spatial();
            return;
        }
        let np = self.np;
        self.hess.fill(0.0);
        self.grad.fill(0.0);
        let mut s = vec![0.0; np];
        for k in 0..=self.steps {
            let w = self.horizon.cost.weight(k);
            if w != 0.0 {
                sens_row(&self.chunks, k, 0, &mut s);
                // Decisions after stage k do not act on M₀(t_k).
                let last = self.horizon.piece[k.saturating_sub(1)].min(np - 1) + 1;
                let nom = &self.horizon.nominal;
                let (r, dr) = (nom.residual[k], nom.dresidual_dm[k]);
                // ∇r_k = r′ S_k: g += w r r′ S_k, H += w r′² S_kᵀS_k (c_sum: 2M₀ and 2).
                let (gk, hk) = (w * r * dr, w * dr * dr);
                for i in 0..last {
                    self.grad[i] += gk * s[i];
                    let row = &mut self.hess[i * np..i * np + i + 1];
                    let si = hk * s[i];
                    for (h, sj) in row.iter_mut().zip(&s[..=i]) {
                        *h += si * sj;
                    }
                }
            }
            self.control_terms(k);
        }
    }

    /// The exact effort and rate terms of stage k in H and g (each axis).
    fn control_terms(&mut self, k: usize) {
        for axis in 0..self.horizon.axes {
            let np = self.np;
            let hz = &self.horizon;
            let (p, u) = (hz.theta_index(k, axis), control(&hz.nominal, axis, k));
            self.grad[p] += 2.0 * hz.cost.effort(k) * u;
            self.hess[p * np + p] += 2.0 * hz.cost.effort(k);
            self.rate_terms(k, axis);
        }
    }

    /// The rate penalty's terms of stage k in H and g (one axis).
    fn rate_terms(&mut self, k: usize, axis: usize) {
        let np = self.np;
        let hz = &self.horizon;
        let (p, u) = (hz.theta_index(k, axis), control(&hz.nominal, axis, k));
        let r = hz.cost.rate;
        if k > 0 && r > 0.0 && hz.piece[k - 1] != hz.piece[k] {
            let q = hz.theta_index(k - 1, axis);
            let du = u - control(&hz.nominal, axis, k - 1);
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
        let hz = &self.horizon;
        let (lo, hi) = (hz.opts.lower, hz.opts.upper);
        self.grad
            .iter()
            .enumerate()
            .map(|(i, g)| {
                let t = hz.theta_at(i);
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
        super::globalise::run(self, theta0, None)
    }

    /// [`Condensed::solve`] with an observer called after every accepted iteration (θ, J and
    /// the record of the step); it may stop the run ([`OcpTermination::Stopped`]).
    pub fn solve_observed(
        &mut self,
        theta0: &[f64],
        observer: IterationObserver<'_>,
    ) -> Result<OcpResult> {
        super::globalise::run(self, theta0, Some(observer))
    }

    /// The QP step and the line search, raising μ until a step is accepted (into `trial`), or
    /// `None` with μ beyond its limit.
    fn search(&mut self, mu: &mut f64, j0: f64) -> Option<(Accepted, ModelChange)> {
        let theta = self.theta();
        let (lo, hi) = (self.horizon.opts.lower, self.horizon.opts.upper);
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
                let hz = &mut self.horizon;
                let search = LineSearch {
                    jbar: hz.nominal.cost,
                    j0,
                    model,
                    armijo: hz.opts.armijo,
                    tries: hz.opts.backtracks,
                };
                let mut trial = theta.clone();
                let mut rollout = |alpha: f64| {
                    for ((t, th), d) in trial.iter_mut().zip(&theta).zip(&self.qp.delta) {
                        *t = th + alpha * d;
                    }
                    hz.simulate(&trial, true).ok()
                };
                if let Some(acc) = backtrack(search, &mut rollout) {
                    return Some((acc, model));
                }
            }
            *mu = if *mu == 0.0 { MU_FIRST } else { raise_mu(*mu) };
            if *mu > self.horizon.opts.max_regularisation {
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
        let actual = self.horizon.trial.cost - self.horizon.nominal.cost;
        self.use_secant = (actual - (gn + qa)).abs() < (actual - gn).abs();
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

impl<const DIM: usize> Outer for Condensed<DIM> {
    fn begin(&mut self) {
        self.horizon.rollouts = 0;
        self.linearisations = 0;
        self.secant.fill(0.0);
        self.has_prev = false;
        self.use_secant = false;
    }

    fn options(&self) -> &OcpOptions {
        &self.horizon.opts
    }

    fn nominal_cost(&self) -> f64 {
        self.horizon.nominal.cost
    }

    fn theta(&self) -> Vec<f64> {
        Condensed::theta(self)
    }

    fn set_point(&mut self, theta: &[f64]) -> Result<f64> {
        Condensed::set_point(self, theta)
    }

    /// The sensitivities, H and the exact gradient at the nominal.
    fn linearise(&mut self) -> Result<f64> {
        Condensed::linearise(self)?;
        Ok(self.projected_norm())
    }

    fn gradient(&self) -> &[f64] {
        &self.grad
    }

    /// The QP step and its open-loop line search (raising μ until one is accepted), and the
    /// model of the next step chosen on this one.
    fn step(&mut self, pr: &mut Progress, _pg: f64, _gref: f64) -> Result<Step> {
        Ok(match self.search(&mut pr.mu, pr.j0) {
            Some((acc, model)) => {
                self.choose_model(&acc, model);
                Step::Accepted(acc)
            }
            None => Step::NoModel,
        })
    }

    fn take_step(&mut self) {
        self.horizon.take_trial();
    }

    fn stalled(&mut self, _target: f64) -> Result<OcpTermination> {
        Ok(OcpTermination::RoundOff)
    }

    fn report(&mut self, termination: OcpTermination, pr: Progress, t0: Instant) -> OcpResult {
        let theta = self.theta();
        let gn = self.grad.iter().map(|x| x * x).sum::<f64>().sqrt();
        let hz = &self.horizon;
        let (lo, hi) = (hz.opts.lower, hz.opts.upper);
        OcpResult {
            objective: hz.nominal.cost,
            initial_objective: pr.j0,
            controls: hz.nominal.u.clone(),
            controls_x: hz.nominal.ux.clone(),
            active_bounds: (0..self.np)
                .filter(|&i| theta[i] <= lo || theta[i] >= hi)
                .collect(),
            theta,
            gradient_norm: gn,
            projected_gradient_norm: pr.last_pg,
            initial_gradient_norm: pr.g0.unwrap_or(gn),
            iterations: pr.iterations,
            rollouts: hz.rollouts,
            jacobian_passes: self.linearisations,
            backward_passes: 0,
            seconds: t0.elapsed().as_secs_f64(),
            converged: termination == OcpTermination::Converged,
            termination,
            history: pr.history,
        }
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
        return Err(OcpError::CondensedTooLarge {
            steps,
            params: np,
            bytes: u64::try_from(bytes).unwrap_or(u64::MAX),
        }
        .into());
    }
    Ok(())
}

/// u_k along `axis` (0: z, 1: x).
#[inline]
fn control<const DIM: usize>(t: &Traj<DIM>, axis: usize, k: usize) -> f64 {
    if axis == 0 {
        t.u[k]
    } else {
        t.ux[k]
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
        let p = ControlProblem::builder(&catalogue::riser(3))
            .map(Parametrisation::PerStep(PerStepControl { steps: 10 }))
            .objective(BendingObjective::summed_moment())
            .build_in::<2>()
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
            let m = c.horizon.nominal.moment[k];
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
