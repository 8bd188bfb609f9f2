//! `chainbeam fatigue --controller LIST` and `--scatter FILE`: the study of
//! [`chainbeam::fatigue_study::run_study`] from the flags, its JSON, and the scatter CSV reader.

use std::path::Path;

use serde::Serialize;

use chainbeam::fatigue::{FatigueSpec, ScatterCell};
use chainbeam::fatigue_study::{
    run_study, seeds_run, CellOutcome, ControlSettings, ControllerKind, ControllerOutcome, Study,
    StudyError, StudyInput, WorseThanNone, PRACTICE_RECORD_S,
};
use chainbeam::mpc::{Horizon, MpcOptions};
use chainbeam::ocp::OcpOptions;
use chainbeam::scene::{MpcPlanObjective, MpcSettings, MpcTable, MPC_KEYS};
use chainbeam::Scene;

use super::{FatigueArgs, HotSpotJson, MpcObjective};
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
    /// The thrust on the vessel in the cell (a thrust scene) \[N\].
    #[serde(skip_serializing_if = "Option::is_none")]
    thrust_rms: Option<f64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    thrust_peak: Option<f64>,
    /// With more than one seed: the seeds' Miner sums (in seed order), their sample standard
    /// deviation (K − 1 in the denominator), least and greatest; `damage` is their mean.
    #[serde(skip_serializing_if = "Option::is_none")]
    seed_damages: Option<Vec<f64>>,
    #[serde(skip_serializing_if = "Option::is_none")]
    damage_std: Option<f64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    damage_min: Option<f64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    damage_max: Option<f64>,
    /// A closed-loop controller's damage over no control's in the same cell (above 1: worse
    /// than no control, also said on stderr).
    #[serde(skip_serializing_if = "Option::is_none")]
    damage_ratio_to_none: Option<f64>,
}

/// With more than one seed, each seed's life and their range (`null`: an infinite life).
#[derive(Serialize)]
struct SeedLives {
    life_years_seeds: Vec<Option<f64>>,
    life_years_min: Option<f64>,
    life_years_max: Option<f64>,
}

impl SeedLives {
    /// `None` with one seed (the JSON keeps its shape).
    fn of(c: &ControllerOutcome) -> Option<Self> {
        c.seed_life_range().map(|range| {
            let finite = |l: f64| Some(l).filter(|l| l.is_finite());
            SeedLives {
                life_years_seeds: c.seed_lives.iter().map(|&l| finite(l)).collect(),
                life_years_min: finite(range.min),
                life_years_max: finite(range.max),
            }
        })
    }
}

/// One controller in the JSON.
#[derive(Serialize)]
struct ControllerJson {
    damage_per_year: f64,
    life_years: Option<f64>,
    #[serde(flatten, skip_serializing_if = "Option::is_none")]
    seed_lives: Option<SeedLives>,
    #[serde(skip_serializing_if = "Option::is_none")]
    hotspots: Option<Vec<HotSpotJson>>,
    #[serde(skip_serializing_if = "Option::is_none")]
    critical: Option<String>,
    /// The thrust on the vessel over the diagram (a thrust scene) \[N\]: the
    /// probability-weighted rms and the peak ([`ControllerOutcome::thrust_rms`]).
    #[serde(skip_serializing_if = "Option::is_none")]
    thrust_rms: Option<f64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    thrust_peak: Option<f64>,
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
    record: Option<f64>,
    seeds: usize,
    /// What MPC's plan started from ("state" or "sensors").
    observe: &'static str,
    /// The hot spot the controllers acted on, whose damage and life the controllers' numbers
    /// are (absent: the chain's base moment).
    #[serde(skip_serializing_if = "Option::is_none")]
    hotspot: Option<String>,
    /// What MPC measured the hot spot's moment from ("mean"; absent: "zero", as before).
    #[serde(skip_serializing_if = "Option::is_none")]
    moment_about: Option<&'static str>,
    /// MPC's reduced planning model's pendulums (absent: the model's own).
    #[serde(skip_serializing_if = "Option::is_none")]
    plan_pendulums: Option<usize>,
    /// MPC's planning step \[s\] (absent: the model's own).
    #[serde(skip_serializing_if = "Option::is_none")]
    plan_step: Option<f64>,
}

/// `--controller` output.
#[derive(Serialize)]
struct ControllersReport {
    controllers: ByController<ControllerJson>,
    life_extension: ByController<Option<f64>>,
    settings: SettingsJson,
    /// The seeds run, s..s+K−1 (with more than one).
    #[serde(skip_serializing_if = "Option::is_none")]
    seeds: Option<Vec<u64>>,
}

/// `--scatter` (or `--seeds`) output without `--controller`.
#[derive(Serialize)]
struct ScatterReport {
    damage_per_year: f64,
    life_years: Option<f64>,
    #[serde(flatten, skip_serializing_if = "Option::is_none")]
    seed_lives: Option<SeedLives>,
    #[serde(skip_serializing_if = "Option::is_none")]
    hotspots: Option<Vec<HotSpotJson>>,
    #[serde(skip_serializing_if = "Option::is_none")]
    critical: Option<String>,
    /// The seeds run, s..s+K−1 (with more than one).
    #[serde(skip_serializing_if = "Option::is_none")]
    seeds: Option<Vec<u64>>,
    cells: Vec<CellJson>,
}

fn cell_json(c: &CellOutcome, ratio_to_none: Option<f64>) -> CellJson {
    let spread = c.seed_spread();
    CellJson {
        seed_damages: spread.map(|_| c.seed_damages.clone()),
        damage_std: spread.map(|s| s.std),
        damage_min: spread.map(|s| s.min),
        damage_max: spread.map(|s| s.max),
        damage_ratio_to_none: ratio_to_none,
        hs: c.sea.map(|s| s.hs),
        tp: c.sea.map(|s| s.tp),
        direction: c.sea.and_then(|s| s.direction),
        probability: c.probability,
        damage_per_year: c.damage_per_year,
        damage: c.damage,
        duration_s: c.duration_s,
        force: c.force,
        gains: c.gains,
        thrust_rms: c.thrust.map(|t| t[0]),
        thrust_peak: c.thrust.map(|t| t[1]),
    }
}

fn controller_json(
    scene_file: &Path,
    study: &Study,
    c: &ControllerOutcome,
) -> Result<ControllerJson, CliError> {
    let key = format!("controllers.{}", c.kind.name());
    check_finite(scene_file, &key, &[c.damage_per_year])?;
    for cell in &c.cells {
        check_finite(scene_file, &key, &[cell.damage, cell.damage_per_year])?;
        check_finite(scene_file, &key, &cell.seed_damages)?;
        check_finite(scene_file, &key, cell.gains.as_ref().map_or(&[][..], |g| g))?;
    }
    let mut hotspots = None;
    let mut critical = None;
    if !c.hotspots.is_empty() {
        let mut spots = Vec::with_capacity(c.hotspots.len());
        for h in &c.hotspots {
            check_finite(scene_file, &format!("{key}.hotspots"), &[h.damage_per_year])?;
            spots.push(HotSpotJson {
                name: h.name.clone(),
                elevation: h.elevation,
                joint: None,
                joint_elevation: None,
                damage: None,
                damage_per_year: h.damage_per_year,
                life_years: Some(h.life_years).filter(|l| l.is_finite()),
            });
        }
        critical =
            chainbeam::hotspots::critical(c.hotspots.iter().map(|h| (h.damage_per_year, h.dff)))
                .map(|i| c.hotspots[i].name.clone());
        hotspots = Some(spots);
    }
    Ok(ControllerJson {
        damage_per_year: c.damage_per_year,
        life_years: Some(c.life_years).filter(|l| l.is_finite()),
        seed_lives: SeedLives::of(c),
        hotspots,
        critical,
        thrust_rms: c.thrust_rms,
        thrust_peak: c.thrust_peak,
        cells: c
            .cells
            .iter()
            .enumerate()
            .map(|(s, cell)| {
                let ratio = c
                    .kind
                    .is_feedback()
                    .then(|| study.damage_ratio_to_none(c.kind, s))
                    .flatten();
                cell_json(cell, ratio)
            })
            .collect(),
    })
}

/// One stderr line per (closed-loop controller, cell) whose damage is above no control's in
/// that cell ([`Study::worse_than_none`]): the run still exits 0 with its outputs, and the
/// cell's `damage_ratio_to_none` says the same, but a controller that does harm is never
/// reported as a success in silence.
pub fn warnings(a: &FatigueArgs, solved: &Solved) -> Vec<String> {
    solved
        .study
        .worse_than_none()
        .iter()
        .map(|w| worse_than_none_line(&a.scene, w, &solved.study))
        .collect()
}

fn worse_than_none_line(scene: &Path, w: &WorseThanNone, study: &Study) -> String {
    let sea = study
        .get(w.controller)
        .and_then(|c| c.cells.get(w.cell))
        .and_then(|c| c.sea)
        .map_or_else(String::new, |s| {
            format!(" (H_s = {} m, T_p = {} s)", s.hs, s.tp)
        });
    format!(
        "{}: warning: controller `{}`, cell {}{sea}: damage {:.6e} above no control's {:.6e} \
         (ratio {:.4}): the controller made the fatigue worse in this cell",
        scene.display(),
        w.controller.name(),
        w.cell,
        w.damage,
        w.none,
        w.damage / w.none
    )
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
fn settings(a: &FatigueArgs, r: &MpcSettings, scene: &Scene) -> Result<ControlSettings, CliError> {
    if r.bound.is_finite() {
        check_force_flag("--bound", r.bound)?;
    }
    a.mpc.check_forecast_error()?;
    Ok(ControlSettings {
        interval: r.interval,
        mpc: MpcOptions {
            horizon: Horizon::Seconds(r.horizon),
            iterations: r.iterations,
            effort: r.effort,
            ocp: OcpOptions::default().with_bound(r.bound),
            plan_pendulums: r.plan_pendulums,
            plan_step: r.plan_step,
            forecast: r.forecast,
            forecast_error: r.forecast_error,
            forecast_seed: r.forecast_seed,
            observe: r.observe,
            hotspot: r.hotspot_spec(scene).map_err(|e| {
                let flags = flags(a);
                let flag = setting_name(&flags, scene.mpc.as_ref(), e.argument());
                CliError::msg(format!("{}: {flag}: {e}", a.scene.display()))
            })?,
            moment_about: r.moment_about,
            ..MpcOptions::default()
        },
        pd_training: r.pd_training,
        spin_up: a.spin_up,
        mpc_fatigue_proxy: plan_objective(r) == MpcPlanObjective::Power,
        record: Some(a.record.unwrap_or(PRACTICE_RECORD_S)),
        seeds: a.seeds,
        ..ControlSettings::default()
    })
}

/// The flag (or the scene's `mpc.KEY` it came from) of a library argument name.
fn flag_of(name: &str, flags: &MpcTable, table: Option<&MpcTable>) -> Option<String> {
    let key = match name {
        "bounds" => "bound",
        "spin_up" => return Some("--spin-up".into()),
        "record" => return Some("--record".into()),
        "seeds" => return Some("--seeds".into()),
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
        StudyError::Record { .. } => CliError::msg(format!("{scene}: --record: {e}")),
        StudyError::Seeds { .. } => CliError::msg(format!("{scene}: --seeds: {e}")),
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
    /// The seeds run, with more than one.
    seeds: Option<Vec<u64>>,
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
    let settings = settings(a, &resolved, scene)?;
    let n_cells = cells.as_ref().map_or(1, Vec::len);
    let bar = progress.bar(
        (n_cells * a.seeds * kinds.len()) as u64,
        format!(
            "{} cells × {} seeds × {} controllers",
            n_cells,
            a.seeds,
            kinds.len()
        ),
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
    let seeds = seeds_run(scene, a.seeds);
    Ok(Solved {
        study,
        settings: resolved,
        seeds,
    })
}

/// The JSON of a study: per controller with `--controller`, else the scatter's plain run.
pub fn report(a: &FatigueArgs, solved: &Solved) -> Result<String, CliError> {
    match &a.controller {
        Some(_) => controllers_json(a, solved),
        None => {
            let c = &solved.study.controllers[0];
            let c = controller_json(&a.scene, &solved.study, c)?;
            crate::to_json(&ScatterReport {
                damage_per_year: c.damage_per_year,
                life_years: c.life_years,
                seed_lives: c.seed_lives,
                hotspots: c.hotspots,
                critical: c.critical,
                seeds: solved.seeds.clone(),
                cells: c.cells,
            })
        }
    }
}

fn controllers_json(a: &FatigueArgs, solved: &Solved) -> Result<String, CliError> {
    let (settings, study) = (&solved.settings, &solved.study);
    let mut controllers = ByController::new();
    let mut extension = ByController::new();
    for c in &study.controllers {
        if let Some(slot) = controllers.slot(c.kind) {
            *slot = Some(controller_json(&a.scene, study, c)?);
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
            record: Some(a.record.unwrap_or(PRACTICE_RECORD_S)),
            seeds: a.seeds,
            observe: settings.observe.name(),
            hotspot: settings.hotspot.clone(),
            moment_about: crate::cmd_mpc::moment_about_json(settings.moment_about),
            plan_pendulums: settings.plan_pendulums,
            plan_step: settings.plan_step,
        },
        seeds: solved.seeds.clone(),
    })
}

/// Reads a `--scatter` CSV: the library's reader
/// ([`chainbeam::fatigue::scatter::read_scatter_file`]: header `hs,tp,probability[,direction]`
/// in any order, each column once, no other column; probabilities adding up to (0, 1]). Errors
/// name the file, the line and the column.
pub fn read_scatter(path: &Path) -> Result<Vec<ScatterCell>, CliError> {
    chainbeam::fatigue::scatter::read_scatter_file(path).map_err(|e| CliError::msg(e.to_string()))
}

#[cfg(test)]
mod tests {
    use super::worse_than_none_line;
    use chainbeam::fatigue::SeaState;
    use chainbeam::fatigue_study::{
        CellOutcome, ControllerKind, ControllerOutcome, Study, WorseThanNone,
    };
    use std::path::Path;

    fn outcome(kind: ControllerKind, damages: &[f64]) -> ControllerOutcome {
        ControllerOutcome {
            kind,
            damage_per_year: 0.0,
            life_years: f64::INFINITY,
            cells: damages
                .iter()
                .map(|&d| CellOutcome {
                    sea: Some(SeaState {
                        hs: 2.5,
                        tp: 9.0,
                        direction: None,
                    }),
                    probability: 0.5,
                    damage: d,
                    seed_damages: vec![d],
                    duration_s: 1.0,
                    damage_per_year: 0.0,
                    force: None,
                    gains: None,
                    thrust: None,
                })
                .collect(),
            seed_lives: vec![f64::INFINITY],
            hotspots: Vec::new(),
            thrust_rms: None,
            thrust_peak: None,
        }
    }

    /// Study::worse_than_none lists exactly the closed-loop cells above `none`'s damage (not the
    /// equal or lower ones, nor `none` itself), and the warning names the scene, the controller,
    /// the cell's sea, both damages and their ratio.
    #[test]
    fn worse_than_none_cells_and_their_warning() {
        let study = Study {
            controllers: vec![
                outcome(ControllerKind::None, &[2.0, 2.0, 0.0]),
                outcome(ControllerKind::Pd, &[3.0, 2.0, 0.0]),
                outcome(ControllerKind::Mpc, &[1.0, 2.5, 0.0]),
            ],
        };
        let w = study.worse_than_none();
        assert_eq!(
            w,
            [
                WorseThanNone {
                    controller: ControllerKind::Pd,
                    cell: 0,
                    damage: 3.0,
                    none: 2.0
                },
                WorseThanNone {
                    controller: ControllerKind::Mpc,
                    cell: 1,
                    damage: 2.5,
                    none: 2.0
                }
            ]
        );
        assert_eq!(study.damage_ratio_to_none(ControllerKind::Pd, 0), Some(1.5));
        assert_eq!(study.damage_ratio_to_none(ControllerKind::Pd, 2), None);
        let line = worse_than_none_line(Path::new("s.toml"), &w[0], &study);
        assert!(
            line.starts_with("s.toml: warning: controller `pd`, cell 0"),
            "{line}"
        );
        assert!(line.contains("H_s = 2.5 m, T_p = 9 s"), "{line}");
        assert!(
            line.contains("3.000000e0") && line.contains("2.000000e0"),
            "{line}"
        );
        assert!(line.contains("ratio 1.5000"), "{line}");
    }
}
