//! The plan's prediction error over one horizon (src/mpc/prediction.rs): at round-off for the
//! plant's own model, above it for a coarser plan, typed errors for a setup it cannot measure;
//! the reduced model of a stack-up held by the vessel (src/mpc/planning.rs).

use chainbeam::mpc::planning::{planning_scene, StateMap};
use chainbeam::mpc::prediction::{
    predict, Forcing, PlanModel, PlantRuns, PredictionError, PredictionSetup,
};
use chainbeam::steppers::Stepper;
use chainbeam::{Chain, Rattle, Scene, State};

/// examples/scenes/riser_300m.toml (the 300 m drilling riser in a current and a JONSWAP sea)
/// as 16 pendulums at h = 0.05 s: the same pipe, loads and sea as a test-sized chain (the
/// planning model's own rebuild, tests/mpc/mpc_planning.rs uses the same).
fn riser() -> Scene {
    let path = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/examples/scenes/riser_300m.toml"
    );
    let scene = Scene::from_file(path).unwrap();
    planning_scene(&scene, 16, 0.05).unwrap()
}

fn setup(plan: PlanModel) -> PredictionSetup {
    PredictionSetup {
        plan,
        horizon: 4.0,
        starts: vec![6.0, 10.0],
        forcing: Forcing {
            interval: 1.0,
            amplitude: 5e4,
            seed: 7,
            rate: None,
        },
        elevation: 0.0,
    }
}

#[test]
fn the_plants_own_model_predicts_it_to_round_off() {
    // Reference: with n_p = n and h_p = h the map is the identity up to round-off and the plan
    // repeats the plant's RATTLE steps with the same controls and sea, so every error is
    // round-off (the brief's bound: < 1e-9).
    let scene = riser();
    let runs = PlantRuns::new(&scene, &setup(PlanModel::Plant)).unwrap();
    for plan in [
        PlanModel::Plant,
        PlanModel::Reduced {
            pendulums: 16,
            step: 0.05,
        },
    ] {
        let r = runs.predict(plan).unwrap();
        assert_eq!(r.starts.len(), 2);
        for s in &r.starts {
            // The references are not zero: the forcing moves the wellhead.
            assert!(s.plant_rms > 1e3 && s.plant_response_rms > 1e2, "{s:?}");
            assert!(
                s.total < 1e-9 && s.response < 1e-9 && s.unforced < 1e-9,
                "{plan:?} {s:?}"
            );
        }
        assert!(r.total < 1e-9 && r.response < 1e-9 && r.unforced < 1e-9);
        assert!(r.forcing_peak <= 5e4 && r.forcing_rms > 0.0);
    }
}

#[test]
fn a_coarser_plan_misses() {
    // Reference: 8 pendulums at 0.1 s are a different discretisation of the same pipe; their
    // moment cannot be the plant's sample for sample (positive error, far above round-off),
    // yet it is the same riser in the same sea (the error stays below 100 % of the moment).
    let scene = riser();
    let r = predict(
        &scene,
        &setup(PlanModel::Reduced {
            pendulums: 8,
            step: 0.1,
        }),
    )
    .unwrap();
    assert_eq!((r.plan_pendulums, r.plan_step), (8, 0.1));
    assert!(
        r.total > 1e-6 && r.response > 1e-6 && r.unforced > 1e-6,
        "{r:?}"
    );
    assert!(r.total < 1.0, "{r:?}");
}

#[test]
fn a_setup_it_cannot_measure_is_a_typed_error() {
    let scene = riser();
    let mut s = setup(PlanModel::Reduced {
        pendulums: 8,
        step: 0.075,
    });
    assert!(matches!(
        predict(&scene, &s),
        Err(PredictionError::StepRatio { .. })
    ));
    s.plan = PlanModel::Reduced {
        pendulums: 8,
        step: 0.1,
    };
    s.starts = vec![6.05];
    assert!(matches!(
        predict(&scene, &s),
        Err(PredictionError::OffGrid { name: "starts", .. })
    ));
    s.starts = vec![];
    assert!(matches!(
        predict(&scene, &s),
        Err(PredictionError::NoStarts)
    ));
    s.starts = vec![6.0];
    s.horizon = f64::NAN;
    assert!(matches!(
        predict(&scene, &s),
        Err(PredictionError::Value {
            name: "horizon",
            ..
        })
    ));
    s.horizon = 4.0;
    s.forcing.amplitude = -1.0;
    assert!(matches!(
        predict(&scene, &s),
        Err(PredictionError::Value {
            name: "amplitude",
            ..
        })
    ));
}

/// examples/scenes/riser_300m_system.toml (the stack-up from the conductor to the vessel) with
/// the vessel's thrust as the control (the documented default vessel), rebuilt with
/// `pendulums` at its own step and run for `seconds`.
fn system(pendulums: usize, seconds: f64) -> Scene {
    let path = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/examples/scenes/riser_300m_system.toml"
    );
    let mut scene = Scene::from_file(path).unwrap();
    scene.vessel.as_mut().unwrap().mass = Some(chainbeam::scene::DEFAULT_VESSEL_MASS);
    let mut s = planning_scene(&scene, pendulums, scene.time.step).unwrap();
    s.time.steps = (seconds / s.time.step).round() as usize;
    s
}

#[test]
fn a_stack_up_plan_keeps_every_piece_and_the_vessels_top() {
    // Reference: the stack-up's own rebuild (Stackup::beam) at n_p keeps the segments' and the
    // bodies' lengths; the map of a moving state onto the coarser chain satisfies the vessel's
    // constraint Σ l_J Q_J,z = Z and its rate exactly (planning.rs, "The tip held by the
    // vessel"), and copies the vessel's state (Z, Ż).
    let fine = system(40, 25.0);
    let coarse = planning_scene(&fine, 24, 0.008).unwrap();
    assert_eq!(coarse.n(), 24);
    let total = |s: &Scene| s.beam.lengths.iter().sum::<f64>();
    assert!((total(&fine) - total(&coarse)).abs() < 1e-9 * total(&fine));
    // Every piece kept: the same part names in the same order.
    let parts = |s: &Scene| {
        let mut p = s.stackup.as_ref().unwrap().layout.parts.clone();
        p.dedup();
        p
    };
    assert_eq!(parts(&fine), parts(&coarse));

    // A state of the fine chain with the vessel moved by its thrust: 25 s under a command of
    // 1 MN (through the rate limit Ḟ_max h per step), so Z and Ż are not the prescribed motion's.
    let mut stepper =
        Rattle::new(Chain::<f64, 2>::from_scene(&fine).unwrap(), fine.time.step).unwrap();
    let rate = fine.thrust().unwrap().rate_bound * fine.time.step;
    let thrust = |k: usize| (k as f64 * rate).min(1e6);
    let mut state = stepper.initial_state(thrust(0)).unwrap();
    for k in 0..fine.time.steps {
        stepper
            .step(&mut state, k, thrust(k), thrust(k + 1))
            .unwrap();
    }
    assert!(
        state.tip_target[1].abs() > 0.0,
        "the vessel moves: {:?}",
        state.tip_target
    );
    let zf: f64 = fine
        .beam
        .lengths
        .iter()
        .zip(&state.q)
        .map(|(l, q)| l * q[1])
        .sum();
    assert!(zf.abs() > 1e-3, "the top moved: Z = {zf}");
    let mut map = StateMap::<2>::new(&fine, &coarse).unwrap();
    let mut out = State::straight(24);
    map.map(&state, &mut out).unwrap();
    let zc: f64 = coarse
        .beam
        .lengths
        .iter()
        .zip(&out.q)
        .map(|(l, q)| l * q[1])
        .sum();
    assert!((zc - zf).abs() < 1e-12 * zf.abs().max(1.0), "{zc} vs {zf}");
    assert_eq!(out.tip_target, state.tip_target);
    for q in &out.q {
        assert!((q[0] * q[0] + q[1] * q[1] - 1.0).abs() < 1e-14);
    }
}
