//! Fatigue of the wellhead: hot-spot stress from the base moment, rainflow counting
//! (ASTM E1049-85), DNV-RP-C203 S-N curves, Miner's rule, annual damage and life, scatter
//! diagrams, and the damage's gradient with respect to the stress history (docs/fatigue.md).
//!
//! The chain of a fatigue assessment, each link its own module:
//! 1. [`HotSpot`] (`stress`): σ(t) = SCF · M_w(t) · (D_o/2)/I in MPa, M_w = M₀ · l₁/2 the
//!    wellhead moment of the chain's M₀ ([`MomentMeasure`]); in a spatial scene at several
//!    points θ around the circumference, the worst one reported.
//! 2. [`rainflow`](rainflow::rainflow) (`rainflow`): cycles of σ per ASTM E1049-85 §5.4.4,
//!    residue as half cycles, O(N) and allocation-free with a [`RainflowWorkspace`].
//! 3. [`SnCurve`] (`sn`): DNV-RP-C203 Tables 2-1 to 2-3, every class, with the thickness
//!    correction (t/t_ref)^k.
//! 4. [`miner_sum`], [`damage_per_year`], [`life_years`], [`combine_scatter`] (`miner`):
//!    D = Σ nᵢ/Nᵢ, D_y = D · Y/T, L = 1/(DFF · D_y), D_y = Σ_s p_s D_s Y/T_s.
//! 5. [`damage_gradient`] (`gradient`): ∂D/∂σ_k, non-zero at turning points only, and the smooth
//!    proxy Σ|σ_k|^m.
//!
//! [`assess`] runs 1–4 on a moment history described by a [`FatigueSpec`]; the scatter
//! diagram's cells ([`ScatterCell`], `scatter`) are plain data here. Running controllers (none,
//! the best constant force, a PD law, MPC) on every cell of a diagram and reporting damage per
//! year, life and life extension per controller is the layer above the controllers,
//! `chainbeam::fatigue_study` (`run_study`): this module knows nothing of simulation or control.
//!
//! ```
//! use chainbeam::fatigue::{assess, FatigueSpec, MomentHistory, MomentMeasure};
//! // A 0.5 m × 25 mm pipe, 1 MN·m wellhead moment amplitude at 0.1 Hz for 100 s, sampled at 0.5 s.
//! let t: Vec<f64> = (0..=200).map(|k| 0.5 * k as f64).collect();
//! let m: Vec<f64> = t.iter().map(|t| 1e6 * (0.2 * std::f64::consts::PI * t).sin()).collect();
//! let spec = FatigueSpec::new(0.5, 0.025);
//! let history = MomentHistory {
//!     duration_s: 100.0,
//!     moment: &m,
//!     moment_x: None,
//!     measure: MomentMeasure::Wellhead,
//! };
//! let a = assess(&spec, history)?;
//! assert!(a.damage > 0.0 && a.life_years.is_finite());
//! # Ok::<(), chainbeam::fatigue::FatigueError>(())
//! ```

pub mod damage;
pub mod gradient;
pub mod miner;
pub mod rainflow;
pub mod scatter;
pub mod sn;
pub mod stress;

use thiserror::Error;

pub use damage::{DamageGradient, WellheadDamage};
pub use gradient::{damage_gradient, pairing_damage, power_gradient, power_objective};
pub use miner::{
    combine_scatter, damage_per_year, life_years, miner_sum, CellDamage, ScatterDamage,
    SECONDS_PER_YEAR,
};
pub use rainflow::{rainflow, rainflow_into, rainflow_visit, Cycle, RainflowWorkspace};
pub use scatter::{ScatterCell, SeaState};
pub use sn::{DnvClass, Environment, Segment, SnCurve, DNV_REFERENCE_THICKNESS_M};
pub use stress::{HotSpot, MomentMeasure};

/// Errors of the fatigue assessment; each names the quantity (and key or index) at fault.
#[derive(Debug, Error, Clone, PartialEq)]
#[non_exhaustive]
pub enum FatigueError {
    /// A parameter of the assessment is out of range (`key` is the `[fatigue]` key).
    #[error("invalid fatigue parameter `{key}` = {value}: {reason}")]
    InvalidSpec {
        /// The `[fatigue]` key (or argument) at fault.
        key: &'static str,
        /// Its value.
        value: f64,
        /// What it must be.
        reason: &'static str,
    },
    /// A sample of a history, or a damage, is NaN or infinite (or a damage is negative).
    #[error("non-finite {quantity} at index {index}: {value}")]
    NonFinite {
        /// What is not finite (`stress`, `moment`, `damage`).
        quantity: &'static str,
        /// Index of the sample (or scatter cell).
        index: usize,
        /// The value.
        value: f64,
    },
    /// Two histories (or a history and its output buffer) have different lengths.
    #[error("length mismatch: `{what}` has {got} values, expected {expected}")]
    LengthMismatch {
        /// The array at fault.
        what: &'static str,
        /// The length it must have.
        expected: usize,
        /// Its length.
        got: usize,
    },
    /// Not a DNV-RP-C203 class name.
    #[error(
        "unknown S-N curve `{name}` (DNV-RP-C203 classes: B1, B2, C, C1, C2, D, E, F, F1, F3, \
         G, W1, W2, W3)"
    )]
    UnknownCurve {
        /// The name given.
        name: String,
    },
    /// Not an environment name.
    #[error("unknown environment `{name}` (one of \"air\", \"seawater-cp\", \"free-corrosion\")")]
    UnknownEnvironment {
        /// The name given.
        name: String,
    },
    /// A scatter cell's probability is outside [0, 1] or not finite.
    #[error("scatter cell {index}: probability {value} is not in [0, 1]")]
    InvalidProbability {
        /// Index of the cell.
        index: usize,
        /// The probability.
        value: f64,
    },
    /// The scatter diagram has no cell, or its probabilities add up to 0: it describes no time,
    /// and a damage of 0 from it would be an infinite life read from nothing.
    #[error(
        "the scatter diagram's {cells} cells have probabilities that add up to 0: it describes \
         no sea states (give each cell its probability of occurrence)"
    )]
    EmptyDiagram {
        /// The number of cells.
        cells: usize,
    },
    /// The scatter diagram's probabilities add up to more than 1.
    #[error("the scatter diagram's probabilities add up to {sum}, more than 1")]
    ProbabilitySum {
        /// Σ p_s.
        sum: f64,
    },
}

pub(crate) fn check_positive(key: &'static str, value: f64) -> Result<(), FatigueError> {
    if !(value.is_finite() && value > 0.0) {
        return Err(FatigueError::InvalidSpec {
            key,
            value,
            reason: "must be positive and finite",
        });
    }
    Ok(())
}

fn check_finite(quantity: &'static str, values: &[f64]) -> Result<(), FatigueError> {
    match values.iter().position(|v| !v.is_finite()) {
        Some(index) => Err(FatigueError::NonFinite {
            quantity,
            index,
            value: values[index],
        }),
        None => Ok(()),
    }
}

/// The default number of points around the circumference checked in a spatial scene (every
/// 22.5° over [0°, 180°), which covers the whole circumference, [`HotSpot::points`]).
pub const DEFAULT_CIRCUMFERENCE_POINTS: usize = 8;

/// What a fatigue assessment needs besides the moment history: the `[fatigue]` scene table.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FatigueSpec {
    /// Outer diameter D_o \[m\] (`outer_diameter`).
    pub outer_diameter: f64,
    /// Wall thickness t \[m\] (`wall_thickness`), also the thickness of the S-N correction.
    pub wall_thickness: f64,
    /// Stress concentration factor (`scf`, default 1).
    pub scf: f64,
    /// DNV-RP-C203 class (`curve`, default `"D"`, a common class for girth welds).
    pub curve: DnvClass,
    /// Environment (`environment`, default `"seawater-cp"`: a subsea wellhead under cathodic
    /// protection).
    pub environment: Environment,
    /// Thickness exponent k (`thickness_exponent`); `None`: the class's k from the tables.
    pub thickness_exponent: Option<f64>,
    /// Reference thickness t_ref \[m\] (`reference_thickness`, default 0.025 m, DNV-RP-C203
    /// §2.4.3).
    pub reference_thickness: f64,
    /// Design fatigue factor (`dff`, default 1).
    pub dff: f64,
    /// Points around the circumference in a spatial scene (default
    /// [`DEFAULT_CIRCUMFERENCE_POINTS`]).
    pub circumference_points: usize,
}

impl FatigueSpec {
    /// A pipe of outer diameter D_o and wall t (m) with every other value at its default.
    pub fn new(outer_diameter: f64, wall_thickness: f64) -> Self {
        FatigueSpec {
            outer_diameter,
            wall_thickness,
            scf: 1.0,
            curve: DnvClass::D,
            environment: Environment::SeawaterCp,
            thickness_exponent: None,
            reference_thickness: DNV_REFERENCE_THICKNESS_M,
            dff: 1.0,
            circumference_points: DEFAULT_CIRCUMFERENCE_POINTS,
        }
    }

    /// Checks every value (the error names the `[fatigue]` key): D_o, t, SCF, t_ref and DFF
    /// positive and finite, t ≤ D_o/2, k finite and ≥ 0, at least one circumference point.
    ///
    /// # Errors
    /// [`FatigueError::InvalidSpec`] naming the key.
    pub fn validate(&self) -> Result<(), FatigueError> {
        self.hot_spot()?;
        self.sn_curve()?;
        check_positive("dff", self.dff)?;
        if self.circumference_points == 0 {
            return Err(FatigueError::InvalidSpec {
                key: "circumference_points",
                value: 0.0,
                reason: "must be at least 1",
            });
        }
        Ok(())
    }

    /// The validated hot spot (section and SCF).
    ///
    /// # Errors
    /// See [`HotSpot::new`].
    pub fn hot_spot(&self) -> Result<HotSpot, FatigueError> {
        HotSpot::new(self.outer_diameter, self.wall_thickness, self.scf)
    }

    /// The S-N curve of the class and environment with the thickness correction
    /// (t_eff/t_ref)^k, t = the wall thickness.
    ///
    /// # Errors
    /// See [`SnCurve::with_thickness`].
    pub fn sn_curve(&self) -> Result<SnCurve, FatigueError> {
        let k = self
            .thickness_exponent
            .unwrap_or_else(|| self.curve.thickness_exponent());
        SnCurve::dnv(self.curve, self.environment).with_thickness(
            self.wall_thickness,
            self.reference_thickness,
            k,
        )
    }
}

/// A bending-moment history at the wellhead, sampled on a uniform or non-uniform grid.
#[derive(Clone, Copy, Debug)]
pub struct MomentHistory<'a> {
    /// The record's duration T \[s\] (t_N − t_0).
    pub duration_s: f64,
    /// The moment (the z component in a spatial scene), in the unit `measure` says: the chain's
    /// M₀ of a simulation, or the wellhead moment M_w \[N·m\].
    pub moment: &'a [f64],
    /// Its x component of a spatial scene (same length), or `None` for a planar one.
    pub moment_x: Option<&'a [f64]>,
    /// What the values are: [`MomentMeasure::ChainM0`] with the scene's l₁
    /// ([`crate::Scene::moment_measure`]) for a simulated M₀, whose wellhead moment is
    /// M_w = M₀ · l₁/2; [`MomentMeasure::Wellhead`] for M_w itself.
    pub measure: MomentMeasure,
}

/// The outcome of [`assess`].
#[derive(Clone, Debug, PartialEq)]
pub struct Assessment {
    /// The cycles of the worst point's stress (MPa).
    pub cycles: Vec<Cycle>,
    /// Miner's sum over the record.
    pub damage: f64,
    /// The record's duration \[s\].
    pub duration_s: f64,
    /// D · Y/T.
    pub damage_per_year: f64,
    /// 1/(DFF · D_y) years.
    pub life_years: f64,
    /// The worst point θ \[rad\] around the circumference (0 for a planar history).
    pub theta: f64,
}

/// Stress (σ = SCF · M_w · (D_o/2)/I, M_w from the history's [`MomentMeasure`]), rainflow, S-N
/// and Miner on a moment history: the damage at the worst of
/// `spec.circumference_points` points around the circumference (one point, θ = 0, for a planar
/// history), its damage per year and life.
///
/// # Errors
/// Any [`FatigueError`] of the spec (naming its key), of the history (length mismatch,
/// non-finite sample, `base_length` of its measure) or of the duration.
pub fn assess(spec: &FatigueSpec, history: MomentHistory<'_>) -> Result<Assessment, FatigueError> {
    spec.validate()?;
    let hot_spot = spec.hot_spot()?;
    let curve = spec.sn_curve()?;
    check_positive("duration", history.duration_s)?;
    history.measure.check()?;
    check_finite("moment", history.moment)?;
    if let Some(mx) = history.moment_x {
        check_finite("moment_x", mx)?;
    }
    let n = history.moment.len();
    let mut stress = vec![0.0; n];
    let mut workspace = RainflowWorkspace::new();
    let mut cycles = Vec::new();
    let mut best: Option<(f64, f64, Vec<Cycle>)> = None;
    let thetas: Vec<f64> = match history.moment_x {
        Some(_) => HotSpot::points(spec.circumference_points).collect(),
        None => vec![0.0],
    };
    for theta in thetas {
        match history.moment_x {
            Some(mx) => {
                hot_spot.stress_at(mx, history.moment, theta, history.measure, &mut stress)?
            }
            None => hot_spot.stress(history.moment, history.measure, &mut stress)?,
        }
        rainflow_into(&stress, &mut workspace, &mut cycles)?;
        let damage = miner_sum(&cycles, &curve);
        if best.as_ref().is_none_or(|b| damage > b.1) {
            best = Some((theta, damage, cycles.clone()));
        }
    }
    let (theta, damage, cycles) = best.unwrap_or((0.0, 0.0, Vec::new()));
    let per_year = damage_per_year(damage, history.duration_s)?;
    Ok(Assessment {
        cycles,
        damage,
        duration_s: history.duration_s,
        damage_per_year: per_year,
        life_years: life_years(per_year, spec.dff)?,
        theta,
    })
}
