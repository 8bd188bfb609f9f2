//! Irregular waves (`[loads.waves]`, docs/scene-format.md): the sea state of a scene, its file
//! form and its validation. The realisation and the kinematics are [`crate::ocean`]'s; the
//! loads they give are [`crate::model::WaveInertia`] and the drag relative to the water
//! ([`crate::model::CurrentDrag`]).

use serde::{Deserialize, Serialize};

use super::validate::check_finite;
use super::{Scene, SceneError, SceneErrorKind};
use crate::ocean::{Sea, SeaError, SeaSpec, Spectrum, SpectrumKind};

/// The default JONSWAP peak-enhancement factor γ (the North Sea mean, DNV-RP-C205 §3.5.5).
pub const DEFAULT_GAMMA: f64 = 3.3;

/// The spectral shape of `[loads.waves] spectrum`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum WaveSpectrum {
    /// `"jonswap"`: DNV-RP-C205 eq. 3.5.6.
    Jonswap,
    /// `"pierson-moskowitz"`: DNV-RP-C205 eq. 3.5.5.
    PiersonMoskowitz,
}

/// How the waves' kinematics are lumped onto the nodes (`[loads.waves] lumping`,
/// docs/conventions.md "Waves on the chain").
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum WaveLumping {
    /// `"node"` (default): the Airy velocity at the node's height y_k.
    #[default]
    Node,
    /// `"cell"`: the Airy velocity averaged exactly over the node's cell
    /// [y_k − l_k/2, y_k + l_{k+1}/2] (the half cell [y_n − l_n/2, y_n] at the tip), the cell of
    /// its lumped mass ([`crate::ocean::cell_profile`]): the distributed Morison loads
    /// integrated over each cell instead of sampled at its node.
    Cell,
}

/// An irregular sea state (`[loads.waves]`, docs/ocean.md "Irregular seas"): a spectrum given by
/// H_s and T_p, a
/// mean direction and a seeded realisation. The water depth is `[water] depth`
/// ([`Scene::wave_depth`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Waves {
    /// The spectral shape.
    pub spectrum: WaveSpectrum,
    /// Significant wave height H_s \[m\] (> 0).
    pub hs: f64,
    /// Peak period T_p \[s\] (> 0).
    pub tp: f64,
    /// JONSWAP peak-enhancement factor γ in [1, 10] (`None`: [`DEFAULT_GAMMA`]; not allowed
    /// with Pierson-Moskowitz).
    pub gamma: Option<f64>,
    /// The seed of the phases (crate::ocean's module docs say what it promises).
    pub seed: u64,
    /// Mean direction \[degrees\] in the horizontal (x, z) plane, from +z toward +x (default 0:
    /// the waves travel along +z).
    pub direction: f64,
    /// Number of components N (`None`: enough that the sea repeats only after
    /// max(3 h, the simulated duration)).
    pub components: Option<usize>,
    /// How the kinematics are lumped onto the nodes (default [`WaveLumping::Node`]).
    pub lumping: WaveLumping,
    /// The time step \[s\] of the wave record, a whole multiple r h of `time.step` (`None`: h,
    /// every step). With r > 1 the model keeps the kinematics and their time derivatives every
    /// r steps and reads them by cubic Hermite interpolation ([`crate::model::WaveField`]): r/2
    /// times less memory, an error below (r h)⁴/384 · Σⱼ |Xⱼ| ωⱼ⁴ on a series Re Σⱼ Xⱼ e^{iωⱼ t}.
    pub record_step: Option<f64>,
}

impl Waves {
    /// A JONSWAP sea (γ = 3.3) of H_s `hs` and T_p `tp`, seed 0, direction 0.
    pub fn jonswap(hs: f64, tp: f64) -> Self {
        Waves {
            spectrum: WaveSpectrum::Jonswap,
            hs,
            tp,
            gamma: None,
            seed: 0,
            direction: 0.0,
            components: None,
            lumping: WaveLumping::Node,
            record_step: None,
        }
    }

    /// The record's stride r = `record_step`/h for a time step h (1 without `record_step`).
    ///
    /// # Errors
    /// [`SceneErrorKind::InvalidValue`] naming `loads.waves.record_step` unless it is a whole
    /// multiple r h of h with 1 ≤ r ≤ [`super::MAX_STEPS`] (to 1e-9 relative).
    pub fn record_stride(&self, step: f64) -> Result<usize, SceneError> {
        let Some(x) = self.record_step else {
            return Ok(1);
        };
        let r = x / step;
        let whole = r.round();
        if (1.0..=super::MAX_STEPS as f64).contains(&whole) && (r - whole).abs() <= 1e-9 * whole {
            return Ok(whole as usize);
        }
        Err(SceneError::invalid(
            "loads.waves.record_step",
            format!(
                "must be a whole multiple r·h of time.step h = {step} s with r in 1..={} (the \
                 record is read at every step by interpolation between its times), got {x} s \
                 ({r} steps)",
                super::MAX_STEPS
            ),
        ))
    }

    /// `record_step` for another time step h: the largest whole multiple of h not above it, at
    /// least h (unchanged without `record_step`). For scenes derived with a new `time.step` (a
    /// planning model, a convergence study).
    pub fn fit_record_step(&mut self, step: f64) {
        if let Some(x) = self.record_step {
            let r = (x / step * (1.0 + 1e-9)).floor().max(1.0);
            self.record_step = Some(r * step);
        }
    }

    /// The spectrum S(ω).
    ///
    /// # Errors
    /// [`SceneErrorKind::InvalidValue`] naming `loads.waves.hs`, `.tp` or `.gamma`.
    pub fn spectrum(&self) -> Result<Spectrum, SceneError> {
        let kind = match (self.spectrum, self.gamma) {
            (WaveSpectrum::Jonswap, g) => SpectrumKind::Jonswap {
                gamma: g.unwrap_or(DEFAULT_GAMMA),
            },
            (WaveSpectrum::PiersonMoskowitz, None) => SpectrumKind::PiersonMoskowitz,
            (WaveSpectrum::PiersonMoskowitz, Some(_)) => {
                return Err(SceneError::new(SceneErrorKind::ExclusiveKeys {
                    key: "loads.waves.gamma".to_string(),
                    other: "loads.waves.spectrum".to_string(),
                    note: "γ is JONSWAP's peak enhancement; a Pierson-Moskowitz sea has none \
                           (it is JONSWAP with γ = 1)"
                        .to_string(),
                }))
            }
        };
        Spectrum::new(kind, self.hs, self.tp).map_err(|e| sea_error(e, None))
    }

    /// What [`crate::ocean::Sea::new`] realises, in water of depth `depth` \[m\].
    ///
    /// # Errors
    /// As [`Waves::spectrum`].
    pub fn sea_spec(&self, depth: f64) -> Result<SeaSpec, SceneError> {
        let mut spec = SeaSpec::new(self.spectrum()?, depth, self.seed);
        spec.direction_deg = self.direction;
        spec.components = self.components;
        Ok(spec)
    }

    /// The direction's unit vector (d_x, d_z) in the transverse plane (exact at multiples of
    /// 90°, as a current's: [`super::direction_of_angle`]).
    pub fn unit_direction(&self) -> [f64; 2] {
        super::direction_of_angle(self.direction)
    }

    /// The rules of docs/scene-format.md, `[loads.waves]`, and the realisation's size for
    /// `scene`'s time grid.
    pub(super) fn check(&self, scene: &Scene) -> Result<(), SceneError> {
        check_finite("loads.waves.direction", self.direction)?;
        if scene.pipe.is_none() && scene.stackup.is_none() {
            return Err(SceneError::new(SceneErrorKind::MissingKey {
                key: "pipe".to_string(),
                note: Some(
                    "`[loads.waves]` needs the pipe's outer diameter and added-mass \
                     coefficient for the wave inertia load ρ_w (1 + C_a) A_o l u̇ (or a \
                     `[stackup]`)"
                        .to_string(),
                ),
            }));
        }
        let spec = self.sea_spec(scene.wave_depth())?;
        let t = scene.time;
        // The realisation's size, checked without realising it (the model realises it once).
        let plan = Sea::plan(&spec, t.step, t.steps as f64 * t.step)
            .map_err(|e| sea_error(e, self.components))?;
        let every = self.record_stride(t.step)?;
        // The record: two series per pendulum and the elevation, steps + 1 rows; with a record
        // step r h > h, each with its derivative, ⌈steps/r⌉ + 1 rows.
        let (rows, width) = if every == 1 {
            (t.steps as u64 + 1, 2 * scene.n() as u64 + 1)
        } else {
            (t.steps.div_ceil(every) as u64 + 1, 4 * scene.n() as u64 + 2)
        };
        let bytes = rows.saturating_mul(width).saturating_mul(8);
        if bytes > crate::ocean::waves::MAX_RECORD_BYTES {
            let hint = if self.record_step.is_some() {
                "; use fewer steps or pendulums, or a longer `loads.waves.record_step`"
            } else {
                "; use fewer steps or pendulums, or a `loads.waves.record_step` of several steps"
            };
            return Err(SceneError::invalid(
                "time.steps",
                format!(
                    "the wave record of {rows} times × {} pendulums needs {bytes} bytes, over \
                     the limit of {}{hint}",
                    scene.n(),
                    crate::ocean::waves::MAX_RECORD_BYTES
                ),
            ));
        }
        // The model's amplitudes: two complex values per pendulum and component.
        let nc = plan.components as u64;
        let amp_bytes = (scene.n() as u64).saturating_mul(nc).saturating_mul(32);
        if amp_bytes > crate::ocean::waves::MAX_RECORD_BYTES {
            let key = if self.components.is_some() {
                "loads.waves.components"
            } else {
                "loads.waves.tp"
            };
            return Err(SceneError::invalid(
                key,
                format!(
                    "the waves' amplitudes of {} pendulums × {nc} components need {amp_bytes} \
                     bytes, over the limit of {}; use fewer pendulums or components (by default \
                     ⌊6 T_r/T_p⌋), or a longer peak period",
                    scene.n(),
                    crate::ocean::waves::MAX_RECORD_BYTES
                ),
            ));
        }
        Ok(())
    }
}

/// A [`SeaError`] as a scene error naming its key (`components`: the scene's
/// `loads.waves.components`): `loads.waves.<quantity>` for the sea's own
/// quantities, `water.depth`, `time.step`; a too large FFT names `loads.waves.components` when
/// it was given, `time.step` otherwise; too many default components name `loads.waves.tp` (the
/// count is ⌊6 T_r/T_p⌋).
pub fn sea_error(e: SeaError, components: Option<usize>) -> SceneError {
    match e {
        SeaError::Invalid {
            quantity,
            value,
            expected,
        } => {
            let key = match quantity {
                "depth" => "water.depth".to_string(),
                "step" => "time.step".to_string(),
                "duration" => "time.steps".to_string(),
                q => format!("loads.waves.{q}"),
            };
            SceneError::invalid(key, format!("must be {expected}, got {value}"))
        }
        e @ SeaError::TooManyComponents { .. } => {
            SceneError::invalid("loads.waves.tp", e.to_string())
        }
        e @ SeaError::TooLarge { .. } => {
            let key = if components.is_some() {
                "loads.waves.components"
            } else {
                "time.step"
            };
            SceneError::invalid(key, e.to_string())
        }
    }
}

/// `[loads.waves]` as written in a file.
#[derive(Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RawWaves {
    spectrum: WaveSpectrum,
    hs: f64,
    tp: f64,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    gamma: Option<f64>,
    #[serde(default)]
    seed: i64,
    #[serde(default, skip_serializing_if = "is_positive_zero")]
    direction: f64,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    components: Option<i64>,
    #[serde(default, skip_serializing_if = "is_node")]
    lumping: WaveLumping,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    record_step: Option<f64>,
}

fn is_node(l: &WaveLumping) -> bool {
    *l == WaveLumping::Node
}

fn is_positive_zero(x: &f64) -> bool {
    x.to_bits() == 0
}

impl RawWaves {
    pub(super) fn from_waves(w: &Waves) -> Self {
        RawWaves {
            spectrum: w.spectrum,
            hs: w.hs,
            tp: w.tp,
            gamma: w.gamma,
            seed: i64::try_from(w.seed).unwrap_or(i64::MAX),
            direction: w.direction,
            components: w.components.map(|c| i64::try_from(c).unwrap_or(i64::MAX)),
            lumping: w.lumping,
            record_step: w.record_step,
        }
    }

    pub(super) fn into_waves(self) -> Result<Waves, SceneError> {
        let seed = u64::try_from(self.seed).map_err(|_| {
            SceneError::invalid(
                "loads.waves.seed",
                format!("must be a non-negative integer, got {}", self.seed),
            )
        })?;
        let components = match self.components {
            None => None,
            Some(c) => Some(
                usize::try_from(c)
                    .ok()
                    .filter(|c| (1..=crate::ocean::waves::MAX_COMPONENTS).contains(c))
                    .ok_or_else(|| {
                        SceneError::invalid(
                            "loads.waves.components",
                            format!(
                                "must be an integer in 1..={}, got {c}",
                                crate::ocean::waves::MAX_COMPONENTS
                            ),
                        )
                    })?,
            ),
        };
        Ok(Waves {
            spectrum: self.spectrum,
            hs: self.hs,
            tp: self.tp,
            gamma: self.gamma,
            seed,
            direction: self.direction,
            components,
            lumping: self.lumping,
            record_step: self.record_step,
        })
    }
}

impl Scene {
    /// The surface elevation η(0, t_k) \[m\] at x = z = 0 of the scene's waves at every time of
    /// its grid, k = 0..=N (`None` without `[loads.waves]`), by one inverse FFT: the same sea,
    /// bit for bit, as the model's ([`crate::model::WaveField::elevation`]).
    ///
    /// # Errors
    /// The waves' [`SceneError`]s (see [`Waves::spectrum`]; the scene is normally validated).
    pub fn wave_elevation(&self) -> Result<Option<Vec<f64>>, SceneError> {
        let Some(w) = &self.loads.waves else {
            return Ok(None);
        };
        let spec = w.sea_spec(self.wave_depth())?;
        let t = self.time;
        let sea = Sea::new(&spec, t.step, t.steps as f64 * t.step)
            .map_err(|e| sea_error(e, w.components))?;
        let record = sea
            .record(&[], t.steps)
            .map_err(|e| sea_error(e, w.components))?;
        Ok(Some(record.elevations().to_vec()))
    }
}
