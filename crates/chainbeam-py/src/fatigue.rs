//! `fatigue`: the command line's `chainbeam fatigue` (plain, `--scatter`, `--controller`) on the
//! same library calls (src/bin/chainbeam/cmd_fatigue.rs, cmd_fatigue/study.rs), returning its
//! JSON's fields as Python dicts, lists and floats; and the two halves of a study that
//! `chainbeam.fatigue(..., executor=...)` spreads over an executor: [`_fatigue_cell`] (every
//! controller on one cell, `run_study` of a one-cell diagram) and [`_fatigue_combine`] (the cells
//! combined as `run_study` combines them: `combine_scatter`, `life_years`, `life_extension`).

use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList};

use chainbeam::fatigue::scatter::reduced_north_atlantic;
use chainbeam::fatigue::{
    assess, combine_scatter, life_years, CellDamage, FatigueError, FatigueSpec, MomentHistory,
    ScatterCell, SeaState,
};
use chainbeam::fatigue_study::{
    run_study, spin_up_steps, CellOutcome, ControlSettings, ControllerKind, ControllerOutcome,
    Study, StudyError, StudyInput,
};
use chainbeam::mpc::{Horizon, MpcOptions};
use chainbeam::ocp::OcpOptions;
use chainbeam::scene::{MpcPlanObjective, MpcSettings, MpcTable, FORCE_RANGE, MPC_KEYS};

use crate::errors::{check, Failure};
use crate::run::{interruptible, watched, with_pool};
use crate::scene::Scene;

/// A scatter cell as Python passes it: (hs, tp, probability, direction or None).
type CellTuple = (f64, f64, f64, Option<f64>);

/// One (cell, controller) run as it travels between processes: (probability, damage,
/// duration_s, force, gains).
type RunTuple = (f64, f64, f64, Option<f64>, Option<[f64; 3]>);

/// The closed-loop settings as the package passes them: the command line's flags `--interval
/// --horizon --iterations --bound --effort --plan-pendulums --plan-step --pd-training
/// --mpc-objective` (`None`: not given, the scene's `[mpc]` key or the default then) and
/// `--spin-up`.
///
/// Extracted by hand, item by item: a value of the wrong type or range (a negative
/// `iterations`, `spin_up="soon"`) raises `InvalidArgumentError` with `.key` the argument's name,
/// not pyo3's `TypeError` naming the struct's field.
#[derive(Clone)]
pub struct Settings {
    interval: Option<f64>,
    horizon: Option<f64>,
    iterations: Option<usize>,
    bound: Option<f64>,
    effort: Option<f64>,
    plan_pendulums: Option<usize>,
    plan_step: Option<f64>,
    pd_training: Option<f64>,
    mpc_objective: Option<String>,
    spin_up: f64,
}

impl<'a, 'py> FromPyObject<'a, 'py> for Settings {
    type Error = PyErr;

    fn extract(obj: Borrowed<'a, 'py, PyAny>) -> PyResult<Self> {
        // The item `name` (absent or None: not given), converted to T, or an
        // InvalidArgumentError naming the argument.
        fn item<'py, T: for<'b> FromPyObject<'b, 'py>>(
            obj: Borrowed<'_, 'py, PyAny>,
            name: &str,
            expected: &str,
        ) -> PyResult<Option<T>> {
            let py = obj.py();
            let value = match obj.get_item(name) {
                Ok(v) if !v.is_none() => v,
                _ => return Ok(None),
            };
            value.extract::<T>().map(Some).map_err(|_| {
                let shown = value
                    .repr()
                    .map(|r| r.to_string())
                    .unwrap_or_else(|_| "?".into());
                Failure::argument(name, format!("{name}: expected {expected}, got {shown}"))
                    .into_py(py)
            })
        }
        const COUNT: &str = "a non-negative integer";
        const NUMBER: &str = "a number";
        let spin_up = item::<f64>(obj, "spin_up", "a number of seconds")?.unwrap_or(0.0);
        Ok(Settings {
            interval: item(obj, "interval", NUMBER)?,
            horizon: item(obj, "horizon", NUMBER)?,
            iterations: item(obj, "iterations", COUNT)?,
            bound: item(obj, "bound", NUMBER)?,
            effort: item(obj, "effort", NUMBER)?,
            plan_pendulums: item(obj, "plan_pendulums", COUNT)?,
            plan_step: item(obj, "plan_step", NUMBER)?,
            pd_training: item(obj, "pd_training", NUMBER)?,
            mpc_objective: item(obj, "mpc_objective", "\"power\" or \"sum\"")?,
            spin_up,
        })
    }
}

/// Reads a scatter-diagram CSV by the library's reader
/// ([`chainbeam::fatigue::scatter::read_scatter_file`]: the bounded input reader, so `/dev/zero`,
/// a huge or sparse file, a directory or a non-UTF-8 file fail at once, naming the file), as
/// cells (hs, tp, probability, direction or None). Errors raise `InvalidArgumentError` with
/// `.key` `scatter` and `.file` the file.
#[pyfunction]
pub fn _read_scatter(py: Python<'_>, path: std::path::PathBuf) -> PyResult<Vec<CellTuple>> {
    let read = interruptible(py, move || {
        chainbeam::fatigue::scatter::read_scatter_file(&path)
    })?;
    match read {
        Ok(cells) => Ok(cells
            .iter()
            .map(|c| (c.sea.hs, c.sea.tp, c.probability, c.sea.direction))
            .collect()),
        Err(e) => Err(crate::errors::raise(
            py,
            "InvalidArgumentError",
            &format!("scatter: {e}"),
            "InvalidArgument",
            Some("scatter"),
            Some(e.file.display().to_string()),
        )),
    }
}

/// The settings a study ran with (the command line's `settings` in the JSON) and the scene's
/// table they were resolved with (for naming a setting in an error).
struct Resolved {
    given: MpcTable,
    table: Option<MpcTable>,
    settings: MpcSettings,
    spin_up: f64,
}

impl Resolved {
    /// The objective MPC plans on: the argument, else `mpc.objective`, else the fatigue proxy.
    fn objective(&self) -> MpcPlanObjective {
        self.settings.objective.unwrap_or(MpcPlanObjective::Power)
    }

    /// How an error names the setting `key` (an `[mpc]` key): the scene's `mpc.KEY` when the
    /// value came from its table, else the Python argument.
    fn fault(&self, key: &str, message: String) -> Failure {
        if self.given.defers_to(self.table.as_ref(), key) {
            Failure::SceneKey {
                key: format!("mpc.{key}"),
                message: format!("mpc.{key}: {message}"),
            }
        } else {
            let name = if key == "objective" {
                "mpc_objective"
            } else {
                key
            };
            Failure::argument(name, message)
        }
    }
}

impl Settings {
    /// The arguments over the scene's `[mpc]` table ([`MpcTable::resolve`], the command line's
    /// precedence).
    fn resolve(&self, scene: &chainbeam::Scene) -> Result<Resolved, Failure> {
        let objective = match self.mpc_objective.as_deref() {
            None => None,
            Some("power") => Some(MpcPlanObjective::Power),
            Some("sum") => Some(MpcPlanObjective::Sum),
            Some(other) => {
                return Err(Failure::argument(
                    "mpc_objective",
                    format!("unknown objective {other:?}; expected \"power\" or \"sum\""),
                ))
            }
        };
        let given = MpcTable {
            interval: self.interval,
            horizon: self.horizon,
            iterations: self.iterations,
            bound: self.bound,
            effort: self.effort,
            plan_pendulums: self.plan_pendulums,
            plan_step: self.plan_step,
            pd_training: self.pd_training,
            objective,
        };
        Ok(Resolved {
            given,
            table: scene.mpc,
            settings: given.resolve(scene.mpc.as_ref()),
            spin_up: self.spin_up,
        })
    }

    /// The library's settings (the command line's `settings`) and what they were resolved from.
    fn control(&self, scene: &chainbeam::Scene) -> Result<(ControlSettings, Resolved), Failure> {
        let r = self.resolve(scene)?;
        let s = &r.settings;
        if s.bound.is_finite() && !FORCE_RANGE.contains(s.bound) {
            return Err(r.fault(
                "bound",
                format!(
                    "{:e}: outside the supported force range [{:e}, {:e}] N",
                    s.bound, FORCE_RANGE.min, FORCE_RANGE.max
                ),
            ));
        }
        let control = ControlSettings {
            interval: s.interval,
            mpc: MpcOptions {
                horizon: Horizon::Seconds(s.horizon),
                iterations: s.iterations,
                effort: s.effort,
                ocp: OcpOptions::default().with_bound(s.bound),
                plan_pendulums: s.plan_pendulums,
                plan_step: s.plan_step,
                ..MpcOptions::default()
            },
            pd_training: s.pd_training,
            spin_up: self.spin_up,
            mpc_fatigue_proxy: r.objective() == MpcPlanObjective::Power,
            ..ControlSettings::default()
        };
        Ok((control, r))
    }
}

/// The scene's fatigue assessment (`Scene::fatigue_spec`: the `[fatigue]` table, else the
/// `[pipe]`'s section; the command line's refusal with neither).
fn spec(scene: &chainbeam::Scene) -> Result<FatigueSpec, Failure> {
    scene.fatigue_spec().ok_or_else(|| Failure::SceneKey {
        key: "fatigue".into(),
        message: "key `fatigue`: fatigue needs a [fatigue] table with outer_diameter and \
                  wall_thickness, or a [pipe] table whose section it takes (docs/scene-format.md)"
            .into(),
    })
}

/// The controllers of a study: `None` → the scene's own control (a plain scatter run), else the
/// names with `none` put first when missing (the reference of `life_extension`).
fn kinds(controllers: Option<&[String]>) -> Result<Vec<ControllerKind>, Failure> {
    let Some(list) = controllers else {
        return Ok(vec![ControllerKind::Scene]);
    };
    let mut kinds =
        ControllerKind::parse_list(&list.join(",")).map_err(|e| study_error(e, 0, None))?;
    if !kinds.contains(&ControllerKind::None) {
        kinds.insert(0, ControllerKind::None);
    }
    Ok(kinds)
}

fn cells(cells: &[CellTuple]) -> Vec<ScatterCell> {
    cells
        .iter()
        .map(|&(hs, tp, probability, direction)| ScatterCell {
            sea: SeaState { hs, tp, direction },
            probability,
        })
        .collect()
}

/// A study's error as the exception of the argument at fault (the command line's flags are the
/// Python arguments of the same names), or of the scene's `mpc.KEY` when the setting came from
/// its table (`r`); `offset` is added to cell indices (a one-cell run of an executor).
fn study_error(e: StudyError, offset: usize, r: Option<&Resolved>) -> Failure {
    let e = match e {
        StudyError::Run {
            controller,
            cell,
            source,
        } => StudyError::Run {
            controller,
            cell: cell + offset,
            source,
        },
        StudyError::SeaState { cell, reason } => StudyError::SeaState {
            cell: cell + offset,
            reason,
        },
        other => other,
    };
    match e {
        StudyError::Run {
            controller,
            cell,
            source,
        } => {
            let named = source.argument_fault().map(|(name, _)| name);
            let key = match named {
                Some("bounds") => Some("bound"),
                Some(n) if MPC_KEYS.contains(&n) || n == "spin_up" => Some(n),
                _ => None,
            };
            match key {
                Some(key) => {
                    let e = StudyError::Run {
                        controller,
                        cell,
                        source,
                    };
                    match r {
                        Some(r) => r.fault(key, e.to_string()),
                        None => Failure::argument(key, e.to_string()),
                    }
                }
                None => Failure::Lib(*source),
            }
        }
        e @ StudyError::SpinUp { .. } => Failure::argument("spin_up", e.to_string()),
        e @ (StudyError::UnknownController { .. }
        | StudyError::DuplicateController { .. }
        | StudyError::NoControllers
        | StudyError::ControlCannotAct { .. }) => Failure::argument("controllers", e.to_string()),
        e => Failure::argument("scatter", e.to_string()),
    }
}

/// The command line's refusal of a non-finite number in the report (`key` names it).
fn finite(key: &str, values: &[f64]) -> Result<(), Failure> {
    match values.iter().find(|v| !v.is_finite()) {
        None => Ok(()),
        Some(v) => Err(Failure::Internal(format!(
            "the fatigue report's `{key}` is not finite ({v}); nothing was returned"
        ))),
    }
}

fn cell_dict<'py>(py: Python<'py>, c: &CellOutcome) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    d.set_item("hs", c.sea.map(|s| s.hs))?;
    d.set_item("tp", c.sea.map(|s| s.tp))?;
    if let Some(dir) = c.sea.and_then(|s| s.direction) {
        d.set_item("direction", dir)?;
    }
    d.set_item("probability", c.probability)?;
    d.set_item("damage_per_year", c.damage_per_year)?;
    d.set_item("damage", c.damage)?;
    d.set_item("duration_s", c.duration_s)?;
    if let Some(f) = c.force {
        d.set_item("force", f)?;
    }
    if let Some(g) = c.gains {
        d.set_item("gains", g.to_vec())?;
    }
    Ok(d)
}

fn controller_dict<'py>(py: Python<'py>, c: &ControllerOutcome) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    d.set_item("damage_per_year", c.damage_per_year)?;
    d.set_item("life_years", Some(c.life_years).filter(|l| l.is_finite()))?;
    let cells = PyList::empty(py);
    for cell in &c.cells {
        cells.append(cell_dict(py, cell)?)?;
    }
    d.set_item("cells", cells)?;
    if !c.hotspots.is_empty() {
        let spots = PyList::empty(py);
        for h in &c.hotspots {
            let x = PyDict::new(py);
            x.set_item("name", &h.name)?;
            x.set_item("elevation", h.elevation)?;
            x.set_item("damage_per_year", h.damage_per_year)?;
            x.set_item("life_years", Some(h.life_years).filter(|l| l.is_finite()))?;
            spots.append(x)?;
        }
        d.set_item("hotspots", spots)?;
        let critical =
            chainbeam::hotspots::critical(c.hotspots.iter().map(|h| (h.damage_per_year, h.dff)));
        d.set_item("critical", critical.map(|i| c.hotspots[i].name.clone()))?;
    }
    Ok(d)
}

/// The command line's checks of a study's numbers.
fn check_study(study: &Study) -> Result<(), Failure> {
    for c in &study.controllers {
        let key = format!("controllers.{}", c.kind.name());
        finite(&key, &[c.damage_per_year])?;
        for cell in &c.cells {
            finite(&key, &[cell.damage, cell.damage_per_year])?;
            finite(&key, cell.gains.as_ref().map_or(&[][..], |g| g))?;
        }
    }
    Ok(())
}

/// A study as the command line's JSON: with controllers `{controllers, life_extension,
/// settings}`, else `{damage_per_year, life_years, cells}`.
fn study_dict<'py>(
    py: Python<'py>,
    study: &Study,
    with_controllers: bool,
    r: &Resolved,
) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    if !with_controllers {
        let c = controller_dict(py, &study.controllers[0])?;
        for key in [
            "damage_per_year",
            "life_years",
            "hotspots",
            "critical",
            "cells",
        ] {
            if let Some(v) = c.get_item(key)? {
                d.set_item(key, v)?;
            }
        }
        return Ok(d);
    }
    let (controllers, extension) = (PyDict::new(py), PyDict::new(py));
    // Report order: none, constant, pd, mpc (the command line's object keys).
    for kind in [
        ControllerKind::None,
        ControllerKind::Constant,
        ControllerKind::Pd,
        ControllerKind::Mpc,
    ] {
        if let Some(c) = study.get(kind) {
            controllers.set_item(kind.name(), controller_dict(py, c)?)?;
            extension.set_item(kind.name(), study.life_extension(kind))?;
        }
    }
    d.set_item("controllers", controllers)?;
    d.set_item("life_extension", extension)?;
    let (settings, s) = (PyDict::new(py), &r.settings);
    settings.set_item("interval", s.interval)?;
    settings.set_item("horizon", s.horizon)?;
    settings.set_item("iterations", s.iterations)?;
    settings.set_item("bound", s.bound)?;
    settings.set_item("effort", s.effort)?;
    settings.set_item("spin_up", r.spin_up)?;
    settings.set_item("mpc_objective", r.objective().name())?;
    d.set_item("settings", settings)?;
    Ok(d)
}

/// The plain assessment (no scatter, no controllers): simulate, count (after the first
/// `spin_up` seconds, the command line's `--spin-up`), Miner.
fn plain<'py>(
    py: Python<'py>,
    scene: &chainbeam::Scene,
    spin_up: f64,
    progress: Option<&Bound<'py, PyAny>>,
) -> PyResult<Bound<'py, PyDict>> {
    let s = scene.clone();
    let a = check(
        py,
        watched(py, progress, move |ticker| -> Result<_, Failure> {
            ticker.set_total(1);
            let spec = spec(&s)?;
            let skip = spin_up_steps(&s, spin_up).map_err(|e| study_error(e, 0, None))?;
            let traj = chainbeam::simulate(&s)?;
            let moment_x = traj.is_spatial().then(|| &traj.moment_x()[skip..]);
            let history = MomentHistory {
                duration_s: traj.steps() as f64 * traj.h() - skip as f64 * s.time.step,
                moment: &traj.moment()[skip..],
                moment_x,
                measure: s.moment_measure(),
            };
            let a = assess(&spec, history).map_err(|e| match e {
                FatigueError::InvalidSpec { key, .. } => Failure::SceneKey {
                    key: format!("fatigue.{key}"),
                    message: e.to_string(),
                },
                e => Failure::Internal(e.to_string()),
            })?;
            let cycles: Vec<[f64; 3]> = a
                .cycles
                .iter()
                .map(|c| [c.range, c.mean, c.count])
                .collect();
            finite("cycles", cycles.as_flattened())?;
            finite("damage", &[a.damage, a.duration_s, a.damage_per_year])?;
            let hot = if s.hotspots.is_empty() {
                None
            } else {
                let hot = chainbeam::hotspots::assess_hot_spots(&s, &s.hotspots, skip)?;
                for h in &hot {
                    let key = format!("hotspots.{}", h.name);
                    finite(&key, &[h.assessment.damage, h.assessment.damage_per_year])?;
                }
                Some(hot)
            };
            ticker.tick();
            Ok((cycles, a, hot))
        })?,
    )?;
    let (cycles, a, hot) = a;
    let d = PyDict::new(py);
    d.set_item(
        "cycles",
        cycles.iter().map(|c| c.to_vec()).collect::<Vec<_>>(),
    )?;
    d.set_item("damage", a.damage)?;
    d.set_item("duration_s", a.duration_s)?;
    d.set_item("damage_per_year", a.damage_per_year)?;
    d.set_item("life_years", Some(a.life_years).filter(|l| l.is_finite()))?;
    if let Some(hot) = hot {
        // The command line's `hotspots` and `critical` (cmd_fatigue.rs).
        let spots = PyList::empty(py);
        for h in &hot {
            let x = PyDict::new(py);
            x.set_item("name", &h.name)?;
            x.set_item("elevation", h.elevation)?;
            x.set_item("joint", h.joint + 1)?;
            x.set_item("joint_elevation", h.joint_elevation)?;
            x.set_item("damage", h.assessment.damage)?;
            x.set_item("damage_per_year", h.assessment.damage_per_year)?;
            let life = Some(h.assessment.life_years).filter(|l| l.is_finite());
            x.set_item("life_years", life)?;
            spots.append(x)?;
        }
        d.set_item("hotspots", spots)?;
        let critical = chainbeam::hotspots::critical(
            hot.iter()
                .zip(&scene.hotspots)
                .map(|(h, s)| (h.assessment.damage_per_year, s.spec.dff)),
        );
        d.set_item("critical", critical.map(|i| hot[i].name.clone()))?;
    }
    Ok(d)
}

/// `chainbeam fatigue` in one process; see `chainbeam.fatigue`. `progress(done, total)` (or
/// None) is called on this thread as the (cell, controller) runs end.
#[pyfunction]
#[pyo3(signature = (scene, scatter, controllers, settings, progress=None))]
pub fn _fatigue<'py>(
    py: Python<'py>,
    scene: &Scene,
    scatter: Option<Vec<CellTuple>>,
    controllers: Option<Vec<String>>,
    settings: Settings,
    progress: Option<Bound<'py, PyAny>>,
) -> PyResult<Bound<'py, PyDict>> {
    let progress = progress.as_ref().filter(|p| !p.is_none());
    if scatter.is_none() && controllers.is_none() {
        // The controllers' settings are not used; their names are checked all the same.
        check(py, settings.resolve(&scene.inner))?;
        return plain(py, &scene.inner, settings.spin_up, progress);
    }
    let with_controllers = controllers.is_some();
    let s = scene.inner.clone();
    let (study, resolved) = check(
        py,
        watched(py, progress, move |ticker| -> Result<_, Failure> {
            let spec = spec(&s)?;
            let kinds = kinds(controllers.as_deref())?;
            let (control, resolved) = settings.control(&s)?;
            let cells = scatter.as_deref().map(cells);
            let runs = cells.as_ref().map_or(1, Vec::len) * kinds.len();
            ticker.set_total(runs as u64);
            let input = StudyInput {
                scene: &s,
                spec: &spec,
                cells: cells.as_deref(),
                controllers: &kinds,
                settings: &control,
            };
            let study = with_pool(|| run_study(&input, &|| ticker.tick()))
                .map_err(Failure::Internal)?
                .map_err(|e| study_error(e, 0, Some(&resolved)))?;
            check_study(&study)?;
            Ok((study, resolved))
        })?,
    )?;
    study_dict(py, &study, with_controllers, &resolved)
}

/// Every controller on one scatter cell (a one-cell `run_study`): one (probability, damage,
/// duration_s, force, gains) per controller, in the study's order. `index` is the cell's place in
/// the diagram (for error messages).
#[pyfunction]
pub fn _fatigue_cell(
    py: Python<'_>,
    scene: &Scene,
    cell: CellTuple,
    index: usize,
    controllers: Option<Vec<String>>,
    settings: Settings,
) -> PyResult<Vec<RunTuple>> {
    let s = scene.inner.clone();
    check(
        py,
        interruptible(py, move || -> Result<_, Failure> {
            let spec = spec(&s)?;
            let kinds = kinds(controllers.as_deref())?;
            let (control, resolved) = settings.control(&s)?;
            let one = cells(&[cell]);
            let input = StudyInput {
                scene: &s,
                spec: &spec,
                cells: Some(&one),
                controllers: &kinds,
                settings: &control,
            };
            let study = with_pool(|| run_study(&input, &|| {}))
                .map_err(Failure::Internal)?
                .map_err(|e| study_error(e, index, Some(&resolved)))?;
            Ok(study
                .controllers
                .iter()
                .map(|c| {
                    let r = &c.cells[0];
                    (r.probability, r.damage, r.duration_s, r.force, r.gains)
                })
                .collect())
        })?,
    )
}

/// The cells' runs ([`_fatigue_cell`], one list per cell) combined as `run_study` combines them,
/// as the command line's JSON.
#[pyfunction]
pub fn _fatigue_combine<'py>(
    py: Python<'py>,
    scene: &Scene,
    scatter: Vec<CellTuple>,
    controllers: Option<Vec<String>>,
    settings: Settings,
    runs: Vec<Vec<RunTuple>>,
) -> PyResult<Bound<'py, PyDict>> {
    let with_controllers = controllers.is_some();
    let combined = (|| -> Result<_, Failure> {
        let spec = spec(&scene.inner)?;
        let kinds = kinds(controllers.as_deref())?;
        let (_, resolved) = settings.control(&scene.inner)?;
        let cells = cells(&scatter);
        if runs.len() != cells.len() || runs.iter().any(|r| r.len() != kinds.len()) {
            return Err(Failure::argument(
                "runs",
                "one run per controller for every cell is needed",
            ));
        }
        let mut outcomes = Vec::with_capacity(kinds.len());
        for (j, &kind) in kinds.iter().enumerate() {
            let damages: Vec<CellDamage> = runs
                .iter()
                .map(|r| CellDamage {
                    probability: r[j].0,
                    damage: r[j].1,
                    duration_s: r[j].2,
                })
                .collect();
            let total = combine_scatter(&damages)
                .map_err(|e| study_error(StudyError::Fatigue(e), 0, None))?;
            let cells = runs
                .iter()
                .zip(&cells)
                .zip(&total.cells)
                .map(|((r, c), &per_year)| CellOutcome {
                    sea: Some(c.sea),
                    probability: r[j].0,
                    damage: r[j].1,
                    duration_s: r[j].2,
                    damage_per_year: per_year,
                    force: r[j].3,
                    gains: r[j].4,
                    seed_damages: vec![r[j].1],
                    // The executor's one-cell runs do not carry the thrust yet.
                    thrust: None,
                })
                .collect();
            let life = life_years(total.damage_per_year, spec.dff)
                .map_err(|e| study_error(StudyError::Fatigue(e), 0, None))?;
            outcomes.push(ControllerOutcome {
                kind,
                damage_per_year: total.damage_per_year,
                life_years: life,
                cells,
                seed_lives: vec![life],
                // The executor's one-cell runs return the wellhead's numbers only.
                hotspots: Vec::new(),
                thrust_rms: None,
                thrust_peak: None,
            });
        }
        let study = Study {
            controllers: outcomes,
        };
        check_study(&study)?;
        Ok((study, resolved))
    })();
    let (study, resolved) = check(py, combined)?;
    study_dict(py, &study, with_controllers, &resolved)
}

/// The IACS Rec. No. 34 North Atlantic scatter diagram reduced to 20 cells
/// (`chainbeam::fatigue::scatter::reduced_north_atlantic`, the rows of
/// examples/scatter/north_atlantic_iacs34.csv): one (hs \[m\], tp \[s\], probability) per cell,
/// H_s slowest; `chainbeam.reduced_north_atlantic()` makes it a DataFrame.
#[pyfunction]
pub fn _reduced_north_atlantic() -> Vec<(f64, f64, f64)> {
    reduced_north_atlantic()
        .iter()
        .map(|c| (c.sea.hs, c.sea.tp, c.probability))
        .collect()
}
