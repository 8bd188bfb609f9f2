//! Issue 28 item 4: the structured solvers in the spatial model — a 2-axis control
//! u = (u_x, u_z) per decision and the vector wellhead moment (M₀ₓ, M₀_z) in the objective
//! Σ (M₀ₓ² + M₀_z²) + ρ h Σ |u|² (and Σ |M₀|^p).
//!
//! References:
//! - Rotational symmetry: the model is invariant under rotations about the beam's axis y (drag
//!   included, issue 28 item 2, tests/drag_rotation.rs), so a planar scene turned by ψ about y
//!   (load, current and control direction turned) has the same optimal objective as the planar
//!   scene, reached at the turned controls (u_x, u_z) = (sin ψ·u, cos ψ·u). The planar optimum
//!   comes from the planar solver (an independent model: `Chain<f64, 2>`); the spatial one must
//!   equal it to 1e-9 relative (both solved to ‖∇J‖ ≤ 1e-10‖∇J₀‖).
//! - Exactness: the condensed solver's gradient at a point equals the discrete adjoint
//!   (`ControlProblem::gradient`, itself equal to `Dual64` to 1e-12 in tests/spatial_control.rs)
//!   of the same spatial problem to 1e-12 relative, and its objective `ControlProblem::value` to
//!   1e-12 relative (the same trajectory: |R|² = M₀ₓ² + M₀_z² up to round-off).

use chainbeam::ocp::{Condensed, OcpOptions};
use chainbeam::*;

const STEPS: usize = 120;
const PIECES: usize = 12;

/// The thesis riser (n = 10, l = 1 m, m = 1 kg, k = 1000 N·m/rad, k₁ = k₁₁ = 2000) with drag
/// D = 3 in a sheared current (0.3 m/s at the surface, 0.05 at the seabed) and a point load of
/// 2 N at node 5, both along the direction ψ from +z toward +x, h = 0.01 s, N = 120; a
/// piecewise control at the tip (12 pieces): along z for the planar scene (ψ = 0), 2-axis
/// otherwise.
fn scene(psi_deg: f64, two_axis: bool) -> Scene {
    let (s, c) = psi_deg.to_radians().sin_cos();
    let b = SceneBuilder::new(10)
        .support(Support::Riser)
        .base_stiffness(2000.0)
        .tip_stiffness(2000.0)
        .drag(3.0)
        .current(Current::linear(0.3, 0.05, [s, c]))
        .point_load_vector(5, [2.0 * s, 2.0 * c])
        .step(0.01)
        .steps(STEPS);
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
        let planar = ControlProblem::new(&scene(0.0, false), map(), obj).unwrap();
        let r0 = Condensed::new(&planar, &options())
            .unwrap()
            .solve(&[0.0; PIECES])
            .unwrap();
        assert!(r0.converged, "planar: {:?}", r0.termination);
        let umax = r0.theta.iter().fold(0.0f64, |m, u| m.max(u.abs()));
        assert!(umax > 0.1, "the control acts ({umax} N)");
        for psi in [45.0f64, 120.0] {
            let (s, c) = psi.to_radians().sin_cos();
            let p = ControlProblem::spatial(&scene(psi, true), map(), obj, true).unwrap();
            let r = Condensed::new(&p, &options())
                .unwrap()
                .solve(&[0.0; 2 * PIECES])
                .unwrap();
            assert!(r.converged, "ψ = {psi}: {:?}", r.termination);
            assert!(
                rel(r.objective, r0.objective) <= 1e-9,
                "ψ = {psi}: J {} against the planar {}",
                r.objective,
                r0.objective
            );
            let (tx, tz) = r.theta.split_at(PIECES);
            for j in 0..PIECES {
                let u = r0.theta[j];
                assert!(
                    (tx[j] - s * u).abs() <= 1e-6 * umax && (tz[j] - c * u).abs() <= 1e-6 * umax,
                    "ψ = {psi}, piece {j}: ({}, {}) against ({}, {})",
                    tx[j],
                    tz[j],
                    s * u,
                    c * u
                );
            }
            assert_eq!(r.controls_x.len(), STEPS + 1);
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
            let p = ControlProblem::spatial(&scene(60.0, true), m, obj, true).unwrap();
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
    let p = ControlProblem::spatial(
        &scene(30.0, false),
        map(),
        BendingObjective::summed_moment(),
        false,
    )
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
