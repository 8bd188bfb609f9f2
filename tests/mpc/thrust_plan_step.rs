//! MPC through the vessel's thrust planning at a coarser step (`plan_step` = r h with the
//! model's own pendulums; src/mpc/receding.rs `coarse_thrust_model`): the plan starts at t_k
//! from the observed state with the applied thrust fixed, and runs the model scene at r h.
//!
//! References: the full-step plan's closed loop on the same scene (the coarse plan is an
//! approximation of it, so the two loops' c_sum are compared and printed, not asserted equal);
//! the plant's clipping (the thrust limits are asserted at every step by the loop itself).

use chainbeam::mpc::{self, Horizon, Mpc, MpcOptions};
use chainbeam::*;

use crate::vessel_riser::riser_in_waves;

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
/// (`MpcError::ThrustStep`). Fewer pendulums: tests/mpc/thrust_reduced.rs.
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
}
