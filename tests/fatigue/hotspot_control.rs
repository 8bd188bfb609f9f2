//! Controllers acting on a hot spot (`[mpc] hotspot`, `--hotspot`): the study's per-cell damage
//! and the totals' damage per year and life are the hot spot's, as its own `hotspots` entry
//! computes them; the constant force and the PD law are chosen on the hot spot's moment.
//!
//! References: the study's `hotspots` entry of the same hot spot (its section, SCF, S-N curve
//! and DFF, from the joint torques of the replayed closed loop: tests/fatigue/hotspots.rs); the
//! same study without `hotspot` (the wellhead's numbers); the hot spot's objective
//! ([`HotSpotObjective`]) evaluated at the two constant forces by the library's control problem.

use std::fs;

use chainbeam::adjoint::{ControlProblem, HotSpotObjective, PiecewiseControl};
use chainbeam::fatigue::{MomentMeasure, WellheadDamage};
use chainbeam::fatigue_study::{
    run_study, training_scene, ControlSettings, ControllerKind, StudyInput,
};
use chainbeam::Scene;

use crate::fatigue_cli::{json, run};
use crate::gradient_check::{assert_close, central_gradient, Tolerance};

/// A 60 m steel riser (6 pendulums of 10 m) in a JONSWAP sea and a 0.3 m/s current, 0.05 s steps
/// (the scene of tests/fatigue/hotspots.rs), with a riser weld at 25 m (between joints 3 and 4:
/// a blend; F1, SCF 1.3, DFF 3) and the top joint as hot spots.
fn riser(extra: &str) -> String {
    format!(
        "[beam]\npendulums = 6\nsupport = \"riser\"\n\n\
         [pipe]\nlength = 60.0\nouter_diameter = 0.5334\nwall_thickness = 0.0222\n\n\
         [water]\ndepth = 60.0\n\n\
         [loads]\ntension = 1e6\ndrag = 1e-4\n\n\
         [loads.current]\nprofile = \"uniform\"\nspeed = 0.3\n\n\
         [loads.waves]\nspectrum = \"jonswap\"\nhs = 3.0\ntp = 9.0\nseed = 7\n\n\
         [time]\nstep = 0.05\nsteps = 100\n\n\
         [fatigue]\nouter_diameter = 0.5334\nwall_thickness = 0.0222\n\
         \n[[fatigue.hotspot]]\nname = \"weld\"\nelevation = 25.0\nscf = 1.3\ncurve = \"F1\"\n\
         dff = 3.0\n\
         \n[[fatigue.hotspot]]\nname = \"top\"\nelevation = 60.0\n{extra}"
    )
}

/// The study settings of these tests: decisions every 0.5 s, |u| ≤ 2·10⁵ N, 1 s spin-up, a 4 s
/// record, the PD gains tuned in 3 iterations on the first 2 s.
fn settings(hotspot: Option<&Scene>) -> ControlSettings {
    let mut s = ControlSettings {
        interval: 0.5,
        spin_up: 1.0,
        record: Some(4.0),
        pd_max_iters: 3,
        pd_training: Some(2.0),
        ..ControlSettings::default()
    };
    s.mpc.ocp = s.mpc.ocp.clone().with_bound(2e5);
    s.mpc.hotspot = hotspot.map(|scene| scene.hotspots[0].clone());
    s
}

/// With `hotspot` = the weld, every controller's totals (damage per year, life, each seed's life)
/// are the weld's `hotspots` entry, bit for bit (the same Miner sums of the same replayed
/// moment, combined by the same scatter sum with the weld's DFF); without it they are the
/// wellhead's, which differ, while the hot spots' own entries of the uncontrolled run do not
/// change. The constant force chosen for the weld beats the wellhead's constant force on the
/// weld's objective h Σ|M|^m + ρ h Σ u² over the training window (the optimiser's own claim,
/// checked by evaluating both forces), and the PD gains differ from the wellhead's.
#[test]
fn the_totals_are_the_hot_spots() {
    let scene = Scene::from_toml_str(&riser("")).unwrap();
    let spec = scene.fatigue_spec().unwrap();
    let controllers = [
        ControllerKind::None,
        ControllerKind::Constant,
        ControllerKind::Pd,
    ];
    let at_weld = settings(Some(&scene));
    let base = settings(None);
    let study = |settings: &ControlSettings| {
        run_study(
            &StudyInput {
                scene: &scene,
                spec: &spec,
                cells: None,
                controllers: &controllers,
                settings,
            },
            &|| {},
        )
        .unwrap()
    };
    let hot = study(&at_weld);
    let plain = study(&base);
    for (c, p) in hot.controllers.iter().zip(&plain.controllers) {
        let weld = &c.hotspots[0];
        assert_eq!(weld.name, "weld");
        println!(
            "{:?}: weld life {:.4e} y (totals {:.4e} y); wellhead life {:.4e} y",
            c.kind, weld.life_years, c.life_years, p.life_years
        );
        assert_eq!(c.life_years.to_bits(), weld.life_years.to_bits());
        assert_eq!(c.damage_per_year.to_bits(), weld.damage_per_year.to_bits());
        assert_eq!(c.seed_lives, vec![weld.life_years]);
        assert!(c.cells[0].damage > 0.0);
        assert_ne!(p.life_years, p.hotspots[0].life_years, "{:?}", c.kind);
    }
    // No control is the same run either way.
    assert_eq!(hot.controllers[0].hotspots, plain.controllers[0].hotspots);
    assert_eq!(
        hot.damage_ratio_to_none(ControllerKind::Constant, 0),
        Some(hot.controllers[1].cells[0].damage / hot.controllers[0].cells[0].damage)
    );
    // The constant forces: the weld's is the better one for the weld's objective.
    let (u_hot, u_base) = (
        hot.controllers[1].cells[0].force.unwrap(),
        plain.controllers[1].cells[0].force.unwrap(),
    );
    let cell =
        chainbeam::fatigue_study::with_record(&scene, &at_weld, ControllerKind::Constant, 4.0)
            .unwrap();
    let training = training_scene(&cell, &at_weld).unwrap();
    let m = WellheadDamage::new(&scene.hotspots[0].spec, MomentMeasure::Wellhead)
        .unwrap()
        .exponent();
    let objective = HotSpotObjective::new(
        &training,
        scene.hotspots[0].elevation,
        m,
        at_weld.mpc.effort,
    )
    .unwrap();
    let steps = training.time.steps;
    let problem = ControlProblem::builder(&training)
        .map(PiecewiseControl { steps, pieces: 1 })
        .objective(objective)
        .build_in::<2>()
        .unwrap();
    let (j_hot, j_base) = (
        problem.value(&[u_hot]).unwrap(),
        problem.value(&[u_base]).unwrap(),
    );
    println!(
        "constant: weld {u_hot:.4e} N (J {j_hot:.6e}), wellhead {u_base:.4e} N (J {j_base:.6e})"
    );
    assert_ne!(u_hot, u_base);
    assert!(j_hot <= j_base);
    assert_ne!(
        hot.controllers[2].cells[0].gains,
        plain.controllers[2].cells[0].gains
    );
}

/// `chainbeam fatigue --hotspot weld`: the JSON's totals are the weld's entry in `hotspots`,
/// `settings.hotspot` says so; the scene's `[mpc] hotspot` does the same; an unknown name is
/// refused naming the flag (or `mpc.hotspot`) and the scene's hot spots.
#[test]
fn cli_reports_the_hot_spots_life() {
    let dir = tempfile::tempdir().unwrap();
    fs::write(dir.path().join("h.toml"), riser("")).unwrap();
    fs::write(
        dir.path().join("k.toml"),
        riser("\n[mpc]\nhotspot = \"weld\"\n"),
    )
    .unwrap();
    let args = |scene: &'static str, extra: &[&'static str]| {
        let mut a = vec![
            "fatigue",
            scene,
            "--controller",
            "constant",
            "--interval",
            "0.5",
            "--bound",
            "2e5",
            "--spin-up",
            "1",
            "--record",
            "4",
        ];
        a.extend_from_slice(extra);
        a
    };
    let (code, out, stderr) = run(dir.path(), &args("h.toml", &["--hotspot", "weld"]));
    assert_eq!(code, 0, "{stderr}");
    let v = json(&out);
    assert_eq!(v["settings"]["hotspot"].as_str(), Some("weld"));
    for c in ["none", "constant"] {
        let c = &v["controllers"][c];
        let weld = &c["hotspots"][0];
        assert_eq!(weld["name"].as_str(), Some("weld"));
        assert_eq!(c["life_years"], weld["life_years"]);
        assert_eq!(c["damage_per_year"], weld["damage_per_year"]);
    }
    let (code, keyed, stderr) = run(dir.path(), &args("k.toml", &[]));
    assert_eq!(code, 0, "{stderr}");
    let keyed = json(&keyed);
    assert_eq!(keyed["controllers"], v["controllers"]);
    // Without it, the wellhead's numbers and no `settings.hotspot`.
    let (code, plain, stderr) = run(dir.path(), &args("h.toml", &[]));
    assert_eq!(code, 0, "{stderr}");
    let plain = json(&plain);
    assert!(plain["settings"].get("hotspot").is_none());
    assert_ne!(
        plain["controllers"]["none"]["life_years"],
        v["controllers"]["none"]["life_years"]
    );
    let (code, _, stderr) = run(dir.path(), &args("h.toml", &["--hotspot", "nope"]));
    assert_eq!(code, 1);
    assert!(
        stderr.contains("--hotspot") && stderr.contains("nope") && stderr.contains("weld"),
        "{stderr}"
    );
    fs::write(
        dir.path().join("bad.toml"),
        riser("\n[mpc]\nhotspot = \"nope\"\n"),
    )
    .unwrap();
    let (code, _, stderr) = run(dir.path(), &args("bad.toml", &[]));
    assert_eq!(code, 1);
    assert!(stderr.contains("mpc.hotspot"), "{stderr}");
}

/// The PD law about the moment's running mean (`moment_about = "mean"`), the gains given: each
/// decision is u_j = clamp(u_b − K_p (M_j − M̄_j) − K_d Ṁ_j, ±u_max), recomputed here on a
/// replay of the run's own decisions with the hot spot's moment M_j and its last step's
/// difference Ṁ_j read from the plant, and the running mean by its recurrence written out,
/// M̄_j = M̄_{j−1} + Δt (M_j − M̄_{j−1})/(τ + Δt), M̄_0 = M_0 (`running_mean`'s docs). The same
/// gains about zero give other decisions; about the mean without a hot spot is refused.
#[test]
fn pd_about_the_mean_feeds_back_the_fluctuation() {
    use chainbeam::fatigue_study::run_controller;
    use chainbeam::mpc::{MomentAbout, Plant, PD_MEAN_TIME};
    let scene = Scene::from_toml_str(&riser("")).unwrap();
    let [bias, kp, kd] = [2e4, 5e-3, 2e-3];
    let mut settings = settings(Some(&scene));
    settings.pd_gains = Some([bias, kp, kd]);
    settings.mpc.moment_about = MomentAbout::Mean;
    let record = run_controller(&scene, ControllerKind::Pd, &settings).unwrap();
    let decisions = record.decisions.as_deref().unwrap();
    let spot = HotSpotObjective::new(&scene, scene.hotspots[0].elevation, 3.0, 0.0).unwrap();
    let mut plant = Plant::<f64>::new(&scene).unwrap();
    let (h, dt, bound) = (plant.h(), settings.interval, 2e5);
    let m = (dt / h).round() as usize;
    assert_eq!(decisions.len() * m, plant.steps());
    let mut mean = f64::NAN;
    let mut worst = 0.0_f64;
    for (j, &u) in decisions.iter().enumerate() {
        let moment = spot.moment_of_attitudes(&plant.state().q);
        let rate = plant
            .previous_state()
            .map_or(0.0, |p| (moment - spot.moment_of_attitudes(&p.q)) / h);
        mean = if j == 0 {
            moment
        } else {
            mean + dt * (moment - mean) / (PD_MEAN_TIME + dt)
        };
        let expected = (bias - kp * (moment - mean) - kd * rate).clamp(-bound, bound);
        worst = worst.max((u - expected).abs());
        plant.set_control(u).unwrap();
        for _ in 0..m {
            plant.advance().unwrap();
        }
    }
    println!("largest |u − law| {worst:.3e} N of decisions up to {bound:e} N");
    assert!(worst <= 1e-9 * bound, "{worst}");
    // The law acted: no decision on the bound, and the feedback moved them off the bias.
    let spread = decisions
        .iter()
        .map(|u| (u - bias).abs())
        .fold(0.0, f64::max);
    println!("decisions within {spread:.3e} N of the bias");
    assert!(decisions.iter().all(|u| u.abs() < bound) && spread > 1.0);
    // About zero, the same gains decide otherwise.
    settings.mpc.moment_about = MomentAbout::Zero;
    let zero = run_controller(&scene, ControllerKind::Pd, &settings).unwrap();
    assert_ne!(zero.decisions.as_deref(), Some(decisions));
    // About the mean without a hot spot: refused, naming the setting.
    let mut plain = settings.clone();
    plain.mpc.hotspot = None;
    plain.mpc.moment_about = MomentAbout::Mean;
    let e = run_controller(&scene, ControllerKind::Pd, &plain).unwrap_err();
    assert!(e.to_string().contains("moment_about"), "{e}");
}

/// The tuning of the PD law about the running mean: its scales start the bias at zero (not at
/// the force that cancels the static moment), and the gradient of its closed-loop objective
/// J = Σ_k [(M_k − M̄_k)² + ρ h u_k²] in the scaled parameters (dual numbers through the loop and
/// the running mean) agrees with central differences of the plain f64 loop to 1e-6, at the start
/// and at larger gains.
#[test]
fn pd_about_the_mean_gradient_matches_central_differences() {
    use chainbeam::fatigue_study::pd::{PdScales, ScaledPdTuning, PD_START};
    use chainbeam::mpc::{MomentAbout, PdTuning};
    use chainbeam::optimize::OptimProblem;
    let mut scene = Scene::from_toml_str(&riser("")).unwrap();
    scene.time.steps = 60;
    let spot = HotSpotObjective::new(&scene, scene.hotspots[0].elevation, 3.0, 0.0)
        .unwrap()
        .with_about(MomentAbout::Mean);
    let bound = 2e5;
    let zero = PdScales::of_at(
        &scene,
        bound,
        Some(&spot.clone().with_about(MomentAbout::Zero)),
    );
    let scales = PdScales::of_at(&scene, bound, Some(&spot)).unwrap();
    assert_eq!(scales.static_bias, 0.0);
    assert_ne!(zero.unwrap().static_bias, 0.0);
    let scaled = ScaledPdTuning {
        tuning: PdTuning::new(&scene, 0.5, bound, 1e-6)
            .unwrap()
            .at_hot_spot(spot),
        scales,
    };
    for x in [PD_START, [0.2, 0.5, -0.5]] {
        let (_, g) = scaled.value_and_gradient(&x).unwrap();
        let fd = central_gradient(&|x| scaled.value(x).unwrap(), &x, 1e-5);
        let label = format!("∂J/∂x at {x:?}");
        let source = "central difference, step 1e-5";
        let worst = assert_close(&label, &g, &fd, source, Tolerance::relative(1e-6));
        println!("{label}: {g:?} vs {fd:?} (worst {worst:.1e}, tolerance 1e-6)");
    }
}
