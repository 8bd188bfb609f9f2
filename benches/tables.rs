//! Time to regenerate the thesis's optimisation tables (issue: optimal control), on the riser
//! scene (docs/conventions.md): single rows of Table 3.2 (constant u, c_sum, L-BFGS) and Table 3.4 (per-step
//! u, c_sum, L-BFGS with the thesis's own force bound) for the load at nodes 5 and 9, and each
//! whole table exactly as the `tables` example computes it (its `compute.rs`, included here).
//!
//! Run with `cargo bench --bench tables -- --warm-up-time 1 --measurement-time 3`.

#[path = "../examples/tables/compute.rs"]
mod compute;
#[path = "../examples/tables/thesis.rs"]
mod thesis;

use std::hint::black_box;

use chainbeam::optimize::{minimize, OptimOptions};
use chainbeam::{catalogue, BendingObjective, ControlProblem, Parametrisation, PerStepControl};
use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion};

fn bench_tables(c: &mut Criterion) {
    let mut g = c.benchmark_group("tables");
    g.sample_size(20);
    for node in [5usize, 9] {
        let scene = catalogue::riser(node);
        let p32 = ControlProblem::builder(&scene)
            .map(Parametrisation::Constant)
            .objective(BendingObjective::summed_moment())
            .build_in::<2>()
            .expect("valid scene");
        g.bench_with_input(BenchmarkId::new("3.2_row", node), &node, |b, _| {
            b.iter(|| {
                black_box(minimize(&p32, black_box(&[0.0]), &OptimOptions::default()).unwrap())
            })
        });
        // Table 3.4's bound: the largest |u_k| the thesis used (node 5: 374.15 N, node 9: 43.34 N).
        let bound = if node == 5 { 374.15217067 } else { 43.33886443 };
        let map = Parametrisation::PerStep(PerStepControl { steps: 10 });
        let p34 = ControlProblem::builder(&scene)
            .map(map)
            .objective(BendingObjective::summed_moment())
            .build_in::<2>()
            .expect("valid scene");
        let opts = OptimOptions {
            bound: Some(bound),
            max_iters: 2000,
            ..OptimOptions::default()
        };
        g.bench_with_input(BenchmarkId::new("3.4_row", node), &node, |b, _| {
            b.iter(|| black_box(minimize(&p34, black_box(&[0.0; 11]), &opts).unwrap()))
        });
    }
    g.finish();
}

/// Each whole table, as the example computes it (3.4 runs three L-BFGS per row: two bounded
/// starts and the unbounded run).
fn bench_whole_tables(c: &mut Criterion) {
    let mut g = c.benchmark_group("tables_whole");
    g.sample_size(10);
    for name in compute::NAMES {
        g.bench_with_input(BenchmarkId::new("table", name), &name, |b, &name| {
            b.iter(|| black_box(compute::table(black_box(name)).unwrap()))
        });
    }
    g.finish();
}

criterion_group!(benches, bench_tables, bench_whole_tables);
criterion_main!(benches);
