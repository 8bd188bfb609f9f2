//! Is the optimal-control landscape "highly nonconvex", as the thesis concluded from SLSQP over
//! 800 transcribed variables (§3.3.1, Fig. 3.13)? With exact gradients in single shooting on the
//! thesis's riser scene (docs/conventions.md), multistart from 64 random starts per case (seeded, parallel)
//! and clustering of the local minima found answers it:
//!
//! 1. Constant control (Tables 3.1/3.2): one minimum, certified by a positive Hessian.
//! 2. Per-step control, c = M₀(T)² (Table 3.3, Fig. 3.13, load at the tip): every start reaches
//!    the global minimum c = 0 (to round-off); the zeros form a manifold of dimension N, so the
//!    "different local solutions" are different points of one set of global minima.
//! 3. Per-step control, c_sum (Table 3.4), unbounded: descent drives the forces to 10³-10⁴ N and
//!    folds the chain; there is no minimum inside the beam model.
//! 4. Per-step control, c_sum, with a force limit: a few distinct local minima (different sets of
//!    active bounds) whose values differ by less than a few percent.
//!
//! `cargo run --release --example landscape`

use chainbeam::multistart::{multistart, MultistartReport, StartDesign};
use chainbeam::optimize::OptimOptions;
use chainbeam::{
    catalogue, BendingObjective, ControlProblem, Objective, Parametrisation, PerStepControl, Result,
};

fn summary(label: &str, r: &MultistartReport) {
    let converged = r.results.iter().filter(|x| x.converged).count();
    let objs: Vec<f64> = r
        .results
        .iter()
        .filter(|x| x.converged)
        .map(|x| x.objective)
        .collect();
    let (lo, hi) = objs
        .iter()
        .fold((f64::INFINITY, 0.0f64), |(a, b), &o| (a.min(o), b.max(o)));
    let umax = r
        .results
        .iter()
        .flat_map(|x| x.controls.iter())
        .fold(0.0f64, |a, u| a.max(u.abs()));
    println!("\n{label}");
    println!(
        "  {} starts: {converged} converged, {} not converged, {} failed; {:.3} s",
        r.start_points.len(),
        r.results.len() - converged,
        r.failures.len(),
        r.seconds
    );
    if converged > 0 {
        println!("  converged objectives in [{lo:.6e}, {hi:.6e}]");
    }
    println!("  largest |u| reached by any run: {umax:.1} N");
    println!(
        "  inert parameters (ignored when clustering): {:?}",
        r.inert
    );
    println!("  distinct minima: {}", r.minima.len());
    for m in r.minima.iter().take(6) {
        println!(
            "    J = {:.8e} reached by {} start(s)",
            m.objective, m.count
        );
    }
    if let Some(c) = &r.certificate {
        println!(
            "  certificate: Hessian eigenvalues {:?} -> {}",
            c.eigenvalues
                .iter()
                .map(|e| format!("{e:.3e}"))
                .collect::<Vec<_>>(),
            if c.positive_definite {
                "strict local minimum"
            } else {
                "not positive definite"
            }
        );
    }
    if let Some(f) = r.failures.first() {
        println!("  first failure: {}", f.error);
    }
    let stopped = r.results.iter().find(|x| !x.converged);
    if let Some(s) = stopped {
        println!("  a non-converged run stopped with: {}", s.termination);
    }
}

fn run_case<O: Objective + Clone>(
    label: &str,
    node: usize,
    map: Parametrisation,
    obj: O,
    box_half_width: f64,
    bound: Option<f64>,
) -> Result<()> {
    let problem = ControlProblem::builder(&catalogue::riser(node))
        .map(map)
        .objective(obj)
        .build_in::<2>()?;
    let design = StartDesign::RandomBox {
        lo: -box_half_width,
        hi: box_half_width,
    };
    let opts = OptimOptions {
        bound,
        max_iters: 2000,
        ..OptimOptions::default()
    };
    let r = multistart(&problem, &design, 64, 7, 0, &opts)?;
    summary(label, &r);
    Ok(())
}

fn run() -> Result<()> {
    let per_step = Parametrisation::PerStep(PerStepControl { steps: 10 });
    run_case(
        "1. constant u, c_sum, load at node 5, starts in [-600, 600] N",
        5,
        Parametrisation::Constant,
        BendingObjective::summed_moment(),
        600.0,
        None,
    )?;
    run_case(
        "2. per-step u, c = M0(T)^2, load at node 10, starts in [-10, 10] N (thesis Fig. 3.13)",
        10,
        per_step,
        BendingObjective::final_moment(),
        10.0,
        None,
    )?;
    run_case(
        "3. per-step u, c_sum, load at node 5, unbounded, starts in [-10, 10] N",
        5,
        per_step,
        BendingObjective::summed_moment(),
        10.0,
        None,
    )?;
    for bound in [50.0, 400.0] {
        run_case(
            &format!("4. per-step u, c_sum, load at node 5, |u| <= {bound} N, starts in the box"),
            5,
            per_step,
            BendingObjective::summed_moment(),
            bound,
            Some(bound),
        )?;
    }
    Ok(())
}

fn main() {
    if let Err(e) = run() {
        eprintln!("error: {e}");
        std::process::exit(1);
    }
}
