//! Irregular seas (`chainbeam::ocean`, docs/ocean.md "Irregular seas", DNV-RP-C205 §3.5): dispersion limits, the
//! 3-hour statistics H_s = 4σ_η and T_p against the scene's values, the spectrum of η and of
//! the particle velocity against S(ω) and the Airy transfer function, the FFT record against
//! the direct sum, and the seed's reproducibility (against the RFC 8439 ChaCha20 test vector).

use chainbeam::ocean::{
    depth_profile, wavenumber, Sea, SeaSpec, Spectrum, SpectrumKind, STANDARD_GRAVITY,
};
use rustfft::num_complex::Complex;
use rustfft::FftPlanner;
use std::f64::consts::PI;

const G: f64 = STANDARD_GRAVITY;
const THREE_HOURS: f64 = 10_800.0;

#[test]
fn dispersion_solves_the_relation_and_meets_both_limits() {
    // Residual of ω² = g k tanh(k d) over ten decades of ν = ω²d/g.
    let d = 100.0;
    for e in -80..=30 {
        let nu = 10f64.powf(e as f64 / 10.0);
        let w = (nu * G / d).sqrt();
        let k = wavenumber(w, d, G);
        let res = (G * k * (k * d).tanh() - w * w).abs() / (w * w);
        assert!(res < 1e-14, "ν = {nu}: residual {res:e}");
    }
    // Deep water (k d ≫ 1): k = ω²/g (tanh(kd) = 1 to 1e-17 at kd > 20).
    for w in [0.5, 1.0, 3.0] {
        let k = wavenumber(w, 1e4, G);
        assert!((k / (w * w / G) - 1.0).abs() < 1e-15, "deep ω = {w}");
        assert!(wavenumber(w, f64::INFINITY, G) == w * w / G);
    }
    // Shallow water (k d ≪ 1): k = ω/√(g d) (1 + (kd)²/6 + O((kd)⁴)), from tanh x = x − x³/3.
    for kd_shallow in [1e-2, 1e-3, 1e-4] {
        let d = 10.0;
        let w = kd_shallow / d * (G * d).sqrt();
        let k = wavenumber(w, d, G);
        let kd = k * d;
        let rel = k / (w / (G * d).sqrt()) - 1.0;
        assert!(
            (rel - kd * kd / 6.0).abs() < 0.1 * kd * kd * kd * kd + 1e-15,
            "kd {kd}"
        );
    }
}

#[test]
fn depth_profile_is_cosh_over_sinh() {
    // Closed form cosh(ky)/sinh(kd) where it is representable.
    for (k, d) in [(0.01f64, 30.0f64), (0.05, 300.0), (0.2, 50.0), (1e-5, 10.0)] {
        for f in [0.0, 0.3, 0.7, 1.0] {
            let y = f * d;
            let naive = (k * y).cosh() / (k * d).sinh();
            let p = depth_profile(k, y, d);
            assert!(
                (p / naive - 1.0).abs() < 1e-12,
                "k {k} d {d} y {y}: {p} {naive}"
            );
        }
    }
    // Deep water: e^{k(y−d)} without overflow.
    let p = depth_profile(1.5, 990.0, 1000.0);
    assert!((p / (-15.0f64).exp() - 1.0).abs() < 1e-14);
    assert!(depth_profile(1.5, 0.0, 1000.0) >= 0.0);
}

#[test]
fn spectra_have_their_peak_and_pm_its_variance() {
    // S_PM integrates to m₀ = H_s²/16 exactly (DNV-RP-C205 §3.5.5.1); the peak is at ω_p for both
    // (dS/dω = 0 there). Trapezoid on a fine grid up to 60 ω_p (tail there: 5/64 H_s² 60⁻⁴).
    for (kind, tol) in [
        (SpectrumKind::PiersonMoskowitz, 1e-6),
        (SpectrumKind::Jonswap { gamma: 1.0 }, 1e-6),
    ] {
        let s = Spectrum::new(kind, 3.0, 9.0).unwrap();
        let wp = s.peak_frequency();
        let n = 600_000;
        let dw = 60.0 * wp / n as f64;
        let m0: f64 = (1..n).map(|j| s.density(j as f64 * dw)).sum::<f64>() * dw;
        assert!((m0 / (9.0 / 16.0) - 1.0).abs() < tol, "{kind:?}: m0 {m0}");
    }
    for kind in [
        SpectrumKind::PiersonMoskowitz,
        SpectrumKind::Jonswap { gamma: 3.3 },
        SpectrumKind::Jonswap { gamma: 7.0 },
    ] {
        let s = Spectrum::new(kind, 3.0, 9.0).unwrap();
        let wp = s.peak_frequency();
        let e = 1e-4 * wp;
        assert!(s.density(wp) > s.density(wp - e) && s.density(wp) > s.density(wp + e));
    }
    // JONSWAP with γ = 1 is Pierson-Moskowitz bit for bit (A_γ = 1, γ^… = 1).
    let pm = Spectrum::pierson_moskowitz(2.0, 7.0).unwrap();
    let j1 = Spectrum::jonswap(2.0, 7.0, 1.0).unwrap();
    for w in [0.3, 0.9, 1.2, 4.0] {
        assert_eq!(pm.density(w).to_bits(), j1.density(w).to_bits());
    }
    assert!(Spectrum::jonswap(2.0, 7.0, 0.5).is_err());
    assert!(Spectrum::pierson_moskowitz(-1.0, 7.0).is_err());
    assert!(Spectrum::pierson_moskowitz(1.0, f64::NAN).is_err());
}

/// One-sided periodogram Ŝ(ωⱼ) = 2|Xⱼ|²/(M² Δω) of a record of M samples spanning T = M h.
fn periodogram(x: &[f64], h: f64) -> Vec<f64> {
    let m = x.len();
    let mut buf: Vec<Complex<f64>> = x.iter().map(|&v| Complex::new(v, 0.0)).collect();
    FftPlanner::new().plan_fft_forward(m).process(&mut buf);
    let dw = 2.0 * PI / (m as f64 * h);
    (0..m / 2)
        .map(|j| 2.0 * buf[j].norm_sqr() / (m as f64 * m as f64 * dw))
        .collect()
}

/// Moving average over ±w bins.
fn smooth(p: &[f64], w: usize) -> Vec<f64> {
    (0..p.len())
        .map(|j| {
            let (a, b) = (j.saturating_sub(w), (j + w + 1).min(p.len()));
            p[a..b].iter().sum::<f64>() / (b - a) as f64
        })
        .collect()
}

struct Case {
    spectrum: Spectrum,
    depth: f64,
    seed: u64,
}

fn cases() -> Vec<Case> {
    let c = |spectrum: Spectrum, depth, seed| Case {
        spectrum,
        depth,
        seed,
    };
    vec![
        c(Spectrum::pierson_moskowitz(4.0, 10.0).unwrap(), 1000.0, 1),
        c(Spectrum::jonswap(6.0, 12.0, 3.3).unwrap(), 300.0, 2),
        // Finite depth: k_p d ≈ 2.0 and ≈ 1.4 (< π).
        c(Spectrum::jonswap(2.0, 8.0, 5.0).unwrap(), 30.0, 3),
        c(Spectrum::jonswap(8.0, 14.0, 2.0).unwrap(), 60.0, 4),
    ]
}

#[test]
fn three_hour_record_returns_hs_and_tp() {
    let h = 0.1;
    let steps = (THREE_HOURS / h).round() as usize - 1; // M samples: one full period
    for case in cases() {
        let s = case.spectrum;
        let spec = SeaSpec::new(s, case.depth, case.seed);
        let sea = Sea::new(&spec, h, THREE_HOURS).unwrap();
        assert!((sea.repeat_period() - THREE_HOURS).abs() < 1e-9);
        let kp = wavenumber(s.peak_frequency(), case.depth, G);
        let rec = sea.record(&[], steps).unwrap();
        let eta = rec.elevations();
        let mean = eta.iter().sum::<f64>() / eta.len() as f64;
        let var = eta.iter().map(|e| (e - mean) * (e - mean)).sum::<f64>() / eta.len() as f64;
        let hs = 4.0 * var.sqrt();
        let p = smooth(&periodogram(eta, h), 20); // ±20 bins = ±0.012 rad/s
        let jmax = (0..p.len()).max_by(|&a, &b| p[a].total_cmp(&p[b])).unwrap();
        let tp = 2.0 * PI / (jmax as f64 * sea.frequency_step());
        println!(
            "{:?} Hs {} Tp {} d {} (k_p d = {:.2}): N = {}, Hs = 4σ = {hs:.4} ({:+.2} %), \
             Tp = {tp:.3} ({:+.2} %)",
            s.kind,
            s.hs,
            s.tp,
            case.depth,
            kp * case.depth,
            sea.frequencies().len(),
            100.0 * (hs / s.hs - 1.0),
            100.0 * (tp / s.tp - 1.0)
        );
        assert!((hs / s.hs - 1.0).abs() < 0.03, "Hs {hs} vs {}", s.hs);
        assert!((tp / s.tp - 1.0).abs() < 0.05, "Tp {tp} vs {}", s.tp);
    }
}

#[test]
fn spectrum_of_eta_and_of_the_velocity_follow_s_and_the_airy_transfer() {
    // Over one repeat period the periodogram of η is Σ aⱼ²/(2Δω) = S(ωⱼ) at each component, and
    // that of u(y, t) is (ωⱼ cosh(kⱼy)/sinh(kⱼd))² S(ωⱼ): compared band by band (±10 bins).
    let h = 0.2;
    let case = &cases()[2];
    let spec = SeaSpec::new(case.spectrum, case.depth, 9);
    let sea = Sea::new(&spec, h, THREE_HOURS).unwrap();
    let m = (sea.repeat_period() / h).round() as usize;
    let y = 0.4 * case.depth;
    let rec = sea.record(&[y], m - 1).unwrap();
    let u: Vec<f64> = (0..m).map(|k| rec.velocity(k)[0]).collect();
    let (pe, pu) = (
        smooth(&periodogram(rec.elevations(), h), 10),
        smooth(&periodogram(&u, h), 10),
    );
    let dw = sea.frequency_step();
    let target = |j: usize| case.spectrum.density(j as f64 * dw);
    let transfer = |j: usize| {
        let w = j as f64 * dw;
        let g = depth_profile(wavenumber(w, case.depth, G), y, case.depth);
        (w * g) * (w * g) * target(j)
    };
    let (se, su) = (
        smooth(&(0..pe.len()).map(target).collect::<Vec<_>>(), 10),
        smooth(&(0..pe.len()).map(transfer).collect::<Vec<_>>(), 10),
    );
    let (emax, umax) = (
        se.iter().cloned().fold(0.0, f64::max),
        su.iter().cloned().fold(0.0, f64::max),
    );
    let n = sea.frequencies().len();
    let mut compared = 0;
    for j in 20..n - 20 {
        if se[j] > 1e-3 * emax {
            assert!(
                (pe[j] / se[j] - 1.0).abs() < 1e-8,
                "η bin {j}: {} vs {}",
                pe[j],
                se[j]
            );
            compared += 1;
        }
        if su[j] > 1e-3 * umax {
            assert!(
                (pu[j] / su[j] - 1.0).abs() < 1e-8,
                "u bin {j}: {} vs {}",
                pu[j],
                su[j]
            );
        }
    }
    assert!(compared > 500, "{compared} bins compared");
}

#[test]
fn fft_record_equals_the_direct_sum() {
    let h = 0.05;
    for case in cases() {
        let mut spec = SeaSpec::new(case.spectrum, case.depth, case.seed);
        spec.direction_deg = 30.0;
        let sea = Sea::new(&spec, h, 600.0).unwrap();
        let heights = [
            0.0,
            0.25 * case.depth,
            0.9 * case.depth,
            case.depth,
            1.2 * case.depth,
        ];
        let steps = 4000;
        let rec = sea.record(&heights, steps).unwrap();
        // Scale: Σ|terms| of each sum.
        let scale_eta: f64 = sea.amplitudes().iter().sum();
        let mut worst: f64 = 0.0;
        for k in [0, 1, 7, 1234, 2999, steps] {
            let t = k as f64 * h;
            let e = (rec.elevation(k) - sea.elevation(t)).abs() / scale_eta;
            worst = worst.max(e);
            for (i, &y) in heights.iter().enumerate() {
                let su: f64 = (0..sea.frequencies().len())
                    .map(|j| {
                        let w = sea.frequencies()[j];
                        w * w
                            * sea.amplitudes()[j]
                            * depth_profile(sea.wavenumbers()[j], y, case.depth)
                    })
                    .sum();
                let du = (rec.velocity(k)[i] - sea.velocity(y, t)).abs() / su;
                let da = (rec.acceleration(k)[i] - sea.acceleration(y, t)).abs() / su;
                worst = worst.max(du).max(da);
            }
        }
        println!(
            "{:?}: worst |FFT − direct| / Σ|terms| = {worst:.1e}",
            case.spectrum.kind
        );
        assert!(worst < 1e-12, "{worst:e}");
    }
}

#[test]
fn acceleration_is_the_time_derivative_of_velocity() {
    let case = &cases()[1];
    let sea = Sea::new(&SeaSpec::new(case.spectrum, case.depth, 5), 0.1, 100.0).unwrap();
    let d = 1e-3;
    for (y, t) in [(150.0, 10.0), (290.0, 55.5), (10.0, 99.9)] {
        let fd = (sea.velocity(y, t + d) - sea.velocity(y, t - d)) / (2.0 * d);
        let a = sea.acceleration(y, t);
        assert!(
            (fd - a).abs() < 1e-6 * (1.0 + a.abs()),
            "y {y} t {t}: {fd} vs {a}"
        );
    }
}

#[test]
fn the_seed_reproduces_the_sea_bit_for_bit() {
    let s = Spectrum::jonswap(5.0, 11.0, 3.3).unwrap();
    let spec = SeaSpec::new(s, 200.0, 42);
    let heights = [10.0, 100.0, 190.0];
    let (a, b) = (
        Sea::new(&spec, 0.1, 60.0).unwrap(),
        Sea::new(&spec, 0.1, 60.0).unwrap(),
    );
    let (ra, rb) = (
        a.record(&heights, 600).unwrap(),
        b.record(&heights, 600).unwrap(),
    );
    let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
    assert_eq!(bits(a.phases()), bits(b.phases()));
    for k in 0..=600 {
        assert_eq!(bits(ra.velocity(k)), bits(rb.velocity(k)));
        assert_eq!(bits(ra.acceleration(k)), bits(rb.acceleration(k)));
    }
    assert_eq!(bits(ra.elevations()), bits(rb.elevations()));
    // Another seed, another sea.
    let c = Sea::new(&SeaSpec { seed: 43, ..spec }, 0.1, 60.0).unwrap();
    assert!(c.phases()[0].to_bits() != a.phases()[0].to_bits());
    // The generator is ChaCha20 keyed by the seed: seed 0 is the all-zero key, whose first
    // keystream bytes are RFC 8439 §A.1 test vector #1, 76 b8 e0 ad a0 f1 3d 90 (checked also
    // with Python's `cryptography`): φ₁ = 2π ⌊0x903df1a0ade0b876 / 2¹¹⌋ 2⁻⁵³.
    let zero = Sea::new(&SeaSpec { seed: 0, ..spec }, 0.1, 60.0).unwrap();
    let expect = (0x903d_f1a0_ade0_b876u64 >> 11) as f64 * (2.0 * PI / (1u64 << 53) as f64);
    assert_eq!(zero.phases()[0].to_bits(), expect.to_bits());
    // The default sea does not depend on the step when h divides 3 h: same frequencies, phases
    // and (up to the FFTs' round-off) the same record at common times.
    let fine = Sea::new(&spec, 0.05, 60.0).unwrap();
    assert_eq!(bits(fine.frequencies()), bits(a.frequencies()));
    assert_eq!(bits(fine.phases()), bits(a.phases()));
    let rf = fine.record(&heights, 1200).unwrap();
    for k in 0..=600 {
        assert!((rf.elevation(2 * k) - ra.elevation(k)).abs() < 1e-12);
    }
}

#[test]
fn bad_sea_states_are_rejected_with_the_quantity_named() {
    use chainbeam::ocean::SeaError;
    let s = Spectrum::pierson_moskowitz(2.0, 8.0).unwrap();
    let named = |r: Result<Sea, SeaError>| match r {
        Err(SeaError::Invalid { quantity, .. }) => quantity,
        other => panic!("{other:?}"),
    };
    assert_eq!(
        named(Sea::new(&SeaSpec::new(s, -1.0, 0), 0.1, 1.0)),
        "depth"
    );
    assert_eq!(named(Sea::new(&SeaSpec::new(s, 10.0, 0), 0.0, 1.0)), "step");
    assert_eq!(
        named(Sea::new(
            &SeaSpec {
                components: Some(0),
                ..SeaSpec::new(s, 10.0, 0)
            },
            0.1,
            1.0
        )),
        "components"
    );
    assert!(matches!(
        Sea::new(&SeaSpec::new(s, 10.0, 0), 1e-5, 1.0),
        Err(SeaError::TooLarge { .. })
    ));
    let sea = Sea::new(&SeaSpec::new(s, 10.0, 0), 0.1, 1.0).unwrap();
    assert!(matches!(
        sea.record(&[f64::NAN], 3),
        Err(SeaError::Invalid {
            quantity: "height",
            ..
        })
    ));
}
