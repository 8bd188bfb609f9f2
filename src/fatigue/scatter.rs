//! A scatter diagram from a published joint distribution of (H_s, T_p): the lognormal-Weibull
//! ("LoNoWe") model of a northern North Sea site, binned into a few cells.
//!
//! The model (Kvitebjørn, northern North Sea; Johannessen & Nygaard (2000), "Metocean design
//! criteria for Kvitebjørn", Statoil report C193-KVB-N-FD-0001, with the parameters as quoted by
//! Y. M. Low and X. Huang, "Long-term extreme response analysis of offshore structures by
//! combining importance sampling with subset simulation", Structural Safety 2017, §5; not
//! checked against the Statoil report itself):
//! ```text
//! H_s:     lognormal, ln H ~ N(0.77, 0.6565²)           for h ≤ 2.9 m
//!          Weibull, F(h) = 1 − exp(−(h/2.691)^1.503)      for h > 2.9 m (continuous at 2.9 m)
//! T_p | h: lognormal, ln T ~ N(μ(h), σ²(h)),
//!          μ(h) = 1.134 + 0.892 h^0.225,  σ²(h) = 0.005 + 0.120 exp(−0.455 h)
//! ```
//! [`JointSea::cells`] integrates the joint density over rectangular (H_s, T_p) bins (the
//! midpoint rule in F_H over 400 slices of each H_s bin, the exact conditional lognormal
//! probability of each T_p bin) and gives each bin the representative sea state it is given.
//!
//! A published tabulated diagram, the North Atlantic table of IACS Rec. No. 34, and its
//! reduction to 20 cells are in [`north_atlantic`] ([`reduced_north_atlantic`]). A diagram's
//! CSV file is read by [`read_scatter_file`] ([`mod@file`]).

/// The most cells a scatter diagram may have (a published diagram has tens to a few hundred;
/// each cell is a simulation per controller).
pub const MAX_SCATTER_CELLS: usize = 10_000;

pub mod file;
pub mod north_atlantic;

pub use file::{
    check_diagram, parse_scatter, read_scatter_file, ScatterFileError, ScatterFileErrorKind,
    SCATTER_COLUMNS,
};

pub use north_atlantic::{
    lump_north_atlantic, reduced_north_atlantic, tp_over_tz, NORTH_ATLANTIC_HS,
    NORTH_ATLANTIC_OCCURRENCES, NORTH_ATLANTIC_TOTAL, NORTH_ATLANTIC_TZ, REDUCED_NA_HS_EDGES,
    REDUCED_NA_MIN_PROBABILITY, REDUCED_NA_TZ_EDGES,
};

/// A sea state: significant wave height H_s \[m\], peak period T_p \[s\] and, optionally, the
/// mean direction \[° from +z toward +x\].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SeaState {
    /// H_s \[m\].
    pub hs: f64,
    /// T_p \[s\].
    pub tp: f64,
    /// Mean direction \[°\]; `None`: the scene's.
    pub direction: Option<f64>,
}

/// A cell of a scatter diagram: a sea state and its probability of occurrence.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ScatterCell {
    /// The sea state.
    pub sea: SeaState,
    /// Probability of occurrence p_s ∈ \[0, 1\].
    pub probability: f64,
}

/// The (H_s, T_p) joint model of the module docs.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct JointSea {
    /// Mean and standard deviation of ln H_s below `h0`.
    pub ln_hs: (f64, f64),
    /// Weibull shape and scale of H_s above `h0`.
    pub weibull: (f64, f64),
    /// The switch height h₀ \[m\].
    pub h0: f64,
    /// (a₁, a₂, a₃) of μ(h) = a₁ + a₂ h^a₃.
    pub mu: [f64; 3],
    /// (b₁, b₂, b₃) of σ²(h) = b₁ + b₂ exp(−b₃ h).
    pub var: [f64; 3],
}

/// The Kvitebjørn model (module docs).
pub const KVITEBJORN: JointSea = JointSea {
    ln_hs: (0.77, 0.6565),
    weibull: (1.503, 2.691),
    h0: 2.9,
    mu: [1.134, 0.892, 0.225],
    var: [0.005, 0.120, 0.455],
};

/// Φ(z), the standard normal CDF.
fn normal_cdf(z: f64) -> f64 {
    0.5 * libm::erfc(-z / std::f64::consts::SQRT_2)
}

/// A bin edge and the sea state that represents a bin.
#[derive(Clone, Debug, PartialEq)]
pub struct Bins {
    /// Edges e₀ < e₁ < … (the last may be +∞).
    pub edges: Vec<f64>,
    /// One representative value per bin (`edges.len() − 1` of them).
    pub centres: Vec<f64>,
}

impl Bins {
    /// Bins between `edges` represented by `centres` (one per bin); `None` unless there is one
    /// centre per bin.
    pub fn new(edges: &[f64], centres: &[f64]) -> Option<Self> {
        (centres.len() + 1 == edges.len()).then(|| Bins {
            edges: edges.to_vec(),
            centres: centres.to_vec(),
        })
    }
}

impl JointSea {
    /// F_H(h), the marginal CDF of H_s.
    pub fn hs_cdf(&self, h: f64) -> f64 {
        if h <= 0.0 {
            0.0
        } else if h <= self.h0 {
            normal_cdf((h.ln() - self.ln_hs.0) / self.ln_hs.1)
        } else if h.is_infinite() {
            1.0
        } else {
            1.0 - (-(h / self.weibull.1).powf(self.weibull.0)).exp()
        }
    }

    /// P(t₀ < T_p ≤ t₁ | H_s = h).
    pub fn tp_probability(&self, h: f64, t0: f64, t1: f64) -> f64 {
        let mu = self.mu[0] + self.mu[1] * h.powf(self.mu[2]);
        let sigma = (self.var[0] + self.var[1] * (-self.var[2] * h).exp()).sqrt();
        let cdf = |t: f64| {
            if t <= 0.0 {
                0.0
            } else if t.is_infinite() {
                1.0
            } else {
                normal_cdf((t.ln() - mu) / sigma)
            }
        };
        cdf(t1) - cdf(t0)
    }

    /// P(h₀ < H_s ≤ h₁, t₀ < T_p ≤ t₁): Σ over 400 slices of [h₀, h₁] (an open bin cut where
    /// F_H = 1 − 10⁻¹²) of ΔF_H · P(T_p bin | slice midpoint).
    pub fn cell_probability(&self, h: (f64, f64), t: (f64, f64)) -> f64 {
        const SLICES: usize = 400;
        let top = if h.1.is_finite() {
            h.1
        } else {
            // F_H(h) = 1 − 1e−12 on the Weibull branch.
            self.weibull.1 * (12.0 * std::f64::consts::LN_10).powf(1.0 / self.weibull.0)
        };
        let dh = (top - h.0) / SLICES as f64;
        (0..SLICES)
            .map(|i| {
                let (a, b) = (h.0 + i as f64 * dh, h.0 + (i + 1) as f64 * dh);
                (self.hs_cdf(b) - self.hs_cdf(a)) * self.tp_probability(0.5 * (a + b), t.0, t.1)
            })
            .sum()
    }

    /// The diagram of `hs` × `tp` bins, H_s slowest, leaving out cells of probability below
    /// `min_probability` (their sum is what the diagram's probabilities fall short of 1).
    /// A bin without a centre (a [`Bins`] built by hand with too few) is left out.
    pub fn cells(&self, hs: &Bins, tp: &Bins, min_probability: f64) -> Vec<ScatterCell> {
        let mut out = Vec::new();
        for (i, h) in hs.edges.windows(2).enumerate().take(hs.centres.len()) {
            for (j, t) in tp.edges.windows(2).enumerate().take(tp.centres.len()) {
                let p = self.cell_probability((h[0], h[1]), (t[0], t[1]));
                if p >= min_probability {
                    out.push(ScatterCell {
                        sea: SeaState {
                            hs: hs.centres[i],
                            tp: tp.centres[j],
                            direction: None,
                        },
                        probability: p,
                    });
                }
            }
        }
        out
    }
}

/// The H_s classes of [`reduced_kvitebjorn`]: 0–1.5–3–4.5–∞ m, represented by 0.75, 2.25, 3.75
/// and 5.25 m (a regular grid).
pub fn reduced_hs_bins() -> Bins {
    Bins {
        edges: vec![0.0, 1.5, 3.0, 4.5, f64::INFINITY],
        centres: vec![0.75, 2.25, 3.75, 5.25],
    }
}

/// The T_p classes of [`reduced_kvitebjorn`]: 0–9–12–∞ s, represented by 7.5, 10.5 and 13.5 s
/// (the first class's sea states are mostly between 6 and 9 s: below 6 s the model holds little
/// probability at these heights; a regular grid).
pub fn reduced_tp_bins() -> Bins {
    Bins {
        edges: vec![0.0, 9.0, 12.0, f64::INFINITY],
        centres: vec![7.5, 10.5, 13.5],
    }
}

/// The least probability of a cell kept by [`reduced_kvitebjorn`].
pub const REDUCED_MIN_PROBABILITY: f64 = 0.005;

/// [`KVITEBJORN`] reduced to at most 12 cells ([`reduced_hs_bins`] × [`reduced_tp_bins`], cells
/// below [`REDUCED_MIN_PROBABILITY`] left out): the wave climate of the wellhead example.
pub fn reduced_kvitebjorn() -> Vec<ScatterCell> {
    KVITEBJORN.cells(
        &reduced_hs_bins(),
        &reduced_tp_bins(),
        REDUCED_MIN_PROBABILITY,
    )
}
