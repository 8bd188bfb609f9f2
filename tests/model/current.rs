//! Drag relative to a current along the depth: F = F_D(p − P) (Morison's drag,
//! transversally −D |r_⊥| r_⊥ with the Euclidean norm, axially −D r_y|r_y|) with
//! Pᵢ = lᵢ Σ_{k≥i} m_k U(y_k) (docs/conventions.md, "Drag in a current").
//!
//! References: the still-water drag of thesis eq. 2.4.4, which a zero current must reproduce
//! exactly (P = 0, p − 0 = p: equal trajectories in IEEE arithmetic, compared with `==`); the
//! planar model, which the spatial one must reproduce for a current along z (1e-12); the symmetry
//! of the model under the signed permutations of (x, z) (a quarter turn, a mirror, the swap
//! x ↔ z), under which the drag is invariant (as under every rotation about y), so the motion follows the current
//! exactly (to round-off, 1e-12); forward-mode dual numbers (1e-12) and central differences (1e-6)
//! for the adjoint's gradients with respect to the current's speed, D and the mass; and the
//! static solver (an independent method, in angle coordinates) for the state a long simulation
//! settles to, as the thesis checks eq. 2.4.4 in §2.4.4.

use chainbeam::statics::{static_equilibrium, static_equilibrium_at};
use chainbeam::*;

use crate::gradient_check;
use crate::settle;

const H: f64 = 0.01;

/// The thesis riser (n = 10, l = 1 m, m = 1 kg, k = 1000, k₁ = k₁₁ = 2000) with drag D = 10,
/// h = 0.01 s, N = `steps`, no loads.
fn riser(steps: usize) -> SceneBuilder {
    SceneBuilder::new(10)
        .support(Support::Riser)
        .base_stiffness(2000.0)
        .tip_stiffness(2000.0)
        .drag(10.0)
        .step(H)
        .steps(steps)
}

/// The trajectory of `scene` in the model of dimension DIM, with the scene's controls.
fn run<const DIM: usize>(scene: &Scene) -> Trajectory<f64, DIM> {
    let chain = Chain::<f64, DIM>::from_scene(scene).unwrap();
    simulate_chain(
        chain,
        scene.time.step,
        scene.time.steps,
        &scene_controls(scene),
    )
    .unwrap()
}

/// Whether two runs have equal q and p at every step (IEEE `==`, so ±0 compare equal).
fn identical<const DIM: usize>(a: &Trajectory<f64, DIM>, b: &Trajectory<f64, DIM>) -> bool {
    (0..=a.steps()).all(|k| a.q(k) == b.q(k) && a.p(k) == b.p(k))
}

/// max over k and nodes of |f(r_a) − r_b| (componentwise, positions (x, y, z)).
fn max_difference(
    a: &SceneTrajectory,
    b: &SceneTrajectory,
    map: impl Fn([f64; 3]) -> [f64; 3],
) -> f64 {
    let mut worst: f64 = 0.0;
    for k in 0..=a.steps() {
        for (ra, rb) in a.positions(k).into_iter().zip(b.positions(k)) {
            let ra = map(ra);
            for d in 0..3 {
                worst = worst.max((ra[d] - rb[d]).abs());
            }
        }
    }
    worst
}

/// A current of speed 0 (each profile) gives exactly the still-water drag's trajectory: with a
/// point load, a control and drag, planar and (a zero current along x) spatial.
#[test]
fn zero_current_is_the_still_water_drag() {
    let base = riser(300)
        .point_load(5, 2.0)
        .control_constant(10, -0.5)
        .build()
        .unwrap();
    let still2 = run::<2>(&base);
    let still3 = run::<3>(&base);
    let zero = [
        Current::uniform(0.0, [0.0, 1.0]),
        Current::linear(0.0, 0.0, [0.0, -1.0]),
        Current::power_law(0.0, 1.0 / 7.0, [0.0, 1.0]).with_surface(12.0),
        Current::table(vec![[0.0, 0.0, 0.0], [4.0, 0.0, 90.0], [9.0, 0.0, 200.0]]),
        Current::uniform(0.0, [1.0, 0.0]),
    ];
    for c in zero {
        let mut s = base.clone();
        s.loads.current = Some(c.clone());
        let chain = Chain::<f64, 3>::from_scene(&s).unwrap();
        assert!(chain.current_drag().is_some() && chain.drag().is_none());
        assert!(identical(&run::<3>(&s), &still3), "{c:?} (spatial)");
        if !s.is_spatial() {
            assert!(identical(&run::<2>(&s), &still2), "{c:?} (planar)");
        }
    }
    // and the current's parameter is there, at speed 0
    let mut s = base.clone();
    s.loads.current = Some(Current::uniform(0.0, [0.0, 1.0]));
    assert!(Chain::<f64, 2>::from_scene(&s)
        .unwrap()
        .has_parameter(Parameter::CurrentSpeed));
}

/// A sheared current along z: the spatial model keeps x = 0 and agrees with the planar model to
/// 1e-12 (positions and momenta), and the beam drifts along +z (the current's direction).
#[test]
fn current_along_z_is_planar() {
    let scene = riser(400)
        .current(Current::linear(0.8, 0.2, [0.0, 1.0]))
        .build()
        .unwrap();
    assert!(!scene.is_spatial());
    let (t2, t3) = (run::<2>(&scene), run::<3>(&scene));
    let mut err: f64 = 0.0;
    for k in 0..=400 {
        for (a, b) in t2
            .q(k)
            .iter()
            .zip(t3.q(k))
            .chain(t2.p(k).iter().zip(t3.p(k)))
        {
            assert!(b[0] == 0.0, "x left the plane");
            err = err.max((a[0] - b[1]).abs()).max((a[1] - b[2]).abs());
        }
    }
    println!("max |2D − 3D| over 400 steps: {err:e}");
    assert!(err <= 1e-12);
    let tip = t2.positions(400)[9];
    assert!(
        tip[2] > 0.0,
        "the current pushes toward +z: tip z = {}",
        tip[2]
    );
}

/// The drag is invariant under the signed permutations of (x, z), and so is the rest of the
/// model: a current turned by 90° (along +x) turns the motion by 90°, a current along −z mirrors
/// it, and a current at 45° gives x = z at every node and time (1e-12). Morison's drag acts on
/// the transverse momentum with its Euclidean norm, so a general rotation is a symmetry too: the
/// 45° beam drifts as far as the in-plane one, turned by 45° (1e-9 m; the thesis's
/// per-component drag made it drift less far; tests/model/drag_rotation.rs turns loads and controls
/// as well).
#[test]
fn quarter_turns_and_mirrors_of_the_current_move_the_beam_alike() {
    let scene = |dir: [f64; 2]| {
        riser(400)
            .current(Current::linear(0.8, 0.2, dir))
            .build()
            .unwrap()
    };
    let along_z = simulate(&scene([0.0, 1.0])).unwrap();
    let along_x = simulate(&scene([1.0, 0.0])).unwrap();
    let against_z = simulate(&scene([0.0, -1.0])).unwrap();
    let diagonal = simulate(&scene([1.0, 1.0])).unwrap();
    assert!(along_x.is_spatial() && !against_z.is_spatial());
    let turned = max_difference(&along_z, &along_x, |[_, y, z]| [z, y, 0.0]);
    let mirrored = max_difference(&along_z, &against_z, |[x, y, z]| [x, y, -z]);
    let swapped = max_difference(&diagonal, &diagonal, |[x, y, z]| [z, y, x]);
    println!("quarter turn {turned:e}, mirror {mirrored:e}, x↔z swap at 45° {swapped:e}");
    assert!(turned <= 1e-12 && mirrored <= 1e-12 && swapped <= 1e-12);
    let (tip_z, tip_d) = (along_z.positions(400)[9], diagonal.positions(400)[9]);
    let reach = tip_d[0].hypot(tip_d[2]);
    println!("tip drift: along z {:.6} m, at 45° {reach:.6} m", tip_z[2]);
    assert!((reach - tip_z[2]).abs() <= 1e-9, "{reach} vs {}", tip_z[2]);
}

/// Gradients with a current present (planar: a sheared current along z with a point load and a
/// constant control; spatial: the current at (0.6, 0.8) and a tabulated one): ∂J/∂θ for the
/// current's speed, D and the mass by the adjoint = forward-mode Dual64 (1e-12 relative) =
/// central differences (1e-6), J = Σ M₀².
#[test]
fn gradients_with_a_current() {
    let build = |c: Current| {
        riser(40)
            .point_load(6, 1.3)
            .current(c)
            .control_constant(10, -0.4)
            .objective(ObjectiveKind::Sum)
            .build()
            .unwrap()
    };
    let params = [
        (Parameter::CurrentSpeed, 0.8),
        (Parameter::Drag, 10.0),
        (Parameter::Mass, 1.0),
    ];
    let planar = build(Current::linear(0.8, 0.3, [0.0, 1.0]));
    check_gradients::<2>(&planar, &params);
    let spatial = build(Current::power_law(0.8, 0.25, [0.6, 0.8]));
    assert!(spatial.is_spatial());
    check_gradients::<3>(&spatial, &params);
    let table = Current::table(vec![[0.0, 0.9, 30.0], [6.0, 0.4, 60.0], [10.0, 0.1, 60.0]]);
    check_gradients::<3>(&build(table), &params[1..]);
}

/// dJ/dθ of `params` on `scene` in the model of dimension DIM over 40 steps
/// ([`gradient_check::check_parameters`]; five-point central difference, δ = 1e-3·|θ|:
/// truncation O(δ⁴)).
fn check_gradients<const DIM: usize>(scene: &Scene, params: &[(Parameter, f64)]) {
    let chain = Chain::<f64, DIM>::from_scene(scene).unwrap();
    let u = scene_controls(scene);
    gradient_check::check_parameters(&chain, &u, params, (H, 40), |value| 1e-3 * value);
}

/// [`settle::settle`] under the scene's last control value.
fn settle(scene: &Scene, v_tol: f64, t_max: f64) -> (Vec<[f64; 2]>, f64) {
    let u = *scene_controls(scene).last().unwrap_or(&0.0);
    settle::settle(scene, u, v_tol, t_max)
}

/// The current's steady drag gives a static offset: the static solver (angle coordinates, the
/// current's drag at rest D P⊙|P| as a load) against a long simulation with strong damping
/// (D = 100) settling onto it, for a sheared current alone, a power-law current against a point
/// load, and a tabulated current on a cantilever, to 1e-6 (the reference is the independent
/// dynamic simulation). Near rest the current's drag is linear in p (slope 2D|P|), so the beam
/// settles exponentially, unlike the still-water drag's creep.
#[test]
fn statics_with_a_current_is_where_the_simulation_settles() {
    let riser100 = || riser(10).drag(100.0);
    let cases = [
        (
            "sheared",
            riser100().current(Current::linear(0.1, 0.02, [0.0, 1.0])),
        ),
        (
            "power law against a load",
            riser100()
                .current(Current::power_law(0.15, 1.0 / 7.0, [0.0, 1.0]))
                .point_load(7, 3.0),
        ),
        (
            "table, cantilever",
            riser100().support(Support::Cantilever).current(
                Current::table(vec![[0.0, 0.12, 180.0], [5.0, 0.05, 180.0]]).with_surface(9.5),
            ),
        ),
    ];
    for (name, b) in cases {
        let scene = b.build().unwrap();
        let stat = static_equilibrium(&scene).unwrap();
        let (end, t) = settle(&scene, 1e-9, 5000.0);
        let mut dev: f64 = 0.0;
        for (r, s) in end.iter().zip(&stat.positions) {
            dev = dev.max((r[0] - s[0]).abs()).max((r[1] - s[1]).abs());
        }
        let tip = stat.positions[9][1];
        println!(
            "{name}: settled after {t:.0} s; tip z = {tip:.6} m; |dynamic − static| = {dev:.2e}"
        );
        assert!(tip.abs() > 1e-3, "{name}: a visible offset");
        assert!(dev <= 1e-6, "{name}: {dev:e}");
    }
}

/// `static_equilibrium_at` freezes time-varying loads at t: a ramped harmonic at t equals the
/// constant load of its value F(t) (the same force terms, so the same Newton iterates: equal).
#[test]
fn statics_at_a_time_freezes_the_loads() {
    let wave = Harmonic {
        amplitude: 2.0,
        period: 8.0,
        phase: 0.3,
    };
    let t = 5.3;
    let harmonic = riser(10)
        .load(PointLoad::harmonic(5, [0.0, 1.0], vec![wave]).ramped(8.0))
        .build()
        .unwrap();
    let ramp = 0.5 * (1.0 - (std::f64::consts::PI * t / 8.0).cos());
    let value = 2.0 * (0.3 + std::f64::consts::TAU * t / 8.0).sin() * ramp;
    let constant = riser(10).point_load(5, value).build().unwrap();
    let a = static_equilibrium_at(&harmonic, t, 0.0).unwrap();
    let b = static_equilibrium(&constant).unwrap();
    for (x, y) in a.positions.iter().zip(&b.positions) {
        assert!((x[0] - y[0]).abs() <= 1e-14 && (x[1] - y[1]).abs() <= 1e-14);
    }
    assert!(a.positions[9][1].abs() > 1e-4);
}

/// A scene file with `loads` after a 4-pendulum cantilever, in a temporary directory.
fn scene_file(loads: &str) -> (tempfile::TempDir, std::path::PathBuf) {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("current.toml");
    let beam = "[beam]\npendulums = 4\nlength = 1.0\nmass = 1.0\nstiffness = 100.0\n\
                support = \"cantilever\"\n[time]\nstep = 0.01\nsteps = 10\n";
    std::fs::write(&path, format!("{beam}{loads}")).unwrap();
    (dir, path)
}

/// Bad `[loads.current]` tables: the error names the file and the key, and says what is wrong.
#[test]
fn bad_currents_name_the_key_and_the_file() {
    let d = "[loads]\ndrag = 10.0\n[loads.current]\n";
    let cases: &[(&str, &str, &[&str])] = &[
        (
            "profile = \"table\"\ntable = [[0.0, 1.0, 0.0], [-2.0, 0.5, 0.0]]\n",
            "loads.current.table[1]",
            &["depth must be 0 or more", "got -2"],
        ),
        (
            "profile = \"table\"\ntable = [[0.0, 1.0, 0.0], [3.0, 0.5, 0.0], [2.0, 0.5, 0.0]]\n",
            "loads.current.table[2]",
            &["depths must increase strictly: 2 after 3"],
        ),
        (
            "profile = \"table\"\ntable = [[0.0, 1.0]]\n",
            "loads.current.table[0]",
            &["3 values [depth, speed, direction], got 2"],
        ),
        (
            "profile = \"table\"\ntable = [[0.0, nan, 0.0]]\n",
            "loads.current.table[0]",
            &["must be finite, got NaN"],
        ),
        (
            "profile = \"uniform\"\nspeed = 1.0\ndirection = [0.0, 0.0]\n",
            "loads.current.direction",
            &["non-zero length"],
        ),
        (
            "profile = \"linear\"\nspeed = inf\n",
            "loads.current.speed",
            &["must be finite"],
        ),
        (
            "profile = \"uniform\"\nspeed = -1.0\n",
            "loads.current.speed",
            &["must be a speed in [0, 1000] m/s"],
        ),
        (
            "profile = \"power\"\nspeed = 1.0\nexponent = 0.0\n",
            "loads.current.exponent",
            &["must be positive"],
        ),
        (
            "profile = \"uniform\"\nspeed = 1.0\nsurface = -3.0\n",
            "loads.current.surface",
            &["must be positive"],
        ),
        (
            "profile = \"uniform\"\nspeed = 1.0\nbottom_speed = 0.5\n",
            "loads.current.bottom_speed",
            &["not used by profile = \"uniform\""],
        ),
        (
            "profile = \"power\"\n",
            "loads.current.speed",
            &["required by profile = \"power\""],
        ),
        (
            "profile = \"spiral\"\nspeed = 1.0\n",
            "loads.current.profile",
            &["spiral"],
        ),
    ];
    for (body, key, texts) in cases {
        let (_dir, path) = scene_file(&format!("{d}{body}"));
        let err = Scene::from_file(&path).unwrap_err();
        let msg = err.to_string();
        println!("{msg}");
        assert_eq!(err.key(), Some(*key), "{msg}");
        assert!(msg.starts_with(&path.display().to_string()), "{msg}");
        for t in *texts {
            assert!(msg.contains(t), "{msg} lacks {t}");
        }
    }
    // a current whose steady drag D·|P|² no step could resolve: the load number names time.step
    let (_dir, path) = scene_file(
        "[loads]\ndrag = 1e12\n[loads.current]\nprofile = \"uniform\"\nspeed = 1000.0\n",
    );
    let err = Scene::from_file(&path).unwrap_err();
    assert_eq!(err.key(), Some("time.step"), "{err}");
    assert!(err.to_string().contains("the load number"), "{err}");
    // a current without drag
    let (_dir, path) = scene_file("[loads.current]\nprofile = \"uniform\"\nspeed = 1.0\n");
    let err = Scene::from_file(&path).unwrap_err();
    assert_eq!(err.key(), Some("loads.drag"), "{err}");
    assert!(err
        .to_string()
        .contains("must be positive when the scene has a current"));
    // the planar model refuses a current with an x component, naming the key
    let (_dir, path) = scene_file(&format!(
        "{d}profile = \"uniform\"\nspeed = 1.0\ndirection = [1.0, 1.0]\n"
    ));
    let scene = Scene::from_file(&path).unwrap();
    match Chain::<f64, 2>::from_scene(&scene) {
        Err(Error::NeedsSpatialModel { key }) => assert_eq!(key, "loads.current.direction"),
        other => panic!("{other:?}"),
    }
}

/// Every key of `[loads.current]` round-trips through `to_toml_string`, for each profile.
#[test]
fn currents_round_trip() {
    for c in [
        Current::uniform(0.5, [0.0, -1.0]),
        Current::linear(0.5, 0.1, [0.3, 0.4]).with_surface(20.0),
        Current::power_law(0.5, 0.2, [0.0, 1.0]),
        Current::table(vec![[0.0, 0.5, 10.0], [2.0, 0.3, 45.0]]),
    ] {
        let scene = riser(10).current(c).build().unwrap();
        let text = scene.to_toml_string();
        assert_eq!(Scene::from_toml_str(&text).unwrap(), scene, "{text}");
    }
}
