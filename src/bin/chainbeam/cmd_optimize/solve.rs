//! `chainbeam optimize`, solve: the inputs checked (flags, scene, start, range) and the
//! minimisation run, from one start or many.

use std::path::Path;
use std::time::Instant;

use chainbeam::multistart::{multistart, MultistartReport, StartDesign};
use chainbeam::optimize::{
    choose_method, minimize, Method, Minimizer, ObserverMode, OptimOptions, OptimProblem,
    OptimResult,
};

use super::OptimizeArgs;
use crate::output::{refuse_overwrite, Inputs, Output};
use crate::problem::{self, SceneProblem};
use crate::progress::{IterationProgress, Progress};
use crate::{lib_error, CliError};

/// A run's checked inputs: the problem, the options, the start design and the start's
/// objective.
pub struct Setup {
    /// The scene's control problem and θ₀.
    pub sp: SceneProblem,
    /// The solver's options from the flags.
    pub opts: OptimOptions,
    /// The start design of a multistart.
    pub design: StartDesign,
    /// J(θ₀).
    pub initial_objective: f64,
    /// Started before J(θ₀) was evaluated: the run's `seconds`.
    pub clock: Instant,
}

impl Setup {
    /// Reads the scene and checks every input before any optimisation: the flags, that `out`
    /// is none of the inputs, the method against the model, the start against the force limit
    /// and the resolved force range; then evaluates J(θ₀).
    pub fn load(a: &OptimizeArgs, out: &Output) -> Result<Self, CliError> {
        let opts = a.solver.options()?;
        problem::check_effort(a.problem.effort)?;
        if a.progress && a.starts > 1 {
            return Err(CliError::msg(
                "--progress: prints the iterations of a single optimisation; it cannot be \
                 combined with --starts > 1",
            ));
        }
        let mut inputs = Inputs::new();
        let scene = inputs.load_scene(&a.scene)?;
        refuse_overwrite(&[("--output", out)], &inputs)?;
        let sp = problem::build(&a.scene, &scene, Some(&a.problem), None)?;
        let design = a.design.design(&sp.theta0)?;
        check_start_in_bound(&a.scene, &sp, a.problem.pieces.is_some(), &opts)?;
        // Before the start's objective is evaluated: a start beyond the resolved force range
        // would otherwise fail as a Newton failure that does not name the control.
        sp.problem
            .check_range(&sp.theta0)
            .map_err(|e| lib_error(&a.scene, e))?;
        let clock = Instant::now();
        let initial_objective = sp
            .problem
            .value(&sp.theta0)
            .map_err(|e| lib_error(&a.scene, e))?;
        Ok(Setup {
            sp,
            opts,
            design,
            initial_objective,
            clock,
        })
    }
}

/// What the minimisation found: the best result, and for a multistart the distinct minima and
/// the starts that failed.
pub struct Solved {
    /// The lowest result over the starts.
    pub best: OptimResult,
    /// Distinct minima among the starts (1 for a single start).
    pub minima_found: usize,
    /// Starts whose minimisation failed (0 for a single start).
    pub failed_starts: usize,
}

/// Minimises from the scene's start, or with `--starts K > 1` from it and K − 1 design points.
pub fn solve(a: &OptimizeArgs, setup: &Setup, progress: &Progress) -> Result<Solved, CliError> {
    let n = setup.sp.theta0.len();
    let params = format!("{n} parameter{}", if n == 1 { "" } else { "s" });
    let method = choose_method(&setup.sp.problem, &setup.opts).method.name();
    if a.starts > 1 {
        let spinner = progress.spinner(format!("{} starts of {} on {params}", a.starts, method));
        let solved = solve_multistart(a, setup);
        spinner.finish_and_clear();
        solved
    } else {
        // The per-iteration lines of --progress replace the spinner.
        let spinner = (!a.progress).then(|| progress.spinner(format!("{method} on {params}")));
        let r = solve_single(a.progress, setup);
        if let Some(s) = spinner {
            s.finish_and_clear();
        }
        Ok(Solved {
            best: r.map_err(|e| lib_error(&a.scene, e))?,
            minima_found: 1,
            failed_starts: 0,
        })
    }
}

/// One minimisation from θ₀, with the iterations on stderr for `--progress`.
fn solve_single(show_progress: bool, setup: &Setup) -> chainbeam::Result<OptimResult> {
    let (sp, opts) = (&setup.sp, &setup.opts);
    if show_progress {
        // With --method auto: the choice first, and again with its fallback if there was one.
        if opts.method == Method::Auto {
            eprintln!("method auto: {}", choose_method(&sp.problem, opts));
        }
        Minimizer::new(&sp.problem, opts.clone())
            .add_observer(
                IterationProgress::on_stderr(opts.max_iters),
                ObserverMode::Always,
            )
            .run(&sp.theta0)
            .inspect(|r| {
                if let Some(c) = r.choice.as_ref().filter(|c| c.fallback.is_some()) {
                    eprintln!("method auto: {c}");
                }
            })
    } else {
        minimize(&sp.problem, &sp.theta0, opts)
    }
}

/// The scene's own start, then K − 1 design points; the lowest finite objective wins.
fn solve_multistart(a: &OptimizeArgs, setup: &Setup) -> Result<Solved, CliError> {
    let (sp, opts) = (&setup.sp, &setup.opts);
    let starts = a.starts as usize;
    let own = minimize(&sp.problem, &sp.theta0, opts);
    let threads = usize::from(a.parallel.threads).min(starts - 1);
    let report = multistart(
        &sp.problem,
        &setup.design,
        starts - 1,
        a.parallel.seed,
        threads,
        opts,
    )
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
    Ok(Solved {
        best,
        minima_found: report.minima.len(),
        failed_starts: failed,
    })
}

/// Where θᵢ sits in the scene's `control.values`: "key `control.values[j]`", with `[0]` (u_x) or
/// `[1]` (u_z) for a 2-axis control, or "piece j" (and its component) with `--pieces`.
fn theta_name(i: usize, n: usize, two_axis: bool, pieces: bool) -> String {
    let (j, component) = if two_axis {
        let m = n / 2;
        (i % m, Some(usize::from(i >= m)))
    } else {
        (i, None)
    };
    match (pieces, component) {
        (true, None) => format!("piece {j}"),
        (true, Some(c)) => format!("piece {j} ({})", ["u_x", "u_z"][c]),
        (false, None) => format!("key `control.values[{j}]`"),
        (false, Some(c)) => format!("key `control.values[{j}][{c}]` ({})", ["u_x", "u_z"][c]),
    }
}

/// The start θ₀ must lie within the force limit; the error names the key (or the piece) and the
/// limit.
fn check_start_in_bound(
    path: &Path,
    sp: &SceneProblem,
    pieces: bool,
    opts: &OptimOptions,
) -> Result<(), CliError> {
    let Some(b) = opts.force_bounds().map_err(|e| lib_error(path, e))? else {
        return Ok(());
    };
    let limit = match opts.bound {
        Some(u) => format!("(--bound) ±{u}"),
        None => format!("(--lower/--upper) [{}, {}]", b.lower(), b.upper()),
    };
    let (n, two_axis) = (sp.theta0.len(), sp.problem.is_two_axis());
    match sp.theta0.iter().position(|&t| !b.contains(t)) {
        None => Ok(()),
        Some(i) if pieces => Err(CliError::msg(format!(
            "{}: the start value {} of {} (the mean of control.values over it) lies outside the \
             force limit {limit}",
            path.display(),
            sp.theta0[i],
            theta_name(i, n, two_axis, true)
        ))),
        Some(i) => Err(CliError::msg(format!(
            "{}: {}: the start value {} lies outside the force limit {limit}",
            path.display(),
            theta_name(i, n, two_axis, false),
            sp.theta0[i]
        ))),
    }
}

/// The error when every start of a multistart failed: the first failure, with its start.
pub(super) fn all_failed(path: &Path, report: &MultistartReport) -> CliError {
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
