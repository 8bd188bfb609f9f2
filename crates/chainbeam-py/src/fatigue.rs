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
    assess, CellDamage, FatigueError, FatigueSpec, MomentHistory, ScatterCell, SeaState,
};
use chainbeam::fatigue_study::{
    combine_study, run_study, run_study_cell, seeds_run, spin_up_steps, CellOutcome, CellRun,
    ControlSettings, ControllerKind, ControllerOutcome, Study, StudyError, StudyInput,
    PRACTICE_RECORD_S,
};
use chainbeam::mpc::{Horizon, MpcOptions};
use chainbeam::ocp::OcpOptions;
use chainbeam::scene::{MpcPlanObjective, MpcSettings, MpcTable, FORCE_RANGE, MPC_KEYS};

use crate::errors::{check, Failure};
use crate::run::{interruptible, watched, with_pool};
use crate::scene::Scene;

/// A scatter cell as Python passes it: (hs, tp, probability, direction or None).
type CellTuple = (f64, f64, f64, Option<f64>);

/// One (cell, seed, controller) run as it travels between processes
/// ([`chainbeam::fatigue_study::CellRun`]): (probability, damage, duration_s, force, gains,
/// the hot spots' Miner sums, the thrust's (rms, peak)).
type RunTuple = (
    f64,
    f64,
    f64,
    Option<f64>,
    Option<[f64; 3]>,
    Vec<f64>,
    Option<[f64; 2]>,
);

fn run_tuple(r: &CellRun) -> RunTuple {
    let d = r.damage;
    (
        d.probability,
        d.damage,
        d.duration_s,
        r.force,
        r.gains,
        r.hotspots.clone(),
        r.thrust,
    )
}

fn cell_run(t: RunTuple) -> CellRun {
    CellRun {
        damage: CellDamage {
            probability: t.0,
            damage: t.1,
            duration_s: t.2,
        },
        force: t.3,
        gains: t.4,
        hotspots: t.5,
        thrust: t.6,
    }
}

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
    /// `forecast` ("perfect", "none" or "noisy"; `None`: not given).
    forecast: Option<String>,
    /// `observe` ("state" or "sensors"; `None`: not given).
    observe: Option<String>,
    /// `hotspot` (the name of a `[[fatigue.hotspot]]`; `None`: not given).
    hotspot: Option<String>,
    /// `moment_about` ("zero" or "mean"; `None`: not given).
    moment_about: Option<String>,
    spin_up: f64,
    /// `forecast_error` (the noisy forecast's error growth e; `None`: not given).
    forecast_error: Option<f64>,
    /// The record counted after the spin-up in a study \[s\] (`None`: 3 hours, the command
    /// line's `--record` default).
    record: Option<f64>,
    /// Seeds per cell (the command line's `--seeds`; `None`: 1).
    seeds: Option<usize>,
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
            forecast: item(obj, "forecast", "\"perfect\", \"none\" or \"noisy\"")?,
            observe: item(obj, "observe", "\"state\" or \"sensors\"")?,
            hotspot: item(obj, "hotspot", "the name of a [[fatigue.hotspot]]")?,
            moment_about: item(obj, "moment_about", "\"zero\" or \"mean\"")?,
            spin_up,
            forecast_error: item(obj, "forecast_error", NUMBER)?,
            record: item(obj, "record", NUMBER)?,
            seeds: item(obj, "seeds", COUNT)?,
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
    /// The record counted after the spin-up \[s\].
    record: f64,
    /// Seeds per cell.
    seeds: usize,
    /// The seeds drawn, with more than one (`seeds_run`).
    seeds_run: Option<Vec<u64>>,
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
        let forecast = match self.forecast.as_deref() {
            None => None,
            Some(name) => Some(chainbeam::scene::Forecast::from_name(name).ok_or_else(|| {
                Failure::argument(
                    "forecast",
                    format!(
                        "unknown forecast {name:?}; expected \"perfect\", \"none\" or \"noisy\""
                    ),
                )
            })?),
        };
        let observe = match self.observe.as_deref() {
            None => None,
            Some(name) => Some(chainbeam::scene::Observe::from_name(name).ok_or_else(|| {
                Failure::argument(
                    "observe",
                    format!("unknown observe {name:?}; expected \"state\" or \"sensors\""),
                )
            })?),
        };
        let moment_about = match self.moment_about.as_deref() {
            None => None,
            Some(name) => Some(chainbeam::scene::MomentAbout::from_name(name).ok_or_else(
                || {
                    Failure::argument(
                        "moment_about",
                        format!("unknown moment_about {name:?}; expected \"zero\" or \"mean\""),
                    )
                },
            )?),
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
            forecast,
            forecast_error: self
                .forecast_error
                .map(|e| {
                    chainbeam::scene::check_forecast_error("forecast_error", e)
                        .map_err(|err| Failure::argument("forecast_error", err.to_string()))
                })
                .transpose()?,
            forecast_seed: None,
            observe,
            hotspot: self.hotspot.clone(),
            moment_about,
        };
        let settings = given.resolve(scene.mpc.as_ref());
        Ok(Resolved {
            given,
            table: scene.mpc.clone(),
            settings,
            spin_up: self.spin_up,
            record: self.record.unwrap_or(PRACTICE_RECORD_S),
            seeds: self.seeds.unwrap_or(1),
            seeds_run: seeds_run(scene, self.seeds.unwrap_or(1)),
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
                forecast: s.forecast,
                forecast_error: s.forecast_error,
                forecast_seed: s.forecast_seed,
                observe: s.observe,
                hotspot: s
                    .hotspot_spec(scene)
                    .map_err(|e| r.fault(e.argument(), e.to_string()))?,
                moment_about: s.moment_about,
                ..MpcOptions::default()
            },
            pd_training: s.pd_training,
            spin_up: self.spin_up,
            mpc_fatigue_proxy: r.objective() == MpcPlanObjective::Power,
            record: Some(r.record),
            seeds: r.seeds,
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
    if let Some([rms, peak]) = c.thrust {
        d.set_item("thrust_rms", rms)?;
        d.set_item("thrust_peak", peak)?;
    }
    if let Some(spread) = c.seed_spread() {
        d.set_item("seed_damages", c.seed_damages.clone())?;
        d.set_item("damage_std", spread.std)?;
        d.set_item("damage_min", spread.min)?;
        d.set_item("damage_max", spread.max)?;
    }
    Ok(d)
}

/// One controller as the command line's JSON (`damage_ratio_to_none` per cell for a closed loop
/// in a study with `none`).
fn controller_dict<'py>(
    py: Python<'py>,
    study: &Study,
    c: &ControllerOutcome,
) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    d.set_item("damage_per_year", c.damage_per_year)?;
    let finite = |l: f64| Some(l).filter(|l| l.is_finite());
    d.set_item("life_years", finite(c.life_years))?;
    if let Some(range) = c.seed_life_range() {
        let lives: Vec<Option<f64>> = c.seed_lives.iter().map(|&l| finite(l)).collect();
        d.set_item("life_years_seeds", lives)?;
        d.set_item("life_years_min", finite(range.min))?;
        d.set_item("life_years_max", finite(range.max))?;
    }
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
    if let Some(rms) = c.thrust_rms {
        d.set_item("thrust_rms", rms)?;
    }
    if let Some(peak) = c.thrust_peak {
        d.set_item("thrust_peak", peak)?;
    }
    let cells = PyList::empty(py);
    for (i, cell) in c.cells.iter().enumerate() {
        let cd = cell_dict(py, cell)?;
        if let Some(r) = c
            .kind
            .is_feedback()
            .then(|| study.damage_ratio_to_none(c.kind, i))
            .flatten()
        {
            cd.set_item("damage_ratio_to_none", r)?;
        }
        cells.append(cd)?;
    }
    d.set_item("cells", cells)?;
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
        let c = controller_dict(py, study, &study.controllers[0])?;
        for key in [
            "damage_per_year",
            "life_years",
            "life_years_seeds",
            "life_years_min",
            "life_years_max",
            "hotspots",
            "critical",
        ] {
            if let Some(v) = c.get_item(key)? {
                d.set_item(key, v)?;
            }
        }
        if let Some(seeds) = &r.seeds_run {
            d.set_item("seeds", seeds.clone())?;
        }
        d.set_item("cells", c.get_item("cells")?)?;
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
            controllers.set_item(kind.name(), controller_dict(py, study, c)?)?;
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
    settings.set_item("record", r.record)?;
    settings.set_item("seeds", r.seeds)?;
    settings.set_item("observe", s.observe.name())?;
    if let Some(h) = &s.hotspot {
        settings.set_item("hotspot", h)?;
    }
    if s.moment_about != chainbeam::scene::MomentAbout::Zero {
        settings.set_item("moment_about", s.moment_about.name())?;
    }
    d.set_item("settings", settings)?;
    if let Some(seeds) = &r.seeds_run {
        d.set_item("seeds", seeds.clone())?;
    }
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
    if scatter.is_none() && controllers.is_none() && settings.seeds.unwrap_or(1) <= 1 {
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

/// Every seed and controller on cell `index` of the diagram (`run_study_cell`): one run tuple
/// per (seed, controller), seed-major, in the study's order.
#[pyfunction]
pub fn _fatigue_cell(
    py: Python<'_>,
    scene: &Scene,
    scatter: Vec<CellTuple>,
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
            let cells = cells(&scatter);
            let input = StudyInput {
                scene: &s,
                spec: &spec,
                cells: Some(&cells),
                controllers: &kinds,
                settings: &control,
            };
            let runs = with_pool(|| run_study_cell(&input, index))
                .map_err(Failure::Internal)?
                .map_err(|e| study_error(e, index, Some(&resolved)))?;
            Ok(runs.iter().map(run_tuple).collect())
        })?,
    )
}

/// The cells' runs ([`_fatigue_cell`], one list per cell) combined as `run_study` combines them
/// (`combine_study`: the same numbers bit for bit), as the command line's JSON.
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
        let (control, resolved) = settings.control(&scene.inner)?;
        let cells = cells(&scatter);
        let input = StudyInput {
            scene: &scene.inner,
            spec: &spec,
            cells: Some(&cells),
            controllers: &kinds,
            settings: &control,
        };
        let runs: Vec<CellRun> = runs.into_iter().flatten().map(cell_run).collect();
        let study = combine_study(&input, &runs).map_err(|e| match e {
            e @ StudyError::RunCount { .. } => Failure::argument("runs", e.to_string()),
            e => study_error(e, 0, None),
        })?;
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
