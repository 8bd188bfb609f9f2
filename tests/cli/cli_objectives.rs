//! The command line takes the power objective Σ_k |M₀(t_k)|^p (`[objective] kind = "power",
//! exponent = p`): `gradient` and `optimize` with the structured solvers.

use crate::thesis;

use chainbeam::{catalogue, ControlProblem, Parametrisation, PerStepControl, PowerObjective};

fn max_abs(v: &[f64]) -> f64 {
    v.iter().fold(0.0f64, |m, x| m.max(x.abs()))
}

/// The command line: a scene with `kind = "power", exponent = 4` (Table 3.4's row 5 as a file):
/// `gradient` reports the kind and exponent and the library's objective bit for bit, and
/// `optimize --method riccati` and `condensed` reach `trust-region`'s objective (1e-6).
#[test]
fn command_line_takes_the_power_objective() {
    let dir = tempfile::tempdir().unwrap();
    let text = std::fs::read_to_string(
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("examples/scenes/riser_5.toml"),
    )
    .unwrap()
    .replace("kind = \"final\"", "kind = \"power\"\nexponent = 4")
    .replace(
        "kind = \"constant\"\nvalues = [0.0]",
        "kind = \"per-step\"\nvalues = [0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0]",
    );
    let path = dir.path().join("power.toml");
    std::fs::write(&path, &text).unwrap();
    let run = |args: &[&str]| -> serde_json::Value {
        let out = std::process::Command::new(env!("CARGO_BIN_EXE_chainbeam"))
            .args(args)
            .arg(&path)
            .args(["--quiet"])
            .output()
            .unwrap();
        assert!(
            out.status.success(),
            "{args:?}: {}",
            String::from_utf8_lossy(&out.stderr)
        );
        serde_json::from_slice(&out.stdout).unwrap()
    };
    let g = run(&["gradient"]);
    assert_eq!(g["objective_kind"], "power");
    assert_eq!(g["objective_exponent"], 4.0);
    let lib = ControlProblem::builder(&catalogue::riser(5))
        .map(Parametrisation::PerStep(PerStepControl { steps: 10 }))
        .objective(PowerObjective::new(4.0).unwrap())
        .build_in::<2>()
        .unwrap();
    let j = lib.value(&[0.0; 11]).unwrap();
    assert_eq!(g["objective"].as_f64().unwrap().to_bits(), j.to_bits());
    let bound = max_abs(&thesis::TABLE_3_4[4].0).to_string();
    let opt = |m: &str| run(&["optimize", "--method", m, "--bound", &bound]);
    let tr = opt("trust-region")["objective"].as_f64().unwrap();
    for m in ["riccati", "condensed"] {
        let v = opt(m);
        let j = v["objective"].as_f64().unwrap();
        println!("optimize --method {m}: {j:.10e}, trust-region {tr:.10e}");
        assert_eq!(v["converged"], true);
        assert!((j - tr) / tr <= 1e-6, "{m}: {j} vs {tr}");
    }
}
