//! `chainbeam fatigue` (docs/cli.md): the JSON fields, the same result from a simulation and
//! from its `simulate` CSV (`--series`), a spatial scene's worst point, and typed one-line errors.

use std::fs;

use crate::fatigue_cli;

use chainbeam::fatigue::{assess, MomentHistory};
use chainbeam::{simulate, Scene};
use fatigue_cli::{beam, json, run, FATIGUE_TABLE};

/// The thesis riser (load 2 N at node 5, or at 45° between x and z) over `steps` steps of
/// 0.01 s, with a `[fatigue]` table for a small steel tube.
fn scene(force: &str, steps: usize) -> String {
    format!(
        r#"{beam}
[loads]
gravity = 0.0
drag = 0.0
[[loads.point]]
node = 5
force = {force}

[time]
step = 0.01
steps = {steps}

{table}"#,
        beam = beam("riser"),
        table = FATIGUE_TABLE
    )
}

/// The JSON has exactly the documented fields; its damage is the library's assessment of the
/// simulated moment; the simulate CSV read back with --series gives the same JSON.
#[test]
fn fatigue_of_a_simulation_and_of_its_csv_agree() {
    let dir = tempfile::tempdir().unwrap();
    let text = scene("2.0", 400);
    fs::write(dir.path().join("s.toml"), &text).unwrap();
    let (code, stdout, stderr) = run(dir.path(), &["fatigue", "s.toml"]);
    assert_eq!(code, 0, "{stderr}");
    let v = json(&stdout);
    let keys: Vec<&str> = v.as_object().unwrap().keys().map(String::as_str).collect();
    let mut sorted = keys.clone();
    sorted.sort_unstable();
    assert_eq!(
        sorted,
        [
            "cycles",
            "damage",
            "damage_per_year",
            "duration_s",
            "life_years"
        ]
    );

    let scene = Scene::from_toml_str(&text).unwrap();
    let traj = simulate(&scene).unwrap();
    let spec = scene.fatigue.unwrap();
    let history = MomentHistory {
        duration_s: 4.0,
        moment: traj.moment(),
        moment_x: None,
        measure: scene.moment_measure(),
    };
    let a = assess(&spec, history).unwrap();
    assert_eq!(v["damage"].as_f64().unwrap(), a.damage);
    assert!(a.damage > 0.0);
    assert_eq!(v["duration_s"].as_f64().unwrap(), 4.0);
    let cycles = v["cycles"].as_array().unwrap();
    assert_eq!(cycles.len(), a.cycles.len());
    for (c, ours) in cycles.iter().zip(&a.cycles) {
        let c: Vec<f64> = c
            .as_array()
            .unwrap()
            .iter()
            .map(|x| x.as_f64().unwrap())
            .collect();
        assert_eq!(c, [ours.range, ours.mean, ours.count]);
    }
    let dpy = v["damage_per_year"].as_f64().unwrap();
    assert!((dpy - a.damage * 365.25 * 86400.0 / 4.0).abs() <= 1e-15 * dpy);
    let life = v["life_years"].as_f64().unwrap();
    assert!((life - 1.0 / (3.0 * dpy)).abs() <= 1e-12 * life);

    let (code, _, stderr) = run(dir.path(), &["simulate", "s.toml", "--output", "s.csv"]);
    assert_eq!(code, 0, "{stderr}");
    let (code, from_csv, stderr) = run(dir.path(), &["fatigue", "s.toml", "--series", "s.csv"]);
    assert_eq!(code, 0, "{stderr}");
    assert_eq!(json(&from_csv), v);
}

/// A load at 45° between x and z moves the riser as the same load along z, turned by 45°
/// (lib.rs docs), so the worst of the 8 points (θ = 45°) sees the planar riser's stress: the
/// same damage; and the spatial simulate CSV (with moment_x) read back gives the same JSON.
#[test]
fn spatial_worst_point_equals_the_planar_riser() {
    let dir = tempfile::tempdir().unwrap();
    fs::write(dir.path().join("planar.toml"), scene("2.0", 300)).unwrap();
    let oblique = scene("[1.4142135623730951, 1.4142135623730951]", 300);
    fs::write(dir.path().join("oblique.toml"), oblique).unwrap();
    let (code, planar, stderr) = run(dir.path(), &["fatigue", "planar.toml"]);
    assert_eq!(code, 0, "{stderr}");
    let (code, spatial, stderr) = run(dir.path(), &["fatigue", "oblique.toml"]);
    assert_eq!(code, 0, "{stderr}");
    let (p, s) = (json(&planar), json(&spatial));
    let (dp, ds) = (p["damage"].as_f64().unwrap(), s["damage"].as_f64().unwrap());
    assert!((dp - ds).abs() <= 1e-9 * dp, "{dp} vs {ds}");

    let (code, _, stderr) = run(dir.path(), &["simulate", "oblique.toml", "-o", "o.csv"]);
    assert_eq!(code, 0, "{stderr}");
    assert!(fs::read_to_string(dir.path().join("o.csv"))
        .unwrap()
        .contains("moment_x"));
    let (code, from_csv, stderr) = run(
        dir.path(),
        &["fatigue", "oblique.toml", "--series", "o.csv"],
    );
    assert_eq!(code, 0, "{stderr}");
    assert_eq!(json(&from_csv), s);
}

/// No load, no damage: life_years is null (an infinite life), not a non-finite number.
#[test]
fn no_damage_gives_a_null_life() {
    let dir = tempfile::tempdir().unwrap();
    fs::write(dir.path().join("s.toml"), scene("0.0", 50)).unwrap();
    let (code, stdout, stderr) = run(dir.path(), &["fatigue", "s.toml"]);
    assert_eq!(code, 0, "{stderr}");
    let v = json(&stdout);
    assert_eq!(v["damage"].as_f64().unwrap(), 0.0);
    assert!(v["life_years"].is_null());
}

/// Bad input: one line on stderr naming the file and the key or column, exit status 1.
#[test]
fn bad_fatigue_input_names_the_key() {
    let dir = tempfile::tempdir().unwrap();
    let good = scene("2.0", 50);
    let cases = [
        (good.replace("[fatigue]", "[other]"), "unknown"),
        (
            good.replace("curve = \"F1\"", "curve = \"F9\""),
            "fatigue.curve",
        ),
        (good.replace("\"air\"", "\"sea\""), "fatigue.environment"),
        (
            good.replace("wall_thickness = 0.002", "wall_thickness = 0.02"),
            "fatigue.wall_thickness",
        ),
        (good.replace("dff = 3.0", "dff = -1.0"), "fatigue.dff"),
        (good.replace("scf = 1.2", "scf = 0.0"), "fatigue.scf"),
    ];
    for (text, key) in cases {
        fs::write(dir.path().join("bad.toml"), &text).unwrap();
        let (code, _, stderr) = run(dir.path(), &["fatigue", "bad.toml"]);
        assert_eq!(code, 1, "{key}: {stderr}");
        assert!(
            stderr.contains(key) && stderr.contains("bad.toml"),
            "{key}: {stderr}"
        );
        assert_eq!(stderr.lines().count(), 1, "{stderr}");
    }
    let without = good.split("[fatigue]").next().unwrap().to_string();
    fs::write(dir.path().join("none.toml"), without).unwrap();
    let (code, _, stderr) = run(dir.path(), &["fatigue", "none.toml"]);
    assert_eq!(code, 1);
    assert!(
        stderr.contains("`fatigue`") && stderr.contains("none.toml"),
        "{stderr}"
    );

    fs::write(dir.path().join("s.toml"), &good).unwrap();
    for (csv, what) in [
        ("t,energy\n0,1\n1,2\n", "no column `moment`"),
        ("t,moment\n0,1\n0,2\n", "line 3: t must increase strictly"),
        (
            "t,moment\n0,1\n1,abc\n",
            "line 3: column `moment`: not a finite number",
        ),
        ("t,moment\n0,1\n", "at least 2 rows"),
    ] {
        fs::write(dir.path().join("m.csv"), csv).unwrap();
        let (code, _, stderr) = run(dir.path(), &["fatigue", "s.toml", "--series", "m.csv"]);
        assert_eq!(code, 1, "{stderr}");
        assert!(
            stderr.contains(what) && stderr.contains("m.csv"),
            "{what}: {stderr}"
        );
    }
    // The output never lands on an input.
    let (code, _, stderr) = run(
        dir.path(),
        &[
            "fatigue", "s.toml", "--series", "m.csv", "--output", "m.csv",
        ],
    );
    assert_eq!(code, 1, "{stderr}");
    assert_eq!(
        fs::read_to_string(dir.path().join("m.csv")).unwrap(),
        "t,moment\n0,1\n"
    );
}
