//! Cost of exact gradients relative to one simulation (docs/conventions.md, issue "discrete adjoint").
//!
//! Groups (all on the thesis riser, F = 2 N at node 5, per-step controls u_0..u_N):
//! - `adjoint_n10`: for N = 10 and N = 1000: the forward simulation (`value`), the adjoint
//!   gradient (`value_and_gradient`, forward + reverse sweep with √N checkpointing), the
//!   Hessian-vector product (forward-over-adjoint in `Dual64`), and, for N = 10, forward-mode
//!   gradients with one `Dual64` direction per control (N + 1 simulations) to show where the
//!   adjoint wins. Ratios gradient/simulation and HVP/simulation are read off the report.
//! - `adjoint_large_n`: the same simulation/gradient pair for n = 100 and 1000 pendulums
//!   (scaled cantilever, h shrunk with n² to stay below the stability limit), N = 100, built in
//!   this file because the catalogue scene's N = 10⁷ at n = 1000 is over the stored-state limit.
//!
//! Run with `cargo bench --bench adjoint -- --warm-up-time 1 --measurement-time 3`.

#[path = "common/cantilever.rs"]
mod cantilever;

use std::hint::black_box;

use cantilever::scaled_cantilever;
use chainbeam::adjoint::forward_value;
use chainbeam::{
    catalogue, BendingObjective, ControlProblem, Parametrisation, PerStepControl, Scene,
};
use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion};
use num_dual::Dual64;

fn problem(scene: &Scene) -> ControlProblem {
    let map = Parametrisation::PerStep(PerStepControl {
        steps: scene.time.steps,
    });
    ControlProblem::builder(scene)
        .map(map)
        .objective(BendingObjective::summed_moment())
        .build_in::<2>()
        .expect("valid scene")
}

fn theta(steps: usize) -> Vec<f64> {
    (0..=steps)
        .map(|k| -1.5 + 0.2 * (k as f64 * 0.1).sin())
        .collect()
}

fn bench_riser(c: &mut Criterion) {
    let mut g = c.benchmark_group("adjoint_n10");
    g.sample_size(20);
    for steps in [10usize, 1000] {
        let mut scene = catalogue::riser(5);
        scene.time.steps = steps;
        let p = problem(&scene);
        let th = theta(steps);
        let v: Vec<f64> = (0..=steps).map(|k| ((k % 3) as f64) - 1.0).collect();
        g.bench_with_input(BenchmarkId::new("simulation", steps), &steps, |b, _| {
            b.iter(|| black_box(p.value(black_box(&th)).unwrap()))
        });
        g.bench_with_input(BenchmarkId::new("gradient", steps), &steps, |b, _| {
            b.iter(|| black_box(p.value_and_gradient(black_box(&th)).unwrap()))
        });
        g.bench_with_input(BenchmarkId::new("hvp", steps), &steps, |b, _| {
            b.iter(|| black_box(p.hessian_vec(black_box(&th), black_box(&v)).unwrap()))
        });
        if steps == 10 {
            let chain = p.chain_as::<Dual64>();
            let obj = BendingObjective::summed_moment();
            g.bench_with_input(
                BenchmarkId::new("forward_mode_gradient", steps),
                &steps,
                |b, _| {
                    b.iter(|| {
                        let mut grad = vec![0.0; steps + 1];
                        for (j, gj) in grad.iter_mut().enumerate() {
                            let u: Vec<Dual64> = th
                                .iter()
                                .enumerate()
                                .map(|(i, &t)| Dual64::new(t, if i == j { 1.0 } else { 0.0 }))
                                .collect();
                            *gj = forward_value(&chain, 0.01, steps, &u, &obj).unwrap().eps;
                        }
                        black_box(grad)
                    })
                },
            );
        }
    }
    g.finish();
}

/// Steps of the `adjoint_large_n` scenes.
const LARGE_N_STEPS: usize = 100;

/// The scaled cantilever (benches/common/cantilever.rs) with base spring 2k and `steps` steps.
fn cantilever(n: usize, steps: usize) -> Scene {
    scaled_cantilever(n, 2.0, steps)
}

fn bench_large_n(c: &mut Criterion) {
    let mut g = c.benchmark_group("adjoint_large_n");
    g.sample_size(10);
    for n in [100usize, 1000] {
        let scene = cantilever(n, LARGE_N_STEPS);
        let p = problem(&scene);
        let th = theta(LARGE_N_STEPS);
        g.bench_with_input(BenchmarkId::new("simulation", n), &n, |b, _| {
            b.iter(|| black_box(p.value(black_box(&th)).unwrap()))
        });
        g.bench_with_input(BenchmarkId::new("gradient", n), &n, |b, _| {
            b.iter(|| black_box(p.value_and_gradient(black_box(&th)).unwrap()))
        });
    }
    g.finish();
}

criterion_group!(benches, bench_riser, bench_large_n);
criterion_main!(benches);
