//! `chainbeam optimize` and `chainbeam explore` (JSON).

use std::path::{Path, PathBuf};
use std::time::Instant;

use clap::{Args, ValueEnum};
use serde::Serialize;

use chainbeam::multistart::{multistart, MultistartReport, StartDesign};
use chainbeam::ocp::Curvature;
use chainbeam::optimize::{
    minimize, Bounds, Method, Minimizer, ObserverMode, OptimOptions, OptimProblem, OptimResult,
};

use crate::output::{refuse_overwrite, Inputs, Output};
use crate::problem::{
    self, kind_report, objective_name, AnyProblem, KindReport, ProblemArgs, SceneProblem, Values,
};
use crate::progress::{IterationProgress, Progress};
use crate::{check_finite, check_force_flag, lib_error, load_scene, to_json, CliError};
use crate::{OUTPUT_HELP, SCENE_HELP};

/// `optimize --help`.
pub const OPTIMIZE_LONG_ABOUT: &str = "\
Minimise the scene's [objective] (default \"final\": c = M₀(t_N)², eq. 3.3.2; \"sum\": \
c_sum = Σ M₀(t_k)², eq. 3.3.4; plus ρ·h·Σ u_k² with --effort ρ) over the scene's [control] \
parameters θ (constant or per-step force [N] at control.node, default the tip; P pieces with \
--pieces P) by single shooting with exact adjoint gradients, starting from control.values. With \
--starts K > 1 it runs K starts (the scene's values and K − 1 others drawn with --seed) in \
parallel (--threads) and reports the best.

Spatial scenes (a load, the current or the control with an x component) are optimised in the \
spatial model, planar ones in the planar model (JSON key model); the objectives then use \
|M₀|² = M₀ₓ² + M₀². A 2-axis control (control.values as pairs [u_x, u_z]) has 2 parameters per \
value and its controls are reported as pairs [u_x, u_z]; --bound, --lower and --upper limit each \
component. --method riccati and condensed are planar only and refuse a spatial scene.

Output (JSON): objective [N²m²], controls (the optimal θ, laid out as control.values: numbers, \
or pairs [u_x, u_z] for a 2-axis control) [N], gradient_norm, iterations, seconds, converged, \
termination, model, and further details (docs/cli.md). The output is a valid --controls file \
for simulate and gradient.

Exit status 3 (not 0) when the optimiser stopped without meeting a convergence test (iteration \
limit, no progress): the JSON is written with \"converged\": false and one line on stderr says \
why (the termination, the iterations and the relative gradient ‖∇c‖/‖∇c(start)‖).

Sign convention: a load F > 0 enters H as +F·z and pushes toward −z; u = −F cancels a tip load F.";

/// `explore --help`.
pub const EXPLORE_LONG_ABOUT: &str = "\
Run a multistart exploration of the landscape of the scene's [objective] over its [control] \
parameters: K local minimisations from the points of a start design (--design latin|random|\
perturb, drawn with --seed; results do not depend on --threads), run in parallel, then cluster \
the converged results into distinct local minima. Spatial scenes run the spatial model (JSON key \
model); a 2-axis control's controls and start points are pairs [u_x, u_z], and the indices of \
inert, certificate.free and active bounds count θ = (θ_x; θ_z), the x components first.

Output (JSON):
  minima        the distinct minima, lowest objective first: objective [N²m²], controls [N] \
(laid out as control.values), count, best_start, starts
  results       one entry per start, in start order: start, start_point, objective, controls, \
gradient_norm, iterations, converged, termination, minimum (index into minima, for converged \
starts), or error (for a start whose simulation failed)
  certificate   when every converged start reached one minimum (and it has at most 200 \
parameters): the Hessian's eigenvalues there and whether it is positive definite
  and model, objective_kind, effort, control_kind, pieces, control_node, method, bound, design, \
seed, starts, converged_starts, failed_starts, inert, seconds.

Exit status 3 (not 0) when any start did not converge or failed: the map is then incomplete. The \
JSON is written all the same, and one line on stderr counts those starts and gives the first.

Sign convention: a load F > 0 enters H as +F·z and pushes toward −z; u = −F cancels a tip load F.";

/// The largest `--threads`: far above any core count a run benefits from, low enough that a
/// mistyped value fails at once instead of spawning threads for minutes.
pub const MAX_THREADS: u16 = 1024;

/// Options of the local solver (optimize, explore).
#[derive(Args)]
pub struct SolverArgs {
    /// Optimisation method.
    #[arg(long, value_enum, default_value_t = MethodArg::Lbfgs)]
    method: MethodArg,
    /// The model of --method riccati: auto (Gauss-Newton, then the exact Hessian of the
    /// objective from the first step Gauss-Newton predicts poorly), exact (the exact Hessian
    /// throughout), gauss-newton (throughout). Refused with the other methods [default: auto].
    #[arg(long, value_enum)]
    curvature: Option<CurvatureArg>,
    /// Largest number of iterations per start [default: 1000]. A run that reaches it has not
    /// converged (exit status 3).
    #[arg(long, value_name = "N")]
    max_iters: Option<usize>,
    /// Stop when the gradient norm ‖∇c‖ falls below this, in Nm² [default: off; the relative
    /// test ‖∇c‖ ≤ 1e-8·‖∇c(start)‖ always applies].
    #[arg(long, value_name = "TOL", allow_hyphen_values = true)]
    gtol: Option<f64>,
    /// Force limit: every control value stays in [−U, U] N [default: unbounded].
    #[arg(long, value_name = "U", allow_hyphen_values = true)]
    bound: Option<f64>,
    /// Lower force limit L [N], with --upper: every control value stays in [L, U] (L < U, both
    /// finite; asymmetric allowed). One-sided limits are refused: give a finite far side.
    #[arg(
        long,
        value_name = "L",
        allow_hyphen_values = true,
        conflicts_with = "bound"
    )]
    lower: Option<f64>,
    /// Upper force limit U [N], with --lower.
    #[arg(
        long,
        value_name = "U",
        allow_hyphen_values = true,
        conflicts_with = "bound"
    )]
    upper: Option<f64>,
}

#[derive(Clone, Copy, PartialEq, Eq, ValueEnum)]
enum CurvatureArg {
    /// Gauss-Newton, then the exact Hessian (default).
    Auto,
    /// The exact Hessian throughout (Newton).
    Exact,
    /// Gauss-Newton throughout.
    GaussNewton,
}

#[derive(Clone, Copy, PartialEq, Eq, ValueEnum)]
enum MethodArg {
    /// Limited-memory BFGS with a line search (gradients only).
    Lbfgs,
    /// Trust-region Newton-CG (Hessian-vector products by forward-over-adjoint).
    TrustRegion,
    /// Structured Gauss-Newton with Riccati passes (per-step, piecewise or constant controls;
    /// O(N) per iteration, bounds handled exactly; planar scenes only).
    Riccati,
    /// Condensed Gauss-Newton (the same problems as riccati; sensitivities to the controls and
    /// a dense QP: the faster for few controls, e.g. Table 3.4; planar scenes only).
    Condensed,
}

impl SolverArgs {
    /// The symmetric limit (--bound) or the box (--lower/--upper), checked.
    fn limits(&self) -> Result<(Option<f64>, Option<Bounds>), CliError> {
        for (flag, v) in [
            ("--bound", self.bound),
            ("--lower", self.lower),
            ("--upper", self.upper),
        ] {
            match v {
                Some(v) if v.is_finite() => check_force_flag(flag, v)?,
                _ => {}
            }
        }
        let one_sided = |given: String, missing: &str| {
            CliError::msg(format!(
                "{given} without {missing}: one-sided force limits are not supported (the bounded \
                 optimiser keeps every control in a finite box [L, U]); give {missing} too, e.g. \
                 far beyond the forces you expect (forces above π·m·l/h² are refused anyway)"
            ))
        };
        match (self.bound, self.lower, self.upper) {
            (Some(b), _, _) if b.is_finite() && b > 0.0 => Ok((Some(b), None)),
            (Some(b), _, _) => Err(CliError::msg(format!(
                "--bound: must be positive and finite, got {b}"
            ))),
            (None, None, None) => Ok((None, None)),
            (None, Some(l), Some(u)) => match Bounds::new(l, u) {
                Ok(b) => Ok((None, Some(b))),
                Err(_) => Err(CliError::msg(format!(
                    "--lower/--upper: need finite L < U, got L = {l}, U = {u}"
                ))),
            },
            (None, Some(l), None) => Err(one_sided(format!("--lower {l}"), "--upper")),
            (None, None, Some(u)) => Err(one_sided(format!("--upper {u}"), "--lower")),
        }
    }

    fn options(&self) -> Result<OptimOptions, CliError> {
        if let Some(g) = self.gtol {
            if !(g.is_finite() && g >= 0.0) {
                return Err(CliError::msg(format!(
                    "--gtol: must be finite and non-negative, got {g}"
                )));
            }
        }
        let (bound, bounds) = self.limits()?;
        if self.max_iters == Some(0) {
            return Err(CliError::msg("--max-iters: must be at least 1"));
        }
        let defaults = OptimOptions::default();
        let curvature = match (self.curvature, self.method) {
            (None, _) => defaults.curvature,
            (Some(c), MethodArg::Riccati) => match c {
                CurvatureArg::Auto => Curvature::Auto,
                CurvatureArg::Exact => Curvature::Exact,
                CurvatureArg::GaussNewton => Curvature::GaussNewton,
            },
            (Some(_), _) => {
                return Err(CliError::msg(
                    "--curvature: only --method riccati has a choice of model",
                ))
            }
        };
        Ok(OptimOptions {
            method: match self.method {
                MethodArg::Lbfgs => Method::Lbfgs,
                MethodArg::TrustRegion => Method::TrustRegion,
                MethodArg::Riccati => Method::Riccati,
                MethodArg::Condensed => Method::Condensed,
            },
            curvature,
            max_iters: self.max_iters.unwrap_or(defaults.max_iters),
            grad_tol: self.gtol.unwrap_or(defaults.grad_tol),
            bound,
            bounds,
            progress: false,
            ..defaults
        })
    }
}

/// Threads and seed of a multistart.
#[derive(Args)]
pub struct ParallelArgs {
    /// Worker threads for the starts, 1 to 1024; 0 means one per CPU core. Results do not depend
    /// on it.
    #[arg(long, value_name = "N", default_value_t = 0, allow_hyphen_values = true,
          value_parser = clap::value_parser!(u16).range(0..=MAX_THREADS as i64))]
    threads: u16,
    /// Seed for the random start designs; the same seed gives the same starts and results.
    #[arg(long, value_name = "S", default_value_t = 0)]
    seed: u64,
}

/// How the start points of a multistart are drawn.
#[derive(Args)]
pub struct DesignArgs {
    /// Start design: `latin` (a Latin hypercube in [LO, HI]ⁿ), `random` (uniform in [LO, HI]ⁿ) or
    /// `perturb` (the scene's control values + uniform noise in [−R, R]ⁿ). Points outside
    /// the force limit are clamped into it.
    #[arg(long, value_enum, default_value_t = DesignArg::Latin)]
    design: DesignArg,
    /// Lower end of the start box, in N (latin, random). The default [−600, 600] holds every
    /// constant optimum of the thesis's riser.
    #[arg(long, value_name = "LO", default_value_t = -600.0, allow_hyphen_values = true)]
    lo: f64,
    /// Upper end of the start box, in N (latin, random).
    #[arg(
        long,
        value_name = "HI",
        default_value_t = 600.0,
        allow_hyphen_values = true
    )]
    hi: f64,
    /// Half-width of the perturbation, in N (perturb).
    #[arg(
        long,
        value_name = "R",
        default_value_t = 1.0,
        allow_hyphen_values = true
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
                check_force_flag("--lo", self.lo)?;
                check_force_flag("--hi", self.hi)?;
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
                check_force_flag("--radius", self.radius)?;
                Ok(StartDesign::Perturb {
                    center: theta0.to_vec(),
                    radius: self.radius,
                })
            }
        }
    }

    fn describe(&self) -> DesignReport {
        let (kind, box_) = match self.design {
            DesignArg::Latin => ("latin", true),
            DesignArg::Random => ("random", true),
            DesignArg::Perturb => ("perturb", false),
        };
        DesignReport {
            kind,
            lo: box_.then_some(self.lo),
            hi: box_.then_some(self.hi),
            radius: (!box_).then_some(self.radius),
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

/// `optimize`'s flags.
#[derive(Args)]
pub struct OptimizeArgs {
    #[arg(value_name = "SCENE.toml", help = SCENE_HELP)]
    scene: PathBuf,
    /// Number of starts. K > 1 runs a multistart: the scene's control values and K − 1 points of
    /// the start design (--design, drawn with --seed), in parallel on --threads; the result with
    /// the lowest objective is reported (never worse than K = 1).
    #[arg(long, value_name = "K", default_value_t = 1, value_parser = clap::value_parser!(u32).range(1..=100_000))]
    starts: u32,
    #[command(flatten)]
    problem: ProblemArgs,
    #[command(flatten)]
    solver: SolverArgs,
    /// Show the iteration, the objective and ‖∇c‖ of every iteration on stderr (a single
    /// optimisation, --starts 1, only): a progress bar on a terminal, else one line per
    /// iteration (`iter K  cost C  |g| G`). Shown also with --quiet.
    #[arg(long)]
    progress: bool,
    #[command(flatten)]
    parallel: ParallelArgs,
    #[command(flatten)]
    design: DesignArgs,
    #[arg(long, short, value_name = "FILE", help = OUTPUT_HELP)]
    output: Option<PathBuf>,
}

/// `explore`'s flags.
#[derive(Args)]
pub struct ExploreArgs {
    #[arg(value_name = "SCENE.toml", help = SCENE_HELP)]
    scene: PathBuf,
    /// Number of starts.
    #[arg(long, value_name = "K", default_value_t = 16, value_parser = clap::value_parser!(u32).range(1..=100_000))]
    starts: u32,
    #[command(flatten)]
    problem: ProblemArgs,
    #[command(flatten)]
    solver: SolverArgs,
    #[command(flatten)]
    parallel: ParallelArgs,
    #[command(flatten)]
    design: DesignArgs,
    #[arg(long, short, value_name = "FILE", help = OUTPUT_HELP)]
    output: Option<PathBuf>,
}

/// `--method riccati` on a problem in the spatial model: refused before any work, naming the
/// flag and why the scene is spatial.
fn refuse_riccati_on_spatial(
    path: &Path,
    sp: &SceneProblem,
    opts: &OptimOptions,
) -> Result<(), CliError> {
    match (&sp.spatial_reason, opts.method) {
        (Some(why), m @ (Method::Riccati | Method::Condensed)) => Err(CliError::msg(format!(
            "{}: --method {m}: this scene needs the spatial model ({why}), and {}",
            path.display(),
            problem::RICCATI_PLANAR
        ))),
        _ => Ok(()),
    }
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

/// The force limits of a run as reported in the JSON: `bound` for --bound, `lower` and `upper`
/// for any limit.
#[derive(Serialize)]
struct LimitsReport {
    #[serde(skip_serializing_if = "Option::is_none")]
    bound: Option<f64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    lower: Option<f64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    upper: Option<f64>,
}

impl LimitsReport {
    fn of(opts: &OptimOptions) -> Self {
        let b = opts.force_bounds().ok().flatten();
        LimitsReport {
            bound: opts.bound,
            lower: b.map(|b| b.lower()),
            upper: b.map(|b| b.upper()),
        }
    }
}

/// ‖∇c‖/‖∇c(start)‖ of a result (projected on active bounds), or `None` at a zero start gradient.
fn relative_gradient(r: &OptimResult) -> Option<f64> {
    (r.initial_gradient_norm > 0.0).then(|| r.projected_gradient_norm / r.initial_gradient_norm)
}

/// "…, N iterations, relative gradient …" for a stderr line.
fn why(r: &OptimResult) -> String {
    let rel = match relative_gradient(r) {
        Some(g) => format!("relative gradient ‖∇c‖/‖∇c(start)‖ = {g:.3e}"),
        None => "the gradient was zero at the start".into(),
    };
    let its = r.iterations;
    format!(
        "{}; after {its} iteration{}, {rel}",
        r.termination,
        if its == 1 { "" } else { "s" }
    )
}

#[derive(Serialize)]
struct OptimizeReport {
    objective: f64,
    controls: Values,
    gradient_norm: f64,
    iterations: usize,
    seconds: f64,
    converged: bool,
    termination: String,
    #[serde(skip_serializing_if = "Option::is_none")]
    relative_gradient_norm: Option<f64>,
    method: &'static str,
    starts: usize,
    #[serde(skip_serializing_if = "Option::is_none")]
    seed: Option<u64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    minima_found: Option<usize>,
    #[serde(skip_serializing_if = "Option::is_none")]
    failed_starts: Option<usize>,
    initial_objective: f64,
    initial_controls: Values,
    projected_gradient_norm: f64,
    active_bounds: Vec<usize>,
    #[serde(flatten)]
    limits: LimitsReport,
    gradient_evals: usize,
    hvp_evals: usize,
    model: &'static str,
    objective_kind: &'static str,
    effort: f64,
    #[serde(flatten)]
    kind: KindReport,
    control_node: usize,
}

/// Runs `optimize`.
pub fn run_optimize(a: &OptimizeArgs, progress: Progress) -> Result<(), CliError> {
    let out = Output::prepare(a.output.as_deref())?;
    let opts = a.solver.options()?;
    problem::check_effort(a.problem.effort)?;
    let starts = a.starts as usize;
    if a.progress && starts > 1 {
        return Err(CliError::msg(
            "--progress: prints the iterations of a single optimisation; it cannot be combined \
             with --starts > 1",
        ));
    }
    let scene = load_scene(&a.scene)?;
    refuse_overwrite(&[("--output", &out)], Inputs::new().scene(&a.scene, &scene))?;
    let sp = problem::build(&a.scene, &scene, Some(&a.problem), None)?;
    refuse_riccati_on_spatial(&a.scene, &sp, &opts)?;
    let design = a.design.design(&sp.theta0)?;
    check_start_in_bound(&a.scene, &sp, a.problem.pieces.is_some(), &opts)?;
    // Before the start's objective is evaluated: a start beyond the resolved force range would
    // otherwise fail as a Newton failure that does not name the control.
    sp.problem
        .check_range(&sp.theta0)
        .map_err(|e| lib_error(&a.scene, e))?;
    let clock = Instant::now();
    let initial_objective = sp
        .problem
        .value(&sp.theta0)
        .map_err(|e| lib_error(&a.scene, e))?;
    let n = sp.theta0.len();
    let params = format!("{n} parameter{}", if n == 1 { "" } else { "s" });
    let seed = a.parallel.seed;
    let (best, minima_found, failed_starts) = if starts > 1 {
        let spinner = progress.spinner(format!(
            "{starts} starts of {} on {params}",
            opts.method.name()
        ));
        let run = || -> Result<(OptimResult, usize, usize), CliError> {
            // The scene's own start, then K − 1 design points.
            let own = minimize(&sp.problem, &sp.theta0, &opts);
            let threads = usize::from(a.parallel.threads).min(starts - 1);
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
        // The per-iteration lines of --progress replace the spinner.
        let spinner =
            (!a.progress).then(|| progress.spinner(format!("{} on {params}", opts.method.name())));
        let r = if a.progress {
            Minimizer::new(&sp.problem, opts.clone())
                .add_observer(
                    IterationProgress::on_stderr(opts.max_iters),
                    ObserverMode::Always,
                )
                .run(&sp.theta0)
        } else {
            minimize(&sp.problem, &sp.theta0, &opts)
        };
        if let Some(s) = spinner {
            s.finish_and_clear();
        }
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
        controls: sp.problem.layout(&best.theta),
        gradient_norm: best.gradient_norm,
        iterations: best.iterations,
        seconds: clock.elapsed().as_secs_f64(),
        converged: best.converged,
        termination: best.termination.to_string(),
        relative_gradient_norm: relative_gradient(&best),
        method: best.method.name(),
        starts,
        seed: (starts > 1).then_some(seed),
        minima_found: (starts > 1).then_some(minima_found),
        failed_starts: (starts > 1).then_some(failed_starts),
        initial_objective,
        initial_controls: sp.problem.layout(&sp.theta0),
        projected_gradient_norm: best.projected_gradient_norm,
        active_bounds: best.active_bounds.clone(),
        limits: LimitsReport::of(&opts),
        gradient_evals: best.gradient_evals,
        hvp_evals: best.hvp_evals,
        model: sp.problem.model_name(),
        objective_kind: objective_name(sp.objective.kind),
        effort: sp.objective.effort,
        kind: kind_report(sp.problem.map()),
        control_node: sp.control_node,
    };
    out.write_all(&to_json(&report)?)?;
    if best.converged {
        Ok(())
    } else {
        Err(CliError::NotConverged(format!(
            "{}: the optimiser did not converge: {}; the result was written with \"converged\": \
             false",
            a.scene.display(),
            why(&best)
        )))
    }
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
    start_point: Values,
    #[serde(skip_serializing_if = "Option::is_none")]
    objective: Option<f64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    controls: Option<Values>,
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
    controls: Values,
    count: usize,
    best_start: usize,
    starts: Vec<usize>,
}

#[derive(Serialize)]
struct CertificateReport {
    objective: f64,
    controls: Values,
    eigenvalues: Vec<f64>,
    positive_definite: bool,
    free: Vec<usize>,
    asymmetry: f64,
}

#[derive(Serialize)]
struct ExploreReport {
    model: &'static str,
    objective_kind: &'static str,
    effort: f64,
    #[serde(flatten)]
    kind: KindReport,
    control_node: usize,
    method: &'static str,
    #[serde(flatten)]
    limits: LimitsReport,
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

/// One entry per start, in start order: its start point, its result (or its error) and the
/// minimum it reached; every number checked finite (the error names `results[i]`).
fn start_reports(
    path: &Path,
    report: &MultistartReport,
    problem: &AnyProblem,
) -> Result<Vec<StartReport>, CliError> {
    // Which minimum each start reached.
    let mut minimum_of = vec![None; report.start_points.len()];
    for (m, min) in report.minima.iter().enumerate() {
        for &s in &min.starts {
            if let Some(slot) = minimum_of.get_mut(s) {
                *slot = Some(m);
            }
        }
    }
    let mut results = Vec::with_capacity(report.start_points.len());
    for (start, p) in report.start_points.iter().enumerate() {
        check_finite(path, &format!("results[{start}]"), p)?;
        results.push(StartReport {
            start,
            start_point: problem.layout(p),
            objective: None,
            controls: None,
            gradient_norm: None,
            iterations: None,
            converged: None,
            termination: None,
            minimum: minimum_of[start],
            error: None,
        });
    }
    for (r, &start) in report.results.iter().zip(&report.result_starts) {
        // Never write NaN: check every number.
        let key = format!("results[{start}]");
        check_finite(path, &key, &r.theta)?;
        check_finite(path, &key, &[r.objective, r.gradient_norm])?;
        if let Some(e) = results.get_mut(start) {
            e.objective = Some(r.objective);
            e.controls = Some(problem.layout(&r.theta));
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
    Ok(results)
}

/// The distinct minima, every number checked finite (the error names `minima[i]`).
fn minimum_reports(
    path: &Path,
    report: &MultistartReport,
    problem: &AnyProblem,
) -> Result<Vec<MinimumReport>, CliError> {
    let mut minima = Vec::with_capacity(report.minima.len());
    for (i, m) in report.minima.iter().enumerate() {
        let key = format!("minima[{i}]");
        check_finite(path, &key, &[m.objective])?;
        check_finite(path, &key, &m.theta)?;
        minima.push(MinimumReport {
            objective: m.objective,
            controls: problem.layout(&m.theta),
            count: m.count,
            best_start: m.best_start,
            starts: m.starts.clone(),
        });
    }
    Ok(minima)
}

/// The second-order certificate, if the multistart gave one, checked finite.
fn certificate_report(
    path: &Path,
    report: &MultistartReport,
    problem: &AnyProblem,
) -> Result<Option<CertificateReport>, CliError> {
    let Some(c) = &report.certificate else {
        return Ok(None);
    };
    check_finite(path, "certificate.eigenvalues", &c.eigenvalues)?;
    check_finite(path, "certificate", &[c.objective, c.asymmetry])?;
    check_finite(path, "certificate.controls", &c.theta)?;
    Ok(Some(CertificateReport {
        objective: c.objective,
        controls: problem.layout(&c.theta),
        eigenvalues: c.eigenvalues.clone(),
        positive_definite: c.positive_definite,
        free: c.free.clone(),
        asymmetry: c.asymmetry,
    }))
}

/// Runs `explore`.
pub fn run_explore(a: &ExploreArgs, progress: Progress) -> Result<(), CliError> {
    let out = Output::prepare(a.output.as_deref())?;
    let opts = a.solver.options()?;
    problem::check_effort(a.problem.effort)?;
    let scene = load_scene(&a.scene)?;
    refuse_overwrite(&[("--output", &out)], Inputs::new().scene(&a.scene, &scene))?;
    let sp = problem::build(&a.scene, &scene, Some(&a.problem), None)?;
    refuse_riccati_on_spatial(&a.scene, &sp, &opts)?;
    let design = a.design.design(&sp.theta0)?;
    let starts = a.starts as usize;
    let seed = a.parallel.seed;
    let n = sp.theta0.len();
    let spinner = progress.spinner(format!(
        "exploring: {starts} starts of {} on {n} parameter{}",
        opts.method.name(),
        if n == 1 { "" } else { "s" }
    ));
    let threads = usize::from(a.parallel.threads).min(starts);
    let report = multistart(&sp.problem, &design, starts, seed, threads, &opts);
    spinner.finish_and_clear();
    let report = report.map_err(|e| lib_error(&a.scene, e))?;
    if report.results.is_empty() {
        return Err(all_failed(&a.scene, &report));
    }

    let results = start_reports(&a.scene, &report, &sp.problem)?;
    let minima = minimum_reports(&a.scene, &report, &sp.problem)?;
    let certificate = certificate_report(&a.scene, &report, &sp.problem)?;
    let converged_starts = report.results.iter().filter(|r| r.converged).count();
    let json = ExploreReport {
        model: sp.problem.model_name(),
        objective_kind: objective_name(sp.objective.kind),
        effort: sp.objective.effort,
        kind: kind_report(sp.problem.map()),
        control_node: sp.control_node,
        method: opts.method.name(),
        limits: LimitsReport::of(&opts),
        design: a.design.describe(),
        seed,
        starts,
        converged_starts,
        failed_starts: report.failures.len(),
        seconds: report.seconds,
        inert: report.inert.clone(),
        minima,
        results,
        certificate,
    };
    out.write_all(&to_json(&json)?)?;
    if converged_starts == starts {
        return Ok(());
    }
    let first_unconverged = report
        .results
        .iter()
        .zip(&report.result_starts)
        .find(|(r, _)| !r.converged)
        .map(|(r, s)| format!("start {s}: {}", why(r)));
    let first_failed = report
        .failures
        .first()
        .map(|f| format!("start {} failed: {}", f.start, f.error));
    let first = [first_unconverged, first_failed]
        .into_iter()
        .flatten()
        .collect::<Vec<_>>()
        .join("; ");
    Err(CliError::NotConverged(format!(
        "{}: {} of {starts} starts did not converge ({first}); the map was written, its minima \
         come from the {converged_starts} converged starts",
        a.scene.display(),
        starts - converged_starts,
    )))
}
