//! The dense box QP of the condensed solver ([`super::Condensed`]): a primal active-set method
//! on the m × m Gauss-Newton model of the decisions.

use faer::Mat;

use super::globalise::ModelChange;

/// A dense convex box QP min ½ δᵀ(H + λI)δ + gᵀδ, lo ≤ δ ≤ hi (lo ≤ 0 ≤ hi), by a primal
/// active-set method from δ = 0 (Nocedal & Wright, *Numerical Optimization*, Alg. 16.3):
/// Newton steps on the free set (Cholesky of its block), a ratio test that fixes the first
/// blocking bound, and the release of the bound whose multiplier has the wrong sign.
/// A decision without effect (a zero row of H and a zero gradient: u_N of a per-step control
/// without effort penalty acts on nothing J sees) stays where it is, as the Riccati solver's
/// inert controls ([`super::boxqp`]).
const INERT: i8 = 2;

/// The data of one dense box QP: H (lower triangle, row-major), g, the shift λ, and the box
/// lower ≤ θ + δ ≤ upper about the point θ.
#[derive(Clone, Copy, Debug)]
pub(crate) struct DenseQp<'a> {
    pub h: &'a [f64],
    pub g: &'a [f64],
    pub theta: &'a [f64],
    pub lower: f64,
    pub upper: f64,
    pub lambda: f64,
}

#[derive(Clone, Debug)]
pub(crate) struct BoxQp {
    /// The step δ of the last solve.
    pub delta: Vec<f64>,
    /// 0 free, −1 at its lower bound, +1 at its upper bound, [`INERT`].
    fixed: Vec<i8>,
    free: Vec<usize>,
    resid: Vec<f64>,
}

impl BoxQp {
    pub(super) fn new(np: usize) -> Self {
        BoxQp {
            delta: vec![0.0; np],
            fixed: vec![0; np],
            free: Vec::with_capacity(np),
            resid: vec![0.0; np],
        }
    }

    /// (H + λI)δ + g into `resid` (H: lower triangle, row-major).
    fn residual(&mut self, h: &[f64], g: &[f64], lambda: f64) {
        let np = g.len();
        for i in 0..np {
            let mut r = g[i] + lambda * self.delta[i];
            for j in 0..np {
                r += h[i.max(j) * np + i.min(j)] * self.delta[j];
            }
            self.resid[i] = r;
        }
    }

    /// Solves the QP with the box lo − θ ≤ δ ≤ hi − θ; returns the model change (gᵀδ, ½δᵀHδ)
    /// without λ, or `None` when H + λI is not positive definite on a free set.
    pub(super) fn solve(&mut self, qp: &DenseQp<'_>) -> Option<ModelChange> {
        let DenseQp {
            h,
            g,
            theta,
            lower: lo,
            upper: hi,
            lambda,
        } = *qp;
        let np = g.len();
        let bounds = |i: usize| (lo - theta[i], hi - theta[i]);
        self.delta.fill(0.0);
        for i in 0..np {
            let inert = g[i] == 0.0 && (0..np).all(|j| h[i.max(j) * np + i.min(j)] == 0.0);
            let (l, u) = bounds(i);
            self.fixed[i] = if inert {
                INERT
            } else if l >= 0.0 && g[i] > 0.0 {
                -1
            } else if u <= 0.0 && g[i] < 0.0 {
                1
            } else {
                0
            };
        }
        for _ in 0..10 * np + 10 {
            let p = self.free_newton_step(h, g, lambda)?;
            // The first bound the full step crosses, if any, joins the working set.
            let (alpha, block) = self.ratio_test(&p, bounds);
            for (a, &i) in self.free.iter().enumerate() {
                self.delta[i] += alpha * p[(a, 0)];
            }
            if let Some((i, side, to)) = block {
                self.delta[i] = to;
                self.fixed[i] = side;
                continue;
            }
            // A minimiser on the working set: release the worst wrong-signed multiplier.
            self.residual(h, g, lambda);
            let worst = (0..np)
                .filter(|&i| self.fixed[i] == -1 || self.fixed[i] == 1)
                .map(|i| (i, -f64::from(self.fixed[i]) * self.resid[i]))
                .filter(|&(_, m)| m < 0.0)
                .min_by(|a, b| a.1.total_cmp(&b.1));
            match worst {
                Some((i, _)) => self.fixed[i] = 0,
                None => return Some(self.model_change(h, g)),
            }
        }
        None
    }

    /// The Newton step p on the free set (the others held): (H + λI)_FF p = −((H + λI)δ + g)_F,
    /// by faer's Cholesky; `None` when the free block is not positive definite.
    fn free_newton_step(&mut self, h: &[f64], g: &[f64], lambda: f64) -> Option<Mat<f64>> {
        let np = g.len();
        self.free.clear();
        self.free.extend((0..np).filter(|&i| self.fixed[i] == 0));
        self.residual(h, g, lambda);
        let nf = self.free.len();
        if nf == 0 {
            return Some(Mat::zeros(0, 1));
        }
        let hf = Mat::from_fn(nf, nf, |a, b| {
            let (i, j) = (self.free[a], self.free[b]);
            h[i.max(j) * np + i.min(j)] + if a == b { lambda } else { 0.0 }
        });
        let rhs = Mat::from_fn(nf, 1, |a, _| -self.resid[self.free[a]]);
        let llt = hf.llt(faer::Side::Lower).ok()?;
        Some(faer::linalg::solvers::Solve::solve(&llt, &rhs))
    }

    /// The largest α ≤ 1 that keeps δ + α p in the box (bounds of decision i: `bounds(i)`), and
    /// the bound that stops it (decision, side, value).
    fn ratio_test(
        &self,
        p: &Mat<f64>,
        bounds: impl Fn(usize) -> (f64, f64),
    ) -> (f64, Option<(usize, i8, f64)>) {
        let (mut alpha, mut block) = (1.0, None);
        for (a, &i) in self.free.iter().enumerate() {
            let (d, pi) = (self.delta[i], p[(a, 0)]);
            let (l, u) = bounds(i);
            let (to, side) = if pi < 0.0 { (l, -1) } else { (u, 1) };
            let crosses = (pi < 0.0 && d + pi < to) || (pi > 0.0 && d + pi > to);
            if crosses {
                let a_i = ((to - d) / pi).max(0.0);
                if a_i < alpha {
                    alpha = a_i;
                    block = Some((i, side, to));
                }
            }
        }
        (alpha, block)
    }

    /// (gᵀδ, ½δᵀHδ).
    fn model_change(&self, h: &[f64], g: &[f64]) -> ModelChange {
        let np = g.len();
        let mut quad = 0.0;
        for i in 0..np {
            for j in 0..np {
                quad += self.delta[i] * h[i.max(j) * np + i.min(j)] * self.delta[j];
            }
        }
        let lin = g.iter().zip(&self.delta).map(|(a, b)| a * b).sum();
        ModelChange {
            d1: lin,
            d2: 0.5 * quad,
        }
    }
}
