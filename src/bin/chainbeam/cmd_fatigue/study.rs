//! `chainbeam fatigue --controller LIST` and `--scatter FILE`: the study of
//! [`chainbeam::fatigue_study::run_study`] from the flags, its JSON, and the scatter CSV reader.

use std::path::Path;

use serde::Serialize;

use chainbeam::fatigue::{FatigueSpec, ScatterCell};
use chainbeam::fatigue_study::{
    run_study, CellOutcome, ControlSettings, ControllerKind, ControllerOutcome, Study, StudyError,
    StudyInput,
};
use chainbeam::mpc::{Horizon, MpcOptions};
use chainbeam::ocp::OcpOptions;
use chainbeam::scene::{MpcPlanObjective, MpcSettings, MpcTable, MPC_KEYS};
use chainbeam::Scene;

use super::{FatigueArgs, MpcObjective};
use crate::cmd_mpc::setting_name;
use crate::progress::Progress;
use crate::{check_finite, check_force_flag, CliError};

/// One cell of a controller (or of the plain scatter run) in the JSON.
#[derive(Serialize)]
struct CellJson {
    hs: Option<f64>,
    tp: Option<f64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    direction: Option<f64>,
    probability: f64,
    damage_per_year: f64,
    damage: f64,
    duration_s: f64,
    #[serde(skip_serializing_if = "Option::is_none")]
    force: Option<f64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    gains: Option<[f64; 3]>,
}

/// One controller in the JSON.
#[derive(Serialize)]
struct ControllerJson {
    damage_per_year: f64,
    life_years: Option<f64>,
    cells: Vec<CellJson>,
}

/// An object keyed by controller name, in report order (none, constant, pd, mpc).
#[derive(Serialize)]
struct ByController<T> {
    #[serde(skip_serializing_if = "Option::is_none")]
    none: Option<T>,
    #[serde(skip_serializing_if = "Option::is_none")]
    constant: Option<T>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pd: Option<T>,
    #[serde(skip_serializing_if = "Option::is_none")]
    mpc: Option<T>,
}

impl<T> ByController<T> {
    fn new() -> Self {
        ByController {
            none: None,
            constant: None,
            pd: None,
            mpc: None,
        }
    }

    fn slot(&mut self, kind: ControllerKind) -> Option<&mut Option<T>> {
        match kind {
            ControllerKind::None => Some(&mut self.none),
            ControllerKind::Constant => Some(&mut self.constant),
            ControllerKind::Pd => Some(&mut self.pd),
            ControllerKind::Mpc => Some(&mut self.mpc),
            _ => None,
        }
    }
}

/// The closed-loop settings in the JSON.
#[derive(Serialize)]
struct SettingsJson {
    interval: f64,
    horizon: f64,
    iterations: usize,
    bound: f64,
    effort: f64,
    spin_up: f64,
    mpc_objective: &'static str,
}

/// `--controller` output.
#[derive(Serialize)]
struct ControllersReport {
    controllers: ByController<ControllerJson>,
    life_extension: ByController<Option<f64>>,
    settings: SettingsJson,
}

/// `--scatter` output without `--controller`.
#[derive(Serialize)]
struct ScatterReport {
    damage_per_year: f64,
    life_years: Option<f64>,
    cells: Vec<CellJson>,
}

fn cell_json(c: &CellOutcome) -> CellJson {
    CellJson {
        hs: c.sea.map(|s| s.hs),
        tp: c.sea.map(|s| s.tp),
        direction: c.sea.and_then(|s| s.direction),
        probability: c.probability,
        damage_per_year: c.damage_per_year,
        damage: c.damage,
        duration_s: c.duration_s,
        force: c.force,
        gains: c.gains,
    }
}

fn controller_json(scene_file: &Path, c: &ControllerOutcome) -> Result<ControllerJson, CliError> {
    let key = format!("controllers.{}", c.kind.name());
    check_finite(scene_file, &key, &[c.damage_per_year])?;
    for cell in &c.cells {
        check_finite(scene_file, &key, &[cell.damage, cell.damage_per_year])?;
        check_finite(scene_file, &key, cell.gains.as_ref().map_or(&[][..], |g| g))?;
    }
    Ok(ControllerJson {
        damage_per_year: c.damage_per_year,
        life_years: Some(c.life_years).filter(|l| l.is_finite()),
        cells: c.cells.iter().map(cell_json).collect(),
    })
}

/// The flags of the closed-loop settings as an `[mpc]` table (`None`: not given), the values
/// that override the scene's table ([`MpcTable::resolve`]).
fn flags(a: &FatigueArgs) -> MpcTable {
    MpcTable {
        pd_training: a.pd_training,
        objective: a.mpc_objective.map(|o| match o {
            MpcObjective::Power => MpcPlanObjective::Power,
            MpcObjective::Sum => MpcPlanObjective::Sum,
        }),
        ..a.mpc.table()
    }
}

/// What MPC plans on: the flag, else `mpc.objective`, else the fatigue proxy.
fn plan_objective(r: &MpcSettings) -> MpcPlanObjective {
    r.objective.unwrap_or(MpcPlanObjective::Power)
}

/// The closed-loop settings of the flags and the scene's `[mpc]` table.
fn settings(a: &FatigueArgs, r: &MpcSettings) -> Result<ControlSettings, CliError> {
    if r.bound.is_finite() {
        check_force_flag("--bound", r.bound)?;
    }
    Ok(ControlSettings {
        interval: r.interval,
        mpc: MpcOptions {
            horizon: Horizon::Seconds(r.horizon),
            iterations: r.iterations,
            effort: r.effort,
            ocp: OcpOptions::default().with_bound(r.bound),
            plan_pendulums: r.plan_pendulums,
            plan_step: r.plan_step,
            ..MpcOptions::default()
        },
        pd_training: r.pd_training,
        spin_up: a.spin_up,
        mpc_fatigue_proxy: plan_objective(r) == MpcPlanObjective::Power,
        ..ControlSettings::default()
    })
}

/// The flag (or the scene's `mpc.KEY` it came from) of a library argument name.
fn flag_of(name: &str, flags: &MpcTable, table: Option<&MpcTable>) -> Option<String> {
    let key = match name {
        "bounds" => "bound",
        "spin_up" => return Some("--spin-up".into()),
        other => other,
    };
    MPC_KEYS
        .contains(&key)
        .then(|| setting_name(flags, table, key))
}

/// A study's error as one line naming the scene (or the scatter file) and the flag.
fn study_error(a: &FatigueArgs, table: Option<&MpcTable>, e: StudyError) -> CliError {
    let scene = a.scene.display();
    match &e {
        StudyError::Run {
            controller,
            cell,
            source,
        } => {
            let named = source.argument_fault();
            let flags = flags(a);
            let flagged =
                named.and_then(|(name, reason)| flag_of(name, &flags, table).map(|f| (f, reason)));
            match flagged {
                Some((flag, reason)) => CliError::msg(format!(
                    "{scene}: controller `{controller}`, cell {cell}: {flag}: {reason}"
                )),
                None => CliError::msg(format!("{scene}: {e}")),
            }
        }
        StudyError::UnknownController { .. }
        | StudyError::DuplicateController { .. }
        | StudyError::NoControllers => CliError::msg(format!("--controller: {e}")),
        StudyError::SpinUp { .. } => CliError::msg(format!("{scene}: --spin-up: {e}")),
        StudyError::SeaState { .. } | StudyError::NoCells | StudyError::Fatigue(_)
            if a.scatter.is_some() =>
        {
            let file = a.scatter.as_deref().unwrap_or(&a.scene).display();
            CliError::msg(format!("{file} (with {scene}): {e}"))
        }
        _ => CliError::msg(format!("{scene}: {e}")),
    }
}

/// A study run from the flags: its outcome and the closed-loop settings it ran with.
pub struct Solved {
    study: Study,
    settings: MpcSettings,
}

/// Runs the study the flags ask for.
pub fn solve(
    a: &FatigueArgs,
    scene: &Scene,
    spec: &FatigueSpec,
    progress: &Progress,
) -> Result<Solved, CliError> {
    let kinds = match &a.controller {
        Some(list) => {
            let mut kinds =
                ControllerKind::parse_list(list).map_err(|e| study_error(a, None, e))?;
            if !kinds.contains(&ControllerKind::None) {
                // The reference of `life_extension`.
                kinds.insert(0, ControllerKind::None);
            }
            kinds
        }
        None => vec![ControllerKind::Scene],
    };
    let cells = match &a.scatter {
        Some(path) => Some(read_scatter(path)?),
        None => None,
    };
    let resolved = flags(a).resolve(scene.mpc.as_ref());
    let settings = settings(a, &resolved)?;
    let n_cells = cells.as_ref().map_or(1, Vec::len);
    let bar = progress.bar(
        (n_cells * kinds.len()) as u64,
        format!("{} cells × {} controllers", n_cells, kinds.len()),
    );
    let input = StudyInput {
        scene,
        spec,
        cells: cells.as_deref(),
        controllers: &kinds,
        settings: &settings,
    };
    let study = run_study(&input, &|| bar.inc(1));
    bar.finish_and_clear();
    let study = study.map_err(|e| study_error(a, scene.mpc.as_ref(), e))?;
    Ok(Solved {
        study,
        settings: resolved,
    })
}

/// The JSON of a study: per controller with `--controller`, else the scatter's plain run.
pub fn report(a: &FatigueArgs, solved: &Solved) -> Result<String, CliError> {
    match &a.controller {
        Some(_) => controllers_json(a, &solved.settings, &solved.study),
        None => {
            let c = &solved.study.controllers[0];
            let c = controller_json(&a.scene, c)?;
            crate::to_json(&ScatterReport {
                damage_per_year: c.damage_per_year,
                life_years: c.life_years,
                cells: c.cells,
            })
        }
    }
}

fn controllers_json(
    a: &FatigueArgs,
    settings: &MpcSettings,
    study: &Study,
) -> Result<String, CliError> {
    let mut controllers = ByController::new();
    let mut extension = ByController::new();
    for c in &study.controllers {
        if let Some(slot) = controllers.slot(c.kind) {
            *slot = Some(controller_json(&a.scene, c)?);
        }
        if let Some(slot) = extension.slot(c.kind) {
            *slot = Some(study.life_extension(c.kind));
        }
    }
    crate::to_json(&ControllersReport {
        controllers,
        life_extension: extension,
        settings: SettingsJson {
            interval: settings.interval,
            horizon: settings.horizon,
            iterations: settings.iterations,
            bound: settings.bound,
            effort: settings.effort,
            spin_up: a.spin_up,
            mpc_objective: plan_objective(settings).name(),
        },
    })
}

/// Reads a `--scatter` CSV: the library's reader
/// ([`chainbeam::fatigue::scatter::read_scatter_file`]: header `hs,tp,probability[,direction]`
/// in any order, each column once, no other column; probabilities adding up to (0, 1]). Errors
/// name the file, the line and the column.
pub fn read_scatter(path: &Path) -> Result<Vec<ScatterCell>, CliError> {
    chainbeam::fatigue::scatter::read_scatter_file(path).map_err(|e| CliError::msg(e.to_string()))
}
