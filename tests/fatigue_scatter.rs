//! The scatter diagram of the Kvitebjørn joint model (src/fatigue/scatter.rs): the cells add up
//! to 1, the marginal is continuous at h₀, and a cell's probability equals a direct 2-D
//! integration of the joint density (an independent computation: densities, not CDFs).

use chainbeam::fatigue::scatter::{Bins, KVITEBJORN};

/// f_H(h) f_T|H(t) of the model, written from the formulas of the module docs.
fn joint_density(h: f64, t: f64) -> f64 {
    let m = KVITEBJORN;
    let two_pi = 2.0 * std::f64::consts::PI;
    let lognormal = |x: f64, mu: f64, s: f64| {
        (-(x.ln() - mu).powi(2) / (2.0 * s * s)).exp() / (x * s * two_pi.sqrt())
    };
    let fh = if h <= m.h0 {
        lognormal(h, m.ln_hs.0, m.ln_hs.1)
    } else {
        let (k, l) = m.weibull;
        k / l * (h / l).powf(k - 1.0) * (-(h / l).powf(k)).exp()
    };
    let mu = m.mu[0] + m.mu[1] * h.powf(m.mu[2]);
    let s = (m.var[0] + m.var[1] * (-m.var[2] * h).exp()).sqrt();
    fh * lognormal(t, mu, s)
}

#[test]
fn cells_add_up_and_match_a_direct_integration() {
    let m = KVITEBJORN;
    // Continuity of F_H at h₀ = 2.9 m (the two branches were fitted to meet there).
    let (below, above) = (m.hs_cdf(2.9), m.hs_cdf(2.9 + 1e-9));
    assert!((below - above).abs() < 1e-3, "{below} {above}");

    let hs = Bins::new(
        &[0.0, 1.0, 2.0, 3.0, 4.0, 6.0, f64::INFINITY],
        &[0.5, 1.5, 2.5, 3.5, 5.0, 7.0],
    )
    .unwrap();
    let tp = Bins::new(
        &[0.0, 8.0, 11.0, 14.0, f64::INFINITY],
        &[6.0, 9.5, 12.5, 16.0],
    )
    .unwrap();
    assert!(Bins::new(&[0.0, 1.0], &[0.5, 1.5]).is_none());
    let all = m.cells(&hs, &tp, 0.0);
    assert_eq!(all.len(), 24);
    let total: f64 = all.iter().map(|c| c.probability).sum();
    assert!((total - 1.0).abs() < 1e-6, "{total}");

    // Direct midpoint integration of the density over a cell on each branch (a cell across
    // h₀ would differ by the branches' small mismatch there: the bin method takes F_H's step).
    for ((h0, h1), (t0, t1)) in [((1.0, 2.0), (8.0, 11.0)), ((4.0, 6.0), (11.0, 14.0))] {
        let n = 1000;
        let (dh, dt) = ((h1 - h0) / n as f64, (t1 - t0) / n as f64);
        let mut direct = 0.0;
        for i in 0..n {
            for j in 0..n {
                let h = h0 + (i as f64 + 0.5) * dh;
                let t = t0 + (j as f64 + 0.5) * dt;
                direct += joint_density(h, t) * dh * dt;
            }
        }
        let cell = m.cell_probability((h0, h1), (t0, t1));
        assert!((cell - direct).abs() < 1e-5 * direct, "{cell} vs {direct}");
        assert!(cell > 0.01, "a common sea state: {cell}");
    }
    // Leaving out rare cells lowers the sum by what they held.
    let kept = m.cells(&hs, &tp, 1e-3);
    let dropped: f64 = all
        .iter()
        .filter(|c| c.probability < 1e-3)
        .map(|c| c.probability)
        .sum();
    let kept_sum: f64 = kept.iter().map(|c| c.probability).sum();
    assert!((kept_sum + dropped - total).abs() < 1e-12);
    // The cells carry their bins' representatives.
    assert_eq!((all[9].sea.hs, all[9].sea.tp), (2.5, 9.5));
}
