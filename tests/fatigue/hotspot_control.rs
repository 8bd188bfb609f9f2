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
