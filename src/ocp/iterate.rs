//! The QP iterate: the model point δ = (δv per stage, δz per stage) of the Gauss-Newton QP's
//! iterations and its trial, the linearised rollouts that move it (module docs, "The step"), the
//! ε-active set and the feedforward the closed-loop rollouts replay.

use super::horizon::ControlHorizon;
use super::jacobians::{JacobianStore, PREFETCH_AHEAD};
use super::riccati::{dot, StageJacobians};
use super::second_order::SecondOrder;

/// How [`QpIterate::linearised`] moves the controls along a linearised rollout.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum RolloutMode {
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
pub(crate) struct LinearModel<'a, const DIM: usize = 2> {
    pub horizon: &'a ControlHorizon<DIM>,
    pub store: &'a JacobianStore<DIM>,
    /// K_k (n_z per decision).
    pub gain: &'a [f64],
    /// k_k of the last pass (per decision).
    pub ff: &'a [f64],
    /// H_k and the cost's curvature (exact model), read for the value.
    pub second: Option<SecondOrder<'a>>,
}

/// The model point of the QP iterations and its buffers (sized once per problem). Decisions
/// are indexed i = k m + a (m controls per stage, a = 0 the z component).
#[derive(Clone, Debug)]
pub(crate) struct QpIterate {
    nz: usize,
    /// Controls per stage m.
    m: usize,
    /// δv_i (per decision) and δz_k (n_z per stage) of the current point.
    pub dv: Vec<f64>,
    pub dz: Vec<f64>,
    /// The point a linearised rollout reached.
    pub dv_t: Vec<f64>,
    pub dz_t: Vec<f64>,
    lin_dz: Vec<f64>,
    lin_next: Vec<f64>,
    /// The direction Δv (interior point) or the open-loop step of a projected rollout.
    pub dir: Vec<f64>,
    /// The ε-active set of the current iteration: decision i moves to its bound
    /// (step `fixed[i]`) without feedback.
    pub active: Vec<bool>,
    pub fixed: Vec<f64>,
    /// Feedforward of the closed-loop rollout about the nominal.
    pub ff: Vec<f64>,
}

impl QpIterate {
    /// The point δ = 0 of a horizon of `steps` stages with `nz` state coordinates and `m`
    /// controls per stage.
    pub(super) fn new(steps: usize, nz: usize, m: usize) -> Self {
        let nd = (steps + 1) * m;
        QpIterate {
            nz,
            m,
            dv: vec![0.0; nd],
            dz: vec![0.0; (steps + 1) * nz],
            dv_t: vec![0.0; nd],
            dz_t: vec![0.0; (steps + 1) * nz],
            lin_dz: vec![0.0; nz],
            lin_next: vec![0.0; nz],
            dir: vec![0.0; nd],
            active: vec![false; nd],
            fixed: vec![0.0; nd],
            ff: vec![0.0; nd],
        }
    }

    /// δ = 0: the nominal.
    pub(super) fn at_nominal(&mut self) {
        self.dv.fill(0.0);
        self.dz.fill(0.0);
    }

    /// The rollout's point becomes the current one.
    pub(super) fn take_trial(&mut self) {
        std::mem::swap(&mut self.dv, &mut self.dv_t);
        std::mem::swap(&mut self.dz, &mut self.dz_t);
    }

    /// The feedforward of the closed-loop rollouts: k_i = δv_i − K_i δz_k, so that
    /// u_i = ū_i + α k_i + K_i δz_k reproduces the QP's step at α = 1.
    pub(super) fn store_feedforward(&mut self, gain: &[f64]) {
        let (nz, m) = (self.nz, self.m);
        for i in 0..self.ff.len() {
            let g = &gain[i * nz..(i + 1) * nz];
            let k = i / m;
            self.ff[i] = self.dv[i] - dot(g, &self.dz[k * nz..(k + 1) * nz]);
        }
    }

    /// Bertsekas's ε-active set at the model point from the gradient `grad` of the last
    /// costate sweep: a control within ε of a bound whose gradient pushes it outward moves to
    /// that bound and is fixed there (no feedback); every other control is free in the Newton
    /// step.
    pub(super) fn set_active<const DIM: usize>(
        &mut self,
        hz: &ControlHorizon<DIM>,
        grad: &[f64],
        eps: f64,
    ) {
        let (lo, hi) = (hz.opts.lower, hz.opts.upper);
        let m = self.m;
        for i in 0..(hz.steps + 1) * m {
            let k = i / m;
            let (u, g) = (hz.nominal.control(k, i % m) + self.dv[i], grad[i]);
            self.active[i] = false;
            if !hz.free[k] {
                continue;
            }
            if u <= lo + eps && g > 0.0 {
                self.active[i] = true;
                self.fixed[i] = lo - u;
            } else if u >= hi - eps && g < 0.0 {
                self.active[i] = true;
                self.fixed[i] = hi - u;
            }
        }
    }

    /// A rollout of the *linearised* dynamics from the model point δ with step length α:
    /// closed loop with the gains of the last Riccati pass, Δv_i = clamp(α k_i + K_i Δz_k)
    /// (clamped to the box about the model point; unclamped and recorded in `dir` for
    /// [`RolloutMode::Direction`]), or open loop to clamp(u + α dir) ([`RolloutMode::Projected`]);
    /// Δz_{k+1} = Ã_k Δz_k + B̃_k Δv_k, written to `dv_t`, `dz_t` as δ + Δ. Returns the model of J
    /// at δ + Δ without the proximal term: Σ ℓ_k(R + ∂R/∂φ₁ δφ₁, u + δu, w + δw) (+ the
    /// second-order terms of the exact model), or 0 for [`RolloutMode::Direction`] (its caller gets
    /// the value from the Newton step; with the exact model the value would read every H_k
    /// once more). Needs every stage Jacobian in memory.
    pub(super) fn linearised<const DIM: usize>(
        &mut self,
        lm: &LinearModel<'_, DIM>,
        alpha: f64,
        mode: RolloutMode,
    ) -> f64 {
        let value = mode != RolloutMode::Direction;
        let hz = lm.horizon;
        let (nz, m, steps) = (self.nz, self.m, hz.steps);
        let nxi = hz.model.nx();
        let (lo, hi) = (hz.opts.lower, hz.opts.upper);
        let nom = &hz.nominal;
        let (dz, next) = (&mut self.lin_dz, &mut self.lin_next);
        dz.fill(0.0);
        // H_k is read only for the value.
        let h_ahead = lm.second.as_ref().filter(|_| value).map(|s| s.h());
        let mut q = 0.0;
        for k in 0..=steps {
            let mut d = [0.0; 2];
            for (a, da) in d.iter_mut().enumerate().take(m) {
                let i = k * m + a;
                let u0 = nom.control(k, a) + self.dv[i];
                *da = if hz.free[k] {
                    match mode {
                        RolloutMode::Projected => (u0 + alpha * self.dir[i]).clamp(lo, hi) - u0,
                        _ => {
                            let g = &lm.gain[i * nz..(i + 1) * nz];
                            let x = alpha * lm.ff[i] + dot(g, dz);
                            if mode == RolloutMode::Direction {
                                self.dir[i] = x;
                                x
                            } else {
                                (u0 + x).clamp(lo, hi) - u0
                            }
                        }
                    }
                } else {
                    dz[nxi + a]
                };
                self.dv_t[i] = self.dv[i] + *da;
            }
            let (zt, z0) = (
                &mut self.dz_t[k * nz..(k + 1) * nz],
                &self.dz[k * nz..(k + 1) * nz],
            );
            zt.iter_mut()
                .zip(z0.iter().zip(dz.iter()))
                .for_each(|(t, (a, b))| *t = a + b);
            if value {
                let zt = &self.dz_t[k * nz..(k + 1) * nz];
                q += stage_value(lm, k, (&self.dv_t, m), zt);
                if let Some(so) = &lm.second {
                    q += so.value(k, zt, self.dv_t[k]);
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
                head.iter_mut().zip(b).for_each(|(y, bi)| *y = bi * d[0]);
                if m == 2 {
                    head.iter_mut()
                        .zip(&b[nxi..])
                        .for_each(|(y, bi)| *y += bi * d[1]);
                }
                for (col, &x) in a.chunks_exact(nxi).zip(&dz[..nxi]) {
                    head.iter_mut().zip(col).for_each(|(y, c)| *y += c * x);
                }
                next[nxi..nz].copy_from_slice(&d[..nz - nxi]);
                std::mem::swap(dz, next);
            }
        }
        q
    }
}

/// Stage k's term of the model of J at a linearised rollout's point δ + Δ (`dv_t`, per decision
/// with `m` controls per stage; `zt` = δz_k + Δz_k): ℓ_k(R + ∂R/∂φ₁ δφ₁, u + δu, w + δw)
/// (planar: the scalar residual r + ∂r/∂φ₁ δφ₁), without the exact model's second-order terms.
fn stage_value<const DIM: usize>(
    lm: &LinearModel<'_, DIM>,
    k: usize,
    (dv_t, m): (&[f64], usize),
    zt: &[f64],
) -> f64 {
    let hz = lm.horizon;
    let nom = &hz.nominal;
    let (r, dr) = nom.residual_model(k, hz.model.moment_scale);
    let ctl = |k: usize| {
        let mut u = [0.0; 2];
        for (a, ua) in u.iter_mut().enumerate().take(m) {
            *ua = nom.control(k, a) + dv_t[k * m + a];
        }
        u
    };
    let u = ctl(k);
    let w = if k > 0 { ctl(k - 1) } else { [0.0; 2] };
    if DIM == 2 {
        let r = r[0] + dr[0][0] * zt[0];
        hz.cost.value(k, r, u[0], w[0])
    } else {
        let mut rl = r;
        for (c, x) in rl.iter_mut().enumerate() {
            *x += dr[c][0] * zt[0] + dr[c][1] * zt[1];
        }
        hz.cost.value_axes(k, rl, u, w)
    }
}
