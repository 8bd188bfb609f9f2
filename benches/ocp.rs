//! The Riccati solver of `chainbeam::ocp` (issue: long horizons) on the long-horizon scene
//! (riser, D = 10, F = 2 N at node 5, h = 0.01 s, per-step tip control, c_sum + ρh Σu²,
//! ρ = 0.01, |u| ≤ 5 N) and on Table 3.4 rows, against L-BFGS and the trust region.
//!
//! - `ocp_parts/*/N`: the parts of one iteration at N = 10³ and 10⁴ — one forward simulation
//!   (`ControlProblem::value`, the unit), a rollout plus the stage Jacobians plus the costate
//!   sweep (`set_point` + `gradient`), and one Riccati pass with a linearised rollout
//!   (`gauss_newton_step`), and the exact model's extra: the costate sweep, the second-order
//!   terms H_k of every stage and one Riccati pass with them (`newton_step`, after the Jacobians
//!   of `gradient`). A Gauss-Newton iteration is one Jacobian pass plus a few Riccati passes
//!   (the warm face or the interior-point QP) plus 1–3 rollouts; an exact one adds the H_k
//!   pass; the ratios to `forward` are machine-independent.
//! - `ocp_solve/riccati/1000`: time to the optimum (projected gradient ≤ 10⁻⁸‖g₀‖) from u = 0
//!   with the default curvature (Gauss-Newton, then exact), `ocp_solve/riccati_gauss_newton`
//!   with Gauss-Newton throughout (the same optimum, J = 1507.4813624 against 1507.4813611, in
//!   23 iterations against 11).
//!   With `OCP_BENCH_LONG=1` also N = 10⁴ (and 10⁵ with `OCP_BENCH_LONG=2`), and L-BFGS and the
//!   trust region at N = 10³ (minutes: L-BFGS stops at 5000 iterations, the trust region
//!   converges after about 225-375 s; `examples/long_horizon.rs` prints the same comparison).
//! - `ocp_table_3_4/all_rows/{riccati,condensed,lbfgs,trust_region}`: all ten rows of Table
//!   3.4 (per-step, N = 10, c_sum, each row bounded by the thesis's largest |u_k|) from u = 0,
//!   in total, through `minimize` (`condensed`: [`Method::Condensed`], the dense Gauss-Newton
//!   on the 11 controls); the per-row objectives, convergence and times are printed to stderr
//!   first.
//!
//! Run with `cargo bench --bench ocp -- --warm-up-time 1 --measurement-time 5`.

use std::hint::black_box;

use chainbeam::ocp::{solve, Curvature, OcpOptions, Solver};
use chainbeam::optimize::{minimize, Method, OptimOptions};
use chainbeam::{
    catalogue, BendingObjective, ControlProblem, Parametrisation, PerStepControl, Scene,
};
use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion, SamplingMode};

#[allow(dead_code)]
#[path = "../examples/tables/thesis.rs"]
mod thesis;

fn long_horizon(steps: usize) -> Scene {
    let mut s = catalogue::long_horizon();
    s.time.steps = steps;
    if let Some(c) = s.control.as_mut() {
        c.values = vec![0.0; steps + 1];
    }
    s
}

fn problem(steps: usize) -> ControlProblem {
    ControlProblem::builder(&long_horizon(steps))
        .map(Parametrisation::PerStep(PerStepControl { steps }))
        .objective(BendingObjective::summed_moment().with_effort(0.01))
        .build_in::<2>()
        .expect("valid scene")
}

fn long_level() -> u32 {
    std::env::var("OCP_BENCH_LONG")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(0)
}

fn bench_parts(c: &mut Criterion) {
    let mut g = c.benchmark_group("ocp_parts");
    g.sample_size(10);
    for steps in [1000usize, 10_000] {
        let p = problem(steps);
        let theta: Vec<f64> = (0..=steps).map(|k| 2.0 * (0.01 * k as f64).sin()).collect();
        let opts = OcpOptions::default().with_bound(5.0);
        let mut s = Solver::new(&p, &opts).expect("solver");
        g.bench_with_input(BenchmarkId::new("forward", steps), &steps, |b, _| {
            b.iter(|| black_box(p.value(black_box(&theta)).unwrap()))
        });
        g.bench_with_input(
            BenchmarkId::new("rollout_jacobians_costate", steps),
            &steps,
            |b, _| {
                b.iter(|| {
                    s.set_point(black_box(&theta)).unwrap();
                    black_box(s.gradient().unwrap())
                })
            },
        );
        s.set_point(&theta).unwrap();
        s.gradient().unwrap();
        g.bench_with_input(BenchmarkId::new("riccati_pass", steps), &steps, |b, _| {
            b.iter(|| black_box(s.gauss_newton_step(black_box(1e-3)).unwrap()))
        });
        g.bench_with_input(
            BenchmarkId::new("costate_hessians_newton_pass", steps),
            &steps,
            |b, _| b.iter(|| black_box(s.newton_step(black_box(1.0)).unwrap())),
        );
    }
    g.finish();
}

fn bench_solve(c: &mut Criterion) {
    let mut g = c.benchmark_group("ocp_solve");
    g.sample_size(10);
    g.sampling_mode(SamplingMode::Flat);
    let level = long_level();
    let mut sizes = vec![1000usize];
    if level >= 1 {
        sizes.push(10_000);
    }
    if level >= 2 {
        sizes.push(100_000);
    }
    for steps in sizes {
        let p = problem(steps);
        let theta0 = vec![0.0; steps + 1];
        let auto = OcpOptions::default().with_bound(5.0);
        let gn = OcpOptions {
            curvature: Curvature::GaussNewton,
            ..auto.clone()
        };
        for (name, opts) in [("riccati", auto), ("riccati_gauss_newton", gn)] {
            if name == "riccati_gauss_newton" && steps > 1000 {
                continue;
            }
            g.bench_with_input(BenchmarkId::new(name, steps), &steps, |b, _| {
                b.iter(|| {
                    let r = solve(&p, black_box(&theta0), &opts).unwrap();
                    assert!(r.converged, "{}", r.termination);
                    black_box(r.objective)
                })
            });
        }
    }
    if level >= 1 {
        let p = problem(1000);
        let theta0 = vec![0.0; 1001];
        for (name, method) in [
            ("lbfgs", Method::Lbfgs),
            ("trust_region", Method::TrustRegion),
        ] {
            let opts = OptimOptions {
                method,
                bound: Some(5.0),
                max_iters: 5000,
                ..OptimOptions::default()
            };
            g.bench_with_input(BenchmarkId::new(name, 1000), &1000, |b, _| {
                b.iter(|| black_box(minimize(&p, black_box(&theta0), &opts).unwrap().objective))
            });
        }
    }
    g.finish();
}

/// Table 3.4's ten rows (per-step, N = 10, c_sum, no effort), each bounded by the thesis's
/// largest |u_k| of its row (examples/tables/thesis.rs, as the `tables` example bounds them).
fn table_3_4_rows() -> Vec<(usize, ControlProblem, f64)> {
    (1..=10)
        .map(|node| {
            let p = ControlProblem::builder(&catalogue::riser(node))
                .map(Parametrisation::PerStep(PerStepControl { steps: 10 }))
                .objective(BendingObjective::summed_moment())
                .build_in::<2>()
                .expect("valid scene");
            let bound = thesis::TABLE_3_4[node - 1]
                .0
                .iter()
                .fold(0.0f64, |m, u| m.max(u.abs()));
            (node, p, bound)
        })
        .collect()
}

fn optim(method: Method, bound: f64) -> OptimOptions {
    OptimOptions {
        method,
        bound: Some(bound),
        max_iters: 2000,
        ..OptimOptions::default()
    }
}

/// Prints each row's objective, convergence and time for the three methods (one run each).
fn print_table_3_4(rows: &[(usize, ControlProblem, f64)]) {
    eprintln!("Table 3.4 (per-step, N = 10), from u = 0, bound = the thesis row's max |u|:");
    eprintln!(
        "{:>4} {:>9} {:>22} {:>22} {:>22} {:>22}",
        "node",
        "bound",
        "riccati J (conv, ms)",
        "condensed J (conv, ms)",
        "trust region J",
        "lbfgs J"
    );
    let mut total = [0.0f64; 4];
    for (node, p, bound) in rows {
        // What `minimize` with Method::Riccati returns (a stalled Gauss-Newton run finished by
        // the trust region: `+tr` after the time).
        let r = minimize(p, &[0.0; 11], &optim(Method::Riccati, *bound)).unwrap();
        let tr = minimize(p, &[0.0; 11], &optim(Method::TrustRegion, *bound)).unwrap();
        let lb = minimize(p, &[0.0; 11], &optim(Method::Lbfgs, *bound)).unwrap();
        let c = minimize(p, &[0.0; 11], &optim(Method::Condensed, *bound)).unwrap();
        let times = [r.seconds, c.seconds, tr.seconds, lb.seconds];
        for (t, s) in total.iter_mut().zip(times) {
            *t += s;
        }
        eprintln!(
            "{node:>4} {bound:>9.3} {:>14.9e} {} {:>5.1}{} {:>14.9e} {} {:>5.1} {:>14.9e} {} \
             {:>14.9e} {}",
            r.objective,
            u8::from(r.converged),
            r.seconds * 1e3,
            if r.method == Method::Riccati {
                "   "
            } else {
                "+tr"
            },
            c.objective,
            u8::from(c.converged),
            c.seconds * 1e3,
            tr.objective,
            u8::from(tr.converged),
            lb.objective,
            u8::from(lb.converged)
        );
    }
    eprintln!(
        "total optimisation time [ms]: riccati {:.1}, condensed {:.1}, trust region {:.1}, \
         lbfgs {:.1}",
        total[0] * 1e3,
        total[1] * 1e3,
        total[2] * 1e3,
        total[3] * 1e3
    );
}

fn bench_table_3_4(c: &mut Criterion) {
    let rows = table_3_4_rows();
    print_table_3_4(&rows);
    let mut g = c.benchmark_group("ocp_table_3_4");
    g.sample_size(10);
    for (name, method) in [
        ("all_rows/riccati", Method::Riccati),
        ("all_rows/condensed", Method::Condensed),
        ("all_rows/lbfgs", Method::Lbfgs),
        ("all_rows/trust_region", Method::TrustRegion),
    ] {
        g.bench_function(name, |b| {
            b.iter(|| {
                for (_, p, bound) in &rows {
                    let o = optim(method, *bound);
                    black_box(minimize(p, black_box(&[0.0; 11]), &o).unwrap().objective);
                }
            })
        });
    }

    g.finish();
}

criterion_group!(benches, bench_parts, bench_solve, bench_table_3_4);
criterion_main!(benches);
