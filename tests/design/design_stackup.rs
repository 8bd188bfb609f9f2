//! The fatigue design of a stack-up (`chainbeam::design`): the named flex joints of
//! `[[stackup.flex_joint]]` as design parameters (`stackup.flex_joint.<name>.stiffness`, a name
//! with spaces included), their exact adjoint gradient against central differences at two
//! designs and against dual numbers, and the `[design]` table's refusals of a flex joint the
//! stack-up does not have.
//!
//! The reduced stack-up: a 36-inch conductor 60 m into the clay of
//! examples/scenes/riser_300m_stackup.toml (its sections, contents, soil and tension) and a bare
//! 21-inch riser up to 300 m of water, the lower flex joint on the conductor's top (an interior
//! joint of the chain: the library's `Parameter::JointStiffness`) and the upper one at the top
//! (the tip spring of the `riser` support); 8 pendulums at h = 0.02 s (no body: the bodies' short
//! pendulums would need the full scene's 0.004 s), records of 10 s after a 5 s spin-up.

use crate::design_study::{check_central_differences, check_dual_numbers};
use chainbeam::design::{DesignParameter, DesignStudy};
use chainbeam::fatigue::ScatterCell;
use chainbeam::{Chain, Parameter, Scene};

/// The conductor's section (outer diameter, wall thickness) \[m\], the `[fatigue]` section of
/// the reduced stack-up.
const CONDUCTOR_SECTION: (f64, f64) = (0.9144, 0.0381);

/// The reduced stack-up (module docs) with `design` appended.
fn scene_text(design: &str) -> String {
    crate::design_study::scene_text(
        r#"
[beam]
pendulums = 8
support = "riser"

[soil]
mudline = 60.0
modulus = 3.35e5
gradient = 1.0e5

[loads]
tension = 1.5e6

[loads.waves]
spectrum = "jonswap"
hs = 2.0
tp = 8.0
gamma = 1.0
seed = 3
direction = 0.0

[time]
step = 0.02
steps = 750

[stackup]
foot = "clamped"

[[stackup.segment]]
name = "conductor"
length = 60.0
outer_diameter = 0.9144
wall_thickness = 0.0381
contents_density = 1437.912

[[stackup.segment]]
name = "riser"
length = 22.86
joints = 13
outer_diameter = 0.5334
wall_thickness = 0.022225
contents_density = 1437.912

[[stackup.flex_joint]]
name = "lower flex joint"
above = "conductor"
stiffness = 2.865e6

[[stackup.flex_joint]]
name = "upper flex joint"
above = "riser"
stiffness = 1.146e6
"#,
        CONDUCTOR_SECTION,
        design,
    )
}

const DESIGN: &str = r#"
[[design.parameter]]
name = "loads.tension"
lower = 1.0e6
upper = 3.0e6

[[design.parameter]]
name = "stackup.flex_joint.lower flex joint.stiffness"
lower = 1.0e5
upper = 1.0e9

[[design.parameter]]
name = "stackup.flex_joint.upper flex joint.stiffness"
lower = 1.0e5
upper = 1.0e9
"#;

fn scene() -> Scene {
    Scene::from_toml_str(&scene_text(DESIGN)).unwrap()
}

fn params() -> Vec<DesignParameter> {
    vec![
        DesignParameter::Tension,
        DesignParameter::FlexJoint("lower flex joint".into()),
        DesignParameter::FlexJoint("upper flex joint".into()),
    ]
}

/// Two sea states (probabilities 0.7, 0.3).
fn cells() -> Vec<ScatterCell> {
    crate::design_study::cells(&[(1.5, 7.0, 0.7), (3.0, 9.5, 0.3)])
}

fn study<'a>(scene: &'a Scene, cells: &'a [ScatterCell], spin_up: f64) -> DesignStudy<'a> {
    crate::design_study::study(scene, cells, 10.0, spin_up)
}

/// The names read from the `[design]` table (spaces and all), the flex joints' values the
/// stack-up's, and the springs they are: the lower flex joint an interior joint of the chain,
/// the upper one the tip spring.
#[test]
fn flex_joints_are_named_parameters_of_the_chain() {
    let scene = scene();
    let table = scene.design.as_ref().unwrap();
    let names: Vec<String> = table
        .parameters
        .iter()
        .map(|p| p.parameter.name())
        .collect();
    assert_eq!(
        names,
        [
            "loads.tension",
            "stackup.flex_joint.lower flex joint.stiffness",
            "stackup.flex_joint.upper flex joint.stiffness"
        ]
    );
    let p = params();
    assert_eq!(table.parameters[1].parameter, p[1]);
    assert_eq!(p[1].value(&scene), Ok(2.865e6));
    assert_eq!(p[2].value(&scene), Ok(1.146e6));
    let j = scene.stackup.as_ref().unwrap().layout.flex_joints.clone();
    let n = scene.beam.lengths.len();
    assert_eq!(j.len(), 2);
    assert!((1..n).contains(&j[0]), "{j:?}");
    assert_eq!(j[1], n);
    // The lower flex joint sits on the conductor's top, 60 m above the foot.
    let top: f64 = scene.beam.lengths[..j[0]].iter().sum();
    assert!((top - 60.0).abs() < 1e-9, "{top}");
    assert_eq!(
        p[1].parameter(&scene),
        Some(Parameter::JointStiffness(j[0]))
    );
    assert_eq!(p[2].parameter(&scene), Some(Parameter::TipStiffness));
    assert_eq!(scene.beam.stiffness[j[0] - 1], 2.865e6);
    // Setting it sets the stack-up's value and the chain's spring.
    let mut s = scene.clone();
    p[1].set(&mut s, 5.0e6).unwrap();
    assert_eq!(s.beam.stiffness[j[0] - 1], 5.0e6);
    assert_eq!(p[1].value(&s), Ok(5.0e6));
}

/// ∂D_y/∂θ_i by the adjoint = central differences of D_y (forward runs of every cell) with the
/// step 10⁻⁵ θ_i, to 10⁻⁵ relative, at the scene's design and at a second one (tension +20 %,
/// lower flex joint × 4, upper ÷ 2), for the tension and the lower flex joint (an interior
/// joint). The reference is the central difference (truncation O(10⁻¹⁰) relative, round-off
/// about 10⁻¹¹). The upper flex joint (the tip spring, 300 m above the base) barely moves the
/// base's damage (∂D_y/∂k = −5.93·10⁻²³ per N·m/rad at the scene's design), so its central
/// difference is dominated by round-off (it differed from the adjoint by 1.0·10⁻⁴ relative);
/// its gradient is checked against dual numbers below, to 10⁻⁹.
#[test]
fn flex_joint_gradient_matches_central_differences_at_two_designs() {
    let scene = scene();
    let cells = cells();
    let st = study(&scene, &cells, 5.0);
    let p = params();
    let v0 = crate::design_study::values(&scene, &p);
    let v1 = vec![v0[0] * 1.2, v0[1] * 4.0, v0[2] / 2.0];
    for v in [v0, v1] {
        check_central_differences(&st, &p, &v, &[0, 1]);
    }
}

/// ∂D_s/∂θ_i of every cell by the adjoint = the dual part of D_s computed in `Dual64` with θ_i
/// seeded through `Chain::set_parameter` (forward-mode differentiation of the whole run; no
/// spin-up, as the library's fatigue objective counts the whole record), to 10⁻⁹ relative
/// (`design_study::check_dual_numbers`).
#[test]
fn flex_joint_gradient_matches_dual_numbers() {
    let scene = scene();
    let cells = cells();
    let st = study(&scene, &cells, 0.0);
    let p = params();
    check_dual_numbers(&st, &p, &crate::design_study::values(&scene, &p));
}

/// A flex joint the stack-up does not have, or a scene without a stack-up, is refused when the
/// scene is read, naming the key; the table written back reads as itself.
#[test]
fn unknown_flex_joints_are_refused_naming_the_key() {
    let text = scene_text(
        "[[design.parameter]]\nname = \"stackup.flex_joint.middle flex joint.stiffness\"\n\
         lower = 1.0\nupper = 1.0e9\n",
    );
    let err = Scene::from_toml_str(&text).unwrap_err();
    assert_eq!(err.key(), Some("design.parameter[0].name"), "{err}");
    assert!(err.to_string().contains("middle flex joint"), "{err}");
    let text = scene_text(
        "[[design.parameter]]\nname = \"stackup.flex_joint..stiffness\"\nlower = 1.0\n\
         upper = 1.0e9\n",
    );
    let err = Scene::from_toml_str(&text).unwrap_err();
    assert_eq!(err.key(), Some("design.parameter[0].name"), "{err}");
    // Bounds that leave out the stack-up's own value.
    let text = scene_text(
        "[[design.parameter]]\nname = \"stackup.flex_joint.lower flex joint.stiffness\"\n\
         lower = 1.0e7\nupper = 1.0e9\n",
    );
    let err = Scene::from_toml_str(&text).unwrap_err();
    assert_eq!(err.key(), Some("design.parameter[0].lower"), "{err}");
    let scene = scene();
    assert_eq!(
        Scene::from_toml_str(&scene.to_toml_string()).unwrap(),
        scene
    );
}

/// The shipped system design scene (examples/scenes/riser_300m_system_design.toml, the README's
/// worked example) reads, builds a chain, and frees the tension and the named lower flex joint
/// with the bounds its comments state (f = 1.1 and 2.0 of 1.344615e6 N; 1e5 to 1e8 N·m/rad).
#[test]
fn the_shipped_system_design_scene_frees_tension_and_the_lower_flex_joint() {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("examples/scenes/riser_300m_system_design.toml");
    let scene = Scene::from_file(&path).unwrap();
    Chain::<f64, 2>::from_scene(&scene).unwrap();
    let table = scene.design.as_ref().expect("a [design] table");
    let freed: Vec<_> = table
        .parameters
        .iter()
        .map(|p| (p.parameter.clone(), p.bounds))
        .collect();
    assert_eq!(
        freed,
        vec![
            (DesignParameter::Tension, Some((1.4790765e6, 2.68923e6))),
            (
                DesignParameter::FlexJoint("lower flex joint".into()),
                Some((1.0e5, 1.0e8))
            ),
        ]
    );
}
