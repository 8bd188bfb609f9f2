//! Still-water drag on the conjugate momenta (thesis eq. 2.4.4, docs/conventions.md).

use super::{Ctx, DissipativeTerm, Embed};
use crate::base::{Parameter, Scalar};

/// F_D(p) = −D p ⊙ |p| (eq. 2.4.4), componentwise, added to ṗ.
#[derive(Clone, Debug)]
pub struct Drag<D> {
    pub(crate) d: D,
}

impl<D: Scalar> Drag<D> {
    /// The same term over another scalar (real part).
    pub(crate) fn lift<D2: Scalar>(&self) -> Drag<D2> {
        Drag {
            d: D2::from(self.d.re()),
        }
    }
}

/// The root of r + (hD/2) r|r| = c: r = 2c / (1 + √(1 + 2hD|c|)), with W = ∂r/∂c =
/// 1/(1 + hD|r|) (shared by [`Drag`] and [`super::CurrentDrag`], which solves it for r = p − P).
#[inline]
pub(super) fn quadratic_root<D: Scalar>(drag: D, c: D, h: f64) -> (D, D) {
    let root = (drag * (2.0 * h) * c.abs() + 1.0).sqrt() + 1.0;
    let r = c * 2.0 * root.recip();
    (r, (drag * h * r.abs() + 1.0).recip())
}

impl<D: Scalar> DissipativeTerm<D> for Drag<D> {
    fn name(&self) -> &'static str {
        "drag"
    }

    #[inline]
    fn force_component<E: Embed<D>>(&self, _i: usize, _d: usize, p: E, ctx: &Ctx<E>) -> E {
        -(ctx.param(Parameter::Drag, self.d) * p * p.abs())
    }

    fn has_parameter(&self, p: Parameter) -> bool {
        p == Parameter::Drag
    }

    /// Closed form (F, F′) = (−D p|p|, −2D|p|), equal to the default's `Dual<D>` evaluation
    /// (tested; it avoids nested dual arithmetic in the reverse step of the dual Hessians).
    #[inline]
    fn force_and_slope(&self, _i: usize, _d: usize, p: D, _ctx: &Ctx<D>) -> (D, D) {
        let a = p.abs();
        (-(self.d * p * a), -(self.d * (a * 2.0)))
    }

    /// Closed-form root of p + (hD/2) p|p| = c: p = 2c / (1 + √(1 + 2hD|c|)), and
    /// W = 1/(1 + hD|p|) (tested equal to the default Newton solve).
    #[inline]
    fn implicit_half_step(&self, _i: usize, _d: usize, c: D, h: f64, _ctx: &Ctx<D>) -> (D, D) {
        quadratic_root(self.d, c, h)
    }
}
