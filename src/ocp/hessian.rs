//! The exact second-order term of a stage: the Hessian of its Lagrangian term
//! ```text
//! G_k(ξ_k, u_k) = ν_{k+1} · F̃_k(ξ_k, u_k),   F̃_k = chart⁻¹ ∘ F_k ∘ chart,
//! ```
//! with ν_{k+1} the costate of the nominal (∂J/∂ξ_{k+1}, the multiplier of the stage map in the
//! multiple-shooting view) and F̃_k the stage map in the tangent coordinates ξ = (φ, ω) of
//! [`super::stage`], which are global coordinates of the planar state manifold:
//! chart(ξ) = (qᵢ = (cos φᵢ, sin φᵢ), p = M v, vᵢ = ωᵢ tᵢ) and chart⁻¹(q, p) = (φᵢ = atan2 qᵢ,
//! ωᵢ = tᵢ·(M⁻¹p)ᵢ). Adding H_k = ∇²G_k to the Gauss-Newton stage terms (Q_zz += H_k) turns the
//! Riccati step into the exact Newton step of J(u) (Dunn and Bertsekas 1989: the reduced
//! Hessian of the single-shooting objective is that of the Lagrangian with the adjoint
//! costates), which Gauss-Newton misses where the residual M₀ is not small.
//!
//! # Forward over reverse, from the one model
//! The gradient ∇G_k = [A_k B_k]ᵀν_{k+1} is the reverse (vector-Jacobian) step of the stage map:
//! the chart's inverse at k + 1 (closed form), the discrete adjoint's reverse RATTLE step
//! ([`crate::adjoint`], the same one the gradient uses), the reverse of the control's
//! half-kick p_k = p̂_k − (h/2) u_k P(q_k) b (the reverse of a projection, the step's own
//! [`ReverseSweep::projection_reverse`]) and the chart's at k. Run in `DualSVec64<8>` on the
//! forward step of the Jacobians (same seeds, same dual states), the derivative parts of that
//! gradient are the Hessian's columns: H_k e_j for the 8 directions of a chunk, exact (no
//! differencing), including the chart's curvature since the chart maps are differentiated
//! at the dual point. Three chunks of a forward and a reverse dual step for n = 10.

use super::stage::{
    chunks, eps, ndir, tangent, Dv, JacobianWorkspace, JacobiansMut, StageAt, StageModel, Stepper,
    CHUNK,
};
use crate::adjoint::{Cotangents, ReverseSweep, StateView};
use crate::base::Scalar;
use crate::error::Result;
use crate::model::Chain;
use num_dual::DualSVec64;
use std::ops::Range;

/// The buffers of a stage's vector-Jacobian product (per thread, sized once): the chart point
/// (q_k, ω_k), the post-kick momentum p_k, the kick's multipliers y, and scratch.
#[derive(Clone, Debug)]
pub(crate) struct VjpBuffers<D> {
    q0: Vec<[D; 2]>,
    p0: Vec<[D; 2]>,
    /// The rates ω_k of the chart point (set by the caller).
    pub omega0: Vec<D>,
    y: Vec<D>,
    w: Vec<[D; 2]>,
    s: Vec<[D; 2]>,
}

impl<D: Scalar> VjpBuffers<D> {
    pub(super) fn new(n: usize) -> Self {
        let v = vec![[D::zero(); 2]; n];
        VjpBuffers {
            q0: v.clone(),
            p0: v.clone(),
            omega0: vec![D::zero(); n],
            y: vec![D::zero(); n],
            w: v.clone(),
            s: v,
        }
    }
}

/// The reverse step's scratch and cotangents for one thread and one pass (borrows the chain;
/// created once per pass, not per stage).
pub(crate) struct Reverse<'a, D> {
    sweep: ReverseSweep<'a, D, 2>,
    cot: Cotangents<D, 2>,
}

impl<'a, D: Scalar> Reverse<'a, D> {
    /// For stages of `model` over a horizon of `steps` steps.
    pub(super) fn new(chain: &'a Chain<D, 2>, model: &StageModel, steps: usize) -> Self {
        let n = model.n;
        let zero = vec![[D::zero(); 2]; n];
        let mut sweep = ReverseSweep::new(chain, model.h, &[]);
        sweep.t0 = model.start.as_ref().map_or(0.0, |s| s.t0);
        Reverse {
            sweep,
            cot: Cotangents {
                qbar: zero.clone(),
                pbar: zero,
                tip_bar: [D::zero(); 2],
                ubar: vec![D::zero(); steps + 2],
                uxbar: Vec::new(),
                thbar: Vec::new(),
            },
        }
    }
}

#[inline]
fn dot2<D: Scalar>(a: &[D; 2], b: &[D; 2]) -> D {
    a[0] * b[0] + a[1] * b[1]
}

/// One stage's vector-Jacobian product ∇(ν·F̃_k): stage k of `model` with the control u_k = `u`
/// and the costate ν = ν_{k+1} (2n entries).
#[derive(Clone, Copy, Debug)]
pub(crate) struct VjpStage<'a, D> {
    /// The stage maps.
    pub model: &'a StageModel,
    /// The stage index k.
    pub k: usize,
    /// u_k (seeded along the control's direction in dual numbers).
    pub u: D,
    /// ν_{k+1}.
    pub nu: &'a [f64],
}

/// A stage map with the buffers of its vector-Jacobian product, sized once: the f64 costate
/// sweep by reverse steps.
#[derive(Clone, Debug)]
pub(crate) struct VjpWorkspace<D> {
    /// The stage map (x̂_k and its Newton start are loaded by the caller).
    pub stepper: Stepper<D>,
    /// The product's buffers (the rates ω_k set by the caller).
    pub bufs: VjpBuffers<D>,
}

impl<D: Scalar> VjpWorkspace<D> {
    /// For the stages of `model`.
    pub(super) fn new(model: &StageModel) -> Result<Self> {
        Ok(VjpWorkspace {
            stepper: Stepper::new(model)?,
            bufs: VjpBuffers::new(model.n),
        })
    }
}

/// Per-thread workspace of the stage derivatives: the dual-number stage Jacobians
/// ([`JacobianWorkspace`], planar or spatial) and the dual buffers of the second-order terms
/// (planar: the exact model is planar only).
#[derive(Clone, Debug)]
pub(crate) struct HessianWorkspace<const DIM: usize = 2> {
    /// The forward dual step (A_k, B_k alone: [`JacobianWorkspace::jacobians`]).
    pub jac: JacobianWorkspace<DIM>,
    hb: VjpBuffers<Dv>,
}

impl<const DIM: usize> HessianWorkspace<DIM> {
    /// For the stages of `model`.
    pub(super) fn new(model: &StageModel<DIM>) -> Result<Self> {
        Ok(HessianWorkspace {
            jac: JacobianWorkspace::new(model)?,
            hb: VjpBuffers::new(if DIM == 2 { model.n } else { 0 }),
        })
    }
}

/// Where [`HessianWorkspace::second_order`] writes: H_k (column-major (2n + 1)², the control
/// last), ∇(ν·F̃_k) = [A_k B_k]ᵀν (2n + 1) and A_k, B_k.
#[derive(Debug)]
pub(crate) struct SecondOrderMut<'a> {
    /// H_k = ∇²_{(ξ,u)}(ν·F̃_k).
    pub hess: &'a mut [f64],
    /// ∇(ν·F̃_k).
    pub grad: &'a mut [f64],
    /// A_k and B_k.
    pub jac: JacobiansMut<'a>,
}

/// ∇(ν·F̃_k) by one reverse step, for any scalar: the stage point x̂_k = (q_k, p̂_k) is in
/// `stepper` (with its Newton start) and its rates in `hb.omega0`; afterwards
/// [`gradient_entry`] reads the 2n + 1 entries. In `f64` this is one costate step
/// ν_k = l_x + A_kᵀν_{k+1} without the Jacobians; in dual numbers seeded along the tangent
/// directions its derivative parts are H_k's columns (module docs).
pub(crate) fn stage_vjp<D: Scalar>(
    stepper: &mut Stepper<D>,
    hb: &mut VjpBuffers<D>,
    stage: VjpStage<'_, D>,
    rev: &mut Reverse<'_, D>,
) -> Result<()> {
    let VjpStage { model, k, u, nu } = stage;
    let kicked = record_step(stepper, hb, k, u)?;
    chart_inverse_reverse(stepper, hb, nu, rev);
    let st = &stepper.state;
    let m = st.multipliers.as_ref().expect("a step sets multipliers");
    let (phalf, w) = stepper.rattle.last_half_step();
    let sk = kick_view(hb);
    let sk1 = StateView {
        q: &st.q,
        p: &st.p,
        lambda: &m.lambda,
        mu: &m.mu,
        tip: [D::zero(); 2],
        phalf,
        w,
    };
    rev.cot.ubar[k] = D::zero();
    rev.cot.ubar[k + 1] = D::zero();
    rev.sweep
        .step(k, (&sk, &sk1), (u, D::zero()), &mut rev.cot)?;
    if kicked {
        kick_reverse(stepper, hb, stage, rev)?;
    }
    model.apply_mass(&rev.cot.pbar, &mut hb.s);
    Ok(())
}

/// Entry r of ∇(ν·F̃_k) after [`stage_vjp`] of stage k: the chart's reverse at k (m̄ = M p̂̄),
/// φ̄ᵢ = tᵢ·q̄ᵢ − ωᵢ qᵢ·m̄ᵢ, ω̄ᵢ = tᵢ·m̄ᵢ, and ū for r = 2n.
pub(crate) fn gradient_entry<D: Scalar>(
    hb: &VjpBuffers<D>,
    rev: &Reverse<'_, D>,
    k: usize,
    r: usize,
) -> D {
    let n = hb.q0.len();
    if r == 2 * n {
        return rev.cot.ubar[k];
    }
    let i = r % n;
    let (q, mbar) = (&hb.q0[i], &hb.s[i]);
    let t = tangent(q);
    if r < n {
        dot2(&t, &rev.cot.qbar[i]) - hb.omega0[i] * dot2(q, mbar)
    } else {
        dot2(&t, mbar)
    }
}

/// The stage's forward step, recording q_k, the post-kick p_k and the kick's multipliers
/// y = −u y_b (so that p_k = (p̂_k − (h/2) u b) − Ĝᵀ y (h/2)).
fn record_step<D: Scalar>(
    stepper: &mut Stepper<D>,
    hb: &mut VjpBuffers<D>,
    k: usize,
    u: D,
) -> Result<bool> {
    hb.q0.copy_from_slice(&stepper.state.q);
    let kicked = stepper.kick(k, u)?;
    hb.p0.copy_from_slice(&stepper.state.p);
    if kicked {
        for (y, yb) in hb.y.iter_mut().zip(stepper.proj.y()) {
            *y = -(u * *yb);
        }
    }
    stepper.rattle.prepare_force(&stepper.state, k, u)?;
    stepper.rattle.step(&mut stepper.state, k, u, D::zero())?;
    Ok(kicked)
}

/// Cotangents at k + 1 of ν·chart⁻¹(q′, p′): q̄′ᵢ = ν_φᵢ tᵢ/|qᵢ|² + ν_ωᵢ (w_z, −w_y),
/// p̄′ = M⁻¹ Σᵢ ν_ωᵢ tᵢ eᵢ, with w = M⁻¹p′.
fn chart_inverse_reverse<D: Scalar>(
    stepper: &Stepper<D>,
    hb: &mut VjpBuffers<D>,
    nu: &[f64],
    rev: &mut Reverse<'_, D>,
) {
    let st = &stepper.state;
    let ch = stepper.rattle.chain();
    let n = st.q.len();
    ch.apply_inverse_mass(&st.p, &mut hb.w);
    for i in 0..n {
        let q = &st.q[i];
        let t = tangent(q);
        let r2 = dot2(q, q);
        let (nf, nw) = (nu[i], nu[n + i]);
        let w = &hb.w[i];
        rev.cot.qbar[i] = [t[0] / r2 * nf + w[1] * nw, t[1] / r2 * nf - w[0] * nw];
        hb.s[i] = [t[0] * nw, t[1] * nw];
    }
    ch.apply_inverse_mass(&hb.s, &mut rev.cot.pbar);
}

/// The reverse of the half-kick: c̄ by the projection's reverse, p̂̄ = c̄, ū −= (h/2) b·c̄.
fn kick_reverse<D: Scalar>(
    stepper: &Stepper<D>,
    hb: &VjpBuffers<D>,
    stage: VjpStage<'_, D>,
    rev: &mut Reverse<'_, D>,
) -> Result<()> {
    let VjpStage { model, k, .. } = stage;
    let s = kick_view(hb);
    let cbar = rev.sweep.projection_reverse(k, &s, &mut rev.cot)?;
    let b = stepper.control_direction();
    let mut bc = D::zero();
    for (c, bi) in cbar.iter().zip(b) {
        bc += c[0] * bi[0] + c[1] * bi[1];
    }
    rev.cot.pbar.copy_from_slice(cbar);
    rev.cot.ubar[k] -= bc * (0.5 * model.h);
    Ok(())
}

impl HessianWorkspace {
    /// H_k = ∇²_{(ξ,u)} (ν·F̃_k) at x̂_k (column-major (2n + 1)², the control last, into
    /// `out.hess`), ∇(ν·F̃_k) = [A_k B_k]ᵀν (into `out.grad`), and A_k, B_k themselves (into
    /// `out.jac`, as [`JacobianWorkspace::jacobians`]: the forward dual step is the same), for
    /// the costate ν = ν_{k+1} (module docs). The point and the Newton start are those of
    /// `jacobians`.
    pub(super) fn second_order(
        &mut self,
        at: StageAt<'_>,
        nu: &[f64],
        rev: &mut Reverse<'_, Dv>,
        out: SecondOrderMut<'_>,
    ) -> Result<()> {
        let SecondOrderMut {
            hess,
            grad,
            mut jac,
        } = out;
        let (model, k) = (at.model, at.k);
        let nd = ndir(model.n);
        for cols in chunks(nd) {
            let [u, _] = self.jac.seed(&at, cols.clone());
            self.seed_rates(&at, cols.clone());
            let stage = VjpStage { model, k, u, nu };
            stage_vjp(&mut self.jac.stepper, &mut self.hb, stage, rev)?;
            for r in 0..nd {
                let e = gradient_entry(&self.hb, rev, k, r);
                grad[r] = e.re;
                for j in cols.clone() {
                    hess[j * nd + r] = eps(&e, j - cols.start);
                }
            }
            self.jac.read_columns(model, cols, &mut jac);
        }
        Ok(())
    }

    /// The rates ωᵢ at k with their seeds in the directions `cols` (for the chart's reverse).
    fn seed_rates(&mut self, at: &StageAt<'_>, cols: Range<usize>) {
        let (n, x) = (at.model.n, at.x);
        for i in 0..n {
            let j = n + i;
            self.hb.omega0[i] = if cols.contains(&j) {
                let mut e = [0.0; CHUNK];
                e[j - cols.start] = 1.0;
                DualSVec64::new(x.omega[i], num_dual::Derivative::some(e.into()))
            } else {
                Dv::from_re(x.omega[i])
            };
        }
    }
}

/// The state x_k of the reverse step's input: q_k, the post-kick p_k and the kick's
/// multipliers y (as both λ and μ; no half step).
fn kick_view<D: Scalar>(hb: &VjpBuffers<D>) -> StateView<'_, D, 2> {
    StateView {
        q: &hb.q0,
        p: &hb.p0,
        lambda: &hb.y,
        mu: &hb.y,
        tip: [D::zero(); 2],
        phalf: &[],
        w: &[],
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::catalogue;
    use crate::ocp::stage::fixture::point;
    use crate::ocp::stage::StagePoint;

    /// A chart point of stage k: ξ = (φ, ω), the control u and the Newton start λ.
    struct ChartPoint<'a> {
        k: usize,
        xi: Vec<f64>,
        u: f64,
        lambda: &'a [f64],
    }

    /// [A B]ᵀν from the dual-number stage Jacobians at the chart point.
    fn jacobian_gradient(
        model: &StageModel,
        ws: &mut JacobianWorkspace,
        at: ChartPoint<'_>,
        nu: &[f64],
    ) -> Vec<f64> {
        let ChartPoint { k, xi, u, lambda } = at;
        let xi = &xi[..];
        let n = model.n;
        let nx = 2 * n;
        let q: Vec<[f64; 2]> = (0..n).map(|i| [xi[i].cos(), xi[i].sin()]).collect();
        let v: Vec<[f64; 2]> = (0..n)
            .map(|i| {
                let t = tangent(&q[i]);
                [t[0] * xi[n + i], t[1] * xi[n + i]]
            })
            .collect();
        let mut p = vec![[0.0; 2]; n];
        model.apply_mass(&v, &mut p);
        let omega = &xi[n..];
        let (mut a, mut b) = (vec![0.0; nx * nx], vec![0.0; nx]);
        let x = StagePoint {
            q: &q,
            p: &p,
            omega,
            mu: lambda,
        };
        let at = StageAt {
            model,
            k,
            x,
            u,
            ux: 0.0,
        };
        let out = JacobiansMut {
            a: &mut a,
            b: &mut b,
        };
        ws.jacobians(at, out).unwrap();
        let mut g: Vec<f64> = (0..nx)
            .map(|j| (0..nx).map(|r| a[j * nx + r] * nu[r]).sum())
            .collect();
        g.push((0..nx).map(|r| b[r] * nu[r]).sum());
        g
    }

    /// The forward-over-reverse Hessian of ν·F̃_k against central differences (step 10⁻⁵) of
    /// its gradient [A_k B_k]ᵀν, the gradient taken from the dual-number stage Jacobians (an
    /// independent derivation: forward mode, no reverse step): agreement to 10⁻⁶ relative to
    /// the largest entry, and the forward-over-reverse gradient itself equal to [A B]ᵀν to
    /// 10⁻¹² (real parts of the same computation), and the pass's A_k, B_k bit for bit those of
    /// `jacobians`. At a stage without the control's half-kick
    /// (k = 0) and with it (k = 20), on the long-horizon scene (drag, a moving state).
    #[test]
    fn hessian_matches_differenced_jacobian_gradient() {
        let scene = catalogue::long_horizon();
        let chain = Chain::<f64, 2>::from_scene(&scene).unwrap();
        let model = StageModel::new(&chain, scene.time.step).unwrap();
        let n = model.n;
        let nd = ndir(n);
        let chain_dv = chain.lift::<Dv>();
        let mut ws = HessianWorkspace::new(&model).unwrap();
        let nu: Vec<f64> = (0..2 * n)
            .map(|i| ((i as f64 + 1.0) * 0.7).sin() * 10f64.powi(-((i % 3) as i32)))
            .collect();
        for k in [0, 20] {
            let pt = point(&model, k);
            let mut xi: Vec<f64> = pt.q.iter().map(|q| q[1].atan2(q[0])).collect();
            xi.extend_from_slice(&pt.omega);
            let x = StagePoint {
                q: &pt.q,
                p: &pt.p,
                omega: &pt.omega,
                mu: &pt.lambda,
            };
            let mut rev = Reverse::new(&chain_dv, &model, 40);
            let (mut h, mut g) = (vec![0.0; nd * nd], vec![0.0; nd]);
            let nx = 2 * n;
            let (mut a, mut b) = (vec![0.0; nx * nx], vec![0.0; nx]);
            let at = StageAt {
                model: &model,
                k,
                x,
                u: pt.u,
                ux: 0.0,
            };
            let out = SecondOrderMut {
                hess: &mut h,
                grad: &mut g,
                jac: JacobiansMut {
                    a: &mut a,
                    b: &mut b,
                },
            };
            ws.second_order(at, &nu, &mut rev, out).unwrap();
            // The Jacobians of the same pass are those of `jacobians` (the same dual step).
            let (mut a2, mut b2) = (vec![0.0; nx * nx], vec![0.0; nx]);
            let out2 = JacobiansMut {
                a: &mut a2,
                b: &mut b2,
            };
            ws.jac.jacobians(at, out2).unwrap();
            assert!(
                a == a2 && b == b2,
                "k = {k}: the pass's A, B differ from jacobians'"
            );
            let chart = |xi: &'_ [f64], u| ChartPoint {
                k,
                xi: xi.to_vec(),
                u,
                lambda: &pt.lambda,
            };
            let g_fwd = jacobian_gradient(&model, &mut ws.jac, chart(&xi, pt.u), &nu);
            let gs = g_fwd.iter().fold(0.0f64, |m, v| m.max(v.abs()));
            for (a, b) in g.iter().zip(&g_fwd) {
                assert!((a - b).abs() <= 1e-12 * gs, "k = {k}: gradient {a} vs {b}");
            }
            let hs = h.iter().fold(0.0f64, |m, v| m.max(v.abs()));
            let eps = 1e-5;
            for j in 0..nd {
                let mut shifted = |s: f64| {
                    let mut z = xi.clone();
                    let mut u = pt.u;
                    if j < 2 * n {
                        z[j] += s;
                    } else {
                        u += s;
                    }
                    jacobian_gradient(&model, &mut ws.jac, chart(&z, u), &nu)
                };
                let gp = shifted(eps);
                let gm = shifted(-eps);
                for r in 0..nd {
                    let fd = (gp[r] - gm[r]) / (2.0 * eps);
                    let an = h[j * nd + r];
                    assert!(
                        (fd - an).abs() <= 1e-6 * hs,
                        "k = {k}: H[{r}, {j}] = {an:e}, differences {fd:e} (scale {hs:e})"
                    );
                }
            }
            // Symmetric, as a Hessian.
            for j in 0..nd {
                for r in 0..j {
                    let (a, b) = (h[j * nd + r], h[r * nd + j]);
                    assert!((a - b).abs() <= 1e-10 * hs, "asymmetry {a} {b}");
                }
            }
        }
    }
}
