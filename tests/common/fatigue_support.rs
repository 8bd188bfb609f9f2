//! Helpers of tests/fatigue/fatigue.rs: an allocation counter and a narrow-band Gaussian generator.

use std::alloc::{GlobalAlloc, Layout, System};
use std::cell::Cell;

use rand_chacha::rand_core::{RngCore, SeedableRng};
use rand_chacha::ChaCha8Rng;

/// Counts the allocations of the current thread (tests run on several threads).
struct Counting;

thread_local! {
    static ALLOCATIONS: Cell<usize> = const { Cell::new(0) };
}

unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        ALLOCATIONS.with(|c| c.set(c.get() + 1));
        // SAFETY: forwards the caller's layout to the system allocator unchanged.
        unsafe { System.alloc(layout) }
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        // SAFETY: `ptr` was allocated by `System` with this layout (see `alloc`).
        unsafe { System.dealloc(ptr, layout) }
    }
    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        ALLOCATIONS.with(|c| c.set(c.get() + 1));
        // SAFETY: as `alloc` and `dealloc`.
        unsafe { System.realloc(ptr, layout, new_size) }
    }
}

#[global_allocator]
static GLOBAL: Counting = Counting;

/// Allocations made so far by the current thread.
pub fn allocations() -> usize {
    ALLOCATIONS.with(|c| c.get())
}

/// A narrow-band Gaussian record: a flat spectrum over f₀ · [1 − w, 1 + w].
pub struct NarrowBand {
    /// Number of cosines.
    pub components: usize,
    /// w.
    pub relative_half_width: f64,
    /// f₀ \[Hz\].
    pub frequency_hz: f64,
    /// Standard deviation σ of the stress \[MPa\].
    pub std_mpa: f64,
    /// Record length in mean periods 1/f₀.
    pub periods: usize,
    /// Samples per period 1/f₀.
    pub samples_per_period: usize,
    /// ChaCha8 seed.
    pub seed: u64,
}

/// x(t) = Σ_j a cos(2π f_j t + φ_j), a = σ √(2/K), f_j uniform in the band, φ_j uniform in
/// [0, 2π): Gaussian by the central limit theorem, variance σ². Returns the samples, the
/// zero-upcrossing rate ν₀ = √(Σ f_j²/K) of the realised spectrum (Rice: √(m₂/m₀)) and the
/// duration. Each component turns by a fixed phasor per step, re-synchronised exactly every
/// 4096 steps so round-off does not accumulate.
pub fn narrow_band(band: &NarrowBand) -> (Vec<f64>, f64, f64) {
    let mut rng = ChaCha8Rng::seed_from_u64(band.seed);
    let mut uniform = || (rng.next_u64() >> 11) as f64 * (1.0 / (1u64 << 53) as f64);
    let k = band.components;
    let two_pi = 2.0 * std::f64::consts::PI;
    let f: Vec<f64> = (0..k)
        .map(|_| band.frequency_hz * (1.0 + band.relative_half_width * (2.0 * uniform() - 1.0)))
        .collect();
    let phase: Vec<f64> = (0..k).map(|_| two_pi * uniform()).collect();
    let amplitude = band.std_mpa * (2.0 / k as f64).sqrt();
    let nu0 = (f.iter().map(|f| f * f).sum::<f64>() / k as f64).sqrt();
    let dt = 1.0 / (band.frequency_hz * band.samples_per_period as f64);
    let n = band.periods * band.samples_per_period;
    let (step_re, step_im): (Vec<f64>, Vec<f64>) = f
        .iter()
        .map(|f| ((two_pi * f * dt).cos(), (two_pi * f * dt).sin()))
        .unzip();
    let (mut re, mut im) = (vec![0.0; k], vec![0.0; k]);
    let mut out = Vec::with_capacity(n + 1);
    for i in 0..=n {
        if i % 4096 == 0 {
            let t = i as f64 * dt;
            for j in 0..k {
                let a = two_pi * f[j] * t + phase[j];
                re[j] = a.cos();
                im[j] = a.sin();
            }
        }
        out.push(amplitude * re.iter().sum::<f64>());
        for j in 0..k {
            let r = re[j] * step_re[j] - im[j] * step_im[j];
            im[j] = re[j] * step_im[j] + im[j] * step_re[j];
            re[j] = r;
        }
    }
    (out, nu0, n as f64 * dt)
}
