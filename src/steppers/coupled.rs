//! RATTLE's first half step with dissipative terms that couple pendulums
//! ([`crate::model::CoupledDissipativeTerm`], the joint damping; docs/conventions.md), forward and
//! reverse, in O(n).
//!
//! With such a term the first half step p − (h/2) F(q_k, p) = c (F = Σ of the block terms F_D(p)
//! and the coupled F_J(q_k, M⁻¹p)) is no longer block by block: its Jacobian
//! ```text
//! A = I − (h/2)(∂F_D/∂p + ∂F_J/∂p),    ∂F_J/∂p δp = F_J(q_k, M⁻¹δp) = −B(q_k) M⁻¹ δp,
//! ```
//! couples every pendulum to its neighbours. B is block tridiagonal (a coupled term's Fᵢ reads
//! the velocities of pendulums i − 1, i, i + 1: the joint dampers at the two ends of pendulum i)
//! and M⁻¹ = M̄⁻¹ ⊗ I is tridiagonal, so A is block **pentadiagonal**: A_ij = 0 for |i − j| > 2.
//! It is assembled by probing, ∂F_J/∂p applied to the sum of the unit vectors e_{j,e} with
//! j ≡ r (mod 5) for r = 0..5, e = 0..DIM (5·DIM evaluations of F_J, each O(n): a column j
//! reaches only rows |i − j| ≤ 2, so the five columns a probe sums never meet in a row), and
//! factorised as a band matrix ([`BandedLu`], kl = ku = 3·DIM − 1). W = ∂p_{k+½}/∂c = A⁻¹ is
//! dense but is only ever applied, W x or Wᵀ x, by a band solve.
//!
//! RATTLE's Newton matrix J = −h²/2 Ĝ(q_{k+1}) M⁻¹ A⁻¹ Ĝ(q_k)ᵀ is dense too, so J x = r is solved
//! through the sparse augmented system (y = A⁻¹ Ĝ(q_k)ᵀ x)
//! ```text
//! [ A           −Ĝ(q_k)ᵀ ] [y]   [ 0            ]
//! [ Σ Ĝ(q′)M⁻¹     0     ] [x] = [ −(2/h²) Σ r  ] ,
//! ```
//! ordered pendulum by pendulum (y_i then x_i, DIM + 1 unknowns per pendulum): a band matrix with
//! kl = ku = 3·DIM + 1 ([`BorderedBanded`]), bordered by the tip constraint's column (lᵢ e_z on
//! every block; its row is sparse, Σᵢ lᵢ M̄⁻¹ᵢⱼ = δ_{j,n−1}/(m_n l_n)). Σ scales each constraint
//! row by 1/M̄⁻¹ᵢᵢ (the tip's by m_n l_n) so that its entries are of the size of A's for the
//! pivot choice; x does not depend on Σ. Jᵀν = b is the transposed system with ν = Σ w.
//!
//! Cost per Newton iteration: O(n · DIM³) (two band factorisations), against the dense LU's
//! O((n·DIM)³) this replaced (kept as the tests' reference, `coupled/dense.rs`, which gives the
//! same numbers to round-off: `coupled/tests.rs`). Only scenes with a coupled term take this
//! path; every other scene keeps the block path and its numbers bit for bit. The second half step
//! reads F_J at (q_{k+1}, p_{k+½}), so the step stays symmetric.
//!
//! The reverse step (the discrete adjoint) reads the same matrices at (q_k, p_{k+½}):
//! c̄ = Wᵀ S = A⁻ᵀ S, Jᵀν = λ̄, and the attitude q_k gains (h/2) ∇_q(c̄·F_J(q_k, M⁻¹p_{k+½})).

use crate::banded::{BandedLu, BorderedBanded};
use crate::base::Scalar;
use crate::model::{zi, Chain, Ctx};
use crate::tridiag::ZeroPivot;

#[cfg(test)]
mod dense;
#[cfg(test)]
mod tests;

/// The block bandwidth of A: A_ij = 0 for |i − j| > `REACH` (module docs).
const REACH: usize = 2;
/// Blocks per block row of A, and the probing period.
const WIDTH: usize = 2 * REACH + 1;

#[cfg(test)]
thread_local! {
    /// Tests only: [`CoupledHalf::new`] builds the dense reference (`coupled/dense.rs`) instead
    /// of the band solver, so that whole trajectories can be compared.
    pub(crate) static DENSE_REFERENCE: std::cell::Cell<bool> = const { std::cell::Cell::new(false) };
}

/// The half step of a chain with coupled dissipative terms (module docs): A and the augmented
/// Newton matrix as band LUs, and scratch, sized once per chain (no allocation per step).
#[derive(Clone, Debug)]
pub(crate) struct CoupledHalf<D, const DIM: usize> {
    /// A's blocks at the last assembly: `blocks[i · WIDTH + j + REACH − i]` = A_ij.
    blocks: Vec<[[D; DIM]; DIM]>,
    /// A = I − (h/2) ∂F/∂p (n·DIM unknowns).
    a: BandedLu<D>,
    /// The augmented Newton system (n·(DIM + 1) unknowns, bordered by the tip).
    newton: BorderedBanded<D>,
    /// Σ's row scales: 1/M̄⁻¹ᵢᵢ per pendulum, then the tip's m_n l_n.
    sigma: Vec<D>,
    /// −2/h² of the last [`CoupledHalf::factor_newton`].
    rhs_scale: f64,
    /// v = M⁻¹p, the coupled force, and a probe.
    v: Vec<[D; DIM]>,
    f: Vec<[D; DIM]>,
    probe: Vec<[D; DIM]>,
    /// A flat copy of a block vector, and the augmented system's right-hand side.
    flat: Vec<D>,
    aug: Vec<D>,
    /// Tests only: the dense reference that replaces every solve ([`DENSE_REFERENCE`]).
    #[cfg(test)]
    dense: Option<Box<dense::DenseHalf<D, DIM>>>,
}

impl<D: Scalar, const DIM: usize> CoupledHalf<D, DIM> {
    /// Buffers for `ch`.
    pub(crate) fn new(ch: &Chain<D, DIM>) -> Self {
        let (n, bordered) = (ch.n(), ch.has_tip_constraint());
        let v = vec![[D::zero(); DIM]; n];
        let s = DIM + 1;
        CoupledHalf {
            blocks: vec![[[D::zero(); DIM]; DIM]; n * WIDTH],
            a: BandedLu::new(n * DIM, 3 * DIM - 1, 3 * DIM - 1),
            newton: BorderedBanded::new(n * s, (3 * DIM + 1, 3 * DIM + 1), bordered),
            sigma: vec![D::zero(); n + 1],
            rhs_scale: 0.0,
            v: v.clone(),
            f: v.clone(),
            probe: v,
            flat: vec![D::zero(); n * DIM],
            aug: vec![D::zero(); n * s + usize::from(bordered)],
            #[cfg(test)]
            dense: DENSE_REFERENCE
                .with(|d| d.get())
                .then(|| Box::new(dense::DenseHalf::new(ch))),
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

    /// A's blocks at (q, p): the identity, the block terms' −(h/2) ∂F_D/∂p on the diagonal, and
    /// −(h/2) ∂F_J/∂p by probing with period 5 (module docs).
    fn assemble(
        &mut self,
        ch: &Chain<D, DIM>,
        (q, p): (&[[D; DIM]], &[[D; DIM]]),
        h: f64,
        ctx: &Ctx<D>,
    ) {
        let (n, hh) = (ch.n(), 0.5 * h);
        self.blocks
            .iter_mut()
            .for_each(|b| *b = [[D::zero(); DIM]; DIM]);
        for (i, pi) in p.iter().enumerate() {
            let a = &mut self.blocks[i * WIDTH + REACH];
            for (d, row) in a.iter_mut().enumerate() {
                row[d] = D::one();
            }
            if let Some((_, s)) = ch.dissipative_slope(i, pi, ctx) {
                for d in 0..DIM {
                    a[d][d] -= s.diag[d] * hh;
                }
                if DIM == 3 {
                    a[0][2] -= s.xz * hh;
                    a[2][0] -= s.xz * hh;
                }
            }
        }
        for r in 0..WIDTH.min(n) {
            for e in 0..DIM {
                self.probe.iter_mut().for_each(|b| *b = [D::zero(); DIM]);
                for j in (r..n).step_by(WIDTH) {
                    self.probe[j][e] = D::one();
                }
                ch.apply_inverse_mass(&self.probe, &mut self.v);
                self.f.iter_mut().for_each(|f| *f = [D::zero(); DIM]);
                ch.coupled_force(q, &self.v, ctx, &mut self.f);
                for (i, f) in self.f.iter().enumerate() {
                    // The probed column within reach of row i: j ≡ r (mod 5), |i − j| ≤ 2.
                    let off = (r + WIDTH - i % WIDTH) % WIDTH;
                    let j = if off <= REACH {
                        i + off
                    } else if i + off >= WIDTH {
                        i + off - WIDTH
                    } else {
                        continue;
                    };
                    if j >= n {
                        continue;
                    }
                    let a = &mut self.blocks[i * WIDTH + j + REACH - i];
                    for d in 0..DIM {
                        a[d][e] -= f[d] * hh;
                    }
                }
            }
        }
    }

    /// Assembles and factorises A = I − (h/2)(∂F_D/∂p + ∂F_J/∂p) at (q, p).
    pub(crate) fn factor_at(
        &mut self,
        ch: &Chain<D, DIM>,
        (q, p): (&[[D; DIM]], &[[D; DIM]]),
        h: f64,
        ctx: &Ctx<D>,
    ) -> Result<(), ZeroPivot> {
        #[cfg(test)]
        if let Some(dense) = &mut self.dense {
            return dense.factor_at(ch, (q, p), h, ctx);
        }
        self.assemble(ch, (q, p), h, ctx);
        let n = ch.n();
        self.a.clear();
        for i in 0..n {
            for j in i.saturating_sub(REACH)..(i + REACH + 1).min(n) {
                let b = &self.blocks[i * WIDTH + j + REACH - i];
                for (d, row) in b.iter().enumerate() {
                    for (e, x) in row.iter().enumerate() {
                        self.a.add(i * DIM + d, j * DIM + e, *x);
                    }
                }
            }
        }
        self.a.factor()
    }

    /// Solves p − (h/2) F(q, p) = c (every dissipative term, block and coupled) into `p`, and
    /// leaves A factorised at the solution (W = A⁻¹). Linear when the model has no block term
    /// (one solve); Newton from p = c otherwise, with one update past the real parts'
    /// convergence so that the derivative parts of dual numbers converge too.
    pub(crate) fn solve(
        &mut self,
        ch: &Chain<D, DIM>,
        (q, c): (&[[D; DIM]], &[[D; DIM]]),
        (h, ctx): (f64, &Ctx<D>),
        p: &mut [[D; DIM]],
    ) -> Result<(), ZeroPivot> {
        #[cfg(test)]
        if let Some(dense) = &mut self.dense {
            return solve_half_step(&mut **dense, ch, (q, c), (h, ctx), p);
        }
        solve_half_step(self, ch, (q, c), (h, ctx), p)
    }

    /// Assembles and factorises the augmented system of RATTLE's Newton matrix
    /// J = −h²/2 Ĝ(q′) M⁻¹ A⁻¹ Ĝ(q)ᵀ (module docs; A's blocks as last assembled).
    pub(crate) fn factor_newton(
        &mut self,
        ch: &Chain<D, DIM>,
        (q, qnew): (&[[D; DIM]], &[[D; DIM]]),
        h: f64,
    ) -> Result<(), ZeroPivot> {
        #[cfg(test)]
        if let Some(dense) = &mut self.dense {
            return dense.factor_newton(ch, (q, qnew), h);
        }
        let (n, s) = (ch.n(), DIM + 1);
        let k = &mut self.newton;
        k.clear();
        for i in 0..n {
            let (yi, xi) = (i * s, i * s + DIM);
            for j in i.saturating_sub(REACH)..(i + REACH + 1).min(n) {
                let b = &self.blocks[i * WIDTH + j + REACH - i];
                for (d, row) in b.iter().enumerate() {
                    for (e, x) in row.iter().enumerate() {
                        k.band.add(yi + d, j * s + e, *x);
                    }
                }
            }
            // −Ĝ(q)ᵀ: the column of x_i is −qᵢ on block i.
            for d in 0..DIM {
                k.band.add(yi + d, xi, -q[i][d]);
            }
            // Σ Ĝ(q′) M⁻¹: row i is σᵢ M̄⁻¹ᵢⱼ q′ᵢᵀ on blocks j = i − 1, i, i + 1 (σᵢ M̄⁻¹ᵢᵢ = 1).
            let (dii, off) = ch.minv_entries(i);
            let sigma = dii.recip();
            self.sigma[i] = sigma;
            let below = if i > 0 {
                ch.minv_entries(i - 1).1 * sigma
            } else {
                D::zero()
            };
            let above = off * sigma;
            for e in 0..DIM {
                k.band.add(xi, yi + e, qnew[i][e]);
                if i > 0 {
                    k.band.add(xi, yi - s + e, qnew[i][e] * below);
                }
                if i + 1 < n {
                    k.band.add(xi, yi + s + e, qnew[i][e] * above);
                }
            }
        }
        if k.bordered {
            // The tip: column −lᵢ e_z on every block; row Σᵢ lᵢ (M⁻¹y)_{i,z} = y_{n−1,z}/(m_n l_n),
            // scaled by σ_tip = m_n l_n.
            let z = zi::<DIM>();
            for i in 0..n {
                k.col[i * s + z] = -ch.lengths[i];
            }
            k.row[(n - 1) * s + z] = D::one();
            self.sigma[n] = (ch.inv_masses[n - 1] * ch.inv_lengths[n - 1]).recip();
        }
        self.rhs_scale = -2.0 / (h * h);
        k.factor()
    }

    /// Solves J x = b in place (after [`CoupledHalf::factor_newton`]).
    pub(crate) fn newton_solve(&mut self, b: &mut [D]) {
        #[cfg(test)]
        if let Some(dense) = &mut self.dense {
            return dense.newton_solve(b);
        }
        let n = self.sigma.len() - 1;
        self.aug.iter_mut().for_each(|x| *x = D::zero());
        for (i, x) in b.iter().enumerate() {
            self.aug[slot::<DIM>(i, n)] = *x * self.sigma[i] * self.rhs_scale;
        }
        self.newton.solve(&mut self.aug);
        for (i, x) in b.iter_mut().enumerate() {
            *x = self.aug[slot::<DIM>(i, n)];
        }
    }

    /// Solves Jᵀ x = b in place: Kᵀ(z; w) = (0; −(2/h²) b), x = Σ w (module docs).
    pub(crate) fn newton_solve_transpose(&mut self, b: &mut [D]) {
        #[cfg(test)]
        if let Some(dense) = &mut self.dense {
            return dense.newton_solve_transpose(b);
        }
        let n = self.sigma.len() - 1;
        self.aug.iter_mut().for_each(|x| *x = D::zero());
        for (i, x) in b.iter().enumerate() {
            self.aug[slot::<DIM>(i, n)] = *x * self.rhs_scale;
        }
        self.newton.solve_transpose(&mut self.aug);
        for (i, x) in b.iter_mut().enumerate() {
            *x = self.aug[slot::<DIM>(i, n)] * self.sigma[i];
        }
    }

    /// `s` ← Wᵀ s = A⁻ᵀ s (after [`CoupledHalf::factor_at`] or [`CoupledHalf::solve`]).
    pub(crate) fn apply_w_transpose(&mut self, s: &mut [[D; DIM]]) {
        #[cfg(test)]
        if let Some(dense) = &mut self.dense {
            return dense.apply_w_transpose(s);
        }
        flatten(s, &mut self.flat);
        self.a.solve_transpose(&mut self.flat);
        unflatten(&self.flat, s);
    }
}

/// What the half step's Newton iteration ([`solve_half_step`]) needs of a solver of A: the band
/// solver here and the tests' dense reference (`coupled/dense.rs`), which share the iteration and
/// differ only in how A is assembled and solved.
trait HalfSystem<D: Scalar, const DIM: usize> {
    /// Σ_T F_T(q, M⁻¹p) of the coupled terms into the workspace (`CoupledHalf::coupled_force`).
    fn force(&mut self, ch: &Chain<D, DIM>, q: &[[D; DIM]], p: &[[D; DIM]], ctx: &Ctx<D>);
    /// The force of the last [`HalfSystem::force`], and the flat right-hand side of A x = b.
    fn parts(&mut self) -> (&[[D; DIM]], &mut [D]);
    /// Assembles and factorises A at (q, p) (`CoupledHalf::factor_at`).
    fn factor(
        &mut self,
        ch: &Chain<D, DIM>,
        at: (&[[D; DIM]], &[[D; DIM]]),
        h: f64,
        ctx: &Ctx<D>,
    ) -> Result<(), ZeroPivot>;
    /// Solves A x = b in place on the flat right-hand side (after [`HalfSystem::factor`]).
    fn solve_flat(&mut self);
}

impl<D: Scalar, const DIM: usize> HalfSystem<D, DIM> for CoupledHalf<D, DIM> {
    #[inline]
    fn force(&mut self, ch: &Chain<D, DIM>, q: &[[D; DIM]], p: &[[D; DIM]], ctx: &Ctx<D>) {
        self.coupled_force(ch, q, p, ctx);
    }

    #[inline]
    fn parts(&mut self) -> (&[[D; DIM]], &mut [D]) {
        (&self.f, &mut self.flat)
    }

    #[inline]
    fn factor(
        &mut self,
        ch: &Chain<D, DIM>,
        (q, p): (&[[D; DIM]], &[[D; DIM]]),
        h: f64,
        ctx: &Ctx<D>,
    ) -> Result<(), ZeroPivot> {
        self.factor_at(ch, (q, p), h, ctx)
    }

    #[inline]
    fn solve_flat(&mut self) {
        self.a.solve(&mut self.flat);
    }
}

/// Solves p − (h/2) F(q, p) = c (every dissipative term, block and coupled) into `p`, and
/// leaves A factorised at the solution (W = A⁻¹): one solve when the model has no block term;
/// Newton from p = c otherwise, with one update past the real parts' convergence so that the
/// derivative parts of dual numbers converge too ([`CoupledHalf::solve`]).
fn solve_half_step<D: Scalar, const DIM: usize, S: HalfSystem<D, DIM>>(
    s: &mut S,
    ch: &Chain<D, DIM>,
    (q, c): (&[[D; DIM]], &[[D; DIM]]),
    (h, ctx): (f64, &Ctx<D>),
    p: &mut [[D; DIM]],
) -> Result<(), ZeroPivot> {
    p.copy_from_slice(c);
    if ch.dissipation_count() == 0 {
        s.factor(ch, (q, p), h, ctx)?;
        flatten(c, s.parts().1);
        s.solve_flat();
        unflatten(s.parts().1, p);
        return Ok(());
    }
    let hh = 0.5 * h;
    let mut extra = false;
    for _ in 0..50 {
        // r = p − (h/2) F(p) − c
        s.force(ch, q, p, ctx);
        let (f, flat) = s.parts();
        let mut rmax: f64 = 0.0;
        let mut pmax: f64 = 0.0;
        for i in 0..p.len() {
            let fd = ch.dissipative_force(i, &p[i], ctx);
            for d in 0..DIM {
                let mut fi = f[i][d];
                if let Some(fd) = &fd {
                    fi += fd[d];
                }
                let r = p[i][d] - fi * hh - c[i][d];
                flat[i * DIM + d] = r;
                rmax = rmax.max(r.re().abs());
                pmax = pmax.max(p[i][d].re().abs());
            }
        }
        let small = rmax <= 1e-15 * (1.0 + pmax);
        if small && extra {
            break;
        }
        extra |= small;
        s.factor(ch, (q, p), h, ctx)?;
        s.solve_flat();
        let flat = s.parts().1;
        for (i, pi) in p.iter_mut().enumerate() {
            for d in 0..DIM {
                pi[d] -= flat[i * DIM + d];
            }
        }
    }
    s.factor(ch, (q, p), h, ctx)
}

/// The augmented system's index of constraint i: x_i after y_i's DIM components, the tip (i = n)
/// last.
#[inline]
fn slot<const DIM: usize>(i: usize, n: usize) -> usize {
    if i < n {
        i * (DIM + 1) + DIM
    } else {
        n * (DIM + 1)
    }
}

fn flatten<D: Scalar, const DIM: usize>(v: &[[D; DIM]], out: &mut [D]) {
    for (i, b) in v.iter().enumerate() {
        out[i * DIM..(i + 1) * DIM].copy_from_slice(b);
    }
}

fn unflatten<D: Scalar, const DIM: usize>(v: &[D], out: &mut [[D; DIM]]) {
    for (i, b) in out.iter_mut().enumerate() {
        b.copy_from_slice(&v[i * DIM..(i + 1) * DIM]);
    }
}
