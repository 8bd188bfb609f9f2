//! The fast paths of the wave field's set-up and of the step's solves give the reference
//! arithmetic's values bit for bit:
//!
//! - [`Profiles`] (the velocity amplitudes of many cells or heights of one sea: denominators once
//!   per component, e^{−k(y+d)} left out where it cannot change the rounded sum, shared cell ends
//!   reused) against [`Sea::cell_velocity_amplitudes`] and [`Sea::velocity_amplitudes`], which
//!   evaluate [`chainbeam::ocean::cell_profile`] and [`chainbeam::ocean::depth_profile`] per
//!   component: the reference is the library's own direct formula, compared with `to_bits`;
//! - [`BorderedTridiag`] with the tip constraint's border (zero but in its last entry), whose
//!   factorisation skips the forward sweep's zeros, against the full Thomas sweep and Schur
//!   complement written out here (the algorithm of `src/tridiag.rs` before the fast path).

use chainbeam::ocean::{Complex, Profiles, Sea, SeaSpec, Spectrum};
use chainbeam::tridiag::BorderedTridiag;

/// The riser system's sea (examples/scenes/riser_300m_system.toml: JONSWAP H_s = 1.44 m,
/// T_p = 7.66 s, γ = 1, 300 m of water, seed 1, h = 0.004 s, a 3-hour repeat period): about
/// 8 500 components, from long waves (k d ≪ 1) to k ≈ 2.5 rad/m.
fn riser_sea() -> Sea {
    let spectrum = Spectrum::jonswap(1.44, 7.66, 1.0).unwrap();
    Sea::new(&SeaSpec::new(spectrum, 300.0, 1), 0.004, 10.0).unwrap()
}

fn bits(v: &[Complex<f64>]) -> Vec<(u64, u64)> {
    v.iter().map(|c| (c.re.to_bits(), c.im.to_bits())).collect()
}

/// Cells as a chain's nodes have them (ends shared, from the top down as the wave field forms
/// them, some lengths that do not add up exactly), one cut by the surface, one reaching below
/// the seabed, and heights from the seabed to above the surface.
#[test]
fn profiles_equal_the_direct_formula_bit_for_bit() {
    let sea = riser_sea();
    let nc = sea.frequencies().len();
    assert!(nc > 8000, "{nc} components");
    let zero = Complex::new(0.0, 0.0);
    let (mut fast, mut reference) = (vec![zero; nc], vec![zero; nc]);
    let mut profiles = Profiles::new(&sea);
    // Node heights of a chain with pendulums of 7.62 m and 3 m (as the riser system's), from
    // 300.5 m (above the surface) down: each cell [y − l/2, y + l_next/2].
    let mut heights = vec![0.0];
    for i in 0..60 {
        let l = if i % 7 == 3 { 3.0 } else { 7.62 };
        heights.push(heights[i] + l);
    }
    let mut cells = Vec::new();
    for i in (1..heights.len() - 1).rev() {
        let (lo, hi) = (
            0.5 * (heights[i - 1] + heights[i]),
            0.5 * (heights[i] + heights[i + 1]),
        );
        cells.push((lo, hi));
    }
    cells.extend([
        (295.0, 305.0),
        (299.999_999, 300.000_001),
        (-2.0, 1.5),
        (0.0, 1e-3),
        (150.0, 150.0 + 1e-9),
        (301.0, 302.0),
    ]);
    let mut skipped = 0usize;
    for &(lo, hi) in &cells {
        profiles.cell_velocity_amplitudes((lo, hi), &mut fast);
        sea.cell_velocity_amplitudes((lo, hi), &mut reference);
        assert_eq!(bits(&fast), bits(&reference), "cell [{lo}, {hi}]");
        skipped += sea
            .wavenumbers()
            .iter()
            .filter(|&&k| k * lo.clamp(0.0, 300.0) >= 20.0)
            .count();
    }
    // The negligible exponential is left out for most components of most cells.
    assert!(skipped > cells.len() * nc / 2, "{skipped}");
    for y in [
        0.0,
        1e-6,
        0.5,
        7.62,
        30.0,
        150.0,
        299.0,
        300.0,
        300.0 + 1e-8,
        301.0,
    ] {
        profiles.velocity_amplitudes(y, &mut fast);
        sea.velocity_amplitudes(y, &mut reference);
        assert_eq!(bits(&fast), bits(&reference), "height {y}");
    }
}

/// The full Thomas sweep and Schur complement of a bordered tridiagonal system (the algorithm
/// of `src/tridiag.rs` without the tip-border path): reciprocal pivots, x2 = T⁻¹b by the full
/// sweep, y = (s − cᵀx1)/(d − cᵀx2), x = x1 − y x2.
fn reference_solve(t: &BorderedTridiag<f64>, rhs: &mut [f64]) {
    let n = t.diag.len();
    let (mut cp, mut piv) = (vec![0.0; n], vec![0.0; n]);
    for i in 0..n {
        let m = if i > 0 {
            t.diag[i] - t.lower[i] * cp[i - 1]
        } else {
            t.diag[i]
        };
        let inv = m.recip();
        piv[i] = inv;
        cp[i] = if i + 1 < n { t.upper[i] * inv } else { 0.0 };
    }
    let sweep = |x: &mut [f64]| {
        for i in 0..n {
            let prev = if i > 0 { x[i - 1] * t.lower[i] } else { 0.0 };
            x[i] = (x[i] - prev) * piv[i];
        }
        for i in (0..n - 1).rev() {
            let next = x[i + 1];
            x[i] -= next * cp[i];
        }
    };
    let mut x2 = t.col.clone();
    sweep(&mut x2);
    let mut cx2 = 0.0;
    for (r, x) in t.row.iter().zip(&x2) {
        cx2 += r * x;
    }
    let schur_inv = (t.corner - cx2).recip();
    sweep(&mut rhs[..n]);
    let mut cx1 = 0.0;
    for (r, c) in rhs.iter().zip(&t.row) {
        cx1 += r * c;
    }
    let y = (rhs[n] - cx1) * schur_inv;
    for (r, x) in rhs.iter_mut().zip(&x2) {
        *r -= y * x;
    }
    rhs[n] = y;
}

/// The tip constraint's border (zero but in its last entry) solves to the full sweep's values
/// bit for bit, on matrices of the Newton and projection kind (diagonally dominant, pivots of
/// both signs) with n = 1, 2, 60 and 1000, and a right-hand side with zeros of both signs.
#[test]
fn tip_border_solve_equals_the_full_sweep_bit_for_bit() {
    let mut seed = 0x2545_f491_4f6c_dd1du64;
    let mut rand = move || {
        seed ^= seed << 13;
        seed ^= seed >> 7;
        seed ^= seed << 17;
        (seed >> 11) as f64 / (1u64 << 53) as f64 - 0.5
    };
    for n in [1usize, 2, 60, 1000] {
        for sign in [1.0, -1.0] {
            let mut t = BorderedTridiag::<f64>::new(n, true);
            for ((d, l), u) in t.diag.iter_mut().zip(&mut t.lower).zip(&mut t.upper) {
                *d = sign * (4.0 + rand());
                *l = rand();
                *u = rand();
            }
            t.col[n - 1] = rand();
            t.row[n - 1] = rand();
            t.corner = 3.0 + rand();
            let mut rhs: Vec<f64> = (0..=n).map(|_| rand()).collect();
            if n > 2 {
                rhs[0] = -0.0;
                rhs[1] = 0.0;
            }
            let mut expected = rhs.clone();
            reference_solve(&t, &mut expected);
            t.solve(&mut rhs).unwrap();
            let b = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
            assert_eq!(b(&rhs), b(&expected), "n = {n}, sign {sign}");
        }
    }
}
