//! The design's objective at a named hot spot (`[design] hotspot`): the rainflow damage of a
//! `[[fatigue.hotspot]]`'s moment, interpolated in elevation between two joints, and its exact
//! design gradient (a forward run for the damage's gradient in the moment, then an adjoint sweep
//! seeded with the blend of the two joints' seeds), against central differences at two designs
//! and two hot spots and against forward-mode dual numbers; its damage against the hot spots'
//! assessment of `chainbeam fatigue`; the report naming it; the key's refusals.
//!
//! The reduced scene is tests/design/design.rs's (the 21-inch riser on 10 pendulums of 30 m at
//! h = 0.1 s, three cells of 40 s records) with two hot spots: "mid joint 1-2" halfway between
//! joints 1 and 2 (45 m; their springs are the pipe's bending springs, no design parameter), and
//! "near the base" a third of the way from the base joint to joint 1 (10 m; the base spring k₁,
//! `beam.base_stiffness`, enters its moment directly as well as through the motion).

use crate::design::scene_text;
use crate::design_study::{cells, check_central_differences, eval, hot_spot_run, study, values};
use chainbeam::design::{
    optimise, sensitivities, DesignError, DesignOptions, DesignParameter, DesignPoint,
    DesignReport, DesignStudy, Execution, Want,
};
use chainbeam::hotspots::{assess_hot_spots, interpolation_joints};
use chainbeam::{Chain, Scene};
use num_dual::Dual64;

const PARAMS: [DesignParameter; 3] = [
    DesignParameter::Tension,
    DesignParameter::BaseStiffness,
    DesignParameter::TipStiffness,
];

/// The two hot spots (module docs) and the `[design]` table with `hotspot = name`.
fn design(hotspot: &str) -> String {
    format!(
        r#"
[design]
max_iterations = 8
tolerance = 1e-3
hotspot = "{hotspot}"

[[design.parameter]]
name = "loads.tension"
lower = 1.0e6
upper = 2.0e6

[[design.parameter]]
name = "beam.base_stiffness"
lower = 1.0e6
upper = 1.0e9

[[fatigue.hotspot]]
name = "mid joint 1-2"
elevation = 45.0

[[fatigue.hotspot]]
name = "near the base"
elevation = 10.0
scf = 1.5
"#
    )
}

fn scene(hotspot: &str) -> Scene {
    Scene::from_toml_str(&scene_text(&design(hotspot))).unwrap()
}

fn diagram() -> Vec<chainbeam::fatigue::ScatterCell> {
    cells(&[(1.0, 6.5, 0.5), (2.0, 8.0, 0.3), (3.5, 10.0, 0.2)])
}

/// The hot spots lie where the module docs say: between joints 1 and 2 at w = ½, and between
/// joints 0 and 1 at w = ⅓ (30 m pendulums).
#[test]
fn the_hot_spots_interpolate_between_the_joints_stated() {
    let s = scene("mid joint 1-2");
    let w = interpolation_joints(&s.beam.lengths, 45.0);
    assert_eq!((w.lower, w.upper), (1, 2));
    assert!((w.weight - 0.5).abs() < 1e-12, "{w:?}");
    let w = interpolation_joints(&s.beam.lengths, 10.0);
    assert_eq!((w.lower, w.upper), (0, 1));
    assert!((w.weight - 1.0 / 3.0).abs() < 1e-12, "{w:?}");
}

/// ∂D_y/∂θ at each hot spot = central differences (relative 10⁻⁵) at the scene's design and at a
/// second one (tension +25 %, base spring ÷ 3, tip spring × 2): the tension, the base spring
/// (directly in the "near the base" moment) and the tip spring.
#[test]
fn hot_spot_gradient_matches_central_differences_at_two_designs() {
    let cells = diagram();
    for name in ["mid joint 1-2", "near the base"] {
        let s = scene(name);
        let st = study(&s, &cells, 40.0, 10.0);
        let v0 = values(&s, &PARAMS);
        let v1 = vec![v0[0] * 1.25, v0[1] / 3.0, v0[2] * 2.0];
        for v in [v0, v1] {
            check_central_differences(&st, &PARAMS, &v, &[0, 1, 2]);
        }
    }
}

/// ∂D_s/∂θ_i of every cell at the hot spot between joints 1 and 2 by the adjoint = the dual
/// part of the linearised damage J = Σ_k g_k M(t_k) computed in `Dual64` with θ_i seeded
/// (forward-mode differentiation of the whole run, `design_study::LinearisedHotSpot`;
/// g_k = ∂D_s/∂M(t_k) from this test's own f64 run of the joint torques,
/// `design_study::hot_spot_run`, and the damage's gradient): at
/// the run's rainflow pairing dD_s/dθ_i = Σ_k g_k dM(t_k)/dθ_i, which is that dual part. To
/// 10⁻⁹ relative (both exact, round-off in different orders). Neither joint's spring is a
/// parameter here, so M depends on θ through the motion alone; D_s from this test's history =
/// the study's to 10⁻¹².
#[test]
fn hot_spot_gradient_matches_dual_numbers_cell_by_cell() {
    let s = scene("mid joint 1-2");
    let cells = diagram();
    let st = study(&s, &cells, 40.0, 0.0);
    let v = values(&s, &PARAMS);
    let g = eval(&st, &PARAMS, &v, Want::Gradient, Execution::Serial);
    let point = DesignPoint {
        params: &PARAMS,
        values: &v,
    };
    let hot = s
        .hotspots
        .iter()
        .find(|h| h.name == "mid joint 1-2")
        .unwrap();
    for (c, cell) in g.cells.iter().enumerate() {
        let cs = st.cell_scene(c, &point).unwrap();
        let run = hot_spot_run(&cs, hot);
        let d = run.damage;
        assert!(
            (d - cell.damage).abs() <= 1e-12 * cell.damage,
            "cell {c}: D_s {d} against {}",
            cell.damage
        );
        let objective = run.linearised(&cs);
        let steps = cs.time.steps;
        for (i, p) in PARAMS.iter().enumerate() {
            let mut chain = Chain::<Dual64, 2>::from_scene(&cs).unwrap();
            chain
                .set_parameter(p.parameter(&cs).unwrap(), Dual64::new(v[i], 1.0))
                .unwrap();
            let u = vec![Dual64::from(0.0); steps + 1];
            let j = chainbeam::adjoint::forward_value(&chain, cs.time.step, steps, &u, &objective)
                .unwrap();
            let rel = (cell.gradient[i] - j.eps).abs() / j.eps.abs();
            assert!(
                rel < 1e-9,
                "cell {c}, {}: adjoint {:e}, Dual64 {:e} (relative {rel:e})",
                p.name(),
                cell.gradient[i],
                j.eps
            );
        }
    }
}

/// The design's D_s at a hot spot is the damage the hot spots' assessment (`chainbeam fatigue`)
/// gives the same record after the same spin-up, to 10⁻¹² relative (the same moment history,
/// interpolated the same way, through the same S-N curve), and the study's D_y combines them.
#[test]
fn hot_spot_damage_is_the_assessments() {
    let cells = diagram();
    let s = scene("near the base");
    let st = study(&s, &cells, 40.0, 10.0);
    let v = values(&s, &PARAMS);
    let g = eval(&st, &PARAMS, &v, Want::Value, Execution::Serial);
    let point = DesignPoint {
        params: &PARAMS,
        values: &v,
    };
    for (c, cell) in g.cells.iter().enumerate() {
        let cs = st.cell_scene(c, &point).unwrap();
        let skip = (10.0 / cs.time.step).round() as usize;
        let a = assess_hot_spots(&cs, &cs.hotspots, skip).unwrap();
        let near = a.iter().find(|h| h.name == "near the base").unwrap();
        assert!(
            (near.assessment.damage - cell.damage).abs() <= 1e-12 * cell.damage,
            "cell {c}: the assessment's {} against the design's {}",
            near.assessment.damage,
            cell.damage
        );
    }
}

/// The report names the objective's hot spot (its name, elevation, joints, weight and DFF), the
/// chain's base by `null`; the optimiser at a hot spot ends within the bounds with a life at
/// least the scene's, and its count of cell runs is one adjoint sweep and one forward run per
/// cell for each evaluation with the gradient.
#[test]
fn report_names_the_hot_spot_and_the_optimiser_runs_there() {
    let cells = diagram();
    let s = scene("mid joint 1-2");
    let st = study(&s, &cells, 40.0, 10.0);
    assert_eq!(st.runs_per_evaluation(Want::Gradient), (3, 3));
    assert_eq!(st.runs_per_evaluation(Want::Value), (0, 3));
    let dff = st.dff().unwrap();
    let (g, t) = sensitivities(&st, Execution::Serial, &|| {}).unwrap();
    let r = DesignReport::sensitivities(&st, (&g, &t), dff, 40.0, 0.0);
    assert_eq!(r.hot_spot.name.as_deref(), Some("mid joint 1-2"));
    assert_eq!(r.hot_spot.joints, [1, 2]);
    assert_eq!(r.hot_spot.elevation, 45.0);
    let json = serde_json::to_value(&r).unwrap();
    assert_eq!(json["hot_spot"]["name"], "mid joint 1-2");
    // Without `hotspot` the objective is the chain's base.
    let base =
        Scene::from_toml_str(&scene_text(&design("x").replace("hotspot = \"x\"\n", ""))).unwrap();
    let sb = study(&base, &cells, 40.0, 10.0);
    assert_eq!(sb.hot_spot().unwrap(), None);
    let (gb, tb) = sensitivities(&sb, Execution::Serial, &|| {}).unwrap();
    let rb = DesignReport::sensitivities(&sb, (&gb, &tb), dff, 40.0, 0.0);
    assert!(serde_json::to_value(&rb).unwrap()["hot_spot"]["name"].is_null());
    let o = optimise(&st, &DesignOptions::default()).unwrap();
    assert!(o.life_years >= o.initial.life_years, "{o:?}");
    for it in &o.iterates {
        for ((_, (lo, hi)), v) in o.parameters.iter().zip(&it.values) {
            assert!((*lo..=*hi).contains(v), "{it:?}");
        }
    }
    let last = o.iterates.last().unwrap();
    // Every evaluation with the gradient is an adjoint sweep and a forward run per cell; the
    // value-only trials are forward runs.
    assert_eq!(o.adjoint_sweeps % 3, 0);
    assert!(o.forward_runs >= o.adjoint_sweeps);
    assert_eq!(o.simulations, o.adjoint_sweeps + o.forward_runs);
    assert!(last.simulations <= o.simulations);
}

/// `[design] hotspot` naming no `[[fatigue.hotspot]]` is refused when the scene is read, naming
/// the key; a study whose scene was changed to name one it lacks is refused by name, typed.
#[test]
fn unknown_hot_spot_is_refused_naming_the_key() {
    let err = Scene::from_toml_str(&scene_text(&design("no such hot spot"))).unwrap_err();
    assert_eq!(err.key(), Some("design.hotspot"), "{err}");
    assert!(err.to_string().contains("no such hot spot"), "{err}");
    let mut s = scene("mid joint 1-2");
    s.design.as_mut().unwrap().hotspot = Some("gone".into());
    let cells = diagram();
    let st: DesignStudy<'_> = study(&s, &cells, 40.0, 10.0);
    let v = values(&s, &PARAMS);
    let point = DesignPoint {
        params: &PARAMS,
        values: &v,
    };
    let e = st
        .evaluate(&point, Want::Value, Execution::Serial, &|| {})
        .unwrap_err();
    assert!(
        matches!(e, DesignError::NoHotSpot { ref name } if name == "gone"),
        "{e}"
    );
    // The table written back reads as itself, the hot spot included.
    let s = scene("near the base");
    assert_eq!(Scene::from_toml_str(&s.to_toml_string()).unwrap(), s);
}
