//! The structured solvers in the spatial model — a 2-axis control
//! u = (u_x, u_z) per decision and the vector wellhead moment (M₀ₓ, M₀_z) in the objective
//! Σ (M₀ₓ² + M₀_z²) + ρ h Σ |u|² (and Σ |M₀|^p).
//!
//! References:
//! - Rotational symmetry: the model is invariant under rotations about the beam's axis y (drag
//!   included, tests/model/drag_rotation.rs), so a planar scene turned by ψ about y
//!   (load, current and control direction turned) has the same optimal objective as the planar
//!   scene, reached at the turned controls (u_x, u_z) = (sin ψ·u, cos ψ·u). The planar optimum
//!   comes from the planar solver (an independent model: `Chain<f64, 2>`); the spatial one must
//!   equal it to 1e-9 relative (both solved to ‖∇J‖ ≤ 1e-10‖∇J₀‖).
//! - Exactness: the condensed solver's gradient at a point equals the discrete adjoint
//!   (`ControlProblem::gradient`, itself equal to `Dual64` to 1e-12 in tests/adjoint/spatial_control.rs)
//!   of the same spatial problem to 1e-12 relative, and its objective `ControlProblem::value` to
//!   1e-12 relative (the same trajectory: |R|² = M₀ₓ² + M₀_z² up to round-off). So does the
//!   Riccati solver's costate gradient (its spatial stage Jacobians in the tangent chart,
//!   chained by the costate sweep).
//! - Independent methods: the spatial Riccati optimum equals the spatial condensed optimum (a
//!   different algorithm on the same problem: dense sensitivities and QP instead of stage
//!   Jacobians and Riccati passes) to 1e-9 relative.

use chainbeam::ocp::{self, Condensed, OcpOptions, Solver};
use chainbeam::optimize::{choose_method, Method, OptimOptions};
use chainbeam::*;

use crate::turned_riser;

const STEPS: usize = 120;
const PIECES: usize = 12;

/// The thesis riser (n = 10, l = 1 m, m = 1 kg, k = 1000 N·m/rad, k₁ = k₁₁ = 2000) with drag
/// D = 3 in a sheared current (0.3 m/s at the surface, 0.05 at the seabed) and a point load of
/// 2 N at node 5, both along the direction ψ from +z toward +x, h = 0.01 s, N = 120; a
/// piecewise control at the tip (12 pieces): along z for the planar scene (ψ = 0), 2-axis
/// otherwise.
fn scene(psi_deg: f64, two_axis: bool) -> Scene {
    let b = turned_riser::builder(psi_deg, STEPS);
    if two_axis {
        b.control_two_axis(10, ControlKind::Piecewise, &[[0.0, 0.0]; PIECES])
    } else {
        b.control_piecewise(10, vec![0.0; PIECES])
    }
    .build()
    .unwrap()
}

fn map() -> Parametrisation {
    Parametrisation::Piecewise(PiecewiseControl {
        steps: STEPS,
        pieces: PIECES,
    })
}

fn options() -> OcpOptions {
    OcpOptions {
        rel_grad_tol: 1e-10,
        ..OcpOptions::default()
    }
}

fn rel(a: f64, b: f64) -> f64 {
    (a - b).abs() / b.abs()
}

/// The spatial optimum `r` of the scene turned by ψ = `psi` degrees against the planar optimum
/// `r0` (rotational symmetry, module docs): the control acts (its largest force |u|_max > 0.1
/// N), equal objectives to 1e-9 relative, the turned controls (u_x, u_z) = (sin ψ·u, cos ψ·u)
/// to 1e-6 |u|_max, and u_x for every step; `case` names the case in the messages.
fn assert_turned(r0: &ocp::OcpResult, r: &ocp::OcpResult, psi: f64, case: &str) {
    let umax = r0.theta.iter().fold(0.0f64, |m, u| m.max(u.abs()));
    assert!(umax > 0.1, "the control acts ({umax} N)");
    let (s, c) = psi.to_radians().sin_cos();
    assert!(
        rel(r.objective, r0.objective) <= 1e-9,
        "ψ = {psi} {case}: J {} against the planar {}",
        r.objective,
        r0.objective
    );
    let np = r0.theta.len();
    let (tx, tz) = r.theta.split_at(np);
    for j in 0..np {
        let u = r0.theta[j];
        assert!(
            (tx[j] - s * u).abs() <= 1e-6 * umax && (tz[j] - c * u).abs() <= 1e-6 * umax,
            "ψ = {psi} {case}, θ {j}: ({}, {}) against ({}, {})",
            tx[j],
            tz[j],
            s * u,
            c * u
        );
    }
    assert_eq!(r.controls_x.len(), STEPS + 1);
}

/// The planar optimum and the spatial optimum of the scene turned by ψ = 45° (and 120°), by
/// the condensed solver: equal objectives to 1e-9 relative, turned controls to 1e-6 of the
/// largest force, for c_sum with effort and for Σ|M₀|⁴.
#[test]
fn turned_scene_has_the_planar_optimum_turned() {
    let objectives = [
        BendingObjective::summed_moment().with_effort(0.01),
        BendingObjective {
            kind: ObjectiveKind::Power { exponent: 4.0 },
            effort: 0.01,
        },
    ];
    for obj in objectives {
        let planar = ControlProblem::builder(&scene(0.0, false))
            .map(map())
            .objective(obj)
            .build_in::<2>()
            .unwrap();
        let r0 = Condensed::new(&planar, &options())
            .unwrap()
            .solve(&[0.0; PIECES])
            .unwrap();
        assert!(r0.converged, "planar: {:?}", r0.termination);
        for psi in [45.0f64, 120.0] {
            let p = ControlProblem::builder(&scene(psi, true))
                .map(map())
                .objective(obj)
                .two_axis(true)
                .build_in::<3>()
                .unwrap();
            let r = Condensed::new(&p, &options())
                .unwrap()
                .solve(&[0.0; 2 * PIECES])
                .unwrap();
            assert!(r.converged, "ψ = {psi}: {:?}", r.termination);
            assert_turned(&r0, &r, psi, "");
        }
    }
}

/// The condensed solver's objective and exact gradient at a point of a 2-axis problem in the
/// spatial model (oblique load and current, controls of both signs on both axes) equal the
/// discrete adjoint's to 1e-12 relative, for c_sum with effort, c (the final moment) and
/// Σ|M₀|⁴, and per-step as well as piecewise controls.
#[test]
fn condensed_gradient_equals_the_adjoint_in_space() {
    let objectives = [
        BendingObjective::summed_moment().with_effort(0.01),
        BendingObjective::final_moment(),
        BendingObjective {
            kind: ObjectiveKind::Power { exponent: 4.0 },
            effort: 0.0,
        },
    ];
    let maps = [
        map(),
        Parametrisation::PerStep(PerStepControl { steps: STEPS }),
    ];
    for obj in objectives {
        for m in maps {
            let p = ControlProblem::builder(&scene(60.0, true))
                .map(m)
                .objective(obj)
                .two_axis(true)
                .build_in::<3>()
                .unwrap();
            let theta: Vec<f64> = (0..p.n_params())
                .map(|i| 1.5 * ((i as f64) * 0.7 + 0.3).sin())
                .collect();
            let mut c = Condensed::new(&p, &OcpOptions::default()).unwrap();
            let j = c.set_point(&theta).unwrap();
            let (_, g) = c.gauss_newton().unwrap();
            let (ja, ga) = p.value_and_gradient(&theta).unwrap();
            assert!(rel(j, ja) <= 1e-12, "{obj:?} {m:?}: J {j} against {ja}");
            let scale = ga.iter().fold(0.0f64, |a, x| a.max(x.abs()));
            assert!(scale > 0.0);
            for (i, (a, b)) in g.iter().zip(&ga).enumerate() {
                assert!(
                    (a - b).abs() <= 1e-12 * scale,
                    "{obj:?} {m:?} θ[{i}]: condensed {a} against the adjoint {b}"
                );
            }
        }
    }
}

/// A 1-axis control (along z) in a spatial scene (the load along x): the condensed solver takes
/// the spatial model with one control per decision, and its gradient is the adjoint's.
#[test]
fn one_axis_control_in_a_spatial_scene() {
    let p = ControlProblem::builder(&scene(30.0, false))
        .map(map())
        .objective(BendingObjective::summed_moment())
        .two_axis(false)
        .build_in::<3>()
        .unwrap();
    let theta: Vec<f64> = (0..PIECES).map(|i| (i as f64 * 0.4).cos()).collect();
    let mut c = Condensed::new(&p, &OcpOptions::default()).unwrap();
    let j = c.set_point(&theta).unwrap();
    let (_, g) = c.gauss_newton().unwrap();
    let (ja, ga) = p.value_and_gradient(&theta).unwrap();
    assert!(rel(j, ja) <= 1e-12, "J {j} against {ja}");
    let scale = ga.iter().fold(0.0f64, |a, x| a.max(x.abs()));
    for (a, b) in g.iter().zip(&ga) {
        assert!((a - b).abs() <= 1e-12 * scale, "{a} against {b}");
    }
    let r = c.solve(&theta).unwrap();
    assert!(r.converged && r.objective < j, "{:?}", r.termination);
}

fn per_step() -> Parametrisation {
    Parametrisation::PerStep(PerStepControl { steps: STEPS })
}

/// The Riccati solver's cases: per-step controls with ρ = 0.1 (N + 1 stages with a decision
/// each) and the piecewise control with ρ = 0.01 (held stages: the augmented state
/// w_k = u_{k−1} of both components), c_sum with effort.
fn riccati_cases() -> [(Parametrisation, BendingObjective); 2] {
    [
        (
            per_step(),
            BendingObjective::summed_moment().with_effort(0.1),
        ),
        (map(), BendingObjective::summed_moment().with_effort(0.01)),
    ]
}

/// Whether a Riccati run ended at its optimum: converged, or (Gauss-Newton throughout, as the
/// spatial model runs) at steps below J's round-off, where the planar Gauss-Newton run of the
/// per-step case ends too (41 iterations, J within 4e-12 of the exact model's optimum).
fn done(r: &ocp::OcpResult) -> bool {
    r.converged || r.termination == ocp::OcpTermination::RoundOff
}

/// The Riccati solver (2 controls per stage in the spatial model): the planar scene turned by
/// ψ = 45° and 120° has the planar Riccati optimum (to 1e-9 relative) at the controls turned
/// (to 1e-6 of the largest force), for the cases of [`riccati_cases`].
#[test]
fn riccati_turned_scene_has_the_planar_riccati_optimum_turned() {
    for (m, obj) in riccati_cases() {
        let np = m.n_params();
        let planar = ControlProblem::builder(&scene(0.0, false))
            .map(m)
            .objective(obj)
            .build_in::<2>()
            .unwrap();
        let r0 = ocp::solve(&planar, &vec![0.0; np], &options()).unwrap();
        assert!(r0.converged, "planar {m:?}: {:?}", r0.termination);
        for psi in [45.0f64, 120.0] {
            let p = ControlProblem::builder(&scene(psi, true))
                .map(m)
                .objective(obj)
                .two_axis(true)
                .build_in::<3>()
                .unwrap();
            let r = ocp::solve(&p, &vec![0.0; 2 * np], &options()).unwrap();
            assert!(done(&r), "ψ = {psi} {m:?}: {:?}", r.termination);
            assert_turned(&r0, &r, psi, &format!("{m:?}"));
        }
    }
}

/// The spatial Riccati optimum equals the spatial condensed optimum (an independent method on
/// the same problem) to 1e-9 relative: load and current from 60°, a 2-axis control in the
/// cases of [`riccati_cases`], with and without the box |u_x|, |u_z| ≤ 0.3 N (which binds:
/// the interior point's bounds on both components).
#[test]
fn riccati_equals_condensed_in_space() {
    for (m, obj) in riccati_cases() {
        for bound in [None, Some(0.3)] {
            let p = ControlProblem::builder(&scene(60.0, true))
                .map(m)
                .objective(obj)
                .two_axis(true)
                .build_in::<3>()
                .unwrap();
            let opts = match bound {
                Some(b) => options().with_bound(b),
                None => options(),
            };
            let theta0 = vec![0.0; p.n_params()];
            let r = ocp::solve(&p, &theta0, &opts).unwrap();
            let c = Condensed::new(&p, &opts).unwrap().solve(&theta0).unwrap();
            assert!(done(&r), "{m:?} {bound:?}: {:?}", r.termination);
            assert!(done(&c), "{m:?} {bound:?}: condensed {:?}", c.termination);
            assert!(
                rel(r.objective, c.objective) <= 1e-9,
                "{m:?} {bound:?}: Riccati {} against condensed {}",
                r.objective,
                c.objective
            );
            if let Some(b) = bound {
                let on = r
                    .theta
                    .iter()
                    .filter(|u| u.abs() >= b * (1.0 - 1e-9))
                    .count();
                assert!(on > 0, "{m:?}: the box |u| ≤ {b} does not bind");
                assert!(r.theta.iter().all(|u| u.abs() <= b));
            }
        }
    }
}

/// The Riccati solver's costate gradient (the spatial stage Jacobians A_k, B_k in the tangent
/// chart, chained backwards) equals the discrete adjoint of the same problem to 1e-12 of its
/// largest entry, at a point with controls of both signs: 2-axis per-step and piecewise, and a
/// control along z in a spatial scene.
#[test]
fn riccati_gradient_equals_the_adjoint_in_space() {
    let obj = BendingObjective::summed_moment().with_effort(0.01);
    let cases = [
        (per_step(), true, 60.0),
        (map(), true, 60.0),
        (map(), false, 30.0),
    ];
    for (m, two_axis, psi) in cases {
        let p = ControlProblem::builder(&scene(psi, two_axis))
            .map(m)
            .objective(obj)
            .two_axis(two_axis)
            .build_in::<3>()
            .unwrap();
        let theta: Vec<f64> = (0..p.n_params())
            .map(|i| 1.5 * ((i as f64) * 0.7 + 0.3).sin())
            .collect();
        let mut s = Solver::new(&p, &OcpOptions::default()).unwrap();
        let j = s.set_point(&theta).unwrap();
        let g = s.gradient().unwrap();
        let (ja, ga) = p.value_and_gradient(&theta).unwrap();
        assert!(rel(j, ja) <= 1e-12, "{m:?}: J {j} against {ja}");
        let scale = ga.iter().fold(0.0f64, |a, x| a.max(x.abs()));
        assert!(scale > 0.0);
        for (i, (a, b)) in g.iter().zip(&ga).enumerate() {
            assert!(
                (a - b).abs() <= 1e-12 * scale,
                "{m:?} two-axis {two_axis} θ[{i}]: Riccati {a} against the adjoint {b}"
            );
        }
    }
}

/// `Method::Auto` takes the Riccati solver for a long spatial horizon (a 2-axis per-step
/// control: 2(N + 1) = 242 parameters, more than 4(2n + 1) = 84) and the condensed one for a
/// short one (24 parameters), as in the planar model.
#[test]
fn auto_picks_riccati_for_long_spatial_horizons() {
    let obj = BendingObjective::summed_moment().with_effort(0.01);
    let opts = OptimOptions::default();
    let long = ControlProblem::builder(&scene(60.0, true))
        .map(per_step())
        .objective(obj)
        .two_axis(true)
        .build_in::<3>()
        .unwrap();
    let short = ControlProblem::builder(&scene(60.0, true))
        .map(map())
        .objective(obj)
        .two_axis(true)
        .build_in::<3>()
        .unwrap();
    let c = choose_method(&long, &opts);
    assert_eq!(c.method, Method::Riccati, "{c}");
    assert!(c.reason.contains("spatial"), "{c}");
    assert_eq!(choose_method(&short, &opts).method, Method::Condensed);
}

/// MPC in the spatial model: the closed loop of the planar riser (drag,
/// sheared current, a harmonic sea) and of the same scene turned by 45° about the beam's axis
/// (load, current turned; the spatial plant and a 2-axis controller, `Mpc::spatial`) have the
/// same closed-loop c_sum = Σ |M₀(t_k)|² to 1e-9 relative and the turned forces
/// (u_x, u_z) = (sin 45°·u, cos 45°·u) to 1e-7 of the largest force, with the condensed solver
/// re-planning (`mpc`'s choice for this horizon); with the Riccati solver to 1e-7 and 1e-5:
/// its Gauss-Newton re-plans end at J's round-off or their budget short of the tolerance, and
/// its planar closed loop is itself 2e-8 from the condensed one. Reference: the planar closed
/// loop (the planar plant and controller), by the rotational symmetry of the model. Each plan is
/// solved as far as it goes (200 iterations first, 30 per re-plan, ‖pg‖ ≤ 1e-13‖g₀‖), so the
/// plans are the optimum's, not a path of iterates that the two models' round-off could split
/// (with 1 iteration per re-plan the closed loops parted by 10 %: the unconverged plans of a
/// loop whose forces reach 10³ N amplify round-off); ρ = 1 and no box (a box per component is
/// not rotation-invariant).
#[test]
fn turned_closed_loop_is_the_planar_one_turned() {
    use chainbeam::mpc::{run_closed_loop, Mpc, MpcOptions, MpcSolver};
    let sea = |psi: f64| {
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
    };
    for (solver, tol_j, tol_u) in [
        (MpcSolver::Condensed, 1e-9, 1e-7),
        (MpcSolver::Riccati, 1e-7, 1e-5),
    ] {
        let options = || MpcOptions {
            horizon: chainbeam::mpc::Horizon::Seconds(1.0),
            first_iterations: 200,
            iterations: 30,
            ocp: OcpOptions {
                rel_grad_tol: 1e-13,
                ..OcpOptions::default()
            },
            solver,
            effort: 1.0,
            ..MpcOptions::default()
        };
        let mut planar = Mpc::new(&sea(0.0), 0.1, options()).unwrap();
        let r0 = run_closed_loop(&sea(0.0), 0.1, &mut planar).unwrap();
        let (s, c) = 45f64.to_radians().sin_cos();
        let mut spatial = Mpc::spatial(&sea(45.0), 0.1, options()).unwrap();
        let r = run_closed_loop(&sea(45.0), 0.1, &mut spatial).unwrap();
        let (j0, j) = (r0.summary.c_sum, r.summary.c_sum);
        let umax = r0.summary.max_abs_control;
        assert!(umax > 0.5, "{solver:?}: the controller acts");
        assert!(
            rel(j, j0) <= tol_j,
            "{solver:?}: closed-loop c_sum {j} against the planar {j0}"
        );
        for k in 0..r0.control.len() {
            let u = r0.control[k];
            assert!(
                (r.control_x[k] - s * u).abs() <= tol_u * umax
                    && (r.control[k] - c * u).abs() <= tol_u * umax,
                "{solver:?} step {k}: ({}, {}) against ({}, {})",
                r.control_x[k],
                r.control[k],
                s * u,
                c * u
            );
        }
    }
}
