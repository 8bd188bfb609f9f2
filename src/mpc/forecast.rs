//! The noisy forecast of the sea ahead (`[mpc] forecast = "noisy"`, [`crate::mpc`] "What the
//! plan knows"): at each re-plan every wave component's complex amplitude is forecast with an
//! error that grows with the lead time, drawn from a seeded stream, and the plan runs on the
//! forecast while the plant runs the true sea.
//!
//! **The error model.** The sea is Re Σⱼ Aⱼ e^{iωⱼ t} with Aⱼ = aⱼ e^{iφⱼ} ([`crate::ocean`]); a
//! forecast issued at the decision time t₀ predicts, at lead time τ = t − t₀,
//! ```text
//! Âⱼ(τ) = Aⱼ (1 + σ(τ) wⱼ),   wⱼ = ξⱼ + i ηⱼ,   ξⱼ, ηⱼ ~ N(0, 1) independent,
//! σ(τ) = min(e · max(τ, 0) / T_p, 1/√2),
//! ```
//! e = `forecast_error`, T_p the sea's peak period. To first order in σ the component's relative
//! amplitude error is σ ξⱼ and its phase error σ ηⱼ rad, each of standard deviation σ(τ): zero
//! at the present (the observed sea), growing linearly with the lead time, e per peak period.
//! The cap 1/√2 is where the forecast stops having skill: the error Aⱼ σ wⱼ then has the mean
//! square 2σ²|Aⱼ|² = |Aⱼ|², the sea's own, so the forecast's mean-square error equals that of
//! forecasting a calm sea (`forecast = "none"`); a larger σ would forecast worse than no
//! forecast at all. The wⱼ are drawn afresh at every re-plan (a new forecast every decision,
//! independent of the last), and within a plan they are fixed, so the error of a component is
//! a smooth function of the lead time.
//!
//! Every kinematic series of the model is linear in the Aⱼ (the water's momentum Wᵢ and the
//! inertia load Gᵢ of each pendulum, [`crate::model::WaveField`]; the vessel's wave-frequency
//! surge X_w, [`crate::model::VesselMotion`]), so the forecast of a series y = Re Σⱼ Yⱼ e^{iωⱼ t}
//! is the truth plus σ(τ) times the error series E = Re Σⱼ Yⱼ wⱼ e^{iωⱼ t}:
//! ```text
//! ŷ(t) = y(t) + σ(τ) E(t),   dŷ/dt = ẏ(t) + σ'(τ) E(t) + σ(τ) Ė(t).
//! ```
//! The truth comes from the plan's record (the same values as a perfect forecast); E and Ė
//! are summed directly over the components at knots of the record's grid (every record time
//! when the record keeps derivatives, `record_step` > `time.step`; else every
//! max(1, ⌊T_p/(40 h)⌋) steps, E linearly interpolated between knots: an error of at most
//! (2π/40)²/8 = 0.3 % of E at the peak period) and added over a window of the record that
//! covers the horizon ([`crate::model::WaveField::window`],
//! [`crate::model::VesselMotion::surge_window`]). With e = 0 the additions are zeros and the
//! plan reads the record's values: the perfect forecast, bit for bit.
//!
//! **The seed.** The draws are Box-Muller pairs (ξ, η) = √(−2 ln u₁) (cos 2πu₂, sin 2πu₂) from
//! the 64-bit words of the ChaCha20 stream keyed by `forecast_seed`'s 8 little-endian bytes, the
//! 8 bytes `b"forecast"` and 16 zero bytes (u₁ = (⌊r₁/2¹¹⌋ + 1) 2⁻⁵³, u₂ = ⌊r₂/2¹¹⌋ 2⁻⁵³, in
//! the order of the components, re-plan after re-plan). The seed defaults to the sea's own: a
//! run's forecast errors follow its sea, and the `b"forecast"` tag keeps them a stream apart
//! from the sea's phases, which the same seed keys with zero bytes.

use std::sync::Arc;

use rand_chacha::rand_core::{RngCore, SeedableRng};
use rand_chacha::ChaCha20Rng;

use crate::error::{MpcError, Result};
use crate::model::Chain;
use crate::ocean::Complex;
use crate::scene::Scene;

/// The cap of σ(τ): 1/√2, where the forecast's mean-square error reaches the sea's variance
/// (module docs).
pub const SIGMA_CAP: f64 = std::f64::consts::FRAC_1_SQRT_2;

/// Knots per peak period of the error series on a record that keeps every step (module docs).
const KNOTS_PER_PERIOD: f64 = 40.0;

/// σ(τ) = min(e · max(τ, 0) / T_p, [`SIGMA_CAP`]): the standard deviation of a component's
/// relative amplitude error and of its phase error (rad) at lead time τ \[s\] (module docs).
pub fn forecast_sigma(error: f64, peak_period: f64, tau: f64) -> f64 {
    (error * tau.max(0.0) / peak_period).min(SIGMA_CAP)
}

/// dσ/dτ: e/T_p where σ grows, 0 before the present and beyond the cap.
fn forecast_sigma_rate(error: f64, peak_period: f64, tau: f64) -> f64 {
    if tau > 0.0 && error * tau / peak_period < SIGMA_CAP {
        error / peak_period
    } else {
        0.0
    }
}

/// The noisy forecast of one controller (module docs): its error growth, the sea's peak period
/// and frequencies, the seeded stream and the current draws wⱼ.
#[derive(Clone, Debug)]
pub struct NoisyForecast {
    error: f64,
    peak_period: f64,
    rng: ChaCha20Rng,
    /// wⱼ of the current forecast (one per component).
    draws: Vec<Complex<f64>>,
    /// The knot tables' scratch: wⱼ e^{iωⱼ t} and ωⱼ wⱼ e^{iωⱼ t} as re/im arrays.
    scratch: [Vec<f64>; 4],
}

impl NoisyForecast {
    /// The forecast of `model`'s sea with error growth `error` (e of σ(τ) = e τ / T_p) from
    /// `seed` (`None`: the sea's seed).
    ///
    /// # Errors
    /// [`MpcError::ForecastWithoutSea`] when `model` has no `[loads.waves]`;
    /// [`MpcError::ForecastError`] for an `error` not finite and ≥ 0.
    pub fn new(model: &Scene, error: f64, seed: Option<u64>) -> Result<Self> {
        let waves = model
            .loads
            .waves
            .as_ref()
            .ok_or(MpcError::ForecastWithoutSea)?;
        if !(error.is_finite() && error >= 0.0) {
            return Err(MpcError::ForecastError { value: error }.into());
        }
        let mut key = [0u8; 32];
        key[..8].copy_from_slice(&seed.unwrap_or(waves.seed).to_le_bytes());
        key[8..16].copy_from_slice(b"forecast");
        Ok(NoisyForecast {
            error,
            peak_period: waves.tp,
            rng: ChaCha20Rng::from_seed(key),
            draws: Vec::new(),
            scratch: Default::default(),
        })
    }

    /// σ(τ) of this forecast ([`forecast_sigma`]).
    pub fn sigma(&self, tau: f64) -> f64 {
        forecast_sigma(self.error, self.peak_period, tau)
    }

    /// The draws wⱼ of the current forecast (empty before the first).
    pub fn draws(&self) -> &[Complex<f64>] {
        &self.draws
    }

    /// Draws a new forecast's wⱼ for `components` components (module docs, "The seed").
    pub fn draw(&mut self, components: usize) {
        let scale = 1.0 / (1u64 << 53) as f64;
        self.draws.clear();
        for _ in 0..components {
            let u1 = ((self.rng.next_u64() >> 11) + 1) as f64 * scale;
            let u2 = (self.rng.next_u64() >> 11) as f64 * scale;
            let r = libm::sqrt(-2.0 * libm::log(u1));
            let a = 2.0 * std::f64::consts::PI * u2;
            self.draws
                .push(Complex::new(r * libm::cos(a), r * libm::sin(a)));
        }
    }

    /// A new forecast (fresh draws) issued at `t_decision` for a plan over the times
    /// [`t_start`, `t_end`]: `record`, the plan's chain with the true sea over the run, with its
    /// waves' field and vessel motion replaced by the forecast's over a window of their
    /// records that covers the plan (module docs). A chain without waves is returned as it is.
    ///
    /// # Errors
    /// [`MpcError::ForecastWindow`] when the plan's times are not within the record.
    pub fn forecast_chain<const DIM: usize>(
        &mut self,
        record: &Chain<f64, DIM>,
        t_decision: f64,
        (t_start, t_end): (f64, f64),
    ) -> Result<Chain<f64, DIM>> {
        let mut chain = record.clone();
        let Some(field) = record.waves() else {
            return Ok(chain);
        };
        let omega = field.sea().frequencies().to_vec();
        let nc = omega.len();
        self.draw(nc);
        let window_err = || MpcError::ForecastWindow {
            start: t_start,
            end: t_end,
        };
        // The field's window: from the record time at or before t_start to two past t_end (the
        // steps read at their half and the interpolant's next time).
        let dt = field.record_step();
        let (rec_first, rec_rows) = field.record_rows();
        let first = ((t_start / dt).floor().max(0.0) as usize).max(rec_first);
        let last = ((t_end / dt).ceil() as usize + 2).min(rec_first + rec_rows - 1);
        if last < first + 1 {
            return Err(window_err().into());
        }
        let rows = last - first + 1;
        let (n, width) = (field.pendulums(), field.record_width());
        let derivatives = width == 4;
        let stride = if derivatives { 1 } else { self.knot_stride(dt) };
        let amps: Vec<[&[Complex<f64>]; 2]> = (0..n)
            .map(|i| [field.amplitudes(i, false), field.amplitudes(i, true)])
            .collect();
        // E and Ė of (W, G) per pendulum at the knots, then σ applied row by row.
        let knots = knot_rows(rows, stride);
        let mut at_knot = vec![[0.0f64; 4]; knots.len() * n];
        for (kk, &r) in knots.iter().enumerate() {
            let t = (first + r) as f64 * dt;
            self.phasors(&omega, t);
            for (i, a) in amps.iter().enumerate() {
                let (ew, dw) = self.error_sums(a[0]);
                let (eg, dg) = self.error_sums(a[1]);
                at_knot[kk * n + i] = [ew, dw, eg, dg];
            }
        }
        let mut add = vec![0.0; rows * n * width];
        for r in 0..rows {
            let t = (first + r) as f64 * dt;
            let tau = t - t_decision;
            let (s, ds) = (self.sigma(tau), self.sigma_rate(tau));
            for i in 0..n {
                let [ew, dw, eg, dg] = interpolate(&knots, &at_knot, n, r, i);
                let out = &mut add[(r * n + i) * width..(r * n + i + 1) * width];
                if derivatives {
                    out.copy_from_slice(&[s * ew, ds * ew + s * dw, s * eg, ds * eg + s * dg]);
                } else {
                    out.copy_from_slice(&[s * ew, s * eg]);
                }
            }
        }
        let window = field.window(first, rows, &add).map_err(|_| window_err())?;
        // The vessel's wave-frequency surge, on the sea's step grid.
        let vessel = match record.vessel() {
            Some(v) => match (v.surge_amplitudes(), v.surge_step()) {
                (Some(amp), Some(h)) => {
                    let first = (t_start / h).floor().max(0.0) as usize;
                    let rows = (t_end / h).ceil() as usize + 2 - first;
                    let stride = self.knot_stride(h);
                    let knots = knot_rows(rows, stride);
                    let mut at_knot = vec![[0.0f64; 4]; knots.len()];
                    for (kk, &r) in knots.iter().enumerate() {
                        self.phasors(&omega, (first + r) as f64 * h);
                        let (e, d) = self.error_sums(amp);
                        at_knot[kk] = [e, d, 0.0, 0.0];
                    }
                    let add: Vec<[f64; 2]> = (0..rows)
                        .map(|r| {
                            let tau = (first + r) as f64 * h - t_decision;
                            let (s, ds) = (self.sigma(tau), self.sigma_rate(tau));
                            let [e, d, _, _] = interpolate(&knots, &at_knot, 1, r, 0);
                            [s * e, ds * e + s * d]
                        })
                        .collect();
                    let moved = v.surge_window(first, &add).map_err(|_| window_err())?;
                    Some(Arc::new(moved))
                }
                _ => None,
            },
            None => None,
        };
        chain.set_forecast(Some(Arc::new(window)), vessel);
        Ok(chain)
    }

    fn sigma_rate(&self, tau: f64) -> f64 {
        forecast_sigma_rate(self.error, self.peak_period, tau)
    }

    /// Rows between knots on a grid of step `dt` that keeps no derivatives (module docs).
    fn knot_stride(&self, dt: f64) -> usize {
        ((self.peak_period / (KNOTS_PER_PERIOD * dt)).floor() as usize).max(1)
    }

    /// wⱼ e^{iωⱼ t} and ωⱼ wⱼ e^{iωⱼ t} into the scratch (re/im arrays).
    fn phasors(&mut self, omega: &[f64], t: f64) {
        let [er, ei, fr, fi] = &mut self.scratch;
        for v in [&mut *er, &mut *ei, &mut *fr, &mut *fi] {
            v.clear();
        }
        for (w, d) in omega.iter().zip(&self.draws) {
            let a = w * t;
            let z = *d * Complex::new(libm::cos(a), libm::sin(a));
            er.push(z.re);
            ei.push(z.im);
            fr.push(w * z.re);
            fi.push(w * z.im);
        }
    }

    /// (E, Ė) = (Re Σⱼ Yⱼ wⱼ e^{iωⱼ t}, Re Σⱼ iωⱼ Yⱼ wⱼ e^{iωⱼ t}) of amplitudes Y at the time of
    /// the scratch's phasors.
    fn error_sums(&self, y: &[Complex<f64>]) -> (f64, f64) {
        let [er, ei, fr, fi] = &self.scratch;
        let (mut e, mut d) = (0.0, 0.0);
        for (((yj, (a, b)), c), g) in y.iter().zip(er.iter().zip(ei)).zip(fr).zip(fi) {
            e += yj.re * a - yj.im * b;
            d -= yj.re * g + yj.im * c;
        }
        (e, d)
    }
}

/// The knot rows of a window of `rows` rows: every `stride`-th and the last.
fn knot_rows(rows: usize, stride: usize) -> Vec<usize> {
    let mut k: Vec<usize> = (0..rows).step_by(stride.max(1)).collect();
    if k.last() != Some(&(rows - 1)) {
        k.push(rows - 1);
    }
    k
}

/// The values at row `r` of item `i` (of `n` per knot): the knot's at a knot, linear between.
fn interpolate(knots: &[usize], at: &[[f64; 4]], n: usize, r: usize, i: usize) -> [f64; 4] {
    let k = match knots.binary_search(&r) {
        Ok(k) => return at[k * n + i],
        Err(k) => k,
    };
    let (r0, r1) = (knots[k - 1], knots[k]);
    let x = (r - r0) as f64 / (r1 - r0) as f64;
    let (a, b) = (at[(k - 1) * n + i], at[k * n + i]);
    std::array::from_fn(|c| a[c] + x * (b[c] - a[c]))
}
