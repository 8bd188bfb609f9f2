//! A fixed amount of the work of the `step`, `adjoint` and `ocp` benches, for counting
//! instructions where timings are too noisy (a shared machine): `bench_probe CASE REPS` repeats
//! one bench case REPS times, so that the count of two runs, I(R₂) − I(R₁) over R₂ − R₁, is the
//! instructions of one repetition with the set-up cancelled. docs/architecture.md "Benches" has
//! the commands (valgrind's cachegrind on an x86-64-v3 build: valgrind does not decode AVX-512)
//! and the counts. The cases are the benches' scenes, built here the same way:
//! `step_planar100`, `step_still100`, `step_linear100`, `step_table100`, `step_spatial45` (one
//! RATTLE step each, n = 100, after 50 steps), `adj_sim1000`, `adj_grad1000`, `adj_hvp1000`
//! (riser, N = 1000), `adj_large_sim1000`, `adj_large_grad1000`, `adj_large_grad100` (scaled
//! cantilever, N = 100), `ocp_forward`, `ocp_jac`, `ocp_riccati`, `ocp_newton`, `ocp_solve`
//! (long-horizon riser, N = 1000).

#[path = "../benches/common/cantilever.rs"]
mod cantilever;

use std::hint::black_box;

use cantilever::scaled_cantilever;
use chainbeam::ocp::{solve, OcpOptions, Solver};
use chainbeam::{
    catalogue, BendingObjective, Chain, ControlProblem, Current, Parametrisation, PerStepControl,
    Rattle, Scene,
};

const PRE_STEPS: usize = 50;

fn cantilever(n: usize, base: f64, steps: usize) -> Scene {
    scaled_cantilever(n, base, steps)
}

fn with_current(n: usize, current: Option<Current>) -> Scene {
    let mut s = cantilever(n, 1.0, PRE_STEPS);
    s.loads.drag = 10.0;
    s.loads.current = current;
    s.validate().unwrap();
    s
}

fn steps<const DIM: usize>(scene: &Scene, reps: usize) {
    let chain = Chain::<f64, DIM>::from_scene(scene).unwrap();
    let mut r = Rattle::new(chain, scene.time.step).unwrap();
    let mut st = r.straight_state();
    for k in 0..PRE_STEPS + reps {
        black_box(r.step(black_box(&mut st), k, 0.0, 0.0).unwrap());
    }
}

fn problem(scene: &Scene, effort: f64) -> ControlProblem {
    let map = Parametrisation::PerStep(PerStepControl {
        steps: scene.time.steps,
    });
    let mut o = BendingObjective::summed_moment();
    if effort > 0.0 {
        o = o.with_effort(effort);
    }
    ControlProblem::builder(scene)
        .map(map)
        .objective(o)
        .build_in::<2>()
        .unwrap()
}

fn theta(steps: usize) -> Vec<f64> {
    (0..=steps)
        .map(|k| -1.5 + 0.2 * (k as f64 * 0.1).sin())
        .collect()
}

fn riser_problem(steps: usize) -> ControlProblem {
    let mut scene = catalogue::riser(5);
    scene.time.steps = steps;
    problem(&scene, 0.0)
}

fn long_horizon(steps: usize) -> ControlProblem {
    let mut s = catalogue::long_horizon();
    s.time.steps = steps;
    if let Some(c) = s.control.as_mut() {
        c.values = vec![0.0; steps + 1];
    }
    problem(&s, 0.01)
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let (Some(case), Some(Ok(reps))) = (args.get(1), args.get(2).map(|r| r.parse::<usize>()))
    else {
        eprintln!("usage: bench_probe CASE REPS (the cases: the module docs)");
        std::process::exit(2);
    };
    let case = case.as_str();
    match case {
        "step_planar100" => steps::<2>(&cantilever(100, 1.0, PRE_STEPS), reps),
        "step_still100" => steps::<2>(&with_current(100, None), reps),
        "step_linear100" => steps::<2>(
            &with_current(100, Some(Current::linear(0.5, 0.1, [0.0, 1.0]))),
            reps,
        ),
        "step_table100" => steps::<2>(
            &with_current(
                100,
                Some(Current::table(vec![
                    [0.0, 0.5, 0.0],
                    [5.0, 0.3, 0.0],
                    [10.0, 0.1, 0.0],
                ])),
            ),
            reps,
        ),
        "step_spatial45" => steps::<3>(
            &with_current(100, Some(Current::linear(0.5, 0.1, [1.0, 1.0]))),
            reps,
        ),
        "adj_sim1000" | "adj_grad1000" | "adj_hvp1000" => {
            let p = riser_problem(1000);
            let th = theta(1000);
            let v: Vec<f64> = (0..=1000).map(|k| ((k % 3) as f64) - 1.0).collect();
            for _ in 0..reps {
                match case {
                    "adj_sim1000" => {
                        black_box(p.value(black_box(&th)).unwrap());
                    }
                    "adj_grad1000" => {
                        black_box(p.value_and_gradient(black_box(&th)).unwrap());
                    }
                    _ => {
                        black_box(p.hessian_vec(black_box(&th), black_box(&v)).unwrap());
                    }
                }
            }
        }
        "adj_large_sim1000" | "adj_large_grad1000" | "adj_large_grad100" => {
            let n = if case.ends_with("100") && !case.ends_with("1000") {
                100
            } else {
                1000
            };
            let p = problem(&cantilever(n, 2.0, 100), 0.0);
            let th = theta(100);
            for _ in 0..reps {
                if case.starts_with("adj_large_sim") {
                    black_box(p.value(black_box(&th)).unwrap());
                } else {
                    black_box(p.value_and_gradient(black_box(&th)).unwrap());
                }
            }
        }
        "ocp_forward" | "ocp_jac" | "ocp_riccati" | "ocp_newton" => {
            let steps = 1000;
            let p = long_horizon(steps);
            let th: Vec<f64> = (0..=steps).map(|k| 2.0 * (0.01 * k as f64).sin()).collect();
            let opts = OcpOptions::default().with_bound(5.0);
            let mut s = Solver::new(&p, &opts).unwrap();
            s.set_point(&th).unwrap();
            s.gradient().unwrap();
            for _ in 0..reps {
                match case {
                    "ocp_forward" => {
                        black_box(p.value(black_box(&th)).unwrap());
                    }
                    "ocp_jac" => {
                        s.set_point(black_box(&th)).unwrap();
                        black_box(s.gradient().unwrap());
                    }
                    "ocp_riccati" => {
                        black_box(s.gauss_newton_step(black_box(1e-3)).unwrap());
                    }
                    _ => {
                        black_box(s.newton_step(black_box(1.0)).unwrap());
                    }
                }
            }
        }
        "ocp_solve" => {
            let p = long_horizon(1000);
            let th0 = vec![0.0; 1001];
            let opts = OcpOptions::default().with_bound(5.0);
            for _ in 0..reps {
                let r = solve(&p, black_box(&th0), &opts).unwrap();
                assert!(r.converged);
                black_box(r.objective);
            }
        }
        other => {
            eprintln!("bench_probe: unknown case {other} (the cases: the module docs)");
            std::process::exit(2);
        }
    }
}
