//! Round trips between the subcommands (`optimize` → `simulate|gradient --controls`), the
//! `control` column, `.npy` output, `--pieces`, `--effort`, `--lower/--upper`, `--progress`,
//! `--threads`, the exit status of a run that did not converge, and the per-subcommand help.

use crate::common;

use std::fs;
use std::path::Path;

use chainbeam::{ControlMap, PiecewiseControl, Scene};
use common::*;

/// Table 3.2's scene, system 5: the riser with the load at node 5 and c_sum = Σ M₀(t_k)²
/// (eq. 3.3.4), constant control at the tip; its minimum is not zero, so objectives compare.
fn riser_sum(dir: &Dir) -> std::path::PathBuf {
    let text = fs::read_to_string(scene("riser_5.toml"))
        .unwrap()
        .replace("kind = \"final\"", "kind = \"sum\"");
    assert!(text.contains("kind = \"sum\""));
    dir.write("riser_sum.toml", &text)
}

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

/// Σ_k M₀(t_k)² from a simulate CSV (the `moment` column).
fn sum_of_squared_moments(csv: &str) -> f64 {
    let (header, rows) = parse_csv(csv);
    let m = header.iter().position(|h| h == "moment").unwrap();
    rows.iter().map(|r| r[m] * r[m]).sum()
}

fn column(csv: &str, name: &str) -> Vec<f64> {
    let (header, rows) = parse_csv(csv);
    let c = header.iter().position(|h| h == name).unwrap();
    rows.iter().map(|r| r[c]).collect()
}

#[test]
fn optimize_output_round_trips_through_simulate_and_gradient() {
    let dir = Dir::new();
    let sc = riser_sum(&dir);
    let u_json = dir.join("u.json");
    let o = run(&["optimize", s(&sc), "-o", s(&u_json)]);
    assert_success(&o);
    let opt = json_text(&fs::read_to_string(&u_json).unwrap());
    assert_eq!(opt["converged"], true);
    let u = numbers(&opt, "controls");
    assert_eq!(u.len(), 1);

    // simulate with those controls: the control column is u at every t_k, and Σ M₀² from the
    // simulated moments (an independent evaluation: the simulation path, not the adjoint's
    // forward sweep) is the optimiser's objective.
    let o = run(&["simulate", s(&sc), "--controls", s(&u_json)]);
    assert_success(&o);
    let csv = stdout(&o);
    let control = column(&csv, "control");
    assert_eq!(control.len(), 11);
    assert!(control.iter().all(|c| c.to_bits() == u[0].to_bits()));
    let c = opt["objective"].as_f64().unwrap();
    let c_sim = sum_of_squared_moments(&csv);
    assert!((c_sim - c).abs() <= 1e-12 * c, "{c_sim} vs {c}");

    // gradient at those controls: the optimiser's objective and a gradient at its tolerance.
    let o = run(&["gradient", s(&sc), "--controls", s(&u_json)]);
    assert_success(&o);
    let g = json(&o);
    assert_eq!(numbers(&g, "controls"), u);
    assert!((g["objective"].as_f64().unwrap() - c).abs() <= 1e-14 * c);
    let gn = g["gradient_norm"].as_f64().unwrap();
    assert!(
        gn <= opt["gradient_norm"].as_f64().unwrap() * (1.0 + 1e-9),
        "{gn} vs {}",
        opt["gradient_norm"]
    );

    // The simulate CSV's control column is itself a controls file (N + 1 = 11 values: per-step).
    let traj = dir.write("traj.csv", &csv);
    let o = run(&["gradient", s(&sc), "--controls", s(&traj)]);
    assert_success(&o);
    let g_ps = json(&o);
    assert_eq!(g_ps["control_kind"], "per-step");
    let gk = numbers(&g_ps, "gradient");
    assert_eq!(gk.len(), 11);
    // The constant control's gradient is the sum of the per-step gradient (chain rule).
    let total: f64 = gk.iter().sum();
    let g0 = numbers(&g, "gradient")[0];
    assert!((total - g0).abs() <= 1e-10 * gk.iter().map(|x| x.abs()).sum::<f64>());
}

#[test]
fn a_single_column_file_and_a_json_array_are_controls_too() {
    let dir = Dir::new();
    let sc = riser_sum(&dir);
    // The scene's own control (constant 0) applied from files must reproduce `simulate SCENE`
    // byte for byte once the scene's value is the same.
    let text = fs::read_to_string(&sc)
        .unwrap()
        .replace("values = [0.0]", "values = [-7.5]");
    let sc75 = dir.write("riser_75.toml", &text);
    let want = stdout(&run(&["simulate", s(&sc75)]));
    for (name, body) in [
        ("one.txt", "-7.5\n"),
        ("one_header.csv", "u\n-7.5\n"),
        ("array.json", "[-7.5]"),
        ("per_step.txt", &"-7.5\n".repeat(11)),
    ] {
        let f = dir.write(name, body);
        let o = run(&["simulate", s(&sc), "--controls", s(&f)]);
        assert_success(&o);
        assert_eq!(stdout(&o), want, "{name}");
    }
}

#[test]
fn piecewise_controls_round_trip() {
    let dir = Dir::new();
    let sc = riser_sum(&dir);
    let u_json = dir.join("u.json");
    let o = run(&["optimize", s(&sc), "--pieces", "2", "-o", s(&u_json)]);
    assert_success(&o);
    let opt = json_text(&fs::read_to_string(&u_json).unwrap());
    assert_eq!(opt["control_kind"], "piecewise");
    assert_eq!(opt["pieces"], 2);
    let theta = numbers(&opt, "controls");
    assert_eq!(theta.len(), 2);
    // Two pieces do at least as well as one constant (the constant is a special case).
    let constant = json(&run(&["optimize", s(&sc)]));
    let c = opt["objective"].as_f64().unwrap();
    assert!(c <= constant["objective"].as_f64().unwrap() * (1.0 + 1e-9));

    // simulate maps θ to u_k with the library's piecewise convention (the reference).
    let o = run(&["simulate", s(&sc), "--controls", s(&u_json)]);
    assert_success(&o);
    let csv = stdout(&o);
    let mut u = vec![0.0; 11];
    PiecewiseControl {
        steps: 10,
        pieces: 2,
    }
    .controls(&theta, &mut u);
    assert_eq!(column(&csv, "control"), u);
    let c_sim = sum_of_squared_moments(&csv);
    assert!((c_sim - c).abs() <= 1e-12 * c, "{c_sim} vs {c}");
    // gradient reads the same file as a 2-piece control.
    let g = json(&run(&["gradient", s(&sc), "--controls", s(&u_json)]));
    assert_eq!(g["control_kind"], "piecewise");
    assert_eq!(numbers(&g, "gradient").len(), 2);
}

#[test]
fn effort_adds_rho_h_sum_of_squared_controls() {
    // Closed form: with u_k = −1 N for k = 0..10, h = 0.01 s, ρ = 0.5:
    // ρ h Σ u_k² = 0.5·0.01·11 = 0.055 and d/du (ρ h Σ u²) = 2ρ h·11·u = −0.11.
    let dir = Dir::new();
    let sc = riser_sum(&dir);
    let u = dir.write("u.txt", "-1\n");
    let plain = json(&run(&["gradient", s(&sc), "--controls", s(&u)]));
    let o = run(&["gradient", s(&sc), "--controls", s(&u), "--effort", "0.5"]);
    assert_success(&o);
    let with = json(&o);
    assert_eq!(with["effort"], 0.5);
    let dc = with["objective"].as_f64().unwrap() - plain["objective"].as_f64().unwrap();
    assert!((dc - 0.055).abs() < 1e-12, "{dc}");
    let dg = numbers(&with, "gradient")[0] - numbers(&plain, "gradient")[0];
    assert!((dg + 0.11).abs() < 1e-12, "{dg}");

    // The optimum with an effort penalty: its own gradient vanishes there, and it pulls |u|
    // below the unpenalised optimum's.
    let opt = json(&run(&["optimize", s(&sc)]));
    let o = run(&["optimize", s(&sc), "--effort", "0.5"]);
    assert_success(&o);
    let opt_e = json(&o);
    assert_eq!(opt_e["effort"], 0.5);
    let (u0, ue) = (numbers(&opt, "controls")[0], numbers(&opt_e, "controls")[0]);
    assert!(ue.abs() < u0.abs(), "{ue} vs {u0}");
}

#[test]
fn symmetric_lower_upper_is_the_bound() {
    let sc = scene("riser_5.toml");
    let a = run(&["optimize", s(&sc), "--bound", "10"]);
    let b = run(&["optimize", s(&sc), "--lower", "-10", "--upper", "10"]);
    assert_success(&a);
    assert_success(&b);
    let (a, b) = (json(&a), json(&b));
    assert_eq!(a["controls"], b["controls"]);
    assert_eq!(a["bound"], 10.0);
    assert_eq!((&a["lower"], &a["upper"]), (&b["lower"], &b["upper"]));
    assert_eq!(
        (b["lower"].as_f64(), b["upper"].as_f64()),
        (Some(-10.0), Some(10.0))
    );
}

/// `--lower/--upper` with an asymmetric box on Table 3.1's scene (riser_5.toml: c = M₀(t_N)²,
/// constant control; the unbounded root is u* = −33.41 N, where c = 0): a box holding u* finds
/// it (the same controls as the unbounded run, to the optimiser's 10⁻⁶ N), a box above it stops
/// on its lower end, and c there is what `gradient` reports for that control (an independent
/// evaluation of the same objective).
#[test]
fn asymmetric_lower_upper_box() {
    let dir = Dir::new();
    let sc = scene("riser_5.toml");
    let free = numbers(&json(&run(&["optimize", s(&sc)])), "controls")[0];
    assert!((free + 33.4).abs() < 0.1, "{free}");
    let o = run(&["optimize", s(&sc), "--lower", "-50", "--upper", "5"]);
    assert_success(&o);
    let inside = json(&o);
    assert!((numbers(&inside, "controls")[0] - free).abs() < 1e-6);
    assert_eq!(inside["active_bounds"], serde_json::json!([]));
    assert!(inside.get("bound").is_none());
    let out = dir.join("u.json");
    let o = run(&[
        "optimize",
        s(&sc),
        "--lower",
        "-20",
        "--upper",
        "5",
        "-o",
        s(&out),
    ]);
    assert_success(&o);
    let clamped = json_text(&fs::read_to_string(&out).unwrap());
    assert_eq!(numbers(&clamped, "controls"), vec![-20.0]);
    assert_eq!(clamped["active_bounds"], serde_json::json!([0]));
    assert_eq!(
        (clamped["lower"].as_f64(), clamped["upper"].as_f64()),
        (Some(-20.0), Some(5.0))
    );
    let g = json(&run(&["gradient", s(&sc), "--controls", s(&out)]));
    assert_eq!(g["objective"], clamped["objective"]);
}

#[test]
fn not_converged_optimize_exits_3_and_says_why() {
    let dir = Dir::new();
    let out = dir.join("u.json");
    let o = run(&[
        "optimize",
        s(&scene("riser_5.toml")),
        "--max-iters",
        "1",
        "-o",
        s(&out),
    ]);
    // One L-BFGS iteration from u = 0 does not reach ‖∇c‖ ≤ 1e-8‖∇c₀‖ (Table 3.1's root is at
    // u = −33.4 N).
    let v = json_text(&fs::read_to_string(&out).unwrap());
    assert_eq!(v["converged"], false);
    let rel = v["relative_gradient_norm"].as_f64().unwrap();
    assert!(rel > 1e-8);
    let rel_text = format!("{rel:.3e}");
    assert_one_line(
        &o,
        3,
        &[
            "riser_5.toml",
            "did not converge",
            "maximum iterations (1)",
            "after 1 iteration,",
            "relative gradient",
            &rel_text,
            "written",
        ],
    );
    // On stdout too: the JSON is written, the status is still 3.
    let o = run(&["optimize", s(&scene("riser_5.toml")), "--max-iters", "1"]);
    assert_eq!(o.status.code(), Some(3));
    assert_eq!(json(&o)["converged"], false);
    // explore: every start stopped at the limit.
    let o = run(&[
        "explore",
        s(&scene("riser_5.toml")),
        "--starts",
        "3",
        "--max-iters",
        "1",
    ]);
    assert_one_line(&o, 3, &["3 of 3 starts did not converge", "start 0:"]);
    assert_eq!(json(&o)["converged_starts"], 0);
    // A converged run exits 0 (Table 3.1, system 5).
    assert_success(&run(&["optimize", s(&scene("riser_5.toml"))]));
}

#[test]
fn progress_prints_iterations_on_stderr() {
    // stderr is a pipe here, so --progress prints plain lines (no terminal codes): the start,
    // then one line per iteration numbered 1, 2, …, whose count and last cost and ‖∇c‖ are the
    // JSON's `iterations`, `objective` and `gradient_norm` (the same run's result). Also under
    // --quiet, which only silences spinners. L-BFGS, asked for: these lines are the argmin
    // solvers' (the default `auto` prints its choice first, tests/cli/cli_hostile.rs).
    let sc = scene("riser_5.toml");
    for quiet in [false, true] {
        let mut args = vec!["optimize", s(&sc), "--progress", "--method", "lbfgs"];
        if quiet {
            args.push("--quiet");
        }
        let o = run(&args);
        assert_success(&o);
        let v = json(&o);
        let err = stderr(&o);
        assert!(!err.contains('\u{1b}'), "terminal codes in {err:?}");
        let lines: Vec<&str> = err.lines().collect();
        assert!(lines[0].starts_with("lbfgs: start, cost "), "{err}");
        let iters: Vec<&str> = lines[1..]
            .iter()
            .copied()
            .filter(|l| !l.ends_with("(polish)"))
            .collect();
        assert_eq!(
            iters.len() as u64,
            v["iterations"].as_u64().unwrap(),
            "{err}"
        );
        for (k, l) in iters.iter().enumerate() {
            let f: Vec<&str> = l.split_whitespace().collect();
            assert_eq!((f[0], f[2], f[4]), ("iter", "cost", "|g|"), "{l}");
            assert_eq!(f[1].parse::<usize>().unwrap(), k + 1);
        }
        let last: Vec<&str> = lines.last().unwrap().split_whitespace().collect();
        let (cost, g) = (
            last[3].parse::<f64>().unwrap(),
            last[5].parse::<f64>().unwrap(),
        );
        let (j, gn) = (
            v["objective"].as_f64().unwrap(),
            v["gradient_norm"].as_f64().unwrap(),
        );
        // Printed to 13 and 4 significant digits.
        assert!((cost - j).abs() <= 1e-12 * j.abs(), "{cost} vs {j}");
        assert!((g - gn).abs() <= 1e-3 * gn, "{g} vs {gn}");
        assert_eq!(v["converged"], true);
    }
}

#[test]
fn threads_within_the_bound_are_accepted() {
    let o = run(&[
        "explore",
        s(&scene("riser_5.toml")),
        "--starts",
        "2",
        "--threads",
        "1024",
    ]);
    assert_success(&o);
}

/// Parses a `.npy` v1.0 file (numpy.lib.format): (descr, fortran_order, shape, data).
fn parse_npy(bytes: &[u8]) -> (String, bool, Vec<usize>, Vec<f64>) {
    assert_eq!(&bytes[..6], b"\x93NUMPY");
    assert_eq!(&bytes[6..8], &[1, 0]);
    let len = u16::from_le_bytes([bytes[8], bytes[9]]) as usize;
    assert_eq!((10 + len) % 64, 0);
    let dict = std::str::from_utf8(&bytes[10..10 + len]).unwrap();
    assert!(dict.ends_with('\n'));
    let field = |key: &str| {
        let start = dict.find(&format!("'{key}': ")).unwrap() + key.len() + 4;
        &dict[start..]
    };
    let descr = field("descr").split('\'').nth(1).unwrap().to_string();
    let fortran = field("fortran_order").starts_with("True");
    let shape_text = field("shape");
    let shape: Vec<usize> = shape_text[1..shape_text.find(')').unwrap()]
        .split(',')
        .filter(|x| !x.trim().is_empty())
        .map(|x| x.trim().parse().unwrap())
        .collect();
    let data = bytes[10 + len..]
        .chunks_exact(8)
        .map(|c| f64::from_le_bytes(c.try_into().unwrap()))
        .collect();
    (descr, fortran, shape, data)
}

#[test]
fn npy_holds_the_csv_columns_exactly() {
    let dir = Dir::new();
    let sc = scene("thesis_cantilever.toml");
    let n = Scene::from_file(&sc).unwrap().n();
    let csv = stdout(&run(&["simulate", s(&sc)]));
    let (header, rows) = parse_csv(&csv);
    assert_eq!(header.len(), 3 * n + 4);
    assert_eq!(header.last().unwrap(), "control");
    // By extension, and by --format to stdout (a pipe here).
    let out = dir.join("traj.npy");
    assert_success(&run(&["simulate", s(&sc), "-o", s(&out)]));
    let file = fs::read(&out).unwrap();
    let piped = run(&["simulate", s(&sc), "--format", "npy"]);
    assert_success(&piped);
    assert_eq!(piped.stdout, file);
    let (descr, fortran, shape, data) = parse_npy(&file);
    assert_eq!(descr, "<f8");
    assert!(!fortran);
    assert_eq!(shape, [rows.len(), 3 * n + 4]);
    assert_eq!(data.len(), shape[0] * shape[1]);
    for (k, row) in rows.iter().enumerate() {
        for (j, x) in row.iter().enumerate() {
            assert_eq!(
                data[k * shape[1] + j].to_bits(),
                x.to_bits(),
                "row {k} col {j}"
            );
        }
    }
    // --format csv wins over the extension.
    let out_csv = dir.join("forced.npy");
    assert_success(&run(&[
        "simulate",
        s(&sc),
        "--format",
        "csv",
        "-o",
        s(&out_csv),
    ]));
    assert_eq!(fs::read_to_string(&out_csv).unwrap(), csv);
}

#[test]
fn each_subcommand_help_lists_only_its_own_flags() {
    let help = |args: &[&str]| {
        let o = run(args);
        assert_success(&o);
        stdout(&o)
    };
    let all = [
        "--threads",
        "--seed",
        "--starts",
        "--method",
        "--bound",
        "--lower",
        "--upper",
        "--max-iters",
        "--progress",
        "--design",
        "--pieces",
        "--effort",
        "--controls",
        "--format",
    ];
    let own: [(&str, &[&str]); 4] = [
        ("simulate", &["--controls", "--format"]),
        ("gradient", &["--controls", "--pieces", "--effort"]),
        (
            "optimize",
            &[
                "--threads",
                "--seed",
                "--starts",
                "--method",
                "--bound",
                "--lower",
                "--upper",
                "--max-iters",
                "--progress",
                "--design",
                "--pieces",
                "--effort",
            ],
        ),
        (
            "explore",
            &[
                "--threads",
                "--seed",
                "--starts",
                "--method",
                "--bound",
                "--lower",
                "--upper",
                "--max-iters",
                "--design",
                "--pieces",
                "--effort",
            ],
        ),
    ];
    for (sub, flags) in own {
        let h = help(&["help", sub]);
        // The flags clap lists: lines of the options section that start with a flag.
        let listed: Vec<&str> = h
            .lines()
            .map(str::trim_start)
            .filter(|l| l.starts_with('-'))
            .filter_map(|l| l.split([' ', ',']).find(|w| w.starts_with("--")))
            .collect();
        for f in all {
            assert_eq!(
                listed.contains(&f),
                flags.contains(&f),
                "`help {sub}` and {f}: {listed:?}"
            );
        }
        assert!(
            listed.contains(&"--output") && listed.contains(&"--quiet"),
            "{sub}"
        );
    }
    // No help text sends the reader outside the repository; the exit statuses are documented.
    let main = help(&["--help"]);
    assert!(main.contains("3 the optimiser did not converge"), "{main}");
    for args in [
        &["--help"][..],
        &["help", "simulate"],
        &["help", "gradient"],
        &["help", "optimize"],
        &["help", "explore"],
    ] {
        let h = help(args);
        // No pointer to a design note outside the repository (a file name or its folder).
        let outside = concat!("..", "/shared");
        assert!(!h.contains("SPEC") && !h.contains(outside), "{args:?}");
    }
    assert!(help(&["help", "optimize"]).contains("Exit status 3"));
}
