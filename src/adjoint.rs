//! Discrete adjoint of the RATTLE map: exact gradients (to round-off) of bending-moment objectives
//! with respect to the controls and the physical parameters, checkpointing, and Hessian-vector
//! products by forward-over-adjoint (SPEC §2-§3, thesis §3.3).
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
//! with K = ∂²U/∂q² (block-tridiagonal, [`Chain::force_jacobian_product`]) and J the Newton matrix
//! of the step. Every product is O(n), so a gradient costs a small constant times one simulation,
//! whatever the number of controls. Controls and parameters collect −h/2 c̄ · ∂U_q/∂θ and
//! −h/2 b̄ · ∂U_q/∂θ per step, plus the mass-matrix and drag terms.
//!
//! # Checkpointing
//! The forward pass keeps every K-th state; the reverse pass recomputes each segment forward into
//! a buffer of K states (memory O(n (N/K + K)), K ≈ √N by default). Recomputation repeats exactly
//! the forward arithmetic, so the gradient is bit-for-bit the same for every K.

use crate::error::{Error, Result};
use crate::model::{dot, zi, Chain, Parameter, Scalar, TipCondition};
use crate::rattle::{half_step_momentum, newton_jacobian, Rattle, State};
use crate::scene::{ControlKind, ObjectiveKind, Scene};
use crate::tridiag::{BorderedTridiag, ZeroPivot};
use num_dual::{Dual, Dual64};

/// What a stage cost sees at t_k.
#[derive(Clone, Copy, Debug)]
pub struct Stage<'a, D> {
    /// Step index k (0..=N).
    pub k: usize,
    /// N.
    pub steps: usize,
    /// Step h.
    pub h: f64,
    /// Base bending moment M₀(t_k) (eq. 3.1.3).
    pub moment: D,
    /// Control u_k.
    pub control: D,
    /// Node z-displacements z₁..zₙ at t_k (filled only when [`Objective::uses_positions`]).
    pub z: &'a [D],
}

/// A sum of stage costs ℓ_k(M₀(t_k), u_k, z(t_k)), k = 0..=N, written once over [`Scalar`] so
/// that its partial derivatives come from (nested) dual numbers.
pub trait Objective: Send + Sync {
    /// The stage cost ℓ_k.
    fn stage<D: Scalar>(&self, s: Stage<'_, D>) -> D;
    /// Whether ℓ depends on the node displacements z (then its partials cost n evaluations).
    fn uses_positions(&self) -> bool {
        false
    }
}

/// The thesis's bending-moment objectives (§3.3) with an optional effort penalty.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BendingObjective {
    /// c = M₀(t_N)² (eq. 3.3.2) or c_sum = Σ_{k=0}^{N} M₀(t_k)² (eq. 3.3.4).
    pub kind: ObjectiveKind,
    /// ρ ≥ 0 of the control-effort penalty ρ h Σ_{k=0}^{N} u_k² \[N²m²/(N² s)\].
    pub effort: f64,
}

impl BendingObjective {
    /// c = M₀(t_N)² (eq. 3.3.2).
    pub fn final_moment() -> Self {
        BendingObjective {
            kind: ObjectiveKind::Final,
            effort: 0.0,
        }
    }
    /// c_sum = Σ M₀(t_k)² (eq. 3.3.4).
    pub fn summed_moment() -> Self {
        BendingObjective {
            kind: ObjectiveKind::Sum,
            effort: 0.0,
        }
    }
    /// Adds the effort penalty ρ h Σ u_k².
    pub fn with_effort(mut self, rho: f64) -> Self {
        self.effort = rho;
        self
    }
}

impl Objective for BendingObjective {
    fn stage<D: Scalar>(&self, s: Stage<'_, D>) -> D {
        let m = match self.kind {
            ObjectiveKind::Final if s.k != s.steps => D::zero(),
            _ => s.moment * s.moment,
        };
        if self.effort > 0.0 {
            m + s.control * s.control * (self.effort * s.h)
        } else {
            m
        }
    }
}

/// The residual r = M₀(t_N) itself, not squared: c = r² (eq. 3.3.2), so Newton or Gauss-Newton
/// on r with the adjoint's ∇r finds the zeros of c exactly (Tables 3.1 and 3.3).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct FinalMomentResidual;

impl Objective for FinalMomentResidual {
    fn stage<D: Scalar>(&self, s: Stage<'_, D>) -> D {
        if s.k == s.steps {
            s.moment
        } else {
            D::zero()
        }
    }
}

/// Squared displacement of one node, Σ_k z_i(t_k)² (or its final value): an objective that also
/// sees beams without a base spring (pinned-pinned, where M₀ ≡ 0).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct NodeDisplacementObjective {
    /// Node 1..=n.
    pub node: usize,
    /// Final value only, or summed over k.
    pub kind: ObjectiveKind,
}

impl Objective for NodeDisplacementObjective {
    fn stage<D: Scalar>(&self, s: Stage<'_, D>) -> D {
        match self.kind {
            ObjectiveKind::Final if s.k != s.steps => D::zero(),
            _ => s.z[self.node - 1] * s.z[self.node - 1],
        }
    }
    fn uses_positions(&self) -> bool {
        true
    }
}

/// A control parametrisation θ ↦ (u_0, …, u_N) with its transpose product.
pub trait ControlMap: Send + Sync {
    /// Number of parameters θ.
    fn n_params(&self) -> usize;
    /// Writes u_0..u_N (`u.len()` = N + 1) from θ.
    fn controls<D: Scalar>(&self, theta: &[D], u: &mut [D]);
    /// Accumulates θ̄ = (∂u/∂θ)ᵀ ū.
    fn transpose<D: Scalar>(&self, u_bar: &[D], theta_bar: &mut [D]);
}

/// One constant force u for all k (1 parameter).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct ConstantControl;

impl ControlMap for ConstantControl {
    fn n_params(&self) -> usize {
        1
    }
    fn controls<D: Scalar>(&self, theta: &[D], u: &mut [D]) {
        u.iter_mut().for_each(|x| *x = theta[0]);
    }
    fn transpose<D: Scalar>(&self, u_bar: &[D], theta_bar: &mut [D]) {
        theta_bar[0] += u_bar.iter().fold(D::zero(), |a, b| a + *b);
    }
}

/// One force per time t_k (N + 1 parameters; u_N only reaches p_N, thesis §3.3.1).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PerStepControl {
    /// N.
    pub steps: usize,
}

impl ControlMap for PerStepControl {
    fn n_params(&self) -> usize {
        self.steps + 1
    }
    fn controls<D: Scalar>(&self, theta: &[D], u: &mut [D]) {
        u.copy_from_slice(theta);
    }
    fn transpose<D: Scalar>(&self, u_bar: &[D], theta_bar: &mut [D]) {
        for (t, b) in theta_bar.iter_mut().zip(u_bar) {
            *t += *b;
        }
    }
}

/// Piecewise-constant control on a coarser grid: `pieces` values, piece j covering the steps
/// k with ⌊k · pieces / (N + 1)⌋ = j (so long horizons are optimised with few parameters).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PiecewiseControl {
    /// N.
    pub steps: usize,
    /// Number of pieces (1..=N + 1).
    pub pieces: usize,
}

impl PiecewiseControl {
    fn piece(&self, k: usize) -> usize {
        k * self.pieces / (self.steps + 1)
    }
}

impl ControlMap for PiecewiseControl {
    fn n_params(&self) -> usize {
        self.pieces
    }
    fn controls<D: Scalar>(&self, theta: &[D], u: &mut [D]) {
        for (k, x) in u.iter_mut().enumerate() {
            *x = theta[self.piece(k)];
        }
    }
    fn transpose<D: Scalar>(&self, u_bar: &[D], theta_bar: &mut [D]) {
        for (k, b) in u_bar.iter().enumerate() {
            theta_bar[self.piece(k)] += *b;
        }
    }
}

/// Any of the three built-in parametrisations (what a scene file can ask for).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Parametrisation {
    /// [`ConstantControl`].
    Constant,
    /// [`PerStepControl`].
    PerStep(PerStepControl),
    /// [`PiecewiseControl`].
    Piecewise(PiecewiseControl),
}

impl ControlMap for Parametrisation {
    fn n_params(&self) -> usize {
        match self {
            Parametrisation::Constant => 1,
            Parametrisation::PerStep(p) => p.n_params(),
            Parametrisation::Piecewise(p) => p.n_params(),
        }
    }
    fn controls<D: Scalar>(&self, theta: &[D], u: &mut [D]) {
        match self {
            Parametrisation::Constant => ConstantControl.controls(theta, u),
            Parametrisation::PerStep(p) => p.controls(theta, u),
            Parametrisation::Piecewise(p) => p.controls(theta, u),
        }
    }
    fn transpose<D: Scalar>(&self, u_bar: &[D], theta_bar: &mut [D]) {
        match self {
            Parametrisation::Constant => ConstantControl.transpose(u_bar, theta_bar),
            Parametrisation::PerStep(p) => p.transpose(u_bar, theta_bar),
            Parametrisation::Piecewise(p) => p.transpose(u_bar, theta_bar),
        }
    }
}

/// How the reverse sweep gets the forward states.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Checkpointing {
    /// Every state is kept (memory O(nN), no recomputation).
    StoreAll,
    /// Every K-th state is kept, segments are recomputed (memory O(n(N/K + K))).
    Every(usize),
    /// K = ⌈√N⌉: memory O(n√N), one extra forward sweep.
    Sqrt,
    /// Store every state while the trajectory fits in [`AUTO_MEMORY_BUDGET`] bytes (no
    /// recomputation: the gradient then costs one forward and one reverse sweep), otherwise
    /// K = ⌈√N⌉ (memory O(n√N), one extra forward sweep).
    #[default]
    Auto,
}

/// Memory for stored states below which [`Checkpointing::Auto`] keeps every state: 256 MiB.
pub const AUTO_MEMORY_BUDGET: usize = 256 << 20;

impl Checkpointing {
    fn interval(self, steps: usize, state_bytes: usize) -> usize {
        match self {
            Checkpointing::StoreAll => 1,
            Checkpointing::Every(k) => k.clamp(1, steps.max(1)),
            Checkpointing::Auto
                if (steps + 1).saturating_mul(state_bytes) <= AUTO_MEMORY_BUDGET =>
            {
                1
            }
            Checkpointing::Auto | Checkpointing::Sqrt => {
                ((steps as f64).sqrt().ceil() as usize).max(1)
            }
        }
    }
}

/// Value and gradients from one forward and one reverse sweep.
#[derive(Clone, Debug, PartialEq)]
pub struct AdjointResult<D> {
    /// The objective.
    pub value: D,
    /// ∂J/∂u_k, k = 0..=N.
    pub control_gradient: Vec<D>,
    /// ∂J/∂θ for the requested physical parameters, in request order.
    pub parameter_gradient: Vec<D>,
    /// Bytes of forward states held at the peak (checkpoints plus the segment buffer).
    pub state_bytes: usize,
}

/// Forward states stored flat (one allocation per array, sized once), for the reverse sweep.
struct StateStore<D, const DIM: usize> {
    n: usize,
    nc: usize,
    q: Vec<[D; DIM]>,
    p: Vec<[D; DIM]>,
    lambda: Vec<D>,
    mu: Vec<D>,
    tip: Vec<[D; 2]>,
}

/// A stored state, borrowed.
struct StateView<'a, D, const DIM: usize> {
    q: &'a [[D; DIM]],
    p: &'a [[D; DIM]],
    lambda: &'a [D],
    mu: &'a [D],
    tip: [D; 2],
}

impl<D: Scalar, const DIM: usize> StateStore<D, DIM> {
    fn new(n: usize, nc: usize, capacity: usize) -> Self {
        StateStore {
            n,
            nc,
            q: Vec::with_capacity(capacity * n),
            p: Vec::with_capacity(capacity * n),
            lambda: Vec::with_capacity(capacity * nc),
            mu: Vec::with_capacity(capacity * nc),
            tip: Vec::with_capacity(capacity),
        }
    }
    fn push(&mut self, s: &State<D, DIM>) {
        self.q.extend_from_slice(&s.q);
        self.p.extend_from_slice(&s.p);
        self.lambda.extend_from_slice(&s.lambda);
        self.mu.extend_from_slice(&s.mu);
        self.tip.push(s.tip_target);
    }
    fn clear(&mut self) {
        self.q.clear();
        self.p.clear();
        self.lambda.clear();
        self.mu.clear();
        self.tip.clear();
    }
    fn len(&self) -> usize {
        self.tip.len()
    }
    fn capacity(&self) -> usize {
        self.tip.capacity()
    }
    fn view(&self, i: usize) -> StateView<'_, D, DIM> {
        let (n, nc) = (self.n, self.nc);
        StateView {
            q: &self.q[i * n..(i + 1) * n],
            p: &self.p[i * n..(i + 1) * n],
            lambda: &self.lambda[i * nc..(i + 1) * nc],
            mu: &self.mu[i * nc..(i + 1) * nc],
            tip: self.tip[i],
        }
    }
    fn load(&self, i: usize, s: &mut State<D, DIM>) {
        let v = self.view(i);
        s.q.copy_from_slice(v.q);
        s.p.copy_from_slice(v.p);
        s.lambda.copy_from_slice(v.lambda);
        s.mu.copy_from_slice(v.mu);
        s.tip_target = v.tip;
    }
}

/// Scratch memory of a reverse step (allocated once per sweep).
struct AdjointWorkspace<D, const DIM: usize> {
    fk: Vec<[D; DIM]>,
    a: Vec<[D; DIM]>,
    c: Vec<[D; DIM]>,
    phalf: Vec<[D; DIM]>,
    w: Vec<[D; DIM]>,
    tmp: Vec<[D; DIM]>,
    tmp2: Vec<[D; DIM]>,
    bbar: Vec<[D; DIM]>,
    phbar: Vec<[D; DIM]>,
    rhs: Vec<D>,
    scal: Vec<D>,
    tri: BorderedTridiag<D>,
}

impl<D: Scalar, const DIM: usize> AdjointWorkspace<D, DIM> {
    fn new(ch: &Chain<D, DIM>) -> Self {
        let n = ch.n();
        let v = vec![[D::zero(); DIM]; n];
        AdjointWorkspace {
            fk: v.clone(),
            a: v.clone(),
            c: v.clone(),
            phalf: v.clone(),
            w: vec![[D::one(); DIM]; n],
            tmp: v.clone(),
            tmp2: v.clone(),
            bbar: v.clone(),
            phbar: v,
            rhs: vec![D::zero(); ch.n_constraints()],
            scal: vec![D::zero(); n],
            tri: BorderedTridiag::new(n, ch.has_tip_constraint()),
        }
    }
}

fn singular(step: usize, zp: ZeroPivot) -> Error {
    Error::SingularSystem {
        step,
        index: zp.index,
        pivot: zp.pivot,
    }
}

/// Evaluates a stage cost and accumulates its partial derivatives into q̄_k, ū_k and k̄₁, by nested
/// dual numbers (so that this works for any `D`, including the `Dual64` of Hessian-vector
/// products). `zbuf` is scratch of length n.
struct StageEval<'a, O, D> {
    obj: &'a O,
    steps: usize,
    h: f64,
    zbuf: Vec<Dual<D>>,
    zpos: Vec<D>,
}

impl<O: Objective, D: Scalar> StageEval<'_, O, D> {
    fn value<const DIM: usize>(&mut self, ch: &Chain<D, DIM>, k: usize, q: &[[D; DIM]], u: D) -> D {
        let m = ch.base_moment(q);
        if self.obj.uses_positions() {
            positions_z(ch, q, &mut self.zpos);
        }
        self.obj.stage(Stage {
            k,
            steps: self.steps,
            h: self.h,
            moment: m,
            control: u,
            z: &self.zpos,
        })
    }

    #[allow(clippy::too_many_arguments)]
    fn accumulate<const DIM: usize>(
        &mut self,
        ch: &Chain<D, DIM>,
        k: usize,
        q: &[[D; DIM]],
        u: D,
        qbar: &mut [[D; DIM]],
        ubar: &mut [D],
        k1bar: Option<&mut D>,
    ) {
        let zi_ = zi::<DIM>();
        let scale = ch.moment_stiffness * 2.0 * ch.inv_lengths[0];
        let m = scale * q[0][zi_];
        let st = |obj: &O, steps, h, m: Dual<D>, u: Dual<D>, z: &[Dual<D>]| {
            obj.stage(Stage {
                k,
                steps,
                h,
                moment: m,
                control: u,
                z,
            })
        };
        let uses_z = self.obj.uses_positions();
        if uses_z {
            let mut acc = D::zero();
            for (i, zb) in self.zbuf.iter_mut().enumerate() {
                acc += ch.lengths[i] * q[i][zi_];
                *zb = Dual::from_re(acc);
            }
        }
        let zslice: &[Dual<D>] = if uses_z { &self.zbuf } else { &[] };
        let dm = st(
            self.obj,
            self.steps,
            self.h,
            Dual::new(m, D::one()),
            Dual::from_re(u),
            zslice,
        )
        .eps;
        let du = st(
            self.obj,
            self.steps,
            self.h,
            Dual::from_re(m),
            Dual::new(u, D::one()),
            zslice,
        )
        .eps;
        qbar[0][zi_] += dm * scale;
        ubar[k] += du;
        if let Some(kb) = k1bar {
            *kb += dm * 2.0 * q[0][zi_] * ch.inv_lengths[0];
        }
        if uses_z {
            // ∂ℓ/∂z_i, then q̄_{j,z} += l_j Σ_{i ≥ j} ∂ℓ/∂z_i.
            let n = ch.n();
            let mut acc = D::zero();
            for i in (0..n).rev() {
                let zi_re = self.zbuf[i].re;
                self.zbuf[i] = Dual::new(zi_re, D::one());
                let g = st(
                    self.obj,
                    self.steps,
                    self.h,
                    Dual::from_re(m),
                    Dual::from_re(u),
                    &self.zbuf,
                )
                .eps;
                self.zbuf[i] = Dual::from_re(zi_re);
                acc += g;
                qbar[i][zi_] += acc * ch.lengths[i];
            }
        }
    }
}

/// Node z-displacements z₁..zₙ into `out` (resized once to n).
fn positions_z<D: Scalar, const DIM: usize>(ch: &Chain<D, DIM>, q: &[[D; DIM]], out: &mut Vec<D>) {
    let z = zi::<DIM>();
    out.resize(ch.n(), D::zero());
    let mut acc = D::zero();
    for ((o, qi), l) in out.iter_mut().zip(q).zip(&ch.lengths) {
        acc += *l * qi[z];
        *o = acc;
    }
}

/// Validates the parameters requested for a gradient.
fn check_parameters<D: Scalar, const DIM: usize>(
    ch: &Chain<D, DIM>,
    params: &[Parameter],
) -> Result<()> {
    for &p in params {
        let ok = match p {
            Parameter::Mass => ch.has_uniform_mass(),
            Parameter::Drag => ch.has_drag(),
            Parameter::BaseStiffness => ch.has_spring[0],
            Parameter::TipStiffness => ch.has_spring[ch.n()],
            Parameter::InteriorStiffness => true,
            Parameter::LoadForce(i) => ch.loads.iter().any(|l| l.scene_index == i),
        };
        if !ok {
            return Err(Error::InvalidArgument {
                name: "parameter",
                reason: format!(
                    "{p:?} is not a parameter of this scene (mass needs uniform masses, drag needs \
                     D > 0, end stiffnesses need an end spring, loads need that load)"
                ),
            });
        }
    }
    Ok(())
}

/// One forward and one reverse sweep: J, ∂J/∂u_k and ∂J/∂θ (physical parameters), generic over
/// the scalar (`Dual64` with seeded inputs gives Hessian-vector products).
pub fn adjoint_gradient<D: Scalar, O: Objective, const DIM: usize>(
    chain: &Chain<D, DIM>,
    h: f64,
    steps: usize,
    u: &[D],
    objective: &O,
    params: &[Parameter],
    checkpointing: Checkpointing,
) -> Result<AdjointResult<D>> {
    if u.len() != steps + 1 {
        return Err(Error::InvalidArgument {
            name: "controls",
            reason: format!("expected N + 1 = {} values, got {}", steps + 1, u.len()),
        });
    }
    if let Some(i) = u.iter().position(|x| !x.re().is_finite()) {
        return Err(Error::InvalidArgument {
            name: "controls",
            reason: format!("u_{i} is not finite"),
        });
    }
    check_parameters(chain, params)?;
    let n = chain.n();
    let state_size = (2 * n * DIM + 2 * chain.n_constraints() + 2) * std::mem::size_of::<D>();
    let kk = checkpointing.interval(steps, state_size);
    let mut stage = StageEval {
        obj: objective,
        steps,
        h,
        zbuf: vec![Dual::from_re(D::zero()); n],
        zpos: Vec::new(),
    };
    let k1_param = params.iter().position(|p| *p == Parameter::BaseStiffness);

    // Forward sweep with checkpoints (flat storage: no allocation per stored state).
    let mut rattle = Rattle::new(chain.clone(), h)?;
    let mut state = rattle.straight_state();
    rattle.prepare(&mut state, 0, u[0])?;
    let mut value = stage.value(chain, 0, &state.q, u[0]);
    let nc = chain.n_constraints();
    let mut checkpoints = StateStore::<D, DIM>::new(n, nc, steps / kk + 2);
    checkpoints.push(&state);
    for k in 0..steps {
        rattle.step(&mut state, k, u[k], u[k + 1])?;
        value += stage.value(chain, k + 1, &state.q, u[k + 1]);
        if (k + 1) % kk == 0 || k + 1 == steps {
            checkpoints.push(&state);
        }
    }

    // Reverse sweep.
    let mut ws = AdjointWorkspace::new(chain);
    let mut qbar = vec![[D::zero(); DIM]; n];
    let mut pbar = vec![[D::zero(); DIM]; n];
    let mut tip_bar = [D::zero(); 2];
    let mut ubar = vec![D::zero(); steps + 1];
    let mut thbar = vec![D::zero(); params.len()];
    let n_segments = checkpoints.len() - 1;
    stage.accumulate(
        chain,
        steps,
        checkpoints.view(n_segments).q,
        u[steps],
        &mut qbar,
        &mut ubar,
        k1_param.map(|i| &mut thbar[i]),
    );

    // Interior states S_{a+1..b−1} of the current segment, recomputed from S_a.
    let mut buffer = StateStore::<D, DIM>::new(n, nc, kk.saturating_sub(1));
    for seg in (0..n_segments).rev() {
        let a = seg * kk;
        let b = (a + kk).min(steps);
        buffer.clear();
        if b - a > 1 {
            checkpoints.load(seg, &mut state);
            rattle.prepare_force(&state, a, u[a])?;
            for k in a..b - 1 {
                rattle.step(&mut state, k, u[k], u[k + 1])?;
                buffer.push(&state);
            }
        }
        let view = |k: usize| {
            if k == a {
                checkpoints.view(seg)
            } else if k == b {
                checkpoints.view(seg + 1)
            } else {
                buffer.view(k - a - 1)
            }
        };
        for k in (a..b).rev() {
            let (sk, sk1) = (view(k), view(k + 1));
            reverse_step(
                chain,
                h,
                k,
                &sk,
                &sk1,
                u[k],
                u[k + 1],
                &mut ws,
                &mut qbar,
                &mut pbar,
                &mut tip_bar,
                &mut ubar,
                params,
                &mut thbar,
            )?;
            stage.accumulate(
                chain,
                k,
                sk.q,
                u[k],
                &mut qbar,
                &mut ubar,
                k1_param.map(|i| &mut thbar[i]),
            );
        }
    }
    let state_bytes = (checkpoints.capacity() + buffer.capacity()) * state_size;
    Ok(AdjointResult {
        value,
        control_gradient: ubar,
        parameter_gradient: thbar,
        state_bytes,
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
    if u.len() != steps + 1 {
        return Err(Error::InvalidArgument {
            name: "controls",
            reason: format!("expected N + 1 = {} values, got {}", steps + 1, u.len()),
        });
    }
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

/// Adds −h/2 Σ_{j < c} l_j w_{j,z} (the control's force term contracted with w) to `ubar`.
#[inline]
fn control_contraction<D: Scalar, const DIM: usize>(
    ch: &Chain<D, DIM>,
    w: &[[D; DIM]],
    hh: f64,
) -> D {
    match ch.control_node {
        Some(c) => {
            let z = zi::<DIM>();
            let mut s = D::zero();
            for j in 0..c {
                s += ch.lengths[j] * w[j][z];
            }
            -s * hh
        }
        None => D::zero(),
    }
}

/// One reverse step k + 1 → k of the discrete adjoint (see the module docs).
#[allow(clippy::too_many_arguments)]
fn reverse_step<D: Scalar, const DIM: usize>(
    ch: &Chain<D, DIM>,
    h: f64,
    k: usize,
    sk: &StateView<'_, D, DIM>,
    sk1: &StateView<'_, D, DIM>,
    u_k: D,
    u_k1: D,
    ws: &mut AdjointWorkspace<D, DIM>,
    qbar: &mut [[D; DIM]],
    pbar: &mut [[D; DIM]],
    tip_bar: &mut [D; 2],
    ubar: &mut [D],
    params: &[Parameter],
    thbar: &mut [D],
) -> Result<()> {
    let n = ch.n();
    let z = zi::<DIM>();
    let hh = 0.5 * h;
    let bordered = ch.has_tip_constraint();
    let (q, q1, p1) = (sk.q, sk1.q, sk1.p);
    let (lam, mu) = (sk1.lambda, sk1.mu);
    let (tk, tk1) = (k as f64 * h, (k + 1) as f64 * h);

    // Recompute the step's intermediates (same arithmetic as the forward step).
    ch.potential_gradient(q, tk, u_k, k, &mut ws.fk)?;
    for i in 0..n {
        for d in 0..DIM {
            ws.a[i][d] = sk.p[i][d] - ws.fk[i][d] * hh;
        }
    }
    half_step_momentum(ch, q, &ws.a, lam, h, &mut ws.c, &mut ws.phalf, &mut ws.w);

    // Projection: A ŷ = Ĝ(q′) p̄′.
    {
        let tri = &mut ws.tri;
        for i in 0..n {
            ws.rhs[i] = dot(&q1[i], &pbar[i]);
            let (dii, off) = ch.minv_entries(i);
            tri.diag[i] = dot(&q1[i], &q1[i]) * dii;
            if i + 1 < n {
                let v = dot(&q1[i], &q1[i + 1]) * off;
                tri.upper[i] = v;
                tri.lower[i + 1] = v;
            }
        }
        if bordered {
            let mut s = D::zero();
            for i in 0..n {
                s += ch.lengths[i] * pbar[i][z];
                tri.col[i] = D::zero();
                tri.row[i] = D::zero();
            }
            ws.rhs[n] = s;
            let inv_mn = ch.inv_masses[n - 1];
            let v = q1[n - 1][z] * inv_mn * ch.inv_lengths[n - 1];
            tri.col[n - 1] = v;
            tri.row[n - 1] = v;
            tri.corner = inv_mn;
        }
        tri.solve(&mut ws.rhs).map_err(|zp| singular(k, zp))?;
    }
    // b̄ = p̄′ − M⁻¹ Ĝᵀ ŷ
    for i in 0..n {
        for d in 0..DIM {
            ws.tmp[i][d] = ws.rhs[i] * q1[i][d];
        }
        if bordered {
            ws.tmp[i][z] += ws.rhs[n] * ch.lengths[i];
        }
    }
    ch.apply_inverse_mass(&ws.tmp, &mut ws.tmp2);
    for i in 0..n {
        for d in 0..DIM {
            ws.bbar[i][d] = pbar[i][d] - ws.tmp2[i][d];
        }
    }
    // q̄′ += −(h/2) μᵢ b̄ᵢ − ŷᵢ (M⁻¹p′)ᵢ
    ch.apply_inverse_mass(p1, &mut ws.tmp2);
    for i in 0..n {
        let y = mu[i] * hh;
        for d in 0..DIM {
            qbar[i][d] -= y * ws.bbar[i][d] + ws.rhs[i] * ws.tmp2[i][d];
        }
    }
    let mass_param = params.iter().position(|p| *p == Parameter::Mass);
    let drag_param = params.iter().position(|p| *p == Parameter::Drag);
    let reaction = ch.tip == TipCondition::Reaction;
    if reaction {
        tip_bar[1] += ws.rhs[n];
        if let Some(ip) = mass_param {
            thbar[ip] += ws.rhs[n] * sk1.tip[1] * ch.inv_masses[0];
        }
    }

    // Second half-step: b = p½ − h/2 U_q(q′) − h/2 D p½|p½|.
    if let Some(dr) = ch.drag {
        let mut dbar = D::zero();
        for i in 0..n {
            for d in 0..DIM {
                let p = ws.phalf[i][d];
                ws.phbar[i][d] = ws.bbar[i][d] * (-(dr * h * p.abs()) + 1.0);
                dbar += ws.bbar[i][d] * p * p.abs();
            }
        }
        if let Some(ip) = drag_param {
            thbar[ip] -= dbar * hh;
        }
    } else {
        ws.phbar.copy_from_slice(&ws.bbar);
    }
    ch.force_jacobian_product(q1, &ws.bbar, D::from(-hh), qbar);
    ubar[k + 1] += control_contraction(ch, &ws.bbar, hh);
    for (tb, p) in thbar.iter_mut().zip(params) {
        *tb -= ch.force_parameter_contraction(q1, tk1, &ws.bbar, *p) * hh;
    }

    // Newton system: λ̄ = −h/2 Ĝ(q_k)(W ⊙ S), S = p̄½ + h M⁻¹ q̄′; Jᵀν = λ̄.
    ch.apply_inverse_mass(qbar, &mut ws.tmp);
    for i in 0..n {
        for d in 0..DIM {
            ws.tmp[i][d] = (ws.phbar[i][d] + ws.tmp[i][d] * h) * ws.w[i][d];
        }
        ws.rhs[i] = -dot(&q[i], &ws.tmp[i]) * hh;
    }
    if bordered {
        let mut s = D::zero();
        for i in 0..n {
            s += ch.lengths[i] * ws.tmp[i][z];
        }
        ws.rhs[n] = -s * hh;
    }
    newton_jacobian(ch, q, q1, &ws.w, h, &mut ws.tri, &mut ws.scal);
    ws.tri
        .solve_transpose(&mut ws.rhs)
        .map_err(|zp| singular(k, zp))?;
    for i in 0..n {
        let nu = ws.rhs[i];
        for d in 0..DIM {
            qbar[i][d] -= nu * q1[i][d];
        }
        if bordered {
            qbar[i][z] -= ws.rhs[n] * ch.lengths[i];
        }
    }
    if reaction {
        tip_bar[0] += ws.rhs[n];
    }
    if let Some(ip) = mass_param {
        // q′ = q + h M⁻¹ p½ with M⁻¹ ∝ 1/m: ∂q′/∂m = −(q′ − q)/m.
        let mut s = D::zero();
        for i in 0..n {
            for d in 0..DIM {
                s += qbar[i][d] * (q1[i][d] - q[i][d]);
            }
        }
        thbar[ip] -= s * ch.inv_masses[0];
    }
    // c̄ = W ⊙ (p̄½ + h M⁻¹ q̄′)  (into ws.c)
    ch.apply_inverse_mass(qbar, &mut ws.tmp);
    for i in 0..n {
        for d in 0..DIM {
            ws.c[i][d] = (ws.phbar[i][d] + ws.tmp[i][d] * h) * ws.w[i][d];
        }
    }
    if let (Some(ip), true) = (drag_param, ch.has_drag()) {
        let mut s = D::zero();
        for i in 0..n {
            for d in 0..DIM {
                let p = ws.phalf[i][d];
                s += ws.c[i][d] * p * p.abs();
            }
        }
        thbar[ip] -= s * hh;
    }

    // First half-step: c = p_k − h/2 U_q(q_k) − h/2 Ĝ(q_k)ᵀλ.
    for i in 0..n {
        let l = lam[i] * hh;
        for d in 0..DIM {
            pbar[i][d] = ws.c[i][d];
            qbar[i][d] -= l * ws.c[i][d];
        }
    }
    ch.force_jacobian_product(q, &ws.c, D::from(-hh), qbar);
    ubar[k] += control_contraction(ch, &ws.c, hh);
    for (tb, p) in thbar.iter_mut().zip(params) {
        *tb -= ch.force_parameter_contraction(q, tk, &ws.c, *p) * hh;
    }

    // Tip target dynamics of the reaction-force variant (Störmer–Verlet for m_n ζ̈ = −u).
    if reaction {
        let inv_mn = ch.inv_masses[n - 1];
        let v_half_bar = tip_bar[1] + tip_bar[0] * h;
        ubar[k + 1] -= tip_bar[1] * inv_mn * hh;
        ubar[k] -= v_half_bar * inv_mn * hh;
        if let Some(ip) = mass_param {
            thbar[ip] += (tip_bar[1] * u_k1 + v_half_bar * u_k) * inv_mn * inv_mn * hh;
        }
        tip_bar[1] = v_half_bar;
    }
    Ok(())
}

/// An optimal-control problem on a scene: J(θ) = Σ ℓ_k(M₀(t_k), u_k(θ)) over the RATTLE
/// trajectory, with exact gradients by the discrete adjoint and Hessian-vector products by
/// forward-over-adjoint.
#[derive(Clone, Debug)]
pub struct ControlProblem<P = Parametrisation, O = BendingObjective> {
    chain: Chain<f64, 2>,
    h: f64,
    steps: usize,
    map: P,
    objective: O,
    checkpointing: Checkpointing,
}

impl ControlProblem<Parametrisation, BendingObjective> {
    /// The problem a scene file describes: its `[control]` (node and kind; default: constant at
    /// the tip) and `[objective]` (default: final), without effort penalty.
    pub fn from_scene(scene: &Scene) -> Result<Self> {
        let map = match scene.control.as_ref().map(|c| c.kind) {
            Some(ControlKind::PerStep) => Parametrisation::PerStep(PerStepControl {
                steps: scene.time.steps,
            }),
            _ => Parametrisation::Constant,
        };
        let obj = BendingObjective {
            kind: scene.objective.unwrap_or(ObjectiveKind::Final),
            effort: 0.0,
        };
        ControlProblem::new(scene, map, obj)
    }
}

impl<P: ControlMap, O: Objective> ControlProblem<P, O> {
    /// A problem with the given parametrisation and objective; the control acts at the scene's
    /// control node (default: the tip n).
    pub fn new(scene: &Scene, map: P, objective: O) -> Result<Self> {
        let mut chain = Chain::<f64, 2>::from_scene(scene)?;
        if chain.control_node().is_none() {
            chain.set_control_node(Some(scene.n()))?;
        }
        Ok(ControlProblem {
            chain,
            h: scene.time.step,
            steps: scene.time.steps,
            map,
            objective,
            checkpointing: Checkpointing::default(),
        })
    }

    /// Sets the checkpointing strategy (default [`Checkpointing::Auto`]).
    pub fn with_checkpointing(mut self, c: Checkpointing) -> Self {
        self.checkpointing = c;
        self
    }

    /// Number of parameters θ.
    pub fn n_params(&self) -> usize {
        self.map.n_params()
    }

    /// Number of steps N.
    pub fn steps(&self) -> usize {
        self.steps
    }

    /// The model (f64).
    pub fn chain(&self) -> &Chain<f64, 2> {
        &self.chain
    }

    /// The parametrisation.
    pub fn map(&self) -> &P {
        &self.map
    }

    /// The step h.
    pub fn h(&self) -> f64 {
        self.h
    }

    /// The objective.
    pub fn objective(&self) -> &O {
        &self.objective
    }

    fn check_theta(&self, theta: &[f64], name: &'static str) -> Result<()> {
        if theta.len() != self.map.n_params() {
            return Err(Error::InvalidArgument {
                name,
                reason: format!(
                    "expected {} values, got {}",
                    self.map.n_params(),
                    theta.len()
                ),
            });
        }
        if let Some(i) = theta.iter().position(|x| !x.is_finite()) {
            return Err(Error::InvalidArgument {
                name,
                reason: format!("entry {i} is not finite"),
            });
        }
        Ok(())
    }

    /// The per-step controls u_0..u_N of θ.
    pub fn controls(&self, theta: &[f64]) -> Result<Vec<f64>> {
        self.check_theta(theta, "theta")?;
        let mut u = vec![0.0; self.steps + 1];
        self.map.controls(theta, &mut u);
        Ok(u)
    }

    /// J(θ) by one forward simulation (no storage).
    pub fn value(&self, theta: &[f64]) -> Result<f64> {
        let u = self.controls(theta)?;
        forward_value(&self.chain, self.h, self.steps, &u, &self.objective)
    }

    /// (J(θ), ∇J(θ)) by the discrete adjoint.
    pub fn value_and_gradient(&self, theta: &[f64]) -> Result<(f64, Vec<f64>)> {
        let u = self.controls(theta)?;
        self.theta_gradient(&self.chain, &u)
    }

    /// J and ∇_θJ = (∂u/∂θ)ᵀ ∇_u J for controls `u` on `chain`, in any scalar type.
    fn theta_gradient<D: Scalar>(&self, chain: &Chain<D, 2>, u: &[D]) -> Result<(D, Vec<D>)> {
        let r = adjoint_gradient(
            chain,
            self.h,
            self.steps,
            u,
            &self.objective,
            &[],
            self.checkpointing,
        )?;
        let mut g = vec![D::zero(); self.map.n_params()];
        self.map.transpose(&r.control_gradient, &mut g);
        Ok((r.value, g))
    }

    /// ∇J(θ) by the discrete adjoint.
    pub fn gradient(&self, theta: &[f64]) -> Result<Vec<f64>> {
        Ok(self.value_and_gradient(theta)?.1)
    }

    /// The full adjoint result at θ, with gradients for the physical parameters `params` too.
    pub fn adjoint(&self, theta: &[f64], params: &[Parameter]) -> Result<AdjointResult<f64>> {
        let u = self.controls(theta)?;
        adjoint_gradient(
            &self.chain,
            self.h,
            self.steps,
            &u,
            &self.objective,
            params,
            self.checkpointing,
        )
    }

    /// ∂J/∂θ_phys for physical parameters (stiffnesses, mass, drag, load magnitudes).
    pub fn parameter_gradient(&self, theta: &[f64], params: &[Parameter]) -> Result<Vec<f64>> {
        Ok(self.adjoint(theta, params)?.parameter_gradient)
    }

    /// The Hessian-vector product ∇²J(θ) v by forward-over-adjoint: the forward and adjoint sweeps
    /// run in `Dual64` with θ seeded along v.
    pub fn hessian_vec(&self, theta: &[f64], v: &[f64]) -> Result<Vec<f64>> {
        self.check_theta(theta, "theta")?;
        self.check_theta(v, "v")?;
        let th: Vec<Dual64> = theta
            .iter()
            .zip(v)
            .map(|(&t, &d)| Dual64::new(t, d))
            .collect();
        let mut u = vec![Dual64::from(0.0); self.steps + 1];
        self.map.controls(&th, &mut u);
        let (_, g) = self.theta_gradient(&self.chain_as::<Dual64>(), &u)?;
        Ok(g.iter().map(|x| x.eps).collect())
    }

    /// The model lifted to another scalar type.
    pub fn chain_as<D: Scalar>(&self) -> Chain<D, 2> {
        self.chain.lift()
    }
}
