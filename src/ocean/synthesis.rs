//! The plans of [`Sea::synthesize`](super::Sea::synthesize): the inverse FFT of the repeat
//! period, the zoom transform of a short record, and the direct sum of a very short one
//! ([`Sea::synthesis_rows`](super::Sea::synthesis_rows) chooses among them from the sizes).

use rustfft::num_complex::Complex;

/// A planned synthesis with its buffers ([`Sea::synthesis`](super::Sea::synthesis),
/// [`Sea::synthesis_every`](super::Sea::synthesis_every),
/// [`Sea::synthesis_rows`](super::Sea::synthesis_rows),
/// [`Sea::synthesize`](super::Sea::synthesize)).
pub struct Synthesis {
    pub(super) engine: Engine,
}

/// How a [`Synthesis`] forms the series.
pub(super) enum Engine {
    /// The inverse FFT of length L, read every `stride`-th value (1 unless a coarser grid's r
    /// does not divide M).
    Full {
        fft: std::sync::Arc<dyn rustfft::Fft<f64>>,
        buf: Vec<Complex<f64>>,
        scratch: Vec<Complex<f64>>,
        stride: usize,
    },
    /// The zoom transform of [`Sea::synthesis_rows`](super::Sea::synthesis_rows).
    Zoom(Box<Zoom>),
    /// The direct sum over the components at each of a few rows ([`Direct`]).
    Direct(Direct),
}

/// The plan of the zoom transform ([`Sea::synthesis_rows`](super::Sea::synthesis_rows)): the
/// chirps V^{u²} (u = 0..=2N) and V^{k² − 2Nk} (k = 0..rows), the kernel's transform over P,
/// and the FFTs of length P.
pub(super) struct Zoom {
    pub(super) forward: std::sync::Arc<dyn rustfft::Fft<f64>>,
    pub(super) inverse: std::sync::Arc<dyn rustfft::Fft<f64>>,
    pub(super) kernel: Vec<Complex<f64>>,
    pub(super) pre: Vec<Complex<f64>>,
    pub(super) post: Vec<Complex<f64>>,
    pub(super) buf: Vec<Complex<f64>>,
    pub(super) scratch: Vec<Complex<f64>>,
    /// The grid's time step r h \[s\] (for rows beyond the plan's, summed directly).
    pub(super) dt: f64,
}

/// The direct sum of a few rows: the series Re Σⱼ Xⱼ e^{iωⱼ tₖ} at tₖ = k r h as
/// Σⱼ (Re Xⱼ cos ωⱼtₖ − Im Xⱼ sin ωⱼtₖ), with cos ωⱼtₖ and sin ωⱼtₖ tabulated once per plan
/// (rows × N of each) and shared by every series the plan forms: O(N) per row and series, no
/// transform. The angle and the sum are those of [`Sea::sum_at`](super::Sea::sum_at) (aⱼ =
/// ωⱼ·tₖ, tₖ = k·(r h), the components in order), so each value equals the direct sum's bit for
/// bit, and the rows beyond the plan's continue it.
pub(super) struct Direct {
    /// cos ωⱼtₖ, row-major (row k: N values).
    cos: Vec<f64>,
    /// sin ωⱼtₖ, likewise.
    sin: Vec<f64>,
    /// The number of rows tabulated.
    rows: usize,
    /// The number of components N.
    nc: usize,
    /// The grid's time step r h \[s\].
    pub(super) dt: f64,
}

impl Direct {
    /// The tables of `rows` times tₖ = k·`dt` for the frequencies `omega`.
    pub(super) fn new(omega: &[f64], rows: usize, dt: f64) -> Self {
        let nc = omega.len();
        let (mut cos, mut sin) = (Vec::with_capacity(rows * nc), Vec::with_capacity(rows * nc));
        for k in 0..rows {
            let t = k as f64 * dt;
            for &w in omega {
                let a = w * t;
                cos.push(libm::cos(a));
                sin.push(libm::sin(a));
            }
        }
        Direct {
            cos,
            sin,
            rows,
            nc,
            dt,
        }
    }

    /// The number of rows tabulated.
    pub(super) fn rows(&self) -> usize {
        self.rows
    }

    /// Re Σⱼ cⱼ e^{iωⱼ t_k} for row k < [`Direct::rows`], cⱼ = `coef(j)` (j = 0..N).
    pub(super) fn sum(&self, k: usize, coef: impl Fn(usize) -> Complex<f64>) -> f64 {
        let row = k * self.nc..(k + 1) * self.nc;
        let mut s = 0.0;
        for (j, (c, sn)) in self.cos[row.clone()].iter().zip(&self.sin[row]).enumerate() {
            let x = coef(j);
            s += x.re * c - x.im * sn;
        }
        s
    }
}

impl Synthesis {
    /// Whether the plan forms only the rows asked for (the zoom transform or the direct sum of
    /// [`Sea::synthesis_rows`](super::Sea::synthesis_rows)) rather than the whole repeat period.
    pub fn is_zoom(&self) -> bool {
        matches!(self.engine, Engine::Zoom(_) | Engine::Direct(_))
    }

    /// Whether the plan is the direct sum of a few rows (no transform).
    pub fn is_direct(&self) -> bool {
        matches!(self.engine, Engine::Direct(_))
    }

    /// The number of points of its FFTs (L for the full transform, P for the zoom), or of
    /// rows of the direct sum.
    pub fn len(&self) -> usize {
        match &self.engine {
            Engine::Full { buf, .. } => buf.len(),
            Engine::Zoom(z) => z.buf.len(),
            Engine::Direct(d) => d.rows,
        }
    }

    /// Whether it has no points (a direct sum of no rows).
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }
}

impl std::fmt::Debug for Synthesis {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let mut d = f.debug_struct("Synthesis");
        d.field("len", &self.len())
            .field("zoom", &self.is_zoom())
            .field("direct", &self.is_direct());
        if let Engine::Full { stride, .. } = &self.engine {
            d.field("stride", stride);
        }
        d.finish()
    }
}
