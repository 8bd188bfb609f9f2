//! `chainbeam optimize` and `chainbeam explore` (JSON): the flags here; `optimize` runs
//! [`solve`] (inputs checked, the minimisation) then [`report`] (the JSON, the exit status);
//! `explore` is [`explore`].

mod explore;
mod report;
mod solve;

pub use explore::run_explore;

use std::path::PathBuf;

use clap::{Args, ValueEnum};
use serde::Serialize;

use chainbeam::multistart::StartDesign;
use chainbeam::ocp::Curvature;
use chainbeam::optimize::{Bounds, Method, OptimOptions};

use crate::output::Output;
use crate::problem::ProblemArgs;
use crate::progress::Progress;
use crate::{check_force_flag, CliError};
use crate::{OUTPUT_HELP, SCENE_HELP};

/// `optimize --help`.
pub const OPTIMIZE_LONG_ABOUT: &str = "\
Minimise the scene's [objective] (default \"final\": c = M₀(t_N)², eq. 3.3.2; \"sum\": \
c_sum = Σ M₀(t_k)², eq. 3.3.4; \"power\" with exponent p ≥ 2: Σ |M₀(t_k)|^p; \"fatigue\": the \
rainflow damage of the wellhead stress with the [fatigue] table, L-BFGS or trust-region only \
(auto chooses lbfgs; riccati and condensed refuse it); plus ρ·h·Σ u_k² \
with --effort ρ) over the scene's [control] \
parameters θ (constant or per-step force [N] at control.node, default the tip; P pieces with \
--pieces P) by single shooting with exact adjoint gradients, starting from control.values. With \
--starts K > 1 it runs K starts (the scene's values and K − 1 others drawn with --seed) in \
parallel (--threads) and reports the best.

Spatial scenes (a load, the current or the control with an x component) are optimised in the \
spatial model, planar ones in the planar model (JSON key model); the objectives then use \
|M₀|² = M₀ₓ² + M₀². A 2-axis control (control.values as pairs [u_x, u_z]) has 2 parameters per \
value and its controls are reported as pairs [u_x, u_z]; --bound, --lower and --upper limit each \
component. --method condensed (and auto) run spatial scenes in the spatial model with the vector \
moment; --method riccati is planar only and refuses a spatial scene.

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
    /// Optimisation method; `auto` (the default) chooses from the problem: condensed for a
    /// planar per-step, piecewise or constant control with at most 4(2n+1) parameters (n
    /// pendulums, planar or spatial), riccati with more (planar), lbfgs for other problems; a structured
    /// run that fails or does not converge is followed by lbfgs from the same start, the better
    /// result kept. The JSON's `method` says whose result it is and `method_choice` why.
    #[arg(long, value_enum, default_value_t = MethodArg::Auto)]
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
    /// Chosen from the problem (optimize::choose_method): condensed, riccati or lbfgs, with an
    /// lbfgs fallback.
    Auto,
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
                MethodArg::Auto => Method::Auto,
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

/// Runs `optimize`: the inputs checked and the minimisation ([`solve`]), then the JSON and the
/// exit status ([`report`]).
pub fn run_optimize(a: &OptimizeArgs, progress: Progress) -> Result<(), CliError> {
    let out = Output::prepare(a.output.as_deref())?;
    let setup = solve::Setup::load(a, &out)?;
    let solved = solve::solve(a, &setup, &progress)?;
    report::write(a, &setup, &solved, out)
}
