//! Momentum-dependent (dissipative) terms as an open set (thesis eq. 2.4.4, docs/conventions.md):
//! each term is one type implementing [`DissipativeTerm`], listed once in
//! [`crate::Chain::visit_dissipation`], and every consumer (the steppers, RATTLE's implicit half
//! step, the adjoint's reverse step, the statics) takes the **sum** F = Σ_T F_T through the
//! methods of [`crate::Chain`] below.
//!
//! A term's force on pendulum i depends on that pendulum's momentum pᵢ only, and splits into an
//! axial part (the y component, a function of p_y) and a transverse part ((x, z), a function of
//! (p_x, p_z)) with a symmetric Jacobian: the block Jacobian ∂Fᵢ/∂pᵢ is then a [`BlockSym`], and so
//! is W = ∂p_{k+½}/∂c of the implicit half step. In the planar model the transverse part is z
//! alone and every block is diagonal.

use super::{Ctx, Embed};
use crate::base::{Parameter, Scalar};
use crate::model::Chain;
use num_dual::Dual;

/// A symmetric DIM×DIM block with the axial/transverse pattern of a dissipative term: the
/// diagonal, and (spatial model only) the (x, z) off-diagonal entry `xz` (always 0 in the planar
/// model, where it is never read).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BlockSym<D, const DIM: usize> {
    /// The diagonal entries.
    pub diag: [D; DIM],
    /// The entry (x, z) = (z, x) of a spatial block.
    pub xz: D,
}

impl<D: Scalar, const DIM: usize> BlockSym<D, DIM> {
    /// The zero block.
    pub fn zero() -> Self {
        BlockSym {
            diag: [D::zero(); DIM],
            xz: D::zero(),
        }
    }

    /// The identity.
    pub fn identity() -> Self {
        BlockSym {
            diag: [D::one(); DIM],
            xz: D::zero(),
        }
    }

    /// B v.
    #[inline]
    pub fn apply(&self, v: &[D; DIM]) -> [D; DIM] {
        let mut out = *v;
        for (o, (x, w)) in out.iter_mut().zip(v.iter().zip(&self.diag)) {
            *o = *x * *w;
        }
        if DIM == 3 {
            out[0] += self.xz * v[2];
            out[2] += self.xz * v[0];
        }
        out
    }

    /// (I + s B) v, written v_d (B_dd s + 1) + s B_xz v_other (the reverse step's p̄½ = (I + h/2
    /// ∂F/∂p)ᵀ b̄, B symmetric).
    #[inline]
    pub fn identity_plus_scaled_apply(&self, s: f64, v: &[D; DIM]) -> [D; DIM] {
        let mut out: [D; DIM] = std::array::from_fn(|d| v[d] * (self.diag[d] * s + 1.0));
        if DIM == 3 {
            let x = self.xz * s;
            out[0] += x * v[2];
            out[2] += x * v[0];
        }
        out
    }

    /// The sum of two blocks.
    #[inline]
    pub fn add(&self, o: &Self) -> Self {
        BlockSym {
            diag: std::array::from_fn(|d| self.diag[d] + o.diag[d]),
            xz: self.xz + o.xz,
        }
    }

    /// (I − s B)⁻¹ (axial entry 1/(1 − s B_yy); the transverse 2×2 block inverted in closed
    /// form): W of an implicit half step p − s F(p) = c with B = ∂F/∂p.
    pub fn inverse_of_identity_minus(&self, s: f64) -> Self {
        let mut w = BlockSym {
            diag: std::array::from_fn(|d| (-(self.diag[d] * s) + 1.0).recip()),
            xz: D::zero(),
        };
        if DIM == 3 {
            let (a, b, c) = (
                -(self.diag[0] * s) + 1.0,
                -(self.xz * s),
                -(self.diag[2] * s) + 1.0,
            );
            let det = (a * c - b * b).recip();
            w.diag[0] = c * det;
            w.diag[2] = a * det;
            w.xz = -(b * det);
        }
        w
    }

    /// The block with the real parts only.
    pub fn real_part(&self) -> Self {
        BlockSym {
            diag: self.diag.map(|x| D::from(x.re())),
            xz: D::from(self.xz.re()),
        }
    }
}

/// A momentum-dependent force Fᵢ(pᵢ) added to ṗ (thesis eq. 2.4.4), block by block (module
/// docs), written once over the evaluation scalar.
///
/// RATTLE evaluates it at p_{k+½} in both half-steps (docs/conventions.md), so the first
/// half-step solves p − (h/2) Σ_T F_T(p) = c per block; [`DissipativeTerm::implicit_half_step`]
/// does so by Newton on the dual-derived Jacobian, and a term with a closed-form root may
/// override it (tested equal). Likewise (F, ∂F/∂p) and ∂F/∂θ come from one `Dual<D>` evaluation
/// of [`DissipativeTerm::force`] unless overridden by a closed form (tested equal).
pub trait DissipativeTerm<D: Scalar, const DIM: usize>:
    Clone + std::fmt::Debug + Send + Sync
{
    /// A short name for diagnostics and tests.
    fn name(&self) -> &'static str;

    /// The force Fᵢ(pᵢ) on pendulum `i` (0-based), parameters read through [`Ctx::param`].
    fn force<E: Embed<D>>(&self, i: usize, p: &[E; DIM], ctx: &Ctx<E>) -> [E; DIM];

    /// Whether the term reads the physical parameter `p`.
    fn has_parameter(&self, p: Parameter) -> bool;

    /// (Fᵢ, ∂Fᵢ/∂pᵢ) by `Dual<D>` evaluations seeded along y, z (and x: its z part is the
    /// off-diagonal entry).
    fn force_and_slope(
        &self,
        i: usize,
        p: &[D; DIM],
        ctx: &Ctx<D>,
    ) -> ([D; DIM], BlockSym<D, DIM>) {
        let c = ctx.dual(None);
        let mut j = BlockSym::zero();
        let mut f = [D::zero(); DIM];
        for s in 0..DIM {
            let x: [Dual<D>; DIM] =
                std::array::from_fn(|d| Dual::new(p[d], if d == s { D::one() } else { D::zero() }));
            let g = self.force(i, &x, &c);
            j.diag[s] = g[s].eps;
            if DIM == 3 && s == 0 {
                j.xz = g[2].eps;
            }
            f = g.map(|v| v.re);
        }
        (f, j)
    }

    /// ∂Fᵢ/∂θ for a physical parameter θ, by one `Dual<D>` evaluation with θ seeded.
    fn parameter_derivative(
        &self,
        i: usize,
        p: &[D; DIM],
        ctx: &Ctx<D>,
        param: Parameter,
    ) -> [D; DIM] {
        if !self.has_parameter(param) {
            return [D::zero(); DIM];
        }
        let c = ctx.dual(Some(param));
        self.force(i, &p.map(Dual::from_re), &c).map(|v| v.eps)
    }

    /// Solves p − (h/2) Fᵢ(p) = c for one block and returns (p, W) with W = ∂p/∂c =
    /// (I − (h/2) ∂F/∂p)⁻¹. Default: Newton from p = c ([`block_newton`]).
    fn implicit_half_step(
        &self,
        i: usize,
        c: &[D; DIM],
        h: f64,
        ctx: &Ctx<D>,
    ) -> ([D; DIM], BlockSym<D, DIM>) {
        block_newton(c, h, |p| self.force_and_slope(i, p, ctx))
    }

    /// [`DissipativeTerm::implicit_half_step`] on every block ([`HalfSteps`]: cᵢ in, (pᵢ, Wᵢ)
    /// out). Default: block by block; a term overrides it to hoist what is the same for every
    /// block out of the loop (the drags' hD and 2hD), with the same arithmetic per block.
    #[inline]
    fn implicit_half_steps(&self, blocks: HalfSteps<'_, D, DIM>, h: f64, ctx: &Ctx<D>) {
        let HalfSteps { c, p, w } = blocks;
        for (i, (c, (p, w))) in c.iter().zip(p.iter_mut().zip(w)).enumerate() {
            (*p, *w) = self.implicit_half_step(i, c, h, ctx);
        }
    }

    /// The half kick of every block with this term's force at the block's own momentum,
    /// bᵢ = pᵢ − s gᵢ + s Fᵢ(pᵢ) (RATTLE's second half step: p = p_{k+½}, g = U_q(q_{k+1}),
    /// s = h/2), into `out[i]`, evaluated in that order ((pᵢ − s gᵢ) first). Default:
    /// [`DissipativeTerm::force`] block by block; overridden like
    /// [`DissipativeTerm::implicit_half_steps`].
    #[inline]
    fn half_kick(&self, kick: HalfKick<'_, D, DIM>, ctx: &Ctx<D>, out: &mut [[D; DIM]]) {
        let HalfKick { p, g, s } = kick;
        for (i, (o, (p, g))) in out.iter_mut().zip(p.iter().zip(g)).enumerate() {
            let f = self.force(i, p, ctx);
            for d in 0..DIM {
                o[d] = p[d] - g[d] * s + f[d] * s;
            }
        }
    }
}

/// Newton for p − (h/2) F(p) = c on one block from p = c, to round-off, with (F, ∂F/∂p) from
/// `slope`; returns (p, (I − (h/2) ∂F/∂p(p))⁻¹).
pub fn block_newton<D: Scalar, const DIM: usize>(
    c: &[D; DIM],
    h: f64,
    slope: impl Fn(&[D; DIM]) -> ([D; DIM], BlockSym<D, DIM>),
) -> ([D; DIM], BlockSym<D, DIM>) {
    let hh = 0.5 * h;
    let mut p = *c;
    for _ in 0..50 {
        let (f, j) = slope(&p);
        let r: [D; DIM] = std::array::from_fn(|d| p[d] - f[d] * hh - c[d]);
        let step = j.inverse_of_identity_minus(hh).apply(&r);
        let mut small = true;
        for d in 0..DIM {
            p[d] -= step[d];
            small &= step[d].re().abs() <= 1e-15 * (1.0 + p[d].re().abs());
        }
        if small {
            break;
        }
    }
    let (_, j) = slope(&p);
    (p, j.inverse_of_identity_minus(hh))
}

/// Visits every dissipative term of a chain (see [`crate::Chain::visit_dissipation`]).
pub trait DissipationVisitor<D: Scalar, const DIM: usize> {
    /// Called once per dissipative term present in the model.
    fn visit<T: DissipativeTerm<D, DIM>>(&mut self, term: &T);
}

/// Σ_T of a per-term value: the first term's value as is, the others added (so one term gives
/// its own value bit for bit, the sign of a zero included).
#[inline(always)]
fn accumulate<X, const DIM: usize>(acc: &mut Option<X>, x: X, add: impl Fn(&X, &X) -> X) {
    match acc {
        Some(a) => *a = add(a, &x),
        None => *acc = Some(x),
    }
}

fn add_arrays<D: Scalar, const DIM: usize>(a: &[D; DIM], b: &[D; DIM]) -> [D; DIM] {
    std::array::from_fn(|d| a[d] + b[d])
}

/// Σ_T F_T at one block.
struct ForceAt<'a, D, const DIM: usize> {
    i: usize,
    p: &'a [D; DIM],
    ctx: &'a Ctx<D>,
    sum: Option<[D; DIM]>,
}

impl<D: Scalar, const DIM: usize> DissipationVisitor<D, DIM> for ForceAt<'_, D, DIM> {
    #[inline]
    fn visit<T: DissipativeTerm<D, DIM>>(&mut self, term: &T) {
        let f = term.force(self.i, self.p, self.ctx);
        accumulate::<_, DIM>(&mut self.sum, f, add_arrays);
    }
}

/// Σ_T (F_T, ∂F_T/∂p) at one block.
struct SlopeAt<'a, D, const DIM: usize> {
    i: usize,
    p: &'a [D; DIM],
    ctx: &'a Ctx<D>,
    sum: Option<([D; DIM], BlockSym<D, DIM>)>,
}

impl<D: Scalar, const DIM: usize> DissipationVisitor<D, DIM> for SlopeAt<'_, D, DIM> {
    #[inline]
    fn visit<T: DissipativeTerm<D, DIM>>(&mut self, term: &T) {
        let x = term.force_and_slope(self.i, self.p, self.ctx);
        accumulate::<_, DIM>(&mut self.sum, x, |a, b| {
            (add_arrays(&a.0, &b.0), a.1.add(&b.1))
        });
    }
}

/// Σ_T ∂F_T/∂θ at one block.
struct ParameterAt<'a, D, const DIM: usize> {
    i: usize,
    p: &'a [D; DIM],
    ctx: &'a Ctx<D>,
    param: Parameter,
    sum: [D; DIM],
}

impl<D: Scalar, const DIM: usize> DissipationVisitor<D, DIM> for ParameterAt<'_, D, DIM> {
    fn visit<T: DissipativeTerm<D, DIM>>(&mut self, term: &T) {
        if term.has_parameter(self.param) {
            let g = term.parameter_derivative(self.i, self.p, self.ctx, self.param);
            self.sum = add_arrays(&self.sum, &g);
        }
    }
}

/// The implicit half step of the only term (its own solve, closed forms included).
struct SolveOne<'a, D, const DIM: usize> {
    i: usize,
    c: &'a [D; DIM],
    h: f64,
    ctx: &'a Ctx<D>,
    out: Option<([D; DIM], BlockSym<D, DIM>)>,
}

impl<D: Scalar, const DIM: usize> DissipationVisitor<D, DIM> for SolveOne<'_, D, DIM> {
    #[inline]
    fn visit<T: DissipativeTerm<D, DIM>>(&mut self, term: &T) {
        self.out = Some(term.implicit_half_step(self.i, self.c, self.h, self.ctx));
    }
}

/// The blocks of an implicit half step p − (h/2) F(p) = c ([`DissipativeTerm::implicit_half_steps`]):
/// cᵢ in, pᵢ and Wᵢ = ∂pᵢ/∂cᵢ out, block i at index i of each.
#[derive(Debug)]
pub struct HalfSteps<'a, D, const DIM: usize> {
    /// The right-hand sides cᵢ (RATTLE: a − h/2 Ĝ(q_k)ᵀλ).
    pub c: &'a [[D; DIM]],
    /// The roots pᵢ (RATTLE: p_{k+½}).
    pub p: &'a mut [[D; DIM]],
    /// Wᵢ = (I − (h/2) ∂Fᵢ/∂pᵢ)⁻¹.
    pub w: &'a mut [BlockSym<D, DIM>],
}

impl<'a, D, const DIM: usize> HalfSteps<'a, D, DIM> {
    /// The blocks of `c`, with `p` and `w` cut to its length (one length check here, none per
    /// block in the loops).
    ///
    /// # Panics
    /// If `p` or `w` is shorter than `c` (a caller's bug: the steppers size them once).
    #[inline]
    pub fn new(c: &'a [[D; DIM]], p: &'a mut [[D; DIM]], w: &'a mut [BlockSym<D, DIM>]) -> Self {
        let n = c.len();
        HalfSteps {
            c,
            p: &mut p[..n],
            w: &mut w[..n],
        }
    }

    /// The same blocks, borrowed again (to pass them on and keep them).
    #[inline]
    pub fn reborrow(&mut self) -> HalfSteps<'_, D, DIM> {
        HalfSteps {
            c: self.c,
            p: &mut *self.p,
            w: &mut *self.w,
        }
    }
}

/// The implicit half step of the only term on every block.
struct SolveAll<'a, D, const DIM: usize> {
    blocks: HalfSteps<'a, D, DIM>,
    h: f64,
    ctx: &'a Ctx<D>,
}

impl<D: Scalar, const DIM: usize> DissipationVisitor<D, DIM> for SolveAll<'_, D, DIM> {
    #[inline]
    fn visit<T: DissipativeTerm<D, DIM>>(&mut self, term: &T) {
        term.implicit_half_steps(self.blocks.reborrow(), self.h, self.ctx);
    }
}

/// The inputs of a half kick bᵢ = pᵢ − s gᵢ + s Fᵢ(pᵢ) ([`DissipativeTerm::half_kick`]).
#[derive(Clone, Copy, Debug)]
pub struct HalfKick<'a, D, const DIM: usize> {
    /// The momenta pᵢ (RATTLE: p_{k+½}), at which F is evaluated.
    pub p: &'a [[D; DIM]],
    /// The potential's gradient gᵢ (RATTLE: U_q(q_{k+1}; u_{k+1})).
    pub g: &'a [[D; DIM]],
    /// The scale s (RATTLE: h/2).
    pub s: f64,
}

/// The only term's half kick on every block.
struct KickAll<'a, D, const DIM: usize> {
    kick: HalfKick<'a, D, DIM>,
    ctx: &'a Ctx<D>,
    out: &'a mut [[D; DIM]],
}

impl<D: Scalar, const DIM: usize> DissipationVisitor<D, DIM> for KickAll<'_, D, DIM> {
    #[inline]
    fn visit<T: DissipativeTerm<D, DIM>>(&mut self, term: &T) {
        term.half_kick(self.kick, self.ctx, self.out);
    }
}

/// Counts the terms, and whether any reads a parameter (no allocation: called per step).
struct Census {
    count: usize,
    param: Option<Parameter>,
    reads: bool,
}

impl<D: Scalar, const DIM: usize> DissipationVisitor<D, DIM> for Census {
    #[inline]
    fn visit<T: DissipativeTerm<D, DIM>>(&mut self, term: &T) {
        self.count += 1;
        self.reads |= self.param.is_some_and(|p| term.has_parameter(p));
    }
}

/// The terms' names.
struct Names(Vec<&'static str>);

impl<D: Scalar, const DIM: usize> DissipationVisitor<D, DIM> for Names {
    fn visit<T: DissipativeTerm<D, DIM>>(&mut self, term: &T) {
        self.0.push(term.name());
    }
}

impl<D: Scalar, const DIM: usize> Chain<D, DIM> {
    #[inline]
    fn dissipation_census(&self, param: Option<Parameter>) -> Census {
        let mut c = Census {
            count: 0,
            param,
            reads: false,
        };
        self.visit_dissipation(&mut c);
        c
    }

    /// Number of dissipative terms the model has ([`Chain::visit_dissipation`]).
    #[inline]
    pub fn dissipation_count(&self) -> usize {
        self.dissipation_census(None).count
    }

    /// The names of the dissipative terms the model has, in the order they are visited.
    pub fn dissipation_names(&self) -> Vec<&'static str> {
        let mut v = Names(Vec::new());
        self.visit_dissipation(&mut v);
        v.0
    }

    /// Whether the model has a dissipative term, a block term or a coupled one
    /// ([`Chain::has_coupled_dissipation`]); then RATTLE records p_{k+½} and W.
    #[inline]
    pub fn has_dissipation(&self) -> bool {
        self.dissipation_count() > 0 || self.has_coupled_dissipation()
    }

    /// Whether some dissipative term reads the physical parameter `p`.
    pub fn dissipation_has_parameter(&self, p: Parameter) -> bool {
        self.dissipation_census(Some(p)).reads
    }

    /// Σ_T F_T(pᵢ) on pendulum `i` (eq. 2.4.4 and the terms of docs/conventions.md), `None`
    /// without dissipative terms.
    #[inline]
    pub fn dissipative_force(&self, i: usize, p: &[D; DIM], ctx: &Ctx<D>) -> Option<[D; DIM]> {
        let mut v = ForceAt {
            i,
            p,
            ctx,
            sum: None,
        };
        self.visit_dissipation(&mut v);
        v.sum
    }

    /// bᵢ = pᵢ − s gᵢ + s Σ_T F_T(pᵢ) on every pendulum ([`HalfKick`]; RATTLE's second half
    /// step), evaluated in that order: pᵢ − s gᵢ without dissipative terms; the only term's
    /// [`DissipativeTerm::half_kick`] (one dispatch per step); with several, the sum
    /// [`Chain::dissipative_force`] per block.
    #[inline]
    pub fn dissipative_half_kick(
        &self,
        kick: HalfKick<'_, D, DIM>,
        ctx: &Ctx<D>,
        out: &mut [[D; DIM]],
    ) {
        let HalfKick { p, g, s } = kick;
        match self.dissipation_count() {
            0 => {
                for (o, (p, g)) in out.iter_mut().zip(p.iter().zip(g)) {
                    for d in 0..DIM {
                        o[d] = p[d] - g[d] * s;
                    }
                }
            }
            1 => self.visit_dissipation(&mut KickAll { kick, ctx, out }),
            _ => {
                for (i, (o, (p, g))) in out.iter_mut().zip(p.iter().zip(g)).enumerate() {
                    let f = self
                        .dissipative_force(i, p, ctx)
                        .unwrap_or([D::zero(); DIM]);
                    for d in 0..DIM {
                        o[d] = p[d] - g[d] * s + f[d] * s;
                    }
                }
            }
        }
    }

    /// Σ_T (F_T, ∂F_T/∂pᵢ) on pendulum `i`, `None` without dissipative terms.
    #[inline]
    pub fn dissipative_slope(
        &self,
        i: usize,
        p: &[D; DIM],
        ctx: &Ctx<D>,
    ) -> Option<([D; DIM], BlockSym<D, DIM>)> {
        let mut v = SlopeAt {
            i,
            p,
            ctx,
            sum: None,
        };
        self.visit_dissipation(&mut v);
        v.sum
    }

    /// The context of the dissipative terms in RATTLE's step k → k + 1 from t_k (forward and
    /// reverse alike): both half steps read F at p_{k+½}, so they read a time-dependent term
    /// (the waves' water momentum) at the midpoint t_k + h/2; u = 0 (no term reads it).
    #[inline]
    pub fn dissipation_ctx(&self, t_k: f64, h: f64, k: usize) -> Ctx<D> {
        Ctx::new(t_k + 0.5 * h, D::zero(), k)
    }

    /// Σ_T ∂F_T(pᵢ)/∂θ on pendulum `i` (zero when no term reads θ).
    pub fn dissipative_parameter_derivative(
        &self,
        i: usize,
        p: &[D; DIM],
        ctx: &Ctx<D>,
        param: Parameter,
    ) -> [D; DIM] {
        let mut v = ParameterAt {
            i,
            p,
            ctx,
            param,
            sum: [D::zero(); DIM],
        };
        self.visit_dissipation(&mut v);
        v.sum
    }

    /// Solves p − (h/2) Σ_T F_T(p) = c on block `i` and returns (p, W = ∂p/∂c): the term's own
    /// solve when there is one term (closed forms for the drags), Newton on the summed Jacobian
    /// ([`block_newton`]) when there are several, (c, I) when there is none. `terms` is
    /// [`Chain::dissipation_count`] (counted once per step by the caller).
    #[inline]
    pub fn dissipative_half_step(
        &self,
        terms: usize,
        i: usize,
        c: &[D; DIM],
        h: f64,
        ctx: &Ctx<D>,
    ) -> ([D; DIM], BlockSym<D, DIM>) {
        match terms {
            0 => (*c, BlockSym::identity()),
            1 => {
                let mut v = SolveOne {
                    i,
                    c,
                    h,
                    ctx,
                    out: None,
                };
                self.visit_dissipation(&mut v);
                v.out.unwrap_or((*c, BlockSym::identity()))
            }
            _ => block_newton(c, h, |p| {
                self.dissipative_slope(i, p, ctx)
                    .unwrap_or(([D::zero(); DIM], BlockSym::zero()))
            }),
        }
    }

    /// [`Chain::dissipative_half_step`] on every block ([`HalfSteps`]: cᵢ in, (pᵢ, Wᵢ) out); the
    /// only term's [`DissipativeTerm::implicit_half_steps`] (one dispatch per step, its per-step
    /// constants hoisted), (c, I) without terms, the summed Newton with several.
    #[inline]
    pub fn dissipative_half_steps(&self, blocks: HalfSteps<'_, D, DIM>, h: f64, ctx: &Ctx<D>) {
        match self.dissipation_count() {
            0 => {
                blocks.p.copy_from_slice(blocks.c);
                blocks.w.fill(BlockSym::identity());
            }
            1 => self.visit_dissipation(&mut SolveAll { blocks, h, ctx }),
            terms => {
                let HalfSteps { c, p, w } = blocks;
                for (i, (c, (p, w))) in c.iter().zip(p.iter_mut().zip(w)).enumerate() {
                    (*p, *w) = self.dissipative_half_step(terms, i, c, h, ctx);
                }
            }
        }
    }
}
