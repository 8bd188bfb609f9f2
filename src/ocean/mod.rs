//! Irregular seas (docs/ocean.md "Irregular seas"; DNV-RP-C205 §3.5): wave spectra, the
//! finite-depth dispersion
//! relation, a seeded realisation of a sea state and its linear (Airy) kinematics over a whole
//! record, evaluated by inverse FFT.
//!
//! - [`spectrum`]: Pierson-Moskowitz and JONSWAP spectral densities S(ω) \[m² s/rad\].
//! - [`dispersion`]: the wavenumber k of ω² = g k tanh(k d), by Newton.
//! - [`waves`]: [`Sea`], the components η(x', t) = Σⱼ aⱼ cos(ωⱼ t − kⱼ x' + φⱼ) with
//!   aⱼ = √(2 S(ωⱼ) Δω) and seeded phases φⱼ, and [`WaveRecord`], the horizontal particle
//!   velocity and acceleration at given heights above the seabed at every time step, ready for a
//!   load term to read per node and step without allocating.
//!
//! Conventions (docs/conventions.md, "Waves"): heights y are measured up from the seabed
//! (y = 0) to the mean surface (y = d); the mean wave direction is an angle in the horizontal
//! (x, z) plane, in degrees from +z toward +x; the record's times are t_k = k h from t = 0; the
//! riser's nodes are evaluated at their undisplaced horizontal position x = z = 0.

pub mod dispersion;
pub mod spectrum;
mod synthesis;
pub mod waves;

pub use dispersion::wavenumber;
/// The complex numbers of the amplitudes (`rustfft`'s `num_complex`).
pub use rustfft::num_complex::Complex;
pub use spectrum::{Spectrum, SpectrumKind};
pub use waves::{
    above_surface, cell_profile, depth_profile, Profiles, Sea, SeaPlan, SeaSpec, Synthesis,
    WaveRecord, MAX_RECORD_BYTES, SURFACE_TOLERANCE,
};

use thiserror::Error;

/// Standard gravity g \[m/s²\] (ISO 80000-3), the default of [`SeaSpec::gravity`].
pub const STANDARD_GRAVITY: f64 = 9.80665;

/// Why a sea state or its record could not be built: the quantity, its value and what it must
/// be, so that a scene reader can name its key.
#[derive(Clone, Debug, Error, PartialEq)]
#[non_exhaustive]
pub enum SeaError {
    /// A quantity is out of its range (or not finite).
    #[error("{quantity} = {value} is invalid: it must be {expected}")]
    Invalid {
        /// The quantity's name (`hs`, `tp`, `gamma`, `depth`, `direction`, `components`,
        /// `step`, `duration`, `gravity`, `height`).
        quantity: &'static str,
        /// The value given.
        value: f64,
        /// The valid range, in words.
        expected: &'static str,
    },
    /// The default number of components N = ⌊ω_c T_r/2π⌋ = ⌊6 T_r/T_p⌋ (the spectrum's cutoff
    /// ω_c = 6 ω_p over the frequency step 2π/T_r) is over the limit of a given `components`
    /// (a very short peak period, or a very long run).
    #[error(
        "the sea needs {needed:e} components (⌊6 T_r/T_p⌋ with the repeat period T_r = \
         {repeat_period} s), over the limit of {limit}; use a longer peak period tp (or a \
         shorter run), or give the number of components"
    )]
    TooManyComponents {
        /// N = ⌊ω_c T_r/2π⌋ (may be +∞).
        needed: f64,
        /// The repeat period T_r \[s\].
        repeat_period: f64,
        /// The limit, [`waves::MAX_COMPONENTS`].
        limit: usize,
    },
    /// The record (or its FFT) would need more memory than the limit.
    #[error(
        "the wave record needs {needed} {what}, over the limit of {limit}; use a larger time \
         step, fewer steps or fewer components"
    )]
    TooLarge {
        /// What is counted (`FFT points`, `bytes`).
        what: &'static str,
        /// How many are needed.
        needed: u64,
        /// The limit.
        limit: u64,
    },
}
