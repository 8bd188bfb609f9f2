//! The stack-up (`[stackup]`, docs/scene-format.md; docs/conventions.md "The stack-up"): the chain
//! it builds, its weights and drag, the shipped drilling-riser scene, and the keys it refuses.

use std::f64::consts::PI;
use std::path::Path;

use chainbeam::model::Ctx;
use chainbeam::scene::STANDARD_GRAVITY;
use chainbeam::statics::static_equilibrium;
use chainbeam::{Chain, Scene, SceneErrorKind};

fn shipped() -> Scene {
    let path =
        Path::new(env!("CARGO_MANIFEST_DIR")).join("examples/scenes/riser_300m_stackup.toml");
    Scene::from_file(path).expect("the shipped stack-up scene")
}

/// The heights of the joints 0..=n (node heights on the undeformed chain).
fn joint_heights(scene: &Scene) -> Vec<f64> {
    let mut y = vec![0.0];
    for l in &scene.beam.lengths {
        y.push(y.last().unwrap() + l);
    }
    y
}

fn has_joint_at(heights: &[f64], at: f64) -> bool {
    heights.iter().any(|h| (h - at).abs() < 1e-9)
}

/// Every forced pendulum end of the shipped scene is a joint (segment and body ends, the flex
/// joints, the mudline), the bodies are one pendulum each, and the chain has `beam.pendulums`
/// pendulums.
#[test]
fn pendulum_ends_fall_on_the_stackups_places() {
    let scene = shipped();
    let st = scene.stackup.as_ref().unwrap();
    assert_eq!(scene.n(), 100);
    let y = joint_heights(&scene);
    // From the file: conductor 60, wellhead 3, BOP 8, LMRP 5, then the riser's segments.
    let mut top = 0.0;
    for (name, length) in [
        ("conductor", 60.0),
        ("wellhead", 3.0),
        ("BOP", 8.0),
        ("LMRP", 5.0),
        ("riser_buoyant_1", 2.0 * 22.86),
        ("riser_buoyant_2", 4.0 * 22.86),
        ("riser_bare", 5.0 * 22.86),
        ("pups", 18.824),
        ("termination", 13.716),
    ] {
        top += length;
        assert!(
            has_joint_at(&y, top),
            "a joint at the top of {name} ({top} m)"
        );
    }
    assert!(
        (y[scene.n()] - top).abs() < 1e-9,
        "the chain is the stack-up's length"
    );
    assert!(has_joint_at(&y, 60.0), "the mudline");
    for body in ["BOP", "LMRP"] {
        let count = st.layout.parts.iter().filter(|p| *p == body).count();
        assert_eq!(count, 1, "{body} is one pendulum");
    }
    // The lower flex joint sits on the LMRP's top, the upper one is the tip spring.
    let lfj = y.iter().position(|h| (h - 76.0).abs() < 1e-9).unwrap();
    assert_eq!(scene.beam.stiffness[lfj - 1], 2.865e6);
    assert_eq!(scene.beam.tip_stiffness, 1.146e6);
}

/// The chain's weights are the stack-up's, computed here from the file's numbers independently
/// of the library's section code: Σ node weights = the whole stack-up's submerged weight less the
/// half of the first pendulum that node 0 (the fixed foot) would carry; the bodies' weights appear
/// as steps of the axial force at their ends.
#[test]
fn weights_are_the_stackups() {
    let scene = shipped();
    let st = scene.stackup.as_ref().unwrap();
    let (g, rw) = (STANDARD_GRAVITY, 1025.0);
    let inch = 0.0254;
    let area = |d: f64| PI / 4.0 * d * d;
    let pipe = |od: f64, wall: f64| {
        let di = od - 2.0 * wall;
        (
            7850.0 * (area(od) - area(di)),
            1437.912 * area(di),
            area(od),
        )
    };
    let lines = 192.745;
    let line_area = 0.041803;
    // w = g (m_air − ρ_w A_displaced) per segment
    let w_seg = |od: f64, wall: f64, buoy: Option<(f64, f64)>, with_lines: bool| {
        let (steel, mud, ao) = pipe(od, wall);
        let (foam, disp) = match buoy {
            Some((bd, rho)) => (rho * (area(bd) - ao), area(bd)),
            None => (0.0, ao),
        };
        let (lm, la) = if with_lines {
            (lines, line_area)
        } else {
            (0.0, 0.0)
        };
        g * (steel + mud + foam + lm - rw * (disp + la))
    };
    let thick = 0.875 * inch;
    let thin = 0.625 * inch;
    let od = 21.0 * inch;
    let segments = [
        (w_seg(0.9144, 0.0381, None, false), 60.0),
        (w_seg(0.9144, 0.0508, None, false), 3.0),
        (w_seg(od, thick, Some((1.1938, 416.48)), true), 2.0 * 22.86),
        (w_seg(od, thin, Some((1.2192, 496.57)), true), 4.0 * 22.86),
        (w_seg(od, thin, None, true), 5.0 * 22.86),
        (w_seg(od, thick, None, true), 18.824 + 13.716),
    ];
    let bodies = 2.1315e6 + 8.526e5;
    let total: f64 = segments.iter().map(|(w, l)| w * l).sum::<f64>() + bodies;
    let l1 = scene.beam.lengths[0];
    let expect = total - 0.5 * segments[0].0 * l1;
    let got: f64 = st.layout.node_weights.iter().sum();
    assert!(
        ((got - expect) / expect).abs() < 1e-12,
        "Σ node weights {got} vs {expect}"
    );
    // The riser and the LMRP (what the tensioner holds, the file's tension 1.3 ×): the axial
    // force at the BOP's top is T − (weights above it).
    let y = joint_heights(&scene);
    let bop_top = y.iter().position(|h| (h - 71.0).abs() < 1e-9).unwrap();
    let above: f64 = st.layout.node_weights[bop_top - 1..].iter().sum();
    // Node bop_top (1-based) carries half the BOP's weight too.
    let hanging = above - 0.5 * 2.1315e6;
    let riser_lmrp = segments[2..].iter().map(|(w, l)| w * l).sum::<f64>() + 8.526e5;
    assert!(
        ((hanging - riser_lmrp) / riser_lmrp).abs() < 1e-12,
        "{hanging} vs {riser_lmrp}"
    );
    assert!((1.3 * riser_lmrp - scene.loads.tension).abs() < 1e-3 * scene.loads.tension);
}

/// The stack-up's momentum drag at rest in a uniform current is Morison's load on every
/// pendulum: Dᵢ|Pᵢ|² = lᵢ Σ_{k≥i} F_k U² (docs/conventions.md "The stack-up's drag"; F_k the
/// node drag coefficients, zero in the soil) to 1e-12.
#[test]
fn drag_in_a_uniform_current_is_morisons_load() {
    let scene = shipped();
    let st = scene.stackup.as_ref().unwrap();
    let u = 0.5;
    let chain = Chain::<f64, 2>::from_scene(&scene).unwrap();
    let ctx = Ctx::new(0.0, 0.0, 0);
    let mut suffix = 0.0;
    let n = scene.n();
    let mut expect = vec![0.0; n];
    for i in (0..n).rev() {
        suffix += st.layout.node_drag[i];
        expect[i] = scene.beam.lengths[i] * suffix * u * u;
    }
    for i in 0..n {
        let f = chain.dissipative_force(i, &[0.0; 2], &ctx).unwrap();
        let rel = (f[1] - expect[i]).abs() / expect[0];
        assert!(
            rel < 1e-12,
            "pendulum {i}: {} vs {} ({rel:e})",
            f[1],
            expect[i]
        );
    }
    // The conductor's nodes (below the mudline) have no drag coefficient.
    let y = joint_heights(&scene);
    for i in 0..n {
        if y[i + 1] < 60.0 - 1e-9 {
            assert_eq!(st.layout.node_drag[i], 0.0);
        }
    }
}

/// The shipped scene reads back from its own text (`to_toml_string`), runs its 10 s from rest,
/// and stands in the current with a sane static offset: toward the current, the top's offset a
/// small fraction of the depth, the conductor held by the soil (its head moving far less than the
/// top).
#[test]
fn the_shipped_scene_round_trips_runs_and_stands() {
    let scene = shipped();
    let again = Scene::from_toml_str(&scene.to_toml_string()).unwrap();
    assert_eq!(again, scene);
    let traj = chainbeam::simulate(&scene).unwrap().into_planar().unwrap();
    assert!(traj.moment.iter().all(|x| x.is_finite()));
    let last = traj.positions(traj.steps());
    let top_dyn = last[scene.n() - 1][2];
    println!("after 10 s from rest: top z {top_dyn:.4} m");
    assert!(top_dyn.is_finite() && top_dyn.abs() < 0.05 * 300.0);
    let sol = static_equilibrium(&scene).unwrap();
    let y = joint_heights(&scene);
    let mudline = y.iter().position(|h| (h - 60.0).abs() < 1e-9).unwrap();
    let top = sol.positions[scene.n() - 1][1];
    let head = sol.positions[mudline - 1][1];
    println!("static offset: top {top:.3} m, conductor head {head:.4} m");
    assert!(top > 0.0 && top < 0.05 * 300.0, "top offset {top}");
    assert!(head.abs() < 0.1 * top, "head {head} vs top {top}");
}

/// A one-segment stack-up of a pipe is the `[pipe]` chain (the one-segment case): the same
/// lengths, masses and springs.
#[test]
fn one_segment_is_the_pipe_chain() {
    let pipe = "[beam]\npendulums = 12\nsupport = \"riser\"\n\n[pipe]\nlength = 60.0\n\
                outer_diameter = 0.5334\nwall_thickness = 0.022225\ncontents_density = 1437.9\n\n\
                [time]\nstep = 0.01\nsteps = 5\n";
    let stack = "[beam]\npendulums = 12\nsupport = \"riser\"\n\n[time]\nstep = 0.01\nsteps = 5\n\n\
                 [stackup]\n[[stackup.segment]]\nname = \"riser\"\nlength = 20.0\njoints = 3\n\
                 outer_diameter = 0.5334\nwall_thickness = 0.022225\ncontents_density = 1437.9\n";
    let a: Scene = pipe.parse().unwrap();
    let b: Scene = stack.parse().unwrap();
    let close = |x: &[f64], y: &[f64]| {
        x.iter()
            .zip(y)
            .all(|(p, q)| (p - q).abs() <= 1e-12 * p.abs().max(q.abs()))
    };
    assert!(close(&a.beam.lengths, &b.beam.lengths));
    assert!(close(&a.beam.masses, &b.beam.masses));
    assert!(close(&a.beam.stiffness, &b.beam.stiffness));
    assert!(close(
        &[a.beam.base_stiffness, a.beam.tip_stiffness],
        &[b.beam.base_stiffness, b.beam.tip_stiffness]
    ));
}

fn key_of(text: &str) -> String {
    match Scene::from_toml_str(text).unwrap_err().kind {
        SceneErrorKind::InvalidValue { key, .. }
        | SceneErrorKind::MissingKey { key, .. }
        | SceneErrorKind::ExclusiveKeys { key, .. } => key,
        other => panic!("{other:?}"),
    }
}

/// Bad stack-up and soil values are refused with the key named.
#[test]
fn bad_values_name_their_key() {
    let base = "[beam]\npendulums = 6\nsupport = \"riser\"\n\n[time]\nstep = 0.001\nsteps = 5\n\n\
                [soil]\nmudline = 1.0\nmodulus = 1e4\n\n[stackup]\n\n\
                [[stackup.segment]]\nname = \"a\"\nlength = 2.0\nouter_diameter = 0.5\n\
                wall_thickness = 0.02\n\n\
                [[stackup.body]]\nname = \"c\"\nabove = \"a\"\nmass = 300.0\n\
                submerged_weight = 2000.0\nheight = 1.0\n\n\
                [[stackup.flex_joint]]\nname = \"f\"\nabove = \"c\"\nstiffness = 1e5\n";
    Scene::from_toml_str(base).unwrap();
    for (from, to, key) in [
        ("modulus = 1e4", "modulus = -1.0", "soil.modulus"),
        ("mudline = 1.0", "mudline = 9.0", "soil.mudline"),
        ("above = \"a\"", "above = \"x\"", "stackup.body[0].above"),
        ("mass = 300.0", "mass = 0.0", "stackup.body[0].mass"),
        (
            "wall_thickness = 0.02",
            "wall_thickness = 0.3",
            "stackup.segment[0].wall_thickness",
        ),
        (
            "length = 2.0",
            "length = 2.0\nbuoyancy_diameter = 0.8",
            "stackup.segment[0].buoyancy_density",
        ),
        (
            "stiffness = 1e5",
            "stiffness = -1.0",
            "stackup.flex_joint[0].stiffness",
        ),
        (
            "above = \"c\"",
            "above = \"c\"\nelevation = 1.0",
            "stackup.flex_joint[0].elevation",
        ),
        ("above = \"c\"", "elevation = 2.5", "stackup.flex_joint"),
        ("pendulums = 6", "pendulums = 2", "beam.pendulums"),
        (
            "support = \"riser\"",
            "support = \"fixed-fixed\"",
            "beam.support",
        ),
        (
            "steps = 5\n",
            "steps = 5\n\n[loads]\ndrag = 1.0\n",
            "loads.drag",
        ),
        (
            "steps = 5\n",
            "steps = 5\n\n[loads]\naxial_weight = 1.0\n",
            "loads.axial_weight",
        ),
        (
            "support = \"riser\"",
            "support = \"riser\"\nlength = 1.0",
            "beam.length",
        ),
    ] {
        assert!(base.contains(from), "{from}");
        let text = base.replacen(from, to, 1);
        assert_eq!(key_of(&text), key, "{to}");
    }
}

/// Waves on the stack-up: the shipped scene in a JONSWAP sea runs, and the nodes in the soil
/// move no water. The waves' share of pendulum i's water momentum is Wᵢ = lᵢ Σ_{k≥i} m_k u_k
/// and its inertia Gᵢ = lᵢ Σ_{k≥i} c_k u̇_k (docs/conventions.md "Waves on the chain"), so for
/// every pendulum whose nodes up to the mudline are all in the soil, Wᵢ/lᵢ and Gᵢ/lᵢ are those of
/// the pendulum just below the mudline: the soil's nodes add nothing (to 1e-12).
#[test]
fn waves_stop_at_the_mudline() {
    let mut scene = shipped();
    let mut w = chainbeam::scene::Waves::jonswap(2.0, 8.0);
    w.components = Some(64);
    w.lumping = chainbeam::scene::WaveLumping::Cell;
    scene.loads.waves = Some(w);
    scene.time.steps = 50;
    scene.validate().unwrap();
    let chain = Chain::<f64, 2>::from_scene(&scene).unwrap();
    let field = chain.waves().expect("the scene has waves");
    let y = joint_heights(&scene);
    let last_soil = (0..scene.n())
        .filter(|&i| y[i + 1] <= 60.0 + 1e-9)
        .max()
        .unwrap();
    let l = &scene.beam.lengths;
    for t in [3.0, 7.5] {
        let (w0, g0) = (
            field.momentum(last_soil, t) / l[last_soil],
            field.inertia(last_soil, t) / l[last_soil],
        );
        assert!(
            w0.abs() > 0.0 && g0.abs() > 0.0,
            "the waves reach the wet nodes"
        );
        for (i, li) in l.iter().enumerate().take(last_soil) {
            let (wi, gi) = (field.momentum(i, t) / li, field.inertia(i, t) / li);
            assert!(
                (wi - w0).abs() <= 1e-12 * w0.abs(),
                "W at {i}: {wi} vs {w0}"
            );
            assert!(
                (gi - g0).abs() <= 1e-12 * g0.abs(),
                "G at {i}: {gi} vs {g0}"
            );
        }
    }
    let traj = chainbeam::simulate(&scene).unwrap().into_planar().unwrap();
    assert!(traj.moment.iter().all(|x| x.is_finite()));
}

/// A stack-up whose layout was not computed for its chain (a scene assembled in code) is refused
/// by the validation, naming `stackup`, instead of reaching the model.
#[test]
fn a_stackup_without_its_layout_is_refused() {
    let mut scene = shipped();
    scene.stackup.as_mut().unwrap().layout = chainbeam::scene::Layout::default();
    let err = scene.validate().unwrap_err();
    match err.kind {
        SceneErrorKind::InvalidValue { key, .. } => assert_eq!(key, "stackup"),
        other => panic!("{other:?}"),
    }
    assert!(Chain::<f64, 2>::from_scene(&scene).is_err());
}
