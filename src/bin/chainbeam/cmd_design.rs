//! `chainbeam design`: the design that maximises the wellhead's fatigue life over a scatter
//! diagram ([`chainbeam::design::optimise`]), or the sensitivities of its annual damage at the
//! scene's design (`--sensitivities`), as JSON.

use std::path::PathBuf;
use std::sync::Arc;

use clap::Args;

use chainbeam::design::{
    optimise, sensitivities, DesignError, DesignIterate, DesignOptions, DesignParameter,
    DesignReport, DesignStudy, Execution,
};
use chainbeam::fatigue_study::{StudyError, PRACTICE_RECORD_S};

use crate::output::{refuse_overwrite, Inputs, Output};
use crate::progress::Progress;
use crate::{check_finite, to_json, CliError};
use crate::{OUTPUT_HELP, SCENE_HELP};

/// `design --help`.
pub const LONG_ABOUT: &str = "\
The design that maximises the wellhead's fatigue life over a scatter diagram: the parameters of \
the scene's [design] table (docs/scene-format.md: loads.tension, beam.base_stiffness (the lower \
flex joint), beam.tip_stiffness (the upper one), a stack-up's named flex joints \
stackup.flex_joint.<name>.stiffness, with bounds; soil.modulus as an uncertainty) optimised \
by a projected L-BFGS on ln D_y with exact adjoint gradients, from the scene's own design.

D_y = Σ_s p_s · D_s · Y/T_s is the expected damage per year at the wellhead (the rainflow damage \
`chainbeam fatigue --scatter` reports, the same cells, records and spin-up), and its gradient \
∂D_y/∂θ = Σ_s p_s · ∂D_s/∂θ · Y/T_s comes from one adjoint sweep per cell (cells on all cores; the \
result does not depend on where they ran). Life L = 1/(DFF · D_y) years. Bounds: the optimiser works in \
u = ln(θ/lo)/ln(hi/lo) ∈ [0, 1]; a step beyond a bound lands on it and a parameter on a bound whose \
gradient pushes outward stays there (an active set, as L-BFGS-B); it stops when the projected \
gradient's norm ‖P(u − ∇_u ln D_y) − u‖_∞ ≤ [design] tolerance.

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
simulations, adjoint_sweeps, forward_runs}], the start first
  converged, termination, simulations (cell runs: adjoint_sweeps, each a forward and a reverse \
pass, plus forward_runs, line-search trials that need the value alone), adjoint_sweeps, \
forward_runs, seconds
  cells                   [{hs, tp, direction, probability, damage, duration_s}] at the result

Progress: one line per iteration on stderr (damage per year, life, the projected gradient's \
norm, the design), \
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
    let dff = study.dff().map_err(|e| design_error(a, e))?;
    let n_cells = study.n_cells();
    let json = if a.sensitivities {
        let bar = progress.bar(n_cells as u64, format!("{n_cells} cells (adjoint sweeps)"));
        let started = std::time::Instant::now();
        let on_cell = || bar.inc(1);
        let (g, s) =
            sensitivities(&study, Execution::Parallel, &on_cell).map_err(|e| design_error(a, e))?;
        bar.finish_and_clear();
        DesignReport::sensitivities(
            &study,
            (&g, &s),
            dff,
            record,
            started.elapsed().as_secs_f64(),
        )
    } else {
        let names: Vec<DesignParameter> = scene
            .design
            .as_ref()
            .map(|t| t.design_choices().iter().map(|c| c.0.clone()).collect())
            .unwrap_or_default();
        let on_iterate = (!quiet).then(|| {
            Arc::new(move |it: &DesignIterate| {
                eprintln!(
                    "iter {:>3}  damage/yr {:.6e}  life {:.6e} y  |Pg| {:.3e}  sims {}  {}",
                    it.iteration,
                    it.damage_per_year,
                    it.life_years,
                    it.gradient_norm,
                    it.simulations,
                    design_line(&names, &it.values)
                );
            }) as chainbeam::design::IterateCallback
        });
        let options = DesignOptions {
            execution: Execution::Parallel,
            on_iterate,
            runner: None,
        };
        let o = optimise(&study, &options).map_err(|e| design_error(a, e))?;
        if !o.converged {
            eprintln!(
                "{}: warning: the optimiser did not converge: {}",
                a.scene.display(),
                o.termination
            );
        }
        DesignReport::optimised(&study, &o, record)
    };
    check_finite(
        &a.scene,
        "sensitivities, design or damage_per_year",
        &json.numbers(),
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
