//! The forward pass: closed-loop rollouts u_k = clamp(ū_k + α k_k + K_k δz_k) of the nonlinear
//! RATTLE map, and the trajectory storage they fill.
//!
//! δz_k = (δφ, δω, δw) is the deviation from the nominal trajectory in the tangent coordinates of
//! [`super::stage`]: δφᵢ = atan2(q̄ᵢ × qᵢ, q̄ᵢ·qᵢ) (the exact angle between the nominal and the
//! new attitude), δωᵢ = ωᵢ − ω̄ᵢ, δw = u_{k−1} − ū_{k−1}. Every rollout starts from the fixed
//! initial state (single shooting: every iterate is a trajectory of the simulator), and clamping
//! keeps every control inside the box exactly. A step whose simulation fails (Newton, a folded
//! joint, a non-finite state) returns the error and the line search rejects that α.
//!
//! Acceptance (Crocoddyl's rule, Mastalli et al. 2020): J̄ − J(α) ≥ c·(−ΔJ(α)) with the
//! predicted change ΔJ(α) = α d₁ + α² d₂ of the backward pass; α ∈ {1, ½, …}.

use super::riccati::StageCost;
use super::stage::{tangent, StageModel, Stepper};
use crate::error::Result;

/// A trajectory in DDP form: x̂_k = (q_k, p̂_k) for k = 0..=N with the controls, rates, Newton
/// predictors and bending moments (flat storage, allocated once).
#[derive(Clone, Debug)]
pub(crate) struct Traj {
    n: usize,
    pub q: Vec<[f64; 2]>,
    pub p: Vec<[f64; 2]>,
    pub omega: Vec<f64>,
    pub mu: Vec<f64>,
    /// λ of step k (k < N): the converged position multiplier, the exact Newton start of the
    /// dual-number step of the stage Jacobians.
    pub lambda: Vec<f64>,
    pub u: Vec<f64>,
    pub moment: Vec<f64>,
    /// The objective's residual r_k(M₀(t_k)) and its first two derivatives in M₀
    /// ([`StageCost::residual`]).
    pub residual: Vec<f64>,
    pub dresidual_dm: Vec<f64>,
    pub d2residual_dm2: Vec<f64>,
    pub cost: f64,
}

impl Traj {
    pub fn new(n: usize, steps: usize) -> Self {
        let m = steps + 1;
        Traj {
            n,
            q: vec![[0.0; 2]; m * n],
            p: vec![[0.0; 2]; m * n],
            omega: vec![0.0; m * n],
            mu: vec![0.0; m * n],
            lambda: vec![0.0; m * n],
            u: vec![0.0; m],
            moment: vec![0.0; m],
            residual: vec![0.0; m],
            dresidual_dm: vec![0.0; m],
            d2residual_dm2: vec![0.0; m],
            cost: 0.0,
        }
    }
    #[inline]
    pub fn q(&self, k: usize) -> &[[f64; 2]] {
        &self.q[k * self.n..(k + 1) * self.n]
    }
    #[inline]
    pub fn p(&self, k: usize) -> &[[f64; 2]] {
        &self.p[k * self.n..(k + 1) * self.n]
    }
    #[inline]
    pub fn omega(&self, k: usize) -> &[f64] {
        &self.omega[k * self.n..(k + 1) * self.n]
    }
    #[inline]
    pub fn mu(&self, k: usize) -> &[f64] {
        &self.mu[k * self.n..(k + 1) * self.n]
    }
    #[inline]
    pub fn lambda(&self, k: usize) -> &[f64] {
        &self.lambda[k * self.n..(k + 1) * self.n]
    }
    /// ∂M₀/∂φ₁ at t_k: M₀ = s·q₁,z, ∂q₁/∂φ₁ = t₁, so ∂M₀/∂φ₁ = s·t₁,z = s·q₁,y.
    #[inline]
    pub fn dmoment(&self, k: usize, scale: f64) -> f64 {
        scale * tangent(&self.q[k * self.n])[1]
    }
    /// ∂r_k/∂φ₁ = r_k′(M₀) ∂M₀/∂φ₁ at t_k.
    #[inline]
    pub fn dresidual(&self, k: usize, scale: f64) -> f64 {
        self.dresidual_dm[k] * self.dmoment(k, scale)
    }
}

/// The feedback law of a rollout: `None` replays `u` (the nominal of a fresh start).
pub(crate) struct Feedback<'a> {
    pub nominal: &'a Traj,
    pub gain: &'a [f64],
    pub ff: &'a [f64],
    pub alpha: f64,
    pub nz: usize,
}

/// What every rollout of one problem shares: the stage maps, the stage costs, which stages
/// hold a decision and the box of the controls.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Shooting<'a> {
    /// The stage maps (and the start).
    pub model: &'a StageModel,
    /// ℓ_k.
    pub cost: &'a StageCost,
    /// Whether stage k has a decision (the first stage of a piece); held stages copy u_{k−1}.
    pub free: &'a [bool],
    /// The box lower ≤ u_k ≤ upper.
    pub lower: f64,
    pub upper: f64,
}

/// The simulator of the rollouts, sized once: the stage map and the scratch of the rates.
#[derive(Clone, Debug)]
pub(crate) struct Simulator {
    /// The stage map in f64.
    pub stepper: Stepper<f64>,
    /// n blocks of scratch (M⁻¹p for the rates).
    pub scratch: Vec<[f64; 2]>,
}

impl Simulator {
    /// For the stages of `model`.
    pub fn new(model: &StageModel) -> Result<Self> {
        Ok(Simulator {
            stepper: Stepper::new(model)?,
            scratch: vec![[0.0; 2]; model.n],
        })
    }

    /// Rolls out the stage maps of `shooting` from the initial state, writing `out` and its
    /// cost: [`rollout`].
    pub fn rollout(
        &mut self,
        shooting: &Shooting<'_>,
        fb: Option<&Feedback<'_>>,
        out: &mut Traj,
    ) -> Result<()> {
        rollout(shooting, &mut self.stepper, fb, out, &mut self.scratch)
    }
}

/// Rolls out the stage maps from the initial state, writing `out` and its cost. With `fb`
/// the free controls follow the feedback law; without it they are `out.u` as given. Held stages
/// copy the previous control. Controls stay in the box. `scratch` has length n.
fn rollout(
    shooting: &Shooting<'_>,
    stepper: &mut Stepper<f64>,
    fb: Option<&Feedback<'_>>,
    out: &mut Traj,
    scratch: &mut [[f64; 2]],
) -> Result<()> {
    let Shooting {
        model,
        cost,
        free,
        lower: lo,
        upper: hi,
    } = *shooting;
    let n = model.n;
    let steps = cost.steps;
    let mut total = 0.0;
    for k in 0..=steps {
        let w = if k > 0 { out.u[k - 1] } else { 0.0 };
        // The control of stage k (needs x̂_k for k ≥ 1; x̂_0 is fixed, δz_0 = 0).
        let u = if !free[k] {
            w
        } else if let Some(f) = fb {
            let mut v = f.nominal.u[k] + f.alpha * f.ff[k];
            if k > 0 {
                let g = &f.gain[k * f.nz..(k + 1) * f.nz];
                let (qn, wn) = (f.nominal.q(k), f.nominal.omega(k));
                let st = &stepper.state;
                // ω of the new state into `out` first.
                model.rates(&st.q, &st.p, scratch, &mut out.omega[k * n..(k + 1) * n]);
                for i in 0..n {
                    let (a, b) = (qn[i], st.q[i]);
                    let dphi = (a[0] * b[1] - a[1] * b[0]).atan2(a[0] * b[0] + a[1] * b[1]);
                    v += g[i] * dphi + g[n + i] * (out.omega[k * n + i] - wn[i]);
                }
                if f.nz > 2 * n {
                    v += g[2 * n] * (w - f.nominal.u[k - 1]);
                }
            }
            v.clamp(lo, hi)
        } else {
            out.u[k]
        };
        if k == 0 {
            stepper.reset(u)?;
        }
        let st = &stepper.state;
        out.q[k * n..(k + 1) * n].copy_from_slice(&st.q);
        out.p[k * n..(k + 1) * n].copy_from_slice(&st.p);
        let mu = match &st.multipliers {
            Some(m) => &m.mu[..],
            None => stepper.rattle.consistent_multiplier(),
        };
        out.mu[k * n..(k + 1) * n].copy_from_slice(mu);
        if fb.is_none() || k == 0 || !free[k] {
            model.rates(&st.q, &st.p, scratch, &mut out.omega[k * n..(k + 1) * n]);
        }
        out.u[k] = u;
        let m = model.chain.base_moment(&st.q);
        let r = cost.residual(k, m);
        out.moment[k] = m;
        (out.residual[k], out.dresidual_dm[k], out.d2residual_dm2[k]) = (r.r, r.dr, r.d2r);
        total += cost.value(k, r.r, u, w);
        if k < steps {
            stepper.advance(k, u)?;
            let m = stepper.state.multipliers.as_ref();
            let lambda = m.expect("a step leaves its multipliers").lambda.as_slice();
            out.lambda[k * n..(k + 1) * n].copy_from_slice(lambda);
        }
    }
    out.cost = total;
    Ok(())
}
