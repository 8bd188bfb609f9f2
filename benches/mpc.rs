//! Receding-horizon control on `catalogue::mpc_riser` (n = 10, D = 10 kg/m, an
//! irregular sea at node 5 in a sheared current, h = 0.01 s), a decision every 0.1 s,
//! |u| ≤ 5 N, ρ = 0.01.
//!
//! - `mpc_replan/{condensed,riccati}/{1,2,3,4}s`: one re-plan — by the condensed solver (the
//!   default, [`MpcSolver::Condensed`]) and by the Riccati solver, on a horizon of 1, 2, 3 or
//!   4 s (10 to 40 pieces of 0.1 s; 3 s is the default) from the plant's state at t = 10 s,
//!   warm-started from the plan of the previous decision, with the default budget of 1
//!   Gauss-Newton iteration. The target is ≤ 100 ms (the control interval: real-time capable)
//!   worst case, ≤ 10 ms mean; the pair of solvers at one horizon is the speed-up ratio.
//! - `mpc_closed_loop/{condensed,riccati}/10s`: the whole closed loop over 10 s of the scene
//!   (plant, 100 decisions, 3 s horizon). Criterion's throughput is in simulated milliseconds
//!   per second: divide by 1000 for the real-time factor of the whole loop. The factor of the
//!   controller alone and the worst re-plan of one run are printed before the measurements.
//!
//! Run with `cargo bench --bench mpc -- --warm-up-time 1 --measurement-time 5`.

use std::hint::black_box;

use chainbeam::catalogue;
use chainbeam::mpc::{
    run_closed_loop, Controller, Horizon, Mpc, MpcOptions, MpcSolver, Observation, Plant,
};
use chainbeam::ocp::OcpOptions;
use chainbeam::Scene;
use criterion::{criterion_group, criterion_main, BatchSize, BenchmarkId, Criterion, Throughput};

const INTERVAL: f64 = 0.1;

const SOLVERS: [(MpcSolver, &str); 2] = [
    (MpcSolver::Condensed, "condensed"),
    (MpcSolver::Riccati, "riccati"),
];

fn options(horizon: f64, solver: MpcSolver) -> MpcOptions {
    MpcOptions {
        horizon: Horizon::Seconds(horizon),
        solver,
        ocp: OcpOptions::default().with_bound(5.0),
        ..MpcOptions::default()
    }
}

fn scene(seconds: f64) -> Scene {
    let mut s = catalogue::mpc_riser();
    s.time.steps = (seconds / s.time.step).round() as usize;
    s
}

fn bench_replan(c: &mut Criterion) {
    let mut g = c.benchmark_group("mpc_replan");
    g.sample_size(20);
    let s = scene(20.0);
    let mut plant = Plant::<f64>::new(&s).expect("plant");
    for _ in 0..1000 {
        plant.advance().expect("step");
    }
    plant.update_state_before_kick().expect("projection");
    let obs = Observation::of_plant(&mut plant, INTERVAL);
    for (solver, name) in SOLVERS {
        for horizon in [1.0, 2.0, 3.0, 4.0] {
            let mut mpc = Mpc::new(&s, INTERVAL, options(horizon, solver)).expect("mpc");
            mpc.control(&obs).expect("first plan");
            // The controller as it stands after the previous decision (its plan and, for the
            // condensed solver, the solver it keeps), cloned outside the timing.
            g.bench_with_input(
                BenchmarkId::new(name, format!("{horizon}s")),
                &obs,
                |b, obs| {
                    b.iter_batched(
                        || mpc.clone(),
                        |mut m| black_box(m.control(obs).expect("re-plan")),
                        BatchSize::SmallInput,
                    )
                },
            );
        }
    }
    g.finish();
}

fn bench_loop(c: &mut Criterion) {
    let s = scene(10.0);
    let mut g = c.benchmark_group("mpc_closed_loop");
    g.sample_size(10);
    g.throughput(Throughput::Elements(10_000)); // simulated milliseconds
    for (solver, name) in SOLVERS {
        let r = run_closed_loop(
            &s,
            INTERVAL,
            &mut Mpc::new(&s, INTERVAL, options(3.0, solver)).expect("mpc"),
        )
        .expect("closed loop");
        eprintln!(
            "mpc_riser, 10 s, 3 s horizon, {name}: controller real-time factor {:.1}, mean \
             re-plan {:.2} ms, worst {:.2} ms, mean iterations {:.2}, c_sum {:.1}",
            r.summary.real_time_factor,
            1e3 * r.summary.mean_replan_seconds,
            1e3 * r.summary.worst_replan_seconds,
            r.summary.mean_iterations.unwrap_or(0.0),
            r.summary.c_sum
        );
        g.bench_function(BenchmarkId::new(name, "10s"), |b| {
            b.iter(|| {
                let mut mpc = Mpc::new(&s, INTERVAL, options(3.0, solver)).expect("mpc");
                black_box(run_closed_loop(&s, INTERVAL, &mut mpc).expect("closed loop"))
            })
        });
    }
    g.finish();
}

criterion_group!(benches, bench_replan, bench_loop);
criterion_main!(benches);
