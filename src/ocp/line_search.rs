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

use super::cost::ResidualVector;
use super::riccati::StageCost;
use super::stage::{dot, tangent, tangent_basis, StageModel, Stepper};
use crate::error::Result;

/// A trajectory in DDP form: x̂_k = (q_k, p̂_k) for k = 0..=N with the controls, rates, Newton
/// predictors and bending moments (flat storage, allocated once), in the planar or the spatial
/// model.
#[derive(Clone, Debug)]
pub(crate) struct Traj<const DIM: usize = 2> {
    n: usize,
    pub q: Vec<[f64; DIM]>,
    pub p: Vec<[f64; DIM]>,
    /// ω_{i,a} (DIM − 1 per pendulum, [`StageModel::rates`]).
    pub omega: Vec<f64>,
    pub mu: Vec<f64>,
    /// λ of step k (k < N): the converged position multiplier, the exact Newton start of the
    /// dual-number step of the stage Jacobians.
    pub lambda: Vec<f64>,
    /// u_k (the z component of a 2-axis control).
    pub u: Vec<f64>,
    /// u_{x,k} of a 2-axis control (empty for a control along z).
    pub ux: Vec<f64>,
    /// M₀(t_k) (M₀_z in the spatial model).
    pub moment: Vec<f64>,
    /// M₀ₓ(t_k) (spatial model; empty in the planar one).
    pub moment_x: Vec<f64>,
    /// The objective's residual r_k(M₀(t_k)) and its first two derivatives in M₀
    /// ([`StageCost::residual`]); in the spatial model r_k is the z component of the vector
    /// residual R_k and `dresidual_dm`, `d2residual_dm2` are unused.
    pub residual: Vec<f64>,
    pub dresidual_dm: Vec<f64>,
    pub d2residual_dm2: Vec<f64>,
    /// The spatial model's vector residual R_k = (R_z, R_x) and its Jacobian ∂R/∂(M₀_z, M₀ₓ)
    /// ([`StageCost::residual_vector`]; empty in the planar model).
    pub residual_vec: Vec<ResidualVector>,
    pub cost: f64,
}

impl<const DIM: usize> Traj<DIM> {
    /// Storage for N = `steps` stages of n pendulums, with x components for a 2-axis control.
    pub(crate) fn new(n: usize, steps: usize, two_axis: bool) -> Self {
        let m = steps + 1;
        let spatial = if DIM == 3 { m } else { 0 };
        Traj {
            n,
            q: vec![[0.0; DIM]; m * n],
            p: vec![[0.0; DIM]; m * n],
            omega: vec![0.0; m * n * (DIM - 1)],
            mu: vec![0.0; m * n],
            lambda: vec![0.0; m * n],
            u: vec![0.0; m],
            ux: vec![0.0; if two_axis { m } else { 0 }],
            moment: vec![0.0; m],
            moment_x: vec![0.0; spatial],
            residual: vec![0.0; m],
            dresidual_dm: vec![0.0; m],
            d2residual_dm2: vec![0.0; m],
            residual_vec: vec![ResidualVector::default(); spatial],
            cost: 0.0,
        }
    }
    #[inline]
    pub(crate) fn q(&self, k: usize) -> &[[f64; DIM]] {
        &self.q[k * self.n..(k + 1) * self.n]
    }
    #[inline]
    pub(crate) fn p(&self, k: usize) -> &[[f64; DIM]] {
        &self.p[k * self.n..(k + 1) * self.n]
    }
    #[inline]
    pub(crate) fn omega(&self, k: usize) -> &[f64] {
        let w = self.n * (DIM - 1);
        &self.omega[k * w..(k + 1) * w]
    }
    #[inline]
    pub(crate) fn mu(&self, k: usize) -> &[f64] {
        &self.mu[k * self.n..(k + 1) * self.n]
    }
    #[inline]
    pub(crate) fn lambda(&self, k: usize) -> &[f64] {
        &self.lambda[k * self.n..(k + 1) * self.n]
    }
    /// u_{x,k} (0 for a control along z).
    #[inline]
    pub(crate) fn ux(&self, k: usize) -> f64 {
        self.ux.get(k).copied().unwrap_or(0.0)
    }

    /// Component `axis` of u_k: 0 the z component u_k, 1 the x component u_{x,k}.
    #[inline]
    pub(crate) fn control(&self, k: usize, axis: usize) -> f64 {
        if axis == 0 {
            self.u[k]
        } else {
            self.ux(k)
        }
    }

    /// The Gauss-Newton residual at t_k and its derivative in the attitude of pendulum 1,
    /// (R, ∂R_c/∂φ_{1,a}): planar (r_k, ∂r_k/∂φ₁ in [0][0], [`Traj::dresidual`]); spatial
    /// R_k = (R_z, R_x) and ∂R/∂M₀ (`residual_vec`) times ∂(M₀_z, M₀ₓ)/∂φ_{1,a} =
    /// s ((e_a)_z, (e_a)_x) in the basis e_a(q₁) of the stage map's chart ([`tangent_basis`]).
    #[inline]
    pub(crate) fn residual_model(&self, k: usize, scale: f64) -> ([f64; 2], [[f64; 2]; 2]) {
        let q = &self.q[k * self.n];
        if DIM == 2 {
            let dm = scale * q[0];
            let d = self.dresidual_dm[k] * dm;
            return ([self.residual[k], 0.0], [[d, 0.0], [0.0, 0.0]]);
        }
        let e = tangent_basis(q);
        let rv = &self.residual_vec[k];
        let mut jac = [[0.0; 2]; 2];
        for (a, ea) in e.iter().enumerate() {
            let dm = [scale * ea[DIM - 1], scale * ea[0]];
            for (c, row) in jac.iter_mut().enumerate() {
                row[a] = rv.jac[c][0] * dm[0] + rv.jac[c][1] * dm[1];
            }
        }
        (rv.r, jac)
    }
}

impl Traj {
    /// ∂M₀/∂φ₁ at t_k: M₀ = s·q₁,z, ∂q₁/∂φ₁ = t₁, so ∂M₀/∂φ₁ = s·t₁,z = s·q₁,y.
    #[inline]
    pub(crate) fn dmoment(&self, k: usize, scale: f64) -> f64 {
        scale * tangent(&self.q[k * self.n])[1]
    }
    /// ∂r_k/∂φ₁ = r_k′(M₀) ∂M₀/∂φ₁ at t_k.
    #[inline]
    pub(crate) fn dresidual(&self, k: usize, scale: f64) -> f64 {
        self.dresidual_dm[k] * self.dmoment(k, scale)
    }
}

/// The feedback law of a rollout: `None` replays `u` (the nominal of a fresh start).
pub(crate) struct Feedback<'a, const DIM: usize = 2> {
    pub nominal: &'a Traj<DIM>,
    pub gain: &'a [f64],
    pub ff: &'a [f64],
    pub alpha: f64,
    pub nz: usize,
}

/// What every rollout of one problem shares: the stage maps, the stage costs, which stages
/// hold a decision and the box of the controls.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Shooting<'a, const DIM: usize = 2> {
    /// The stage maps (and the start).
    pub model: &'a StageModel<DIM>,
    /// ℓ_k.
    pub cost: &'a StageCost,
    /// Whether stage k has a decision (the first stage of a piece); held stages copy u_{k−1}.
    pub free: &'a [bool],
    /// The box lower ≤ u_k ≤ upper (each component of a 2-axis control).
    pub lower: f64,
    pub upper: f64,
}

/// The simulator of the rollouts, sized once: the stage map and the scratch of the rates.
#[derive(Clone, Debug)]
pub(crate) struct Simulator<const DIM: usize = 2> {
    /// The stage map in f64.
    pub stepper: Stepper<f64, DIM>,
    /// n blocks of scratch (M⁻¹p for the rates).
    pub scratch: Vec<[f64; DIM]>,
}

impl<const DIM: usize> Simulator<DIM> {
    /// For the stages of `model`.
    pub(crate) fn new(model: &StageModel<DIM>) -> Result<Self> {
        Ok(Simulator {
            stepper: Stepper::new(model)?,
            scratch: vec![[0.0; DIM]; model.n],
        })
    }
}

impl<const DIM: usize> Simulator<DIM> {
    /// Rolls out the stage maps of `shooting` from the initial state, writing `out` and its
    /// cost: [`rollout`].
    pub(crate) fn rollout(
        &mut self,
        shooting: &Shooting<'_, DIM>,
        fb: Option<&Feedback<'_, DIM>>,
        out: &mut Traj<DIM>,
    ) -> Result<()> {
        rollout(shooting, &mut self.stepper, fb, out, &mut self.scratch)
    }
}

/// The angle coordinates δφ_{i,a} of the attitude `b` about the nominal `a` in the nominal's
/// chart: planar the exact angle atan2(a × b, a·b); spatial the rotation vector of the shortest
/// rotation from a to b, θ (b − (a·b) a)/|b − (a·b) a| with θ = atan2(|a × b|, a·b), in the basis
/// e_a(a) ([`tangent_basis`]).
#[inline]
fn chart_angles<const DIM: usize>(a: &[f64; DIM], b: &[f64; DIM]) -> [f64; 2] {
    if DIM == 2 {
        return [
            (a[0] * b[1] - a[1] * b[0]).atan2(a[0] * b[0] + a[1] * b[1]),
            0.0,
        ];
    }
    let c = dot(a, b);
    let mut perp = [0.0; DIM];
    for d in 0..DIM {
        perp[d] = b[d] - c * a[d];
    }
    let s = dot(&perp, &perp).sqrt();
    if s == 0.0 {
        return [0.0; 2];
    }
    let theta = s.atan2(c) / s;
    let e = tangent_basis(a);
    [theta * dot(&e[0], &perp), theta * dot(&e[1], &perp)]
}

/// The controls of a free stage k under the feedback law `f`: ū_i + α k_i + K_i δz_k for each
/// control a (decision i = k m + a; before the clamp), δz_k = (δφ, δω, δw) from the state in
/// `stepper` (its ω written into `omega`, and `scratch` = M⁻¹p): δφ by [`chart_angles`], δω
/// planar ωᵢ − ω̄ᵢ, spatial ē_a·vᵢ − ω̄_{i,a} (the nominal chart's map L applied to the state's
/// velocity), δw = w − ū_{k−1} (`w`: u_{k−1} of this rollout, both components).
fn feedback_control<const DIM: usize>(
    f: &Feedback<'_, DIM>,
    model: &StageModel<DIM>,
    stepper: &Stepper<f64, DIM>,
    (k, w): (usize, [f64; 2]),
    (omega, scratch): (&mut [f64], &mut [[f64; DIM]]),
) -> [f64; 2] {
    let n = model.n;
    let na = DIM - 1;
    let nw = n * na;
    let m = if f.nominal.ux.is_empty() { 1 } else { 2 };
    let mut v = [0.0; 2];
    for (a, va) in v.iter_mut().enumerate().take(m) {
        *va = f.nominal.control(k, a) + f.alpha * f.ff[k * m + a];
    }
    if k > 0 {
        let gain = |a: usize| &f.gain[(k * m + a) * f.nz..(k * m + a + 1) * f.nz];
        let (qn, wn) = (f.nominal.q(k), f.nominal.omega(k));
        let st = &stepper.state;
        // ω of the new state into `out` first.
        model.rates(&st.q, &st.p, scratch, omega);
        for i in 0..n {
            let dphi = chart_angles(&qn[i], &st.q[i]);
            if DIM == 2 {
                let g = gain(0);
                v[0] += g[i] * dphi[0] + g[n + i] * (omega[i] - wn[i]);
                continue;
            }
            let e = tangent_basis(&qn[i]);
            for (c, vc) in v.iter_mut().enumerate().take(m) {
                let g = gain(c);
                for a in 0..na {
                    let j = i * na + a;
                    *vc += g[j] * dphi[a] + g[nw + j] * (dot(&e[a], &scratch[i]) - wn[j]);
                }
            }
        }
        for (c, vc) in v.iter_mut().enumerate().take(m) {
            let g = gain(c);
            for b in 0..f.nz - 2 * nw {
                *vc += g[2 * nw + b] * (w[b] - f.nominal.control(k - 1, b));
            }
        }
    }
    v
}

/// Rolls out the stage maps from the initial state, writing `out` and its cost. With `fb`
/// the free controls follow the feedback law; without it they are `out.u` (and
/// `out.ux`) as given. Held stages copy the previous control. Controls stay in the box.
/// `scratch` has length n.
fn rollout<const DIM: usize>(
    shooting: &Shooting<'_, DIM>,
    stepper: &mut Stepper<f64, DIM>,
    fb: Option<&Feedback<'_, DIM>>,
    out: &mut Traj<DIM>,
    scratch: &mut [[f64; DIM]],
) -> Result<()> {
    let Shooting {
        model,
        cost,
        free,
        lower: lo,
        upper: hi,
    } = *shooting;
    let n = model.n;
    let nw = n * (DIM - 1);
    let steps = cost.steps;
    let two_axis = !out.ux.is_empty();
    let mut total = 0.0;
    for k in 0..=steps {
        let w = if k > 0 { out.u[k - 1] } else { 0.0 };
        let wx = if k > 0 { out.ux(k - 1) } else { 0.0 };
        // The control of stage k (needs x̂_k for k ≥ 1; x̂_0 is fixed, δz_0 = 0).
        let (u, ux) = if !free[k] {
            (w, wx)
        } else if let Some(f) = fb {
            let omega = &mut out.omega[k * nw..(k + 1) * nw];
            let v = feedback_control(f, model, stepper, (k, [w, wx]), (omega, scratch));
            let vx = if two_axis { v[1].clamp(lo, hi) } else { 0.0 };
            (v[0].clamp(lo, hi), vx)
        } else {
            (out.u[k], out.ux(k))
        };
        if two_axis {
            stepper.set_control_x(k, ux);
        }
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
            model.rates(&st.q, &st.p, scratch, &mut out.omega[k * nw..(k + 1) * nw]);
        }
        out.u[k] = u;
        let [m, mx] = model.moment(&st.q);
        out.moment[k] = m;
        if DIM == 2 {
            let r = cost.residual(k, m);
            (out.residual[k], out.dresidual_dm[k], out.d2residual_dm2[k]) = (r.r, r.dr, r.d2r);
            total += cost.value(k, r.r, u, w);
        } else {
            out.moment_x[k] = mx;
            let r = cost.residual_vector(k, [m, mx]);
            out.residual[k] = r.r[0];
            out.residual_vec[k] = r;
            if two_axis {
                out.ux[k] = ux;
            }
            total += cost.value_axes(k, r.r, [u, ux], [w, wx]);
        }
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
