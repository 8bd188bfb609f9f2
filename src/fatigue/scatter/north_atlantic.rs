//! A published, tabulated scatter diagram: the North Atlantic (H_s, T_z) table of IACS
//! Recommendation No. 34 ("Standard Wave Data"), and its reduction to a few cells.
//!
//! Source, as retrieved: Korean Register, *Rules for the Classification of Steel Ships*, Guidance
//! RA-03-E (2025), Part 3, Annex 3-2 "Guidance for the Direct Strength Assessment", II.5.(3)(F),
//! Table 3: "Probability of sea-states in the North Atlantic described as occurrence per 100000
//! observations. Derived from BMT's Global Wave Statistics" (areas 8, 9, 15 and 16 of Global
//! Wave Statistics; the text names it IACS Rec. No. 34). H_s and T_z are the class midpoints
//! (1 m × 1 s classes). [`NORTH_ATLANTIC_OCCURRENCES`] is that table cell by cell; its rows and
//! columns add up to the table's printed totals within their rounding (tests/fatigue/fatigue_scatter.rs)
//! and the whole to 100 000.
//!
//! The same guidance, II.5.(3)(E), gives the table's spectrum: the two-parameter
//! Pierson-Moskowitz (Bretschneider) sea
//! S(ω | H_s, T_z) = H_s²/(4π) (2π/T_z)⁴ ω⁻⁵ exp(−(1/π) (2π/T_z)⁴ ω⁻⁴).
//! It is [`crate::ocean::SpectrumKind::PiersonMoskowitz`] (docs/ocean.md "Irregular seas") with
//! ω_p⁴ = 4/(5π) (2π/T_z)⁴ (set dS/dω = 0), i.e. T_p = (5π/4)^¼ T_z ≈ 1.4077 T_z
//! ([`tp_over_tz`]): the conversion this module applies. A scene run on these cells should keep
//! γ = 1 (a Pierson-Moskowitz sea) to be the table's sea.
//!
//! The reduction ([`lump_north_atlantic`], [`reduced_north_atlantic`]): adjacent classes are
//! lumped into rectangular groups (the table's occurrences added); each group is represented by
//! the root-mean-square of its H_s midpoints (so the group's mean wave variance H_s²/16 is kept)
//! and the occurrence-weighted mean of its T_z midpoints, converted to T_p; groups holding less
//! than a threshold are dropped and the kept ones renormalised to add up to 1.

use super::{ScatterCell, SeaState};

/// T_p/T_z of the table's Pierson-Moskowitz spectrum: (5π/4)^¼ (module docs).
pub fn tp_over_tz() -> f64 {
    (1.25 * std::f64::consts::PI).powf(0.25)
}

/// The table's H_s class midpoints \[m\] (rows).
pub const NORTH_ATLANTIC_HS: [f64; 17] = [
    0.5, 1.5, 2.5, 3.5, 4.5, 5.5, 6.5, 7.5, 8.5, 9.5, 10.5, 11.5, 12.5, 13.5, 14.5, 15.5, 16.5,
];

/// The table's T_z class midpoints \[s\] (columns).
pub const NORTH_ATLANTIC_TZ: [f64; 18] = [
    1.5, 2.5, 3.5, 4.5, 5.5, 6.5, 7.5, 8.5, 9.5, 10.5, 11.5, 12.5, 13.5, 14.5, 15.5, 16.5, 17.5,
    18.5,
];

/// Occurrences per 100 000 observations, `[row H_s][column T_z]` (module docs: IACS Rec. No. 34
/// as printed in KR Guidance RA-03-E (2025), Pt 3 Annex 3-2, Table 3).
#[rustfmt::skip]
pub const NORTH_ATLANTIC_OCCURRENCES: [[f64; 18]; 17] = [
    [0.0, 0.0, 1.3, 133.7, 865.6, 1186.0, 634.2, 186.3, 36.9, 5.6, 0.7, 0.1, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0],
    [0.0, 0.0, 0.0, 29.3, 986.0, 4976.0, 7738.0, 5569.7, 2375.7, 703.5, 160.7, 30.5, 5.1, 0.8, 0.1, 0.0, 0.0, 0.0],
    [0.0, 0.0, 0.0, 2.2, 197.5, 2158.8, 6230.0, 7449.5, 4860.4, 2066.0, 644.5, 160.2, 33.7, 6.3, 1.1, 0.2, 0.0, 0.0],
    [0.0, 0.0, 0.0, 0.2, 34.9, 695.5, 3226.5, 5675.0, 5099.1, 2838.0, 1114.1, 337.7, 84.3, 18.2, 3.5, 0.6, 0.1, 0.0],
    [0.0, 0.0, 0.0, 0.0, 6.0, 196.1, 1354.3, 3288.5, 3857.5, 2685.5, 1275.2, 455.1, 130.9, 31.9, 6.9, 1.3, 0.2, 0.0],
    [0.0, 0.0, 0.0, 0.0, 1.0, 51.0, 498.4, 1602.9, 2372.7, 2008.3, 1126.0, 463.6, 150.9, 41.0, 9.7, 2.1, 0.4, 0.1],
    [0.0, 0.0, 0.0, 0.0, 0.2, 12.6, 167.0, 690.3, 1257.9, 1268.6, 825.9, 386.8, 140.8, 42.2, 10.9, 2.5, 0.5, 0.1],
    [0.0, 0.0, 0.0, 0.0, 0.0, 3.0, 52.1, 270.1, 594.4, 703.2, 524.9, 276.7, 111.7, 36.7, 10.2, 2.5, 0.6, 0.1],
    [0.0, 0.0, 0.0, 0.0, 0.0, 0.7, 15.4, 97.9, 255.9, 350.6, 296.9, 174.6, 77.6, 27.7, 8.4, 2.2, 0.5, 0.1],
    [0.0, 0.0, 0.0, 0.0, 0.0, 0.2, 4.3, 33.2, 101.9, 159.9, 152.2, 99.2, 48.3, 18.7, 6.1, 1.7, 0.4, 0.1],
    [0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 1.2, 10.7, 37.9, 67.5, 71.7, 51.5, 27.3, 11.4, 4.0, 1.2, 0.3, 0.1],
    [0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.3, 3.3, 13.3, 26.6, 31.4, 24.7, 14.2, 6.4, 2.4, 0.7, 0.2, 0.1],
    [0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.1, 1.0, 4.4, 9.9, 12.8, 11.0, 6.8, 3.3, 1.3, 0.4, 0.1, 0.0],
    [0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.3, 1.4, 3.5, 5.0, 4.6, 3.1, 1.6, 0.7, 0.2, 0.1, 0.0],
    [0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.1, 0.4, 1.2, 1.8, 1.8, 1.3, 0.7, 0.3, 0.1, 0.0, 0.0],
    [0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.1, 0.4, 0.6, 0.7, 0.5, 0.3, 0.1, 0.1, 0.0, 0.0],
    [0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.1, 0.2, 0.2, 0.2, 0.1, 0.1, 0.0, 0.0, 0.0],
];

/// The number of observations the table's occurrences are counted out of.
pub const NORTH_ATLANTIC_TOTAL: f64 = 100_000.0;

/// The H_s group edges of [`reduced_north_atlantic`] \[m\]: pairs of adjacent 1 m rows
/// (0–2, 2–4, 4–6, 6–8 m) and every row from 8 m up.
pub const REDUCED_NA_HS_EDGES: [f64; 6] = [0.0, 2.0, 4.0, 6.0, 8.0, f64::INFINITY];

/// The T_z group edges of [`reduced_north_atlantic`] \[s\]: the columns below 6 s (almost
/// empty), pairs of adjacent 1 s columns (6–8, 8–10, 10–12 s) and every column from 12 s up.
pub const REDUCED_NA_TZ_EDGES: [f64; 6] = [0.0, 6.0, 8.0, 10.0, 12.0, f64::INFINITY];

/// The least probability of a group kept by [`reduced_north_atlantic`] (0.1 %): the 4 of the
/// 24 non-empty groups below it hold 66 of the 100 000 observations (0.066 %).
pub const REDUCED_NA_MIN_PROBABILITY: f64 = 1e-3;

/// The table lumped into the groups between `hs_edges` × `tz_edges` (a class belongs to the
/// group with `lo ≤ midpoint < hi`), H_s slowest, empty groups left out, each with the
/// probability `occurrences / 100 000` and the sea state of the module docs
/// (H_s = √(Σ o H²/Σ o), T_p = [`tp_over_tz`] · Σ o T_z/Σ o, direction the scene's).
pub fn lump_north_atlantic(hs_edges: &[f64], tz_edges: &[f64]) -> Vec<ScatterCell> {
    let mut out = Vec::new();
    for h in hs_edges.windows(2) {
        for t in tz_edges.windows(2) {
            let (mut occurrences, mut h2, mut tz) = (0.0, 0.0, 0.0);
            for (row, hs) in NORTH_ATLANTIC_OCCURRENCES.iter().zip(NORTH_ATLANTIC_HS) {
                if !(h[0] <= hs && hs < h[1]) {
                    continue;
                }
                for (&o, t_z) in row.iter().zip(NORTH_ATLANTIC_TZ) {
                    if t[0] <= t_z && t_z < t[1] {
                        occurrences += o;
                        h2 += o * hs * hs;
                        tz += o * t_z;
                    }
                }
            }
            if occurrences > 0.0 {
                out.push(ScatterCell {
                    sea: SeaState {
                        hs: (h2 / occurrences).sqrt(),
                        tp: tp_over_tz() * tz / occurrences,
                        direction: None,
                    },
                    probability: occurrences / NORTH_ATLANTIC_TOTAL,
                });
            }
        }
    }
    out
}

/// The IACS Rec. No. 34 North Atlantic diagram reduced to 20 cells: [`lump_north_atlantic`]
/// over [`REDUCED_NA_HS_EDGES`] × [`REDUCED_NA_TZ_EDGES`], groups below
/// [`REDUCED_NA_MIN_PROBABILITY`] dropped (0.066 % of the time) and the rest renormalised to
/// add up to 1. The wave climate of `examples/scatter/north_atlantic_iacs34.csv`.
pub fn reduced_north_atlantic() -> Vec<ScatterCell> {
    let mut cells: Vec<ScatterCell> =
        lump_north_atlantic(&REDUCED_NA_HS_EDGES, &REDUCED_NA_TZ_EDGES)
            .into_iter()
            .filter(|c| c.probability >= REDUCED_NA_MIN_PROBABILITY)
            .collect();
    let kept: f64 = cells.iter().map(|c| c.probability).sum();
    for c in &mut cells {
        c.probability /= kept;
    }
    cells
}
