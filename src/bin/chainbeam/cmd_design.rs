//! `chainbeam design`: the design that maximises the wellhead's fatigue life over a scatter
//! diagram ([`chainbeam::design::optimise`]), or the sensitivities of its annual damage at the
//! scene's design (`--sensitivities`), as JSON.

use std::collections::BTreeMap;
use std::path::PathBuf;
use std::sync::Arc;

use clap::Args;
use serde::Serialize;

use chainbeam::design::{
    optimise, sensitivities, DesignError, DesignIterate, DesignOptions, DesignParameter,
    DesignStudy, Execution, ScatterGradient, Sensitivity,
};
use chainbeam::fatigue::life_years;
use chainbeam::fatigue_study::{StudyError, PRACTICE_RECORD_S};

use crate::output::{refuse_overwrite, Inputs, Output};
use crate::progress::Progress;
use crate::{check_finite, to_json, CliError};
use crate::{OUTPUT_HELP, SCENE_HELP};

/// `design --help`.
pub const LONG_ABOUT: &str = "\
The design that maximises the wellhead's fatigue life over a scatter diagram: the parameters of \
the scene's [design] table (docs/scene-format.md: loads.tension, beam.base_stiffness (the lower \
flex joint), beam.tip_stiffness (the upper one), with bounds; soil.modulus as an uncertainty) \
optimised by L-BFGS on ln D_y with exact adjoint gradients, from the scene's own design.

D_y = Σ_s p_s · D_s · Y/T_s is the expected damage per year at the wellhead (the rainflow damage \
`chainbeam fatigue --scatter` reports, the same cells, records and spin-up), and its gradient \
∂D_y/∂θ = Σ_s p_s · ∂D_s/∂θ · Y/T_s comes from one adjoint sweep per cell (cells on all cores; the \
result does not depend on where they ran). Life L = 1/(DFF · D_y) years. Bounds: θ = lo + (hi − lo) \
· σ(z) with σ the logistic function, the optimiser working in z.

--sensitivities: no optimisation; the sensitivities at the scene's design of every [design] \
parameter (every design parameter the scene has, without a [design] table).

Output (JSON):
  sensitivities           {name: ∂D_y/∂p [1/year per unit of p]} at the scene's design
  relative_sensitivities  {name: ∂ln L/∂ln p = −(p/D_y) ∂D_y/∂p}: % of life per % of p
  roles                   {name: \"design\" or \"uncertainty\"}
  scene_design            {values {name: p}, damage_per_year, life_years} (the scene's own)
  design                  {name: optimised value} (not with --sensitivities)
  damage_per_year, life_years   at the optimised design (the scene's with --sensitivities)
  iterates                [{iteration, design, damage_per_year, life_years, gradient_norm, \
simulations}], the start first
  converged, termination, simulations (cell runs: adjoint sweeps), seconds
  cells                   [{hs, tp, direction, probability, damage, duration_s}] at the result

Progress: one line per iteration on stderr (damage per year, life, ‖∇_z ln D_y‖, the design), \
not with --quiet. Exit status 3 when the optimiser did not converge (the JSON is written all the \
same). Details: docs/cli.md.";

/// `design`'s flags.
#[derive(Args)]
pub struct DesignArgs {
    #[arg(value_name = "SCENE.toml", help = SCENE_HELP)]
    pub scene: PathBuf,
    /// The scatter diagram: a CSV with header hs,tp,probability[,direction] (as `fatigue
    /// --scatter`) [default: the scene's own sea, probability 1].
    #[arg(long, value_name = "FILE")]
    pub scatter: Option<PathBuf>,
    /// Report the sensitivities at the scene's design only (no optimisation).
    #[arg(long)]
    pub sensitivities: bool,
    /// Leave the first S seconds of every record out of the count (the start-up from rest).
    #[arg(
        long,
        value_name = "S",
        default_value_t = 0.0,
        allow_negative_numbers = true
    )]
    pub spin_up: f64,
    /// Count S seconds of every record after the spin-up [default: 10800 (3 hours)].
    #[arg(long, value_name = "S", allow_negative_numbers = true)]
    pub record: Option<f64>,
    #[arg(long, short, value_name = "FILE", help = OUTPUT_HELP)]
    pub output: Option<PathBuf>,
}

#[derive(Serialize)]
struct DesignJson {
    /// ∂D_y/∂p at the scene's design.
    sensitivities: BTreeMap<&'static str, f64>,
    relative_sensitivities: BTreeMap<&'static str, f64>,
    roles: BTreeMap<&'static str, &'static str>,
    scene_design: PointJson,
    #[serde(skip_serializing_if = "Option::is_none")]
    design: Option<BTreeMap<&'static str, f64>>,
    damage_per_year: f64,
    life_years: Option<f64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    iterates: Option<Vec<IterateJson>>,
    #[serde(skip_serializing_if = "Option::is_none")]
    converged: Option<bool>,
    #[serde(skip_serializing_if = "Option::is_none")]
    termination: Option<String>,
    simulations: usize,
    seconds: f64,
    record_s: f64,
    spin_up_s: f64,
    cells: Vec<CellJson>,
}

#[derive(Serialize)]
struct PointJson {
    values: BTreeMap<&'static str, f64>,
    damage_per_year: f64,
    life_years: Option<f64>,
}

#[derive(Serialize)]
struct IterateJson {
    iteration: usize,
    design: BTreeMap<&'static str, f64>,
    damage_per_year: f64,
    life_years: Option<f64>,
    gradient_norm: Option<f64>,
    simulations: usize,
}

#[derive(Serialize)]
struct CellJson {
    #[serde(skip_serializing_if = "Option::is_none")]
    hs: Option<f64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    tp: Option<f64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    direction: Option<f64>,
    probability: f64,
    damage: f64,
    duration_s: f64,
}

/// A design's error as one line naming the scene, the scatter file or the flag.
fn design_error(a: &DesignArgs, e: DesignError) -> CliError {
    let scene = a.scene.display();
    match &e {
        DesignError::Study(StudyError::SpinUp { .. }) => {
            CliError::msg(format!("{scene}: --spin-up: {e}"))
        }
        DesignError::Study(StudyError::Record { .. }) => {
            CliError::msg(format!("{scene}: --record: {e}"))
        }
        DesignError::Study(
            StudyError::SeaState { .. }
            | StudyError::NoCells
            | StudyError::TooManyCells { .. }
            | StudyError::Fatigue(_),
        ) if a.scatter.is_some() => {
            let file = a.scatter.as_deref().unwrap_or(&a.scene).display();
            CliError::msg(format!("{file} (with {scene}): {e}"))
        }
        _ => CliError::msg(format!("{scene}: {e}")),
    }
}

/// `name = value` of every design choice, for a progress line.
fn design_line(names: &[DesignParameter], values: &[f64]) -> String {
    names
        .iter()
        .zip(values)
        .map(|(p, v)| format!("{}={v:.6e}", p.name()))
        .collect::<Vec<_>>()
        .join("  ")
}

fn by_name(names: &[DesignParameter], values: &[f64]) -> BTreeMap<&'static str, f64> {
    names
        .iter()
        .map(|p| p.name())
        .zip(values.iter().copied())
        .collect()
}

/// The life as JSON: `null` for an infinite one.
fn finite(x: f64) -> Option<f64> {
    x.is_finite().then_some(x)
}

/// Runs `design`.
pub fn run(a: &DesignArgs, progress: Progress, quiet: bool) -> Result<(), CliError> {
    let out = Output::prepare(a.output.as_deref())?;
    let mut inputs = Inputs::new();
    let scene = inputs.load_scene(&a.scene)?;
    if let Some(s) = &a.scatter {
        inputs.file(s);
    }
    refuse_overwrite(&[("--output", &out)], &inputs)?;
    let cells = match &a.scatter {
        Some(path) => Some(
            chainbeam::fatigue::scatter::read_scatter_file(path)
                .map_err(|e| CliError::msg(e.to_string()))?,
        ),
        None => None,
    };
    let record = a.record.unwrap_or(PRACTICE_RECORD_S);
    let study = DesignStudy {
        scene: &scene,
        cells: cells.as_deref(),
        record: Some(record),
        spin_up: a.spin_up,
    };
    let dff = scene
        .fatigue_spec()
        .ok_or_else(|| design_error(a, DesignError::NoFatigueSpec))?
        .dff;
    let sens_json = |s: &[Sensitivity]| {
        let names: Vec<DesignParameter> = s.iter().map(|x| x.parameter).collect();
        let d: Vec<f64> = s.iter().map(|x| x.damage_per_year).collect();
        let r: Vec<f64> = s.iter().map(|x| x.relative_life).collect();
        let v: Vec<f64> = s.iter().map(|x| x.value).collect();
        let roles = s
            .iter()
            .map(|x| (x.parameter.name(), x.role.name()))
            .collect();
        (
            by_name(&names, &d),
            by_name(&names, &r),
            roles,
            by_name(&names, &v),
        )
    };
    let cells_json = |g: &ScatterGradient| -> Vec<CellJson> {
        g.cells
            .iter()
            .enumerate()
            .map(|(s, c)| {
                let sea = cells.as_ref().map(|cs| cs[s].sea);
                CellJson {
                    hs: sea.map(|x| x.hs),
                    tp: sea.map(|x| x.tp),
                    direction: sea.and_then(|x| x.direction),
                    probability: c.probability,
                    damage: c.damage,
                    duration_s: c.duration_s,
                }
            })
            .collect()
    };
    let n_cells = study.n_cells();
    let json = if a.sensitivities {
        let bar = progress.bar(n_cells as u64, format!("{n_cells} cells (adjoint sweeps)"));
        let started = std::time::Instant::now();
        let on_cell = || bar.inc(1);
        let (g, s) =
            sensitivities(&study, Execution::Parallel, &on_cell).map_err(|e| design_error(a, e))?;
        bar.finish_and_clear();
        let (sens, rel, roles, values) = sens_json(&s);
        let life = life_years(g.damage_per_year, dff).unwrap_or(f64::INFINITY);
        DesignJson {
            sensitivities: sens,
            relative_sensitivities: rel,
            roles,
            scene_design: PointJson {
                values,
                damage_per_year: g.damage_per_year,
                life_years: finite(life),
            },
            design: None,
            damage_per_year: g.damage_per_year,
            life_years: finite(life),
            iterates: None,
            converged: None,
            termination: None,
            simulations: n_cells,
            seconds: started.elapsed().as_secs_f64(),
            record_s: record,
            spin_up_s: a.spin_up,
            cells: cells_json(&g),
        }
    } else {
        let names: Vec<DesignParameter> = scene
            .design
            .as_ref()
            .map(|t| t.design_choices().iter().map(|c| c.0).collect())
            .unwrap_or_default();
        let line_names = names.clone();
        let on_iterate = (!quiet).then(|| {
            Arc::new(move |it: &DesignIterate| {
                eprintln!(
                    "iter {:>3}  damage/yr {:.6e}  life {:.6e} y  |g| {:.3e}  sims {}  {}",
                    it.iteration,
                    it.damage_per_year,
                    it.life_years,
                    it.gradient_norm,
                    it.simulations,
                    design_line(&line_names, &it.values)
                );
            }) as chainbeam::design::IterateCallback
        });
        let options = DesignOptions {
            execution: Execution::Parallel,
            on_iterate,
        };
        let o = optimise(&study, &options).map_err(|e| design_error(a, e))?;
        let (sens, rel, roles, values) = sens_json(&o.sensitivities);
        let final_cells = {
            let point = chainbeam::design::DesignPoint {
                params: &names,
                values: &o.design,
            };
            // The final design's cells (already evaluated: recomputed forward, cheap next to the
            // optimisation, to report them).
            study
                .evaluate(
                    &point,
                    chainbeam::design::Want::Value,
                    Execution::Parallel,
                    &|| {},
                )
                .map_err(|e| design_error(a, e))?
        };
        let iterates = o
            .iterates
            .iter()
            .map(|it| IterateJson {
                iteration: it.iteration,
                design: by_name(&names, &it.values),
                damage_per_year: it.damage_per_year,
                life_years: finite(it.life_years),
                gradient_norm: finite(it.gradient_norm),
                simulations: it.simulations,
            })
            .collect();
        if !o.converged {
            eprintln!(
                "{}: warning: the optimiser did not converge: {}",
                a.scene.display(),
                o.termination
            );
        }
        DesignJson {
            sensitivities: sens,
            relative_sensitivities: rel,
            roles,
            scene_design: PointJson {
                values,
                damage_per_year: o.initial.damage_per_year,
                life_years: finite(o.initial.life_years),
            },
            design: Some(by_name(&names, &o.design)),
            damage_per_year: o.damage_per_year,
            life_years: finite(o.life_years),
            iterates: Some(iterates),
            converged: Some(o.converged),
            termination: Some(o.termination.clone()),
            simulations: o.simulations,
            seconds: o.seconds,
            record_s: record,
            spin_up_s: a.spin_up,
            cells: cells_json(&final_cells),
        }
    };
    let mut numbers: Vec<f64> = json.sensitivities.values().copied().collect();
    numbers.extend(json.relative_sensitivities.values());
    numbers.push(json.damage_per_year);
    if let Some(d) = &json.design {
        numbers.extend(d.values());
    }
    check_finite(
        &a.scene,
        "sensitivities, design or damage_per_year",
        &numbers,
    )?;
    let converged = json.converged;
    out.write_all(&to_json(&json)?)?;
    if converged == Some(false) {
        return Err(CliError::NotConverged(format!(
            "{}: the optimiser did not converge (the JSON was written)",
            a.scene.display()
        )));
    }
    Ok(())
}
