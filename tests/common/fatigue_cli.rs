//! What the `chainbeam fatigue` tests share (tests/cli/cli_fatigue.rs, tests/cli/cli_fatigue_study.rs):
//! the thesis riser's `[beam]` table, a `[fatigue]` table for a small steel tube, and running
//! the binary in a directory.
#![allow(dead_code)]

use std::path::Path;

use assert_cmd::cargo::cargo_bin_cmd;

/// The thesis riser's `[beam]` (n = 10, l = 1 m, m = 1 kg, k = 1000 N·m/rad, k₁ = k₁₁ = 2000)
/// on the support `support`.
pub fn beam(support: &str) -> String {
    format!(
        r#"[beam]
pendulums = 10
length = 1.0
mass = 1.0
stiffness = 1000.0
support = "{support}"
base_stiffness = 2000.0
tip_stiffness = 2000.0
"#
    )
}

/// A `[fatigue]` table for a small steel tube (D_o = 20 mm, t = 2 mm, SCF 1.2, DNV F1 in air,
/// DFF 3).
pub const FATIGUE_TABLE: &str = r#"[fatigue]
outer_diameter = 0.02
wall_thickness = 0.002
scf = 1.2
curve = "F1"
environment = "air"
dff = 3.0
"#;

/// Runs the binary in `dir`: (exit code, stdout, stderr).
pub fn run(dir: &Path, args: &[&str]) -> (i32, String, String) {
    let out = cargo_bin_cmd!("chainbeam")
        .current_dir(dir)
        .args(args)
        .output()
        .unwrap();
    (
        out.status.code().unwrap_or(-1),
        String::from_utf8(out.stdout).unwrap(),
        String::from_utf8(out.stderr).unwrap(),
    )
}

/// The JSON of `text` (panics with the text on a parse error).
pub fn json(text: &str) -> serde_json::Value {
    serde_json::from_str(text).unwrap_or_else(|e| panic!("{e}: {text}"))
}
