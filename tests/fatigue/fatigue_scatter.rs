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

/// The totals printed with the IACS Rec. No. 34 North Atlantic table (KR Guidance RA-03-E
/// (2025), Pt 3 Annex 3-2, Table 3): the SUM column (per H_s row) and the SUM row (per T_z
/// column), rounded to whole observations by the table itself.
const PRINTED_ROW_SUMS: [f64; 17] = [
    3050.0, 22575.0, 23810.0, 19128.0, 13289.0, 8328.0, 4806.0, 2586.0, 1309.0, 626.0, 285.0,
    124.0, 51.0, 21.0, 8.0, 3.0, 1.0,
];
const PRINTED_COLUMN_SUMS: [f64; 18] = [
    0.0, 0.0, 1.0, 165.0, 2091.0, 9280.0, 19922.0, 24879.0, 20870.0, 12898.0, 6245.0, 2479.0,
    837.0, 247.0, 66.0, 16.0, 3.0, 1.0,
];

#[test]
fn north_atlantic_table_matches_its_printed_totals() {
    use chainbeam::fatigue::scatter::{NORTH_ATLANTIC_OCCURRENCES as O, NORTH_ATLANTIC_TOTAL};
    // Every cell as transcribed against the source's own row and column totals: each printed
    // total is the sum of its 0.1-resolution cells rounded, so they agree within 0.5 (the
    // largest difference here is 0.5, row 8.5 m: 1308.5 printed as 1309).
    for (row, printed) in O.iter().zip(PRINTED_ROW_SUMS) {
        let sum: f64 = row.iter().sum();
        assert!((sum - printed).abs() <= 0.5 + 1e-9, "{sum} vs {printed}");
    }
    for (j, printed) in PRINTED_COLUMN_SUMS.iter().enumerate() {
        let sum: f64 = O.iter().map(|row| row[j]).sum();
        assert!(
            (sum - printed).abs() <= 0.5 + 1e-9,
            "column {j}: {sum} vs {printed}"
        );
    }
    let total: f64 = O.iter().flatten().sum();
    assert!((total - NORTH_ATLANTIC_TOTAL).abs() < 1e-6, "{total}");
}

#[test]
fn tp_over_tz_is_the_peak_of_the_tables_spectrum() {
    use chainbeam::fatigue::scatter::tp_over_tz;
    use chainbeam::ocean::Spectrum;
    use std::f64::consts::PI;
    // The table's spectrum as the guidance writes it (Pt 3 Annex 3-2, II.5.(3)(E)):
    // S(ω | H_s, T_z) = H_s²/(4π) (2π/T_z)⁴ ω⁻⁵ exp(−(1/π) (2π/T_z)⁴ ω⁻⁴).
    let (hs, tz) = (3.0, 8.5);
    let bretschneider = |w: f64| {
        let a = (2.0 * PI / tz).powi(4);
        hs * hs / (4.0 * PI) * a * w.powi(-5) * (-a / PI * w.powi(-4)).exp()
    };
    // Its peak by a golden-section search (independent of the closed form).
    let (mut a, mut b) = (0.2, 2.0);
    let g = 0.5 * (5f64.sqrt() - 1.0);
    for _ in 0..200 {
        let (c, d) = (b - g * (b - a), a + g * (b - a));
        if bretschneider(c) > bretschneider(d) {
            b = d;
        } else {
            a = c;
        }
    }
    let tp_search = 2.0 * PI / (0.5 * (a + b));
    let tp = tp_over_tz() * tz;
    assert!((tp_search - tp).abs() < 1e-6 * tp, "{tp_search} vs {tp}");
    // And it is the library's Pierson-Moskowitz sea at that T_p, point by point.
    let pm = Spectrum::pierson_moskowitz(hs, tp).unwrap();
    for w in [0.3, 0.5, 0.74, 1.0, 1.7] {
        let (s, r) = (pm.density(w), bretschneider(w));
        assert!((s - r).abs() <= 1e-12 * r, "ω = {w}: {s} vs {r}");
    }
}

#[test]
fn reduced_north_atlantic_lumps_and_renormalises() {
    use chainbeam::fatigue::scatter::{
        lump_north_atlantic, reduced_north_atlantic, tp_over_tz, NORTH_ATLANTIC_HS as H,
        NORTH_ATLANTIC_OCCURRENCES as O, NORTH_ATLANTIC_TZ as T, REDUCED_NA_HS_EDGES,
        REDUCED_NA_MIN_PROBABILITY, REDUCED_NA_TZ_EDGES,
    };
    // Lumping every class on its own gives the table back, cell by cell.
    let edges = |mids: &[f64]| {
        let mut e: Vec<f64> = mids.iter().map(|m| m - 0.5).collect();
        e.push(mids[mids.len() - 1] + 0.5);
        e
    };
    let fine = lump_north_atlantic(&edges(&H), &edges(&T));
    let nonzero = O.iter().flatten().filter(|&&o| o > 0.0).count();
    assert_eq!(fine.len(), nonzero);
    let first = fine[0]; // H_s = 0.5 m, T_z = 3.5 s: 1.3 observations
    assert_eq!(first.sea.hs, 0.5);
    assert!((first.sea.tp - tp_over_tz() * 3.5).abs() < 1e-12);
    assert!((first.probability - 1.3e-5).abs() < 1e-15);

    // The 5 × 5 groups: 24 non-empty, 4 below 0.1 % holding 66 observations.
    let all = lump_north_atlantic(&REDUCED_NA_HS_EDGES, &REDUCED_NA_TZ_EDGES);
    assert_eq!(all.len(), 24);
    let total: f64 = all.iter().map(|c| c.probability).sum();
    assert!((total - 1.0).abs() < 1e-12, "{total}");
    let dropped: f64 = all
        .iter()
        .filter(|c| c.probability < REDUCED_NA_MIN_PROBABILITY)
        .map(|c| c.probability)
        .sum();
    assert!((dropped - 66.0e-5).abs() < 1e-12, "{dropped}");

    let cells = reduced_north_atlantic();
    assert_eq!(cells.len(), 20);
    let sum: f64 = cells.iter().map(|c| c.probability).sum();
    assert!((sum - 1.0).abs() < 1e-12, "{sum}");
    // A group by hand: H_s 2–4 m × T_z 8–10 s = rows 2.5, 3.5 × columns 8.5, 9.5.
    let o = [[7449.5, 4860.4], [5675.0, 5099.1]];
    let n: f64 = o.iter().flatten().sum();
    let hs = ((o[0][0] + o[0][1]) * 2.5f64.powi(2) + (o[1][0] + o[1][1]) * 3.5f64.powi(2)) / n;
    let tz = ((o[0][0] + o[1][0]) * 8.5 + (o[0][1] + o[1][1]) * 9.5) / n;
    let cell = cells
        .iter()
        .find(|c| (c.sea.hs - hs.sqrt()).abs() < 1e-12)
        .expect("the 2–4 m × 8–10 s group is kept");
    assert!((cell.sea.tp - tp_over_tz() * tz).abs() < 1e-12);
    assert!((cell.probability - n / 1e5 / (1.0 - dropped)).abs() < 1e-12);
}

#[test]
fn the_committed_csv_is_the_reduced_north_atlantic() {
    use chainbeam::fatigue::scatter::reduced_north_atlantic;
    let path = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/examples/scatter/north_atlantic_iacs34.csv"
    );
    let text = std::fs::read_to_string(path).unwrap();
    let rows: Vec<&str> = text
        .lines()
        .filter(|l| !l.starts_with('#') && !l.trim().is_empty())
        .collect();
    let expected: Vec<String> = reduced_north_atlantic()
        .iter()
        .map(|c| format!("{},{},{}", c.sea.hs, c.sea.tp, c.probability))
        .collect();
    assert_eq!(rows[0], "hs,tp,probability");
    assert_eq!(
        rows[1..],
        expected.iter().map(String::as_str).collect::<Vec<_>>()[..],
        "regenerate the rows from reduced_north_atlantic():\n{}",
        expected.join("\n")
    );
}

/// `chainbeam fatigue --scatter examples/scatter/north_atlantic_iacs34.csv` reads the committed
/// file (its comment lines, header and 20 rows) and reports its 20 cells with their
/// probabilities, the total being their sum, on a small wave riser (6 pendulums of a 60 m,
/// 533.4 × 22.2 mm pipe, a Pierson-Moskowitz sea as the table's, 20 s of 0.05 s).
#[test]
fn the_committed_csv_runs_through_the_cli() {
    use assert_cmd::cargo::cargo_bin_cmd;
    use chainbeam::fatigue::scatter::reduced_north_atlantic;
    let dir = tempfile::tempdir().unwrap();
    let scene = "[beam]\npendulums = 6\nsupport = \"riser\"\n\n\
                 [pipe]\nlength = 60.0\nouter_diameter = 0.5334\nwall_thickness = 0.0222\n\n\
                 [water]\ndepth = 60.0\n\n[loads]\ntension = 1e6\ndrag = 1e-4\n\n\
                 [loads.waves]\nspectrum = \"pierson-moskowitz\"\nhs = 3.0\ntp = 9.0\nseed = 7\n\n\
                 [time]\nstep = 0.05\nsteps = 400\n\n\
                 [fatigue]\nouter_diameter = 0.5334\nwall_thickness = 0.0222\n";
    std::fs::write(dir.path().join("w.toml"), scene).unwrap();
    let csv = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/examples/scatter/north_atlantic_iacs34.csv"
    );
    let out = cargo_bin_cmd!("chainbeam")
        .current_dir(dir.path())
        .args(["fatigue", "w.toml", "--scatter", csv, "--record", "20"])
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(0), "{stderr}");
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    let cells = v["cells"].as_array().unwrap();
    let expected = reduced_north_atlantic();
    assert_eq!(cells.len(), expected.len());
    let mut total = 0.0;
    for (cell, e) in cells.iter().zip(&expected) {
        assert_eq!(cell["hs"].as_f64().unwrap(), e.sea.hs);
        assert_eq!(cell["tp"].as_f64().unwrap(), e.sea.tp);
        assert_eq!(cell["probability"].as_f64().unwrap(), e.probability);
        total += cell["damage_per_year"].as_f64().unwrap();
    }
    let reported = v["damage_per_year"].as_f64().unwrap();
    assert!(reported > 0.0);
    assert!(
        (reported - total).abs() <= 1e-12 * reported,
        "{reported} vs {total}"
    );
}
