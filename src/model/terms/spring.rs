//! Torsional springs ½ Σᵢ kᵢ θᵢ² between consecutive pendulums and at the supports (thesis eq.
//! 2.2.2-2.2.3, docs/conventions.md).

use super::{Ctx, DualScratch, Embed, ForceTerm};
use crate::base::{Parameter, Scalar};
use crate::error::{Error, Result};
use crate::model::geometry::{arccos_squared, dot, e2, spring_s, spring_s_ds};

/// The springs k₁..k_{n+1} (index 0..=n) with θᵢ = ∠(q_{i−1}, qᵢ), q₀ = q_{n+1} = e₂; only the
/// springs the support has are present (k₁: cantilever, riser, fixed-fixed; k_{n+1}: riser,
/// fixed-fixed).
///
/// Energy ½ kᵢ θᵢ² with θᵢ² = arccos(q_{i−1}·qᵢ)² ([`arccos_squared`]); force on the two pendulums of joint i
/// −kᵢ s(q_{i−1}·qᵢ) (qᵢ on q_{i−1}, q_{i−1} on qᵢ) with s(x) = arccos(x)/√(1 − x²) (eq. 2.2.3).
/// A joint beyond the fold limit is [`Error::Folded`].
#[derive(Clone, Debug)]
pub struct Springs<D> {
    pub(crate) k: Vec<D>,
    pub(crate) present: Vec<bool>,
    pub(crate) fold_cos: f64,
}

impl<D: Scalar> Springs<D> {
    /// The parameter spring i (0-based joint, 0..=n) is read as.
    #[inline]
    fn parameter(&self, i: usize) -> Parameter {
        if i == 0 {
            Parameter::BaseStiffness
        } else if i + 1 == self.k.len() {
            Parameter::TipStiffness
        } else {
            Parameter::InteriorStiffness
        }
    }

    /// The parameter spring i is read as when `seed` is seeded: [`Parameter::JointStiffness`]
    /// of an interior joint when that joint's spring alone is seeded, else
    /// [`Springs::parameter`].
    #[inline]
    fn parameter_at(&self, i: usize, seed: Option<Parameter>) -> Parameter {
        match seed {
            Some(p @ Parameter::JointStiffness(j)) if j == i => p,
            _ => self.parameter(i),
        }
    }

    /// The same springs over another scalar (real parts).
    pub(crate) fn lift<D2: Scalar>(&self) -> Springs<D2> {
        Springs {
            k: self.k.iter().map(|x| D2::from(x.re())).collect(),
            present: self.present.clone(),
            fold_cos: self.fold_cos,
        }
    }

    /// The two attitude vectors of joint i (q₀ = q_{n+1} = e₂).
    #[inline]
    fn ends<'a, E: Scalar, const DIM: usize>(
        q: &'a [[E; DIM]],
        i: usize,
        e: &'a [E; DIM],
    ) -> (&'a [E; DIM], &'a [E; DIM]) {
        let n = q.len();
        let a = if i == 0 { e } else { &q[i - 1] };
        let b = if i == n { e } else { &q[i] };
        (a, b)
    }

    fn folded<E: Scalar>(&self, step: usize, i: usize, x: E) -> Error {
        let x = x.re().clamp(-1.0, 1.0);
        Error::Folded {
            step,
            joint: i + 1,
            angle_deg: x.acos().to_degrees(),
            limit_deg: self.fold_cos.acos().to_degrees(),
        }
    }
}

impl<D: Scalar, const DIM: usize> ForceTerm<D, DIM> for Springs<D> {
    fn name(&self) -> &'static str {
        "springs"
    }

    fn energy<E: Embed<D>>(&self, q: &[[E; DIM]], ctx: &Ctx<E>) -> E {
        let e = e2::<E, DIM>();
        let mut u = E::zero();
        for i in 0..self.k.len() {
            if self.present[i] {
                let (a, b) = Self::ends(q, i, &e);
                let k = ctx.param(self.parameter_at(i, ctx.seed), self.k[i]);
                u += k * arccos_squared(dot(a, b)) * 0.5;
            }
        }
        u
    }

    fn force<E: Embed<D>>(&self, q: &[[E; DIM]], ctx: &Ctx<E>, out: &mut [[E; DIM]]) -> Result<()> {
        let n = q.len();
        let e = e2::<E, DIM>();
        for i in 0..=n {
            if !self.present[i] {
                continue;
            }
            let (a, b) = Self::ends(q, i, &e);
            let x = dot(a, b);
            if x.re() < self.fold_cos {
                return Err(self.folded(ctx.step, i, x));
            }
            let ks = ctx.param(self.parameter_at(i, ctx.seed), self.k[i]) * spring_s(x);
            if i > 0 {
                for d in 0..DIM {
                    out[i - 1][d] -= ks * b[d];
                }
            }
            if i < n {
                for d in 0..DIM {
                    out[i][d] -= ks * a[d];
                }
            }
        }
        Ok(())
    }

    fn has_parameter(&self, p: Parameter) -> bool {
        let n = self.k.len() - 1;
        match p {
            Parameter::InteriorStiffness => n > 1,
            Parameter::JointStiffness(j) => (1..n).contains(&j) && self.present[j],
            Parameter::BaseStiffness => self.present[0],
            Parameter::TipStiffness => self.present[n],
            _ => false,
        }
    }

    /// Hand-written K v (the adjoint calls it twice per step; `cargo bench --bench step --
    /// force_jvp` measures it against the dual-derived default, `tests/model/terms.rs` proves them
    /// equal): for the spring between a and b (x = a·b), σ = b·v_a + a·v_b,
    /// (K v)_a = −k [s v_b + s′ σ b], (K v)_b = −k [s v_a + s′ σ a].
    fn force_jvp(
        &self,
        q: &[[D; DIM]],
        v: &[[D; DIM]],
        _ctx: &Ctx<D>,
        scale: D,
        out: &mut [[D; DIM]],
        _scratch: &mut DualScratch<D, DIM>,
    ) -> Result<()> {
        let n = q.len();
        let e = e2::<D, DIM>();
        let zero = [D::zero(); DIM];
        for i in 0..=n {
            if !self.present[i] {
                continue;
            }
            let (a, b) = Self::ends(q, i, &e);
            let va = if i == 0 { &zero } else { &v[i - 1] };
            let vb = if i == n { &zero } else { &v[i] };
            let (s, ds) = spring_s_ds(dot(a, b));
            let sigma = dot(b, va) + dot(a, vb);
            let k = -self.k[i] * scale;
            if i > 0 {
                for d in 0..DIM {
                    out[i - 1][d] += k * (s * vb[d] + ds * sigma * b[d]);
                }
            }
            if i < n {
                for d in 0..DIM {
                    out[i][d] += k * (s * va[d] + ds * sigma * a[d]);
                }
            }
        }
        Ok(())
    }
}
