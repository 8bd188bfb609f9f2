//! How well MPC's plan predicts the plant over one horizon (chainbeam::mpc::prediction): the
//! plan's bending moment against the plant's from the plant's own states, under the same
//! controls and the same sea, as a Markdown table, one row per sea state and plan.
//!
//! ```text
//! cargo run --release --example plan_prediction -- SCENE PLANS HORIZON CELLS [options]
//!   PLANS      comma-separated n_p:h_p (e.g. 20:0.1,40:0.05), or `plant` for the scene itself
//!   HORIZON    the horizon T [s]
//!   CELLS      `scene` (the scene's own sea), or comma-separated Hs:Tp [m:s] (γ as the scene)
//!   --starts T0,T1,...   start times [s] (default 100,140,180,220,260)
//!   --drag scene|morison|off   the drag of plant and plan: as the scene; Morison's node by node
//!                        (a [pipe] scene); none,
//!                        and no current, which acts through it (default scene)
//!   --seed S            the forcing's seed (default 1)
//!   --amplitude A       the forcing's bound [N] (default: the vessel's thrust bound in a thrust
//!                        scene, else [mpc] bound, else 5e4)
//!   --interval T        the forcing's pieces [s] (default [mpc] interval, else 1)
//!   --rate R            the forcing moves at most R [N/s] (default: jumps between pieces)
//!   --elevation E       the moment at E [m] above the base, blended between the two joints
//!                        around it as a hot spot's (default 0, M_w)
//!   --thrust            a `support = "vessel"` scene without thrust keys: the vessel's thrust
//!                        (the documented default mass, damping and bounds) is the control
//! ```

use std::process::ExitCode;

use chainbeam::mpc::prediction::{Forcing, PlanModel, PlantRuns, PredictionSetup};
use chainbeam::scene::{DragModel, MpcSettings, Support};
use chainbeam::Scene;

struct Args {
    scene: String,
    plans: Vec<PlanModel>,
    horizon: f64,
    cells: Option<Vec<(f64, f64)>>,
    starts: Vec<f64>,
    drag: String,
    seed: u64,
    amplitude: Option<f64>,
    interval: Option<f64>,
    rate: Option<f64>,
    elevation: f64,
    thrust: bool,
}

fn number(what: &str, s: &str) -> Result<f64, String> {
    s.trim()
        .parse::<f64>()
        .map_err(|_| format!("{what}: not a number: `{s}`"))
}

fn parse() -> Result<Args, String> {
    let argv: Vec<String> = std::env::args().skip(1).collect();
    let mut pos = Vec::new();
    let mut a = Args {
        scene: String::new(),
        plans: Vec::new(),
        horizon: 0.0,
        cells: None,
        starts: vec![100.0, 140.0, 180.0, 220.0, 260.0],
        drag: "scene".into(),
        seed: 1,
        amplitude: None,
        interval: None,
        rate: None,
        elevation: 0.0,
        thrust: false,
    };
    let mut i = 0;
    while i < argv.len() {
        let flag = argv[i].as_str();
        let mut value = || {
            i += 1;
            argv.get(i)
                .cloned()
                .ok_or_else(|| format!("{flag} needs a value"))
        };
        match flag {
            "--starts" => {
                a.starts = value()?
                    .split(',')
                    .map(|s| number("--starts", s))
                    .collect::<Result<_, _>>()?
            }
            "--drag" => a.drag = value()?,
            "--seed" => {
                let v = value()?;
                a.seed = v
                    .parse()
                    .map_err(|_| format!("--seed: not a count: `{v}`"))?
            }
            "--amplitude" => a.amplitude = Some(number("--amplitude", &value()?)?),
            "--interval" => a.interval = Some(number("--interval", &value()?)?),
            "--rate" => a.rate = Some(number("--rate", &value()?)?),
            "--elevation" => a.elevation = number("--elevation", &value()?)?,
            "--thrust" => a.thrust = true,
            f if f.starts_with("--") => return Err(format!("unknown flag {f}")),
            _ => pos.push(argv[i].clone()),
        }
        i += 1;
    }
    let [scene, plans, horizon, cells] = <[String; 4]>::try_from(pos)
        .map_err(|_| "usage: plan_prediction SCENE PLANS HORIZON CELLS [options]".to_string())?;
    a.scene = scene;
    for p in plans.split(',') {
        if p == "plant" {
            a.plans.push(PlanModel::Plant);
            continue;
        }
        let (np, hp) = p
            .split_once(':')
            .ok_or_else(|| format!("PLANS: `{p}` is not n_p:h_p or `plant`"))?;
        a.plans.push(PlanModel::Reduced {
            pendulums: np
                .parse()
                .map_err(|_| format!("PLANS: `{np}` is not a count"))?,
            step: number("PLANS h_p", hp)?,
        });
    }
    a.horizon = number("HORIZON", &horizon)?;
    if cells != "scene" {
        let mut v = Vec::new();
        for c in cells.split(',') {
            let (hs, tp) = c
                .split_once(':')
                .ok_or_else(|| format!("CELLS: `{c}` is not Hs:Tp"))?;
            v.push((number("CELLS H_s", hs)?, number("CELLS T_p", tp)?));
        }
        a.cells = Some(v);
    }
    Ok(a)
}

fn scene_of(a: &Args) -> Result<Scene, String> {
    let mut scene = Scene::from_file(&a.scene).map_err(|e| format!("{}: {e}", a.scene))?;
    match a.drag.as_str() {
        "scene" => {}
        "morison" => {
            let pipe = scene
                .pipe
                .as_mut()
                .ok_or("--drag morison: the scene has no [pipe] (a stack-up sets its own)")?;
            pipe.drag_model = DragModel::Morison;
            scene.loads.drag = 0.0;
        }
        "off" => {
            if let Some(p) = scene.pipe.as_mut() {
                p.drag_model = DragModel::Momentum;
            }
            if scene.stackup.is_some() {
                return Err("--drag off: not for a stack-up scene".into());
            }
            scene.loads.drag = 0.0;
            // The current acts only through the drag.
            scene.loads.current = None;
        }
        d => return Err(format!("--drag: `{d}` is not scene, morison or off")),
    }
    if a.thrust {
        if scene.beam.support != Support::Vessel {
            return Err("--thrust: the scene's support is not `vessel`".into());
        }
        let v = scene.vessel.get_or_insert_with(Default::default);
        if v.thrust().is_none() {
            v.mass = Some(chainbeam::scene::DEFAULT_VESSEL_MASS);
        }
    }
    scene.validate().map_err(|e| format!("{}: {e}", a.scene))?;
    Ok(scene)
}

/// A relative error in per cent: two decimals, or three significant digits below 0.01 %.
fn percent(x: f64) -> String {
    let p = 100.0 * x;
    if p >= 0.01 {
        format!("{p:.2} %")
    } else {
        format!("{p:.2e} %")
    }
}

fn main() -> ExitCode {
    match run() {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("plan_prediction: {e}");
            ExitCode::FAILURE
        }
    }
}

fn run() -> Result<(), String> {
    let a = parse()?;
    let base = scene_of(&a)?;
    let mpc = base.mpc.as_ref();
    let amplitude = a.amplitude.unwrap_or_else(|| match base.thrust() {
        Some(t) => t.bound,
        None => mpc
            .and_then(|m| m.bound)
            .unwrap_or(MpcSettings::DEFAULT_BOUND),
    });
    let interval = a
        .interval
        .unwrap_or_else(|| mpc.and_then(|m| m.interval).unwrap_or(1.0));
    let cells = match &a.cells {
        None => vec![None],
        Some(c) => c.iter().map(|&c| Some(c)).collect(),
    };
    println!(
        "Plan vs plant over {} s from t0 = {:?} s; {}; drag {}; forcing ±{amplitude} N pieces of \
         {interval} s, rate bound {:?} N/s, seed {}; moment at {} m (blended between the joints around it).\n",
        a.horizon, a.starts, a.scene, a.drag, a.rate, a.seed, a.elevation
    );
    println!(
        "| H_s [m] | T_p [s] | plan n_p @ h_p | e_total | e_response | e_unforced | e_response per start (min–max) | rms plant ΔM [N·m] | plant s/horizon | plan s/horizon | moment's elevation plant/plan [m] |"
    );
    println!("|---|---|---|---|---|---|---|---|---|---|---|");
    for cell in cells {
        let mut scene = base.clone();
        if let Some((hs, tp)) = cell {
            let w = scene
                .loads
                .waves
                .as_mut()
                .ok_or("CELLS: the scene has no [loads.waves]")?;
            w.hs = hs;
            w.tp = tp;
            scene.validate().map_err(|e| e.to_string())?;
        }
        let (hs, tp) = scene
            .loads
            .waves
            .as_ref()
            .map_or((0.0, 0.0), |w| (w.hs, w.tp));
        let setup = PredictionSetup {
            plan: PlanModel::Plant,
            horizon: a.horizon,
            starts: a.starts.clone(),
            forcing: Forcing {
                interval,
                amplitude,
                seed: a.seed,
                rate: a.rate,
            },
            elevation: a.elevation,
        };
        let runs = PlantRuns::new(&scene, &setup).map_err(|e| e.to_string())?;
        for &plan in &a.plans {
            let r = match runs.predict(plan) {
                Ok(r) => r,
                Err(e) => {
                    // A plan that cannot be rolled (a step too large for its chain) is a row.
                    let name = match plan {
                        PlanModel::Plant => "plant".to_string(),
                        PlanModel::Reduced { pendulums, step } => format!("{pendulums} @ {step} s"),
                    };
                    println!("| {hs:.2} | {tp:.2} | {name} | fails: {e} | | | | | | | |");
                    continue;
                }
            };
            let (lo, hi) = r.starts.iter().fold((f64::INFINITY, 0.0f64), |(l, h), s| {
                (l.min(s.response), h.max(s.response))
            });
            let dm = (r
                .starts
                .iter()
                .map(|s| s.plant_response_rms.powi(2))
                .sum::<f64>()
                / r.starts.len() as f64)
                .sqrt();
            println!(
                "| {hs:.2} | {tp:.2} | {} @ {} s | {} | {} | {} | {}–{} | {dm:.3e} | {:.3} | {:.3} | {:.2}/{:.2} |",
                r.plan_pendulums,
                r.plan_step,
                percent(r.total),
                percent(r.response),
                percent(r.unforced),
                percent(lo),
                percent(hi),
                r.plant_seconds,
                r.plan_seconds,
                r.joint_elevations[0],
                r.joint_elevations[1]
            );
        }
    }
    Ok(())
}
