//! Property tests on random scene files (docs/scene-format.md), valid and invalid.
//!
//! - A valid file parses to the scene it describes, round-trips through `Scene::to_toml_string`,
//!   and simulates without panic: either the constraints |qᵢ| = 1 hold to 1e-10 at every step with
//!   finite energy and moment, or the run stops with a typed runtime error (Newton not converging,
//!   a folded beam, ...), never a scene or argument error.
//! - A file with one deliberate defect (unknown key, missing key, wrong type, NaN or infinity,
//!   negative value, node out of range, wrong number of values) is an error naming the key.
//! - Arbitrary truncations and byte edits never panic.
//! - The `chainbeam` binary on such files exits 0 or 1 with one message, never a panic.
//!
//! Small beams (n ≤ 5) and short horizons (N ≤ 20) keep the whole file well under a second.

use chainbeam::{simulate, ControlProblem, Error, Scene, SceneError};
use proptest::collection::vec;
use proptest::prelude::*;
use proptest::test_runner::TestCaseError;

/// One `key = value` line.
#[derive(Clone, Debug)]
struct Entry {
    key: &'static str,
    value: String,
    /// Removing it makes the file invalid.
    required: bool,
    /// A number that must be finite (all numbers are).
    number: bool,
    /// Must be > 0 (or ≥ 0 for springs and drag: a negative value is invalid either way).
    nonneg: bool,
}

/// One `[table]` or `[[array.of.tables]]` with its entries.
#[derive(Clone, Debug)]
struct Section {
    header: String,
    /// The prefix of the keys in error messages, e.g. `beam` or `loads.point[1]`.
    path: String,
    entries: Vec<Entry>,
}

/// A scene file as sections, so that defects can be put in exactly one place.
#[derive(Clone, Debug)]
struct SceneFile {
    sections: Vec<Section>,
    n: usize,
    steps: usize,
}

impl SceneFile {
    fn render(&self) -> String {
        let mut s = String::new();
        for sec in &self.sections {
            s.push_str(&sec.header);
            s.push('\n');
            for e in &sec.entries {
                s.push_str(&format!("{} = {}\n", e.key, e.value));
            }
            s.push('\n');
        }
        s
    }

    fn section_mut(&mut self, header: &str) -> Option<&mut Section> {
        self.sections.iter_mut().find(|s| s.header == header)
    }
}

fn entry(key: &'static str, value: String, required: bool, number: bool, nonneg: bool) -> Entry {
    Entry {
        key,
        value,
        required,
        number,
        nonneg,
    }
}

/// A float written as TOML: sometimes as an integer when it is one.
fn num(x: f64) -> String {
    format!("{x:?}")
}

fn num_or_array(scalar: bool, values: &[f64]) -> String {
    if scalar {
        num(values[0])
    } else {
        let items: Vec<String> = values.iter().map(|&v| num(v)).collect();
        format!("[{}]", items.join(", "))
    }
}

const SUPPORTS: [&str; 4] = ["cantilever", "riser", "fixed-fixed", "pinned-pinned"];

/// A point load: node, force, optional (start, duration) window.
type Point = (usize, f64, Option<(f64, f64)>);

#[derive(Clone, Debug)]
struct Loads {
    gravity: Option<f64>,
    drag: Option<f64>,
    points: Vec<Point>,
}

#[derive(Clone, Debug)]
struct ControlSpec {
    node: Option<usize>,
    /// 0: constant, 1: per-step, 2: piecewise.
    kind: usize,
    /// Number of pieces of a piecewise control (1..=N).
    pieces: usize,
    values: Vec<f64>,
}

/// Random valid scene files: n ≤ 5, N ≤ 20, physically moderate values.
fn valid_scene() -> impl Strategy<Value = SceneFile> {
    (1usize..=5, 1usize..=20).prop_flat_map(|(n, steps)| {
        let beam = (
            vec(0.5f64..2.0, n),
            vec(0.5f64..2.0, n),
            vec(100.0f64..2000.0, n.max(2) - 1),
            (any::<bool>(), any::<bool>(), any::<bool>()),
            0usize..4,
            (100.0f64..3000.0, 100.0f64..3000.0, any::<bool>()),
            any::<bool>(),
        );
        let loads = (
            prop::option::of(prop_oneof![Just(0.0), Just(9.81), -2.0f64..2.0]),
            prop::option::of(0.0f64..20.0),
            vec(
                (
                    1usize..=n,
                    // Mostly moderate loads; sometimes violent ones that fold the beam or stall
                    // the Newton solve (typed errors).
                    prop_oneof![4 => -5.0f64..5.0, 1 => -5000.0f64..5000.0],
                    prop::option::of((0.0f64..0.05, 0.01f64..0.2)),
                ),
                0..3,
            ),
        )
            .prop_map(|(gravity, drag, points)| Loads {
                gravity,
                drag,
                points,
            });
        let control = prop::option::of(
            (
                prop::option::of(1usize..=n),
                (0usize..3, 1usize..=steps),
                vec(-5.0f64..5.0, steps + 1),
            )
                .prop_map(|(node, (kind, pieces), values)| ControlSpec {
                    node,
                    kind,
                    pieces,
                    values,
                }),
        );
        let objective = prop::option::of(prop_oneof![Just("final"), Just("sum")]);
        (
            Just((n, steps)),
            beam,
            loads,
            control,
            objective,
            prop_oneof![4 => 0.001f64..0.01, 1 => 0.01f64..0.1],
        )
            .prop_map(|((n, steps), beam, loads, control, objective, h)| {
                let (l, m, k, (l_scalar, m_scalar, k_scalar), support, ends, reaction) = beam;
                let (base, tip, give_ends) = ends;
                let support = SUPPORTS[support];
                let mut beam_entries = vec![
                    entry("pendulums", n.to_string(), true, false, true),
                    entry("length", num_or_array(l_scalar, &l), true, true, true),
                    entry("mass", num_or_array(m_scalar, &m), true, true, true),
                    entry(
                        "stiffness",
                        if k_scalar {
                            num(k[0])
                        } else {
                            num_or_array(false, &k[..n - 1])
                        },
                        true,
                        true,
                        true,
                    ),
                    entry("support", format!("\"{support}\""), true, false, false),
                ];
                // With an array of interior springs the end springs must be given.
                if give_ends || !k_scalar {
                    beam_entries.push(entry("base_stiffness", num(base), false, true, true));
                    beam_entries.push(entry("tip_stiffness", num(tip), false, true, true));
                }
                if reaction && matches!(support, "fixed-fixed" | "pinned-pinned") {
                    beam_entries.push(entry("reaction_force", "true".into(), false, false, false));
                }
                let mut sections = vec![Section {
                    header: "[beam]".into(),
                    path: "beam".into(),
                    entries: beam_entries,
                }];
                let mut load_entries = Vec::new();
                if let Some(g) = loads.gravity {
                    load_entries.push(entry("gravity", num(g), false, true, false));
                }
                if let Some(d) = loads.drag {
                    load_entries.push(entry("drag", num(d), false, true, true));
                }
                if !load_entries.is_empty() || !loads.points.is_empty() {
                    sections.push(Section {
                        header: "[loads]".into(),
                        path: "loads".into(),
                        entries: load_entries,
                    });
                }
                for (i, (node, force, window)) in loads.points.iter().enumerate() {
                    let mut e = vec![
                        entry("node", node.to_string(), true, false, true),
                        entry("force", num(*force), true, true, false),
                    ];
                    if let Some((start, len)) = window {
                        e.push(entry("start", num(*start), false, true, false));
                        e.push(entry("end", num(start + len), false, true, false));
                    }
                    sections.push(Section {
                        header: "[[loads.point]]".into(),
                        path: format!("loads.point[{i}]"),
                        entries: e,
                    });
                }
                sections.push(Section {
                    header: "[time]".into(),
                    path: "time".into(),
                    entries: vec![
                        entry("step", num(h), true, true, true),
                        entry("steps", steps.to_string(), true, false, true),
                    ],
                });
                if let Some(c) = control {
                    let mut e = Vec::new();
                    // The reaction-force variant needs the control at the tip (the library
                    // checks this when it builds the chain, not in `Scene::validate`).
                    let tip_only = reaction && matches!(support, "fixed-fixed" | "pinned-pinned");
                    if let Some(node) = c.node.map(|k| if tip_only { n } else { k }) {
                        e.push(entry("node", node.to_string(), false, false, true));
                    }
                    let (kind, values) = match c.kind {
                        0 => ("constant", &c.values[..1]),
                        1 => ("per-step", &c.values[..]),
                        _ => ("piecewise", &c.values[..c.pieces]),
                    };
                    e.push(entry("kind", format!("\"{kind}\""), true, false, false));
                    // Not required: an absent `control.values` means zeros.
                    e.push(entry(
                        "values",
                        num_or_array(false, values),
                        false,
                        false,
                        false,
                    ));
                    sections.push(Section {
                        header: "[control]".into(),
                        path: "control".into(),
                        entries: e,
                    });
                }
                if let Some(kind) = objective {
                    sections.push(Section {
                        header: "[objective]".into(),
                        path: "objective".into(),
                        entries: vec![entry("kind", format!("\"{kind}\""), true, false, false)],
                    });
                }
                SceneFile { sections, n, steps }
            })
    })
}

/// A deliberate defect and the key its error must name.
#[derive(Clone, Debug)]
enum Defect {
    UnknownKey,
    MissingKey,
    WrongType,
    NonFinite(&'static str),
    Negative,
    NodeOutOfRange(bool),
    WrongCount,
}

fn defect() -> impl Strategy<Value = (Defect, usize)> {
    (
        prop_oneof![
            Just(Defect::UnknownKey),
            Just(Defect::MissingKey),
            Just(Defect::WrongType),
            Just(Defect::NonFinite("nan")),
            Just(Defect::NonFinite("inf")),
            Just(Defect::NonFinite("-inf")),
            Just(Defect::Negative),
            Just(Defect::NodeOutOfRange(false)),
            Just(Defect::NodeOutOfRange(true)),
            Just(Defect::WrongCount),
        ],
        any::<usize>(),
    )
}

/// Applies `defect` at a place chosen by `pick`; returns the key the error must name.
fn apply(file: &mut SceneFile, defect: &Defect, pick: usize) -> String {
    // All (section, entry) places matching a predicate.
    let places = |f: &SceneFile, pred: &dyn Fn(&Section, &Entry) -> bool| -> Vec<(usize, usize)> {
        let mut v = Vec::new();
        for (si, s) in f.sections.iter().enumerate() {
            for (ei, e) in s.entries.iter().enumerate() {
                if pred(s, e) {
                    v.push((si, ei));
                }
            }
        }
        v
    };
    let choose = |v: Vec<(usize, usize)>| v[pick % v.len()];
    match defect {
        Defect::UnknownKey => {
            let si = pick % file.sections.len();
            let sec = &mut file.sections[si];
            sec.entries
                .insert(0, entry("colour", "1".into(), false, false, false));
            format!("{}.colour", sec.path)
        }
        Defect::MissingKey => {
            let (si, ei) = choose(places(file, &|_, e| e.required));
            let sec = &mut file.sections[si];
            let e = sec.entries.remove(ei);
            format!("{}.{}", sec.path, e.key)
        }
        Defect::WrongType => {
            let (si, ei) = choose(places(file, &|_, e| e.key != "reaction_force"));
            let sec = &mut file.sections[si];
            let e = &mut sec.entries[ei];
            e.value = if e.value.starts_with('"') {
                "3".into()
            } else {
                "\"oops\"".into()
            };
            format!("{}.{}", sec.path, e.key)
        }
        Defect::NonFinite(word) => {
            let (si, ei) = choose(places(file, &|_, e| e.number));
            let sec = &mut file.sections[si];
            let e = &mut sec.entries[ei];
            e.value = (*word).into();
            format!("{}.{}", sec.path, e.key)
        }
        Defect::Negative => {
            let (si, ei) = choose(places(file, &|_, e| e.nonneg));
            let sec = &mut file.sections[si];
            let e = &mut sec.entries[ei];
            e.value = if e.number { "-1.5".into() } else { "-1".into() };
            format!("{}.{}", sec.path, e.key)
        }
        Defect::NodeOutOfRange(above) => {
            let n = file.n;
            let bad = if *above { n + 1 + pick % 3 } else { 0 };
            let nodes = places(file, &|_, e| e.key == "node");
            if nodes.is_empty() {
                // No node key yet: add a point load at the bad node.
                let at = file
                    .sections
                    .iter()
                    .position(|s| s.header == "[loads]")
                    .map_or(1, |i| i + 1);
                file.sections.insert(
                    at,
                    Section {
                        header: "[[loads.point]]".into(),
                        path: "loads.point[0]".into(),
                        entries: vec![
                            entry("node", bad.to_string(), true, false, true),
                            entry("force", "1.0".into(), true, true, false),
                        ],
                    },
                );
                return "loads.point[0].node".into();
            }
            let (si, ei) = choose(nodes);
            let sec = &mut file.sections[si];
            sec.entries[ei].value = bad.to_string();
            format!("{}.node", sec.path)
        }
        Defect::WrongCount => {
            let steps = file.steps;
            let n = file.n;
            if let Some(c) = file.section_mut("[control]") {
                let per_step = c.entries.iter().any(|e| e.value == "\"per-step\"");
                let piecewise = c.entries.iter().any(|e| e.value == "\"piecewise\"");
                let count = if piecewise {
                    // more pieces than steps
                    steps + 1 + pick % 2
                } else if per_step {
                    steps + 2 + pick % 2
                } else {
                    2 + pick % 3
                };
                let values = c.entries.iter_mut().find(|e| e.key == "values");
                if let Some(v) = values {
                    v.value = num_or_array(false, &vec![0.5; count]);
                    return "control.values".into();
                }
            }
            let beam = file.section_mut("[beam]").expect("[beam]");
            let key = if pick.is_multiple_of(2) {
                "length"
            } else {
                "mass"
            };
            let e = beam.entries.iter_mut().find(|e| e.key == key).expect(key);
            e.value = num_or_array(false, &vec![1.0; n + 1]);
            format!("beam.{key}")
        }
    }
}

/// Max over steps and pendulums of ||q_i| − 1|.
fn constraint_error(traj: &chainbeam::Trajectory<f64, 2>) -> f64 {
    let mut worst: f64 = 0.0;
    for k in 0..=traj.steps() {
        for q in traj.q(k) {
            worst = worst.max(((q[0] * q[0] + q[1] * q[1]).sqrt() - 1.0).abs());
        }
    }
    worst
}

fn check_valid(file: &SceneFile) -> Result<(), TestCaseError> {
    let text = file.render();
    let scene = Scene::from_toml_str(&text)
        .map_err(|e| TestCaseError::fail(format!("valid file rejected: {e}\n{text}")))?;
    prop_assert_eq!(scene.n(), file.n);
    prop_assert_eq!(scene.time.steps, file.steps);
    let again = Scene::from_toml_str(&scene.to_toml_string());
    prop_assert_eq!(again.as_ref(), Ok(&scene));
    match simulate(&scene).and_then(|t| t.into_planar()) {
        Ok(traj) => {
            prop_assert_eq!(traj.steps(), file.steps);
            let err = constraint_error(&traj);
            prop_assert!(err <= 1e-10, "constraint error {err:e}\n{text}");
            for k in 0..=traj.steps() {
                prop_assert!(traj.energy[k].is_finite() && traj.moment[k].is_finite());
                prop_assert!(traj.positions(k).iter().flatten().all(|x| x.is_finite()));
            }
            // The adjoint runs on every scene that simulates (the CLI's `gradient`).
            let theta: Vec<f64> = scene
                .control
                .as_ref()
                .map_or(vec![0.0], |c| c.values.clone());
            let problem = ControlProblem::builder(&scene)
                .build_in::<2>()
                .map_err(|e| TestCaseError::fail(format!("{e}\n{text}")))?;
            match problem.value_and_gradient(&theta) {
                Ok((c, g)) => {
                    prop_assert!(c.is_finite() && c >= 0.0, "objective {c}");
                    prop_assert_eq!(g.len(), theta.len());
                    prop_assert!(g.iter().all(|x| x.is_finite()), "{g:?}");
                }
                // The scene's own controls simulate, but without a [control] the gradient runs
                // with u = 0, which may fail like any simulation.
                Err(Error::NewtonNotConverged { .. } | Error::Folded { .. }) => {}
                Err(e) => return Err(TestCaseError::fail(format!("gradient: {e:?}\n{text}"))),
            }
        }
        Err(
            e @ (Error::NewtonNotConverged { .. }
            | Error::Folded { .. }
            | Error::SingularSystem { .. }
            | Error::NonFinite { .. }),
        ) => {
            prop_assert!(e.to_string().contains("step"), "{e}");
        }
        Err(e) => {
            return Err(TestCaseError::fail(format!(
                "unexpected error {e:?}\n{text}"
            )))
        }
    }
    Ok(())
}

fn expect_error(text: &str, key: &str) -> Result<SceneError, TestCaseError> {
    match Scene::from_toml_str(text) {
        Ok(_) => Err(TestCaseError::fail(format!(
            "defective file accepted (key {key}):\n{text}"
        ))),
        Err(e) => Ok(e),
    }
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 64, ..ProptestConfig::default() })]

    #[test]
    fn valid_scene_files_parse_and_simulate(file in valid_scene()) {
        check_valid(&file)?;
    }

    #[test]
    fn defective_scene_files_name_the_key(file in valid_scene(), (d, pick) in defect()) {
        let mut file = file;
        let key = apply(&mut file, &d, pick);
        let text = file.render();
        let err = expect_error(&text, &key)?;
        let msg = err.to_string();
        let named = err.key().unwrap_or("");
        // The error names the defective key (with an index for arrays, `beam.length[2]`), or, for
        // a missing table entry that other keys depend on, the key that needed it.
        let ok = named.starts_with(&key)
            || (matches!(d, Defect::MissingKey) && msg.contains(key.rsplit('.').next().unwrap_or("")));
        prop_assert!(ok, "{d:?}: expected key `{key}`, got {err:?} ({msg})\n{text}");
        prop_assert!(!msg.contains('\n'), "multi-line message {msg:?}");
    }

    #[test]
    fn arbitrary_edits_never_panic(
        file in valid_scene(),
        cut in any::<usize>(),
        edits in vec((any::<usize>(), any::<u8>()), 0..4),
    ) {
        let mut bytes = file.render().into_bytes();
        for (at, b) in edits {
            let at = at % bytes.len();
            bytes[at] = b;
        }
        bytes.truncate(cut % (bytes.len() + 1));
        let text = String::from_utf8_lossy(&bytes);
        if let Ok(scene) = Scene::from_toml_str(&text) {
            prop_assert!(scene.validate().is_ok());
            // A scene that still parses may be anything valid: it must not panic either.
            if scene.n() <= 5 && scene.time.steps <= 20 {
                let _ = simulate(&scene);
            }
        }
    }
}

proptest! {
    // Each case starts a process: fewer cases.
    #![proptest_config(ProptestConfig { cases: 16, ..ProptestConfig::default() })]

    #[test]
    fn binary_never_panics(file in valid_scene(), (d, pick) in defect(), broken in any::<bool>()) {
        let mut file = file;
        if broken {
            apply(&mut file, &d, pick);
        }
        let dir = tempfile::tempdir().expect("temporary directory");
        let path = dir.path().join("scene.toml");
        std::fs::write(&path, file.render()).expect("write");
        for sub in ["simulate", "gradient"] {
            let out = assert_cmd::cargo::cargo_bin_cmd!("chainbeam")
                .arg(sub)
                .arg(&path)
                .output()
                .expect("run chainbeam");
            let err = String::from_utf8_lossy(&out.stderr);
            match out.status.code() {
                Some(0) => prop_assert!(!broken, "{sub} accepted a broken file"),
                Some(1) => {
                    prop_assert_eq!(err.lines().count(), 1, "{}", err);
                    prop_assert!(err.contains("scene.toml"), "{}", err);
                }
                other => prop_assert!(false, "{sub}: exit {other:?}, stderr {err}"),
            }
            prop_assert!(!err.contains("panicked"), "{}", err);
        }
    }
}
