//! `chainbeam simulate` with waves (`[loads.waves]`): the `eta` column, `--columns` and `--every`.
//!
//! References: η(t_k) against the direct sum Σⱼ aⱼ cos(ωⱼ t_k + φⱼ) of the scene's sea
//! (`Sea::elevation`, component by component, independent of the FFT); `--columns` and
//! `--every` against the full CSV (the same text, column by column and row by row).

use crate::common;

use chainbeam::ocean::Sea;
use chainbeam::Scene;
use common::*;

const SCENE: &str = "[beam]\npendulums = 6\nsupport = \"riser\"\n\n\
[pipe]\nlength = 60.0\nouter_diameter = 0.5334\nwall_thickness = 0.0222\n\n\
[water]\ndepth = 60.0\n\n\
[loads]\ndrag = 2e-6\ntension = 1e6\n\n\
[loads.current]\nprofile = \"uniform\"\nspeed = 0.3\n\n\
[loads.waves]\nspectrum = \"pierson-moskowitz\"\nhs = 3.0\ntp = 9.0\nseed = 11\ndirection = 45.0\n\n\
[time]\nstep = 0.05\nsteps = 120\n";

fn csv(dir: &Dir, extra: &[&str]) -> (Vec<String>, Vec<Vec<f64>>, String) {
    let path = dir.write("waves.toml", SCENE);
    let mut args = vec!["simulate".to_string(), path.display().to_string()];
    args.extend(extra.iter().map(|s| s.to_string()));
    let o = run(&args);
    assert_success(&o);
    let text = stdout(&o);
    let (h, rows) = parse_csv(&text);
    (h, rows, text)
}

#[test]
fn eta_is_the_surface_elevation_of_the_scene_sea() {
    let dir = Dir::new();
    let (header, rows, _) = csv(&dir, &[]);
    let e = header.iter().position(|h| h == "eta").expect("eta column");
    assert_eq!(header.last().map(String::as_str), Some("control"));
    assert_eq!(header[e - 1], "control_x", "spatial: eta after control_x");
    let scene = Scene::from_toml_str(SCENE).unwrap();
    let w = scene.loads.waves.unwrap();
    let spec = w.sea_spec(scene.wave_depth()).unwrap();
    let sea = Sea::new(&spec, 0.05, 6.0).unwrap();
    let mut largest: f64 = 0.0;
    for (k, r) in rows.iter().enumerate() {
        let want = sea.elevation(k as f64 * 0.05);
        largest = largest.max(want.abs());
        assert!((r[e] - want).abs() < 1e-11, "k = {k}: {} vs {want}", r[e]);
    }
    assert!(largest > 0.3, "a sea of H_s = 3 m: |η| up to {largest}");
}

#[test]
fn columns_and_every_select_from_the_full_output() {
    let dir = Dir::new();
    let (header, rows, _) = csv(&dir, &[]);
    let (h2, rows2, text) = csv(&dir, &["--columns", "t,eta,moment", "--every", "7"]);
    assert_eq!(h2, ["t", "eta", "moment"]);
    assert!(text.starts_with("t,eta,moment\n"));
    let idx: Vec<usize> = h2
        .iter()
        .map(|n| header.iter().position(|h| h == n).unwrap())
        .collect();
    let want: Vec<Vec<f64>> = rows
        .iter()
        .step_by(7)
        .map(|r| idx.iter().map(|&i| r[i]).collect())
        .collect();
    assert_eq!(rows2.len(), 120 / 7 + 1);
    assert_eq!(rows2, want);
    // Any order, any subset.
    let (h3, rows3, _) = csv(&dir, &["--columns", "control,z6"]);
    assert_eq!(h3, ["control", "z6"]);
    let z6 = header.iter().position(|h| h == "z6").unwrap();
    for (a, b) in rows3.iter().zip(&rows) {
        assert_eq!(a[1].to_bits(), b[z6].to_bits());
    }
}

#[test]
fn unknown_or_repeated_columns_name_the_flag() {
    let dir = Dir::new();
    let path = dir.write("waves.toml", SCENE);
    for (cols, needle) in [("t,bogus", "`bogus`"), ("t,moment,t", "twice")] {
        let o = run(&["simulate", path.to_str().unwrap(), "--columns", cols]);
        assert_eq!(o.status.code(), Some(1), "{cols}");
        let err = stderr(&o);
        assert!(err.contains("--columns") && err.contains(needle), "{err}");
        assert!(o.stdout.is_empty());
    }
    // `eta` without waves.
    let plain = dir.write("plain.toml", &SCENE.replace("[loads.waves]", "[unused]").replace(
        "[unused]\nspectrum = \"pierson-moskowitz\"\nhs = 3.0\ntp = 9.0\nseed = 11\ndirection = 45.0\n",
        "",
    ));
    let o = run(&["simulate", plain.to_str().unwrap(), "--columns", "t,eta"]);
    assert_eq!(o.status.code(), Some(1));
    assert!(stderr(&o).contains("[loads.waves]"), "{}", stderr(&o));
    let o = run(&["simulate", path.to_str().unwrap(), "--every", "0"]);
    assert_eq!(o.status.code(), Some(2));
    assert!(stderr(&o).contains("--every"));
}
