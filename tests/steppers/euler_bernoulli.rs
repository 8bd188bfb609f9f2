//! Tests of the Euler-Bernoulli reference beam (`chainbeam::euler_bernoulli`): the closed-form
//! static deflections (thesis eq. 2.4.5-2.4.7, docs/conventions.md corrected), the finite-difference beam
//! (eq. 2.3.1) with ghost-node end conditions, its convergence to the closed forms, its Störmer–Verlet
//! time integration, and argument validation.

use chainbeam::euler_bernoulli::{
    static_cantilever, static_fixed_fixed, static_pinned_pinned, EbSupport, EulerBernoulli,
    EulerBernoulliError,
};
use nalgebra::DMatrix;

/// Grid-convergence scene of the brief: L = 10 m, EI = 1000 Nm², F = 2 N (the thesis's §2.4.4
/// values with EI = k·l).
const L: f64 = 10.0;
const EI: f64 = 1000.0;
const F: f64 = 2.0;

/// Formats a slice in scientific notation for the diagnostic prints.
fn sci(x: &[f64]) -> String {
    x.iter()
        .map(|v| format!("{v:.3e}"))
        .collect::<Vec<_>>()
        .join(", ")
}

fn rel(a: f64, b: f64) -> f64 {
    (a - b).abs() / b.abs()
}

const SUPPORTS: [EbSupport; 3] = [
    EbSupport::Cantilever,
    EbSupport::FixedFixed,
    EbSupport::PinnedPinned,
];

/// Closed form for a support, with its load node for a grid of n segments: the tip for the
/// cantilever (eq. 2.4.5), the centre for the others (eq. 2.4.6/2.4.7).
fn closed_form(support: EbSupport) -> fn(f64, f64, f64, f64) -> f64 {
    match support {
        EbSupport::Cantilever => static_cantilever,
        EbSupport::FixedFixed => static_fixed_fixed,
        EbSupport::PinnedPinned => static_pinned_pinned,
    }
}

fn load_node(support: EbSupport, n: usize) -> usize {
    match support {
        EbSupport::Cantilever => n,
        _ => n / 2,
    }
}

fn beam(support: EbSupport, n: usize, mass: f64) -> EulerBernoulli {
    EulerBernoulli::new(n, L, EI, mass, support, &[(load_node(support, n), F)]).unwrap()
}

// ---------------------------------------------------------------------------------------------
// (a) closed forms
// ---------------------------------------------------------------------------------------------

/// Reference: textbook (Gere & Timoshenko, *Mechanics of Materials*, App. G; thesis ref. [21]):
/// cantilever tip δ = P L³/(3EI), fixed-fixed centre δ = P L³/(192 EI), simply supported centre
/// δ = P L³/(48 EI), all toward −z for positive F (thesis sign, docs/conventions.md).
#[test]
fn closed_forms_reference_deflections() {
    let tip = static_cantilever(L, F, EI, L);
    assert!(rel(tip, -F * L.powi(3) / (3.0 * EI)) < 1e-14, "{tip}");
    let ff = static_fixed_fixed(L / 2.0, F, EI, L);
    assert!(rel(ff, -F * L.powi(3) / (192.0 * EI)) < 1e-14, "{ff}");
    let pp = static_pinned_pinned(L / 2.0, F, EI, L);
    assert!(rel(pp, -F * L.powi(3) / (48.0 * EI)) < 1e-14, "{pp}");
    // the ends: clamped/pinned supports have z = 0
    for f in [static_cantilever, static_fixed_fixed, static_pinned_pinned] {
        assert!(f(0.0, F, EI, L).abs() < 1e-15);
    }
    assert!(static_fixed_fixed(L, F, EI, L).abs() < 1e-15);
    assert!(static_pinned_pinned(L, F, EI, L).abs() < 1e-15);
    // all three deflect toward −z for positive F (docs/conventions.md sign erratum of eq. 2.4.7)
    for f in [static_cantilever, static_fixed_fixed, static_pinned_pinned] {
        for k in 1..10 {
            assert!(f(k as f64, F, EI, L) < 0.0);
        }
    }
}

/// Reference: the split at L/2 of eq. 2.4.6/2.4.7 (docs/conventions.md): the beams are symmetric about the
/// centre, and z, z′ are continuous there (z′(L/2) = 0 by symmetry); the slopes at the supports are
/// the textbook ones (clamped: 0; simply supported: −F L²/(16 EI)).
#[test]
fn closed_forms_symmetry_and_continuity() {
    for f in [static_fixed_fixed, static_pinned_pinned] {
        for k in 0..=100 {
            let y = L * k as f64 / 100.0;
            let (a, b) = (f(y, F, EI, L), f(L - y, F, EI, L));
            assert!(
                (a - b).abs() <= 1e-14 * a.abs().max(1e-300),
                "y = {y}: {a} vs {b}"
            );
        }
        // continuity of z and of the slope at L/2 (one-sided differences)
        let c = f(L / 2.0, F, EI, L);
        let eps = 1e-7;
        let left = f(L / 2.0 - eps, F, EI, L);
        let right = f(L / 2.0 + eps, F, EI, L);
        assert!((left - c).abs() < 1e-12 && (right - c).abs() < 1e-12);
        let slope_left = (c - left) / eps;
        let slope_right = (right - c) / eps;
        assert!(slope_left.abs() < 1e-6 && slope_right.abs() < 1e-6);
    }
    let eps = 1e-6;
    let clamped_slope = static_fixed_fixed(eps, F, EI, L) / eps;
    assert!(clamped_slope.abs() < 1e-6);
    let pinned_slope = static_pinned_pinned(eps, F, EI, L) / eps;
    assert!(rel(pinned_slope, -F * L * L / (16.0 * EI)) < 1e-6);
    // the cantilever's free end: zero moment z″(L) = 0, shear EI z‴ = F (the cubic's coefficients)
    let g = |y: f64| static_cantilever(y, F, EI, L);
    let h = 1e-3;
    let curv = (g(L + h) - 2.0 * g(L) + g(L - h)) / (h * h);
    assert!(curv.abs() < 1e-9, "{curv}");
}

// ---------------------------------------------------------------------------------------------
// structure of the finite-difference operator
// ---------------------------------------------------------------------------------------------

/// Reference: thesis eq. 2.3.1 (interior stencil EI/d⁴·(1, −4, 6, −4, 1), times d for point masses)
/// and the ghost-node rows derived in the module documentation.
#[test]
fn stiffness_rows_match_stencil_and_ghost_nodes() {
    let n = 10;
    let d = L / n as f64;
    let s = EI / d.powi(3);
    let rows = |support| {
        let k = EulerBernoulli::new(n, L, EI, 1.0, support, &[])
            .unwrap()
            .stiffness_matrix();
        let m = k.nrows();
        (0..m)
            .map(|j| (0..m).map(|c| k[(j, c)] / s).collect::<Vec<_>>())
            .collect::<Vec<_>>()
    };
    let close = |a: &[f64], b: &[f64]| a.iter().zip(b).all(|(x, y)| (x - y).abs() < 1e-12);
    let pad = |m: usize, start: usize, vals: &[f64]| {
        let mut r = vec![0.0; m];
        r[start..start + vals.len()].copy_from_slice(vals);
        r
    };

    // cantilever: free nodes 1..=10 → 10 dofs
    let c = rows(EbSupport::Cantilever);
    assert_eq!(c.len(), 10);
    assert!(close(&c[0], &pad(10, 0, &[7.0, -4.0, 1.0]))); // z₋₁ = z₁
    assert!(close(&c[4], &pad(10, 2, &[1.0, -4.0, 6.0, -4.0, 1.0])));
    assert!(close(&c[8], &pad(10, 6, &[1.0, -4.0, 5.0, -2.0]))); // z_{n+1} = 2zₙ − z_{n−1}
    assert!(close(&c[9], &pad(10, 7, &[1.0, -2.0, 1.0]))); // ghost row halved
                                                           // fixed-fixed: free nodes 1..=9
    let f = rows(EbSupport::FixedFixed);
    assert_eq!(f.len(), 9);
    assert!(close(&f[0], &pad(9, 0, &[7.0, -4.0, 1.0])));
    assert!(close(&f[8], &pad(9, 6, &[1.0, -4.0, 7.0])));
    // pinned-pinned: z₋₁ = −z₁
    let p = rows(EbSupport::PinnedPinned);
    assert!(close(&p[0], &pad(9, 0, &[5.0, -4.0, 1.0])));
    assert!(close(&p[8], &pad(9, 6, &[1.0, -4.0, 5.0])));
}

/// Reference: a linear Hamiltonian system needs K = Kᵀ > 0 (it is the Hessian of the bending
/// energy); the free-end ghost row is symmetric only after the half-cell scaling.
#[test]
fn stiffness_symmetric_positive_definite_for_all_sizes() {
    for support in SUPPORTS {
        for n in 2..=14 {
            let b = EulerBernoulli::new(n, L, EI, 1.0, support, &[]).unwrap();
            let k = b.stiffness_matrix();
            assert!(
                (&k - k.transpose()).amax() < 1e-9 * k.amax(),
                "{support:?} n={n}"
            );
            assert!(k.clone().cholesky().is_some(), "{support:?} n={n}");
            assert_eq!(*b.free_nodes().end(), k.nrows());
        }
    }
}

/// Reference: the banded Cholesky solve must agree with a dense LU solve of the same K z = f
/// (nalgebra), to round-off.
#[test]
fn banded_solve_matches_dense_lu() {
    for support in SUPPORTS {
        let loads = [(3, 1.5), (7, -0.5), (5, 2.0)];
        let b = EulerBernoulli::new(12, L, EI, 1.0, support, &loads).unwrap();
        let k = b.stiffness_matrix();
        let f = nalgebra::DVector::from_vec(b.load_vector());
        let dense = k.lu().solve(&f).unwrap();
        let z = b.static_solution();
        assert_eq!(z.len(), 13);
        assert!(z[0].abs() < 1e-300);
        for (j, node) in b.free_nodes().enumerate() {
            assert!(
                (z[node] - dense[j]).abs() < 1e-12 * dense.amax(),
                "{support:?}"
            );
        }
    }
}

// ---------------------------------------------------------------------------------------------
// (b) grid convergence of the static solution
// ---------------------------------------------------------------------------------------------

/// Max nodal error of the FD static solution against the closed form (eq. 2.4.5-2.4.7).
fn static_error(support: EbSupport, n: usize) -> f64 {
    let b = beam(support, n, 1.0);
    let z = b.static_solution();
    b.node_positions()
        .iter()
        .zip(&z)
        .map(|(&y, &zi)| (zi - closed_form(support)(y, F, EI, L)).abs())
        .fold(0.0, f64::max)
}

/// Reference: closed forms eq. 2.4.5-2.4.7 (docs/conventions.md corrected) with L = 10, EI = 1000, F = 2. None
/// of the three is reproduced exactly: the clamped ghost z₋₁ = z₁ is a central difference for z′ = 0
/// and misses the cubic's z‴ d³/3 (cantilever, fixed-fixed), and a point load at a node sits on the
/// kink of z‴, which the central stencil smears (fixed-fixed, pinned-pinned; the pinned ghost
/// z₋₁ = −z₁ is exact for the odd cubic and the free-end ghosts are exact for the tip-loaded cubic).
/// Each is an O(d²) residual, so the observed order must be 2.
#[test]
fn static_solution_converges_at_second_order() {
    for support in SUPPORTS {
        let errors: Vec<f64> = [10, 20, 40, 80]
            .iter()
            .map(|&n| static_error(support, n))
            .collect();
        let orders: Vec<f64> = errors.windows(2).map(|w| (w[0] / w[1]).log2()).collect();
        // least-squares slope of log e against log d
        let xs: Vec<f64> = [10.0_f64, 20.0, 40.0, 80.0]
            .iter()
            .map(|n| (L / n).ln())
            .collect();
        let ys: Vec<f64> = errors.iter().map(|e| e.ln()).collect();
        let (mx, my) = (xs.iter().sum::<f64>() / 4.0, ys.iter().sum::<f64>() / 4.0);
        let slope = xs
            .iter()
            .zip(&ys)
            .map(|(x, y)| (x - mx) * (y - my))
            .sum::<f64>()
            / xs.iter().map(|x| (x - mx).powi(2)).sum::<f64>();
        println!(
            "{support:?}: errors {}, pairwise orders {orders:.12?}, fit {slope:.12}",
            sci(&errors)
        );
        assert!((slope - 2.0).abs() < 0.05, "{support:?}: order {slope}");
        for p in orders {
            assert!((p - 2.0).abs() < 0.1, "{support:?}: order {p}");
        }
        // The leading error term, from the residuals named above, is exact here (the error
        // expansion stops at d²): at the load node the FD solution misses the closed form by
        // F L d²/(6EI) (cantilever tip: the response to the clamped-ghost residual F/3 at node 1)
        // and F L d²/(24EI) (centre of fixed-fixed and pinned-pinned; for pinned-pinned K = D² and
        // the error is (F d³/(6EI))·D⁻¹e_centre with D⁻¹e_centre = n/4 there).
        let c = if support == EbSupport::Cantilever {
            F * L / (6.0 * EI)
        } else {
            F * L / (24.0 * EI)
        };
        for (&n, &e) in [10_usize, 20, 40, 80].iter().zip(&errors) {
            let d = L / n as f64;
            assert!(
                rel(e, c * d * d) < 1e-5,
                "{support:?} n={n}: {e} vs {}",
                c * d * d
            );
        }
        // and the error is small in absolute terms at n = 80 (relative to the peak deflection)
        let peak = closed_form(support)(
            if support == EbSupport::Cantilever {
                L
            } else {
                L / 2.0
            },
            F,
            EI,
            L,
        )
        .abs();
        assert!(errors[3] < 2e-3 * peak, "{support:?}");
    }
}

/// Reference: eq. 2.4.5 and the half-cell lumping (module docs). The tip deflection of the FD
/// cantilever approaches −F L³/(3EI) = −2/3 m; loading the *unhalved* ghost row instead (tip load
/// counted on a full cell) would give exactly half of it, one way to get a free end as stiff as the
/// one the thesis reports in §2.3.1 and Fig. 2.16.
#[test]
fn cantilever_tip_matches_eq_2_4_5() {
    let exact = -F * L.powi(3) / (3.0 * EI);
    let z = beam(EbSupport::Cantilever, 80, 1.0).static_solution();
    assert!(rel(z[80], exact) < 1e-3, "{} vs {exact}", z[80]);
}

// ---------------------------------------------------------------------------------------------
// dynamics
// ---------------------------------------------------------------------------------------------

/// Reference: first natural frequency of the continuous beam, ω₁ = (β₁L)² √(EI/(μ L⁴)), with
/// β₁L = 1.875104068711961 (cantilever), 4.730040744862704 (clamped-clamped), π (pinned-pinned)
/// (Rao, *Vibration of Continuous Systems*, Table 11.1). With μ = m/d and the half-cell tip mass the
/// discrete frequency converges at second order, an independent check of the mass lumping.
#[test]
fn fundamental_frequency_converges_at_second_order() {
    let mu = 1.0; // kg/m
    for (support, beta_l) in [
        (EbSupport::Cantilever, 1.875_104_068_711_961_f64),
        (EbSupport::FixedFixed, 4.730_040_744_862_704),
        (EbSupport::PinnedPinned, std::f64::consts::PI),
    ] {
        let exact = beta_l.powi(2) * (EI / (mu * L.powi(4))).sqrt();
        let errs: Vec<f64> = [10, 20, 40]
            .iter()
            .map(|&n| {
                let d = L / n as f64;
                let b = beam(support, n, mu * d);
                let k = b.stiffness_matrix();
                let s: Vec<f64> = b.lumped_masses().iter().map(|m| 1.0 / m.sqrt()).collect();
                let a = DMatrix::from_fn(k.nrows(), k.ncols(), |i, j| s[i] * k[(i, j)] * s[j]);
                let lmin = a.symmetric_eigenvalues().min();
                (lmin.sqrt() - exact).abs() / exact
            })
            .collect();
        let p1 = (errs[0] / errs[1]).log2();
        let p2 = (errs[1] / errs[2]).log2();
        println!(
            "{support:?}: ω₁ rel errors {}, orders {p1:.3} {p2:.3}",
            sci(&errs)
        );
        assert!((p2 - 2.0).abs() < 0.1, "{support:?}: {p1} {p2}");
        assert!(errs[2] < 5e-3, "{support:?}");
    }
}

/// Reference: Gershgorin's theorem bounds λ_max from above; in the interior the bound equals the
/// stencil symbol's maximum 16 EI/(m d³), approached by the true λ_max, so the limit must be nearly
/// sharp. Compared with nalgebra's symmetric eigenvalues.
#[test]
fn stability_limit_is_a_tight_upper_bound() {
    for support in SUPPORTS {
        let b = beam(support, 20, 0.5);
        let k = b.stiffness_matrix();
        let s: Vec<f64> = b.lumped_masses().iter().map(|m| 1.0 / m.sqrt()).collect();
        let a = DMatrix::from_fn(k.nrows(), k.ncols(), |i, j| s[i] * k[(i, j)] * s[j]);
        let lmax = a.symmetric_eigenvalues().max();
        let bound = b.max_eigenvalue_bound();
        assert!(bound >= lmax, "{support:?}: {bound} < {lmax}");
        assert!(bound < 1.05 * lmax, "{support:?}: {bound} vs {lmax}");
        // just below the limit runs, above it is refused
        let h = b.stability_limit();
        assert!(b.simulate(0.999 * h, 10).is_ok());
        assert!(matches!(
            b.simulate(1.001 * h, 10),
            Err(EulerBernoulliError::Unstable { .. })
        ));
    }
}

/// Reference: a step load on a linear undamped system at rest gives z(t) = z_s − Σ cⱼ cos(ωⱼ t)
/// about the static solution z_s, so the long-time average of the response is z_s (the discrete
/// static solution; its distance from eq. 2.4.5-2.4.7 is the O(d²) of test (b)). Averaging over
/// T ≈ 60 fundamental periods leaves a bias ≲ 1/(ω₁ T) ≈ 0.3 %.
#[test]
fn time_average_equals_static_solution() {
    let n = 10;
    let mu = 1.0;
    let d = L / n as f64;
    for support in SUPPORTS {
        let b = beam(support, n, mu * d);
        let node = load_node(support, n);
        let zs = b.static_solution()[node];
        let h = 0.5 * b.stability_limit();
        // fundamental period from the cantilever's β₁L (the longest of the three)
        let omega1 = 1.875_f64.powi(2) * (EI / (mu * L.powi(4))).sqrt();
        let steps = (60.0 * 2.0 * std::f64::consts::PI / omega1 / h) as usize;
        let traj = b.simulate(h, steps).unwrap();
        assert_eq!(traj.len(), steps + 1);
        assert!(traj[0].iter().all(|z| z.abs() < 1e-300));
        let avg = traj.iter().map(|z| z[node]).sum::<f64>() / traj.len() as f64;
        let min = traj.iter().map(|z| z[node]).fold(f64::INFINITY, f64::min);
        println!(
            "{support:?}: steps {steps}, h {h:.3e}, average {avg:.6e}, static {zs:.6e}, rel {:.2e}, \
             min {min:.4e}",
            rel(avg, zs)
        );
        assert!(rel(avg, zs) < 0.02, "{support:?}: {avg} vs {zs}");
        // it does oscillate: a step load overshoots to about twice the static deflection
        assert!(min < 1.7 * zs, "{support:?}: min {min} vs static {zs}");
        // and the fixed nodes stay put
        assert!(traj.iter().all(|z| z[0].abs() < 1e-300));
    }
}

/// Max |E_k − E_0| over a run of the energy of [`EulerBernoulli::energy`].
fn energy_drift(b: &EulerBernoulli, h: f64, t_end: f64) -> f64 {
    let steps = (t_end / h).round() as usize;
    let tr = b.simulate_states(h, steps).unwrap();
    let e0 = b.energy(&tr.z[0], &tr.v[0]).unwrap();
    tr.z.iter()
        .zip(&tr.v)
        .map(|(z, v)| (b.energy(z, v).unwrap() - e0).abs())
        .fold(0.0, f64::max)
}

/// Reference: Störmer–Verlet is symplectic and of order 2, so the energy error is O(h²) and bounded
/// (no drift); for a linear system it conserves exactly the modified energy
/// ½ vᵀMv + ½ xᵀK x − (h²/8) xᵀK M⁻¹K x with x = z − z_s (per mode: v² + ω²(1 − h²ω²/4) x²).
#[test]
fn energy_conserved_to_second_order() {
    let n = 10;
    let d = L / n as f64;
    for support in SUPPORTS {
        let b = beam(support, n, d);
        let h0 = 0.2 * b.stability_limit();
        let t_end = 50.0;
        let e1 = energy_drift(&b, h0, t_end);
        let e2 = energy_drift(&b, h0 / 2.0, t_end);
        let e4 = energy_drift(&b, h0 / 4.0, t_end);
        let (p1, p2) = ((e1 / e2).log2(), (e2 / e4).log2());
        // the energy scale: the work of the load at the static deflection
        let scale = b
            .load_vector()
            .iter()
            .zip(&b.static_solution()[b.free_nodes()])
            .map(|(f, z)| (f * z).abs())
            .sum::<f64>();
        println!(
            "{support:?}: drift {e1:.3e} {e2:.3e} {e4:.3e} (scale {scale:.3e}), \
             orders {p1:.3} {p2:.3}"
        );
        assert!(
            (p1 - 2.0).abs() < 0.15 && (p2 - 2.0).abs() < 0.15,
            "{support:?}: {p1} {p2}"
        );
        assert!(e1 < 0.05 * scale);

        // modified energy: conserved to round-off
        let steps = (t_end / h0).round() as usize;
        let tr = b.simulate_states(h0, steps).unwrap();
        let zs = b.static_solution();
        let k = b.stiffness_matrix();
        let m = b.lumped_masses();
        let free: Vec<usize> = b.free_nodes().collect();
        let modified = |z: &[f64], v: &[f64]| {
            let x =
                nalgebra::DVector::from_iterator(free.len(), free.iter().map(|&i| z[i] - zs[i]));
            let kx = &k * &x;
            let kin: f64 = free
                .iter()
                .enumerate()
                .map(|(j, &i)| 0.5 * m[j] * v[i] * v[i])
                .sum();
            let corr: f64 = (0..free.len()).map(|j| kx[j] * kx[j] / m[j]).sum();
            kin + 0.5 * x.dot(&kx) - h0 * h0 / 8.0 * corr
        };
        let m0 = modified(&tr.z[0], &tr.v[0]);
        let dev =
            tr.z.iter()
                .zip(&tr.v)
                .map(|(z, v)| (modified(z, v) - m0).abs())
                .fold(0.0, f64::max);
        assert!(
            dev < 1e-10 * m0.abs(),
            "{support:?}: modified energy deviates {dev:e} of {m0:e}"
        );
    }
}

// ---------------------------------------------------------------------------------------------
// (d) bad inputs
// ---------------------------------------------------------------------------------------------

fn arg_name(r: Result<EulerBernoulli, EulerBernoulliError>) -> &'static str {
    match r {
        Err(e) => e.argument(),
        Ok(b) => panic!("expected an EulerBernoulliError, got {b:?}"),
    }
}

/// Reference: the API contract (docs/scene-format.md, "never a panic"): bad arguments are typed errors naming
/// the argument.
#[test]
fn bad_inputs_are_errors() {
    use EbSupport::*;
    let ok = EulerBernoulli::new(10, L, EI, 1.0, Cantilever, &[(10, F)]);
    assert!(ok.is_ok());
    assert_eq!(
        arg_name(EulerBernoulli::new(0, L, EI, 1.0, Cantilever, &[])),
        "n_segments"
    );
    assert_eq!(
        arg_name(EulerBernoulli::new(1, L, EI, 1.0, FixedFixed, &[])),
        "n_segments"
    );
    assert_eq!(
        arg_name(EulerBernoulli::new(usize::MAX, L, EI, 1.0, FixedFixed, &[])),
        "n_segments"
    );
    assert_eq!(
        arg_name(EulerBernoulli::new(
            10,
            L,
            EI,
            1.0,
            Cantilever,
            &[(5, 1e308), (5, 1e308)]
        )),
        "loads"
    );
    for bad in [0.0, -1.0, f64::NAN, f64::INFINITY] {
        assert_eq!(
            arg_name(EulerBernoulli::new(10, bad, EI, 1.0, Cantilever, &[])),
            "length"
        );
        assert_eq!(
            arg_name(EulerBernoulli::new(10, L, bad, 1.0, Cantilever, &[])),
            "ei"
        );
        assert_eq!(
            arg_name(EulerBernoulli::new(10, L, EI, bad, Cantilever, &[])),
            "mass_per_node"
        );
    }
    // EI/d³ overflows
    assert_eq!(
        arg_name(EulerBernoulli::new(10, 1e-300, EI, 1.0, Cantilever, &[])),
        "ei"
    );
    // load nodes: out of range, on a support, non-finite force
    assert_eq!(
        arg_name(EulerBernoulli::new(10, L, EI, 1.0, Cantilever, &[(11, F)])),
        "loads"
    );
    assert_eq!(
        arg_name(EulerBernoulli::new(10, L, EI, 1.0, Cantilever, &[(0, F)])),
        "loads"
    );
    assert_eq!(
        arg_name(EulerBernoulli::new(10, L, EI, 1.0, FixedFixed, &[(10, F)])),
        "loads"
    );
    assert_eq!(
        arg_name(EulerBernoulli::new(10, L, EI, 1.0, PinnedPinned, &[(0, F)])),
        "loads"
    );
    assert_eq!(
        arg_name(EulerBernoulli::new(
            10,
            L,
            EI,
            1.0,
            Cantilever,
            &[(usize::MAX, F)]
        )),
        "loads"
    );
    assert_eq!(
        arg_name(EulerBernoulli::new(
            10,
            L,
            EI,
            1.0,
            Cantilever,
            &[(5, f64::NAN)]
        )),
        "loads"
    );

    // simulate: bad steps h
    let b = ok.unwrap();
    for h in [0.0, -0.01, f64::NAN, f64::INFINITY] {
        assert!(
            matches!(
                b.simulate(h, 5),
                Err(EulerBernoulliError::NotPositive { name: "h", .. })
            ),
            "{h}"
        );
    }
    assert!(matches!(
        b.simulate(1.0, 5),
        Err(EulerBernoulliError::Unstable { h: 1.0, .. })
    ));
    assert!(matches!(
        b.simulate(0.5 * b.stability_limit(), usize::MAX),
        Err(EulerBernoulliError::StepsOverflow { .. })
    ));
    // energy: wrong lengths
    assert!(matches!(
        b.energy(&[0.0; 3], &[0.0; 11]),
        Err(EulerBernoulliError::WrongNodeCount { name: "z", .. })
    ));
    assert!(matches!(
        b.energy(&[0.0; 11], &[0.0; 12]),
        Err(EulerBernoulliError::WrongNodeCount { name: "v", .. })
    ));
    // the smallest grid is accepted and solvable for every support
    for s in SUPPORTS {
        let b = EulerBernoulli::new(2, L, EI, 1.0, s, &[(1, F)]).unwrap();
        assert!(b.static_solution().iter().all(|z| z.is_finite()));
    }
}

/// Reference: linearity and superposition of eq. 2.1.4; the thesis sign (positive F toward −z) and
/// loads at the same node adding up.
#[test]
fn loads_superpose_with_thesis_sign() {
    let one = EulerBernoulli::new(20, L, EI, 1.0, EbSupport::Cantilever, &[(20, 2.0)]).unwrap();
    let split = EulerBernoulli::new(
        20,
        L,
        EI,
        1.0,
        EbSupport::Cantilever,
        &[(20, 0.5), (20, 1.5)],
    )
    .unwrap();
    assert_eq!(one.load_vector(), split.load_vector());
    assert!(one.load_vector()[19] < 0.0);
    let z = one.static_solution();
    assert!(z[1..].iter().all(|&zi| zi < 0.0));
}
