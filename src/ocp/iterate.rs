//! The QP iterate: the model point δ = (δv per stage, δz per stage) of the Gauss-Newton QP's
//! iterations and its trial, the linearised rollouts that move it (module docs, "The step"), the
//! ε-active set and the feedforward the closed-loop rollouts replay.

use super::horizon::ControlHorizon;
use super::jacobians::{JacobianStore, PREFETCH_AHEAD};
use super::riccati::{dot, StageJacobians};
use super::second_order::SecondOrder;

/// How [`QpIterate::linearised`] moves the controls.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Arc {
    /// Closed loop with the Riccati gains, clamped to the box.
    ClosedLoop,
    /// Closed loop, unclamped, recording the direction Δv in `dir`.
    Direction,
    /// Open loop to the clamped controls u + α dir.
    Projected,
}

/// The linear model a linearised rollout runs on: the nominal and its structure, the stored
/// Jacobians of every stage, the Riccati gains and feedforward of the last pass, and the
/// second-order terms when the exact model is in use.
pub(crate) struct LinearModel<'a> {
    pub horizon: &'a ControlHorizon,
    pub store: &'a JacobianStore,
    /// K_k (n_z per stage).
    pub gain: &'a [f64],
    /// k_k of the last pass.
    pub ff: &'a [f64],
    /// H_k and the cost's curvature (exact model), read for the value.
    pub second: Option<SecondOrder<'a>>,
}

/// The model point of the QP iterations and its buffers (sized once per problem).
#[derive(Clone, Debug)]
pub(crate) struct QpIterate {
    nz: usize,
    /// δv_k and δz_k (n_z per stage) of the current point.
    pub dv: Vec<f64>,
    pub dz: Vec<f64>,
    /// The point a linearised rollout reached.
    pub dv_t: Vec<f64>,
    pub dz_t: Vec<f64>,
    lin_dz: Vec<f64>,
    lin_next: Vec<f64>,
    /// The direction Δv (interior point) or the open-loop step of a projected rollout.
    pub dir: Vec<f64>,
    /// The ε-active set of the current iteration: stage k's control moves to its bound
    /// (step `fixed[k]`) without feedback.
    pub active: Vec<bool>,
    pub fixed: Vec<f64>,
    /// Feedforward of the closed-loop rollout about the nominal.
    pub ff: Vec<f64>,
}

impl QpIterate {
    /// The point δ = 0 of a horizon of `steps` stages with `nz` state coordinates.
    pub fn new(steps: usize, nz: usize) -> Self {
        QpIterate {
            nz,
            dv: vec![0.0; steps + 1],
            dz: vec![0.0; (steps + 1) * nz],
            dv_t: vec![0.0; steps + 1],
            dz_t: vec![0.0; (steps + 1) * nz],
            lin_dz: vec![0.0; nz],
            lin_next: vec![0.0; nz],
            dir: vec![0.0; steps + 1],
            active: vec![false; steps + 1],
            fixed: vec![0.0; steps + 1],
            ff: vec![0.0; steps + 1],
        }
    }

    /// δ = 0: the nominal.
    pub fn at_nominal(&mut self) {
        self.dv.fill(0.0);
        self.dz.fill(0.0);
    }

    /// The rollout's point becomes the current one.
    pub fn take_trial(&mut self) {
        std::mem::swap(&mut self.dv, &mut self.dv_t);
        std::mem::swap(&mut self.dz, &mut self.dz_t);
    }

    /// The feedforward of the closed-loop rollouts: k_k = δv_k − K_k δz_k, so that
    /// u_k = ū_k + α k_k + K_k δz_k reproduces the QP's step at α = 1.
    pub fn store_feedforward(&mut self, gain: &[f64]) {
        let nz = self.nz;
        for k in 0..self.ff.len() {
            let g = &gain[k * nz..(k + 1) * nz];
            self.ff[k] = self.dv[k] - dot(g, &self.dz[k * nz..(k + 1) * nz]);
        }
    }

    /// Bertsekas's ε-active set at the model point from the gradient `grad` of the last
    /// costate sweep: a control within ε of a bound whose gradient pushes it outward moves to
    /// that bound and is fixed there (no feedback); every other control is free in the Newton
    /// step.
    pub fn set_active(&mut self, hz: &ControlHorizon, grad: &[f64], eps: f64) {
        let (lo, hi) = (hz.opts.lower, hz.opts.upper);
        for k in 0..=hz.steps {
            let (u, g) = (hz.nominal.u[k] + self.dv[k], grad[k]);
            self.active[k] = false;
            if !hz.free[k] {
                continue;
            }
            if u <= lo + eps && g > 0.0 {
                self.active[k] = true;
                self.fixed[k] = lo - u;
            } else if u >= hi - eps && g < 0.0 {
                self.active[k] = true;
                self.fixed[k] = hi - u;
            }
        }
    }

    /// A rollout of the *linearised* dynamics from the model point δ with step length α:
    /// closed loop with the gains of the last Riccati pass, Δv_k = clamp(α k_k + K_k Δz_k)
    /// (clamped to the box about the model point; unclamped and recorded in `dir` for
    /// [`Arc::Direction`]), or open loop to clamp(u + α dir) ([`Arc::Projected`]);
    /// Δz_{k+1} = Ã_k Δz_k + B̃_k Δv_k, written to `dv_t`, `dz_t` as δ + Δ. Returns the model of J
    /// at δ + Δ without the proximal term: Σ ℓ_k(M₀ + ∂M₀/∂φ₁ δφ₁, u + δu, w + δw) (+ the
    /// second-order terms of the exact model), or 0 for [`Arc::Direction`] (its caller gets
    /// the value from the Newton step; with the exact model the value would read every H_k
    /// once more). Needs every stage Jacobian in memory.
    pub fn linearised(&mut self, lm: &LinearModel<'_>, alpha: f64, mode: Arc) -> f64 {
        let value = mode != Arc::Direction;
        let hz = lm.horizon;
        let (nz, steps) = (self.nz, hz.steps);
        let nxi = hz.model.nx();
        let (lo, hi) = (hz.opts.lower, hz.opts.upper);
        let nom = &hz.nominal;
        let scale = hz.model.moment_scale;
        let (dz, next) = (&mut self.lin_dz, &mut self.lin_next);
        dz.fill(0.0);
        // H_k is read only for the value.
        let h_ahead = lm.second.as_ref().filter(|_| value).map(|s| s.h());
        let mut q = 0.0;
        for k in 0..=steps {
            let u0 = nom.u[k] + self.dv[k];
            let d = if hz.free[k] {
                match mode {
                    Arc::Projected => (u0 + alpha * self.dir[k]).clamp(lo, hi) - u0,
                    _ => {
                        let g = &lm.gain[k * nz..(k + 1) * nz];
                        let x = alpha * lm.ff[k] + dot(g, dz);
                        if mode == Arc::Direction {
                            self.dir[k] = x;
                            x
                        } else {
                            (u0 + x).clamp(lo, hi) - u0
                        }
                    }
                }
            } else {
                dz[nxi]
            };
            self.dv_t[k] = self.dv[k] + d;
            let (zt, z0) = (
                &mut self.dz_t[k * nz..(k + 1) * nz],
                &self.dz[k * nz..(k + 1) * nz],
            );
            zt.iter_mut()
                .zip(z0.iter().zip(dz.iter()))
                .for_each(|(t, (a, b))| *t = a + b);
            if value {
                let r = nom.residual[k] + nom.dresidual(k, scale) * self.dz_t[k * nz];
                let u = nom.u[k] + self.dv_t[k];
                let w = if k > 0 {
                    nom.u[k - 1] + self.dv_t[k - 1]
                } else {
                    0.0
                };
                q += hz.cost.value(k, r, u, w);
                if let Some(so) = &lm.second {
                    q += so.value(k, &self.dz_t[k * nz..(k + 1) * nz], self.dv_t[k]);
                }
            }
            if k + PREFETCH_AHEAD < steps {
                let ahead = k + PREFETCH_AHEAD;
                lm.store.prefetch(ahead, h_ahead, ahead);
            }
            if k < steps {
                let StageJacobians { a, b } = lm.store.stage(k);
                // δz' = A δz + B δv, column by column (contiguous AXPYs, no bounds checks).
                let head = &mut next[..nxi];
                head.iter_mut().zip(b).for_each(|(y, bi)| *y = bi * d);
                for (col, &x) in a.chunks_exact(nxi).zip(&dz[..nxi]) {
                    head.iter_mut().zip(col).for_each(|(y, c)| *y += c * x);
                }
                if nz > nxi {
                    next[nxi] = d;
                }
                std::mem::swap(dz, next);
            }
        }
        q
    }
}
