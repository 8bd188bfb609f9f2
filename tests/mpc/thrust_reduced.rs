//! MPC through the vessel's thrust on a reduced planning model (`plan_pendulums` < n with
//! `plan_step`; src/mpc/receding/thrust_plan.rs): the plan's problem is the library's
//! [`ControlProblem`] on the rebuilt stack-up, started from the plant's state mapped onto it.
//!
//! References: forward-mode Dual64 through the same simulation and a five-point central
//! difference (tests/common/gradient_check.rs) for the gradient of the reduced plan's objective;
//! the plant's thrust bounds for the closed loops (the plant clips, the loop reports the peaks);
//! the plant's own chain size for the filter's estimate under `observe = "sensors"`.

use crate::gradient_check::{assert_close, five_point, Tolerance};
use crate::vessel_riser::riser_in_waves;
use chainbeam::adjoint::{forward_value_from, HotSpotObjective, Start};
use chainbeam::fatigue::{MomentMeasure, WellheadDamage};
use chainbeam::mpc::planning::{planning_scene, StateMap};
use chainbeam::mpc::{self, run_closed_loop, Horizon, Mpc, MpcOptions};
use chainbeam::scene::{Forecast, Observe};
use chainbeam::steppers::rattle::{Rattle, State};
use chainbeam::steppers::Stepper;
use chainbeam::*;
use num_dual::Dual64;

/// examples/scenes/riser_300m_system.toml with the vessel's thrust as the control (the documented
/// default vessel mass makes the thrust keys present), its stack-up rebuilt with `n` pendulums
/// at `step`, run for `seconds`: a plant cheaper than the scene's 60 pendulums at 0.004 s.
fn system(n: usize, step: f64, seconds: f64) -> Scene {
    let path = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/examples/scenes/riser_300m_system.toml"
    );
    let mut scene = Scene::from_file(path).unwrap();
    scene.vessel.as_mut().unwrap().mass = Some(chainbeam::scene::DEFAULT_VESSEL_MASS);
    let mut s = planning_scene(&scene, n, step).unwrap();
    s.time.steps = (seconds / step).round() as usize;
    s
}

/// The plant's state after `steps` steps of its sea with no thrust (the vessel's (Z, Ż) in it).
fn plant_state(scene: &Scene, steps: usize) -> State<f64, 2> {
    let mut s = scene.clone();
    s.control = Some(Control {
        node: s.n(),
        kind: ControlKind::Constant,
        values: vec![0.0],
        values_x: None,
    });
    let chain = Chain::<f64, 2>::from_scene(&s).unwrap();
    let mut stepper = Rattle::new(chain, s.time.step).unwrap();
    let mut state = stepper.initial_state(0.0).unwrap();
    for k in 0..steps {
        stepper.step(&mut state, k, 0.0, 0.0).unwrap();
    }
    state
}

/// The system scene's hot spot "conductor below mudline" and its S-N curve's first slope.
fn conductor(s: &Scene) -> (hotspots::HotSpotSpec, f64) {
    let spot = s
        .hotspots
        .iter()
        .find(|h| h.name == "conductor below mudline")
        .expect("the system scene's hot spot")
        .clone();
    let m = WellheadDamage::new(&spot.spec, MomentMeasure::Wellhead)
        .unwrap()
        .exponent();
    (spot, m)
}

/// The references of the gradient of `problem` (four pieces, started from a state) at θ: per
/// component, the forward-mode Dual64 run of the horizon from the problem's start seeded along
/// that piece, and the five-point central difference of J (step 10³ N).
fn references(
    problem: &ControlProblem<PiecewiseControl, HotSpotObjective, 2>,
    theta: [f64; 4],
) -> (Vec<f64>, Vec<f64>) {
    let start = problem.start().expect("a started problem");
    let start = Start {
        state: start.state.lift::<Dual64>(),
        t0: start.t0,
        kick: start.kick,
    };
    let chain = problem.chain().lift::<Dual64>();
    let (h, steps) = (problem.time_step(), problem.steps());
    let (mut forward, mut central) = (Vec::new(), Vec::new());
    for i in 0..theta.len() {
        let th: Vec<Dual64> = (0..4)
            .map(|k| Dual64::new(theta[k], f64::from(u8::from(k == i))))
            .collect();
        let mut u = vec![Dual64::from(0.0); steps + 1];
        problem.map().controls(&th, &mut u);
        let objective = problem.objective();
        let fwd = forward_value_from(&chain, h, steps, &u, objective, Some(&start))
            .unwrap()
            .eps;
        let at = |x: f64| {
            let mut t = theta;
            t[i] = x;
            problem.value(&t).unwrap()
        };
        assert!(fwd.abs() > 0.0, "theta_{i} acts");
        forward.push(fwd);
        central.push(five_point(&at, theta[i], 1e3));
    }
    (forward, central)
}

/// dJ/dθ_j of the reduced thrust plan's objective J = h_p Σ|M|^m + ρ h_p Σ F² (M at the
/// conductor's hot spot on the plan's chain), F held over 4 pieces of 2 s, on a 16-pendulum
/// plan at 0.008 s started from the state of a 24-pendulum plant after 2 s of its sea, mapped
/// by [`StateMap`] (the vessel's (Z, Ż) copied): the adjoint equals forward-mode Dual64 from
/// the same start to 1e-11 and a five-point central difference (step 10³ N) to 1e-6, both of the
/// largest component (the tolerances of tests/mpc/hotspot.rs, whose problem this is but
/// started from a mapped state instead of rest; measured 1.9·10⁻¹² and 4.4·10⁻⁸).
#[test]
fn the_reduced_thrust_plans_gradient_is_exact() {
    let plant = system(24, 0.008, 2.0);
    let state = plant_state(&plant, plant.time.steps);
    assert!(state.tip_target[0].abs() > 0.0, "the vessel moved");
    let mut plan = planning_scene(&plant, 16, 0.008).unwrap();
    plan.time.steps = 1000;
    let mut map = StateMap::<2>::new(&plant, &plan).unwrap();
    let mut mapped = State::straight(16);
    map.map(&state, &mut mapped).unwrap();
    assert_eq!(mapped.tip_target, state.tip_target, "copied one to one");
    let (spot, m) = conductor(&plan);
    let objective = HotSpotObjective::new(&plan, spot.elevation, m, 0.01).unwrap();
    let steps = plan.time.steps;
    let t0 = 2.0;
    let problem = ControlProblem::builder(&plan)
        .map(PiecewiseControl { steps, pieces: 4 })
        .objective(objective)
        .build_in::<2>()
        .unwrap()
        .starting_from(mapped, t0)
        .unwrap();
    let theta = [1.0e6, -0.5e6, 1.5e6, 0.5e6];
    let (j, adjoint) = problem.value_and_gradient(&theta).unwrap();
    println!("J = {j:.6e}, adjoint {adjoint:?}");
    assert!(j.is_finite() && j > 0.0);
    let (forward, central) = references(&problem, theta);
    let scale = forward.iter().fold(0.0f64, |a, g| a.max(g.abs()));
    println!("forward {forward:?}\ncentral {central:?}");
    let source = "forward-mode Dual64 from the mapped start";
    let tol = Tolerance::of_scale(1e-11, scale);
    assert_close("dJ/dθ, adjoint", &adjoint, &forward, source, tol);
    let fd = "dJ/dθ, five-point central difference (step 10³ N)";
    let tol = Tolerance::of_scale(1e-6, scale);
    assert_close(fd, &central, &forward, source, tol);
}

/// A reduced plan through the thrust runs the closed loop with every forecast setting (it was
/// refused before): riser_in_waves' 15 pendulums at 0.05 s planned on 5 at 0.1 s; the plant's
/// thrust stays within its bounds (the plant clips: the loop's peaks are asserted, not tuned).
/// The c_sum against the full plan's are printed (the reduced plan is an approximation).
#[test]
fn a_reduced_plan_runs_through_the_thrust() {
    let s = riser_in_waves(400);
    let limit = s.thrust().unwrap();
    for forecast in [Forecast::Perfect, Forecast::None, Forecast::Noisy] {
        let run = |plan_pendulums, plan_step| {
            let options = MpcOptions {
                horizon: Horizon::Seconds(4.0),
                effort: 0.0,
                plan_pendulums,
                plan_step,
                forecast,
                ..MpcOptions::default()
            };
            let mut c = Mpc::new(&s, 1.0, options).unwrap();
            run_closed_loop(&s, 1.0, &mut c).unwrap()
        };
        let full = run(None, None);
        let reduced = run(Some(5), Some(0.1));
        assert!(reduced.summary.max_abs_control <= limit.bound);
        assert!(reduced.summary.max_abs_control > 0.0, "the plan acts");
        let rate = reduced.summary.thrust_rate_peak.unwrap();
        assert!(rate <= limit.rate_bound * (1.0 + 1e-9), "{rate}");
        println!(
            "{forecast:?}: c_sum full {:.6e}, 5 pendulums at 2h {:.6e} ({:+.1} %)",
            full.summary.c_sum,
            reduced.summary.c_sum,
            100.0 * (reduced.summary.c_sum / full.summary.c_sum - 1.0)
        );
    }
    // A plan step that is not a whole multiple of the plant's is refused at build.
    let options = MpcOptions {
        plan_pendulums: Some(5),
        plan_step: Some(0.075),
        ..MpcOptions::default()
    };
    let e = Mpc::new(&s, 0.15, options).unwrap_err();
    assert!(
        matches!(e, Error::Mpc(mpc::MpcError::ThrustStep { .. })),
        "{e:?}"
    );
}

/// `observe = "sensors"` under a reduced plan: the filter runs on the plant's own chain (its
/// estimate has the plant's 20 pendulums, not the plan's 14) and the plan starts from the
/// estimate mapped onto its chain; the loop runs and acts within the thrust bound.
#[test]
fn sensors_feed_a_reduced_plan_through_the_plants_chain() {
    let s = system(20, 0.008, 2.4);
    let limit = s.thrust().unwrap();
    let options = MpcOptions {
        horizon: Horizon::Seconds(1.6),
        first_iterations: 5,
        thrust_iterations: 2,
        plan_pendulums: Some(14),
        plan_step: Some(0.008),
        observe: Observe::Sensors,
        ..MpcOptions::default()
    };
    let mut mpc = Mpc::new(&s, 0.4, options).unwrap();
    let r = run_closed_loop(&s, 0.4, &mut mpc).unwrap();
    let estimate = mpc.observer().expect("the filter").estimate();
    assert_eq!(estimate.q.len(), 20, "the filter runs on the plant's chain");
    let plan = mpc.last_thrust_plan().expect("a plan");
    assert!(plan.start > 0.0, "a re-plan from the mapped estimate");
    assert!(r.summary.max_abs_control <= limit.bound);
    assert!(r.summary.max_abs_control > 0.0, "the plan acts");
}
