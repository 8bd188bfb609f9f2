//! The control force u at node c (thesis eq. 3.1.1 in eq. 2.2.2's form, docs/conventions.md and §4 errata).

use super::{Ctx, DualScratch, Embed, ForceTerm};
use crate::error::Result;
use crate::model::geometry::zi;
use crate::model::{Parameter, Scalar};

/// The control force u(t) at node c: U = u Σ_{j≤c} l_j e₃ᵀq_j, so pendulums j ≤ c feel l_j u e₃
/// (the same sign convention as a point load: u = −F cancels a tip load F).
#[derive(Clone, Debug)]
pub struct ControlForce<D> {
    /// Node 1..=n.
    pub(crate) node: usize,
    pub(crate) lengths: Vec<D>,
}

impl<D: Scalar> ControlForce<D> {
    /// The same term over another scalar (real parts).
    pub(crate) fn lift<D2: Scalar>(&self) -> ControlForce<D2> {
        ControlForce {
            node: self.node,
            lengths: self.lengths.iter().map(|x| D2::from(x.re())).collect(),
        }
    }
}

impl<D: Scalar, const DIM: usize> ForceTerm<D, DIM> for ControlForce<D> {
    fn name(&self) -> &'static str {
        "control"
    }

    fn energy<E: Embed<D>>(&self, q: &[[E; DIM]], ctx: &Ctx<E>) -> E {
        let mut s = E::zero();
        for j in 0..self.node {
            s += E::embed(self.lengths[j]) * q[j][zi::<DIM>()];
        }
        s * ctx.u
    }

    fn force<E: Embed<D>>(
        &self,
        _q: &[[E; DIM]],
        ctx: &Ctx<E>,
        out: &mut [[E; DIM]],
    ) -> Result<()> {
        for j in 0..self.node {
            out[j][zi::<DIM>()] += E::embed(self.lengths[j]) * ctx.u;
        }
        Ok(())
    }

    fn depends_on_configuration(&self) -> bool {
        false
    }

    fn depends_on_control(&self) -> bool {
        true
    }

    fn has_parameter(&self, _p: Parameter) -> bool {
        false
    }

    /// Hand-written w · ∂F/∂u = Σ_{j<c} l_j w_{j,z} (called twice per adjoint step; proven equal
    /// to the dual-derived default in `tests/terms.rs`).
    fn control_contraction(
        &self,
        _q: &[[D; DIM]],
        w: &[[D; DIM]],
        _ctx: &Ctx<D>,
        _scratch: &mut DualScratch<D, DIM>,
    ) -> Result<D> {
        let mut s = D::zero();
        for j in 0..self.node {
            s += self.lengths[j] * w[j][zi::<DIM>()];
        }
        Ok(s)
    }
}
