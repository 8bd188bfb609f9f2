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
//! Every run starts from the scene's start (`[time] initial`, like `simulate` and the plant of
//! [`crate::mpc`]): by default the straight riser at rest, with the current and the sea switched
//! on at t = 0, so the riser swings out to its offset in the current, a start-up whose one large
//! half cycle a short record would count as fatigue. The first [`ControlSettings::spin_up`] seconds of every record are therefore left
//! out of the count (its damage and its duration T_s): the record of a cell runs spin-up + T_s
//! seconds (the controllers act, and MPC and the constant force plan, over all of it). The
//! spin-up must outlast the start-up transient: measured on `riser_300m` (docs/cli.md,
//! `fatigue`, "The start of a record"). Starting instead from the static equilibrium in the
//! current (`initial = "static"`, [`crate::statics::static_start`]) removes the current's part
//! but not the sea's (the waves start at t = 0 on a riser at rest, which then takes the riser's
//! first periods to settle), so a window is needed either way.
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
use crate::scene::{ObjectiveKind, Scene, Support, ValidScene};
use crate::simulate::moment_history;

mod controllers;
mod error;
mod outcome;
pub mod pd;
mod scenes;

use controllers::scene_controls;
pub use controllers::{
    best_constant_at_hot_spot, check_control_can_act, control_bound, pd_law, run_controller,
    training_scene,
};
pub use error::StudyError;
pub use outcome::{
    thrust_stats, CellOutcome, ControlledRecord, ControllerOutcome, HotSpotOutcome, LifeRange,
    SeedSpread, Study, WorseThanNone,
};
pub use scenes::{
    cell_scene, fatigue_proxy, scene_sea_state, seeds_run, spin_up_steps, with_record,
    with_sea_state, with_seed,
};

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
    // The cell's scene validated once for its sea state and record (the seed cannot break
    // it); the runs take it without validating it again.
    let seeded = with_seed(input.scene, seed)?;
    let sea = input.cells.map(|cells| (&cells[cell].sea, cell));
    let record = settings.record.map(|r| (&settings, kind, r));
    let scene = match (sea, record) {
        (None, None) => seeded.into_valid().map_err(|e| run_err(e.into()))?,
        _ => cell_scene(&seeded, sea, record)?,
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
    let (damage, duration_s) = match acted_hot_spot(input).map_err(run_err)? {
        Some(h) => {
            let a = &hot_assessed[h].assessment;
            (a.damage, a.duration_s)
        }
        None => {
            let a = assess(
                input.spec,
                MomentHistory {
                    duration_s: record.duration_s - skip as f64 * input.scene.time.step,
                    moment: &record.moment[skip..],
                    moment_x: record.moment_x.as_deref().map(|m| &m[skip..]),
                    measure: input.scene.moment_measure(),
                },
            )?;
            (a.damage, a.duration_s)
        }
    };
    Ok(CellRun {
        damage: CellDamage {
            probability,
            damage,
            duration_s,
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
    scene: &ValidScene,
    kind: ControllerKind,
    hotspots: &[crate::hotspots::HotSpotSpec],
) -> crate::Result<(ControlledRecord, crate::hotspots::JointMoments)> {
    let free;
    let run = if kind == ControllerKind::None {
        free = scene.without_control();
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

/// The design fatigue factor of the damage a study's cells hold: the acted-on hot spot's
/// ([`MpcOptions::hotspot`](crate::mpc::MpcOptions::hotspot)), else the wellhead's.
fn study_dff(input: &StudyInput<'_>) -> Result<f64, StudyError> {
    let acted = acted_hot_spot(input).map_err(|e| StudyError::Run {
        controller: "mpc",
        cell: 0,
        source: Box::new(e),
    })?;
    Ok(match acted {
        Some(h) => input.scene.hotspots[h].spec.dff,
        None => input.spec.dff,
    })
}

/// The thrust over the diagram from each cell's (probability, [rms, peak]): the rms weighted by
/// the probabilities, √(Σ p_s F_s² / Σ p_s) (0 when they sum to 0), and the largest peak;
/// `None` for a study without thrust.
fn diagram_thrust(thrusts: Option<&[(f64, [f64; 2])]>) -> (Option<f64>, Option<f64>) {
    match thrusts {
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
    }
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
    let dff = study_dff(input)?;
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
        let (thrust_rms, thrust_peak) = diagram_thrust(thrusts.as_deref());
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
