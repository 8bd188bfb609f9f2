//! The `chainbeam` command line (docs/scene-format.md) and the shipped scene files.
//!
//! Runs the binary on good and bad scene files and checks exit codes, the one-line error messages
//! (file, key, reason), the CSV header and row count, the JSON keys and the atomic `--output`.
//!
//! The files in `examples/scenes/` are generated from [`chainbeam::catalogue`]; after changing the
//! catalogue, regenerate them with
//! `CHAINBEAM_WRITE_SCENES=1 cargo test --release --test cli shipped_scenes`.

use std::fs;
use std::path::{Path, PathBuf};
use std::process::Output;

use assert_cmd::cargo::cargo_bin_cmd;
use chainbeam::{catalogue, simulate, ControlProblem, Scene};

// ---------------------------------------------------------------------------------------------
// Helpers
// ---------------------------------------------------------------------------------------------

/// docs/scene-format.md's example scene with N = `steps` (riser, load at node 5, constant control −1 at the tip,
/// objective "sum").
fn riser_scene(steps: usize) -> String {
    format!(
        r#"[beam]
pendulums = 10
length = 1.0
mass = 1.0
stiffness = 1000.0
support = "riser"
base_stiffness = 2000.0
tip_stiffness = 2000.0

[loads]
gravity = 0.0
drag = 0.0
[[loads.point]]
node = 5
force = 2.0

[time]
step = 0.01
steps = {steps}

[control]
node = 10
kind = "constant"
values = [-1.0]

[objective]
kind = "sum"
"#
    )
}

/// A small per-step scene: n = 3 cantilever, N = 4, five control values.
const PER_STEP: &str = r#"[beam]
pendulums = 3
length = [1.0, 0.5, 0.5]
mass = 1
stiffness = 500
support = "cantilever"

[[loads.point]]
node = 3
force = 1.5

[time]
step = 0.01
steps = 4

[control]
kind = "per-step"
values = [0.1, -0.2, 0.3, -0.4, 0.5]

[objective]
kind = "final"
"#;

struct Dir(tempfile::TempDir);

impl Dir {
    fn new() -> Self {
        Dir(tempfile::tempdir().expect("temporary directory"))
    }
    fn path(&self) -> &Path {
        self.0.path()
    }
    fn write(&self, name: &str, text: &str) -> PathBuf {
        let p = self.0.path().join(name);
        fs::write(&p, text).expect("write scene");
        p
    }
    /// File names in the directory, sorted.
    fn files(&self) -> Vec<String> {
        let mut v: Vec<String> = fs::read_dir(self.path())
            .expect("read dir")
            .map(|e| e.expect("entry").file_name().to_string_lossy().into_owned())
            .collect();
        v.sort();
        v
    }
}

fn run(args: &[&std::ffi::OsStr]) -> Output {
    cargo_bin_cmd!("chainbeam")
        .args(args)
        .output()
        .expect("run chainbeam")
}

fn run_on(sub: &str, scene: &Path, extra: &[&str]) -> Output {
    let mut args: Vec<&std::ffi::OsStr> = vec![sub.as_ref(), scene.as_os_str()];
    args.extend(extra.iter().map(|s| std::ffi::OsStr::new(*s)));
    run(&args)
}

fn stdout(o: &Output) -> String {
    String::from_utf8(o.stdout.clone()).expect("utf-8 stdout")
}

fn stderr(o: &Output) -> String {
    String::from_utf8(o.stderr.clone()).expect("utf-8 stderr")
}

fn assert_success(o: &Output) {
    assert!(
        o.status.success(),
        "exit {:?}, stderr: {}",
        o.status.code(),
        stderr(o)
    );
}

/// Exit status 1, nothing on stdout, exactly one line on stderr starting with `error: `, no panic,
/// containing every one of `needles`.
fn assert_one_error(o: &Output, needles: &[&str]) -> String {
    let err = stderr(o);
    assert_eq!(o.status.code(), Some(1), "stderr: {err}");
    assert!(o.stdout.is_empty(), "stdout not empty: {}", stdout(o));
    assert_eq!(err.lines().count(), 1, "not one line: {err:?}");
    assert!(err.starts_with("error: "), "{err}");
    assert!(
        !err.contains("panicked") && !err.contains("internal error"),
        "{err}"
    );
    for n in needles {
        assert!(err.contains(n), "message {err:?} lacks {n:?}");
    }
    err
}

fn header(n: usize) -> String {
    let mut h = String::from("t,energy,moment");
    for i in 1..=n {
        h.push_str(&format!(",x{i},y{i},z{i}"));
    }
    h.push_str(",control");
    h
}

/// Parses a CSV body (after the header) into rows of finite numbers.
fn parse_rows(csv: &str) -> Vec<Vec<f64>> {
    csv.lines()
        .skip(1)
        .map(|line| {
            line.split(',')
                .map(|f| {
                    let x: f64 = f.parse().unwrap_or_else(|_| panic!("not a number: {f:?}"));
                    assert!(x.is_finite(), "non-finite {f}");
                    x
                })
                .collect()
        })
        .collect()
}

fn json(o: &Output) -> serde_json::Value {
    serde_json::from_slice(&o.stdout).expect("valid JSON on stdout")
}

fn numbers(v: &serde_json::Value, key: &str) -> Vec<f64> {
    v[key]
        .as_array()
        .unwrap_or_else(|| panic!("`{key}` is not an array: {v}"))
        .iter()
        .map(|x| x.as_f64().expect("number"))
        .collect()
}

// ---------------------------------------------------------------------------------------------
// simulate
// ---------------------------------------------------------------------------------------------

#[test]
fn simulate_csv_header_and_rows_follow_spec() {
    let dir = Dir::new();
    let path = dir.write("riser.toml", &riser_scene(10));
    let o = run_on("simulate", &path, &[]);
    assert_success(&o);
    let out = stdout(&o);
    assert_eq!(out.lines().next(), Some(header(10).as_str()));
    assert_eq!(
        out.lines().next(),
        Some(
            "t,energy,moment,x1,y1,z1,x2,y2,z2,x3,y3,z3,x4,y4,z4,x5,y5,z5,x6,y6,z6,x7,y7,z7,\
             x8,y8,z8,x9,y9,z9,x10,y10,z10,control"
        )
    );
    let rows = parse_rows(&out);
    assert_eq!(rows.len(), 11, "one row per t_k, k = 0..N");
    // The library's trajectory, value for value (the CSV numbers round-trip exactly).
    let scene = Scene::from_file(&path).unwrap();
    let traj = simulate(&scene).unwrap();
    for (k, row) in rows.iter().enumerate() {
        assert_eq!(row.len(), 3 + 3 * 10 + 1);
        assert_eq!(row[0].to_bits(), traj.time(k).to_bits());
        assert_eq!(row[1].to_bits(), traj.energy()[k].to_bits());
        assert_eq!(row[2].to_bits(), traj.moment()[k].to_bits());
        for (i, r) in traj.positions(k).iter().enumerate() {
            for d in 0..3 {
                assert_eq!(row[3 + 3 * i + d].to_bits(), r[d].to_bits());
            }
        }
        // The last column is the control force applied at t_k: the scene's constant −1 N.
        assert_eq!(row[3 + 3 * 10], -1.0);
    }
    // Straight beam along +y at t = 0; the load at node 5 (F > 0) pushes it toward −z.
    assert_eq!(&rows[0][3..6], &[0.0, 1.0, 0.0]);
    assert!(rows[10][3 + 3 * 4 + 2] < 0.0);
}

#[test]
fn simulate_output_is_written_atomically() {
    let dir = Dir::new();
    let path = dir.write("riser.toml", &riser_scene(7));
    let out = dir.path().join("traj.csv");
    let o = run_on("simulate", &path, &["--output", out.to_str().unwrap()]);
    assert_success(&o);
    assert!(o.stdout.is_empty());
    let csv = fs::read_to_string(&out).unwrap();
    assert_eq!(csv.lines().next(), Some(header(10).as_str()));
    assert_eq!(parse_rows(&csv).len(), 8);
    // No temporary file is left beside it.
    assert_eq!(dir.files(), ["riser.toml", "traj.csv"]);

    // An existing output is replaced whole...
    fs::write(&out, "old contents").unwrap();
    let o = run_on("simulate", &path, &["-o", out.to_str().unwrap()]);
    assert_success(&o);
    assert_eq!(fs::read_to_string(&out).unwrap(), csv);

    // ...and a failing run leaves it untouched, with no temporary file.
    let bad = dir.write(
        "bad.toml",
        &riser_scene(7).replace("mass = 1.0", "mass = -1.0"),
    );
    let o = run_on("simulate", &bad, &["--output", out.to_str().unwrap()]);
    assert_one_error(&o, &["bad.toml", "beam.mass", "-1"]);
    assert_eq!(fs::read_to_string(&out).unwrap(), csv);
    assert_eq!(dir.files(), ["bad.toml", "riser.toml", "traj.csv"]);
}

#[test]
fn unwritable_output_is_one_error() {
    let dir = Dir::new();
    let path = dir.write("riser.toml", &riser_scene(3));
    let target = dir.path().join("no_such_dir").join("out.csv");
    let o = run_on("simulate", &path, &["--output", target.to_str().unwrap()]);
    assert_one_error(&o, &["out.csv", "cannot write"]);
    let o = run_on(
        "gradient",
        &path,
        &["--output", dir.path().to_str().unwrap()],
    );
    assert_one_error(&o, &["directory"]);
}

#[test]
fn failed_simulation_names_step_and_residual() {
    // docs/conventions.md: RATTLE's Newton solve fails at large steps; a stiff, heavily loaded beam at h = 0.05.
    let dir = Dir::new();
    let text = riser_scene(50)
        .replace("step = 0.01", "step = 0.05")
        .replace("force = 2.0", "force = 2000.0");
    let path = dir.write("stiff.toml", &text);
    let out = dir.path().join("out.csv");
    let o = run_on("simulate", &path, &["--output", out.to_str().unwrap()]);
    assert_one_error(&o, &["stiff.toml", "step", "residual"]);
    assert!(!out.exists(), "nothing is written on failure");
    assert_eq!(dir.files(), ["stiff.toml"]);
    let o = run_on("gradient", &path, &[]);
    assert_one_error(&o, &["stiff.toml", "step", "residual"]);
}

// ---------------------------------------------------------------------------------------------
// gradient
// ---------------------------------------------------------------------------------------------

#[test]
fn gradient_json_has_spec_keys_and_library_values() {
    let dir = Dir::new();
    let path = dir.write("riser.toml", &riser_scene(10));
    let o = run_on("gradient", &path, &[]);
    assert_success(&o);
    let v = json(&o);
    for key in ["objective", "gradient", "controls"] {
        assert!(v.get(key).is_some(), "missing `{key}` in {v}");
    }
    let scene = Scene::from_file(&path).unwrap();
    let problem = ControlProblem::builder(&scene).build_in::<2>().unwrap();
    let (c, g) = problem.value_and_gradient(&[-1.0]).unwrap();
    assert_eq!(v["objective"].as_f64().unwrap().to_bits(), c.to_bits());
    assert_eq!(numbers(&v, "gradient"), g);
    assert_eq!(numbers(&v, "controls"), [-1.0]);
    assert_eq!(v["objective_kind"], "sum");
    assert_eq!(v["control_kind"], "constant");
}

#[test]
fn gradient_per_step_has_n_plus_one_entries() {
    let dir = Dir::new();
    let path = dir.write("per_step.toml", PER_STEP);
    let out = dir.path().join("g.json");
    let o = run_on("gradient", &path, &["--output", out.to_str().unwrap()]);
    assert_success(&o);
    assert!(o.stdout.is_empty());
    let v: serde_json::Value = serde_json::from_str(&fs::read_to_string(&out).unwrap()).unwrap();
    let g = numbers(&v, "gradient");
    assert_eq!(g.len(), 5);
    assert_eq!(numbers(&v, "controls"), [0.1, -0.2, 0.3, -0.4, 0.5]);
    // u_N only touches p_N, never a configuration (docs/conventions.md): its gradient entry is 0.
    assert!(g[4].abs() < 1e-12 * g[0].abs().max(1e-300), "{g:?}");
    assert!(v["objective"].as_f64().unwrap() > 0.0);
    assert_eq!(dir.files(), ["g.json", "per_step.toml"]);
}

#[test]
fn gradient_without_control_uses_a_constant_tip_force() {
    let dir = Dir::new();
    let text = riser_scene(5);
    let text = &text[..text.find("[control]").unwrap()];
    let path = dir.write("plain.toml", text);
    let o = run_on("gradient", &path, &[]);
    assert_success(&o);
    let v = json(&o);
    assert_eq!(numbers(&v, "controls"), [0.0]);
    assert_eq!(numbers(&v, "gradient").len(), 1);
    assert_eq!(v["objective_kind"], "final");
}

// ---------------------------------------------------------------------------------------------
// optimize
// ---------------------------------------------------------------------------------------------

fn assert_optimize_keys(v: &serde_json::Value) {
    for key in [
        "objective",
        "controls",
        "gradient_norm",
        "iterations",
        "seconds",
    ] {
        assert!(v.get(key).is_some(), "missing `{key}` in {v}");
    }
    assert!(v["iterations"].as_u64().is_some());
    assert!(v["seconds"].as_f64().unwrap() >= 0.0);
}

#[test]
fn optimize_reproduces_table_3_1() {
    let scenes = scenes_dir();
    // docs/conventions.md: Table 3.1, system 5: the root of M₀(T; u) = 0 is u ≈ −33.40696 N (thesis −33.4070).
    let o = run_on("optimize", &scenes.join("riser_5.toml"), &[]);
    assert_success(&o);
    let v = json(&o);
    assert_optimize_keys(&v);
    let u = numbers(&v, "controls");
    assert_eq!(u.len(), 1);
    assert!((u[0] + 33.40696).abs() < 1e-4, "{u:?}");
    assert!(v["objective"].as_f64().unwrap() < 1e-16);
    // System 10: the load is at the tip, so u = −F = −2 N cancels it exactly (sign convention).
    let dir = Dir::new();
    let out = dir.path().join("opt.json");
    let o = run_on(
        "optimize",
        &scenes.join("riser_10.toml"),
        &[
            "--method",
            "trust-region",
            "--output",
            out.to_str().unwrap(),
        ],
    );
    assert_success(&o);
    assert!(o.stdout.is_empty());
    let v: serde_json::Value = serde_json::from_str(&fs::read_to_string(&out).unwrap()).unwrap();
    assert_optimize_keys(&v);
    assert_eq!(v["method"], "trust-region");
    assert!((numbers(&v, "controls")[0] + 2.0).abs() < 1e-6, "{v}");
    assert_eq!(dir.files(), ["opt.json"]);
}

#[test]
fn optimize_respects_the_force_bound() {
    let scenes = scenes_dir();
    let o = run_on("optimize", &scenes.join("riser_5.toml"), &["--bound", "10"]);
    assert_success(&o);
    let v = json(&o);
    assert_optimize_keys(&v);
    let u = numbers(&v, "controls")[0];
    assert!((-10.0..=-9.99).contains(&u), "{u}");
    assert_eq!(numbers(&v, "active_bounds"), [0.0]);
    let o = run_on(
        "optimize",
        &scenes.join("long_horizon.toml"),
        &["--bound", "2", "--max-iters", "3"],
    );
    // Three iterations do not converge on 1001 parameters: exit status 3, the JSON still written.
    assert_eq!(o.status.code(), Some(3), "{}", stderr(&o));
    assert!(stderr(&o).contains("did not converge"), "{}", stderr(&o));
    let v = json(&o);
    assert_eq!(v["converged"], false);
    let u = numbers(&v, "controls");
    assert_eq!(u.len(), 1001);
    assert!(u.iter().all(|x| x.abs() <= 2.0));
    assert!(v["objective"].as_f64().unwrap() <= v["initial_objective"].as_f64().unwrap());
}

#[test]
fn optimize_rejects_bad_options() {
    let dir = Dir::new();
    let path = dir.write("riser.toml", &riser_scene(10));
    let o = run_on("optimize", &path, &["--bound", "-1"]);
    assert_one_error(&o, &["--bound", "positive", "-1"]);
    let o = run_on("optimize", &path, &["--gtol", "nan"]);
    assert_one_error(&o, &["--gtol", "NaN"]);
    let o = run_on("optimize", &path, &["--max-iters", "0"]);
    assert_one_error(&o, &["--max-iters"]);
    // The scene's start u = −1 N lies outside a bound of 0.5 N.
    let o = run_on("optimize", &path, &["--bound", "0.5"]);
    assert_one_error(&o, &["riser.toml", "control.values[0]", "--bound"]);
    let o = run_on("optimize", &path, &["--starts", "0"]);
    assert_eq!(o.status.code(), Some(2));
}

#[test]
fn optimize_with_starts_is_never_worse_and_deterministic() {
    let dir = Dir::new();
    // Table 3.2, system 5 (c_sum, constant u): a flat valley, one minimum.
    let text = fs::read_to_string(scenes_dir().join("riser_5.toml"))
        .unwrap()
        .replace("kind = \"final\"", "kind = \"sum\"");
    let path = dir.write("riser_5_sum.toml", &text);
    let single = json(&run_on("optimize", &path, &[]));
    let multi = |threads: &str| {
        let o = run_on(
            "optimize",
            &path,
            &["--starts", "6", "--seed", "7", "--threads", threads],
        );
        assert_success(&o);
        json(&o)
    };
    let (a, b) = (multi("1"), multi("3"));
    assert_optimize_keys(&a);
    assert_eq!(a["starts"], 6);
    assert_eq!(a["seed"], 7);
    assert!(
        a["objective"].as_f64().unwrap() <= single["objective"].as_f64().unwrap(),
        "{a} vs {single}"
    );
    // Bit-for-bit the same result on 1 and 3 threads.
    assert_eq!(a["objective"], b["objective"]);
    assert_eq!(a["controls"], b["controls"]);
}

#[test]
fn explore_maps_every_start_and_the_minima() {
    let dir = Dir::new();
    let out = dir.path().join("map.json");
    // Table 3.1, system 5: c = M₀(T)² is convex in u with one root (docs/conventions.md).
    let o = run_on(
        "explore",
        &scenes_dir().join("riser_5.toml"),
        &[
            "--starts",
            "5",
            "--seed",
            "3",
            "--output",
            out.to_str().unwrap(),
        ],
    );
    assert_success(&o);
    assert!(o.stdout.is_empty());
    let v: serde_json::Value = serde_json::from_str(&fs::read_to_string(&out).unwrap()).unwrap();
    let results = v["results"].as_array().expect("results");
    assert_eq!(results.len(), 5);
    for (i, r) in results.iter().enumerate() {
        assert_eq!(r["start"], i);
        for key in [
            "start_point",
            "objective",
            "controls",
            "gradient_norm",
            "iterations",
        ] {
            assert!(r.get(key).is_some(), "results[{i}] lacks `{key}`: {r}");
        }
        let p = numbers(r, "start_point")[0];
        assert!((-600.0..=600.0).contains(&p));
    }
    let minima = v["minima"].as_array().expect("minima");
    assert_eq!(minima.len(), 1, "{v}");
    assert!((numbers(&minima[0], "controls")[0] + 33.40696).abs() < 1e-4);
    assert_eq!(minima[0]["count"], 5);
    assert_eq!(v["certificate"]["positive_definite"], true);
    assert_eq!(v["design"]["kind"], "latin");

    // The same seed gives the same map; the box and the design are honoured.
    let again = run_on(
        "explore",
        &scenes_dir().join("riser_5.toml"),
        &["--starts", "5", "--seed", "3", "--threads", "2"],
    );
    assert_eq!(json(&again)["results"], v["results"]);
    let o = run_on(
        "explore",
        &scenes_dir().join("riser_5.toml"),
        &["--starts", "3", "--design", "perturb", "--radius", "0.5"],
    );
    assert_success(&o);
    for r in json(&o)["results"].as_array().unwrap() {
        assert!(numbers(r, "start_point")[0].abs() <= 0.5);
    }
    let o = run_on(
        "explore",
        &scenes_dir().join("riser_5.toml"),
        &["--lo", "5", "--hi", "1"],
    );
    assert_one_error(&o, &["--lo", "--hi"]);
}

// ---------------------------------------------------------------------------------------------
// Bad input
// ---------------------------------------------------------------------------------------------

/// (file name, scene text, words the one-line message must contain).
fn bad_scenes() -> Vec<(&'static str, String, Vec<&'static str>)> {
    let good = riser_scene(10);
    let sub = |from: &str, to: &str| {
        assert!(good.contains(from), "{from}");
        good.replacen(from, to, 1)
    };
    vec![
        (
            "syntax.toml",
            sub("[time]", "[time"),
            vec!["syntax error", "line"],
        ),
        ("empty.toml", String::new(), vec!["`beam`", "missing"]),
        (
            "unknown_key.toml",
            sub("mass = 1.0", "mass = 1.0\nlenght = 1.0"),
            vec!["beam.lenght", "unknown"],
        ),
        (
            "unknown_table.toml",
            format!("{good}\n[solver]\ntol = 1e-9\n"),
            vec!["solver"],
        ),
        (
            "missing_key.toml",
            sub("step = 0.01\n", ""),
            vec!["time.step", "missing"],
        ),
        (
            "missing_table.toml",
            good.replace("[time]\nstep = 0.01\nsteps = 10\n", ""),
            vec!["time", "missing"],
        ),
        (
            "wrong_type.toml",
            sub("mass = 1.0", "mass = \"heavy\""),
            vec!["beam.mass", "wrong type", "heavy"],
        ),
        (
            "float_count.toml",
            sub("pendulums = 10", "pendulums = 10.5"),
            vec!["beam.pendulums"],
        ),
        (
            "nan.toml",
            sub("force = 2.0", "force = nan"),
            vec!["loads.point[0].force", "finite", "NaN"],
        ),
        (
            "inf.toml",
            sub("step = 0.01", "step = inf"),
            vec!["time.step", "finite"],
        ),
        (
            "negative.toml",
            sub("mass = 1.0", "mass = -1.0"),
            vec!["beam.mass", "positive", "-1"],
        ),
        (
            "node_range.toml",
            sub("node = 5", "node = 11"),
            vec!["loads.point[0].node", "11"],
        ),
        (
            "control_node.toml",
            sub("node = 10", "node = 0"),
            vec!["control.node", "0"],
        ),
        (
            "control_count.toml",
            sub("values = [-1.0]", "values = [-1.0, 2.0]"),
            vec!["control.values", "expected 1 value", "got 2"],
        ),
        (
            "per_step_count.toml",
            sub("kind = \"constant\"", "kind = \"per-step\""),
            vec!["control.values", "11", "got 1"],
        ),
        (
            "support.toml",
            sub("support = \"riser\"", "support = \"welded\""),
            vec!["beam.support", "welded"],
        ),
        (
            "length_count.toml",
            sub("length = 1.0", "length = [1.0, 1.0]"),
            vec!["beam.length", "10", "2"],
        ),
        (
            "too_long.toml",
            sub("steps = 10", "steps = 100000000"),
            vec!["time.steps", "10000000"],
        ),
        (
            "too_much_memory.toml",
            sub("pendulums = 10", "pendulums = 1000").replace("steps = 10", "steps = 1000000"),
            vec!["time.steps", "limit"],
        ),
        (
            "zero_steps.toml",
            sub("steps = 10", "steps = 0"),
            vec!["time.steps", "at least 1"],
        ),
    ]
}

#[test]
fn bad_scene_files_give_one_message_naming_file_and_key() {
    let dir = Dir::new();
    for (name, text, needles) in bad_scenes() {
        let path = dir.write(name, &text);
        let mut words = vec![name];
        words.extend(needles.iter().copied());
        for sub in ["simulate", "gradient", "optimize", "explore"] {
            let o = run_on(sub, &path, &[]);
            let msg = assert_one_error(&o, &words);
            assert!(!msg.contains("not available"), "{sub} {name}: {msg}");
        }
    }
}

#[test]
fn missing_file_is_one_error() {
    let dir = Dir::new();
    let path = dir.path().join("nowhere.toml");
    let o = run_on("simulate", &path, &[]);
    assert_one_error(&o, &["nowhere.toml", "cannot read"]);
}

#[test]
fn usage_errors_exit_with_status_two() {
    let o = run(&["simulate".as_ref()]);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    let o = run(&["frobnicate".as_ref()]);
    assert_eq!(o.status.code(), Some(2));
    let o = run(&[
        "optimize".as_ref(),
        "x.toml".as_ref(),
        "--method".as_ref(),
        "newton".as_ref(),
    ]);
    assert_eq!(o.status.code(), Some(2));
    assert!(stderr(&o).contains("lbfgs") && stderr(&o).contains("trust-region"));
}

#[test]
fn help_explains_units_and_sign_convention() {
    let o = run(&["--help".as_ref()]);
    assert_success(&o);
    let h = stdout(&o);
    for word in [
        "+F·z",
        "toward −z",
        "u = −F",
        "Nm/rad",
        "kg",
        "simulate",
        "explore",
    ] {
        assert!(h.contains(word), "--help lacks {word:?}");
    }
    for sub in ["simulate", "gradient", "optimize", "explore"] {
        let o = run(&[sub.as_ref(), "--help".as_ref()]);
        assert_success(&o);
        let h = stdout(&o);
        assert!(h.contains("--output"), "{sub} --help");
        if sub != "explore" {
            assert!(
                h.contains("u = −F"),
                "{sub} --help lacks the sign convention"
            );
        }
    }
    let o = run(&["simulate".as_ref(), "--help".as_ref()]);
    assert!(stdout(&o).contains("t,energy,moment") || stdout(&o).contains("moment"));
}

// ---------------------------------------------------------------------------------------------
// Shipped scene files
// ---------------------------------------------------------------------------------------------

/// The comment heading each shipped scene file.
fn describe(name: &str) -> String {
    let riser_i = |prefix: &str| {
        name.strip_prefix(prefix)
            .and_then(|s| s.parse::<usize>().ok())
    };
    if let Some(i) = riser_i("riser_dissipative_") {
        return format!(
            "Thesis §3.1 (Fig. 3.1-3.2): the manually controlled riser with drag D = 10 kg/m, F = 2 N \
             at node {i}, control at node 10, t in [0, 10] s (N = 1000). The thesis's manual control \
             for this node is {} N (set control.values to apply it).",
            -[0.37, 0.72, 1.01, 1.28, 1.50, 1.68, 1.83, 1.93, 1.99, 2.0][i - 1]
        );
    }
    if let Some(i) = riser_i("riser_") {
        return format!(
            "Thesis §3.3.1 (Tables 3.1-3.4, system {i}), docs/conventions.md: riser (k1 = k11 = 2000 Nm/rad), no \
             drag, F = 2 N at node {i}, constant control at node 10 (initial guess 0), objective \
             c = M0(t_N)^2 (set objective.kind = \"sum\" for Tables 3.2/3.4), h = 0.01 s, N = 10."
        );
    }
    match name {
        "thesis_cantilever" => "Thesis §2.2.4 (Fig. 2.5-2.8): conservative cantilever, k = 1000 Nm/rad \
             for every spring, F = 2 N at the tip, no drag, t in [0, 10] s."
            .into(),
        "fixed_fixed" => "Thesis §2.4.2 (Fig. 2.12-2.13): fixed-fixed beam, end springs 2000 Nm/rad, \
             tip z locked, F = 2 N at the central node 5, t in [0, 10] s."
            .into(),
        "pinned_pinned" => "Thesis §2.4.2 (Fig. 2.13): pinned-pinned beam (no end springs), tip z \
             locked, F = 2 N at node 5, t in [0, 10] s."
            .into(),
        "scaled_cantilever_n20" => "Convergence study (end of thesis §2.4.4): cantilever of length 10 m, \
             EI = 1000 Nm^2, mass 10 kg, discretised by n = 20 pendulums, base spring 2k, F = 2 N at \
             the tip."
            .into(),
        "oblique_riser" => "Out-of-plane loads: the thesis riser with F = 2 N at node 5 at \
             45 degrees between x and z (force = [fx, fz] = [sqrt 2, sqrt 2]), no drag, t in [0, 10] s. \
             Spatial: simulate runs the spatial model and fills in the x columns."
            .into(),
        "oblique_control" => "A 2-axis control: the oblique riser (F = 2 N at node 5 at 45 \
             degrees, force = [sqrt 2, sqrt 2]) with a 2-axis piecewise control [u_x, u_z] at node 10, \
             10 pieces of 1 s (initial guess 0), objective c_sum = sum of |M0(t_k)|^2, t in [0, 10] s. \
             Spatial; the optimal control points along the load (rotational symmetry)."
            .into(),
        "wave_riser" => "A regular wave: the riser with drag D = 10 kg/m and a harmonic load \
             2 N sin(2 pi t / 8 s) at node 5, ramped in over 8 s, t in [0, 32] s; piecewise control at \
             node 10 (32 pieces of 1 s), objective c_sum = sum of M0(t_k)^2 (chainbeam optimize \
             counters the wave)."
            .into(),
        "wave_series" => "A load history: the riser with drag D = 10 kg/m and the load at \
             node 5 read from the time series wave_series.csv (t, fx, fz; an oblique sea of two wave \
             components, linearly interpolated), ramped in over 8 s, t in [0, 32] s. Spatial."
            .into(),
        "spatial_mpc_riser" => "MPC in the spatial model: the riser of mpc_riser \
             (drag D = 10 kg/m, control at node 10) in a sheared current along +z (0.1 m/s at the \
             surface falling linearly to 0.02 m/s at the seabed) while the sea comes from 60 degrees \
             (from +z toward +x): 2 N sin(2 pi t / 8 s) + 0.5 N sin(2 pi t / 5.3 s + 1) at node 5, \
             ramped in over 8 s, t in [0, 30] s. Spatial: a spatial closed loop decides a 2-axis force \
             (u_x, u_z) every interval on the vector moment, objective c_sum = sum of |M0(t_k)|^2 \
             (docs/cli.md)."
            .into(),
        "mpc_riser" => "Closed-loop control: the riser with drag D = 10 kg/m under an irregular \
             sea at node 5, 2 N sin(2 pi t / 8 s) + 0.5 N sin(2 pi t / 5.3 s + 1), ramped in over \
             8 s, in a sheared current (along +z, 0.1 m/s at the surface falling linearly to \
             0.02 m/s at the seabed), t in [0, 60] s; control at node 10 (the platform), objective c_sum = sum of \
             M0(t_k)^2. chainbeam mpc decides the control every interval (docs/cli.md)."
            .into(),
        "mpc_riser_wrong_model" => "Closed-loop control with a model mismatch: a wrong model of \
             mpc_riser for chainbeam mpc --model: drag 7 instead of 10 kg/m, the current 20 % too \
             strong, and a forecast of the sea without its 5.3 s component and with the 8 s wave \
             20 % too weak (1.6 N). The plant is mpc_riser.toml."
            .into(),
        "long_horizon" => "Future work of thesis §3.3 (Fig. 3.12): riser with drag D = 10 kg/m, F = 2 N \
             at node 5, per-step control at node 10 (1001 zeros as initial guess), objective \
             c_sum = sum of M0(t_k)^2, t in [0, 10] s."
            .into(),
        "sheared_current" => "A sheared current: the riser with drag D = 10 kg/m in a current along +z \
             falling linearly from 0.3 m/s at the surface (top node) to 0.05 m/s at the seabed; the \
             drag acts on the motion relative to the water. Piecewise control at node 10 (10 pieces \
             of 1 s), objective c_sum = sum of M0(t_k)^2, t in [0, 10] s."
            .into(),
        "turning_current" => "A current turning with depth: the riser with drag D = 10 kg/m in a tabulated current \
             turning with depth: rows (depth m, speed m/s, direction deg from +z toward +x), along +z \
             at the surface, 45 deg at 5 m, along +x at the seabed (10 m). Spatial; t in [0, 10] s."
            .into(),
        _ => {
            let (support, d) = name
                .strip_prefix("dissipative_")
                .and_then(|s| s.rsplit_once("_d"))
                .unwrap_or_else(|| panic!("no description for catalogue scene `{name}`"));
            let eq = match support {
                "cantilever" => "2.4.5",
                "fixed_fixed" => "2.4.6",
                _ => "2.4.7",
            };
            format!(
                "Thesis §2.4.4 (Fig. 2.14-2.16): dissipative {} beam, drag D = {d} kg/m, F = 2 N, \
                 t in [0, 10] s; settles at the static deflection of eq. {eq} (lengthen time.steps).",
                support.replace('_', "-")
            )
        }
    }
}

fn wrap_comment(text: &str) -> String {
    let mut out = String::new();
    let mut line = String::from("#");
    for word in text.split_whitespace() {
        if line.len() + 1 + word.len() > 99 {
            out.push_str(&line);
            out.push('\n');
            line = String::from("#");
        }
        line.push(' ');
        line.push_str(word);
    }
    out.push_str(&line);
    out.push('\n');
    out
}

fn scene_file_text(name: &str, scene: &Scene) -> String {
    format!(
        "{}#\n{}\n{}",
        wrap_comment(&describe(name)),
        wrap_comment(&format!(
            "Generated from chainbeam::catalogue::by_name(\"{name}\") (tests/cli/cli.rs). Units SI: m, \
             kg, Nm/rad, N, s. Sign convention (the thesis's): a load F enters H as +F z, so F > 0 \
             pushes toward -z; a control u = -F cancels a tip load F."
        )),
        scene.to_toml_string()
    )
}

/// Catalogue scenes that are not shipped as files, with the reason.
const NOT_SHIPPED: [(&str, &str); 0] = [];

/// The catalogue scenes shipped under examples/scenes/.
fn shipped() -> Vec<(&'static str, Scene)> {
    catalogue::all()
        .into_iter()
        .filter(|(name, _)| NOT_SHIPPED.iter().all(|(skip, _)| skip != name))
        .collect()
}

fn scenes_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("examples/scenes")
}

#[test]
fn shipped_scenes_match_catalogue_validate_and_simulate() {
    let dir = scenes_dir();
    let all = shipped();
    if std::env::var_os("CHAINBEAM_WRITE_SCENES").is_some() {
        fs::create_dir_all(&dir).unwrap();
        for (name, scene) in &all {
            fs::write(
                dir.join(format!("{name}.toml")),
                scene_file_text(name, scene),
            )
            .unwrap();
            // a load's time series goes to its file, named relative to the scene file
            for series in scene.loads.points.iter().filter_map(|p| p.series.as_ref()) {
                fs::write(dir.join(&series.file), series.to_csv()).unwrap();
            }
        }
    }
    for (name, scene) in &all {
        let path = dir.join(format!("{name}.toml"));
        let read = Scene::from_file(&path).unwrap_or_else(|e| {
            panic!("{e} (regenerate with CHAINBEAM_WRITE_SCENES=1 cargo test --test cli)")
        });
        assert_eq!(
            &read,
            scene,
            "{} differs from catalogue::{name}",
            path.display()
        );
        read.validate().unwrap();
        let traj = simulate(&read).unwrap_or_else(|e| panic!("{name}: {e}"));
        assert_eq!(
            traj.is_spatial(),
            read.is_spatial(),
            "{name}: the model it needs"
        );
        for k in [0, traj.steps()] {
            // |rᵢ − rᵢ₋₁| = lᵢ: the pendulums keep their lengths (in either model)
            let mut prev = [0.0; 3];
            for (r, l) in traj.positions(k).iter().zip(&read.beam.lengths) {
                let d: f64 = (0..3).map(|c| (r[c] - prev[c]).powi(2)).sum::<f64>().sqrt();
                assert!(
                    (d / l - 1.0).abs() < 1e-10,
                    "{name}: |q| = {} at step {k}",
                    d / l
                );
                prev = *r;
            }
            assert!(traj.energy()[k].is_finite() && traj.moment()[k].is_finite());
        }
    }
    // Every shipped file is a catalogue scene, except the real-scale risers written by hand from
    // their sources (checked and run in tests/fatigue/wave_riser.rs, tests/model/stackup.rs and
    // tests/model/riser_scenes.rs; the system design scene in tests/design/design_stackup.rs).
    for entry in fs::read_dir(&dir).unwrap() {
        let path = entry.unwrap().path();
        if path.extension().is_some_and(|e| e == "toml") {
            let stem = path.file_stem().unwrap().to_string_lossy().into_owned();
            assert!(
                all.iter().any(|(name, _)| *name == stem)
                    || [
                        "riser_300m",
                        "riser_1000m",
                        "riser_300m_stackup",
                        "riser_300m_system",
                        "riser_1000m_system",
                        "riser_300m_design",
                        "riser_300m_system_design",
                    ]
                    .contains(&stem.as_str()),
                "{} is not a catalogue scene",
                path.display()
            );
        }
    }
}

#[test]
fn cli_reads_shipped_scenes() {
    let dir = scenes_dir();
    let o = run_on("simulate", &dir.join("thesis_cantilever.toml"), &[]);
    assert_success(&o);
    let out = stdout(&o);
    assert_eq!(out.lines().next(), Some(header(10).as_str()));
    let rows = parse_rows(&out);
    assert_eq!(rows.len(), 1001);
    // The tip moves toward −z under F = +2 N (thesis sign).
    assert!(rows.iter().skip(1).all(|r| r[3 + 27 + 2] <= 0.0));

    let o = run_on("gradient", &dir.join("riser_10.toml"), &[]);
    assert_success(&o);
    let v = json(&o);
    assert_eq!(numbers(&v, "controls"), [0.0]);
    // u = −F = −2 cancels the tip load (docs/conventions.md: the Table 3.1 root for node 10 is −2), so at
    // u = 0 the objective decreases toward negative u: dc/du > 0.
    assert!(numbers(&v, "gradient")[0] > 0.0);
    let o = run_on("gradient", &dir.join("long_horizon.toml"), &[]);
    assert_success(&o);
    assert_eq!(numbers(&json(&o), "gradient").len(), 1001);
}

/// A spatial scene (a load with an x component or a 2-axis control, docs/scene-format.md):
/// `simulate` keeps the CSV header, fills in the x columns with the library's spatial trajectory
/// and has `moment_x` and `control_x` before the last column `control` (docs/cli.md); `gradient`
/// runs it in the spatial model (its numbers are checked in tests/cli/cli_spatial.rs). The series
/// scene reads its CSV beside the scene file.
#[test]
fn cli_simulates_spatial_scenes() {
    let dir = scenes_dir();
    for name in ["oblique_riser", "wave_series", "oblique_control"] {
        let path = dir.join(format!("{name}.toml"));
        let o = run_on("simulate", &path, &[]);
        assert_success(&o);
        let out = stdout(&o);
        let spatial_header = header(10).replace(",control", ",moment_x,control_x,control");
        assert_eq!(out.lines().next(), Some(spatial_header.as_str()));
        let rows = parse_rows(&out);
        let traj = simulate(&Scene::from_file(&path).unwrap()).unwrap();
        assert!(traj.is_spatial());
        assert_eq!(rows.len(), traj.steps() + 1);
        let ux = |k: usize| traj.controls_x().get(k).copied().unwrap_or(0.0);
        for (k, row) in rows.iter().enumerate() {
            for (i, r) in traj.positions(k).iter().enumerate() {
                for d in 0..3 {
                    assert_eq!(row[3 + 3 * i + d].to_bits(), r[d].to_bits());
                }
            }
            assert_eq!(row[2].to_bits(), traj.moment()[k].to_bits());
            assert_eq!(row[33].to_bits(), traj.moment_x()[k].to_bits());
            assert_eq!(row[34].to_bits(), ux(k).to_bits());
            assert_eq!(row[35].to_bits(), traj.controls()[k].to_bits());
        }
        if name == "oblique_control" {
            continue; // its control starts at 0 and cancels nothing: the load moves it as oblique_riser
        }
        // the x of the tip moves: toward −x, as the x components of the loads push it
        let tip_x = rows.iter().map(|r| r[3 + 27]).fold(0.0f64, f64::min);
        assert!(tip_x < -1e-3, "{name}: tip x {tip_x}");
    }
    let o = run_on("gradient", &dir.join("oblique_riser.toml"), &[]);
    assert_success(&o);
    assert_eq!(json(&o)["model"], "spatial");
    // the planar wave scene optimises like the thesis scenes: its gradient has one entry per piece
    let o = run_on("gradient", &dir.join("wave_riser.toml"), &[]);
    assert_success(&o);
    assert_eq!(numbers(&json(&o), "gradient").len(), 32);
}

/// A load's series file is an input too: the output may not overwrite it.
#[test]
fn output_onto_a_series_file_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let scene = dir.path().join("s.toml");
    let series = dir.path().join("f.csv");
    let csv = "t,fx,fz\n0,0,1\n1,0,2\n";
    fs::write(&series, csv).unwrap();
    fs::write(
        &scene,
        "[beam]\npendulums = 3\nlength = 1.0\nmass = 1.0\nstiffness = 100.0\n\
         support = \"cantilever\"\n[[loads.point]]\nnode = 3\nseries = \"f.csv\"\n\
         [time]\nstep = 0.01\nsteps = 10\n",
    )
    .unwrap();
    let out = series.to_str().unwrap();
    for sub in ["simulate", "gradient"] {
        let o = run_on(sub, &scene, &["--output", out]);
        assert_one_error(&o, &["f.csv", "refusing", "input"]);
        assert_eq!(fs::read_to_string(&series).unwrap(), csv, "{sub}");
    }
    let o = run_on(
        "simulate",
        &scene,
        &["--output", dir.path().join("r.csv").to_str().unwrap()],
    );
    assert_success(&o);
    // no temporary file left beside the refused outputs
    let names: Vec<_> = fs::read_dir(dir.path())
        .unwrap()
        .map(|e| e.unwrap().file_name())
        .collect();
    assert_eq!(names.len(), 3, "{names:?}");
}
