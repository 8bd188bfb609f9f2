//! The RATTLE integrator (thesis §1.6, eq. 1.6.1; docs/conventions.md) for the constrained chain, generic over
//! the scalar [`Scalar`] and the dimension.
//!
//! One step (q_k, p_k) → (q_{k+1}, p_{k+1}) with controls u_k, u_{k+1}:
//! ```text
//! p_{k+½} = p_k − h/2 (U_q(q_k; u_k) + Ĝ(q_k)ᵀ λ_k) + h/2 F(p_{k+½})
//! q_{k+1} = q_k + h M⁻¹ p_{k+½},                 ĝ(q_{k+1}) = 0
//! p_{k+1} = p_{k+½} − h/2 (U_q(q_{k+1}; u_{k+1}) + Ĝ(q_{k+1})ᵀ μ_k) + h/2 F(p_{k+½})
//! 0       = Ĝ(q_{k+1}) M⁻¹ p_{k+1}
//! ```
//! ĝ stacks the length constraints gᵢ = ½(‖qᵢ‖² − 1) and, for locked tips, l(q) = Σ lᵢ e₃ᵀqᵢ.
//! F = Σ_T F_T is the sum of the dissipative terms (the drag F_D(p) = −D p ⊙ |p| of eq. 2.4.4 in the
//! planar model, [`crate::model::DissipativeTerm`]), evaluated at p_{k+½} in both halves
//! (docs/conventions.md); in the first half it is implicit, and each pendulum's block solves
//! p − (h/2) F(p) = c ([`Chain::dissipative_half_step`]: for the drag in closed form,
//! p = 2c / (1 + √(1 + 2hD|c|)) per planar component). The step calls the dissipative terms once
//! per half step for every block together ([`Chain::dissipative_half_steps`],
//! [`Chain::dissipative_half_kick`]), so that a term hoists what its blocks share out of the loop. A term that couples pendulums (the joint
//! damping) is read at (q_k, p_{k+½}) in the first half and (q_{k+1}, p_{k+½}) in the second, and
//! couples the half step's blocks and makes the Newton matrix below dense; both are solved in O(n)
//! as band systems (`steppers/coupled.rs`).
//!
//! **Newton solve for λ.** q_{k+1}(λ) is explicit, so Newton runs on ĝ(q_{k+1}(λ)) = 0 only. Its
//! Jacobian −h²/2 Ĝ(q_{k+1}) M⁻¹ W Ĝ(q_k)ᵀ (W = ∂p_{k+½}/∂c, the identity without drag) is
//! tridiagonal in the length constraints because M̄⁻¹ is, bordered by the tip row and column, and is
//! solved in O(n) by [`BorderedTridiag`]. The predictor is μ_{k−1}, the multiplier of the previous
//! projection (at step 0, the consistent multiplier of the initial state), which leaves Newton 1-2
//! iterations per step on the thesis scenes. On a chain with Morison's drag node by node the
//! predictor adds the quadratic extrapolation of the gaps γ_k = λ_k − μ_{k−1} of the last two
//! steps, λ⁰_{k+1} = μ_k + 2γ_k − γ_{k−1} ([`Multipliers::predictor`]): λ and μ each carry the
//! step's O(h) offset from the continuous multiplier, their gap varies smoothly, and the
//! extrapolation meets the tolerance without an update on about half the steps of a 3-hour
//! sea state of the 300 m riser system (0.515 updates per step against exactly 1 with μ_{k−1};
//! 16 % less CPU on that record: 7.9 s for 3 hours, docs/benchmarks.md). The gaps travel with the state
//! ([`Multipliers::gaps`]), so a step recomputed from a stored state (the adjoint's
//! checkpoints, the MPC plant's re-taken step) repeats its arithmetic bit for bit; the other
//! chains keep μ_{k−1} alone and every number of the thesis's scenes bit for bit. The tolerance
//! is the same 10⁻¹⁴ either way: only where Newton starts changes, so the results move at
//! round-off. When `D` carries derivatives, one more update is
//! applied after the real part has converged, with its real part removed: the derivative parts
//! (which Newton converges only linearly, at the rate of the residual) become exact, and the real
//! parts stay bit-for-bit those of the `f64` run. For first-order duals that update is the
//! implicit function theorem, and its matrix is assembled from real parts only (its derivative
//! parts would multiply the converged residual): the dual stage Jacobians of [`crate::ocp`]
//! cost 10 % less (`cargo bench --bench ocp -- rollout_jacobians_costate`).
//!
//! **Projection for (p_{k+1}, μ_k)** is linear with the symmetric tridiagonal (bordered) matrix
//! Ĝ(q_{k+1}) M⁻¹ Ĝ(q_{k+1})ᵀ.
//!
//! **Reaction-force tip** ([`crate::model::TipCondition::Reaction`], eq. 3.2.1/3.2.2, the type
//! [`crate::model::ReactionTip`]): the tip's z follows m_n ζ̈ = −u (the reaction cancels every other force on it), integrated by Störmer–Verlet
//! v_{k+½} = v_k − h/(2 m_n) u_k, ζ_{k+1} = ζ_k + h v_{k+½}, v_{k+1} = v_{k+½} − h/(2 m_n) u_{k+1},
//! and imposed as the rheonomic constraints l(q_{k+1}) = ζ_{k+1}, L M⁻¹ p_{k+1} = v_{k+1}. With
//! u = 0 this is exactly the locked beam. The control then needs no potential term: its force lies
//! along Lᵀ and would be absorbed by the tip multiplier.
//!
//! **Prescribed tip** ([`crate::model::TipCondition::Prescribed`], `support = "vessel"`): the
//! vessel's Z(t) and Ż(t) ([`crate::model::VesselMotion`]) take the place of ζ and v:
//! l(q_{k+1}) = Z(t_{k+1}) and L M⁻¹ p_{k+1} = Ż(t_{k+1}), both at the end of the step, where the
//! locked tip has 0. Each half of the step then stays the adjoint of the other under
//! k ↔ k + 1, h ↔ −h (the constraint of a position is read at that position's time), so the step
//! is symmetric and of order 2 (tests/model/riser_system.rs measures it); with Z ≡ 0 it is the fixed-fixed
//! step bit for bit.
//!
//! **The vessel under thrust** (`[vessel]` thrust keys, [`crate::model::ThrustDrive`]): the top
//! follows Z = P(t) + x_v with the vessel's surge x_v a state driven by the control (the thrust),
//! stepped by the same split as the reaction-force tip's target (with the vessel's linear
//! damping read at the half step); the state's target (Z, Ż) carries it, and the constraints
//! are those of the prescribed tip with Z_{k+1}, Ż_{k+1} from the drive.

pub use crate::base::StepStats;

use super::coupled::CoupledHalf;
use super::fused::{self, FusedScratch, Projected, Projection};
use super::{refuse_reaction_tip, singular, Stepper};
use crate::base::Scalar;
use crate::error::{Error, Result};
use crate::model::geometry::derivative_updates;
use crate::model::terms::{IterateInputs, IterateOutputs};
use crate::model::{e2, BlockSym, Chain, Ctx, HalfKick, HalfSteps};
use crate::tridiag::BorderedTridiag;

mod halves;

/// Whether the runs of `chain` keep the gaps γ_k = λ_k − μ_{k−1} for Newton's predictor
/// ([`Multipliers::gaps`]): the chains with Morison's drag node by node. Every other chain
/// predicts with μ_{k−1} alone, so that the thesis's scenes keep their numbers bit for bit.
pub(crate) fn keeps_gaps<D: Scalar, const DIM: usize>(chain: &Chain<D, DIM>) -> bool {
    chain.node_drag().is_some()
}

/// Newton settings of the RATTLE step.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RattleOptions {
    /// Convergence tolerance on the max-norm of the constraint residual ½(‖qᵢ‖² − 1) (the tip row
    /// is scaled by the beam length).
    pub tolerance: f64,
    /// Maximum Newton iterations per step.
    pub max_iterations: usize,
}

impl Default for RattleOptions {
    fn default() -> Self {
        RattleOptions {
            tolerance: 1e-14,
            max_iterations: 25,
        }
    }
}

/// The multipliers of one RATTLE step q_k → q_{k+1} (eq. 1.6.1): λ_k of the position constraint
/// and μ_k of the hidden (momentum) constraint, each of length n (+1 with a tip constraint).
#[derive(Clone, Debug, PartialEq)]
pub struct Multipliers<D> {
    /// λ_k.
    pub lambda: Vec<D>,
    /// μ_k (the next step's Newton predictor).
    pub mu: Vec<D>,
    /// The gaps of the last two steps between the position multiplier and the predictor it
    /// started from, [γ_k | γ_{k−1}] with γ_k = λ_k − μ_{k−1} (2 × the multipliers' length), that
    /// a chain with Morison's drag node by node extrapolates for its next predictor
    /// ([`Rattle::step`], "Newton solve for λ"); empty on every other chain, and on a state
    /// whose run kept no gaps (its next step then predicts with μ_k alone).
    pub gaps: Vec<D>,
}

impl<D: Scalar> Multipliers<D> {
    /// Newton's predictor for the next step's λ_{k+1} into `out`: μ_k, plus, when the gaps are
    /// kept, their quadratic extrapolation 2γ_k − γ_{k−1} (λ_{k+1} − μ_k changes smoothly along
    /// a run where λ and μ alone jump by O(h)).
    ///
    /// # Panics
    /// If `out` is not as long as μ_k (the chain's constraint count), as `copy_from_slice`.
    pub fn predictor(&self, out: &mut [D]) {
        out.copy_from_slice(&self.mu);
        let nc = self.mu.len();
        if self.gaps.len() == 2 * nc {
            let (g1, g2) = self.gaps.split_at(nc);
            for ((o, a), b) in out.iter_mut().zip(g1).zip(g2) {
                *o += *a * D::from(2.0) - *b;
            }
        }
    }

    /// Records the converged λ_{k+1} of a step whose predictor was based on μ_k (`mu_prev`, or
    /// with `None` these multipliers' own `mu`, which the step has not overwritten yet) and,
    /// when `keep_gaps`, its gap γ_{k+1} = λ_{k+1} − μ_k, shifting γ_k back (both set to it on
    /// the first record).
    pub(super) fn record(&mut self, lambda: &[D], mu_prev: Option<&[D]>, keep_gaps: bool) {
        let nc = lambda.len();
        if keep_gaps {
            let first = self.gaps.len() != 2 * nc;
            if first {
                self.gaps.clear();
                self.gaps.resize(2 * nc, D::zero());
            }
            let base = mu_prev.unwrap_or(&self.mu);
            let (g1, g2) = self.gaps.split_at_mut(nc);
            for (((a, b), l), m) in g1.iter_mut().zip(g2.iter_mut()).zip(lambda).zip(base) {
                let gap = *l - *m;
                *b = if first { gap } else { *a };
                *a = gap;
            }
        }
        self.lambda.copy_from_slice(lambda);
    }
}

/// The state at time t_k, with the multipliers of the step that produced it.
#[derive(Clone, Debug, PartialEq)]
pub struct State<D, const DIM: usize> {
    /// Attitudes qᵢ.
    pub q: Vec<[D; DIM]>,
    /// Conjugate momenta pᵢ.
    pub p: Vec<[D; DIM]>,
    /// The multipliers of the step that produced this state; `None` for an initial state, which
    /// no step produced (its first step then starts Newton from the consistent multiplier,
    /// [`Rattle::consistent_multiplier`]).
    pub multipliers: Option<Multipliers<D>>,
    /// Reaction-force variant: the tip target ζ_k and velocity v_k (zero otherwise).
    pub tip_target: [D; 2],
}

impl<D: Scalar, const DIM: usize> State<D, DIM> {
    /// The straight beam at rest, qᵢ = e₂, p = 0 (the initial state of every thesis scene).
    pub fn straight(n: usize) -> Self {
        State {
            q: vec![e2::<D, DIM>(); n],
            p: vec![[D::zero(); DIM]; n],
            multipliers: None,
            tip_target: [D::zero(); 2],
        }
    }

    /// The state the runs of `chain` start from at t = 0, at rest (p = 0): the straight beam, or
    /// the chain's static start (`[time] initial = "static"`, [`Chain::start_attitudes`], with
    /// its tip target [`Chain::start_tip_target`]).
    ///
    /// # Errors
    /// [`Chain::start_attitudes`]'s: a chain of a static scene without its start.
    pub fn start(chain: &Chain<D, DIM>) -> Result<Self> {
        Ok(State {
            q: chain.start_attitudes()?,
            p: vec![[D::zero(); DIM]; chain.n()],
            multipliers: None,
            tip_target: chain.start_tip_target(),
        })
    }

    /// The multipliers, created (zero) if the state has none yet: what a step writes into.
    /// Allocates only the first time.
    pub fn multipliers_mut(&mut self, n_constraints: usize) -> &mut Multipliers<D> {
        self.multipliers.get_or_insert_with(|| Multipliers {
            lambda: vec![D::zero(); n_constraints],
            mu: vec![D::zero(); n_constraints],
            gaps: Vec::new(),
        })
    }

    /// The same state in another scalar type (real parts only).
    pub fn lift<D2: Scalar>(&self) -> State<D2, DIM> {
        let v = |x: &[[D; DIM]]| {
            x.iter()
                .map(|a| std::array::from_fn(|d| D2::from(a[d].re())))
                .collect()
        };
        let s = |x: &[D]| x.iter().map(|a| D2::from(a.re())).collect();
        State {
            q: v(&self.q),
            p: v(&self.p),
            multipliers: self.multipliers.as_ref().map(|m| Multipliers {
                lambda: s(&m.lambda),
                mu: s(&m.mu),
                gaps: s(&m.gaps),
            }),
            tip_target: [
                D2::from(self.tip_target[0].re()),
                D2::from(self.tip_target[1].re()),
            ],
        }
    }
}

/// Scratch memory of a step, allocated once per chain.
#[derive(Clone, Debug)]
struct Workspace<D, const DIM: usize> {
    force: Vec<[D; DIM]>,
    a: Vec<[D; DIM]>,
    half: HalfStep<D, DIM>,
    qnew: Vec<[D; DIM]>,
    tmp: Vec<[D; DIM]>,
    lam: Vec<D>,
    /// The consistent multiplier of a state without multipliers (the first step's predictor).
    mu0: Vec<D>,
    /// Whether `mu0` belongs to the state being stepped.
    mu0_ready: bool,
    rhs: Vec<D>,
    scal: Vec<D>,
    tri: BorderedTridiag<D>,
    force_ready: bool,
    /// Real parts of q_k, q_{k+1} for the Newton matrix of the derivative-only update.
    real: [Vec<[D; DIM]>; 2],
    /// Real parts of W, likewise.
    real_w: Vec<BlockSym<D, DIM>>,
    /// The coupled half step of a model with coupled dissipative terms (joint damping).
    coupled: Option<CoupledHalf<D, DIM>>,
    /// The water's momentum P(t_k + h/2) of a model with Morison's drag node by node, read
    /// once per step ([`crate::model::NodeDrag::water_momenta`]); empty without that term.
    water: Vec<[D; DIM]>,
    /// The fused passes of the `f64` step with that term (`steppers::fused`,
    /// [`crate::model::NodeDrag::half_step_iterate`]); `None` for other models and scalars.
    fused: Option<FusedScratch<D>>,
}

/// RATTLE for a [`Chain`], with its workspace. `step` does not allocate.
#[derive(Clone, Debug)]
pub struct Rattle<D, const DIM: usize> {
    chain: Chain<D, DIM>,
    h: f64,
    t0: f64,
    options: RattleOptions,
    ws: Workspace<D, DIM>,
}

impl<D: Scalar, const DIM: usize> Rattle<D, DIM> {
    /// An integrator with step `h` (must be positive and finite).
    pub fn new(chain: Chain<D, DIM>, h: f64) -> Result<Self> {
        if !(h > 0.0 && h.is_finite()) {
            return Err(Error::InvalidStep { h });
        }
        let n = chain.n();
        let nc = chain.n_constraints();
        let v = vec![[D::zero(); DIM]; n];
        let ws = Workspace {
            force: v.clone(),
            a: v.clone(),
            half: HalfStep {
                c: v.clone(),
                phalf: v.clone(),
                w: vec![BlockSym::identity(); n],
            },
            qnew: v.clone(),
            tmp: v.clone(),
            lam: vec![D::zero(); nc],
            mu0: vec![D::zero(); nc],
            mu0_ready: false,
            rhs: vec![D::zero(); nc],
            scal: vec![D::zero(); n],
            tri: BorderedTridiag::new(n, chain.has_tip_constraint()),
            force_ready: false,
            real: [v.clone(), v.clone()],
            real_w: vec![BlockSym::identity(); n],
            coupled: chain
                .has_coupled_dissipation()
                .then(|| CoupledHalf::new(&chain)),
            water: if chain.node_drag().is_some() {
                v.clone()
            } else {
                Vec::new()
            },
            fused: (chain.node_drag().is_some()
                && !chain.has_coupled_dissipation()
                && D::NDERIV == 0)
                .then(|| FusedScratch::new(n, nc)),
        };
        Ok(Rattle {
            chain,
            h,
            t0: 0.0,
            options: RattleOptions::default(),
            ws,
        })
    }

    /// Replaces the Newton options.
    pub fn with_options(mut self, options: RattleOptions) -> Self {
        self.options = options;
        self
    }

    /// Sets the start time t₀: step k is taken at t_k = t₀ + k h (default t₀ = 0), so that a
    /// horizon starting from a state of a longer run sees the same time-dependent loads.
    pub fn with_start_time(mut self, t0: f64) -> Self {
        self.t0 = t0;
        self
    }

    /// Changes the start time t₀ in place ([`Rattle::with_start_time`]).
    pub fn set_start_time(&mut self, t0: f64) {
        self.t0 = t0;
    }

    /// t_k = t₀ + k h.
    #[inline]
    pub fn time(&self, k: usize) -> f64 {
        self.t0 + k as f64 * self.h
    }

    /// The model.
    pub fn chain(&self) -> &Chain<D, DIM> {
        &self.chain
    }

    /// Mutable access to the model (e.g. to seed a parameter); invalidates the cached force.
    pub fn chain_mut(&mut self) -> &mut Chain<D, DIM> {
        self.ws.force_ready = false;
        self.ws.mu0_ready = false;
        &mut self.chain
    }

    /// The step h.
    pub fn h(&self) -> f64 {
        self.h
    }

    /// The straight beam at rest.
    pub fn straight_state(&self) -> State<D, DIM> {
        State::straight(self.chain.n())
    }

    /// The state the chain's runs start from ([`State::start`]: the straight beam at rest, or
    /// the static start of `[time] initial = "static"`).
    ///
    /// # Errors
    /// [`State::start`]'s.
    pub fn start_state(&self) -> Result<State<D, DIM>> {
        State::start(&self.chain)
    }

    /// Prepares a step from `state` at step index `k` with control u_k: evaluates U_q(q_k; u_k)
    /// and, when `state` has no multipliers yet (an initial state), the consistent multiplier used
    /// as the Newton predictor ([`Rattle::consistent_multiplier`]). Called automatically by
    /// [`Rattle::step`] when needed.
    pub fn prepare(&mut self, state: &mut State<D, DIM>, k: usize, u_k: D) -> Result<()> {
        self.prepare_force(state, k, u_k)?;
        if state.multipliers.is_none() {
            self.solve_consistent_multiplier(state, k)?;
        }
        Ok(())
    }

    /// The consistent multiplier of the last prepared state without multipliers: the solution of
    /// Ĝ M⁻¹ Ĝᵀ μ = −Ĝ M⁻¹ U_q(q_k) (the multiplier that keeps Ĝ M⁻¹ p = 0 at rest), which the
    /// first step starts Newton from and [`crate::simulate()`] reports as λ_0 = μ_0.
    pub fn consistent_multiplier(&self) -> &[D] {
        &self.ws.mu0
    }

    /// Solves Ĝ M⁻¹ Ĝᵀ μ₀ = −Ĝ M⁻¹ U_q into the workspace (U_q must be prepared).
    fn solve_consistent_multiplier(&mut self, state: &State<D, DIM>, k: usize) -> Result<()> {
        let t = self.time(k);
        let ws = &mut self.ws;
        for (o, f) in ws.a.iter_mut().zip(ws.force.iter()) {
            *o = f.map(|x| -x);
        }
        // The tip's rate: the state's Ż_k for a vessel under thrust, the vessel's Ż(t_k) for a
        // prescribed tip, else 0 (at rest).
        let target = match (self.chain.thrust_drive(), self.chain.prescribed_tip(t)) {
            (Some(_), _) => state.tip_target[1],
            (None, Some([_, v])) => v,
            (None, None) => D::zero(),
        };
        let q = &state.q;
        projection_solve(
            &self.chain,
            q,
            &ws.a,
            target,
            &mut ws.tmp,
            &mut ws.tri,
            &mut ws.rhs,
        )
        .map_err(|zp| singular(k, zp))?;
        ws.mu0.copy_from_slice(&ws.rhs);
        ws.mu0_ready = true;
        Ok(())
    }

    /// Evaluates and caches U_q(q_k; u_k) for the next [`Rattle::step`] without touching the
    /// multipliers (the Newton predictor stays the state's μ), so that a step recomputed from a
    /// stored state repeats the original arithmetic bit for bit.
    pub fn prepare_force(&mut self, state: &State<D, DIM>, k: usize, u_k: D) -> Result<()> {
        let t = self.time(k);
        self.chain
            .potential_gradient(&state.q, t, u_k, k, &mut self.ws.force)?;
        self.ws.force_ready = true;
        self.ws.mu0_ready = false;
        Ok(())
    }

    /// The control's half-kick at q (the part of a step's second half-kick that the control
    /// u_{k+1} contributes, after the projection):
    /// `out` = −(h/2) P(q)(u ∂U_q/∂u + u_x ∂U_q/∂u_x), P(q) = I − Ĝᵀ(Ĝ M⁻¹ Ĝᵀ)⁻¹ Ĝ M⁻¹, so
    /// that a step's p_{k+1} is that of the same step taken with zero control in its second
    /// half-kick plus this (exactly in exact arithmetic: U_q is affine in the control and the
    /// projection linear). O(n), no allocation; the cached force and Newton predictor of the
    /// next step are untouched.
    ///
    /// # Errors
    /// [`StepperError::ReactionTipUnsupported`](super::StepperError::ReactionTipUnsupported) for the reaction-force tip, whose control
    /// drives the tip target (eq. 3.2.1) instead of acting as a force term;
    /// [`Error::SingularSystem`] (reported at step 0).
    pub fn control_half_kick(
        &mut self,
        q: &[[D; DIM]],
        (u, ux): (D, D),
        out: &mut [[D; DIM]],
    ) -> Result<()> {
        refuse_reaction_tip(&self.chain, "a control half-kick")?;
        if self.chain.thrust_drive().is_some() {
            return Err(super::StepperError::ThrustControlUnsupported {
                method: "a control half-kick",
            }
            .into());
        }
        let ws = &mut self.ws;
        self.chain.control_force(u, ux, &mut ws.a)?;
        projection_solve(
            &self.chain,
            q,
            &ws.a,
            D::zero(),
            &mut ws.tmp,
            &mut ws.tri,
            &mut ws.rhs,
        )
        .map_err(|zp| singular(0, zp))?;
        self.chain
            .constraints()
            .subtract_transpose(&ws.a, q, &ws.rhs, out);
        let hh = D::from(-0.5 * self.h);
        out.iter_mut().flatten().for_each(|x| *x *= hh);
        Ok(())
    }

    /// The half-step momentum p_{k+½} and W = ∂p_{k+½}/∂c of the last step (W = 1 without
    /// drag): what the adjoint records from the forward step ([`crate::adjoint`]).
    pub(crate) fn last_half_step(&self) -> (&[[D; DIM]], &[BlockSym<D, DIM>]) {
        (&self.ws.half.phalf, &self.ws.half.w)
    }

    /// Advances `state` from t_k to t_{k+1} with controls u_k (at t_k) and u_{k+1} (at t_{k+1}).
    ///
    /// The caller must pass the same u_k that the previous step received as its u_{k+1} (the force
    /// at q_k is cached between steps); use [`Rattle::prepare`] after changing the state by hand.
    ///
    /// # Errors
    /// [`Error::NewtonNotConverged`] (with the step and the residual), [`Error::Folded`] when a
    /// joint passes the fold limit, [`Error::SingularSystem`], [`Error::NonFinite`]. After an
    /// error `state` is not a valid state of the trajectory (it may hold q_{k+1} with p_k): restart
    /// from a stored state.
    pub fn step(
        &mut self,
        state: &mut State<D, DIM>,
        k: usize,
        u_k: D,
        u_k1: D,
    ) -> Result<StepStats> {
        if !self.ws.force_ready {
            self.prepare_force(state, k, u_k)?;
        }
        if state.multipliers.is_none() && !self.ws.mu0_ready {
            self.solve_consistent_multiplier(state, k)?;
        }
        let hh = 0.5 * self.h;
        // a = p_k − h/2 U_q(q_k; u_k)
        for (a, (p, f)) in self.ws.a.iter_mut().zip(state.p.iter().zip(&self.ws.force)) {
            *a = std::array::from_fn(|d| p[d] - f[d] * hh);
        }
        let (zeta_next, v_half) = self.tip_half_kick(state, k, u_k);
        if self.ws.coupled.is_some() {
            return self.coupled_halves(state, (k, u_k1), (v_half, zeta_next));
        }
        let stats = self.solve_positions::<false>(state, k, zeta_next)?;
        self.second_half::<false>(state, k, u_k1, v_half, zeta_next)?;
        Ok(stats)
    }

    /// The two halves of [`Rattle::step`] for a model with coupled dissipative terms (the joint
    /// damping, `steppers/coupled.rs`), out of line: the block path above is the instance
    /// `COUPLED = false` of the same code without any of the coupled path, so that it compiles
    /// to what it was before the coupled terms existed (inlined, the coupled path's code made
    /// `step` too large for LLVM to keep the current drag's force inlined in it: 10 % more
    /// instructions per step on `step_current`, docs/architecture.md "Benches").
    #[inline(never)]
    fn coupled_halves(
        &mut self,
        state: &mut State<D, DIM>,
        (k, u_k1): (usize, D),
        (v_half, zeta_next): (D, D),
    ) -> Result<StepStats> {
        let stats = self.solve_positions::<true>(state, k, zeta_next)?;
        self.second_half::<true>(state, k, u_k1, v_half, zeta_next)?;
        Ok(stats)
    }

    /// Tip target of the reaction-force variant (Störmer–Verlet for m_n ζ̈ = −u): (ζ_{k+1},
    /// v_{k+½}); of the vessel under thrust ([`crate::model::ThrustDrive`]): (Z_{k+1}, the
    /// vessel's v_{k+½}); of a prescribed tip: (Z(t_{k+1}), 0); zeros for other tips.
    fn tip_half_kick(&self, state: &State<D, DIM>, k: usize, u_k: D) -> (D, D) {
        if let Some(tip) = self.chain.reaction_tip() {
            return tip.first_half(state.tip_target, u_k, self.h);
        }
        let next = self.chain.prescribed_tip(self.time(k + 1));
        match (self.chain.thrust_drive(), next) {
            (Some(drive), Some([z1, _])) => {
                let now = self
                    .chain
                    .prescribed_tip(self.time(k))
                    .unwrap_or([D::zero(); 2]);
                drive.first_half(state.tip_target, (now, z1), u_k, self.h)
            }
            (None, Some([z, _])) => (z, D::zero()),
            _ => (D::zero(), D::zero()),
        }
    }

    /// [`Error::NewtonNotConverged`] of step k after `iterations` Newton iterations that left
    /// the residual max|ĝ| = `residual`.
    fn not_converged(&self, k: usize, residual: f64, iterations: usize) -> Error {
        Error::NewtonNotConverged {
            step: k,
            time: self.t0 + k as f64 * self.h,
            residual,
            iterations,
            tolerance: self.options.tolerance,
            h: Some(self.h),
        }
    }
}

impl<D: Scalar, const DIM: usize> Stepper<D, DIM> for Rattle<D, DIM> {
    type State = State<D, DIM>;

    fn chain(&self) -> &Chain<D, DIM> {
        &self.chain
    }

    fn h(&self) -> f64 {
        self.h
    }

    fn initial_state(&mut self, u_0: D) -> Result<State<D, DIM>> {
        let mut s = self.start_state()?;
        self.prepare(&mut s, 0, u_0)?;
        Ok(s)
    }

    fn step(&mut self, state: &mut State<D, DIM>, k: usize, u_k: D, u_k1: D) -> Result<StepStats> {
        Rattle::step(self, state, k, u_k, u_k1)
    }

    fn q<'s>(&self, state: &'s State<D, DIM>) -> &'s [[D; DIM]] {
        &state.q
    }

    fn p<'s>(&self, state: &'s State<D, DIM>) -> &'s [[D; DIM]] {
        &state.p
    }

    fn resume(&mut self, state: &State<D, DIM>, k: usize, u_k: D) -> Result<()> {
        self.prepare_force(state, k, u_k)
    }

    fn control_kick(&mut self, state: &State<D, DIM>, u: D, out: &mut [[D; DIM]]) -> Result<()> {
        self.control_half_kick(&state.q, (u, D::zero()), out)
    }
}

/// `out` = the real parts of `x` (no derivative parts).
fn real_parts<D: Scalar, const DIM: usize>(x: &[[D; DIM]], out: &mut [[D; DIM]]) {
    for (o, v) in out.iter_mut().zip(x) {
        *o = v.map(|c| D::from(c.re()));
    }
}

/// The first half-step's momenta: c = a − h/2 Ĝ(q_k)ᵀλ, p_{k+½} and W = ∂p_{k+½}/∂c.
#[derive(Clone, Debug)]
struct HalfStep<D, const DIM: usize> {
    c: Vec<[D; DIM]>,
    phalf: Vec<[D; DIM]>,
    w: Vec<BlockSym<D, DIM>>,
}

/// c = a − h/2 Ĝ(q_k)ᵀλ and p_{k+½} solving p − (h/2) Σ_T F_T(p) = c block by block
/// ([`Chain::dissipative_half_step`]; p = c without dissipative terms), with W = ∂p_{k+½}/∂c
/// (left at I without them); `water` is the node drag's P(t_k + h/2) (empty without it).
fn half_step_momentum<D: Scalar, const DIM: usize>(
    ch: &Chain<D, DIM>,
    q: &[[D; DIM]],
    (a, lam): (&[[D; DIM]], &[D]),
    (h, ctx, water): (f64, &Ctx<D>, &[[D; DIM]]),
    out: &mut HalfStep<D, DIM>,
) {
    out.c.copy_from_slice(a);
    ch.constraints()
        .add_transpose(q, lam, D::from(-0.5 * h), &mut out.c);
    if let Some(nd) = ch.node_drag() {
        let ls = (ch.lengths(), ch.inverse_lengths());
        nd.implicit_half_step(&out.c, ls, (h, ctx, water), &mut out.phalf, &mut out.w);
        return;
    }
    match ch.dissipation_count() {
        0 => out.phalf.copy_from_slice(&out.c),
        _ => {
            let blocks = HalfSteps::new(&out.c, &mut out.phalf, &mut out.w);
            ch.dissipative_half_steps(blocks, h, ctx);
        }
    }
}

/// Solves Ĝ(q) M⁻¹ Ĝ(q)ᵀ y = Ĝ(q) M⁻¹ b − (0, …, 0, v_tip) for y (returned in `ws.rhs`), so that
/// p = b − Ĝ(q)ᵀ y satisfies Ĝ(q) M⁻¹ p = (0, …, 0, v_tip). O(n).
pub(crate) fn projection_solve<D: Scalar, const DIM: usize>(
    ch: &Chain<D, DIM>,
    q: &[[D; DIM]],
    b: &[[D; DIM]],
    v_tip: D,
    tmp: &mut [[D; DIM]],
    tri: &mut BorderedTridiag<D>,
    rhs: &mut [D],
) -> std::result::Result<(), crate::tridiag::ZeroPivot> {
    let ops = ch.constraints();
    ch.apply_inverse_mass(b, tmp);
    ops.apply(q, tmp, rhs);
    if ops.bordered() {
        rhs[ch.n()] -= v_tip;
    }
    ops.assemble_projection(q, tri);
    tri.solve(rhs)
}
