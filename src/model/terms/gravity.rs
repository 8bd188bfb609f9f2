//! Gravity on the point masses (thesis §2.2.2, docs/conventions.md).

use super::{Ctx, Embed, ForceTerm};
use crate::base::{Parameter, Scalar};
use crate::error::Result;
use crate::model::geometry::zi;

/// Gravity g along −z on the masses: U = Σᵢ mᵢ g Σ_{j≤i} l_j (e₃ᵀq_j + 1), so pendulum j feels
/// l_j g (Σ_{i≥j} mᵢ) e₃. Reads the masses as [`Parameter::Mass`] (all seeded together: the
/// derivative with respect to a common mass).
#[derive(Clone, Debug)]
pub struct Gravity<D> {
    pub(crate) g: D,
    pub(crate) lengths: Vec<D>,
    pub(crate) masses: Vec<D>,
}

impl<D: Scalar> Gravity<D> {
    /// The same term over another scalar (real parts).
    pub(crate) fn lift<D2: Scalar>(&self) -> Gravity<D2> {
        let l = |v: &[D]| v.iter().map(|x| D2::from(x.re())).collect();
        Gravity {
            g: D2::from(self.g.re()),
            lengths: l(&self.lengths),
            masses: l(&self.masses),
        }
    }

    /// Calls `f(j, l_j g Σ_{i≥j} mᵢ)` for j = n−1..0.
    #[inline]
    fn for_each<E: Embed<D>>(&self, ctx: &Ctx<E>, mut f: impl FnMut(usize, E)) {
        let g = E::embed(self.g);
        let mut acc = E::zero();
        for j in (0..self.lengths.len()).rev() {
            acc += g * ctx.param(Parameter::Mass, self.masses[j]);
            f(j, E::embed(self.lengths[j]) * acc);
        }
    }
}

impl<D: Scalar, const DIM: usize> ForceTerm<D, DIM> for Gravity<D> {
    fn name(&self) -> &'static str {
        "gravity"
    }

    fn energy<E: Embed<D>>(&self, q: &[[E; DIM]], ctx: &Ctx<E>) -> E {
        let mut u = E::zero();
        self.for_each(ctx, |j, c| u += c * (q[j][zi::<DIM>()] + 1.0));
        u
    }

    fn force<E: Embed<D>>(
        &self,
        _q: &[[E; DIM]],
        ctx: &Ctx<E>,
        out: &mut [[E; DIM]],
    ) -> Result<()> {
        self.for_each(ctx, |j, c| out[j][zi::<DIM>()] += c);
        Ok(())
    }

    fn depends_on_configuration(&self) -> bool {
        false
    }

    fn has_parameter(&self, p: Parameter) -> bool {
        p == Parameter::Mass
    }
}
