//! The documentation of the scene format (docs/scene-format.md) and the parser agree:
//!
//! - every key documented in the key tables is accepted by the parser (a file setting every
//!   documented key parses, and each key changes the scene it sets);
//! - every key the parser accepts is documented. The accepted keys are not listed by hand: they
//!   are read from the parser's own "unknown key" error, which lists the fields of the serde
//!   structure of each table (`expected one of ...`);
//! - the valid ranges in the tables are those the validation enforces (the library's constants);
//! - every `toml` example in the document is a valid scene;
//! - nothing in the repository sends readers outside it: no path into the workplace's shared
//!   folder, no design note named by its file, no issue number (`docs_stay_inside_the_repository`).

use std::collections::{BTreeMap, BTreeSet};
use std::path::Path;

use chainbeam::scene::{
    ValueRange, CURRENT_SPEED_RANGE, DRAG_RANGE, FORCE_RANGE, GRAVITY_RANGE, JOINT_DAMPING_RANGE,
    LENGTH_RANGE, MASS_RANGE, MAX_PENDULUMS, MAX_STEPS, PERIOD_RANGE, SOIL_GRADIENT_RANGE,
    SOIL_MODULUS_RANGE, SOIL_MUDLINE_RANGE, STEP_RANGE, STIFFNESS_RANGE,
};
use chainbeam::{Scene, SceneErrorKind};

fn read(rel: &str) -> String {
    std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join(rel))
        .unwrap_or_else(|e| panic!("{rel}: {e}"))
}

/// The key tables of the document: table path (`beam`, `loads.point`) → key → the row's cells.
fn documented() -> BTreeMap<String, BTreeMap<String, Vec<String>>> {
    let doc = read("docs/scene-format.md");
    let mut tables: BTreeMap<String, BTreeMap<String, Vec<String>>> = BTreeMap::new();
    let mut current: Option<String> = None;
    for line in doc.lines() {
        if line.starts_with('#') {
            // "### `[beam]`" or "### `[[loads.point]]`" opens a table; any other heading closes it
            current = line
                .strip_prefix("### `[")
                .and_then(|s| s.split_once("]`"))
                .map(|(name, _)| {
                    name.trim_start_matches('[')
                        .trim_end_matches(']')
                        .to_string()
                });
            if let Some(t) = &current {
                assert!(
                    tables.insert(t.clone(), BTreeMap::new()).is_none(),
                    "{t} twice"
                );
            }
            continue;
        }
        let (Some(table), Some(row)) = (&current, line.strip_prefix("| `")) else {
            continue;
        };
        let cells: Vec<String> = line
            .trim_matches('|')
            .split(" | ")
            .map(|c| c.trim().to_string())
            .collect();
        let key = row.split('`').next().unwrap().to_string();
        let rows = tables.get_mut(table).unwrap();
        assert!(
            rows.insert(key.clone(), cells).is_none(),
            "{table}.{key} twice"
        );
    }
    tables
}

/// A valid scene with every table, as (table, [(key, value)]).
const SECTIONS: &[(&str, &[(&str, &str)])] = &[
    (
        "beam",
        &[
            ("pendulums", "4"),
            ("length", "1.0"),
            ("mass", "1.0"),
            ("stiffness", "100.0"),
            ("support", "\"fixed-fixed\""),
        ],
    ),
    ("water", &[("density", "1025.0")]),
    ("loads", &[("gravity", "1.0"), ("drag", "1.0")]),
    ("loads.point", &[("node", "2"), ("force", "1.0")]),
    (
        "loads.point.harmonic",
        &[("amplitude", "1.0"), ("period", "2.0")],
    ),
    (
        "loads.current",
        &[("profile", "\"linear\""), ("speed", "0.5")],
    ),
    ("time", &[("step", "0.01"), ("steps", "5")]),
    ("control", &[("kind", "\"constant\""), ("values", "[0.0]")]),
    ("objective", &[("kind", "\"final\"")]),
    (
        "fatigue",
        &[("outer_diameter", "0.5"), ("wall_thickness", "0.025")],
    ),
    (
        "fatigue.hotspot",
        &[("name", "\"a\""), ("elevation", "1.0")],
    ),
    ("mpc", &[("interval", "0.1")]),
    ("design", &[("max_iterations", "5")]),
    (
        "design.parameter",
        &[
            ("name", "\"beam.base_stiffness\""),
            ("lower", "10.0"),
            ("upper", "1000.0"),
        ],
    ),
];

/// One table of [`stackup_text`]: (its path, its header, its (key, value) entries).
type Table<'a> = (&'a str, &'a str, Vec<(&'a str, &'a str)>);

/// A valid scene with a `[stackup]` (two segments, a body, a flex joint) and `[soil]`, with
/// `set` = (table, key, value) replacing or adding one key of the stack-up's tables (the first
/// of an array of tables). `elevation` replaces the flex joint's `above` (one of the two).
fn stackup_text(set: Option<(&str, &str, &str)>) -> String {
    let tables: [Table; 5] = [
        ("stackup", "[stackup]", vec![]),
        (
            "stackup.segment",
            "[[stackup.segment]]",
            vec![
                ("name", "\"a\""),
                ("length", "2.0"),
                ("outer_diameter", "0.5"),
                ("wall_thickness", "0.02"),
                ("buoyancy_diameter", "0.8"),
                ("buoyancy_density", "400.0"),
            ],
        ),
        (
            "stackup.body",
            "[[stackup.body]]",
            vec![
                ("name", "\"c\""),
                ("above", "\"b\""),
                ("mass", "300.0"),
                ("submerged_weight", "2000.0"),
                ("height", "1.0"),
            ],
        ),
        (
            "stackup.flex_joint",
            "[[stackup.flex_joint]]",
            vec![("name", "\"f\""), ("above", "\"b\""), ("stiffness", "1e5")],
        ),
        (
            "stackup.segment",
            "[[stackup.segment]]",
            vec![
                ("name", "\"b\""),
                ("length", "1.0"),
                ("joints", "2"),
                ("outer_diameter", "0.4"),
                ("wall_thickness", "0.02"),
            ],
        ),
    ];
    let mut text = String::from(
        "[beam]\npendulums = 7\nsupport = \"riser\"\n\n[time]\nstep = 0.001\nsteps = 5\n\n\
         [loads]\ntension = 1e4\n\n",
    );
    let mut soil = vec![("mudline", "1.0"), ("modulus", "1e4")];
    if let Some(("soil", k, v)) = set {
        match soil.iter_mut().find(|e| e.0 == k) {
            Some(e) => e.1 = v,
            None => soil.push((k, v)),
        }
    }
    text.push_str("[soil]\n");
    for (k, v) in &soil {
        text.push_str(&format!("{k} = {v}\n"));
    }
    let mut done = false;
    for (table, header, mut entries) in tables {
        if let Some((t, k, v)) = set {
            if t == table && !done {
                done = true;
                if k == "elevation" {
                    entries.retain(|e| e.0 != "above");
                }
                match entries.iter_mut().find(|e| e.0 == k) {
                    Some(e) => e.1 = v,
                    None => entries.push((k, v)),
                }
            }
        }
        text.push_str(&format!("\n{header}\n"));
        for (k, v) in &entries {
            text.push_str(&format!("{k} = {v}\n"));
        }
    }
    text
}

/// The scene of [`SECTIONS`] with `set` = (table, key, value): the key's value replaced, or the
/// key added to its table (the document root for table ""); the stack-up's and the soil's tables
/// are those of [`stackup_text`].
fn render(set: Option<(&str, &str, &str)>) -> String {
    if let Some((t, _, _)) = set {
        if t == "soil" || t.starts_with("stackup") {
            return stackup_text(set);
        }
    }
    let mut text = String::new();
    if let Some(("", key, value)) = set {
        text.push_str(&format!("{key} = {value}\n"));
    }
    // `[design]` names a base spring within bounds, which other settings (a support without
    // one, another spring) would leave: rendered only when one of its keys is set.
    let design = matches!(set, Some((t, _, _)) if t.starts_with("design"));
    for (table, entries) in SECTIONS {
        if table.starts_with("design") && !design {
            continue;
        }
        if table.starts_with("loads.point")
            || *table == "fatigue.hotspot"
            || *table == "design.parameter"
        {
            text.push_str(&format!("[[{table}]]\n"));
        } else {
            text.push_str(&format!("[{table}]\n"));
        }
        let mut done = false;
        for (key, value) in *entries {
            match set {
                Some((t, k, v)) if t == *table && k == *key => {
                    text.push_str(&format!("{key} = {v}\n"));
                    done = true;
                }
                _ => text.push_str(&format!("{key} = {value}\n")),
            }
        }
        if let Some((t, k, v)) = set {
            if t == *table && !done {
                text.push_str(&format!("{k} = {v}\n"));
            }
        }
        text.push('\n');
    }
    // `[pipe]` excludes `beam.length`, `mass`, `stiffness`: rendered only when one of its keys is set.
    if let Some(("pipe", k, v)) = set {
        text.push_str(&format!("[pipe]\n{k} = {v}\n"));
    }
    // `[loads.waves]` needs `[pipe]` (see `waves_scene`): rendered only when one of its keys is set.
    if let Some(("loads.waves", k, v)) = set {
        text.push_str(&format!("[loads.waves]\n{k} = {v}\n"));
    }
    // `[vessel]` needs `support = "vessel"`: rendered only when one of its keys is set.
    if let Some((t @ ("vessel" | "vessel.rao"), k, v)) = set {
        text = vessel_text(Some((t, k, v)));
    }
    text
}

/// The scene of [`SECTIONS`] held by a vessel (`support = "vessel"`), with `[vessel]` and a
/// two-row `[vessel.rao]`, and `set` = (table, key, value) replaced or added.
fn vessel_text(set: Option<(&str, &str, &str)>) -> String {
    let mut vessel = vec![("offset", "0.5"), ("ramp", "2.0")];
    let mut rao = vec![
        ("period", "[5.0, 10.0]"),
        ("amplitude", "[0.2, 0.9]"),
        ("phase", "[-95.0, -90.0]"),
    ];
    if let Some((t, k, v)) = set {
        let table = if t == "vessel" { &mut vessel } else { &mut rao };
        match table.iter_mut().find(|e| e.0 == k) {
            Some(e) => e.1 = v,
            None => table.push((k, v)),
        }
    }
    let mut text = render(None).replace("support = \"fixed-fixed\"", "support = \"vessel\"");
    text.push_str("[vessel]\n");
    for (k, v) in &vessel {
        text.push_str(&format!("{k} = {v}\n"));
    }
    text.push_str("\n[vessel.rao]\n");
    for (k, v) in &rao {
        text.push_str(&format!("{k} = {v}\n"));
    }
    text
}

/// `text` without its `[design]` tables (the last of [`SECTIONS`]): a `[pipe]` derives the base
/// spring, which then leaves the design's bounds.
fn without_design(text: String) -> String {
    match text.split_once("[design]\n") {
        Some((head, _)) => head.to_string(),
        None => text,
    }
}

/// The keys the parser accepts in `table`, from its unknown-key error.
fn accepted(table: &str) -> BTreeSet<String> {
    let text = render(Some((table, "not_a_key", "1")));
    let err = Scene::from_toml_str(&text).unwrap_err();
    match err.kind {
        SceneErrorKind::UnknownKey { key, expected } => {
            let want = if table.is_empty() {
                "not_a_key".to_string()
            } else {
                format!(
                    "{}.not_a_key",
                    match table {
                        "loads.point.harmonic" => "loads.point[0].harmonic[0]".to_string(),
                        "loads.current" => table.to_string(),
                        "stackup.segment" | "stackup.body" | "stackup.flex_joint" => {
                            format!("{table}[0]")
                        }
                        "fatigue.hotspot" => "fatigue.hotspot[0]".to_string(),
                        "design.parameter" => "design.parameter[0]".to_string(),
                        _ => table.replace("loads.point", "loads.point[0]"),
                    }
                )
            };
            assert_eq!(key, want);
            assert!(!expected.is_empty(), "{table}: no list of keys");
            expected.into_iter().collect()
        }
        other => panic!("{table}: {other:?}"),
    }
}

#[test]
fn every_accepted_key_is_documented_and_every_documented_key_is_accepted() {
    let doc = documented();
    // The document's tables are exactly the parser's: the root's keys are the top-level tables,
    // and `point` and `current` are the tables inside `[loads]`.
    let roots = accepted("");
    let doc_roots: BTreeSet<String> = doc.keys().filter(|t| !t.contains('.')).cloned().collect();
    assert_eq!(doc_roots, roots, "top-level tables");
    let mut checked = 0;
    for (table, rows) in &doc {
        let mut keys: BTreeSet<String> = rows.keys().cloned().collect();
        // direct sub-tables documented under their own heading
        for sub in doc.keys() {
            if let Some(rest) = sub.strip_prefix(&format!("{table}.")) {
                if !rest.contains('.') {
                    keys.insert(rest.to_string());
                }
            }
        }
        assert_eq!(keys, accepted(table), "keys of [{table}]");
        checked += keys.len();
    }
    assert_eq!(checked, 152, "number of documented keys");
}

/// Each documented key, set to a value other than its default, is read: the scene changes.
#[test]
fn every_documented_key_is_read() {
    let base = Scene::from_toml_str(&render(None)).unwrap();
    let settings: &[(&str, &str, &str)] = &[
        ("beam", "pendulums", "5"),
        ("beam", "length", "2.0"),
        ("beam", "mass", "2.0"),
        ("beam", "stiffness", "200.0"),
        ("beam", "support", "\"pinned-pinned\""),
        ("beam", "base_stiffness", "5.0"),
        ("beam", "tip_stiffness", "5.0"),
        ("beam", "reaction_force", "true"),
        ("beam", "joint_damping", "1.0"),
        ("loads", "gravity", "2.0"),
        ("loads", "drag", "3.0"),
        ("water", "depth", "30.0"),
        ("water", "density", "1000.0"),
        ("loads", "tension", "50.0"),
        ("loads", "axial_weight", "4.0"),
        ("loads.point", "node", "3"),
        ("loads.point", "force", "4.0"),
        ("loads.point", "start", "0.5"),
        ("loads.point", "end", "0.75"),
        ("loads.point", "ramp", "0.02"),
        ("loads.point", "direction", "[1.0, 0.0]"),
        // the shipped series (relative to the current directory, the package root under cargo)
        (
            "loads.point",
            "series",
            "\"examples/scenes/wave_series.csv\"",
        ),
        ("loads.point.harmonic", "amplitude", "3.0"),
        ("loads.point.harmonic", "period", "0.5"),
        ("loads.point.harmonic", "phase", "0.25"),
        ("loads.current", "profile", "\"uniform\""),
        ("loads.current", "speed", "0.25"),
        ("loads.current", "bottom_speed", "0.1"),
        ("loads.current", "surface", "3.5"),
        ("loads.current", "direction", "[0.0, -1.0]"),
        ("time", "step", "0.02"),
        ("time", "steps", "6"),
        ("time", "initial", "\"static\""),
        ("control", "node", "3"),
        ("control", "kind", "\"piecewise\""),
        ("control", "values", "[1.0]"),
        ("objective", "kind", "\"sum\""),
        ("fatigue", "outer_diameter", "0.6"),
        ("fatigue", "wall_thickness", "0.03"),
        ("fatigue", "scf", "1.5"),
        ("fatigue", "curve", "\"F1\""),
        ("fatigue", "environment", "\"air\""),
        ("fatigue", "thickness_exponent", "0.1"),
        ("fatigue", "reference_thickness", "0.032"),
        ("fatigue", "dff", "3.0"),
        ("fatigue.hotspot", "name", "\"b\""),
        ("fatigue.hotspot", "elevation", "2.0"),
        ("fatigue.hotspot", "outer_diameter", "0.6"),
        ("fatigue.hotspot", "wall_thickness", "0.03"),
        ("fatigue.hotspot", "scf", "1.5"),
        ("fatigue.hotspot", "curve", "\"F1\""),
        ("fatigue.hotspot", "environment", "\"air\""),
        ("fatigue.hotspot", "thickness_exponent", "0.1"),
        ("fatigue.hotspot", "reference_thickness", "0.032"),
        ("fatigue.hotspot", "dff", "3.0"),
        ("mpc", "interval", "0.2"),
        ("mpc", "horizon", "5.0"),
        ("mpc", "iterations", "2"),
        ("mpc", "bound", "10.0"),
        ("mpc", "effort", "0.5"),
        ("mpc", "plan_pendulums", "3"),
        ("mpc", "plan_step", "0.02"),
        ("mpc", "pd_training", "1.0"),
        ("mpc", "objective", "\"sum\""),
        ("mpc", "forecast", "\"none\""),
        ("mpc", "observe", "\"sensors\""),
        ("mpc", "hotspot", "\"b\""),
        ("mpc", "moment_about", "\"mean\""),
        ("mpc", "forecast_error", "0.5"),
        ("mpc", "forecast_seed", "3"),
        ("design", "max_iterations", "7"),
        ("design", "tolerance", "1e-3"),
        ("design", "hotspot", "\"a\""),
        ("design.parameter", "name", "\"beam.tip_stiffness\""),
        ("design.parameter", "lower", "20.0"),
        ("design.parameter", "upper", "500.0"),
    ];
    let doc = documented();
    let mut seen = BTreeSet::new();
    // keys of another profile replace the current's table (base: linear, speed 0.5)
    let base_current = "[loads.current]\nprofile = \"linear\"\nspeed = 0.5\n";
    for (key, current) in [
        (
            "exponent",
            "profile = \"power\"\nspeed = 0.5\nexponent = 0.2\n",
        ),
        ("table", "profile = \"table\"\ntable = [[0.0, 0.5, 0.0]]\n"),
    ] {
        assert!(
            doc["loads.current"].contains_key(key),
            "loads.current.{key}"
        );
        seen.insert(format!("loads.current.{key}"));
        let text = render(None).replace(base_current, &format!("[loads.current]\n{current}"));
        let scene = Scene::from_toml_str(&text).unwrap_or_else(|e| panic!("{e}\n{text}"));
        assert_ne!(scene, base, "loads.current.{key} changed nothing");
    }
    // `objective.exponent` goes with kind = "power" only.
    assert!(doc["objective"].contains_key("exponent"));
    seen.insert("objective.exponent".to_string());
    let power = render(Some(("objective", "kind", "\"power\"")))
        .replace("kind = \"power\"\n", "kind = \"power\"\nexponent = 3.0\n");
    let scene = Scene::from_toml_str(&power).unwrap_or_else(|e| panic!("{e}\n{power}"));
    assert_ne!(scene, base, "objective.exponent changed nothing");
    // `[pipe]` replaces `beam.length`, `mass` and `stiffness` (exclusive keys).
    let pipe_base = |set: Option<(&str, &str)>| {
        let mut pipe = vec![
            ("length", "10.0"),
            ("outer_diameter", "0.5"),
            ("wall_thickness", "0.02"),
        ];
        match set {
            Some((k, v)) if pipe.iter().any(|(key, _)| *key == k) => pipe
                .iter_mut()
                .filter(|(key, _)| *key == k)
                .for_each(|e| e.1 = v),
            Some(kv) => pipe.push(kv),
            None => {}
        }
        let body: String = pipe.iter().map(|(k, v)| format!("{k} = {v}\n")).collect();
        let text = without_design(render(None))
            .replace("length = 1.0\n", "")
            .replace("mass = 1.0\n", "")
            .replace("stiffness = 100.0\n", "");
        Scene::from_toml_str(&format!("{text}[pipe]\n{body}")).unwrap()
    };
    let with_pipe = pipe_base(None);
    for (key, value) in [
        ("length", "12.0"),
        ("outer_diameter", "0.6"),
        ("wall_thickness", "0.03"),
        ("youngs_modulus", "2e11"),
        ("steel_density", "7800.0"),
        ("contents_density", "1000.0"),
        ("drag_coefficient", "1.2"),
        ("added_mass_coefficient", "0.9"),
    ] {
        assert!(doc["pipe"].contains_key(key), "pipe.{key} not documented");
        seen.insert(format!("pipe.{key}"));
        assert_ne!(
            pipe_base(Some((key, value))),
            with_pipe,
            "pipe.{key} changed nothing"
        );
    }
    // `[loads.waves]` on a pipe (it needs its diameter), JONSWAP by default.
    let waves = |set: Option<(&str, &str)>| {
        let mut w = vec![
            ("spectrum", "\"jonswap\""),
            ("hs", "2.0"),
            ("tp", "8.0"),
            ("components", "64"),
        ];
        match set {
            Some((k, v)) if w.iter().any(|(key, _)| *key == k) => w
                .iter_mut()
                .filter(|(key, _)| *key == k)
                .for_each(|e| e.1 = v),
            Some(kv) => w.push(kv),
            None => {}
        }
        let body: String = w.iter().map(|(k, v)| format!("{k} = {v}\n")).collect();
        let text = without_design(render(None))
            .replace("length = 1.0\n", "")
            .replace("mass = 1.0\n", "")
            .replace("stiffness = 100.0\n", "");
        let text = format!(
            "{text}[pipe]\nlength = 10.0\nouter_diameter = 0.5\nwall_thickness = 0.02\n\n\
             [loads.waves]\n{body}"
        );
        Scene::from_toml_str(&text).unwrap_or_else(|e| panic!("{e}\n{text}"))
    };
    let with_waves = waves(None);
    for (key, value) in [
        ("spectrum", "\"pierson-moskowitz\""),
        ("hs", "3.0"),
        ("tp", "9.0"),
        ("gamma", "2.0"),
        ("seed", "5"),
        ("direction", "180.0"),
        ("components", "65"),
        ("lumping", "\"cell\""),
        ("record_step", "0.03"),
    ] {
        assert!(doc["loads.waves"].contains_key(key), "loads.waves.{key}");
        seen.insert(format!("loads.waves.{key}"));
        assert_ne!(waves(Some((key, value))), with_waves, "loads.waves.{key}");
    }
    // `[soil]` and `[stackup]` on the stack-up scene of `stackup_text`.
    let stack = Scene::from_toml_str(&stackup_text(None)).unwrap();
    for (table, key, value) in [
        ("soil", "mudline", "1.5"),
        ("soil", "modulus", "2e4"),
        ("soil", "gradient", "3e3"),
        ("stackup", "foot", "\"pinned\""),
        ("stackup", "drag_model", "\"morison\""),
        ("stackup.segment", "name", "\"z\""),
        ("stackup.segment", "length", "2.5"),
        ("stackup.segment", "joints", "2"),
        ("stackup.segment", "outer_diameter", "0.6"),
        ("stackup.segment", "wall_thickness", "0.03"),
        ("stackup.segment", "youngs_modulus", "2e11"),
        ("stackup.segment", "steel_density", "7800.0"),
        ("stackup.segment", "contents_density", "1000.0"),
        ("stackup.segment", "line_mass", "50.0"),
        ("stackup.segment", "line_area", "0.01"),
        ("stackup.segment", "buoyancy_diameter", "0.9"),
        ("stackup.segment", "buoyancy_density", "300.0"),
        ("stackup.segment", "hydrodynamic_diameter", "0.7"),
        ("stackup.segment", "drag_coefficient", "1.2"),
        ("stackup.segment", "added_mass_coefficient", "0.9"),
        ("stackup.segment", "refinement", "3.0"),
        ("stackup.body", "name", "\"d\""),
        ("stackup.body", "above", "\"a\""),
        ("stackup.body", "mass", "400.0"),
        ("stackup.body", "submerged_weight", "2500.0"),
        ("stackup.body", "height", "1.2"),
        ("stackup.body", "drag_area", "2.0"),
        ("stackup.body", "added_mass", "50.0"),
        ("stackup.body", "bending_stiffness", "1e8"),
        ("stackup.flex_joint", "name", "\"g\""),
        ("stackup.flex_joint", "stiffness", "2e5"),
        ("stackup.flex_joint", "above", "\"a\""),
        ("stackup.flex_joint", "elevation", "3.0"),
    ] {
        assert!(doc[table].contains_key(key), "{table}.{key} not documented");
        seen.insert(format!("{table}.{key}"));
        let text = stackup_text(Some((table, key, value)));
        let scene = Scene::from_toml_str(&text).unwrap_or_else(|e| panic!("{e}\n{text}"));
        assert_ne!(scene, stack, "{table}.{key} = {value} changed nothing");
    }
    // `[vessel]` and `[vessel.rao]` on the vessel scene of `vessel_text`.
    let held = Scene::from_toml_str(&vessel_text(None)).unwrap();
    for (table, key, value) in [
        ("vessel", "offset", "1.5"),
        ("vessel", "ramp", "3.0"),
        ("vessel", "mass", "5e7"),
        ("vessel", "added_mass", "2e6"),
        ("vessel", "damping", "4e5"),
        ("vessel", "thrust_bound", "2e6"),
        ("vessel", "thrust_rate_bound", "1e5"),
        ("vessel", "position_stiffness", "3e5"),
        ("vessel.rao", "period", "[6.0, 10.0]"),
        ("vessel.rao", "amplitude", "[0.3, 0.9]"),
        ("vessel.rao", "phase", "[-80.0, -90.0]"),
    ] {
        assert!(doc[table].contains_key(key), "{table}.{key} not documented");
        seen.insert(format!("{table}.{key}"));
        let text = vessel_text(Some((table, key, value)));
        let scene = Scene::from_toml_str(&text).unwrap_or_else(|e| panic!("{e}\n{text}"));
        assert_ne!(scene, held, "{table}.{key} = {value} changed nothing");
    }
    // `design.parameter.role = "uncertainty"` takes no bounds.
    assert!(doc["design.parameter"].contains_key("role"));
    seen.insert("design.parameter.role".to_string());
    let text = render(Some(("design", "max_iterations", "5")))
        .replace("lower = 10.0\nupper = 1000.0\n", "role = \"uncertainty\"\n");
    let scene = Scene::from_toml_str(&text).unwrap_or_else(|e| panic!("{e}\n{text}"));
    assert_ne!(scene, base, "design.parameter.role changed nothing");
    // `pipe.drag_model = "morison"` leaves `loads.drag` out (it does not use it).
    assert!(doc["pipe"].contains_key("drag_model"));
    seen.insert("pipe.drag_model".to_string());
    let momentum = pipe_base(None);
    let text = without_design(render(None))
        .replace("length = 1.0\n", "")
        .replace("mass = 1.0\n", "")
        .replace("stiffness = 100.0\n", "")
        .replace("drag = 1.0\n", "");
    let morison = Scene::from_toml_str(&format!(
        "{text}[pipe]\nlength = 10.0\nouter_diameter = 0.5\nwall_thickness = 0.02\n\
         drag_model = \"morison\"\n"
    ))
    .unwrap();
    assert_ne!(
        morison.pipe, momentum.pipe,
        "pipe.drag_model changed nothing"
    );
    for &(table, key, value) in settings {
        assert!(doc[table].contains_key(key), "{table}.{key} not documented");
        seen.insert(format!("{table}.{key}"));
        let text = render(Some((table, key, value)));
        let scene = Scene::from_toml_str(&text).unwrap_or_else(|e| panic!("{e}\n{text}"));
        assert_ne!(scene, base, "{table}.{key} = {value} changed nothing");
    }
    let all: BTreeSet<String> = doc
        .iter()
        .flat_map(|(t, rows)| rows.keys().map(move |k| format!("{t}.{k}")))
        .collect();
    assert_eq!(seen, all);
}

/// The "valid values" column agrees with the ranges the validation enforces.
#[test]
fn documented_ranges_are_the_enforced_ones() {
    fn short(x: f64) -> String {
        if x == 0.0 {
            "0".into()
        } else {
            format!("{x:e}")
        }
    }
    let doc = documented();
    let cell = |table: &str, key: &str| doc[table][key][4].clone();
    let range = |r: &ValueRange| format!("{} to {}", short(r.min), short(r.max));
    assert_eq!(cell("beam", "length"), range(&LENGTH_RANGE));
    assert_eq!(cell("beam", "mass"), range(&MASS_RANGE));
    for key in ["stiffness", "base_stiffness", "tip_stiffness"] {
        assert_eq!(cell("beam", key), range(&STIFFNESS_RANGE));
    }
    assert_eq!(cell("beam", "joint_damping"), range(&JOINT_DAMPING_RANGE));
    assert_eq!(cell("loads", "gravity"), range(&GRAVITY_RANGE));
    assert_eq!(cell("loads", "drag"), range(&DRAG_RANGE));
    assert_eq!(cell("loads.current", "speed"), range(&CURRENT_SPEED_RANGE));
    assert_eq!(cell("loads.point", "force"), range(&FORCE_RANGE));
    assert_eq!(
        cell("loads.point.harmonic", "amplitude"),
        range(&FORCE_RANGE)
    );
    assert_eq!(cell("loads.point.harmonic", "period"), range(&PERIOD_RANGE));
    assert!(cell("control", "values").starts_with(&range(&FORCE_RANGE)));
    assert_eq!(cell("time", "step"), range(&STEP_RANGE));
    assert_eq!(cell("soil", "modulus"), range(&SOIL_MODULUS_RANGE));
    assert_eq!(cell("soil", "gradient"), range(&SOIL_GRADIENT_RANGE));
    assert!(cell("soil", "mudline").starts_with(&range(&SOIL_MUDLINE_RANGE)));
    // The stack-up's keys: each table's cell starts with the range the validation enforces.
    for table in ["stackup.segment", "stackup.body", "stackup.flex_joint"] {
        for (key, row) in &doc[table] {
            if let Some(r) = chainbeam::scene::stackup_range_of(key) {
                assert!(row[4].starts_with(&range(&r)), "{table}.{key}: {}", row[4]);
            }
        }
    }
    assert_eq!(cell("beam", "pendulums"), format!("1 to {MAX_PENDULUMS}"));
    assert!(cell("time", "steps").starts_with(&format!("1 to {MAX_STEPS}")));
    // and the same numbers in the summary table of "Valid ranges"
    let text = read("docs/scene-format.md");
    for (name, r) in [
        ("length l", &LENGTH_RANGE),
        ("mass m", &MASS_RANGE),
        ("spring k (interior, base, tip)", &STIFFNESS_RANGE),
        ("joint damper c", &JOINT_DAMPING_RANGE),
        ("force F, control u", &FORCE_RANGE),
        ("harmonic amplitude A, series forces", &FORCE_RANGE),
        ("harmonic period T", &PERIOD_RANGE),
        ("gravity g", &GRAVITY_RANGE),
        ("drag D", &DRAG_RANGE),
        ("current speed U", &CURRENT_SPEED_RANGE),
        ("time step h", &STEP_RANGE),
    ] {
        let row = format!("| {name} | {} | {} |", range(r), r.unit);
        assert!(text.contains(&row), "missing row {row}");
    }
}

/// Every `toml` block of the document is a valid scene (the first one is the thesis's riser
/// scene, catalogue::riser(5); the wave example is catalogue::wave_riser()). Series files are
/// named relative to examples/scenes/, where the shipped one is.
#[test]
fn documented_examples_are_valid_scenes() {
    let text = read("docs/scene-format.md");
    let blocks: Vec<&str> = text
        .split("```toml\n")
        .skip(1)
        .map(|b| b.split("```").next().unwrap())
        .collect();
    assert_eq!(blocks.len(), 8);
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("examples/scenes");
    let mut scenes = Vec::new();
    for b in &blocks {
        let scene = Scene::from_toml_str_in_dir(b, &dir).unwrap_or_else(|e| panic!("{e}\n{b}"));
        chainbeam::simulate(&scene).unwrap();
        scenes.push(scene);
    }
    // scenes[1] is the hot spots' example of `[[fatigue.hotspot]]`.
    assert_eq!(scenes[1].hotspots.len(), 2);
    assert_eq!(scenes[5], chainbeam::catalogue::wave_riser());
    assert!(scenes[6].is_spatial() && !scenes[5].is_spatial());
    assert_eq!(scenes[7], chainbeam::catalogue::sheared_current());
    assert_eq!(
        Scene::from_toml_str(blocks[0]).unwrap(),
        chainbeam::catalogue::riser(5)
    );
}

/// A clone of the repository holds only the repository: no source, test, example, bench, script
/// or document may point a reader to the workplace's shared folder, to a design note by its file
/// name, or to an issue by its number (the reasons are written out where they matter, and the
/// design notes live in docs/: ocean.md, fatigue.md, riccati.md). The needles are assembled
/// here so that this file does not contain them itself.
#[test]
fn docs_stay_inside_the_repository() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let mut needles: Vec<String> = ["OCEAN", "RISER", "RICCATI", "SPEC", "STYLE"]
        .iter()
        .map(|n| format!("{n}.md"))
        .collect();
    needles.push(["shared", ""].join("/"));
    needles.push(format!("thesis.{}", "txt"));
    needles.push(format!("SPEC {}", '§'));
    let mut files = vec![root.join("README.md")];
    for dir in [
        "src", "crates", "python", "tests", "examples", "docs", "benches", "scripts",
    ] {
        collect_files(&root.join(dir), &mut files);
    }
    assert!(files.len() > 100, "only {} files found", files.len());
    let mut found = Vec::new();
    for file in &files {
        // Binary files (figures, .npy) and the deliberately invalid UTF-8 fixtures are not read.
        let Ok(text) = std::fs::read_to_string(file) else {
            continue;
        };
        let name = file
            .strip_prefix(root)
            .unwrap_or(file)
            .display()
            .to_string();
        for (i, line) in text.lines().enumerate() {
            let lower = line.to_lowercase();
            let issue = lower.match_indices("issue ").any(|(at, _)| {
                lower[at + 6..]
                    .chars()
                    .next()
                    .is_some_and(|c| c.is_ascii_digit())
            });
            if issue || needles.iter().any(|n| line.contains(n.as_str())) {
                found.push(format!("{name}:{}: {line}", i + 1));
            }
        }
    }
    assert!(found.is_empty(), "{}", found.join("\n"));
}

/// Every file under `dir` (recursively), leaving out hidden folders and Python caches.
fn collect_files(dir: &Path, out: &mut Vec<std::path::PathBuf>) {
    let Ok(entries) = std::fs::read_dir(dir) else {
        return;
    };
    for entry in entries.flatten() {
        let path = entry.path();
        let name = entry.file_name().to_string_lossy().into_owned();
        if path.is_dir() {
            if !name.starts_with('.') && name != "__pycache__" && name != "target" {
                collect_files(&path, out);
            }
        } else {
            out.push(path);
        }
    }
}
