//! Wellhead fatigue (src/fatigue): rainflow counting against ASTM E1049-85's worked example and
//! the independent `rainflow` Python package, the DNV-RP-C203 tables against hand-computed
//! damages, the narrow-band Gaussian check against the Rayleigh closed form, the damage's
//! gradient against central differences and dual numbers, and the scatter combination.

use crate::fatigue_support;

use chainbeam::fatigue::{
    assess, combine_scatter, damage_gradient, damage_per_year, life_years, miner_sum,
    pairing_damage, power_gradient, power_objective, rainflow, rainflow_visit, CellDamage, Cycle,
    DnvClass, Environment, FatigueError, FatigueSpec, HotSpot, MomentHistory, MomentMeasure,
    RainflowWorkspace, SnCurve, SECONDS_PER_YEAR,
};
use fatigue_support::{allocations, narrow_band, NarrowBand};
use num_dual::Dual64;
use rand_chacha::rand_core::{RngCore, SeedableRng};
use rand_chacha::ChaCha8Rng;

/// ASTM E1049-85 (2011) §5.4.4, Fig. 6 and Table 4: the rainflow count of the worked example,
/// −2, 1, −3, 5, −1, 3, −4, 4, −2: ranges 3 (½), 4 (1½), 6 (½), 8 (1), 9 (½).
#[test]
fn astm_e1049_worked_example() {
    let cycles = rainflow(&[-2.0, 1.0, -3.0, 5.0, -1.0, 3.0, -4.0, 4.0, -2.0]).unwrap();
    let mut table = [0.0; 11];
    for c in &cycles {
        assert_eq!(c.range.fract(), 0.0);
        table[c.range as usize] += c.count;
    }
    let expected = [0.0, 0.0, 0.0, 0.5, 1.5, 0.0, 0.5, 0.0, 1.0, 0.5, 0.0];
    assert_eq!(table, expected);
    // Table 4's total: 4 cycles, counted by §5.4.4 in this order: half cycles −2…1 and 1…−3
    // (each contains the starting point), the full cycle −1…3, half cycles −3…5 and 5…−4, and
    // the residue −4…4, 4…−2.
    assert_eq!(cycles.iter().map(|c| c.count).sum::<f64>(), 4.0);
    let steps: Vec<(f64, f64, f64)> = cycles.iter().map(|c| (c.range, c.mean, c.count)).collect();
    let fig6 = [
        (3.0, -0.5, 0.5),
        (4.0, -1.0, 0.5),
        (4.0, 1.0, 1.0),
        (8.0, 1.0, 0.5),
        (9.0, 0.5, 0.5),
        (8.0, 0.0, 0.5),
        (6.0, 1.0, 0.5),
    ];
    assert_eq!(steps, fig6);
}

#[derive(serde::Deserialize)]
struct Fixtures {
    rainflow_version: String,
    series: Vec<FixtureSeries>,
}

#[derive(serde::Deserialize)]
struct FixtureSeries {
    name: String,
    samples: Vec<f64>,
    cycles: Vec<(f64, f64, f64, usize, usize)>,
}

/// The same cycles, bit for bit and in the same order, as the independent `rainflow` package
/// (PyPI 3.2.0) on four random series (white noise, a random walk, small integers with
/// plateaus and exact ties, two sines with noise): tests/fixtures/fatigue/, made by
/// make_rainflow_fixtures.py there.
#[test]
fn random_series_match_the_rainflow_package() {
    let text = include_str!("../fixtures/fatigue/rainflow_random.json");
    let fixtures: Fixtures = serde_json::from_str(text).unwrap();
    assert_eq!(fixtures.rainflow_version, "3.2.0");
    assert_eq!(fixtures.series.len(), 4);
    let mut workspace = RainflowWorkspace::new();
    for s in &fixtures.series {
        let mut got = Vec::new();
        rainflow_visit(s.samples.iter().copied(), &mut workspace, |c| {
            got.push((c.range, c.mean, c.count, c.start, c.end))
        })
        .unwrap();
        assert!(s.cycles.len() > 50, "{}: {} cycles", s.name, s.cycles.len());
        assert_eq!(got, s.cycles, "{}", s.name);
    }
}

/// Counting a long record with a warm workspace allocates nothing (a counting global
/// allocator, tests/fatigue_support), and neither does the damage gradient.
#[test]
fn rainflow_and_gradient_do_not_allocate() {
    let mut rng = ChaCha8Rng::seed_from_u64(7);
    let series: Vec<f64> = (0..200_000).map(|_| uniform(&mut rng) - 0.5).collect();
    let mut workspace = RainflowWorkspace::new();
    let mut warm = 0.0;
    rainflow_visit(series.iter().copied(), &mut workspace, |c| warm += c.count).unwrap();
    let mut counted = 0.0;
    let before = allocations();
    rainflow_visit(series.iter().copied(), &mut workspace, |c| {
        counted += c.count
    })
    .unwrap();
    assert_eq!(allocations(), before, "rainflow allocated");
    assert_eq!(counted, warm);
    assert!(counted > 50_000.0, "{counted} cycles");

    let curve = SnCurve::dnv(DnvClass::D, Environment::Air);
    let mut gradient = vec![0.0; series.len()];
    let before = allocations();
    let d = damage_gradient(&series, &curve, &mut workspace, &mut gradient).unwrap();
    assert_eq!(allocations(), before, "damage_gradient allocated");
    assert!(d > 0.0);
    // The stack of unpaired points of a stationary record stays small.
    assert!(
        workspace.capacity() < 1000,
        "capacity {}",
        workspace.capacity()
    );
}

#[test]
fn non_finite_samples_are_typed_errors() {
    let err = rainflow(&[0.0, 1.0, f64::NAN, 2.0]).unwrap_err();
    assert!(
        matches!(
            err,
            FatigueError::NonFinite {
                quantity: "stress",
                index: 2,
                ..
            }
        ),
        "{err}"
    );
    let spec = FatigueSpec::new(0.5, 0.025);
    let m = [0.0, 1.0, f64::INFINITY];
    let history = MomentHistory {
        duration_s: 1.0,
        moment: &m,
        moment_x: None,
        measure: MomentMeasure::Wellhead,
    };
    let err = assess(&spec, history).unwrap_err();
    assert!(
        matches!(
            err,
            FatigueError::NonFinite {
                quantity: "moment",
                index: 2,
                ..
            }
        ),
        "{err}"
    );
    let bad = FatigueSpec {
        wall_thickness: 0.3,
        ..spec
    };
    let err = assess(
        &bad,
        MomentHistory {
            duration_s: 1.0,
            moment: &[0.0, 1.0],
            moment_x: None,
            measure: MomentMeasure::Wellhead,
        },
    )
    .unwrap_err();
    assert!(
        matches!(
            err,
            FatigueError::InvalidSpec {
                key: "wall_thickness",
                ..
            }
        ),
        "{err}"
    );
    let err = "X9".parse::<DnvClass>().unwrap_err();
    assert!(matches!(err, FatigueError::UnknownCurve { .. }), "{err}");
    let err = "sea".parse::<Environment>().unwrap_err();
    assert!(
        matches!(err, FatigueError::UnknownEnvironment { .. }),
        "{err}"
    );
}

/// Curve D against docs/fatigue.md "S-N curves" (air log ā₁ = 12.164, log ā₂ = 15.606; seawater with CP
/// log ā₁ = 11.764, log ā₂ = 15.606), and every class's two segments meeting at the standard's
/// knee (N = 10⁷ in air, 10⁶ in seawater with CP) to the tables' rounding — a typo in the table
/// would break this.
#[test]
fn dnv_tables_are_consistent() {
    let air = SnCurve::dnv(DnvClass::D, Environment::Air);
    assert_eq!(
        (air.first.log_a, air.second.unwrap().log_a),
        (12.164, 15.606)
    );
    let cp = SnCurve::dnv(DnvClass::D, Environment::SeawaterCp);
    assert_eq!((cp.first.log_a, cp.second.unwrap().log_a), (11.764, 15.606));
    for class in DnvClass::ALL {
        assert_eq!(class.name().parse::<DnvClass>().unwrap(), class);
        for (env, log_n_knee) in [(Environment::Air, 7.0), (Environment::SeawaterCp, 6.0)] {
            let c = SnCurve::dnv(class, env);
            let knee = c.knee_range().unwrap();
            let log_n = c.cycles_to_failure(knee).log10();
            assert!(
                (log_n - log_n_knee).abs() < 2e-3,
                "{class} {env}: log N = {log_n}"
            );
            assert_eq!(c.second.unwrap().m, 5.0);
        }
        let fc = SnCurve::dnv(class, Environment::FreeCorrosion);
        assert!(fc.second.is_none() && fc.first.m == 3.0);
        // At 100 MPa free corrosion is the shortest life (Table 2-3 below Tables 2-1, 2-2).
        let cp = SnCurve::dnv(class, Environment::SeawaterCp);
        let air = SnCurve::dnv(class, Environment::Air);
        assert!(
            fc.cycles_to_failure(100.0) < cp.cycles_to_failure(100.0),
            "{class}"
        );
        assert!(
            cp.cycles_to_failure(100.0) <= air.cycles_to_failure(100.0),
            "{class}"
        );
    }
}

fn cycles(list: &[(f64, f64)]) -> Vec<Cycle> {
    list.iter()
        .map(|&(range, count)| Cycle {
            range,
            mean: 0.0,
            count,
            start: 0,
            end: 1,
        })
        .collect()
}

/// Miner's sum against hand-computed DNV-RP-C203 damages for curves D and F1 in each
/// environment, one range above and one below the knee (free corrosion: one slope).
/// Per-cycle damages by hand from the tables, d = Δσ^m/ā = 10^(m log Δσ − log ā):
#[test]
fn miner_sum_matches_hand_computed_dnv_damage() {
    // (class, environment, [(range, d by hand)]), n = 1000 cycles at the first range,
    // 2·10⁵ at the second, and one half cycle at the first.
    let cases = [
        // D air (knee 52.6 MPa): 10^(6 − 12.164); 10^(5·1.602060 − 15.606) = 10^−7.595700.
        (
            DnvClass::D,
            Environment::Air,
            [(100.0, 6.85488e-7), (40.0, 2.53688e-8)],
        ),
        // D seawater-CP (knee 83.4 MPa): 10^(6 − 11.764); 10^(5·1.778151 − 15.606).
        (
            DnvClass::D,
            Environment::SeawaterCp,
            [(100.0, 1.72187e-6), (60.0, 1.92644e-7)],
        ),
        // D free corrosion (m = 3): 10^(6 − 11.687); 10^(3·1.477121 − 11.687).
        (
            DnvClass::D,
            Environment::FreeCorrosion,
            [(100.0, 2.05589e-6), (30.0, 5.55090e-8)],
        ),
        // F1 air (knee 36.9 MPa): 10^(6 − 11.699); 10^(5·1.477121 − 14.832).
        (
            DnvClass::F1,
            Environment::Air,
            [(100.0, 1.99986e-6), (30.0, 3.57772e-8)],
        ),
        // F1 seawater-CP (knee 58.4 MPa): 10^(6 − 11.299); 10^(5·1.602060 − 14.832).
        (
            DnvClass::F1,
            Environment::SeawaterCp,
            [(100.0, 5.02343e-6), (40.0, 1.50765e-7)],
        ),
        // F1 free corrosion: 10^(6 − 11.222); 10^(3·1.477121 − 11.222).
        (
            DnvClass::F1,
            Environment::FreeCorrosion,
            [(100.0, 5.99791e-6), (30.0, 1.61944e-7)],
        ),
    ];
    for (class, env, [(r1, d1), (r2, d2)]) in cases {
        let curve = SnCurve::dnv(class, env);
        if let Some(knee) = curve.knee_range() {
            assert!(
                r1 > knee && r2 < knee,
                "{class} {env}: the ranges straddle the knee"
            );
        }
        let got = miner_sum(&cycles(&[(r1, 1000.0), (r2, 2.0e5), (r1, 0.5)]), &curve);
        let hand = 1000.5 * d1 + 2.0e5 * d2;
        assert!(
            (got - hand).abs() <= 1e-5 * hand,
            "{class} {env}: {got} vs {hand}"
        );
    }
    // Thickness: D in air at t = 50 mm, k = 0.20: s = 2^0.2 = 1.148698, d(100) =
    // 114.8698³/10^12.164 = 1.03901e-6 (by hand); t = 20 mm < t_ref: no correction.
    let d = SnCurve::dnv(DnvClass::D, Environment::Air);
    let thick = d
        .with_thickness(0.050, 0.025, DnvClass::D.thickness_exponent())
        .unwrap();
    assert!((thick.cycle_damage(100.0_f64) - 1.03901e-6).abs() < 1e-5 * 1.03901e-6);
    let thin = d.with_thickness(0.020, 0.025, 0.2).unwrap();
    assert_eq!(thin.cycle_damage(100.0_f64), d.cycle_damage(100.0_f64));
    let err = d.with_thickness(0.05, 0.025, -1.0).unwrap_err();
    assert!(matches!(
        err,
        FatigueError::InvalidSpec {
            key: "thickness_exponent",
            ..
        }
    ));
}

fn uniform(rng: &mut ChaCha8Rng) -> f64 {
    (rng.next_u64() >> 11) as f64 * (1.0 / (1u64 << 53) as f64)
}

/// Narrow-band check (docs/fatigue.md "Miner's rule, a year, a life"): a stationary Gaussian stress with a flat spectrum over
/// f₀ · [0.97, 1.03] (64 components, random frequencies and phases from ChaCha8 seed 31),
/// σ = 20 MPa, 3·10⁵ mean periods at 32 samples per period; one-slope curve m = 3, log ā = 12.
/// Rayleigh closed form E[D] = ν₀ T/ā (2√2 σ)^m Γ(1 + m/2), ν₀ = √(m₂/m₀) of the realised
/// spectrum. Expected gap: rainflow on a band of ε ≈ 0.035 counts about 1.5 % less than the
/// narrow-band form (Wirsching-Light), the record's statistical scatter about 1 %.
#[test]
fn narrow_band_damage_matches_rayleigh() {
    let band = NarrowBand {
        components: 64,
        relative_half_width: 0.03,
        frequency_hz: 0.1,
        std_mpa: 20.0,
        periods: 300_000,
        samples_per_period: 32,
        seed: 31,
    };
    let (series, nu0, duration) = narrow_band(&band);
    let curve = SnCurve::one_slope(3.0, 12.0);
    let mut damage = 0.0;
    rainflow_visit(series.iter().copied(), &mut RainflowWorkspace::new(), |c| {
        damage += c.count * curve.cycle_damage(c.range)
    })
    .unwrap();
    let gamma_2_5 = 0.75 * std::f64::consts::PI.sqrt(); // Γ(5/2) = (3/4)√π
    let rayleigh = nu0 * duration / 1e12 * (2.0 * 2f64.sqrt() * band.std_mpa).powi(3) * gamma_2_5;
    let ratio = damage / rayleigh;
    println!("narrow band: D = {damage:.6e}, Rayleigh {rayleigh:.6e}, ratio {ratio:.4}");
    assert!((ratio - 1.0).abs() < 0.05, "ratio {ratio}");
}

/// A stress history of `n` samples, N(0, 50 MPa) white noise: ranges on both sides of the
/// D-curve's knee in air (52.6 MPa).
fn random_stress(seed: u64, n: usize) -> Vec<f64> {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    (0..n)
        .map(|_| {
            // Box-Muller.
            let (u, v) = (uniform(&mut rng).max(1e-300), uniform(&mut rng));
            50.0 * (-2.0 * u.ln()).sqrt() * (2.0 * std::f64::consts::PI * v).cos()
        })
        .collect()
}

fn pairing(stress: &[f64], curve: &SnCurve) -> Vec<(usize, usize, u64, bool)> {
    let knee = curve.knee_range().unwrap_or(0.0);
    rainflow(stress)
        .unwrap()
        .iter()
        .map(|c| (c.start, c.end, c.count.to_bits(), c.range >= knee))
        .collect()
}

/// ∂D/∂σ_k of the rainflow damage against central differences of the whole count (relative
/// 10⁻⁶ of the largest component, h = 10⁻⁴ MPa) at five random histories, each difference
/// checked to keep the pairing and the S-N segment of every cycle; against Dual64 of the same
/// pairing to 10⁻¹²; non-zero at turning points only.
#[test]
fn damage_gradient_matches_central_differences_and_duals() {
    let curve = SnCurve::dnv(DnvClass::D, Environment::Air)
        .with_thickness(0.04, 0.025, 0.2)
        .unwrap();
    let mut ws = RainflowWorkspace::new();
    for seed in 0..5 {
        let sigma = random_stress(100 + seed, 80);
        let mut g = vec![0.0; sigma.len()];
        let d = damage_gradient(&sigma, &curve, &mut ws, &mut g).unwrap();
        let cycles = rainflow(&sigma).unwrap();
        assert_eq!(d, miner_sum(&cycles, &curve));
        let scale = g.iter().fold(0.0_f64, |a, b| a.max(b.abs()));
        let reference = pairing(&sigma, &curve);
        let turning: Vec<usize> = cycles.iter().flat_map(|c| [c.start, c.end]).collect();
        for k in 0..sigma.len() {
            let h = 1e-4;
            let (mut plus, mut minus) = (sigma.clone(), sigma.clone());
            plus[k] += h;
            minus[k] -= h;
            assert_eq!(
                pairing(&plus, &curve),
                reference,
                "seed {seed}: pairing changes at {k}"
            );
            assert_eq!(
                pairing(&minus, &curve),
                reference,
                "seed {seed}: pairing changes at {k}"
            );
            let fd = (miner_sum(&rainflow(&plus).unwrap(), &curve)
                - miner_sum(&rainflow(&minus).unwrap(), &curve))
                / (2.0 * h);
            assert!(
                (fd - g[k]).abs() <= 1e-6 * scale,
                "seed {seed}, k {k}: {fd} vs {}",
                g[k]
            );
            if !turning.contains(&k) {
                assert_eq!(g[k], 0.0);
            }
            let dual: Vec<Dual64> = (0..sigma.len())
                .map(|i| Dual64::new(sigma[i], if i == k { 1.0 } else { 0.0 }))
                .collect();
            let dd = pairing_damage(&dual, &cycles, &curve).unwrap();
            assert!((dd.re - d).abs() <= 1e-14 * d);
            assert!(
                (dd.eps - g[k]).abs() <= 1e-12 * scale,
                "k {k}: {} vs {}",
                dd.eps,
                g[k]
            );
        }
    }
}

/// At a change of pairing the damage is continuous and its gradient jumps. The history
/// 0, 1, c, 5 with c → 0 ties X = Y in the three-point rule. By hand (one slope m = 3, ā = 1):
/// c < 0: half cycles 1, 1 − c, 5 − c: D = ½(1 + (1−c)³ + (5−c)³), ∂D/∂c = −(3/2)((1−c)² + (5−c)²) → −39;
/// c > 0: a full cycle 1 − c and the half cycle 5: D = (1−c)³ + 62.5, ∂D/∂c = −3(1−c)² → −3;
/// both D → 63.5.
#[test]
fn pairing_change_keeps_damage_continuous_and_gradient_one_sided() {
    let curve = SnCurve::one_slope(3.0, 0.0);
    let mut ws = RainflowWorkspace::new();
    let mut g = [0.0; 4];
    let eps = 1e-9;
    let below = damage_gradient(&[0.0, 1.0, -eps, 5.0], &curve, &mut ws, &mut g).unwrap();
    let g_below = g[2];
    let above = damage_gradient(&[0.0, 1.0, eps, 5.0], &curve, &mut ws, &mut g).unwrap();
    let g_above = g[2];
    assert!(
        (below - 63.5).abs() < 1e-6 && (above - 63.5).abs() < 1e-6,
        "{below} {above}"
    );
    assert!((g_below + 39.0).abs() < 1e-6, "{g_below}");
    assert!((g_above + 3.0).abs() < 1e-6, "{g_above}");
}

/// The smooth proxy J_m = Σ|σ_k|^m: its gradient against Dual64 to 10⁻¹² (m = 3 and 5).
#[test]
fn power_objective_gradient_matches_duals() {
    let sigma = random_stress(9, 40);
    for m in [3.0, 5.0] {
        let mut g = vec![0.0; sigma.len()];
        let j = power_gradient(&sigma, m, &mut g).unwrap();
        assert!((j - power_objective(&sigma, m)).abs() <= 1e-14 * j);
        for (k, &gk) in g.iter().enumerate() {
            let dual: Vec<Dual64> = (0..sigma.len())
                .map(|i| Dual64::new(sigma[i], if i == k { 1.0 } else { 0.0 }))
                .collect();
            let d = power_objective(&dual, m);
            assert!((d.re - j).abs() <= 1e-14 * j);
            assert!(
                (d.eps - gk).abs() <= 1e-12 * gk.abs().max(1.0),
                "m {m} k {k}"
            );
        }
    }
}

/// Annual damage and life, and the scatter diagram: one cell of probability 1 reproduces the
/// single-state damage per year; the damage adds over cells.
#[test]
fn annual_damage_life_and_scatter() {
    let dpy = damage_per_year(0.01, 3.0 * 3600.0).unwrap();
    assert!((dpy - 0.01 * SECONDS_PER_YEAR / 10_800.0).abs() <= 1e-15 * dpy);
    assert_eq!(SECONDS_PER_YEAR, 31_557_600.0);
    assert!((life_years(dpy, 3.0).unwrap() - 1.0 / (3.0 * dpy)).abs() < 1e-12);
    assert_eq!(life_years(0.0, 3.0).unwrap(), f64::INFINITY);

    let a = CellDamage {
        probability: 1.0,
        damage: 0.01,
        duration_s: 10_800.0,
    };
    let one = combine_scatter(&[a]).unwrap();
    assert_eq!(one.damage_per_year, dpy);
    let cells = [
        CellDamage {
            probability: 0.5,
            damage: 0.02,
            duration_s: 3600.0,
        },
        CellDamage {
            probability: 0.3,
            damage: 0.001,
            duration_s: 1800.0,
        },
        CellDamage {
            probability: 0.2,
            damage: 0.0,
            duration_s: 600.0,
        },
    ];
    let all = combine_scatter(&cells).unwrap();
    let parts: f64 = cells
        .iter()
        .map(|c| c.probability * damage_per_year(c.damage, c.duration_s).unwrap())
        .sum();
    assert!((all.damage_per_year - parts).abs() <= 1e-15 * parts);
    let split = combine_scatter(&cells[..1]).unwrap().damage_per_year
        + combine_scatter(&cells[1..]).unwrap().damage_per_year;
    assert!((all.damage_per_year - split).abs() <= 1e-15 * parts);
    assert_eq!(all.cells.len(), 3);
    assert!((all.probability_sum - 1.0).abs() < 1e-15);

    let bad = CellDamage {
        probability: -0.1,
        ..a
    };
    assert!(matches!(
        combine_scatter(&[a, bad]),
        Err(FatigueError::InvalidProbability { index: 1, .. })
    ));
    assert!(matches!(
        combine_scatter(&[a, a]),
        Err(FatigueError::ProbabilitySum { .. })
    ));
    let zero = CellDamage {
        duration_s: 0.0,
        ..a
    };
    assert!(matches!(
        combine_scatter(&[zero]),
        Err(FatigueError::InvalidSpec {
            key: "duration",
            ..
        })
    ));
}

/// σ = SCF·M₀·(D_o/2)/I: a 0.5 m × 25 mm pipe has I = π/64 (0.5⁴ − 0.45⁴) = 1.055 e-3 m⁴
/// (by hand: 0.0625 − 0.04100625 = 0.02149375, × π/64 = 1.05508e-3), so 1 MN·m gives
/// 0.25/1.05508e-3 = 236.95 MPa. A spatial moment at 45° in phase, (M/√2, M/√2), has its worst
/// point at θ = 45° with the stress (and damage) of the planar moment M.
#[test]
fn hot_spot_stress_and_worst_point() {
    let hs = HotSpot::new(0.5, 0.025, 1.0).unwrap();
    assert!((hs.second_moment() - 1.05508e-3).abs() < 1e-5 * 1.05508e-3);
    assert!((hs.stress_per_moment() * 1e6 - 236.95).abs() < 1e-4 * 236.95);
    let scf2 = HotSpot::new(0.5, 0.025, 2.0).unwrap();
    assert_eq!(scf2.stress_per_moment(), 2.0 * hs.stress_per_moment());

    let m: Vec<f64> = (0..400)
        .map(|k| 4e5 * (0.3 * k as f64).sin() + 1e5 * (0.71 * k as f64).cos())
        .collect();
    let mx: Vec<f64> = m.iter().map(|v| v / 2f64.sqrt()).collect();
    let spec = FatigueSpec::new(0.5, 0.025);
    let planar = assess(
        &spec,
        MomentHistory {
            duration_s: 399.0,
            moment: &m,
            moment_x: None,
            measure: MomentMeasure::Wellhead,
        },
    )
    .unwrap();
    let spatial = assess(
        &spec,
        MomentHistory {
            duration_s: 399.0,
            moment: &mx,
            moment_x: Some(&mx),
            measure: MomentMeasure::Wellhead,
        },
    )
    .unwrap();
    assert!((spatial.theta - std::f64::consts::FRAC_PI_4).abs() < 1e-15);
    assert!((spatial.damage - planar.damage).abs() <= 1e-12 * planar.damage);
    assert!((planar.life_years - 1.0 / planar.damage_per_year).abs() <= 1e-12 * planar.life_years);
    assert!(planar.cycles.iter().all(|c| c.range < 236.95 * 1.0));
}

/// The `[fatigue]` scene table: defaults (scf 1, curve D, seawater with CP, the class's k,
/// t_ref = 25 mm, DFF 1), written back by `to_toml_string` and read again unchanged.
#[test]
fn fatigue_table_defaults_and_round_trip() {
    let text = "[beam]\npendulums = 3\nlength = 1.0\nmass = 1.0\nstiffness = 100.0\n\
                support = \"cantilever\"\n[time]\nstep = 0.01\nsteps = 10\n\
                [fatigue]\nouter_diameter = 0.5\nwall_thickness = 0.03\n";
    let scene = chainbeam::Scene::from_toml_str(text).unwrap();
    let spec = scene.fatigue.unwrap();
    assert_eq!(spec, FatigueSpec::new(0.5, 0.03));
    assert_eq!(
        (spec.scf, spec.dff, spec.reference_thickness),
        (1.0, 1.0, 0.025)
    );
    assert_eq!(
        (spec.curve, spec.environment),
        (DnvClass::D, Environment::SeawaterCp)
    );
    let k = DnvClass::D.thickness_exponent();
    let s = spec.sn_curve().unwrap().thickness_factor;
    assert!((s - (0.03_f64 / 0.025).powf(k)).abs() < 1e-15 && k == 0.2);
    let again = chainbeam::Scene::from_toml_str(&scene.to_toml_string()).unwrap();
    assert_eq!(again, scene);
    let bad = text.replace("0.03\n", "0.03\nreference_thickness = -1.0\n");
    let err = chainbeam::Scene::from_toml_str(&bad).unwrap_err();
    assert_eq!(err.key(), Some("fatigue.reference_thickness"), "{err}");
}

/// The rainflow damage of a simulated riser as a function of a constant tip control u (thesis
/// riser, load 2 N at node 5, 400 steps of 0.01 s, a 20 mm × 2 mm tube, curve D in air):
/// dD/du = Σ_k ∂D/∂σ_k · c · dM₀(t_k)/du (c the stress per unit M₀, l₁/2 of it the wellhead
/// moment), with ∂D/∂σ_k from [`damage_gradient`] and dM₀/du from
/// the Dual64 simulation (the chain an adjoint objective will take), against central differences
/// of f64 simulations (relative 1e-6, h = 1e-6 N, pairing checked unchanged) at three random
/// controls from ChaCha8 seed 5.
#[test]
fn damage_gradient_through_a_simulation_matches_central_differences() {
    use chainbeam::{catalogue, simulate_chain, Chain};
    let scene = catalogue::riser(5);
    let hot_spot = HotSpot::new(0.02, 0.002, 1.0).unwrap();
    let c = hot_spot.stress_per_unit(scene.moment_measure());
    let curve = SnCurve::dnv(DnvClass::D, Environment::Air);
    let steps = 400;
    let stress_of = |u: f64| -> Vec<f64> {
        let mut chain = Chain::<f64, 2>::from_scene(&scene).unwrap();
        chain.set_control_node(Some(10)).unwrap();
        let traj = simulate_chain(chain, 0.01, steps, &vec![u; steps + 1]).unwrap();
        traj.moment.iter().map(|m| c * m).collect()
    };
    let mut rng = ChaCha8Rng::seed_from_u64(5);
    let mut ws = RainflowWorkspace::new();
    for _ in 0..3 {
        let u = -6.0 + 4.0 * uniform(&mut rng);
        let mut chain = Chain::<Dual64, 2>::from_scene(&scene).unwrap();
        chain.set_control_node(Some(10)).unwrap();
        let traj = simulate_chain(chain, 0.01, steps, &vec![Dual64::new(u, 1.0); steps + 1]);
        let moment = traj.unwrap().moment;
        let sigma: Vec<f64> = moment.iter().map(|m| c * m.re).collect();
        assert_eq!(sigma, stress_of(u));
        let mut g = vec![0.0; sigma.len()];
        let d = damage_gradient(&sigma, &curve, &mut ws, &mut g).unwrap();
        let dd_du: f64 = g.iter().zip(&moment).map(|(g, m)| g * c * m.eps).sum();
        let h = 1e-6;
        let (plus, minus) = (stress_of(u + h), stress_of(u - h));
        assert_eq!(pairing(&plus, &curve), pairing(&sigma, &curve), "u = {u}");
        assert_eq!(pairing(&minus, &curve), pairing(&sigma, &curve), "u = {u}");
        let fd = (miner_sum(&rainflow(&plus).unwrap(), &curve)
            - miner_sum(&rainflow(&minus).unwrap(), &curve))
            / (2.0 * h);
        println!("u = {u:.4} N: D = {d:.6e}, dD/du = {dd_du:.9e}, central difference {fd:.9e}");
        assert!(d > 0.0 && dd_du != 0.0);
        assert!(
            (fd - dd_du).abs() <= 1e-6 * dd_du.abs(),
            "u = {u}: {fd} vs {dd_du}"
        );
    }
}
