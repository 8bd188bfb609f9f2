//! `chainbeam fatigue`: the wellhead's fatigue damage and life from the base moment (JSON).

use std::path::{Path, PathBuf};

use clap::Args;
use serde::Serialize;

use chainbeam::fatigue::{assess, Assessment, FatigueSpec, MomentHistory};
use chainbeam::fatigue_study::{spin_up_steps, with_record, ControlSettings, ControllerKind};
use chainbeam::hotspots::{
    assess_histories, critical, hot_spot_joints, joint_moment_history, HotSpotAssessment,
    HotSpotSpec, JointMoments,
};
use chainbeam::scene::read_text_file;
use chainbeam::{moment_history, Scene, ValidScene};

mod study;

use crate::cmd_mpc::MpcFlags;
use crate::output::{refuse_overwrite, Inputs, Output};
use crate::progress::Progress;
use crate::{check_finite, lib_error, to_json, CliError};
use crate::{OUTPUT_HELP, SCENE_HELP};

/// `fatigue --help`.
pub const LONG_ABOUT: &str = "\
Fatigue damage and life of the wellhead from the base bending moment M₀: simulate the scene (or \
read a moment history with --series FILE) and count the hot-spot stress per ASTM E1049-85 \
(rainflow), with the DNV-RP-C203 S-N curve of the scene's [fatigue] table (docs/scene-format.md).

Stress: σ(t) = SCF · M_w(t) · (D_o/2)/I in MPa, I = π/64 (D_o⁴ − D_i⁴), D_i = D_o − 2t, with \
M_w = k₁z₁/l₁ = M₀ · l₁/2 the wellhead moment (the base spring's torque) of the chain's M₀ = \
2k₁z₁/l₁², l₁ the scene's first pendulum length (docs/conventions.md). A spatial \
history (moment_x) is checked at 8 points θ = 0°, 22.5°, …, 157.5° around the circumference, \
σ_θ = SCF · (M_wₓ sin θ + M_w cos θ) · (D_o/2)/I, and the worst point is reported (the other half of \
the circumference has the same ranges).

S-N curve (DNV-RP-C203 April 2016, Tables 2-1 air, 2-2 seawater-cp, 2-3 free-corrosion): \
N = ā · (Δσ (t/t_ref)^k)^(−m), two slopes (m₂ = 5 below the knee) except under free corrosion. \
Miner's sum D = Σ n_i/N_i over the cycles (n = 0.5 for a half cycle of the residue).

Output (JSON):
  cycles           [[stress_range_MPa, mean_MPa, count], …] in the order counted, count 1 or 0.5
  damage           Miner's sum D over the record
  duration_s       the record's duration T [s] (N·h, or the last t minus the first of --series)
  damage_per_year  D · Y/T, Y = 365.25 · 86400 s
  life_years       1/(DFF · damage_per_year); null when the record does no damage (infinite life)

--series FILE: a CSV with a header line naming its columns, among them t [s] and moment (and \
moment_x for a spatial history), the chain's M₀ as `simulate` writes it (converted to M_w = \
M₀ · l₁/2 with the scene's l₁); other columns are ignored, so a `chainbeam simulate` CSV \
is a valid series. Times must increase strictly; blank lines and lines starting with # are \
skipped.

--controller none,constant,pd,mpc (any comma list; none is always run): each controller on the \
scene (or every cell) in the closed loop of `chainbeam mpc` (--interval, --horizon, --iterations, \
--bound, --effort as there): constant = the best constant force of the record, pd = a PD law on \
M₀ with tuned gains, mpc = receding horizon. JSON: controllers.NAME.{damage_per_year, \
life_years, cells} and life_extension.NAME = its life over the life without control; with the \
vessel's thrust as the control (the [vessel] thrust keys) also thrust_rms and thrust_peak [N]. A \
control at a node the supports lock is refused. The controllers' flags default to the scene's [mpc] \
table (docs/scene-format.md); mpc plans on Σ|M₀|^m, m the S-N curve's first slope \
(--mpc-objective).

--spin-up S: the first S seconds of every record (the start-up from the riser at rest, with the \
current and the sea switched on at t = 0) are not counted.

--record S: S seconds are counted after the spin-up (each run is spin-up + S long). Default: \
10800 (3 hours) for every cell of a study (--scatter, --controller, --seeds K > 1); the scene's \
own [time] for the plain run.

--seeds K: K seas per cell, the scene's [loads.waves] seed s, s+1, …, s+K−1. JSON (K > 1): \
seeds; per cell seed_damages, damage (their mean), damage_std (sample, K−1), damage_min, \
damage_max; in the totals life_years_seeds, life_years_min, life_years_max.

[[fatigue.hotspot]] (docs/scene-format.md): hotspots [{name, elevation, joint, joint_elevation, \
damage, damage_per_year, life_years}] and critical (the shortest-lived one's name); the moment \
at a hot spot is the joint torques k_j θ_j interpolated linearly in elevation between the two \
joints around it (joint: the lower one, or the joint it lies on). In a study, per \
controller (a closed loop's decisions replayed on its plant).

A cell of constant, pd or mpc has damage_ratio_to_none (its damage over none's); above 1 a \
warning on stderr says the controller did worse than no control there.

--scatter FILE: a CSV with header hs,tp,probability[,direction]; every cell sets the scene's \
[loads.waves] hs, tp (direction) and keeps its seed (the same phases in every cell). JSON: \
damage_per_year = Σ_s p_s·D_s·Y/T_s, life_years, cells [{hs, tp, probability, damage_per_year \
(the cell's weighted contribution), damage, duration_s}]. Details: docs/cli.md.";

/// `fatigue`'s flags.
#[derive(Args)]
pub struct FatigueArgs {
    #[arg(value_name = "SCENE.toml", help = SCENE_HELP)]
    pub scene: PathBuf,
    /// Read the moment history from this CSV (columns t, moment[, moment_x]; a `simulate` CSV is
    /// one) instead of simulating the scene; the scene gives the [fatigue] table.
    #[arg(long, value_name = "FILE")]
    pub series: Option<PathBuf>,
    /// Run these controllers (a comma list of none, constant, pd, mpc) and report each one's
    /// damage per year, life and life extension over no control (`none` is always run).
    #[arg(long, value_name = "LIST", conflicts_with = "series")]
    pub controller: Option<String>,
    /// A scatter diagram: a CSV with header hs,tp,probability[,direction]; the scene's
    /// [loads.waves] sea state is run for every cell.
    #[arg(long, value_name = "FILE", conflicts_with = "series")]
    pub scatter: Option<PathBuf>,
    #[command(flatten)]
    pub mpc: MpcFlags,
    /// Tune the PD law's gains on the first S seconds of each cell's record [default:
    /// mpc.pd_training, else all of it].
    #[arg(long, value_name = "S")]
    pub pd_training: Option<f64>,
    /// Leave the first S seconds of the record (of every cell and controller) out of the count:
    /// the start-up from the riser at rest (docs/cli.md, "The start of a record").
    #[arg(
        long,
        value_name = "S",
        default_value_t = 0.0,
        conflicts_with = "series"
    )]
    pub spin_up: f64,
    /// Count S seconds of every record after the spin-up (each run is spin-up + S long)
    /// [default: 10800 (3 hours) for every cell of --scatter, --controller and --seeds; the
    /// scene's own [time] for the plain assessment].
    #[arg(
        long,
        value_name = "S",
        conflicts_with = "series",
        allow_negative_numbers = true
    )]
    pub record: Option<f64>,
    /// Run K seeds per cell (the scene's [loads.waves] seed s, s+1, …, s+K−1) and report each
    /// cell's mean damage and its spread over the seeds, and the life's spread.
    #[arg(long, value_name = "K", default_value_t = 1, conflicts_with = "series")]
    pub seeds: usize,
    /// What MPC plans on: `power` = Σ|M₀|^m with m the S-N curve's first slope (the fatigue
    /// proxy), or `sum` = Σ M₀² [default: mpc.objective, else power].
    #[arg(long, value_name = "KIND")]
    pub mpc_objective: Option<MpcObjective>,
    #[arg(long, short, value_name = "FILE", help = OUTPUT_HELP)]
    pub output: Option<PathBuf>,
}

/// `--mpc-objective`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum MpcObjective {
    /// Σ|M₀|^m, m the S-N curve's first slope.
    Power,
    /// Σ M₀² (the thesis's c_sum).
    Sum,
}

#[derive(Serialize)]
struct FatigueReport {
    cycles: Vec<[f64; 3]>,
    damage: f64,
    duration_s: f64,
    damage_per_year: f64,
    life_years: Option<f64>,
    /// Per `[[fatigue.hotspot]]` (absent without them: today's JSON bit for bit).
    #[serde(skip_serializing_if = "Option::is_none")]
    hotspots: Option<Vec<HotSpotJson>>,
    /// The name of the shortest-lived hot spot.
    #[serde(skip_serializing_if = "Option::is_none")]
    critical: Option<String>,
}

/// One hot spot in the JSON (the plain assessment's, and a study controller's).
#[derive(Serialize)]
pub struct HotSpotJson {
    pub name: String,
    pub elevation: f64,
    /// The joint read, j = 1..n+1 (1: the base; absent in a study): the one the hot spot lies
    /// on, else the lower of the two its moment is interpolated between.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub joint: Option<usize>,
    /// The joint's elevation s_j [m] (absent in a study).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub joint_elevation: Option<f64>,
    /// Miner's sum over the record (absent in a study).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub damage: Option<f64>,
    pub damage_per_year: f64,
    pub life_years: Option<f64>,
}

/// A moment history: M₀, M₀ₓ of a spatial one, and the duration.
struct History {
    moment: Vec<f64>,
    moment_x: Option<Vec<f64>>,
    duration_s: f64,
}

/// Runs `fatigue`: inputs → solve (the assessment, or the study of `--controller`/`--scatter`)
/// → report.
pub fn run(a: &FatigueArgs, progress: Progress) -> Result<(), CliError> {
    let out = Output::prepare(a.output.as_deref())?;
    let mut inputs = Inputs::new();
    let scene = inputs.load_scene(&a.scene)?;
    if let Some(s) = &a.series {
        inputs.file(s);
    }
    if let Some(s) = &a.scatter {
        inputs.file(s);
    }
    refuse_overwrite(&[("--output", &out)], &inputs)?;
    let spec = fatigue_spec(&a.scene, &scene)?;
    if a.controller.is_some() || a.scatter.is_some() || a.seeds != 1 {
        let solved = study::solve(a, &scene, &spec, &progress)?;
        out.write_all(&study::report(a, &solved)?)?;
        for w in study::warnings(a, &solved) {
            eprintln!("{w}");
        }
        return Ok(());
    }
    let scene = match a.record {
        Some(record) => {
            let settings = ControlSettings {
                spin_up: a.spin_up,
                ..ControlSettings::default()
            };
            with_record(&scene, &settings, ControllerKind::Scene, record)
                .map_err(|e| CliError::msg(format!("{}: --record: {e}", a.scene.display())))?
        }
        None => scene,
    };
    if a.series.is_some() && !scene.hotspots.is_empty() {
        eprintln!(
            "{}: warning: the [[fatigue.hotspot]] entries are not assessed with --series (they \
             need the chain's joint angles, a series has the base moment only): the wellhead \
             alone is reported",
            a.scene.display()
        );
    }
    let (assessment, hot) = solve(a, &scene, &spec, &progress)?;
    let mut json = report(&a.scene, &assessment)?;
    if let Some(hot) = hot {
        let (spots, critical) = hotspots_json(&a.scene, &scene.hotspots, &hot)?;
        json.hotspots = Some(spots);
        json.critical = critical;
    }
    out.write_all(&to_json(&json)?)
}

/// The hot spots' JSON and the critical one's name; a non-finite number is refused naming the
/// scene.
fn hotspots_json(
    scene_file: &Path,
    specs: &[HotSpotSpec],
    hot: &[HotSpotAssessment],
) -> Result<(Vec<HotSpotJson>, Option<String>), CliError> {
    let mut out = Vec::with_capacity(hot.len());
    for h in hot {
        let a = &h.assessment;
        let key = format!("hotspots.{}", h.name);
        check_finite(scene_file, &key, &[a.damage, a.damage_per_year])?;
        out.push(HotSpotJson {
            name: h.name.clone(),
            elevation: h.elevation,
            joint: Some(h.joint + 1),
            joint_elevation: Some(h.joint_elevation),
            damage: Some(a.damage),
            damage_per_year: a.damage_per_year,
            life_years: Some(a.life_years).filter(|l| l.is_finite()),
        });
    }
    let critical = critical(
        hot.iter()
            .zip(specs)
            .map(|(h, s)| (h.assessment.damage_per_year, s.spec.dff)),
    )
    .map(|i| hot[i].name.clone());
    Ok((out, critical))
}

/// The assessment of the simulated (or `--series`) moment history, and the hot spots' of the
/// same run (when the scene has `[[fatigue.hotspot]]` and no `--series`).
fn solve(
    a: &FatigueArgs,
    scene: &ValidScene,
    spec: &FatigueSpec,
    progress: &Progress,
) -> Result<(Assessment, Option<Vec<HotSpotAssessment>>), CliError> {
    let mut joints = None;
    let history = match &a.series {
        Some(path) => read_series(path)?,
        None if !scene.hotspots.is_empty() => {
            let (h, j) = simulated_joints(&a.scene, scene, progress)?;
            joints = Some(j);
            h
        }
        None => simulated(&a.scene, scene, progress)?,
    };
    let skip = match &a.series {
        Some(_) => 0,
        None => spin_up_steps(scene, a.spin_up)
            .map_err(|e| CliError::msg(format!("{}: --spin-up: {e}", a.scene.display())))?,
    };
    let wellhead = assess(
        spec,
        MomentHistory {
            duration_s: history.duration_s - skip as f64 * scene.time.step,
            moment: &history.moment[skip..],
            moment_x: history.moment_x.as_deref().map(|m| &m[skip..]),
            measure: scene.moment_measure(),
        },
    )
    .map_err(|e| {
        let file = a.series.as_deref().unwrap_or(&a.scene);
        CliError::msg(format!("{}: {e}", file.display()))
    })?;
    let hot = match joints {
        Some(j) => Some(
            assess_histories(scene, &scene.hotspots, &j, skip)
                .map_err(|e| lib_error(&a.scene, e))?,
        ),
        None => None,
    };
    Ok((wellhead, hot))
}

/// The simulated base moment and the hot spots' joint torques, from one streamed run.
fn simulated_joints(
    path: &Path,
    scene: &ValidScene,
    progress: &Progress,
) -> Result<(History, JointMoments), CliError> {
    let spinner = progress.spinner(format!(
        "simulating {} steps of a {}-pendulum beam",
        scene.time.steps,
        scene.n()
    ));
    let joints = hot_spot_joints(&scene.beam.lengths, &scene.hotspots);
    let history = joint_moment_history(scene, &joints);
    spinner.finish_and_clear();
    let mut j = history.map_err(|e| lib_error(path, e))?;
    let h = History {
        duration_s: j.duration(),
        moment: std::mem::take(&mut j.base_moment),
        moment_x: j.base_moment_x.take(),
    };
    Ok((h, j))
}

/// The JSON of an assessment; a non-finite number is refused naming the scene.
fn report(scene_file: &Path, assessment: &Assessment) -> Result<FatigueReport, CliError> {
    let cycles: Vec<[f64; 3]> = assessment
        .cycles
        .iter()
        .map(|c| [c.range, c.mean, c.count])
        .collect();
    check_finite(scene_file, "cycles", cycles.as_flattened())?;
    let totals = [
        assessment.damage,
        assessment.duration_s,
        assessment.damage_per_year,
    ];
    check_finite(scene_file, "damage", &totals)?;
    Ok(FatigueReport {
        cycles,
        damage: assessment.damage,
        duration_s: assessment.duration_s,
        damage_per_year: assessment.damage_per_year,
        life_years: Some(assessment.life_years).filter(|l| l.is_finite()),
        hotspots: None,
        critical: None,
    })
}

fn fatigue_spec(path: &Path, scene: &Scene) -> Result<FatigueSpec, CliError> {
    scene.fatigue_spec().ok_or_else(|| {
        CliError::msg(format!(
            "{}: key `fatigue`: the fatigue command needs a [fatigue] table with outer_diameter \
             and wall_thickness, or a [pipe] table whose section it takes (docs/scene-format.md)",
            path.display()
        ))
    })
}

fn simulated(path: &Path, scene: &ValidScene, progress: &Progress) -> Result<History, CliError> {
    let spinner = progress.spinner(format!(
        "simulating {} steps of a {}-pendulum beam",
        scene.time.steps,
        scene.n()
    ));
    let history = moment_history(scene);
    spinner.finish_and_clear();
    let history = history.map_err(|e| lib_error(path, e))?;
    Ok(History {
        duration_s: history.duration(),
        moment: history.moment,
        moment_x: history.moment_x,
    })
}

fn series_error(path: &Path, what: impl std::fmt::Display) -> CliError {
    CliError::msg(format!("{}: {what}", path.display()))
}

/// Reads a `--series` CSV (the library's bounded reader, then the `csv` crate).
fn read_series(path: &Path) -> Result<History, CliError> {
    let text = read_text_file(path).map_err(|e| CliError::msg(e.to_string()))?;
    let mut reader = csv::ReaderBuilder::new()
        .trim(csv::Trim::All)
        .comment(Some(b'#'))
        .from_reader(text.as_bytes());
    let header = reader.headers().map_err(|e| series_error(path, e))?.clone();
    let column = |name: &str| header.iter().position(|h| h == name);
    let missing = |name: &str| {
        series_error(
            path,
            format!("no column `{name}` in the header (a CSV with columns t, moment[, moment_x])"),
        )
    };
    let t_col = column("t").ok_or_else(|| missing("t"))?;
    let m_col = column("moment").ok_or_else(|| missing("moment"))?;
    let x_col = column("moment_x");
    let (mut t, mut moment, mut moment_x) = (Vec::new(), Vec::new(), Vec::new());
    for record in reader.records() {
        let record = record.map_err(|e| series_error(path, e))?;
        let line = record.position().map_or(0, |p| p.line());
        let value = |col: usize, name: &str| -> Result<f64, CliError> {
            let field = record.get(col).unwrap_or("");
            match field.parse::<f64>() {
                Ok(v) if v.is_finite() => Ok(v),
                _ => Err(series_error(
                    path,
                    format!("line {line}: column `{name}`: not a finite number: `{field}`"),
                )),
            }
        };
        let tk = value(t_col, "t")?;
        if t.last().is_some_and(|&prev| tk <= prev) {
            return Err(series_error(
                path,
                format!("line {line}: t must increase strictly"),
            ));
        }
        t.push(tk);
        moment.push(value(m_col, "moment")?);
        if let Some(c) = x_col {
            moment_x.push(value(c, "moment_x")?);
        }
    }
    if t.len() < 2 {
        return Err(series_error(path, "needs at least 2 rows"));
    }
    Ok(History {
        duration_s: t[t.len() - 1] - t[0],
        moment,
        moment_x: x_col.map(|_| moment_x),
    })
}
