//! O(n) solves with tridiagonal matrices bordered by one extra row and column.
//!
//! Every linear system of the RATTLE step and of its adjoint has this form (docs/conventions.md): the
//! length-constraint block G(q′) M⁻¹ G(q)ᵀ is tridiagonal because M̄⁻¹ is, and the tip constraint
//! of fixed-fixed and pinned-pinned beams adds one row and column. The border is eliminated by a
//! Schur complement on the Thomas factorisation (two triangular sweeps, no pivoting: the matrices
//! are perturbations of the symmetric positive definite G M⁻¹ Gᵀ).
//!
//! Divisions are written as multiplications by reciprocals: num-dual divides that way, so the
//! `f64` and dual-number runs then agree bit for bit in their real parts.
//!
//! **First-order dual numbers** (`D::NDERIV == 1`: the stage Jacobians and the forward-over-
//! reverse Hessians of [`crate::ocp`]) are solved by the implicit function theorem instead of
//! factorising in dual arithmetic: with T = T₀ + εT′ and r = r₀ + εr′, the real solution
//! y₀ = T₀⁻¹r₀ comes from the `f64` factorisation of the real parts (the same arithmetic as the
//! `f64` run, so the real parts stay bit for bit), and the derivative parts from one more solve
//! with the same real factors, y′ = T₀⁻¹(r′ − T′y₀) (the residual r − T y₀ carries them). The
//! dual-arithmetic factorisation's derivative parts are the same quantities to round-off.

use crate::base::Scalar;
use std::ops::Mul;

/// A zero pivot met while factorising.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ZeroPivot {
    /// Zero-based pivot index (n for the border's Schur complement).
    pub index: usize,
    /// The pivot's value.
    pub pivot: f64,
}

/// Storage and scratch of a bordered tridiagonal system
/// ```text
/// [ T   b ] [x]   [r]
/// [ cᵀ  d ] [y] = [s]
/// ```
/// of size n (+1 when `bordered`). Sized once; solves do not allocate.
#[derive(Clone, Debug)]
pub struct BorderedTridiag<D> {
    /// Sub-diagonal: `lower[i]` = T_{i,i−1} (`lower[0]` unused).
    pub lower: Vec<D>,
    /// Diagonal T_{ii}.
    pub diag: Vec<D>,
    /// Super-diagonal: `upper[i]` = T_{i,i+1} (`upper[n−1]` unused).
    pub upper: Vec<D>,
    /// Border column b.
    pub col: Vec<D>,
    /// Border row c.
    pub row: Vec<D>,
    /// Corner d.
    pub corner: D,
    /// Whether the border is present.
    pub bordered: bool,
    /// The factors of a solve in `D` arithmetic (`f64`, higher-order duals).
    factors: Factors<D>,
    /// The real parts' matrix, factors and solution (first-order duals).
    real: RealSolve,
}

/// A Thomas factorisation of the tridiagonal part (or of its transpose) and the border's Schur
/// complement: cp the eliminated super-diagonal, piv the pivots' reciprocals, x2 = T⁻¹b (or
/// T⁻ᵀc) and the Schur complement's reciprocal.
#[derive(Clone, Debug)]
struct Factors<M> {
    cp: Vec<M>,
    piv: Vec<M>,
    x2: Vec<M>,
    schur_inv: M,
    /// Whether the factored border is the tip's (zero but in its last entry,
    /// [`Factors::tip_border_solve`]).
    tip_border: bool,
}

/// The f64 copy of a dual matrix's real parts, its factors and the real solution y₀.
#[derive(Clone, Debug)]
struct RealSolve {
    lower: Vec<f64>,
    diag: Vec<f64>,
    upper: Vec<f64>,
    col: Vec<f64>,
    row: Vec<f64>,
    factors: Factors<f64>,
    y: Vec<f64>,
}

/// The matrix entries the factorisation reads, in the orientation solved: (sub, sup) of row i
/// and the border (column, row).
#[derive(Clone, Copy)]
struct Entries<'a, M> {
    lower: &'a [M],
    diag: &'a [M],
    upper: &'a [M],
    col: &'a [M],
    row: &'a [M],
    corner: M,
    bordered: bool,
    transpose: bool,
}

impl<M: Scalar> Entries<'_, M> {
    /// T_{i,i−1} of the solved orientation (0 for i = 0).
    #[inline]
    fn sub(&self, i: usize) -> M {
        if self.transpose {
            if i > 0 {
                self.upper[i - 1]
            } else {
                M::zero()
            }
        } else {
            self.lower[i]
        }
    }

    /// T_{i,i+1} of the solved orientation (`None` past the end).
    #[inline]
    fn sup(&self, i: usize) -> Option<M> {
        if self.transpose {
            self.lower.get(i + 1).copied()
        } else {
            self.upper.get(i).copied()
        }
    }

    /// The border (column, row) of the solved orientation (Aᵀ has column c and row b).
    fn border(&self) -> (&[M], &[M]) {
        if self.transpose {
            (self.row, self.col)
        } else {
            (self.col, self.row)
        }
    }
}

impl<M: Scalar> Factors<M> {
    fn new(n: usize) -> Self {
        let z = vec![M::zero(); n];
        Factors {
            cp: z.clone(),
            piv: z.clone(),
            x2: z,
            schur_inv: M::zero(),
            tip_border: false,
        }
    }

    /// Factorises `a`: the tridiagonal part, then (bordered) x2 and the Schur complement.
    fn factor(&mut self, a: &Entries<'_, M>) -> Result<(), ZeroPivot> {
        let n = a.diag.len();
        for i in 0..n {
            let m = if i > 0 {
                a.diag[i] - a.sub(i) * self.cp[i - 1]
            } else {
                a.diag[i]
            };
            check_pivot(i, m)?;
            // The pivot's reciprocal, stored for the sweeps (one reciprocal per pivot).
            let inv = m.recip();
            self.piv[i] = inv;
            self.cp[i] = if i + 1 < n {
                a.sup(i).unwrap_or(M::zero()) * inv
            } else {
                M::zero()
            };
        }
        self.tip_border = false;
        if a.bordered {
            let (col, row) = a.border();
            let mut x2 = std::mem::take(&mut self.x2);
            let cx2 = match self.tip_border_solve(a, &mut x2) {
                Some(cx2) => cx2,
                None => {
                    x2.copy_from_slice(col);
                    self.sweep(a, &mut x2);
                    let mut cx2 = M::zero();
                    for i in 0..n {
                        cx2 += row[i] * x2[i];
                    }
                    cx2
                }
            };
            self.x2 = x2;
            let schur = a.corner - cx2;
            check_pivot(n, schur)?;
            self.schur_inv = schur.recip();
        }
        Ok(())
    }

    /// x2 = T⁻¹b and cᵀx2 of a border that is zero (+0) but in its last entry (the tip
    /// constraint's border after the assemblies of [`crate::constraints`]), in `f64`: the full
    /// sweep's forward pass then only carries zeros, +0 · pivot (0 − (±0) = +0), so x2's last
    /// entry is (b_{n−1} − (+0 · p_{n−2}) T_{n−1,n−2}) p_{n−1} and the back pass
    /// x2ᵢ = +0 · pᵢ − x2ᵢ₊₁ cpᵢ; and cᵀx2 = +0 + c_{n−1} x2_{n−1} (each term before the last
    /// is ±0, which leaves the sum at +0): the values of the full sweep and sum bit for bit,
    /// without the forward pass's dependent chain. `None` (the caller sweeps) for any other
    /// border, for dual numbers, or when x2 is not finite (where ±0 · x2ᵢ would be a NaN).
    fn tip_border_solve(&mut self, a: &Entries<'_, M>, x2: &mut [M]) -> Option<M> {
        let n = a.diag.len();
        let (col, row) = a.border();
        let plus_zero = |v: &[M]| v.iter().all(|x| x.re().to_bits() == 0);
        if M::NDERIV != 0 || n == 0 || !plus_zero(&col[..n - 1]) || !plus_zero(&row[..n - 1]) {
            return None;
        }
        let last = n - 1;
        let prev = if last > 0 {
            (M::zero() * self.piv[last - 1]) * a.sub(last)
        } else {
            M::zero()
        };
        x2[last] = (col[last] - prev) * self.piv[last];
        let mut finite = x2[last].re().is_finite();
        for i in (0..last).rev() {
            x2[i] = M::zero() * self.piv[i] - x2[i + 1] * self.cp[i];
            finite &= x2[i].re().is_finite();
        }
        if !finite {
            return None;
        }
        self.tip_border = true;
        Some(M::zero() + row[last] * x2[last])
    }

    /// Forward and back substitution of the tridiagonal part on `x` (length n).
    fn sweep<R: Scalar + Mul<M, Output = R>>(&self, a: &Entries<'_, M>, x: &mut [R]) {
        let n = a.diag.len();
        for i in 0..n {
            let prev = if i > 0 {
                x[i - 1] * a.sub(i)
            } else {
                R::zero()
            };
            x[i] = (x[i] - prev) * self.piv[i];
        }
        for i in (0..n.saturating_sub(1)).rev() {
            let next = x[i + 1];
            x[i] -= next * self.cp[i];
        }
    }

    /// Solves with the factors in place (`rhs.len()` = n, or n + 1 when bordered).
    fn apply<R: Scalar + Mul<M, Output = R>>(&self, a: &Entries<'_, M>, rhs: &mut [R]) {
        let n = a.diag.len();
        self.sweep(a, &mut rhs[..n]);
        if a.bordered {
            let (_, row) = a.border();
            // With the tip's border (zero but in its last entry, `tip_border_solve`) and a
            // finite real right-hand side, the terms before the last are ±0 and leave the sum
            // at +0: the same value as the full sum.
            let tip =
                self.tip_border && R::NDERIV == 0 && rhs[..n].iter().all(|r| r.re().is_finite());
            let mut cx1 = R::zero();
            if tip {
                cx1 += rhs[n - 1] * row[n - 1];
            } else {
                for i in 0..n {
                    cx1 += rhs[i] * row[i];
                }
            }
            let y = (rhs[n] - cx1) * self.schur_inv;
            for i in 0..n {
                rhs[i] -= y * self.x2[i];
            }
            rhs[n] = y;
        }
    }
}

/// A zero or non-finite pivot is an error (its index: n for the Schur complement).
#[inline]
fn check_pivot<M: Scalar>(index: usize, m: M) -> Result<(), ZeroPivot> {
    if m.re() == 0.0 || !m.re().is_finite() {
        return Err(ZeroPivot {
            index,
            pivot: m.re(),
        });
    }
    Ok(())
}

impl<D: Scalar> BorderedTridiag<D> {
    /// Storage for an n×n tridiagonal part, with or without the border.
    pub fn new(n: usize, bordered: bool) -> Self {
        let z = vec![D::zero(); n];
        // First-order duals solve with the real mirror, everything else in `D` (the other
        // storage stays empty).
        let (m, nd) = if D::NDERIV == 1 { (n, 0) } else { (0, n) };
        let r = vec![0.0; m];
        BorderedTridiag {
            lower: z.clone(),
            diag: z.clone(),
            upper: z.clone(),
            col: z.clone(),
            row: z,
            corner: D::zero(),
            bordered,
            factors: Factors::new(nd),
            real: RealSolve {
                lower: r.clone(),
                diag: r.clone(),
                upper: r.clone(),
                col: r.clone(),
                row: r,
                factors: Factors::new(m),
                y: vec![0.0; m + usize::from(bordered && m > 0)],
            },
        }
    }

    /// Size of the tridiagonal part.
    pub fn n(&self) -> usize {
        self.diag.len()
    }

    /// The solved orientation's entries, and the factors' storage (disjoint borrows).
    fn parts(&mut self, transpose: bool) -> (Entries<'_, D>, &mut Factors<D>, &mut RealSolve) {
        let a = Entries {
            lower: &self.lower,
            diag: &self.diag,
            upper: &self.upper,
            col: &self.col,
            row: &self.row,
            corner: self.corner,
            bordered: self.bordered,
            transpose,
        };
        (a, &mut self.factors, &mut self.real)
    }

    /// Solves A x = rhs in place (`rhs.len()` = n, or n + 1 when bordered).
    pub fn solve(&mut self, rhs: &mut [D]) -> Result<(), ZeroPivot> {
        self.solve_impl(rhs, false)
    }

    /// Solves Aᵀ x = rhs in place (for adjoint sweeps).
    pub fn solve_transpose(&mut self, rhs: &mut [D]) -> Result<(), ZeroPivot> {
        self.solve_impl(rhs, true)
    }

    fn solve_impl(&mut self, rhs: &mut [D], transpose: bool) -> Result<(), ZeroPivot> {
        let (a, factors, real) = self.parts(transpose);
        if D::NDERIV == 1 {
            return solve_first_order(&a, real, rhs);
        }
        factors.factor(&a)?;
        factors.apply(&a, rhs);
        Ok(())
    }
}

/// First-order duals (module docs): y₀ from the real parts' `f64` factors, then the derivative
/// parts from the residual, y = y₀ − T₀⁻¹(T y₀ − r) with the real part of the correction
/// removed (so that the result's real part is exactly y₀).
fn solve_first_order<D: Scalar>(
    a: &Entries<'_, D>,
    real: &mut RealSolve,
    rhs: &mut [D],
) -> Result<(), ZeroPivot> {
    let re = |src: &[D], dst: &mut [f64]| {
        dst.iter_mut().zip(src).for_each(|(d, s)| *d = s.re());
    };
    re(a.lower, &mut real.lower);
    re(a.diag, &mut real.diag);
    re(a.upper, &mut real.upper);
    if a.bordered {
        re(a.col, &mut real.col);
        re(a.row, &mut real.row);
    }
    let a0 = Entries {
        lower: &real.lower,
        diag: &real.diag,
        upper: &real.upper,
        col: &real.col,
        row: &real.row,
        corner: a.corner.re(),
        bordered: a.bordered,
        transpose: a.transpose,
    };
    real.factors.factor(&a0)?;
    let y = &mut real.y;
    y.iter_mut().zip(rhs.iter()).for_each(|(y, r)| *y = r.re());
    real.factors.apply(&a0, y);
    // rhs ← T y₀ − r (dual), then T₀⁻¹ of it, then y₀ minus its derivative parts.
    a.residual(y, rhs);
    real.factors.apply(&a0, rhs);
    for (r, &y0) in rhs.iter_mut().zip(y.iter()) {
        let correction = *r - r.re();
        *r = D::from(y0) - correction;
    }
    Ok(())
}

impl<D: Scalar> Entries<'_, D> {
    /// rhs ← A y − rhs (A in the solved orientation) for a real y.
    fn residual(&self, y: &[f64], rhs: &mut [D]) {
        let n = self.diag.len();
        for i in 0..n {
            let mut t = self.diag[i] * y[i];
            if i > 0 {
                t += self.sub(i) * y[i - 1];
            }
            if let Some(sup) = self.sup(i).filter(|_| i + 1 < n) {
                t += sup * y[i + 1];
            }
            rhs[i] = t - rhs[i];
        }
        if self.bordered {
            let (col, row) = self.border();
            let mut t = self.corner * y[n];
            for i in 0..n {
                rhs[i] += col[i] * y[n];
                t += row[i] * y[i];
            }
            rhs[n] = t - rhs[n];
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::DMatrix;
    use num_dual::{Derivative, Dual2_64, DualSVec64};

    /// A bordered system whose entries depend smoothly on a parameter t (diagonally dominant
    /// tridiagonal part, as G M⁻¹ Gᵀ is), and its right-hand side.
    fn system<D: Scalar>(n: usize, bordered: bool, t: D) -> (BorderedTridiag<D>, Vec<D>) {
        let mut a = BorderedTridiag::new(n, bordered);
        for i in 0..n {
            let x = i as f64;
            a.diag[i] = (t * (0.3 + 0.1 * x)).sin() + 4.0 + x * 0.2;
            a.lower[i] = (t * 0.7 + x).cos() * 0.9;
            a.upper[i] = (t * 1.3 - x).sin() * 1.1;
            a.col[i] = (t + x * 0.5).cos() * 0.2;
            a.row[i] = (t * 0.4 + x).sin() * 0.3;
        }
        a.corner = t.cos() + 2.0;
        let m = n + usize::from(bordered);
        let rhs = (0..m).map(|i| (t * 2.0 + i as f64).sin() + 0.5).collect();
        (a, rhs)
    }

    fn dense(a: &BorderedTridiag<f64>, transpose: bool) -> DMatrix<f64> {
        let n = a.n();
        let m = n + usize::from(a.bordered);
        let mut d = DMatrix::zeros(m, m);
        for i in 0..n {
            d[(i, i)] = a.diag[i];
            if i > 0 {
                d[(i, i - 1)] = a.lower[i];
            }
            if i + 1 < n {
                d[(i, i + 1)] = a.upper[i];
            }
            if a.bordered {
                d[(i, n)] = a.col[i];
                d[(n, i)] = a.row[i];
            }
        }
        if a.bordered {
            d[(n, n)] = a.corner;
        }
        if transpose {
            d.transpose()
        } else {
            d
        }
    }

    fn solve<D: Scalar>(a: &mut BorderedTridiag<D>, rhs: &mut [D], transpose: bool) {
        let r = if transpose {
            a.solve_transpose(rhs)
        } else {
            a.solve(rhs)
        };
        r.expect("non-singular test system");
    }

    /// The O(n) solve against nalgebra's dense LU (both orientations, with and without border).
    #[test]
    fn solves_equal_dense_lu() {
        for (bordered, transpose) in [(false, false), (false, true), (true, false), (true, true)] {
            let (mut a, mut x) = system(7, bordered, 0.4);
            let b = nalgebra::DVector::from_vec(x.clone());
            let reference = dense(&a, transpose).lu().solve(&b).expect("regular");
            solve(&mut a, &mut x, transpose);
            for (xi, ri) in x.iter().zip(reference.iter()) {
                assert!((xi - ri).abs() <= 1e-13 * ri.abs().max(1.0), "{xi} vs {ri}");
            }
        }
    }

    /// First-order duals (the implicit-function-theorem path): real parts bit for bit those of
    /// the f64 solve; derivative parts equal to the dual-arithmetic factorisation's, which
    /// second-order duals (`Dual2_64`, first derivative v1) still take, to 1e-13 relative, and to
    /// central finite differences (step 1e-6) to 1e-8.
    #[test]
    fn first_order_duals_equal_dual_arithmetic_and_differences() {
        let t = 0.4;
        for (bordered, transpose) in [(false, false), (false, true), (true, false), (true, true)] {
            let seeds = nalgebra::SVector::<f64, 2>::new(1.0, -0.5);
            let td = DualSVec64::<2>::new(t, Derivative::some(seeds));
            let (mut a, mut x) = system(6, bordered, td);
            solve(&mut a, &mut x, transpose);
            let (mut a2, mut x2) = system(6, bordered, Dual2_64::new(t, 1.0, 0.0));
            solve(&mut a2, &mut x2, transpose);
            let (mut af, mut xf) = system(6, bordered, t);
            solve(&mut af, &mut xf, transpose);
            let fd = |s: f64| {
                let (mut a, mut x) = system(6, bordered, t + s);
                solve(&mut a, &mut x, transpose);
                x
            };
            let (xp, xm) = (fd(1e-6), fd(-1e-6));
            for i in 0..x.len() {
                assert_eq!(x[i].re.to_bits(), xf[i].to_bits(), "real part {i}");
                let eps = x[i]
                    .eps
                    .unwrap_generic(nalgebra::Const::<2>, nalgebra::Const::<1>);
                let (d, d2) = (eps[0], x2[i].v1);
                assert!((d - d2).abs() <= 1e-13 * d2.abs().max(1.0), "{d} vs {d2}");
                assert!((eps[1] + 0.5 * d).abs() <= 1e-15 * d.abs().max(1.0));
                let central = (xp[i] - xm[i]) / 2e-6;
                assert!(
                    (d - central).abs() <= 1e-8 * central.abs().max(1.0),
                    "{d} vs {central}"
                );
            }
        }
    }
}
