//! `chainbeam`: the command line of the chain-of-pendulums beam simulator.
//!
//! ```text
//! chainbeam simulate SCENE.toml [--controls FILE] [--format csv|npy] [--output FILE]
//! chainbeam gradient SCENE.toml [--controls FILE | --pieces P] [--effort RHO] [--output FILE]
//! chainbeam optimize SCENE.toml [--starts K] [--method lbfgs|trust-region|riccati] [--bound U]
//!                               [--pieces P] [--effort RHO] [--progress] [--output FILE]
//! chainbeam explore  SCENE.toml [--starts K] [--design latin|random|perturb] [--output FILE]
//! chainbeam mpc      SCENE.toml [--horizon S] [--interval S] [--iterations K] [--bound U]
//!                               [--model MODEL.toml] [--baselines] [--summary FILE] [--output FILE]
//! chainbeam fatigue  SCENE.toml [--series FILE | --scatter FILE] [--controller LIST] [--output FILE]
//! ```
//!
//! The full contract (every flag, the CSV columns, the `.npy` layout, the JSON keys and the exit
//! statuses) is `docs/cli.md` in the repository; the `--help` texts below say the same in short.
//!
//! Exit status ([`ExitStatus`]): 0 success; 1 an error (invalid scene, invalid controls file,
//! failed computation, unwritable output), one line on stderr naming the file, key or flag and the
//! reason; 2 a command-line usage error (clap); 3 the optimiser did not converge (`optimize`:
//! the reported result; `explore`: any start), one line on stderr saying why, the JSON written
//! all the same. A signal (SIGINT, SIGTERM, SIGHUP) removes the temporary output file and ends
//! the process by that signal.
//!
//! Module map: [`cmd_simulate`], [`cmd_gradient`], [`cmd_optimize`] (optimize and explore),
//! [`cmd_mpc`], [`cmd_fatigue`] run the subcommands; [`problem`] builds the control problem from the scene and the flags;
//! [`controls_io`] reads `--controls` files; [`output`] writes results safely; [`npy`] is the
//! NumPy writer; [`progress`] draws spinners.

mod cmd_design;
mod cmd_fatigue;
mod cmd_gradient;
mod cmd_mpc;
mod cmd_optimize;
mod cmd_simulate;
mod controls_io;
mod npy;
mod output;
mod problem;
mod progress;

use std::fmt;
use std::path::{Path, PathBuf};
use std::process::ExitCode;

use clap::{Parser, Subcommand};

use chainbeam::{Scene, ValidScene};
use progress::Progress;

/// The process's exit statuses (documented in `--help` and `docs/cli.md`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ExitStatus {
    /// The command did what it was asked.
    Success = 0,
    /// An error: invalid input, a failed computation, an unwritable output.
    Error = 1,
    /// A command-line usage error (unknown flag, missing argument, value out of range); clap
    /// exits with it.
    Usage = 2,
    /// The optimiser stopped without meeting a convergence test; the result was written.
    NotConverged = 3,
}

const LONG_ABOUT: &str = "\
Simulate, differentiate and optimise a slender beam modelled as a chain of rigid pendulums joined \
by torsional springs (Nøst 2023), integrated with RATTLE, with exact gradients from a discrete \
adjoint.

A scene is a TOML file: [beam], [loads], [time], and optionally [control] and [objective]. The \
format is described in docs/scene-format.md; examples/scenes/ holds the thesis's scenes. The \
command line is described in full in docs/cli.md.

Units (SI): lengths and positions in m, masses in kg, spring constants in Nm/rad, forces and \
controls in N, drag D in kg/m, current speeds in m/s, gravity in m/s², time and step h in s, \
energy in J, base bending moment M₀ in Nm, objectives in N²m².

Geometry and sign convention (the thesis's): the undeformed beam lies along +y from node 0 at the \
origin; loads act along z. A load F enters the Hamiltonian as +F·z, so F > 0 pushes the beam toward \
−z, and a control u = −F at the tip cancels a tip load F. A load, current or control with an x \
component makes the scene spatial: simulate, gradient, optimize and explore run it in the spatial \
model (a planar scene keeps the planar one), and a 2-axis control is written as pairs [u_x, u_z] \
in the scene and in the JSON.

Exit status: 0 success; 1 error (invalid scene or controls file, failed computation, unwritable \
output: one line on stderr naming the file, the key or flag and the reason); 2 command-line usage \
error; 3 the optimiser did not converge (optimize, explore: one line on stderr saying why; the \
JSON is written all the same). Output never contains NaN or infinity: non-finite results are an \
error and nothing is written.";

const AFTER_HELP: &str = "\
Examples:
  chainbeam simulate examples/scenes/thesis_cantilever.toml --output tip.csv
  chainbeam simulate examples/scenes/thesis_cantilever.toml --output tip.npy
  chainbeam gradient examples/scenes/riser_5.toml
  chainbeam optimize examples/scenes/riser_5.toml --output u.json
  chainbeam simulate examples/scenes/riser_5.toml --controls u.json
  chainbeam explore examples/scenes/riser_5.toml --starts 16 --seed 1";

/// The scene argument's help (shared by every subcommand).
pub const SCENE_HELP: &str = "\
The scene file (TOML; format and size limits in docs/scene-format.md, examples in \
examples/scenes/)";

/// The `--output` help (shared by every subcommand).
pub const OUTPUT_HELP: &str = "\
Write the result to FILE instead of standard output. A regular file is replaced atomically (a \
temporary file in its directory, renamed over it at the end) and keeps its permissions; a file \
with several hard links, a FIFO or a device is written in place; a symbolic link is followed. \
FILE must not be any input of the run (the scene, its series files, --controls, --model and its \
series), under any name: a link or another path to an input is refused. An interrupted or \
failed run leaves FILE as it was and no temporary file behind";

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
    /// Do not draw progress spinners (they are drawn on stderr only when it is a terminal).
    #[arg(long, short, global = true)]
    quiet: bool,
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Simulate a scene and write its trajectory (CSV or NumPy .npy).
    #[command(long_about = cmd_simulate::LONG_ABOUT)]
    Simulate(cmd_simulate::SimulateArgs),
    /// Objective and exact gradient with respect to the controls (JSON).
    #[command(long_about = cmd_gradient::LONG_ABOUT)]
    Gradient(cmd_gradient::GradientArgs),
    /// Minimise the scene's objective over its controls (JSON).
    #[command(long_about = cmd_optimize::OPTIMIZE_LONG_ABOUT)]
    Optimize(cmd_optimize::OptimizeArgs),
    /// Map the local minima of the scene's objective from many starts (JSON).
    #[command(long_about = cmd_optimize::EXPLORE_LONG_ABOUT)]
    Explore(cmd_optimize::ExploreArgs),
    /// Receding-horizon (MPC) control in closed loop, with baselines (CSV and JSON).
    #[command(long_about = cmd_mpc::LONG_ABOUT)]
    Mpc(cmd_mpc::MpcArgs),
    /// Fatigue damage and life of the wellhead (rainflow, DNV-RP-C203 S-N curves; JSON).
    #[command(long_about = cmd_fatigue::LONG_ABOUT)]
    Fatigue(cmd_fatigue::FatigueArgs),
    /// The design (top tension, flex-joint stiffness) that maximises the wellhead's fatigue
    /// life over a scatter diagram, with exact adjoint gradients.
    #[command(long_about = cmd_design::LONG_ABOUT)]
    Design(cmd_design::DesignArgs),
}

/// A failure reported to the user: one line on stderr and a non-zero exit status.
#[derive(Debug)]
pub enum CliError {
    /// An error (exit status 1); the message already names the file, key or flag and the reason.
    Msg(String),
    /// The optimiser did not converge (exit status 3); the result has been written.
    NotConverged(String),
    /// Standard output was closed by the reader (`| head`): stop quietly (exit status 0).
    BrokenPipe,
}

impl CliError {
    /// An error with a message.
    pub fn msg(m: impl Into<String>) -> Self {
        CliError::Msg(m.into())
    }

    fn status(&self) -> ExitStatus {
        match self {
            CliError::Msg(_) => ExitStatus::Error,
            CliError::NotConverged(_) => ExitStatus::NotConverged,
            CliError::BrokenPipe => ExitStatus::Success,
        }
    }
}

impl fmt::Display for CliError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            CliError::Msg(m) | CliError::NotConverged(m) => f.write_str(m),
            CliError::BrokenPipe => f.write_str("broken pipe"),
        }
    }
}

/// A library error while working on `scene_file`, as one message naming the file.
pub fn lib_error(scene_file: &Path, e: chainbeam::Error) -> CliError {
    match e {
        chainbeam::Error::Scene(se) if se.file.is_some() => CliError::msg(se.to_string()),
        chainbeam::Error::Scene(se) => CliError::msg(se.with_file(scene_file).to_string()),
        other => CliError::msg(format!("{}: {other}", scene_file.display())),
    }
}

/// Reads and validates a scene file, once: the runs built from the [`ValidScene`] do not
/// validate it again (a command that edits it validates the edit). The error names the file,
/// the key and the reason.
pub fn load_scene(path: &Path) -> Result<ValidScene, CliError> {
    ValidScene::from_file(path).map_err(|e| CliError::msg(e.to_string()))
}

/// The time-series files a scene read from `path` loads (inputs the output must not overwrite).
pub fn series_files(path: &Path, scene: &Scene) -> Vec<PathBuf> {
    let dir = path.parent().unwrap_or(Path::new(""));
    scene
        .loads
        .points
        .iter()
        .filter_map(|p| p.series.as_ref())
        .map(|s| dir.join(&s.file))
        .collect()
}

/// Checks that every number about to be written is finite; the error names the output key.
pub fn check_finite(path: &Path, key: &str, values: &[f64]) -> Result<(), CliError> {
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

/// Refuses a force given by `flag` outside the forces a scene may have
/// ([`chainbeam::scene::FORCE_RANGE`]): beyond it every derived quantity (a bounded map, a start
/// box) would overflow, and the message would otherwise name an internal quantity.
pub fn check_force_flag(flag: &str, value: f64) -> Result<(), CliError> {
    let range = chainbeam::scene::FORCE_RANGE;
    if range.contains(value) {
        return Ok(());
    }
    Err(CliError::msg(format!(
        "{flag} {value:e}: outside the supported force range [{:e}, {:e}] N (docs/scene-format.md, \
         \"Valid ranges\")",
        range.min, range.max
    )))
}

/// Pretty JSON with a final newline.
pub fn to_json<T: serde::Serialize>(value: &T) -> Result<String, CliError> {
    serde_json::to_string_pretty(value)
        .map(|mut s| {
            s.push('\n');
            s
        })
        .map_err(|e| CliError::msg(format!("cannot format the JSON output: {e}")))
}

fn main() -> ExitCode {
    // A panic is a bug; report it as one line instead of a backtrace dump (exit status 101).
    std::panic::set_hook(Box::new(|info| {
        eprintln!("error: internal error in chainbeam (please report this bug): {info}");
    }));
    output::remove_temporary_files_on_signal();
    let cli = Cli::parse();
    match run(cli) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            if !matches!(e, CliError::BrokenPipe) {
                eprintln!("error: {e}");
            }
            ExitCode::from(e.status() as u8)
        }
    }
}

fn run(cli: Cli) -> Result<(), CliError> {
    let progress = Progress::new(cli.quiet);
    match cli.command {
        Command::Simulate(a) => cmd_simulate::run(&a, progress),
        Command::Gradient(a) => cmd_gradient::run(&a, progress),
        Command::Optimize(a) => cmd_optimize::run_optimize(&a, progress),
        Command::Explore(a) => cmd_optimize::run_explore(&a, progress),
        Command::Mpc(a) => cmd_mpc::run(&a, progress),
        Command::Fatigue(a) => cmd_fatigue::run(&a, progress),
        Command::Design(a) => cmd_design::run(&a, progress, cli.quiet),
    }
}
