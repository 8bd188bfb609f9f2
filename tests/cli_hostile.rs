//! Hostile command lines (tests/hostile/cases.toml) and the message each must produce: a clear
//! error naming the file, key or flag and the reason, never a panic, never a success.

mod common;

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
    }
}
