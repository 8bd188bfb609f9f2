//! `chainbeam fatigue --controller` (docs/cli.md): the JSON contract, `none` against the plain
//! run, `constant` against `fatigue --series` of a `simulate` with its force, and refusals.

use std::fs;
use std::path::Path;

use assert_cmd::cargo::cargo_bin_cmd;

/// The thesis riser with drag 1 kg/m under a 2 N wave (period 2 s) at node 5 and a steady 1 N
/// load, 4 s of 0.01 s, control at node 10 (constant 0), a [fatigue] table of a small tube.
fn scene(support: &str) -> String {
    format!(
        r#"[beam]
pendulums = 10
length = 1.0
mass = 1.0
stiffness = 1000.0
support = "{support}"
base_stiffness = 2000.0
tip_stiffness = 2000.0

[loads]
gravity = 0.0
drag = 1.0
[[loads.point]]
node = 5
force = 1.0
[[loads.point.harmonic]]
amplitude = 2.0
period = 2.0

[time]
step = 0.01
steps = 400

[control]
node = 10
kind = "constant"
values = [0.0]

[fatigue]
outer_diameter = 0.02
wall_thickness = 0.002
scf = 1.2
curve = "F1"
environment = "air"
dff = 3.0
"#
    )
}

fn run(dir: &Path, args: &[&str]) -> (i32, String, String) {
    let out = cargo_bin_cmd!("chainbeam")
        .current_dir(dir)
        .args(args)
        .output()
        .unwrap();
    (
        out.status.code().unwrap_or(-1),
        String::from_utf8(out.stdout).unwrap(),
        String::from_utf8(out.stderr).unwrap(),
    )
}

fn json(text: &str) -> serde_json::Value {
    serde_json::from_str(text).unwrap_or_else(|e| panic!("{e}: {text}"))
}

fn num(v: &serde_json::Value) -> f64 {
    v.as_f64().unwrap_or_else(|| panic!("not a number: {v}"))
}

fn rel(a: f64, b: f64) -> f64 {
    (a - b).abs() / b.abs()
}

/// `--controller none,constant`: the documented keys; `none` is the plain `fatigue` run (the
/// same JSON numbers); `constant`'s damage is `fatigue --series` of the `simulate` CSV of the
/// scene with the reported force as its constant control; `life_extension` is the ratio of
/// the lives.
#[test]
fn controllers_against_the_plain_run_and_a_simulation() {
    let dir = tempfile::tempdir().unwrap();
    fs::write(dir.path().join("s.toml"), scene("riser")).unwrap();
    let (code, plain, stderr) = run(dir.path(), &["fatigue", "s.toml"]);
    assert_eq!(code, 0, "{stderr}");
    let plain = json(&plain);
    let (code, out, stderr) = run(
        dir.path(),
        &["fatigue", "s.toml", "--controller", "constant,none"],
    );
    assert_eq!(code, 0, "{stderr}");
    let v = json(&out);
    // (serde_json's maps here sort their keys; the output's order is checked on its text.)
    let top: Vec<&String> = v.as_object().unwrap().keys().collect();
    assert_eq!(top, ["controllers", "life_extension", "settings"]);
    let controllers = v["controllers"].as_object().unwrap();
    assert_eq!(
        controllers.keys().collect::<Vec<_>>(),
        ["constant", "none"]
    );
    assert!(out.find("\"none\"").unwrap() < out.find("\"constant\"").unwrap());
    for c in controllers.values() {
        let keys: Vec<&String> = c.as_object().unwrap().keys().collect();
        assert_eq!(keys, ["cells", "damage_per_year", "life_years"]);
        let cell = &c["cells"][0];
        for key in ["hs", "tp", "probability", "damage_per_year"] {
            assert!(cell.get(key).is_some(), "{key}: {cell}");
        }
        assert_eq!(num(&cell["probability"]), 1.0);
        assert_eq!(num(&cell["damage_per_year"]), num(&c["damage_per_year"]));
    }

    let none = &v["controllers"]["none"];
    assert_eq!(num(&none["damage_per_year"]), num(&plain["damage_per_year"]));
    assert_eq!(num(&none["life_years"]), num(&plain["life_years"]));
    assert_eq!(num(&none["cells"][0]["damage"]), num(&plain["damage"]));

    let constant = &v["controllers"]["constant"];
    let force = num(&constant["cells"][0]["force"]);
    assert!(force.abs() > 0.1, "the force acts against the 1 N load: {force}");
    let with_force = scene("riser").replace("values = [0.0]", &format!("values = [{force:e}]"));
    fs::write(dir.path().join("u.toml"), with_force).unwrap();
    let (code, _, stderr) = run(dir.path(), &["simulate", "u.toml", "-o", "u.csv"]);
    assert_eq!(code, 0, "{stderr}");
    let (code, series, stderr) = run(dir.path(), &["fatigue", "u.toml", "--series", "u.csv"]);
    assert_eq!(code, 0, "{stderr}");
    let series = json(&series);
    let (a, b) = (
        num(&constant["damage_per_year"]),
        num(&series["damage_per_year"]),
    );
    assert!(rel(a, b) <= 1e-12, "{a} vs {b}");

    let ext = &v["life_extension"];
    assert_eq!(num(&ext["none"]), 1.0);
    let expected = num(&constant["life_years"]) / num(&none["life_years"]);
    assert!(rel(num(&ext["constant"]), expected) <= 1e-12);
}

/// `pd` and `mpc` run (a short horizon) and report finite lives; `none` is added as the
/// reference of `life_extension` when the list leaves it out.
#[test]
fn pd_and_mpc_report_lives() {
    let dir = tempfile::tempdir().unwrap();
    fs::write(dir.path().join("s.toml"), scene("riser")).unwrap();
    let (code, out, stderr) = run(
        dir.path(),
        &[
            "fatigue",
            "s.toml",
            "--controller",
            "pd,mpc",
            "--horizon",
            "0.5",
        ],
    );
    assert_eq!(code, 0, "{stderr}");
    let v = json(&out);
    let keys: Vec<&String> = v["controllers"].as_object().unwrap().keys().collect();
    assert_eq!(keys, ["mpc", "none", "pd"]);
    let at = |name: &str| out.find(&format!("\"{name}\": {{")).unwrap();
    assert!(at("none") < at("pd") && at("pd") < at("mpc"));
    assert_eq!(v["controllers"]["pd"]["cells"][0]["gains"].as_array().unwrap().len(), 3);
    for name in ["pd", "mpc"] {
        let c = &v["controllers"][name];
        let life = num(&c["life_years"]);
        assert!(life.is_finite() && life > 0.0);
        let expected = life / num(&v["controllers"]["none"]["life_years"]);
        assert!(rel(num(&v["life_extension"][name]), expected) <= 1e-12);
    }
    assert_eq!(num(&v["settings"]["horizon"]), 0.5);
}

/// Refusals: one line on stderr, exit status 1 (2 for clap's conflicts).
#[test]
fn controller_refusals() {
    let dir = tempfile::tempdir().unwrap();
    fs::write(dir.path().join("ff.toml"), scene("fixed-fixed")).unwrap();
    let (code, _, stderr) = run(dir.path(), &["fatigue", "ff.toml", "--controller", "mpc"]);
    assert_eq!(code, 1, "{stderr}");
    assert!(
        stderr.contains("ff.toml") && stderr.contains("`mpc` cannot act") && stderr.contains("node 10"),
        "{stderr}"
    );
    assert_eq!(stderr.lines().count(), 1);

    fs::write(dir.path().join("s.toml"), scene("riser")).unwrap();
    let (code, _, stderr) = run(dir.path(), &["fatigue", "s.toml", "--controller", "none,lqr"]);
    assert_eq!(code, 1, "{stderr}");
    assert!(stderr.contains("--controller") && stderr.contains("`lqr`"), "{stderr}");

    let (code, _, stderr) = run(
        dir.path(),
        &["fatigue", "s.toml", "--controller", "pd", "--interval", "0.015"],
    );
    assert_eq!(code, 1, "{stderr}");
    assert!(stderr.contains("--interval") && stderr.contains("s.toml"), "{stderr}");

    fs::write(dir.path().join("m.csv"), "t,moment\n0,1\n1,2\n").unwrap();
    let (code, _, stderr) = run(
        dir.path(),
        &["fatigue", "s.toml", "--series", "m.csv", "--controller", "none"],
    );
    assert_eq!(code, 2, "{stderr}");
}
