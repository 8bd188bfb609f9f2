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

use crate::model::Scalar;

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
    cp: Vec<D>,
    /// Reciprocals of the pivots.
    piv: Vec<D>,
    x2: Vec<D>,
}

impl<D: Scalar> BorderedTridiag<D> {
    /// Storage for an n×n tridiagonal part, with or without the border.
    pub fn new(n: usize, bordered: bool) -> Self {
        let z = vec![D::zero(); n];
        BorderedTridiag {
            lower: z.clone(),
            diag: z.clone(),
            upper: z.clone(),
            col: z.clone(),
            row: z.clone(),
            corner: D::zero(),
            bordered,
            cp: z.clone(),
            piv: z.clone(),
            x2: z,
        }
    }

    /// Size of the tridiagonal part.
    pub fn n(&self) -> usize {
        self.diag.len()
    }

    fn factor(&mut self, transpose: bool) -> Result<(), ZeroPivot> {
        let n = self.n();
        for i in 0..n {
            let (sub, sup) = if transpose {
                (
                    if i > 0 { self.upper[i - 1] } else { D::zero() },
                    self.lower.get(i + 1).copied(),
                )
            } else {
                (self.lower[i], self.upper.get(i).copied())
            };
            let m = if i > 0 {
                self.diag[i] - sub * self.cp[i - 1]
            } else {
                self.diag[i]
            };
            if m.re() == 0.0 || !m.re().is_finite() {
                return Err(ZeroPivot {
                    index: i,
                    pivot: m.re(),
                });
            }
            // The pivot's reciprocal, stored for the sweeps (one reciprocal per pivot).
            let inv = m.recip();
            self.piv[i] = inv;
            self.cp[i] = if i + 1 < n {
                sup.unwrap_or(D::zero()) * inv
            } else {
                D::zero()
            };
        }
        Ok(())
    }

    fn sweep(&self, transpose: bool, x: &mut [D]) {
        let n = self.n();
        for i in 0..n {
            let sub = if transpose {
                if i > 0 {
                    self.upper[i - 1]
                } else {
                    D::zero()
                }
            } else {
                self.lower[i]
            };
            let prev = if i > 0 { sub * x[i - 1] } else { D::zero() };
            x[i] = (x[i] - prev) * self.piv[i];
        }
        for i in (0..n.saturating_sub(1)).rev() {
            let next = x[i + 1];
            x[i] -= self.cp[i] * next;
        }
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
        let n = self.n();
        self.factor(transpose)?;
        self.sweep(transpose, &mut rhs[..n]);
        if self.bordered {
            // The border of Aᵀ is (column c, row b).
            let mut x2 = std::mem::take(&mut self.x2);
            x2.copy_from_slice(if transpose { &self.row } else { &self.col });
            self.sweep(transpose, &mut x2);
            let crow = if transpose { &self.col } else { &self.row };
            let mut cx1 = D::zero();
            let mut cx2 = D::zero();
            for i in 0..n {
                cx1 += crow[i] * rhs[i];
                cx2 += crow[i] * x2[i];
            }
            let schur = self.corner - cx2;
            if schur.re() == 0.0 || !schur.re().is_finite() {
                self.x2 = x2;
                return Err(ZeroPivot {
                    index: n,
                    pivot: schur.re(),
                });
            }
            let y = (rhs[n] - cx1) * schur.recip();
            for i in 0..n {
                rhs[i] -= y * x2[i];
            }
            rhs[n] = y;
            self.x2 = x2;
        }
        Ok(())
    }
}
