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
use crate::model::{Chain, Parameter, Scalar};
use crate::rattle::Rattle;
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
    kk: usize,
) -> Result<(D, StateStore<D, DIM>)> {
    let (chain, u, steps) = (hz.chain, hz.controls, hz.steps);
    let half = chain.has_drag();
    let mut state = rattle.straight_state();
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
    let mut rattle = Rattle::new(chain.clone(), h)?;
    let hz = Horizon {
        chain,
        steps,
        controls: u,
    };
    let (value, checkpoints) = forward_sweep(&hz, &mut rattle, &mut stage, kk)?;

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
    check_controls(u, steps)?;
    let mut r = Rattle::new(chain.clone(), h)?;
    let mut st = r.straight_state();
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
