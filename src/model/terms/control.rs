//! The control force u at node c (thesis eq. 3.1.1 in eq. 2.2.2's form, docs/conventions.md and §4 errata),
//! with an x component u_x for a 2-axis control in the spatial model.

use super::{Ctx, DualScratch, Embed, ForceTerm};
use crate::base::{Parameter, Scalar};
use crate::error::Result;
use crate::model::geometry::zi;

/// The control force u(t) = (u_x, u_z) at node c: U = Σ_{j≤c} l_j (u_z e₃ᵀq_j + u_x e₁ᵀq_j), so
/// pendulums j ≤ c feel l_j (u_x, u_z) (the same sign convention as a point load: u = −F cancels
/// a tip load F, in each component). u_z is [`Ctx::u`], u_x is [`Ctx::ux`] and only enters the
/// spatial model (`DIM = 3`); a 1-axis control has u_x = 0.
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

    /// Σ_{j<c} l_j w_{j,d} (0-based j): the contraction of the force with w along component d.
    fn sum_along<const DIM: usize>(&self, w: &[[D; DIM]], d: usize) -> D {
        let mut s = D::zero();
        for j in 0..self.node {
            s += self.lengths[j] * w[j][d];
        }
        s
    }
}

impl<D: Scalar, const DIM: usize> ForceTerm<D, DIM> for ControlForce<D> {
    fn name(&self) -> &'static str {
        "control"
    }

    fn energy<E: Embed<D>>(&self, q: &[[E; DIM]], ctx: &Ctx<E>) -> E {
        let (mut sz, mut sx) = (E::zero(), E::zero());
        for j in 0..self.node {
            let l = E::embed(self.lengths[j]);
            sz += l * q[j][zi::<DIM>()];
            if DIM == 3 {
                sx += l * q[j][0];
            }
        }
        if DIM == 3 {
            sz * ctx.u + sx * ctx.ux
        } else {
            sz * ctx.u
        }
    }

    fn force<E: Embed<D>>(
        &self,
        _q: &[[E; DIM]],
        ctx: &Ctx<E>,
        out: &mut [[E; DIM]],
    ) -> Result<()> {
        for j in 0..self.node {
            let l = E::embed(self.lengths[j]);
            out[j][zi::<DIM>()] += l * ctx.u;
            if DIM == 3 {
                out[j][0] += l * ctx.ux;
            }
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
    /// to the dual-derived default in `tests/model/terms.rs`).
    fn control_contraction(
        &self,
        _q: &[[D; DIM]],
        w: &[[D; DIM]],
        _ctx: &Ctx<D>,
        _scratch: &mut DualScratch<D, DIM>,
    ) -> Result<D> {
        Ok(self.sum_along(w, zi::<DIM>()))
    }

    /// Hand-written w · ∂F/∂u_x = Σ_{j<c} l_j w_{j,x} in the spatial model, 0 in the planar one
    /// (proven equal to the dual-derived default in `tests/adjoint/spatial_control.rs`).
    fn control_x_contraction(
        &self,
        _q: &[[D; DIM]],
        w: &[[D; DIM]],
        _ctx: &Ctx<D>,
        _scratch: &mut DualScratch<D, DIM>,
    ) -> Result<D> {
        Ok(if DIM == 3 {
            self.sum_along(w, 0)
        } else {
            D::zero()
        })
    }
}
