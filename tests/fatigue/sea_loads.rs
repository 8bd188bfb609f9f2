//! Irregular waves on a riser (`[loads.waves]`; docs/scene-format.md, docs/ocean.md):
//! the keys and their errors, the per-pendulum wave kinematics of the model against the direct
//! sum of the Airy components (an independent evaluation: `Sea::velocity` / `Sea::acceleration`
//! cosine by cosine), and the round trip through a scene file.

use chainbeam::model::Ctx;
use chainbeam::ocean::Sea;
use chainbeam::scene::{WaveLumping, WaveSpectrum, Waves};
use chainbeam::*;

/// A 100 m pipe riser (21" drilling riser section) in 100 m of water under a JONSWAP sea, with
/// `extra` appended to `[loads.waves]` and `drag` as D.
pub fn wave_scene(extra: &str, drag: f64) -> String {
    format!(
        "[beam]\npendulums = 10\nsupport = \"riser\"\n\n\
         [pipe]\nlength = 100.0\nouter_diameter = 0.5334\nwall_thickness = 0.0222\n\n\
         [water]\ndepth = 100.0\n\n\
         [loads]\ndrag = {drag:e}\ntension = 2e6\naxial_weight = 1500.0\n\n\
         [loads.waves]\nspectrum = \"jonswap\"\nhs = 4.0\ntp = 10.0\nseed = 7\n{extra}\n\
         [time]\nstep = 0.05\nsteps = 200\n"
    )
}

fn key_of(e: &SceneError) -> String {
    match &e.kind {
        SceneErrorKind::InvalidValue { key, .. }
        | SceneErrorKind::MissingKey { key, .. }
        | SceneErrorKind::ExclusiveKeys { key, .. }
        | SceneErrorKind::WrongType { key, .. }
        | SceneErrorKind::UnknownKey { key, .. } => key.clone(),
        other => format!("{other:?}"),
    }
}

#[test]
fn bad_values_are_refused_naming_the_key() {
    let base = wave_scene("", 1e-6);
    assert!(Scene::from_toml_str(&base).is_ok());
    let cases: &[(&str, &str, &str)] = &[
        ("hs = 4.0", "hs = -1.0", "loads.waves.hs"),
        ("hs = 4.0", "hs = nan", "loads.waves.hs"),
        ("tp = 10.0", "tp = 0.0", "loads.waves.tp"),
        ("seed = 7", "seed = -3", "loads.waves.seed"),
        ("seed = 7", "seed = 7\ngamma = 0.5", "loads.waves.gamma"),
        ("seed = 7", "seed = 7\ngamma = 11.0", "loads.waves.gamma"),
        (
            "seed = 7",
            "seed = 7\ncomponents = 0",
            "loads.waves.components",
        ),
        (
            "seed = 7",
            "seed = 7\ndirection = inf",
            "loads.waves.direction",
        ),
        ("seed = 7", "seed = 7\nhieght = 2.0", "loads.waves.hieght"),
        (
            "spectrum = \"jonswap\"",
            "spectrum = \"bretschneider\"",
            "loads.waves.spectrum",
        ),
        (
            "spectrum = \"jonswap\"",
            "spectrum = \"pierson-moskowitz\"\ngamma = 2.0",
            "loads.waves.gamma",
        ),
        ("step = 0.05", "step = 1e-6", "time.step"),
        (
            "seed = 7",
            "seed = 7\nlumping = \"cells\"",
            "loads.waves.lumping",
        ),
    ];
    for (from, to, key) in cases {
        let text = base.replacen(from, to, 1);
        let err = Scene::from_toml_str(&text).expect_err(to);
        assert_eq!(key_of(&err), *key, "{to}: {err}");
    }
    // No pipe: the inertia load has no diameter.
    let text = "[beam]\npendulums = 4\nlength = 1.0\nmass = 1.0\nstiffness = 100.0\n\
                support = \"riser\"\n[loads]\ndrag = 1.0\n\
                [loads.waves]\nspectrum = \"jonswap\"\nhs = 1.0\ntp = 5.0\n\
                [time]\nstep = 0.01\nsteps = 10\n";
    let err = Scene::from_toml_str(text).unwrap_err();
    assert_eq!(key_of(&err), "pipe", "{err}");
}

#[test]
fn keys_read_and_write_back() {
    let text = wave_scene("direction = 30.0\ncomponents = 500\ngamma = 2.5", 1e-6);
    let scene = Scene::from_toml_str(&text).unwrap();
    let w = scene.loads.waves.unwrap();
    assert_eq!(
        w,
        Waves {
            spectrum: WaveSpectrum::Jonswap,
            hs: 4.0,
            tp: 10.0,
            gamma: Some(2.5),
            seed: 7,
            direction: 30.0,
            components: Some(500),
            lumping: WaveLumping::Node,
            record_step: None,
        }
    );
    assert!(scene.is_spatial());
    assert_eq!(
        scene.spatial_key().as_deref(),
        Some("loads.waves.direction")
    );
    let again = Scene::from_toml_str(&scene.to_toml_string()).unwrap();
    assert_eq!(again, scene);
    // 0° and 180° stay in the y–z plane.
    for d in ["0.0", "180.0"] {
        let s = Scene::from_toml_str(&wave_scene(&format!("direction = {d}"), 1e-6)).unwrap();
        assert!(!s.is_spatial(), "direction {d}");
    }
}

/// The model's per-pendulum series (suffix sums of complex amplitudes, one inverse FFT per
/// pendulum) against the direct sums u(y, t) = Σⱼ ωⱼ aⱼ cosh(kⱼ y)/sinh(kⱼ d) cos(ωⱼ t + φⱼ)
/// of `Sea::velocity` and `Sea::acceleration`, node by node: Wᵢ = lᵢ Σ_{k≥i} m_k u_k and
/// Gᵢ = lᵢ Σ_{k≥i} ρ_w (1 + C_a) A_o c_k u̇_k, on the grid, between grid times (linear
/// interpolation) and beyond the record (the direct continuation).
#[test]
fn kinematics_equal_the_direct_sum_of_the_components() {
    let scene = Scene::from_toml_str(&wave_scene("components = 300", 1e-6)).unwrap();
    let chain = Chain::<f64, 2>::from_scene(&scene).unwrap();
    let field = chain.waves().expect("waves");
    let sea: &Sea = field.sea();
    let pipe = scene.pipe.unwrap();
    let c_in = scene.water.density * (1.0 + pipe.added_mass_coefficient) * pipe.outer_area();
    let (l, m) = (&scene.beam.lengths, &scene.beam.masses);
    let n = scene.n();
    let y: Vec<f64> = (1..=n).map(|k| l[..k].iter().sum()).collect();
    let direct = |i: usize, t: f64| {
        let (mut w, mut g) = (0.0, 0.0);
        for k in i..n {
            let cell = 0.5 * (l[k] + if k + 1 < n { l[k + 1] } else { 0.0 });
            w += m[k] * sea.velocity(y[k], t);
            g += c_in * cell * sea.acceleration(y[k], t);
        }
        (l[i] * w, l[i] * g)
    };
    let h = scene.time.step;
    let (mut scale_w, mut scale_g, mut err_w, mut err_g) = (0.0f64, 0.0f64, 0.0f64, 0.0f64);
    for k in (0..=scene.time.steps).step_by(7) {
        let t = k as f64 * h;
        for i in 0..n {
            let (w, g) = direct(i, t);
            scale_w = scale_w.max(w.abs());
            scale_g = scale_g.max(g.abs());
            err_w = err_w.max((field.momentum(i, t) - w).abs());
            err_g = err_g.max((field.inertia(i, t) - g).abs());
        }
        assert!((field.elevation(t) - sea.elevation(t)).abs() < 1e-12 * 4.0);
    }
    assert!(scale_w > 0.0 && scale_g > 0.0);
    assert!(err_w < 1e-10 * scale_w, "W: {err_w:e} of {scale_w:e}");
    assert!(err_g < 1e-10 * scale_g, "G: {err_g:e} of {scale_g:e}");
    // Midpoints: the mean of the neighbours (RATTLE's drag reads t_k + h/2).
    let t = 40.5 * h;
    let mid = 0.5 * (field.momentum(3, 40.0 * h) + field.momentum(3, 41.0 * h));
    assert!((field.momentum(3, t) - mid).abs() <= 1e-12 * scale_w);
    // Beyond the record: the direct sum.
    let t = (scene.time.steps as f64 + 10.3) * h;
    let (w, _) = direct(2, t);
    assert!((field.momentum(2, t) - w).abs() < 1e-10 * scale_w);
}

/// With the waves, the drag relative to the water at rest (p = 0) is Dᵢ |P_⊥| P_⊥ with the water
/// momentum Pᵢ(t) = lᵢ Σ_{k≥i} m_k (U_k + u_k(t) e) (docs/conventions.md "Drag in a current") and
/// the `[pipe]` chain's per-pendulum Dᵢ = D l₁S₁/(lᵢSᵢ), Sᵢ = Σ_{k≥i} m_k ("Equivalent drag
/// constant, per pendulum"),
/// and with `tension`, `axial_weight` and no waves the scene is the one without the table.
#[test]
fn the_water_momentum_adds_current_and_waves() {
    let text = wave_scene("direction = 0.0", 2e-6).replace(
        "[loads.waves]",
        "[loads.current]\nprofile = \"uniform\"\nspeed = 0.4\n\n[loads.waves]",
    );
    let scene = Scene::from_toml_str(&text).unwrap();
    let chain = Chain::<f64, 2>::from_scene(&scene).unwrap();
    let field = chain.waves().unwrap();
    let (l, m) = (&scene.beam.lengths, &scene.beam.masses);
    let t = 3.25;
    let ctx = Ctx::new(t, 0.0, 0);
    for i in [0, 4, 9] {
        let big = l[i] * m[i..].iter().sum::<f64>() * 0.4 + field.momentum(i, t);
        let f = chain.dissipative_force(i, &[0.0, 0.0], &ctx).unwrap();
        let weight = l[0] * m.iter().sum::<f64>() / (l[i] * m[i..].iter().sum::<f64>());
        let want = 2e-6 * weight * big.abs() * big;
        assert!(
            (f[1] - want).abs() <= 1e-12 * want.abs(),
            "{i}: {f:?} {want}"
        );
        assert_eq!(f[0], 0.0);
    }
}

/// `lumping = "cell"`: the exact cell mean of the Airy profile ([`chainbeam::ocean::cell_profile`])
/// against a 20-point Gauss-Legendre quadrature of `depth_profile` over the cell (an independent
/// evaluation), including a cell reaching above the surface (clamped to the surface's
/// kinematics) and shallow and deep components; the model's series with it against the direct
/// sum of the same cell means; the key reads and writes back.
#[test]
fn cell_lumping_averages_the_profile_over_each_cell() {
    use chainbeam::ocean::{cell_profile, depth_profile};
    // Gauss-Legendre nodes and weights of order 20 on [-1, 1] (the 10 positive nodes): the
    // roots of P₂₀ by Newton's method from cos(π(i − ¼)/(20 + ½)), w = 2/((1 − x²) P₂₀′(x)²).
    let legendre = |x: f64| {
        let (mut p0, mut p1) = (1.0, x);
        for k in 2..=20 {
            let p2 = ((2 * k - 1) as f64 * x * p1 - (k - 1) as f64 * p0) / k as f64;
            (p0, p1) = (p1, p2);
        }
        (p1, 20.0 * (x * p1 - p0) / (x * x - 1.0))
    };
    let (mut nodes, mut weights) = ([0.0; 10], [0.0; 10]);
    for i in 0..10 {
        let mut x = (std::f64::consts::PI * (i as f64 + 0.75) / 20.5).cos();
        for _ in 0..100 {
            let (p, dp) = legendre(x);
            x -= p / dp;
        }
        let (_, dp) = legendre(x);
        nodes[i] = x;
        weights[i] = 2.0 / ((1.0 - x * x) * dp * dp);
    }
    assert!((weights.iter().sum::<f64>() - 1.0).abs() < 1e-14);
    let gauss = |f: &dyn Fn(f64) -> f64, a: f64, b: f64| {
        let (c, r) = (0.5 * (a + b), 0.5 * (b - a));
        nodes
            .iter()
            .zip(weights)
            .map(|(x, w)| w * (f(c - r * x) + f(c + r * x)))
            .sum::<f64>()
            * 0.5
    };
    let d = 300.0;
    for k in [1e-3, 0.02, 0.07, 0.3, 1.0] {
        for (y0, y1) in [
            (0.0, 1.875),
            (150.0, 155.0),
            (290.0, 297.5),
            (296.25, 300.0),
        ] {
            let q = gauss(&|y| depth_profile(k, y, d), y0, y1);
            let c = cell_profile(k, (y0, y1), d);
            assert!(
                (c - q).abs() <= 1e-12 * q.abs().max(1e-300),
                "k {k}, [{y0}, {y1}]: {c} vs {q}"
            );
        }
        // Cut by the surface: the part beyond d holds no water and adds nothing (the profile
        // is 0 above the mean surface), so the mean is the wet part's integral over the cell.
        let (y0, y1) = (298.0, 302.0);
        let q = gauss(&|y| depth_profile(k, y, d), y0, d) * (d - y0) / (y1 - y0);
        let c = cell_profile(k, (y0, y1), d);
        assert!((c - q).abs() <= 1e-12 * q, "k {k}: {c} vs {q}");
    }

    // The model's series with cell lumping: Wᵢ = lᵢ Σ_{k≥i} m_k ū_k with ū_k the cell mean.
    let scene =
        Scene::from_toml_str(&wave_scene("components = 300\nlumping = \"cell\"", 1e-6)).unwrap();
    assert_eq!(scene.loads.waves.unwrap().lumping, WaveLumping::Cell);
    let again = Scene::from_toml_str(&scene.to_toml_string()).unwrap();
    assert_eq!(again, scene);
    let chain = Chain::<f64, 2>::from_scene(&scene).unwrap();
    let field = chain.waves().expect("waves");
    let sea: &Sea = field.sea();
    let (l, m) = (&scene.beam.lengths, &scene.beam.masses);
    let n = scene.n();
    let y: Vec<f64> = (1..=n).map(|k| l[..k].iter().sum()).collect();
    let mean_velocity = |k: usize, t: f64| {
        let (a, b) = (
            y[k] - 0.5 * l[k],
            y[k] + 0.5 * l.get(k + 1).copied().unwrap_or(0.0),
        );
        gauss(&|z| sea.velocity(z, t), a, b) / 1.0
    };
    let mut scale = 0.0f64;
    let mut err = 0.0f64;
    for step in (0..=scene.time.steps).step_by(23) {
        let t = step as f64 * scene.time.step;
        for i in [0, 4, n - 1] {
            let w: f64 = l[i] * (i..n).map(|k| m[k] * mean_velocity(k, t)).sum::<f64>();
            scale = scale.max(w.abs());
            err = err.max((field.momentum(i, t) - w).abs());
        }
    }
    assert!(scale > 0.0);
    assert!(err < 1e-10 * scale, "W: {err:e} of {scale:e}");
    // Node lumping is the default and differs (the profile is convex in y).
    let node = Scene::from_toml_str(&wave_scene("components = 300", 1e-6)).unwrap();
    let node_chain = Chain::<f64, 2>::from_scene(&node).unwrap();
    let nf = node_chain.waves().unwrap();
    assert!((nf.momentum(n - 1, 3.0) - field.momentum(n - 1, 3.0)).abs() > 1e-9 * scale);
}
