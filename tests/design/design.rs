//! The fatigue design (`chainbeam::design`): the exact design gradient of the scatter-diagram
//! damage against central differences and dual numbers, the cells' independence of where they
//! ran, the agreement with the fatigue study's own damage, the optimiser, and the `[design]`
//! table's refusals.
//!
//! The reduced scene: the 21-inch riser of examples/scenes/riser_300m.toml (its pipe, water,
//! tension, current, sea and `[fatigue]`) on 10 pendulums at h = 0.1 s (its fastest bending mode
//! is then ω_max ≈ 2.5 rad/s, ω_max h ≈ 0.25), short records, three cells.

use crate::design_study::{check_central_differences, check_dual_numbers};
use chainbeam::design::{
    optimise, sensitivities, DesignOptions, DesignParameter, DesignPoint, DesignStudy, Execution,
    ScatterGradient, Want,
};
use chainbeam::fatigue::{ScatterCell, SeaState};
use chainbeam::fatigue_study::{run_study, ControlSettings, ControllerKind, StudyInput};
use chainbeam::Scene;

/// The reduced riser (module docs) with `design` appended.
pub(crate) fn scene_text(design: &str) -> String {
    crate::design_study::scene_text(
        r#"
[beam]
pendulums = 10
support = "riser"

[pipe]
length = 300.0
outer_diameter = 0.5334
wall_thickness = 0.022225
contents_density = 1437.912
drag_coefficient = 1.0
added_mass_coefficient = 1.0

[loads]
drag = 3.0e-6
tension = 1.228e6
axial_weight = 3149.1

[loads.waves]
spectrum = "jonswap"
hs = 1.44
tp = 7.66
gamma = 1.0
seed = 1
direction = 0.0
lumping = "cell"

[time]
step = 0.1
steps = 600

"#,
        crate::design_study::RISER_SECTION,
        design,
    )
}

const DESIGN: &str = r#"
[design]
max_iterations = 8
tolerance = 1e-3

[[design.parameter]]
name = "loads.tension"
lower = 1.0e6
upper = 2.0e6

[[design.parameter]]
name = "beam.base_stiffness"
lower = 1.0e6
upper = 1.0e9
"#;

fn scene() -> Scene {
    Scene::from_toml_str(&scene_text(DESIGN)).unwrap()
}

/// Three sea states of a reduced diagram (probabilities 0.5, 0.3, 0.2).
fn cells() -> Vec<ScatterCell> {
    crate::design_study::cells(&[(1.0, 6.5, 0.5), (2.0, 8.0, 0.3), (3.5, 10.0, 0.2)])
}

const PARAMS: [DesignParameter; 3] = [
    DesignParameter::Tension,
    DesignParameter::BaseStiffness,
    DesignParameter::TipStiffness,
];

fn study<'a>(scene: &'a Scene, cells: &'a [ScatterCell], spin_up: f64) -> DesignStudy<'a> {
    crate::design_study::study(scene, cells, 40.0, spin_up)
}

fn values(scene: &Scene) -> Vec<f64> {
    crate::design_study::values(scene, &PARAMS)
}

/// D_y (and its gradient) at `v` of [`PARAMS`].
fn eval(st: &DesignStudy<'_>, v: &[f64], want: Want, execution: Execution) -> ScatterGradient {
    crate::design_study::eval(st, &PARAMS, v, want, execution)
}

/// ∂D_y/∂θ_i by the adjoint = central differences of D_y (each D_y by forward runs of every
/// cell) with the step 10⁻⁵ θ_i, to 10⁻⁵ relative, at the scene's design and at a second design
/// (tension +25 %, base spring ÷ 3, tip spring × 2). The reference is the central difference:
/// its truncation error is O(10⁻¹⁰) relative and its round-off about 10⁻¹¹.
#[test]
fn design_gradient_matches_central_differences_at_two_designs() {
    let scene = scene();
    let cells = cells();
    let st = study(&scene, &cells, 10.0);
    let v0 = values(&scene);
    let v1 = vec![v0[0] * 1.25, v0[1] / 3.0, v0[2] * 2.0];
    for v in [v0, v1] {
        check_central_differences(&st, &PARAMS, &v, &[0, 1, 2]);
    }
}

/// ∂D_s/∂θ_i of every cell by the adjoint = the dual part of D_s computed in `Dual64` with θ_i
/// seeded (forward-mode differentiation of the whole run through the library's fatigue
/// objective, which counts the whole record: no spin-up here), to 10⁻⁹ relative, and D_s
/// itself to 10⁻¹² (`design_study::check_dual_numbers`).
#[test]
fn design_gradient_matches_dual_numbers_cell_by_cell() {
    let scene = scene();
    let cells = cells();
    let st = study(&scene, &cells, 0.0);
    check_dual_numbers(&st, &PARAMS, &values(&scene));
}

/// The cells on rayon's pool give the damage and the gradient bit for bit as serially (each
/// cell's numbers are its own; the sum is in the diagram's order).
#[test]
fn cells_serial_and_parallel_bit_for_bit() {
    let scene = scene();
    let cells = cells();
    let st = study(&scene, &cells, 10.0);
    let v = values(&scene);
    let a = eval(&st, &v, Want::Gradient, Execution::Serial);
    let b = eval(&st, &v, Want::Gradient, Execution::Parallel);
    let bits = |g: &ScatterGradient| {
        let mut out = vec![g.damage_per_year.to_bits()];
        out.extend(g.gradient.iter().map(|x| x.to_bits()));
        for c in &g.cells {
            out.push(c.damage.to_bits());
            out.extend(c.gradient.iter().map(|x| x.to_bits()));
        }
        out
    };
    assert_eq!(bits(&a), bits(&b));
    // Cells run one by one and combined: the same again (the Python package's Dask path).
    let point = DesignPoint {
        params: &PARAMS,
        values: &v,
    };
    let one_by_one: Vec<_> = (0..st.n_cells())
        .rev()
        .map(|s| st.run_cell(s, &point, Want::Gradient).unwrap())
        .rev()
        .collect();
    assert_eq!(bits(&DesignStudy::combine(one_by_one).unwrap()), bits(&a));
}

/// The design's D_y at the scene's own values is the fatigue study's (`chainbeam fatigue
/// --scatter`, controller `scene`) damage per year over the same diagram, record and spin-up,
/// bit for bit: the same records, the same counted samples, the same combination.
#[test]
fn damage_is_the_fatigue_studys() {
    let scene = scene();
    let cells = cells();
    let st = study(&scene, &cells, 10.0);
    let g = eval(&st, &values(&scene), Want::Value, Execution::Parallel);
    let settings = ControlSettings {
        spin_up: 10.0,
        record: Some(40.0),
        ..ControlSettings::default()
    };
    let spec = scene.fatigue_spec().unwrap();
    let study = run_study(
        &StudyInput {
            scene: &scene,
            spec: &spec,
            cells: Some(&cells),
            controllers: &[ControllerKind::Scene],
            settings: &settings,
        },
        &|| {},
    )
    .unwrap();
    let c = study.get(ControllerKind::Scene).unwrap();
    assert_eq!(c.damage_per_year.to_bits(), g.damage_per_year.to_bits());
    for (a, b) in c.cells.iter().zip(&g.cells) {
        assert_eq!(a.damage.to_bits(), b.damage.to_bits());
        assert_eq!(a.duration_s.to_bits(), b.duration_s.to_bits());
    }
}

/// The optimiser (the projected L-BFGS on ln D_y in the log-scaled unit box) ends at a design
/// whose life is at least the scene's, within the bounds, having reported every iterate with
/// non-increasing damage from the start, and the sensitivities at the start are the gradient
/// of an evaluation there (the same numbers bit for bit). Converged, its design satisfies the
/// first-order conditions with the bounds: each parameter's ∂D_y/∂θ vanishes to the tolerance
/// or pushes it against the bound it lies on. Its count of cell runs is the adjoint sweeps
/// (three cells per evaluation with the gradient) plus the forward runs (three per
/// value-only trial).
#[test]
fn optimiser_improves_the_life_within_the_bounds() {
    let scene = scene();
    let cells = cells();
    let st = study(&scene, &cells, 10.0);
    let o = optimise(&st, &DesignOptions::default()).unwrap();
    assert!(o.life_years >= o.initial.life_years, "{o:?}");
    for it in &o.iterates {
        for ((_, (lo, hi)), v) in o.parameters.iter().zip(&it.values) {
            assert!((*lo..=*hi).contains(v), "{it:?}");
        }
    }
    assert_eq!(
        o.iterates[0].values,
        vec![1.228e6, scene.beam.base_stiffness]
    );
    let last = o.iterates.last().unwrap();
    assert!(last.damage_per_year <= o.initial.damage_per_year);
    let (g, sens) = sensitivities(&st, Execution::Serial, &|| {}).unwrap();
    assert_eq!(
        g.damage_per_year.to_bits(),
        o.initial.damage_per_year.to_bits()
    );
    assert_eq!(sens.len(), 2);
    for (s, t) in sens.iter().zip(&o.sensitivities) {
        assert_eq!(s.damage_per_year.to_bits(), t.damage_per_year.to_bits());
    }
    assert!(o.simulations >= cells.len());
    assert_eq!(o.simulations, o.adjoint_sweeps + o.forward_runs);
    assert_eq!(o.adjoint_sweeps % cells.len(), 0);
    assert_eq!(o.forward_runs % cells.len(), 0);
    assert!(last.simulations <= o.simulations);
    eprintln!(
        "optimiser on the reduced scene: {} iterations, {} adjoint sweeps, {} forward runs, \
         converged {} ({}), design {:?}",
        o.iterates.len() - 1,
        o.adjoint_sweeps,
        o.forward_runs,
        o.converged,
        o.termination,
        o.design
    );
    if o.converged {
        for (((_, (lo, hi)), v), g) in o.parameters.iter().zip(&o.design).zip(&last.gradient) {
            let on_lower = v == lo && *g >= 0.0;
            let on_upper = v == hi && *g <= 0.0;
            // |∂ ln D_y/∂u| = |θ ln(hi/lo) ∂D_y/∂θ / D_y| ≤ the tolerance 10⁻³ in the interior.
            let scaled = (v * (hi / lo).ln() * g / last.damage_per_year).abs();
            assert!(
                on_lower || on_upper || scaled <= 1e-3,
                "{v} in [{lo}, {hi}]: {scaled}"
            );
        }
    }
}

/// Bad `[design]` tables are refused when the scene is read, the error naming the key.
#[test]
fn bad_design_keys_are_refused_naming_the_key() {
    let cases: &[(&str, &str)] = &[
        (
            "[[design.parameter]]\nname = \"loads.drag\"\nlower = 1.0\nupper = 2.0\n",
            "design.parameter[0].name",
        ),
        (
            "[[design.parameter]]\nname = \"loads.tension\"\nlower = 1.0e6\n",
            "design.parameter[0].upper",
        ),
        (
            "[[design.parameter]]\nname = \"loads.tension\"\nlower = 2.0e6\nupper = 1.0e6\n",
            "design.parameter[0].upper",
        ),
        (
            "[[design.parameter]]\nname = \"loads.tension\"\nlower = 1.3e6\nupper = 2.0e6\n",
            "design.parameter[0].lower",
        ),
        (
            "[[design.parameter]]\nname = \"loads.tension\"\nlower = -1.0\nupper = 2.0e6\n",
            "design.parameter[0].lower",
        ),
        (
            "[[design.parameter]]\nname = \"loads.tension\"\nlower = 1.0e6\nupper = inf\n",
            "design.parameter[0].upper",
        ),
        (
            "[[design.parameter]]\nname = \"loads.tension\"\nrole = \"maybe\"\n",
            "design.parameter[0].role",
        ),
        (
            "[[design.parameter]]\nname = \"loads.tension\"\nrole = \"uncertainty\"\nlower = 1.0\n",
            "design.parameter[0].lower",
        ),
        (
            "[[design.parameter]]\nname = \"soil.modulus\"\n",
            "design.parameter[0].name",
        ),
        (
            "[[design.parameter]]\nname = \"loads.tension\"\nlower = 1.0e6\nupper = 2.0e6\n\
             [[design.parameter]]\nname = \"loads.tension\"\nlower = 1.0e6\nupper = 2.0e6\n",
            "design.parameter[1].name",
        ),
        ("[design]\nmax_iterations = 0\n", "design.max_iterations"),
        ("[design]\ntolerance = -1.0\n", "design.tolerance"),
        ("[design]\nstep = 1.0\n", "design.step"),
        (
            "[[design.parameter]]\nname = \"loads.tension\"\nbound = 1.0\n",
            "design.parameter[0].bound",
        ),
    ];
    for (design, key) in cases {
        let err = Scene::from_toml_str(&scene_text(design)).unwrap_err();
        assert_eq!(err.key(), Some(*key), "{design}: {err}");
    }
    // A base spring on a support without one.
    let text = scene_text(
        "[[design.parameter]]\nname = \"beam.tip_stiffness\"\nlower = 1.0\nupper = 2.0\n",
    )
    .replace("support = \"riser\"", "support = \"cantilever\"");
    let err = Scene::from_toml_str(&text).unwrap_err();
    assert_eq!(err.key(), Some("design.parameter[0].name"), "{err}");
    // The table written back reads as itself.
    let scene = scene();
    assert_eq!(
        Scene::from_toml_str(&scene.to_toml_string()).unwrap(),
        scene
    );
}

/// `chainbeam design --sensitivities` on the README's example scene and a one-cell diagram: the
/// JSON's `sensitivities` are keyed by parameter name and equal the library's (to the 17 digits
/// JSON keeps), the scene's design and life are reported, and no `design` without an
/// optimisation.
#[test]
fn cli_design_sensitivities_json() {
    let dir = tempfile_dir();
    let csv = dir.join("cells.csv");
    std::fs::write(&csv, "hs,tp,probability\n2.0,8.0,1.0\n").unwrap();
    let scene_path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("examples/scenes/riser_300m_design.toml");
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_chainbeam"))
        .arg("design")
        .arg(&scene_path)
        .args([
            "--sensitivities",
            "--record",
            "30",
            "--spin-up",
            "10",
            "--scatter",
        ])
        .arg(&csv)
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let json: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert!(json.get("design").is_none());
    let scene = Scene::from_file(&scene_path).unwrap();
    let cells = vec![ScatterCell {
        sea: SeaState {
            hs: 2.0,
            tp: 8.0,
            direction: None,
        },
        probability: 1.0,
    }];
    let st = DesignStudy {
        scene: &scene,
        cells: Some(&cells),
        record: Some(30.0),
        spin_up: 10.0,
    };
    let (g, sens) = sensitivities(&st, Execution::Serial, &|| {}).unwrap();
    for s in &sens {
        let v = json["sensitivities"][s.parameter.name()].as_f64().unwrap();
        assert_eq!(v, s.damage_per_year, "{}", s.parameter.name());
    }
    assert_eq!(json["damage_per_year"].as_f64().unwrap(), g.damage_per_year);
    assert!(json["scene_design"]["life_years"].as_f64().unwrap() > 0.0);
}

/// A fresh directory under the target's temporary directory.
fn tempfile_dir() -> std::path::PathBuf {
    let d = std::path::Path::new(env!("CARGO_TARGET_TMPDIR")).join(format!(
        "design-{}-{:?}",
        std::process::id(),
        std::thread::current().id()
    ));
    std::fs::create_dir_all(&d).unwrap();
    d
}
