//! The README's headline: the fatigue life of a wellhead in a North Atlantic wave climate
//! without control, with the best constant force, a tuned PD law and MPC at the platform, and
//! the CPU time each took (`chainbeam::fatigue_study::run_study`, the library behind
//! `chainbeam fatigue --scatter FILE --controller none,constant,pd,mpc`).
//!
//! ```sh
//! cargo run --release --example wellhead_fatigue                     # 120 s per cell, all four
//! cargo run --release --example wellhead_fatigue -- 600              # 600 s per cell
//! cargo run --release --example wellhead_fatigue -- 30 none,constant # 30 s per cell, two
//! ```
//!
//! Cost: the plant is riser_300m's n = 60 pendulums at h = 0.0125 s (52 800 steps per cell of
//! 600 s and the spin-up); `none` is a simulation per cell, `constant` a one-piece optimal
//! control per cell over the training window (`pd_training`: the condensed solver, one
//! sensitivity direction, a few rollouts) and a simulation, `pd` one tuning of its gains (a fixed
//! design, as an engineer would commission one PD law, not one per sea state: [`PD_ITERS`]
//! L-BFGS iterations of a dual-number closed loop over the first `pd_training` s of the
//! scene's own sea, in the scaled, bounded parameters of `chainbeam::fatigue_study::pd`) and a
//! closed loop per cell, `mpc` a re-plan every second over 20 s on the reduced planning model
//! (the pipe as 20 pendulums at 0.1 s, src/mpc/planning.rs) per cell. The horizon must reach
//! the riser's first natural period (≈ 19 s): 8 s plans are myopic and drive the riser
//! (src/mpc/planning.rs tests, and the commit that added the planning model).
//!
//! - The riser: `examples/scenes/riser_300m.toml` (a 21" drilling riser in 300 m of water, a
//!   JONSWAP sea and a 0.5 m/s current; its sources are in the file). Every record runs
//!   [`SPIN_UP_S`] + the seconds given (default 120 s; a design analysis would run 3 hours per
//!   cell: the damage per year is a rate, and a short record estimates it with sampling error)
//!   from the riser at rest, and the first [`SPIN_UP_S`] s (the start-up: the swing out to the
//!   current's offset and the sea's first periods) are not counted (docs/cli.md, "The start of
//!   a record").
//! - The wellhead: the pipe's section, DNV-RP-C203 curve F1 in seawater with cathodic
//!   protection, SCF 1.2, DFF 10 (our choices for a girth weld at a subsea wellhead;
//!   DNV-RP-C203 practice is 3–10 for the DFF, docs/fatigue.md).
//! - The wave climate: the North Atlantic scatter diagram of IACS Rec. No. 34 (as printed in
//!   KR Guidance RA-03-E (2025), Pt 3 Annex 3-2, Table 3; `chainbeam::fatigue::scatter`
//!   cites it) reduced to 20 cells: 2 m × 2 s groups of its classes, T_z → T_p by its
//!   Pierson-Moskowitz spectrum (riser_300m's γ = 1), groups below 0.1 % dropped (0.066 % of
//!   the time) and the rest renormalised (`scatter::reduced_north_atlantic`, the rows of
//!   `examples/scatter/north_atlantic_iacs34.csv`); `--scatter FILE` runs another diagram (a
//!   CSV with the columns hs, tp, probability, e.g. `scatter::reduced_kvitebjorn`'s cells).
//! - The controllers' settings are riser_300m.toml's `[mpc]` table: they act at the platform
//!   (the tip node) with |u| ≤ 200 kN, a decision every second: the best constant force and the PD law minimise Σ M₀² + ρ h Σ u² (ρ = 10⁻⁴), MPC
//!   plans 20 s ahead (one Gauss-Newton iteration per re-plan) on the fatigue proxy
//!   Σ|M₀|^m + ρ h Σ u², m = 3 the first slope of curve F1. Each cell keeps the scene's seed
//!   (docs/cli.md, "Seeds").
//!
//! Output: the table (damage per year, life, life extension, CPU and wall seconds per
//! controller), the PD gains, the damage per cell, the load average before and after; with a
//! third argument, the same as JSON into that file.

use std::time::Instant;

use chainbeam::fatigue::scatter::{
    lump_north_atlantic, reduced_north_atlantic, REDUCED_NA_HS_EDGES, REDUCED_NA_MIN_PROBABILITY,
    REDUCED_NA_TZ_EDGES,
};
use chainbeam::fatigue::{DnvClass, Environment, FatigueSpec, ScatterCell, SeaState};
use chainbeam::fatigue_study::{
    pd_law, run_study, ControlSettings, ControllerKind, Study, StudyInput,
};
use chainbeam::mpc::{Horizon, MpcOptions};
use chainbeam::ocp::OcpOptions;
use chainbeam::scene::MpcPlanObjective;
use chainbeam::Scene;
use serde_json::json;

/// The spin-up window not counted \[s\] (docs/cli.md, "The start of a record").
const SPIN_UP_S: f64 = 60.0;
/// L-BFGS iterations of the PD tuning.
const PD_ITERS: usize = 15;

/// Process CPU time (user + system) of every thread so far \[s\].
fn cpu_seconds() -> f64 {
    // SAFETY: getrusage writes into the zeroed struct we own.
    let mut usage: libc::rusage = unsafe { std::mem::zeroed() };
    if unsafe { libc::getrusage(libc::RUSAGE_SELF, &mut usage) } != 0 {
        return f64::NAN;
    }
    let t = |v: libc::timeval| v.tv_sec as f64 + 1e-6 * v.tv_usec as f64;
    t(usage.ru_utime) + t(usage.ru_stime)
}

/// The 1, 5 and 15 minute load averages (/proc/loadavg), or "unknown".
fn load_average() -> String {
    std::fs::read_to_string("/proc/loadavg").map_or_else(
        |_| "unknown".to_string(),
        |s| s.split_whitespace().take(3).collect::<Vec<_>>().join(" "),
    )
}

/// A scatter CSV with header `hs,tp,probability` (the columns of `chainbeam fatigue --scatter`;
/// `#` lines skipped).
fn read_scatter(path: &str) -> Result<Vec<ScatterCell>, Box<dyn std::error::Error>> {
    let text = std::fs::read_to_string(path)?;
    let mut lines = text
        .lines()
        .map(str::trim)
        .filter(|l| !l.is_empty() && !l.starts_with('#'));
    let header: Vec<&str> = lines
        .next()
        .ok_or("empty scatter file")?
        .split(',')
        .collect();
    let col = |name: &str| {
        header
            .iter()
            .position(|h| h.trim() == name)
            .ok_or(format!("{path}: no column {name}"))
    };
    let (h, t, p) = (col("hs")?, col("tp")?, col("probability")?);
    let mut cells = Vec::new();
    for line in lines {
        let f: Vec<f64> = line
            .split(',')
            .map(|x| x.trim().parse())
            .collect::<Result<_, _>>()?;
        let get = |i: usize| {
            f.get(i)
                .copied()
                .ok_or(format!("{path}: short line {line}"))
        };
        cells.push(ScatterCell {
            sea: SeaState {
                hs: get(h)?,
                tp: get(t)?,
                direction: None,
            },
            probability: get(p)?,
        });
    }
    Ok(cells)
}

/// What the diagram's cells stand for. The built-in reduction renormalises its cells to add up
/// to 1, so their sum says nothing: the share of the source table's observations they hold
/// does (the groups kept, before renormalising). A file's probabilities are taken as given
/// (the time they leave out counts no damage), so their sum is what they cover.
fn coverage(cells: &[ScatterCell], built_in: bool) -> String {
    if built_in {
        let kept: f64 = lump_north_atlantic(&REDUCED_NA_HS_EDGES, &REDUCED_NA_TZ_EDGES)
            .iter()
            .map(|c| c.probability)
            .filter(|&p| p >= REDUCED_NA_MIN_PROBABILITY)
            .sum();
        format!(
            "the groups holding {:.3} % of the table's observations, renormalised to 1",
            100.0 * kept
        )
    } else {
        let sum: f64 = cells.iter().map(|c| c.probability).sum();
        format!("probabilities adding up to {sum:.4} (the rest of the time counts no damage)")
    }
}

/// The command line: `[SECONDS] [CONTROLLERS] [--json FILE] [--scatter FILE]
/// [--mpc-objective power|sum]` (the last overrides the scene's `mpc.objective`).
struct Args {
    seconds: f64,
    kinds: Vec<ControllerKind>,
    json: Option<String>,
    scatter: Option<String>,
    objective: Option<MpcPlanObjective>,
}

fn args() -> Result<Args, Box<dyn std::error::Error>> {
    let mut positional = Vec::new();
    let (mut json, mut scatter, mut objective) = (None, None, None);
    let mut it = std::env::args().skip(1);
    while let Some(a) = it.next() {
        match a.as_str() {
            "--json" => json = Some(it.next().ok_or("--json FILE")?),
            "--scatter" => scatter = Some(it.next().ok_or("--scatter FILE")?),
            "--mpc-objective" => {
                objective = match it.next().as_deref() {
                    Some("power") => Some(MpcPlanObjective::Power),
                    Some("sum") => Some(MpcPlanObjective::Sum),
                    _ => return Err("--mpc-objective power|sum".into()),
                }
            }
            _ => positional.push(a),
        }
    }
    Ok(Args {
        seconds: positional.first().map_or(Ok(120.0), |a| a.parse())?,
        kinds: match positional.get(1) {
            Some(list) => ControllerKind::parse_list(list)?,
            None => ControllerKind::CHOICES.to_vec(),
        },
        json,
        scatter,
        objective,
    })
}

/// What [`write_json`] writes besides the studies.
struct RunInfo<'a> {
    diagram: &'a str,
    seconds: f64,
    settings: &'a ControlSettings,
    pd_gains: Option<[f64; 3]>,
    load_before: &'a str,
}

/// The run so far as JSON into `file` (rewritten after every controller, so a run stopped
/// early keeps the controllers it finished).
fn write_json(
    file: &str,
    info: &RunInfo<'_>,
    studies: &[(Study, f64, f64)],
) -> Result<(), Box<dyn std::error::Error>> {
    let none_life = studies
        .iter()
        .find(|s| s.0.controllers[0].kind == ControllerKind::None)
        .map_or(f64::NAN, |s| s.0.controllers[0].life_years);
    let controllers: Vec<_> = studies
        .iter()
        .map(|(study, cpu, wall)| {
            let c = &study.controllers[0];
            let cells: Vec<_> = c
                .cells
                .iter()
                .map(|cell| {
                    json!({
                        "hs": cell.sea.map(|s| s.hs), "tp": cell.sea.map(|s| s.tp),
                        "probability": cell.probability, "damage": cell.damage,
                        "duration_s": cell.duration_s,
                        "damage_per_year": cell.damage_per_year, "force": cell.force,
                    })
                })
                .collect();
            json!({
                "controller": c.kind.name(), "damage_per_year": c.damage_per_year,
                "life_years": c.life_years, "life_extension": c.life_years / none_life,
                "cpu_s": cpu, "wall_s": wall, "cells": cells,
            })
        })
        .collect();
    let s = info.settings;
    let report = json!({
        "scene": "examples/scenes/riser_300m.toml", "scatter": info.diagram,
        "seconds_counted": info.seconds, "spin_up_s": SPIN_UP_S, "interval": s.interval,
        "horizon": format!("{:?}", s.mpc.horizon), "plan_pendulums": s.mpc.plan_pendulums,
        "plan_step": s.mpc.plan_step, "iterations": s.mpc.iterations,
        "bound_n": s.bound(), "effort": s.mpc.effort, "mpc_fatigue_proxy": s.mpc_fatigue_proxy,
        "pd_gains": info.pd_gains, "pd_training_s": s.pd_training,
        "load_average_before": info.load_before, "load_average_now": load_average(),
        "controllers": controllers,
    });
    std::fs::write(file, serde_json::to_string_pretty(&report)?)?;
    Ok(())
}

/// The controllers' settings: the scene's `[mpc]` table (docs/scene-format.md "[mpc]"), the
/// spin-up window and the PD tuning's iterations of this example; `objective` overrides the
/// table's `objective`.
fn control_settings(
    scene: &Scene,
    objective: Option<MpcPlanObjective>,
) -> Result<ControlSettings, Box<dyn std::error::Error>> {
    let t = scene
        .mpc
        .as_ref()
        .ok_or("riser_300m.toml has an [mpc] table")?;
    let need = |key: &str| format!("riser_300m.toml: [mpc] sets {key}");
    Ok(ControlSettings {
        interval: t.interval.ok_or_else(|| need("interval"))?,
        mpc: MpcOptions {
            horizon: Horizon::Seconds(t.horizon.ok_or_else(|| need("horizon"))?),
            iterations: t.iterations.unwrap_or(1),
            effort: t.effort.ok_or_else(|| need("effort"))?,
            ocp: OcpOptions::default().with_bound(t.bound.ok_or_else(|| need("bound"))?),
            plan_pendulums: t.plan_pendulums,
            plan_step: t.plan_step,
            ..MpcOptions::default()
        },
        pd_max_iters: PD_ITERS,
        pd_training: t.pd_training,
        pd_gains: None,
        spin_up: SPIN_UP_S,
        mpc_fatigue_proxy: objective.or(t.objective) != Some(MpcPlanObjective::Sum),
        // The scene's own [time] (this example sets it to the headline's record).
        record: None,
        seeds: 1,
    })
}

/// The table of the controllers (each with its CPU and wall seconds) and the damage per cell;
/// `record_s` is the simulated length of one cell's record (spin-up included) \[s\].
fn print_results(cells: &[ScatterCell], studies: &[(Study, f64, f64)], record_s: f64) {
    let none_life = studies
        .iter()
        .find(|s| s.0.controllers[0].kind == ControllerKind::None)
        .map_or(f64::NAN, |s| s.0.controllers[0].life_years);
    println!(
        "\n| controller | damage per year | life (years, DFF 10) | life extension | CPU (s) | \
         wall (s) | simulated s per CPU s |\n|---|---|---|---|---|---|---|"
    );
    let simulated = record_s * cells.len() as f64;
    for (study, cpu, wall) in studies {
        let c = &study.controllers[0];
        println!(
            "| {} | {:.4e} | {:.4e} | {:.3} | {cpu:.1} | {wall:.1} | {:.1} |",
            c.kind.name(),
            c.damage_per_year,
            c.life_years,
            c.life_years / none_life,
            simulated / cpu
        );
    }
    println!("\nper cell, damage per year (probability-weighted), by controller:");
    for (s, cell) in cells.iter().enumerate() {
        let row: Vec<String> = studies
            .iter()
            .map(|(study, _, _)| {
                let c = &study.controllers[0];
                let force = c.cells[s]
                    .force
                    .map_or(String::new(), |f| format!(" (u = {f:.3e} N)"));
                format!(
                    "{} {:.3e}{force}",
                    c.kind.name(),
                    c.cells[s].damage_per_year
                )
            })
            .collect();
        println!(
            "  H_s {:4.2} m, T_p {:5.2} s: {}",
            cell.sea.hs,
            cell.sea.tp,
            row.join(", ")
        );
    }
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let Args {
        seconds,
        kinds,
        json,
        scatter,
        objective,
    } = args()?;
    let path = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/examples/scenes/riser_300m.toml"
    );
    let mut scene = Scene::from_file(path)?;
    scene.time.steps = ((SPIN_UP_S + seconds) / scene.time.step).round() as usize;
    let pipe = scene.pipe.ok_or("riser_300m.toml has a [pipe]")?;
    let spec = FatigueSpec {
        scf: 1.2,
        curve: DnvClass::F1,
        environment: Environment::SeawaterCp,
        dff: 10.0,
        ..FatigueSpec::new(pipe.outer_diameter, pipe.wall_thickness)
    };
    let (cells, diagram) = match &scatter {
        Some(file) => (read_scatter(file)?, file.clone()),
        None => (
            reduced_north_atlantic(),
            "reduced_north_atlantic".to_string(),
        ),
    };
    let coverage = coverage(&cells, scatter.is_none());
    let mut settings = control_settings(&scene, objective)?;
    let load_before = load_average();
    println!(
        "riser_300m: {} pendulums, {seconds} s counted per cell after a {SPIN_UP_S} s spin-up \
         (h = {} s), scatter {diagram}: {} cells, {coverage}; load average {}",
        scene.n(),
        scene.time.step,
        cells.len(),
        load_before
    );
    for c in &cells {
        println!(
            "  cell H_s = {:4.2} m, T_p = {:5.2} s, p = {:.4}",
            c.sea.hs, c.sea.tp, c.probability
        );
    }
    let mut studies: Vec<(Study, f64, f64)> = Vec::new();
    let mut pd_gains = None;
    for &kind in &kinds {
        let (cpu0, wall0) = (cpu_seconds(), Instant::now());
        if kind == ControllerKind::Pd {
            // One design for every cell, tuned on the scene's own sea (module docs).
            let pd = pd_law(&scene, &settings)?;
            settings.pd_gains = Some([pd.bias.z, pd.kp, pd.kd]);
            pd_gains = settings.pd_gains;
            println!(
                "pd gains (tuned on the first {:?} s of the scene's sea): u_b = {:.4e} N, K_p = \
                 {:.4e} N/(N·m), K_d = {:.4e} N·s/(N·m)",
                settings.pd_training, pd.bias.z, pd.kp, pd.kd
            );
        }
        let input = StudyInput {
            scene: &scene,
            spec: &spec,
            cells: Some(&cells),
            controllers: &[kind],
            settings: &settings,
        };
        let study = run_study(&input, &|| {})?;
        let (cpu, wall) = (cpu_seconds() - cpu0, wall0.elapsed().as_secs_f64());
        let c = &study.controllers[0];
        println!(
            "{}: damage per year {:.4e}, life {:.4e} years, {cpu:.1} s CPU, {wall:.1} s wall, \
             load average {}",
            kind.name(),
            c.damage_per_year,
            c.life_years,
            load_average()
        );
        studies.push((study, cpu, wall));
        if let Some(file) = &json {
            let info = RunInfo {
                diagram: &diagram,
                seconds,
                settings: &settings,
                pd_gains,
                load_before: &load_before,
            };
            write_json(file, &info, &studies)?;
        }
    }
    print_results(&cells, &studies, SPIN_UP_S + seconds);
    println!("load average after: {}", load_average());
    Ok(())
}
