//! Two-axis controls and the bending moment in 3D: a control u = (u_x, u_z) in the
//! transverse plane with constant, per-step and piecewise parametrisations (θ = (θ_x; θ_z)),
//! the base moment vector M₀ = (M₀ₓ, M₀_z) and the objectives on |M₀|².
//!
//! References: the adjoint gradient is compared with forward-mode dual numbers (`Dual64`, exact
//! to round-off: 1e-12 relative) and central differences (step 1e-6·max(1, |θᵢ|), truncation
//! O(δ²) ≈ 1e-12 relative to J's curvature scale, so 1e-6 relative); rotational symmetry about
//! the beam's axis y (the model is invariant under rotations of the (x, z) plane) gives the
//! exact references of the rotation tests.

use std::f64::consts::FRAC_PI_4;

use chainbeam::adjoint::{forward_value, AdjointResult};
use chainbeam::optimize::{minimize, OptimOptions};
use chainbeam::*;
use num_dual::Dual64;

const H: f64 = 0.01;

/// The thesis riser (n = 10, l = 1 m, m = 1 kg, k = 1000, k₁ = k₁₁ = 2000) without drag, h =
/// 0.01 s, N = `steps`, and a load of 2 N at node 5 at angle `alpha` from z toward x:
/// [F_x, F_z] = 2 (sin α, cos α). Without drag the model is symmetric under rotations about y
/// (as it is with drag, whose transverse part uses the Euclidean norm).
fn riser(steps: usize, alpha: f64) -> SceneBuilder {
    SceneBuilder::new(10)
        .support(Support::Riser)
        .base_stiffness(2000.0)
        .tip_stiffness(2000.0)
        .step(H)
        .steps(steps)
        .point_load_vector(5, [2.0 * alpha.sin(), 2.0 * alpha.cos()])
}

/// The three parametrisations on N steps (piecewise: 4 pieces).
fn maps(steps: usize) -> [Parametrisation; 3] {
    [
        Parametrisation::Constant,
        Parametrisation::PerStep(PerStepControl { steps }),
        Parametrisation::Piecewise(PiecewiseControl { steps, pieces: 4 }),
    ]
}

/// A θ with distinct, nonzero entries of a few newtons (both signs), so every component acts.
fn theta_of(n: usize) -> Vec<f64> {
    (0..n)
        .map(|i| 1.5 * ((i as f64) * 0.7 + 0.3).sin())
        .collect()
}

/// J(θ) of a 2-axis problem in `Dual64` with θᵢ seeded: the forward-mode derivative ∂J/∂θᵢ.
fn dual_derivative(
    p: &ControlProblem<Parametrisation, BendingObjective, 3>,
    theta: &[f64],
    i: usize,
) -> f64 {
    let th: Vec<Dual64> = theta
        .iter()
        .enumerate()
        .map(|(j, &t)| Dual64::new(t, if i == j { 1.0 } else { 0.0 }))
        .collect();
    let m = p.map().n_params();
    let n1 = p.steps() + 1;
    let (mut ux, mut uz) = (vec![Dual64::from(0.0); n1], vec![Dual64::from(0.0); n1]);
    p.map().controls(&th[..m], &mut ux);
    p.map().controls(&th[m..], &mut uz);
    let mut chain = p.chain_as::<Dual64>();
    chain.set_control_x(&ux).unwrap();
    forward_value(&chain, p.time_step(), p.steps(), &uz, p.objective())
        .unwrap()
        .eps
}

/// The adjoint gradient of a 2-axis control equals the `Dual64` forward derivative to 1e-12 and
/// central differences to 1e-6 (relative to ‖∇J‖∞), for constant (2), per-step (2(N + 1)) and
/// piecewise (2P) parametrisations, on an oblique load with c_sum and an effort penalty (which
/// reads both components).
#[test]
fn two_axis_adjoint_equals_dual_numbers_and_differences() {
    let steps = 20;
    // With drag D = 10, so the drag's per-component nonlinearity is differentiated too.
    let scene = riser(steps, 0.6).drag(10.0).build().unwrap();
    let obj = BendingObjective::summed_moment().with_effort(0.01);
    for map in maps(steps) {
        let p = ControlProblem::builder(&scene)
            .map(map)
            .objective(obj)
            .two_axis(true)
            .build_in::<3>()
            .unwrap();
        assert_eq!(p.n_params(), 2 * map.n_params());
        let theta = theta_of(p.n_params());
        let (j, g) = p.value_and_gradient(&theta).unwrap();
        assert_eq!(j, p.value(&theta).unwrap(), "adjoint's J = forward J");
        let scale = g.iter().fold(0.0f64, |a, x| a.max(x.abs()));
        assert!(scale > 0.0);
        for i in 0..p.n_params() {
            let fwd = dual_derivative(&p, &theta, i);
            assert!(
                (g[i] - fwd).abs() <= 1e-12 * scale,
                "{map:?} θ[{i}]: adjoint {} vs Dual64 {fwd}",
                g[i]
            );
            let d = 1e-6 * theta[i].abs().max(1.0);
            let (mut tp, mut tm) = (theta.clone(), theta.clone());
            tp[i] += d;
            tm[i] -= d;
            let fd = (p.value(&tp).unwrap() - p.value(&tm).unwrap()) / (2.0 * d);
            assert!(
                (g[i] - fd).abs() <= 1e-6 * scale,
                "{map:?} θ[{i}]: adjoint {} vs central difference {fd}",
                g[i]
            );
        }
    }
}

/// The Hessian-vector product of a 2-axis problem (forward-over-adjoint) equals central
/// differences of the adjoint gradient (step 1e-6, so 1e-6 relative to ‖Hv‖∞).
#[test]
fn two_axis_hessian_vector_product_equals_differences_of_gradients() {
    let steps = 20;
    let scene = riser(steps, 0.6).build().unwrap();
    let map = Parametrisation::Piecewise(PiecewiseControl { steps, pieces: 3 });
    let p = ControlProblem::builder(&scene)
        .map(map)
        .objective(BendingObjective::summed_moment())
        .two_axis(true)
        .build_in::<3>()
        .unwrap();
    let theta = theta_of(6);
    let v: Vec<f64> = (0..6).map(|i| 1.0 - 0.3 * i as f64).collect();
    let hv = p.hessian_vec(&theta, &v).unwrap();
    let d = 1e-6;
    let shift = |s: f64| -> Vec<f64> { theta.iter().zip(&v).map(|(t, x)| t + s * x).collect() };
    let (gp, gm) = (
        p.gradient(&shift(d)).unwrap(),
        p.gradient(&shift(-d)).unwrap(),
    );
    let scale = hv.iter().fold(0.0f64, |a, x| a.max(x.abs()));
    for i in 0..6 {
        let fd = (gp[i] - gm[i]) / (2.0 * d);
        assert!(
            (hv[i] - fd).abs() <= 1e-6 * scale,
            "i = {i}: {} vs {fd}",
            hv[i]
        );
    }
}

/// The control term's hand-written w · ∂F/∂u_x (Σ_{j<c} l_j w_{j,x}) equals the derivative of the
/// force itself: the ε-part of ∂U/∂q with u_{x,k} seeded in `Dual64`, contracted with w (exact:
/// the force is linear in u_x).
#[test]
fn control_x_contraction_equals_dual_derivative_of_the_force() {
    let scene = riser(4, 0.6).control_constant(7, 0.0).build().unwrap();
    let chain = Chain::<f64, 3>::from_scene(&scene).unwrap();
    let q: Vec<[f64; 3]> = (0..10)
        .map(|i| {
            let a = 0.05 * i as f64;
            [a.sin() * 0.3, a.cos(), a.sin()]
        })
        .collect();
    let w: Vec<[f64; 3]> = (0..10)
        .map(|i| [1.0 + i as f64, -0.5 * i as f64, 0.25])
        .collect();
    let mut with_x = chain.clone();
    with_x.set_control_x(&[0.0, 0.0, 0.4]).unwrap();
    let mut scratch = chainbeam::model::DualScratch::new(10);
    let ctx = with_x.ctx(2.0 * H, -0.7, 2);
    let hand = with_x
        .control_x_contraction(&q, &w, &ctx, &mut scratch)
        .unwrap();

    let mut dual = chain.lift::<Dual64>();
    let ux = [0.0, 0.0, 0.4].map(Dual64::from);
    let mut seeded = ux;
    seeded[2] = Dual64::new(0.4, 1.0);
    dual.set_control_x(&seeded).unwrap();
    let qd: Vec<[Dual64; 3]> = q.iter().map(|r| r.map(Dual64::from)).collect();
    let mut f = vec![[Dual64::from(0.0); 3]; 10];
    dual.potential_gradient(&qd, 2.0 * H, Dual64::from(-0.7), 2, &mut f)
        .unwrap();
    let reference: f64 = f
        .iter()
        .zip(&w)
        .map(|(fi, wi)| (0..3).map(|d| fi[d].eps * wi[d]).sum::<f64>())
        .sum();
    // Σ_{j<7} l_j w_{j,x} = Σ_{j=0}^{6} (1 + j) = 28 with l = 1.
    assert_eq!(reference, 28.0);
    assert!(
        (hand - reference).abs() <= 1e-12 * reference,
        "{hand} vs {reference}"
    );
    // Steps beyond the schedule have u_x = 0; the planar model has no x contraction.
    assert_eq!(with_x.control_x(3), 0.0);
    let planar = Chain::<f64, 2>::from_scene(&riser(4, 0.0).build().unwrap()).unwrap();
    let q2: Vec<[f64; 2]> = q.iter().map(|r| [r[1], r[2]]).collect();
    let w2: Vec<[f64; 2]> = w.iter().map(|r| [r[1], r[2]]).collect();
    let mut s2 = chainbeam::model::DualScratch::new(10);
    let c2 = planar.ctx(0.0, 1.0, 0);
    assert_eq!(
        planar
            .control_x_contraction(&q2, &w2, &c2, &mut s2)
            .unwrap(),
        0.0
    );
}

/// On an in-plane scene, the spatial 2-axis problem with θ_x = 0 equals the planar problem: J
/// and the z block of ∇J to 1e-12 relative, and ∂J/∂θ_x = 0 (J is even in x by the mirror
/// symmetry x → −x, so its x derivatives vanish at u_x = 0; round-off only), for all three
/// parametrisations.
#[test]
fn two_axis_with_zero_x_equals_the_planar_problem() {
    let steps = 20;
    let scene = riser(steps, 0.0).drag(10.0).build().unwrap();
    assert!(!scene.is_spatial());
    let obj = BendingObjective::summed_moment().with_effort(0.01);
    for map in maps(steps) {
        let planar = ControlProblem::builder(&scene)
            .map(map)
            .objective(obj)
            .build_in::<2>()
            .unwrap();
        let spatial = ControlProblem::builder(&scene)
            .map(map)
            .objective(obj)
            .two_axis(true)
            .build_in::<3>()
            .unwrap();
        let m = map.n_params();
        let theta_z = theta_of(m);
        let mut theta = vec![0.0; m];
        theta.extend(&theta_z);
        let (j2, g2) = planar.value_and_gradient(&theta_z).unwrap();
        let (j3, g3) = spatial.value_and_gradient(&theta).unwrap();
        assert!((j2 - j3).abs() <= 1e-12 * j2, "{map:?}: {j2} vs {j3}");
        let scale = g2.iter().fold(0.0f64, |a, x| a.max(x.abs()));
        for i in 0..m {
            assert!((g3[m + i] - g2[i]).abs() <= 1e-12 * scale, "{map:?} z[{i}]");
            assert!(g3[i].abs() <= 1e-12 * scale, "{map:?} x[{i}] = {}", g3[i]);
        }
    }
}

/// |M₀|² reduces to the thesis's M₀² in planar scenes: the planar model's moment vector is
/// (0, M₀) with M₀ = `base_moment`, the bending objective's stage cost is bit-for-bit M₀², and the
/// planar problem's c_sum equals Σ_k M₀(t_k)² of the simulated trajectory; the spatial model of the
/// same scene has M₀ₓ ≡ 0 exactly.
#[test]
fn squared_norm_of_the_moment_reduces_to_the_planar_square() {
    let steps = 30;
    let scene = riser(steps, 0.0)
        .control_constant(10, -0.5)
        .build()
        .unwrap();
    let traj = simulate(&scene).unwrap();
    assert!(!traj.is_spatial());
    assert!(traj.moment_x().is_empty());
    let planar = traj.as_planar().unwrap();
    let chain = Chain::<f64, 2>::from_scene(&scene).unwrap();
    for k in 0..=steps {
        let [mx, mz] = chain.base_moment_vector(planar.q(k));
        assert_eq!(mx, 0.0);
        assert_eq!(mz, chain.base_moment(planar.q(k)));
        assert_eq!(mz, traj.moment()[k]);
        let stage = adjoint::Stage {
            k,
            steps,
            h: H,
            moment: mz,
            moment_x: mx,
            control: -0.5,
            control_x: 0.0,
            z: &[],
        };
        let cost = BendingObjective::summed_moment().stage(stage);
        assert_eq!(cost.to_bits(), (mz * mz).to_bits());
    }
    let p = ControlProblem::builder(&scene)
        .map(Parametrisation::Constant)
        .objective(BendingObjective::summed_moment())
        .build_in::<2>()
        .unwrap();
    let direct: f64 = traj.moment().iter().map(|m| m * m).sum();
    let j = p.value(&[-0.5]).unwrap();
    assert!((j - direct).abs() <= 1e-12 * direct, "{j} vs {direct}");
    // The same scene in the spatial model: x stays exactly 0, so M₀ₓ = 0.
    let spatial = simulate(
        SimulateInput::new(&scene).controls_xz(&vec![0.0; steps + 1], &vec![-0.5; steps + 1]),
    )
    .unwrap();
    assert!(spatial.moment_x().iter().all(|m| *m == 0.0));
    for (a, b) in spatial.moment().iter().zip(traj.moment()) {
        assert!((a - b).abs() <= 1e-12 * b.abs().max(1e-300), "{a} vs {b}");
    }
}

/// Rotating the load and the control together by α about the beam's axis rotates M₀ by α and
/// leaves |M₀|² unchanged (1e-12 relative to max |M₀|): the model is invariant under rotations of
/// the (x, z) plane, and M₀ = 2k₁(x₁, z₁)/l₁² rotates with node 1.
#[test]
fn rotating_load_and_control_rotates_the_moment() {
    let steps = 60;
    let uz: Vec<f64> = (0..=steps).map(|k| -1.0 - 0.02 * k as f64).collect();
    let base = riser(steps, 0.0).build().unwrap();
    let reference =
        simulate(SimulateInput::new(&base).controls_xz(&vec![0.0; steps + 1], &uz)).unwrap();
    let m0 = reference.moment();
    let scale = m0.iter().fold(0.0f64, |a, m| a.max(m.abs()));
    for alpha in [FRAC_PI_4, 1.0, 2.5, -2.0] {
        let scene = riser(steps, alpha).build().unwrap();
        let (s, c) = alpha.sin_cos();
        let ux: Vec<f64> = uz.iter().map(|u| u * s).collect();
        let uzr: Vec<f64> = uz.iter().map(|u| u * c).collect();
        let t = simulate(SimulateInput::new(&scene).controls_xz(&ux, &uzr)).unwrap();
        let mag = t.moment_magnitude();
        for k in 0..=steps {
            let (mx, mz) = (t.moment_x()[k], t.moment()[k]);
            assert!(
                (mx - s * m0[k]).abs() <= 1e-12 * scale,
                "α = {alpha}, k = {k}: M₀ₓ"
            );
            assert!(
                (mz - c * m0[k]).abs() <= 1e-12 * scale,
                "α = {alpha}, k = {k}: M₀_z"
            );
            assert!(
                (mag[k] - m0[k].abs()).abs() <= 1e-12 * scale,
                "α = {alpha}, k = {k}"
            );
        }
    }
}

/// A 45° load with a 2-axis constant tip control: the optimum found by `minimize` from u = 0
/// points along the load (u_x = u_z to the optimiser's tolerance) and has the objective of the
/// in-plane problem, whose optimum u* rotated by 45° is, by rotational symmetry, the spatial
/// optimum: J equal to 1e-12 there and a gradient at round-off level.
#[test]
fn oblique_optimum_points_along_the_load() {
    let steps = 100;
    let obj = BendingObjective::summed_moment().with_effort(0.01);
    let planar_scene = riser(steps, 0.0).build().unwrap();
    let planar = ControlProblem::builder(&planar_scene)
        .map(Parametrisation::Constant)
        .objective(obj)
        .build_in::<2>()
        .unwrap();
    let opts = OptimOptions::default();
    let r2 = minimize(&planar, &[0.0], &opts).unwrap();
    assert!(r2.converged, "{}", r2.termination);
    let u_star = r2.theta[0];
    assert!(u_star < 0.0, "the control opposes the load: {u_star}");

    let scene = riser(steps, FRAC_PI_4).build().unwrap();
    let spatial = ControlProblem::builder(&scene)
        .map(Parametrisation::Constant)
        .objective(obj)
        .two_axis(true)
        .build_in::<3>()
        .unwrap();
    let rotated = [u_star * FRAC_PI_4.sin(), u_star * FRAC_PI_4.cos()];
    let (j_rot, g_rot) = spatial.value_and_gradient(&rotated).unwrap();
    assert!(
        (j_rot - r2.objective).abs() <= 1e-12 * r2.objective,
        "{j_rot} vs {}",
        r2.objective
    );
    let g2 = planar.gradient(&[u_star]).unwrap()[0].abs();
    // The rotated optimum's gradient is the planar one's, rotated: as small.
    assert!(
        g_rot[0].hypot(g_rot[1]) <= g2 + 1e-12 * j_rot,
        "{g_rot:?} vs {g2}"
    );

    let r3 = minimize(&spatial, &[0.0, 0.0], &opts).unwrap();
    assert!(r3.converged, "{}", r3.termination);
    let (ux, uz) = (r3.theta[0], r3.theta[1]);
    assert!(
        (ux - uz).abs() <= 1e-6 * uz.abs(),
        "direction: {ux} vs {uz}"
    );
    assert!((ux.hypot(uz) - u_star.abs()).abs() <= 1e-6 * u_star.abs());
    assert!(
        (r3.objective - r2.objective).abs() <= 1e-10 * r2.objective,
        "{} vs {}",
        r3.objective,
        r2.objective
    );
}

/// A 2-axis scene file: `values` as pairs [u_x, u_z] selects the spatial model, round-trips
/// through TOML, and simulates with its x components (the trajectory's `controls_x`).
#[test]
fn two_axis_scene_file_round_trips_and_simulates() {
    let scene = riser(20, FRAC_PI_4)
        .control_two_axis(10, ControlKind::Piecewise, &[[-1.0, -1.5], [0.5, -0.5]])
        .build()
        .unwrap();
    assert!(scene.is_spatial() && scene.has_two_axis_control());
    let text = scene.to_toml_string();
    assert!(text.contains("[-1.0, -1.5]"), "{text}");
    let back = Scene::from_toml_str(&text).unwrap();
    assert_eq!(back, scene);
    let t = simulate(&scene).unwrap();
    assert!(t.is_spatial());
    assert_eq!(t.controls_x()[0], -1.0);
    assert_eq!(t.controls_x()[20], 0.5);
    assert_eq!(t.controls()[0], -1.5);
    let p = ControlProblem::builder(&scene).build_in::<3>().unwrap();
    assert!(p.is_two_axis());
    assert_eq!(
        p.controls_x(&[-1.0, 0.5, -1.5, -0.5]).unwrap(),
        t.controls_x()
    );
}

/// Bad input names the key or the quantity: mixed numbers and pairs, a pair of three numbers, a
/// non-finite x component, the planar model of a 2-axis scene, x components on a planar chain,
/// and a θ of the 1-axis length for a 2-axis problem.
#[test]
fn bad_two_axis_input_is_a_typed_error() {
    let scene = riser(10, 0.0)
        .control_two_axis(10, ControlKind::Constant, &[[1.0, 2.0]])
        .build()
        .unwrap();
    let text = scene.to_toml_string();
    let with = |values: &str| text.replace("values = [[1.0, 2.0]]", values);
    assert!(text.contains("values = [[1.0, 2.0]]"), "{text}");
    let e = Scene::from_toml_str(&with("values = [[1.0, 2.0], 3.0]")).unwrap_err();
    let e = e.to_string();
    assert!(
        e.contains("control.values[1]") && e.contains("all pairs"),
        "{e}"
    );
    let e = Scene::from_toml_str(&with("values = [[1.0, 2.0, 3.0]]")).unwrap_err();
    let e = e.to_string();
    assert!(
        e.contains("control.values[0]") && e.contains("[u_x, u_z]"),
        "{e}"
    );
    let e = Scene::from_toml_str(&with("values = [[nan, 2.0]]")).unwrap_err();
    assert!(e.to_string().contains("control.values[0]"), "{e}");

    match Chain::<f64, 2>::from_scene(&scene) {
        Err(Error::NeedsSpatialModel { key }) => assert_eq!(key, "control.values"),
        other => panic!("expected NeedsSpatialModel, got {other:?}"),
    }
    let planar_scene = riser(10, 0.0).control_constant(10, 0.0).build().unwrap();
    let mut planar = Chain::<f64, 2>::from_scene(&planar_scene).unwrap();
    assert!(matches!(
        planar.set_control_x(&[1.0]),
        Err(Error::NeedsSpatialModel { .. })
    ));
    let mut spatial = Chain::<f64, 3>::from_scene(&planar_scene).unwrap();
    match spatial.set_control_x(&[1.0, f64::NAN]) {
        Err(Error::NotFinite { name, index }) => assert_eq!((name, index), ("control_x", 1)),
        other => panic!("expected NotFinite, got {other:?}"),
    }
    let p = ControlProblem::builder(&scene).build_in::<3>().unwrap();
    match p.value(&[1.0]) {
        Err(Error::WrongLength {
            name,
            expected,
            got,
        }) => assert_eq!((name, expected, got), ("theta", 2, 1)),
        other => panic!("expected WrongLength, got {other:?}"),
    }
    let r: AdjointResult<f64> = p.adjoint(&[1.0, 2.0], &[]).unwrap();
    assert_eq!(r.control_gradient_x.len(), 11);
}
