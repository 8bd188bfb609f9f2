//! Time steppers for the constrained chain, all generic over the scalar and the dimension, each
//! owning its workspace (no allocation per step) and its own state type, so that a state of one
//! method cannot be passed to another.
//!
//! * [`rattle`]: RATTLE (thesis §1.6, eq. 1.6.1), symmetric, symplectic, order 2: the library's
//!   integrator, with the discrete adjoint of [`crate::adjoint`].
//! * [`shake`] and [`rk4`]: SHAKE and projected RK4, for speed-against-accuracy and stability
//!   comparisons ([`crate::integrators`]). They share the Newton solve of their implicit position
//!   stage and take every force from the model ([`Chain::potential_gradient`], the drag term).
//!
//! ```
//! use chainbeam::steppers::{Shake, Stepper};
//! use chainbeam::{catalogue, Chain};
//! // The spatial model of the thesis cantilever (F = 2 N at the tip), 10 SHAKE steps.
//! let chain = Chain::<f64, 3>::from_scene(&catalogue::thesis_cantilever())?;
//! let mut shake = Shake::new(chain, 0.01)?;
//! let mut state = shake.initial_state(0.0)?;
//! for k in 0..10 {
//!     shake.step(&mut state, k, 0.0, 0.0)?;
//! }
//! assert!(shake.q(&state)[9][2] < 0.0); // the tip load pushes toward −z
//! # Ok::<(), chainbeam::Error>(())
//! ```
//! A state of one method cannot be handed to another; this does not compile:
//! ```compile_fail,E0308
//! use chainbeam::steppers::{ProjectedRk4, Shake, Stepper};
//! use chainbeam::{catalogue, Chain};
//! let chain = Chain::<f64, 3>::from_scene(&catalogue::thesis_cantilever())?;
//! let mut shake = Shake::new(chain.clone(), 0.01)?;
//! let mut state = ProjectedRk4::new(chain, 0.01)?.initial_state(0.0)?;
//! for k in 0..10 {
//!     shake.step(&mut state, k, 0.0, 0.0)?;
//! }
//! # Ok::<(), chainbeam::Error>(())
//! ```

pub(crate) mod coupled;
mod fused;
pub mod rattle;
pub mod rk4;
pub mod shake;

use crate::base::{Scalar, TipCondition};
pub use crate::error::StepperError;
use crate::error::{Error, Result};
use crate::model::geometry::derivative_updates;
use crate::model::{Chain, Ctx};
use crate::tridiag::{BorderedTridiag, ZeroPivot};

pub use rattle::{Rattle, RattleOptions, StepStats};
pub use rk4::{ProjectedRk4, Rk4State};
pub use shake::{Shake, ShakeState};

/// One step map (q_k, p_k) → (q_{k+1}, p_{k+1}) of a constrained integrator.
pub trait Stepper<D: Scalar, const DIM: usize> {
    /// The method's state (its own type: states of different methods cannot be mixed up).
    type State;

    /// The model.
    fn chain(&self) -> &Chain<D, DIM>;

    /// The step h.
    fn h(&self) -> f64;

    /// The straight beam at rest at t = 0 with control u_0, ready to step.
    fn initial_state(&mut self, u_0: D) -> Result<Self::State>;

    /// Advances `state` from t_k to t_{k+1} with the controls u_k and u_{k+1}.
    fn step(&mut self, state: &mut Self::State, k: usize, u_k: D, u_k1: D) -> Result<StepStats>;

    /// The attitudes qᵢ of a state.
    fn q<'s>(&self, state: &'s Self::State) -> &'s [[D; DIM]];

    /// The momenta pᵢ of a state.
    fn p<'s>(&self, state: &'s Self::State) -> &'s [[D; DIM]];

    /// Makes `state`, a state of this method at t_k restored by the caller, the start of the
    /// next step with the control u_k: what a method carries from one step to the next besides
    /// the state (RATTLE: the force U_q(q_k; u_k)) is recomputed from it, so that a step
    /// re-taken from a stored state repeats bit for bit the step first taken from it. Methods
    /// that carry nothing keep this default.
    ///
    /// # Errors
    /// The force's errors.
    fn resume(&mut self, state: &Self::State, k: usize, u_k: D) -> Result<()> {
        let _ = (state, k, u_k);
        Ok(())
    }

    /// The control's half-kick at the attitudes of `state`: the part of a step's p_{k+1} that
    /// the control u_{k+1} = `u` contributes, −(h/2) P(q) u ∂U_q/∂u with the projection
    /// P(q) = I − Ĝᵀ(Ĝ M⁻¹ Ĝᵀ)⁻¹ Ĝ M⁻¹ (eq. 3.1.1's control direction), into `out` (n blocks).
    /// For a method whose step ends with such a kick (RATTLE: [`Rattle::control_half_kick`]).
    ///
    /// # Errors
    /// [`StepperError::ControlKickUnsupported`] for a method without one (the default); the
    /// method's own errors.
    fn control_kick(&mut self, state: &Self::State, u: D, out: &mut [[D; DIM]]) -> Result<()> {
        let _ = (state, u, out);
        Err(StepperError::ControlKickUnsupported {
            method: std::any::type_name::<Self>(),
        }
        .into())
    }
}

/// The typed error of a zero pivot met at step `step`.
pub(crate) fn singular(step: usize, zp: ZeroPivot) -> Error {
    Error::SingularSystem {
        step,
        index: zp.index,
        pivot: zp.pivot,
    }
}

/// Refuses the reaction-force tip ([`TipCondition::Reaction`], eq. 3.2.1) for a method that does
/// not implement its rheonomic tip constraint.
pub(crate) fn refuse_reaction_tip<D: Scalar, const DIM: usize>(
    chain: &Chain<D, DIM>,
    method: &'static str,
) -> Result<()> {
    if chain.tip_condition() == TipCondition::Reaction {
        return Err(StepperError::ReactionTipUnsupported { method }.into());
    }
    Ok(())
}

/// Refuses what only RATTLE implements: the tips whose constraint moves (the reaction-force tip
/// and the vessel's prescribed tip) and Morison's drag node by node.
pub(crate) fn refuse_rattle_only<D: Scalar, const DIM: usize>(
    chain: &Chain<D, DIM>,
    method: &'static str,
) -> Result<()> {
    refuse_reaction_tip(chain, method)?;
    if chain.tip_condition() == TipCondition::Prescribed {
        return Err(StepperError::PrescribedTipUnsupported { method }.into());
    }
    if chain.node_drag().is_some() {
        return Err(StepperError::NodeDragUnsupported { method }.into());
    }
    Ok(())
}

/// Checks that the step h is positive and finite.
pub(crate) fn check_step(h: f64) -> Result<()> {
    if !(h > 0.0 && h.is_finite()) {
        return Err(StepperError::StepNotPositive { h }.into());
    }
    Ok(())
}

/// Checks that a state passed to a stepper has the chain's n blocks.
pub(crate) fn check_len<T>(v: &[T], n: usize) -> Result<()> {
    if v.len() != n {
        return Err(StepperError::StateSize {
            got: v.len(),
            expected: n,
        }
        .into());
    }
    Ok(())
}

/// [`Error::NonFinite`] at `step` if a (real part of a) component of q or p is not finite.
pub(crate) fn check_finite<D: Scalar, const DIM: usize>(
    q: &[[D; DIM]],
    p: &[[D; DIM]],
    step: usize,
) -> Result<()> {
    if q.iter().chain(p).flatten().all(|x| x.re().is_finite()) {
        Ok(())
    } else {
        Err(Error::NonFinite {
            step,
            quantity: "the state (q, p)",
        })
    }
}

/// f(q, p) = U_q(q; t, u) − F_D(p) − F_J(q, M⁻¹p): the generalised force with the sign of U_q,
/// the conservative terms from [`Chain::potential_gradient`], the dissipative block terms (eq.
/// 2.4.4) from [`Chain::dissipative_force`] and the coupled ones (joint damping) from
/// [`Chain::coupled_force`], into `out`; `scratch` (n blocks) holds the velocities M⁻¹p. The ODE
/// is ṗ = −f − Ĝᵀλ.
pub(crate) fn total_force<D: Scalar, const DIM: usize>(
    ch: &Chain<D, DIM>,
    (q, p): (&[[D; DIM]], &[[D; DIM]]),
    ctx: &Ctx<D>,
    out: &mut [[D; DIM]],
    scratch: &mut [[D; DIM]],
) -> Result<()> {
    ch.potential_gradient(q, ctx.t, ctx.u, ctx.step, out)?;
    if ch.has_dissipation() {
        for (i, (o, pi)) in out.iter_mut().zip(p).enumerate() {
            if let Some(f) = ch.dissipative_force(i, pi, ctx) {
                for d in 0..DIM {
                    o[d] -= f[d];
                }
            }
        }
    }
    if ch.has_coupled_dissipation() {
        // out −= F_J(q, M⁻¹p): F_J is linear in the velocities, so F_J(q, −v) = −F_J(q, v).
        ch.apply_inverse_mass(p, scratch);
        scratch.iter_mut().flatten().for_each(|x| *x = -*x);
        ch.coupled_force(q, scratch, ctx, out);
    }
    Ok(())
}

/// The Newton solve of the implicit position stage shared by SHAKE and projected RK4:
/// ĝ(q′(λ)) = 0 for q′(λ) = a − c M⁻¹ Ĝ(q_b)ᵀ λ, with the Jacobian −c Ĝ(q′) M⁻¹ Ĝ(q_b)ᵀ
/// assembled O(n) by [`crate::constraints::ConstraintOperator::assemble_newton`] (with
/// h = √(2c)) and solved by [`BorderedTridiag`]. Sized once; [`PositionSolve::solve`] does not
/// allocate.
///
/// As in RATTLE, when `D` carries derivatives, `D::NDERIV` more updates with their real parts
/// removed follow the real part's convergence: the derivative parts become those of the implicit
/// function and the real parts stay bit for bit those of the `f64` run.
#[derive(Clone, Debug)]
pub(crate) struct PositionSolve<D, const DIM: usize> {
    options: RattleOptions,
    h: f64,
    /// Ĝ(q_b)ᵀ λ.
    gt: Vec<[D; DIM]>,
    /// M⁻¹ Ĝ(q_b)ᵀ λ.
    minv_gt: Vec<[D; DIM]>,
    /// The solution q′ once converged.
    pub(crate) qnew: Vec<[D; DIM]>,
    rhs: Vec<D>,
    scal: Vec<D>,
    tri: BorderedTridiag<D>,
}

/// The data of one [`PositionSolve::solve`]: q′(λ) = a − c M⁻¹ Ĝ(q_b)ᵀ λ.
pub(crate) struct PositionStage<'a, D, const DIM: usize> {
    /// q_b, the configuration the constraint forces act at.
    pub q_base: &'a [[D; DIM]],
    /// a, the unconstrained update.
    pub a: &'a [[D; DIM]],
    /// c, the scale of the constraint forces (h² for SHAKE, 1 for a projection).
    pub c: f64,
}

impl<D: Scalar, const DIM: usize> PositionSolve<D, DIM> {
    /// Buffers for `chain`, with the Newton options and the step h (for error reports).
    pub(crate) fn new(chain: &Chain<D, DIM>, options: RattleOptions, h: f64) -> Self {
        let n = chain.n();
        let nc = chain.n_constraints();
        let v = vec![[D::zero(); DIM]; n];
        PositionSolve {
            options,
            h,
            gt: v.clone(),
            minv_gt: v.clone(),
            qnew: v,
            rhs: vec![D::zero(); nc],
            scal: vec![D::zero(); n],
            tri: BorderedTridiag::new(n, chain.has_tip_constraint()),
        }
    }

    /// Replaces the Newton options.
    pub(crate) fn set_options(&mut self, options: RattleOptions) {
        self.options = options;
    }

    /// Solves the stage for λ from the predictor in `lam` (overwritten by the solution), leaving
    /// q′ in `self.qnew`. Returns the linear solves and the final residual (max-norm, tip row
    /// scaled by the beam length).
    ///
    /// # Errors
    /// [`Error::NonFinite`], [`Error::NewtonNotConverged`], [`Error::SingularSystem`], all at
    /// `step` (time `step`·h).
    pub(crate) fn solve(
        &mut self,
        ch: &Chain<D, DIM>,
        stage: PositionStage<'_, D, DIM>,
        lam: &mut [D],
        step: usize,
    ) -> Result<StepStats> {
        let PositionStage { q_base, a, c } = stage;
        let ops = ch.constraints();
        let h_eff = (2.0 * c).sqrt();
        let updates = derivative_updates::<D>();
        let mut extra_done = 0;
        let mut iterations = 0;
        loop {
            self.gt.iter_mut().for_each(|g| *g = [D::zero(); DIM]);
            ops.add_transpose(q_base, lam, D::one(), &mut self.gt);
            ch.apply_inverse_mass(&self.gt, &mut self.minv_gt);
            for (qn, (ai, mi)) in self.qnew.iter_mut().zip(a.iter().zip(&self.minv_gt)) {
                *qn = std::array::from_fn(|d| ai[d] - mi[d] * c);
            }
            let rmax = ops.residual(&self.qnew, D::zero(), &mut self.rhs);
            if !rmax.is_finite() {
                return Err(Error::NonFinite {
                    step,
                    quantity: "the positions of the Newton iterate",
                });
            }
            if rmax <= self.options.tolerance {
                if extra_done == updates {
                    return Ok(StepStats {
                        iterations,
                        residual: rmax,
                    });
                }
                extra_done += 1;
            }
            // (The derivative-only updates after convergence are allowed past the limit.)
            if iterations >= self.options.max_iterations && extra_done == 0 {
                return Err(Error::NewtonNotConverged {
                    step,
                    time: step as f64 * self.h,
                    residual: rmax,
                    iterations,
                    tolerance: self.options.tolerance,
                    h: Some(self.h),
                });
            }
            let pair = (q_base, &self.qnew[..]);
            ops.assemble_newton(pair, None, h_eff, &mut self.tri, &mut self.scal);
            self.tri
                .solve(&mut self.rhs)
                .map_err(|zp| singular(step, zp))?;
            for (l, r) in lam.iter_mut().zip(&self.rhs) {
                *l -= if extra_done > 0 { *r - r.re() } else { *r };
            }
            iterations += 1;
        }
    }
}
