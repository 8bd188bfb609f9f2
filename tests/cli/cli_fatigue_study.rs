//! `chainbeam fatigue --controller` (docs/cli.md): the JSON contract, `none` against the plain
//! run, `constant` against `fatigue --series` of a `simulate` with its force, and refusals.

use std::fs;

use crate::fatigue_cli;

use fatigue_cli::{beam, json, run, FATIGUE_TABLE};

/// The thesis riser with drag 1 kg/m under a 2 N wave (period 2 s) at node 5 and a steady 1 N
/// load, 4 s of 0.01 s, control at node 10 (constant 0), a [fatigue] table of a small tube.
fn scene(support: &str) -> String {
    format!(
        r#"{beam}
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

{table}"#,
        beam = beam(support),
        table = FATIGUE_TABLE
    )
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
        &[
            "fatigue",
            "s.toml",
            "--controller",
            "constant,none",
            "--record",
            "4",
        ],
    );
    assert_eq!(code, 0, "{stderr}");
    let v = json(&out);
    // (serde_json's maps here sort their keys; the output's order is checked on its text.)
    let top: Vec<&String> = v.as_object().unwrap().keys().collect();
    assert_eq!(top, ["controllers", "life_extension", "settings"]);
    let controllers = v["controllers"].as_object().unwrap();
    assert_eq!(controllers.keys().collect::<Vec<_>>(), ["constant", "none"]);
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
    assert_eq!(
        num(&none["damage_per_year"]),
        num(&plain["damage_per_year"])
    );
    assert_eq!(num(&none["life_years"]), num(&plain["life_years"]));
    assert_eq!(num(&none["cells"][0]["damage"]), num(&plain["damage"]));

    let constant = &v["controllers"]["constant"];
    let force = num(&constant["cells"][0]["force"]);
    assert!(
        force.abs() > 0.1,
        "the force acts against the 1 N load: {force}"
    );
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
            "--record",
            "4",
        ],
    );
    assert_eq!(code, 0, "{stderr}");
    let v = json(&out);
    let keys: Vec<&String> = v["controllers"].as_object().unwrap().keys().collect();
    assert_eq!(keys, ["mpc", "none", "pd"]);
    let at = |name: &str| out.find(&format!("\"{name}\": {{")).unwrap();
    assert!(at("none") < at("pd") && at("pd") < at("mpc"));
    assert_eq!(
        v["controllers"]["pd"]["cells"][0]["gains"]
            .as_array()
            .unwrap()
            .len(),
        3
    );
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
        stderr.contains("ff.toml")
            && stderr.contains("`mpc` cannot act")
            && stderr.contains("node 10"),
        "{stderr}"
    );
    assert_eq!(stderr.lines().count(), 1);

    fs::write(dir.path().join("s.toml"), scene("riser")).unwrap();
    let (code, _, stderr) = run(
        dir.path(),
        &["fatigue", "s.toml", "--controller", "none,lqr"],
    );
    assert_eq!(code, 1, "{stderr}");
    assert!(
        stderr.contains("--controller") && stderr.contains("`lqr`"),
        "{stderr}"
    );

    let (code, _, stderr) = run(
        dir.path(),
        &[
            "fatigue",
            "s.toml",
            "--controller",
            "pd",
            "--interval",
            "0.015",
        ],
    );
    assert_eq!(code, 1, "{stderr}");
    assert!(
        stderr.contains("--interval") && stderr.contains("s.toml"),
        "{stderr}"
    );

    fs::write(dir.path().join("m.csv"), "t,moment\n0,1\n1,2\n").unwrap();
    let (code, _, stderr) = run(
        dir.path(),
        &[
            "fatigue",
            "s.toml",
            "--series",
            "m.csv",
            "--controller",
            "none",
        ],
    );
    assert_eq!(code, 2, "{stderr}");
}

/// A 60 m steel riser (6 pendulums, 533.4 × 22.2 mm) under 1 MN top tension in a JONSWAP sea
/// (seed 7) along z and a 0.3 m/s current, 40 s of 0.05 s, curve D in seawater with CP. The
/// drag on the momenta D = ½ ρ_w C_d D_o l / m² ≈ 1e-4 (C_d = 1, l = 10 m, m = μ l ≈ 5.1 t).
fn wave_scene(hs: f64, tp: f64) -> String {
    format!(
        "[beam]\npendulums = 6\nsupport = \"riser\"\n\n\
         [pipe]\nlength = 60.0\nouter_diameter = 0.5334\nwall_thickness = 0.0222\n\n\
         [water]\ndepth = 60.0\n\n\
         [loads]\ntension = 1e6\ndrag = 1e-4\n\n\
         [loads.current]\nprofile = \"uniform\"\nspeed = 0.3\n\n\
         [loads.waves]\nspectrum = \"jonswap\"\nhs = {hs:?}\ntp = {tp:?}\nseed = 7\n\n\
         [time]\nstep = 0.05\nsteps = 800\n\n\
         [fatigue]\nouter_diameter = 0.5334\nwall_thickness = 0.0222\n"
    )
}

/// `--scatter`: one cell of probability 1 at the scene's own sea state reproduces the plain
/// run's `damage_per_year` (the seed is the scene's in every cell); over three cells the total
/// is the sum of the cells, and each cell's contribution is p_s times the plain run of a scene
/// written with that cell's H_s and T_p.
#[test]
fn scatter_one_cell_and_additivity() {
    let dir = tempfile::tempdir().unwrap();
    fs::write(dir.path().join("w.toml"), wave_scene(3.0, 9.0)).unwrap();
    let plain = |hs: f64, tp: f64| {
        fs::write(dir.path().join("cell.toml"), wave_scene(hs, tp)).unwrap();
        let (code, out, stderr) = run(dir.path(), &["fatigue", "cell.toml"]);
        assert_eq!(code, 0, "{stderr}");
        num(&json(&out)["damage_per_year"])
    };

    fs::write(
        dir.path().join("one.csv"),
        "hs,tp,probability\n3.0,9.0,1.0\n",
    )
    .unwrap();
    let (code, out, stderr) = run(
        dir.path(),
        &[
            "fatigue",
            "w.toml",
            "--scatter",
            "one.csv",
            "--record",
            "40",
        ],
    );
    assert_eq!(code, 0, "{stderr}");
    let v = json(&out);
    let keys: Vec<&String> = v.as_object().unwrap().keys().collect();
    assert_eq!(keys, ["cells", "damage_per_year", "life_years"]);
    let single = plain(3.0, 9.0);
    assert!(single > 0.0);
    assert_eq!(num(&v["damage_per_year"]), single);
    assert_eq!(num(&v["life_years"]), 1.0 / single);

    let diagram = [(1.5, 7.0, 0.5), (3.0, 9.0, 0.3), (5.0, 11.0, 0.2)];
    let mut text = String::from("# a three-cell diagram\ntp,hs,probability\n");
    for (hs, tp, p) in diagram {
        text.push_str(&format!("{tp},{hs},{p}\n"));
    }
    fs::write(dir.path().join("three.csv"), text).unwrap();
    let (code, out, stderr) = run(
        dir.path(),
        &[
            "fatigue",
            "w.toml",
            "--scatter",
            "three.csv",
            "--record",
            "40",
        ],
    );
    assert_eq!(code, 0, "{stderr}");
    let v = json(&out);
    let cells = v["cells"].as_array().unwrap();
    assert_eq!(cells.len(), 3);
    let mut sum = 0.0;
    for (cell, (hs, tp, p)) in cells.iter().zip(diagram) {
        assert_eq!((num(&cell["hs"]), num(&cell["tp"])), (hs, tp));
        assert_eq!(num(&cell["probability"]), p);
        let contribution = num(&cell["damage_per_year"]);
        assert!(rel(contribution, p * plain(hs, tp)) <= 1e-14, "{hs} {tp}");
        sum += contribution;
    }
    assert!(rel(num(&v["damage_per_year"]), sum) <= 1e-14);
    // Higher seas do more damage per hour (a check that the cells differ at all).
    let per_hour: Vec<f64> = cells
        .iter()
        .map(|c| num(&c["damage_per_year"]) / num(&c["probability"]))
        .collect();
    assert!(
        per_hour[0] < per_hour[1] && per_hour[1] < per_hour[2],
        "{per_hour:?}"
    );

    // With controllers every controller runs every cell; `none` is the plain scatter run.
    let (code, out, stderr) = run(
        dir.path(),
        &[
            "fatigue",
            "w.toml",
            "--scatter",
            "three.csv",
            "--controller",
            "none",
            "--record",
            "40",
        ],
    );
    assert_eq!(code, 0, "{stderr}");
    let c = json(&out);
    assert_eq!(c["controllers"]["none"]["cells"], v["cells"]);
    assert_eq!(
        c["controllers"]["none"]["damage_per_year"],
        v["damage_per_year"]
    );
}

/// Bad scatter files and scenes: one line naming the file, the line and the column.
#[test]
fn scatter_refusals() {
    let dir = tempfile::tempdir().unwrap();
    fs::write(dir.path().join("w.toml"), wave_scene(3.0, 9.0)).unwrap();
    for (csv, what) in [
        ("hs,tp\n1,2\n", "line 1: no column `probability`"),
        (
            "hs,tp,probability,period\n1,2,0.5,3\n",
            "line 1, column 4: unknown column `period`",
        ),
        (
            "hs,tp,probability\n1,2,0.5\n1,x,0.5\n",
            "line 3, column 2 (`tp`): `x`",
        ),
        ("hs,tp,probability\n-1,2,0.5\n", "line 2, column 1 (`hs`)"),
        (
            "hs,tp,probability\n1,2,1.5\n",
            "line 2, column 3 (`probability`)",
        ),
        ("hs,tp,probability\n1,8,0.6\n2,9,0.6\n", "add up to 1.2"),
        // No time at all: refused, not an infinite life (it exited 0 with life_years null).
        ("hs,tp,probability\n1,8,0\n2,9,0.0\n", "add up to 0"),
        // A repeated column (the first used to win, the rest ignored).
        (
            "hs,tp,probability,tp\n1,8,0.5,9\n",
            "columns 2 and 4: the column `tp` is named twice",
        ),
        // One bad row's sea: the default components of T_p = 1 ms (used to abort).
        (
            "hs,tp,probability\n1,8,0.5\n1,0.001,0.5\n",
            "loads.waves.tp",
        ),
        ("hs,tp,probability\n", "no cells"),
        (
            "hs,tp,probability,direction\n1,8,0.5,inf\n",
            "column 4 (`direction`)",
        ),
    ] {
        fs::write(dir.path().join("d.csv"), csv).unwrap();
        let (code, _, stderr) = run(dir.path(), &["fatigue", "w.toml", "--scatter", "d.csv"]);
        assert_eq!(code, 1, "{csv}: {stderr}");
        assert!(
            stderr.contains("d.csv") && stderr.contains(what),
            "{what}: {stderr}"
        );
        assert_eq!(stderr.lines().count(), 1, "{stderr}");
    }
    // A scene without [loads.waves] has no sea state for a cell to set.
    fs::write(dir.path().join("s.toml"), scene("riser")).unwrap();
    fs::write(dir.path().join("d.csv"), "hs,tp,probability\n1,8,0.5\n").unwrap();
    let (code, _, stderr) = run(dir.path(), &["fatigue", "s.toml", "--scatter", "d.csv"]);
    assert_eq!(code, 1, "{stderr}");
    assert!(
        stderr.contains("[loads.waves]") && stderr.contains("cell 0"),
        "{stderr}"
    );
}

/// The scene's `[mpc]` table sets the controllers' settings, a flag overrides its key, an
/// invalid key is refused naming `mpc.KEY`; `--spin-up` leaves the record's start out of the
/// count (its duration in every cell) and is refused when it is not shorter than the record.
#[test]
fn the_mpc_table_flags_and_spin_up() {
    let dir = tempfile::tempdir().unwrap();
    let table = "\n[mpc]\nhorizon = 0.5\nbound = 3.0\ninterval = 0.1\nobjective = \"sum\"\n";
    fs::write(dir.path().join("s.toml"), scene("riser") + table).unwrap();
    let args = ["fatigue", "s.toml", "--controller", "mpc"];
    // The scene's 4 s counted (the default would be 3 hours).
    let (code, out, stderr) = run(dir.path(), &[&args[..], &["--record", "4"]].concat());
    assert_eq!(code, 0, "{stderr}");
    let v = json(&out);
    assert_eq!(num(&v["settings"]["horizon"]), 0.5);
    assert_eq!(num(&v["settings"]["bound"]), 3.0);
    assert_eq!(v["settings"]["mpc_objective"].as_str(), Some("sum"));
    assert_eq!(num(&v["settings"]["spin_up"]), 0.0);
    let flags = [
        &args[..],
        &["--horizon", "0.3", "--spin-up", "1.5", "--record", "2.5"],
    ]
    .concat();
    let (code, out, stderr) = run(dir.path(), &flags);
    assert_eq!(code, 0, "{stderr}");
    let w = json(&out);
    assert_eq!(num(&w["settings"]["horizon"]), 0.3);
    assert_eq!(num(&w["settings"]["bound"]), 3.0);
    for name in ["none", "mpc"] {
        // 4 s recorded, the first 1.5 s not counted.
        let cell = &w["controllers"][name]["cells"][0];
        assert!((num(&cell["duration_s"]) - 2.5).abs() < 1e-12, "{cell}");
    }
    // The same flag on the plain run: the same record, the same count.
    let (code, plain, stderr) = run(dir.path(), &["fatigue", "s.toml", "--spin-up", "1.5"]);
    assert_eq!(code, 0, "{stderr}");
    let plain = json(&plain);
    assert_eq!(
        num(&plain["damage"]),
        num(&w["controllers"]["none"]["cells"][0]["damage"])
    );
    let (code, _, stderr) = run(dir.path(), &["fatigue", "s.toml", "--spin-up", "4"]);
    assert_eq!(code, 1);
    assert!(stderr.contains("--spin-up"), "{stderr}");
    fs::write(
        dir.path().join("bad.toml"),
        scene("riser") + "\n[mpc]\nhorizon = -1.0\n",
    )
    .unwrap();
    let (code, _, stderr) = run(dir.path(), &["fatigue", "bad.toml", "--controller", "mpc"]);
    assert_eq!(code, 1);
    assert!(stderr.contains("mpc.horizon"), "{stderr}");
}

/// A closed loop's cells carry `damage_ratio_to_none`, its damage over `none`'s in the same cell
/// (`none` has none); a warning line on stderr names the controller and the cell exactly when
/// the ratio is above 1 (the controller did worse than no control there), and the run exits 0.
#[test]
fn closed_loop_cells_carry_the_ratio_to_none() {
    let dir = tempfile::tempdir().unwrap();
    fs::write(dir.path().join("s.toml"), scene("riser")).unwrap();
    let (code, out, stderr) = run(
        dir.path(),
        &[
            "fatigue",
            "s.toml",
            "--controller",
            "constant,pd",
            "--record",
            "4",
        ],
    );
    assert_eq!(code, 0, "{stderr}");
    let v = json(&out);
    let none = num(&v["controllers"]["none"]["cells"][0]["damage"]);
    assert!(v["controllers"]["none"]["cells"][0]
        .get("damage_ratio_to_none")
        .is_none());
    for name in ["constant", "pd"] {
        let cell = &v["controllers"][name]["cells"][0];
        let ratio = num(&cell["damage_ratio_to_none"]);
        assert_eq!(ratio, num(&cell["damage"]) / none, "{name}");
        let warned = stderr
            .lines()
            .any(|l| l.contains("warning") && l.contains(&format!("`{name}`, cell 0")));
        assert_eq!(
            warned,
            ratio > 1.0,
            "{name}: ratio {ratio}, stderr {stderr}"
        );
    }
}
