//! MPC's reduced planning model (src/mpc/planning.rs): the coarser chain of the same pipe, the
//! map of a plant's state onto it, the closed loop that plans on it, its refusals; and the best
//! constant force by the condensed solver against the Riccati solver.

use chainbeam::mpc::planning::{planning_scene, StateMap};
use chainbeam::mpc::{
    run_closed_loop, ConstantForce, Horizon, Mpc, MpcError, MpcOptions, NoControl,
};
use chainbeam::ocp::{self, OcpOptions};
use chainbeam::{
    catalogue, BendingObjective, Chain, ControlProblem, Error, PiecewiseControl, Scene, State,
};

/// examples/scenes/riser_300m.toml (the 300 m drilling riser in a current and a JONSWAP sea)
/// at n = 16 pendulums, h = 0.05 s and 20 s: the same pipe, loads and sea, a test-sized chain
/// (its fastest mode, ω ≈ 4√(EI/(μ l⁴)) ≈ 6 rad/s at l = 18.75 m, allows the step). The drag
/// constant follows the scene's rule D ∝ n (its header).
fn riser(n: usize, step: f64, seconds: f64) -> Scene {
    let path = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/examples/scenes/riser_300m.toml"
    );
    let scene = Scene::from_file(path).unwrap();
    let mut coarse = planning_scene(&scene, n, step).unwrap();
    coarse.time.steps = (seconds / step).round() as usize;
    coarse
}

/// A state of the plant's chain: the riser after `seconds` of its sea.
fn moving_state(scene: &Scene, seconds: f64) -> State<f64, 2> {
    let mut s = scene.clone();
    s.time.steps = (seconds / s.time.step).round() as usize;
    let any = chainbeam::simulate(&s).unwrap();
    let traj = any.as_planar().unwrap();
    let k = traj.steps();
    State {
        q: traj.q(k).to_vec(),
        p: traj.p(k).to_vec(),
        multipliers: None,
        tip_target: [0.0; 2],
    }
}

#[test]
fn the_map_onto_the_same_chain_is_the_identity() {
    // Reference: the identity (a model of n pendulums at the plant's step is the plant's chain).
    let scene = riser(16, 0.05, 20.0);
    let state = moving_state(&scene, 12.0);
    let same = planning_scene(&scene, 16, 0.05).unwrap();
    let mut map = StateMap::<2>::new(&scene, &same).unwrap();
    let mut out = State::straight(16);
    map.map(&state, &mut out).unwrap();
    let pmax = state.p.iter().flatten().fold(0.0f64, |a, x| a.max(x.abs()));
    assert!(pmax > 0.0);
    for i in 0..16 {
        for d in 0..2 {
            assert!((out.q[i][d] - state.q[i][d]).abs() < 1e-13, "q[{i}][{d}]");
            assert!(
                (out.p[i][d] - state.p[i][d]).abs() < 1e-11 * pmax,
                "p[{i}][{d}]: {} vs {}",
                out.p[i][d],
                state.p[i][d]
            );
        }
    }
}

#[test]
fn a_rigid_rotation_maps_onto_the_same_rotation() {
    // Reference, closed form: a straight chain tilted at α and turning at ω about its base has
    // every attitude q = (sin α, cos α) and q̇ = ω (cos α, −sin α); so must the coarse chain.
    let scene = riser(16, 0.05, 20.0);
    let coarse = planning_scene(&scene, 4, 0.2).unwrap();
    let (alpha, omega) = (0.03f64, 0.2f64);
    let q = [alpha.sin(), alpha.cos()];
    let qdot = [omega * alpha.cos(), -omega * alpha.sin()];
    let fine = Chain::<f64, 2>::from_scene(&scene).unwrap();
    let mut state = State::straight(16);
    state.q = vec![q; 16];
    fine.apply_mass(&vec![qdot; 16], &mut state.p);
    let mut map = StateMap::<2>::new(&scene, &coarse).unwrap();
    let mut out = State::straight(4);
    map.map(&state, &mut out).unwrap();
    let chain = Chain::<f64, 2>::from_scene(&coarse).unwrap();
    let mut expected = vec![[0.0; 2]; 4];
    chain.apply_mass(&[qdot; 4], &mut expected);
    for j in 0..4 {
        for d in 0..2 {
            assert!((out.q[j][d] - q[d]).abs() < 1e-14, "Q[{j}][{d}]");
            let scale = expected
                .iter()
                .flatten()
                .fold(0.0f64, |a, x| a.max(x.abs()));
            assert!(
                (out.p[j][d] - expected[j][d]).abs() < 1e-12 * scale,
                "P[{j}][{d}]: {} vs {}",
                out.p[j][d],
                expected[j][d]
            );
        }
    }
}

#[test]
fn the_coarse_state_keeps_the_model_constraints_and_the_sampled_nodes() {
    // Reference: the plant's own node positions (Chain::node_positions) at every 4th node, and
    // the model's constraints |Q_J| = 1, Q_J·Q̇_J = 0 (q̇ = M⁻¹p of the model's chain).
    let scene = riser(16, 0.05, 20.0);
    let coarse = planning_scene(&scene, 4, 0.2).unwrap();
    let state = moving_state(&scene, 12.0);
    let mut map = StateMap::<2>::new(&scene, &coarse).unwrap();
    let mut out = State::straight(4);
    map.map(&state, &mut out).unwrap();
    let (fine, chain) = (
        Chain::<f64, 2>::from_scene(&scene).unwrap(),
        Chain::<f64, 2>::from_scene(&coarse).unwrap(),
    );
    let mut nodes = vec![[0.0; 2]; 16];
    fine.node_positions(&state.q, &mut nodes);
    let mut qdot = vec![[0.0; 2]; 4];
    chain.apply_inverse_mass(&out.p, &mut qdot);
    let mut prev = [0.0; 2];
    for j in 0..4 {
        let node = nodes[4 * j + 3];
        let chord = [node[0] - prev[0], node[1] - prev[1]];
        let len = chord[0].hypot(chord[1]);
        assert!((out.q[j][0].hypot(out.q[j][1]) - 1.0).abs() < 1e-14);
        assert!((out.q[j][0] - chord[0] / len).abs() < 1e-12, "Q[{j}]");
        assert!((out.q[j][1] - chord[1] / len).abs() < 1e-12, "Q[{j}]");
        let dot = out.q[j][0] * qdot[j][0] + out.q[j][1] * qdot[j][1];
        assert!(dot.abs() < 1e-12 * qdot[j][0].hypot(qdot[j][1]).max(1e-300));
        prev = node;
    }
}

#[test]
fn mpc_on_a_reduced_model_controls_the_full_plant() {
    // The plant at n = 32, h = 0.025 s; the plan on n = 16 at h = 0.1 s (an eighth of the work
    // per step and pendulum) over 20 s, about the riser's first natural period (≈ 19 s: a
    // horizon much shorter is myopic; with the full model at n = 16, 8 s left c_sum 32× above
    // no control over 60 s, 20 s 6.5× below). It must do what a controller is for: reduce c_sum
    // below no control (measured 0.48×, the full-model planner 0.44×; the bar is 0.75×).
    // Pendulums of 25 m or more (n_p = 12 here) are too coarse for this riser: the plan then
    // saturates the force and c_sum grows 28× (src/mpc/planning.rs).
    let plant = riser(32, 0.025, 20.0);
    let options = MpcOptions {
        horizon: Horizon::Seconds(20.0),
        effort: 1e-4,
        ocp: OcpOptions::default().with_bound(2e5),
        plan_pendulums: Some(16),
        plan_step: Some(0.1),
        ..MpcOptions::default()
    };
    let mut mpc = Mpc::new(&plant, 0.5, options).unwrap();
    let controlled = run_closed_loop(&plant, 0.5, &mut mpc).unwrap();
    let free = run_closed_loop(&plant, 0.5, &mut NoControl).unwrap();
    assert!(controlled.summary.max_abs_control <= 2e5);
    assert!(
        controlled.summary.c_sum < 0.75 * free.summary.c_sum,
        "{} vs {}",
        controlled.summary.c_sum,
        free.summary.c_sum
    );
}

#[test]
fn bad_planning_models_are_refused_by_name() {
    let plant = riser(16, 0.05, 20.0);
    let with = |pendulums, step| MpcOptions {
        plan_pendulums: pendulums,
        plan_step: step,
        ..MpcOptions::default()
    };
    let argument = |scene: &Scene, o: MpcOptions| match Mpc::new(scene, 0.5, o) {
        Err(Error::Mpc(e)) => (e.argument(), e),
        other => panic!("expected an MpcError, got {other:?}"),
    };
    let (name, e) = argument(&plant, with(Some(0), None));
    assert_eq!(name, "plan_pendulums");
    assert!(matches!(
        e,
        MpcError::PlanPendulums {
            pendulums: 0,
            n: 16
        }
    ));
    let (name, _) = argument(&plant, with(Some(17), None));
    assert_eq!(name, "plan_pendulums");
    let (name, _) = argument(&plant, with(Some(8), Some(-0.1)));
    assert_eq!(name, "plan_step");
    // 0.5 s is not a multiple of 0.3 s.
    let (name, _) = argument(&plant, with(Some(8), Some(0.3)));
    assert_eq!(name, "interval");
    // No [pipe] to rebuild the chain from.
    let (name, e) = argument(&catalogue::mpc_riser(), with(Some(5), None));
    assert_eq!(name, "plan_pendulums");
    assert!(matches!(e, MpcError::PlanWithoutPipe));
}

#[test]
fn the_best_constant_force_by_the_condensed_solver_is_the_riccati_solvers() {
    // Reference: the Riccati solver on the same one-piece problem (an independent method).
    let scene = riser(16, 0.05, 20.0);
    let (c, r) = ConstantForce::best(&scene, 2e5, 1e-4).unwrap();
    let map = PiecewiseControl {
        steps: scene.time.steps,
        pieces: 1,
    };
    let objective = BendingObjective::summed_moment().with_effort(1e-4);
    let problem = ControlProblem::builder(&scene)
        .map(map)
        .objective(objective)
        .build_in::<2>()
        .unwrap();
    let riccati = ocp::solve(&problem, &[0.0], &OcpOptions::default().with_bound(2e5)).unwrap();
    assert!(r.converged && riccati.converged);
    assert!(c.u.z.abs() > 1.0, "a current to cancel: u = {}", c.u.z);
    assert!(
        (c.u.z - riccati.theta[0]).abs() < 1e-6 * c.u.z.abs(),
        "{} vs {}",
        c.u.z,
        riccati.theta[0]
    );
}
