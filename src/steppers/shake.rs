//! SHAKE (thesis §1.6) for the constrained chain, generic over the scalar [`Scalar`] and the
//! dimension, for comparisons with RATTLE ([`super::rattle`]).
//!
//! The two-step recursion in the positions,
//! ```text
//! q_{k+1} − 2 q_k + q_{k−1} = −h² M⁻¹ (f(q_k, p̃_k) + Ĝ(q_k)ᵀ λ_k),      ĝ(q_{k+1}) = 0,
//! ```
//! with f = U_q − F_D ([`Chain::potential_gradient`] and the drag term, eq. 2.4.4) and the
//! momentum recovered by central differences, p_k = M (q_{k+1} − q_{k−1}) / 2h (not projected onto
//! the hidden constraint Ĝ M⁻¹ p = 0). It is started by one RATTLE-type half step from the straight beam at rest,
//! q_1 = q_0 + h M⁻¹ p_0 − h²/2 M⁻¹ (f(q_0, p_0) + Ĝ(q_0)ᵀ λ), ĝ(q_1) = 0.
//!
//! Without drag its positions are those of RATTLE up to round-off (the two methods are equivalent
//! in q); its momenta are not, so its energy error is larger. With drag, the drag force at t_k is
//! evaluated at the momentum extrapolated from the two previous half-step momenta,
//! p̃_k = p_{k−½} + (p_{k−½} − p_{k−3/2})/2 with p_{k−½} = M (q_k − q_{k−1}) / h (second order,
//! explicit).
//!
//! Each step solves ĝ(q_{k+1}(λ)) = 0 by the Newton routine shared with projected RK4, predictor
//! λ of the previous step. The reaction-force tip is refused at construction.

use super::{
    check_finite, check_len, check_step, refuse_rattle_only, total_force, PositionSolve,
    PositionStage, Stepper,
};
use crate::base::Scalar;
use crate::error::Result;
use crate::model::{Chain, Ctx};
use crate::steppers::rattle::{RattleOptions, StepStats};

/// SHAKE's state at t_k: the reported (q_k, p_k) and what the recursion carries forward. SHAKE
/// runs one configuration ahead of the reported state.
#[derive(Clone, Debug, PartialEq)]
pub struct ShakeState<D, const DIM: usize> {
    /// q_k.
    q: Vec<[D; DIM]>,
    /// p_k = M (q_{k+1} − q_{k−1}) / 2h (p_0 = 0).
    p: Vec<[D; DIM]>,
    /// q_{k+1}.
    next: Vec<[D; DIM]>,
    /// p_{k−½} = M (q_k − q_{k−1}) / h (for the drag extrapolation; p_½ at k = 0).
    phalf_prev: Vec<[D; DIM]>,
    /// λ of the last solve (the next Newton predictor).
    lam: Vec<D>,
}

impl<D: Scalar, const DIM: usize> ShakeState<D, DIM> {
    /// Attitudes q_k.
    pub fn q(&self) -> &[[D; DIM]] {
        &self.q
    }

    /// Momenta p_k (central differences).
    pub fn p(&self) -> &[[D; DIM]] {
        &self.p
    }

    /// The configuration q_{k+1} already computed.
    pub fn next_q(&self) -> &[[D; DIM]] {
        &self.next
    }
}

/// Per-step buffers, allocated once.
#[derive(Clone, Debug)]
struct Workspace<D, const DIM: usize> {
    force: Vec<[D; DIM]>,
    /// M⁻¹ f, and then M⁻¹ p_0 in the starter.
    minv_f: Vec<[D; DIM]>,
    /// Velocities (difference quotients) before M is applied.
    vel: Vec<[D; DIM]>,
    a: Vec<[D; DIM]>,
    phalf: Vec<[D; DIM]>,
    /// The momentum the drag is evaluated at.
    pd: Vec<[D; DIM]>,
    solve: PositionSolve<D, DIM>,
}

/// SHAKE for a [`Chain`], with its workspace. `step` does not allocate.
#[derive(Clone, Debug)]
pub struct Shake<D, const DIM: usize> {
    chain: Chain<D, DIM>,
    h: f64,
    ws: Workspace<D, DIM>,
}

impl<D: Scalar, const DIM: usize> Shake<D, DIM> {
    /// SHAKE with step `h` and the Newton options of [`RattleOptions::default`].
    ///
    /// # Errors
    /// [`super::StepperError::StepNotPositive`] if `h` is not positive and finite,
    /// [`super::StepperError::ReactionTipUnsupported`] if the chain has the reaction-force tip
    /// (only RATTLE supports it).
    pub fn new(chain: Chain<D, DIM>, h: f64) -> Result<Self> {
        check_step(h)?;
        refuse_rattle_only(&chain, "SHAKE")?;
        let v = vec![[D::zero(); DIM]; chain.n()];
        let ws = Workspace {
            force: v.clone(),
            minv_f: v.clone(),
            vel: v.clone(),
            a: v.clone(),
            phalf: v.clone(),
            pd: v,
            solve: PositionSolve::new(&chain, RattleOptions::default(), h),
        };
        Ok(Shake { chain, h, ws })
    }

    /// Replaces the Newton options (tolerance on the constraint residual, iteration limit).
    pub fn with_options(mut self, options: RattleOptions) -> Self {
        self.ws.solve.set_options(options);
        self
    }

    /// The next configuration from the unconstrained update in `ws.a`: Newton for λ (predictor
    /// `lam`) with constraint forces −c M⁻¹ Ĝ(q_b)ᵀ λ; the solution is left in `ws.solve.qnew`.
    fn constrain(
        &mut self,
        q_base: &[[D; DIM]],
        c: f64,
        lam: &mut [D],
        step: usize,
    ) -> Result<StepStats> {
        let ws = &mut self.ws;
        let a = &ws.a;
        let stage = PositionStage { q_base, a, c };
        ws.solve.solve(&self.chain, stage, lam, step)
    }
}

impl<D: Scalar, const DIM: usize> Stepper<D, DIM> for Shake<D, DIM> {
    type State = ShakeState<D, DIM>;

    fn chain(&self) -> &Chain<D, DIM> {
        &self.chain
    }

    fn h(&self) -> f64 {
        self.h
    }

    /// The start at rest ([`Chain::start_attitudes`]: straight, or the static start), and
    /// SHAKE's starter for q_1 with the force at (q_0, u_0).
    fn initial_state(&mut self, u_0: D) -> Result<ShakeState<D, DIM>> {
        let (n, h) = (self.chain.n(), self.h);
        let mut s = ShakeState {
            q: self.chain.start_attitudes()?,
            p: vec![[D::zero(); DIM]; n],
            next: vec![[D::zero(); DIM]; n],
            phalf_prev: vec![[D::zero(); DIM]; n],
            lam: vec![D::zero(); self.chain.n_constraints()],
        };
        let ch = &self.chain;
        let ws = &mut self.ws;
        let ctx = Ctx::new(0.0, u_0, 0);
        total_force(ch, (&s.q, &s.p), &ctx, &mut ws.force, &mut ws.minv_f)?;
        // a = q_0 + h M⁻¹ p_0 − h²/2 M⁻¹ f_0
        ch.apply_inverse_mass(&s.p, &mut ws.vel);
        ch.apply_inverse_mass(&ws.force, &mut ws.minv_f);
        for i in 0..n {
            for d in 0..DIM {
                ws.a[i][d] = s.q[i][d] + ws.vel[i][d] * h - ws.minv_f[i][d] * (0.5 * h * h);
            }
        }
        self.constrain(&s.q, 0.5 * h * h, &mut s.lam, 0)?;
        let ws = &mut self.ws;
        s.next.copy_from_slice(&ws.solve.qnew);
        // p_½ = M (q_1 − q_0) / h, for the drag extrapolation
        for i in 0..n {
            for d in 0..DIM {
                ws.vel[i][d] = (s.next[i][d] - s.q[i][d]) / h;
            }
        }
        self.chain.apply_mass(&ws.vel, &mut s.phalf_prev);
        Ok(s)
    }

    /// From (q_k, q_{k+1}) to (q_{k+1}, q_{k+2}): the force at q_{k+1} with u_{k+1} (`u_k` is
    /// not used: the starter has applied u_0), Newton for q_{k+2}, and
    /// p_{k+1} = M (q_{k+2} − q_k) / 2h.
    ///
    /// # Errors
    /// [`crate::Error::Folded`], [`crate::Error::NewtonNotConverged`],
    /// [`crate::Error::SingularSystem`], [`crate::Error::NonFinite`] (at step k + 1), and
    /// [`super::StepperError::StateSize`] for a state of another chain's size. After an error q_k,
    /// p_k and q_{k+1} are unchanged (the Newton predictor λ may not be).
    fn step(
        &mut self,
        state: &mut ShakeState<D, DIM>,
        k: usize,
        _u_k: D,
        u_k1: D,
    ) -> Result<StepStats> {
        let (n, h) = (self.chain.n(), self.h);
        check_len(&state.q, n)?;
        let k1 = k + 1;
        let ch = &self.chain;
        let ws = &mut self.ws;
        // p_{k+½} = M (q_{k+1} − q_k) / h
        for i in 0..n {
            for d in 0..DIM {
                ws.vel[i][d] = (state.next[i][d] - state.q[i][d]) / h;
            }
        }
        ch.apply_mass(&ws.vel, &mut ws.phalf);
        // drag momentum at t_{k+1}: extrapolated p_{k+½} + (p_{k+½} − p_{k−½})/2
        ws.pd.copy_from_slice(&ws.phalf);
        if ch.has_dissipation() {
            for i in 0..n {
                for d in 0..DIM {
                    ws.pd[i][d] += (ws.phalf[i][d] - state.phalf_prev[i][d]) * 0.5;
                }
            }
        }
        let ctx = Ctx::new(k1 as f64 * h, u_k1, k1);
        total_force(
            ch,
            (&state.next, &ws.pd),
            &ctx,
            &mut ws.force,
            &mut ws.minv_f,
        )?;
        ch.apply_inverse_mass(&ws.force, &mut ws.minv_f);
        // a = 2 q_{k+1} − q_k − h² M⁻¹ f
        for i in 0..n {
            for d in 0..DIM {
                ws.a[i][d] = state.next[i][d] * 2.0 - state.q[i][d] - ws.minv_f[i][d] * (h * h);
            }
        }
        let stats = self.constrain(&state.next, h * h, &mut state.lam, k1)?;
        let ws = &mut self.ws;
        // p_{k+1} = M (q_{k+2} − q_k) / 2h
        for i in 0..n {
            for d in 0..DIM {
                ws.vel[i][d] = (ws.solve.qnew[i][d] - state.q[i][d]) / (2.0 * h);
            }
        }
        check_finite(&ws.solve.qnew, &ws.vel, k1)?;
        self.chain.apply_mass(&ws.vel, &mut state.p);
        // rotate: q ← q_{k+1}, next ← q_{k+2}, p_{k−½} ← p_{k+½}
        std::mem::swap(&mut state.q, &mut state.next);
        std::mem::swap(&mut state.next, &mut ws.solve.qnew);
        std::mem::swap(&mut state.phalf_prev, &mut ws.phalf);
        Ok(stats)
    }

    fn q<'s>(&self, state: &'s ShakeState<D, DIM>) -> &'s [[D; DIM]] {
        &state.q
    }

    fn p<'s>(&self, state: &'s ShakeState<D, DIM>) -> &'s [[D; DIM]] {
        &state.p
    }
}
