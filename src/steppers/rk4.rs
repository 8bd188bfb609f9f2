//! Projected RK4 for the constrained chain, generic over the scalar [`Scalar`] and the dimension,
//! for comparisons with RATTLE ([`super::rattle`]).
//!
//! The classical explicit Runge–Kutta method of order 4 on the index-1 formulation (the
//! constraints differentiated twice):
//! ```text
//! q̇ = v = M⁻¹ p,    ṗ = −f(q, p) − Ĝ(q)ᵀ λ,
//! Ĝ M⁻¹ Ĝᵀ λ = −Ĝ M⁻¹ f + (‖vᵢ‖²)ᵢ        (tip row: −L M⁻¹ f),
//! ```
//! f = U_q − F_D ([`Chain::potential_gradient`] and the drag term, eq. 2.4.4), the control at the
//! stage times t_k, t_k + h/2, t_k + h taken as u_k, (u_k + u_{k+1})/2, u_{k+1}. After every step
//! q is projected onto ĝ(q) = 0 along M⁻¹Ĝ(q̃)ᵀ (Newton from λ = 0, shared with SHAKE) and p onto
//! Ĝ M⁻¹ p = 0 (the linear projection of RATTLE). Neither symplectic nor symmetric: its energy
//! error drifts, and it is only conditionally stable (h ω ≲ 2.8). A step that blows up is
//! [`crate::Error::NonFinite`]; a folded joint at the new configuration is
//! [`crate::Error::Folded`]. The reaction-force tip is refused at construction.

use super::rattle::projection_solve;
use super::{
    check_finite, check_len, check_step, refuse_rattle_only, singular, total_force, PositionSolve,
    PositionStage, Stepper,
};
use crate::base::Scalar;
use crate::error::Result;
use crate::model::{Chain, Ctx};
use crate::steppers::rattle::{RattleOptions, StepStats};
use crate::tridiag::BorderedTridiag;

/// Projected RK4's state at t_k: (q_k, p_k) on the constraint manifold.
#[derive(Clone, Debug, PartialEq)]
pub struct Rk4State<D, const DIM: usize> {
    q: Vec<[D; DIM]>,
    p: Vec<[D; DIM]>,
}

impl<D: Scalar, const DIM: usize> Rk4State<D, DIM> {
    /// Attitudes q_k.
    pub fn q(&self) -> &[[D; DIM]] {
        &self.q
    }

    /// Momenta p_k.
    pub fn p(&self) -> &[[D; DIM]] {
        &self.p
    }
}

/// Buffers of one evaluation of the index-1 right-hand side (and of the final projection).
#[derive(Clone, Debug)]
struct Rhs<D, const DIM: usize> {
    force: Vec<[D; DIM]>,
    minv_f: Vec<[D; DIM]>,
    rhs: Vec<D>,
    scal: Vec<D>,
    tri: BorderedTridiag<D>,
}

impl<D: Scalar, const DIM: usize> Rhs<D, DIM> {
    /// (q̇, ṗ) of the index-1 equations at (q, p; ctx) into `out`.
    fn eval(
        &mut self,
        ch: &Chain<D, DIM>,
        (q, p): (&[[D; DIM]], &[[D; DIM]]),
        ctx: &Ctx<D>,
        (qdot, pdot): (&mut [[D; DIM]], &mut [[D; DIM]]),
    ) -> Result<()> {
        let ops = ch.constraints();
        total_force(ch, (q, p), ctx, &mut self.force, &mut self.minv_f)?;
        ch.apply_inverse_mass(p, qdot);
        ch.apply_inverse_mass(&self.force, &mut self.minv_f);
        // r = −Ĝ M⁻¹ f + (‖vᵢ‖²)ᵢ (no velocity term in the tip row: l is linear)
        ops.apply(q, &self.minv_f, &mut self.rhs);
        for (r, v) in self.rhs.iter_mut().zip(qdot.iter()) {
            *r = -*r;
            for d in 0..DIM {
                *r += v[d] * v[d];
            }
        }
        if ops.bordered() {
            let n = ch.n();
            self.rhs[n] = -self.rhs[n];
        }
        // assemble_newton with q′ = q and h = √2 assembles −Ĝ M⁻¹ Ĝᵀ, so the solve gives −λ.
        let sqrt2 = std::f64::consts::SQRT_2;
        ops.assemble_newton((q, q), None, sqrt2, &mut self.tri, &mut self.scal);
        self.tri
            .solve(&mut self.rhs)
            .map_err(|zp| singular(ctx.step, zp))?;
        // ṗ = −f − Ĝᵀλ = −f + Ĝᵀ(−λ)
        for (pd, f) in pdot.iter_mut().zip(&self.force) {
            *pd = f.map(|x| -x);
        }
        ops.add_transpose(q, &self.rhs, D::one(), pdot);
        Ok(())
    }
}

/// The stage point (q, p) + c (k_q, k_p) into `out`.
fn stage_point<D: Scalar, const DIM: usize>(
    (qs, ps): (&mut [[D; DIM]], &mut [[D; DIM]]),
    (q, p): (&[[D; DIM]], &[[D; DIM]]),
    (dq, dp): (&[[D; DIM]], &[[D; DIM]]),
    c: f64,
) {
    for i in 0..q.len() {
        for d in 0..DIM {
            qs[i][d] = q[i][d] + dq[i][d] * c;
            ps[i][d] = p[i][d] + dp[i][d] * c;
        }
    }
}

/// Per-step buffers, allocated once.
#[derive(Clone, Debug)]
struct Workspace<D, const DIM: usize> {
    /// Stage slopes (k_q, k_p) of the four stages.
    kq: [Vec<[D; DIM]>; 4],
    kp: [Vec<[D; DIM]>; 4],
    /// Stage point, then the unprojected result (q̃, p̃).
    qs: Vec<[D; DIM]>,
    ps: Vec<[D; DIM]>,
    lam: Vec<D>,
    rhs: Rhs<D, DIM>,
    solve: PositionSolve<D, DIM>,
}

/// Projected RK4 for a [`Chain`], with its workspace. `step` does not allocate.
#[derive(Clone, Debug)]
pub struct ProjectedRk4<D, const DIM: usize> {
    chain: Chain<D, DIM>,
    h: f64,
    ws: Workspace<D, DIM>,
}

impl<D: Scalar, const DIM: usize> ProjectedRk4<D, DIM> {
    /// Projected RK4 with step `h`; the position projection uses the Newton options of
    /// [`RattleOptions::default`].
    ///
    /// # Errors
    /// [`super::StepperError::StepNotPositive`] if `h` is not positive and finite,
    /// [`super::StepperError::ReactionTipUnsupported`] if the chain has the reaction-force tip
    /// (only RATTLE supports it).
    pub fn new(chain: Chain<D, DIM>, h: f64) -> Result<Self> {
        check_step(h)?;
        refuse_rattle_only(&chain, "projected RK4")?;
        let n = chain.n();
        let v = vec![[D::zero(); DIM]; n];
        let ws = Workspace {
            kq: std::array::from_fn(|_| v.clone()),
            kp: std::array::from_fn(|_| v.clone()),
            qs: v.clone(),
            ps: v.clone(),
            lam: vec![D::zero(); chain.n_constraints()],
            rhs: Rhs {
                force: v.clone(),
                minv_f: v,
                rhs: vec![D::zero(); chain.n_constraints()],
                scal: vec![D::zero(); n],
                tri: BorderedTridiag::new(n, chain.has_tip_constraint()),
            },
            solve: PositionSolve::new(&chain, RattleOptions::default(), h),
        };
        Ok(ProjectedRk4 { chain, h, ws })
    }

    /// Replaces the Newton options of the position projection.
    pub fn with_options(mut self, options: RattleOptions) -> Self {
        self.ws.solve.set_options(options);
        self
    }

    /// The four stages and their combination (q̃, p̃) into `ws.qs`, `ws.ps`.
    fn stages(&mut self, state: &Rk4State<D, DIM>, k: usize, u: [D; 2]) -> Result<()> {
        let (n, h) = (self.chain.n(), self.h);
        let t = k as f64 * h;
        let u_mid = (u[0] + u[1]) * 0.5;
        let ch = &self.chain;
        let ws = &mut self.ws;
        let base = (&state.q[..], &state.p[..]);
        let [kq1, kq2, kq3, kq4] = &mut ws.kq;
        let [kp1, kp2, kp3, kp4] = &mut ws.kp;
        let (qs, ps) = (&mut ws.qs, &mut ws.ps);
        ws.rhs.eval(ch, base, &Ctx::new(t, u[0], k), (kq1, kp1))?;
        stage_point((qs, ps), base, (kq1, kp1), 0.5 * h);
        let ctx = Ctx::new(t + 0.5 * h, u_mid, k);
        ws.rhs.eval(ch, (qs, ps), &ctx, (kq2, kp2))?;
        stage_point((qs, ps), base, (kq2, kp2), 0.5 * h);
        ws.rhs.eval(ch, (qs, ps), &ctx, (kq3, kp3))?;
        stage_point((qs, ps), base, (kq3, kp3), h);
        ws.rhs
            .eval(ch, (qs, ps), &Ctx::new(t + h, u[1], k), (kq4, kp4))?;
        let [kq1, kq2, kq3, kq4] = &ws.kq;
        let [kp1, kp2, kp3, kp4] = &ws.kp;
        let w = h / 6.0;
        for i in 0..n {
            for d in 0..DIM {
                let sq = kq1[i][d] + kq2[i][d] * 2.0 + kq3[i][d] * 2.0 + kq4[i][d];
                let sp = kp1[i][d] + kp2[i][d] * 2.0 + kp3[i][d] * 2.0 + kp4[i][d];
                ws.qs[i][d] = state.q[i][d] + sq * w;
                ws.ps[i][d] = state.p[i][d] + sp * w;
            }
        }
        Ok(())
    }
}

impl<D: Scalar, const DIM: usize> Stepper<D, DIM> for ProjectedRk4<D, DIM> {
    type State = Rk4State<D, DIM>;

    fn chain(&self) -> &Chain<D, DIM> {
        &self.chain
    }

    fn h(&self) -> f64 {
        self.h
    }

    /// The start at rest ([`Chain::start_attitudes`]: straight, or the static start; u_0 is
    /// first used by the first step).
    fn initial_state(&mut self, _u_0: D) -> Result<Rk4State<D, DIM>> {
        let n = self.chain.n();
        Ok(Rk4State {
            q: self.chain.start_attitudes()?,
            p: vec![[D::zero(); DIM]; n],
        })
    }

    /// One RK4 step, then the projections of q (Newton, reported in the statistics) and p.
    ///
    /// # Errors
    /// [`crate::Error::NonFinite`] when the explicit step blows up, [`crate::Error::Folded`],
    /// [`crate::Error::NewtonNotConverged`] (projection), [`crate::Error::SingularSystem`], and
    /// [`super::StepperError::StateSize`] for a state of another chain's size. After an error q
    /// may already be q_{k+1} while p is still p_k: restart from a stored state.
    fn step(
        &mut self,
        state: &mut Rk4State<D, DIM>,
        k: usize,
        u_k: D,
        u_k1: D,
    ) -> Result<StepStats> {
        check_len(&state.q, self.chain.n())?;
        self.stages(state, k, [u_k, u_k1])?;
        let t1 = k as f64 * self.h + self.h;
        let ch = &self.chain;
        let ws = &mut self.ws;
        check_finite(&ws.qs, &ws.ps, k + 1)?;
        // Project q onto ĝ = 0 along M⁻¹Ĝ(q̃)ᵀ, then p onto Ĝ M⁻¹ p = 0.
        ws.lam.iter_mut().for_each(|l| *l = D::zero());
        let (qs, lam) = (&ws.qs, &mut ws.lam);
        let stage = PositionStage {
            q_base: qs,
            a: qs,
            c: 1.0,
        };
        let stats = ws.solve.solve(ch, stage, lam, k + 1)?;
        state.q.copy_from_slice(&ws.solve.qnew);
        let r = &mut ws.rhs;
        projection_solve(
            ch,
            &state.q,
            &ws.ps,
            D::zero(),
            &mut r.minv_f,
            &mut r.tri,
            &mut r.rhs,
        )
        .map_err(|zp| singular(k + 1, zp))?;
        ch.constraints()
            .subtract_transpose(&ws.ps, &state.q, &r.rhs, &mut state.p);
        // A fold is an error, not garbage: check the joint angles of the new configuration.
        ch.potential_gradient(&state.q, t1, u_k1, k + 1, &mut r.force)?;
        Ok(stats)
    }

    fn q<'s>(&self, state: &'s Rk4State<D, DIM>) -> &'s [[D; DIM]] {
        &state.q
    }

    fn p<'s>(&self, state: &'s Rk4State<D, DIM>) -> &'s [[D; DIM]] {
        &state.p
    }
}
