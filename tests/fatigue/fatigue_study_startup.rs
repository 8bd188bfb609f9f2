//! The fatigue study's start of a record, its PD tuning and MPC's proxy (src/fatigue_study.rs,
//! src/fatigue_study/pd.rs): the spin-up window against the static equilibrium, the scaled PD
//! tuning's gradient against central differences and its gains' signs, the proxy's exponent
//! against the DNV-RP-C203 table.

use chainbeam::fatigue::{DnvClass, Environment, FatigueSpec};
use chainbeam::fatigue_study::pd::{PdScales, ScaledPdTuning, PD_BOX, PD_START};
use chainbeam::fatigue_study::{
    fatigue_proxy, pd_law, run_controller, run_study, spin_up_steps, training_scene,
    ControlSettings, ControllerKind, StudyError, StudyInput,
};
use chainbeam::mpc::planning::planning_scene;
use chainbeam::mpc::{run_closed_loop, ConstantForce, PdTuning};
use chainbeam::optimize::OptimProblem;
use chainbeam::scene::ObjectiveKind;
use chainbeam::statics::static_equilibrium;
use chainbeam::{catalogue, Chain, Scene};

use crate::gradient_check::{assert_close, central_gradient, Tolerance};

/// riser_300m.toml (the 300 m drilling riser in a 0.5 m/s current) without its sea, rebuilt as
/// 15 pendulums at h = 0.05 s (the drag constant rescaled; the convergence table of
/// docs/scene-format.md runs this resolution), `seconds` long.
fn calm_riser(seconds: f64) -> Scene {
    let path = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/examples/scenes/riser_300m.toml"
    );
    let mut scene = planning_scene(&Scene::from_file(path).unwrap(), 15, 0.05).unwrap();
    scene.loads.waves = None;
    scene.time.steps = (seconds / 0.05).round() as usize;
    scene
}

/// The headline's wellhead: the pipe's section, F1 in seawater with CP, SCF 1.2, DFF 10.
fn spec(scene: &Scene) -> FatigueSpec {
    let pipe = scene.pipe.unwrap();
    FatigueSpec {
        scf: 1.2,
        curve: DnvClass::F1,
        environment: Environment::SeawaterCp,
        dff: 10.0,
        ..FatigueSpec::new(pipe.outer_diameter, pipe.wall_thickness)
    }
}

fn damage_per_year(scene: &Scene, spin_up: f64) -> f64 {
    let settings = ControlSettings {
        spin_up,
        ..ControlSettings::default()
    };
    let spec = spec(scene);
    let input = StudyInput {
        scene,
        spec: &spec,
        cells: None,
        controllers: &[ControllerKind::None],
        settings: &settings,
    };
    run_study(&input, &|| {}).unwrap().controllers[0].damage_per_year
}

/// A riser at rest in a current, no sea: the record swings out to the static offset and settles
/// there. Reference: the static equilibrium in the current (src/statics.rs, Newton on ∇U = 0,
/// an independent method), which the record reaches (a steady state); counted from t = 0 the
/// start-up's half cycle up to the offset is the damage, after the spin-up window there is
/// next to none.
#[test]
fn spin_up_leaves_out_the_start_up() {
    let scene = calm_riser(300.0);
    let record = run_controller(&scene, ControllerKind::None, &ControlSettings::default()).unwrap();
    let statics = static_equilibrium(&scene).unwrap();
    let chain = Chain::<f64, 2>::from_scene(&scene).unwrap();
    let q: Vec<[f64; 2]> = statics.attitudes.iter().map(|a| [a[1], a[2]]).collect();
    let m_static = chain.base_moment(&q);
    let skip = spin_up_steps(&scene, SPIN_UP).unwrap();
    let after = &record.moment[skip..];
    let worst = after
        .iter()
        .fold(0.0f64, |a, m| a.max((m - m_static).abs()));
    println!(
        "static M₀ {m_static:.6e}, first peak {:.6e}, worst deviation after {SPIN_UP} s {worst:.3e}",
        record.moment.iter().fold(0.0f64, |a, m| a.max(m.abs()))
    );
    assert!(worst < DEVIATION * m_static.abs(), "{worst} vs {m_static}");
    let (counted, left_out) = (
        damage_per_year(&scene, 0.0),
        damage_per_year(&scene, SPIN_UP),
    );
    println!("damage per year from t = 0: {counted:.4e}, after the spin-up: {left_out:.4e}");
    assert!(counted > 0.0);
    assert!(left_out < RATIO * counted, "{left_out} vs {counted}");
}

/// The spin-up window the headline uses [s] (docs/cli.md, "The start of a record").
const SPIN_UP: f64 = 60.0;
/// The largest deviation from the static moment after the window, relative.
const DEVIATION: f64 = 1e-2;
/// The largest damage after the window, relative to the damage counted from t = 0.
const RATIO: f64 = 1e-6;

/// A window that is negative, not finite or not shorter than the record is refused before any
/// run, naming the window and the record.
#[test]
fn spin_up_refusals() {
    let scene = calm_riser(10.0);
    for bad in [-1.0, f64::NAN, f64::INFINITY, 10.0, 20.0] {
        let settings = ControlSettings {
            spin_up: bad,
            ..ControlSettings::default()
        };
        let spec = spec(&scene);
        let input = StudyInput {
            scene: &scene,
            spec: &spec,
            cells: None,
            controllers: &[ControllerKind::None],
            settings: &settings,
        };
        let e = run_study(&input, &|| {}).unwrap_err();
        assert!(matches!(e, StudyError::SpinUp { .. }), "{bad}: {e}");
        assert!(e.to_string().contains("spin_up"), "{e}");
    }
    // Whole steps: 0.05 s is one step, 0.06 s two.
    assert_eq!(spin_up_steps(&scene, 0.05).unwrap(), 1);
    assert_eq!(spin_up_steps(&scene, 0.06).unwrap(), 2);
}

/// MPC's proxy is Σ|M₀|^m with m the first slope of the S-N curve: 3 for F1 and D, 4 for B1
/// (DNV-RP-C203 Table 2-2, m₁).
#[test]
fn the_proxy_exponent_is_the_first_slope() {
    let scene = calm_riser(10.0);
    for (class, m) in [(DnvClass::F1, 3.0), (DnvClass::D, 3.0), (DnvClass::B1, 4.0)] {
        let spec = FatigueSpec {
            curve: class,
            ..spec(&scene)
        };
        assert_eq!(
            fatigue_proxy(&spec, &scene).unwrap(),
            ObjectiveKind::Power { exponent: m }
        );
    }
}

/// The mpc riser (n = 10, a sheared current and an irregular sea at node 5) over 4 s.
fn small() -> Scene {
    let mut scene = catalogue::mpc_riser();
    scene.time.steps = 400;
    scene
}

/// The scaled tuning's gradient (the chain rule on the dual-number gradient of the closed loop)
/// against central differences of its value (a plain f64 closed loop), at the start and at a
/// point with larger gains; the steps stay away from the force bound's kinks.
#[test]
fn scaled_pd_gradient_matches_central_differences() {
    let scene = small();
    let scaled = ScaledPdTuning {
        tuning: PdTuning::new(&scene, 0.1, 50.0, 0.01).unwrap(),
        scales: PdScales::of(&scene, 50.0).unwrap(),
    };
    for x in [PD_START, [0.3, -0.5, -1.0]] {
        let (_, g) = scaled.value_and_gradient(&x).unwrap();
        let fd = central_gradient(&|x| scaled.value(x).unwrap(), &x, 1e-5);
        let label = format!("∂J/∂x at {x:?}");
        let source = "central difference, step 1e-5";
        assert_close(&label, &g, &fd, source, Tolerance::relative(1e-6));
    }
}

/// The tuned law keeps positive loop gains K_p k_u and K_d k_u ω inside the box (it cannot end
/// reversed), its bias is the static one plus at most u_max, and it does better on its own
/// closed-loop objective than the start; the static gain is the statics' (a second solve at
/// another force gives the same slope: the statics are linear in u to 10⁻³ here).
#[test]
fn tuned_pd_gains_stay_positive_and_improve() {
    let scene = small();
    let bound = 5.0;
    let settings = ControlSettings {
        interval: 0.1,
        pd_max_iters: 10,
        mpc: chainbeam::mpc::MpcOptions {
            ocp: chainbeam::ocp::OcpOptions::default().with_bound(bound),
            ..Default::default()
        },
        ..ControlSettings::default()
    };
    let law = pd_law(&scene, &settings).unwrap();
    let scales = PdScales::of(&scene, bound).unwrap();
    let (gp, gd) = (law.kp / scales.kp, law.kd / scales.kd);
    println!(
        "loop gains {gp:.4e}, {gd:.4e}; bias {:.4e} (static {:.4e})",
        law.bias.z, scales.static_bias
    );
    let limit = PD_BOX.exp() * (1.0 + 1e-12);
    assert!(
        gp > 0.0 && gp <= limit && gd > 0.0 && gd <= limit,
        "{gp} {gd}"
    );
    assert!((law.bias.z - scales.static_bias).abs() <= bound * (1.0 + 1e-12));
    let tuning = PdTuning::new(&scene, 0.1, bound, settings.mpc.effort).unwrap();
    let start = scales.gains(&PD_START);
    let (j0, j1) = (
        tuning.value(&start).unwrap(),
        tuning.value(&[law.bias.z, law.kp, law.kd]).unwrap(),
    );
    println!("closed-loop J: start {j0:.6e}, tuned {j1:.6e}");
    assert!(j1 < j0, "{j1} vs {j0}");
    // The tuned law run by the closed loop (not the tuning's own loop) leaves the same J's
    // moment part: the law is what was tuned.
    let mut pd = law;
    let run = run_closed_loop(&scene, 0.1, &mut pd).unwrap();
    assert!(run.summary.c_sum <= j1 * (1.0 + 1e-12));
}

/// The training window of the PD law and the constant force: whole control intervals, at most
/// the record; the constant controller's force is the best constant force of that window (the
/// condensed solver on the cut scene, computed here directly).
#[test]
fn the_training_window_cuts_whole_intervals() {
    let scene = small();
    let with = |pd_training| ControlSettings {
        interval: 0.1,
        pd_training,
        ..ControlSettings::default()
    };
    assert_eq!(
        training_scene(&scene, &with(Some(0.3))).unwrap().time.steps,
        30
    );
    assert_eq!(
        training_scene(&scene, &with(Some(0.04)))
            .unwrap()
            .time
            .steps,
        10
    );
    assert_eq!(
        training_scene(&scene, &with(Some(100.0)))
            .unwrap()
            .time
            .steps,
        400
    );
    assert_eq!(training_scene(&scene, &with(None)).unwrap().time.steps, 400);
    let e = training_scene(&scene, &with(Some(-1.0))).unwrap_err();
    assert!(e.to_string().contains("pd_training"), "{e}");
    let settings = ControlSettings {
        mpc: chainbeam::mpc::MpcOptions {
            ocp: chainbeam::ocp::OcpOptions::default().with_bound(5.0),
            ..Default::default()
        },
        ..with(Some(1.0))
    };
    let record = run_controller(&scene, ControllerKind::Constant, &settings).unwrap();
    let cut = training_scene(&scene, &settings).unwrap();
    let (best, _) = ConstantForce::best(&cut, 5.0, settings.mpc.effort).unwrap();
    assert_eq!(record.force, Some(best.u.z));
    assert_eq!(record.moment.len(), 401);
}
