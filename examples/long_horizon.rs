//! What the thesis left for future work (end of §3.3, Fig. 3.12): optimal control over a long
//! horizon. The riser with drag (D = 10 kg/m), F = 2 N at node 5 from t = 0, h = 0.01 s,
//! N = 1000 (t ∈ [0, 10] s), per-step control at the tip (N + 1 = 1001 parameters), minimising
//! J = c_sum + ρ h Σ u_k² with a small effort penalty ρ and a force limit |u_k| ≤ u_max.
//!
//! By default the true per-step problem is solved by the structure-exploiting Riccati solver
//! ([`chainbeam::ocp`]: box-constrained iLQR, O(N) per iteration, bounds handled exactly), from
//! u = 0 to a projected gradient ≤ 10⁻⁸ ‖g₀‖. For comparison:
//! - `--method lbfgs` or `--method trust-region` solve the same per-step problem with the
//!   general-purpose solvers of [`chainbeam::optimize`] (L-BFGS stalls on this badly conditioned
//!   1001-dimensional problem; the trust region converges but each Hessian-vector product costs a
//!   forward-over-adjoint sweep of the whole horizon);
//! - `--compare` runs all three on the same problem and prints one row each (time, iterations,
//!   J, Σ M₀², projected gradient relative to ‖g₀‖, converged); `--skip-trust-region` and
//!   `--skip-lbfgs` leave out the slow baselines, `--method riccati,lbfgs` picks a list;
//! - `--pieces P` replaces the per-step control by P piecewise-constant pieces: a *different,
//!   coarser* problem (fewer parameters, a higher optimum), solvable by any method, among them
//!   `--method condensed` ([`chainbeam::ocp::Condensed`]: Gauss-Newton on the P forces
//!   themselves, whose cost per iteration grows with N × P — fine for tens of pieces, not for
//!   the 1001 per-step controls).
//!
//! Prints Σ M₀², max |M₀| and J against no control and against the best constant control (same
//! objective and limit), the iterations, the first-order optimality reached and the time.
//!
//! `--max-iters K` sets every method's iteration limit (default: the Riccati solver's 200,
//! 5000 for L-BFGS and the trust region; a run that reaches it says *not converged*): it bounds
//! the time of the slow baselines (the trust region at N = 10⁴ did not finish within an hour).
//!
//! `--curvature auto|exact|gauss-newton` chooses the Riccati solver's model
//! ([`chainbeam::ocp::Curvature`]; default `auto`: Gauss-Newton, then the exact Hessian from
//! the first step Gauss-Newton predicts poorly).
//!
//! Measured (2-core machine, the solve's time as printed, release build, all from u = 0):
//! N = 1000, the Riccati solver converges in 11 iterations (7 Gauss-Newton, 4 Newton) and
//! 0.29–0.36 s (criterion median 289 ms) to J = 1507.481361068 (Σ M₀² = 1507.2286), the
//! optimum the trust region reaches in 243.5 s (119 iterations, J = 1507.4813611); with
//! Gauss-Newton throughout it takes 23 iterations and 0.54 s to the same optimum
//! (J = 1507.4813624 at its tolerance); L-BFGS stops at its 5000-iteration limit (9.1 s,
//! projected gradient 1.0·10⁻⁵ ‖g₀‖, J = 1507.4899744). N = 10⁴: 2.8–2.9 s, 11 iterations,
//! J = 1509.506385425 (Gauss-Newton throughout: 3.2 s, 14 iterations, J = 1509.5064804);
//! N = 10⁵: 26.4–30.2 s, 11 iterations, J = 1529.756629004, 900 MB peak (Gauss-Newton, an
//! earlier build: 222.7 s, 15 iterations, J = 1529.7569188). The machine's speed drifts by
//! 10–20 % over minutes, which these ranges include. The Riccati rows also print the time
//! per iteration in forward simulations of the same horizon at the solution (the fastest of
//! five; 46 at N = 1000, 62–65 at 10⁴, 69 at 10⁵: at the optimum the beam rests in the
//! middle of the horizon and a simulation is cheap). See the module docs of
//! `chainbeam::ocp` for the method and the limits.
//!
//! ```text
//! cargo run --release --example long_horizon
//! cargo run --release --example long_horizon -- --steps 10000
//! cargo run --release --example long_horizon -- --method trust-region
//! cargo run --release --example long_horizon -- --compare [--skip-trust-region] [--skip-lbfgs]
//! cargo run --release --example long_horizon -- --pieces 50 [--method lbfgs]
//! cargo run --release --example long_horizon -- --rho 0.01 --umax 5 --rate 0.001 --history
//! cargo run --release --example long_horizon -- --curvature gauss-newton
//! ```

use chainbeam::ocp::{self, Curvature, OcpOptions};
use chainbeam::optimize::{History, Method, Minimizer, ObserverMode, OptimOptions};
use chainbeam::{
    catalogue, simulate, BendingObjective, ControlProblem, Parametrisation, PerStepControl,
    PiecewiseControl, Result, Scene, SimulateInput,
};
use std::time::Instant;

/// Why the example stopped: a command-line flag it cannot use, or the library's error.
#[derive(Debug, thiserror::Error)]
enum RunError {
    /// A flag's value that does not parse or is not one of the choices.
    #[error("invalid argument `{flag}`: expected {expected}, got {got:?}")]
    Flag {
        /// The flag, e.g. `--method`.
        flag: &'static str,
        /// What it takes.
        expected: &'static str,
        /// The value given.
        got: String,
    },
    /// `--rate` with a method other than the Riccati solver.
    #[error(
        "invalid argument `--rate`: the rate penalty is a term of the Riccati solver's objective \
         only"
    )]
    RateNeedsRiccati,
    /// The library's error.
    #[error(transparent)]
    Lib(#[from] chainbeam::Error),
}

fn moments(scene: &Scene, u: &[f64]) -> Result<(f64, f64)> {
    let t = simulate(SimulateInput::new(scene).controls(u))?;
    let sum: f64 = t.moment().iter().map(|m| m * m).sum();
    let max = t.moment().iter().fold(0.0f64, |a, m| a.max(m.abs()));
    Ok((sum, max))
}

/// The time of one forward simulation of the horizon with the objective (the yardstick of the
/// issue's "cost per iteration in simulations"): the fastest of five, as the machine's speed
/// drifts.
fn simulation_seconds(problem: &ControlProblem, theta: &[f64]) -> Result<f64> {
    let mut best = f64::INFINITY;
    for _ in 0..5 {
        let t = Instant::now();
        std::hint::black_box(problem.value(std::hint::black_box(theta))?);
        best = best.min(t.elapsed().as_secs_f64());
    }
    Ok(best)
}

fn value<'a>(args: &'a [String], name: &str) -> Option<&'a str> {
    args.iter()
        .position(|a| a == name)
        .and_then(|i| args.get(i + 1))
        .map(String::as_str)
}

fn arg(args: &[String], flag: &'static str, default: f64) -> Result<f64, RunError> {
    match value(args, flag) {
        None => Ok(default),
        Some(v) => v.parse().map_err(|_| RunError::Flag {
            flag,
            expected: "a number",
            got: v.into(),
        }),
    }
}

/// What a run produced, whichever solver.
struct Outcome {
    controls: Vec<f64>,
    objective: f64,
    iterations: usize,
    seconds: f64,
    ratio: f64,
    converged: bool,
    note: String,
}

/// The settings shared by the runs.
#[derive(Clone, Copy)]
struct Setup {
    umax: f64,
    rate: f64,
    history: bool,
    curvature: Curvature,
    /// Iteration limit of every method (`--max-iters`); by default the Riccati solver's own
    /// (200) and 5000 for L-BFGS and the trust region.
    max_iters: Option<usize>,
}

/// Solves `problem` from θ₀ with one method.
fn solve_with(
    method: &str,
    problem: &ControlProblem,
    theta0: &[f64],
    set: &Setup,
) -> Result<Outcome> {
    if method == "riccati" || method == "condensed" {
        let opts = OcpOptions {
            rate_penalty: set.rate,
            curvature: set.curvature,
            max_iters: set.max_iters.unwrap_or(OcpOptions::default().max_iters),
            ..OcpOptions::default().with_bound(set.umax)
        };
        let r = if method == "condensed" {
            ocp::Condensed::new(problem, &opts)?.solve(theta0)?
        } else {
            ocp::solve(problem, theta0, &opts)?
        };
        if set.history {
            for (i, h) in r.history.iter().enumerate() {
                eprintln!(
                    "iter {:>3}: J = {:.12}, |pg| before = {:.3e}, alpha = {}, mu = {:.1e}",
                    i + 1,
                    h.objective,
                    h.projected_gradient_norm,
                    h.alpha,
                    h.regularisation
                );
            }
        }
        let sim = simulation_seconds(problem, &r.theta)?;
        let per_iteration = r.seconds / r.iterations.max(1) as f64 / sim;
        return Ok(Outcome {
            controls: r.controls.clone(),
            objective: r.objective,
            iterations: r.iterations,
            seconds: r.seconds,
            ratio: r.projected_gradient_norm / r.initial_gradient_norm,
            converged: r.converged,
            note: format!(
                "{} rollouts, {} Jacobian passes, {} backward passes, {} active bounds; \
                 {per_iteration:.1} simulations per iteration (one: {:.3} ms); {}",
                r.rollouts,
                r.jacobian_passes,
                r.backward_passes,
                r.active_bounds.len(),
                sim * 1e3,
                r.termination
            ),
        });
    }
    let m = if method == "lbfgs" {
        Method::Lbfgs
    } else {
        Method::TrustRegion
    };
    let opts = OptimOptions {
        method: m,
        bound: Some(set.umax),
        max_iters: set.max_iters.unwrap_or(5000),
        ..OptimOptions::default()
    };
    // --history: the iterations, recorded by an observer and printed after the run.
    let history = History::default();
    let mut minimizer = Minimizer::new(problem, opts);
    if set.history {
        minimizer = minimizer.add_observer(history.clone(), ObserverMode::Always);
    }
    let r = minimizer.run(theta0)?;
    for h in history.records() {
        eprintln!(
            "iter {:>5}  cost {:.12e}  |g| {:.3e}{}",
            h.iteration,
            h.objective,
            h.gradient_norm,
            if h.polish { "  (polish)" } else { "" }
        );
    }
    Ok(Outcome {
        controls: r.controls.clone(),
        objective: r.objective,
        iterations: r.iterations,
        seconds: r.seconds,
        ratio: r.projected_gradient_norm / r.initial_gradient_norm,
        converged: r.converged,
        note: format!(
            "{} adjoint sweeps, {} HVPs; {}",
            r.gradient_evals, r.hvp_evals, r.termination
        ),
    })
}

/// The methods to run: `--method a,b`, or `--compare` (all three) minus `--skip-lbfgs` /
/// `--skip-trust-region`.
fn methods(args: &[String]) -> Result<Vec<String>, RunError> {
    let list = if args.iter().any(|a| a == "--compare") {
        "riccati,lbfgs,trust-region"
    } else {
        value(args, "--method").unwrap_or("riccati")
    };
    let skip = |m: &str| args.iter().any(|a| a == &format!("--skip-{m}"));
    let out: Vec<String> = list
        .split(',')
        .filter(|m| !skip(m))
        .map(str::to_owned)
        .collect();
    match out
        .iter()
        .find(|m| !["riccati", "condensed", "lbfgs", "trust-region"].contains(&m.as_str()))
    {
        Some(m) => Err(RunError::Flag {
            flag: "--method",
            expected: "riccati, condensed, lbfgs or trust-region",
            got: m.clone(),
        }),
        None => Ok(out),
    }
}

fn run() -> Result<(), RunError> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let rho = arg(&args, "--rho", 0.01)?;
    let set = Setup {
        umax: arg(&args, "--umax", 5.0)?,
        rate: arg(&args, "--rate", 0.0)?,
        history: args.iter().any(|a| a == "--history"),
        max_iters: value(&args, "--max-iters")
            .map(|v| {
                v.parse::<usize>().map_err(|_| RunError::Flag {
                    flag: "--max-iters",
                    expected: "a whole number of iterations",
                    got: v.into(),
                })
            })
            .transpose()?,
        curvature: match value(&args, "--curvature") {
            None | Some("auto") => Curvature::Auto,
            Some("exact") => Curvature::Exact,
            Some("gauss-newton") => Curvature::GaussNewton,
            Some(other) => {
                return Err(RunError::Flag {
                    flag: "--curvature",
                    expected: "auto, exact or gauss-newton",
                    got: other.into(),
                })
            }
        },
    };
    let steps = arg(&args, "--steps", 1000.0)? as usize;
    let pieces = arg(&args, "--pieces", 0.0)? as usize;
    let methods = methods(&args)?;
    if set.rate > 0.0 && methods.iter().any(|m| m != "riccati") {
        return Err(RunError::RateNeedsRiccati);
    }
    let mut scene = catalogue::long_horizon();
    scene.time.steps = steps;
    if let Some(c) = scene.control.as_mut() {
        c.values = vec![0.0; steps + 1];
    }
    let objective = BendingObjective::summed_moment().with_effort(rho);

    // Best constant control (1 parameter) as the baseline.
    let constant = ControlProblem::builder(&scene)
        .map(Parametrisation::Constant)
        .objective(objective)
        .build_in::<2>()?;
    let c = solve_with(
        "lbfgs",
        &constant,
        &[0.0],
        &Setup {
            history: false,
            ..set
        },
    )?;

    let map = if pieces == 0 {
        Parametrisation::PerStep(PerStepControl { steps })
    } else {
        Parametrisation::Piecewise(PiecewiseControl { steps, pieces })
    };
    let problem = ControlProblem::builder(&scene)
        .map(map)
        .objective(objective)
        .build_in::<2>()?;
    let theta0 = vec![0.0; problem.n_params()];
    let label = |method: &str| {
        if pieces == 0 {
            format!("per-step ({} values), {method}", steps + 1)
        } else {
            format!(
                "{pieces} pieces of {:.2} s (coarser problem), {method}",
                scene.time.step * (steps + 1) as f64 / pieces as f64
            )
        }
    };
    let (s0, m0) = moments(&scene, &vec![0.0; steps + 1])?;
    let (sc, mc) = moments(&scene, &c.controls)?;
    println!(
        "riser, D = 10 kg/m, F = 2 N at node 5, N = {steps}, h = 0.01 s; rho = {rho}, \
         |u| <= {} N{}\n",
        set.umax,
        if set.rate > 0.0 {
            format!(", rate penalty sigma = {}", set.rate)
        } else {
            String::new()
        }
    );
    println!(
        "{:<44} {:>14} {:>9} {:>17} {:>7} {:>6} {:>9} {:>8} {:>5}",
        "control", "sum M0^2", "max |M0|", "J", "max |u|", "iters", "time [s]", "pg/|g0|", "conv"
    );
    println!("{:<44} {:>14.4} {:>9.4}", "none", s0, m0);
    let row = |name: String, o: &Outcome, sum: f64, max: f64| {
        let umax_used = o.controls.iter().fold(0.0f64, |a, u| a.max(u.abs()));
        println!(
            "{:<44} {:>14.4} {:>9.4} {:>17.9} {:>7.3} {:>6} {:>9.3} {:>8.1e} {:>5}",
            name, sum, max, o.objective, umax_used, o.iterations, o.seconds, o.ratio, o.converged
        );
    };
    row(
        format!("best constant u = {:.3} N (lbfgs)", c.controls[0]),
        &c,
        sc,
        mc,
    );
    let mut notes = Vec::new();
    for method in &methods {
        let out = solve_with(method, &problem, &theta0, &set)?;
        let (sp, mp) = moments(&scene, &out.controls)?;
        row(label(method), &out, sp, mp);
        notes.push(format!(
            "{method}: vs none sum M0^2 reduced {:.1}x, max |M0| {:.2}x; vs best constant \
             {:.2}x, {:.2}x; {}",
            s0 / sp,
            m0 / mp,
            sc / sp,
            mc / mp,
            out.note
        ));
    }
    println!();
    for n in notes {
        println!("{n}");
    }
    Ok(())
}

fn main() {
    if let Err(e) = run() {
        eprintln!("error: {e}");
        std::process::exit(1);
    }
}
