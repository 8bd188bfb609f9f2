//! The mass matrix M = M̄ ⊗ I of the chain and its inverse, applied in O(n) (docs/conventions.md).

use super::Chain;
use crate::base::Scalar;

impl<D: Scalar, const DIM: usize> Chain<D, DIM> {
    /// Applies M⁻¹ = M̄⁻¹ ⊗ I in O(n): M̄⁻¹ = diag(1/l) Δ diag(1/m) Δᵀ diag(1/l) with Δ the
    /// lower-bidiagonal difference matrix (docs/conventions.md). `out` may not alias `v`.
    #[inline]
    pub fn apply_inverse_mass(&self, v: &[[D; DIM]], out: &mut [[D; DIM]]) {
        let n = self.n;
        // u = diag(1/m) Δᵀ diag(1/l) v, stored in out; then out = diag(1/l) Δ u.
        let mut next = [D::zero(); DIM];
        for i in (0..n).rev() {
            let mut cur = v[i];
            for c in cur.iter_mut() {
                *c *= self.inv_lengths[i];
            }
            for d in 0..DIM {
                out[i][d] = (cur[d] - next[d]) * self.inv_masses[i];
            }
            next = cur;
        }
        let mut prev = [D::zero(); DIM];
        for i in 0..n {
            let cur = out[i];
            for d in 0..DIM {
                out[i][d] = (cur[d] - prev[d]) * self.inv_lengths[i];
            }
            prev = cur;
        }
    }

    /// Applies M = M̄ ⊗ I in O(n): M̄ = diag(l) Tᵀ diag(m) T diag(l) with T the lower-triangular
    /// matrix of ones (docs/conventions.md; the inverse of [`Chain::apply_inverse_mass`]): a forward prefix sum
    /// of lᵢvᵢ weighted by mᵢ, then a backward suffix sum weighted by lᵢ. `out` may not alias `v`.
    #[inline]
    pub fn apply_mass(&self, v: &[[D; DIM]], out: &mut [[D; DIM]]) {
        let n = self.n;
        let mut acc = [D::zero(); DIM];
        for i in 0..n {
            for d in 0..DIM {
                acc[d] += self.lengths[i] * v[i][d];
                out[i][d] = self.masses[i] * acc[d];
            }
        }
        let mut rev = [D::zero(); DIM];
        for i in (0..n).rev() {
            for d in 0..DIM {
                rev[d] += out[i][d];
                out[i][d] = self.lengths[i] * rev[d];
            }
        }
    }

    /// The tridiagonal entries of M̄⁻¹ in row i (0-based): `(diag_i, off_i)` with
    /// off_i = M̄⁻¹_{i,i+1} = −1/(lᵢ l_{i+1} mᵢ) and M̄⁻¹_{ii} = (1/lᵢ²)(1/mᵢ + 1/m_{i−1}) (no
    /// m₀ term for the first pendulum). From M̄⁻¹ = diag(1/l) Δ diag(1/m) Δᵀ diag(1/l).
    #[inline(always)]
    pub(crate) fn minv_entries(&self, i: usize) -> (D, D) {
        let li = self.inv_lengths[i];
        let mi = self.inv_masses[i];
        let d = if i > 0 {
            li * li * (mi + self.inv_masses[i - 1])
        } else {
            li * li * mi
        };
        let off = if i + 1 < self.n {
            -(li * self.inv_lengths[i + 1] * mi)
        } else {
            D::zero()
        };
        (d, off)
    }
}
