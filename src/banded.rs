//! O(n) LU factorisation of banded matrices with partial pivoting, optionally bordered by one
//! dense row and column: the linear algebra of RATTLE's half step with joint damping
//! (`steppers/coupled.rs`, docs/conventions.md "Joint damping").
//!
//! A matrix with kl sub- and ku super-diagonals is factorised as P A = L U by Gaussian
//! elimination with row interchanges (LAPACK's `gbtf2`, unblocked): L has kl sub-diagonals, and
//! the interchanges widen U to kl + ku super-diagonals. The storage is LAPACK's band layout,
//! column by column with 2 kl + ku + 1 entries (the top kl of them for U's fill-in), so the
//! factorisation costs O(n · kl · (kl + ku)) and a solve O(n · (2 kl + ku)) — linear in n for
//! a fixed band. Both A x = b and Aᵀ x = b are solved with the same factors (`gbtrs`).
//!
//! A border (one extra row rᵀ and column c, corner d) is eliminated by its Schur complement
//! s = d − rᵀ A⁻¹ c, with A⁻¹c and A⁻ᵀr solved once per factorisation, as
//! [`crate::tridiag::BorderedTridiag`] does for the tridiagonal systems.
//!
//! Why hand-written: the systems are solved over dual numbers (`num_dual`'s `DualNum`, for the
//! forward-mode derivatives of whole trajectories and the Hessians of [`crate::ocp`]). The Rust
//! crates with a banded LU (RustedSciThe) or a general LU (faer, nalgebra) work on `f64` or on
//! their own field traits, which num-dual's types do not implement, and nalgebra has no banded
//! storage. Pivots are chosen on the real parts; divisions are multiplications by the pivots'
//! reciprocals (so `f64` and dual runs agree in their real parts, as in [`crate::tridiag`]).

use crate::base::Scalar;
use crate::tridiag::ZeroPivot;

/// A banded n × n matrix and, after [`BandedLu::factor`], its LU factors with partial pivoting
/// (module docs). Sized once; assembly, factorisation and solves do not allocate.
#[derive(Clone, Debug)]
pub struct BandedLu<D> {
    n: usize,
    kl: usize,
    ku: usize,
    /// Column-major band storage: entry (i, j) at `j · ld + kl + ku + i − j`,
    /// ld = 2 kl + ku + 1.
    ab: Vec<D>,
    /// Row interchanged with row j at step j.
    piv: Vec<usize>,
    /// Reciprocals of U's diagonal.
    dinv: Vec<D>,
}

impl<D: Scalar> BandedLu<D> {
    /// Zero storage for an n × n matrix with `kl` sub- and `ku` super-diagonals.
    pub fn new(n: usize, kl: usize, ku: usize) -> Self {
        BandedLu {
            n,
            kl,
            ku,
            ab: vec![D::zero(); n * (2 * kl + ku + 1)],
            piv: vec![0; n],
            dinv: vec![D::zero(); n],
        }
    }

    /// The size n.
    pub fn n(&self) -> usize {
        self.n
    }

    /// The bandwidths (kl, ku) of the matrix (before the interchanges' fill-in).
    pub fn bandwidths(&self) -> (usize, usize) {
        (self.kl, self.ku)
    }

    #[inline]
    fn ld(&self) -> usize {
        2 * self.kl + self.ku + 1
    }

    /// Index of entry (i, j) in `ab` (i − j in −(kl + ku)..=kl).
    #[inline]
    fn idx(&self, i: usize, j: usize) -> usize {
        j * self.ld() + self.kl + self.ku + i - j
    }

    /// Sets every entry to zero (before an assembly).
    pub fn clear(&mut self) {
        self.ab.iter_mut().for_each(|x| *x = D::zero());
    }

    /// Adds `v` to entry (i, j), which must lie in the band (−ku ≤ j − i … i − j ≤ kl).
    #[inline]
    pub fn add(&mut self, i: usize, j: usize, v: D) {
        debug_assert!(i < self.n && j < self.n, "({i}, {j}) outside {}", self.n);
        debug_assert!(
            i <= j + self.kl && j <= i + self.ku,
            "({i}, {j}) outside the band"
        );
        let k = self.idx(i, j);
        self.ab[k] += v;
    }

    /// Entry (i, j) of the assembled matrix (zero outside the band; before [`BandedLu::factor`]).
    pub fn get(&self, i: usize, j: usize) -> D {
        if i > j + self.kl || j > i + self.ku {
            D::zero()
        } else {
            self.ab[self.idx(i, j)]
        }
    }

    /// Factorises the assembled matrix in place: P A = L U (module docs).
    ///
    /// # Errors
    /// [`ZeroPivot`] when a column has no non-zero (finite) pivot: A is singular.
    pub fn factor(&mut self) -> Result<(), ZeroPivot> {
        let (n, kl, ld) = (self.n, self.kl, self.ld());
        let kv = self.kl + self.ku;
        // Last column touched by the interchanges so far.
        let mut ju = 0;
        for j in 0..n {
            let km = kl.min(n - 1 - j);
            let col = j * ld + kv;
            let mut jp = 0;
            let mut best = self.ab[col].re().abs();
            for r in 1..=km {
                let a = self.ab[col + r].re().abs();
                if a > best {
                    best = a;
                    jp = r;
                }
            }
            self.piv[j] = j + jp;
            let pivot = self.ab[col + jp];
            if pivot.re() == 0.0 || !pivot.re().is_finite() {
                return Err(ZeroPivot {
                    index: j,
                    pivot: pivot.re(),
                });
            }
            ju = ju.max((j + self.ku + jp).min(n - 1));
            if jp != 0 {
                for c in j..=ju {
                    let (a, b) = (self.idx(j, c), self.idx(j + jp, c));
                    self.ab.swap(a, b);
                }
            }
            let inv = self.ab[col].recip();
            self.dinv[j] = inv;
            for r in 1..=km {
                self.ab[col + r] *= inv;
            }
            // Rank-one update of rows j+1..=j+km, columns j+1..=ju.
            for c in j + 1..=ju {
                let uc = self.idx(j, c);
                let u = self.ab[uc];
                for r in 1..=km {
                    let l = self.ab[col + r];
                    self.ab[uc + r] -= l * u;
                }
            }
        }
        Ok(())
    }

    /// Solves A x = b in place (after [`BandedLu::factor`]).
    pub fn solve(&self, b: &mut [D]) {
        let (n, kl, ld) = (self.n, self.kl, self.ld());
        let kv = self.kl + self.ku;
        for j in 0..n {
            let km = kl.min(n - 1 - j);
            b.swap(j, self.piv[j]);
            let bj = b[j];
            let col = j * ld + kv;
            for r in 1..=km {
                b[j + r] -= self.ab[col + r] * bj;
            }
        }
        for j in (0..n).rev() {
            let col = j * ld + kv;
            let x = b[j] * self.dinv[j];
            b[j] = x;
            for i in j.saturating_sub(kv)..j {
                b[i] -= self.ab[col - (j - i)] * x;
            }
        }
    }

    /// Solves Aᵀ x = b in place (after [`BandedLu::factor`]): Uᵀ, then Lᵀ and the interchanges
    /// in reverse.
    pub fn solve_transpose(&self, b: &mut [D]) {
        let (n, kl, ld) = (self.n, self.kl, self.ld());
        let kv = self.kl + self.ku;
        for j in 0..n {
            let col = j * ld + kv;
            let mut s = b[j];
            for i in j.saturating_sub(kv)..j {
                s -= self.ab[col - (j - i)] * b[i];
            }
            b[j] = s * self.dinv[j];
        }
        for j in (0..n).rev() {
            let km = kl.min(n - 1 - j);
            let col = j * ld + kv;
            let mut s = b[j];
            for r in 1..=km {
                s -= self.ab[col + r] * b[j + r];
            }
            b[j] = s;
            b.swap(j, self.piv[j]);
        }
    }
}

/// A banded matrix bordered by one dense column c, row rᵀ and corner d (module docs):
/// ```text
/// [ A   c ] [x]   [b]
/// [ rᵀ  d ] [y] = [e]
/// ```
/// of size n (+1 when `bordered`). Sized once; solves do not allocate.
#[derive(Clone, Debug)]
pub struct BorderedBanded<D> {
    /// The banded part A (assembled through [`BandedLu::add`]).
    pub band: BandedLu<D>,
    /// Border column c.
    pub col: Vec<D>,
    /// Border row r.
    pub row: Vec<D>,
    /// Corner d.
    pub corner: D,
    /// Whether the border is present.
    pub bordered: bool,
    /// A⁻¹c, A⁻ᵀr and 1/(d − rᵀA⁻¹c) of the last factorisation.
    x2: Vec<D>,
    z2: Vec<D>,
    schur_inv: D,
}

impl<D: Scalar> BorderedBanded<D> {
    /// Zero storage: an n × n band (`kl`, `ku`) and, when `bordered`, the border.
    pub fn new(n: usize, (kl, ku): (usize, usize), bordered: bool) -> Self {
        let m = if bordered { n } else { 0 };
        BorderedBanded {
            band: BandedLu::new(n, kl, ku),
            col: vec![D::zero(); m],
            row: vec![D::zero(); m],
            corner: D::zero(),
            bordered,
            x2: vec![D::zero(); m],
            z2: vec![D::zero(); m],
            schur_inv: D::zero(),
        }
    }

    /// Sets the band, the border and the corner to zero (before an assembly).
    pub fn clear(&mut self) {
        self.band.clear();
        self.col.iter_mut().for_each(|x| *x = D::zero());
        self.row.iter_mut().for_each(|x| *x = D::zero());
        self.corner = D::zero();
    }

    /// Factorises the band, then (bordered) the Schur complement d − rᵀA⁻¹c.
    ///
    /// # Errors
    /// [`ZeroPivot`] (index n for the Schur complement).
    pub fn factor(&mut self) -> Result<(), ZeroPivot> {
        self.band.factor()?;
        if self.bordered {
            self.x2.copy_from_slice(&self.col);
            self.band.solve(&mut self.x2);
            self.z2.copy_from_slice(&self.row);
            self.band.solve_transpose(&mut self.z2);
            let mut rx = D::zero();
            for (r, x) in self.row.iter().zip(&self.x2) {
                rx += *r * *x;
            }
            let schur = self.corner - rx;
            let n = self.band.n();
            if schur.re() == 0.0 || !schur.re().is_finite() {
                return Err(ZeroPivot {
                    index: n,
                    pivot: schur.re(),
                });
            }
            self.schur_inv = schur.recip();
        }
        Ok(())
    }

    /// Solves the bordered system in place (`rhs.len()` = n, or n + 1 when bordered).
    pub fn solve(&self, rhs: &mut [D]) {
        self.solve_impl(rhs, false);
    }

    /// Solves its transpose in place.
    pub fn solve_transpose(&self, rhs: &mut [D]) {
        self.solve_impl(rhs, true);
    }

    fn solve_impl(&self, rhs: &mut [D], transpose: bool) {
        let n = self.band.n();
        // Aᵀ's border is (column r, row c), with A⁻ᵀr in place of A⁻¹c.
        let (x, border_row) = if transpose {
            self.band.solve_transpose(&mut rhs[..n]);
            (&self.z2, &self.col)
        } else {
            self.band.solve(&mut rhs[..n]);
            (&self.x2, &self.row)
        };
        if self.bordered {
            let mut ry = D::zero();
            for (r, y) in border_row.iter().zip(rhs.iter()) {
                ry += *r * *y;
            }
            let y = (rhs[n] - ry) * self.schur_inv;
            for (r, x) in rhs.iter_mut().zip(x) {
                *r -= *x * y;
            }
            rhs[n] = y;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::{DMatrix, DVector};
    use num_dual::{Dual64, DualNum};

    /// A pseudo-random number in [−1, 1) (a fixed LCG, so the tests are deterministic).
    fn rand(state: &mut u64) -> f64 {
        *state = state
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        ((*state >> 11) as f64 / (1u64 << 53) as f64) * 2.0 - 1.0
    }

    /// A random banded matrix (with a small diagonal, so that pivoting happens) and its dense
    /// copy, bordered when asked.
    fn system(
        n: usize,
        (kl, ku): (usize, usize),
        bordered: bool,
        seed: u64,
    ) -> (BorderedBanded<f64>, DMatrix<f64>) {
        let mut s = seed;
        let mut a = BorderedBanded::new(n, (kl, ku), bordered);
        let m = n + usize::from(bordered);
        let mut d = DMatrix::zeros(m, m);
        for i in 0..n {
            for j in i.saturating_sub(kl)..(i + ku + 1).min(n) {
                // A small diagonal, so that rows are interchanged, except for a triangular
                // band (kl = 0: no interchange possible), which is kept well conditioned.
                let v = match (i == j, kl) {
                    (true, 0) => 3.0 + rand(&mut s),
                    (true, _) => 0.1 * rand(&mut s),
                    _ => rand(&mut s),
                };
                a.band.add(i, j, v);
                d[(i, j)] = v;
            }
        }
        if bordered {
            for i in 0..n {
                (a.col[i], a.row[i]) = (rand(&mut s), rand(&mut s));
                (d[(i, n)], d[(n, i)]) = (a.col[i], a.row[i]);
            }
            a.corner = rand(&mut s);
            d[(n, n)] = a.corner;
        }
        (a, d)
    }

    /// The banded solves (both orientations, with and without the border, several bands and
    /// sizes down to 1) equal nalgebra's dense LU of the same matrix to 1e-12 relative to the
    /// solution's size.
    #[test]
    fn solves_equal_dense_lu() {
        let mut seed = 7;
        for &(n, kl, ku) in &[
            (1, 0, 0),
            (2, 1, 1),
            (9, 2, 3),
            (30, 5, 5),
            (41, 7, 4),
            (25, 0, 3),
        ] {
            for bordered in [false, true] {
                for transpose in [false, true] {
                    seed += 1;
                    let (mut a, d) = system(n, (kl, ku), bordered, seed);
                    a.factor().unwrap();
                    let m = d.nrows();
                    let mut s = seed * 31;
                    let b: Vec<f64> = (0..m).map(|_| rand(&mut s)).collect();
                    let dd = if transpose { d.transpose() } else { d };
                    let reference = dd.lu().solve(&DVector::from_vec(b.clone())).unwrap();
                    let mut x = b;
                    if transpose {
                        a.solve_transpose(&mut x);
                    } else {
                        a.solve(&mut x);
                    }
                    let scale = reference.amax();
                    for (xi, ri) in x.iter().zip(reference.iter()) {
                        assert!(
                            (xi - ri).abs() <= 1e-12 * scale,
                            "n {n} kl {kl} ku {ku} bordered {bordered} transpose {transpose}: \
                             {xi} vs {ri}"
                        );
                    }
                }
            }
        }
    }

    /// Over dual numbers the solve is the derivative of the f64 solve: with A(t) and b(t)
    /// seeded, the derivative parts equal central differences (step 1e-6) to 1e-8, and the real
    /// parts are the f64 solve's bit for bit (same pivots, same arithmetic).
    #[test]
    fn dual_solve_is_the_derivative() {
        let (n, kl, ku) = (20, 4, 3);
        let build = |t: Dual64| {
            let (a0, _) = system(n, (kl, ku), true, 99);
            let mut a = BorderedBanded::<Dual64>::new(n, (kl, ku), true);
            for i in 0..n {
                for j in i.saturating_sub(kl)..(i + ku + 1).min(n) {
                    let v = a0.band.get(i, j);
                    a.band
                        .add(i, j, (t * (0.3 + 0.01 * (i + j) as f64)).sin() * 0.5 + v);
                }
                a.col[i] = Dual64::from(a0.col[i]) + t * 0.2;
                a.row[i] = Dual64::from(a0.row[i]) - t.cos() * 0.1;
            }
            a.corner = Dual64::from(a0.corner) + t;
            let b: Vec<Dual64> = (0..=n).map(|i| (t + i as f64).sin()).collect();
            (a, b)
        };
        for transpose in [false, true] {
            let run = |t: Dual64| {
                let (mut a, mut b) = build(t);
                a.factor().unwrap();
                if transpose {
                    a.solve_transpose(&mut b);
                } else {
                    a.solve(&mut b);
                }
                b
            };
            let t = 0.37;
            let x = run(Dual64::new(t, 1.0));
            let xp = run(Dual64::from(t + 1e-6));
            let xm = run(Dual64::from(t - 1e-6));
            for i in 0..=n {
                let fd = (xp[i].re - xm[i].re) / 2e-6;
                assert!((x[i].eps - fd).abs() <= 1e-8 * fd.abs().max(1.0), "{i}");
            }
            // The f64 solve has the same real parts.
            let (a0, _) = build(Dual64::from(t));
            let mut af = BorderedBanded::<f64>::new(n, (kl, ku), true);
            for i in 0..n {
                for j in i.saturating_sub(kl)..(i + ku + 1).min(n) {
                    af.band.add(i, j, a0.band.get(i, j).re);
                }
                (af.col[i], af.row[i]) = (a0.col[i].re, a0.row[i].re);
            }
            af.corner = a0.corner.re;
            af.factor().unwrap();
            let mut bf: Vec<f64> = (0..=n).map(|i| (t + i as f64).sin()).collect();
            if transpose {
                af.solve_transpose(&mut bf);
            } else {
                af.solve(&mut bf);
            }
            for i in 0..=n {
                assert_eq!(x[i].re.to_bits(), bf[i].to_bits(), "real part {i}");
            }
        }
    }

    /// A singular band (a zero column) is reported with its column, not divided by.
    #[test]
    fn zero_pivot_is_reported() {
        let mut a = BandedLu::<f64>::new(4, 1, 1);
        for i in 0..4 {
            if i != 2 {
                a.add(i, i, 1.0);
            }
        }
        let err = a.factor().unwrap_err();
        assert_eq!(err.index, 2);
    }
}
