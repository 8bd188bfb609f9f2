//! The vessel that holds the riser's top (`support = "vessel"`, `[vessel]`; docs/scene-format.md
//! "[vessel]", docs/conventions.md "A top held by the vessel").
//!
//! A drilling riser hangs from a vessel that holds its top within metres: the top node's lateral
//! position is the vessel's, not a free end. The top follows
//!
//! ```text
//! Z(t) = ρ(t) (Z₀ + d_z X_w(t)),   X_w(t) = Re Σⱼ H(ωⱼ) aⱼ e^{i(ωⱼ t + φⱼ)}
//! ```
//!
//! with Z₀ the mean offset (`offset`), X_w the wave-frequency surge, the response amplitude
//! operator H(ω) = A(ω) e^{iψ(ω)} (`[vessel.rao]`) applied to each component aⱼ e^{iφⱼ} of the
//! scene's own sea (`[loads.waves]`, the same phases, the elevation at the riser's top), d_z the
//! waves' direction along z, and ρ(t) = ½(1 − cos(π t/T_ramp)) for t < T_ramp (1 after it), the
//! ramp that starts the vessel from the straight riser at rest (`ramp`). The upper flex joint is
//! the tip spring k_{n+1} (`[beam] tip_stiffness`), between the top pendulum and the vessel's
//! vertical; the tensioner's tension is `[loads] tension`.

use serde::{Deserialize, Serialize};

use super::error::SceneError;

/// The most rows a `[vessel.rao]` table may have.
pub const MAX_RAO_ROWS: usize = 100_000;

/// Default ramp time T_ramp \[s\] of the vessel's motion.
pub const DEFAULT_VESSEL_RAMP: f64 = 20.0;

/// The vessel at the top (`[vessel]`).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Vessel {
    /// Mean offset Z₀ of the top from above the wellhead, along z \[m\] (default 0).
    #[serde(default)]
    pub offset: f64,
    /// Ramp time T_ramp \[s\] over which the motion (offset and waves) grows from 0 (default
    /// [`DEFAULT_VESSEL_RAMP`]; 0: none, which needs a motion that starts at rest at the
    /// straight riser).
    #[serde(default = "default_ramp")]
    pub ramp: f64,
    /// The surge response amplitude operator; `None`: the vessel does not move with the waves.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub rao: Option<Rao>,
    /// The vessel's mass m \[kg\] (the thrust actuator, [`Thrust`]; default
    /// [`DEFAULT_VESSEL_MASS`] when another thrust key is given).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub mass: Option<f64>,
    /// The surge added mass m_a \[kg\] (default [`DEFAULT_VESSEL_ADDED_MASS`]).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub added_mass: Option<f64>,
    /// The linear surge damping c \[N·s/m\] (default [`DEFAULT_VESSEL_DAMPING`]).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub damping: Option<f64>,
    /// The thrust bound F_max \[N\]: |F| ≤ F_max (default [`DEFAULT_THRUST_BOUND`]).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub thrust_bound: Option<f64>,
    /// The thrust rate bound Ḟ_max \[N/s\]: |dF/dt| ≤ Ḟ_max (default
    /// [`DEFAULT_THRUST_RATE_BOUND`]).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub thrust_rate_bound: Option<f64>,
    /// The station-keeping stiffness k \[N/m\] of the vessel's dynamic positioning: the
    /// position loop that holds the vessel over its mean offset, (m + m_a) ẍ_v = F − c ẋ_v −
    /// k x_v ([`Thrust`]; default 0: no station keeping, the vessel drifts under a constant
    /// thrust).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub position_stiffness: Option<f64>,
}

/// Default vessel mass m \[kg\]: a deepwater drillship's displacement, about 10⁵ t
/// (docs/scene-format.md "\[vessel\]" cites the magnitudes).
pub const DEFAULT_VESSEL_MASS: f64 = 1.0e8;
/// Default surge added mass m_a \[kg\]: 5 % of the default mass (a ship's surge added mass is a
/// few per cent of its displacement).
pub const DEFAULT_VESSEL_ADDED_MASS: f64 = 5.0e6;
/// Default linear surge damping c \[N·s/m\]: (m + m_a)/c = 150 s, the slow surge time constant
/// of a dynamically positioned vessel.
pub const DEFAULT_VESSEL_DAMPING: f64 = 7.0e5;
/// Default thrust bound F_max \[N\]: the surge thrust of six azimuth thrusters of about 5 MW.
pub const DEFAULT_THRUST_BOUND: f64 = 3.0e6;
/// Default thrust rate bound Ḟ_max \[N/s\]: full thrust reached in 15 s.
pub const DEFAULT_THRUST_RATE_BOUND: f64 = 2.0e5;

/// The thrust actuator of a vessel (`[vessel]` `mass`, `added_mass`, `damping`, `thrust_bound`,
/// `thrust_rate_bound`; docs/conventions.md "The vessel as the actuator"): the control is the
/// thrust F on the vessel, whose low-frequency surge x_v obeys
///
/// ```text
/// (m + m_a) ẍ_v = F − c ẋ_v − k x_v,     |F| ≤ F_max,   |dF/dt| ≤ Ḟ_max,
/// ```
///
/// (k the station keeping of its dynamic positioning, `position_stiffness`: a constant thrust
/// F then moves the vessel by F/k and it settles there; with k = 0 it drifts at F/c) and the top
/// follows Z(t) = ρ(t)(Z₀ + d_z X_w(t)) + x_v(t).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Thrust {
    /// m \[kg\].
    pub mass: f64,
    /// m_a \[kg\].
    pub added_mass: f64,
    /// c \[N·s/m\].
    pub damping: f64,
    /// F_max \[N\].
    pub bound: f64,
    /// Ḟ_max \[N/s\].
    pub rate_bound: f64,
    /// k \[N/m\]: the station keeping's stiffness (0: none).
    pub stiffness: f64,
}

fn default_ramp() -> f64 {
    DEFAULT_VESSEL_RAMP
}

impl Default for Vessel {
    fn default() -> Self {
        Vessel {
            offset: 0.0,
            ramp: DEFAULT_VESSEL_RAMP,
            rao: None,
            mass: None,
            added_mass: None,
            damping: None,
            thrust_bound: None,
            thrust_rate_bound: None,
            position_stiffness: None,
        }
    }
}

/// A surge RAO as a table (`[vessel.rao]`): at wave period Tᵢ the vessel's surge has the
/// amplitude Aᵢ per metre of wave amplitude and leads the wave elevation at the riser's top by
/// the phase ψᵢ. Between rows A and ψ are interpolated linearly in the period; outside the table
/// they keep the nearest row's values. (In long waves a floating vessel moves with the water:
/// A → 1 and ψ → −90°, the horizontal displacement of a surface particle, a quarter period
/// behind the elevation; a table should reach periods where that holds.)
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Rao {
    /// Wave periods Tᵢ \[s\], strictly increasing.
    pub period: Vec<f64>,
    /// Surge amplitude per wave amplitude Aᵢ \[m/m\], non-negative.
    pub amplitude: Vec<f64>,
    /// Phase lead ψᵢ of the surge over the elevation \[degrees\].
    pub phase: Vec<f64>,
}

impl Rao {
    /// H(ω) = A(ω) e^{iψ(ω)} at angular frequency ω \[rad/s\] (period 2π/ω), as (Re H, Im H).
    pub fn transfer(&self, omega: f64) -> [f64; 2] {
        let t = 2.0 * std::f64::consts::PI / omega;
        let p = &self.period;
        let last = p.len() - 1;
        let (a, psi) = if t <= p[0] {
            (self.amplitude[0], self.phase[0])
        } else if t >= p[last] {
            (self.amplitude[last], self.phase[last])
        } else {
            let i = p.partition_point(|&x| x <= t) - 1;
            let s = (t - p[i]) / (p[i + 1] - p[i]);
            let lerp = |v: &[f64]| v[i] + s * (v[i + 1] - v[i]);
            (lerp(&self.amplitude), lerp(&self.phase))
        };
        let r = psi.to_radians();
        [a * r.cos(), a * r.sin()]
    }

    /// Checks the table: 1..=[`MAX_RAO_ROWS`] rows, three columns of one length, periods
    /// positive, finite and strictly increasing, amplitudes finite and non-negative, phases finite.
    ///
    /// # Errors
    /// [`SceneError`] naming `vessel.rao.period`, `vessel.rao.amplitude` or `vessel.rao.phase`.
    pub fn check(&self) -> Result<(), SceneError> {
        let rows = self.period.len();
        if rows == 0 || rows > MAX_RAO_ROWS {
            return Err(SceneError::invalid(
                "vessel.rao.period",
                format!("must have 1 to {MAX_RAO_ROWS} rows, got {rows}"),
            ));
        }
        for (key, len) in [
            ("vessel.rao.amplitude", self.amplitude.len()),
            ("vessel.rao.phase", self.phase.len()),
        ] {
            if len != rows {
                return Err(SceneError::invalid(
                    key,
                    format!("must have one value per period ({rows}), got {len}"),
                ));
            }
        }
        for (i, &t) in self.period.iter().enumerate() {
            let increasing = i == 0 || t > self.period[i - 1];
            if !(t.is_finite() && t > 0.0 && increasing) {
                return Err(SceneError::invalid(
                    "vessel.rao.period",
                    format!(
                        "must be positive, finite and strictly increasing [s], got {t} at row {}",
                        i + 1
                    ),
                ));
            }
        }
        if let Some((i, a)) = self
            .amplitude
            .iter()
            .enumerate()
            .find(|(_, a)| !(a.is_finite() && **a >= 0.0))
        {
            return Err(SceneError::invalid(
                "vessel.rao.amplitude",
                format!(
                    "must be finite and non-negative [m/m], got {a} at row {}",
                    i + 1
                ),
            ));
        }
        if let Some((i, p)) = self.phase.iter().enumerate().find(|(_, p)| !p.is_finite()) {
            return Err(SceneError::invalid(
                "vessel.rao.phase",
                format!("must be finite [degrees], got {p} at row {}", i + 1),
            ));
        }
        Ok(())
    }
}

impl Vessel {
    /// The ramp factor ρ(t) = ½(1 − cos(π t/T_ramp)) and its rate ρ̇(t) (module docs).
    pub fn ramp_factor(&self, t: f64) -> (f64, f64) {
        if self.ramp > 0.0 && t < self.ramp {
            let s = std::f64::consts::PI / self.ramp;
            let x = s * t.max(0.0);
            (0.5 * (1.0 - x.cos()), 0.5 * s * x.sin())
        } else {
            (1.0, 0.0)
        }
    }

    /// The thrust actuator, when any of its keys is given (the others take their defaults);
    /// `None`: the top is prescribed (offset, ramp and RAO only) and a control is a force on the
    /// riser, as before these keys existed.
    pub fn thrust(&self) -> Option<Thrust> {
        let keys = [
            self.mass,
            self.added_mass,
            self.damping,
            self.thrust_bound,
            self.thrust_rate_bound,
            self.position_stiffness,
        ];
        keys.iter().any(Option::is_some).then(|| Thrust {
            mass: self.mass.unwrap_or(DEFAULT_VESSEL_MASS),
            added_mass: self.added_mass.unwrap_or(DEFAULT_VESSEL_ADDED_MASS),
            damping: self.damping.unwrap_or(DEFAULT_VESSEL_DAMPING),
            bound: self.thrust_bound.unwrap_or(DEFAULT_THRUST_BOUND),
            rate_bound: self.thrust_rate_bound.unwrap_or(DEFAULT_THRUST_RATE_BOUND),
            stiffness: self.position_stiffness.unwrap_or(0.0),
        })
    }

    /// Checks `offset` (finite), `ramp` (finite, non-negative), the RAO and the thrust keys
    /// (`mass` positive, `added_mass` and `damping` non-negative, `thrust_bound` and
    /// `thrust_rate_bound` positive; all finite).
    ///
    /// # Errors
    /// [`SceneError`] naming the `vessel.*` key.
    pub fn check(&self) -> Result<(), SceneError> {
        self.check_for(super::Initial::Rest)
    }

    /// [`Vessel::check`] for a run that starts from `initial` (`[time] initial`): from the
    /// static equilibrium the offset is held from t = 0, so `ramp` = 0 needs only no RAO.
    ///
    /// # Errors
    /// As [`Vessel::check`].
    pub fn check_for(&self, initial: super::Initial) -> Result<(), SceneError> {
        if !self.offset.is_finite() {
            return Err(SceneError::invalid(
                "vessel.offset",
                format!("must be finite [m], got {}", self.offset),
            ));
        }
        if !(self.ramp.is_finite() && self.ramp >= 0.0) {
            return Err(SceneError::invalid(
                "vessel.ramp",
                format!("must be finite and non-negative [s], got {}", self.ramp),
            ));
        }
        let held = initial == super::Initial::Static;
        if self.ramp == 0.0 && ((self.offset != 0.0 && !held) || self.rao.is_some()) {
            return Err(SceneError::invalid(
                "vessel.ramp",
                if held {
                    "must be positive with a RAO: the surge starts at t = 0 on a riser at rest"
                } else {
                    "must be positive when the vessel moves (an offset or a RAO): a run from \
                     `[time] initial = \"rest\"` starts from the straight riser at rest, with the \
                     top over the wellhead"
                },
            ));
        }
        for (key, value, positive) in [
            ("vessel.mass", self.mass, true),
            ("vessel.added_mass", self.added_mass, false),
            ("vessel.damping", self.damping, false),
            ("vessel.thrust_bound", self.thrust_bound, true),
            ("vessel.thrust_rate_bound", self.thrust_rate_bound, true),
            ("vessel.position_stiffness", self.position_stiffness, false),
        ] {
            let Some(v) = value else { continue };
            let ok = v.is_finite() && if positive { v > 0.0 } else { v >= 0.0 };
            if !ok {
                let what = if positive { "positive" } else { "non-negative" };
                let unit = match key {
                    "vessel.damping" => "N·s/m",
                    "vessel.thrust_bound" => "N",
                    "vessel.thrust_rate_bound" => "N/s",
                    "vessel.position_stiffness" => "N/m",
                    _ => "kg",
                };
                return Err(SceneError::invalid(
                    key,
                    format!("must be finite and {what} [{unit}], got {v}"),
                ));
            }
        }
        match &self.rao {
            Some(r) => r.check(),
            None => Ok(()),
        }
    }
}
