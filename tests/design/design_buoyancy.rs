//! The buoyancy modules of a named stack-up segment as a design parameter
//! (`stackup.segment.<name>.buoyancy_diameter`): the name read from `[design]` and its
//! refusals (no such segment, a segment without modules, a lower bound below the pipe's outer
//! diameter), the chain laid out again when it is set, the exact derivatives of the layout's
//! per-node quantities against central differences of the layout, and the design gradient
//! (the cell's adjoint sweep through the chain's node tangents) against the forward mode
//! (every cell run in `Dual64` with the node quantities seeded) and against central
//! differences of the scatter-diagram damage at two designs; its refusal with the momentum
//! drag. The same gradient at a named hot spot: tests/design/design_buoyancy_hotspot.rs.
//!
//! The reduced riser system of tests/design/design_vessel.rs: its 91.44 m of riser with
//! buoyancy modules (`riser_buoyant`, 47 in = 1.1938 m, foam 416.48 kg/m³, the Morison
//! diameter following the modules) under 205.74 m of bare riser, Morison's drag node by node,
//! the vessel with its surge RAO, the current and the sea; 8 pendulums at h = 0.02 s, two cells
//! of 10 s records.

use crate::design_study::{check_buoyancy_designs, eval, study, values};
use crate::design_vessel::scene_text;
use chainbeam::design::{DesignError, DesignParameter, DesignPoint, Execution, Want};
use chainbeam::fatigue::ScatterCell;
use chainbeam::Scene;

const NAME: &str = "stackup.segment.riser_buoyant.buoyancy_diameter";

fn design(name: &str, lower: &str, upper: &str) -> String {
    format!(
        "[design]\n[[design.parameter]]\nname = \"{name}\"\nlower = {lower}\nupper = {upper}\n\n\
         [[design.parameter]]\nname = \"loads.tension\"\nlower = 1.0e6\nupper = 3.0e6\n"
    )
}

fn scene() -> Scene {
    Scene::from_toml_str(&scene_text("", &design(NAME, "0.6", "1.5"))).unwrap()
}

fn buoyancy() -> DesignParameter {
    DesignParameter::BuoyancyDiameter("riser_buoyant".into())
}

/// Two sea states (probabilities 0.7, 0.3), those of tests/design/design_vessel.rs.
fn cells() -> Vec<ScatterCell> {
    crate::design_study::cells(&[(1.5, 7.0, 0.7), (3.0, 9.5, 0.3)])
}

/// The name reads from `[design]` (unit m, positive, no library parameter: a node quantity), its
/// value is the segment's 1.1938 m, and setting it lays the chain out again: thinner modules
/// (1.0 m) make the buoyant segment's nodes lighter and heavier in water (less foam, less
/// displaced water: foam 416.48 kg/m³ is lighter than the water), the bare segment's nodes
/// above it unchanged; the table written back reads as itself.
#[test]
fn buoyancy_diameter_is_a_named_parameter_that_relays_the_chain() {
    let scene = scene();
    let table = scene.design.as_ref().unwrap();
    let p = buoyancy();
    assert_eq!(table.parameters[0].parameter, p);
    assert_eq!(p.name(), NAME);
    assert_eq!(DesignParameter::from_name(NAME), Some(p.clone()));
    assert_eq!(p.unit(), "m");
    assert!(!p.is_signed());
    assert!(p.is_node_quantity());
    assert_eq!(p.parameter(&scene), None);
    assert_eq!(p.value(&scene), Ok(1.1938));
    let mut s = scene.clone();
    p.set(&mut s, 1.0).unwrap();
    assert_eq!(p.value(&s), Ok(1.0));
    let parts = &scene.stackup.as_ref().unwrap().layout.parts;
    let (w0, w1) = (
        &scene.stackup.as_ref().unwrap().layout.node_weights,
        &s.stackup.as_ref().unwrap().layout.node_weights,
    );
    for i in 0..scene.n() {
        let on_segment =
            parts[i] == "riser_buoyant" || parts.get(i + 1).is_some_and(|p| p == "riser_buoyant");
        if on_segment {
            assert!(s.beam.masses[i] < scene.beam.masses[i], "node {i}");
            assert!(w1[i] > w0[i], "node {i}: {} against {}", w1[i], w0[i]);
        } else {
            assert_eq!(s.beam.masses[i], scene.beam.masses[i], "node {i}");
            assert_eq!(w1[i], w0[i], "node {i}");
        }
    }
    assert_eq!(s.beam.lengths, scene.beam.lengths);
    // Setting it back gives the scene's chain bit for bit.
    p.set(&mut s, 1.1938).unwrap();
    assert_eq!(s.beam.masses, scene.beam.masses);
    assert_eq!(s.stackup, scene.stackup);
    // A value below the pipe's outer diameter is refused naming the segment's key.
    let err = p.set(&mut s, 0.3).unwrap_err();
    assert_eq!(
        err.key(),
        Some("stackup.segment[0].buoyancy_diameter"),
        "{err}"
    );
    assert_eq!(
        Scene::from_toml_str(&scene.to_toml_string()).unwrap(),
        scene
    );
}

/// Refusals naming the key: a segment the stack-up does not have, a segment without buoyancy
/// modules, a lower bound below the pipe's outer diameter (0.5334 m), an empty segment name,
/// an upper bound beyond the stack-up's diameters.
#[test]
fn bad_buoyancy_parameters_are_refused_naming_the_key() {
    let read = |name: &str, lower: &str, upper: &str| {
        Scene::from_toml_str(&scene_text("", &design(name, lower, upper))).unwrap_err()
    };
    let err = read(
        "stackup.segment.no such riser.buoyancy_diameter",
        "0.6",
        "1.5",
    );
    assert_eq!(err.key(), Some("design.parameter[0].name"), "{err}");
    assert!(err.to_string().contains("no such riser"), "{err}");
    let err = read("stackup.segment.riser_bare.buoyancy_diameter", "0.6", "1.5");
    assert_eq!(err.key(), Some("design.parameter[0].name"), "{err}");
    assert!(err.to_string().contains("buoyancy modules"), "{err}");
    let err = read(NAME, "0.5", "1.5");
    assert_eq!(err.key(), Some("design.parameter[0].lower"), "{err}");
    assert!(err.to_string().contains("0.5334"), "{err}");
    let err = read("stackup.segment..buoyancy_diameter", "0.6", "1.5");
    assert_eq!(err.key(), Some("design.parameter[0].name"), "{err}");
    let err = read(NAME, "0.6", "2000.0");
    assert_eq!(err.key(), Some("design.parameter[0].upper"), "{err}");
    // The scene's own 1.1938 m must lie within the bounds.
    let err = read(NAME, "1.2", "1.5");
    assert_eq!(err.key(), Some("design.parameter[0].lower"), "{err}");
}

/// The layout's derivatives (`Stackup::buoyancy_tangents`) = central differences of the
/// layout itself (the stack-up laid out at D_b ± h, h = 10⁻⁴ D_b), node by node for the masses,
/// weights, drag and inertia coefficients, to 10⁻⁸ of each quantity's largest derivative: the
/// quantities are quadratic in D_b, so the difference has no truncation error and differs by
/// round-off alone (about ε m / h ≈ 10⁻¹⁰ relative). With the Morison diameter given
/// explicitly (`hydrodynamic_diameter`) the drag and inertia do not move and the added mass's
/// share of ∂m/∂D_b is gone.
#[test]
fn layout_tangents_match_central_differences_of_the_layout() {
    for explicit in [false, true] {
        let mut text = scene_text("", &design(NAME, "0.6", "1.5"));
        if explicit {
            text = text.replace(
                "buoyancy_density = 416.48\n",
                "buoyancy_density = 416.48\nhydrodynamic_diameter = 1.1938\n",
            );
        }
        let scene = Scene::from_toml_str(&text).unwrap();
        let p = buoyancy();
        let st = scene.stackup.as_ref().unwrap();
        let segment = p.segment(&scene).unwrap();
        let t = st.buoyancy_tangents(
            segment,
            &scene.beam.lengths,
            scene.water.density,
            scene.mudline(),
        );
        let b = 1.1938;
        let h = 1e-4 * b;
        let at = |x: f64| {
            let mut s = scene.clone();
            p.set(&mut s, x).unwrap();
            let l = s.stackup.as_ref().unwrap().layout.clone();
            (s.beam.masses.clone(), l)
        };
        let ((m_hi, l_hi), (m_lo, l_lo)) = (at(b + h), at(b - h));
        let fd = |hi: &[f64], lo: &[f64]| -> Vec<f64> {
            hi.iter()
                .zip(lo)
                .map(|(a, c)| (a - c) / (2.0 * h))
                .collect()
        };
        let cases = [
            ("masses", &t.masses, fd(&m_hi, &m_lo)),
            (
                "weights",
                &t.weights,
                fd(&l_hi.node_weights, &l_lo.node_weights),
            ),
            ("drag", &t.drag, fd(&l_hi.node_drag, &l_lo.node_drag)),
            (
                "inertia",
                &t.inertia,
                fd(&l_hi.node_inertia, &l_lo.node_inertia),
            ),
        ];
        for (what, exact, diff) in cases {
            let scale = exact.iter().fold(0.0_f64, |m, x| m.max(x.abs()));
            if explicit && (what == "drag" || what == "inertia") {
                assert_eq!(scale, 0.0, "{what}: {exact:?}");
            } else {
                assert!(scale > 0.0, "{what} ({explicit}): {exact:?}");
            }
            for (i, (e, d)) in exact.iter().zip(&diff).enumerate() {
                assert!(
                    (e - d).abs() <= 1e-8 * scale.max(f64::MIN_POSITIVE),
                    "{what} (explicit D_h: {explicit}), node {i}: {e} against {d}"
                );
            }
        }
    }
}

/// ∂D_y/∂D_b and ∂D_y/∂T (both from the one adjoint sweep per cell) = central differences of
/// D_y (forward runs
/// of every cell, step 10⁻⁵ θ) to 10⁻⁵ relative of the largest relative sensitivity
/// (`design_study::check_central_differences`), at the scene's design (D_b = 1.1938 m,
/// T = 1.5 MN) and at a second one (D_b = 0.9 m, T = 1.8 MN). The reference is the central
/// difference (truncation O(10⁻¹⁰) relative). The gradient does not depend on the executor
/// (serial = parallel bit for bit).
#[test]
fn buoyancy_gradient_matches_central_differences_at_two_designs() {
    let scene = scene();
    let cells = cells();
    let st = study(&scene, &cells, 10.0, 2.0);
    let p = vec![buoyancy(), DesignParameter::Tension];
    let v0 = values(&scene, &p);
    assert_eq!(v0, vec![1.1938, 1.5e6]);
    let v1 = vec![0.9, 1.8e6];
    check_buoyancy_designs(&st, &p, [v0, v1]);
}

/// The buoyancy diameter's gradient is refused, naming the parameter and the key that would
/// make it available, where the sweep has no node tangents for it: the momentum drag
/// (`stackup.drag_model = "momentum"`, whose constant comes from the masses in real
/// arithmetic); the values alone are evaluated there.
#[test]
fn buoyancy_gradient_is_refused_with_the_momentum_drag() {
    let text = scene_text("", &design(NAME, "0.6", "1.5"))
        .replace("drag_model = \"morison\"", "drag_model = \"momentum\"");
    let scene = Scene::from_toml_str(&text).unwrap();
    let cells = cells();
    let st = study(&scene, &cells, 10.0, 2.0);
    let p = vec![buoyancy()];
    let v = values(&scene, &p);
    let point = DesignPoint {
        params: &p,
        values: &v,
    };
    let err = st
        .evaluate(&point, Want::Gradient, Execution::Serial, &|| {})
        .unwrap_err();
    assert!(
        matches!(&err, DesignError::NoGradient { name, reason }
            if name == NAME && reason.contains("stackup.drag_model")),
        "{err}"
    );
    let value = st
        .evaluate(&point, Want::Value, Execution::Serial, &|| {})
        .unwrap();
    assert!(value.damage_per_year > 0.0, "{value:?}");
}

/// The study's ∂D_s/∂D_b of every cell (its adjoint sweep through the node tangents) = the
/// derivative part of the cell's run in `Dual64` (forward mode, the reference: exact to
/// round-off by another route, no reverse pass) taken here through the library's public pieces
/// alone (the layout's tangents `Stackup::buoyancy_tangents`, `Chain::set_node_quantities`,
/// `adjoint::forward_value` with the fatigue objective, which counts the whole record:
/// spin-up 0), to 10⁻¹² relative; and that run's real part = D_s of the study's adjoint sweep
/// in f64 to 10⁻¹² (seeding the node quantities leaves the real arithmetic as built; dual
/// arithmetic rounds some real parts differently, by an ulp). With the tension's adjoint
/// gradient beside it, against its own `Dual64` run (`Chain::set_parameter`) to 10⁻⁹. And the
/// count of runs: an evaluation with the gradient is one adjoint sweep per cell, no extra run
/// for the buoyancy parameter.
#[test]
fn adjoint_buoyancy_gradient_equals_the_forward_mode() {
    use chainbeam::{Chain, Parameter};
    use num_dual::Dual64;
    let scene = scene();
    let cells = cells();
    let st = study(&scene, &cells, 10.0, 0.0);
    let p = vec![buoyancy(), DesignParameter::Tension];
    let v = vec![1.05, 1.6e6];
    let g = eval(&st, &p, &v, Want::Gradient, Execution::Serial);
    assert_eq!(st.runs_per_evaluation(Want::Gradient), (cells.len(), 0));
    let point = DesignPoint {
        params: &p,
        values: &v,
    };
    for (s, cell) in g.cells.iter().enumerate() {
        let (cs, objective) = crate::design_study::cell_objective(&st, s, &point);
        let steps = cs.time.steps;
        let u = vec![Dual64::from(0.0); steps + 1];
        let chain = crate::design_study::seeded_buoyancy_chain(&cs, &p[0]);
        let d =
            chainbeam::adjoint::forward_value(&chain, cs.time.step, steps, &u, &objective).unwrap();
        let rel = (d.re - cell.damage).abs() / cell.damage;
        assert!(
            rel < 1e-12,
            "cell {s}: D_s {} against {}",
            d.re,
            cell.damage
        );
        let rel = (cell.gradient[0] - d.eps).abs() / d.eps.abs();
        eprintln!(
            "cell {s}: dD_s/dD_b adjoint {:e}, forward mode {:e}, relative {rel:e}",
            cell.gradient[0], d.eps
        );
        assert!(
            rel < 1e-12,
            "cell {s}: adjoint {:e}, forward mode {:e}",
            cell.gradient[0],
            d.eps
        );
        let mut chain = Chain::<Dual64, 2>::from_scene(&cs).unwrap();
        chain
            .set_parameter(Parameter::Tension, Dual64::new(v[1], 1.0))
            .unwrap();
        let d =
            chainbeam::adjoint::forward_value(&chain, cs.time.step, steps, &u, &objective).unwrap();
        let rel = (cell.gradient[1] - d.eps).abs() / d.eps.abs();
        assert!(
            rel < 1e-9,
            "cell {s}: tension adjoint {:e}, Dual64 {:e}",
            cell.gradient[1],
            d.eps
        );
        eprintln!(
            "cell {s}: D_s = {:e}, dD_s/dD_b = {:e}, dD_s/dT = {:e}",
            cell.damage, cell.gradient[0], cell.gradient[1]
        );
    }
}
