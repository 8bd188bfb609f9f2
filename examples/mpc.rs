//! Receding-horizon control of the riser against waves: the closed loop of
//! `catalogue::mpc_riser` (n = 10, an irregular sea at node 5, 60 s, a decision every 0.1 s)
//! under no control, the best constant force, a tuned PD law on the base moment, MPC with a
//! perfect model and MPC with a wrong model, printed as a table. The MPC rows re-plan with the
//! condensed solver (the default, `MpcSolver::Condensed`); the perfect model is also run with
//! the Riccati solver, for the speed of the two on the same loop.
//!
//! ```sh
//! cargo run --release --example mpc            # 60 s
//! cargo run --release --example mpc -- 20      # the first 20 s only
//! ```
//!
//! The wrong model (`catalogue::mpc_riser_wrong_model`) underestimates the drag by 30 %
//! (D = 7 instead of 10 kg/m), overestimates the current by 20 %, and its forecast misses the
//! sea's 5.3 s component (0.5 N) and underestimates the 8 s wave by 20 %: the
//! controller sees the true state at every decision, but plans with these loads.

use chainbeam::catalogue;
use chainbeam::mpc::{
    run_closed_loop, ConstantForce, Horizon, Mpc, MpcOptions, MpcSolver, NoControl, PdLaw,
    PdTuning, Summary,
};
use chainbeam::ocp::OcpOptions;
use chainbeam::optimize::OptimOptions;

const INTERVAL: f64 = 0.1;
const HORIZON: f64 = 3.0;
const BOUND: f64 = 5.0;
const EFFORT: f64 = 0.01;

fn row(s: &Summary, label: &str) {
    let ms = |x: f64| format!("{:9.2}", 1e3 * x);
    let timing = if s.mean_iterations.is_some() {
        format!(
            "{} {} {:10.1}",
            ms(s.mean_replan_seconds),
            ms(s.worst_replan_seconds),
            s.real_time_factor
        )
    } else {
        format!("{:>9} {:>9} {:>10}", "-", "-", "-")
    };
    println!(
        "{label:<22} {:12.3} {:9.3} {:7.3} {timing}",
        s.c_sum, s.max_abs_moment, s.max_abs_control
    );
}

fn main() -> chainbeam::Result<()> {
    let mut scene = catalogue::mpc_riser();
    if let Some(seconds) = std::env::args().nth(1).and_then(|a| a.parse::<f64>().ok()) {
        scene.time.steps = (seconds / scene.time.step).round() as usize;
    }
    let options = MpcOptions {
        horizon: Horizon::Seconds(HORIZON),
        effort: EFFORT,
        ocp: OcpOptions::default().with_bound(BOUND),
        ..MpcOptions::default()
    };
    let none = run_closed_loop(&scene, INTERVAL, &mut NoControl)?.summary;
    let (mut constant, _) = ConstantForce::best(&scene, BOUND, EFFORT)?;
    let constant = run_closed_loop(&scene, INTERVAL, &mut constant)?.summary;
    let tuning = PdTuning::new(&scene, INTERVAL, BOUND, EFFORT)?;
    let opts = OptimOptions {
        max_iters: 200,
        first_step: 0.01,
        ..OptimOptions::default()
    };
    let (mut pd, _) = PdLaw::tune(&tuning, &[0.0; 3], &opts)?;
    let gains = (pd.bias.z, pd.kp, pd.kd);
    let pd = run_closed_loop(&scene, INTERVAL, &mut pd)?.summary;
    let mut perfect = Mpc::new(&scene, INTERVAL, options.clone())?;
    let perfect = run_closed_loop(&scene, INTERVAL, &mut perfect)?.summary;
    let mut wrong = Mpc::new(
        &catalogue::mpc_riser_wrong_model(),
        INTERVAL,
        options.clone(),
    )?;
    let wrong = run_closed_loop(&scene, INTERVAL, &mut wrong)?.summary;
    let riccati = MpcOptions {
        solver: MpcSolver::Riccati,
        ..options.clone()
    };
    let mut riccati = Mpc::new(&scene, INTERVAL, riccati)?;
    let riccati = run_closed_loop(&scene, INTERVAL, &mut riccati)?.summary;

    let t = scene.time.steps as f64 * scene.time.step;
    println!(
        "mpc_riser: n = {}, {t} s, decisions every {INTERVAL} s, horizon {HORIZON} s, \
         {} Gauss-Newton iterations per re-plan, |u| <= {BOUND} N, rho = {EFFORT}",
        scene.n(),
        options.iterations
    );
    println!(
        "PD gains: u_b = {:.4} N, K_p = {:.4} N/Nm, K_d = {:.4} Ns/Nm",
        gains.0, gains.1, gains.2
    );
    println!(
        "{:<22} {:>12} {:>9} {:>7} {:>9} {:>9} {:>10}",
        "controller", "sum M0^2", "max|M0|", "max|u|", "mean ms", "worst ms", "RT factor"
    );
    for (s, label) in [
        (&none, "no control"),
        (&constant, "best constant force"),
        (&pd, "tuned PD on M0"),
        (&perfect, "MPC, perfect model"),
        (&wrong, "MPC, wrong model"),
        (&riccati, "MPC, perfect, Riccati"),
    ] {
        row(s, label);
    }
    for (s, label) in [(&perfect, "perfect model"), (&wrong, "wrong model")] {
        println!(
            "MPC ({label}): sum M0^2 is {:.1} % of the best constant force's and {:.1} % of the \
             tuned PD law's; first plan {:.1} ms",
            100.0 * s.c_sum / constant.c_sum,
            100.0 * s.c_sum / pd.c_sum,
            1e3 * s.initial_decision_seconds
        );
    }
    println!(
        "Re-plans: the condensed solver takes {:.2}x less time than the Riccati solver on average \
         (worst {:.2}x)",
        riccati.mean_replan_seconds / perfect.mean_replan_seconds,
        riccati.worst_replan_seconds / perfect.worst_replan_seconds
    );
    Ok(())
}
