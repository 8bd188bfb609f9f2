//! The bordered tridiagonal solves of the `f64` RATTLE step with Morison's drag node by node
//! (the riser system's plant: [`crate::model::NodeDrag`]), each fused into two passes over the
//! chain: the forward pass assembles a row of the matrix, factorises it (Thomas: the pivot's
//! reciprocal, the eliminated super-diagonal) and substitutes forward in the right-hand side;
//! the backward pass substitutes back, forms the tip border's x₂ = T⁻¹b and applies its Schur
//! correction. The separate passes they replace (`ConstraintOperator::assemble_newton_nodes`
//! or `assemble_projection`, then [`crate::tridiag::BorderedTridiag::solve`]: factor, the tip
//! border's back pass, forward sweep, back sweep, correction) each form the same values by the
//! same arithmetic (every entry, pivot and substitution below is written as it is there), so the
//! solution is theirs bit for bit; the pivots' chain of divisions then overlaps the row's
//! assembly and the forward substitution, and the chain is read twice instead of six times.
//!
//! Only for `f64` (`D::NDERIV == 0`: the tip border's shortcut is the `f64` one,
//! `Factors::tip_border_solve`) and only while every value stays finite: a zero or non-finite
//! pivot is reported as the separate solve reports it ([`ZeroPivot`], same index and value);
//! a non-finite x₂ or back-substituted entry (where the separate solve would take its general
//! path) makes the function return `Ok(false)` with the right-hand side restored, and the
//! caller solves by the separate passes.

use crate::base::Scalar;
use crate::model::geometry::dot;
use crate::model::{zi, BlockSym, Chain};
use crate::tridiag::ZeroPivot;

/// The factors and scratch of the fused solves, sized once per chain.
#[derive(Clone, Debug)]
pub(crate) struct FusedScratch<D> {
    /// The eliminated super-diagonal cpᵢ.
    cp: Vec<D>,
    /// The pivots' reciprocals.
    piv: Vec<D>,
    /// The right-hand side as given (restored when the caller must solve by the separate passes).
    saved: Vec<D>,
}

impl<D: Scalar> FusedScratch<D> {
    /// For a chain of `n` pendulums with `nc` constraints.
    pub(crate) fn new(n: usize, nc: usize) -> Self {
        FusedScratch {
            cp: vec![D::zero(); n],
            piv: vec![D::zero(); n],
            saved: vec![D::zero(); nc],
        }
    }
}

/// A zero or non-finite pivot, as `tridiag`'s factorisation reports it.
#[inline]
fn check_pivot<D: Scalar>(index: usize, m: D) -> Result<(), ZeroPivot> {
    if m.re() == 0.0 || !m.re().is_finite() {
        return Err(ZeroPivot {
            index,
            pivot: m.re(),
        });
    }
    Ok(())
}

/// The tip border of a bordered system: the last entries of its column and row (the others
/// +0) and its corner.
#[derive(Clone, Copy, Debug)]
struct TipBorder<D> {
    col: D,
    row: D,
    corner: D,
}

/// One row of the forward pass: the row's pivot from its diagonal `diag`, sub-diagonal `sub`
/// (T_{i,i−1}) and super-diagonal `sup` (T_{i,i+1}, unused in the last row), and the forward
/// substitution of rhsᵢ; `carry` holds (cp_{i−1}, x_{i−1}).
#[inline(always)]
fn factor_row<D: Scalar>(
    sc: &mut FusedScratch<D>,
    (i, n): (usize, usize),
    (diag, sub, sup): (D, D, D),
    carry: &mut (D, D),
    rhs: &mut [D],
) -> Result<(), ZeroPivot> {
    let m = if i > 0 { diag - sub * carry.0 } else { diag };
    check_pivot(i, m)?;
    let inv = m.recip();
    sc.piv[i] = inv;
    let cp = if i + 1 < n { sup * inv } else { D::zero() };
    sc.cp[i] = cp;
    let prev = if i > 0 { carry.1 * sub } else { D::zero() };
    let x = (rhs[i] - prev) * inv;
    rhs[i] = x;
    *carry = (cp, x);
    Ok(())
}

/// After the forward pass: the back substitution, the tip border's x₂ = T⁻¹b (its forward part
/// over +0 entries is +0, `Factors::tip_border_solve`) and Schur complement, and the border's
/// correction, in one backward pass; `sub_last` = T_{n−1,n−2}. `Ok(false)`: a non-finite
/// entry (where the separate solve takes its general path), `rhs` restored from the scratch's
/// copy.
#[inline(always)]
fn finish<D: Scalar>(
    sc: &FusedScratch<D>,
    border: Option<(TipBorder<D>, D)>,
    rhs: &mut [D],
) -> Result<bool, ZeroPivot> {
    let n = sc.piv.len();
    let last = n - 1;
    let Some((tb, sub_last)) = border else {
        let mut next = rhs[last];
        let mut finite = next.re().is_finite();
        for i in (0..last).rev() {
            let x = rhs[i] - next * sc.cp[i];
            finite &= x.re().is_finite();
            rhs[i] = x;
            next = x;
        }
        if !finite {
            rhs.copy_from_slice(&sc.saved);
        }
        return Ok(finite);
    };
    let prev = if last > 0 {
        (D::zero() * sc.piv[last - 1]) * sub_last
    } else {
        D::zero()
    };
    let x2_last = (tb.col - prev) * sc.piv[last];
    if !x2_last.re().is_finite() {
        rhs.copy_from_slice(&sc.saved);
        return Ok(false);
    }
    let cx2 = D::zero() + tb.row * x2_last;
    let schur = tb.corner - cx2;
    check_pivot(n, schur)?;
    let schur_inv = schur.recip();
    // rhs[last] is final after the forward pass; the other back-substituted entries are finite
    // (checked below), so the border's sum is its last term (`Factors::apply`).
    let y = (rhs[n] - (D::zero() + rhs[last] * tb.row)) * schur_inv;
    let (mut x2_next, mut r_next) = (x2_last, rhs[last]);
    let mut finite = r_next.re().is_finite();
    rhs[last] = r_next - y * x2_last;
    for i in (0..last).rev() {
        let x2 = D::zero() * sc.piv[i] - x2_next * sc.cp[i];
        let r = rhs[i] - r_next * sc.cp[i];
        finite &= x2.re().is_finite() && r.re().is_finite();
        rhs[i] = r - y * x2;
        (x2_next, r_next) = (x2, r);
    }
    rhs[n] = y;
    if !finite {
        rhs.copy_from_slice(&sc.saved);
    }
    Ok(finite)
}

/// Solves J Δ = `rhs` in place for RATTLE's Newton matrix with the node drag,
/// J = −h²/2 Ĝ(q′) M⁻¹ W Ĝ(q)ᵀ (the matrix of `ConstraintOperator::assemble_newton_nodes`,
/// whose rows are formed here by its arithmetic, aⱼ = qⱼ/lⱼ, a′ⱼ = q′ⱼ/lⱼ, Ω̃ₖ = Ωₖ/mₖ), fused as
/// the module docs say. `Ok(false)`: solve by the separate passes (`rhs` as given).
pub(crate) fn newton_nodes_solve<D: Scalar, const DIM: usize>(
    ch: &Chain<D, DIM>,
    (q, qnew): (&[[D; DIM]], &[[D; DIM]]),
    omega: &[BlockSym<D, DIM>],
    h: f64,
    sc: &mut FusedScratch<D>,
    rhs: &mut [D],
) -> Result<bool, ZeroPivot> {
    debug_assert_eq!(D::NDERIV, 0);
    let n = ch.n();
    sc.saved.copy_from_slice(rhs);
    let s = -(h * h * 0.5);
    let scaled = |x: &[D; DIM], j: usize| x.map(|c| c * ch.inv_lengths[j]);
    let om = |k: usize, v: &[D; DIM]| omega[k].apply(v).map(|c| c * ch.inv_masses[k]);
    let (mut a, mut an) = (scaled(&q[0], 0), scaled(&qnew[0], 0));
    // Ω̃ⱼ₋₁aⱼ (formed in row j − 1), J_{j,j−1}, and (cp_{j−1}, x_{j−1}).
    let mut prev = [D::zero(); DIM];
    let mut sub = D::zero();
    let mut sub_last = D::zero();
    let mut carry = (D::zero(), D::zero());
    for j in 0..n {
        let oa = om(j, &a);
        let mut d = dot(&an, &oa);
        if j > 0 {
            d += dot(&an, &prev);
        }
        let diag = d * s;
        let (mut sup, mut sub_next) = (D::zero(), D::zero());
        if j + 1 < n {
            let (b, bn) = (scaled(&q[j + 1], j + 1), scaled(&qnew[j + 1], j + 1));
            let ob = om(j, &b);
            sup = -(dot(&an, &ob) * s);
            sub_next = -(dot(&bn, &oa) * s);
            (a, an, prev) = (b, bn, ob);
        }
        factor_row(sc, (j, n), (diag, sub, sup), &mut carry, rhs)?;
        sub_last = sub;
        sub = sub_next;
    }
    let border = ch.has_tip_constraint().then(|| {
        let z = zi::<DIM>();
        let mut ez = [D::zero(); DIM];
        ez[z] = D::one();
        let last = n - 1;
        let (a, an) = (scaled(&q[last], last), scaled(&qnew[last], last));
        let oz = om(last, &ez);
        let tb = TipBorder {
            col: dot(&an, &oz) * s,
            row: dot(&ez, &om(last, &a)) * s,
            corner: oz[z] * s,
        };
        (tb, sub_last)
    });
    finish(sc, border, rhs)
}

/// What the fused projection of RATTLE's second half step reads ([`project`]).
pub(crate) struct Projection<'a, D, const DIM: usize> {
    /// q_{k+1}.
    pub q: &'a [[D; DIM]],
    /// b = p_{k+½} − (h/2) U_q(q_{k+1}) + (h/2) F(p_{k+½}).
    pub b: &'a [[D; DIM]],
    /// The tip row's velocity target.
    pub v_tip: D,
    /// h/2.
    pub hh: f64,
}

/// Where [`project`] writes.
pub(crate) struct Projected<'a, D, const DIM: usize> {
    /// M⁻¹b (scratch).
    pub tmp: &'a mut [[D; DIM]],
    /// y (n, + 1 with the tip row).
    pub rhs: &'a mut [D],
    /// p_{k+1}.
    pub p: &'a mut [[D; DIM]],
    /// μ_k = y/(h/2).
    pub mu: &'a mut [D],
}

/// The projection of RATTLE's second half step fused (`steppers::rattle::projection_solve`
/// followed by `ConstraintOperator::subtract_transpose` and μ = y/(h/2)): M⁻¹b, the right-hand
/// side Ĝ(q) M⁻¹ b − (0, …, 0, v_tip), the matrix Ĝ(q) M⁻¹ Ĝ(q)ᵀ, its solve y, and
/// p = b − Ĝ(q)ᵀ y, μ = y/(h/2), each by the arithmetic of the separate passes (the matrix's
/// rows those of `ConstraintOperator::assemble_projection`). `tmp` gets M⁻¹b.
/// `Ok(false)`: nothing usable was written, project by the separate passes.
pub(crate) fn project<D: Scalar, const DIM: usize>(
    ch: &Chain<D, DIM>,
    x: &Projection<'_, D, DIM>,
    sc: &mut FusedScratch<D>,
    o: &mut Projected<'_, D, DIM>,
) -> Result<bool, ZeroPivot> {
    debug_assert_eq!(D::NDERIV, 0);
    let n = ch.n();
    let z = zi::<DIM>();
    let (q, b) = (x.q, x.b);
    // M⁻¹'s first pass (`Chain::apply_inverse_mass`).
    let mut next = [D::zero(); DIM];
    for i in (0..n).rev() {
        let mut cur = b[i];
        for c in cur.iter_mut() {
            *c *= ch.inv_lengths[i];
        }
        for d in 0..DIM {
            o.tmp[i][d] = (cur[d] - next[d]) * ch.inv_masses[i];
        }
        next = cur;
    }
    let mut prev = [D::zero(); DIM];
    let mut tip = D::zero();
    let mut sub = D::zero();
    let mut sub_last = D::zero();
    let mut carry = (D::zero(), D::zero());
    for i in 0..n {
        let cur = o.tmp[i];
        for d in 0..DIM {
            o.tmp[i][d] = (cur[d] - prev[d]) * ch.inv_lengths[i];
        }
        prev = cur;
        o.rhs[i] = dot(&q[i], &o.tmp[i]);
        tip += ch.lengths[i] * o.tmp[i][z];
        let (dii, off) = ch.minv_entries(i);
        let diag = dot(&q[i], &q[i]) * dii;
        let sup = if i + 1 < n {
            dot(&q[i], &q[i + 1]) * off
        } else {
            D::zero()
        };
        factor_row(sc, (i, n), (diag, sub, sup), &mut carry, o.rhs)?;
        sub_last = sub;
        sub = sup;
    }
    let bordered = ch.has_tip_constraint();
    let border = bordered.then(|| {
        o.rhs[n] = tip - x.v_tip;
        let inv_mn = ch.inv_masses[n - 1];
        let v = q[n - 1][z] * inv_mn * ch.inv_lengths[n - 1];
        let tb = TipBorder {
            col: v,
            row: v,
            corner: inv_mn,
        };
        (tb, sub_last)
    });
    // (On `Ok(false)` the caller projects from b again: what `finish` restores is not read.)
    let hh = x.hh;
    let finite = finish(sc, border, o.rhs)?;
    if !finite {
        return Ok(false);
    }
    // p = b − Ĝᵀy, μ = y/(h/2) (`ConstraintOperator::subtract_transpose`).
    let y_tip = if bordered { o.rhs[n] } else { D::zero() };
    for i in 0..n {
        let y = o.rhs[i];
        for d in 0..DIM {
            o.p[i][d] = b[i][d] - y * q[i][d];
        }
        if bordered {
            o.p[i][z] -= y_tip * ch.lengths[i];
        }
    }
    for (m, y) in o.mu.iter_mut().zip(o.rhs.iter()) {
        *m = *y / hh;
    }
    Ok(true)
}
