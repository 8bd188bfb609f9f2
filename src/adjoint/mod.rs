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
//! 2nd half:    p̄½ = b̄ ⊙ (1 − hD|p½|),  q̄′ += −h/2 K(q′) b̄
//! Newton:      Jᵀ ν = λ̄,  λ̄ = −h/2 Ĝ(q_k)(W ⊙ (p̄½ + h M⁻¹ q̄′))   (implicit function theorem)
//!              q̄′ ← q̄′ − Ĝ(q′)ᵀ ν,   c̄ = W ⊙ (p̄½ + h M⁻¹ q̄′)
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
//! # Checkpointing
//! The forward pass keeps every K-th state; the reverse pass recomputes each segment forward into
//! a buffer of K states (memory O(n (N/K + K)), K ≈ √N by default). Recomputation repeats exactly
//! the forward arithmetic, so the gradient is bit-for-bit the same for every K.

mod control_map;
mod objective;
mod problem;
mod reverse;
mod tape;

pub use control_map::{
    ConstantControl, ControlMap, Parametrisation, PerStepControl, PiecewiseControl,
};
pub use objective::{
    BendingObjective, FinalMomentResidual, NodeDisplacementObjective, Objective, Stage,
};
pub use problem::ControlProblem;
pub use tape::{AdjointResult, Checkpointing, AUTO_MEMORY_BUDGET};

use crate::error::{Error, Result};
use crate::model::{Chain, Parameter, Scalar, TipCondition};
use crate::rattle::{Rattle, State};
use num_dual::Dual;
use objective::StageEval;
use reverse::{Cotangents, ReverseSweep};
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

/// Checks that `u` has N + 1 finite values.
pub(crate) fn check_controls<D: Scalar>(u: &[D], steps: usize) -> Result<()> {
    if u.len() != steps + 1 {
        return Err(Error::WrongLength {
            name: "controls",
            expected: steps + 1,
            got: u.len(),
        });
    }
    match u.iter().position(|x| !x.re().is_finite()) {
        Some(index) => Err(Error::NotFinite {
            name: "controls",
            index,
        }),
        None => Ok(()),
    }
}

/// Tolerance of [`Start::check`] on the position constraints ½(‖qᵢ‖² − 1) (RATTLE's steps meet
/// them to 10⁻¹⁴) and, relative to 1 + maxᵢ‖vᵢ‖, on the hidden constraints qᵢ·vᵢ, v = M⁻¹p.
pub const START_TOLERANCE: f64 = 1e-9;

/// Where a horizon starts: the state S₀ at time t₀. Step k of the horizon runs from
/// t₀ + k h to t₀ + (k + 1) h with the controls u_k, u_{k+1} (indexed from 0 on the horizon);
/// its multipliers μ, if given, are the Newton predictor of the first step (`None`: the
/// consistent multiplier is computed). Without a `Start` a horizon starts from the straight beam at rest at
/// t₀ = 0.
#[derive(Clone, Debug)]
pub struct Start<D, const DIM: usize> {
    /// The state S₀ = (q₀, p₀, λ, μ, tip target).
    pub state: State<D, DIM>,
    /// The start time t₀ \[s\].
    pub t0: f64,
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
        if chain.tip_condition() == TipCondition::Reaction {
            r[n] -= st.tip_target[1];
        }
        let vmax = v.iter().flatten().fold(0.0f64, |m, x| m.max(x.re().abs()));
        let velocity = r.iter().fold(0.0f64, |m, x| m.max(x.re().abs())) / (1.0 + vmax);
        if position > START_TOLERANCE || velocity > START_TOLERANCE {
            return Err(Error::InvalidArgument {
                name: "initial state",
                reason: format!(
                    "not on the constraint manifold: position residual {position:.3e}, \
                     velocity residual {velocity:.3e} (relative), tolerance {START_TOLERANCE:e}"
                ),
            });
        }
        Ok(())
    }
}

/// The state a horizon starts from and the integrator for it (start time set).
fn start_state<D: Scalar, const DIM: usize>(
    chain: &Chain<D, DIM>,
    h: f64,
    start: Option<&Start<D, DIM>>,
) -> Result<(Rattle<D, DIM>, State<D, DIM>)> {
    let t0 = start.map_or(0.0, |s| s.t0);
    let rattle = Rattle::new(chain.clone(), h)?.with_start_time(t0);
    let state = match start {
        Some(s) => {
            s.check(chain)?;
            s.state.clone()
        }
        None => rattle.straight_state(),
    };
    Ok((rattle, state))
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
    let half = chain.has_drag();
    rattle.prepare(&mut state, 0, u[0])?;
    let mut value = stage.value(chain, 0, &state.q, u[0]);
    let (n, nc) = (chain.n(), chain.n_constraints());
    let mut checkpoints = StateStore::new(n, nc, steps / kk + 2, half);
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
    check_controls(u, steps)?;
    check_parameters(chain, params)?;
    let (n, nc) = (chain.n(), chain.n_constraints());
    let state_size = StateStore::<D, DIM>::state_bytes(n, nc, chain.has_drag());
    let kk = checkpointing.interval(steps, state_size);
    let mut stage = StageEval {
        obj: objective,
        steps,
        h,
        zbuf: vec![Dual::from_re(D::zero()); n],
        zpos: Vec::new(),
    };
    let k1_param = params.iter().position(|p| *p == Parameter::BaseStiffness);
    let (mut rattle, state0) = start_state(chain, h, start)?;
    let hz = Horizon {
        chain,
        steps,
        controls: u,
    };
    let (value, checkpoints) = forward_sweep(&hz, &mut rattle, &mut stage, (kk, state0))?;

    let zero = vec![[D::zero(); DIM]; n];
    let mut cot = Cotangents {
        qbar: zero.clone(),
        pbar: zero,
        tip_bar: [D::zero(); 2],
        ubar: vec![D::zero(); steps + 1],
        uxbar: vec![D::zero(); if chain.has_control_x() { steps + 1 } else { 0 }],
        thbar: vec![D::zero(); params.len()],
    };
    let n_segments = checkpoints.len() - 1;
    let last = checkpoints.view(n_segments).q;
    stage.accumulate(chain, (steps, last, u[steps]), &mut cot, k1_param);
    let mut sweep = ReverseSweep::new(chain, h, params);
    sweep.t0 = start.map_or(0.0, |s| s.t0);
    let half = chain.has_drag();
    let mut buffer = StateStore::<D, DIM>::new(n, nc, kk.saturating_sub(1), half);
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
    Ok(AdjointResult {
        value,
        control_gradient: cot.ubar,
        control_gradient_x: cot.uxbar,
        parameter_gradient: cot.thbar,
        state_bytes: (checkpoints.capacity() + buffer.capacity()) * state_size,
    })
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
    let (mut r, mut st) = start_state(chain, h, start)?;
    r.prepare(&mut st, 0, u[0])?;
    let mut stage = StageEval {
        obj: objective,
        steps,
        h,
        zbuf: Vec::new(),
        zpos: Vec::new(),
    };
    let mut j = stage.value(chain, 0, &st.q, u[0]);
    for k in 0..steps {
        r.step(&mut st, k, u[k], u[k + 1])?;
        j += stage.value(chain, k + 1, &st.q, u[k + 1]);
    }
    Ok(j)
}
