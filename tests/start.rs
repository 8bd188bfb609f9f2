//! Horizons that start from a given state at a given time (`ControlProblem::starting_from`): the
//! tail of a longer run is the problem started from the run's state at step m, at t₀ = m h.
//! Reference: the longer run itself (its value and its adjoint gradient, tested elsewhere against
//! dual numbers), so the numbers compared come from two independent runs of the same map.

use chainbeam::ocp::{OcpOptions, Solver};
use chainbeam::{
    catalogue, BendingObjective, ControlKind, ControlProblem, Error, Parametrisation,
    PerStepControl, Rattle, Scene, State,
};

/// The wave riser (drag, harmonic load ramped in over 8 s: the loads depend on t) cut to `steps`
/// per-step controls.
fn wave(steps: usize) -> Scene {
    let mut s = catalogue::wave_riser();
    s.time.steps = steps;
    if let Some(c) = s.control.as_mut() {
        c.kind = ControlKind::PerStep;
        c.values = vec![0.0; steps + 1];
    }
    s
}

fn problem(steps: usize) -> ControlProblem {
    let map = Parametrisation::PerStep(PerStepControl { steps });
    let obj = BendingObjective::summed_moment().with_effort(0.01);
    ControlProblem::new(&wave(steps), map, obj).unwrap()
}

/// Deterministic controls of a few newtons.
fn wiggle(len: usize) -> Vec<f64> {
    (0..len)
        .map(|k| 3.0 * (0.37 * k as f64).sin() + 1.5 * (1.3 * k as f64 + 0.2).cos())
        .collect()
}

/// The state after m steps of the long problem's RATTLE run with controls u, and the head cost
/// Σ_{k<m} (M₀(t_k)² + ρ h u_k²) of the stages before it.
fn state_at(p: &ControlProblem, u: &[f64], m: usize) -> (State<f64, 2>, f64) {
    let mut r = Rattle::new(p.chain().clone(), p.time_step()).unwrap();
    let mut st = r.straight_state();
    r.prepare(&mut st, 0, u[0]).unwrap();
    let mut head = 0.0;
    for k in 0..m {
        let m0 = p.chain().base_moment(&st.q);
        head += m0 * m0 + 0.01 * p.time_step() * u[k] * u[k];
        r.step(&mut st, k, u[k], u[k + 1]).unwrap();
    }
    (st, head)
}

fn max_rel_diff(a: &[f64], b: &[f64]) -> f64 {
    let scale = b.iter().fold(0.0f64, |m, x| m.max(x.abs()));
    a.iter()
        .zip(b)
        .fold(0.0f64, |m, (x, y)| m.max((x - y).abs()))
        / scale
}

/// J_long = head + J_tail, and ∂J_tail/∂u_j = ∂J_long/∂u_{m+j} for j ≥ 1 (u_0 of the tail acts
/// on p_m in the long run, which the tail holds fixed), by the adjoint, the Hessian-free
/// forward value, and the Riccati solver's costate sweep.
#[test]
fn tail_problem_equals_tail_of_longer_run() {
    let (steps, m) = (60, 25);
    let long = problem(steps);
    let u = wiggle(steps + 1);
    let (j_long, g_long) = long.value_and_gradient(&u).unwrap();
    let (s_m, head) = state_at(&long, &u, m);
    let t0 = m as f64 * long.time_step();
    let tail = problem(steps - m).starting_from(s_m, t0).unwrap();
    let (j_tail, g_tail) = tail.value_and_gradient(&u[m..]).unwrap();
    assert!(
        ((head + j_tail) - j_long).abs() <= 1e-12 * j_long,
        "{} vs {j_long}",
        head + j_tail
    );
    assert!((tail.value(&u[m..]).unwrap() - j_tail).abs() <= 1e-12 * j_tail);
    let d = max_rel_diff(&g_tail[1..], &g_long[m + 1..]);
    assert!(d <= 1e-12, "adjoint: tail gradient differs by {d:e}");
    // The Riccati solver's costate sweep on the tail problem (its own rollout from S_m at t₀).
    let mut solver = Solver::new(&tail, &OcpOptions::default()).unwrap();
    solver.set_point(&u[m..]).unwrap();
    let g_ocp = solver.gradient().unwrap();
    let d = max_rel_diff(&g_ocp[1..], &g_long[m + 1..]);
    assert!(d <= 1e-12, "ocp: tail gradient differs by {d:e}");
    assert!((solver.objective() - j_tail).abs() <= 1e-12 * j_tail);
    // The start time matters: the same state at t₀ = 0 sees a different (ramped) load.
    let (s_m, _) = state_at(&long, &u, m);
    let shifted = problem(steps - m).starting_from(s_m, 0.0).unwrap();
    let g0 = shifted.gradient(&u[m..]).unwrap();
    assert!(max_rel_diff(&g0[1..], &g_long[m + 1..]) > 1e-6);
}

/// Both solvers of the tail problem reach the same optimum, |u| ≤ 5 N as in the long-horizon
/// example: the Riccati solver's, and the trust region's, from u = 0 (reference: the
/// independent second-order method of src/optimize).
#[test]
fn tail_optimum_matches_trust_region() {
    use chainbeam::optimize::{minimize, Method, OptimOptions};
    let tr_opts = OptimOptions {
        method: Method::TrustRegion,
        bound: Some(5.0),
        ..Default::default()
    };
    let (steps, m) = (40, 15);
    let long = problem(steps);
    let (s_m, _) = state_at(&long, &wiggle(steps + 1), m);
    let tail = problem(steps - m)
        .starting_from(s_m, m as f64 * long.time_step())
        .unwrap();
    let x0 = vec![0.0; steps - m + 1];
    let opts = OcpOptions::default().with_bound(5.0);
    let r = chainbeam::ocp::solve(&tail, &x0, &opts).unwrap();
    assert!(r.converged, "{r:?}");
    let tr = minimize(&tail, &x0, &tr_opts).unwrap();
    let rel = (r.objective - tr.objective).abs() / tr.objective;
    assert!(
        rel <= 1e-9,
        "ocp {} vs trust region {}",
        r.objective,
        tr.objective
    );
}

/// Bad starts are refused with typed errors naming the quantity.
#[test]
fn bad_starts_are_refused() {
    let p = problem(10);
    let n = p.chain().n();
    let nc = p.chain().n_constraints();
    let good = State::<f64, 2>::straight(n);
    let mut short = good.clone();
    short.q.pop();
    assert!(matches!(
        problem(10).starting_from(short, 0.0),
        Err(Error::WrongLength {
            name: "initial state q",
            ..
        })
    ));
    let mut nan = good.clone();
    nan.p[3][1] = f64::NAN;
    assert!(matches!(
        problem(10).starting_from(nan, 0.0),
        Err(Error::NotFinite {
            name: "initial state p",
            index: 7
        })
    ));
    assert!(matches!(
        problem(10).starting_from(good.clone(), f64::INFINITY),
        Err(Error::NotFinite {
            name: "start time",
            ..
        })
    ));
    let mut off = good.clone();
    off.q[2] = [1.01, 0.0];
    let e = problem(10).starting_from(off, 0.0).unwrap_err();
    assert!(
        matches!(
            e,
            Error::InvalidArgument {
                name: "initial state",
                ..
            }
        ),
        "{e}"
    );
    // Multipliers of the wrong length (n + 1 where the free tip has n).
    let mut long = good.clone();
    long.multipliers_mut(nc + 1);
    assert!(matches!(
        problem(10).starting_from(long, 0.0),
        Err(Error::WrongLength {
            name: "initial state lambda",
            ..
        })
    ));
    // A momentum along the pendulum (qᵢ·vᵢ ≠ 0) violates the hidden constraint.
    let mut along = good;
    along.p[4] = [2.0, 0.0];
    assert!(problem(10).starting_from(along, 0.0).is_err());
}
