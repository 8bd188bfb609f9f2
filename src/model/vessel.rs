//! The vessel's prescribed motion of the riser's top ([`VesselMotion`]; `support = "vessel"`,
//! docs/conventions.md "A top held by the vessel").
//!
//! The top's z is held by the rheonomic constraint l(q) = Σ lᵢ e₃ᵀqᵢ = Z(t), with
//! Z(t) = ρ(t) (Z₀ + d_z X_w(t)) ([`crate::scene::Vessel`]). RATTLE imposes it at t_{k+1} on the
//! positions and its rate Ż(t_{k+1}) on the momenta (`steppers/rattle.rs`). Z is a known function
//! of time: it depends on no state, control or parameter, so every derivative of a step is that
//! of the locked tip, and the adjoint and dual numbers need nothing more.
//!
//! X_w and Ẋ_w are kept on the scene's time grid tₖ = k h for the run (one inverse FFT of the
//! components H(ωⱼ) aⱼ e^{iφⱼ} and iωⱼ H(ωⱼ) aⱼ e^{iφⱼ}, [`Sea::synthesize`]), and summed directly
//! (O(N)) at any other time.

use std::sync::Arc;

use crate::ocean::{Complex, Sea, SeaError};
use crate::scene::Vessel;

/// The top's prescribed position Z(t) and velocity Ż(t) (module docs).
#[derive(Clone, Debug)]
pub struct VesselMotion {
    vessel: Vessel,
    waves: Option<WaveSurge>,
}

/// The wave-frequency surge d_z X_w(t) of a vessel with a RAO in a sea.
#[derive(Clone, Debug)]
struct WaveSurge {
    sea: Arc<Sea>,
    /// d_z Hⱼ aⱼ e^{iφⱼ}: X_w's complex amplitudes along z.
    amplitude: Vec<Complex<f64>>,
    /// iωⱼ times `amplitude`: Ẋ_w's.
    rate: Vec<Complex<f64>>,
    /// (X_w, Ẋ_w) at tₖ = k h, k = 0..rows.
    record: Vec<[f64; 2]>,
}

impl VesselMotion {
    /// The motion of `vessel`; with `sea` = (the scene's sea, the waves' z direction d_z) and a
    /// RAO, the wave-frequency surge is realised for `rows` times tₖ = k h of the sea's grid.
    ///
    /// # Errors
    /// [`SeaError::TooLarge`] when the record's memory is refused.
    pub fn new(
        vessel: &Vessel,
        sea: Option<(Arc<Sea>, f64)>,
        rows: usize,
    ) -> Result<Self, SeaError> {
        let waves = match (sea, &vessel.rao) {
            (Some((sea, dz)), Some(rao)) if dz != 0.0 => {
                let amplitude: Vec<Complex<f64>> = sea
                    .frequencies()
                    .iter()
                    .zip(sea.elevation_amplitudes())
                    .map(|(&w, a)| {
                        let [re, im] = rao.transfer(w);
                        Complex::new(re, im) * *a * dz
                    })
                    .collect();
                let rate = sea
                    .frequencies()
                    .iter()
                    .zip(&amplitude)
                    .map(|(&w, x)| Complex::new(0.0, w) * *x)
                    .collect::<Vec<_>>();
                let mut record = Vec::new();
                record
                    .try_reserve_exact(rows)
                    .map_err(|_| SeaError::TooLarge {
                        what: "bytes",
                        needed: (rows as u64).saturating_mul(16),
                        limit: crate::ocean::MAX_RECORD_BYTES,
                    })?;
                record.resize(rows, [0.0; 2]);
                let mut plan = sea.synthesis();
                sea.synthesize((&amplitude, &rate), rows, &mut plan, |k, x, v| {
                    record[k] = [x, v];
                });
                Some(WaveSurge {
                    sea,
                    amplitude,
                    rate,
                    record,
                })
            }
            _ => None,
        };
        Ok(VesselMotion {
            vessel: vessel.clone(),
            waves,
        })
    }

    /// The vessel's description.
    pub fn vessel(&self) -> &Vessel {
        &self.vessel
    }

    /// (Z(t), Ż(t)): the top's prescribed z and its rate (module docs).
    pub fn at(&self, t: f64) -> [f64; 2] {
        let (rho, rho_dot) = self.vessel.ramp_factor(t);
        let [x, v] = match &self.waves {
            Some(w) => w.at(t),
            None => [0.0; 2],
        };
        let z = self.vessel.offset + x;
        [rho * z, rho_dot * z + rho * v]
    }

    /// The mean position the top settles at, Z₀ (the static equilibrium's target).
    pub fn mean(&self) -> f64 {
        self.vessel.offset
    }
}

impl WaveSurge {
    /// (X_w(t), Ẋ_w(t)): from the record on the grid, else by the direct sum.
    fn at(&self, t: f64) -> [f64; 2] {
        let h = self.sea.step();
        let k = (t / h).round();
        // On the grid exactly (the step's times t₀ + (k + 1) h with t₀ = 0): the record.
        if k >= 0.0 && (k as usize) < self.record.len() && (t - k * h).abs() <= 0.0 {
            return self.record[k as usize];
        }
        [
            self.sea.sum_at(&self.amplitude, t),
            self.sea.sum_at(&self.rate, t),
        ]
    }
}
