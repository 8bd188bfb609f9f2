//! The constraint operator Ĝ(q) of the chain and the O(n) assembly of its products with M⁻¹
//! (thesis §2.4.1, eq. 2.4.1-2.4.2; docs/conventions.md), used by every integrator and the adjoint.
//!
//! ĝ stacks the length constraints gᵢ = ½(‖qᵢ‖² − 1) and, for a locked or reaction-force tip,
//! l(q) = Σ lᵢ e₃ᵀqᵢ. Its Jacobian Ĝ(q) has rows qᵢᵀ on block i and, for the tip, lᵢ e₃ᵀ on every
//! block. Because M̄⁻¹ is tridiagonal, Ĝ(q′) M⁻¹ W Ĝ(q)ᵀ is tridiagonal in the length constraints,
//! bordered by the tip row and column; the tip row is sparse, since Σᵢ lᵢ M̄⁻¹ᵢⱼ = δ_{jn}/(mₙ lₙ).

use crate::base::Scalar;
use crate::model::{dot, zi, BlockSym, Chain};
use crate::tridiag::BorderedTridiag;

/// Ĝ(q) of a chain: apply, transposed apply, residual and the bordered-tridiagonal assemblies.
#[derive(Clone, Copy, Debug)]
pub struct ConstraintOperator<'a, D, const DIM: usize> {
    ch: &'a Chain<D, DIM>,
}

impl<D: Scalar, const DIM: usize> Chain<D, DIM> {
    /// The constraint operator of this chain.
    pub fn constraints(&self) -> ConstraintOperator<'_, D, DIM> {
        ConstraintOperator { ch: self }
    }
}

impl<'a, D: Scalar, const DIM: usize> ConstraintOperator<'a, D, DIM> {
    /// Whether the tip row is present.
    #[inline]
    pub fn bordered(&self) -> bool {
        self.ch.has_tip_constraint()
    }

    /// Ĝ(q) v: (qᵢ·vᵢ)ᵢ and, with the tip row, Σ lᵢ v_{i,z}. `out.len()` = n (+1).
    pub fn apply(&self, q: &[[D; DIM]], v: &[[D; DIM]], out: &mut [D]) {
        let n = self.ch.n();
        for i in 0..n {
            out[i] = dot(&q[i], &v[i]);
        }
        if self.bordered() {
            out[n] = self.ch.tip_z(v);
        }
    }

    /// out += scale · Ĝ(q)ᵀ y: blocks y_i qᵢ (+ y_tip lᵢ e₃).
    pub fn add_transpose(&self, q: &[[D; DIM]], y: &[D], scale: D, out: &mut [[D; DIM]]) {
        let n = self.ch.n();
        let z = zi::<DIM>();
        for i in 0..n {
            for d in 0..DIM {
                out[i][d] += y[i] * q[i][d] * scale;
            }
            if self.bordered() {
                out[i][z] += y[n] * self.ch.lengths[i] * scale;
            }
        }
    }

    /// out = b − Ĝ(q)ᵀ y, written so that its arithmetic is that of the projection p = b − Ĝᵀy.
    pub fn subtract_transpose(
        &self,
        b: &[[D; DIM]],
        q: &[[D; DIM]],
        y: &[D],
        out: &mut [[D; DIM]],
    ) {
        let n = self.ch.n();
        let z = zi::<DIM>();
        for i in 0..n {
            for d in 0..DIM {
                out[i][d] = b[i][d] - y[i] * q[i][d];
            }
            if self.bordered() {
                out[i][z] -= y[n] * self.ch.lengths[i];
            }
        }
    }

    /// The constraint residual ĝ(q) − (0, …, 0, ζ) into `out`, returning its max-norm with the
    /// tip row scaled by the beam length.
    pub fn residual(&self, q: &[[D; DIM]], tip_target: D, out: &mut [D]) -> f64 {
        let n = self.ch.n();
        let mut rmax: f64 = 0.0;
        for i in 0..n {
            let r = (dot(&q[i], &q[i]) - 1.0) * 0.5;
            rmax = rmax.max(r.re().abs());
            out[i] = r;
        }
        if self.bordered() {
            let total: f64 = self.ch.lengths.iter().map(|l| l.re()).sum();
            let r = self.ch.tip_z(q) - tip_target;
            rmax = rmax.max(r.re().abs() / total);
            out[n] = r;
        }
        rmax
    }

    /// Assembles the symmetric Ĝ(q) M⁻¹ Ĝ(q)ᵀ into `tri` (the projection's matrix).
    pub fn assemble_projection(&self, q: &[[D; DIM]], tri: &mut BorderedTridiag<D>) {
        let ch = self.ch;
        let n = ch.n();
        for i in 0..n {
            let (dii, off) = ch.minv_entries(i);
            tri.diag[i] = dot(&q[i], &q[i]) * dii;
            if i + 1 < n {
                let v = dot(&q[i], &q[i + 1]) * off;
                tri.upper[i] = v;
                tri.lower[i + 1] = v;
            }
        }
        if self.bordered() {
            tri.col.iter_mut().for_each(|c| *c = D::zero());
            tri.row.iter_mut().for_each(|c| *c = D::zero());
            let inv_mn = ch.inv_masses[n - 1];
            let v = q[n - 1][zi::<DIM>()] * inv_mn * ch.inv_lengths[n - 1];
            tri.col[n - 1] = v;
            tri.row[n - 1] = v;
            tri.corner = inv_mn;
        }
    }

    /// Assembles the RATTLE Newton matrix J = ∂ĝ(q_{k+1}(λ))/∂λ = −h²/2 Ĝ(q′) M⁻¹ W Ĝ(q)ᵀ into
    /// `tri`: J_{ij} = −h²/2 M̄⁻¹_{ij} q′ᵢ·(W_j q_j) (|i − j| ≤ 1); tip column
    /// −h²/2 q′ᵢ·(M̄⁻¹(l ⊙ W e_z))ᵢ; tip row −h²/2 δ_{jn} (W_n q_n)_z/(mₙ lₙ); corner
    /// −h²/2 (W_n)_{zz}/mₙ. W is block-symmetric ([`BlockSym`]: diagonal, and the (x, z) entry of
    /// the spatial model); `w` = None means W = I (no dissipative term). `scal` is scratch of
    /// length n.
    pub fn assemble_newton(
        &self,
        (q, qnew): (&[[D; DIM]], &[[D; DIM]]),
        w: Option<&[BlockSym<D, DIM>]>,
        h: f64,
        tri: &mut BorderedTridiag<D>,
        scal: &mut [D],
    ) {
        let ch = self.ch;
        let n = ch.n();
        let z = zi::<DIM>();
        let s = -(h * h * 0.5);
        let wq = |i: usize| -> [D; DIM] {
            match w {
                Some(w) => w[i].apply(&q[i]),
                None => q[i],
            }
        };
        // The band, its loop written once per case of W (the check out of the loop).
        match w {
            Some(w) => self.newton_band(qnew, |i| w[i].apply(&q[i]), s, tri),
            None => self.newton_band(qnew, |i| q[i], s, tri),
        }
        if !self.bordered() {
            return;
        }
        let wz = |j: usize| w.map_or(D::one(), |w| w[j].diag[z]);
        self.tip_column(qnew, (z, s), wz, scal, &mut tri.col);
        if let Some(w) = w.filter(|_| DIM == 3) {
            // The (x, z) entries of a spatial W add −h²/2 q′_{i,x} (M̄⁻¹(l ⊙ W_xz))ᵢ; `row`
            // (overwritten below) is the scratch.
            self.tip_column(qnew, (0, s), |j| w[j].xz, scal, &mut tri.row);
            for (c, x) in tri.col.iter_mut().zip(&tri.row) {
                *c += *x;
            }
        }
        tri.row.iter_mut().for_each(|r| *r = D::zero());
        let inv_mn = ch.inv_masses[n - 1];
        let wqn = wq(n - 1);
        tri.row[n - 1] = wqn[z] * inv_mn * ch.inv_lengths[n - 1] * s;
        tri.corner = wz(n - 1) * inv_mn * s;
    }

    /// Assembles the Newton matrix J = −h²/2 Ĝ(q′) M⁻¹ W Ĝ(q)ᵀ of a half step whose W is
    /// A⁻¹ Ω A (the node-by-node Morison drag, [`crate::model::NodeDrag`]): M⁻¹W = Aᵀ diag(Ωₖ/mₖ) A
    /// with (A x)ₖ = xₖ/lₖ − xₖ₊₁/lₖ₊₁, so with aⱼ = qⱼ/lⱼ, a′ⱼ = q′ⱼ/lⱼ and Ω̃ₖ = Ωₖ/mₖ
    /// J_{jj} = s (a′ⱼ·Ω̃ⱼaⱼ + a′ⱼ·Ω̃ⱼ₋₁aⱼ), J_{j,j+1} = −s a′ⱼ·Ω̃ⱼaⱼ₊₁,
    /// J_{j+1,j} = −s a′ⱼ₊₁·Ω̃ⱼaⱼ (s = −h²/2); the tip row Σ lⱼ e₃ᵀ maps to e₃ at the last node
    /// only: col_{n−1} = s a′ₙ₋₁·Ω̃ₙ₋₁e₃, row_{n−1} = s e₃·Ω̃ₙ₋₁aₙ₋₁, corner s e₃·Ω̃ₙ₋₁e₃.
    /// With Ω = I this is [`ConstraintOperator::assemble_newton`] without W.
    pub fn assemble_newton_nodes(
        &self,
        (q, qnew): (&[[D; DIM]], &[[D; DIM]]),
        omega: &[BlockSym<D, DIM>],
        h: f64,
        tri: &mut BorderedTridiag<D>,
    ) {
        let ch = self.ch;
        let n = ch.n();
        let s = -(h * h * 0.5);
        let scaled = |x: &[D; DIM], j: usize| x.map(|c| c * ch.inv_lengths[j]);
        // Ω̃ₖ v = Ωₖ v / mₖ.
        let om = |k: usize, v: &[D; DIM]| omega[k].apply(v).map(|c| c * ch.inv_masses[k]);
        // Each aⱼ, a′ⱼ and Ω̃ product is formed once and carried to the next row (the same
        // values as forming them where they are read).
        let (mut a, mut an) = (scaled(&q[0], 0), scaled(&qnew[0], 0));
        // Ω̃ⱼ₋₁aⱼ, formed in row j − 1.
        let mut prev = [D::zero(); DIM];
        for j in 0..n {
            let oa = om(j, &a);
            let mut d = dot(&an, &oa);
            if j > 0 {
                d += dot(&an, &prev);
            }
            tri.diag[j] = d * s;
            if j + 1 < n {
                let (b, bn) = (scaled(&q[j + 1], j + 1), scaled(&qnew[j + 1], j + 1));
                let ob = om(j, &b);
                tri.upper[j] = -(dot(&an, &ob) * s);
                tri.lower[j + 1] = -(dot(&bn, &oa) * s);
                (a, an, prev) = (b, bn, ob);
            }
        }
        if !self.bordered() {
            return;
        }
        let z = zi::<DIM>();
        let mut ez = [D::zero(); DIM];
        ez[z] = D::one();
        tri.col.iter_mut().for_each(|c| *c = D::zero());
        tri.row.iter_mut().for_each(|c| *c = D::zero());
        let last = n - 1;
        let (a, an) = (scaled(&q[last], last), scaled(&qnew[last], last));
        let oz = om(last, &ez);
        tri.col[last] = dot(&an, &oz) * s;
        tri.row[last] = dot(&ez, &om(last, &a)) * s;
        tri.corner = oz[z] * s;
    }

    /// The tridiagonal band of [`ConstraintOperator::assemble_newton`]: J_{ij} = s M̄⁻¹_{ij}
    /// q′ᵢ·(W_j q_j) for |i − j| ≤ 1, with (W q)_j = `wq`(j).
    #[inline]
    fn newton_band(
        &self,
        qnew: &[[D; DIM]],
        wq: impl Fn(usize) -> [D; DIM],
        s: f64,
        tri: &mut BorderedTridiag<D>,
    ) {
        let ch = self.ch;
        let n = ch.n();
        for i in 0..n {
            let (dii, off) = ch.minv_entries(i);
            let wqi = wq(i);
            tri.diag[i] = dot(&qnew[i], &wqi) * dii * s;
            if i + 1 < n {
                tri.upper[i] = dot(&qnew[i], &wq(i + 1)) * off * s;
                tri.lower[i + 1] = dot(&qnew[i + 1], &wqi) * off * s;
            }
        }
    }

    /// col_i = s q′_{i,c} (M̄⁻¹(l ⊙ ω))ᵢ with ω_j = `weight`(j) (component c of q′).
    fn tip_column(
        &self,
        qnew: &[[D; DIM]],
        (c, s): (usize, f64),
        weight: impl Fn(usize) -> D,
        scal: &mut [D],
        col: &mut [D],
    ) {
        let ch = self.ch;
        let n = ch.n();
        for j in 0..n {
            scal[j] = ch.lengths[j] * weight(j);
        }
        for i in 0..n {
            let (dii, off) = ch.minv_entries(i);
            let mut v = dii * scal[i];
            if i + 1 < n {
                v += off * scal[i + 1];
            }
            if i > 0 {
                v += ch.minv_entries(i - 1).1 * scal[i - 1];
            }
            col[i] = qnew[i][c] * v * s;
        }
    }
}
