//! A pipe riser in a current and irregular waves (docs/ocean.md): what the model must show:
//!
//! - **Rotational symmetry**: the waves and the current turned together by ψ = 30°, 45°, 120°
//!   about the riser's axis y give the planar run (ψ = 0) rotated by ψ, to 1e-9 m at every node
//!   and step. Reference: the planar trajectory; the model (Morison drag on the relative
//!   momentum with the Euclidean transverse norm, the inertia load along the waves' direction)
//!   is exactly rotation-invariant, so the difference is round-off.
//! - **Exact gradients** of J = Σ_k M₀(t_k)² on a wave scene with respect to the controls and to
//!   the H_s-independent parameters D (the drag constant, C_d's stand-in), the top tension and
//!   the current's speed: the discrete adjoint = forward-mode Dual64 through the whole
//!   simulation (1e-12 relative) = five-point central differences (1e-6 relative), planar and
//!   spatial (waves at 40°, current at 40°). The scene is a `[pipe]`, so its drag is the
//!   per-pendulum Dᵢ = D wᵢ (docs/conventions.md "Equivalent drag constant"; asserted on).
//! - **No waves, every number as before**: the same scene without `[loads.waves]` is the
//!   current-only model bit for bit (`==` on the trajectories).

use chainbeam::adjoint::{adjoint_gradient, forward_value};
use chainbeam::*;
use num_dual::Dual64;

use crate::gradient_check;
use crate::rotation;

const H: f64 = 0.05;

/// A 100 m, 21" riser (D_o = 0.5334 m, t = 22.2 mm) of 10 pendulums in 100 m of water under
/// 2 MN top tension, a uniform 0.5 m/s current and a JONSWAP sea (H_s = 4 m, T_p = 10 s,
/// seed 7), both toward ψ (degrees from +z toward +x); `control`: a `[control]` table.
fn scene_text(psi: f64, steps: usize, control: &str) -> String {
    let [s, c] = chainbeam::scene::direction_of_angle(psi);
    format!(
        "[beam]\npendulums = 10\nsupport = \"riser\"\n\n\
         [pipe]\nlength = 100.0\nouter_diameter = 0.5334\nwall_thickness = 0.0222\n\n\
         [water]\ndepth = 100.0\n\n\
         [loads]\ndrag = 2e-6\ntension = 2e6\naxial_weight = 1500.0\n\n\
         [loads.current]\nprofile = \"uniform\"\nspeed = 0.5\ndirection = [{s:e}, {c:e}]\n\n\
         [loads.waves]\nspectrum = \"jonswap\"\nhs = 4.0\ntp = 10.0\nseed = 7\n\
         direction = {psi:e}\ncomponents = 400\n\n\
         [time]\nstep = {H}\nsteps = {steps}\n\n{control}"
    )
}

fn scene(psi: f64, steps: usize, control: &str) -> Scene {
    let text = scene_text(psi, steps, control);
    Scene::from_toml_str(&text).unwrap_or_else(|e| panic!("{e}\n{text}"))
}

/// max over steps and nodes of |R_ψ r_planar − r_ψ| and the largest transverse deflection.
fn rotated_difference(psi: f64) -> (f64, f64) {
    let steps = 240;
    let planar = simulate(&scene(0.0, steps, "")).unwrap();
    assert!(!planar.is_spatial());
    let turned = simulate(&scene(psi, steps, "")).unwrap();
    let [s, c] = chainbeam::scene::direction_of_angle(psi);
    rotation::rotated_gap(&planar, &turned, [s, c], steps)
}

#[test]
fn waves_and_current_turned_about_the_axis_turn_the_motion() {
    for psi in [30.0, 45.0, 120.0] {
        let (worst, reach) = rotated_difference(psi);
        println!("ψ = {psi}°: {worst:.1e} m off the rotated planar run (deflection {reach:.3} m)");
        assert!(reach > 0.05, "the riser deflects ({reach} m)");
        assert!(worst <= 1e-9, "ψ = {psi}°: {worst:e} m");
    }
    // ψ = 0 in the spatial model is the planar run exactly.
    let planar = simulate(&scene(0.0, 60, "")).unwrap();
    let mut s = scene(0.0, 60, "");
    s.loads.waves.as_mut().unwrap().direction = 360.0;
    let chain = Chain::<f64, 3>::from_scene(&s).unwrap();
    let spatial = simulate_chain(chain, H, 60, &vec![0.0; 61]).unwrap();
    for k in 0..=60 {
        let (a, b) = (planar.positions(k), spatial.positions(k));
        assert_eq!(a, b, "step {k}");
    }
}

#[test]
fn without_waves_the_current_model_is_unchanged() {
    let with = scene(30.0, 80, "");
    let mut without = with.clone();
    without.loads.waves = None;
    let text = scene_text(30.0, 80, "");
    let start = text.find("[loads.waves]").unwrap();
    let end = text.find("[time]").unwrap();
    let reread = Scene::from_toml_str(&format!("{}{}", &text[..start], &text[end..])).unwrap();
    assert_eq!(reread, without);
    let a = simulate(&without).unwrap();
    let b = simulate(&reread).unwrap();
    for k in 0..=80 {
        assert_eq!(a.positions(k), b.positions(k));
    }
    // And the waves do move the riser.
    let w = simulate(&with).unwrap();
    let moved = (0..=80).any(|k| w.positions(k) != a.positions(k));
    assert!(moved);
}

fn check_gradients<const DIM: usize>(scene: &Scene, params: &[(Parameter, f64)]) {
    let steps = scene.time.steps;
    let chain = Chain::<f64, DIM>::from_scene(scene).unwrap();
    let w = chain
        .drag_weights()
        .expect("a [pipe] scene's per-pendulum drag");
    assert!(w[0] == 1.0 && w[w.len() - 1] > 5.0, "{w:?}");
    let u = scene_controls(scene);
    let obj = BendingObjective::summed_moment();
    let ps: Vec<Parameter> = params.iter().map(|p| p.0).collect();
    let adj = adjoint_gradient(&chain, H, steps, &u, &obj, &ps, Checkpointing::default()).unwrap();
    let ud: Vec<Dual64> = u.iter().map(|&x| Dual64::from(x)).collect();
    let check = |label: String, adjoint: f64, fwd: f64, fd: f64| {
        println!("DIM {DIM}:");
        gradient_check::assert_derivative(&label, adjoint, fwd, fd);
    };
    for (i, &(p, value)) in params.iter().enumerate() {
        let mut ch = chain.lift::<Dual64>();
        ch.set_parameter(p, Dual64::new(value, 1.0)).unwrap();
        let fwd = forward_value(&ch, H, steps, &ud, &obj).unwrap().eps;
        let at = |v: f64| {
            let mut ch = chain.clone();
            ch.set_parameter(p, v).unwrap();
            forward_value(&ch, H, steps, &u, &obj).unwrap()
        };
        // The drag r|r| is C¹ only: where a relative momentum passes 0 the five-point rule's
        // error is O(d²), not O(d⁴) (measured for the current speed with the per-pendulum drag:
        // 2.4e-6 at d = 1e-3 of the value, 1.1e-7 at 1e-4; round-off stays below 1e-10).
        let fd = gradient_check::five_point(&at, value, 1e-4 * value);
        check(format!("{p:?}"), adj.parameter_gradient[i], fwd, fd);
    }
    for k in [0, steps / 3, steps - 1] {
        let mut seeded = ud.clone();
        seeded[k] = Dual64::new(u[k], 1.0);
        let fwd = forward_value(&chain.lift::<Dual64>(), H, steps, &seeded, &obj)
            .unwrap()
            .eps;
        let at = |v: f64| {
            let mut w = u.clone();
            w[k] = v;
            forward_value(&chain, H, steps, &w, &obj).unwrap()
        };
        let fd = gradient_check::five_point(&at, u[k], 10.0);
        check(format!("u[{k}]"), adj.control_gradient[k], fwd, fd);
    }
}

#[test]
fn gradients_on_a_wave_scene() {
    let steps = 60;
    let values: Vec<String> = (0..=steps)
        .map(|k| format!("{:e}", -2e4 * (0.1 * k as f64).sin()))
        .collect();
    let control = format!(
        "[control]\nkind = \"per-step\"\nvalues = [{}]\n",
        values.join(", ")
    );
    let params = [
        (Parameter::Drag, 2e-6),
        (Parameter::Tension, 2e6),
        (Parameter::CurrentSpeed, 0.5),
    ];
    let planar = scene(0.0, steps, &control);
    assert!(!planar.is_spatial());
    check_gradients::<2>(&planar, &params);
    let spatial = scene(40.0, steps, &control);
    assert!(spatial.is_spatial());
    check_gradients::<3>(&spatial, &params);
}

/// The shipped real-scale risers (`examples/scenes/riser_300m.toml`, `riser_1000m.toml`): their
/// derived numbers are the ones their comments derive from the pipe (the submerged weight
/// `Pipe::submerged_weight`, the tension 1.3 w L, the drag constant ½ ρ_w C_d D_o / (l μ² L),
/// each to the digits written, 2e-4), 600 s of the sea state, and a short run (the first 20 s) is finite
/// and bends the wellhead.
#[test]
fn shipped_real_scale_risers() {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("examples/scenes");
    for (file, depth) in [("riser_300m.toml", 300.0), ("riser_1000m.toml", 1000.0)] {
        let scene = Scene::from_file(dir.join(file)).unwrap();
        let pipe = scene.pipe.unwrap();
        let rho = scene.water.density;
        assert_eq!(pipe.length, depth);
        assert_eq!(scene.wave_depth(), depth);
        let w = pipe.submerged_weight(rho, chainbeam::ocean::STANDARD_GRAVITY);
        let close = |a: f64, b: f64| (a / b - 1.0).abs() < 2e-4;
        assert!(close(scene.loads.axial_weight, w), "{file}: w = {w}");
        assert!(
            close(scene.loads.tension, 1.3 * w * depth),
            "{file}: tension"
        );
        let l = depth / scene.n() as f64;
        let mu = pipe.mass_per_length(rho);
        let d = pipe.drag_per_length(rho) / (l * mu * mu * depth);
        assert!(close(scene.loads.drag, d), "{file}: D = {d:e}");
        assert_eq!(scene.time.steps as f64 * scene.time.step, 600.0);
        let mut short = scene.clone();
        short.time.steps = (20.0 / scene.time.step) as usize;
        let t = simulate(&short).unwrap();
        assert!(t.moment().iter().all(|m| m.is_finite()));
        let peak = t.moment().iter().fold(0.0f64, |a, m| a.max(m.abs()));
        assert!(peak > 1e3, "{file}: wellhead moment {peak} N m");
    }
}
