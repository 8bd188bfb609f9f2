//! Property tests over the sea-state, scatter and fatigue inputs with extreme and non-finite
//! values: every input is accepted (and then runs to a finite result or a typed runtime error)
//! or refused with a scene or fatigue error naming a key; none panics, aborts or allocates
//! without bound. A small riser (n = 3, 40 steps of 0.05 s) keeps each case to milliseconds;
//! the whole file stays well under a minute in CI (`cargo test --test fatigue sea_fatigue_proptest::`).

use chainbeam::fatigue::scatter::{parse_scatter, ScatterFileErrorKind};
use chainbeam::fatigue::{assess, MomentHistory};
use chainbeam::fatigue_study::{run_study, ControlSettings, ControllerKind, StudyInput};
use chainbeam::{moment_history, Scene, SceneErrorKind};
use proptest::prelude::*;

/// A number from the hostile menu: zero, signs, the ends of f64, subnormals, NaN and the
/// infinities, values just around the limits of the keys, or an ordinary value.
fn hostile() -> impl Strategy<Value = f64> {
    prop_oneof![
        3 => prop::sample::select(vec![
            0.0,
            -0.0,
            -1.0,
            1e-300,
            5e-324,
            1e-3,
            6.5e-3,
            0.05,
            1e300,
            f64::MAX,
            f64::MIN_POSITIVE,
            f64::NAN,
            f64::INFINITY,
            f64::NEG_INFINITY,
            0.5,
            1.0,
            10.0,
            11.0,
        ]),
        2 => 0.1f64..30.0,
    ]
}

/// A float as TOML (`nan`, `inf`, `-inf` included).
fn toml(x: f64) -> String {
    if x.is_nan() {
        "nan".into()
    } else if x.is_infinite() {
        if x > 0.0 { "inf" } else { "-inf" }.into()
    } else {
        format!("{x:?}")
    }
}

#[derive(Clone, Debug)]
struct SeaKeys {
    hs: f64,
    tp: f64,
    gamma: Option<f64>,
    direction: f64,
    depth: f64,
    components: Option<i64>,
    scf: f64,
    dff: f64,
}

fn sea_keys() -> impl Strategy<Value = SeaKeys> {
    (
        hostile(),
        hostile(),
        prop::option::of(hostile()),
        prop_oneof![Just(0.0), hostile()],
        hostile(),
        prop::option::of(prop::sample::select(vec![
            -1i64,
            0,
            1,
            7,
            200,
            10_000_001,
            i64::MAX,
        ])),
        prop_oneof![Just(1.0), hostile()],
        prop_oneof![Just(1.0), hostile()],
    )
        .prop_map(
            |(hs, tp, gamma, direction, depth, components, scf, dff)| SeaKeys {
                hs,
                tp,
                gamma,
                direction,
                depth,
                components,
                scf,
                dff,
            },
        )
}

/// The riser with those keys (a `[fatigue]` table whose section is the `[pipe]`'s).
fn scene_text(k: &SeaKeys) -> String {
    let gamma = k
        .gamma
        .map_or(String::new(), |g| format!("gamma = {}\n", toml(g)));
    let components = k
        .components
        .map_or(String::new(), |c| format!("components = {c}\n"));
    format!(
        "[beam]\npendulums = 3\nsupport = \"riser\"\n\n\
         [pipe]\nlength = 30.0\nouter_diameter = 0.5334\nwall_thickness = 0.0222\n\n\
         [water]\ndepth = {}\n\n\
         [loads]\ndrag = 1e-4\ntension = 1e6\n\n\
         [loads.waves]\nspectrum = \"jonswap\"\nhs = {}\ntp = {}\nseed = 3\ndirection = {}\n\
         {gamma}{components}\n\
         [fatigue]\nscf = {}\ndff = {}\n\n\
         [time]\nstep = 0.05\nsteps = 40\n",
        toml(k.depth),
        toml(k.hs),
        toml(k.tp),
        toml(k.direction),
        toml(k.scf),
        toml(k.dff),
    )
}

/// Whether a case would ask for a sea of millions of components (T_p of a few ms is valid but
/// slow: 10⁷ components take seconds and gigabytes): such scenes are only parsed.
fn heavy(k: &SeaKeys) -> bool {
    k.tp.is_finite() && k.tp > 0.0 && k.tp < 0.5 && k.components.is_none()
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 160, ..ProptestConfig::default() })]

    /// A scene with hostile sea and fatigue keys is refused naming a key of `[loads.waves]`,
    /// `[water]` or `[fatigue]`, or runs to a finite damage or a typed runtime error.
    #[test]
    fn sea_and_fatigue_keys_never_abort(k in sea_keys()) {
        let text = scene_text(&k);
        let scene = match Scene::from_toml_str(&text) {
            Err(e) => {
                let key = match &e.kind {
                    SceneErrorKind::InvalidValue { key, .. }
                    | SceneErrorKind::MissingKey { key, .. }
                    | SceneErrorKind::ExclusiveKeys { key, .. }
                    | SceneErrorKind::WrongType { key, .. } => key.clone(),
                    other => panic!("{other:?} for\n{text}"),
                };
                prop_assert!(
                    ["loads.waves.", "water.", "fatigue.", "time."]
                        .iter()
                        .any(|p| key.starts_with(p)),
                    "{key}: {e}\n{text}"
                );
                return Ok(());
            }
            Ok(s) => s,
        };
        if heavy(&k) {
            return Ok(());
        }
        let spec = scene.fatigue_spec().expect("a [fatigue] table");
        match moment_history(&scene) {
            Ok(h) => {
                if let Ok(a) = assess(&spec, MomentHistory {
                    duration_s: h.duration(),
                    moment: &h.moment,
                    moment_x: h.moment_x.as_deref(),
                    measure: scene.moment_measure(),
                }) {
                    prop_assert!(a.damage.is_finite() && a.damage >= 0.0, "{a:?}");
                }
            }
            // A typed runtime error (a folded beam, a non-finite state named): not a panic.
            Err(e) => prop_assert!(!e.to_string().is_empty()),
        }
    }

    /// A scatter CSV with hostile fields is refused naming the line and column (or the
    /// diagram), or its cells are the file's numbers; a diagram that parses runs through the
    /// study (its cells' scenes refused with the cell named, or assessed to a finite damage).
    #[test]
    fn scatter_files_never_abort(
        rows in prop::collection::vec((hostile(), hostile(), hostile()), 0..4),
        duplicate in any::<bool>(),
    ) {
        let mut text = String::from(if duplicate { "hs,tp,probability,hs\n" } else { "hs,tp,probability\n" });
        for (hs, tp, p) in &rows {
            text.push_str(&format!("{},{},{}", toml(*hs), toml(*tp), toml(*p)));
            text.push_str(if duplicate { ",1.0\n" } else { "\n" });
        }
        let cells = match parse_scatter(&text) {
            Err(e) => {
                prop_assert!(!matches!(e, ScatterFileErrorKind::Csv { .. }), "{e}");
                if duplicate {
                    prop_assert!(matches!(e, ScatterFileErrorKind::DuplicateColumn { .. }), "{e}");
                }
                return Ok(());
            }
            Ok(c) => c,
        };
        prop_assert!(!duplicate);
        prop_assert!(cells.iter().map(|c| c.probability).sum::<f64>() > 0.0);
        for (c, (hs, tp, p)) in cells.iter().zip(&rows) {
            prop_assert_eq!((c.sea.hs, c.sea.tp, c.probability), (*hs, *tp, *p));
        }
        if cells.iter().any(|c| c.sea.tp < 0.5) {
            // A valid but heavy sea (see `heavy`): the file is what is tested here.
            return Ok(());
        }
        let keys = SeaKeys {
            hs: 2.0, tp: 9.0, gamma: None, direction: 0.0, depth: 30.0, components: None,
            scf: 1.0, dff: 1.0,
        };
        let scene = Scene::from_toml_str(&scene_text(&keys)).unwrap();
        let spec = scene.fatigue_spec().unwrap();
        let input = StudyInput {
            scene: &scene,
            spec: &spec,
            cells: Some(&cells),
            controllers: &[ControllerKind::None],
            settings: &ControlSettings::default(),
        };
        match run_study(&input, &|| {}) {
            Ok(study) => {
                let d = study.controllers[0].damage_per_year;
                prop_assert!(d.is_finite() && d >= 0.0, "{d}");
            }
            Err(e) => prop_assert!(!e.to_string().is_empty()),
        }
    }
}
