//! Objectives: sums of stage costs ℓ_k(M₀(t_k), u_k, z(t_k)) written once over [`Scalar`], and
//! their evaluation with partial derivatives by nested dual numbers (thesis §3.3, eq. 3.3.2/3.3.4).

use super::reverse::Cotangents;
use crate::model::{zi, Chain, Scalar};
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
    /// The objective as a [`BendingObjective`], if it is one (the structured Riccati solver of
    /// [`crate::ocp`] exploits its Gauss-Newton form Σ c_k M₀² + ρh Σ u²). Default `None`.
    fn bending(&self) -> Option<BendingObjective> {
        None
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
    fn bending(&self) -> Option<BendingObjective> {
        Some(*self)
    }
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

/// Evaluates a stage cost and accumulates its partial derivatives into q̄_k, ū_k and k̄₁, by nested
/// dual numbers (so that this works for any `D`, including the `Dual64` of Hessian-vector
/// products). `zbuf` is scratch of length n.
pub(crate) struct StageEval<'a, O, D> {
    pub(crate) obj: &'a O,
    pub(crate) steps: usize,
    pub(crate) h: f64,
    pub(crate) zbuf: Vec<Dual<D>>,
    pub(crate) zpos: Vec<D>,
}

impl<O: Objective, D: Scalar> StageEval<'_, O, D> {
    pub(crate) fn value<const DIM: usize>(
        &mut self,
        ch: &Chain<D, DIM>,
        k: usize,
        q: &[[D; DIM]],
        u: D,
    ) -> D {
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

    /// Adds ∂ℓ_k/∂q_k to q̄, ∂ℓ_k/∂u_k to ū_k and, when k₁ is a requested parameter (index
    /// `k1_param`), ∂ℓ_k/∂k₁ through M₀ = 2k₁z₁/l₁².
    pub(crate) fn accumulate<const DIM: usize>(
        &mut self,
        ch: &Chain<D, DIM>,
        (k, q, u): (usize, &[[D; DIM]], D),
        cot: &mut Cotangents<D, DIM>,
        k1_param: Option<usize>,
    ) {
        let qbar = &mut cot.qbar;
        let ubar = &mut cot.ubar;
        let k1bar = k1_param.map(|i| &mut cot.thbar[i]);
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
