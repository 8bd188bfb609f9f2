//! Discrete adjoint of the RATTLE map: exact gradients (to round-off) of bending-moment objectives
//! with respect to the controls and the physical parameters, checkpointing, and Hessian-vector
//! products by forward-over-adjoint (docs/conventions.md, thesis §3.3).
//!
//! # Objectives and controls
//! An [`Objective`] is a sum of stage costs ℓ_k(M₀(q_k), u_k), k = 0..=N, written once over
//! [`Scalar`]; [`BendingObjective`] provides c = M₀(t_N)² (eq. 3.3.2), c_sum = Σ M₀(t_k)²
//! (eq. 3.3.4) and an optional control-effort penalty ρ h Σ u_k². A [`ControlMap`] maps parameters
//! θ to the per-step forces u_0..u_N, with its transpose: [`ConstantControl`], [`PerStepControl`],
//! [`PiecewiseControl`].
//!
//! # The adjoint
//! The gradient is that of *exactly* the discrete map of [`crate::rattle`]. One reverse step
//! (k + 1 → k), given q̄_{k+1}, p̄_{k+1}:
//! ```text
//! projection:  A ŷ = Ĝ(q′) p̄′          (A = Ĝ M⁻¹ Ĝᵀ at q′, symmetric bordered tridiagonal)
//!              b̄ = p̄′ − M⁻¹ Ĝᵀ ŷ,   q̄′ᵢ += −(h/2) μᵢ b̄ᵢ − ŷᵢ (M⁻¹p′)ᵢ
//! 2nd half:    p̄½ = (I + h/2 ∂F/∂p)ᵀ b̄ (planar drag: b̄ ⊙ (1 − hD|p½|)),  q̄′ += −h/2 K(q′) b̄
//! Newton:      Jᵀ ν = λ̄,  λ̄ = −h/2 Ĝ(q_k)(Wᵀ(p̄½ + h M⁻¹ q̄′))   (implicit function theorem)
//!              q̄′ ← q̄′ − Ĝ(q′)ᵀ ν,   c̄ = Wᵀ(p̄½ + h M⁻¹ q̄′)   (W block-symmetric)
//! 1st half:    p̄_k = c̄,   q̄_k = q̄′ − h/2 K(q_k) c̄ − h/2 λᵢ c̄ᵢ
//! ```
//! with K = ∂²U/∂q² (block-tridiagonal, [`crate::Chain::force_jacobian_product`]) and J the
//! Newton matrix of the step ([`crate::constraints::ConstraintOperator::assemble_newton`]). The
//! reverse step (`src/adjoint/reverse.rs`) is a vector-Jacobian product of the recorded step
//! (`src/adjoint/tape.rs`) built from the terms' derived products and the constraint operator; it
//! recomputes nothing of the forward step. Every product is O(n), so a gradient costs a small
//! constant times one simulation, whatever the number of controls. Controls and parameters collect −h/2 c̄ · ∂U_q/∂θ and
//! −h/2 b̄ · ∂U_q/∂θ per step, plus the mass-matrix and drag terms.
//!
//! # Per-node quantities
//! Parameters that move the chain's per-node quantities (a stack-up segment's buoyancy diameter
//! D_b: the masses mᵢ with added mass, the submerged weights, the Morison drag coefficients and
//! the waves' inertia coefficients of the segment's nodes) enter the same sweep
//! ([`adjoint_gradient_with_nodes`], [`NodeTangent`]): their partials of the step are
//! hand-written where the step reads M⁻¹ and taken by one `Dual64` evaluation of the terms
//! with the node quantities seeded where it reads the terms,
//! ```text
//! Newton:      θ̄ += h q̄′ᵀ (∂M⁻¹/∂θ) p½                       (q̄′ after Ĝ(q′)ᵀν, as for the mass)
//! projection:  θ̄ −= (Ĝᵀŷ)ᵀ (∂M⁻¹/∂θ) p′                      (Ĝ(q′) M⁻¹p′ = r)
//! terms:       θ̄ −= h/2 (c̄·∂U_q(q_k)/∂θ + b̄·∂U_q(q′)/∂θ),   θ̄ += h/2 (c̄ + b̄)·∂Q(p½)/∂θ
//! aᵀ (∂M⁻¹/∂θ) b = −Σᵢ (∂mᵢ/∂θ / mᵢ²) αᵢ·βᵢ,   αᵢ = aᵢ/lᵢ − aᵢ₊₁/lᵢ₊₁ (β from b)
//! ```
//! ([`crate::Chain::inverse_mass_tangent`]), with ∂mᵢ/∂θ and the seeded chain from the
//! layout's exact derivatives. Every parameter costs per step two `Dual64` evaluations of the
//! conservative terms, two of Morison's drag (O(n), no Newton solve) and two O(n) sums, inside
//! the one forward and one reverse pass that give all the parameters.
//!
//! # Checkpointing
//! The forward pass keeps every K-th state; the reverse pass recomputes each segment forward into
//! a buffer of K states (memory O(n (N/K + K)), K ≈ √N by default). Recomputation repeats exactly
//! the forward arithmetic, so the gradient is bit-for-bit the same for every K.

mod bending;
mod builder;
mod control_map;
mod fatigue;
mod hotspot;
mod node_tangent;
mod objective;
mod power;
mod problem;
mod reverse;
mod tape;

pub(crate) use reverse::{Cotangents, ReverseSweep};
pub(crate) use tape::StateView;

pub use bending::BendingObjective;
pub(crate) use builder::scene_map;
pub use builder::{AnyProblem, ProblemBuilder};
pub use control_map::{
    ConstantControl, ControlMap, Parametrisation, PerStepControl, PiecewiseControl,
};
pub use fatigue::FatigueObjective;
pub use hotspot::HotSpotObjective;
pub use node_tangent::{NodeTangent, SeededNodes};
pub use objective::{
    FinalMomentResidual, GaussNewton, History, MomentStage, NodeDisplacementObjective, Objective,
    Stage,
};
pub use power::PowerObjective;
pub use problem::ControlProblem;
pub use tape::{AdjointResult, Checkpointing, AUTO_MEMORY_BUDGET};

use crate::base::{Parameter, Scalar, TipCondition};
pub use crate::error::StartError;
use crate::error::{Error, Result};
use crate::model::Chain;
use crate::simulate::check_controls;
use crate::steppers::rattle::{Rattle, State};
use num_dual::Dual;
use objective::{HistoryBuf, StageEval};

use crate::steppers::rattle::keeps_gaps;
use tape::StateStore;

/// Validates the parameters requested for a gradient.
fn check_parameters<D: Scalar, const DIM: usize>(
    ch: &Chain<D, DIM>,
    params: &[Parameter],
) -> Result<()> {
    match params.iter().find(|p| !ch.has_parameter(**p)) {
        None => Ok(()),
        Some(&parameter) => Err(Error::NoSuchParameter {
            parameter,
            reason: "mass needs uniform masses, drag needs D > 0, end stiffnesses need an end \
                     spring, loads need that load",
        }),
    }
}

/// Refuses physical parameters (or node quantities, `nodes`) on a run from the chain's static
/// start (`[time] initial = "static"`, no `start` given): that start depends on them,
/// H dq₀/dθ = −∂(∇U)/∂θ (H the statics' Hessian), a derivative the sweep does not carry. The
/// controls' gradient needs none: the start does not depend on u.
fn check_static_start<D: Scalar, const DIM: usize>(
    ch: &Chain<D, DIM>,
    (params, nodes): (&[Parameter], usize),
    start: bool,
) -> Result<()> {
    if ch.has_static_start() && !start && (!params.is_empty() || nodes > 0) {
        return Err(Error::StaticStartRefused {
            reason: "the gradient with respect to physical (design) parameters would need the \
                     static start's own derivative dq₀/dθ, which the adjoint does not carry; \
                     use `initial = \"rest\"` for parameter gradients and design studies",
        });
    }
    Ok(())
}

/// Tolerance of [`Start::check`] on the position constraints ½(‖qᵢ‖² − 1) (RATTLE's steps meet
/// them to 10⁻¹⁴) and, relative to 1 + maxᵢ‖vᵢ‖, on the hidden constraints qᵢ·vᵢ, v = M⁻¹p.
pub const START_TOLERANCE: f64 = 1e-9;

/// Where a horizon starts: the state S₀ at time t₀. Step k of the horizon runs from
/// t₀ + k h to t₀ + (k + 1) h with the controls u_k, u_{k+1} (indexed from 0 on the horizon);
/// its multipliers μ, if given, are the Newton predictor of the first step (`None`: the
/// consistent multiplier is computed). Without a `Start` a horizon starts from the straight beam
/// at rest at t₀ = 0 (or from the chain's static start, [`Chain::start_attitudes`]).
///
/// # The control's half-kick at t₀ ([`StartKick`])
/// A RATTLE step into t₀ takes the control u(t₀) in its second half-kick, and after the
/// projection onto the hidden constraint that half-kick is affine in it: with b = ∂U_q/∂u
/// (block j: l_j e₃ for j below the control node, eq. 3.1.1; b_x = ∂U_q/∂u_x likewise along e₁
/// for the x component of a 2-axis control) and P(q) = I − Ĝᵀ(Ĝ M⁻¹ Ĝᵀ)⁻¹ Ĝ M⁻¹ the
/// projection (linear: the hidden constraint's target is 0),
/// ```text
/// p₀ = p̂₀ − (h/2) P(q₀) (u₀ b + u_{x,0} b_x),
/// ```
/// where p̂₀ is the momentum of the same step taken with zero control in its second half-kick.
/// [`StartKick::Included`] (the default, [`ControlProblem::starting_from`]) holds the given
/// momentum p₀ fixed: the horizon's u₀ acts through the first half-kick of step 0 only.
/// [`StartKick::Pending`] ([`ControlProblem::starting_before_kick`]) reads the given momentum as
/// p̂₀ and the horizon's first force supplies the half-kick by the equation above, so that the
/// horizon's u₀ is *the* control at t₀ of the run it continues, acting on both sides of t₀ as in
/// the run (the start a receding-horizon controller needs, [`crate::mpc`]). The value, the
/// adjoint gradient (∂J/∂u₀ += −(h/2) p̄₀ · P(q₀) b, p̄₀ = ∂J/∂p₀ the costate where the reverse
/// sweep ends; ∂J/∂u_{x,0} likewise with b_x), the Hessian-vector products and the Riccati
/// solver ([`crate::ocp`], whose stage map applies the same rule at every k ≥ 1) all evaluate
/// this one map. A pending kick needs the control to be a force term: the reaction-force tip
/// (whose control drives the tip target, eq. 3.2.1) is refused.
#[derive(Clone, Debug)]
pub struct Start<D, const DIM: usize> {
    /// The state S₀ = (q₀, p₀ or p̂₀, λ, μ, tip target).
    pub state: State<D, DIM>,
    /// The start time t₀ \[s\].
    pub t0: f64,
    /// Whether the momentum already holds the control's half-kick at t₀ (type docs).
    pub kick: StartKick,
}

/// What the momentum of a [`Start`] holds (the equation in the docs of [`Start`]).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum StartKick {
    /// The given momentum is p₀, with the control's half-kick at t₀ in it (or none): the
    /// horizon's u₀ acts through the first half-kick of step 0 only.
    #[default]
    Included,
    /// The given momentum is p̂₀, without the control's half-kick at t₀: the horizon's u₀
    /// supplies it, p₀ = p̂₀ − (h/2) P(q₀)(u₀ b + u_{x,0} b_x).
    Pending,
}

impl<D: Scalar, const DIM: usize> Start<D, DIM> {
    /// Checks S₀ against `chain`: sizes (n attitudes and momenta, n + tip multipliers), finite
    /// values, a finite t₀, and S₀ on the constraint manifold: ĝ(q₀) = 0 (‖qᵢ‖ = 1, and the tip
    /// row against its target) and Ĝ(q₀) M⁻¹ p₀ = 0 (the tip row against the target velocity),
    /// to [`START_TOLERANCE`].
    pub fn check(&self, chain: &Chain<D, DIM>) -> Result<()> {
        let (n, nc, st) = (chain.n(), chain.n_constraints(), &self.state);
        let none: (&[D], &[D]) = (&[], &[]);
        let (lambda, mu) = st
            .multipliers
            .as_ref()
            .map_or(none, |m| (&m.lambda[..], &m.mu[..]));
        let nc_given = if st.multipliers.is_some() { nc } else { 0 };
        for (name, got, expected) in [
            ("initial state q", st.q.len(), n),
            ("initial state p", st.p.len(), n),
            ("initial state lambda", lambda.len(), nc_given),
            ("initial state mu", mu.len(), nc_given),
        ] {
            if got != expected {
                return Err(Error::WrongLength {
                    name,
                    expected,
                    got,
                });
            }
        }
        let flat = |x: &[[D; DIM]]| x.iter().flatten().map(|v| v.re()).collect::<Vec<_>>();
        let scalars = |x: &[D]| x.iter().map(|v| v.re()).collect::<Vec<_>>();
        let tip = scalars(&st.tip_target);
        for (name, values) in [
            ("initial state q", flat(&st.q)),
            ("initial state p", flat(&st.p)),
            ("initial state lambda", scalars(lambda)),
            ("initial state mu", scalars(mu)),
            ("initial state tip target", tip),
            ("start time", vec![self.t0]),
        ] {
            if let Some(index) = values.iter().position(|x| !x.is_finite()) {
                return Err(Error::NotFinite { name, index });
            }
        }
        if self.kick == StartKick::Pending && chain.tip_condition() == TipCondition::Reaction {
            return Err(StartError::PendingKickWithReactionTip.into());
        }
        self.check_manifold(chain)
    }

    /// The constraint part of [`Start::check`].
    fn check_manifold(&self, chain: &Chain<D, DIM>) -> Result<()> {
        let (n, nc, st) = (chain.n(), chain.n_constraints(), &self.state);
        let ops = chain.constraints();
        let mut r = vec![D::zero(); nc];
        let position = ops.residual(&st.q, st.tip_target[0], &mut r);
        let mut v = vec![[D::zero(); DIM]; n];
        chain.apply_inverse_mass(&st.p, &mut v);
        ops.apply(&st.q, &v, &mut r);
        if chain.has_driven_tip() {
            r[n] -= st.tip_target[1];
        }
        let vmax = v.iter().flatten().fold(0.0f64, |m, x| m.max(x.re().abs()));
        let velocity = r.iter().fold(0.0f64, |m, x| m.max(x.re().abs())) / (1.0 + vmax);
        if position > START_TOLERANCE || velocity > START_TOLERANCE {
            return Err(StartError::OffManifold {
                position,
                velocity,
                tolerance: START_TOLERANCE,
            }
            .into());
        }
        Ok(())
    }
}

/// The control's pending half-kick at the start of a horizon ([`StartKick::Pending`]): the
/// directions d = −(h/2) P(q₀) b and d_x = −(h/2) P(q₀) b_x (empty for a 1-axis control), so
/// that p₀ = p̂₀ + u₀ d + u_{x,0} d_x (docs of [`Start`]).
struct PendingKick<D, const DIM: usize> {
    d: Vec<[D; DIM]>,
    dx: Vec<[D; DIM]>,
}

impl<D: Scalar, const DIM: usize> PendingKick<D, DIM> {
    /// The directions at q₀ ([`Rattle::control_half_kick`] with unit controls).
    fn new(rattle: &mut Rattle<D, DIM>, q0: &[[D; DIM]]) -> Result<Self> {
        let n = rattle.chain().n();
        let mut d = vec![[D::zero(); DIM]; n];
        rattle.control_half_kick(q0, (D::one(), D::zero()), &mut d)?;
        let mut dx = Vec::new();
        if rattle.chain().has_control_x() {
            dx.resize(n, [D::zero(); DIM]);
            rattle.control_half_kick(q0, (D::zero(), D::one()), &mut dx)?;
        }
        Ok(PendingKick { d, dx })
    }

    /// p₀ = p̂₀ + u₀ d + u_{x,0} d_x.
    fn apply(&self, (u0, ux0): (D, D), p: &mut [[D; DIM]]) {
        for (i, pi) in p.iter_mut().enumerate() {
            for k in 0..DIM {
                pi[k] += self.d[i][k] * u0;
                if let Some(dx) = self.dx.get(i) {
                    pi[k] += dx[k] * ux0;
                }
            }
        }
    }

    /// Its adjoint: ∂J/∂u₀ += p̄₀ · d, ∂J/∂u_{x,0} += p̄₀ · d_x.
    fn reverse(&self, pbar: &[[D; DIM]], cot: &mut Cotangents<D, DIM>) {
        let dot = |d: &[[D; DIM]]| {
            let mut s = D::zero();
            for (a, b) in pbar.iter().zip(d) {
                for k in 0..DIM {
                    s += a[k] * b[k];
                }
            }
            s
        };
        cot.ubar[0] += dot(&self.d);
        if let Some(uxb) = cot.uxbar.first_mut() {
            *uxb += dot(&self.dx);
        }
    }
}

/// The start of a horizon's sweeps: the integrator (start time set), the state S₀ (with the
/// pending half-kick of u₀ applied) and the kick's directions for the adjoint.
struct Initial<D, const DIM: usize> {
    rattle: Rattle<D, DIM>,
    state: State<D, DIM>,
    kick: Option<PendingKick<D, DIM>>,
}

/// The state a horizon starts from, with the control u₀'s half-kick applied when it is pending
/// ([`StartKick::Pending`]).
fn start_state<D: Scalar, const DIM: usize>(
    chain: &Chain<D, DIM>,
    h: f64,
    start: Option<&Start<D, DIM>>,
    u0: D,
) -> Result<Initial<D, DIM>> {
    let t0 = start.map_or(0.0, |s| s.t0);
    let mut rattle = Rattle::new(chain.clone(), h)?.with_start_time(t0);
    let Some(s) = start else {
        let state = rattle.start_state()?;
        return Ok(Initial {
            rattle,
            state,
            kick: None,
        });
    };
    s.check(chain)?;
    let mut state = s.state.clone();
    let kick = match s.kick {
        StartKick::Included => None,
        StartKick::Pending => {
            let kick = PendingKick::new(&mut rattle, &state.q)?;
            kick.apply((u0, chain.control_x(0)), &mut state.p);
            Some(kick)
        }
    };
    Ok(Initial {
        rattle,
        state,
        kick,
    })
}

/// A horizon: the model, the number of steps N and the controls u_0..u_N.
#[derive(Clone, Copy)]
struct Horizon<'a, D, const DIM: usize> {
    chain: &'a Chain<D, DIM>,
    steps: usize,
    controls: &'a [D],
}

/// The forward sweep of [`adjoint_gradient`]: J and the checkpoints (every K-th state, with the
/// half-step records the reverse step reads).
fn forward_sweep<D: Scalar, O: Objective, const DIM: usize>(
    hz: &Horizon<'_, D, DIM>,
    rattle: &mut Rattle<D, DIM>,
    stage: &mut StageEval<'_, O, D>,
    (kk, mut state): (usize, State<D, DIM>),
) -> Result<(D, StateStore<D, DIM>)> {
    let (chain, u, steps) = (hz.chain, hz.controls, hz.steps);
    let half = chain.records_half_step();
    rattle.prepare(&mut state, 0, u[0])?;
    let mut value = stage.value(chain, 0, &state.q, u[0]);
    let (n, nc) = (chain.n(), chain.n_constraints());
    let mut checkpoints = StateStore::new(n, nc, steps / kk + 2, (half, keeps_gaps(chain)));
    checkpoints.push(&state, (&[], &[]));
    for k in 0..steps {
        rattle.step(&mut state, k, u[k], u[k + 1])?;
        value += stage.value(chain, k + 1, &state.q, u[k + 1]);
        if (k + 1) % kk == 0 || k + 1 == steps {
            checkpoints.push(&state, rattle.last_half_step());
        }
    }
    Ok((value, checkpoints))
}

/// Recomputes the interior states S_{a+1..b−1} of a segment from checkpoint S_a into `buffer`.
fn recompute_segment<D: Scalar, const DIM: usize>(
    u: &[D],
    rattle: &mut Rattle<D, DIM>,
    (checkpoints, seg): (&StateStore<D, DIM>, usize),
    (a, b): (usize, usize),
    buffer: &mut StateStore<D, DIM>,
) -> Result<()> {
    buffer.clear();
    if b - a > 1 {
        let mut state = rattle.straight_state();
        checkpoints.load(seg, &mut state);
        rattle.prepare_force(&state, a, u[a])?;
        for k in a..b - 1 {
            rattle.step(&mut state, k, u[k], u[k + 1])?;
            buffer.push(&state, rattle.last_half_step());
        }
    }
    Ok(())
}

/// One forward and one reverse sweep: J, ∂J/∂u_k and ∂J/∂θ (physical parameters), generic over
/// the scalar (`Dual64` with seeded inputs gives Hessian-vector products). A 2-axis control's x
/// components are read from the chain ([`Chain::set_control_x`]) and their gradient ∂J/∂u_{x,k}
/// is [`AdjointResult::control_gradient_x`].
pub fn adjoint_gradient<D: Scalar, O: Objective, const DIM: usize>(
    chain: &Chain<D, DIM>,
    h: f64,
    steps: usize,
    u: &[D],
    objective: &O,
    params: &[Parameter],
    checkpointing: Checkpointing,
) -> Result<AdjointResult<D>> {
    adjoint_gradient_from(chain, (h, steps), u, objective, params, checkpointing, None)
}

/// [`adjoint_gradient`] on a horizon that starts from `start` (S₀ at t₀) instead of the straight
/// beam at rest at t = 0, over the horizon `(h, steps)` (time step, number of steps N). The
/// initial state is data: no gradient flows into it.
pub fn adjoint_gradient_from<D: Scalar, O: Objective, const DIM: usize>(
    chain: &Chain<D, DIM>,
    (h, steps): (f64, usize),
    u: &[D],
    objective: &O,
    params: &[Parameter],
    checkpointing: Checkpointing,
    start: Option<&Start<D, DIM>>,
) -> Result<AdjointResult<D>> {
    let horizon = (h, steps);
    adjoint_gradient_with_nodes(
        chain,
        horizon,
        (u, objective),
        params,
        Vec::new(),
        checkpointing,
        start,
    )
    .map(|(r, _)| r)
}

/// [`adjoint_gradient_from`] with parameters the chain's per-node quantities carry too
/// (`nodes`, module docs "Per-node quantities"; a segment's buoyancy diameter through
/// [`SeededNodes`]): the same one forward and one reverse sweep, returning the adjoint result
/// and ∂J/∂θ for each of `nodes` in their order.
///
/// # Errors
/// [`adjoint_gradient_from`]'s, and [`crate::model::ModelError::NodeQuantities`] with `nodes` on a
/// chain whose sweep has no node-by-node partials for them (joint damping, a driven tip, a
/// dissipative term other than Morison's drag node by node).
pub fn adjoint_gradient_with_nodes<'a, D: Scalar, O: Objective, const DIM: usize>(
    chain: &'a Chain<D, DIM>,
    (h, steps): (f64, usize),
    (u, objective): (&[D], &O),
    params: &'a [Parameter],
    nodes: Vec<Box<dyn NodeTangent<D, DIM> + 'a>>,
    checkpointing: Checkpointing,
    start: Option<&Start<D, DIM>>,
) -> Result<(AdjointResult<D>, Vec<D>)> {
    check_controls(u, steps)?;
    check_parameters(chain, params)?;
    check_static_start(chain, (params, nodes.len()), start.is_some())?;
    if !nodes.is_empty() {
        node_tangent::check_chain(chain)?;
    }
    let n_nodes = nodes.len();
    let (n, nc) = (chain.n(), chain.n_constraints());
    let state_size =
        StateStore::<D, DIM>::state_bytes(n, nc, (chain.records_half_step(), keeps_gaps(chain)));
    let kk = checkpointing.interval(steps, state_size);
    let mut stage = StageEval {
        obj: objective,
        steps,
        h,
        zbuf: vec![Dual::from_re(D::zero()); n],
        zpos: Vec::new(),
        history: HistoryBuf::default(),
    };
    let k1_param = params.iter().position(|p| *p == Parameter::BaseStiffness);
    let Initial {
        mut rattle,
        state: state0,
        kick,
    } = start_state(chain, h, start, u[0])?;
    let hz = Horizon {
        chain,
        steps,
        controls: u,
    };
    let (value, checkpoints) = forward_sweep(&hz, &mut rattle, &mut stage, (kk, state0))?;
    let value = value + stage.finish_history()?;

    let zero = vec![[D::zero(); DIM]; n];
    let mut cot = Cotangents {
        qbar: zero.clone(),
        pbar: zero,
        tip_bar: [D::zero(); 2],
        ubar: vec![D::zero(); steps + 1],
        uxbar: vec![D::zero(); if chain.has_control_x() { steps + 1 } else { 0 }],
        thbar: vec![D::zero(); params.len() + n_nodes],
    };
    let n_segments = checkpoints.len() - 1;
    let last = checkpoints.view(n_segments).q;
    stage.accumulate(chain, (steps, last, u[steps]), &mut cot, k1_param);
    let mut sweep = ReverseSweep::new(chain, h, params).with_node_tangents(params.len(), nodes);
    sweep.t0 = start.map_or(0.0, |s| s.t0);
    let half = chain.records_half_step();
    let mut buffer = StateStore::<D, DIM>::new(n, nc, kk.saturating_sub(1), (half, false));
    for seg in (0..n_segments).rev() {
        let (a, b) = (seg * kk, (seg * kk + kk).min(steps));
        recompute_segment(u, &mut rattle, (&checkpoints, seg), (a, b), &mut buffer)?;
        let view = |k: usize| match k {
            _ if k == a => checkpoints.view(seg),
            _ if k == b => checkpoints.view(seg + 1),
            _ => buffer.view(k - a - 1),
        };
        for k in (a..b).rev() {
            let (sk, sk1) = (view(k), view(k + 1));
            sweep.step(k, (&sk, &sk1), (u[k], u[k + 1]), &mut cot)?;
            stage.accumulate(chain, (k, sk.q, u[k]), &mut cot, k1_param);
        }
    }
    // The reverse sweep ends with p̄₀ = ∂J/∂p₀; a pending kick makes p₀ depend on u₀.
    if let Some(kick) = &kick {
        let pbar = std::mem::take(&mut cot.pbar);
        kick.reverse(&pbar, &mut cot);
    }
    let mut parameter_gradient = cot.thbar;
    let node_gradient = parameter_gradient.split_off(params.len());
    let result = AdjointResult {
        value,
        control_gradient: cot.ubar,
        control_gradient_x: cot.uxbar,
        parameter_gradient,
        state_bytes: (checkpoints.capacity() + buffer.capacity()) * state_size,
    };
    Ok((result, node_gradient))
}

/// J = Σ_k ℓ_k by one forward simulation without storage, generic over the scalar (with dual
/// numbers this is forward-mode differentiation of the whole objective, the reference the adjoint
/// is tested against).
pub fn forward_value<D: Scalar, O: Objective, const DIM: usize>(
    chain: &Chain<D, DIM>,
    h: f64,
    steps: usize,
    u: &[D],
    objective: &O,
) -> Result<D> {
    forward_value_from(chain, h, steps, u, objective, None)
}

/// [`forward_value`] on a horizon that starts from `start` (S₀ at t₀).
pub fn forward_value_from<D: Scalar, O: Objective, const DIM: usize>(
    chain: &Chain<D, DIM>,
    h: f64,
    steps: usize,
    u: &[D],
    objective: &O,
    start: Option<&Start<D, DIM>>,
) -> Result<D> {
    check_controls(u, steps)?;
    let Initial {
        rattle: mut r,
        state: mut st,
        ..
    } = start_state(chain, h, start, u[0])?;
    r.prepare(&mut st, 0, u[0])?;
    let mut stage = StageEval {
        obj: objective,
        steps,
        h,
        zbuf: Vec::new(),
        zpos: Vec::new(),
        history: HistoryBuf::default(),
    };
    let mut j = stage.value(chain, 0, &st.q, u[0]);
    for k in 0..steps {
        r.step(&mut st, k, u[k], u[k + 1])?;
        j += stage.value(chain, k + 1, &st.q, u[k + 1]);
    }
    Ok(j + stage.finish_history()?)
}
