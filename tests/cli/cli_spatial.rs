//! The command line on spatial scenes (issue "The loads a riser really sees": a load, the
//! current or the control with an x component): `gradient`, `optimize` and `explore` run them in
//! the spatial model and planar scenes in the planar one; a 2-axis control is written as pairs
//! [u_x, u_z] and round-trips through `simulate --controls` and `gradient --controls`; the
//! Riccati solver runs them too (two controls per stage); malformed 2-axis controls files are
//! refused with one clear line.
//!
//! References: the library's `ControlProblem::builder` in the spatial model
//! (gradients to 1e-12 relative) and the planar `ControlProblem::builder` (bit for bit);
//! the simulation path (`simulate`'s moments, an evaluation independent of the adjoint's forward
//! sweep) for the optimiser's objective; the piecewise layout of docs/scene-format.md
//! (`chainbeam::simulate::piece_index`) for the forces `simulate` applies; the rotational
//! symmetry of the drag-free riser about its axis y for the direction of the optimal control.

use crate::common;
use crate::wave_riser4_toml;

use std::fs;
use std::path::{Path, PathBuf};

use chainbeam::simulate::piece_index;
use chainbeam::{BendingObjective, ControlProblem, ObjectiveKind, Parametrisation, Scene};
use common::*;

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

/// A JSON array of pairs [x, z] as the two blocks (xs, zs).
fn pairs(v: &serde_json::Value, key: &str) -> (Vec<f64>, Vec<f64>) {
    v[key]
        .as_array()
        .unwrap_or_else(|| panic!("`{key}` is not an array: {v}"))
        .iter()
        .map(|p| {
            let p = p
                .as_array()
                .unwrap_or_else(|| panic!("`{key}`: {p} is not a pair"));
            assert_eq!(p.len(), 2, "`{key}`: {p:?} is not a pair");
            (p[0].as_f64().unwrap(), p[1].as_f64().unwrap())
        })
        .unzip()
}

/// θ = (θ_x; θ_z) from the pairs under `key` (the library's layout, docs/conventions.md).
fn theta_of_pairs(v: &serde_json::Value, key: &str) -> Vec<f64> {
    let (mut x, z) = pairs(v, key);
    x.extend(z);
    x
}

/// Every |a_i − b_i| ≤ tol·‖b‖ (components near zero are compared on the vector's scale).
fn assert_close(a: &[f64], b: &[f64], tol: f64, what: &str) {
    assert_eq!(a.len(), b.len(), "{what}: lengths");
    let scale = b
        .iter()
        .map(|x| x * x)
        .sum::<f64>()
        .sqrt()
        .max(f64::MIN_POSITIVE);
    for (i, (x, y)) in a.iter().zip(b).enumerate() {
        assert!(
            (x - y).abs() <= tol * scale,
            "{what}[{i}]: {x} vs {y} (scale {scale})"
        );
    }
}

fn rel(a: f64, b: f64) -> f64 {
    (a - b).abs() / b.abs()
}

/// `oblique_control.toml` (the riser with F = 2 N at node 5 at 45°, 10 pieces of a 2-axis
/// control at the tip, c_sum) with distinct, asymmetric values [u_x, u_z] = [0.1 j, 0.2 − 0.07 j],
/// so that a swapped or misplaced component changes the numbers.
fn asymmetric_oblique(dir: &Dir) -> PathBuf {
    let zeros = "values = [[0.0, 0.0], [0.0, 0.0], [0.0, 0.0], [0.0, 0.0], [0.0, 0.0], \
                 [0.0, 0.0], [0.0, 0.0], [0.0, 0.0], [0.0, 0.0], [0.0, 0.0]]";
    let values: Vec<String> = (0..10)
        .map(|j| format!("[{}, {}]", 0.1 * j as f64, 0.2 - 0.07 * j as f64))
        .collect();
    let text = fs::read_to_string(scene("oblique_control.toml")).unwrap();
    assert!(text.contains(zeros));
    let text = text.replace(zeros, &format!("values = [{}]", values.join(", ")));
    dir.write("oblique_asym.toml", &text)
}

/// `gradient` on spatial scenes reports the spatial model and the library's spatial problem's
/// objective and gradient (reference: `ControlProblem::builder`, spatial, 1e-12 relative), with
/// a 2-axis control's θ = (θ_x; θ_z) written as pairs [x, z] per value.
#[test]
fn gradient_of_spatial_scenes_is_the_librarys() {
    let dir = Dir::new();
    let asym = asymmetric_oblique(&dir);
    for path in [
        asym,
        scene("oblique_control.toml"),
        scene("oblique_riser.toml"),
        scene("turning_current.toml"),
    ] {
        let sc = Scene::from_file(&path).unwrap();
        let problem = ControlProblem::builder(&sc).build_in::<3>().unwrap();
        let theta: Vec<f64> = match &sc.control {
            Some(c) => c
                .values_x
                .iter()
                .flatten()
                .chain(&c.values)
                .copied()
                .collect(),
            None => vec![0.0],
        };
        let (c, g) = problem.value_and_gradient(&theta).unwrap();
        let o = run(&["gradient", s(&path)]);
        assert_success(&o);
        let v = json(&o);
        assert_eq!(v["model"], "spatial", "{}", path.display());
        assert!(rel(v["objective"].as_f64().unwrap(), c) <= 1e-12);
        if sc.has_two_axis_control() {
            assert_close(&theta_of_pairs(&v, "gradient"), &g, 1e-12, "gradient");
            assert_eq!(theta_of_pairs(&v, "controls"), theta);
        } else {
            assert_close(&numbers(&v, "gradient"), &g, 1e-12, "gradient");
            assert_eq!(numbers(&v, "controls"), theta);
        }
    }
}

/// `--effort` and `--pieces` on a 2-axis scene: the library's spatial 2-axis problem with the
/// effort ρ and P pieces (reference: `ControlProblem::builder`, spatial, 1e-12 relative), at the start
/// `--pieces` documents: the scene's forces averaged over each piece, per component. From 10
/// pieces of 100 steps to 5 pieces, piece j covers old pieces 2j and 2j + 1 (100 forces each),
/// and the last also u_N (docs/scene-format.md), so its mean is (100 a + 101 b) / 201.
#[test]
fn effort_and_pieces_on_a_two_axis_scene() {
    let dir = Dir::new();
    let path = asymmetric_oblique(&dir);
    let sc = Scene::from_file(&path).unwrap();
    let control = sc.control.as_ref().unwrap();
    let block = |values: &[f64]| -> Vec<f64> {
        (0..5)
            .map(|j| {
                let (a, b) = (values[2 * j], values[2 * j + 1]);
                if j < 4 {
                    (a + b) / 2.0
                } else {
                    (100.0 * a + 101.0 * b) / 201.0
                }
            })
            .collect()
    };
    let mut theta = block(control.values_x.as_ref().unwrap());
    theta.extend(block(&control.values));
    let map = Parametrisation::Piecewise(chainbeam::PiecewiseControl {
        steps: 1000,
        pieces: 5,
    });
    let objective = BendingObjective {
        kind: ObjectiveKind::Sum,
        effort: 0.25,
    };
    let problem = ControlProblem::builder(&sc)
        .map(map)
        .objective(objective)
        .two_axis(true)
        .build_in::<3>()
        .unwrap();
    let (c, g) = problem.value_and_gradient(&theta).unwrap();

    let o = run(&["gradient", s(&path), "--pieces", "5", "--effort", "0.25"]);
    assert_success(&o);
    let v = json(&o);
    assert_eq!(
        (&v["control_kind"], &v["pieces"]),
        (&"piecewise".into(), &5.into())
    );
    assert_eq!(v["effort"], 0.25);
    // means of 200 forces: round-off of a few ulps
    assert_close(&theta_of_pairs(&v, "controls"), &theta, 1e-14, "controls");
    assert!(rel(v["objective"].as_f64().unwrap(), c) <= 1e-12);
    assert_close(&theta_of_pairs(&v, "gradient"), &g, 1e-12, "gradient");
}

/// Planar scenes keep the planar model: `model` is "planar" and the objective and gradient are
/// those of the planar `ControlProblem::builder`, bit for bit (the JSON's shortest decimals
/// read back to the same doubles). A planar current (sheared_current) and a per-step control
/// (long_horizon) included.
#[test]
fn planar_scenes_keep_the_planar_model() {
    for name in ["riser_5.toml", "sheared_current.toml", "long_horizon.toml"] {
        let path = scene(name);
        let sc = Scene::from_file(&path).unwrap();
        assert!(sc.spatial_key().is_none(), "{name} is planar");
        let problem = ControlProblem::builder(&sc).build_in::<2>().unwrap();
        let theta = sc.control.as_ref().map_or(vec![0.0], |c| c.values.clone());
        let (c, g) = problem.value_and_gradient(&theta).unwrap();
        let o = run(&["gradient", s(&path)]);
        assert_success(&o);
        let v = json(&o);
        assert_eq!(v["model"], "planar", "{name}");
        assert_eq!(
            v["objective"].as_f64().unwrap().to_bits(),
            c.to_bits(),
            "{name}"
        );
        let got: Vec<u64> = numbers(&v, "gradient")
            .iter()
            .map(|x| x.to_bits())
            .collect();
        let want: Vec<u64> = g.iter().map(|x| x.to_bits()).collect();
        assert_eq!(got, want, "{name}");
    }
    let o = run(&["optimize", s(&scene("riser_5.toml"))]);
    assert_success(&o);
    assert_eq!(json(&o)["model"], "planar");
}

/// `optimize` on oblique_control.toml converges (exit 0) with 10 pairs [u_x, u_z]; by the
/// rotational symmetry of the drag-free riser about y, the optimal control points along the 45°
/// load (u_x = u_z to the optimiser's tolerance). The JSON round-trips: `simulate --controls`
/// applies both components piece by piece (reference: `piece_index`), and its moments give
/// Σ_k |M₀(t_k)|² = Σ_k (M₀(t_k)² + M₀ₓ(t_k)²) equal to the optimiser's objective to 1e-12
/// relative; `gradient --controls` reads the same pairs back and reports that objective; the
/// simulate CSV (its `control_x` and `control` columns) is itself a 2-axis per-step controls file
/// with the same objective.
#[test]
fn optimize_converges_and_two_axis_controls_round_trip() {
    let dir = Dir::new();
    let path = scene("oblique_control.toml");
    let u_json = dir.join("u.json");
    let o = run(&["optimize", s(&path), "-o", s(&u_json)]);
    assert_success(&o);
    let opt = json_text(&fs::read_to_string(&u_json).unwrap());
    assert_eq!(opt["converged"], true);
    assert_eq!(opt["model"], "spatial");
    assert_eq!(
        (&opt["control_kind"], &opt["pieces"]),
        (&"piecewise".into(), &10.into())
    );
    let (ux, uz) = pairs(&opt, "controls");
    assert_eq!(ux.len(), 10);
    for (x, z) in ux.iter().zip(&uz) {
        assert!(
            (x - z).abs() <= 1e-6 * z.abs(),
            "not along the load: {x} vs {z}"
        );
    }
    let c = opt["objective"].as_f64().unwrap();
    assert!(c < opt["initial_objective"].as_f64().unwrap());
    let (ix, iz) = pairs(&opt, "initial_controls");
    assert!(ix.iter().chain(&iz).all(|&u| u == 0.0), "the scene's start");

    let o = run(&["simulate", s(&path), "--controls", s(&u_json)]);
    assert_success(&o);
    let csv = stdout(&o);
    let (header, rows) = parse_csv(&csv);
    let col = |name: &str| header.iter().position(|h| h == name).unwrap();
    let (m, mx, cx, cz) = (
        col("moment"),
        col("moment_x"),
        col("control_x"),
        col("control"),
    );
    assert_eq!(rows.len(), 1001);
    for (k, r) in rows.iter().enumerate() {
        let j = piece_index(k, 1000, 10);
        assert_eq!((r[cx], r[cz]), (ux[j], uz[j]), "step {k}");
    }
    let c_sim: f64 = rows.iter().map(|r| r[m] * r[m] + r[mx] * r[mx]).sum();
    assert!(rel(c_sim, c) <= 1e-12, "{c_sim} vs {c}");

    let o = run(&["gradient", s(&path), "--controls", s(&u_json)]);
    assert_success(&o);
    let g = json(&o);
    assert_eq!(g["controls"], opt["controls"]);
    assert!(rel(g["objective"].as_f64().unwrap(), c) <= 1e-12);
    let gn = g["gradient_norm"].as_f64().unwrap();
    // `auto` takes the condensed solver (which runs the spatial model), whose reported gradient
    // is its own, exact: equal to the adjoint's to round-off relative to the start's gradient.
    let o = run(&["gradient", s(&path)]);
    assert_success(&o);
    let g0 = json(&o)["gradient_norm"].as_f64().unwrap();
    assert!(
        gn <= opt["gradient_norm"].as_f64().unwrap() * (1.0 + 1e-9) + 1e-12 * g0,
        "{gn} (start: {g0})"
    );

    let traj = dir.write("traj.csv", &csv);
    let o = run(&["gradient", s(&path), "--controls", s(&traj)]);
    assert_success(&o);
    let g = json(&o);
    assert_eq!(g["control_kind"], "per-step");
    assert_eq!(pairs(&g, "controls").0.len(), 1001);
    assert!(rel(g["objective"].as_f64().unwrap(), c) <= 1e-12);
}

/// A pairs file on a planar scene asks for a 2-axis control: `gradient` runs the spatial model
/// (reference: `ControlProblem::builder`, spatial, with a 2-axis constant control) and `simulate` applies
/// u_x (the tip leaves the yz-plane, toward −x for u_x > 0, the sign of a load).
#[test]
fn a_pairs_file_on_a_planar_scene_runs_the_spatial_model() {
    let dir = Dir::new();
    let path = scene("riser_5.toml");
    let f = dir.write("u.json", "[[1.5, -2.0]]");
    let o = run(&["gradient", s(&path), "--controls", s(&f)]);
    assert_success(&o);
    let v = json(&o);
    assert_eq!(v["model"], "spatial");
    let sc = Scene::from_file(&path).unwrap();
    let obj = BendingObjective {
        kind: sc.objective.unwrap(),
        effort: 0.0,
    };
    let p = ControlProblem::builder(&sc)
        .map(Parametrisation::Constant)
        .objective(obj)
        .two_axis(true)
        .build_in::<3>()
        .unwrap();
    let (c, g) = p.value_and_gradient(&[1.5, -2.0]).unwrap();
    assert!(rel(v["objective"].as_f64().unwrap(), c) <= 1e-12);
    assert_close(&theta_of_pairs(&v, "gradient"), &g, 1e-12, "gradient");

    let o = run(&["simulate", s(&path), "--controls", s(&f)]);
    assert_success(&o);
    let (header, rows) = parse_csv(&stdout(&o));
    let x10 = header.iter().position(|h| h == "x10").unwrap();
    assert!(rows.iter().map(|r| r[x10]).fold(0.0f64, f64::min) < -1e-3);
}

/// `--method riccati` on spatial scenes (the Riccati solver with two controls per stage): it runs in the spatial model, converges, and reaches the objective of
/// `--method condensed` (an independent method on the same problem) to 1e-9 relative. The
/// planar riser still runs it (tests/cli/cli_riccati.rs checks its numbers).
#[test]
fn riccati_runs_spatial_scenes() {
    for name in ["oblique_control.toml", "oblique_riser.toml"] {
        let o = run(&["optimize", s(&scene(name)), "--method", "riccati"]);
        assert_success(&o);
        let v = json(&o);
        assert_eq!(v["model"], "spatial", "{name}");
        assert_eq!(v["method"], "riccati", "{name}");
        assert_eq!(v["converged"], true, "{name}");
        let o = run(&["optimize", s(&scene(name)), "--method", "condensed"]);
        assert_success(&o);
        let c = json(&o);
        let (jr, jc) = (
            v["objective"].as_f64().unwrap(),
            c["objective"].as_f64().unwrap(),
        );
        assert!(
            (jr - jc).abs() <= 1e-9 * jc.abs(),
            "{name}: riccati {jr} against condensed {jc}"
        );
    }
    let o = run(&["optimize", s(&scene("riser_5.toml")), "--method", "riccati"]);
    assert_success(&o);
}

/// Malformed controls for a 2-axis scene: each refused with one line naming the file and what is
/// wrong (the counts in pairs), nothing written, no panic.
#[test]
fn bad_two_axis_controls_files_are_refused() {
    let dir = Dir::new();
    let path = scene("oblique_control.toml");
    let nine = ["[1, 2]"; 9].join(", ");
    let cases: Vec<(&str, String, Vec<&str>)> = vec![
        // 20 numbers: θ flattened, not pairs
        (
            "flat.json",
            format!("[{}]", ["0.5"; 20].join(", ")),
            vec!["2-axis", "one number per value", "pairs [u_x, u_z]"],
        ),
        (
            "one.txt",
            "0.5\n".into(),
            vec!["2-axis", "one number per value"],
        ),
        (
            "nine.json",
            format!("{{\"controls\": [{nine}], \"control_kind\": \"piecewise\", \"pieces\": 10}}"),
            vec!["expected pieces = 10 pairs [u_x, u_z]", "got 9 pairs"],
        ),
        (
            "three.json",
            "[[1, 2], [3, 4], [5, 6]]".into(),
            vec!["N + 1 = 1001 pairs [u_x, u_z]", "or 1 pair", "got 3 pairs"],
        ),
        (
            "mixed.json",
            "{\"controls\": [[1, 2], 3]}".into(),
            vec![
                "key `controls`",
                "entry 1 is a number but entry 0 is a pair",
            ],
        ),
        (
            "triple.json",
            "[[1, 2, 3]]".into(),
            vec!["entry 0 is not a finite number or a pair [u_x, u_z]"],
        ),
    ];
    for (name, body, needles) in &cases {
        let f = dir.write(name, body);
        for sub in ["simulate", "gradient"] {
            let o = run(&[sub, s(&path), "--controls", s(&f)]);
            let mut all = needles.clone();
            all.push(name);
            assert_one_error(&o, &all);
        }
    }
}

/// Force limits on a 2-axis control apply to each component: with `--bound 0.5` every u_x and
/// u_z of the optimum lies in [−0.5, 0.5] and the active bounds index θ = (θ_x; θ_z) (20
/// parameters); a start outside `--lower/--upper` names the component's key.
#[test]
fn force_limits_on_a_two_axis_control() {
    let path = scene("oblique_control.toml");
    let o = run(&["optimize", s(&path), "--bound", "0.5"]);
    assert_success(&o);
    let v = json(&o);
    let theta = theta_of_pairs(&v, "controls");
    assert!(theta.iter().all(|u| u.abs() <= 0.5), "{theta:?}");
    let active: Vec<u64> = v["active_bounds"]
        .as_array()
        .unwrap()
        .iter()
        .map(|i| i.as_u64().unwrap())
        .collect();
    assert!(
        !active.is_empty(),
        "the unbounded optimum has |u| ≈ 1 > 0.5"
    );
    for &i in &active {
        assert!(
            (theta[i as usize].abs() - 0.5).abs() < 1e-6,
            "{i}: {theta:?}"
        );
    }
    let o = run(&["optimize", s(&path), "--lower", "1", "--upper", "2"]);
    assert_one_error(
        &o,
        &[
            "key `control.values[0][0]` (u_x)",
            "--lower/--upper",
            "[1, 2]",
        ],
    );
}

/// `explore` on a 2-axis scene (2 pieces, starts in [−3, 3] N): every start reaches the one
/// minimum, reported as pairs along the load (rotational symmetry), with a positive definite
/// Hessian of 2·2 = 4 eigenvalues; start points are pairs too.
#[test]
fn explore_maps_a_two_axis_scene() {
    let path = scene("oblique_control.toml");
    let args = [
        "explore",
        s(&path),
        "--starts",
        "3",
        "--pieces",
        "2",
        "--lo",
        "-3",
        "--hi",
        "3",
    ];
    let o = run(&args);
    assert_success(&o);
    let v = json(&o);
    assert_eq!(v["model"], "spatial");
    assert_eq!(v["converged_starts"], 3);
    let minima = v["minima"].as_array().unwrap();
    assert_eq!(minima.len(), 1);
    let (x, z) = pairs(&minima[0], "controls");
    assert_eq!(x.len(), 2);
    for (a, b) in x.iter().zip(&z) {
        assert!((a - b).abs() <= 1e-6 * b.abs(), "{a} vs {b}");
    }
    assert_eq!(v["certificate"]["positive_definite"], true);
    assert_eq!(v["certificate"]["eigenvalues"].as_array().unwrap().len(), 4);
    for r in v["results"].as_array().unwrap() {
        assert_eq!(pairs(r, "start_point").0.len(), 2);
    }
}

/// Every key of the JSON that `gradient`, `optimize` and `explore` write on a 2-axis scene (top
/// level, and the entries of `results`, `minima` and `certificate`) is documented in docs/cli.md
/// (as `key`), so a reader of the repository finds `model` and the rest.
#[test]
fn json_keys_of_spatial_runs_are_documented() {
    let doc =
        fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("docs/cli.md")).unwrap();
    let path = scene("oblique_control.toml");
    let explore = [
        "explore", "--starts", "2", "--pieces", "2", "--lo", "-3", "--hi", "3",
    ];
    for args in [&["gradient"][..], &["optimize"], &explore] {
        let mut argv = vec![args[0], s(&path)];
        argv.extend(&args[1..]);
        let o = run(&argv);
        assert_success(&o);
        let v = json(&o);
        let mut objects = vec![&v];
        for list in ["results", "minima"] {
            objects.extend(v[list].as_array().into_iter().flatten());
        }
        objects.extend(v.get("certificate"));
        let mut keys: Vec<&String> = objects
            .iter()
            .flat_map(|o| o.as_object().unwrap().keys())
            .collect();
        keys.dedup();
        assert!(keys.iter().any(|k| *k == "model"), "{}", args[0]);
        for key in keys {
            assert!(
                doc.contains(&format!("`{key}`")),
                "{}: `{key}` is not documented in docs/cli.md",
                args[0]
            );
        }
    }
}

/// `chainbeam mpc` on a spatial scene (a spatial closed loop): a small riser (n = 4, D = 10 kg/m) in a
/// current along +z with a wave from 60° (an x component), 1 s of closed loop with a 0.5 s
/// horizon: the run succeeds with either solver, writes the spatial columns (moment_x,
/// control_x, and the baselines' x columns), keeps each force component in the box, reports
/// `"model": "spatial"`, and its c_sum is Σ (M₀ₓ² + M₀²) of the CSV's columns (numbers
/// round-trip); the baselines are the 2-axis ones (pd_gains [u_b,x, u_b,z, K_p, K_d]).
#[test]
fn mpc_runs_a_spatial_scene() {
    let dir = tempfile::tempdir().unwrap();
    fs::write(dir.path().join("scene.toml"), wave_riser4_toml::spatial()).unwrap();
    for solver in ["condensed", "riccati"] {
        let o = assert_cmd::cargo::cargo_bin_cmd!("chainbeam")
            .current_dir(dir.path())
            .args(["mpc", "scene.toml", "--horizon", "0.5", "--bound", "1.0"])
            .args(["--solver", solver, "--baselines"])
            .args(["-o", "loop.csv", "--summary", "summary.json"])
            .output()
            .expect("run chainbeam");
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        let csv = fs::read_to_string(dir.path().join("loop.csv")).unwrap();
        let mut lines = csv.lines();
        assert_eq!(
            lines.next().unwrap(),
            "t,moment,control,tip,moment_x,control_x,moment_none,moment_constant,\
             control_constant,moment_pd,control_pd,moment_x_none,moment_x_constant,\
             control_x_constant,moment_x_pd,control_x_pd"
        );
        let rows: Vec<Vec<f64>> = lines
            .map(|l| l.split(',').map(|x| x.parse().unwrap()).collect())
            .collect();
        assert_eq!(rows.len(), 101, "N + 1 rows");
        assert!(rows.iter().all(|r| r[2].abs() <= 1.0 && r[5].abs() <= 1.0));
        assert!(
            rows.iter().any(|r| r[5].abs() > 1e-3),
            "{solver}: the x component acts"
        );
        let v: serde_json::Value =
            serde_json::from_str(&fs::read_to_string(dir.path().join("summary.json")).unwrap())
                .unwrap();
        assert_eq!(v["model"], "spatial");
        let c_sum: f64 = rows.iter().map(|r| r[1] * r[1] + r[4] * r[4]).sum();
        let reported = v["mpc"]["c_sum"].as_f64().unwrap();
        assert!(
            (reported - c_sum).abs() <= 1e-12 * c_sum,
            "{solver}: {reported} vs {c_sum}"
        );
        assert_eq!(v["mpc"]["decisions"].as_u64(), Some(10));
        assert_eq!(v["baselines"].as_array().unwrap().len(), 3);
        assert_eq!(v["pd_gains"].as_array().unwrap().len(), 4);
        let none: f64 = rows.iter().map(|r| r[6] * r[6] + r[11] * r[11]).sum();
        let none_reported = v["baselines"][0]["c_sum"].as_f64().unwrap();
        assert!((none_reported - none).abs() <= 1e-12 * none);
    }
}
