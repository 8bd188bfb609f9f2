//! Helpers shared by the command-line tests (`tests/cli_*.rs`).
#![allow(dead_code)]

use std::ffi::OsStr;
use std::fs;
use std::path::{Path, PathBuf};
use std::process::Output;

use assert_cmd::cargo::cargo_bin_cmd;

/// A temporary directory that is removed at the end of the test.
pub struct Dir(tempfile::TempDir);

impl Dir {
    pub fn new() -> Self {
        Dir(tempfile::tempdir().expect("temporary directory"))
    }
    pub fn path(&self) -> &Path {
        self.0.path()
    }
    pub fn join(&self, name: &str) -> PathBuf {
        self.0.path().join(name)
    }
    pub fn write(&self, name: &str, text: &str) -> PathBuf {
        let p = self.0.path().join(name);
        fs::write(&p, text).expect("write file");
        p
    }
    /// File names in the directory, sorted.
    pub fn files(&self) -> Vec<String> {
        let mut v: Vec<String> = fs::read_dir(self.path())
            .expect("read dir")
            .map(|e| e.expect("entry").file_name().to_string_lossy().into_owned())
            .collect();
        v.sort();
        v
    }
}

/// Runs the binary with these arguments.
pub fn run<S: AsRef<OsStr>>(args: &[S]) -> Output {
    cargo_bin_cmd!("chainbeam")
        .args(args)
        .output()
        .expect("run chainbeam")
}

pub fn stdout(o: &Output) -> String {
    String::from_utf8(o.stdout.clone()).expect("utf-8 stdout")
}

pub fn stderr(o: &Output) -> String {
    String::from_utf8(o.stderr.clone()).expect("utf-8 stderr")
}

pub fn assert_success(o: &Output) {
    assert!(
        o.status.success(),
        "exit {:?}, stderr: {}",
        o.status.code(),
        stderr(o)
    );
}

/// Exit status `code`, exactly one line on stderr starting with `error: `, no panic, containing
/// every one of `needles`.
pub fn assert_one_line(o: &Output, code: i32, needles: &[&str]) -> String {
    let err = stderr(o);
    assert_eq!(o.status.code(), Some(code), "stderr: {err}");
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

/// Exit status 1, nothing on stdout, one error line containing every one of `needles`.
pub fn assert_one_error(o: &Output, needles: &[&str]) -> String {
    assert!(o.stdout.is_empty(), "stdout not empty: {}", stdout(o));
    assert_one_line(o, 1, needles)
}

pub fn json_text(text: &str) -> serde_json::Value {
    serde_json::from_str(text).expect("valid JSON")
}

pub fn json(o: &Output) -> serde_json::Value {
    serde_json::from_slice(&o.stdout).expect("valid JSON on stdout")
}

pub fn numbers(v: &serde_json::Value, key: &str) -> Vec<f64> {
    v[key]
        .as_array()
        .unwrap_or_else(|| panic!("`{key}` is not an array: {v}"))
        .iter()
        .map(|x| x.as_f64().expect("number"))
        .collect()
}

/// `examples/scenes/NAME`.
pub fn scene(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("examples/scenes")
        .join(name)
}

/// A CSV's header fields and its rows of numbers.
pub fn parse_csv(text: &str) -> (Vec<String>, Vec<Vec<f64>>) {
    let mut lines = text.lines();
    let header = lines
        .next()
        .expect("header")
        .split(',')
        .map(str::to_string)
        .collect();
    let rows = lines
        .map(|l| {
            l.split(',')
                .map(|f| {
                    f.parse::<f64>()
                        .unwrap_or_else(|_| panic!("not a number: {f}"))
                })
                .collect()
        })
        .collect();
    (header, rows)
}
