//! Objectives: sums of stage costs ℓ_k(M₀(t_k), u_k, z(t_k)) written once over [`Scalar`], and
//! their evaluation with partial derivatives by nested dual numbers (thesis §3.3, eq. 3.3.2/3.3.4).

use super::reverse::Cotangents;
use crate::base::Scalar;
use crate::model::{zi, Chain};
use crate::scene::ObjectiveKind;
use num_dual::Dual;

/// What a stage cost sees at t_k.
#[derive(Clone, Copy, Debug)]
pub struct Stage<'a, D> {
    /// Step index k (0..=N).
    pub k: usize,
    /// N.
    pub steps: usize,
    /// Step h.
    pub h: f64,
    /// Base bending moment M₀(t_k) (eq. 3.1.3): the z component M₀_z of the vector
    /// [`crate::Chain::base_moment_vector`].
    pub moment: D,
    /// The x component M₀ₓ(t_k) of the base moment (0 in the planar model).
    pub moment_x: D,
    /// Control u_k (its z component for a 2-axis control).
    pub control: D,
    /// The x component u_{x,k} of a 2-axis control (0 otherwise).
    pub control_x: D,
    /// Node z-displacements z₁..zₙ at t_k (filled only when [`Objective::uses_positions`]).
    pub z: &'a [D],
}

/// A sum of stage costs ℓ_k(M₀(t_k), u_k, z(t_k)), k = 0..=N, written once over [`Scalar`] so
/// that its partial derivatives come from (nested) dual numbers.
///
/// `Clone + 'static` so that the structured solvers of [`crate::ocp`] can keep a copy of it.
pub trait Objective: Clone + Send + Sync + 'static {
    /// The stage cost ℓ_k.
    fn stage<D: Scalar>(&self, s: Stage<'_, D>) -> D;
    /// Whether ℓ depends on the node displacements z (then its partials cost n evaluations).
    fn uses_positions(&self) -> bool {
        false
    }
    /// The stage cost's Gauss-Newton form ℓ_k = ½ w_k r_k(M₀)² + e_k u_k², if it has one: what
    /// the structured solvers of [`crate::ocp`] (Riccati and condensed, hence [`crate::mpc`])
    /// linearise (the residual r_k; l_xx = w_k ∇r_k∇r_kᵀ) and, in their exact phase, complete
    /// with the residual's own curvature w_k r_k ∇²r_k. `stage` must equal this form at every
    /// (M₀, u) of the planar model (M₀ₓ = 0, u_x = 0). Default `None`: the structured solvers
    /// refuse the objective ([`crate::error::OcpError::NoGaussNewtonForm`], named `objective`),
    /// every other method takes it.
    fn gauss_newton<D: Scalar>(&self, s: MomentStage<D>) -> Option<GaussNewton<D>> {
        let _ = s;
        None
    }
    /// Whether J also has a term H(M₀(t_0), …, M₀(t_N)) on the whole base-moment history, which
    /// no sum of stage costs is (the rainflow damage, [`crate::FatigueObjective`]). Default
    /// false; then [`Objective::history`] is never called.
    fn has_history(&self) -> bool {
        false
    }
    /// That term: H of the history `h.moment` (and `h.moment_x`, M₀ₓ(t_k) in the spatial model,
    /// empty in the planar one), with ∂H/∂M₀(t_k) written into `h.grad` (∂H/∂M₀ₓ(t_k) into
    /// `h.grad_x`). The adjoint adds H to J after its forward sweep and ∂H/∂M₀(t_k) to the
    /// stage cost's ∂ℓ_k/∂M₀ in its reverse sweep.
    ///
    /// # Errors
    /// The term's own ([`crate::Error::Fatigue`] for a non-finite stress history).
    fn history<D: Scalar>(&self, h: History<'_, D>) -> crate::error::Result<D> {
        let _ = h;
        Ok(D::zero())
    }
    /// The quantity s_k whose history [`Objective::history`] sees, when it is not the base
    /// moment: `None` (default) for M₀(t_k) (and M₀ₓ(t_k)), as every history term before;
    /// `Some(s_k)`, a function of the stage's inputs (a hot spot's moment from the node
    /// displacements z: [`super::HotSpotObjective`] about its mean). Then `h.moment` holds
    /// s_0..s_N (`h.moment_x` empty), and the adjoint takes ∂H/∂s_k through s_k's own partial
    /// derivatives: the reverse sweep differentiates ℓ_k + g_k s_k with g_k = ∂H/∂s_k held
    /// fixed, whose derivatives are ∂ℓ_k/∂x + (∂H/∂s_k) ∂s_k/∂x exactly (the chain rule).
    /// Read only when [`Objective::has_history`].
    fn history_signal<D: Scalar>(&self, s: Stage<'_, D>) -> Option<D> {
        let _ = s;
        None
    }
    /// The exponent p of the power objective Σ|M₀|^p that stands in for this objective in the
    /// structured solvers when it has no Gauss-Newton form (the rainflow damage: the S-N curve's
    /// slope m), for their refusal to suggest ([`crate::error::OcpError::NeedsPowerProxy`]).
    fn power_proxy(&self) -> Option<f64> {
        None
    }
}

/// What [`Objective::history`] sees and writes.
pub struct History<'a, D> {
    /// M₀(t_k), k = 0..=N (the z component of the base moment vector).
    pub moment: &'a [D],
    /// M₀ₓ(t_k) in the spatial model; empty in the planar one.
    pub moment_x: &'a [D],
    /// ∂H/∂M₀(t_k) (same length as `moment`, zeroed on entry).
    pub grad: &'a mut [D],
    /// ∂H/∂M₀ₓ(t_k) (same length as `moment_x`, zeroed on entry).
    pub grad_x: &'a mut [D],
    /// The step h \[s\] of the horizon (the stages' [`Stage::h`]).
    pub h: f64,
}

/// The history term's buffers in the adjoint's sweeps: M₀ and M₀ₓ as the forward sweep produces
/// them, then ∂H/∂M₀ and ∂H/∂M₀ₓ for the reverse sweep.
pub(crate) struct HistoryBuf<D> {
    moment: Vec<D>,
    moment_x: Vec<D>,
    grad: Vec<D>,
    grad_x: Vec<D>,
    /// Whether `moment` holds the objective's [`Objective::history_signal`] (not M₀).
    signal: bool,
}

impl<D> Default for HistoryBuf<D> {
    fn default() -> Self {
        HistoryBuf {
            moment: Vec::new(),
            moment_x: Vec::new(),
            grad: Vec::new(),
            grad_x: Vec::new(),
            signal: false,
        }
    }
}

/// What the Gauss-Newton form of a stage cost sees at t_k: the planar base moment M₀(t_k).
#[derive(Clone, Copy, Debug)]
pub struct MomentStage<D> {
    /// Step index k (0..=N).
    pub k: usize,
    /// N.
    pub steps: usize,
    /// Step h \[s\].
    pub h: f64,
    /// Base bending moment M₀(t_k) (eq. 3.1.3) \[N m\].
    pub moment: D,
}

/// The Gauss-Newton form of a stage cost, ℓ_k = ½ w_k r_k(M₀)² + e_k u_k² (Gauss-Newton on the
/// residual r_k, Nocedal and Wright §10.3; the effort term is exactly quadratic).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GaussNewton<D> {
    /// The weight w_k ≥ 0 (independent of M₀).
    pub weight: f64,
    /// The residual r_k(M₀), a function of the moment alone.
    pub residual: D,
    /// The effort coefficient e_k ≥ 0 of u_k² (independent of M₀) \[N² m²/N²\].
    pub effort: f64,
}

/// The residual r = M₀(t_N) itself (its z component in the spatial model), not squared: c = r² (eq. 3.3.2), so Newton or Gauss-Newton
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

/// Evaluates a stage cost and accumulates its partial derivatives into q̄_k, ū_k and k̄₁, by nested
/// dual numbers (so that this works for any `D`, including the `Dual64` of Hessian-vector
/// products). `zbuf` is scratch of length n.
pub(crate) struct StageEval<'a, O, D> {
    pub(crate) obj: &'a O,
    pub(crate) steps: usize,
    pub(crate) h: f64,
    pub(crate) zbuf: Vec<Dual<D>>,
    pub(crate) zpos: Vec<D>,
    /// The history term's buffers (used only when [`Objective::has_history`]).
    pub(crate) history: HistoryBuf<D>,
}

impl<O: Objective, D: Scalar> StageEval<'_, O, D> {
    pub(crate) fn value<const DIM: usize>(
        &mut self,
        ch: &Chain<D, DIM>,
        k: usize,
        q: &[[D; DIM]],
        u: D,
    ) -> D {
        let [mx, m] = ch.base_moment_vector(q);
        if self.obj.uses_positions() {
            positions_z(ch, q, &mut self.zpos);
        }
        let stage = Stage {
            k,
            steps: self.steps,
            h: self.h,
            moment: m,
            moment_x: mx,
            control: u,
            control_x: ch.control_x(k),
            z: &self.zpos,
        };
        if self.obj.has_history() {
            if let Some(s) = self.obj.history_signal(stage) {
                self.history.signal = true;
                self.history.moment.push(s);
            } else {
                self.history.moment.push(m);
                if DIM == 3 {
                    self.history.moment_x.push(mx);
                }
            }
        }
        self.obj.stage(stage)
    }

    /// The history term H of the moments [`StageEval::value`] recorded (0 without one), with its
    /// gradient kept for [`StageEval::accumulate`].
    pub(crate) fn finish_history(&mut self) -> crate::error::Result<D> {
        if !self.obj.has_history() {
            return Ok(D::zero());
        }
        let b = &mut self.history;
        b.grad.clear();
        b.grad.resize(b.moment.len(), D::zero());
        b.grad_x.clear();
        b.grad_x.resize(b.moment_x.len(), D::zero());
        self.obj.history(History {
            moment: &b.moment,
            moment_x: &b.moment_x,
            grad: &mut b.grad,
            grad_x: &mut b.grad_x,
            h: self.h,
        })
    }

    /// Adds ∂ℓ_k/∂q_k to q̄, ∂ℓ_k/∂u_k to ū_k (and ∂ℓ_k/∂u_{x,k} to ū_x for a 2-axis control)
    /// and, when k₁ is a requested parameter (index `k1_param`), ∂ℓ_k/∂k₁ through
    /// M₀ = 2k₁(x₁, z₁)/l₁².
    pub(crate) fn accumulate<const DIM: usize>(
        &mut self,
        ch: &Chain<D, DIM>,
        (k, q, u): (usize, &[[D; DIM]], D),
        cot: &mut Cotangents<D, DIM>,
        k1_param: Option<usize>,
    ) {
        let zi_ = zi::<DIM>();
        let scale = ch.moment_stiffness * 2.0 * ch.inv_lengths[0];
        let [mx, m] = ch.base_moment_vector(q);
        let point = [m, mx, u, ch.control_x(k)];
        let two_axis = ch.has_control_x();
        let uses_z = self.obj.uses_positions();
        if uses_z {
            let mut acc = D::zero();
            for (i, zb) in self.zbuf.iter_mut().enumerate() {
                acc += ch.lengths[i] * q[i][zi_];
                *zb = Dual::from_re(acc);
            }
        }
        let zslice: &[Dual<D>] = if uses_z { &self.zbuf } else { &[] };
        // ∂ℓ/∂(M₀_z, M₀ₓ, u, u_x), one dual evaluation each (M₀ₓ and u_x only where they exist).
        // A history of the objective's own signal s_k: ∂H/∂s_k joins through s_k's partials.
        let signal = if self.history.signal {
            self.history.grad.get(k).copied()
        } else {
            None
        };
        let mut d = [D::zero(); 4];
        for (i, di) in d.iter_mut().enumerate() {
            if (i == 1 && DIM == 2) || (i == 3 && !two_axis) {
                continue;
            }
            *di = self.stage_dual(k, point, Some(i), zslice, signal).eps;
        }
        // The history term's ∂H/∂M₀(t_k) (and ∂H/∂M₀ₓ(t_k)) joins ∂ℓ_k/∂M₀.
        if signal.is_none() {
            if let Some(g) = self.history.grad.get(k) {
                d[0] += *g;
            }
            if let Some(g) = self.history.grad_x.get(k) {
                d[1] += *g;
            }
        }
        cot.qbar[0][zi_] += d[0] * scale;
        cot.ubar[k] += d[2];
        if DIM == 3 {
            cot.qbar[0][0] += d[1] * scale;
        }
        if two_axis {
            cot.uxbar[k] += d[3];
        }
        if let Some(kb) = k1_param.map(|i| &mut cot.thbar[i]) {
            *kb += d[0] * 2.0 * q[0][zi_] * ch.inv_lengths[0];
            if DIM == 3 {
                *kb += d[1] * 2.0 * q[0][0] * ch.inv_lengths[0];
            }
        }
        if uses_z {
            // ∂ℓ/∂z_i, then q̄_{j,z} += l_j Σ_{i ≥ j} ∂ℓ/∂z_i.
            let mut acc = D::zero();
            for i in (0..ch.n()).rev() {
                let zi_re = self.zbuf[i].re;
                self.zbuf[i] = Dual::new(zi_re, D::one());
                let g = self.stage_dual(k, point, None, &self.zbuf, signal).eps;
                self.zbuf[i] = Dual::from_re(zi_re);
                acc += g;
                cot.qbar[i][zi_] += acc * ch.lengths[i];
            }
        }
    }

    /// ℓ_k in `Dual<D>` at (M₀_z, M₀ₓ, u, u_x) = `point`, with the input `seed` (an index into
    /// `point`) seeded; with `signal` = Some(g_k), ℓ_k + g_k s_k ([`Objective::history_signal`]).
    fn stage_dual(
        &self,
        k: usize,
        point: [D; 4],
        seed: Option<usize>,
        z: &[Dual<D>],
        signal: Option<D>,
    ) -> Dual<D> {
        let v = |i: usize| {
            if seed == Some(i) {
                Dual::new(point[i], D::one())
            } else {
                Dual::from_re(point[i])
            }
        };
        let stage = Stage {
            k,
            steps: self.steps,
            h: self.h,
            moment: v(0),
            moment_x: v(1),
            control: v(2),
            control_x: v(3),
            z,
        };
        let l = self.obj.stage(stage);
        match signal.and_then(|g| self.obj.history_signal(stage).map(|s| (g, s))) {
            Some((g, s)) => l + s * Dual::from_re(g),
            None => l,
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
