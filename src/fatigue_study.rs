//! The wellhead's fatigue life under control, over a scatter diagram (docs/fatigue.md):
//! every controller run on every sea state, each run's moment history counted by rainflow and
//! Miner's rule, the cells combined into damage per year, life and life extension.
//!
//! For controller c and cell s (probability p_s, a record of duration T_s with Miner's sum
//! D_{c,s}):
//! ```text
//! D_y(c)  = Σ_s p_s · D_{c,s} · Y/T_s          (the cell's contribution p_s · D_{c,s} · Y/T_s)
//! L(c)    = 1 / (DFF · D_y(c))                  years
//! ext(c)  = L(c) / L(none)                      the life extension of c over no control
//! ```
//! Without a scatter diagram the scene's own sea is the one cell, of probability 1.
//!
//! # The controllers ([`ControllerKind`])
//! - `scene`: the scene as written, its `[control]` values applied (what `simulate` runs);
//!   `chainbeam fatigue` without `--controller`.
//! - `none`: the scene with its `[control]` removed, by `simulate` (spatial scenes too).
//! - `constant`, `pd`, `mpc`: [`crate::mpc`]'s closed loop on the (planar) plant of the cell's
//!   scene, one decision every [`ControlSettings::interval`] seconds: the best constant force
//!   ([`ConstantForce::best`], an offline optimum of the cell's record that knows its future:
//!   min Σ M₀² + ρ h Σ u², which cancels the mean moment; on the training window
//!   [`ControlSettings::pd_training`] when one is given, [`training_scene`]), a PD law on the measured M₀ with
//!   gains tuned on the cell's record ([`pd_law`]; on its first
//!   [`ControlSettings::pd_training`] seconds, or [`ControlSettings::pd_gains`] given) and the
//!   receding-horizon controller ([`Mpc`], a perfect model of the loads, on the plant's chain or
//!   a reduced planning model of it, [`MpcOptions::plan_pendulums`]).
//! - The PD law is tuned in scaled, bounded parameters ([`pd`]): its bias about the force that
//!   cancels the static moment, its gains as loop gains e^{x} in units of the static gain
//!   k_u = ∂M₀/∂u (and 1/ω_p for K_d), x in a box, so the tuning cannot end at reversed
//!   (destabilising) or unbounded gains; it minimises the closed loop's Σ M₀² + ρ h Σ u².
//! - MPC plans on the fatigue proxy Σ|M₀(t_k)|^m (+ ρ h Σ u²), m the S-N curve's first slope
//!   ([`fatigue_proxy`]; [`ControlSettings::mpc_fatigue_proxy`], else
//!   [`MpcOptions::objective`]): MPC plans on the proxy and the study reports the real damage
//!   (the rainflow damage itself has no Gauss-Newton form; docs/fatigue.md, "Fatigue as an
//!   objective").
//!
//! Every damage reported is the rainflow damage of the moment the controller leaves.
//!
//! # The start of a record
//! Every run starts from the straight riser at rest, with the current and the sea switched on
//! at t = 0 (the plant of [`crate::mpc`], like `simulate`): the riser swings out to its offset
//! in the current, a start-up whose one large half cycle a short record would count as
//! fatigue. The first [`ControlSettings::spin_up`] seconds of every record are therefore left
//! out of the count (its damage and its duration T_s): the record of a cell runs spin-up + T_s
//! seconds (the controllers act, and MPC and the constant force plan, over all of it). The
//! spin-up must outlast the start-up transient: measured on `riser_300m` (docs/cli.md,
//! `fatigue`, "The start of a record"). Starting instead from the static equilibrium in the
//! current ([`crate::statics`]) would remove the current's part but not the sea's (the waves
//! start at t = 0 on a riser at rest, which then takes the riser's first periods to settle),
//! so a window is needed either way.
//!
//! A control that cannot act is refused before any run ([`StudyError::ControlCannotAct`]): a
//! force at the tip of a beam whose supports lock it (fixed-fixed, pinned-pinned without the
//! reaction-force tip) moves nothing, and a "life extension" of 1 would be reported as a result.
//!
//! # Sea states and seeds
//! A cell's sea state is the scene's `[loads.waves]` with `hs` and `tp` (and `direction`, when
//! the diagram gives one) replaced ([`with_sea_state`]); everything else (spectrum, γ, the
//! number of components, the seed) stays the scene's. Every cell keeps the scene's seed: the
//! cells then differ only in H_s, T_p and direction, not in a fresh draw of the phases (common
//! random numbers: the difference between two cells, or two controllers in a cell, is not
//! sampling noise), and a cell's sea does not change when rows are added, removed or reordered
//! in the diagram (a seed derived from the row's index would). The price: the sampling error
//! of the one realisation is shared by every cell and does not average out over the diagram;
//! a record long against T_p (many cycles per cell) keeps it small, and several seeds
//! ("Records") measure it.
//!
//! # Records
//! A short-term sea state is taken as stationary over about three hours (DNV-RP-C205), and a
//! fatigue analysis counts a 3-hour realisation per sea state after the start-up is discarded.
//! [`ControlSettings::record`] sets the seconds counted after the spin-up: every run of a cell
//! is then `spin_up` + `record` seconds long ([`with_record`]: N = ⌈spin_up/h⌉ + ⌈record/h⌉
//! steps, rounded up to whole control intervals for a closed-loop controller), whatever the
//! scene's `[time]` says; `None` keeps the scene's own `[time]`. The command line defaults it to
//! [`PRACTICE_RECORD_S`] (3 hours) for every cell; a shorter record (`--record`) is for tests and
//! quick looks, and is counted as what it is (`duration_s`). Ten minutes hold barely fifteen
//! cycles of a 40 s mode: the damage of a 600 s record of the same sea is not the 3-hour one's.
//!
//! One realisation's damage scatters with its seed. With [`ControlSettings::seeds`] = K > 1,
//! every cell runs K seas, the scene's `[loads.waves]` seed s, s + 1, …, s + K − 1 ([`with_seed`];
//! the same K seeds in every cell, so seed i is one common draw over the whole diagram). The
//! cell's damage is the mean over the seeds, D̄_s = Σᵢ D_{s,i}/K, which enters D_y and the life;
//! [`CellOutcome::seed_damages`] keeps each seed's, and [`ControllerOutcome::seed_lives`] the life
//! of each seed alone over the diagram, L_i = 1/(DFF · Σ_s p_s D_{s,i} Y/T_s): the spread of the
//! life over seeds. K = 1 is exactly the single-seed study (D̄_s = D_{s,0} bit for bit).
//!
//! # Hot spots
//! A scene with `[[fatigue.hotspot]]` gets each hot spot's damage per year and life
//! ([`ControllerOutcome::hotspots`], [`crate::hotspots`]) for every controller: for `scene` and
//! `none` from the same streamed run as the wellhead's base moment; for `constant`, `pd` and
//! `mpc`, whose closed loop records the base moment only, by replaying the loop's decisions on
//! the same plant ([`replay_joint_moments`]: the same states, one more simulation, no re-plan).
//!
//! # The moment the controllers act on
//! With [`MpcOptions::hotspot`] (`[mpc] hotspot`, `--hotspot`) every controller acts on the
//! moment M at that `[[fatigue.hotspot]]` instead of the base moment: MPC plans on
//! h Σ_k |M(t_k)|^m + ρ h Σ_k u_k² ([`HotSpotObjective`], through the vessel's thrust), the PD law
//! feeds back M and its difference over the last step ([`crate::mpc::pd_closed_loop_cost_at`],
//! gains tuned on Σ M² + ρ h Σ u² of the training window), and the constant force is the best
//! for h Σ|M|^m + ρ h Σ u² over the training window ([`best_constant_at_hot_spot`]). Each run's
//! damage ([`CellRun::damage`]) is then that hot spot's Miner sum (its section, SCF and S-N
//! curve, from the same joint torques as its [`ControllerOutcome::hotspots`] entry), and the
//! lives use its DFF: the totals equal that entry.
//!
//! # Work and order
//! The (cell, seed, controller) runs are independent: with the `parallel` feature they run on rayon's
//! pool, and the result (every number) is the same, in the same order, as sequentially.

#[cfg(feature = "parallel")]
use rayon::prelude::*;
use thiserror::Error;

use crate::adjoint::HotSpotObjective;
use crate::error::Requirement;
use crate::fatigue::{
    assess, combine_scatter, life_years, CellDamage, FatigueError, FatigueSpec, MomentHistory,
    ScatterCell, SeaState, WellheadDamage,
};
use crate::mpc::{
    interval_steps, run_closed_loop, ConstantForce, Controller, Force2, Mpc, MpcError, MpcOptions,
    PdLaw, PdTuning,
};
use crate::optimize::{minimize, Bounds, OptimOptions};
use crate::scene::{ObjectiveKind, Scene, Support};
use crate::simulate::moment_history;

pub mod pd;

pub use crate::fatigue::scatter::MAX_SCATTER_CELLS;

/// The record a fatigue cell counts by default on the command line \[s\]: 3 hours, the
/// duration over which a short-term sea state is taken as stationary (DNV-RP-C205, module
/// docs "Records").
pub const PRACTICE_RECORD_S: f64 = 10_800.0;

/// The most seeds per cell.
pub const MAX_SEEDS: usize = 1000;

/// A controller of a fatigue study (module docs).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum ControllerKind {
    /// The scene as written (its `[control]` values applied).
    Scene,
    /// No control: the scene without its `[control]`.
    None,
    /// The best constant force of the cell's record.
    Constant,
    /// A PD law on the measured base moment, gains tuned on the cell's record.
    Pd,
    /// Receding-horizon control with a perfect model.
    Mpc,
}

impl ControllerKind {
    /// The controllers `--controller` accepts, in their report order.
    pub const CHOICES: [ControllerKind; 4] = [
        ControllerKind::None,
        ControllerKind::Constant,
        ControllerKind::Pd,
        ControllerKind::Mpc,
    ];

    /// The name in `--controller` and in the JSON (`scene`, `none`, `constant`, `pd`, `mpc`).
    pub fn name(self) -> &'static str {
        match self {
            ControllerKind::Scene => "scene",
            ControllerKind::None => "none",
            ControllerKind::Constant => "constant",
            ControllerKind::Pd => "pd",
            ControllerKind::Mpc => "mpc",
        }
    }

    /// Whether it applies a force of its own (constant, pd, mpc).
    pub fn is_feedback(self) -> bool {
        matches!(
            self,
            ControllerKind::Constant | ControllerKind::Pd | ControllerKind::Mpc
        )
    }

    /// A comma-separated list of names (`none,constant,pd,mpc`, any subset in any order; spaces
    /// around names are ignored), sorted in report order.
    ///
    /// # Errors
    /// [`StudyError::UnknownController`], [`StudyError::DuplicateController`], or
    /// [`StudyError::NoControllers`] for an empty list.
    pub fn parse_list(list: &str) -> Result<Vec<ControllerKind>, StudyError> {
        let mut kinds = Vec::new();
        for name in list.split(',').map(str::trim).filter(|s| !s.is_empty()) {
            let kind = Self::CHOICES
                .into_iter()
                .find(|k| k.name() == name)
                .ok_or_else(|| StudyError::UnknownController {
                    name: name.to_string(),
                })?;
            if kinds.contains(&kind) {
                return Err(StudyError::DuplicateController {
                    name: name.to_string(),
                });
            }
            kinds.push(kind);
        }
        if kinds.is_empty() {
            return Err(StudyError::NoControllers);
        }
        kinds.sort();
        Ok(kinds)
    }
}

/// Why a study could not be run; each names the controller, the cell or the key at fault.
#[derive(Debug, Error, Clone, PartialEq)]
#[non_exhaustive]
pub enum StudyError {
    /// The assessment's own error (the `[fatigue]` table, a non-finite moment, a probability).
    #[error(transparent)]
    Fatigue(#[from] FatigueError),
    /// Not a controller name.
    #[error("unknown controller `{name}` (one of none, constant, pd, mpc)")]
    UnknownController {
        /// The name given.
        name: String,
    },
    /// A controller named twice.
    #[error("controller `{name}` is named twice")]
    DuplicateController {
        /// The name.
        name: String,
    },
    /// An empty list of controllers.
    #[error("no controller named (give a comma list of none, constant, pd, mpc)")]
    NoControllers,
    /// A scatter diagram without cells.
    #[error("the scatter diagram has no cells")]
    NoCells,
    /// More cells than [`MAX_SCATTER_CELLS`].
    #[error("the scatter diagram has {cells} cells, more than {MAX_SCATTER_CELLS}")]
    TooManyCells {
        /// The number of cells.
        cells: usize,
    },
    /// The control acts at a node the supports lock: it cannot change the moment.
    #[error(
        "controller `{controller}` cannot act: its force is at node {node}, the tip of a \
         {support} beam, which the supports lock (set `control.node` to a free node)"
    )]
    ControlCannotAct {
        /// The controller.
        controller: &'static str,
        /// The control node (`control.node`, default the tip n).
        node: usize,
        /// The support (`beam.support`).
        support: &'static str,
    },
    /// A cell's sea state cannot be set on the scene (e.g. it has no `[loads.waves]`).
    #[error("scatter cell {cell}: {reason}")]
    SeaState {
        /// Index of the cell (0-based, in the diagram's order).
        cell: usize,
        /// Why.
        reason: String,
    },
    /// A spin-up window that is negative, not finite, or not shorter than the record.
    #[error(
        "spin_up = {spin_up} s: the window not counted must be finite, ≥ 0 and shorter than the \
         record ({duration_s} s)"
    )]
    SpinUp {
        /// The window given \[s\].
        spin_up: f64,
        /// The record's duration N h \[s\].
        duration_s: f64,
    },
    /// A record to count that is not positive and finite, or whose run the scene cannot hold.
    #[error("record = {record} s: {reason}")]
    Record {
        /// The record given \[s\].
        record: f64,
        /// Why.
        reason: String,
    },
    /// Seeds per cell that are not in 1..=[`MAX_SEEDS`], more than one on a scene without a sea
    /// to draw, or a seed past the largest.
    #[error("seeds = {seeds}: {reason}")]
    Seeds {
        /// The number of seeds given.
        seeds: usize,
        /// Why.
        reason: String,
    },
    /// A cell index past the diagram's last ([`run_study_cell`]).
    #[error("scatter cell {cell}: the diagram has {cells} cells")]
    CellIndex {
        /// The index given (0-based).
        cell: usize,
        /// The number of cells.
        cells: usize,
    },
    /// Runs to combine that are not one per (cell, seed, controller) ([`combine_study`]).
    #[error("{got} runs to combine where the study has {expected} (cell, seed, controller) runs")]
    RunCount {
        /// Cells × seeds × controllers.
        expected: usize,
        /// The runs given.
        got: usize,
    },
    /// A run failed (a RATTLE step, a solve, settings that do not fit the scene).
    #[error("controller `{controller}`, cell {cell}: {source}")]
    Run {
        /// The controller.
        controller: &'static str,
        /// Index of the cell.
        cell: usize,
        /// The library's error (boxed: it is large, and this is the cold path).
        source: Box<crate::Error>,
    },
}

/// The settings of the closed-loop controllers (`constant`, `pd`, `mpc`).
#[derive(Clone, Debug)]
pub struct ControlSettings {
    /// The control interval \[s\] (a multiple of the step that divides the run). Default 0.1.
    pub interval: f64,
    /// MPC's options; also the force bound (`mpc.ocp`'s symmetric box, upper bound used) and
    /// the effort weight ρ of the constant force and the PD law. Default [`MpcOptions`]'s.
    pub mpc: MpcOptions,
    /// Iterations of the PD gains' tuning ([`PdLaw::tune`]). Default 200.
    pub pd_max_iters: usize,
    /// The training window \[s\] of the PD law and the constant force: the gains are tuned,
    /// and the best constant force found, on the first `pd_training` seconds of the cell's
    /// record (rounded to whole control intervals, at least one, [`training_scene`]), then run
    /// on the whole record. `None` (default): tuned on the whole record. A window of a few
    /// minutes holds tens of wave periods, enough to fit three gains, at a fraction of the
    /// cost of tuning on an hour (module docs, "The controllers").
    pub pd_training: Option<f64>,
    /// Given PD gains (u_b \[N\], K_p \[N/(N·m)\], K_d \[N·s/(N·m)\]) used in every cell
    /// instead of tuning them (a fixed design). Default `None`: tuned per cell.
    pub pd_gains: Option<[f64; 3]>,
    /// The spin-up window \[s\] not counted (module docs, "The start of a record"): every
    /// record's first `spin_up` seconds (rounded up to whole steps) are left out of the rainflow
    /// count, its damage and its duration. Default 0 (everything counted).
    pub spin_up: f64,
    /// MPC plans on the fatigue proxy Σ|M₀(t_k)|^m, m the S-N curve's first slope
    /// ([`ObjectiveKind::Power`], module docs "The controllers"), instead of
    /// [`MpcOptions::objective`]. Default `true`.
    pub mpc_fatigue_proxy: bool,
    /// The record counted after the spin-up \[s\] (module docs, "Records"): every run is
    /// `spin_up` + `record` seconds long ([`with_record`]). `None` (default): the scene's own
    /// `[time]` grid, the spin-up included. The command line defaults it to
    /// [`PRACTICE_RECORD_S`] (3 hours).
    pub record: Option<f64>,
    /// Seeds per cell K ≥ 1 (module docs, "Records"): the runs of a cell use the scene's
    /// `[loads.waves]` seed s, s + 1, …, s + K − 1. Default 1.
    pub seeds: usize,
}

impl Default for ControlSettings {
    fn default() -> Self {
        ControlSettings {
            interval: 0.1,
            mpc: MpcOptions::default(),
            pd_max_iters: 200,
            pd_training: None,
            pd_gains: None,
            spin_up: 0.0,
            mpc_fatigue_proxy: true,
            record: None,
            seeds: 1,
        }
    }
}

impl ControlSettings {
    /// The force bound u_max (the upper bound of the box).
    pub fn bound(&self) -> f64 {
        self.mpc.ocp.upper
    }
}

/// A controller's moment record on one scene.
#[derive(Clone, Debug, PartialEq)]
pub struct ControlledRecord {
    /// M₀(t_k) \[N·m\], k = 0..N.
    pub moment: Vec<f64>,
    /// M₀ₓ of a spatial run.
    pub moment_x: Option<Vec<f64>>,
    /// T = N h \[s\].
    pub duration_s: f64,
    /// The constant controller's force \[N\].
    pub force: Option<f64>,
    /// The PD law's gains (u_b \[N\], K_p \[N/(N·m)\], K_d \[N·s/(N·m)\]).
    pub gains: Option<[f64; 3]>,
    /// A closed loop's decisions: the force \[N\] held over each control interval, in order
    /// (`None` for `scene` and `none`), from which [`replay_joint_moments`] recomputes the
    /// run's joint torques.
    pub decisions: Option<Vec<f64>>,
    /// The thrust applied, when the control is the thrust on the vessel: (rms, peak) \[N\] of
    /// F_k over k = 0..N ([`thrust_stats`]; `none`: zero); `None` otherwise.
    pub thrust: Option<[f64; 2]>,
}

/// (rms, peak) of the thrusts F_0..F_N: (Σ F_k²/(N + 1))^½ and max |F_k| \[N\].
pub fn thrust_stats(thrust: &[f64]) -> [f64; 2] {
    if thrust.is_empty() {
        return [0.0; 2];
    }
    let ms = thrust.iter().map(|f| f * f).sum::<f64>() / thrust.len() as f64;
    [ms.sqrt(), thrust.iter().fold(0.0f64, |m, f| m.max(f.abs()))]
}

/// One controller's outcome in one cell.
#[derive(Clone, Debug, PartialEq)]
pub struct CellOutcome {
    /// The cell's sea state (`None`: the scene as is, without `[loads.waves]`).
    pub sea: Option<SeaState>,
    /// p_s.
    pub probability: f64,
    /// Miner's sum D_{c,s} over the record: the mean over the seeds of `seed_damages`.
    pub damage: f64,
    /// Miner's sum of each seed's record, in seed order (one value with one seed).
    pub seed_damages: Vec<f64>,
    /// T_s \[s\].
    pub duration_s: f64,
    /// The cell's probability-weighted contribution p_s · D_{c,s} · Y/T_s per year.
    pub damage_per_year: f64,
    /// The constant controller's force in this cell \[N\].
    pub force: Option<f64>,
    /// The PD law's gains in this cell.
    pub gains: Option<[f64; 3]>,
    /// The thrust on the vessel in this cell (a thrust scene): (rms over its seeds' records,
    /// the largest |F| of any seed) \[N\].
    pub thrust: Option<[f64; 2]>,
}

/// The spread of a cell's Miner sum over its seeds ([`CellOutcome::seed_spread`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SeedSpread {
    /// The sample standard deviation s = √(Σᵢ (Dᵢ − D̄)² / (K − 1)).
    pub std: f64,
    /// minᵢ Dᵢ.
    pub min: f64,
    /// maxᵢ Dᵢ.
    pub max: f64,
}

impl CellOutcome {
    /// With more than one seed, the spread of the seeds' Miner sums Dᵢ about their mean D̄
    /// (`damage`); `None` with one seed.
    pub fn seed_spread(&self) -> Option<SeedSpread> {
        let k = self.seed_damages.len();
        (k > 1).then(|| {
            let ss: f64 = self
                .seed_damages
                .iter()
                .map(|d| (d - self.damage).powi(2))
                .sum();
            let d = self.seed_damages.iter().copied();
            SeedSpread {
                std: (ss / (k - 1) as f64).sqrt(),
                min: d.clone().fold(f64::INFINITY, f64::min),
                max: d.fold(f64::NEG_INFINITY, f64::max),
            }
        })
    }
}

/// The range of the lives of a controller's seeds ([`ControllerOutcome::seed_life_range`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LifeRange {
    /// minᵢ Lᵢ \[years\] (+∞: no seed does damage).
    pub min: f64,
    /// maxᵢ Lᵢ \[years\].
    pub max: f64,
}

impl ControllerOutcome {
    /// With more than one seed, the least and greatest of the seeds' lives `seed_lives`; `None`
    /// with one seed.
    pub fn seed_life_range(&self) -> Option<LifeRange> {
        let l = self.seed_lives.iter().copied();
        (self.seed_lives.len() > 1).then(|| LifeRange {
            min: l.clone().fold(f64::INFINITY, f64::min),
            max: l.fold(f64::NEG_INFINITY, f64::max),
        })
    }
}

/// One controller over every cell.
#[derive(Clone, Debug, PartialEq)]
pub struct ControllerOutcome {
    /// The controller.
    pub kind: ControllerKind,
    /// D_y = Σ_s of the cells' contributions.
    pub damage_per_year: f64,
    /// L = 1/(DFF · D_y) years (+∞ without damage).
    pub life_years: f64,
    /// Per cell, in the diagram's order.
    pub cells: Vec<CellOutcome>,
    /// The life of each seed alone, L_i = 1/(DFF · Σ_s p_s D_{c,s,i} Y/T_s) years, in seed
    /// order (one value, `life_years`, with one seed).
    pub seed_lives: Vec<f64>,
    /// Per hot spot of the scene's `[[fatigue.hotspot]]` (empty without them): the damage per
    /// year and life over the diagram, each cell's the mean over the seeds.
    pub hotspots: Vec<HotSpotOutcome>,
    /// The thrust on the vessel over the diagram (a thrust scene): the rms
    /// (Σ_s p_s F²_rms,s / Σ_s p_s)^½ \[N\], the cells' mean squares weighted by their
    /// probabilities.
    pub thrust_rms: Option<f64>,
    /// The largest |F| of any cell and seed \[N\].
    pub thrust_peak: Option<f64>,
}

/// A hot spot's outcome over the diagram, for one controller.
#[derive(Clone, Debug, PartialEq)]
pub struct HotSpotOutcome {
    /// The hot spot's name.
    pub name: String,
    /// Its elevation \[m\].
    pub elevation: f64,
    /// D_y = Σ_s p_s · D̄_s · Y/T_s, D̄_s the mean over the seeds of cell s.
    pub damage_per_year: f64,
    /// 1/(DFF · D_y) years (+∞ without damage).
    pub life_years: f64,
    /// The hot spot's design fatigue factor DFF.
    pub dff: f64,
}

/// A cell where a closed-loop controller's damage is above no control's
/// ([`Study::worse_than_none`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct WorseThanNone {
    /// The controller.
    pub controller: ControllerKind,
    /// The cell (0-based, in the diagram's order).
    pub cell: usize,
    /// Its damage D_{c,s} (mean over the seeds).
    pub damage: f64,
    /// No control's damage in the same cell.
    pub none: f64,
}

/// The outcome of [`run_study`]: one entry per controller, in report order.
#[derive(Clone, Debug, PartialEq)]
pub struct Study {
    /// Per controller.
    pub controllers: Vec<ControllerOutcome>,
}

impl Study {
    /// The outcome of `kind`, if it was run.
    pub fn get(&self, kind: ControllerKind) -> Option<&ControllerOutcome> {
        self.controllers.iter().find(|c| c.kind == kind)
    }

    /// D_{c,s}/D_{none,s}, the damage of `kind` in cell s over no control's; `None` unless both
    /// ran, or when no control does no damage there.
    pub fn damage_ratio_to_none(&self, kind: ControllerKind, cell: usize) -> Option<f64> {
        let (c, none) = (self.get(kind)?, self.get(ControllerKind::None)?);
        let (d, d0) = (c.cells.get(cell)?.damage, none.cells.get(cell)?.damage);
        (d0 > 0.0).then_some(d / d0)
    }

    /// Every (closed-loop controller, cell) whose damage is above no control's in that cell:
    /// a controller that does worse than none there (in cell then report order).
    pub fn worse_than_none(&self) -> Vec<WorseThanNone> {
        let Some(none) = self.get(ControllerKind::None) else {
            return Vec::new();
        };
        let mut out = Vec::new();
        for (s, cell0) in none.cells.iter().enumerate() {
            for c in self.controllers.iter().filter(|c| c.kind.is_feedback()) {
                if let Some(cell) = c.cells.get(s).filter(|x| x.damage > cell0.damage) {
                    out.push(WorseThanNone {
                        controller: c.kind,
                        cell: s,
                        damage: cell.damage,
                        none: cell0.damage,
                    });
                }
            }
        }
        out
    }

    /// L(kind)/L(none) = D_y(none)/D_y(kind); `None` unless both ran and both lives are
    /// finite and positive.
    pub fn life_extension(&self, kind: ControllerKind) -> Option<f64> {
        let (c, none) = (self.get(kind)?, self.get(ControllerKind::None)?);
        let ratio = c.life_years / none.life_years;
        (c.life_years.is_finite() && none.life_years.is_finite() && ratio.is_finite())
            .then_some(ratio)
    }
}

/// What [`run_study`] runs.
#[derive(Clone, Copy, Debug)]
pub struct StudyInput<'a> {
    /// The scene (its `[fatigue]` table is not read: `spec` is).
    pub scene: &'a Scene,
    /// The assessment's section and S-N curve.
    pub spec: &'a FatigueSpec,
    /// The scatter diagram; `None`: the scene's own sea, probability 1.
    pub cells: Option<&'a [ScatterCell]>,
    /// The controllers, in report order.
    pub controllers: &'a [ControllerKind],
    /// The closed-loop controllers' settings.
    pub settings: &'a ControlSettings,
}

/// The scene's support as the scene file writes it.
fn support_name(s: Support) -> &'static str {
    s.name()
}

/// Refuses a feedback controller whose force acts at a node the supports lock (the tip of a
/// fixed-fixed or pinned-pinned beam without the reaction-force tip).
///
/// # Errors
/// [`StudyError::ControlCannotAct`].
pub fn check_control_can_act(scene: &Scene, kind: ControllerKind) -> Result<(), StudyError> {
    if !kind.is_feedback() {
        return Ok(());
    }
    let n = scene.n();
    let node = scene.control.as_ref().map_or(n, |c| c.node);
    // The vessel's thrust moves the top the vessel holds: it can act.
    let locked =
        scene.beam.support.holds_tip() && !scene.beam.reaction_force && scene.thrust().is_none();
    if locked && node == n {
        return Err(StudyError::ControlCannotAct {
            controller: kind.name(),
            node,
            support: support_name(scene.beam.support),
        });
    }
    Ok(())
}

/// Runs one controller on `scene` and records M₀ (module docs, "The controllers").
///
/// # Errors
/// The library's errors of the run (a planar-only controller on a spatial scene:
/// [`crate::Error::NeedsSpatialModel`]; a failed step or solve; an interval that does not fit).
pub fn run_controller(
    scene: &Scene,
    kind: ControllerKind,
    settings: &ControlSettings,
) -> crate::Result<ControlledRecord> {
    let (interval, effort) = (settings.interval, settings.mpc.effort);
    let bound = control_bound(scene, settings);
    let thrust_scene = scene.thrust().is_some();
    // The study's controllers and records are planar (M₀ and a force in the plane).
    if kind.is_feedback() {
        if let Some(key) = scene.spatial_key() {
            return Err(crate::Error::NeedsSpatialModel { key });
        }
    }
    let closed = |c: &mut dyn Controller, force, gains| {
        let r = run_closed_loop(scene, interval, c)?;
        Ok(ControlledRecord {
            thrust: thrust_scene.then(|| thrust_stats(&r.control)),
            duration_s: r.summary.simulated_seconds,
            moment: r.moment,
            moment_x: None,
            force,
            gains,
            decisions: Some(r.decisions.iter().map(|d| d.control).collect()),
        })
    };
    match kind {
        ControllerKind::Scene | ControllerKind::None => {
            let mut free;
            let run = if kind == ControllerKind::None {
                free = scene.clone();
                free.control = None;
                &free
            } else {
                scene
            };
            let history = moment_history(run)?;
            // The thrust of `scene` is its `[control]` per step (none: zero).
            let thrust = match (thrust_scene, kind) {
                (false, _) => None,
                (true, ControllerKind::None) => Some([0.0; 2]),
                (true, _) => Some(thrust_stats(&scene_controls(run)?)),
            };
            Ok(ControlledRecord {
                thrust,
                duration_s: history.duration(),
                moment: history.moment,
                moment_x: history.moment_x,
                force: None,
                gains: None,
                decisions: None,
            })
        }
        ControllerKind::Constant => {
            let training = training_scene(scene, settings)?;
            let mut c = if let Some(spot) = settings.mpc.hotspot.as_ref() {
                best_constant_at_hot_spot(&training, spot, bound, effort)?
            } else if scene.thrust().is_some() {
                ConstantForce::best_thrust(&training, bound, effort)?.0
            } else {
                ConstantForce::best(&training, bound, effort)?.0
            };
            let force = c.u.z;
            closed(&mut c, Some(force), None)
        }
        ControllerKind::Pd => {
            let mut pd = pd_law(scene, settings)?;
            let gains = [pd.bias.z, pd.kp, pd.kd];
            match hot_spot_objective(scene, settings)? {
                Some(spot) => closed(&mut HotSpotPd { law: pd, spot }, None, Some(gains)),
                None => closed(&mut pd, None, Some(gains)),
            }
        }
        ControllerKind::Mpc => {
            let mut mpc = Mpc::new(scene, interval, settings.mpc.clone())?;
            closed(&mut mpc, None, None)
        }
    }
}

/// The moment of the hot spot the controllers act on ([`MpcOptions::hotspot`]) as
/// [`HotSpotObjective`] on `scene` (its exponent the S-N curve's first slope, the effort
/// `settings`'), `None` without one.
///
/// # Errors
/// [`HotSpotObjective::new`]'s; the hot spot's S-N curve's.
fn hot_spot_objective(
    scene: &Scene,
    settings: &ControlSettings,
) -> crate::Result<Option<HotSpotObjective>> {
    let Some(spot) = settings.mpc.hotspot.as_ref() else {
        return Ok(None);
    };
    let exponent =
        WellheadDamage::new(&spot.spec, crate::fatigue::MomentMeasure::Wellhead)?.exponent();
    Ok(Some(HotSpotObjective::new(
        scene,
        spot.elevation,
        exponent,
        settings.mpc.effort,
    )?))
}

/// The PD law on the moment M at a hot spot (module docs, "The moment the controllers act
/// on"): u = clamp(u_b − K_p M − K_d Ṁ, ±u_max) with M read from the observed attitudes
/// ([`HotSpotObjective::moment_of_attitudes`]) and Ṁ the difference over the last step,
/// (M(t_k) − M(t_{k−1}))/h (0 at k = 0): the loop its gains were tuned on
/// ([`crate::mpc::pd_closed_loop_cost_at`]).
struct HotSpotPd {
    law: PdLaw,
    spot: HotSpotObjective,
}

impl Controller for HotSpotPd {
    fn name(&self) -> String {
        "pd".into()
    }
    fn control(&mut self, obs: &crate::mpc::Observation<'_>) -> crate::Result<Force2> {
        let obs = obs.in_model::<2>()?;
        let m = self.spot.moment_of_attitudes(&obs.state.q);
        let rate = match obs.previous_state {
            Some(prev) => (m - self.spot.moment_of_attitudes(&prev.q)) / obs.h,
            None => 0.0,
        };
        let u = self.law.bias.z - self.law.kp * m - self.law.kd * rate;
        Ok(Force2::z(u.clamp(-self.law.bound, self.law.bound)))
    }
}

/// The best constant force (or thrust) for a hot spot's moment on `scene` (the training
/// window): min_u h Σ_k |M(t_k)|^m + ρ h Σ_k u², |u| ≤ `bound`, M the hot spot's moment and m
/// its S-N curve's first slope ([`HotSpotObjective`]), by [`minimize`] on the adjoint gradient
/// from u = 0 (the structured solvers need the base moment's Gauss-Newton form).
///
/// # Errors
/// The objective's ([`HotSpotObjective::new`]), the problem's and the optimiser's errors.
pub fn best_constant_at_hot_spot(
    scene: &Scene,
    spot: &crate::hotspots::HotSpotSpec,
    bound: f64,
    effort: f64,
) -> crate::Result<ConstantForce> {
    let exponent =
        WellheadDamage::new(&spot.spec, crate::fatigue::MomentMeasure::Wellhead)?.exponent();
    let objective = HotSpotObjective::new(scene, spot.elevation, exponent, effort)?;
    let steps = scene.time.steps;
    let map = crate::adjoint::PiecewiseControl { steps, pieces: 1 };
    let problem = crate::adjoint::ControlProblem::builder(scene)
        .map(map)
        .objective(objective)
        .build_in::<2>()?;
    let options = OptimOptions {
        bounds: Some(Bounds::symmetric(bound)?),
        first_step: 0.01 * bound,
        trust_radius: 0.1 * bound,
        max_trust_radius: bound,
        ..OptimOptions::default()
    };
    let r = minimize(&problem, &[0.0], &options)?;
    Ok(ConstantForce {
        u: Force2::z(r.theta[0]),
        spatial: false,
    })
}

/// The per-step controls u_0..u_N a scene's `[control]` applies (none: zeros).
///
/// # Errors
/// The scene's model errors.
fn scene_controls(scene: &Scene) -> crate::Result<Vec<f64>> {
    use crate::adjoint::ControlMap;
    let steps = scene.time.steps;
    let Some(c) = scene.control.as_ref() else {
        return Ok(vec![0.0; steps + 1]);
    };
    let mut u = vec![0.0; steps + 1];
    match c.kind {
        crate::scene::ControlKind::Constant => u.fill(c.values[0]),
        crate::scene::ControlKind::PerStep => u.copy_from_slice(&c.values),
        crate::scene::ControlKind::Piecewise => {
            let map = crate::adjoint::PiecewiseControl {
                steps,
                pieces: c.values.len(),
            };
            map.controls(&c.values, &mut u);
        }
    }
    Ok(u)
}

/// The bound of the closed-loop controllers' control on `scene`: the vessel's `thrust_bound`
/// when the control is the thrust on the vessel, else [`ControlSettings::bound`].
pub fn control_bound(scene: &Scene, settings: &ControlSettings) -> f64 {
    scene.thrust().map_or(settings.bound(), |t| t.bound)
}

/// The PD law of a cell ([`ControlSettings::pd_gains`], or tuned on the first
/// [`ControlSettings::pd_training`] seconds of `scene`'s record in the scaled, bounded
/// parameters of [`pd::ScaledPdTuning`] from [`pd::PD_START`]: positive loop gains only).
///
/// # Errors
/// The tuning's errors ([`PdTuning::new`], [`pd::PdScales::of`], [`minimize`]);
/// [`crate::error::ValueError`] naming `pd_training` for a window that is not positive.
pub fn pd_law(scene: &Scene, settings: &ControlSettings) -> crate::Result<PdLaw> {
    let (interval, effort) = (settings.interval, settings.mpc.effort);
    let bound = control_bound(scene, settings);
    if let Some([bias, kp, kd]) = settings.pd_gains {
        return Ok(PdLaw {
            bias: Force2::z(bias),
            kp,
            kd,
            bound,
            spatial: false,
        });
    }
    let training = training_scene(scene, settings)?;
    let spot = hot_spot_objective(scene, settings)?;
    let mut tuning = PdTuning::new(&training, interval, bound, effort)?;
    if let Some(spot) = spot.clone() {
        tuning = tuning.at_hot_spot(spot);
    }
    let scaled = pd::ScaledPdTuning {
        tuning,
        scales: pd::PdScales::of_at(&training, bound, spot.as_ref())?,
    };
    let opts = OptimOptions {
        max_iters: settings.pd_max_iters,
        first_step: 0.1,
        bounds: Some(Bounds::symmetric(pd::PD_BOX)?),
        ..OptimOptions::default()
    };
    let r = minimize(&scaled, &pd::PD_START, &opts)?;
    let [bias, kp, kd] = scaled.scales.gains(&r.theta);
    Ok(PdLaw {
        bias: Force2::z(bias),
        kp,
        kd,
        bound,
        spatial: false,
    })
}

/// The scene cut to its training window: the first [`ControlSettings::pd_training`] seconds
/// (whole control intervals, at least one), or the whole scene without one.
///
/// # Errors
/// [`crate::error::ValueError`] naming `pd_training` for a window that is not positive;
/// [`MpcError::IntervalNotMultiple`].
pub fn training_scene(scene: &Scene, settings: &ControlSettings) -> crate::Result<Scene> {
    let mut training = scene.clone();
    if let Some(seconds) = settings.pd_training {
        Requirement::PositiveFinite
            .check("pd_training", seconds)
            .map_err(MpcError::from)?;
        let interval = settings.interval;
        let m = interval_steps(interval, scene.time.step)?;
        let intervals = ((seconds / interval).round() as usize).max(1);
        training.time.steps = (intervals * m).min(scene.time.steps);
    }
    Ok(training)
}

/// The scene with a cell's sea state: `[loads.waves]` `hs`, `tp` (and `direction` when
/// given) replaced, every other key (the seed among them) kept (module docs, "Sea states and
/// seeds").
///
/// # Errors
/// [`StudyError::SeaState`] when the scene has no `[loads.waves]` to set, or the values are
/// invalid for it (naming the key).
pub fn with_sea_state(scene: &Scene, sea: &SeaState, cell: usize) -> Result<Scene, StudyError> {
    let mut out = scene.clone();
    let Some(waves) = out.loads.waves.as_mut() else {
        return Err(StudyError::SeaState {
            cell,
            reason: "the scene has no [loads.waves] table whose hs and tp a scatter cell could \
                     set (docs/scene-format.md)"
                .to_string(),
        });
    };
    waves.hs = sea.hs;
    waves.tp = sea.tp;
    if let Some(direction) = sea.direction {
        waves.direction = direction;
    }
    out.validate().map_err(|e| StudyError::SeaState {
        cell,
        reason: format!(
            "H_s = {} m, T_p = {} s{}: {e}",
            sea.hs,
            sea.tp,
            sea.direction
                .map_or_else(String::new, |d| format!(", direction {d}°"))
        ),
    })?;
    Ok(out)
}

/// The scene's own sea state (`[loads.waves]` hs, tp, direction), if it has one.
pub fn scene_sea_state(scene: &Scene) -> Option<SeaState> {
    scene.loads.waves.map(|w| SeaState {
        hs: w.hs,
        tp: w.tp,
        direction: Some(w.direction),
    })
}

/// One (cell, controller) run: the cell's scene, the record, its damage.
fn run_cell(
    input: &StudyInput<'_>,
    (cell, seed): (usize, usize),
    kind: ControllerKind,
) -> Result<CellRun, StudyError> {
    let run_err = |source| StudyError::Run {
        controller: kind.name(),
        cell,
        source: Box::new(source),
    };
    // A cancelled study starts no further run (its sea's set-up alone can take seconds).
    crate::cancel::check().map_err(run_err)?;
    let mut settings = input.settings.clone();
    if kind == ControllerKind::Mpc && settings.mpc_fatigue_proxy {
        settings.mpc.objective = fatigue_proxy(input.spec, input.scene)?;
    }
    let scene = match input.cells {
        Some(cells) => with_sea_state(input.scene, &cells[cell].sea, cell)?,
        None => input.scene.clone(),
    };
    let scene = with_seed(&scene, seed)?;
    let scene = match settings.record {
        Some(record) => with_record(&scene, &settings, kind, record)?,
        None => scene,
    };
    let hotspots = &input.scene.hotspots;
    let (record, hot) = if hotspots.is_empty() {
        (
            run_controller(&scene, kind, &settings).map_err(run_err)?,
            None,
        )
    } else if kind.is_feedback() {
        let record = run_controller(&scene, kind, &settings).map_err(run_err)?;
        let decisions = record.decisions.as_deref().unwrap_or(&[]);
        let joints = crate::hotspots::hot_spot_joints(&scene.beam.lengths, hotspots);
        let replay =
            replay_joint_moments(&scene, settings.interval, decisions, &joints).map_err(run_err)?;
        (record, Some(replay))
    } else {
        let (record, joints) = run_open_loop_joints(&scene, kind, hotspots).map_err(run_err)?;
        (record, Some(joints))
    };
    let skip = spin_up_steps(&scene, input.settings.spin_up)?;
    let hot_assessed = match hot {
        Some(joints) => {
            crate::hotspots::assess_histories(&scene, hotspots, &joints, skip).map_err(run_err)?
        }
        None => Vec::new(),
    };
    let hot_damages: Vec<f64> = hot_assessed.iter().map(|h| h.assessment.damage).collect();
    let probability = input.cells.map_or(1.0, |c| c[cell].probability);
    // With a hot spot to act on, the cell's damage is that hot spot's (module docs, "The moment
    // the controllers act on").
    if let Some(h) = acted_hot_spot(input).map_err(run_err)? {
        let a = &hot_assessed[h].assessment;
        return Ok(CellRun {
            damage: CellDamage {
                probability,
                damage: a.damage,
                duration_s: a.duration_s,
            },
            force: record.force,
            gains: record.gains,
            thrust: record.thrust,
            hotspots: hot_damages,
        });
    }
    let a = assess(
        input.spec,
        MomentHistory {
            duration_s: record.duration_s - skip as f64 * input.scene.time.step,
            moment: &record.moment[skip..],
            moment_x: record.moment_x.as_deref().map(|m| &m[skip..]),
            measure: input.scene.moment_measure(),
        },
    )?;
    Ok(CellRun {
        damage: CellDamage {
            probability,
            damage: a.damage,
            duration_s: a.duration_s,
        },
        force: record.force,
        gains: record.gains,
        thrust: record.thrust,
        hotspots: hot_damages,
    })
}

/// The open-loop run (`scene`, `none`) of a scene with hot spots: its base-moment record and
/// the hot spots' joint torques from the same streamed run
/// ([`crate::hotspots::joint_moment_history`]).
fn run_open_loop_joints(
    scene: &Scene,
    kind: ControllerKind,
    hotspots: &[crate::hotspots::HotSpotSpec],
) -> crate::Result<(ControlledRecord, crate::hotspots::JointMoments)> {
    let mut free;
    let run = if kind == ControllerKind::None {
        free = scene.clone();
        free.control = None;
        &free
    } else {
        scene
    };
    let joints = crate::hotspots::hot_spot_joints(&run.beam.lengths, hotspots);
    let mut history = crate::hotspots::joint_moment_history(run, &joints)?;
    let record = ControlledRecord {
        duration_s: history.duration(),
        moment: std::mem::take(&mut history.base_moment),
        moment_x: history.base_moment_x.take(),
        force: None,
        gains: None,
        decisions: None,
        thrust: match (run.thrust().is_some(), kind) {
            (false, _) => None,
            (true, ControllerKind::None) => Some([0.0; 2]),
            (true, _) => Some(thrust_stats(&scene_controls(run)?)),
        },
    };
    Ok((record, history))
}

/// The joint torques of a closed loop, recomputed by replaying its decisions on the plant of
/// [`crate::mpc`]: the same plant, stepped with the same force held over each control interval,
/// so the same states as the closed loop's, bit for bit (its base moment is checked against the
/// closed loop's record in tests/fatigue/hotspots.rs). The closed loop records the base moment only;
/// this costs one more simulation of the record, not a re-plan.
///
/// # Errors
/// The plant's ([`crate::mpc::Plant`]), [`MpcError::IntervalNotMultiple`], and
/// [`MpcError::RunNotWhole`] when the decisions do not cover the run.
pub fn replay_joint_moments(
    scene: &Scene,
    interval: f64,
    decisions: &[f64],
    joints: &[usize],
) -> crate::Result<crate::hotspots::JointMoments> {
    let mut plant = crate::mpc::Plant::<f64, 2>::new(scene)?;
    let m = interval_steps(interval, plant.h())?;
    let steps = plant.steps();
    if steps != m * decisions.len() {
        return Err(MpcError::RunNotWhole {
            steps,
            interval_steps: m,
        }
        .into());
    }
    let mut moment = vec![Vec::with_capacity(steps + 1); joints.len()];
    let mut base = Vec::with_capacity(steps + 1);
    let mut record = |plant: &crate::mpc::Plant<f64, 2>, moment: &mut [Vec<f64>]| {
        crate::hotspots::push_joint_moments(
            plant.chain(),
            &plant.state().q,
            joints,
            moment,
            &mut [],
        );
        base.push(plant.moment());
    };
    for &u in decisions {
        plant.set_controls([0.0, u])?;
        for _ in 0..m {
            record(&plant, &mut moment);
            plant.advance()?;
        }
    }
    record(&plant, &mut moment);
    Ok(crate::hotspots::JointMoments {
        h: plant.h(),
        joints: joints.to_vec(),
        moment,
        moment_x: None,
        base_moment: base,
        base_moment_x: None,
    })
}

/// The seeds a study of `seeds` seeds per cell draws, s, s + 1, …, s + K − 1 (s the scene's
/// `[loads.waves]` seed), as reports list them: `None` with one seed or without a sea.
pub fn seeds_run(scene: &Scene, seeds: usize) -> Option<Vec<u64>> {
    let w = scene.loads.waves.as_ref().filter(|_| seeds > 1)?;
    Some(
        (0..seeds as u64)
            .map(|i| w.seed.saturating_add(i))
            .collect(),
    )
}

/// The scene with seed number `index` of a cell (module docs, "Records"): `[loads.waves]`
/// `seed` + `index`; the scene itself for index 0.
///
/// # Errors
/// [`StudyError::Seeds`] for index > 0 on a scene without `[loads.waves]`, or a seed past
/// the largest the scene file can hold (2⁶³ − 1).
pub fn with_seed(scene: &Scene, index: usize) -> Result<Scene, StudyError> {
    if index == 0 {
        return Ok(scene.clone());
    }
    let mut out = scene.clone();
    let err = |reason: &str| StudyError::Seeds {
        seeds: index + 1,
        reason: reason.to_string(),
    };
    let waves = out.loads.waves.as_mut().ok_or_else(|| {
        err("more than one seed needs a sea to draw ([loads.waves]); this scene has none")
    })?;
    waves.seed = waves
        .seed
        .checked_add(index as u64)
        .filter(|&s| s <= i64::MAX as u64)
        .ok_or_else(|| err("the seeds would pass 2^63 − 1"))?;
    Ok(out)
}

/// The scene run for `spin_up` + `record` seconds (module docs, "Records"): N = ⌈spin_up/h⌉ +
/// ⌈record/h⌉ steps, rounded up to whole control intervals for a closed-loop controller (so the
/// counted record is at least `record`; its exact duration is the cell's `duration_s`).
///
/// # Errors
/// [`StudyError::Record`] for a record that is not positive and finite, or a run the scene
/// refuses (too many steps, a load series that does not cover it: the message names the key);
/// [`StudyError::SpinUp`] for an invalid spin-up.
pub fn with_record(
    scene: &Scene,
    settings: &ControlSettings,
    kind: ControllerKind,
    record: f64,
) -> Result<Scene, StudyError> {
    let err = |reason: String| StudyError::Record { record, reason };
    if !(record.is_finite() && record > 0.0) {
        return Err(err("must be positive and finite".into()));
    }
    let h = scene.time.step;
    let spin_up = settings.spin_up;
    if !(spin_up.is_finite() && spin_up >= 0.0) {
        return Err(StudyError::SpinUp {
            spin_up,
            duration_s: spin_up + record,
        });
    }
    let steps_of = |t: f64| (t / h * (1.0 - 1e-12)).ceil();
    let mut steps = steps_of(spin_up) + steps_of(record).max(1.0);
    // An interval that is not a multiple of h is the run's own error (naming the interval).
    if let (true, Ok(m)) = (kind.is_feedback(), interval_steps(settings.interval, h)) {
        let m = m as f64;
        steps = (steps / m).ceil() * m;
    }
    if steps > crate::scene::MAX_STEPS as f64 {
        return Err(err(format!(
            "{steps} steps of h = {h} s, more than {} (time.steps' limit)",
            crate::scene::MAX_STEPS
        )));
    }
    let mut out = scene.clone();
    out.time.steps = steps as usize;
    out.validate().map_err(|e| err(e.to_string()))?;
    Ok(out)
}

/// The index in `input.scene`'s `[[fatigue.hotspot]]` of the hot spot the controllers act on
/// ([`MpcOptions::hotspot`]), `None` without one.
///
/// # Errors
/// [`MpcError::HotSpotUnknown`] when the scene has no hot spot of that name.
fn acted_hot_spot(input: &StudyInput<'_>) -> crate::Result<Option<usize>> {
    let Some(spot) = input.settings.mpc.hotspot.as_ref() else {
        return Ok(None);
    };
    let hotspots = &input.scene.hotspots;
    match hotspots.iter().position(|h| h.name == spot.name) {
        Some(h) => Ok(Some(h)),
        None => Err(MpcError::HotSpotUnknown {
            name: spot.name.clone(),
            known: hotspots
                .iter()
                .map(|h| h.name.as_str())
                .collect::<Vec<_>>()
                .join(", "),
        }
        .into()),
    }
}

/// The objective MPC plans on as the fatigue proxy: Σ|M₀(t_k)|^m with m the first slope of
/// `spec`'s S-N curve ([`WellheadDamage::exponent`]; m = 3 for the DNV curves C–W3, 4 for B1
/// and B2).
///
/// # Errors
/// The spec's [`FatigueError`].
pub fn fatigue_proxy(spec: &FatigueSpec, scene: &Scene) -> Result<ObjectiveKind, StudyError> {
    let exponent = WellheadDamage::new(spec, scene.moment_measure())?.exponent();
    Ok(ObjectiveKind::Power { exponent })
}

/// The steps of the spin-up window: ⌈spin_up/h⌉ (module docs, "The start of a record").
///
/// # Errors
/// [`StudyError::SpinUp`] for a window that is not finite and ≥ 0, or that leaves fewer than
/// two samples of the record.
pub fn spin_up_steps(scene: &Scene, spin_up: f64) -> Result<usize, StudyError> {
    let h = scene.time.step;
    let duration_s = h * scene.time.steps as f64;
    let steps = (spin_up / h * (1.0 - 1e-12)).ceil();
    if !(spin_up.is_finite() && spin_up >= 0.0) || steps >= scene.time.steps as f64 {
        return Err(StudyError::SpinUp {
            spin_up,
            duration_s,
        });
    }
    Ok(steps as usize)
}

/// The mean of the seeds' Miner sums Σᵢ Dᵢ/K (one seed: D itself, bit for bit).
fn combined_damage(seed_damages: &[f64]) -> f64 {
    seed_damages.iter().sum::<f64>() / seed_damages.len() as f64
}

/// What a study keeps of one (cell, seed, controller) run (not the record: a diagram of 30
/// cells of hour-long records would hold gigabytes). [`run_study_cell`] returns them, for a
/// caller that spreads cells over processes; [`combine_study`] combines them.
#[derive(Clone, Debug, PartialEq)]
pub struct CellRun {
    /// The cell's probability, the record's Miner sum at the wellhead and its duration.
    pub damage: CellDamage,
    /// The constant controller's force \[N\].
    pub force: Option<f64>,
    /// The PD law's gains.
    pub gains: Option<[f64; 3]>,
    /// (rms, peak) of the thrust \[N\] (a thrust scene; [`thrust_stats`]).
    pub thrust: Option<[f64; 2]>,
    /// The hot spots' Miner sums over the record, in the scene's `[[fatigue.hotspot]]` order
    /// (empty: none assessed).
    pub hotspots: Vec<f64>,
}

/// Checks a study's input before any run (module docs): the controllers, the seeds, the record
/// or spin-up of every controller, the cells and their probabilities. Returns the number of
/// cells (1 without a diagram).
fn check_study_input(input: &StudyInput<'_>) -> Result<usize, StudyError> {
    if input.controllers.is_empty() {
        return Err(StudyError::NoControllers);
    }
    input.spec.validate()?;
    // The hot spot to act on is one of the scene's (refused before any run otherwise).
    acted_hot_spot(input).map_err(|e| StudyError::Run {
        controller: ControllerKind::Mpc.name(),
        cell: 0,
        source: Box::new(e),
    })?;
    let seeds = input.settings.seeds;
    if !(1..=MAX_SEEDS).contains(&seeds) {
        return Err(StudyError::Seeds {
            seeds,
            reason: format!("must be 1 to {MAX_SEEDS}"),
        });
    }
    with_seed(input.scene, seeds - 1)?;
    for &kind in input.controllers {
        check_control_can_act(input.scene, kind)?;
        match input.settings.record {
            Some(record) => {
                with_record(input.scene, input.settings, kind, record)?;
            }
            None => {
                spin_up_steps(input.scene, input.settings.spin_up)?;
            }
        }
    }
    let n_cells = match input.cells {
        Some([]) => return Err(StudyError::NoCells),
        Some(cells) if cells.len() > MAX_SCATTER_CELLS => {
            return Err(StudyError::TooManyCells { cells: cells.len() })
        }
        Some(cells) => {
            // The probabilities are checked before hours of runs, not after.
            let dummy: Vec<CellDamage> = cells
                .iter()
                .map(|c| CellDamage {
                    probability: c.probability,
                    damage: 0.0,
                    duration_s: 1.0,
                })
                .collect();
            combine_scatter(&dummy)?;
            cells.len()
        }
        None => 1,
    };
    Ok(n_cells)
}

/// Runs every controller on every cell and combines the cells (module docs). `on_run` is called
/// after each (cell, controller) run, from the thread that ran it (a progress bar).
///
/// # Errors
/// [`StudyError::NoControllers`], [`StudyError::NoCells`], [`StudyError::ControlCannotAct`]
/// before any run; the first failed run's error in (cell, controller) order; the combination's
/// [`FatigueError`] (a probability outside \[0, 1\], a sum over 1).
pub fn run_study(input: &StudyInput<'_>, on_run: &(dyn Fn() + Sync)) -> Result<Study, StudyError> {
    let n_cells = check_study_input(input)?;
    let k_seeds = input.settings.seeds;
    let jobs: Vec<((usize, usize), ControllerKind)> = (0..n_cells)
        .flat_map(|s| (0..k_seeds).map(move |i| (s, i)))
        .flat_map(|si| input.controllers.iter().map(move |&k| (si, k)))
        .collect();
    let job = |&(si, k): &((usize, usize), ControllerKind)| {
        let r = run_cell(input, si, k);
        on_run();
        r
    };
    #[cfg(feature = "parallel")]
    let results: Vec<_> = jobs.par_iter().map(job).collect();
    #[cfg(not(feature = "parallel"))]
    let results: Vec<_> = jobs.iter().map(job).collect();
    let results = results.into_iter().collect::<Result<Vec<_>, _>>()?;
    combine_study(input, &results)
}

/// Runs cell `cell` of a study: each seed (seed-major) and each controller in the study's
/// order, one after the other — what [`run_study`] runs for that cell. For a caller that
/// spreads the cells over processes (the Python package's executor); [`combine_study`] then
/// combines every cell's runs exactly as [`run_study`] does (the same numbers bit for bit).
///
/// # Errors
/// As [`run_study`]; [`StudyError::CellIndex`] for a cell past the diagram's last.
pub fn run_study_cell(input: &StudyInput<'_>, cell: usize) -> Result<Vec<CellRun>, StudyError> {
    let n_cells = check_study_input(input)?;
    if cell >= n_cells {
        return Err(StudyError::CellIndex {
            cell,
            cells: n_cells,
        });
    }
    let mut runs = Vec::with_capacity(input.settings.seeds * input.controllers.len());
    for seed in 0..input.settings.seeds {
        for &kind in input.controllers {
            runs.push(run_cell(input, (cell, seed), kind)?);
        }
    }
    Ok(runs)
}

/// Combines a study's runs (module docs): `results` holds every cell's [`run_study_cell`] runs,
/// cell after cell (cell-major, then seed, then controller).
///
/// # Errors
/// [`StudyError::RunCount`] when `results` does not hold one run per (cell, seed, controller);
/// the combination's [`FatigueError`].
pub fn combine_study(input: &StudyInput<'_>, results: &[CellRun]) -> Result<Study, StudyError> {
    let n_cells = input.cells.map_or(1, <[ScatterCell]>::len);
    let k_seeds = input.settings.seeds;
    let n_ctrl = input.controllers.len();
    if results.len() != n_cells * k_seeds * n_ctrl {
        return Err(StudyError::RunCount {
            expected: n_cells * k_seeds * n_ctrl,
            got: results.len(),
        });
    }
    let run_of = |s: usize, i: usize, j: usize| &results[(s * k_seeds + i) * n_ctrl + j];
    // The DFF of the damage the cells hold: the acted-on hot spot's, else the wellhead's.
    let dff = match acted_hot_spot(input).map_err(|e| StudyError::Run {
        controller: "mpc",
        cell: 0,
        source: Box::new(e),
    })? {
        Some(h) => input.scene.hotspots[h].spec.dff,
        None => input.spec.dff,
    };
    let mut controllers = Vec::with_capacity(n_ctrl);
    for (j, &kind) in input.controllers.iter().enumerate() {
        let seed_damages: Vec<Vec<f64>> = (0..n_cells)
            .map(|s| {
                (0..k_seeds)
                    .map(|i| run_of(s, i, j).damage.damage)
                    .collect()
            })
            .collect();
        // Each cell's damage is the mean over its seeds (one seed: the value itself).
        let cell_damages = |pick: &dyn Fn(usize) -> f64| -> Vec<CellDamage> {
            (0..n_cells)
                .map(|s| CellDamage {
                    damage: pick(s),
                    ..run_of(s, 0, j).damage
                })
                .collect()
        };
        let mean = combined_damage;
        let combined = combine_scatter(&cell_damages(&|s| mean(&seed_damages[s])))?;
        let mut seed_lives = Vec::with_capacity(k_seeds);
        for i in 0..k_seeds {
            let per_seed = combine_scatter(&cell_damages(&|s| seed_damages[s][i]))?;
            seed_lives.push(life_years(per_seed.damage_per_year, dff)?);
        }
        let mut hotspots = Vec::new();
        let assessed = !run_of(0, 0, j).hotspots.is_empty();
        for (h, spot) in input.scene.hotspots.iter().enumerate().filter(|_| assessed) {
            let damage = |s: usize| {
                let v: Vec<f64> = (0..k_seeds).map(|i| run_of(s, i, j).hotspots[h]).collect();
                mean(&v)
            };
            let total = combine_scatter(&cell_damages(&damage))?;
            hotspots.push(HotSpotOutcome {
                name: spot.name.clone(),
                elevation: spot.elevation,
                damage_per_year: total.damage_per_year,
                life_years: life_years(total.damage_per_year, spot.spec.dff)?,
                dff: spot.spec.dff,
            });
        }
        // The thrust of a cell over its seeds: rms of the seeds' records, the largest peak.
        let cell_thrust = |s: usize| -> Option<[f64; 2]> {
            let per_seed: Option<Vec<[f64; 2]>> =
                (0..k_seeds).map(|i| run_of(s, i, j).thrust).collect();
            per_seed.filter(|v| !v.is_empty()).map(|v| {
                let ms = v.iter().map(|t| t[0] * t[0]).sum::<f64>() / v.len() as f64;
                [ms.sqrt(), v.iter().fold(0.0f64, |m, t| m.max(t[1]))]
            })
        };
        let thrusts: Option<Vec<(f64, [f64; 2])>> = (0..n_cells)
            .map(|s| cell_thrust(s).map(|t| (run_of(s, 0, j).damage.probability, t)))
            .collect();
        let (thrust_rms, thrust_peak) = match &thrusts {
            Some(t) if !t.is_empty() => {
                let weight: f64 = t.iter().map(|(p, _)| p).sum();
                let ms: f64 = t.iter().map(|(p, x)| p * x[0] * x[0]).sum();
                let rms = if weight > 0.0 {
                    (ms / weight).sqrt()
                } else {
                    0.0
                };
                (
                    Some(rms),
                    Some(t.iter().fold(0.0f64, |m, (_, x)| m.max(x[1]))),
                )
            }
            _ => (None, None),
        };
        let cells = (0..n_cells)
            .zip(&combined.cells)
            .map(|(s, &per_year)| {
                let run = run_of(s, 0, j);
                CellOutcome {
                    sea: match input.cells {
                        Some(c) => Some(c[s].sea),
                        None => scene_sea_state(input.scene),
                    },
                    probability: run.damage.probability,
                    damage: combined_damage(&seed_damages[s]),
                    seed_damages: seed_damages[s].clone(),
                    duration_s: run.damage.duration_s,
                    damage_per_year: per_year,
                    force: run.force,
                    gains: run.gains,
                    thrust: cell_thrust(s),
                }
            })
            .collect();
        controllers.push(ControllerOutcome {
            kind,
            damage_per_year: combined.damage_per_year,
            life_years: life_years(combined.damage_per_year, dff)?,
            cells,
            seed_lives,
            hotspots,
            thrust_rms,
            thrust_peak,
        });
    }
    Ok(Study { controllers })
}
