//! The sea within its domain: a derived number of components held to the limits a given one
//! has, no wave kinematics above the mean surface (in the profile, the cell mean, the model's
//! loads and the fatigue damage they cause), a tiny water depth without NaN, and the wave record
//! of a short run formed at the cost of the run (the zoom transform) equal to the repeat
//! period's inverse FFT to round-off.

use chainbeam::fatigue::{assess, MomentHistory};
use chainbeam::ocean::{
    cell_profile, depth_profile, Complex, Sea, SeaError, SeaSpec, Spectrum, SURFACE_TOLERANCE,
};
use chainbeam::{moment_history, Scene, SceneError, SceneErrorKind};

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

/// A pipe riser of `length` m and `n` pendulums in `depth` m of water under a JONSWAP sea of
/// peak period `tp`, D = `drag`, `steps` steps of 0.05 s; no `[fatigue]` table (the `[pipe]`'s
/// section serves).
fn riser(length: f64, n: usize, depth: f64, tp: f64, drag: f64, steps: usize) -> String {
    format!(
        "[beam]\npendulums = {n}\nsupport = \"riser\"\n\n\
         [pipe]\nlength = {length:?}\nouter_diameter = 0.5334\nwall_thickness = 0.0222\n\n\
         [water]\ndepth = {depth:e}\n\n\
         [loads]\ndrag = {drag:e}\ntension = 2e6\naxial_weight = 1500.0\n\n\
         [loads.waves]\nspectrum = \"jonswap\"\nhs = 4.0\ntp = {tp:e}\nseed = 7\n\n\
         [time]\nstep = 0.05\nsteps = {steps}\n"
    )
}

/// A peak period so short that the default ⌊6 T_r/T_p⌋ components exceed the limit of a given
/// `components` (10⁷) is refused naming `loads.waves.tp`, from the sea and from a scene, for
/// every value down to the smallest subnormal (these used to abort on a 6 GB – 500 TB
/// allocation). An explicit count keeps its own limit.
#[test]
fn short_peak_periods_are_refused_not_aborted() {
    let depth = 100.0;
    for tp in [1e-3, 1e-6, 1e-300, 5e-324] {
        let s = Spectrum::jonswap(4.0, tp, 3.3).unwrap();
        match Sea::new(&SeaSpec::new(s, depth, 0), 0.05, 10.0) {
            Err(SeaError::TooManyComponents { needed, limit, .. }) => {
                // 6 T_r/T_p with T_r = 3 h.
                assert!(needed > limit as f64, "tp {tp}: {needed}");
                assert!(needed >= (6.0 * 10_800.0 / tp).min(f64::MAX) * (1.0 - 1e-9));
            }
            other => panic!("tp {tp}: {other:?}"),
        }
        let e = Scene::from_toml_str(&riser(100.0, 4, depth, tp, 0.0, 10)).unwrap_err();
        assert_eq!(key_of(&e), "loads.waves.tp", "tp {tp}: {e}");
        assert!(e.to_string().contains("components"), "{e}");
    }
    // At the limit's edge: 6 · 10 800 / T_p ≤ 10⁷ for T_p ≥ 6.48 ms, accepted by the sea (the
    // scene then weighs the amplitudes' memory).
    let s = Spectrum::jonswap(4.0, 0.0065, 3.3).unwrap();
    let sea = Sea::new(&SeaSpec::new(s, depth, 0), 0.05, 10.0).unwrap();
    assert!(sea.frequencies().len() <= 10_000_000);
}

/// Above the mean surface there is no water: the depth profile is 0 beyond y = d (1 + 10⁻⁹),
/// the surface's value within that tolerance, and the mean over a cell cut by the surface is
/// the integral over its wet part over the cell's whole length (checked against a 20 000-point
/// midpoint rule of the profile).
#[test]
fn the_waves_stop_at_the_surface() {
    let (k, d) = (0.05, 40.0);
    let at_surface = depth_profile(k, d, d);
    assert!(at_surface > 0.0);
    assert_eq!(
        depth_profile(k, d * (1.0 + 0.5 * SURFACE_TOLERANCE), d),
        at_surface
    );
    assert_eq!(
        depth_profile(k, d * (1.0 + 2.0 * SURFACE_TOLERANCE), d),
        0.0
    );
    assert_eq!(depth_profile(k, 1e6, d), 0.0);
    assert_eq!(cell_profile(k, (41.0, 45.0), d), 0.0);
    let (y0, y1) = (36.0, 46.0);
    let m = 20_000;
    let dy = (y1 - y0) / m as f64;
    let quad: f64 = (0..m)
        .map(|i| depth_profile(k, y0 + (i as f64 + 0.5) * dy, d) * dy)
        .sum::<f64>()
        / (y1 - y0);
    let exact = cell_profile(k, (y0, y1), d);
    // The midpoint rule's error on the smooth wet part is O(dy²); the jump at the surface falls
    // on a cell edge of the rule (y = 40 = 36 + 8000 dy).
    assert!((exact / quad - 1.0).abs() < 1e-8, "{exact} vs {quad}");
    // The wet part alone, by the closed form over [36, 40] scaled by its fraction 4/10.
    let wet = cell_profile(k, (y0, d), d) * (d - y0) / (y1 - y0);
    assert!((exact / wet - 1.0).abs() < 1e-14, "{exact} vs {wet}");
}

/// The wellhead damage of a riser whose top stands above the water equals that of the same
/// riser with the wave loads of its submerged nodes alone, given as point loads: a 100 m riser
/// of 10 pendulums in 55 m of water (nodes 1–5 at 10 … 50 m wet, 6–10 dry), D = 0 so that the
/// waves act by their inertia load only. The reference's loads are computed independently of
/// the model's wave field: F_k(t) = ρ_w (1 + C_a) A_o c_k u̇(y_k, t) (Morison's inertia term,
/// DNV-RP-C205 eq. 6.2.1; c_k the node's cell l) by the direct Airy sum
/// [`Sea::acceleration`], one row per step, read by linear interpolation as the model reads its
/// record; the upper pendulums carry no load. The model used to give the dry nodes the
/// surface's kinematics.
#[test]
fn a_riser_above_the_water_has_the_damage_of_its_wet_part() {
    let (length, n, depth, steps) = (100.0, 10, 55.0, 2000);
    let text = riser(length, n, depth, 10.0, 0.0, steps);
    let wet = Scene::from_toml_str(&text).unwrap();
    let spec = wet.fatigue_spec().expect("the [pipe]'s section");
    let damage = |s: &Scene| {
        let h = moment_history(s).unwrap();
        assess(
            &spec,
            MomentHistory {
                duration_s: h.duration(),
                moment: &h.moment,
                moment_x: None,
                measure: s.moment_measure(),
            },
        )
        .unwrap()
        .damage
    };
    let d_model = damage(&wet);

    // The reference: no waves, the submerged nodes' inertia loads as series.
    let w = wet.loads.waves.unwrap();
    let pipe = wet.pipe.unwrap();
    let sea = Sea::new(
        &w.sea_spec(depth).unwrap(),
        wet.time.step,
        steps as f64 * 0.05,
    )
    .unwrap();
    let coeff = wet.water.density * (1.0 + pipe.added_mass_coefficient) * pipe.outer_area();
    let dir = tempfile::tempdir().unwrap();
    let mut reference = text.split("[loads.waves]").next().unwrap().to_string();
    let l = length / n as f64;
    let mut wet_nodes = 0;
    for node in 1..=n {
        let y = node as f64 * l;
        if y > depth {
            continue;
        }
        wet_nodes += 1;
        let cell = if node == n { 0.5 * l } else { l };
        let mut csv = String::from("t,fx,fz\n");
        for k in 0..=steps {
            let t = k as f64 * wet.time.step;
            // The thesis's sign: a load F enters H as +F z, so the force +F_k e is −F_k.
            let f = -coeff * cell * sea.acceleration(y, t);
            csv.push_str(&format!("{t:?},0.0,{f:?}\n"));
        }
        let file = dir.path().join(format!("node{node}.csv"));
        std::fs::write(&file, csv).unwrap();
        reference.push_str(&format!(
            "[[loads.point]]\nnode = {node}\nseries = \"{}\"\n\n",
            file.display()
        ));
    }
    assert_eq!(wet_nodes, 5);
    reference.push_str("[time]\nstep = 0.05\nsteps = 2000\n");
    let reference = Scene::from_toml_str(&reference).unwrap();
    let d_reference = damage(&reference);
    let rel = (d_model / d_reference - 1.0).abs();
    println!("damage: model {d_model:e}, wet nodes' loads alone {d_reference:e}, rel {rel:.1e}");
    assert!(d_reference > 0.0);
    assert!(rel < 1e-6, "{d_model:e} vs {d_reference:e}");
}

/// The example: a 60 m riser in 0.5 m of water has no node in the water (the first is
/// at 6 m), so the waves load nothing: the damage is that of the riser in still water (0 here,
/// nothing else moves it), not 10⁶ times the submerged riser's. A tiny depth runs without NaN
/// for the same reason, down to a subnormal one (whose dispersion relation used to be 0/0).
#[test]
fn a_riser_in_shallow_or_no_water_is_not_loaded_by_the_waves() {
    for depth in [0.5, 1e-6, 1e-300, 5e-324] {
        let s = Scene::from_toml_str(&riser(60.0, 10, depth, 10.0, 1e-6, 200)).unwrap();
        let h = moment_history(&s).unwrap_or_else(|e| panic!("depth {depth}: {e}"));
        assert!(h.moment.iter().all(|m| *m == 0.0), "depth {depth}");
    }
}

/// The zoom transform of a short record ([`Sea::synthesis_rows`]) equals the repeat period's
/// inverse FFT ([`Sea::synthesis_every`]) to round-off, on the step grid and on coarser grids
/// (r dividing M and not), rows beyond the plan's summed directly; the largest difference over
/// Σ|terms| is printed (measured 9.5e-17 when written).
#[test]
fn the_zoom_transform_equals_the_full_fft() {
    let s = Spectrum::jonswap(4.0, 10.0, 3.3).unwrap();
    let sea = Sea::new(&SeaSpec::new(s, 100.0, 3), 0.05, 10.0).unwrap();
    let nc = sea.frequencies().len();
    let x: Vec<Complex<f64>> = (0..nc)
        .map(|j| Complex::new((j as f64 * 0.37).sin(), (j as f64 * 0.11).cos()))
        .collect();
    let y: Vec<Complex<f64>> = x.iter().map(|c| c * Complex::new(0.3, -2.0)).collect();
    let scale: f64 = x.iter().chain(&y).map(|c| c.norm()).sum();
    let mut worst: f64 = 0.0;
    // h = 0.05 s: M = 216 000; N = 6480 components, so the zoom transform has P = 16 384 points
    // (2N + rows ≤ 16 384) against L = M/r for r dividing M (r = 1, 2) and L = M read every
    // 7th value for r = 7 (216 000 = 7 · 30 857 + 1).
    for (every, rows) in [(1, 201), (1, 2001), (2, 300), (7, 300)] {
        let mut zoom = sea.synthesis_rows(every, rows);
        assert!(zoom.is_zoom(), "every {every} rows {rows}: {zoom:?}");
        let mut full = sea.synthesis_every(every);
        assert!(!full.is_zoom());
        let (mut a, mut b) = (vec![(0.0, 0.0); rows + 5], vec![(0.0, 0.0); rows + 5]);
        sea.synthesize((&x, &y), rows + 5, &mut zoom, |k, p, q| a[k] = (p, q));
        sea.synthesize((&x, &y), rows + 5, &mut full, |k, p, q| b[k] = (p, q));
        for (p, q) in a.iter().zip(&b) {
            worst = worst.max((p.0 - q.0).abs().max((p.1 - q.1).abs()) / scale);
        }
    }
    println!("zoom vs full: worst |difference| / Σ|terms| = {worst:.1e}");
    assert!(worst < 1e-13, "{worst:e}");
    // A run of most of the repeat period keeps the full transform (and its bits), as does a
    // coarse grid whose transform is already short (L = M/4 = 54 000: 2 P log₂ P is not below
    // half of L log₂ L).
    assert!(!sea.synthesis_rows(1, 200_000).is_zoom());
    assert!(!sea.synthesis_rows(4, 51).is_zoom());
}

/// A scene's validation sizes the sea with [`Sea::plan`] and does not realise it; the model
/// realises it once with [`Sea::new`]. Both must agree: the same (M, Δω, N) wherever `new`
/// succeeds (read back from the realisation: M = T_r/h, Δω, the number of frequencies), and
/// the same error wherever it refuses — a given and a derived component count, an amplitude
/// that overflows (H_s = 1e160: S ∝ H_s² is not finite), wavenumbers that overflow,
/// an FFT over its limit, a non-finite step.
#[test]
fn the_plan_sizes_and_refuses_as_the_realisation_does() {
    let spec = |hs: f64, tp: f64, depth: f64, components: Option<usize>| {
        let mut s = SeaSpec::new(Spectrum::jonswap(hs, tp, 3.3).unwrap(), depth, 3);
        s.components = components;
        s
    };
    // g = 5e-324: the deep-water wavenumbers ω²/g overflow.
    let mut tiny_gravity = spec(4.0, 10.0, 300.0, Some(50));
    tiny_gravity.gravity = 5e-324;
    let cases = [
        (spec(4.0, 10.0, 300.0, None), 0.05, 600.0),
        (spec(4.0, 10.0, 300.0, None), 0.1, 10_800.0),
        (spec(2.0, 6.0, 50.0, Some(200)), 0.02, 60.0),
        (spec(1e160, 10.0, 300.0, Some(50)), 0.1, 60.0),
        (tiny_gravity, 0.1, 60.0),
        (spec(4.0, 10.0, 300.0, None), 1e-9, 600.0),
        (spec(4.0, 10.0, 300.0, None), f64::NAN, 600.0),
        (spec(4.0, 1e-6, 300.0, None), 0.05, 600.0),
    ];
    let mut refused = 0;
    for (i, (s, h, duration)) in cases.iter().enumerate() {
        match (Sea::plan(s, *h, *duration), Sea::new(s, *h, *duration)) {
            (Ok(plan), Ok(sea)) => {
                assert_eq!(plan.fft_len as f64 * h, sea.repeat_period(), "case {i}");
                assert_eq!(plan.frequency_step, sea.frequency_step(), "case {i}");
                assert_eq!(plan.components, sea.frequencies().len(), "case {i}");
            }
            (Err(a), Err(b)) => {
                assert_eq!(format!("{a:?}"), format!("{b:?}"), "case {i}");
                refused += 1;
            }
            (a, b) => panic!("case {i}: plan {a:?}, realisation {:?}", b.map(|_| ())),
        }
    }
    // The cases above are chosen so that five of the eight are refusals.
    assert_eq!(refused, 5, "refusals");
}
