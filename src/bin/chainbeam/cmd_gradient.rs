//! `chainbeam gradient`: objective and exact adjoint gradient (JSON).

use std::path::PathBuf;

use clap::Args;
use serde::Serialize;

use chainbeam::ValidScene;

use crate::controls_io::ControlsFile;
use crate::output::{refuse_overwrite, Inputs, Output};
use crate::problem::{self, ProblemArgs, ProblemReport, SceneProblem, Values};
use crate::progress::Progress;
use crate::{check_finite, controls_io, lib_error, to_json, CliError};
use crate::{OUTPUT_HELP, SCENE_HELP};

/// `gradient --help`.
pub const LONG_ABOUT: &str = "\
Evaluate the objective of the scene's [objective] (default \"final\") and its exact gradient by the \
discrete adjoint with respect to the control parameters θ, at the scene's control.values (or at \
the values of --controls FILE).

Objectives: \"final\" c = M₀(t_N)² (thesis eq. 3.3.2), \"sum\" c_sum = Σ_{k=0..N} M₀(t_k)² \
(eq. 3.3.4), in N²m², plus ρ·h·Σ u_k² with --effort ρ. M₀ is the base bending moment in Nm; the \
gradient is in N²m²/N = Nm².

θ is laid out as control.values: one value for kind = \"constant\", N + 1 values u_0..u_N for \
\"per-step\" (u_N only touches the final momentum, never a configuration, so its entry is 0 \
without --effort), P values with --pieces P. With --controls FILE the file decides: 1 value is a \
constant, N + 1 values are per-step, and the JSON of optimize says its own kind.

Spatial scenes (a load, the current or the control with an x component) run the spatial model, \
planar ones the planar model (JSON key model); the objectives then use |M₀|² = M₀ₓ² + M₀². A \
2-axis control (control.values as pairs [u_x, u_z], or a --controls file of pairs) has 2 \
parameters per value, and controls and gradient are reported as pairs too: [u_x, u_z] and \
[dc/du_x, dc/du_z] per value.

Output (JSON): objective, gradient [dc/dθ], controls [θ], gradient_norm, model, objective_kind, \
objective_exponent (kind \"power\" only), effort, control_kind, pieces (piecewise only), \
control_node. The output is itself a valid --controls file.

Sign convention: a load F > 0 enters H as +F·z and pushes toward −z; u = −F cancels a tip load F.";

/// `gradient`'s flags.
#[derive(Args)]
pub struct GradientArgs {
    #[arg(value_name = "SCENE.toml", help = SCENE_HELP)]
    pub scene: PathBuf,
    /// Evaluate at these controls instead of the scene's control.values: the JSON that
    /// `optimize` or `gradient` writes, the `control` column (and `control_x`, if any) of a
    /// `simulate` CSV, or a single column of numbers (1 value: constant; N + 1 values:
    /// per-step). A 2-axis scene needs pairs [u_x, u_z].
    #[arg(long, value_name = "FILE", conflicts_with = "pieces")]
    pub controls: Option<PathBuf>,
    #[command(flatten)]
    pub problem: ProblemArgs,
    #[arg(long, short, value_name = "FILE", help = OUTPUT_HELP)]
    pub output: Option<PathBuf>,
}

#[derive(Serialize)]
struct GradientReport {
    objective: f64,
    gradient: Values,
    controls: Values,
    gradient_norm: f64,
    #[serde(flatten)]
    problem: ProblemReport,
}

/// What `gradient` reads: the output it will write, the scene and the `--controls` file.
struct GradientInputs {
    out: Output,
    scene: ValidScene,
    controls: Option<ControlsFile>,
}

/// The objective and its adjoint gradient at θ₀ (what `gradient` reports).
struct Solved {
    sp: SceneProblem,
    objective: f64,
    gradient: Vec<f64>,
}

/// Runs `gradient`: inputs → solve → report.
pub fn run(a: &GradientArgs, progress: Progress) -> Result<(), CliError> {
    let inputs = load(a)?;
    let solved = solve(a, &inputs, &progress)?;
    inputs.out.write_all(&to_json(&report(&solved))?)
}

/// Gathers the inputs (the flags checked, the scene and controls read) and refuses an output
/// that is one of them.
fn load(a: &GradientArgs) -> Result<GradientInputs, CliError> {
    let out = Output::prepare(a.output.as_deref())?;
    problem::check_effort(a.problem.effort)?;
    let mut inputs = Inputs::new();
    let scene = inputs.load_scene(&a.scene)?;
    let controls = a.controls.as_deref().map(controls_io::read).transpose()?;
    if let Some(c) = &a.controls {
        inputs.file(c);
    }
    refuse_overwrite(&[("--output", &out)], &inputs)?;
    Ok(GradientInputs {
        out,
        scene,
        controls,
    })
}

/// The problem of the scene (and controls) and one adjoint sweep at θ₀; a non-finite objective
/// or gradient is refused.
fn solve(
    a: &GradientArgs,
    inputs: &GradientInputs,
    progress: &Progress,
) -> Result<Solved, CliError> {
    let scene = &inputs.scene;
    let sp = problem::build(&a.scene, scene, Some(&a.problem), inputs.controls.as_ref())?;
    let n = sp.theta0.len();
    let spinner = progress.spinner(format!(
        "adjoint gradient over {} steps ({n} parameter{})",
        scene.time.steps,
        if n == 1 { "" } else { "s" }
    ));
    let result = sp.problem.value_and_gradient(&sp.theta0);
    spinner.finish_and_clear();
    let (objective, gradient) = result.map_err(|e| lib_error(&a.scene, e))?;
    check_finite(&a.scene, "objective", &[objective])?;
    check_finite(&a.scene, "gradient", &gradient)?;
    Ok(Solved {
        sp,
        objective,
        gradient,
    })
}

/// The JSON of a solved gradient.
fn report(s: &Solved) -> GradientReport {
    let sp = &s.sp;
    GradientReport {
        objective: s.objective,
        gradient_norm: problem::norm(&s.gradient),
        gradient: sp.problem.layout(&s.gradient),
        controls: sp.problem.layout(&sp.theta0),
        problem: ProblemReport::of(sp),
    }
}
