//! Wave spectra of DNV-RP-C205 §3.5.1: Pierson-Moskowitz and JONSWAP, one-sided, in angular
//! frequency.

use super::SeaError;
use std::f64::consts::PI;

/// The spectral shape.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum SpectrumKind {
    /// Pierson-Moskowitz: a fully developed sea (DNV-RP-C205 eq. 3.5.5).
    PiersonMoskowitz,
    /// JONSWAP: a fetch-limited sea (DNV-RP-C205 eq. 3.5.6) with peak-enhancement factor
    /// γ ∈ [1, 10] (γ = 1 is Pierson-Moskowitz; 3.3 the North Sea mean).
    Jonswap {
        /// The peak-enhancement factor γ.
        gamma: f64,
    },
}

/// The range of the peak-enhancement factor γ accepted (DNV-RP-C205 quotes 1 ≤ γ ≤ 7 for its
/// normalisation A_γ = 1 − 0.287 ln γ; it stays positive up to γ ≈ 32).
pub const GAMMA_RANGE: (f64, f64) = (1.0, 10.0);

/// Upper frequency of a realisation, as a multiple of ω_p: the spectrum above 6 ω_p holds
/// 5/4 (1/6)⁴ ≈ 0.1 % of a Pierson-Moskowitz sea's variance (∫_{ω_c}^∞ S_PM = 5/64 H_s² (ω_p/ω_c)⁴).
pub const CUTOFF_FACTOR: f64 = 6.0;

/// A sea-state spectrum S(ω) \[m² s/rad\] given by its significant wave height H_s \[m\] and
/// peak period T_p \[s\].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Spectrum {
    /// The spectral shape.
    pub kind: SpectrumKind,
    /// Significant wave height H_s = 4 √m₀ \[m\], m₀ = ∫ S dω.
    pub hs: f64,
    /// Peak period T_p = 2π/ω_p \[s\].
    pub tp: f64,
}

fn check(
    quantity: &'static str,
    value: f64,
    ok: bool,
    expected: &'static str,
) -> Result<(), SeaError> {
    if value.is_finite() && ok {
        Ok(())
    } else {
        Err(SeaError::Invalid {
            quantity,
            value,
            expected,
        })
    }
}

impl Spectrum {
    /// A Pierson-Moskowitz sea; `hs` and `tp` must be positive and finite.
    ///
    /// # Errors
    /// [`SeaError::Invalid`] naming `hs` or `tp`.
    pub fn pierson_moskowitz(hs: f64, tp: f64) -> Result<Self, SeaError> {
        Self::new(SpectrumKind::PiersonMoskowitz, hs, tp)
    }

    /// A JONSWAP sea; `hs`, `tp` positive and finite, `gamma` in [`GAMMA_RANGE`].
    ///
    /// # Errors
    /// [`SeaError::Invalid`] naming `hs`, `tp` or `gamma`.
    pub fn jonswap(hs: f64, tp: f64, gamma: f64) -> Result<Self, SeaError> {
        Self::new(SpectrumKind::Jonswap { gamma }, hs, tp)
    }

    /// A sea of the given shape, validated.
    ///
    /// # Errors
    /// [`SeaError::Invalid`] naming `hs`, `tp` or `gamma`.
    pub fn new(kind: SpectrumKind, hs: f64, tp: f64) -> Result<Self, SeaError> {
        check("hs", hs, hs > 0.0, "positive and finite [m]")?;
        check("tp", tp, tp > 0.0, "positive and finite [s]")?;
        if let SpectrumKind::Jonswap { gamma } = kind {
            let (lo, hi) = GAMMA_RANGE;
            check("gamma", gamma, (lo..=hi).contains(&gamma), "in [1, 10]")?;
        }
        Ok(Self { kind, hs, tp })
    }

    /// The peak frequency ω_p = 2π/T_p \[rad/s\].
    pub fn peak_frequency(&self) -> f64 {
        2.0 * PI / self.tp
    }

    /// The highest frequency of a realisation, ω_c = [`CUTOFF_FACTOR`] ω_p \[rad/s\].
    pub fn cutoff(&self) -> f64 {
        CUTOFF_FACTOR * self.peak_frequency()
    }

    /// The spectral density S(ω) \[m² s/rad\] (0 for ω ≤ 0):
    /// S_PM(ω) = 5/16 H_s² ω_p⁴ ω⁻⁵ exp(−5/4 (ω/ω_p)⁻⁴) (DNV-RP-C205 eq. 3.5.5);
    /// S_J(ω) = A_γ S_PM(ω) γ^exp(−½((ω − ω_p)/(σ ω_p))²), A_γ = 1 − 0.287 ln γ, σ = 0.07 for
    /// ω ≤ ω_p and 0.09 above (eq. 3.5.6). Transcendentals from `libm`, the same bits on every
    /// machine.
    pub fn density(&self, omega: f64) -> f64 {
        if omega <= 0.0 {
            return 0.0;
        }
        let wp = self.peak_frequency();
        let r = wp / omega;
        let r4 = (r * r) * (r * r);
        let pm = 5.0 / 16.0 * self.hs * self.hs * r4 / omega * libm::exp(-1.25 * r4);
        match self.kind {
            SpectrumKind::PiersonMoskowitz => pm,
            SpectrumKind::Jonswap { gamma } => {
                let sigma = if omega <= wp { 0.07 } else { 0.09 };
                let x = (omega - wp) / (sigma * wp);
                let a_gamma = 1.0 - 0.287 * libm::log(gamma);
                a_gamma * pm * libm::pow(gamma, libm::exp(-0.5 * x * x))
            }
        }
    }
}
