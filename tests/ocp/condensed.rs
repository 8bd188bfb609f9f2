//! The condensed Gauss-Newton solver (`chainbeam::ocp::Condensed`): its gradient against the
//! discrete adjoint, its Gauss-Newton Hessian against the one assembled from the Riccati
//! solver's stage Jacobians (an independent derivation: stage-wise dual numbers and products of
//! A_k, against dual numbers carried along the whole horizon), its optima against the Riccati
//! solver's, bounds, a moving start, and honest failure.

use crate::table_3_4;

use chainbeam::ocp::{Condensed, OcpError, OcpOptions, OcpTermination, Solver};
use chainbeam::optimize::{minimize, riccati_options, Method, OptimOptions};
use chainbeam::{
    catalogue, BendingObjective, ControlProblem, Parametrisation, PerStepControl, PiecewiseControl,
    Scene,
};

/// `mpc_riser` (riser, D = 10, sea at node 5, sheared current) cut to `steps` steps from t = 0.
fn mpc_scene(steps: usize) -> Scene {
    let mut s = catalogue::mpc_riser();
    s.time.steps = steps;
    s
}

fn wiggle(len: usize, amp: f64) -> Vec<f64> {
    (0..len)
        .map(|k| amp * ((0.37 * k as f64).sin() + 0.5 * (1.3 * k as f64 + 0.2).cos()))
        .collect()
}

fn max_rel_diff(a: &[f64], b: &[f64]) -> f64 {
    let d = a
        .iter()
        .zip(b)
        .fold(0.0f64, |m, (x, y)| m.max((x - y).abs()));
    d / b.iter().fold(0.0f64, |m, x| m.max(x.abs()))
}

fn problems() -> Vec<(
    String,
    ControlProblem<Parametrisation, BendingObjective>,
    f64,
)> {
    let piecewise = |steps, pieces| Parametrisation::Piecewise(PiecewiseControl { steps, pieces });
    let per_step = |steps| Parametrisation::PerStep(PerStepControl { steps });
    let sum = BendingObjective::summed_moment().with_effort(0.01);
    let fin = BendingObjective::final_moment();
    vec![
        (
            "mpc_riser, 12 pieces of 10 steps, c_sum + effort".into(),
            ControlProblem::builder(&mpc_scene(120))
                .map(piecewise(120, 12))
                .objective(sum)
                .build_in::<2>()
                .unwrap(),
            0.0,
        ),
        (
            "mpc_riser, 12 pieces, rate penalty 0.05".into(),
            ControlProblem::builder(&mpc_scene(120))
                .map(piecewise(120, 12))
                .objective(sum)
                .build_in::<2>()
                .unwrap(),
            0.05,
        ),
        (
            "thesis riser, per-step N = 10, c".into(),
            ControlProblem::builder(&catalogue::riser(5))
                .map(per_step(10))
                .objective(fin)
                .build_in::<2>()
                .unwrap(),
            0.0,
        ),
    ]
}

/// The gradient of the condensed model is the discrete adjoint's (`ControlProblem::gradient`,
/// itself tested against forward duals) to 1e-12 relative; its Gauss-Newton Hessian equals the
/// dense one assembled from the Riccati solver's stage Jacobians (`Solver::dense_gauss_newton`)
/// to 1e-10 relative, and so does its gradient (with the rate penalty, which the adjoint's J
/// does not carry).
#[test]
fn gradient_and_hessian_equal_independent_derivations() {
    for (name, p, rate) in problems() {
        let opts = OcpOptions {
            rate_penalty: rate,
            ..OcpOptions::default()
        };
        let theta = wiggle(p.n_params(), 1.5);
        let mut c = Condensed::new(&p, &opts).unwrap();
        c.set_point(&theta).unwrap();
        let (h, g) = c.gauss_newton().unwrap();
        let mut s = Solver::new(&p, &opts).unwrap();
        s.set_point(&theta).unwrap();
        let (h_ref, g_ref) = s.dense_gauss_newton().unwrap();
        if rate == 0.0 {
            let adj = p.gradient(&theta).unwrap();
            let e = max_rel_diff(&g, &adj);
            assert!(e <= 1e-12, "{name}: gradient vs adjoint {e:.2e}");
        }
        let e = max_rel_diff(&g, &g_ref);
        assert!(e <= 1e-10, "{name}: gradient vs Riccati's dense GN {e:.2e}");
        let np = p.n_params();
        let flat = |m: &faer::Mat<f64>| -> Vec<f64> {
            (0..np * np).map(|i| m[(i / np, i % np)]).collect()
        };
        let e = max_rel_diff(&flat(&h), &flat(&h_ref));
        assert!(
            e <= 1e-10,
            "{name}: GN Hessian vs Riccati's dense GN {e:.2e}"
        );
    }
}

/// From u = 0 to the projected-gradient tolerance, the condensed solver and the Riccati solver
/// reach the same optimum (the same Gauss-Newton model, different linear algebra and line
/// search: J to 1e-9 relative, θ to 1e-5 of its largest entry), with a few and with most
/// controls on a bound; no control leaves the box. The long-horizon scene (riser, D = 10,
/// F = 2 N at node 5) cut to 120 steps, 12 pieces: measured J 1534.4736034157 (|u| ≤ 5 N) and
/// 3883.6249299814 (|u| ≤ 0.5 N) by both.
#[test]
fn optimum_equals_riccati_solvers() {
    let mut scene = catalogue::long_horizon();
    scene.time.steps = 120;
    if let Some(c) = scene.control.as_mut() {
        c.values = vec![0.0; 121];
    }
    let map = Parametrisation::Piecewise(PiecewiseControl {
        steps: 120,
        pieces: 12,
    });
    let p = ControlProblem::builder(&scene)
        .map(map)
        .objective(BendingObjective::summed_moment().with_effort(0.01))
        .build_in::<2>()
        .unwrap();
    for bound in [5.0, 0.5] {
        let opts = OcpOptions::default().with_bound(bound);
        let zero = vec![0.0; p.n_params()];
        let rc = Condensed::new(&p, &opts).unwrap().solve(&zero).unwrap();
        let rr = Solver::new(&p, &opts).unwrap().solve(&zero).unwrap();
        assert!(rc.converged && rr.converged, "bound {bound}: {rc:?}");
        assert!(rc.projected_gradient_norm <= 1e-8 * rc.initial_gradient_norm);
        let dj = (rc.objective - rr.objective).abs() / rr.objective;
        assert!(
            dj <= 1e-9,
            "bound {bound}: J {} vs {}",
            rc.objective,
            rr.objective
        );
        let e = max_rel_diff(&rc.theta, &rr.theta);
        assert!(e <= 1e-5, "bound {bound}: theta off by {e:.2e}");
        assert!(rc.theta.iter().all(|t| t.abs() <= bound));
        assert!(
            !rc.active_bounds.is_empty(),
            "bound {bound} should be active"
        );
    }
}

/// A horizon from a moving state with the control's half-kick pending (the receding horizon of
/// `chainbeam::mpc`): the gradient is still the adjoint's to 1e-12.
#[test]
fn moving_start_gradient_equals_adjoint() {
    let scene = mpc_scene(400);
    let mut plant = chainbeam::mpc::Plant::<f64>::new(&scene).unwrap();
    for _ in 0..250 {
        plant.advance().unwrap();
    }
    plant.update_state_before_kick().unwrap();
    let hat = plant.state_before_kick().unwrap().clone();
    let tail = mpc_scene(100);
    let map = Parametrisation::Piecewise(PiecewiseControl {
        steps: 100,
        pieces: 10,
    });
    let p = ControlProblem::builder(&tail)
        .map(map)
        .objective(BendingObjective::summed_moment().with_effort(0.01))
        .build_in::<2>()
        .unwrap()
        .starting_before_kick(hat, plant.time())
        .unwrap();
    let theta = wiggle(10, 1.0);
    let mut c = Condensed::new(&p, &OcpOptions::default()).unwrap();
    c.set_point(&theta).unwrap();
    let (_, g) = c.gauss_newton().unwrap();
    let e = max_rel_diff(&g, &p.gradient(&theta).unwrap());
    assert!(e <= 1e-12, "gradient vs adjoint {e:.2e}");
}

/// An iteration budget ends the run as `MaxIterations` (not converged), and `Budget` without the
/// final gradient; wrong θ is a typed error.
#[test]
fn budget_and_errors_are_reported() {
    let (_, p, _) = problems().swap_remove(0);
    let zero = vec![0.0; p.n_params()];
    let opts = OcpOptions {
        max_iters: 1,
        ..OcpOptions::default()
    };
    let r = Condensed::new(&p, &opts).unwrap().solve(&zero).unwrap();
    assert!(!r.converged);
    assert_eq!(r.termination, OcpTermination::MaxIterations);
    let rt = Condensed::new(
        &p,
        &OcpOptions {
            final_gradient: false,
            ..opts
        },
    )
    .unwrap()
    .solve(&zero)
    .unwrap();
    assert_eq!(rt.termination, OcpTermination::Budget);
    assert_eq!(rt.theta, r.theta, "the same step, bit for bit");
    assert_eq!(rt.jacobian_passes + 1, r.jacobian_passes);
    let mut c = Condensed::new(&p, &OcpOptions::default()).unwrap();
    assert!(c.set_point(&[0.0; 3]).is_err());
    assert!(c.set_point(&vec![f64::NAN; p.n_params()]).is_err());
}

/// A solver moved to another start (`Condensed::restart`, as the receding horizon re-plans)
/// gives bit for bit the result of a solver built for that start; a problem of another horizon
/// is refused naming `problem`.
#[test]
fn restart_equals_a_fresh_solver() {
    let scene = mpc_scene(200);
    let mut plant = chainbeam::mpc::Plant::<f64>::new(&scene).unwrap();
    for _ in 0..150 {
        plant.advance().unwrap();
    }
    plant.update_state_before_kick().unwrap();
    let hat = plant.state_before_kick().unwrap().clone();
    let map = Parametrisation::Piecewise(PiecewiseControl {
        steps: 50,
        pieces: 5,
    });
    let obj = BendingObjective::summed_moment().with_effort(0.01);
    let at_rest = ControlProblem::builder(&mpc_scene(50))
        .map(map)
        .objective(obj)
        .build_in::<2>()
        .unwrap();
    let moving = at_rest
        .clone()
        .starting_before_kick(hat, plant.time())
        .unwrap();
    let opts = OcpOptions::default().with_bound(5.0);
    let theta = wiggle(5, 0.5);
    let mut reused = Condensed::new(&at_rest, &opts).unwrap();
    reused.solve(&theta).unwrap();
    reused.restart(&moving).unwrap();
    let a = reused.solve(&theta).unwrap();
    let b = Condensed::new(&moving, &opts)
        .unwrap()
        .solve(&theta)
        .unwrap();
    assert_eq!(a.theta, b.theta);
    assert_eq!(a.objective, b.objective);
    let other = ControlProblem::builder(&mpc_scene(60))
        .map(Parametrisation::Piecewise(PiecewiseControl {
            steps: 60,
            pieces: 5,
        }))
        .objective(obj)
        .build_in::<2>()
        .unwrap();
    match reused.restart(&other) {
        Err(chainbeam::Error::Ocp(OcpError::RestartMismatch { expected, got })) => {
            assert_eq!((expected.steps, got.steps), (50, 60));
        }
        r => panic!("expected the typed error, got {r:?}"),
    }
}

/// Table 3.4 rows 5, 7 and 9 (per-step, N = 10, c_sum without effort penalty, bounded by the
/// thesis's largest |u_k| as in the `tables` example): u_N acts on nothing J sees (a zero row
/// of H and a zero gradient), and the QP leaves it where it is instead of raising the
/// regularisation on a singular Hessian (row 9: 2 iterations; 192 before the inert control and
/// the round-off-level first Levenberg weight, `MU_FIRST`). Each row converges
/// to the trust region's objective (reference: `minimize` with `Method::TrustRegion`, exact
/// Hessian-vector products) to 1e-8 relative.
#[test]
fn table_3_4_rows_with_an_inert_control_converge() {
    for node in [5usize, 7, 9] {
        let (p, bound) = table_3_4::row(node);
        let o = |method| OptimOptions {
            method,
            bound: Some(bound),
            max_iters: 2000,
            ..OptimOptions::default()
        };
        let opts = riccati_options(&o(Method::Riccati)).unwrap();
        let r = Condensed::new(&p, &opts)
            .unwrap()
            .solve(&[0.0; 11])
            .unwrap();
        assert!(r.converged, "row {node}: {:?}", r.termination);
        assert_eq!(r.theta[10], 0.0, "row {node}: u_N moved");
        let tr = minimize(&p, &[0.0; 11], &o(Method::TrustRegion)).unwrap();
        let rel = (r.objective - tr.objective) / tr.objective;
        assert!(
            rel <= 1e-8,
            "row {node}: {} vs trust region {}",
            r.objective,
            tr.objective
        );
    }
}

/// A per-step horizon of N = 40000 steps would need about 51 GB of sensitivities (N × 40001
/// parameters, twice, and two dense 40001² matrices): refused before anything of that size is
/// allocated, with a typed error naming `method` that points to the Riccati solver.
#[test]
fn a_long_per_step_horizon_is_refused_not_allocated() {
    let steps = 40_000;
    let mut scene = catalogue::long_horizon();
    scene.time.steps = steps;
    if let Some(c) = scene.control.as_mut() {
        c.values = vec![0.0; steps + 1];
    }
    let p = ControlProblem::builder(&scene)
        .map(Parametrisation::PerStep(PerStepControl { steps }))
        .objective(BendingObjective::summed_moment().with_effort(0.01))
        .build_in::<2>()
        .unwrap();
    match Condensed::new(&p, &OcpOptions::default()) {
        Err(e @ chainbeam::Error::Ocp(OcpError::CondensedTooLarge { steps: 40_000, .. })) => {
            assert_eq!(e.argument(), Some("method"));
            assert!(e.to_string().contains("Riccati"), "{e}");
        }
        r => panic!("expected the typed refusal, got {:?}", r.map(|_| ())),
    }
}
