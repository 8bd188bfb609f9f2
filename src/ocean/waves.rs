//! A seeded realisation of a sea state and its linear (Airy) kinematics (docs/ocean.md
//! "Irregular seas").
//!
//! The realisation is a sum of N components at equally spaced frequencies
//! ωⱼ = j Δω, j = 1..N, Δω = 2π/T_r:
//! η(x', t) = Σⱼ aⱼ cos(ωⱼ t − kⱼ x' + φⱼ), aⱼ = √(2 S(ωⱼ) Δω), with x' the horizontal
//! coordinate along the mean wave direction and kⱼ the finite-depth wavenumber
//! ([`super::wavenumber`]). The sea repeats after T_r. T_r is a whole number M of time steps
//! h, so that on the step grid tₖ = k h the sum is an inverse discrete Fourier transform of
//! length M: the record of every node costs one FFT, O(M log M), instead of N·M cosines.
//!
//! **The seed's promise**: the phases are φⱼ = 2π uⱼ with uⱼ = ⌊r/2¹¹⌋ 2⁻⁵³ from the 64-bit
//! words r of the ChaCha20 stream (`rand_chacha::ChaCha20Rng`, RFC 8439 block function) keyed
//! by the seed's 8 little-endian bytes followed by 24 zero bytes, taken in order j = 1, 2, ….
//! The spectrum, the wavenumbers, the profiles and the phasors use the pure-Rust `libm`, and the
//! FFT is `rustfft`'s scalar code: the same scene (spectrum, seed, depth, components, step)
//! gives the same sea and the same record bit for bit on every machine.

use super::spectrum::Spectrum;
use super::{wavenumber, SeaError, STANDARD_GRAVITY};
use rand_chacha::rand_core::{RngCore, SeedableRng};
use rand_chacha::ChaCha20Rng;
use rustfft::num_complex::Complex;
use rustfft::FftPlanner;
use std::f64::consts::PI;

pub use super::synthesis::Synthesis;
use super::synthesis::{Direct, Engine, Zoom};

mod profiles;

pub use profiles::{above_surface, cell_profile, depth_profile, Profiles, SURFACE_TOLERANCE};

/// The shortest repeat period T_r \[s\] of a realisation with the default number of components:
/// three hours, the standard duration of a sea state (DNV-RP-C205 §3.5.1).
pub const MIN_REPEAT_PERIOD: f64 = 3.0 * 3600.0;

/// The largest FFT length M (repeat period over time step) accepted.
pub const MAX_FFT_LEN: u64 = 1 << 25;

/// The largest record accepted, in bytes (velocity, acceleration and elevation).
pub const MAX_RECORD_BYTES: u64 = 4 << 30;

/// The largest number of components accepted.
pub const MAX_COMPONENTS: usize = 10_000_000;

/// What defines a sea: its spectrum, the water, the direction and the realisation.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SeaSpec {
    /// The spectrum S(ω).
    pub spectrum: Spectrum,
    /// Water depth d \[m\] (seabed at y = 0, mean surface at y = d).
    pub depth: f64,
    /// Gravity g \[m/s²\] of the dispersion relation (default [`STANDARD_GRAVITY`]).
    pub gravity: f64,
    /// Mean wave direction \[degrees\] in the horizontal plane, from +z toward +x.
    pub direction_deg: f64,
    /// The seed of the phases (see the module docs for what it promises).
    pub seed: u64,
    /// The number of components N; `None`: enough that the sea repeats only after
    /// max(3 h, the record's duration).
    pub components: Option<usize>,
}

impl SeaSpec {
    /// A sea with standard gravity, direction 0 (along +z) and the default components.
    pub fn new(spectrum: Spectrum, depth: f64, seed: u64) -> Self {
        Self {
            spectrum,
            depth,
            gravity: STANDARD_GRAVITY,
            direction_deg: 0.0,
            seed,
            components: None,
        }
    }
}

/// A realisation of a sea state on the time grid tₖ = k h (module docs).
#[derive(Clone, Debug)]
pub struct Sea {
    spec: SeaSpec,
    h: f64,
    /// FFT length M = T_r / h.
    fft_len: usize,
    dw: f64,
    omega: Vec<f64>,
    k: Vec<f64>,
    amplitude: Vec<f64>,
    phase: Vec<f64>,
    /// aⱼ e^{iφⱼ}.
    phasor: Vec<Complex<f64>>,
    direction: [f64; 2],
}

/// The size of a sea's realisation ([`Sea::plan`]), as [`Sea::new`] chooses it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SeaPlan {
    /// The FFT length M = T_r/h.
    pub fft_len: usize,
    /// The frequency spacing Δω = 2π/T_r \[rad/s\].
    pub frequency_step: f64,
    /// The number of components N (ωⱼ = j Δω, j = 1..N).
    pub components: usize,
}

fn invalid(quantity: &'static str, value: f64, expected: &'static str) -> SeaError {
    SeaError::Invalid {
        quantity,
        value,
        expected,
    }
}

/// The phases φⱼ = 2π uⱼ of `count` components from the seed (module docs).
fn phases(seed: u64, count: usize) -> Vec<f64> {
    let mut key = [0u8; 32];
    key[..8].copy_from_slice(&seed.to_le_bytes());
    let mut rng = ChaCha20Rng::from_seed(key);
    let scale = 2.0 * PI / (1u64 << 53) as f64;
    (0..count)
        .map(|_| (rng.next_u64() >> 11) as f64 * scale)
        .collect()
}

impl Sea {
    /// The size of the realisation [`Sea::new`] would make of `spec` for a record of `duration`
    /// seconds at step `h`, checked without realising it (no phase drawn, nothing stored): the
    /// repeat period T_r = M h and N, as [`Sea::new`] chooses them, and a scan of the N
    /// components that the amplitudes aⱼ = √(2 S(ωⱼ) Δω) and the wavenumbers kⱼ are finite.
    /// A scene's validation calls this; the model realises the sea once.
    ///
    /// # Errors
    /// Exactly those of [`Sea::new`], in the same order.
    pub fn plan(spec: &SeaSpec, h: f64, duration: f64) -> Result<SeaPlan, SeaError> {
        let plan = Self::sizes(spec, h, duration)?;
        let (dw, count) = (plan.frequency_step, plan.components);
        let omega = |j: usize| j as f64 * dw;
        if (1..=count).any(|j| !Self::amplitude(spec, omega(j), dw).is_finite()) {
            return Err(Self::infinite_amplitude(spec));
        }
        if (1..=count).any(|j| !wavenumber(omega(j), spec.depth, spec.gravity).is_finite()) {
            return Err(Self::infinite_wavenumber(spec));
        }
        Ok(plan)
    }

    /// The component's amplitude aⱼ = √(2 S(ωⱼ) Δω) \[m\].
    fn amplitude(spec: &SeaSpec, w: f64, dw: f64) -> f64 {
        (2.0 * spec.spectrum.density(w) * dw).sqrt()
    }

    /// Outside the domain of the f64 sea: a height so large that S(ω) overflows (named, never a
    /// NaN in the loads later).
    fn infinite_amplitude(spec: &SeaSpec) -> SeaError {
        invalid(
            "hs",
            spec.spectrum.hs,
            "small enough that the amplitudes √(2 S(ωⱼ) Δω) are finite [m]",
        )
    }

    /// Outside the domain of the f64 sea: a depth so small that the wavenumbers overflow.
    fn infinite_wavenumber(spec: &SeaSpec) -> SeaError {
        invalid(
            "depth",
            spec.depth,
            "large enough that the wavenumbers are finite [m]",
        )
    }

    /// The scalar checks and the sizes of [`Sea::plan`] and [`Sea::new`] (module docs).
    fn sizes(spec: &SeaSpec, h: f64, duration: f64) -> Result<SeaPlan, SeaError> {
        let ok = |x: f64, c: bool| x.is_finite() && c;
        if !ok(spec.depth, spec.depth > 0.0) {
            return Err(invalid("depth", spec.depth, "positive and finite [m]"));
        }
        if !ok(spec.gravity, spec.gravity > 0.0) {
            return Err(invalid(
                "gravity",
                spec.gravity,
                "positive and finite [m/s²]",
            ));
        }
        if !spec.direction_deg.is_finite() {
            return Err(invalid("direction", spec.direction_deg, "finite [degrees]"));
        }
        if !ok(h, h > 0.0) {
            return Err(invalid("step", h, "positive and finite [s]"));
        }
        if !ok(duration, duration >= 0.0) {
            return Err(invalid("duration", duration, "non-negative and finite [s]"));
        }
        if let Some(c) = spec.components {
            if c == 0 || c > MAX_COMPONENTS {
                return Err(invalid("components", c as f64, "in 1..=10000000"));
            }
        }
        let wc = spec.spectrum.cutoff();
        let target = match spec.components {
            Some(c) => 2.0 * PI * c as f64 / wc,
            None => MIN_REPEAT_PERIOD.max(duration),
        };
        // The smallest M with M h ≥ target, forgiving the round-off of target/h.
        let m = (target / h * (1.0 - 4.0 * f64::EPSILON)).ceil().max(1.0);
        if m > MAX_FFT_LEN as f64 {
            return Err(SeaError::TooLarge {
                what: "FFT points",
                needed: m as u64,
                limit: MAX_FFT_LEN,
            });
        }
        let fft_len = m as usize;
        let dw = 2.0 * PI / (fft_len as f64 * h);
        let count = match spec.components {
            Some(c) => c,
            None => {
                // N = ⌊ω_c/Δω⌋ = ⌊6 T_r/T_p⌋ grows without bound as T_p → 0 (a T_p of 1 ms
                // asks for 6.5·10¹⁰ components over 3 h): held to the limit of a given
                // `components`, checked in f64 before any conversion or allocation.
                let derived = (wc / dw).floor();
                if derived.is_nan() || derived > MAX_COMPONENTS as f64 {
                    return Err(SeaError::TooManyComponents {
                        needed: derived,
                        repeat_period: fft_len as f64 * h,
                        limit: MAX_COMPONENTS,
                    });
                }
                (derived as usize).max(1)
            }
        };
        Ok(SeaPlan {
            fft_len,
            frequency_step: dw,
            components: count,
        })
    }

    /// Realises `spec` for a record of `duration` seconds at step `h`: the repeat period T_r is
    /// the smallest whole number of steps not shorter than 2πN/ω_c for a given N = `components`
    /// (ω_c = [`Spectrum::cutoff`]), or than max([`MIN_REPEAT_PERIOD`], `duration`) by default,
    /// with then N = ⌊ω_c/Δω⌋. With h dividing 3 h (0.01, 0.05, 0.1 s, …) and a record of at
    /// most 3 h, T_r = 3 h exactly and the sea does not depend on h. [`Sea::plan`] checks the
    /// same without realising it.
    ///
    /// # Errors
    /// [`SeaError::Invalid`] naming `depth`, `gravity`, `direction`, `components`, `step`,
    /// `duration` or (not finite amplitudes) `hs`; [`SeaError::TooLarge`] when T_r/h exceeds
    /// [`MAX_FFT_LEN`].
    pub fn new(spec: &SeaSpec, h: f64, duration: f64) -> Result<Self, SeaError> {
        let SeaPlan {
            fft_len,
            frequency_step: dw,
            components: count,
        } = Self::sizes(spec, h, duration)?;
        let omega: Vec<f64> = (1..=count).map(|j| j as f64 * dw).collect();
        let k: Vec<f64> = omega
            .iter()
            .map(|&w| wavenumber(w, spec.depth, spec.gravity))
            .collect();
        let amplitude: Vec<f64> = omega
            .iter()
            .map(|&w| Self::amplitude(spec, w, dw))
            .collect();
        if amplitude.iter().any(|a| !a.is_finite()) {
            return Err(Self::infinite_amplitude(spec));
        }
        if k.iter().any(|k: &f64| !k.is_finite()) {
            return Err(Self::infinite_wavenumber(spec));
        }
        let phase = phases(spec.seed, count);
        let phasor = amplitude
            .iter()
            .zip(&phase)
            .map(|(&a, &p)| Complex::new(a * libm::cos(p), a * libm::sin(p)))
            .collect();
        let theta = spec.direction_deg.to_radians();
        Ok(Self {
            spec: *spec,
            h,
            fft_len,
            dw,
            omega,
            k,
            amplitude,
            phase,
            phasor,
            direction: [libm::sin(theta), libm::cos(theta)],
        })
    }

    /// The specification realised.
    pub fn spec(&self) -> &SeaSpec {
        &self.spec
    }

    /// The frequency spacing Δω = 2π/T_r \[rad/s\].
    pub fn frequency_step(&self) -> f64 {
        self.dw
    }

    /// The repeat period T_r = M h \[s\].
    pub fn repeat_period(&self) -> f64 {
        self.fft_len as f64 * self.h
    }

    /// The time step h \[s\] of the grid tₖ = k h.
    pub fn step(&self) -> f64 {
        self.h
    }

    /// The components' frequencies ωⱼ = j Δω \[rad/s\], j = 1..N.
    pub fn frequencies(&self) -> &[f64] {
        &self.omega
    }

    /// The components' wavenumbers kⱼ \[rad/m\] (ωⱼ² = g kⱼ tanh(kⱼ d)).
    pub fn wavenumbers(&self) -> &[f64] {
        &self.k
    }

    /// The components' amplitudes aⱼ = √(2 S(ωⱼ) Δω) \[m\].
    pub fn amplitudes(&self) -> &[f64] {
        &self.amplitude
    }

    /// The components' phases φⱼ ∈ [0, 2π) from the seed.
    pub fn phases(&self) -> &[f64] {
        &self.phase
    }

    /// The mean direction's unit vector (x, z) = (sin θ, cos θ) in the horizontal plane.
    pub fn direction(&self) -> [f64; 2] {
        self.direction
    }

    /// The surface elevation η(0, t) = Σⱼ aⱼ cos(ωⱼ t + φⱼ) \[m\] at x = z = 0, by the direct
    /// sum (O(N); the reference for [`Sea::record`]).
    pub fn elevation(&self, t: f64) -> f64 {
        (0..self.omega.len())
            .map(|j| self.amplitude[j] * libm::cos(self.omega[j] * t + self.phase[j]))
            .sum()
    }

    /// The horizontal particle velocity along the mean direction at height y and x = z = 0,
    /// u(y, t) = Σⱼ ωⱼ aⱼ cosh(kⱼ y)/sinh(kⱼ d) cos(ωⱼ t + φⱼ) \[m/s\] (linear Airy theory,
    /// DNV-RP-C205 Table 3-1), by the direct sum.
    pub fn velocity(&self, y: f64, t: f64) -> f64 {
        (0..self.omega.len())
            .map(|j| {
                let w = self.omega[j];
                let g = depth_profile(self.k[j], y, self.spec.depth);
                w * self.amplitude[j] * g * libm::cos(w * t + self.phase[j])
            })
            .sum()
    }

    /// Its time derivative, the horizontal particle acceleration
    /// u̇(y, t) = −Σⱼ ωⱼ² aⱼ cosh(kⱼ y)/sinh(kⱼ d) sin(ωⱼ t + φⱼ) \[m/s²\], by the direct sum.
    pub fn acceleration(&self, y: f64, t: f64) -> f64 {
        (0..self.omega.len())
            .map(|j| {
                let w = self.omega[j];
                let g = depth_profile(self.k[j], y, self.spec.depth);
                -w * w * self.amplitude[j] * g * libm::sin(w * t + self.phase[j])
            })
            .sum()
    }

    /// The record of `steps + 1` times tₖ = k h (k = 0..=steps) at the given heights above the
    /// seabed \[m\]: one synthesis per height (velocity and acceleration together as the real and
    /// imaginary parts of one transform) and one for η, each the cheaper of the inverse FFT of
    /// length M and the zoom transform of the steps + 1 times alone ([`Sea::synthesis_rows`]):
    /// O((n + 1) min(M log M, P log P)), P ≈ 2N + steps. Beyond T_r the record repeats (k is
    /// taken modulo M).
    ///
    /// # Errors
    /// [`SeaError::Invalid`] naming `height` for a negative or non-finite height;
    /// [`SeaError::TooLarge`] when the record exceeds [`MAX_RECORD_BYTES`] or its memory is
    /// refused.
    pub fn record(&self, heights: &[f64], steps: usize) -> Result<WaveRecord, SeaError> {
        if let Some(&y) = heights.iter().find(|y| !(y.is_finite() && **y >= 0.0)) {
            return Err(invalid("height", y, "non-negative and finite [m]"));
        }
        let n = heights.len();
        let len = steps.saturating_add(1);
        let bytes = (len as u64)
            .saturating_mul(2 * n as u64 + 1)
            .saturating_mul(8)
            .saturating_add(self.fft_len as u64 * 32);
        let too_large = || SeaError::TooLarge {
            what: "bytes",
            needed: bytes,
            limit: MAX_RECORD_BYTES,
        };
        if bytes > MAX_RECORD_BYTES {
            return Err(too_large());
        }
        let alloc = |size: usize| -> Result<Vec<f64>, SeaError> {
            let mut v = Vec::new();
            v.try_reserve_exact(size).map_err(|_| too_large())?;
            v.resize(size, 0.0);
            Ok(v)
        };
        let mut rec = WaveRecord {
            n,
            len,
            h: self.h,
            direction: self.direction,
            velocity: alloc(len * n)?,
            acceleration: alloc(len * n)?,
            elevation: alloc(len)?,
        };
        // The cheaper of the full and the zoom transform for these rows, as the model's record
        // chooses ([`Sea::synthesis_rows`]): the same elevation, bit for bit.
        let mut plan = self.synthesis_rows(1, len);
        // η = Re Σ aⱼ e^{iφⱼ} e^{iωⱼt}.
        let el = &mut rec.elevation;
        self.synthesize((&self.phasor, &[]), len, &mut plan, |k, x, _| el[k] = x);
        let i = Complex::new(0.0, 1.0);
        let nc = self.omega.len();
        let (mut v, mut a) = (
            vec![Complex::new(0.0, 0.0); nc],
            vec![Complex::new(0.0, 0.0); nc],
        );
        for (node, &y) in heights.iter().enumerate() {
            // u = Re Σ Vⱼ e^{iωⱼt}, Vⱼ = ωⱼ Gⱼ(y) aⱼ e^{iφⱼ}, and u̇ = Re Σ i ωⱼ Vⱼ e^{iωⱼt}.
            self.velocity_amplitudes(y, &mut v);
            for ((aj, vj), &w) in a.iter_mut().zip(&v).zip(&self.omega) {
                *aj = i * w * vj;
            }
            let (vel, acc) = (&mut rec.velocity, &mut rec.acceleration);
            self.synthesize((&v, &a), len, &mut plan, |k, x, y| {
                vel[k * n + node] = x;
                acc[k * n + node] = y;
            });
        }
        Ok(rec)
    }

    /// The complex amplitudes of the horizontal particle velocity at height y above the seabed,
    /// Vⱼ = ωⱼ aⱼ e^{iφⱼ} cosh(kⱼ y)/sinh(kⱼ d), written into `out` (one per component):
    /// u(y, t) = Re Σⱼ Vⱼ e^{iωⱼ t} and u̇(y, t) = Re Σⱼ i ωⱼ Vⱼ e^{iωⱼ t} (linear Airy theory,
    /// DNV-RP-C205 Table 3-1; [`Sea::velocity`]).
    pub fn velocity_amplitudes(&self, y: f64, out: &mut [Complex<f64>]) {
        for (j, o) in out.iter_mut().enumerate().take(self.omega.len()) {
            let w = self.omega[j];
            *o = self.phasor[j] * (w * depth_profile(self.k[j], y, self.spec.depth));
        }
    }

    /// The complex amplitudes of the horizontal particle velocity averaged over the heights
    /// [y₀, y₁]: ωⱼ aⱼ e^{iφⱼ} times [`cell_profile`] of kⱼ over (y₀, y₁) in depth d, the mean
    /// of [`Sea::velocity_amplitudes`] over the interval, exactly.
    pub fn cell_velocity_amplitudes(&self, cell: (f64, f64), out: &mut [Complex<f64>]) {
        for (j, o) in out.iter_mut().enumerate().take(self.omega.len()) {
            let w = self.omega[j];
            *o = self.phasor[j] * (w * cell_profile(self.k[j], cell, self.spec.depth));
        }
    }

    /// The complex amplitudes aⱼ e^{iφⱼ} of the elevation: η(0, t) = Re Σⱼ aⱼ e^{iφⱼ} e^{iωⱼ t}.
    pub fn elevation_amplitudes(&self) -> &[Complex<f64>] {
        &self.phasor
    }

    /// Re Σⱼ Xⱼ e^{iωⱼ t} at any time t by the direct sum, O(N) (the reference for
    /// [`Sea::synthesize`], and its continuation beyond a synthesised record).
    pub fn sum_at(&self, x: &[Complex<f64>], t: f64) -> f64 {
        let mut s = 0.0;
        for (j, c) in x.iter().enumerate().take(self.omega.len()) {
            let a = self.omega[j] * t;
            s += c.re * libm::cos(a) - c.im * libm::sin(a);
        }
        s
    }

    /// A reusable inverse FFT of length M for [`Sea::synthesize`].
    pub fn synthesis(&self) -> Synthesis {
        self.synthesis_every(1)
    }

    /// A reusable inverse FFT for [`Sea::synthesize`] on the coarser grid t = k r h (`r` =
    /// `every` ≥ 1; 1 is [`Sea::synthesis`]): of length M/r when r divides M — on that grid
    /// e^{iωⱼ k r h} = e^{2πi (j+1) k/(M/r)}, so the series is the inverse DFT of length M/r with
    /// the components folded modulo M/r, exactly — and otherwise of length M, read every r-th
    /// value.
    pub fn synthesis_every(&self, every: usize) -> Synthesis {
        let (m, stride) = self.grid(every);
        let fft = FftPlanner::<f64>::new().plan_fft_inverse(m);
        let scratch = vec![Complex::new(0.0, 0.0); fft.get_inplace_scratch_len()];
        Synthesis {
            engine: Engine::Full {
                fft,
                buf: vec![Complex::new(0.0, 0.0); m],
                scratch,
                stride,
            },
        }
    }

    /// The transform length L and the stride s of the grid t = k r h (`every` = r ≥ 1): (M/r, 1)
    /// when r divides M, else (M, r): on that grid ωⱼ t = 2π (j+1) s k / L.
    fn grid(&self, every: usize) -> (usize, usize) {
        let every = every.max(1);
        if self.fft_len.is_multiple_of(every) {
            (self.fft_len / every, 1)
        } else {
            (self.fft_len, every)
        }
    }

    /// A reusable synthesis of the first `rows` times of the grid t = k r h (`every` = r ≥ 1)
    /// for [`Sea::synthesize`], at the cost of the run rather than of the repeat period: the
    /// full inverse FFT of [`Sea::synthesis_every`] (length L = M/r or M) when it is the cheaper,
    /// else the **zoom** transform, which forms only the `rows` outputs the run reads.
    ///
    /// The zoom transform (Bluestein's chirp z-transform restricted to the band the components
    /// occupy): on the grid, with signed frequency indices f ∈ [−N, N] (component j at
    /// f = j + 1 with (Xⱼ + i Yⱼ)/2 and at f = −(j + 1) with (X̄ⱼ + i Ȳⱼ)/2, the coefficients the
    /// full transform's bins hold, [`Sea::synthesize`]) and V = e^{iπ s/L},
    /// z_k = Σ_f c_f V^{2 f k}. With u = f + N and 2uk = u² + k² − (k − u)²,
    ///
    /// ```text
    /// z_k = V^{k² − 2Nk} Σ_{u=0}^{2N} (c_{u−N} V^{u²}) V^{−(k−u)²},   k = 0..rows,
    /// ```
    ///
    /// a linear convolution of 2N + 1 values with a kernel of 2N + rows values: two FFTs of a
    /// length P ≥ 2N + rows per series (the kernel's transform is planned once), O(P log P) in
    /// place of O(L log L): a 10 s run of a 3-hour sea at h = 0.01 s transforms 16 384 points
    /// instead of 1 080 000. Every power V^m is formed from m s reduced modulo 2L in integers, so
    /// the transform is exact to round-off whatever the size of the exponents; the sum is the
    /// same trigonometric sum as the full transform's (the same sea: the components, amplitudes
    /// and phases are untouched), its values differ from the full FFT's by round-off
    /// (measured 10⁻¹⁶ of the series' amplitude sum, `tests/fatigue/sea_domain.rs`).
    ///
    /// The choice is made from the sizes alone (the zoom when 2 P log₂ P < L log₂ L / 2, the
    /// margin keeping the full transform, and its bits, for runs of a good part of the repeat
    /// period), so the model's record and [`Sea::record`] of the same grid and rows choose
    /// alike and agree bit for bit.
    ///
    /// **A few rows** (rows · N ≤ P log₂ P / 2 and rows · N ≤ 2²⁰): the direct sum at each row
    /// with the row's cos ωⱼtₖ and sin ωⱼtₖ tabulated once for every series of the plan, O(N)
    /// per row and series in place of two transforms of P points: a 10-step run of a 3-hour sea
    /// sums 11 rows of N ≈ 8 500 components per series instead of transforming 32 768 points
    /// twice. Its values are [`Sea::sum_at`]'s bit for bit.
    pub fn synthesis_rows(&self, every: usize, rows: usize) -> Synthesis {
        let (l, s) = self.grid(every);
        let nc = self.omega.len();
        let band = 2 * nc + 1;
        let p = match band.checked_add(rows) {
            Some(x) => x.next_power_of_two(),
            None => return self.synthesis_every(every),
        };
        let cost = |n: usize| n as f64 * (n.max(2) as f64).log2();
        let terms = rows.saturating_mul(nc);
        if rows > 0 && terms <= 1 << 20 && terms as f64 <= 0.5 * cost(p) {
            let dt = every.max(1) as f64 * self.h;
            return Synthesis {
                engine: Engine::Direct(Direct::new(&self.omega, rows, dt)),
            };
        }
        if rows == 0 || 2.0 * cost(p) >= 0.5 * cost(l) {
            return self.synthesis_every(every);
        }
        // V^m = e^{iπ s m / L}, m reduced modulo 2L exactly.
        let (l2, s) = (2 * l as i128, s as i128);
        let power = |m: i128| {
            let e = (s * m).rem_euclid(l2) as f64;
            let a = PI * e / l as f64;
            Complex::new(libm::cos(a), libm::sin(a))
        };
        let nn = nc as i128;
        let pre: Vec<Complex<f64>> = (0..band as i128).map(|u| power(u * u)).collect();
        let post: Vec<Complex<f64>> = (0..rows as i128)
            .map(|k| power(k * k - 2 * nn * k))
            .collect();
        // The kernel h_d = V^{−d²}, d = −2N..rows−1, stored cyclically (d < 0 at P + d), its
        // transform divided by P (the inverse transform's normalisation).
        let mut planner = FftPlanner::<f64>::new();
        let forward = planner.plan_fft_forward(p);
        let inverse = planner.plan_fft_inverse(p);
        let mut kernel = vec![Complex::new(0.0, 0.0); p];
        for d in -(2 * nn)..rows as i128 {
            let at = if d < 0 { p as i128 + d } else { d } as usize;
            kernel[at] = power(-d * d);
        }
        let mut scratch = vec![
            Complex::new(0.0, 0.0);
            forward
                .get_inplace_scratch_len()
                .max(inverse.get_inplace_scratch_len())
        ];
        forward.process_with_scratch(&mut kernel, &mut scratch);
        let scale = 1.0 / p as f64;
        for x in &mut kernel {
            *x *= scale;
        }
        Synthesis {
            engine: Engine::Zoom(Box::new(Zoom {
                forward,
                inverse,
                kernel,
                pre,
                post,
                buf: vec![Complex::new(0.0, 0.0); p],
                scratch,
                dt: every.max(1) as f64 * self.h,
            })),
        }
    }

    /// Two real series at once on the grid tₖ = k h, k = 0..`rows`, by one inverse FFT of length
    /// M: `out(k, xₖ, yₖ)` with xₖ = Re Σⱼ Xⱼ e^{iωⱼ tₖ} and yₖ = Re Σⱼ Yⱼ e^{iωⱼ tₖ} (one
    /// amplitude per component; k is taken modulo M beyond the repeat period). O(M log M)
    /// instead of the direct sum's O(N) per time. With a plan of [`Sea::synthesis_every`]`(r)`
    /// the grid is tₖ = k r h; with one of [`Sea::synthesis_rows`]`(r, rows)` the same grid by
    /// the cheaper of the full and the zoom transform (rows beyond the plan's are then summed
    /// directly, O(N) each).
    pub fn synthesize(
        &self,
        (x, y): (&[Complex<f64>], &[Complex<f64>]),
        rows: usize,
        plan: &mut Synthesis,
        mut out: impl FnMut(usize, f64, f64),
    ) {
        let zero = Complex::new(0.0, 0.0);
        let coef = |j: usize| {
            (
                x.get(j).copied().unwrap_or(zero),
                y.get(j).copied().unwrap_or(zero),
            )
        };
        match &mut plan.engine {
            Engine::Full {
                fft,
                buf,
                scratch,
                stride,
            } => {
                self.fill(buf, coef);
                fft.process_with_scratch(buf, scratch);
                let m = buf.len();
                for k in 0..rows {
                    let z = buf[(k * *stride) % m];
                    out(k, z.re, z.im);
                }
            }
            Engine::Direct(d) => {
                for k in 0..rows.min(d.rows()) {
                    out(k, d.sum(k, |j| coef(j).0), d.sum(k, |j| coef(j).1));
                }
                self.sum_beyond(coef, (d.rows(), rows), d.dt, &mut out);
            }
            Engine::Zoom(z) => {
                let nc = self.omega.len();
                let i = Complex::new(0.0, 1.0);
                z.buf.fill(zero);
                for j in 0..nc {
                    let (a, b) = coef(j);
                    // f = j + 1 at u = N + j + 1, f = −(j + 1) at u = N − j − 1.
                    z.buf[nc + j + 1] = (a + i * b) * 0.5 * z.pre[nc + j + 1];
                    z.buf[nc - j - 1] = (a.conj() + i * b.conj()) * 0.5 * z.pre[nc - j - 1];
                }
                z.forward.process_with_scratch(&mut z.buf, &mut z.scratch);
                for (b, h) in z.buf.iter_mut().zip(&z.kernel) {
                    *b *= h;
                }
                z.inverse.process_with_scratch(&mut z.buf, &mut z.scratch);
                let formed = rows.min(z.post.len());
                for k in 0..formed {
                    let v = z.buf[k] * z.post[k];
                    out(k, v.re, v.im);
                }
                self.sum_beyond(coef, (formed, rows), z.dt, &mut out);
            }
        }
    }

    /// The rows `from..to` of a plan that formed fewer, summed directly ([`Sea::sum_at`] at
    /// t = k·`dt`).
    fn sum_beyond(
        &self,
        coef: impl Fn(usize) -> (Complex<f64>, Complex<f64>),
        (from, to): (usize, usize),
        dt: f64,
        out: &mut impl FnMut(usize, f64, f64),
    ) {
        if to <= from {
            return;
        }
        let nc = self.omega.len();
        let xs: Vec<Complex<f64>> = (0..nc).map(|j| coef(j).0).collect();
        let ys: Vec<Complex<f64>> = (0..nc).map(|j| coef(j).1).collect();
        for k in from..to {
            let t = k as f64 * dt;
            out(k, self.sum_at(&xs, t), self.sum_at(&ys, t));
        }
    }

    /// Fills the input of the inverse FFT so that its output is xₘ + i yₘ with the two real
    /// series xₘ = Re Σⱼ Xⱼ e^{2πi j m/M} and yₘ = Re Σⱼ Yⱼ e^{2πi j m/M}, where
    /// `coef(j) = (Xⱼ, Yⱼ)` for component j (frequency (j + 1) Δω): bin j + 1 gets (Xⱼ + i Yⱼ)/2
    /// and bin M − j − 1 gets (X̄ⱼ + i Ȳⱼ)/2 (indices modulo M: components beyond M fold onto
    /// the same roots of unity, exactly).
    fn fill(&self, buf: &mut [Complex<f64>], coef: impl Fn(usize) -> (Complex<f64>, Complex<f64>)) {
        let m = buf.len();
        let i = Complex::new(0.0, 1.0);
        buf.fill(Complex::new(0.0, 0.0));
        for j in 0..self.omega.len() {
            let (x, y) = coef(j);
            let bin = (j + 1) % m;
            buf[bin] += (x + i * y) * 0.5;
            buf[(m - bin) % m] += (x.conj() + i * y.conj()) * 0.5;
        }
    }
}

/// The wave kinematics of a record: at each time tₖ = k h (k = 0..=steps) and each node, the
/// horizontal particle velocity u and acceleration u̇ along the mean direction, and the surface
/// elevation η at x = z = 0 ([`Sea::record`]). Stored time-major (the n values of one step are
/// contiguous), read by a load term per node and step without allocating.
#[derive(Clone, Debug)]
pub struct WaveRecord {
    n: usize,
    len: usize,
    h: f64,
    direction: [f64; 2],
    velocity: Vec<f64>,
    acceleration: Vec<f64>,
    elevation: Vec<f64>,
}

impl WaveRecord {
    /// Number of nodes (heights) n.
    pub fn nodes(&self) -> usize {
        self.n
    }

    /// Number of times, steps + 1.
    pub fn len(&self) -> usize {
        self.len
    }

    /// Whether the record has no times (never: it has at least t₀).
    pub fn is_empty(&self) -> bool {
        self.len == 0
    }

    /// The time step h \[s\].
    pub fn step(&self) -> f64 {
        self.h
    }

    /// The mean direction's unit vector (x, z) in the horizontal plane.
    pub fn direction(&self) -> [f64; 2] {
        self.direction
    }

    /// The horizontal particle velocities u(yᵢ, tₖ) \[m/s\] of every node at step k.
    #[inline]
    pub fn velocity(&self, k: usize) -> &[f64] {
        &self.velocity[k * self.n..(k + 1) * self.n]
    }

    /// The horizontal particle accelerations u̇(yᵢ, tₖ) \[m/s²\] of every node at step k.
    #[inline]
    pub fn acceleration(&self, k: usize) -> &[f64] {
        &self.acceleration[k * self.n..(k + 1) * self.n]
    }

    /// The surface elevation η(0, tₖ) \[m\] at step k.
    #[inline]
    pub fn elevation(&self, k: usize) -> f64 {
        self.elevation[k]
    }

    /// The whole elevation series η(0, tₖ), k = 0..=steps.
    pub fn elevations(&self) -> &[f64] {
        &self.elevation
    }
}
