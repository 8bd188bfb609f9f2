//! Runs the figure program reduced (`--quick`: short runs, half-size images) on a few figures
//! (two simulations, the optimiser's constant-control landscape and the gradient calibration) and
//! checks that the PNG, SVG and index files appear. Needs no system font: the program bundles
//! DejaVu Sans.

use std::path::PathBuf;
use std::process::Command;

fn out_dir(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("paper_figures_test_{}_{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    d
}

#[test]
fn quick_run_writes_png_svg_and_index() {
    let out = out_dir("quick");
    let status = Command::new(env!("CARGO_BIN_EXE_paper_figures"))
        .args([
            "--quick",
            "--no-progress",
            "--only",
            "fig_2_5,fig_3_3,fig_3_7,calibration,load_45_symmetry,riser_current_wave_control",
            "--out",
        ])
        .arg(&out)
        .status()
        .expect("run paper_figures");
    assert!(status.success());
    for f in [
        "fig_2_5.png",
        "fig_2_5.svg",
        "fig_3_3.png",
        "fig_3_3.svg",
        "fig_3_7.png",
        "fig_3_7.svg",
        "calibration.png",
        "calibration.svg",
        "load_45_symmetry.png",
        "load_45_symmetry.svg",
        "riser_current_wave_control.png",
        "riser_current_wave_control.svg",
    ] {
        let meta = std::fs::metadata(out.join(f)).unwrap_or_else(|e| panic!("{f}: {e}"));
        assert!(meta.len() > 1000, "{f} is too small");
    }
    let png = std::fs::read(out.join("fig_2_5.png")).unwrap();
    assert_eq!(&png[..8], b"\x89PNG\r\n\x1a\n");
    let svg = std::fs::read_to_string(out.join("fig_2_5.svg")).unwrap();
    assert!(svg.contains("<svg") && svg.contains("step size h [s]"));
    let index = std::fs::read_to_string(out.join("index.md")).unwrap();
    assert!(index.contains("## fig_2_5") && index.contains("## fig_3_3"));
    assert!(index.contains("Norm of energy error"));
    assert!(index.contains("## fig_3_7") && index.contains("## calibration"));
    // the optimiser finds the thesis's minimum u = −2 N, and the calibration reports its fit
    assert!(index.contains("at u* = −2 N"));
    assert!(index.contains("RMS residual"));
    // Loads out of the plane: the 45° load deflects as far as the in-plane one; the 2-axis control is optimised
    assert!(index.contains("## load_45_symmetry") && index.contains("rotational symmetry"));
    assert!(index.contains("## riser_current_wave_control") && index.contains("c_sum falls from"));
    let _ = std::fs::remove_dir_all(&out);
}

#[test]
fn unknown_figure_is_an_error() {
    let out = out_dir("unknown");
    let o = Command::new(env!("CARGO_BIN_EXE_paper_figures"))
        .args(["--quick", "--no-progress", "--only", "fig_9_9", "--out"])
        .arg(&out)
        .output()
        .expect("run paper_figures");
    assert!(!o.status.success());
    assert!(String::from_utf8_lossy(&o.stderr).contains("no figure matches"));
    let _ = std::fs::remove_dir_all(&out);
}
