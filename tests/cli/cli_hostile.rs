//! Hostile command lines (tests/hostile/cases.toml) and the message each must produce: a clear
//! error naming the file, key or flag and the reason, never a panic, never a success.

use crate::common;

use std::path::Path;

use common::*;

#[derive(serde::Deserialize)]
struct Cases {
    case: Vec<Case>,
}

#[derive(serde::Deserialize)]
struct Case {
    args: Vec<String>,
    status: i32,
    message: Vec<String>,
    /// Words the message must not contain (the wrong file, a key the user never wrote).
    #[serde(default)]
    absent: Vec<String>,
}

#[test]
fn every_hostile_case_gives_its_message() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let hostile = root.join("tests/hostile");
    let text = std::fs::read_to_string(hostile.join("cases.toml")).unwrap();
    let cases: Cases = toml::from_str(&text).unwrap();
    assert!(cases.case.len() >= 30, "the table lost cases");
    let scene = scene("riser_5.toml");
    let missing = hostile.join("nowhere.json");
    assert!(!missing.exists());
    for c in &cases.case {
        let args: Vec<String> = c
            .args
            .iter()
            .map(|a| {
                a.replace("{scene}", scene.to_str().unwrap())
                    .replace("{hostile}", hostile.to_str().unwrap())
                    .replace("{missing}", missing.to_str().unwrap())
            })
            .collect();
        let o = run(&args);
        let needles: Vec<&str> = c.message.iter().map(String::as_str).collect();
        let shown = c.args.join(" ");
        match c.status {
            1 => {
                assert!(o.stdout.is_empty(), "{shown}: stdout {}", stdout(&o));
                let err = stderr(&o);
                assert_eq!(o.status.code(), Some(1), "{shown}: {err}");
                assert_eq!(err.lines().count(), 1, "{shown}: not one line: {err:?}");
                assert!(err.starts_with("error: "), "{shown}: {err}");
                for n in &needles {
                    assert!(err.contains(n), "{shown}: message {err:?} lacks {n:?}");
                }
            }
            2 => {
                let err = stderr(&o);
                assert_eq!(o.status.code(), Some(2), "{shown}: {err}");
                assert!(o.stdout.is_empty(), "{shown}");
                for n in &needles {
                    assert!(err.contains(n), "{shown}: message {err:?} lacks {n:?}");
                }
            }
            s => panic!("{shown}: unknown status {s} in cases.toml"),
        }
        let err = stderr(&o);
        assert!(
            !err.contains("panicked") && !err.contains("internal error"),
            "{shown}: {err}"
        );
        for a in &c.absent {
            assert!(
                !err.contains(a.as_str()),
                "{shown}: message {err:?} has {a:?}"
            );
        }
    }
}

/// No subcommand writes onto any of its inputs — the scene, its load series,
/// the `--controls` file, the `--model` scene and its series — through any name (a symbolic
/// link, a `./` path, a hard link), with `--output` nor with `mpc --summary`. Each refusal is one
/// line naming the output, the flag and the input, and leaves every file as it was (before the
/// fix, `mpc --summary` onto the scene's series replaced the series and exited 0).
#[cfg(unix)]
#[test]
fn no_subcommand_writes_onto_any_input_through_any_name() {
    use std::fs;
    let dir = Dir::new();
    let riser = fs::read_to_string(scene("riser_5.toml")).unwrap();
    // riser_5 (N = 10, h = 0.01 s) with a second load read from a series file.
    let with_series =
        |csv: &str| format!("{riser}\n[[loads.point]]\nnode = 3\nseries = \"{csv}\"\n");
    let files = [
        ("scene.toml", with_series("s.csv")),
        ("s.csv", "t,fx,fz\n0,0,0.5\n1,0,0.5\n".to_string()),
        ("u.json", "{\"controls\": [1.5]}\n".to_string()),
        ("model.toml", with_series("m.csv")),
        ("m.csv", "t,fx,fz\n0,0,0.25\n1,0,0.25\n".to_string()),
    ];
    for (name, text) in &files {
        dir.write(name, text);
    }
    // The scene must be valid, or the refusal could come from elsewhere.
    assert_success(&run(&[
        "simulate".as_ref(),
        dir.join("scene.toml").as_os_str(),
    ]));
    let p = |name: &str| dir.join(name).to_str().unwrap().to_string();
    let (sc, u, model) = (p("scene.toml"), p("u.json"), p("model.toml"));
    // (subcommand, its arguments, its inputs, its output flags)
    type Case<'a> = (&'a str, Vec<String>, Vec<&'a str>, Vec<&'a str>);
    let runs: Vec<Case> = vec![
        (
            "simulate",
            vec![sc.clone(), "--controls".into(), u.clone()],
            vec!["scene.toml", "s.csv", "u.json"],
            vec!["-o"],
        ),
        (
            "gradient",
            vec![sc.clone(), "--controls".into(), u.clone()],
            vec!["scene.toml", "s.csv", "u.json"],
            vec!["-o"],
        ),
        (
            "optimize",
            vec![sc.clone()],
            vec!["scene.toml", "s.csv"],
            vec!["-o"],
        ),
        (
            "explore",
            vec![sc.clone(), "--starts".into(), "2".into()],
            vec!["scene.toml", "s.csv"],
            vec!["-o"],
        ),
        (
            "mpc",
            vec![
                sc.clone(),
                "--model".into(),
                model,
                "--horizon".into(),
                "0.05".into(),
                "--interval".into(),
                "0.01".into(),
            ],
            vec!["scene.toml", "s.csv", "model.toml", "m.csv"],
            vec!["-o", "--summary"],
        ),
    ];
    let mut refused = 0;
    for (sub, args, inputs, flags) in &runs {
        for input in inputs {
            std::os::unix::fs::symlink(dir.join(input), dir.join("link")).unwrap();
            fs::hard_link(dir.join(input), dir.join("hard")).unwrap();
            let names = [
                ("symbolic link", p("link")),
                ("./ path", format!("{}/./{input}", dir.path().display())),
                ("hard link", p("hard")),
            ];
            for (how, name) in &names {
                for flag in flags {
                    let mut argv = vec![sub.to_string()];
                    argv.extend(args.iter().cloned());
                    argv.extend([flag.to_string(), name.clone()]);
                    let o = run(&argv);
                    let shown = format!("{sub} {flag} onto {input} by a {how}");
                    let err = stderr(&o);
                    assert_eq!(o.status.code(), Some(1), "{shown}: {err}");
                    let named = if *flag == "-o" { "--output" } else { flag };
                    assert_one_error(&o, &["refusing", input, named]);
                    for (f, text) in &files {
                        assert_eq!(&fs::read_to_string(dir.join(f)).unwrap(), text, "{shown}");
                    }
                    refused += 1;
                }
            }
            fs::remove_file(dir.join("link")).unwrap();
            fs::remove_file(dir.join("hard")).unwrap();
            // No temporary file left behind.
            let mut want: Vec<&str> = files.iter().map(|f| f.0).collect();
            want.sort();
            assert_eq!(dir.files(), want, "{sub}");
        }
    }
    assert_eq!(refused, 3 * (3 + 3 + 2 + 2 + 4 * 2));
    // Two outputs of one run must be two files.
    let o = run(&[
        "mpc",
        &sc,
        "--horizon",
        "0.05",
        "--interval",
        "0.01",
        "-o",
        &p("out.csv"),
        "--summary",
        &format!("{}/./out.csv", dir.path().display()),
    ]);
    assert_one_error(&o, &["--summary and --output name the same file"]);
}

/// Peak memory (KiB), CPU seconds and wall seconds of one run of the binary, measured by
/// `wait4` on the child itself (not RUSAGE_CHILDREN, which other tests' children share).
#[cfg(target_os = "linux")]
struct Usage {
    status: i32,
    stderr: String,
    max_rss_kib: i64,
    cpu_seconds: f64,
    wall_seconds: f64,
}

#[cfg(target_os = "linux")]
#[allow(clippy::zombie_processes)] // reaped by wait4, which also gives its resource usage
fn run_measured(args: &[&str]) -> Usage {
    use std::io::Read;
    use std::process::{Command, Stdio};
    use std::time::{Duration, Instant};
    let clock = Instant::now();
    let mut child = Command::new(env!("CARGO_BIN_EXE_chainbeam"))
        .args(args)
        .stdin(Stdio::null())
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let pid = child.id() as libc::pid_t;
    let mut status = 0;
    let mut usage: libc::rusage = unsafe { std::mem::zeroed() };
    loop {
        // SAFETY: wait4 on our own child with valid pointers.
        let r = unsafe { libc::wait4(pid, &mut status, libc::WNOHANG, &mut usage) };
        assert!(r >= 0, "wait4 failed");
        if r == pid {
            break;
        }
        if clock.elapsed() > Duration::from_secs(20) {
            let _ = child.kill();
            // SAFETY: as above; reaps the killed child.
            unsafe { libc::wait4(pid, &mut status, 0, &mut usage) };
            panic!("chainbeam {args:?} still ran after 20 s (killed)");
        }
        std::thread::sleep(Duration::from_millis(5));
    }
    let wall_seconds = clock.elapsed().as_secs_f64();
    let mut stderr = String::new();
    child
        .stderr
        .take()
        .unwrap()
        .read_to_string(&mut stderr)
        .unwrap();
    let secs = |t: libc::timeval| t.tv_sec as f64 + t.tv_usec as f64 * 1e-6;
    Usage {
        status: if libc::WIFEXITED(status) {
            libc::WEXITSTATUS(status)
        } else {
            -1
        },
        stderr,
        max_rss_kib: usage.ru_maxrss,
        cpu_seconds: secs(usage.ru_utime) + secs(usage.ru_stime),
        wall_seconds,
    }
}

/// `/dev/zero` and `/dev/urandom` as the scene (every subcommand), the
/// `--controls` file, the `--model` scene and a load's series file fail with one line naming the
/// device, within a second of CPU time and with a peak resident memory far below the documented
/// input limit of 1 GiB (`chainbeam::scene::MAX_INPUT_BYTES`, docs/scene-format.md "Size
/// limits"). Before the fix `gradient --controls /dev/zero` grew to 4 GB and `/dev/urandom` as a
/// scene took 20–30 s. The wall-clock bound is generous (the machine is shared); the CPU bound
/// is the second.
#[cfg(target_os = "linux")]
#[test]
fn devices_as_inputs_fail_at_once_in_bounded_memory() {
    let limit_kib = (chainbeam::scene::MAX_INPUT_BYTES / 1024) as i64;
    let dir = Dir::new();
    let riser = std::fs::read_to_string(scene("riser_5.toml")).unwrap();
    let sc = scene("riser_5.toml");
    let sc = sc.to_str().unwrap();
    for dev in ["/dev/zero", "/dev/urandom"] {
        let series_scene = dir.write(
            "series.toml",
            &format!("{riser}\n[[loads.point]]\nnode = 3\nseries = \"{dev}\"\n"),
        );
        let series_scene = series_scene.to_str().unwrap();
        let cases: Vec<Vec<&str>> = vec![
            vec!["simulate", dev],
            vec!["gradient", dev],
            vec!["optimize", dev],
            vec!["explore", dev],
            vec!["mpc", dev],
            vec!["simulate", sc, "--controls", dev],
            vec!["gradient", sc, "--controls", dev],
            vec!["mpc", sc, "--model", dev],
            vec!["simulate", series_scene],
            vec!["mpc", sc, "--model", series_scene],
        ];
        for args in &cases {
            let u = run_measured(args);
            let shown = args.join(" ");
            eprintln!(
                "{shown}: status {}, peak RSS {} KiB, CPU {:.3} s, wall {:.3} s",
                u.status, u.max_rss_kib, u.cpu_seconds, u.wall_seconds
            );
            assert_eq!(u.status, 1, "{shown}: {}", u.stderr);
            assert_eq!(u.stderr.lines().count(), 1, "{shown}: {}", u.stderr);
            assert!(u.stderr.contains(dev), "{shown}: {}", u.stderr);
            assert!(u.cpu_seconds < 1.0, "{shown}: {} s of CPU", u.cpu_seconds);
            // A hang guard, not a speed test: generous, since the machine may be loaded.
            assert!(u.wall_seconds < 120.0, "{shown}: {} s", u.wall_seconds);
            assert!(u.max_rss_kib < limit_kib, "{shown}: {} KiB", u.max_rss_kib);
        }
    }
}

/// A regular file over the input limit is refused by its size, before a byte
/// is read, as a scene, a `--controls` file and a series file (sparse files, so the test writes
/// nothing); the message names the file and the limit.
#[cfg(unix)]
#[test]
fn inputs_over_the_limit_are_refused_by_their_size() {
    let dir = Dir::new();
    let big = dir.join("big.txt");
    std::fs::File::create(&big)
        .unwrap()
        .set_len(chainbeam::scene::MAX_INPUT_BYTES + 1)
        .unwrap();
    let riser = std::fs::read_to_string(scene("riser_5.toml")).unwrap();
    let with_series = dir.write(
        "series.toml",
        &format!("{riser}\n[[loads.point]]\nnode = 3\nseries = \"big.txt\"\n"),
    );
    let sc = scene("riser_5.toml");
    let (big, sc, with_series) = (
        big.to_str().unwrap(),
        sc.to_str().unwrap(),
        with_series.to_str().unwrap(),
    );
    for args in [
        vec!["optimize", big],
        vec!["gradient", sc, "--controls", big],
        vec!["simulate", with_series],
    ] {
        let o = run(&args);
        assert_one_error(
            &o,
            &["big.txt", "over the limit of 1.0 GiB (1073741824 bytes)"],
        );
    }
}

/// An output name of 250 and of 255 bytes (the longest a file name may be) is
/// written; before, the temporary name `.NAME.PID.I.tmp` passed the 255-byte limit and the run
/// failed with "File name too long".
#[test]
fn the_longest_output_names_are_written() {
    let dir = Dir::new();
    let sc = scene("riser_5.toml");
    for len in [250, 255] {
        let name = format!("{}.json", "g".repeat(len - 5));
        let out = dir.join(&name);
        let o = run(&[
            "gradient".as_ref(),
            sc.as_os_str(),
            "-o".as_ref(),
            out.as_os_str(),
        ]);
        assert_success(&o);
        let written = std::fs::read_to_string(&out).unwrap();
        assert!(written.contains("\"gradient\""), "{written}");
        assert_eq!(dir.files(), std::slice::from_ref(&name));
        std::fs::remove_file(out).unwrap();
    }
}

/// `optimize`'s default is `--method auto`, a documented choice reported in
/// the JSON (`method`, `method_choice`) and by `--progress`, and never worse than L-BFGS, the
/// former default (the reference: the same scene with `--method lbfgs`):
/// - the riser's per-step c_sum with effort (Table 3.4's control, n = 10, 11 parameters ≤
///   4(2n + 1) = 84) goes to the condensed solver, which converges to J no higher than L-BFGS's;
/// - the same without effort and without a bound, from u = 0, folds the beam under every method
///   (docs/conventions.md: the forces run to 10⁴ N): the condensed run does not converge, L-BFGS
///   runs from the same start as the fallback, the lower of the two is kept, the JSON says so,
///   and the exit status is still 3 (not converged, never reported as success);
/// - a spatial scene goes to L-BFGS (the structured solvers are planar).
///
/// Before, the default was L-BFGS whatever the problem and no choice was reported.
#[test]
fn the_default_method_is_chosen_and_reported() {
    let dir = Dir::new();
    let riser = std::fs::read_to_string(scene("riser_5.toml")).unwrap();
    // control.values as one number for a per-step control (item 7): 11 equal values.
    let per_step = riser
        .replace("kind = \"constant\"", "kind = \"per-step\"")
        .replace("values = [0.0]", "values = 0.0")
        .replace("kind = \"final\"", "kind = \"sum\"");
    assert_ne!(per_step, riser);
    let sc = dir.write("per_step.toml", &per_step);
    let optimize = |extra: &[&str]| {
        let mut args = vec!["optimize", sc.to_str().unwrap()];
        args.extend_from_slice(extra);
        run(&args)
    };
    // Converged: the condensed solver, no fallback.
    let o = optimize(&["--effort", "1e-3", "--progress"]);
    assert_success(&o);
    let auto = json(&o);
    let lbfgs = json(&optimize(&["--effort", "1e-3", "--method", "lbfgs"]));
    assert_eq!(auto["method"], "condensed");
    let choice = &auto["method_choice"];
    assert_eq!(choice["chosen"], "condensed");
    let why = choice["reason"].as_str().unwrap();
    assert!(why.contains("11 parameters") && why.contains("84"), "{why}");
    assert!(choice.get("fallback").is_none());
    assert!(
        stderr(&o).starts_with("method auto: condensed: "),
        "{}",
        stderr(&o)
    );
    let (ja, jl) = (
        auto["objective"].as_f64().unwrap(),
        lbfgs["objective"].as_f64().unwrap(),
    );
    println!("effort 1e-3: auto J = {ja:e}, lbfgs J = {jl:e}");
    assert!(ja <= jl * (1.0 + 1e-12), "auto {ja} > lbfgs {jl}");
    // Not converged by any method: the fallback, reported, and exit status 3.
    let o = optimize(&["--progress"]);
    assert_eq!(o.status.code(), Some(3), "{}", stderr(&o));
    let auto = json(&o);
    let lb = optimize(&["--method", "lbfgs"]);
    assert_eq!(lb.status.code(), Some(3), "{}", stderr(&lb));
    let lbfgs = json(&lb);
    assert_eq!(auto["converged"], false);
    let fallback = &auto["method_choice"]["fallback"];
    assert_eq!(fallback["method"], "lbfgs");
    let why = fallback["why"].as_str().unwrap();
    assert!(
        why.starts_with("condensed") && why.contains("not converged"),
        "{why}"
    );
    assert_eq!(auto["method"], fallback["kept"]);
    let err = stderr(&o);
    assert!(err.contains("so lbfgs ran from the same start"), "{err}");
    let (ja, jl) = (
        auto["objective"].as_f64().unwrap(),
        lbfgs["objective"].as_f64().unwrap(),
    );
    println!(
        "unbounded: auto J = {ja:e} ({}), lbfgs J = {jl:e}",
        auto["method"]
    );
    assert!(ja <= jl, "auto {ja} > lbfgs {jl}");
    // Spatial: the condensed solver, which runs the spatial model, and the
    // reason says why (a spatial problem of 1 parameter, at most 4(2n + 1)).
    let o = run(&["optimize".as_ref(), scene("oblique_riser.toml").as_os_str()]);
    assert_success(&o);
    let v = json(&o);
    assert_eq!(v["model"], "spatial");
    assert_eq!(v["method"], "condensed");
    assert_eq!(v["method_choice"]["chosen"], "condensed");
    let why = v["method_choice"]["reason"].as_str().unwrap();
    assert!(
        why.contains("spatial control problem") && why.contains("at most"),
        "{why}"
    );
}

/// `control.values` as one number stands for every value equal (N + 1 for a
/// per-step control) and left out for zeros: `gradient` reports the controls it evaluated at,
/// which must be the N + 1 = 11 values written out (the reference: the same scene with the array
/// typed in full gives the same JSON). Before, both scenes were refused.
#[test]
fn control_values_may_be_one_number_or_left_out() {
    let dir = Dir::new();
    let riser = std::fs::read_to_string(scene("riser_5.toml")).unwrap();
    let per_step = |values: &str| {
        riser
            .replace("kind = \"constant\"", "kind = \"per-step\"")
            .replace("values = [0.0]", values)
    };
    for (short, full) in [
        (
            "values = 1.5",
            format!("values = [{}]", ["1.5"; 11].join(", ")),
        ),
        ("", format!("values = [{}]", ["0.0"; 11].join(", "))),
    ] {
        let a = dir.write("short.toml", &per_step(short));
        let b = dir.write("full.toml", &per_step(&full));
        let oa = run(&["gradient".as_ref(), a.as_os_str()]);
        let ob = run(&["gradient".as_ref(), b.as_os_str()]);
        assert_success(&oa);
        assert_success(&ob);
        assert_eq!(json(&oa), json(&ob), "{short:?}");
        assert_eq!(numbers(&json(&oa), "controls").len(), 11);
    }
}
