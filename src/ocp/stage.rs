//! One stage of the optimal-control problem: the DDP state x̂_k, the tangent coordinates
//! ξ = (φ, ω), the stage map F_k(x̂_k, u_k) and its Jacobians A_k = ∂ξ_{k+1}/∂ξ_k,
//! B_k = ∂ξ_{k+1}/∂u_k by dual numbers through the one generic RATTLE step.
//!
//! # One control per stage: the shifted state x̂_k
//! A RATTLE step (q_k, p_k) → (q_{k+1}, p_{k+1}) uses u_k in its first half-kick and u_{k+1} in
//! its second. After the projection onto the hidden constraint the second half-kick is affine in
//! u_{k+1}: since U_q(q; u) = U_q(q; 0) + u b with b = ∂U_q/∂u (block j: l_j e₃ for j below the
//! control node, eq. 3.1.1), and the projection p = P(q) a,
//! P(q) = I − Gᵀ(G M⁻¹ Gᵀ)⁻¹ G M⁻¹, is linear in a,
//! ```text
//! p_{k+1} = p̂_{k+1} − (h/2) u_{k+1} P(q_{k+1}) b,
//! ```
//! where p̂_{k+1} is the momentum of the same step taken with u_{k+1} = 0. The DDP state is
//! x̂_k = (q_k, p̂_k) and the stage map is
//! ```text
//! F_k(x̂_k, u_k):  p_k = p̂_k − (h/2) u_k P(q_k) b   (k ≥ 1, see below for k = 0),
//!                 (q_{k+1}, p̂_{k+1}) = RATTLE step from (q_k, p_k) with controls (u_k, 0).
//! ```
//! At k = 0 the rule depends on the start ([`Start`]): from the straight beam at rest or from a
//! start whose momentum includes its half-kick ([`StartKick::Included`]) the given momentum is
//! p_0 itself (x̂_0 = (q_0, p_0), no kick); from a start with the kick pending
//! ([`StartKick::Pending`]) it is p̂_0 and stage 0 applies the same rule as k ≥ 1, so that B_0
//! carries the half-kick's −(h/2) P(q_0) b as every other B_k does.
//! It lies on the same manifold as (q, p), and the costs (M₀ depends on q only) are unchanged,
//! so the trajectory and the objective are exactly those of [`crate::rattle`]. Without the shift
//! B_k would depend on u_{k+1} and the Riccati recursion would be wrong, not only slow.
//!
//! # Coordinates: simulate maximal, linearise minimal
//! The planar state (q, p) ∈ ℝ^{4n} is constrained to a 2n-dimensional manifold (qᵢ ∈ S¹ and
//! qᵢ·(M⁻¹p)ᵢ = 0). We keep simulating in the maximal coordinates the project validates, but
//! linearise in the tangent coordinates ξ = (φ₁..φₙ, ω₁..ωₙ): φᵢ the absolute angle of
//! pendulum i from e₂ (qᵢ = (cos φᵢ, sin φᵢ) in (y, z)) and ωᵢ = tᵢ·vᵢ its angular rate, with
//! tᵢ = qᵢ rotated by +90° and v = M⁻¹p. In the planar model these are global coordinates of the
//! manifold, so the Riccati matrices are 2n × 2n instead of 4n × 4n (8× fewer flops) and the
//! feedback never acts on directions off the manifold. The maps between tangent and ambient
//! perturbations are
//! ```text
//! E (ξ → x):  δqᵢ = tᵢ δφᵢ,   δp = M δv,   δvᵢ = tᵢ δωᵢ − qᵢ ωᵢ δφᵢ
//! L (x → ξ):  δφᵢ = tᵢ·δqᵢ,   δωᵢ = tᵢ·(M⁻¹ δp)ᵢ              (L E = I)
//! ```
//! and A_k = L_{k+1} ∂F_k/∂x̂ E_k, B_k = L_{k+1} ∂F_k/∂u. Only free tips are supported: a locked
//! or reaction-force tip adds a constraint (the manifold loses dimensions) that these
//! coordinates do not remove ([`OcpError::UnsupportedTip`]).
//!
//! # Jacobians by dual numbers
//! The 2n + 1 directions (E e_j on x̂_k, and u_k) are seeded in chunks of [`CHUNK`] into
//! `DualSVec64<CHUNK>` and pushed through the stage map above: the generic RATTLE step with its
//! derivative-only Newton update after convergence, which is the implicit function theorem on
//! the step residual, ∂λ/∂θ = −R_λ⁻¹ R_θ (the derivative parts are exact, not iterated). The
//! real parts are those of the `f64` stage map bit for bit.

use crate::adjoint::{Start, StartKick};
use crate::base::{Scalar, TipCondition};
use crate::error::{Error, OcpError, Result};
use crate::model::Chain;
use crate::steppers::rattle::{Rattle, State};
use crate::tridiag::BorderedTridiag;
use std::ops::Range;

use nalgebra::SVector;
use num_dual::{Derivative, DualSVec64};

/// The point x̂_k of a stage's linearisation: attitudes q, momenta p, rates ω (the tangent
/// coordinates' velocities) and the Newton start μ of the step (`JacobianWorkspace::jacobians`).
#[derive(Clone, Copy, Debug)]
pub struct StagePoint<'a, const DIM: usize = 2> {
    /// qᵢ.
    pub q: &'a [[f64; DIM]],
    /// pᵢ.
    pub p: &'a [[f64; DIM]],
    /// ωᵢ = tᵢ·(M⁻¹p)ᵢ (DIM − 1 per pendulum, in the tangent basis e_a(qᵢ) of the stage map).
    pub omega: &'a [f64],
    /// The Newton start (the nominal's converged λ_k).
    pub mu: &'a [f64],
}

/// Stage k of a model linearised at the point x̂_k = `x` with the control u_k = `u` (and
/// u_{x,k} = `ux` of a 2-axis control): what [`JacobianWorkspace::jacobians`] and the
/// second-order pass of `hessian.rs` differentiate.
#[derive(Clone, Copy, Debug)]
pub(crate) struct StageAt<'a, const DIM: usize = 2> {
    /// The stage maps.
    pub model: &'a StageModel<DIM>,
    /// The stage index k.
    pub k: usize,
    /// x̂_k with its rates and Newton start.
    pub x: StagePoint<'a, DIM>,
    /// u_k (the z component of a 2-axis control).
    pub u: f64,
    /// u_{x,k} of a 2-axis control (unused otherwise).
    pub ux: f64,
}

/// Where a stage's Jacobians go: A_k (column-major n_ξ × n_ξ) and B_k (n_ξ per control axis,
/// the z component's column first).
#[derive(Debug)]
pub(crate) struct JacobiansMut<'a> {
    /// A_k = ∂ξ_{k+1}/∂ξ_k.
    pub a: &'a mut [f64],
    /// B_k = ∂ξ_{k+1}/∂u_k.
    pub b: &'a mut [f64],
}

/// Directions per dual-number chunk (`DualSVec64<8>`: measured 11 f64-steps per dual step, the
/// best cost per direction of the sizes 8, 10, 12, 16; 7 and 11, which fit the 2n + 1 = 21
/// directions of n = 10 exactly, measured no better).
pub const CHUNK: usize = 8;
pub(crate) type Dv = DualSVec64<CHUNK>;

/// Directions of a planar stage: the 2n tangent coordinates and the control
/// ([`StageModel::ndir`] in general).
pub(crate) fn ndir(n: usize) -> usize {
    2 * n + 1
}

/// The direction chunks [start, end) of `nd` directions, `CHUNK` at a time (the last shorter).
pub(crate) fn chunks(nd: usize) -> impl Iterator<Item = Range<usize>> {
    (0..nd)
        .step_by(CHUNK)
        .map(move |start| start..(start + CHUNK).min(nd))
}

/// The derivative of `x` along the direction in `slot` of its chunk (0 without derivatives).
#[inline]
pub(crate) fn eps(x: &Dv, slot: usize) -> f64 {
    x.eps.0.as_ref().map_or(0.0, |v| v[slot])
}

/// The tangent tᵢ = qᵢ rotated by +90° in the (y, z) plane: ∂q/∂φ for q = (cos φ, sin φ).
#[inline]
pub(crate) fn tangent<D: Scalar>(q: &[D; 2]) -> [D; 2] {
    [-q[1], q[0]]
}

/// a·b in `DIM` components (the planar a₀b₀ + a₁b₁ bit for bit). Always inlined: in dual
/// numbers LLVM otherwise calls it out of line from the projector of the second-order pass
/// (5.2 M instructions per `ocp_newton` pass in its calls, docs/architecture.md "Benches").
#[inline(always)]
pub(crate) fn dot<D: Scalar, const DIM: usize>(a: &[D; DIM], b: &[D; DIM]) -> D {
    let mut s = a[0] * b[0] + a[1] * b[1];
    for d in 2..DIM {
        s += a[d] * b[d];
    }
    s
}

/// The tangent basis e_a(q), a < DIM − 1, of the unit sphere at q (the coordinates of
/// [`StagePoint::omega`] and of the spatial chart): in the plane the tangent t = q rotated by +90°
/// (`tangent`); in space (x, y, z) e₁ = (0, −q_z, q_y)/√(q_y² + q_z²), the rotation of q
/// about x (the planar t when q_x = 0), and e₂ = q × e₁. Orthonormal and orthogonal to q
/// wherever q is not along ±x (a pendulum lying along x: never for a beam hanging along y).
#[inline]
pub(crate) fn tangent_basis<const DIM: usize>(q: &[f64; DIM]) -> [[f64; DIM]; 2] {
    let mut e = [[0.0; DIM]; 2];
    if DIM == 2 {
        e[0][0] = -q[1];
        e[0][1] = q[0];
        return e;
    }
    let r = q[1].hypot(q[2]);
    let e1 = [0.0, -q[2] / r, q[1] / r];
    let e2 = [
        q[1] * e1[2] - q[2] * e1[1],
        q[2] * e1[0] - q[0] * e1[2],
        q[0] * e1[1] - q[1] * e1[0],
    ];
    e[0][..3].copy_from_slice(&e1);
    e[1][..3].copy_from_slice(&e2);
    e
}

/// The f64 data of the stage map that the solvers need beside the chain, in the planar
/// (`DIM = 2`) or the spatial (`DIM = 3`) model.
#[derive(Clone, Debug)]
pub(crate) struct StageModel<const DIM: usize = 2> {
    pub n: usize,
    pub h: f64,
    pub chain: Chain<f64, DIM>,
    /// M̄ (n × n, row-major): M̄_ij = lᵢ l_j Σ_{k ≥ max(i,j)} m_k (kinetic energy ½ Σ m_k |ṙ_k|²).
    pub mass: Vec<f64>,
    /// b = ∂U_q/∂u (block j: l_j e₃ for j below the control node).
    pub control: Vec<[f64; DIM]>,
    /// b_x = ∂U_q/∂u_x (block j: l_j e₁ below the control node) of a 2-axis control (empty for
    /// a control along z).
    pub control_x: Vec<[f64; DIM]>,
    /// N: the stages of the horizon (the length of a 2-axis control's x schedule).
    pub steps: usize,
    /// ∂M₀/∂z-component of q₁: M₀ = scale · q₁,z (eq. 3.1.3); M₀ₓ = scale · q₁,x.
    pub moment_scale: f64,
    /// The horizon's start (S₀, t₀); None: straight at rest at t = 0.
    pub start: Option<Start<f64, DIM>>,
}

impl<const DIM: usize> StageModel<DIM> {
    /// Checks the scene's model (free tip, a control node) and precomputes M̄ and b.
    pub(crate) fn new(chain: &Chain<f64, DIM>, h: f64) -> Result<Self> {
        chain.check_adjoint()?;
        if chain.tip_condition() != TipCondition::Free {
            return Err(OcpError::UnsupportedTip {
                tip: chain.tip_condition(),
            }
            .into());
        }
        let Some(node) = chain.control_node() else {
            return Err(OcpError::NoControlNode.into());
        };
        let n = chain.n();
        let (l, m) = (chain.lengths(), chain.masses());
        // tail_k = Σ_{k' ≥ k} m_k'
        let mut tail = vec![0.0; n + 1];
        for k in (0..n).rev() {
            tail[k] = tail[k + 1] + m[k];
        }
        let mut mass = vec![0.0; n * n];
        for i in 0..n {
            for j in 0..n {
                mass[i * n + j] = l[i] * l[j] * tail[i.max(j)];
            }
        }
        let along = |axis: usize| -> Vec<[f64; DIM]> {
            (0..n)
                .map(|j| {
                    let mut b = [0.0; DIM];
                    if j < node {
                        b[axis] = l[j];
                    }
                    b
                })
                .collect()
        };
        let control = along(DIM - 1);
        // q₁ = e₃, every other pendulum along the beam's axis e₂.
        let mut unit = vec![[0.0; DIM]; n];
        for (i, u) in unit.iter_mut().enumerate() {
            u[if i == 0 { DIM - 1 } else { DIM - 2 }] = 1.0;
        }
        let moment_scale = chain.base_moment(&unit);
        Ok(StageModel {
            n,
            h,
            chain: chain.clone(),
            mass,
            control,
            control_x: Vec::new(),
            steps: 0,
            moment_scale,
            start: None,
        })
    }

    /// The model of a 2-axis control (`two_axis`, spatial model only) over N = `steps` stages:
    /// b_x beside b (nothing changes for a control along z).
    pub(crate) fn with_axes(mut self, two_axis: bool, steps: usize) -> Self {
        self.steps = steps;
        if two_axis && DIM == 3 {
            self.control_x = self
                .control
                .iter()
                .map(|b| {
                    let mut bx = [0.0; DIM];
                    bx[0] = b[DIM - 1];
                    bx
                })
                .collect();
        }
        self
    }

    /// Whether the control is 2-axis: (u_x, u_z) per stage.
    pub(crate) fn two_axis(&self) -> bool {
        !self.control_x.is_empty()
    }

    /// The model of a horizon starting from `start` ([`crate::ControlProblem::starting_from`]).
    pub(crate) fn with_start(mut self, start: Option<&Start<f64, DIM>>) -> Self {
        self.start = start.cloned();
        self
    }

    /// Tangent dimension 2n(DIM − 1): 2n planar, 4n spatial.
    pub(crate) fn nx(&self) -> usize {
        2 * self.n * (DIM - 1)
    }

    /// Controls per stage: 1 (along z) or 2 ((u_z, u_x), a 2-axis control).
    pub(crate) fn controls(&self) -> usize {
        if self.two_axis() {
            2
        } else {
            1
        }
    }

    /// Directions of a stage's Jacobians: the tangent coordinates and the controls
    /// (2n + 1 planar, [`ndir`]).
    pub(crate) fn ndir(&self) -> usize {
        self.nx() + self.controls()
    }

    /// out = M v (v = velocities, out = momenta), O(n): (M̄x)ᵢ = lᵢ Σ_{k≥i} m_k Σ_{j≤k} l_j x_j.
    pub(crate) fn apply_mass<D: Scalar>(&self, v: &[[D; DIM]], out: &mut [[D; DIM]]) {
        let (l, m) = (self.chain.lengths(), self.chain.masses());
        let mut c = [D::zero(); DIM];
        for j in 0..self.n {
            for d in 0..DIM {
                c[d] += v[j][d] * l[j];
                out[j][d] = c[d] * m[j];
            }
        }
        let mut acc = [D::zero(); DIM];
        for i in (0..self.n).rev() {
            for d in 0..DIM {
                acc[d] += out[i][d];
                out[i][d] = acc[d] * l[i];
            }
        }
    }

    /// Angular rates ω_{i,a} = e_a(qᵢ)·(M⁻¹p)ᵢ ([`tangent_basis`]; planar: ωᵢ = tᵢ·(M⁻¹p)ᵢ),
    /// DIM − 1 per pendulum; `scratch` has length n.
    pub(crate) fn rates(
        &self,
        q: &[[f64; DIM]],
        p: &[[f64; DIM]],
        scratch: &mut [[f64; DIM]],
        out: &mut [f64],
    ) {
        self.chain.apply_inverse_mass(p, scratch);
        let na = DIM - 1;
        for i in 0..self.n {
            let e = tangent_basis(&q[i]);
            for a in 0..na {
                out[i * na + a] = dot(&e[a], &scratch[i]);
            }
        }
    }

    /// The base moment (M₀_z, M₀ₓ) of q, z first: planar (M₀ [`Chain::base_moment`], 0), spatial
    /// [`Chain::base_moment_vector`] (the adjoint's objective reads the same).
    #[inline]
    pub(crate) fn moment(&self, q: &[[f64; DIM]]) -> [f64; 2] {
        if DIM == 2 {
            return [self.chain.base_moment(q), 0.0];
        }
        let [mx, mz] = self.chain.base_moment_vector(q);
        [mz, mx]
    }
}

/// P(q) b = b − Gᵀy with (G M⁻¹ Gᵀ) y = G M⁻¹ b (free tip: G M⁻¹ Gᵀ is tridiagonal,
/// (G M⁻¹ Gᵀ)_ij = (qᵢ·q_j) M̄⁻¹_ij, in the plane and in space), O(n), for any scalar.
#[derive(Clone, Debug)]
pub(crate) struct Projector<D, const DIM: usize = 2> {
    lifted: Vec<[D; DIM]>,
    tmp: Vec<[D; DIM]>,
    tri: BorderedTridiag<D>,
    rhs: Vec<D>,
}

impl<D: Scalar, const DIM: usize> Projector<D, DIM> {
    /// The multipliers y_b of the last [`Projector::apply`]: P(q) b = b − Ĝ(q)ᵀ y_b.
    pub(crate) fn y(&self) -> &[D] {
        &self.rhs
    }

    pub(crate) fn new(n: usize) -> Self {
        Projector {
            lifted: vec![[D::zero(); DIM]; n],
            tmp: vec![[D::zero(); DIM]; n],
            tri: BorderedTridiag::new(n, false),
            rhs: vec![D::zero(); n],
        }
    }

    /// out = P(q) b.
    pub(crate) fn apply(
        &mut self,
        ch: &Chain<D, DIM>,
        q: &[[D; DIM]],
        b: &[[f64; DIM]],
        step: usize,
        out: &mut [[D; DIM]],
    ) -> Result<()> {
        let n = ch.n();
        for (o, bi) in self.lifted.iter_mut().zip(b) {
            for d in 0..DIM {
                o[d] = D::from(bi[d]);
            }
        }
        ch.apply_inverse_mass(&self.lifted, &mut self.tmp);
        let (l, m) = (ch.lengths(), ch.masses());
        for i in 0..n {
            self.rhs[i] = dot(&q[i], &self.tmp[i]);
            let li = l[i].recip();
            let mi = m[i].recip();
            let dii = if i > 0 {
                li * li * (mi + m[i - 1].recip())
            } else {
                li * li * mi
            };
            self.tri.diag[i] = dot(&q[i], &q[i]) * dii;
            if i + 1 < n {
                let off = -(li * l[i + 1].recip() * mi);
                let v = dot(&q[i], &q[i + 1]) * off;
                self.tri.upper[i] = v;
                self.tri.lower[i + 1] = v;
            }
        }
        self.tri
            .solve(&mut self.rhs)
            .map_err(|zp| Error::SingularSystem {
                step,
                index: zp.index,
                pivot: zp.pivot,
            })?;
        for i in 0..n {
            for d in 0..DIM {
                out[i][d] = D::from(b[i][d]) - self.rhs[i] * q[i][d];
            }
        }
        Ok(())
    }
}

/// The stage map F_k on a state held in `state`, for any scalar (module docs), in the planar or
/// the spatial model; a 2-axis control's x components u_{x,k} are the chain's x schedule
/// ([`Stepper::set_control_x`]).
#[derive(Clone, Debug)]
pub(crate) struct Stepper<D, const DIM: usize = 2> {
    pub rattle: Rattle<D, DIM>,
    pub state: State<D, DIM>,
    initial: Option<State<D, DIM>>,
    /// Whether stage 0 applies the control's half-kick (a start with [`StartKick::Pending`]).
    pending: bool,
    pub proj: Projector<D, DIM>,
    pb: Vec<[D; DIM]>,
    b: Vec<[f64; DIM]>,
    /// b_x of a 2-axis control (empty otherwise).
    bx: Vec<[f64; DIM]>,
    hh: f64,
}

impl<D: Scalar, const DIM: usize> Stepper<D, DIM> {
    pub(crate) fn new(model: &StageModel<DIM>) -> Result<Self> {
        let t0 = model.start.as_ref().map_or(0.0, |s| s.t0);
        let mut chain = model.chain.lift::<D>();
        if model.two_axis() {
            chain.set_control_x(&vec![D::zero(); model.steps + 1])?;
        }
        let rattle = Rattle::new(chain, model.h)?.with_start_time(t0);
        let state = rattle.straight_state();
        Ok(Stepper {
            rattle,
            state,
            initial: model.start.as_ref().map(|s| s.state.lift()),
            pending: model
                .start
                .as_ref()
                .is_some_and(|s| s.kick == StartKick::Pending),
            proj: Projector::new(model.n),
            pb: vec![[D::zero(); DIM]; model.n],
            b: model.control.clone(),
            bx: model.control_x.clone(),
            hh: 0.5 * model.h,
        })
    }

    /// Moves the stepper to another horizon start of the same model (the receding horizon of
    /// [`crate::mpc`]): its start time, initial state and pending kick.
    pub(crate) fn set_start(&mut self, start: Option<&Start<f64, DIM>>) {
        self.rattle.set_start_time(start.map_or(0.0, |s| s.t0));
        self.initial = start.map(|s| s.state.lift());
        self.pending = start.is_some_and(|s| s.kick == StartKick::Pending);
    }

    /// Sets the x component u_{x,k} of a 2-axis control for stage k (and u_{x,k+1} = 0, the
    /// second half-kick's control of the stage map); nothing for a control along z. Call it
    /// before [`Stepper::reset`] (k = 0) and [`Stepper::advance`].
    #[inline]
    pub(crate) fn set_control_x(&mut self, k: usize, ux: D) {
        if self.bx.is_empty() {
            return;
        }
        let cx = &mut self.rattle.chain_mut().control_x;
        cx[k] = ux;
        if let Some(next) = cx.get_mut(k + 1) {
            *next = D::zero();
        }
    }

    /// Resets `state` to the initial state (the start's S₀, or the chain's start at rest:
    /// straight, or the static start, [`crate::model::Chain::start_attitudes`]) and computes
    /// its consistent multiplier for the control u₀ when it has none (the Newton predictor of
    /// step 0).
    pub(crate) fn reset(&mut self, u0: D) -> Result<()> {
        let st = &mut self.state;
        if let Some(init) = &self.initial {
            st.clone_from(init);
            return self.rattle.prepare(st, 0, u0);
        }
        let q0 = self.rattle.chain().start_attitudes()?;
        for ((q, p), q0) in st.q.iter_mut().zip(st.p.iter_mut()).zip(q0) {
            *q = q0;
            *p = [D::zero(); DIM];
        }
        st.multipliers = None;
        st.tip_target = self.rattle.chain().start_tip_target();
        self.rattle.prepare(st, 0, u0)
    }

    /// x̂_k → x̂_{k+1} = F_k(x̂_k, u_k) (with the half-kick p_k = p̂_k − (h/2) u_k P(q_k) b at
    /// k ≥ 1, and at k = 0 from a start with a pending kick).
    pub(crate) fn advance(&mut self, k: usize, u: D) -> Result<()> {
        self.kick(k, u)?;
        self.rattle.prepare_force(&self.state, k, u)?;
        self.rattle.step(&mut self.state, k, u, D::zero())?;
        Ok(())
    }

    /// The stage's half-kick p_k = p̂_k − (h/2) P(q_k)(u_k b + u_{x,k} b_x) where the stage has
    /// one (k ≥ 1, or a start with a pending kick); returns whether it did ([`Projector::y`]
    /// then holds y_b of the z component).
    pub(crate) fn kick(&mut self, k: usize, u: D) -> Result<bool> {
        if !(k > 0 || self.pending) {
            return Ok(false);
        }
        if !self.bx.is_empty() {
            let ux = self.rattle.chain().control_x(k);
            self.proj.apply(
                self.rattle.chain(),
                &self.state.q,
                &self.bx,
                k,
                &mut self.pb,
            )?;
            for (p, pb) in self.state.p.iter_mut().zip(&self.pb) {
                for d in 0..DIM {
                    p[d] -= pb[d] * ux * self.hh;
                }
            }
        }
        self.proj
            .apply(self.rattle.chain(), &self.state.q, &self.b, k, &mut self.pb)?;
        for (p, pb) in self.state.p.iter_mut().zip(&self.pb) {
            for d in 0..DIM {
                p[d] -= pb[d] * u * self.hh;
            }
        }
        Ok(true)
    }

    /// b = ∂U_q/∂u (block j: l_j e₃ below the control node).
    pub(crate) fn control_direction(&self) -> &[[f64; DIM]] {
        &self.b
    }
}

/// Per-thread scratch of the dual-number stage Jacobians, in the planar or the spatial model.
#[derive(Clone, Debug)]
pub(crate) struct JacobianWorkspace<const DIM: usize = 2> {
    pub(super) stepper: Stepper<Dv, DIM>,
    seed_q: Vec<[[f64; CHUNK]; DIM]>,
    seed_p: Vec<[[f64; CHUNK]; DIM]>,
    dv: Vec<[f64; DIM]>,
    dp: Vec<[f64; DIM]>,
    minv: Vec<[f64; DIM]>,
    basis: Vec<[[f64; DIM]; 2]>,
}

impl<const DIM: usize> JacobianWorkspace<DIM> {
    pub(crate) fn new(model: &StageModel<DIM>) -> Result<Self> {
        let n = model.n;
        Ok(JacobianWorkspace {
            stepper: Stepper::new(model)?,
            seed_q: vec![[[0.0; CHUNK]; DIM]; n],
            seed_p: vec![[[0.0; CHUNK]; DIM]; n],
            dv: vec![[0.0; DIM]; n],
            dp: vec![[0.0; DIM]; n],
            minv: vec![[0.0; DIM]; n],
            basis: vec![[[0.0; DIM]; 2]; n],
        })
    }

    /// Loads x̂_k = (q, p) into the dual stepper with the tangent directions start..end
    /// (ξ_j for j < n_ξ, the controls u_z, u_x for j = n_ξ, n_ξ + 1) seeded into the slots
    /// 0..end − start (E e_j on x̂_k, in the basis e_a(qᵢ) of [`tangent_basis`]:
    /// δqᵢ = e_a δφ_{i,a}, δp = M δv with δvᵢ = e_a δω_{i,a} − qᵢ ω_{i,a} δφ_{i,a}; planar
    /// e = tᵢ, δvᵢ = tᵢ δωᵢ − qᵢ ωᵢ δφᵢ), the Newton start μ, and returns the dual controls
    /// (u_z, u_x).
    ///
    /// Why this chart: the closed-loop rollouts measure δω_{i,a} = ē_a·vᵢ − ω̄_{i,a} in the
    /// nominal's basis (`line_search`), so L is δφ_{i,a} = e_a·δqᵢ, δω_{i,a} = e_a·(M⁻¹δp)ᵢ, and
    /// E above is its inverse on the manifold (|qᵢ| = 1, qᵢ·vᵢ = 0: the −qᵢ ω δφ term keeps the
    /// linearised qᵢ·δvᵢ + δqᵢ·vᵢ = 0), so E L is the identity on tangent vectors and the
    /// Jacobians compose exactly (the costate gradient equals the adjoint's).
    pub(super) fn seed(&mut self, at: &StageAt<'_, DIM>, cols: Range<usize>) -> [Dv; 2] {
        let StagePoint { q, p, omega, mu } = at.x;
        let model = at.model;
        let (start, end) = (cols.start, cols.end);
        let n = model.n;
        let na = DIM - 1;
        let nw = n * na;
        let nx = 2 * nw;
        // Seeds: direction j in slot j − start.
        for s in self.seed_q.iter_mut().chain(self.seed_p.iter_mut()) {
            *s = [[0.0; CHUNK]; DIM];
        }
        let mut u_seed = [[0.0; CHUNK]; 2];
        for j in start..end {
            let slot = j - start;
            if j >= nx {
                u_seed[j - nx][slot] = 1.0;
                continue;
            }
            let (i, a) = ((j % nw) / na, (j % nw) % na);
            let e = tangent_basis(&q[i])[a];
            // δv_i (only pendulum i moves): φ: −qᵢ ω_{i,a}, ω: e_a; δp = M δv = column i of
            // M̄ ⊗ δvᵢ.
            let mut dvi = e;
            if j < nw {
                for d in 0..DIM {
                    self.seed_q[i][d][slot] = e[d];
                    dvi[d] = -q[i][d] * omega[i * na + a];
                }
            }
            for r in 0..n {
                let mri = model.mass[r * n + i];
                for d in 0..DIM {
                    self.seed_p[r][d][slot] = mri * dvi[d];
                }
            }
        }
        let st = &mut self.stepper.state;
        for i in 0..n {
            for d in 0..DIM {
                st.q[i][d] = Dv::new(q[i][d], Derivative::some(SVector::from(self.seed_q[i][d])));
                st.p[i][d] = Dv::new(p[i][d], Derivative::some(SVector::from(self.seed_p[i][d])));
            }
        }
        let m = st.multipliers_mut(mu.len());
        for ((ml, mm), &v) in m.lambda.iter_mut().zip(m.mu.iter_mut()).zip(mu) {
            (*ml, *mm) = (Dv::from_re(v), Dv::from_re(v));
        }
        st.tip_target = [Dv::from_re(0.0); 2];
        let control = |axis: usize, value: f64| {
            if cols.contains(&(nx + axis)) {
                Dv::new(value, Derivative::some(SVector::from(u_seed[axis])))
            } else {
                Dv::from_re(value)
            }
        };
        [control(0, at.u), control(1, at.ux)]
    }

    /// The columns start..end of A_k, B_k from the derivative parts of the dual step's result,
    /// mapped by L_{k+1}: δφ_{i,a} = e_a·δqᵢ, δω_{i,a} = e_a·(M⁻¹δp)ᵢ (planar: tᵢ).
    pub(super) fn read_columns(
        &mut self,
        model: &StageModel<DIM>,
        cols: Range<usize>,
        out: &mut JacobiansMut<'_>,
    ) {
        let start = cols.start;
        let n = model.n;
        let na = DIM - 1;
        let nw = n * na;
        let nx = 2 * nw;
        let st = &self.stepper.state;
        for i in 0..n {
            let mut q = [0.0; DIM];
            for d in 0..DIM {
                q[d] = st.q[i][d].re;
            }
            self.basis[i] = tangent_basis(&q);
        }
        for j in cols {
            let slot = j - start;
            for i in 0..n {
                for d in 0..DIM {
                    self.dv[i][d] = eps(&st.q[i][d], slot);
                    self.dp[i][d] = eps(&st.p[i][d], slot);
                }
            }
            model.chain.apply_inverse_mass(&self.dp, &mut self.minv);
            let col: &mut [f64] = if j < nx {
                &mut out.a[j * nx..(j + 1) * nx]
            } else {
                &mut out.b[(j - nx) * nx..(j - nx + 1) * nx]
            };
            for i in 0..n {
                for a in 0..na {
                    col[i * na + a] = dot(&self.basis[i][a], &self.dv[i]);
                    col[nw + i * na + a] = dot(&self.basis[i][a], &self.minv[i]);
                }
            }
        }
    }

    /// A_k (column-major n_ξ × n_ξ, into `a`) and B_k (n_ξ per control axis, into `b`) at
    /// x̂_k = (q, p) with rates `omega`, Newton start `mu` and controls (u, u_x). With `mu` the
    /// converged λ of the nominal step the real parts are converged at once (bit for bit the
    /// nominal's) and the Newton loop does only its derivative-only update: the implicit
    /// function theorem, one bordered-tridiagonal solve with 8 right-hand sides per chunk.
    pub(crate) fn jacobians(
        &mut self,
        at: StageAt<'_, DIM>,
        mut out: JacobiansMut<'_>,
    ) -> Result<()> {
        for cols in chunks(at.model.ndir()) {
            let [u, ux] = self.seed(&at, cols.clone());
            self.stepper.set_control_x(at.k, ux);
            self.stepper.advance(at.k, u)?;
            self.read_columns(at.model, cols, &mut out);
        }
        Ok(())
    }
}

/// A moving stage point for the tests of this module and of `hessian.rs`.
#[cfg(test)]
pub(crate) mod fixture {
    use super::*;

    /// Stage k of the long-horizon scene (drag) after k steps of a varying control: the
    /// point, its rates, the Newton predictor μ the step starts from, the step's converged λ
    /// and the control.
    pub(crate) struct Point {
        pub q: Vec<[f64; 2]>,
        pub p: Vec<[f64; 2]>,
        pub omega: Vec<f64>,
        pub mu: Vec<f64>,
        pub lambda: Vec<f64>,
        pub u: f64,
    }

    pub(crate) fn point(model: &StageModel, k: usize) -> Point {
        let u = |k: usize| 3.0 * (0.3 * k as f64).sin() + 1.0;
        let mut st = Stepper::<f64>::new(model).unwrap();
        st.reset(u(0)).unwrap();
        for j in 0..k {
            st.advance(j, u(j)).unwrap();
        }
        let mu = st
            .state
            .multipliers
            .as_ref()
            .map_or_else(Vec::new, |m| m.mu.clone());
        let (q, p) = (st.state.q.clone(), st.state.p.clone());
        let mut omega = vec![0.0; model.n];
        let mut scratch = vec![[0.0; 2]; model.n];
        model.rates(&q, &p, &mut scratch, &mut omega);
        st.advance(k, u(k)).unwrap();
        let lambda = st.state.multipliers.as_ref().unwrap().lambda.clone();
        Point {
            q,
            p,
            omega,
            mu,
            lambda,
            u: u(k),
        }
    }
}

#[cfg(test)]
mod tests;
