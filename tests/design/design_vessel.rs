//! The vessel's mean offset as a design parameter (`vessel.offset`, `support = "vessel"`): the
//! top's prescribed Z(t) = ρ(t)(Z₀ + d_z X_w(t)) read by the step's tip constraint, its exact
//! adjoint gradient (the cotangents of Z(t_k) and Ż(t_k) times ρ(t_k) and ρ̇(t_k)) against
//! central differences at two designs (one of them a negative offset) and against forward-mode
//! dual numbers, for a prescribed top and for a vessel under thrust; the affine scaling of the
//! signed parameter in the optimiser; the `[design]` table's refusals.
//!
//! The reduced riser system: the stack-up of examples/scenes/riser_300m_system_design.toml
//! without its wellhead, BOP and LMRP (their short pendulums would need its 0.008 s step) and
//! without its pup joints and termination: 91.44 m of riser with its first buoyancy modules
//! (47 in, 416.48 kg/m³) and 205.74 m of bare riser with the auxiliary lines, Morison's drag node
//! by node, the vessel 3 m offset with a surge RAO (six periods of the system's Froude-Krylov
//! surge, rounded), the current, the sea and the tension of a reduced system (1.5 MN); the lower
//! flex joint at the foot (the base spring) and the upper one at the top (the tip spring);
//! 8 pendulums at h = 0.02 s, two cells of 10 s records.

use crate::design_study::{check_central_differences, check_dual_numbers, eval, study, values};
use chainbeam::design::{
    optimise, DesignOptions, DesignParameter, Execution, ScatterGradient, Want,
};
use chainbeam::fatigue::ScatterCell;
use chainbeam::{Parameter, Scene};

/// The reduced riser system (module docs) with `vessel` in its `[vessel]` table and `design`
/// appended.
pub(crate) fn scene_text(vessel: &str, design: &str) -> String {
    crate::design_study::scene_text(
        &format!(
            r#"
[beam]
pendulums = 8
support = "vessel"

[vessel]
offset = 3.0
ramp = 5.0
{vessel}

[vessel.rao]
period = [4.0, 8.0, 12.0, 16.0, 20.0, 30.0]
amplitude = [0.004, 0.076, 0.012, 0.496, 0.798, 0.987]
phase = [-270.0, -90.0, -270.0, -90.0, -90.0, -90.0]

[loads]
tension = 1.5e6

[loads.waves]
spectrum = "jonswap"
hs = 1.44
tp = 7.66
gamma = 1.0
seed = 1
direction = 0.0
lumping = "cell"

[time]
step = 0.02
steps = 750


[stackup]
foot = "clamped"
drag_model = "morison"

[[stackup.segment]]
name = "riser_buoyant"
length = 22.86
joints = 4
outer_diameter = 0.5334
wall_thickness = 0.022225
contents_density = 1437.912
line_mass = 192.745
line_area = 0.041803
buoyancy_diameter = 1.1938
buoyancy_density = 416.48

[[stackup.segment]]
name = "riser_bare"
length = 22.86
joints = 9
outer_diameter = 0.5334
wall_thickness = 0.015875
contents_density = 1437.912
line_mass = 192.745
line_area = 0.041803

[[stackup.flex_joint]]
name = "lower flex joint"
elevation = 0.0
stiffness = 2.865e6

[[stackup.flex_joint]]
name = "upper flex joint"
above = "riser_bare"
stiffness = 1.146e6
"#
        ),
        crate::design_study::RISER_SECTION,
        design,
    )
}

const DESIGN: &str = r#"
[design]
max_iterations = 3
tolerance = 1e-3

[[design.parameter]]
name = "vessel.offset"
lower = -5.0
upper = 10.0

[[design.parameter]]
name = "loads.tension"
lower = 1.0e6
upper = 3.0e6
"#;

/// The thrust keys of a vessel whose control is its thrust (the scene's control is then zero
/// thrust: the vessel drifts under its prescribed part alone).
const THRUST: &str = "mass = 5.0e7\nadded_mass = 1.0e7\ndamping = 2.0e6\n";
/// The same vessel held on station by a position loop (k = 4e5 N/m: a 77 s natural period):
/// x_k = Z_k − P_k enters the drive's step, so ∂/∂Z₀ of the step at fixed (Z_k, Ż_k) has the
/// spring's terms (`ThrustDrive::offset_derivative`).
const THRUST_HELD: &str =
    "mass = 5.0e7\nadded_mass = 1.0e7\ndamping = 2.0e6\nposition_stiffness = 4.0e5\n";

fn scene(vessel: &str) -> Scene {
    Scene::from_toml_str(&scene_text(vessel, DESIGN)).unwrap()
}

fn params() -> Vec<DesignParameter> {
    vec![
        DesignParameter::VesselOffset,
        DesignParameter::Tension,
        DesignParameter::FlexJoint("lower flex joint".into()),
    ]
}

/// Two sea states (probabilities 0.7, 0.3).
fn cells() -> Vec<ScatterCell> {
    crate::design_study::cells(&[(1.5, 7.0, 0.7), (3.0, 9.5, 0.3)])
}

/// The name reads from `[design]`, the value is the vessel's, the parameter is signed (its
/// bounds may be negative) and is the library's `Parameter::VesselOffset`; setting it sets
/// `[vessel] offset`.
#[test]
fn vessel_offset_is_a_signed_named_parameter() {
    let scene = scene("");
    let table = scene.design.as_ref().unwrap();
    assert_eq!(table.parameters[0].parameter, DesignParameter::VesselOffset);
    assert_eq!(table.parameters[0].parameter.name(), "vessel.offset");
    assert_eq!(table.parameters[0].bounds, Some((-5.0, 10.0)));
    assert_eq!(
        DesignParameter::from_name("vessel.offset"),
        Some(DesignParameter::VesselOffset)
    );
    let p = DesignParameter::VesselOffset;
    assert!(p.is_signed());
    assert!(!DesignParameter::Tension.is_signed());
    assert_eq!(p.unit(), "m");
    assert_eq!(p.value(&scene), Ok(3.0));
    assert_eq!(p.parameter(&scene), Some(Parameter::VesselOffset));
    let mut s = scene.clone();
    p.set(&mut s, -2.5).unwrap();
    assert_eq!(s.vessel.as_ref().unwrap().offset, -2.5);
    assert_eq!(p.value(&s), Ok(-2.5));
    // The table written back reads as itself.
    assert_eq!(
        Scene::from_toml_str(&scene.to_toml_string()).unwrap(),
        scene
    );
}

/// ∂D_y/∂θ_i by the adjoint = central differences of D_y (forward runs of every cell) with the
/// step 10⁻⁵ θ_i, to 10⁻⁵ relative (of the largest relative sensitivity,
/// `design_study::check_central_differences`), at the scene's design (Z₀ = 3 m) and at a second
/// one with a negative offset (Z₀ = −2 m, tension +20 %, lower flex joint × 3), for the offset,
/// the tension and the lower flex joint, with the top prescribed. The reference is the central
/// difference (truncation O(10⁻¹⁰) relative).
#[test]
fn vessel_offset_gradient_matches_central_differences_at_two_designs() {
    let scene = scene("");
    let cells = cells();
    let st = study(&scene, &cells, 10.0, 2.0);
    let p = params();
    let v0 = values(&scene, &p);
    assert_eq!(v0[0], 3.0);
    let v1 = vec![-2.0, v0[1] * 1.2, v0[2] * 3.0];
    for v in [v0, v1] {
        let g = check_central_differences(&st, &p, &v, &[0, 1, 2]);
        eprintln!(
            "at {v:?}: D_y = {:e}, dD_y/dθ = {:?}",
            g.damage_per_year, g.gradient
        );
        assert!(g.gradient[0] != 0.0, "the offset moves the damage: {g:?}");
    }
}

/// The same for a vessel under thrust (its control the thrust, zero here): Z₀ enters the
/// prescribed part P(t) of Z = P + x_v, whose step the adjoint differentiates through
/// `ThrustDrive::offset_derivative`.
#[test]
fn vessel_offset_gradient_under_thrust_matches_central_differences() {
    for thrust in [THRUST, THRUST_HELD] {
        let scene = scene(thrust);
        assert!(scene.vessel.as_ref().unwrap().thrust().is_some());
        let cells = cells();
        let st = study(&scene, &cells, 10.0, 2.0);
        let p = params();
        let v0 = values(&scene, &p);
        let v1 = vec![-2.0, v0[1] * 1.2, v0[2] * 3.0];
        for v in [v0, v1] {
            check_central_differences(&st, &p, &v, &[0, 1]);
        }
    }
}

/// ∂D_s/∂θ_i of every cell by the adjoint = the dual part of D_s computed in `Dual64` with θ_i
/// seeded through `Chain::set_parameter` (for the offset: the chain's Z₀, which the prescribed
/// Z(t) reads as (Z₀ − Z₀,vessel) ρ(t) on top of the vessel's motion), to 10⁻⁹ relative, D_s to
/// 10⁻¹² (`design_study::check_dual_numbers`), for the prescribed top and under thrust.
#[test]
fn vessel_offset_gradient_matches_dual_numbers() {
    let cells = cells();
    for vessel in ["", THRUST, THRUST_HELD] {
        let scene = scene(vessel);
        let st = study(&scene, &cells, 10.0, 0.0);
        let p = params();
        check_dual_numbers(&st, &p, &values(&scene, &p));
    }
}

/// The optimiser with the signed offset among its design choices (scaled affinely,
/// u = (Z₀ − lower)/(upper − lower)): every iterate stays within the bounds, starts at the
/// scene's design, and the life does not decrease (each accepted step passes Armijo's test on
/// ln D_y).
#[test]
fn optimiser_moves_the_signed_offset_within_its_bounds() {
    let scene = scene("");
    let cells = cells();
    let st = study(&scene, &cells, 10.0, 2.0);
    let options = DesignOptions {
        execution: Execution::Parallel,
        ..DesignOptions::default()
    };
    let out = optimise(&st, &options).unwrap();
    for it in &out.iterates {
        eprintln!(
            "iteration {}: {:?}, life {} yr, projected gradient {:e}",
            it.iteration, it.values, it.life_years, it.gradient_norm
        );
    }
    let first = &out.iterates[0];
    assert_eq!(first.values, vec![3.0, 1.5e6]);
    for it in &out.iterates {
        assert!((-5.0..=10.0).contains(&it.values[0]), "{it:?}");
        assert!((1.0e6..=3.0e6).contains(&it.values[1]), "{it:?}");
    }
    let last = out.iterates.last().unwrap();
    assert!(last.life_years >= first.life_years, "{out:?}");
    // The final gradient is the adjoint's at the final design.
    let g: ScatterGradient = eval(
        &st,
        &[DesignParameter::VesselOffset, DesignParameter::Tension],
        &last.values,
        Want::Gradient,
        Execution::Serial,
    );
    assert_eq!(g.gradient, last.gradient);
}

/// Refusals naming the key: the offset on a top not held by a vessel, on a vessel without a
/// ramp (the run starts with the top at 0), and bounds that are not finite or leave out the
/// scene's own offset.
#[test]
fn bad_vessel_offset_keys_are_refused_naming_the_key() {
    let design = |lower: &str, upper: &str| {
        format!(
            "[design]\n[[design.parameter]]\nname = \"vessel.offset\"\nlower = {lower}\n\
             upper = {upper}\n"
        )
    };
    let text = scene_text("", &design("-5.0", "10.0"))
        .replace("support = \"vessel\"", "support = \"riser\"");
    // A riser support has no [vessel] (the table itself is refused there) ...
    let text = text.replace("[vessel]\noffset = 3.0\nramp = 5.0\n", "");
    let text = text.replace(
        "[vessel.rao]\nperiod = [4.0, 8.0, 12.0, 16.0, 20.0, 30.0]\n\
         amplitude = [0.004, 0.076, 0.012, 0.496, 0.798, 0.987]\n\
         phase = [-270.0, -90.0, -270.0, -90.0, -90.0, -90.0]\n",
        "",
    );
    let err = Scene::from_toml_str(&text).unwrap_err();
    assert_eq!(err.key(), Some("design.parameter[0].name"), "{err}");
    assert!(err.to_string().contains("vessel"), "{err}");
    // ... a vessel without a ramp and without a RAO (the only valid scene with ramp 0 has
    // offset 0).
    let text = scene_text("", &design("-5.0", "10.0"))
        .replace("offset = 3.0\nramp = 5.0", "offset = 0.0\nramp = 0.0")
        .replace(
            "[vessel.rao]\nperiod = [4.0, 8.0, 12.0, 16.0, 20.0, 30.0]\n\
             amplitude = [0.004, 0.076, 0.012, 0.496, 0.798, 0.987]\n\
             phase = [-270.0, -90.0, -270.0, -90.0, -90.0, -90.0]\n",
            "",
        );
    let err = Scene::from_toml_str(&text).unwrap_err();
    assert_eq!(err.key(), Some("design.parameter[0].name"), "{err}");
    assert!(err.to_string().contains("vessel.ramp"), "{err}");
    // Bounds: a negative lower bound is fine, an infinite one is not, and the scene's 3 m must
    // lie within them.
    assert!(Scene::from_toml_str(&scene_text("", &design("-5.0", "10.0"))).is_ok());
    let err = Scene::from_toml_str(&scene_text("", &design("-inf", "10.0"))).unwrap_err();
    assert_eq!(err.key(), Some("design.parameter[0].lower"), "{err}");
    let err = Scene::from_toml_str(&scene_text("", &design("4.0", "10.0"))).unwrap_err();
    assert_eq!(err.key(), Some("design.parameter[0].lower"), "{err}");
    let err = Scene::from_toml_str(&scene_text("", &design("-5.0", "-6.0"))).unwrap_err();
    assert_eq!(err.key(), Some("design.parameter[0].upper"), "{err}");
}

/// A design study of a scene that starts from its static equilibrium (`[time] initial =
/// "static"`) is refused before any run, naming `time.initial`: the start depends on the design
/// (dq₀/dθ), a derivative the design gradient does not carry (docs/scene-format.md "[time]").
#[test]
fn a_static_start_is_refused_by_a_design_study() {
    let mut scene = scene("");
    scene.time.initial = chainbeam::Initial::Static;
    let cells = cells();
    let st = study(&scene, &cells, 10.0, 2.0);
    let p = params();
    let v0 = values(&scene, &p);
    let point = chainbeam::design::DesignPoint {
        params: &p,
        values: &v0,
    };
    let err = st
        .evaluate(&point, Want::Gradient, Execution::Serial, &|| {})
        .unwrap_err();
    assert!(
        matches!(err, chainbeam::design::DesignError::StaticStart),
        "{err}"
    );
    assert!(err.to_string().contains("time.initial"), "{err}");
}
