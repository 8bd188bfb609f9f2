//! `chainbeam mpc`: the closed-loop CSV and JSON summary, the baselines, and bad settings
//! (exit status 1, one line naming the flag, outputs untouched).

use std::fs;
use std::path::Path;
use std::process::Output;

use assert_cmd::cargo::cargo_bin_cmd;

use crate::wave_riser4_toml;
use wave_riser4_toml::PLANAR as SCENE;

fn run(dir: &Path, args: &[&str]) -> Output {
    cargo_bin_cmd!("chainbeam")
        .current_dir(dir)
        .arg("mpc")
        .arg("scene.toml")
        .args(args)
        .output()
        .expect("run chainbeam")
}

fn setup() -> tempfile::TempDir {
    let dir = tempfile::tempdir().unwrap();
    fs::write(dir.path().join("scene.toml"), SCENE).unwrap();
    dir
}

#[test]
fn mpc_writes_the_closed_loop_csv_and_summary() {
    let dir = setup();
    let o = run(
        dir.path(),
        &[
            "--horizon",
            "0.5",
            "--bound",
            "1.0",
            "--baselines",
            "-o",
            "loop.csv",
            "--summary",
            "summary.json",
        ],
    );
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let csv = fs::read_to_string(dir.path().join("loop.csv")).unwrap();
    let mut lines = csv.lines();
    assert_eq!(
        lines.next().unwrap(),
        "t,moment,control,tip,moment_none,moment_constant,control_constant,moment_pd,control_pd"
    );
    let rows: Vec<Vec<f64>> = lines
        .map(|l| l.split(',').map(|x| x.parse().unwrap()).collect())
        .collect();
    assert_eq!(rows.len(), 101, "N + 1 rows");
    assert!(rows
        .iter()
        .all(|r| r[2].abs() <= 1.0 && r[6].abs() <= 1.0 && r[8].abs() <= 1.0));
    let v: serde_json::Value =
        serde_json::from_str(&fs::read_to_string(dir.path().join("summary.json")).unwrap())
            .unwrap();
    // c_sum of the summary is Σ M₀(t_k)² of the CSV's moment column (numbers round-trip).
    let c_sum: f64 = rows.iter().map(|r| r[1] * r[1]).sum();
    let reported = v["mpc"]["c_sum"].as_f64().unwrap();
    assert!(
        (reported - c_sum).abs() <= 1e-12 * c_sum,
        "{reported} vs {c_sum}"
    );
    assert_eq!(v["mpc"]["decisions"].as_u64(), Some(10));
    assert_eq!(v["baselines"].as_array().unwrap().len(), 3);
    let none: f64 = rows.iter().map(|r| r[4] * r[4]).sum();
    let none_reported = v["baselines"][0]["c_sum"].as_f64().unwrap();
    assert!((none_reported - none).abs() <= 1e-12 * none);
    let ratio = v["c_sum_ratio_to_pd"].as_f64().unwrap();
    let pd = v["baselines"][2]["c_sum"].as_f64().unwrap();
    assert!((ratio - reported / pd).abs() <= 1e-12 * ratio);
    // MPC's c_sum over the uncontrolled run's; below 1 here, so no warning on stderr.
    let to_none = v["c_sum_ratio_to_none"].as_f64().unwrap();
    assert!((to_none - reported / none_reported).abs() <= 1e-12 * to_none);
    assert!(to_none < 1.0, "MPC worse than no control: {to_none}");
    assert!(!String::from_utf8_lossy(&o.stderr).contains("warning"));
    for key in [
        "real_time_factor",
        "mean_replan_seconds",
        "worst_replan_seconds",
    ] {
        assert!(v["mpc"][key].as_f64().unwrap() > 0.0, "{key}");
    }
    assert!(v["real_time"].is_boolean());
}

#[test]
fn mpc_bad_settings_are_one_error_and_leave_outputs_alone() {
    let dir = setup();
    fs::write(dir.path().join("keep.csv"), "old\n").unwrap();
    for (args, needle) in [
        (vec!["--interval", "0.015"], "interval"),
        (vec!["--horizon", "0.05"], "horizon"),
        (vec!["--iterations", "0"], "iterations"),
        (vec!["--bound=-1"], "--bound"),
        (vec!["--effort=-1"], "effort"),
    ] {
        let mut a = args.clone();
        a.extend(["-o", "keep.csv"]);
        let o = run(dir.path(), &a);
        assert_eq!(o.status.code(), Some(1), "{args:?}");
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(err.lines().count(), 1, "{err}");
        assert!(err.contains(needle), "{args:?}: {err}");
        assert_eq!(
            fs::read_to_string(dir.path().join("keep.csv")).unwrap(),
            "old\n"
        );
    }
    let o = run(dir.path(), &["-o", "x.csv", "--summary", "x.csv"]);
    assert_eq!(o.status.code(), Some(1));
    let o = run(dir.path(), &["-o", "scene.toml"]);
    assert_eq!(o.status.code(), Some(1));
    assert_eq!(
        fs::read_to_string(dir.path().join("scene.toml")).unwrap(),
        SCENE
    );
}

/// `--solver riccati` and the default `condensed` both run and the summary names the solver.
/// With every plan solved to the tolerance (`--iterations 50`) both find each plan's optimum,
/// so the closed-loop costs agree to the plans' tolerance (each plan to a projected gradient of
/// 1e-8 of its initial one; the costs measured 2.8e-9 apart relative, asserted 1e-7; with the
/// default budget of one iteration they differ by 0.4 %: the two line searches differ, open
/// loop against Riccati feedback). An unknown `--solver` is refused naming the flag.
#[test]
fn mpc_solver_flag_selects_the_solver() {
    let dir = setup();
    let mut c_sum = Vec::new();
    for solver in ["condensed", "riccati"] {
        let out = format!("{solver}.json");
        let o = run(
            dir.path(),
            &[
                "--horizon",
                "0.5",
                "--iterations",
                "50",
                "--solver",
                solver,
                "-o",
                "-",
                "--summary",
                &out,
            ],
        );
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        let v: serde_json::Value =
            serde_json::from_str(&fs::read_to_string(dir.path().join(&out)).unwrap()).unwrap();
        assert_eq!(v["settings"]["solver"].as_str(), Some(solver));
        c_sum.push(v["mpc"]["c_sum"].as_f64().unwrap());
    }
    let rel = (c_sum[0] - c_sum[1]).abs() / c_sum[1];
    assert!(
        rel <= 1e-7,
        "condensed {} vs riccati {}",
        c_sum[0],
        c_sum[1]
    );
    let o = run(dir.path(), &["--solver", "newton"]);
    assert_eq!(o.status.code(), Some(2), "clap's usage error");
    assert!(String::from_utf8_lossy(&o.stderr).contains("--solver"));
}

/// The summary without the wall-clock measurements (re-plan times, real-time factors), which
/// differ between two runs of the same loop.
fn without_timings(v: &mut serde_json::Value) {
    match v {
        serde_json::Value::Object(map) => {
            map.retain(|k, _| !(k.ends_with("_seconds") || k.contains("real_time")));
            map.values_mut().for_each(without_timings);
        }
        serde_json::Value::Array(items) => items.iter_mut().for_each(without_timings),
        _ => {}
    }
}

/// `mpc SCENE --baselines` with `args`: (the CSV, the summary without its timings).
fn csv_and_summary(dir: &Path, scene: &str, args: &[&str]) -> (String, serde_json::Value) {
    let o = cargo_bin_cmd!("chainbeam")
        .current_dir(dir)
        .args([
            "mpc",
            scene,
            "--baselines",
            "-o",
            "out.csv",
            "--summary",
            "out.json",
        ])
        .args(args)
        .output()
        .expect("run chainbeam");
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let csv = fs::read_to_string(dir.join("out.csv")).unwrap();
    let mut v: serde_json::Value =
        serde_json::from_str(&fs::read_to_string(dir.join("out.json")).unwrap()).unwrap();
    without_timings(&mut v);
    (csv, v)
}

/// The scene's `[mpc]` table sets `mpc`'s flags (the precedence of `chainbeam fatigue`,
/// `MpcTable::resolve`): a scene with the table gives the CSV and the JSON summary (but its
/// wall-clock timings) of the same values on the command line, byte for byte; a flag overrides
/// its key; a value of the table that does not fit the run is refused naming `mpc.KEY`, the same
/// value as a flag naming the flag.
#[test]
fn the_mpc_table_sets_the_flags() {
    let dir = setup();
    let table = "\n[mpc]\ninterval = 0.2\nhorizon = 0.4\niterations = 2\nbound = 1.5\n\
                 effort = 0.02\n";
    fs::write(dir.path().join("table.toml"), format!("{SCENE}{table}")).unwrap();
    let flags = [
        "--interval",
        "0.2",
        "--horizon",
        "0.4",
        "--iterations",
        "2",
        "--bound",
        "1.5",
        "--effort",
        "0.02",
    ];
    let (csv, v) = csv_and_summary(dir.path(), "table.toml", &[]);
    let (csv_flags, v_flags) = csv_and_summary(dir.path(), "scene.toml", &flags);
    assert_eq!(csv, csv_flags);
    assert_eq!(v, v_flags);
    assert_eq!(v["settings"]["interval"].as_f64(), Some(0.2));
    assert_eq!(v["settings"]["iterations"].as_u64(), Some(2));
    assert_eq!(v["mpc"]["decisions"].as_u64(), Some(5), "1 s at 0.2 s");
    // The MPC force is within the table's bound, not the default 5 N.
    let max = v["mpc"]["max_abs_control"].as_f64().unwrap();
    assert!(max <= 1.5 && max > 0.0, "{max}");
    // A flag overrides its key; the other keys still come from the table.
    let (csv, v) = csv_and_summary(dir.path(), "table.toml", &["--horizon", "0.6"]);
    let mut over = flags;
    over[3] = "0.6";
    let (csv_flags, v_flags) = csv_and_summary(dir.path(), "scene.toml", &over);
    assert_eq!(csv, csv_flags);
    assert_eq!(v, v_flags);
    assert_eq!(v["settings"]["horizon"].as_f64(), Some(0.6));
    // An interval that is not a multiple of time.step = 0.01 s: the table's key, or the flag.
    let bad = "\n[mpc]\ninterval = 0.015\n";
    fs::write(dir.path().join("bad.toml"), format!("{SCENE}{bad}")).unwrap();
    for (scene, args, needle) in [
        ("bad.toml", vec![], "mpc.interval"),
        ("scene.toml", vec!["--interval", "0.015"], "--interval"),
    ] {
        let o = cargo_bin_cmd!("chainbeam")
            .current_dir(dir.path())
            .args(["mpc", scene, "-o", "x.csv"])
            .args(&args)
            .output()
            .unwrap();
        assert_eq!(o.status.code(), Some(1), "{scene} {args:?}");
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(err.contains(needle) && err.contains(scene), "{err}");
        assert_eq!(err.lines().count(), 1, "{err}");
    }
    // A value the table itself refuses, before anything runs (src/scene/mpc.rs).
    fs::write(
        dir.path().join("neg.toml"),
        format!("{SCENE}\n[mpc]\nbound = 1e13\n"),
    )
    .unwrap();
    let o = cargo_bin_cmd!("chainbeam")
        .current_dir(dir.path())
        .args(["mpc", "neg.toml"])
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(1));
    assert!(String::from_utf8_lossy(&o.stderr).contains("mpc.bound"));
}

/// `mpc.objective` sets what the plans minimise: `"power"` is Σ|M₀|^m + ρ·h·Σ u² with m the
/// first slope of the scene's `[fatigue]` S-N curve, so a scene with curve D (m = 3,
/// DNV-RP-C203 Table 2-2) and `mpc.objective = "power"` runs the closed loop of the same scene
/// with `[objective] kind = "power"`, `exponent = 3` (its CSV byte for byte); `"sum"` overrides
/// the model's `[objective]`; `"power"` without a `[fatigue]` table is refused naming
/// `mpc.objective`.
#[test]
fn the_mpc_objective_key_sets_what_the_plans_minimise() {
    let dir = setup();
    let fatigue = "\n[fatigue]\nouter_diameter = 0.02\nwall_thickness = 0.002\ncurve = \"D\"\n";
    let write = |name: &str, tail: &str| {
        fs::write(dir.path().join(name), format!("{SCENE}{fatigue}{tail}")).unwrap();
    };
    write(
        "proxy.toml",
        "\n[mpc]\nobjective = \"power\"\nhorizon = 0.5\n",
    );
    write(
        "cubic.toml",
        "\n[objective]\nkind = \"power\"\nexponent = 3.0\n",
    );
    write(
        "sum.toml",
        "\n[objective]\nkind = \"power\"\nexponent = 3.0\n\n[mpc]\nobjective = \"sum\"\n",
    );
    let (proxy, _) = csv_and_summary(dir.path(), "proxy.toml", &[]);
    let (cubic, _) = csv_and_summary(dir.path(), "cubic.toml", &["--horizon", "0.5"]);
    assert_eq!(proxy, cubic);
    let (sum, _) = csv_and_summary(dir.path(), "sum.toml", &[]);
    let (plain, _) = csv_and_summary(dir.path(), "scene.toml", &[]);
    assert_eq!(sum, plain);
    assert_ne!(sum, cubic, "the two objectives plan differently");
    fs::write(
        dir.path().join("nofatigue.toml"),
        format!("{SCENE}\n[mpc]\nobjective = \"power\"\n"),
    )
    .unwrap();
    let o = cargo_bin_cmd!("chainbeam")
        .current_dir(dir.path())
        .args(["mpc", "nofatigue.toml"])
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(1));
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        err.contains("mpc.objective") && err.contains("[fatigue]"),
        "{err}"
    );
}

/// A planar scene whose load series covers exactly the run (t ∈ [0, t_N]) runs under `mpc`:
/// the last plans look a horizon past t_N, where the plans see the series' last value held
/// (docs/cli.md "mpc"). The hold changes nothing the plant sees, so the closed loop equals the
/// same run with the series extended by hand with its last value over the last horizon (bit
/// for bit: the same model, the same plans).
#[test]
fn a_series_that_covers_exactly_the_run_runs() {
    let dir = setup();
    // The harmonic load of the scene as a series of 101 rows, t = 0 … 1 s.
    let rows: Vec<(f64, f64)> = (0..=100)
        .map(|k| {
            let t = k as f64 * 0.01;
            (t, 2.0 * (std::f64::consts::PI * t).sin())
        })
        .collect();
    let csv = |extra: bool| {
        let mut s = String::from("t,fx,fz\n");
        for (t, f) in &rows {
            s.push_str(&format!("{t:?},0.0,{f:?}\n"));
        }
        if extra {
            s.push_str(&format!("2.0,0.0,{:?}\n", rows[100].1));
        }
        s
    };
    fs::write(dir.path().join("exact.csv"), csv(false)).unwrap();
    fs::write(dir.path().join("longer.csv"), csv(true)).unwrap();
    let scene = |file: &str| {
        SCENE.replacen(
            "[[loads.point]]\nnode = 2\nramp = 0.5\n\n[[loads.point.harmonic]]\namplitude = 2.0\nperiod = 2.0\n",
            &format!("[[loads.point]]\nnode = 2\nseries = \"{file}\"\n"),
            1,
        )
    };
    assert!(scene("x").contains("series"));
    fs::write(dir.path().join("scene.toml"), scene("exact.csv")).unwrap();
    let args = ["--horizon", "0.5", "--bound", "1.0", "-o", "exact_loop.csv"];
    let o = run(dir.path(), &args);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    fs::write(dir.path().join("scene.toml"), scene("longer.csv")).unwrap();
    let args = [
        "--horizon",
        "0.5",
        "--bound",
        "1.0",
        "-o",
        "longer_loop.csv",
    ];
    let o = run(dir.path(), &args);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let exact = fs::read_to_string(dir.path().join("exact_loop.csv")).unwrap();
    let longer = fs::read_to_string(dir.path().join("longer_loop.csv")).unwrap();
    assert_eq!(exact.lines().count(), 102);
    assert_eq!(exact, longer);
}
