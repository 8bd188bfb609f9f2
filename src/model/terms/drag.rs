//! Still-water drag on the conjugate momenta (thesis eq. 2.4.4, docs/conventions.md).

use super::{BlockSym, Ctx, DissipativeTerm, Embed, HalfKick, HalfSteps};
use crate::base::{Parameter, Scalar};

/// Still-water drag added to ṗ, Morison's form on the momenta (`morison` in `drag.rs`): transversally
/// F_⊥ = −D |p_⊥| p_⊥ (rotation-invariant about the beam's axis), axially −D p_y|p_y|; in the
/// planar model exactly the thesis's F_D(p) = −D p ⊙ |p| (eq. 2.4.4).
///
/// On a chain built from `[pipe]` pendulum i takes Dᵢ = D wᵢ ([`DragWeights`]).
#[derive(Clone, Debug)]
pub struct Drag<D> {
    pub(crate) d: D,
    pub(crate) weights: DragWeights,
}

impl<D: Scalar> Drag<D> {
    /// The same term over another scalar (real part).
    pub(crate) fn lift<D2: Scalar>(&self) -> Drag<D2> {
        Drag {
            d: D2::from(self.d.re()),
            weights: self.weights.clone(),
        }
    }
}

/// The per-pendulum factors wᵢ of the drag constant, Dᵢ = D wᵢ (docs/conventions.md "Equivalent
/// drag constant"; [`crate::scene::drag_weights`]: wᵢ = l₁S₁/(lᵢSᵢ) for a chain built from
/// `[pipe]`), stored once when the model is built; none (every wᵢ = 1, and D is used as it is,
/// bit for bit the thesis's eq. 2.4.4) for a chain given by its lengths and masses. The weights
/// are constants: ∂Dᵢ/∂D = wᵢ, so D stays the one [`Parameter::Drag`].
#[derive(Clone, Debug, Default, PartialEq)]
pub struct DragWeights(Vec<f64>);

impl DragWeights {
    /// The weights `w` (one per pendulum), or none.
    pub(crate) fn new(w: Option<Vec<f64>>) -> Self {
        DragWeights(w.unwrap_or_default())
    }

    /// Dᵢ = D wᵢ for pendulum `i` (0-based): D itself without weights.
    #[inline]
    pub(crate) fn apply<S: Scalar>(&self, i: usize, d: S) -> S {
        match self.0.get(i) {
            Some(&w) => d * w,
            None => d,
        }
    }

    /// Calls `f(i, Dᵢ)` for pendulums i = 0..n, Dᵢ = D wᵢ (D without weights, as
    /// [`DragWeights::apply`]). The loop is written once per case so that without weights D
    /// stays the same in every iteration and what depends on it alone (hD, 2hD) is computed once
    /// per call, not per pendulum (docs/architecture.md "Benches").
    #[inline]
    pub(crate) fn each<S: Scalar>(&self, n: usize, d: S, mut f: impl FnMut(usize, S)) {
        match self.as_slice() {
            None => (0..n).for_each(|i| f(i, d)),
            Some(w) => w.iter().take(n).enumerate().for_each(|(i, &w)| f(i, d * w)),
        }
    }

    /// Recomputes the weights of a chain built from `[pipe]` for new lengths and masses (their
    /// real parts: the weights are constants); nothing without weights.
    pub(crate) fn refresh<D: Scalar>(&mut self, lengths: &[D], masses: &[D]) {
        if !self.0.is_empty() {
            let re = |v: &[D]| v.iter().map(|x| x.re()).collect::<Vec<f64>>();
            self.0 = crate::scene::drag_weights(&re(lengths), &re(masses));
        }
    }

    /// The weights, `None` when every pendulum takes D.
    pub fn as_slice(&self) -> Option<&[f64]> {
        (!self.0.is_empty()).then_some(self.0.as_slice())
    }
}

/// The root of r + (hD/2) r|r| = c: r = 2c / (1 + √(1 + 2hD|c|)), with W = ∂r/∂c =
/// 1/(1 + hD|r|) (shared by [`Drag`] and [`super::CurrentDrag`], which solves it for r = p − P).
#[inline(always)]
pub(super) fn quadratic_root<D: Scalar>(drag: D, c: D, h: f64) -> (D, D) {
    let root = (drag * (2.0 * h) * c.abs() + 1.0).sqrt() + 1.0;
    let r = c * 2.0 * root.recip();
    (r, (drag * h * r.abs() + 1.0).recip())
}

impl<D: Scalar, const DIM: usize> DissipativeTerm<D, DIM> for Drag<D> {
    fn name(&self) -> &'static str {
        "drag"
    }

    #[inline]
    fn force<E: Embed<D>>(&self, i: usize, p: &[E; DIM], ctx: &Ctx<E>) -> [E; DIM] {
        morison(self.weights.apply(i, ctx.param(Parameter::Drag, self.d)), p)
    }

    fn has_parameter(&self, p: Parameter) -> bool {
        p == Parameter::Drag
    }

    /// Closed form (`slope_of`; planar: (F, F′) = (−D p|p|, −2D|p|) per component), equal to
    /// the default's `Dual<D>` evaluation (tested; it avoids nested dual arithmetic in the
    /// reverse step of the dual Hessians).
    #[inline]
    fn force_and_slope(
        &self,
        i: usize,
        p: &[D; DIM],
        _ctx: &Ctx<D>,
    ) -> ([D; DIM], BlockSym<D, DIM>) {
        slope_of(self.weights.apply(i, self.d), p)
    }

    /// Closed-form root (`root_of`; planar: p + (hD/2) p|p| = c per component,
    /// p = 2c / (1 + √(1 + 2hD|c|)), W = 1/(1 + hD|p|)), tested equal to the default Newton
    /// solve.
    #[inline]
    fn implicit_half_step(
        &self,
        i: usize,
        c: &[D; DIM],
        h: f64,
        _ctx: &Ctx<D>,
    ) -> ([D; DIM], BlockSym<D, DIM>) {
        root_of(self.weights.apply(i, self.d), c, h)
    }

    /// [`Drag::implicit_half_step`] on every block, Dᵢ by `DragWeights::each`.
    #[inline]
    fn implicit_half_steps(&self, blocks: HalfSteps<'_, D, DIM>, h: f64, _ctx: &Ctx<D>) {
        let HalfSteps { c, p, w } = blocks;
        let n = c.len();
        self.weights.each(
            n,
            self.d,
            #[inline(always)]
            |i, d| {
                (p[i], w[i]) = root_of(d, &c[i], h);
            },
        );
    }

    /// [`DissipativeTerm::half_kick`] on every block ([`Drag::force`]), Dᵢ by
    /// `DragWeights::each`.
    #[inline]
    fn half_kick(&self, kick: HalfKick<'_, D, DIM>, ctx: &Ctx<D>, out: &mut [[D; DIM]]) {
        let HalfKick { p, g, s } = kick;
        let n = p.len();
        let (g, out) = (&g[..n], &mut out[..n]);
        let drag = ctx.param(Parameter::Drag, self.d);
        self.weights.each(
            n,
            drag,
            #[inline(always)]
            |i, d| {
                let f = morison(d, &p[i]);
                for k in 0..DIM {
                    out[i][k] = p[i][k] - g[i][k] * s + f[k] * s;
                }
            },
        );
    }
}

/// |r_⊥|, the Euclidean norm of the transverse part of a block: |r_z| in the planar model, and
/// √(r_x² + r_z²) in the spatial one, taken as |r_z| when r_x = 0 (equal in exact arithmetic, and
/// bit for bit the planar value; the first derivatives are the same, r_x/|r_⊥| = 0).
#[inline]
pub(super) fn transverse_norm<S: Scalar, const DIM: usize>(r: &[S; DIM]) -> S {
    let z = r[DIM - 1];
    if DIM == 3 && r[0].re() != 0.0 {
        (r[0] * r[0] + z * z).sqrt()
    } else {
        z.abs()
    }
}

/// Morison's drag on a block of relative momenta r (docs/conventions.md, "Drag"): the
/// transverse part −D |r_⊥| r_⊥ with the Euclidean norm (invariant under rotations about the
/// beam's axis y), the axial part −D r_y|r_y| (eq. 2.4.4). In the planar model (r_⊥ = r_z) and
/// whenever r_x = 0 this is the thesis's elementwise −D r⊙|r|, bit for bit.
#[inline(always)]
pub(super) fn morison<S: Scalar, const DIM: usize>(drag: S, r: &[S; DIM]) -> [S; DIM] {
    let nt = transverse_norm(r);
    let y = DIM - 2;
    let mut f = *r;
    for (d, f) in f.iter_mut().enumerate() {
        *f = if d == y {
            -(drag * r[d] * r[d].abs())
        } else {
            -(drag * r[d] * nt)
        };
    }
    f
}

/// The transverse 2×2 block a (I − r̂r̂ᵀ) + b r̂r̂ᵀ of a spatial block, written with
/// (1 − r̂_x², 1 − r̂_z²) = (r̂_z², r̂_x²) so that r̂_x = 0 gives b on z exactly; (b, 0) on the
/// diagonal when |r_⊥| = 0 (a = b there).
#[inline]
fn transverse_block<D: Scalar, const DIM: usize>(
    r: &[D; DIM],
    nt: D,
    (a, b): (D, D),
    out: &mut BlockSym<D, DIM>,
) {
    if nt.re() == 0.0 {
        out.diag[0] = b;
        out.diag[2] = b;
        return;
    }
    let (ux, uz) = (r[0] / nt, r[2] / nt);
    let (xx, zz) = (ux * ux, uz * uz);
    out.diag[0] = a * zz + b * xx;
    out.diag[2] = a * xx + b * zz;
    out.xz = (b - a) * ux * uz;
}

/// (F, ∂F/∂r) of [`morison`] in closed form: axial −2D|r_y|; transverse
/// −D(|r_⊥| I + r_⊥ r_⊥ᵀ/|r_⊥|) = −D|r_⊥| (I − r̂r̂ᵀ) − 2D|r_⊥| r̂r̂ᵀ (−2D|r_z| in the planar model)
/// (shared with [`super::CurrentDrag`]).
#[inline(always)]
pub(super) fn slope_of<D: Scalar, const DIM: usize>(
    drag: D,
    r: &[D; DIM],
) -> ([D; DIM], BlockSym<D, DIM>) {
    let f = morison(drag, r);
    let mut j = BlockSym::zero();
    let y = DIM - 2;
    let a = r[y].abs();
    j.diag[y] = -(drag * (a * 2.0));
    let nt = transverse_norm(r);
    if DIM == 2 {
        j.diag[1] = -(drag * (nt * 2.0));
    } else {
        transverse_block(r, nt, (-(drag * nt), -(drag * (nt * 2.0))), &mut j);
    }
    (f, j)
}

/// The root of r + (hD/2) F-form = c for [`morison`]: axially [`quadratic_root`]; transversally
/// r_⊥ = c_⊥ · 2/(1 + √(1 + 2hD|c_⊥|)) (r_⊥ is parallel to c_⊥, and |r_⊥| solves the scalar
/// quadratic), with W_⊥ = (I − r̂r̂ᵀ)/(1 + hD|r_⊥|/2) + r̂r̂ᵀ/(1 + hD|r_⊥|). In the planar model
/// (and for c_x = 0) these are the thesis's per-component roots, bit for bit.
#[inline(always)]
pub(super) fn root_of<D: Scalar, const DIM: usize>(
    drag: D,
    c: &[D; DIM],
    h: f64,
) -> ([D; DIM], BlockSym<D, DIM>) {
    let mut r = [D::zero(); DIM];
    let mut w = BlockSym::zero();
    let y = DIM - 2;
    (r[y], w.diag[y]) = quadratic_root(drag, c[y], h);
    if DIM == 2 {
        (r[1], w.diag[1]) = quadratic_root(drag, c[1], h);
        return (r, w);
    }
    let nc = transverse_norm(c);
    let root = (drag * (2.0 * h) * nc + 1.0).sqrt() + 1.0;
    for d in [0, 2] {
        r[d] = c[d] * 2.0 * root.recip();
    }
    let nt = transverse_norm(&r);
    let along = (drag * h * nt + 1.0).recip();
    let across = (drag * (0.5 * h) * nt + 1.0).recip();
    transverse_block(&r, nt, (across, along), &mut w);
    (r, w)
}
