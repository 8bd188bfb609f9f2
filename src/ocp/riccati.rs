//! The backward pass: the Gauss-Newton Riccati recursion with box-clamped controls, and beside
//! it the exact costate sweep that gives the gradient.
//!
//! State z_k = (ξ_k, w_k): the tangent coordinates ξ (2n) and, when the problem needs it
//! (a rate penalty or controls held over several steps), w_k = u_{k−1}, copied forward by the
//! dynamics. At a *free* stage the decision is v_k = u_k; at a *held* stage (inside a piece of a
//! piecewise-constant control) there is no decision and u_k = w_k:
//! ```text
//! free:  Ã = [A 0; 0 0],  B̃ = [B; 1]          held:  Ã = [A B; 0 1],  no B̃
//! ```
//! Stage cost (Gauss-Newton model of the objective's residual r_k(M₀(q_k)), linear in ∂ξ,
//! `ocp/cost.rs`): ℓ_k = ½ w_k r_k² + e_k u_k² + (σ/h)(u_k − w_k)² (the rate term for
//! k ≥ 1; c_sum: w_k = 2, r_k = M₀, e_k = ρh), so l_x = w_k r_k ∇r_k (+ w terms),
//! l_xx = w_k ∇r_k∇r_kᵀ (rank 1; ∇r_k = r_k′ ∇M₀ has one entry, at φ₁).
//!
//! Recursion (k = N … 0; s′ = 0, S′ = 0 after the last stage), Tassa, Erez, Todorov (IROS 2012):
//! ```text
//! Q_x = l_x + Ãᵀs′   Q_u = l_u + B̃ᵀs′   Q_xx = l_xx + ÃᵀS′Ã   Q_uu = l_uu + B̃ᵀS′B̃
//! Q_ux = l_ux + B̃ᵀS′Ã
//! k = argmin_{lo ≤ δ ≤ hi} ½ Q_uu δ² + Q_u δ,  K = −Q_ux/Q_uu (0 if clamped)
//! s = Q_x + KᵀQ_uu k + KᵀQ_u + Q_uxᵀk     S = Q_xx + KᵀQ_uu K + KᵀQ_ux + Q_uxᵀK  (symmetrised)
//! ΔJ(α) = α Σ k Q_u + ½ α² Σ k² Q_uu
//! ```
//! A regularisation μ enters as a proximal term ½ μ δv² of the model (Q_uu += μ, l_u += μ δv
//! about a shifted point), so K, k and S stay those of one consistent quadratic model. The
//! interior-point QP of [`super::Solver`] uses the same pass with its barrier terms
//! (Q_uu += z/s, l_u += ±τ/s, bounds at ±∞); the fallback without stored Jacobians and the warm
//! start use the stage box-QP (clamped controls: K = 0).
//! The costate sweep ν_k = l_x + Ãᵀν_{k+1}, g_k = l_u + B̃ᵀν_{k+1} (ν after the last stage 0) is
//! the discrete adjoint in tangent coordinates: g is the exact gradient of J with respect to
//! the decisions (Q_u is not, away from the optimum: s carries the feedback terms).
//!
//! Every product with S′, s′ and ν′ comes from two faer matrix products on preallocated
//! matrices (the O(n_z³) part), with E = [Ã B̃]: R = [S′E s′ ν′], then EᵀR, whose blocks are
//! ÃᵀS′Ã, B̃ᵀS′Ã, B̃ᵀS′B̃, Ãᵀs′, B̃ᵀs′, Ãᵀν′ and B̃ᵀν′ (the vectors as extra columns of the
//! matrix kernel instead of 4n_z dot products: `cargo bench --bench ocp --
//! ocp_parts/riccati_pass/1000` 1.65 ms against 1.75 ms). With one control per stage Q_uu is a
//! scalar, so no factorisation is needed: the box-QP is a clamp ([`super::boxqp`]) and the
//! feedback is a scaled row. Nothing allocates per stage.

use super::boxqp::{solve_pair, solve_scalar, BoxQpPair, BoxQpStep};
pub(crate) use super::cost::StageCost;
use faer::linalg::matmul::matmul;
use faer::{Accum, Mat, Par};

#[inline]
/// Σ aᵢbᵢ over the common length, with four partial sums: independent add chains (and SIMD)
/// instead of one chain whose latency bounds a plain fold; the small dense products of a stage
/// are mostly such dots (measured: `cargo bench --bench ocp -- riccati_pass`).
pub(crate) fn dot(a: &[f64], b: &[f64]) -> f64 {
    let n = a.len().min(b.len());
    let (a, b) = (&a[..n], &b[..n]);
    let (ca, cb) = (a.chunks_exact(4), b.chunks_exact(4));
    let tail: f64 = ca
        .remainder()
        .iter()
        .zip(cb.remainder())
        .map(|(x, y)| x * y)
        .sum();
    let mut acc = [0.0; 4];
    for (x, y) in ca.zip(cb) {
        for l in 0..4 {
            acc[l] += x[l] * y[l];
        }
    }
    (acc[0] + acc[2]) + (acc[1] + acc[3]) + tail
}

/// Asks the CPU to bring `x` into its level-2 cache ahead of use: a hint, without effect on
/// any result. The passes over the stages read each stage's A_k and H_k (3.2 and 3.5 kB at
/// n = 10) once; beyond the last-level cache (N ≥ 10⁴: 32 MB of A_k) every stage began with
/// misses that the hardware prefetcher, which follows the ascending reads inside a block but
/// not the jump to the next stage's block, did not hide. Prefetching four stages ahead
/// ([`super::PREFETCH_AHEAD`]): `cargo bench --bench ocp -- ocp_parts/riccati_pass/10000`
/// 19.6–20.0 ms against 25.8–26.2 ms without (one stage ahead into L1: 22.3–23.1 ms), the
/// long-horizon solve at N = 10⁴ and 10⁵ 0.89 of the time (farm-bench wall ratios), N = 10³
/// unchanged. No-op off x86-64.
#[inline(always)]
pub(crate) fn prefetch(x: &[f64]) {
    #[cfg(target_arch = "x86_64")]
    {
        use std::arch::x86_64::{_mm_prefetch, _MM_HINT_T1};
        // One address per 64-byte line, and the last element (a slice need not start on a
        // line).
        for line in x.chunks(8).chain(x.last().map(std::slice::from_ref)) {
            // SAFETY: a prefetch is a hint without architectural effect (it cannot fault or
            // change memory), and the address is that of an element of a live slice.
            unsafe { _mm_prefetch::<_MM_HINT_T1>(line.as_ptr().cast()) }
        }
    }
    #[cfg(not(target_arch = "x86_64"))]
    let _ = x;
}

/// dst = (src + srcᵀ)/2 for a square `src`, by 4 × 4 blocks: each pair of mirrored blocks is
/// read once as columns and transposed in registers. Both triangles take the same sum, so
/// `dst` is symmetric bit for bit. Symmetrising is about a tenth of a Riccati pass at n = 10
/// (`ocp_parts/riccati_pass/1000` without it 1.49 ms against 1.66 ms); of the forms measured
/// in the pass this was the fastest (the pairwise loop in place 1.75–1.82 ms against
/// 1.63–1.72 ms; an element-wise loop into a second matrix, which the compiler vectorises
/// into gathers, in between).
fn symmetrise(dst: &mut Mat<f64>, src: &Mat<f64>) {
    let n = src.nrows();
    let nb = n / 4 * 4;
    for jb in (0..nb).step_by(4) {
        for ib in (jb..nb).step_by(4) {
            // a[c][r] = src[ib + r, jb + c], b[c][r] = src[jb + r, ib + c].
            let (mut a, mut b) = ([[0.0; 4]; 4], [[0.0; 4]; 4]);
            for c in 0..4 {
                a[c].copy_from_slice(&src.col_as_slice(jb + c)[ib..ib + 4]);
                b[c].copy_from_slice(&src.col_as_slice(ib + c)[jb..jb + 4]);
            }
            let (mut lo, mut up) = ([[0.0; 4]; 4], [[0.0; 4]; 4]);
            for c in 0..4 {
                for r in 0..4 {
                    let v = 0.5 * (a[c][r] + b[r][c]);
                    lo[c][r] = v;
                    up[r][c] = v;
                }
            }
            for c in 0..4 {
                dst.col_as_slice_mut(jb + c)[ib..ib + 4].copy_from_slice(&lo[c]);
                dst.col_as_slice_mut(ib + c)[jb..jb + 4].copy_from_slice(&up[c]);
            }
        }
    }
    // The last n − nb rows and columns.
    for j in 0..n {
        for i in nb.max(j)..n {
            let v = 0.5 * (src.col_as_slice(j)[i] + src.col_as_slice(i)[j]);
            dst.col_as_slice_mut(j)[i] = v;
            dst.col_as_slice_mut(i)[j] = v;
        }
    }
}

/// dst += the block (0..n, 0..n) of `src`, column by column (Q_xx += the block of EᵀR in
/// [`Riccati::propagate`]). Out of line so that LLVM vectorises it as it would alone: inlined
/// into `propagate` since cc205e1 it compiled to twice the instructions per stage
/// (docs/architecture.md "Benches"); one rounding per entry either way.
#[inline(never)]
fn add_block(dst: &mut Mat<f64>, src: &Mat<f64>, n: usize) {
    for j in 0..n {
        let s = &src.col_as_slice(j)[..n];
        for (d, s) in dst.col_as_slice_mut(j)[..n].iter_mut().zip(s) {
            *d += s;
        }
    }
}

/// A stage's Jacobians in the tangent coordinates: A_k (column-major n_ξ × n_ξ) and B_k
/// (n_ξ per control, the z component's column first).
#[derive(Clone, Copy, Debug)]
pub(crate) struct StageJacobians<'a> {
    /// A_k = ∂ξ_{k+1}/∂ξ_k.
    pub a: &'a [f64],
    /// B_k = ∂ξ_{k+1}/∂u_k.
    pub b: &'a [f64],
}

/// What the backward pass needs of stage k. Per control (index a < m: 0 the z component,
/// 1 the x component of a 2-axis control) the arrays hold one entry; the residual has
/// `nc` = DIM − 1 components and coordinates (planar: one, the rest 0).
#[derive(Clone, Copy, Debug)]
pub(crate) struct StageInput<'a> {
    pub k: usize,
    pub free: bool,
    /// The residual R_k linearised about the nominal at the model point: planar
    /// r_k + ∂r_k/∂φ₁ δφ₁, spatial R_k + ∂R_k/∂φ₁ δφ₁ with φ₁ = (φ_{1,0}, φ_{1,1}).
    pub residual: [f64; 2],
    /// ∂R_{k,c}/∂φ_{1,a} at the nominal q_k (planar: r_k′(M₀) ∂M₀/∂φ₁ in [0][0]).
    pub dresidual: [[f64; 2]; 2],
    /// u_k and w_k = u_{k−1} (0 at k = 0).
    pub u: [f64; 2],
    pub w: [f64; 2],
    /// Bounds of the step δv_k (lo ≤ 0 ≤ hi).
    pub lo: [f64; 2],
    pub hi: [f64; 2],
    /// Added to l_u at a free stage (the gradient μ δv of a proximal term ½ μ δv²).
    pub lu_shift: [f64; 2],
    /// Added to Q_uu's diagonal at a free stage (interior-point barrier curvature z/s).
    pub quu_shift: [f64; 2],
    /// A_k and B_k; `None` at the last stage.
    pub jac: Option<StageJacobians<'a>>,
    /// The exact second-order term of the stage map, H_k = ∇²(ν_{k+1}·F̃_k) over (ξ, u)
    /// (column-major (2n + 1)², [`super::hessian`]); `None` for Gauss-Newton. Only without an
    /// augmented state, in the planar model.
    pub hess: Option<&'a [f64]>,
    /// The stage cost's curvature beyond Gauss-Newton, added to l_φ₁φ₁:
    /// w r (r″ (∂M₀/∂φ₁)² + r′ ∂²M₀/∂φ₁²) with ∂²M₀/∂φ₁² = −M₀ (M₀ = s sin φ₁; c_sum:
    /// −2M₀²); 0 for Gauss-Newton.
    pub curv: f64,
    /// The model point δz_k (for the gradient H δ of the second-order terms; empty when
    /// they are absent) and δv_k.
    pub dz: &'a [f64],
    pub dv: f64,
}

/// (Q_u, Q_uu, g) of a stage: the control terms of the recursion (m × 1, m × m) and the exact
/// gradient's entries g = l_u + B̃ᵀν′.
#[derive(Clone, Copy, Debug)]
struct QuTerms {
    qu: [f64; 2],
    quu: [[f64; 2]; 2],
    g: [f64; 2],
}

/// The sizes of the recursion: tangent coordinates n_ξ, the augmented state (0 or m), the
/// controls per stage m (1, or 2 for a 2-axis control) and the residual's components n_c
/// (1 planar, 2 spatial).
#[derive(Clone, Copy, Debug)]
pub(crate) struct RiccatiShape {
    pub nxi: usize,
    pub aug: usize,
    pub controls: usize,
    pub residuals: usize,
}

/// The backward pass's workspace and results (sized once per problem).
#[derive(Clone, Debug)]
pub(crate) struct Riccati {
    nxi: usize,
    aug: usize,
    nz: usize,
    /// Controls per stage m.
    ncu: usize,
    /// Residual components n_c.
    nc: usize,
    s_next: Mat<f64>,
    s_cur: Mat<f64>,
    /// E = [Ã B̃] (n_z × (n_z + m)), R = [S′E s′ ν′] (n_z × (n_z + m + 2)) and EᵀR.
    ab: Mat<f64>,
    rhs: Mat<f64>,
    out: Mat<f64>,
    qxx: Mat<f64>,
    sv_next: Vec<f64>,
    sv: Vec<f64>,
    nu_next: Vec<f64>,
    nu: Vec<f64>,
    lx: Vec<f64>,
    qx: Vec<f64>,
    /// Q_ux, row a (n_z entries) per control.
    qux: Vec<f64>,
    /// Feedback gains K_k (n_z per decision: decision k m + a, a < m).
    pub gain: Vec<f64>,
    /// Feedforward steps k_k (per decision).
    pub ff: Vec<f64>,
    /// Exact gradient of J with respect to each decision of a free stage (0 when held).
    pub grad: Vec<f64>,
    /// Σ k Q_u and Σ ½ kᵀ Q_uu k (ΔJ(α) = α d1 + α² d2).
    pub d1: f64,
    pub d2: f64,
    /// Σ Q_uu's diagonal over the free decisions and their count (the scale of the
    /// regularisation).
    pub quu_sum: f64,
    pub quu_count: usize,
}

impl Riccati {
    pub(crate) fn new(shape: RiccatiShape, steps: usize) -> Self {
        let RiccatiShape {
            nxi,
            aug,
            controls: m,
            residuals,
        } = shape;
        let nz = nxi + aug;
        Riccati {
            nxi,
            aug,
            nz,
            ncu: m,
            nc: residuals,
            s_next: Mat::zeros(nz, nz),
            s_cur: Mat::zeros(nz, nz),
            ab: Mat::zeros(nz, nz + m),
            rhs: Mat::zeros(nz, nz + m + 2),
            out: Mat::zeros(nz + m, nz + m + 2),
            qxx: Mat::zeros(nz, nz),
            sv_next: vec![0.0; nz],
            sv: vec![0.0; nz],
            nu_next: vec![0.0; nz],
            nu: vec![0.0; nz],
            lx: vec![0.0; nz],
            qx: vec![0.0; nz],
            qux: vec![0.0; m * nz],
            gain: vec![0.0; (steps + 1) * m * nz],
            ff: vec![0.0; (steps + 1) * m],
            grad: vec![0.0; (steps + 1) * m],
            d1: 0.0,
            d2: 0.0,
            quu_sum: 0.0,
            quu_count: 0,
        }
    }

    /// Starts a backward pass (after the last stage: s′ = 0, S′ = 0, ν′ = 0).
    pub(crate) fn begin(&mut self) {
        self.s_next.fill(0.0);
        self.sv_next.fill(0.0);
        self.nu_next.fill(0.0);
        self.d1 = 0.0;
        self.d2 = 0.0;
        self.quu_sum = 0.0;
        self.quu_count = 0;
    }

    /// l_x of the residual: w J_Rᵀ R over φ₁'s coordinates (planar: w r ∂r/∂φ₁ at φ₁).
    fn residual_gradient(&mut self, inp: &StageInput<'_>, w: f64) {
        let (r, d) = (inp.residual, inp.dresidual);
        if self.nc == 1 {
            self.lx[0] = w * r[0] * d[0][0];
            return;
        }
        for a in 0..self.nc {
            self.lx[a] = w * (r[0] * d[0][a] + r[1] * d[1][a]);
        }
    }

    /// l_x and l_u of the stage's controls (effort, rate, proximal shift) into `lx` and the
    /// returned l_u.
    fn control_gradient(&mut self, inp: &StageInput<'_>, cost: &StageCost) -> [f64; 2] {
        let (wi, k) = (self.nxi, inp.k);
        let e = cost.effort(k);
        let rate = if k > 0 { cost.rate } else { 0.0 };
        let mut lu = [0.0; 2];
        for a in 0..self.ncu {
            if inp.free {
                lu[a] = 2.0 * e * inp.u[a] + 2.0 * rate * (inp.u[a] - inp.w[a]) + inp.lu_shift[a];
                if self.aug > 0 {
                    self.lx[wi + a] = -2.0 * rate * (inp.u[a] - inp.w[a]);
                }
            } else {
                self.lx[wi + a] = 2.0 * e * inp.w[a];
            }
        }
        lu
    }

    /// The costate sweep alone for stage k (called for k = N, …, 0 after [`Riccati::begin`]):
    /// ν_k = l_x + Ãᵀν_{k+1} and the gradient g_k = l_u + B̃ᵀν_{k+1} into `grad` (O(n_z²) per
    /// stage, no Riccati matrices).
    pub(crate) fn costate(&mut self, inp: &StageInput<'_>, cost: &StageCost) {
        let (nxi, k, m) = (self.nxi, inp.k, self.ncu);
        let wi = nxi;
        let w = cost.weight(k);
        self.lx.fill(0.0);
        self.residual_gradient(inp, w);
        let mut lu = self.control_gradient(inp, cost);
        lu[0] += self.second_order(inp, false).0;
        let grad = &mut self.grad[k * m..(k + 1) * m];
        match inp.jac {
            Some(StageJacobians { a, b }) => {
                let nu1 = &self.nu_next;
                for j in 0..nxi {
                    let col = &a[j * nxi..(j + 1) * nxi];
                    self.nu[j] =
                        self.lx[j] + col.iter().zip(&nu1[..nxi]).map(|(x, y)| x * y).sum::<f64>();
                }
                for c in 0..m {
                    let bnu = b[c * nxi..(c + 1) * nxi]
                        .iter()
                        .zip(&nu1[..nxi])
                        .map(|(x, y)| x * y)
                        .sum::<f64>();
                    let nuw = if self.aug > 0 { nu1[wi + c] } else { 0.0 };
                    if inp.free {
                        grad[c] = lu[c] + bnu + nuw;
                        if self.aug > 0 {
                            self.nu[wi + c] = self.lx[wi + c];
                        }
                    } else {
                        grad[c] = 0.0;
                        self.nu[wi + c] = self.lx[wi + c] + bnu + nuw;
                    }
                }
            }
            _ => {
                self.nu.copy_from_slice(&self.lx);
                for c in 0..m {
                    grad[c] = if inp.free { lu[c] } else { 0.0 };
                }
            }
        }
        std::mem::swap(&mut self.nu, &mut self.nu_next);
    }

    /// Processes stage k (called for k = N, N − 1, …, 0) with the absolute regularisation `mu`.
    /// Returns `false` if the stage's box-QP is unbounded below (its step is then 0; raise
    /// `mu`). The costate and the gradient are computed either way.
    pub(crate) fn stage(&mut self, inp: &StageInput<'_>, cost: &StageCost, mu: f64) -> bool {
        let local = self.stage_costs(inp, cost);
        let q = match inp.jac {
            Some(jac) => self.propagate(inp, jac, local),
            _ => {
                self.qx.copy_from_slice(&self.lx);
                self.nu.copy_from_slice(&self.lx);
                local
            }
        };
        let bounded = self.gains_and_value(inp, mu, q);
        self.symmetrise_and_shift();
        bounded
    }

    /// The stage cost's derivatives (Gauss-Newton: l_xx = w J_RᵀJ_R): l_x into `lx`, l_xx
    /// into `qxx`, l_ux into `qux`; returns (l_u, l_uu, l_u) as the start of (Q_u, Q_uu, g).
    fn stage_costs(&mut self, inp: &StageInput<'_>, cost: &StageCost) -> QuTerms {
        let (nxi, nz, k) = (self.nxi, self.nz, inp.k);
        let wi = nxi; // index of w when aug > 0
        let (w, e) = (cost.weight(k), cost.effort(k));
        let rate = if k > 0 { cost.rate } else { 0.0 };
        self.lx.fill(0.0);
        self.residual_gradient(inp, w);
        let mut lu = self.control_gradient(inp, cost);
        let (mut luu, mut lxx_ww, mut lux_w) = (0.0, 0.0, 0.0);
        if inp.free {
            luu = 2.0 * (e + rate);
            if self.aug > 0 {
                lxx_ww = 2.0 * rate;
                lux_w = -2.0 * rate;
            }
        } else {
            // held: u = w; the rate term vanishes inside a piece.
            lxx_ww = 2.0 * e;
        }
        self.qxx.fill(0.0);
        let d = inp.dresidual;
        if self.nc == 1 {
            self.qxx[(0, 0)] = w * d[0][0] * d[0][0];
        } else {
            for a in 0..self.nc {
                for b in 0..self.nc {
                    self.qxx[(a, b)] = w * (d[0][a] * d[0][b] + d[1][a] * d[1][b]);
                }
            }
        }
        self.qux.fill(0.0);
        for a in 0..self.aug {
            self.qxx[(wi + a, wi + a)] += lxx_ww;
            self.qux[a * nz + wi + a] = lux_w;
        }
        let (dlu, dluu) = self.second_order(inp, true);
        lu[0] += dlu;
        let mut quu = [[0.0; 2]; 2];
        for (a, row) in quu.iter_mut().enumerate().take(self.ncu) {
            row[a] = luu;
        }
        quu[0][0] += dluu;
        QuTerms { qu: lu, quu, g: lu }
    }

    /// The exact second-order terms of the stage at the model point δ = (δz, δv): l_x += H_xz δ
    /// (+ curv δφ₁ on φ₁), and with `matrices` l_xx += H_xx (+ curv), l_ux += H_ux; returns
    /// (H_uz δ, H_uu) for l_u and l_uu. Nothing without them (Gauss-Newton; planar only).
    fn second_order(&mut self, inp: &StageInput<'_>, matrices: bool) -> (f64, f64) {
        let nxi = self.nxi;
        if inp.curv != 0.0 {
            self.lx[0] += inp.curv * inp.dz.first().copied().unwrap_or(0.0);
            if matrices {
                self.qxx[(0, 0)] += inp.curv;
            }
        }
        let Some(h) = inp.hess else {
            return (0.0, 0.0);
        };
        let nd = nxi + 1;
        let col = |j: usize| &h[j * nd..(j + 1) * nd];
        // H δ by rows (H is symmetric: row r = column r), contiguous dots.
        for r in 0..nxi {
            let c = col(r);
            self.lx[r] += dot(&c[..nxi], inp.dz) + c[nxi] * inp.dv;
        }
        let cu = col(nxi);
        let lu = dot(&cu[..nxi], inp.dz) + cu[nxi] * inp.dv;
        if !matrices {
            return (lu, 0.0);
        }
        for j in 0..nxi {
            let c = col(j);
            for (dst, src) in self.qxx.col_as_slice_mut(j)[..nxi].iter_mut().zip(c) {
                *dst += src;
            }
            self.qux[j] += c[nxi];
        }
        (lu, cu[nxi])
    }

    /// The dynamics' part with the augmented Ã, B̃ (held stages: u = w enters Ã): Q_xx += ÃᵀS′Ã,
    /// Q_x = l_x + Ãᵀs′, ν = l_x + Ãᵀν′ and, at a free stage, Q_uu += B̃ᵀS′B̃, Q_u += B̃ᵀs′,
    /// g += B̃ᵀν′, Q_ux += B̃ᵀS′Ã.
    ///
    /// All of it from two faer products over the stage's E = [Ã B̃] (B̃ only at a free stage):
    /// R = [S′E  s′  ν′], then Eᵀ R, whose blocks are every term above (the vector terms ride
    /// along as two extra columns of the matrix kernel instead of 4n_z dot products).
    fn propagate(&mut self, inp: &StageInput<'_>, jac: StageJacobians<'_>, q: QuTerms) -> QuTerms {
        let (nz, mu) = (self.nz, self.ncu);
        let m = nz + if inp.free { mu } else { 0 };
        self.fill_stage_matrix(inp, jac);
        let e = self.ab.as_ref().subcols(0, m);
        matmul(
            self.rhs.as_mut().subcols_mut(0, m),
            Accum::Replace,
            self.s_next.as_ref(),
            e,
            1.0,
            Par::Seq,
        );
        self.rhs.col_as_slice_mut(m).copy_from_slice(&self.sv_next);
        self.rhs
            .col_as_slice_mut(m + 1)
            .copy_from_slice(&self.nu_next);
        matmul(
            self.out.as_mut().submatrix_mut(0, 0, m, m + 2),
            Accum::Replace,
            e.transpose(),
            self.rhs.as_ref().subcols(0, m + 2),
            1.0,
            Par::Seq,
        );
        add_block(&mut self.qxx, &self.out, nz);
        let (ox, on) = (self.out.col_as_slice(m), self.out.col_as_slice(m + 1));
        for i in 0..nz {
            self.qx[i] = self.lx[i] + ox[i];
            self.nu[i] = self.lx[i] + on[i];
        }
        if !inp.free {
            return q;
        }
        let mut r = q;
        for a in 0..mu {
            let row = &mut self.qux[a * nz..(a + 1) * nz];
            for (d, s) in row.iter_mut().zip(self.out.col_as_slice(nz + a)) {
                *d += s;
            }
            r.qu[a] = q.qu[a] + ox[nz + a];
            r.g[a] = q.g[a] + on[nz + a];
            for b in 0..mu {
                r.quu[a][b] = q.quu[a][b] + self.out[(nz + a, nz + b)];
            }
        }
        r
    }

    /// E = [Ã B̃] of the stage into `ab` (module docs: free Ã = [A 0; 0 0], B̃ = [B; I]; held
    /// Ã = [A B; 0 I], no B̃).
    fn fill_stage_matrix(&mut self, inp: &StageInput<'_>, jac: StageJacobians<'_>) {
        let StageJacobians { a, b } = jac;
        let (nxi, nz) = (self.nxi, self.nz);
        let wi = nxi;
        for j in 0..nxi {
            let col = self.ab.col_as_slice_mut(j);
            col[..nxi].copy_from_slice(&a[j * nxi..(j + 1) * nxi]);
            col[nxi..].fill(0.0);
        }
        for c in 0..self.aug {
            let col = self.ab.col_as_slice_mut(wi + c);
            col.fill(0.0);
            if !inp.free {
                col[..nxi].copy_from_slice(&b[c * nxi..(c + 1) * nxi]);
                col[wi + c] = 1.0;
            }
        }
        if inp.free {
            for c in 0..self.ncu {
                let col = self.ab.col_as_slice_mut(nz + c);
                col[..nxi].copy_from_slice(&b[c * nxi..(c + 1) * nxi]);
                if nz > nxi {
                    col[nxi..].fill(0.0);
                    col[wi + c] = 1.0;
                }
            }
        }
    }

    /// The stage's box-QP, its gains and the value function handed to stage k − 1 (module
    /// docs: s = Q_x + KᵀQ_uu k + KᵀQ_u + Q_uxᵀk, S = Q_xx + KᵀQ_uu K + KᵀQ_ux + Q_uxᵀK), with
    /// the proximal weight μ in K, k and S alike. `false` if the QP is unbounded below.
    fn gains_and_value(&mut self, inp: &StageInput<'_>, mu: f64, q: QuTerms) -> bool {
        let (nz, k, m) = (self.nz, inp.k, self.ncu);
        self.sv.copy_from_slice(&self.qx);
        if !inp.free {
            self.gain[k * m * nz..(k + 1) * m * nz].fill(0.0);
            self.ff[k * m..(k + 1) * m].fill(0.0);
            self.grad[k * m..(k + 1) * m].fill(0.0);
            return true;
        }
        if m == 1 {
            self.scalar_gains(inp, mu, q)
        } else {
            self.pair_gains(inp, mu, q)
        }
    }

    /// [`Riccati::gains_and_value`] with one control: Q_uu is a scalar and the box-QP a clamp.
    fn scalar_gains(&mut self, inp: &StageInput<'_>, mu: f64, q: QuTerms) -> bool {
        let (nz, k) = (self.nz, inp.k);
        let (qu, mut quu, g) = (q.qu[0], q.quu[0][0], q.g[0]);
        let mut bounded = true;
        let gain = &mut self.gain[k * nz..(k + 1) * nz];
        self.quu_sum += quu.abs();
        self.quu_count += 1;
        quu += mu + inp.quu_shift[0];
        let qt = quu;
        // An unbounded stage QP takes no step; the costate sweep goes on (the gradient does
        // not depend on the model) and the caller raises μ.
        let sol = solve_scalar(qt, qu, inp.lo[0], inp.hi[0]).unwrap_or_else(|| {
            bounded = false;
            BoxQpStep {
                step: 0.0,
                clamped: true,
            }
        });
        let kk = sol.step;
        if sol.clamped {
            gain.fill(0.0);
        } else {
            for (g_, q) in gain.iter_mut().zip(&self.qux) {
                *g_ = -q / qt;
            }
        }
        for i in 0..nz {
            self.sv[i] += gain[i] * (quu * kk + qu) + self.qux[i] * kk;
        }
        if !sol.clamped {
            // K Q_uu Kᵀ + K Q_ux + Q_uxᵀ Kᵀ with K = −Q_ux/Q_uu: the rank-one Q_ux K.
            for (j, &cj) in gain.iter().enumerate() {
                let col = self.qxx.col_as_slice_mut(j);
                for (c, q) in col.iter_mut().zip(&self.qux) {
                    *c += q * cj;
                }
            }
        }
        self.ff[k] = kk;
        self.grad[k] = g;
        self.d1 += kk * qu;
        self.d2 += 0.5 * kk * kk * quu;
        bounded
    }

    /// [`Riccati::gains_and_value`] with two controls (a 2-axis control): the 2 × 2 box-QP
    /// ([`solve_pair`]), K = −Q_uu⁻¹Q_ux over the controls off their bounds (0 for a clamped
    /// one; with one clamped, K_f = −Q_ux,f/Q_uu,ff for the other), and
    /// s = Q_x + KᵀQ_uu k + KᵀQ_u + Q_uxᵀk, S = Q_xx + Q_uxᵀK (what KᵀQ_uuK + KᵀQ_ux + Q_uxᵀK
    /// reduces to with these gains).
    fn pair_gains(&mut self, inp: &StageInput<'_>, mu: f64, q: QuTerms) -> bool {
        let (nz, k) = (self.nz, inp.k);
        let QuTerms { qu, mut quu, g } = q;
        for (a, row) in quu.iter_mut().enumerate() {
            self.quu_sum += row[a].abs();
            self.quu_count += 1;
            row[a] += mu + inp.quu_shift[a];
        }
        let (sol, bounded) = match solve_pair(quu, qu, inp.lo, inp.hi) {
            Some(s) => (s, true),
            None => (
                BoxQpPair {
                    step: [0.0; 2],
                    clamped: [true; 2],
                },
                false,
            ),
        };
        let kk = sol.step;
        let gain = &mut self.gain[2 * k * nz..2 * (k + 1) * nz];
        gain.fill(0.0);
        let (qux0, qux1) = self.qux.split_at(nz);
        match sol.clamped {
            [false, false] => {
                let det = quu[0][0] * quu[1][1] - quu[0][1] * quu[1][0];
                let inv = [
                    [quu[1][1] / det, -quu[0][1] / det],
                    [-quu[1][0] / det, quu[0][0] / det],
                ];
                let (g0, g1) = gain.split_at_mut(nz);
                for i in 0..nz {
                    g0[i] = -(inv[0][0] * qux0[i] + inv[0][1] * qux1[i]);
                    g1[i] = -(inv[1][0] * qux0[i] + inv[1][1] * qux1[i]);
                }
            }
            [false, true] => {
                for (g_, q) in gain[..nz].iter_mut().zip(qux0) {
                    *g_ = -q / quu[0][0];
                }
            }
            [true, false] => {
                for (g_, q) in gain[nz..].iter_mut().zip(qux1) {
                    *g_ = -q / quu[1][1];
                }
            }
            [true, true] => {}
        }
        let back = [
            quu[0][0] * kk[0] + quu[0][1] * kk[1] + qu[0],
            quu[1][0] * kk[0] + quu[1][1] * kk[1] + qu[1],
        ];
        for i in 0..nz {
            self.sv[i] +=
                gain[i] * back[0] + gain[nz + i] * back[1] + qux0[i] * kk[0] + qux1[i] * kk[1];
        }
        for j in 0..nz {
            let (c0, c1) = (gain[j], gain[nz + j]);
            let col = self.qxx.col_as_slice_mut(j);
            for (i, c) in col.iter_mut().enumerate() {
                *c += qux0[i] * c0 + qux1[i] * c1;
            }
        }
        self.ff[2 * k..2 * k + 2].copy_from_slice(&kk);
        self.grad[2 * k..2 * k + 2].copy_from_slice(&g);
        self.d1 += kk[0] * qu[0] + kk[1] * qu[1];
        self.d2 += 0.5
            * (kk[0] * (quu[0][0] * kk[0] + quu[0][1] * kk[1])
                + kk[1] * (quu[1][0] * kk[0] + quu[1][1] * kk[1]));
        bounded
    }

    /// S = (M + Mᵀ)/2 of the stage's M = Q_xx + KᵀQ_uu K + KᵀQ_ux + Q_uxᵀK (left in `qxx`: both
    /// triangles from the same two sums, so S is symmetric bit for bit), and (S, s, ν) become the
    /// next stage's (S′, s′, ν′).
    fn symmetrise_and_shift(&mut self) {
        symmetrise(&mut self.s_cur, &self.qxx);
        std::mem::swap(&mut self.s_cur, &mut self.s_next);
        std::mem::swap(&mut self.sv, &mut self.sv_next);
        std::mem::swap(&mut self.nu, &mut self.nu_next);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// [`symmetrise`] against the element-wise definition (M + Mᵀ)/2, bit for bit, on sizes
    /// that exercise the 4 × 4 blocks, the remainder and both together (the definition is
    /// the reference: the blocks only reorder the reads).
    #[test]
    fn symmetrise_matches_definition() {
        for n in [1, 3, 4, 7, 8, 20, 21] {
            let src = Mat::<f64>::from_fn(n, n, |i, j| ((3 * i + 7 * j) % 11) as f64 / 7.0 - 0.3);
            let mut dst = Mat::<f64>::zeros(n, n);
            symmetrise(&mut dst, &src);
            for j in 0..n {
                for i in 0..n {
                    let want = 0.5 * (src[(i, j)] + src[(j, i)]);
                    assert_eq!(dst[(i, j)].to_bits(), want.to_bits(), "n {n} ({i}, {j})");
                }
            }
        }
    }
}
