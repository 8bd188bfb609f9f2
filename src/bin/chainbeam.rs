//! `chainbeam`: the command line of the chain-of-pendulums beam simulator (SPEC §5).
//!
//! ```text
//! chainbeam simulate SCENE.toml [--output FILE]          CSV: t,energy,moment,x1,y1,z1,...
//! chainbeam gradient SCENE.toml [--output FILE]          JSON: objective, gradient, controls
//! chainbeam optimize SCENE.toml [--starts K] [--method lbfgs|trust-region] [--bound U] [--output FILE]
//! chainbeam explore  SCENE.toml [--starts K] [--design latin|random|perturb] [--output FILE]
//! global: --threads N (multistart workers), --seed S (start designs), --quiet (no progress bars)
//! ```
//!
//! `optimize` and `explore` use [`chainbeam::optimize::minimize`] and
//! [`chainbeam::multistart::multistart`]; `controls` in their JSON are the control parameters laid
//! out as the scene's `control.values` (1 value for a constant control, N + 1 for per-step).
//!
//! Every error exits with status 1 and one message on stderr naming the file, the key and the
//! reason (scene errors) or the step and the residual (solver failures); command-line usage errors
//! exit with status 2. Results are checked for NaN and infinity before anything is written, and
//! `--output` files are written atomically.

#[path = "chainbeam/output.rs"]
mod output;
#[path = "chainbeam/progress.rs"]
mod progress;

use std::fmt;
use std::io::Write;
use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::time::Instant;

use clap::{Args, Parser, Subcommand, ValueEnum};
use serde::Serialize;

use chainbeam::multistart::{multistart, MultistartReport, StartDesign};
use chainbeam::optimize::{minimize, Method, OptimOptions, OptimResult};
use chainbeam::{simulate, ControlKind, ControlProblem, ObjectiveKind, Scene};

use output::{fmt_f64, write_all, Sink};
use progress::Progress;

const LONG_ABOUT: &str = "\
Simulate, differentiate and optimise a slender beam modelled as a chain of rigid pendulums joined \
by torsional springs (Nøst 2023), integrated with RATTLE, with exact gradients from a discrete \
adjoint.

A scene is a TOML file (see examples/scenes/ and SPEC §5): [beam], [loads], [time], and optionally \
[control] and [objective].

Units (SI): lengths and positions in m, masses in kg, spring constants in Nm/rad, forces and \
controls in N, drag D in kg/m, gravity in m/s², time and step h in s, energy in J, base bending \
moment M₀ in Nm.

Geometry and sign convention (the thesis's): the undeformed beam lies along +y from node 0 at the \
origin; loads act along z. A load F enters the Hamiltonian as +F·z, so F > 0 pushes the beam toward \
−z, and a control u = −F at the tip cancels a tip load F.

Exit status: 0 on success, 1 for an invalid scene or a failed computation (one message on stderr \
naming the file, the key and the reason, or the step and the residual), 2 for a command-line usage \
error. Output never contains NaN or infinity: non-finite results are an error and nothing is \
written.";

const AFTER_HELP: &str = "\
Examples:
  chainbeam simulate examples/scenes/thesis_cantilever.toml --output tip.csv
  chainbeam gradient examples/scenes/riser_5.toml
  chainbeam optimize examples/scenes/riser_5.toml --method lbfgs
  chainbeam explore examples/scenes/riser_5.toml --starts 16 --seed 1";

const SCENE_HELP: &str = "\
The scene file (TOML, SPEC §5). Size limits, so that a mistyped file fails cleanly instead of \
exhausting memory: at most 10⁶ pendulums, 10⁷ steps, and (steps + 1)·pendulums ≤ 2·10⁸ stored \
node states (about 10 GB)";

const OUTPUT_HELP: &str = "\
Write the result to FILE instead of standard output. The file is written atomically: to a \
temporary file in the same directory, then renamed, so an interrupted or failed run never leaves a \
half-written result";

#[derive(Parser)]
#[command(
    name = "chainbeam",
    version,
    about = "Chain-of-pendulums beam simulator with RATTLE and discrete-adjoint optimal control",
    long_about = LONG_ABOUT,
    after_help = AFTER_HELP,
    propagate_version = true
)]
struct Cli {
    /// Worker threads for parallel work (the starts of `optimize --starts` and `explore`);
    /// 0 means one per CPU core.
    #[arg(long, global = true, value_name = "N", default_value_t = 0)]
    threads: usize,
    /// Seed for the random start designs of `optimize --starts` and `explore`; the same seed gives
    /// the same starts and the same results.
    #[arg(long, global = true, value_name = "S", default_value_t = 0)]
    seed: u64,
    /// Do not draw progress bars (they are drawn on stderr only when it is a terminal anyway).
    #[arg(long, short, global = true)]
    quiet: bool,
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Simulate a scene and write its trajectory as CSV.
    #[command(long_about = "\
Simulate a scene from the straight beam at rest with RATTLE (step h = time.step, N = time.steps), \
applying the scene's [control] values if it has one (u_k at node control.node; a constant control \
is applied at every t_k), and write the trajectory as CSV.

Columns (header line first, then one row per time t_k = k·h, k = 0..N, so N + 1 rows):
  t        time t_k [s]
  energy   total energy H(q_k, p_k; t_k, u_k) [J] (kinetic + springs + loads + control + gravity)
  moment   base bending moment M₀(t_k) = 2·k₁·z₁/l₁² [Nm] (thesis eq. 3.1.3)
  xi,yi,zi position of node i = 1..n [m]; x = 0 (planar model), the beam lies along +y

Sign convention: a load F > 0 enters H as +F·z and pushes toward −z; u = −F cancels a tip load F.")]
    Simulate(SimulateArgs),
    /// Objective and exact gradient with respect to the scene's controls (JSON).
    #[command(long_about = "\
Evaluate the objective of the scene's [objective] (default \"final\") and its exact gradient by the \
discrete adjoint with respect to the parameters of the scene's [control] (default: one constant \
force at the tip, value 0), at the control values given in the scene file.

Objectives: \"final\" c = M₀(t_N)² (thesis eq. 3.3.2), \"sum\" c_sum = Σ_{k=0..N} M₀(t_k)² \
(eq. 3.3.4), in Nm²; M₀ is the base bending moment in Nm. The gradient is in Nm²/N.

Output (JSON): {\"objective\": c, \"gradient\": [dc/dθ...], \"controls\": [θ...], ...}, where θ \
are the control parameters exactly as in control.values: one value for kind = \"constant\", N + 1 \
values u_0..u_N for kind = \"per-step\" (u_N only touches the final momentum, never a \
configuration, so its gradient entry is 0). Extra keys: gradient_norm, \
objective_kind, control_kind, control_node.

Sign convention: a load F > 0 enters H as +F·z and pushes toward −z; u = −F cancels a tip load F.")]
    Gradient(GradientArgs),
    /// Minimise the scene's objective over its controls (JSON).
    #[command(long_about = "\
Minimise the scene's [objective] (default \"final\": c = M₀(t_N)², eq. 3.3.2; \"sum\": \
c_sum = Σ M₀(t_k)², eq. 3.3.4) over the scene's [control] parameters (constant or per-step force \
[N] at control.node, default the tip) by single shooting with exact adjoint gradients, starting \
from control.values. With --starts K > 1 it runs K starts (the scene's values and K − 1 others \
drawn with --seed) in parallel (--threads) and reports the best.

Output (JSON): objective [Nm²], controls (the optimal parameters, laid out as control.values) [N], \
gradient_norm, iterations, seconds, and further details.

Sign convention: a load F > 0 enters H as +F·z and pushes toward −z; u = −F cancels a tip load F.")]
    Optimize(OptimizeArgs),
    /// Map the local minima of the scene's objective from many starts (JSON).
    #[command(long_about = "\
Run a multistart exploration of the landscape of the scene's [objective] over its [control] \
parameters: K local minimisations from the points of a start design (--design latin|random|\
perturb, drawn with --seed; results do not depend on --threads), run in parallel, then cluster \
the converged results into distinct local minima.

Output (JSON):
  minima        the distinct minima, lowest objective first: objective [Nm²], controls [N] (laid \
out as control.values), count, best_start, starts
  results       one entry per start, in start order: start, start_point, objective, controls, \
gradient_norm, iterations, converged, termination, minimum (index into minima, for converged \
starts), or error (for a start whose simulation failed)
  certificate   when every converged start reached one minimum (and it has at most 200 \
parameters): the Hessian's eigenvalues there and whether it is positive definite
  and objective_kind, control_kind, control_node, method, bound, design, seed, starts, \
converged_starts, failed_starts, seconds.

Sign convention: a load F > 0 enters H as +F·z and pushes toward −z; u = −F cancels a tip load F.")]
    Explore(ExploreArgs),
}

#[derive(Args)]
struct SimulateArgs {
    #[arg(value_name = "SCENE.toml", help = SCENE_HELP)]
    scene: PathBuf,
    #[arg(long, short, value_name = "FILE", help = OUTPUT_HELP)]
    output: Option<PathBuf>,
}

#[derive(Args)]
struct GradientArgs {
    #[arg(value_name = "SCENE.toml", help = SCENE_HELP)]
    scene: PathBuf,
    #[arg(long, short, value_name = "FILE", help = OUTPUT_HELP)]
    output: Option<PathBuf>,
}

#[derive(Args)]
struct OptimizeArgs {
    #[arg(value_name = "SCENE.toml", help = SCENE_HELP)]
    scene: PathBuf,
    /// Number of starts. K > 1 runs a multistart: the scene's control values and K − 1 points of
    /// the start design (--design, drawn with --seed), in parallel on --threads; the result with
    /// the lowest objective is reported (never worse than K = 1).
    #[arg(long, value_name = "K", default_value_t = 1, value_parser = clap::value_parser!(u32).range(1..=100_000))]
    starts: u32,
    #[command(flatten)]
    solver: SolverArgs,
    #[command(flatten)]
    design: DesignArgs,
    #[arg(long, short, value_name = "FILE", help = OUTPUT_HELP)]
    output: Option<PathBuf>,
}

#[derive(Args)]
struct ExploreArgs {
    #[arg(value_name = "SCENE.toml", help = SCENE_HELP)]
    scene: PathBuf,
    /// Number of starts.
    #[arg(long, value_name = "K", default_value_t = 16, value_parser = clap::value_parser!(u32).range(1..=100_000))]
    starts: u32,
    #[command(flatten)]
    solver: SolverArgs,
    #[command(flatten)]
    design: DesignArgs,
    #[arg(long, short, value_name = "FILE", help = OUTPUT_HELP)]
    output: Option<PathBuf>,
}

/// How the start points of a multistart are drawn.
#[derive(Args)]
struct DesignArgs {
    /// Start design: `latin` (a Latin hypercube in [LO, HI]ⁿ), `random` (uniform in [LO, HI]ⁿ) or
    /// `perturb` (the scene's control values + uniform noise in [−R, R]ⁿ). Points outside
    /// --bound are clamped into it.
    #[arg(long, value_enum, default_value_t = DesignArg::Latin)]
    design: DesignArg,
    /// Lower end of the start box, in N (latin, random). The default [−600, 600] holds every
    /// constant optimum of the thesis's riser (SPEC §4).
    #[arg(long, value_name = "LO", default_value_t = -600.0, allow_negative_numbers = true)]
    lo: f64,
    /// Upper end of the start box, in N (latin, random).
    #[arg(
        long,
        value_name = "HI",
        default_value_t = 600.0,
        allow_negative_numbers = true
    )]
    hi: f64,
    /// Half-width of the perturbation, in N (perturb).
    #[arg(
        long,
        value_name = "R",
        default_value_t = 1.0,
        allow_negative_numbers = true
    )]
    radius: f64,
}

#[derive(Clone, Copy, PartialEq, Eq, ValueEnum)]
enum DesignArg {
    /// Latin hypercube in [LO, HI]ⁿ.
    Latin,
    /// Independent uniform draws in [LO, HI]ⁿ.
    Random,
    /// The scene's control values plus uniform noise in [−R, R]ⁿ.
    Perturb,
}

impl DesignArgs {
    fn design(&self, theta0: &[f64]) -> Result<StartDesign, CliError> {
        match self.design {
            DesignArg::Latin | DesignArg::Random => {
                if !(self.lo.is_finite() && self.hi.is_finite() && self.lo < self.hi) {
                    return Err(CliError::msg(format!(
                        "--lo/--hi: the start box needs finite LO < HI, got [{}, {}]",
                        self.lo, self.hi
                    )));
                }
                Ok(if self.design == DesignArg::Latin {
                    StartDesign::LatinHypercube {
                        lo: self.lo,
                        hi: self.hi,
                    }
                } else {
                    StartDesign::RandomBox {
                        lo: self.lo,
                        hi: self.hi,
                    }
                })
            }
            DesignArg::Perturb => {
                if !(self.radius.is_finite() && self.radius >= 0.0) {
                    return Err(CliError::msg(format!(
                        "--radius: must be finite and non-negative, got {}",
                        self.radius
                    )));
                }
                Ok(StartDesign::Perturb {
                    center: theta0.to_vec(),
                    radius: self.radius,
                })
            }
        }
    }

    fn describe(&self) -> DesignReport {
        match self.design {
            DesignArg::Latin => DesignReport {
                kind: "latin",
                lo: Some(self.lo),
                hi: Some(self.hi),
                radius: None,
            },
            DesignArg::Random => DesignReport {
                kind: "random",
                lo: Some(self.lo),
                hi: Some(self.hi),
                radius: None,
            },
            DesignArg::Perturb => DesignReport {
                kind: "perturb",
                lo: None,
                hi: None,
                radius: Some(self.radius),
            },
        }
    }
}

#[derive(Serialize)]
struct DesignReport {
    kind: &'static str,
    #[serde(skip_serializing_if = "Option::is_none")]
    lo: Option<f64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    hi: Option<f64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    radius: Option<f64>,
}

#[derive(Clone, Copy, PartialEq, Eq, ValueEnum)]
enum MethodArg {
    /// Limited-memory BFGS with a line search (gradients only).
    Lbfgs,
    /// Trust-region Newton-CG (Hessian-vector products by forward-over-adjoint).
    TrustRegion,
}

/// A failure reported to the user: one message on stderr and exit status 1.
#[derive(Debug)]
pub enum CliError {
    /// The message (already naming the file, key and reason).
    Msg(String),
    /// Standard output was closed by the reader (`| head`): stop quietly.
    BrokenPipe,
}

impl CliError {
    /// An error with a message.
    pub fn msg(m: impl Into<String>) -> Self {
        CliError::Msg(m.into())
    }
}

impl fmt::Display for CliError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            CliError::Msg(m) => f.write_str(m),
            CliError::BrokenPipe => f.write_str("broken pipe"),
        }
    }
}

/// A library error while working on `scene_file`, as one message naming the file.
fn lib_error(scene_file: &Path, e: chainbeam::Error) -> CliError {
    match e {
        chainbeam::Error::Scene(se) if se.file.is_some() => CliError::msg(se.to_string()),
        chainbeam::Error::Scene(se) => CliError::msg(se.with_file(scene_file).to_string()),
        other => CliError::msg(format!("{}: {other}", scene_file.display())),
    }
}

fn main() -> ExitCode {
    // A panic is a bug; report it as one line instead of a backtrace dump (exit status 101).
    std::panic::set_hook(Box::new(|info| {
        eprintln!("error: internal error in chainbeam (please report this bug): {info}");
    }));
    let cli = Cli::parse();
    match run(cli) {
        Ok(()) | Err(CliError::BrokenPipe) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e}");
            ExitCode::FAILURE
        }
    }
}

fn run(cli: Cli) -> Result<(), CliError> {
    let progress = Progress::new(cli.quiet);
    match cli.command {
        Command::Simulate(a) => cmd_simulate(&a, progress),
        Command::Gradient(a) => cmd_gradient(&a, progress),
        Command::Optimize(a) => cmd_optimize(&a, cli.seed, cli.threads, progress),
        Command::Explore(a) => cmd_explore(&a, cli.seed, cli.threads, progress),
    }
}

/// Reads and validates a scene file; the error names the file, the key and the reason.
fn load_scene(path: &Path) -> Result<Scene, CliError> {
    Scene::from_file(path).map_err(|e| CliError::msg(e.to_string()))
}

fn support_name(scene: &Scene) -> &'static str {
    match scene.beam.support {
        chainbeam::Support::Cantilever => "cantilever",
        chainbeam::Support::Riser => "riser",
        chainbeam::Support::FixedFixed => "fixed-fixed",
        chainbeam::Support::PinnedPinned => "pinned-pinned",
    }
}

// ---------------------------------------------------------------------------------------------
// simulate
// ---------------------------------------------------------------------------------------------

fn cmd_simulate(a: &SimulateArgs, progress: Progress) -> Result<(), CliError> {
    let scene = load_scene(&a.scene)?;
    let steps = scene.time.steps;
    let n = scene.n();
    let spinner = progress.spinner(format!(
        "simulating {steps} steps of a {n}-pendulum {} beam",
        support_name(&scene)
    ));
    let traj = simulate(&scene);
    spinner.finish_and_clear();
    let traj = traj.map_err(|e| lib_error(&a.scene, e))?;

    // Never write NaN: check every value before the first byte goes out.
    for k in 0..=traj.steps() {
        let bad = |col: &str| {
            CliError::msg(format!(
                "{}: the simulation produced a non-finite value in column `{col}` at step {k} \
                 (t = {}); nothing was written",
                a.scene.display(),
                traj.time(k)
            ))
        };
        if !traj.time(k).is_finite() {
            return Err(bad("t"));
        }
        if !traj.energy[k].is_finite() {
            return Err(bad("energy"));
        }
        if !traj.moment[k].is_finite() {
            return Err(bad("moment"));
        }
        for (i, r) in traj.positions(k).iter().enumerate() {
            for (c, v) in ["x", "y", "z"].iter().zip(r) {
                if !v.is_finite() {
                    return Err(bad(&format!("{c}{}", i + 1)));
                }
            }
        }
    }

    let mut sink = Sink::open(a.output.as_deref())?;
    let bar = progress.bar(traj.steps() as u64 + 1, "writing CSV rows");
    let written = write_csv(sink.writer(), &traj, &bar);
    bar.finish_and_clear();
    if let Err(e) = written {
        return Err(sink.fail(&e));
    }
    sink.finish()
}

fn write_csv(
    w: &mut dyn Write,
    traj: &chainbeam::Trajectory<f64, 2>,
    bar: &indicatif::ProgressBar,
) -> std::io::Result<()> {
    let n = traj.n();
    let mut line = String::with_capacity(16 * (3 + 3 * n));
    line.push_str("t,energy,moment");
    for i in 1..=n {
        line.push_str(&format!(",x{i},y{i},z{i}"));
    }
    line.push('\n');
    w.write_all(line.as_bytes())?;
    for k in 0..=traj.steps() {
        line.clear();
        line.push_str(&fmt_f64(traj.time(k)));
        line.push(',');
        line.push_str(&fmt_f64(traj.energy[k]));
        line.push(',');
        line.push_str(&fmt_f64(traj.moment[k]));
        for r in traj.positions(k) {
            for v in r {
                line.push(',');
                line.push_str(&fmt_f64(v));
            }
        }
        line.push('\n');
        w.write_all(line.as_bytes())?;
        if k % 1024 == 0 {
            bar.set_position(k as u64);
        }
    }
    Ok(())
}

// ---------------------------------------------------------------------------------------------
// gradient
// ---------------------------------------------------------------------------------------------

fn kind_name(kind: ControlKind) -> &'static str {
    match kind {
        ControlKind::Constant => "constant",
        ControlKind::PerStep => "per-step",
    }
}

fn objective_name(kind: ObjectiveKind) -> &'static str {
    match kind {
        ObjectiveKind::Final => "final",
        ObjectiveKind::Sum => "sum",
    }
}

/// The control problem of a scene and its initial parameters θ₀ (the scene's `control.values`, or
/// one constant 0 at the tip without a `[control]`).
struct SceneProblem {
    problem: ControlProblem,
    theta0: Vec<f64>,
    control_kind: ControlKind,
    control_node: usize,
    objective_kind: ObjectiveKind,
}

fn scene_problem(path: &Path, scene: &Scene) -> Result<SceneProblem, CliError> {
    let problem = ControlProblem::from_scene(scene).map_err(|e| lib_error(path, e))?;
    let (theta0, control_kind, control_node) = match &scene.control {
        Some(c) => (c.values.clone(), c.kind, c.node),
        None => (vec![0.0], ControlKind::Constant, scene.n()),
    };
    if theta0.len() != problem.n_params() {
        return Err(CliError::msg(format!(
            "{}: key `control.values`: expected {} values, got {}",
            path.display(),
            problem.n_params(),
            theta0.len()
        )));
    }
    Ok(SceneProblem {
        problem,
        theta0,
        control_kind,
        control_node,
        objective_kind: scene.objective.unwrap_or(ObjectiveKind::Final),
    })
}

fn norm(v: &[f64]) -> f64 {
    v.iter().map(|x| x * x).sum::<f64>().sqrt()
}

/// Checks that every number about to be written is finite; the error names the JSON key.
fn check_finite(path: &Path, key: &str, values: &[f64]) -> Result<(), CliError> {
    match values.iter().position(|v| !v.is_finite()) {
        None => Ok(()),
        Some(i) => Err(CliError::msg(format!(
            "{}: the computation produced a non-finite value for `{key}`{}; nothing was written",
            path.display(),
            if values.len() > 1 {
                format!(" (entry {i})")
            } else {
                String::new()
            }
        ))),
    }
}

#[derive(Serialize)]
struct GradientReport {
    objective: f64,
    gradient: Vec<f64>,
    controls: Vec<f64>,
    gradient_norm: f64,
    objective_kind: &'static str,
    control_kind: &'static str,
    control_node: usize,
}

fn to_json<T: Serialize>(value: &T) -> Result<String, CliError> {
    serde_json::to_string_pretty(value)
        .map(|mut s| {
            s.push('\n');
            s
        })
        .map_err(|e| CliError::msg(format!("cannot format the JSON output: {e}")))
}

fn cmd_gradient(a: &GradientArgs, progress: Progress) -> Result<(), CliError> {
    let scene = load_scene(&a.scene)?;
    let sp = scene_problem(&a.scene, &scene)?;
    let spinner = progress.spinner(format!(
        "adjoint gradient over {} steps ({} parameter{})",
        scene.time.steps,
        sp.theta0.len(),
        if sp.theta0.len() == 1 { "" } else { "s" }
    ));
    let result = sp.problem.value_and_gradient(&sp.theta0);
    spinner.finish_and_clear();
    let (objective, gradient) = result.map_err(|e| lib_error(&a.scene, e))?;
    check_finite(&a.scene, "objective", &[objective])?;
    check_finite(&a.scene, "gradient", &gradient)?;
    let report = GradientReport {
        objective,
        gradient_norm: norm(&gradient),
        gradient,
        controls: sp.theta0,
        objective_kind: objective_name(sp.objective_kind),
        control_kind: kind_name(sp.control_kind),
        control_node: sp.control_node,
    };
    write_all(a.output.as_deref(), &to_json(&report)?)
}

// ---------------------------------------------------------------------------------------------
// optimize, explore
// ---------------------------------------------------------------------------------------------

/// Options shared by `optimize` and `explore`.
#[derive(Args)]
struct SolverArgs {
    /// Optimisation method.
    #[arg(long, value_enum, default_value_t = MethodArg::Lbfgs)]
    method: MethodArg,
    /// Largest number of iterations per start [default: 1000].
    #[arg(long, value_name = "N")]
    max_iters: Option<usize>,
    /// Stop when the gradient norm ‖∇c‖ falls below this, in Nm²/N [default: off; the relative
    /// test ‖∇c‖ ≤ 1e-8·‖∇c(start)‖ always applies].
    #[arg(long, value_name = "TOL", allow_negative_numbers = true)]
    gtol: Option<f64>,
    /// Force limit: every control value stays in [−U, U] N [default: unbounded].
    #[arg(long, value_name = "U", allow_negative_numbers = true)]
    bound: Option<f64>,
}

impl SolverArgs {
    fn options(&self) -> Result<OptimOptions, CliError> {
        if let Some(g) = self.gtol {
            if !(g.is_finite() && g >= 0.0) {
                return Err(CliError::msg(format!(
                    "--gtol: must be finite and non-negative, got {g}"
                )));
            }
        }
        if let Some(b) = self.bound {
            if !(b.is_finite() && b > 0.0) {
                return Err(CliError::msg(format!(
                    "--bound: must be positive and finite, got {b}"
                )));
            }
        }
        if self.max_iters == Some(0) {
            return Err(CliError::msg("--max-iters: must be at least 1"));
        }
        let defaults = OptimOptions::default();
        Ok(OptimOptions {
            method: match self.method {
                MethodArg::Lbfgs => Method::Lbfgs,
                MethodArg::TrustRegion => Method::TrustRegion,
            },
            max_iters: self.max_iters.unwrap_or(defaults.max_iters),
            grad_tol: self.gtol.unwrap_or(defaults.grad_tol),
            bound: self.bound,
            progress: false,
            ..defaults
        })
    }
}

/// The start θ₀ must lie within `--bound`; the error names the key and the flag.
fn check_start_in_bound(
    path: &Path,
    sp: &SceneProblem,
    bound: Option<f64>,
) -> Result<(), CliError> {
    let Some(b) = bound else { return Ok(()) };
    match sp.theta0.iter().position(|t| t.abs() > b) {
        None => Ok(()),
        Some(i) => Err(CliError::msg(format!(
            "{}: key `control.values[{i}]`: the start value {} lies outside --bound {b}",
            path.display(),
            sp.theta0[i]
        ))),
    }
}

#[derive(Serialize)]
struct OptimizeReport {
    objective: f64,
    controls: Vec<f64>,
    gradient_norm: f64,
    iterations: usize,
    seconds: f64,
    converged: bool,
    termination: String,
    method: &'static str,
    starts: usize,
    #[serde(skip_serializing_if = "Option::is_none")]
    seed: Option<u64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    minima_found: Option<usize>,
    #[serde(skip_serializing_if = "Option::is_none")]
    failed_starts: Option<usize>,
    initial_objective: f64,
    initial_controls: Vec<f64>,
    projected_gradient_norm: f64,
    active_bounds: Vec<usize>,
    #[serde(skip_serializing_if = "Option::is_none")]
    bound: Option<f64>,
    gradient_evals: usize,
    hvp_evals: usize,
    objective_kind: &'static str,
    control_kind: &'static str,
    control_node: usize,
}

fn cmd_optimize(
    a: &OptimizeArgs,
    seed: u64,
    threads: usize,
    progress: Progress,
) -> Result<(), CliError> {
    let scene = load_scene(&a.scene)?;
    let sp = scene_problem(&a.scene, &scene)?;
    let opts = a.solver.options()?;
    let starts = a.starts as usize;
    let design = a.design.design(&sp.theta0)?;
    check_start_in_bound(&a.scene, &sp, opts.bound)?;
    let clock = Instant::now();
    let initial_objective = sp
        .problem
        .value(&sp.theta0)
        .map_err(|e| lib_error(&a.scene, e))?;
    let (best, minima_found, failed_starts) = if starts > 1 {
        let spinner = progress.spinner(format!(
            "{} starts of {} on {} parameter{}",
            starts,
            opts.method.name(),
            sp.theta0.len(),
            if sp.theta0.len() == 1 { "" } else { "s" }
        ));
        let run = || -> Result<(OptimResult, usize, usize), CliError> {
            // The scene's own start, then K − 1 design points.
            let own = minimize(&sp.problem, &sp.theta0, &opts);
            let report = multistart(&sp.problem, &design, starts - 1, seed, threads, &opts)
                .map_err(|e| lib_error(&a.scene, e))?;
            let mut failed = report.failures.len();
            let mut candidates: Vec<&OptimResult> = report.results.iter().collect();
            let own = match own {
                Ok(r) => Some(r),
                Err(e) => {
                    failed += 1;
                    if report.results.is_empty() {
                        return Err(lib_error(&a.scene, e));
                    }
                    None
                }
            };
            candidates.extend(own.as_ref());
            let best = candidates
                .into_iter()
                .filter(|r| r.objective.is_finite())
                .min_by(|x, y| x.objective.total_cmp(&y.objective))
                .cloned()
                .ok_or_else(|| all_failed(&a.scene, &report))?;
            Ok((best, report.minima.len(), failed))
        };
        let out = run();
        spinner.finish_and_clear();
        out?
    } else {
        let spinner = progress.spinner(format!(
            "{} on {} parameter{}",
            opts.method.name(),
            sp.theta0.len(),
            if sp.theta0.len() == 1 { "" } else { "s" }
        ));
        let r = minimize(&sp.problem, &sp.theta0, &opts);
        spinner.finish_and_clear();
        (r.map_err(|e| lib_error(&a.scene, e))?, 1, 0)
    };
    check_finite(&a.scene, "objective", &[best.objective])?;
    check_finite(&a.scene, "controls", &best.theta)?;
    check_finite(&a.scene, "gradient_norm", &[best.gradient_norm])?;
    check_finite(
        &a.scene,
        "projected_gradient_norm",
        &[best.projected_gradient_norm],
    )?;
    let report = OptimizeReport {
        objective: best.objective,
        controls: best.theta.clone(),
        gradient_norm: best.gradient_norm,
        iterations: best.iterations,
        seconds: clock.elapsed().as_secs_f64(),
        converged: best.converged,
        termination: best.termination.to_string(),
        method: best.method.name(),
        starts,
        seed: (starts > 1).then_some(seed),
        minima_found: (starts > 1).then_some(minima_found),
        failed_starts: (starts > 1).then_some(failed_starts),
        initial_objective,
        initial_controls: sp.theta0.clone(),
        projected_gradient_norm: best.projected_gradient_norm,
        active_bounds: best.active_bounds.clone(),
        bound: opts.bound,
        gradient_evals: best.gradient_evals,
        hvp_evals: best.hvp_evals,
        objective_kind: objective_name(sp.objective_kind),
        control_kind: kind_name(sp.control_kind),
        control_node: sp.control_node,
    };
    write_all(a.output.as_deref(), &to_json(&report)?)
}

/// The error when every start of a multistart failed: the first failure, with its start.
fn all_failed(path: &Path, report: &MultistartReport) -> CliError {
    match report.failures.first() {
        Some(f) => CliError::msg(format!(
            "{}: every start failed; start {}: {}",
            path.display(),
            f.start,
            f.error
        )),
        None => CliError::msg(format!("{}: no start gave a result", path.display())),
    }
}

#[derive(Serialize)]
struct StartReport {
    start: usize,
    start_point: Vec<f64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    objective: Option<f64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    controls: Option<Vec<f64>>,
    #[serde(skip_serializing_if = "Option::is_none")]
    gradient_norm: Option<f64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    iterations: Option<usize>,
    #[serde(skip_serializing_if = "Option::is_none")]
    converged: Option<bool>,
    #[serde(skip_serializing_if = "Option::is_none")]
    termination: Option<String>,
    #[serde(skip_serializing_if = "Option::is_none")]
    minimum: Option<usize>,
    #[serde(skip_serializing_if = "Option::is_none")]
    error: Option<String>,
}

#[derive(Serialize)]
struct MinimumReport {
    objective: f64,
    controls: Vec<f64>,
    count: usize,
    best_start: usize,
    starts: Vec<usize>,
}

#[derive(Serialize)]
struct CertificateReport {
    objective: f64,
    controls: Vec<f64>,
    eigenvalues: Vec<f64>,
    positive_definite: bool,
    free: Vec<usize>,
    asymmetry: f64,
}

#[derive(Serialize)]
struct ExploreReport {
    objective_kind: &'static str,
    control_kind: &'static str,
    control_node: usize,
    method: &'static str,
    #[serde(skip_serializing_if = "Option::is_none")]
    bound: Option<f64>,
    design: DesignReport,
    seed: u64,
    starts: usize,
    converged_starts: usize,
    failed_starts: usize,
    seconds: f64,
    /// Parameter indices that do not act on the objective (ignored when clustering).
    inert: Vec<usize>,
    minima: Vec<MinimumReport>,
    results: Vec<StartReport>,
    #[serde(skip_serializing_if = "Option::is_none")]
    certificate: Option<CertificateReport>,
}

fn cmd_explore(
    a: &ExploreArgs,
    seed: u64,
    threads: usize,
    progress: Progress,
) -> Result<(), CliError> {
    let scene = load_scene(&a.scene)?;
    let sp = scene_problem(&a.scene, &scene)?;
    let opts = a.solver.options()?;
    let design = a.design.design(&sp.theta0)?;
    let starts = a.starts as usize;
    let spinner = progress.spinner(format!(
        "exploring: {} starts of {} on {} parameter{}",
        starts,
        opts.method.name(),
        sp.theta0.len(),
        if sp.theta0.len() == 1 { "" } else { "s" }
    ));
    let report = multistart(&sp.problem, &design, starts, seed, threads, &opts);
    spinner.finish_and_clear();
    let report = report.map_err(|e| lib_error(&a.scene, e))?;
    if report.results.is_empty() {
        return Err(all_failed(&a.scene, &report));
    }

    // Which minimum each start reached.
    let mut minimum_of = vec![None; starts];
    for (m, min) in report.minima.iter().enumerate() {
        for &s in &min.starts {
            if let Some(slot) = minimum_of.get_mut(s) {
                *slot = Some(m);
            }
        }
    }
    let mut results: Vec<StartReport> = report
        .start_points
        .iter()
        .enumerate()
        .map(|(start, p)| StartReport {
            start,
            start_point: p.clone(),
            objective: None,
            controls: None,
            gradient_norm: None,
            iterations: None,
            converged: None,
            termination: None,
            minimum: minimum_of.get(start).copied().flatten(),
            error: None,
        })
        .collect();
    for (r, &start) in report.results.iter().zip(&report.result_starts) {
        if let Some(e) = results.get_mut(start) {
            e.objective = Some(r.objective);
            e.controls = Some(r.theta.clone());
            e.gradient_norm = Some(r.gradient_norm);
            e.iterations = Some(r.iterations);
            e.converged = Some(r.converged);
            e.termination = Some(r.termination.to_string());
        }
    }
    for f in &report.failures {
        if let Some(e) = results.get_mut(f.start) {
            e.error = Some(f.error.to_string());
        }
    }
    // Never write NaN: check every number.
    for r in &results {
        let key = format!("results[{}]", r.start);
        check_finite(&a.scene, &key, &r.start_point)?;
        check_finite(&a.scene, &key, r.controls.as_deref().unwrap_or(&[]))?;
        let scalars: Vec<f64> = [r.objective, r.gradient_norm]
            .into_iter()
            .flatten()
            .collect();
        check_finite(&a.scene, &key, &scalars)?;
    }
    let minima: Vec<MinimumReport> = report
        .minima
        .iter()
        .map(|m| MinimumReport {
            objective: m.objective,
            controls: m.theta.clone(),
            count: m.count,
            best_start: m.best_start,
            starts: m.starts.clone(),
        })
        .collect();
    for (i, m) in minima.iter().enumerate() {
        let key = format!("minima[{i}]");
        check_finite(&a.scene, &key, &[m.objective])?;
        check_finite(&a.scene, &key, &m.controls)?;
    }
    let certificate = match &report.certificate {
        Some(c) => {
            check_finite(&a.scene, "certificate.eigenvalues", &c.eigenvalues)?;
            check_finite(&a.scene, "certificate", &[c.objective, c.asymmetry])?;
            Some(CertificateReport {
                objective: c.objective,
                controls: c.theta.clone(),
                eigenvalues: c.eigenvalues.clone(),
                positive_definite: c.positive_definite,
                free: c.free.clone(),
                asymmetry: c.asymmetry,
            })
        }
        None => None,
    };
    let out = ExploreReport {
        objective_kind: objective_name(sp.objective_kind),
        control_kind: kind_name(sp.control_kind),
        control_node: sp.control_node,
        method: opts.method.name(),
        bound: opts.bound,
        design: a.design.describe(),
        seed,
        starts,
        converged_starts: report.results.iter().filter(|r| r.converged).count(),
        failed_starts: report.failures.len(),
        seconds: report.seconds,
        inert: report.inert.clone(),
        minima,
        results,
        certificate,
    };
    write_all(a.output.as_deref(), &to_json(&out)?)
}
