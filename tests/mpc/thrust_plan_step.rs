//! MPC through the vessel's thrust planning at a coarser step (`plan_step` = r h with the
//! model's own pendulums; src/mpc/receding.rs `coarse_thrust_model`): the plan starts at t_k
//! from the observed state with the applied thrust fixed, and runs the model scene at r h.
//!
//! References: the full-step plan's closed loop on the same scene (the coarse plan is an
//! approximation of it, so the two loops' c_sum are compared and printed, not asserted equal);
//! the plant's clipping (the thrust limits are asserted at every step by the loop itself).

use chainbeam::mpc::{self, Horizon, Mpc, MpcOptions};
use chainbeam::*;

/// riser_300m.toml's pipe and sea at n = 15, h = 0.05 s, held by a drillship-sized vessel
/// whose thrust is the control (tests/mpc/mpc_vessel.rs's `riser_in_waves`).
fn riser_in_waves(steps: usize) -> Scene {
    let path = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/examples/scenes/riser_300m.toml"
    );
    let text = std::fs::read_to_string(path).unwrap();
    let text = text.split("\n[mpc]\n").next().unwrap().to_string()
        + "\n[fatigue]\nouter_diameter = 0.5334\nwall_thickness = 0.022225\ncurve = \"F1\"\n";
    let text = text
        .replace("pendulums = 80", "pendulums = 15")
        .replace("support = \"riser\"", "support = \"vessel\"")
        .replace("step = 0.0125", "step = 0.05")
        .replace("steps = 48000 ", &format!("steps = {steps} "))
        .replace("drag = 4.0020e-7 ", "drag = 7.504e-8 ")
        + "\n[vessel]\noffset = 3.0\nramp = 5.0\nmass = 5e7\nadded_mass = 5e6\ndamping = 1e5\n\
           thrust_bound = 2e6\nthrust_rate_bound = 2e5\n";
    Scene::from_toml_str(&text).unwrap()
}

fn run(s: &Scene, plan_step: Option<f64>) -> mpc::ClosedLoopResult {
    let options = MpcOptions {
        horizon: Horizon::Seconds(4.0),
        effort: 0.0,
        plan_step,
        ..MpcOptions::default()
    };
    let mut c = Mpc::new(s, 1.0, options).unwrap();
    mpc::run_closed_loop(s, 1.0, &mut c).unwrap()
}

/// `plan_step` = 2h runs through the thrust (it was refused as a reduced plan); `plan_step` = h
/// is the full plan bit for bit; a step that is not a multiple of h is refused naming the model
/// (`MpcError::ThrustStep`); fewer pendulums are still refused (`ThrustPlanReduced`).
#[test]
fn a_coarser_plan_step_plans_through_the_thrust() {
    let s = riser_in_waves(400);
    let full = run(&s, None);
    let same = run(&s, Some(0.05));
    assert_eq!(full.control, same.control, "plan_step = h is the full plan");
    let coarse = run(&s, Some(0.1));
    let limit = s.thrust().unwrap();
    assert!(coarse.summary.max_abs_control <= limit.bound);
    let rate = coarse.summary.thrust_rate_peak.unwrap();
    assert!(rate <= limit.rate_bound * (1.0 + 1e-9), "{rate}");
    println!(
        "c_sum full {:.6e}, plan_step 2h {:.6e} ({:+.2} %); mean re-plan {:.3} s against {:.3} s",
        full.summary.c_sum,
        coarse.summary.c_sum,
        100.0 * (coarse.summary.c_sum / full.summary.c_sum - 1.0),
        coarse.summary.mean_replan_seconds,
        full.summary.mean_replan_seconds
    );
    let e = Mpc::new(
        &s,
        1.0,
        MpcOptions {
            plan_step: Some(0.075),
            ..MpcOptions::default()
        },
    )
    .unwrap_err();
    assert!(
        matches!(e, Error::Mpc(mpc::MpcError::ThrustStep { .. })),
        "{e:?}"
    );
    let e = Mpc::new(
        &s,
        1.0,
        MpcOptions {
            plan_pendulums: Some(5),
            plan_step: Some(0.1),
            ..MpcOptions::default()
        },
    )
    .unwrap_err();
    assert!(
        matches!(e, Error::Mpc(mpc::MpcError::ThrustPlanReduced)),
        "{e:?}"
    );
}
