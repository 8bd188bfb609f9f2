//! `--method riccati` and `--method condensed` (the structured solvers of `chainbeam::ocp`)
//! through `minimize`, the multistart and the CLI: the same optima as the trust region (the reference: an independent
//! second-order method on exact Hessian-vector products), the bound kept, and a typed refusal
//! of problems it does not cover.

use crate::common;

use std::fs;

use chainbeam::optimize::{minimize, Method, OptimOptions};
use chainbeam::{catalogue, BendingObjective, ControlProblem, Parametrisation, PerStepControl};
use common::*;

fn opts(method: Method, bound: Option<f64>) -> OptimOptions {
    OptimOptions {
        method,
        bound,
        ..Default::default()
    }
}

/// Table 3.4, row 5 (riser, F = 2 N at node 5, per-step control, c_sum) with ρ = 0.01, bounded
/// and unbounded: `minimize` with `Method::Riccati` and with `Method::Condensed` reaches the
/// trust region's objective.
#[test]
fn minimize_dispatches_to_the_riccati_solver() {
    let map = Parametrisation::PerStep(PerStepControl { steps: 10 });
    let obj = BendingObjective::summed_moment().with_effort(0.01);
    let p = ControlProblem::builder(&catalogue::riser(5))
        .map(map)
        .objective(obj)
        .build_in::<2>()
        .unwrap();
    for (bound, method) in [None, Some(3.0)]
        .into_iter()
        .flat_map(|b| [(b, Method::Riccati), (b, Method::Condensed)])
    {
        let r = minimize(&p, &[0.0; 11], &opts(method, bound)).unwrap();
        assert_eq!(r.method, method);
        assert!(r.converged, "{:?}", r.termination);
        assert!(r.projected_gradient_norm <= 1e-8 * r.initial_gradient_norm);
        let tr = minimize(&p, &[0.0; 11], &opts(Method::TrustRegion, bound)).unwrap();
        let rel = (r.objective - tr.objective).abs() / tr.objective;
        assert!(
            rel <= 1e-9,
            "{method} {bound:?}: {} vs {}",
            r.objective,
            tr.objective
        );
        if let Some(b) = bound {
            assert!(r.theta.iter().all(|u| u.abs() <= b));
            assert!(
                !r.active_bounds.is_empty(),
                "the 3 N bound is active at this optimum"
            );
        }
    }
    // A constant control is one piece: handled.
    let c = ControlProblem::builder(&catalogue::riser(5))
        .map(Parametrisation::Constant)
        .objective(obj)
        .build_in::<2>()
        .unwrap();
    let tr = minimize(&c, &[0.0], &opts(Method::TrustRegion, None)).unwrap();
    for method in [Method::Riccati, Method::Condensed] {
        let r = minimize(&c, &[0.0], &opts(method, None)).unwrap();
        assert!((r.objective - tr.objective).abs() <= 1e-9 * tr.objective);
    }
}

/// A locked tip is outside the solver's model: a typed error naming the tip, no panic.
#[test]
fn unsupported_problems_are_refused() {
    let p = ControlProblem::builder(&catalogue::fixed_fixed())
        .map(Parametrisation::Constant)
        .objective(BendingObjective::summed_moment())
        .build_in::<2>()
        .unwrap();
    for method in [Method::Riccati, Method::Condensed] {
        let e = minimize(&p, &[0.0], &opts(method, None)).unwrap_err();
        assert!(e.to_string().contains("tip"), "{e}");
    }
}

/// The CLI: `optimize --method riccati` (and `condensed`) on the thesis riser (c_sum) with a
/// per-step control reaches the trust region's objective and reports the method; `--pieces` and
/// `--bound` work; a locked-tip scene fails with a message.
#[test]
fn cli_optimize_with_riccati() {
    let dir = Dir::new();
    let text = fs::read_to_string(scene("riser_5.toml"))
        .unwrap()
        .replace("kind = \"final\"", "kind = \"sum\"")
        .replace("kind = \"constant\"", "kind = \"per-step\"")
        .replace(
            "values = [0.0]",
            &format!("values = [{}]", ["0.0"; 11].join(", ")),
        );
    let sc = dir.write("riser_per_step.toml", &text);
    let sc = sc.to_str().unwrap();
    let args = |m: &'static str| {
        [
            "optimize", sc, "--method", m, "--effort", "0.01", "--bound", "3",
        ]
    };
    let tr = json(&run(&args("trust-region")));
    for m in ["riccati", "condensed"] {
        let o = run(&args(m));
        assert_success(&o);
        let r = json(&o);
        assert_eq!(r["method"], m);
        assert_eq!(r["converged"], true);
        assert!(numbers(&r, "controls").iter().all(|u| u.abs() <= 3.0));
        let (a, b) = (
            r["objective"].as_f64().unwrap(),
            tr["objective"].as_f64().unwrap(),
        );
        assert!((a - b).abs() <= 1e-9 * b, "{m}: {a} vs {b}");
        let o = run(&[
            "optimize", sc, "--method", m, "--pieces", "5", "--effort", "0.01", "--bound", "10",
        ]);
        assert_success(&o);
        assert_eq!(numbers(&json(&o), "controls").len(), 5);
        let locked = scene("fixed_fixed.toml");
        let o = run(&["optimize", locked.to_str().unwrap(), "--method", m]);
        assert!(!o.status.success());
        assert!(stderr(&o).contains("tip"), "{}", stderr(&o));
    }
    // --curvature: each model of the Riccati solver reaches the trust region's objective here
    // (a problem with one minimum in reach); with another method it is refused.
    for c in ["auto", "exact", "gauss-newton"] {
        let mut a = args("riccati").to_vec();
        a.extend(["--curvature", c]);
        let o = run(&a);
        assert_success(&o);
        let r = json(&o);
        let (x, y) = (
            r["objective"].as_f64().unwrap(),
            tr["objective"].as_f64().unwrap(),
        );
        assert!((x - y).abs() <= 1e-9 * y, "--curvature {c}: {x} vs {y}");
    }
    let mut a = args("lbfgs").to_vec();
    a.extend(["--curvature", "exact"]);
    let o = run(&a);
    assert!(!o.status.success());
    assert!(stderr(&o).contains("--curvature"), "{}", stderr(&o));
}
