//! Tests only: the dense reference of [`super::CoupledHalf`] — A and RATTLE's Newton matrix J
//! assembled column by column and factorised by a dense LU, O((n·DIM)³) per Newton iteration
//! (the implementation this crate shipped before the band solver, kept to compare with it).

use crate::base::Scalar;
use crate::model::{Chain, Ctx};
use crate::tridiag::ZeroPivot;

use super::{flatten, unflatten, HalfSystem};

/// A dense LU factorisation P A = L U with partial pivoting (pivots chosen on the real parts),
/// over any scalar: `solve` and `solve_transpose` after `factor`.
#[derive(Clone, Debug)]
pub(crate) struct DenseLu<D> {
    n: usize,
    /// Row-major entries (L below the diagonal, unit diagonal implied; U on and above).
    a: Vec<D>,
    piv: Vec<usize>,
}

impl<D: Scalar> DenseLu<D> {
    /// Storage for an n × n matrix.
    pub(crate) fn new(n: usize) -> Self {
        DenseLu {
            n,
            a: vec![D::zero(); n * n],
            piv: vec![0; n],
        }
    }

    /// Entry (r, c) for assembly.
    #[inline]
    fn at(&mut self, r: usize, c: usize) -> &mut D {
        &mut self.a[r * self.n + c]
    }

    /// Factorises the assembled matrix in place.
    fn factor(&mut self) -> Result<(), ZeroPivot> {
        let n = self.n;
        for k in 0..n {
            let mut p = k;
            for r in k + 1..n {
                if self.a[r * n + k].re().abs() > self.a[p * n + k].re().abs() {
                    p = r;
                }
            }
            let pivot = self.a[p * n + k];
            if pivot.re() == 0.0 || !pivot.re().is_finite() {
                return Err(ZeroPivot {
                    index: k,
                    pivot: pivot.re(),
                });
            }
            self.piv[k] = p;
            if p != k {
                for c in 0..n {
                    self.a.swap(k * n + c, p * n + c);
                }
            }
            let inv = self.a[k * n + k].recip();
            for r in k + 1..n {
                let l = self.a[r * n + k] * inv;
                self.a[r * n + k] = l;
                for c in k + 1..n {
                    let u = self.a[k * n + c];
                    self.a[r * n + c] -= l * u;
                }
            }
        }
        Ok(())
    }

    /// Solves A x = b in place.
    fn solve(&self, b: &mut [D]) {
        let n = self.n;
        for k in 0..n {
            b.swap(k, self.piv[k]);
        }
        for r in 0..n {
            let mut s = b[r];
            for c in 0..r {
                s -= self.a[r * n + c] * b[c];
            }
            b[r] = s;
        }
        for r in (0..n).rev() {
            let mut s = b[r];
            for c in r + 1..n {
                s -= self.a[r * n + c] * b[c];
            }
            b[r] = s / self.a[r * n + r];
        }
    }

    /// Solves Aᵀ x = b in place (Aᵀ = Uᵀ Lᵀ P).
    fn solve_transpose(&self, b: &mut [D]) {
        let n = self.n;
        for r in 0..n {
            let mut s = b[r];
            for c in 0..r {
                s -= self.a[c * n + r] * b[c];
            }
            b[r] = s / self.a[r * n + r];
        }
        for r in (0..n).rev() {
            let mut s = b[r];
            for c in r + 1..n {
                s -= self.a[c * n + r] * b[c];
            }
            b[r] = s;
        }
        for k in (0..n).rev() {
            b.swap(k, self.piv[k]);
        }
    }
}

/// The dense half step of a chain with coupled dissipative terms (module docs): A and J
/// factorised, and scratch, sized once per chain (no allocation per step).
#[derive(Clone, Debug)]
pub(crate) struct DenseHalf<D, const DIM: usize> {
    /// A = I − (h/2) ∂F/∂p at the last assembly.
    a: DenseLu<D>,
    /// RATTLE's Newton matrix J (n_c × n_c).
    jac: DenseLu<D>,
    /// v = M⁻¹p, and the coupled force.
    v: Vec<[D; DIM]>,
    f: Vec<[D; DIM]>,
    /// A block vector and its flat copy.
    blocks: Vec<[D; DIM]>,
    flat: Vec<D>,
    /// A constraint-sized vector.
    y: Vec<D>,
}

impl<D: Scalar, const DIM: usize> DenseHalf<D, DIM> {
    /// Buffers for `ch`.
    pub(crate) fn new(ch: &Chain<D, DIM>) -> Self {
        let (n, nc) = (ch.n(), ch.n_constraints());
        let v = vec![[D::zero(); DIM]; n];
        DenseHalf {
            a: DenseLu::new(n * DIM),
            jac: DenseLu::new(nc),
            v: v.clone(),
            f: v.clone(),
            blocks: v,
            flat: vec![D::zero(); n * DIM],
            y: vec![D::zero(); nc],
        }
    }

    /// Σ_T F_T(q, M⁻¹p) of the coupled terms alone (a view of the workspace).
    pub(crate) fn coupled_force(
        &mut self,
        ch: &Chain<D, DIM>,
        q: &[[D; DIM]],
        p: &[[D; DIM]],
        ctx: &Ctx<D>,
    ) -> &[[D; DIM]] {
        ch.apply_inverse_mass(p, &mut self.v);
        self.f.iter_mut().for_each(|f| *f = [D::zero(); DIM]);
        ch.coupled_force(q, &self.v, ctx, &mut self.f);
        &self.f
    }

    /// Assembles and factorises A = I − (h/2)(∂F_D/∂p + ∂F_J/∂p) at (q, p).
    pub(crate) fn factor_at(
        &mut self,
        ch: &Chain<D, DIM>,
        (q, p): (&[[D; DIM]], &[[D; DIM]]),
        h: f64,
        ctx: &Ctx<D>,
    ) -> Result<(), ZeroPivot> {
        let (n, nn, hh) = (ch.n(), ch.n() * DIM, 0.5 * h);
        self.a.a.iter_mut().for_each(|x| *x = D::zero());
        for r in 0..nn {
            *self.a.at(r, r) = D::one();
        }
        for (i, pi) in p.iter().enumerate() {
            if let Some((_, s)) = ch.dissipative_slope(i, pi, ctx) {
                for d in 0..DIM {
                    *self.a.at(i * DIM + d, i * DIM + d) -= s.diag[d] * hh;
                }
                if DIM == 3 {
                    *self.a.at(i * DIM, i * DIM + 2) -= s.xz * hh;
                    *self.a.at(i * DIM + 2, i * DIM) -= s.xz * hh;
                }
            }
        }
        // Column (j, e) of ∂F_J/∂p: F_J(q, M⁻¹ e_{j,e}) (M⁻¹ is tridiagonal, F_J local).
        for j in 0..n {
            for e in 0..DIM {
                self.blocks.iter_mut().for_each(|b| *b = [D::zero(); DIM]);
                self.blocks[j][e] = D::one();
                ch.apply_inverse_mass(&self.blocks, &mut self.v);
                self.f.iter_mut().for_each(|f| *f = [D::zero(); DIM]);
                ch.coupled_force(q, &self.v, ctx, &mut self.f);
                for (i, f) in self.f.iter().enumerate() {
                    for d in 0..DIM {
                        *self.a.at(i * DIM + d, j * DIM + e) -= f[d] * hh;
                    }
                }
            }
        }
        self.a.factor()
    }

    /// Assembles and factorises RATTLE's Newton matrix J = −h²/2 Ĝ(q′) M⁻¹ A⁻¹ Ĝ(q)ᵀ (A as
    /// last factorised), column by column.
    pub(crate) fn factor_newton(
        &mut self,
        ch: &Chain<D, DIM>,
        (q, qnew): (&[[D; DIM]], &[[D; DIM]]),
        h: f64,
    ) -> Result<(), ZeroPivot> {
        let ops = ch.constraints();
        let nc = ch.n_constraints();
        let s = D::from(-(h * h * 0.5));
        for j in 0..nc {
            self.y.iter_mut().for_each(|y| *y = D::zero());
            self.y[j] = D::one();
            self.blocks.iter_mut().for_each(|b| *b = [D::zero(); DIM]);
            ops.add_transpose(q, &self.y, D::one(), &mut self.blocks);
            flatten(&self.blocks, &mut self.flat);
            self.a.solve(&mut self.flat);
            unflatten(&self.flat, &mut self.blocks);
            ch.apply_inverse_mass(&self.blocks, &mut self.v);
            ops.apply(qnew, &self.v, &mut self.y);
            for (r, y) in self.y.iter().enumerate() {
                *self.jac.at(r, j) = *y * s;
            }
        }
        self.jac.factor()
    }

    /// Solves J x = b in place (after [`DenseHalf::factor_newton`]).
    pub(crate) fn newton_solve(&self, b: &mut [D]) {
        self.jac.solve(b);
    }

    /// Solves Jᵀ x = b in place.
    pub(crate) fn newton_solve_transpose(&self, b: &mut [D]) {
        self.jac.solve_transpose(b);
    }

    /// `s` ← Wᵀ s = A⁻ᵀ s (after [`DenseHalf::factor_at`] or the half step's solve).
    pub(crate) fn apply_w_transpose(&mut self, s: &mut [[D; DIM]]) {
        flatten(s, &mut self.flat);
        self.a.solve_transpose(&mut self.flat);
        unflatten(&self.flat, s);
    }
}

/// The dense A in the band solver's Newton iteration of the half step
/// ([`super::CoupledHalf::solve`] runs it on this when the tests ask for the dense reference).
impl<D: Scalar, const DIM: usize> HalfSystem<D, DIM> for DenseHalf<D, DIM> {
    fn force(&mut self, ch: &Chain<D, DIM>, q: &[[D; DIM]], p: &[[D; DIM]], ctx: &Ctx<D>) {
        self.coupled_force(ch, q, p, ctx);
    }

    fn parts(&mut self) -> (&[[D; DIM]], &mut [D]) {
        (&self.f, &mut self.flat)
    }

    fn factor(
        &mut self,
        ch: &Chain<D, DIM>,
        (q, p): (&[[D; DIM]], &[[D; DIM]]),
        h: f64,
        ctx: &Ctx<D>,
    ) -> Result<(), ZeroPivot> {
        self.factor_at(ch, (q, p), h, ctx)
    }

    fn solve_flat(&mut self) {
        self.a.solve(&mut self.flat);
    }
}
