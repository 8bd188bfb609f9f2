//! Horizons that start from a given state at a given time (`ControlProblem::starting_from`): the
//! tail of a longer run is the problem started from the run's state at step m, at t₀ = m h.
//! Reference: the longer run itself (its value and its adjoint gradient, tested elsewhere against
//! dual numbers), so the numbers compared come from two independent runs of the same map.
//!
//! Starts with the control's half-kick pending (`ControlProblem::starting_before_kick`,
//! `StartKick::Pending`): the given momentum is p̂₀, that of the step into t₀ taken with zero
//! control in its second half-kick, and the horizon's u₀ supplies the half-kick,
//! p₀ = p̂₀ − (h/2) P(q₀)(u₀ b + u_{x,0} b_x). References: the longer run (whose u_m acts on both
//! sides of t_m, as the tail's u₀ now does, so the *whole* tail gradient is the run's), forward-
//! mode dual numbers through the same forward value, and central differences.

use chainbeam::adjoint::{forward_value_from, StartError};
use chainbeam::ocp::{OcpOptions, Solver};
use chainbeam::{
    catalogue, BendingObjective, Chain, Control, ControlKind, ControlMap, ControlProblem, Error,
    Parametrisation, PerStepControl, PiecewiseControl, Rattle, Scene, SceneBuilder, Start,
    StartKick, State, Support,
};
use num_dual::Dual64;

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

/// The fixed-fixed beam with drag D = 10 kg/m (locked tip: the projection has the tip row) cut
/// to `steps` per-step controls at node 3 (a control at the locked tip would be absorbed by the
/// tip constraint).
fn locked(steps: usize) -> Scene {
    let mut s = catalogue::dissipative_fixed_fixed(10.0);
    s.time.steps = steps;
    s.control = Some(Control {
        node: 3,
        kind: ControlKind::PerStep,
        values: vec![0.0; steps + 1],
        values_x: None,
    });
    s
}

fn problem_of(scene: &Scene) -> ControlProblem {
    let map = Parametrisation::PerStep(PerStepControl {
        steps: scene.time.steps,
    });
    let obj = BendingObjective::summed_moment().with_effort(0.01);
    ControlProblem::builder(scene)
        .map(map)
        .objective(obj)
        .build_in::<2>()
        .unwrap()
}

fn problem(steps: usize) -> ControlProblem {
    problem_of(&wave(steps))
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
    run_to(p, u, m, true)
}

/// As [`state_at`], the last step taken with zero control in its second half-kick unless
/// `kicked`: then the state is (q_m, p̂_m), the start of a horizon with the kick pending.
fn run_to(p: &ControlProblem, u: &[f64], m: usize, kicked: bool) -> (State<f64, 2>, f64) {
    let mut r = Rattle::new(p.chain().clone(), p.time_step()).unwrap();
    let mut st = r.straight_state();
    r.prepare(&mut st, 0, u[0]).unwrap();
    let mut head = 0.0;
    for k in 0..m {
        let m0 = p.chain().base_moment(&st.q);
        head += m0 * m0 + 0.01 * p.time_step() * u[k] * u[k];
        let next = if kicked || k + 1 < m { u[k + 1] } else { 0.0 };
        r.step(&mut st, k, u[k], next).unwrap();
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
        matches!(e, Error::Start(StartError::OffManifold { .. })),
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
    let mut along = good.clone();
    along.p[4] = [2.0, 0.0];
    assert!(problem(10).starting_from(along.clone(), 0.0).is_err());
    assert!(problem(10).starting_before_kick(along, 0.0).is_err());
    // A pending kick needs the control as a force term: the reaction-force tip's drives the tip.
    let mut reaction = catalogue::fixed_fixed();
    reaction.beam.reaction_force = true;
    reaction.time.steps = 10;
    let p = problem_of(&reaction);
    assert!(p.clone().starting_from(good.clone(), 0.0).is_ok());
    let e = p.starting_before_kick(good, 0.0).unwrap_err();
    assert!(
        matches!(e, Error::Start(StartError::PendingKickWithReactionTip)),
        "{e}"
    );
}

/// With the kick pending, the tail of a longer run from its (q_m, p̂_m) is the run's tail
/// *including* u₀ = u_m: J_long = head + J_tail and ∂J_tail/∂u_j = ∂J_long/∂u_{m+j} for every
/// j ≥ 0 (to 1e-12: the same map, two independent runs), by the adjoint and by the Riccati
/// solver's costate sweep, on a free tip (the wave riser: drag, a ramped load that depends on
/// t) and a locked one (fixed-fixed with drag: the projection's tip row). The ordinary start
/// from the run's own p_m (the kick built in by the run) gives the same J, and the same
/// gradient except ∂J/∂u₀, which misses the second half-kick.
#[test]
fn pending_kick_tail_equals_the_whole_tail_of_a_longer_run() {
    let (steps, m) = (60, 25);
    let cases = [
        ("wave riser", wave(steps), wave(steps - m)),
        ("fixed-fixed", locked(steps), locked(steps - m)),
    ];
    for (name, scene, tail_scene) in cases {
        let long = problem_of(&scene);
        let u = wiggle(steps + 1);
        let (j_long, g_long) = long.value_and_gradient(&u).unwrap();
        let (hat, head) = run_to(&long, &u, m, false);
        let t0 = m as f64 * long.time_step();
        let tail = problem_of(&tail_scene)
            .starting_before_kick(hat, t0)
            .unwrap();
        assert_eq!(tail.start().unwrap().kick, StartKick::Pending);
        let (j_tail, g_tail) = tail.value_and_gradient(&u[m..]).unwrap();
        let dj = ((head + j_tail) - j_long).abs() / j_long;
        assert!(dj <= 1e-12, "{name}: head + tail J differs by {dj:e}");
        assert!((tail.value(&u[m..]).unwrap() - j_tail).abs() <= 1e-12 * j_tail);
        let d = max_rel_diff(&g_tail, &g_long[m..]);
        println!("{name}: J {dj:.1e}, adjoint gradient {d:.1e}");
        assert!(d <= 1e-12, "{name}: adjoint tail gradient differs by {d:e}");
        if name == "wave riser" {
            // The Riccati solver (free tips only): stage 0 applies the kick, B_0 carries it.
            let mut solver = Solver::new(&tail, &OcpOptions::default()).unwrap();
            solver.set_point(&u[m..]).unwrap();
            let g_ocp = solver.gradient().unwrap();
            let d = max_rel_diff(&g_ocp, &g_long[m..]);
            println!("{name}: ocp costate gradient {d:.1e}");
            assert!(d <= 1e-12, "ocp: tail gradient differs by {d:e}");
            assert!((solver.objective() - j_tail).abs() <= 1e-12 * j_tail);
        }
        // p_m built by the run itself, the ordinary start.
        let (s_m, _) = state_at(&long, &u, m);
        let included = problem_of(&tail_scene).starting_from(s_m, t0).unwrap();
        let (j_inc, g_inc) = included.value_and_gradient(&u[m..]).unwrap();
        assert!(
            (j_inc - j_tail).abs() <= 1e-12 * j_tail,
            "{name}: {j_inc} vs {j_tail}"
        );
        assert!(max_rel_diff(&g_inc[1..], &g_tail[1..]) <= 1e-12);
        let scale = g_tail.iter().fold(0.0f64, |a, x| a.max(x.abs()));
        assert!(
            (g_inc[0] - g_tail[0]).abs() > 1e-6 * scale,
            "{name}: the kick's share of ∂J/∂u₀ is missing: {} vs {}",
            g_inc[0],
            g_tail[0]
        );
    }
}

/// The tail problem of the wave riser with the kick pending and piecewise controls (5 pieces
/// of 5 steps, so u₀ is a piece that acts on many stages).
fn pending_tail() -> (ControlProblem, Vec<f64>) {
    let (steps, m) = (40, 15);
    let long = problem(steps);
    let (hat, _) = run_to(&long, &wiggle(steps + 1), m, false);
    let tail_scene = wave(steps - m);
    let map = Parametrisation::Piecewise(PiecewiseControl {
        steps: steps - m,
        pieces: 5,
    });
    let obj = BendingObjective::summed_moment().with_effort(0.01);
    let tail = ControlProblem::builder(&tail_scene)
        .map(map)
        .objective(obj)
        .build_in::<2>()
        .unwrap()
        .starting_before_kick(hat, m as f64 * long.time_step())
        .unwrap();
    (tail, vec![2.0, -1.0, 3.5, 0.5, -2.5])
}

/// The adjoint gradient of a pending-kick start equals forward-mode dual numbers (`Dual64` with
/// θᵢ seeded, through the forward value the problem's `value` runs, the start lifted with its
/// kick) to 1e-12 relative to ‖∇J‖∞ (both exact to round-off) and central differences (step
/// 10⁻⁶·max(1, |θᵢ|): truncation O(δ²) relative to J's curvature, round-off 10⁻¹⁶ J/δ) to
/// 1e-6, and the Riccati solver's costate gradient to 1e-12; its Hessian-vector product
/// (forward-over-adjoint) equals central differences of the gradient (step 10⁻⁶) to 1e-6
/// relative to ‖Hv‖∞.
#[test]
fn pending_kick_gradient_equals_dual_numbers_and_differences() {
    let (tail, theta) = pending_tail();
    let (j, g) = tail.value_and_gradient(&theta).unwrap();
    let start = tail.start().unwrap();
    let start_d = Start::<Dual64, 2> {
        state: start.state.lift(),
        t0: start.t0,
        kick: start.kick,
    };
    let chain_d = tail.chain_as::<Dual64>();
    let (h, steps) = (tail.time_step(), tail.steps());
    let scale = g.iter().fold(0.0f64, |a, x| a.max(x.abs()));
    for i in 0..theta.len() {
        let th: Vec<Dual64> = theta
            .iter()
            .enumerate()
            .map(|(k, &t)| Dual64::new(t, f64::from(u8::from(k == i))))
            .collect();
        let mut u = vec![Dual64::from(0.0); steps + 1];
        tail.map().controls(&th, &mut u);
        let fwd =
            forward_value_from(&chain_d, h, steps, &u, tail.objective(), Some(&start_d)).unwrap();
        assert!((fwd.re - j).abs() <= 1e-12 * j, "{} vs {j}", fwd.re);
        assert!(
            (g[i] - fwd.eps).abs() <= 1e-12 * scale,
            "θ[{i}]: adjoint {} vs Dual64 {}",
            g[i],
            fwd.eps
        );
        let d = 1e-6 * theta[i].abs().max(1.0);
        let (mut tp, mut tm) = (theta.clone(), theta.clone());
        tp[i] += d;
        tm[i] -= d;
        let fd = (tail.value(&tp).unwrap() - tail.value(&tm).unwrap()) / (2.0 * d);
        assert!(
            (g[i] - fd).abs() <= 1e-6 * scale,
            "θ[{i}]: adjoint {} vs central difference {fd}",
            g[i]
        );
    }
    // The Riccati solver's costate sweep (B_0 with the kick; piecewise: held stages) equals the
    // adjoint to 1e-12 (as tests/ocp/ocp.rs for the ordinary start), also with the Jacobians
    // recomputed in blocks of 7 stages.
    for memory in [1 << 30, 7 * 8 * (400 + 20)] {
        let opts = OcpOptions {
            jacobian_memory: memory,
            ..OcpOptions::default()
        };
        let mut solver = Solver::new(&tail, &opts).unwrap();
        let j_ocp = solver.set_point(&theta).unwrap();
        assert!((j_ocp - j).abs() <= 1e-12 * j, "J {j_ocp} vs {j}");
        let e = max_rel_diff(&solver.gradient().unwrap(), &g);
        assert!(
            e <= 1e-12,
            "memory {memory}: costate gradient off by {e:.2e}"
        );
    }
    let v = [1.0, -0.5, 0.25, 0.8, -1.2];
    let hv = tail.hessian_vec(&theta, &v).unwrap();
    let shift = |s: f64| -> Vec<f64> { theta.iter().zip(&v).map(|(t, x)| t + s * x).collect() };
    let d = 1e-6;
    let (gp, gm) = (
        tail.gradient(&shift(d)).unwrap(),
        tail.gradient(&shift(-d)).unwrap(),
    );
    let hscale = hv.iter().fold(0.0f64, |a, x| a.max(x.abs()));
    for i in 0..theta.len() {
        let fd = (gp[i] - gm[i]) / (2.0 * d);
        assert!(
            (hv[i] - fd).abs() <= 1e-6 * hscale,
            "Hv[{i}]: {} vs {fd}",
            hv[i]
        );
    }
}

/// The Riccati solver and the trust region (the independent second-order method of
/// src/optimize, which evaluates the problem through `value` and `gradient`) reach the same
/// optimum of the pending-kick tail, |u| ≤ 5 N, from u = 0: the solver's stage map and the
/// problem's value are one map.
#[test]
fn pending_kick_optimum_matches_trust_region() {
    use chainbeam::optimize::{minimize, Method, OptimOptions};
    let (tail, _) = pending_tail();
    let x0 = vec![0.0; tail.n_params()];
    let r = chainbeam::ocp::solve(&tail, &x0, &OcpOptions::default().with_bound(5.0)).unwrap();
    assert!(r.converged, "{r:?}");
    let tr_opts = OptimOptions {
        method: Method::TrustRegion,
        bound: Some(5.0),
        ..Default::default()
    };
    let tr = minimize(&tail, &x0, &tr_opts).unwrap();
    let rel = (r.objective - tr.objective).abs() / tr.objective;
    assert!(
        rel <= 1e-9,
        "ocp {} vs trust region {}",
        r.objective,
        tr.objective
    );
    assert!((tail.value(&r.theta).unwrap() - r.objective).abs() <= 1e-12 * r.objective);
}

/// A 2-axis control in the spatial model (drag, an oblique load): with the kick pending both
/// components of u₀ supply it (p₀ = p̂₀ − (h/2) P(q₀)(u_{z,0} b + u_{x,0} b_x)), and the tail's
/// whole gradient, both blocks, is the longer run's (to 1e-12, as in the planar test).
#[test]
fn two_axis_pending_kick_tail_equals_tail_of_longer_run() {
    let (steps, m) = (30, 12);
    let riser = |steps: usize| {
        SceneBuilder::new(10)
            .support(Support::Riser)
            .base_stiffness(2000.0)
            .tip_stiffness(2000.0)
            .drag(10.0)
            .step(0.01)
            .steps(steps)
            .point_load_vector(5, [1.2, 1.6])
            .build()
            .unwrap()
    };
    let spatial = |steps: usize| {
        let map = Parametrisation::PerStep(PerStepControl { steps });
        let obj = BendingObjective::summed_moment().with_effort(0.01);
        ControlProblem::builder(&riser(steps))
            .map(map)
            .objective(obj)
            .two_axis(true)
            .build_in::<3>()
            .unwrap()
    };
    let long = spatial(steps);
    let n1 = steps + 1;
    // θ = (u_x; u_z).
    let theta: Vec<f64> = (0..2 * n1).map(|k| 2.0 * (0.41 * k as f64).sin()).collect();
    let (ux, uz) = theta.split_at(n1);
    let (_, g_long) = long.value_and_gradient(&theta).unwrap();
    // (q_m, p̂_m): the last step's second half-kick without either component.
    let mut chain: Chain<f64, 3> = long.chain().clone();
    let mut ux_hat = ux[..=m].to_vec();
    ux_hat[m] = 0.0;
    chain.set_control_x(&ux_hat).unwrap();
    let mut r = Rattle::new(chain, long.time_step()).unwrap();
    let mut st = r.straight_state();
    r.prepare(&mut st, 0, uz[0]).unwrap();
    for k in 0..m {
        let next = if k + 1 < m { uz[k + 1] } else { 0.0 };
        r.step(&mut st, k, uz[k], next).unwrap();
    }
    let tail = spatial(steps - m)
        .starting_before_kick(st, m as f64 * long.time_step())
        .unwrap();
    let tail_theta = [&ux[m..], &uz[m..]].concat();
    let (_, g_tail) = tail.value_and_gradient(&tail_theta).unwrap();
    let expected = [&g_long[m..n1], &g_long[n1 + m..]].concat();
    let d = max_rel_diff(&g_tail, &expected);
    println!("2-axis adjoint gradient {d:.1e}");
    assert!(d <= 1e-12, "2-axis tail gradient differs by {d:e}");
    // ∂J/∂u_{x,0} and ∂J/∂u_{z,0} by central differences (1e-6 relative to ‖∇J‖∞).
    let scale = g_tail.iter().fold(0.0f64, |a, x| a.max(x.abs()));
    for i in [0, n1 - m] {
        let (mut tp, mut tm) = (tail_theta.clone(), tail_theta.clone());
        tp[i] += 1e-6;
        tm[i] -= 1e-6;
        let fd = (tail.value(&tp).unwrap() - tail.value(&tm).unwrap()) / 2e-6;
        assert!(
            (g_tail[i] - fd).abs() <= 1e-6 * scale,
            "{} vs {fd}",
            g_tail[i]
        );
    }
}
