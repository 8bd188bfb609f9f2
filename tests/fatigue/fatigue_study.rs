//! The fatigue study (src/fatigue_study.rs): each controller's damage against an independent
//! computation of the same record, the refusal of a control that cannot act, the controller
//! list.

use chainbeam::catalogue;
use chainbeam::fatigue::{assess, FatigueSpec, MomentHistory};
use chainbeam::fatigue_study::{
    check_control_can_act, run_controller, run_study, ControlSettings, ControllerKind, StudyError,
    StudyInput,
};
use chainbeam::mpc::{run_closed_loop, ConstantForce, NoControl};
use chainbeam::scene::Support;
use chainbeam::{simulate, Scene};

/// The mpc riser (irregular sea at node 5 and a sheared current) over 4 s.
fn riser() -> Scene {
    let mut scene = catalogue::mpc_riser();
    scene.time.steps = 400;
    scene
}

/// A 20 mm × 2 mm steel tube, curve F1 in air, DFF 3: cycles of a few MPa at a 2 N load.
fn spec() -> FatigueSpec {
    let mut spec = FatigueSpec::new(0.02, 0.002);
    spec.dff = 3.0;
    spec
}

fn damage(spec: &FatigueSpec, moment: &[f64], duration_s: f64) -> f64 {
    let history = MomentHistory {
        duration_s,
        moment,
        moment_x: None,
        // The study counts the wellhead moment M_w = M₀ · l₁/2 of the scene's chain.
        measure: riser().moment_measure(),
    };
    assess(spec, history).unwrap().damage
}

fn rel(a: f64, b: f64) -> f64 {
    (a - b).abs() / b.abs()
}

/// `none` (the scene without its control, by `simulate`) and the closed loop with u = 0
/// (mpc::run_closed_loop with NoControl, which re-takes every switching step) are two
/// computations of the same RATTLE trajectory: the same damage.
#[test]
fn none_equals_the_closed_loop_without_control() {
    let scene = riser();
    let spec = spec();
    let settings = ControlSettings::default();
    let none = run_controller(&scene, ControllerKind::None, &settings).unwrap();
    let closed = run_closed_loop(&scene, 0.1, &mut NoControl).unwrap();
    let (a, b) = (
        damage(&spec, &none.moment, none.duration_s),
        damage(&spec, &closed.moment, 4.0),
    );
    assert!(a > 0.0);
    assert!(rel(a, b) <= 1e-12, "{a} vs {b}");
    // The scene as written applies its [control] values (0 N here): the same record.
    let as_written = run_controller(&scene, ControllerKind::Scene, &settings).unwrap();
    assert_eq!(as_written.moment, none.moment);
}

/// The constant controller's record is the open-loop simulation of the scene with
/// [`ConstantForce::best`]'s force as its constant control (`simulate`, another code path than
/// the closed loop), and its study entry is that record's Miner sum scaled to a year.
#[test]
fn constant_equals_the_simulation_with_its_force() {
    let scene = riser();
    let spec = spec();
    let settings = ControlSettings::default();
    let (best, _) = ConstantForce::best(&scene, 5.0, 0.01).unwrap();
    let mut with_force = scene.clone();
    with_force.control.as_mut().unwrap().values = vec![best.u.z];
    let traj = simulate(&with_force).unwrap();
    let expected = damage(&spec, traj.moment(), 4.0);

    let kinds = [ControllerKind::None, ControllerKind::Constant];
    let input = StudyInput {
        scene: &scene,
        spec: &spec,
        cells: None,
        controllers: &kinds,
        settings: &settings,
    };
    let study = run_study(&input, &|| {}).unwrap();
    let c = study.get(ControllerKind::Constant).unwrap();
    assert_eq!(c.cells[0].force, Some(best.u.z));
    assert!(rel(c.cells[0].damage, expected) <= 1e-12);
    let per_year = expected * 365.25 * 86400.0 / 4.0;
    assert!(rel(c.damage_per_year, per_year) <= 1e-12);
    assert!(rel(c.life_years, 1.0 / (3.0 * per_year)) <= 1e-12);
    let none = study.get(ControllerKind::None).unwrap();
    let extension = study.life_extension(ControllerKind::Constant).unwrap();
    assert!(rel(extension, none.damage_per_year / c.damage_per_year) <= 1e-12);
    // The steady current's drag bends the riser one way; the force cancels it (mpc module docs):
    // the mean stress falls, the ranges hardly change.
    assert!(best.u.z > 2.0 && best.u.z < 4.0, "{}", best.u.z);
}

/// A force at the tip of a fixed-fixed beam moves nothing: refused before any run, naming the
/// controller and the node; `none` is not a control and runs.
#[test]
fn a_control_that_cannot_act_is_refused() {
    let mut scene = riser();
    scene.beam.support = Support::FixedFixed;
    let err = check_control_can_act(&scene, ControllerKind::Mpc).unwrap_err();
    assert!(matches!(
        err,
        StudyError::ControlCannotAct {
            controller: "mpc",
            node: 10,
            support: "fixed-fixed"
        }
    ));
    check_control_can_act(&scene, ControllerKind::None).unwrap();
    let spec = spec();
    let settings = ControlSettings::default();
    let kinds = [ControllerKind::None, ControllerKind::Pd];
    let input = StudyInput {
        scene: &scene,
        spec: &spec,
        cells: None,
        controllers: &kinds,
        settings: &settings,
    };
    let err = run_study(&input, &|| panic!("no run may start")).unwrap_err();
    assert!(matches!(
        err,
        StudyError::ControlCannotAct {
            controller: "pd",
            ..
        }
    ));
    // At a free node of the same beam it acts.
    scene.control.as_mut().unwrap().node = 5;
    check_control_can_act(&scene, ControllerKind::Pd).unwrap();
}

#[test]
fn controller_lists() {
    use ControllerKind::*;
    assert_eq!(
        ControllerKind::parse_list("mpc, none,pd,constant").unwrap(),
        [None, Constant, Pd, Mpc]
    );
    assert_eq!(ControllerKind::parse_list("pd").unwrap(), [Pd]);
    assert!(matches!(
        ControllerKind::parse_list("none,lqr"),
        Err(StudyError::UnknownController { name }) if name == "lqr"
    ));
    assert!(matches!(
        ControllerKind::parse_list("pd,pd"),
        Err(StudyError::DuplicateController { .. })
    ));
    assert!(matches!(
        ControllerKind::parse_list(" , "),
        Err(StudyError::NoControllers)
    ));
    // `scene` is the plain run's, not a --controller choice.
    assert!(ControllerKind::parse_list("scene").is_err());
}
