//! The vessel's prescribed motion of the riser's top ([`VesselMotion`]; `support = "vessel"`,
//! docs/conventions.md "A top held by the vessel").
//!
//! The top's z is held by the rheonomic constraint l(q) = Σ lᵢ e₃ᵀqᵢ = Z(t), with
//! Z(t) = ρ(t) (Z₀ + d_z X_w(t)) ([`crate::scene::Vessel`]). RATTLE imposes it at t_{k+1} on the
//! positions and its rate Ż(t_{k+1}) on the momenta (`steppers/rattle.rs`). Z is a known function
//! of time: it depends on no state, control or parameter, so every derivative of a step is that
//! of the locked tip, and the adjoint and dual numbers need nothing more.
//!
//! **The vessel as the actuator** (`[vessel]` `mass`, ..., [`crate::scene::Thrust`]): the top
//! follows Z(t) = P(t) + x_v(t), P the prescribed part above and x_v the vessel's low-frequency
//! surge under the thrust F, (m + m_a) ẍ_v = F − c ẋ_v − k x_v ([`ThrustDrive`]; k the station keeping). x_v is a state of the
//! step, driven by the control: [`ThrustDrive`] integrates it with the step's own split and
//! writes the transpose of that linear map for the adjoint.
//!
//! X_w and Ẋ_w are kept on the scene's time grid tₖ = k h for the run (one inverse transform of
//! the components H(ωⱼ) aⱼ e^{iφⱼ} and iωⱼ H(ωⱼ) aⱼ e^{iφⱼ}, [`Sea::synthesize`] with the plan of
//! [`Sea::synthesis_rows`]: only the run's rows), and summed directly (O(N)) at any other time.

use std::sync::Arc;

use crate::base::Scalar;
use crate::ocean::{Complex, Sea, SeaError};
use crate::scene::Vessel;

/// The top's prescribed position Z(t) and velocity Ż(t) (module docs).
#[derive(Clone, Debug)]
pub struct VesselMotion {
    vessel: Vessel,
    waves: Option<WaveSurge>,
    thrust: Option<ThrustDrive>,
    /// The offset held in full from t = 0 (`[time] initial = "static"`): Z₀ is not ramped.
    offset_held: bool,
}

/// The vessel's surge under the thrust, (m + m_a) ẍ_v = F − c ẋ_v − k x_v, one-way coupled
/// (the riser's top reaction is left out: docs/conventions.md "The vessel as the actuator"; k
/// the station keeping, 0 without it), stepped with RATTLE's split, the spring's force a kick
/// at each end of the step as a potential's is, and the damping read at the half step (as the
/// riser's drag is):
///
/// ```text
/// v_{k+½} = (v_k + h/(2M) (F_k − k x_k)) / (1 + h c/(2M))
/// x_{k+1} = x_k + h v_{k+½}
/// v_{k+1} = v_{k+½} (1 − h c/(2M)) + h/(2M) (F_{k+1} − k x_{k+1})          M = m + m_a
/// ```
///
/// (Störmer–Verlet when c = 0, stable for h √(k/M) < 2; second order and, for c > 0, the
/// trapezoidal rule of the damping. With k = 0 every product k x is an exact zero: the map is
/// the drive without station keeping bit for bit.) The step's tip constraint reads Z = P + x_v, Ż = Ṗ + v_v;
/// the state keeps (Z, Ż) (the `tip_target` of the RATTLE state) and x_v = Z − P(t). The map
/// is linear in (Z, Ż, F_k, F_{k+1}), so its transpose ([`ThrustDrive::reverse`]) is written by
/// hand; tests/model/vessel_thrust.rs checks the adjoint built on it against Dual64 and central
/// differences.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ThrustDrive {
    /// 1/M = 1/(m + m_a) \[1/kg\].
    pub inv_mass: f64,
    /// c \[N·s/m\].
    pub damping: f64,
    /// k \[N/m\], the station keeping's stiffness.
    pub stiffness: f64,
}

/// The cotangents of one reverse step of [`ThrustDrive`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ThrustDriveBar<D> {
    /// (Z̄_k, Ż̄_k).
    pub target: [D; 2],
    /// (F̄_k, F̄_{k+1}): contributions to the thrusts' cotangents.
    pub controls: (D, D),
}

impl ThrustDrive {
    /// The drive of a thrust actuator.
    pub fn new(thrust: &crate::scene::Thrust) -> Self {
        ThrustDrive {
            inv_mass: 1.0 / (thrust.mass + thrust.added_mass),
            damping: thrust.damping,
            stiffness: thrust.stiffness,
        }
    }

    /// (h/(2M), h c/(2M)).
    fn factors(&self, h: f64) -> (f64, f64) {
        let a = 0.5 * h * self.inv_mass;
        (a, a * self.damping)
    }

    /// First half: (Z_{k+1}, v_{k+½}) from the target (Z_k, Ż_k), the prescribed part
    /// (P_k, Ṗ_k) at t_k and P_{k+1} at t_{k+1}, and F_k (type docs).
    pub fn first_half<D: Scalar>(
        &self,
        [z, zd]: [D; 2],
        (prescribed, p_next): ([D; 2], D),
        f_k: D,
        h: f64,
    ) -> (D, D) {
        let (a, b) = self.factors(h);
        let x = z - prescribed[0];
        let v_half = (zd - prescribed[1] + (f_k - x * self.stiffness) * a) * (1.0 / (1.0 + b));
        let x_next = x + v_half * h;
        (x_next + p_next, v_half)
    }

    /// Second half: Ż_{k+1} = Ṗ_{k+1} + v_{k+½}(1 − h c/(2M)) + h/(2M) (F_{k+1} − k x_{k+1}),
    /// with x_{k+1} = Z_{k+1} − P_{k+1} (`next`: (Z_{k+1}, P_{k+1}, Ṗ_{k+1})).
    pub fn second_half<D: Scalar>(
        &self,
        v_half: D,
        (z_next, p_next, pdot_next): (D, D, D),
        f_k1: D,
        h: f64,
    ) -> D {
        let (a, b) = self.factors(h);
        let x_next = z_next - p_next;
        v_half * (1.0 - b) + (f_k1 - x_next * self.stiffness) * a + pdot_next
    }

    /// The derivative of one step's (Z_{k+1}, Ż_{k+1}) with respect to the vessel's mean
    /// offset Z₀ at fixed (Z_k, Ż_k, F): the prescribed part P = ρ(t)(Z₀ + d_z X_w) enters
    /// with ∂P/∂Z₀ = ρ, ∂Ṗ/∂Z₀ = ρ̇ (`ramp_k` = (ρ, ρ̇) at t_k, `ramp_next` at t_{k+1}), and
    /// x = Z − P with ∂x_k/∂Z₀ = −ρ_k (a = h/(2M), b = h c/(2M), k the station keeping):
    /// ```text
    /// ∂v_{k+½}/∂Z₀ = (−ρ̇_k + a k ρ_k) / (1 + b),
    /// ∂Z_{k+1}/∂Z₀ = ρ_{k+1} − ρ_k + h ∂v_{k+½}/∂Z₀,
    /// ∂Ż_{k+1}/∂Z₀ = ρ̇_{k+1} + (1 − b) ∂v_{k+½}/∂Z₀ − a k (∂Z_{k+1}/∂Z₀ − ρ_{k+1}).
    /// ```
    pub fn offset_derivative(&self, ramp_k: (f64, f64), ramp_next: (f64, f64), h: f64) -> [f64; 2] {
        let (a, b) = self.factors(h);
        let k = self.stiffness;
        let dv = (-ramp_k.1 + a * k * ramp_k.0) / (1.0 + b);
        let dz = ramp_next.0 - ramp_k.0 + h * dv;
        [
            dz,
            ramp_next.1 + (1.0 - b) * dv - a * k * (dz - ramp_next.0),
        ]
    }

    /// The transpose of one step (Z_k, Ż_k, F_k, F_{k+1}) ↦ (Z_{k+1}, Ż_{k+1}) applied to
    /// (Z̄_{k+1}, Ż̄_{k+1}) (a = h/(2M), b = h c/(2M)): X̄ = Z̄_{k+1} − a k Ż̄_{k+1},
    /// v̄_{k+½} = (1 − b) Ż̄_{k+1} + h X̄, Ż̄_k = v̄_{k+½}/(1 + b), Z̄_k = X̄ − a k Ż̄_k,
    /// F̄_k = a Ż̄_k, F̄_{k+1} = a Ż̄_{k+1} (k = 0: Z̄_k = Z̄_{k+1}).
    pub fn reverse<D: Scalar>(&self, [z_bar, zd_bar]: [D; 2], h: f64) -> ThrustDriveBar<D> {
        let (a, b) = self.factors(h);
        let x_bar = z_bar - zd_bar * (a * self.stiffness);
        let v_half_bar = zd_bar * (1.0 - b) + x_bar * h;
        let zd_k_bar = v_half_bar * (1.0 / (1.0 + b));
        ThrustDriveBar {
            target: [x_bar - zd_k_bar * (a * self.stiffness), zd_k_bar],
            controls: (zd_k_bar * a, zd_bar * a),
        }
    }
}

/// The wave-frequency surge d_z X_w(t) of a vessel with a RAO in a sea.
#[derive(Clone, Debug)]
struct WaveSurge {
    sea: Arc<Sea>,
    /// d_z Hⱼ aⱼ e^{iφⱼ}: X_w's complex amplitudes along z.
    amplitude: Vec<Complex<f64>>,
    /// iωⱼ times `amplitude`: Ẋ_w's.
    rate: Vec<Complex<f64>>,
    /// (X_w, Ẋ_w) at tₖ = k h, k = 0..rows (shared by a forecast's copies).
    record: Arc<[[f64; 2]]>,
    /// A forecast's error (ΔX_w, ΔẊ_w) at the grid times first..first + len, added to the
    /// motion between them by linear interpolation ([`VesselMotion::surge_window`]).
    forecast: Option<(usize, Vec<[f64; 2]>)>,
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
                // Only the run's rows (a pruned transform when that is cheaper: a short run of a
                // wave scene does not pay for the sea's whole repeat period).
                let mut plan = sea.synthesis_rows(1, rows);
                sea.synthesize((&amplitude, &rate), rows, &mut plan, |k, x, v| {
                    record[k] = [x, v];
                });
                Some(WaveSurge {
                    sea,
                    amplitude,
                    rate,
                    record: record.into(),
                    forecast: None,
                })
            }
            _ => None,
        };
        Ok(VesselMotion {
            vessel: vessel.clone(),
            waves,
            thrust: vessel.thrust().as_ref().map(ThrustDrive::new),
            offset_held: false,
        })
    }

    /// The same motion with the mean offset held in full from t = 0 (`held`, the static start
    /// `[time] initial = "static"`): Z(t) = Z₀ + ρ(t) d_z X_w(t), the ramp bringing in only the
    /// wave-frequency surge; `false` keeps Z(t) = ρ(t)(Z₀ + d_z X_w(t)).
    pub fn holding_offset(mut self, held: bool) -> Self {
        self.offset_held = held;
        self
    }

    /// The factor of the mean offset in Z(t) and its rate, (ρ(t), ρ̇(t)), or (1, 0) when the
    /// offset is held in full ([`VesselMotion::holding_offset`]): ∂Z/∂Z₀ and ∂Ż/∂Z₀.
    pub fn offset_ramp(&self, t: f64) -> (f64, f64) {
        if self.offset_held {
            (1.0, 0.0)
        } else {
            self.vessel.ramp_factor(t)
        }
    }

    /// The vessel's description.
    pub fn vessel(&self) -> &Vessel {
        &self.vessel
    }

    /// (Z(t), Ż(t)): the top's prescribed z and its rate (module docs), with the offset held
    /// in full for a static start: Z(t) = Z₀ + ρ(t) X (X = d_z X_w(t)).
    pub fn at(&self, t: f64) -> [f64; 2] {
        let (rho, rho_dot) = self.vessel.ramp_factor(t);
        let [x, v] = match &self.waves {
            Some(w) => w.at(t),
            None => [0.0; 2],
        };
        if self.offset_held {
            return [self.vessel.offset + rho * x, rho_dot * x + rho * v];
        }
        let z = self.vessel.offset + x;
        [rho * z, rho_dot * z + rho * v]
    }

    /// The thrust drive of a vessel whose control is its thrust, `None` for a prescribed top.
    pub fn thrust(&self) -> Option<&ThrustDrive> {
        self.thrust.as_ref()
    }

    /// The complex amplitudes d_z Hⱼ aⱼ e^{iφⱼ} of the wave-frequency surge X_w(t) = Re Σⱼ
    /// Xⱼ e^{iωⱼ t} over the sea's components (`None` without waves or a RAO).
    pub fn surge_amplitudes(&self) -> Option<&[Complex<f64>]> {
        self.waves.as_ref().map(|w| w.amplitude.as_slice())
    }

    /// The grid step of the surge's record \[s\] (the sea's step; `None` without waves or a
    /// RAO).
    pub fn surge_step(&self) -> Option<f64> {
        self.waves.as_ref().map(|w| w.sea.step())
    }

    /// A copy whose wave-frequency surge has `add` (ΔX_w, ΔẊ_w) at the grid times
    /// `first..first + add.len()` added, linearly interpolated between them (the true motion
    /// as before, from the record or the direct sum, plus the interpolated error; outside the
    /// window the true motion). The vessel's motion in a forecast with errors ([`crate::mpc`],
    /// "What the plan knows"); an `add` of zeros gives the true motion bit for bit.
    ///
    /// # Errors
    /// [`SeaError::Invalid`] naming `window` when the motion has no wave-frequency surge or
    /// `add` has fewer than 2 times.
    pub fn surge_window(&self, first: usize, add: &[[f64; 2]]) -> Result<Self, SeaError> {
        let refuse = || SeaError::Invalid {
            quantity: "window",
            value: first as f64,
            expected: "a vessel with a wave-frequency surge and at least 2 grid times",
        };
        let w = self.waves.as_ref().ok_or_else(refuse)?;
        if add.len() < 2 {
            return Err(refuse());
        }
        Ok(VesselMotion {
            vessel: self.vessel.clone(),
            waves: Some(WaveSurge {
                sea: w.sea.clone(),
                amplitude: w.amplitude.clone(),
                rate: w.rate.clone(),
                record: w.record.clone(),
                forecast: Some((first, add.to_vec())),
            }),
            thrust: self.thrust,
            offset_held: self.offset_held,
        })
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
        // On the grid (the step's times t₀ + (k + 1) h), to within 10⁻⁹ of a step as the wave
        // field reads its record ([`crate::model::WaveField::at`]): the record. A plan's times
        // t_start + j h differ from the grid time k h by round-off only, and the direct sum would
        // cost its N sines and cosines at every step of every plan.
        let on_grid = (t / h - k).abs() <= 1e-9;
        let truth = if k >= 0.0 && (k as usize) < self.record.len() && on_grid {
            self.record[k as usize]
        } else {
            [
                self.sea.sum_at(&self.amplitude, t),
                self.sea.sum_at(&self.rate, t),
            ]
        };
        let Some((first, add)) = &self.forecast else {
            return truth;
        };
        let s = t / h;
        if s < 0.0 {
            return truth;
        }
        let j0 = s.floor();
        let x = s - j0;
        let j = (j0 as usize).wrapping_sub(*first);
        if j < add.len() && j + 1 < add.len() {
            let (a, b) = (add[j], add[j + 1]);
            return [
                truth[0] + (a[0] + x * (b[0] - a[0])),
                truth[1] + (a[1] + x * (b[1] - a[1])),
            ];
        }
        if j < add.len() && x <= 1e-9 {
            return [truth[0] + add[j][0], truth[1] + add[j][1]];
        }
        truth
    }
}
