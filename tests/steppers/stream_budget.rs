//! The stored-trajectory budget (`MAX_TRAJECTORY_BYTES`, 8 GiB) is checked where a trajectory is
//! stored, not when a scene is read: a scene whose trajectory is over the budget is valid, a
//! streamed run of it (the library's `simulate_streaming`, `chainbeam simulate --columns`)
//! starts and writes its rows, and every run that stores one or writes it whole (`simulate`,
//! `simulate` with given controls, the adjoint and the optimisers through `ControlProblem`,
//! `chainbeam gradient`, `chainbeam simulate` without `--columns`) is refused at once with the
//! message the scene check gave before:
//! typed (`Error::Scene` with the key `time.steps`), the bytes needed, the limit and the largest N
//! that fits.
//!
//! Reference: the hand count of docs/scene-format.md "Size limits" (48·n + 48 bytes per step of a
//! riser, `tests/scene/scene_files.rs::trajectory_budget_is_exact`): n = 19, N = 10⁷ needs 8.9 GiB and
//! at most 8 947 847 steps fit. A whole streamed run of 10⁷ steps would take minutes, so the
//! streamed runs are stopped after their first rows: what is shown is that the streaming path is
//! accepted (no refusal before or at its start), not the 10⁷ steps.

use crate::common;

use std::io::{BufRead, BufReader};
use std::process::{Command, Stdio};

use chainbeam::*;
use common::*;

const N: usize = 10_000_000;

/// The riser of `tests/hostile_scenes/trajectory_over_memory_budget.toml`: n = 19, N = 10⁷.
fn scene_text() -> String {
    format!(
        "[beam]\npendulums = 19\nlength = 1.0\nmass = 1.0\nstiffness = 1000.0\n\
         support = \"riser\"\nbase_stiffness = 2000.0\ntip_stiffness = 2000.0\n\n\
         [[loads.point]]\nnode = 3\nforce = 2.0\n\n[time]\nstep = 0.01\nsteps = {N}\n"
    )
}

/// The pieces of the budget's message (the scene check's wording, unchanged).
const MESSAGE: [&str; 4] = [
    "key `time.steps`",
    "the trajectory of N = 10000000 steps of n = 19 pendulums needs 8.9 GiB",
    "over the memory limit of 8.0 GiB",
    "(at most 8947847 for this beam)",
];

fn assert_budget_error(e: &Error, what: &str) {
    match e {
        Error::Scene(se) => assert_eq!(se.key(), Some("time.steps"), "{what}: {se}"),
        other => panic!("{what}: not a scene error: {other:?}"),
    }
    let msg = e.to_string();
    for m in MESSAGE {
        assert!(msg.contains(m), "{what}: {msg:?} lacks {m:?}");
    }
}

/// Stops a streamed run after its first `rows` states.
struct FirstRows {
    rows: usize,
    seen: Vec<(usize, f64)>,
}

impl StepObserver for FirstRows {
    type Error = &'static str;
    fn observe<const DIM: usize>(&mut self, s: &mut StepView<'_, DIM>) -> Result<(), Self::Error> {
        self.seen.push((s.k(), s.moment_vector()[1]));
        if self.seen.len() == self.rows {
            return Err("enough rows");
        }
        Ok(())
    }
}

#[test]
fn a_scene_over_the_trajectory_budget_streams_and_is_refused_where_it_is_stored() {
    let t0 = std::time::Instant::now();
    // Valid: the budget is not a rule of the scene.
    let scene = Scene::from_toml_str(&scene_text()).unwrap();
    assert_eq!(scene.time.steps, N);
    let e = scene.check_stored_trajectory().unwrap_err();
    assert_budget_error(&Error::Scene(e), "check_stored_trajectory");
    // The runs that store it refuse it, before anything of size N is stored (the time bound
    // below is a hang guard, generous for a loaded machine, not a speed test).
    assert_budget_error(&simulate(&scene).unwrap_err(), "simulate");
    let u = vec![0.0; N + 1];
    assert_budget_error(
        &simulate(SimulateInput::new(&scene).controls(&u)).unwrap_err(),
        "simulate with given controls",
    );
    assert_budget_error(
        &ControlProblem::builder(&scene).build_in::<2>().unwrap_err(),
        "ControlProblem (adjoint, optimisers)",
    );
    assert!(
        t0.elapsed().as_secs_f64() < 60.0,
        "refused at once: {:?}",
        t0.elapsed()
    );
    // The streamed run starts and hands over its states: the same numbers as a stored run of a
    // scene under the budget (its first 200 steps), bit for bit.
    let mut first = FirstRows {
        rows: 201,
        seen: Vec::new(),
    };
    match simulate_streaming(&scene, StreamControls::Scene, &mut first) {
        Err(StreamError::Observer("enough rows")) => {}
        other => panic!("the streamed run did not run: {other:?}"),
    }
    let mut short = scene.clone();
    short.time.steps = 200;
    let stored = simulate(&short).unwrap();
    let streamed: Vec<f64> = first.seen.iter().map(|s| s.1).collect();
    assert_eq!(first.seen.last().unwrap().0, 200);
    assert_eq!(streamed, stored.moment());
    assert!(
        stored.moment().iter().any(|m| *m != 0.0),
        "the load bends it"
    );
}

/// The command line: `simulate --columns` streams its rows, so the scene is accepted and its rows
/// come out; `simulate` without `--columns` writes the whole trajectory and `gradient` (the
/// adjoint) keeps per-step quantities: both are refused with the budget's message naming the
/// file and `time.steps`.
#[test]
fn the_command_line_streams_chosen_columns_and_refuses_the_whole_trajectory() {
    let dir = Dir::new();
    let path = dir.write("long.toml", &scene_text());
    let mut child = Command::new(env!("CARGO_BIN_EXE_chainbeam"))
        .arg("simulate")
        .arg(&path)
        .args(["--columns", "t,moment"])
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let mut lines = BufReader::new(child.stdout.take().unwrap()).lines();
    let header = lines.next().expect("a header").unwrap();
    let rows: Vec<String> = lines.by_ref().take(50).map(|l| l.unwrap()).collect();
    // Closing the pipe stops the run (`| head`: exit status 0, nothing on stderr).
    drop(lines);
    let out = child.wait_with_output().unwrap();
    let err = String::from_utf8(out.stderr).unwrap();
    assert!(out.status.success(), "{:?} {err}", out.status);
    assert!(!err.contains("time.steps"), "{err}");
    assert_eq!(header, "t,moment");
    assert_eq!(rows.len(), 50);
    // Rows k = 0..49 in order: t_k = k h, written as the shortest decimal of the double.
    for (k, row) in rows.iter().enumerate() {
        let t: f64 = row.split(',').next().unwrap().parse().unwrap();
        assert_eq!(t, k as f64 * 0.01, "row {k}");
    }
    let mut needles = vec!["long.toml"];
    needles.extend(MESSAGE);
    for sub in ["simulate", "gradient"] {
        let o = run(&[sub.as_ref(), path.as_os_str()]);
        assert_one_line(&o, 1, &needles);
        assert!(o.stdout.is_empty(), "{sub}: nothing written");
    }
}
