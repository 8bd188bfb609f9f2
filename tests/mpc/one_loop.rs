//! One closed loop for both models: `run_closed_loop` runs the spatial plant for a spatial scene
//! or for a controller that plans in the spatial model, every controller decides a 2-axis
//! `Force2` (u_x = 0 in a planar scene), and each baseline is one type for both models.
//!
//! References: the riser is the same in every transverse direction, so a scene turned by ψ about
//! the beam's axis is the planar scene turned (the closed loop of MPC turned by 45° is checked in
//! tests/ocp/ocp_spatial.rs), and a PD law with common gains per axis, its bias turned by ψ,
//! decides the planar law's force turned by ψ; a planar scene run in the spatial model has no
//! out-of-plane motion (every x coordinate stays 0, so M₀ₓ = 0) and the planar numbers to
//! round-off.

use chainbeam::mpc::{
    run_closed_loop, ClosedLoopResult, ConstantForce, Force2, Mpc, MpcError, MpcOptions, PdLaw,
    PdTuning,
};
use chainbeam::optimize::{OptimOptions, OptimProblem};
use chainbeam::*;

const INTERVAL: f64 = 0.1;

/// The riser of tests/ocp/ocp_spatial.rs's turned closed loop: the sea and the current in the
/// direction ψ degrees from +z toward +x, 2 s.
fn sea(psi: f64) -> Scene {
    let (s, c) = psi.to_radians().sin_cos();
    let wave = Harmonic {
        amplitude: 2.0,
        period: 8.0,
        phase: 0.0,
    };
    SceneBuilder::new(10)
        .support(Support::Riser)
        .base_stiffness(2000.0)
        .tip_stiffness(2000.0)
        .drag(10.0)
        .current(Current::linear(0.1, 0.02, [s, c]))
        .load(PointLoad::harmonic(5, [s, c], vec![wave]).ramped(2.0))
        .step(0.01)
        .steps(200)
        .build()
        .unwrap()
}

fn rel(a: f64, b: f64) -> f64 {
    (a - b).abs() / b.abs()
}

/// The spatial run `r` is the planar run `r0` turned by ψ: |M₀| and the force per step, the
/// summary's c_sum.
fn assert_turned(r0: &ClosedLoopResult, r: &ClosedLoopResult, psi: f64, tol: f64) {
    let (s, c) = psi.to_radians().sin_cos();
    assert_eq!(
        r.moment_x.len(),
        r0.moment.len(),
        "a spatial run records M₀ₓ"
    );
    assert!(r0.moment_x.is_empty(), "a planar run records no M₀ₓ");
    let mmax = r0.summary.max_abs_moment;
    let umax = r0.summary.max_abs_control.max(1e-300);
    for k in 0..r0.moment.len() {
        let m = r.moment_x[k].hypot(r.moment[k]);
        assert!(
            (m - r0.moment[k].abs()).abs() <= tol * mmax,
            "step {k}: |M₀| {m} against {}",
            r0.moment[k]
        );
        let u = r0.control[k];
        assert!(
            (r.control_x[k] - s * u).abs() <= tol * umax
                && (r.control[k] - c * u).abs() <= tol * umax,
            "step {k}: ({}, {}) against ({}, {})",
            r.control_x[k],
            r.control[k],
            s * u,
            c * u
        );
    }
    assert!(rel(r.summary.c_sum, r0.summary.c_sum) <= tol, "c_sum");
}

/// A PD law with fixed gains through the one loop: in the scene turned by 45° (the spatial
/// model, chosen by the scene) with its bias turned, it is the planar law turned.
#[test]
fn pd_law_in_a_turned_scene_is_the_planar_law_turned() {
    let psi = 45.0;
    let (s, c) = f64::to_radians(psi).sin_cos();
    let law = |bias: Force2| PdLaw {
        bias,
        kp: 0.3,
        kd: 0.03,
        bound: f64::INFINITY,
        spatial: false,
    };
    let r0 = run_closed_loop(&sea(0.0), INTERVAL, &mut law(Force2::z(1.0))).unwrap();
    let turned = Force2 { x: s, z: c };
    let r = run_closed_loop(&sea(psi), INTERVAL, &mut law(turned)).unwrap();
    assert!(r0.summary.max_abs_control > 0.5, "the law acts");
    assert_turned(&r0, &r, psi, 1e-9);
}

/// The baselines find their optimum in the scene's model: the best constant force and the PD
/// gains of the turned scene are the planar ones turned (the force), and the same (the gains).
/// No box is active (|u| ≤ 10³ N against forces of a few N), as a box per component is not
/// rotation-invariant.
#[test]
fn baselines_in_a_turned_scene_are_the_planar_ones_turned() {
    let psi = 45.0;
    let (s, c) = f64::to_radians(psi).sin_cos();
    let (bound, effort) = (1e3, 0.01);
    let (planar, _) = ConstantForce::best(&sea(0.0), bound, effort).unwrap();
    let (spatial, _) = ConstantForce::best(&sea(psi), bound, effort).unwrap();
    assert!(!planar.spatial && spatial.spatial);
    assert_eq!(planar.u.x, 0.0);
    let u = planar.u.z;
    assert!(u.abs() > 0.1, "a current to cancel: {u}");
    assert!(rel(spatial.u.x, s * u) <= 1e-6 && rel(spatial.u.z, c * u) <= 1e-6);

    let tuning0 = PdTuning::new(&sea(0.0), INTERVAL, bound, effort).unwrap();
    let tuning = PdTuning::new(&sea(psi), INTERVAL, bound, effort).unwrap();
    assert_eq!((tuning0.n_params(), tuning.n_params()), (3, 4));
    let opts = OptimOptions {
        max_iters: 50,
        first_step: 0.01,
        ..OptimOptions::default()
    };
    let (pd0, _) = PdLaw::tune(&tuning0, &[0.0; 3], &opts).unwrap();
    let (pd, _) = PdLaw::tune(&tuning, &[0.0; 4], &opts).unwrap();
    assert!(pd.spatial && !pd0.spatial);
    // The closed-loop cost of the turned gains is the planar cost (the same loop turned).
    let turned = [s * pd0.bias.z, c * pd0.bias.z, pd0.kp, pd0.kd];
    let j0 = tuning0.value(&pd0.gains()).unwrap();
    assert!(rel(tuning.value(&turned).unwrap(), j0) <= 1e-9);
    // The spatial tuning reaches no worse a cost than the planar optimum turned.
    assert!(tuning.value(&pd.gains()).unwrap() <= j0 * (1.0 + 1e-6));
    // A wrong number of starting gains is refused, naming them.
    assert!(matches!(
        PdLaw::tune(&tuning, &[0.0; 3], &opts),
        Err(Error::WrongLength { name: "gains", .. })
    ));
}

/// A planar scene runs in the spatial model when the controller plans there
/// (`Controller::spatial`): no out-of-plane motion, and the planar run's numbers to round-off.
#[test]
fn planar_scene_runs_spatial_when_the_controller_asks() {
    let scene = sea(0.0);
    let mut planar = ConstantForce {
        u: Force2::z(1.5),
        spatial: false,
    };
    let mut spatial = ConstantForce {
        u: Force2::z(1.5),
        spatial: true,
    };
    let r0 = run_closed_loop(&scene, INTERVAL, &mut planar).unwrap();
    let r = run_closed_loop(&scene, INTERVAL, &mut spatial).unwrap();
    assert!(
        r.moment_x.iter().all(|m| *m == 0.0),
        "no out-of-plane moment"
    );
    assert!(r.control_x.iter().all(|u| *u == 0.0));
    assert_turned(&r0, &r, 0.0, 1e-12);
}

/// A controller that plans in the other model than the plant's is refused with a typed error
/// naming both, as is an out-of-plane force on a planar plant.
#[test]
fn a_controller_in_the_other_model_is_refused() {
    let options = || MpcOptions {
        horizon: chainbeam::mpc::Horizon::Seconds(0.5),
        ..MpcOptions::default()
    };
    let mut planar = Mpc::new(&sea(45.0), INTERVAL, options()).unwrap();
    match run_closed_loop(&sea(45.0), INTERVAL, &mut planar) {
        Err(Error::Mpc(MpcError::ControllerModel { controller, plant })) => {
            assert_eq!((controller, plant), ("planar", "spatial"));
        }
        other => panic!("expected ControllerModel, got {other:?}"),
    }
    let mut off_plane = ConstantForce {
        u: Force2 { x: 1.0, z: 0.0 },
        spatial: false,
    };
    assert!(matches!(
        run_closed_loop(&sea(0.0), INTERVAL, &mut off_plane),
        Err(Error::NeedsSpatialModel { .. })
    ));
}
