//! The buoyancy diameter of a named stack-up segment (`stackup.segment.<name>.buoyancy_diameter`)
//! as a design parameter of the objective at a named hot spot (`[design] hotspot`): its gradient
//! from the hot spot's one adjoint sweep per cell (the linearised damage J = Σ_k g_k M(t_k)
//! swept with the chain's node tangents), with the tension's and the lower flex joint's (the
//! base spring, which enters the hot spot's moment directly too) from the same sweep, against
//! the forward mode (every cell run in `Dual64` with the node quantities or the parameter
//! seeded) and against central differences of the scatter-diagram damage at two designs.
//!
//! The reduced riser system of tests/design/design_vessel.rs (8 pendulums at h = 0.02 s, the
//! buoyant segment at the foot, Morison's drag node by node, the vessel with its surge RAO),
//! two cells of 10 s records (those of tests/design/design_buoyancy.rs), and the hot spot
//! "keel" 20 m above the foot, between the base joint and joint 1 (the first pendulum is two of
//! the buoyant segment's 22.86 m joints, 45.72 m: weight 20/45.72 on joint 1), on the buoyant
//! segment.

use crate::design_study::{
    check_buoyancy_designs, eval, hot_spot_run, seeded_buoyancy_chain, study, values,
};
use crate::design_vessel::scene_text;
use chainbeam::design::{DesignParameter, DesignPoint, Execution, Want};
use chainbeam::fatigue::ScatterCell;
use chainbeam::{Chain, Parameter, Scene};
use num_dual::Dual64;

const BUOYANCY: &str = "stackup.segment.riser_buoyant.buoyancy_diameter";
const FLEX_JOINT: &str = "stackup.flex_joint.lower flex joint.stiffness";

/// The `[design]` table (the hot spot "keel", the three parameters) and the hot spot.
const DESIGN: &str = r#"
[design]
hotspot = "keel"

[[design.parameter]]
name = "stackup.segment.riser_buoyant.buoyancy_diameter"
lower = 0.6
upper = 1.5

[[design.parameter]]
name = "loads.tension"
lower = 1.0e6
upper = 3.0e6

[[design.parameter]]
name = "stackup.flex_joint.lower flex joint.stiffness"
lower = 1.0e6
upper = 1.0e7

[[fatigue.hotspot]]
name = "keel"
elevation = 20.0
"#;

fn scene() -> Scene {
    Scene::from_toml_str(&scene_text("", DESIGN)).unwrap()
}

/// The design's parameters, in the table's order.
fn params() -> Vec<DesignParameter> {
    [BUOYANCY, "loads.tension", FLEX_JOINT]
        .iter()
        .map(|n| DesignParameter::from_name(n).unwrap())
        .collect()
}

/// Two sea states (probabilities 0.7, 0.3), those of tests/design/design_buoyancy.rs.
fn cells() -> Vec<ScatterCell> {
    crate::design_study::cells(&[(1.5, 7.0, 0.7), (3.0, 9.5, 0.3)])
}

/// The scene is what the module docs say: the hot spot between the base joint and joint 1
/// at weight 20/45.72, the lower flex joint the base spring (`Parameter::BaseStiffness`), and
/// the springs and lengths do not move with the buoyancy diameter (so D_b enters the hot
/// spot's moment through the motion alone, the forward mode's reference below).
#[test]
fn the_hot_spot_and_its_springs_are_those_stated() {
    let scene = scene();
    let w = chainbeam::hotspots::interpolation_joints(&scene.beam.lengths, 20.0);
    assert_eq!((w.lower, w.upper), (0, 1));
    assert!(
        (scene.beam.lengths[0] - 2.0 * 22.86).abs() < 1e-9,
        "{:?}",
        scene.beam.lengths
    );
    assert!((w.weight - 20.0 / 45.72).abs() < 1e-12, "{w:?}");
    let p = params();
    assert_eq!(p[2].parameter(&scene), Some(Parameter::BaseStiffness));
    let springs = |s: &Scene| Chain::<f64, 2>::from_scene(s).unwrap().springs().to_vec();
    let mut thin = scene.clone();
    p[0].set(&mut thin, 0.9).unwrap();
    assert_ne!(thin.beam.masses, scene.beam.masses);
    assert_eq!(springs(&thin), springs(&scene));
    assert_eq!(thin.beam.lengths, scene.beam.lengths);
}

/// ∂D_s/∂θ of every cell at the hot spot, all three from the study's one adjoint sweep per cell
/// (and one forward run: `runs_per_evaluation` counts no run for the buoyancy parameter), = the
/// forward mode: the derivative part of the linearised damage J = Σ_k g_k M(t_k)
/// (`design_study::LinearisedHotSpot`, g_k from this test's own f64 run of the joint torques,
/// `design_study::hot_spot_run`, whose D_s = the study's to 10⁻¹²) in a `Dual64` run of the
/// cell with the buoyancy's node quantities seeded (`design_study::seeded_buoyancy_chain`) or
/// the parameter seeded (`Chain::set_parameter`); for the base spring plus its direct term
/// Σ_k g_k (1 − w) θ₀(t_k), θ₀ = M₀/k₀ of the same f64 run. Both routes are exact at the run's
/// rainflow pairing and differ by round-off in different orders of operations: to 10⁻¹²
/// relative (the study's spin-up 0: the reference counts the whole record).
#[test]
fn hot_spot_buoyancy_gradient_equals_the_forward_mode() {
    let scene = scene();
    let cells = cells();
    let st = study(&scene, &cells, 10.0, 0.0);
    let p = params();
    let v = vec![1.05, 1.6e6, 4.0e6];
    let g = eval(&st, &p, &v, Want::Gradient, Execution::Serial);
    assert_eq!(
        st.runs_per_evaluation(Want::Gradient),
        (cells.len(), cells.len())
    );
    let point = DesignPoint {
        params: &p,
        values: &v,
    };
    let hot = &scene.hotspots[0];
    for (s, cell) in g.cells.iter().enumerate() {
        let cs = st.cell_scene(s, &point).unwrap();
        let run = hot_spot_run(&cs, hot);
        let rel = (run.damage - cell.damage).abs() / cell.damage;
        assert!(
            rel < 1e-12,
            "cell {s}: D_s {} against {}",
            run.damage,
            cell.damage
        );
        let objective = run.linearised(&cs);
        let steps = cs.time.steps;
        let u = vec![Dual64::from(0.0); steps + 1];
        let forward = |chain: &Chain<Dual64, 2>| {
            chainbeam::adjoint::forward_value(chain, cs.time.step, steps, &u, &objective)
                .unwrap()
                .eps
        };
        let seeded = |i: usize| {
            let mut chain = Chain::<Dual64, 2>::from_scene(&cs).unwrap();
            let q = p[i].parameter(&cs).unwrap();
            chain.set_parameter(q, Dual64::new(v[i], 1.0)).unwrap();
            chain
        };
        // The base spring's direct term: ∂M(t_k)/∂k₀ = (1 − w) θ₀(t_k).
        let k0 = Chain::<f64, 2>::from_scene(&cs).unwrap().springs()[0];
        let direct: f64 = run
            .g
            .iter()
            .zip(&run.torques[0])
            .map(|(gk, m0)| gk * (1.0 - run.joints.weight) * (m0 / k0))
            .sum();
        let reference = [
            forward(&seeded_buoyancy_chain(&cs, &p[0])),
            forward(&seeded(1)),
            forward(&seeded(2)) + direct,
        ];
        for (i, (got, want)) in cell.gradient.iter().zip(reference).enumerate() {
            let rel = (got - want).abs() / want.abs();
            eprintln!(
                "cell {s}, {}: adjoint {got:e}, forward mode {want:e}, relative {rel:e}",
                p[i].name()
            );
            assert!(
                rel < 1e-12,
                "cell {s}, {}: adjoint {got:e}, forward mode {want:e} (relative {rel:e})",
                p[i].name()
            );
        }
        assert!(cell.gradient[0] != 0.0, "the modules move the damage");
    }
}

/// ∂D_y/∂D_b, ∂D_y/∂T and ∂D_y/∂k₀ at the hot spot (one adjoint sweep and one forward run per
/// cell) = central differences of D_y (forward runs of every cell, step 10⁻⁵ θ) to 10⁻⁵ of the
/// largest relative sensitivity (`design_study::check_central_differences`; the reference is
/// the central difference, truncation O(10⁻¹⁰) relative), at the scene's design (D_b =
/// 1.1938 m, T = 1.5 MN, k₀ = 2.865 MN·m/rad) and at a second one (D_b = 0.9 m, T = 1.8 MN,
/// k₀ = 5 MN·m/rad), 2 s of spin-up left out of the count. The gradient does not depend on the
/// executor (serial = parallel bit for bit).
#[test]
fn hot_spot_buoyancy_gradient_matches_central_differences_at_two_designs() {
    let scene = scene();
    let cells = cells();
    let st = study(&scene, &cells, 10.0, 2.0);
    let p = params();
    let v0 = values(&scene, &p);
    assert_eq!(v0, vec![1.1938, 1.5e6, 2.865e6]);
    let v1 = vec![0.9, 1.8e6, 5.0e6];
    check_buoyancy_designs(&st, &p, [v0, v1]);
}
