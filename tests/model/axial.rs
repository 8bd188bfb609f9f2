//! Axial loads (`[loads] tension`, `axial_weight`; docs/ocean.md "From a pipe to a chain"): the lateral stiffening of a
//! tensioned beam comes from the chain's length constraints alone. Checked against closed forms:
//! the natural frequencies of a tensioned pinned-pinned beam-column, the static deflection of a
//! tensioned pinned beam under a uniform lateral load, the deflection of a string whose tension
//! varies with the axial weight; adjoint gradients with respect to T and w in tests/steppers/verification.rs
//! and every derivative of both terms in tests/model/terms.rs.

use chainbeam::statics::static_equilibrium;
use chainbeam::{simulate, Chain, Scene, Support};
use nalgebra::DMatrix;
use num_dual::{DualNum, HyperDual64};
use std::f64::consts::PI;

const L: f64 = 10.0;
const EI: f64 = 100.0;
const MU: f64 = 1.0;

fn pinned(n: usize, ei: f64, tension: f64, weight: f64) -> Scene {
    let l = L / n as f64;
    Scene::builder(n)
        .length(l)
        .mass(MU * l)
        .stiffness(ei / l)
        .support(Support::PinnedPinned)
        .tension(tension)
        .axial_weight(weight)
        .step(1e-3)
        .steps(10)
        .build()
        .unwrap()
}

/// The Hessian ∂²U/∂θ_a∂θ_b of the chain's potential energy at the straight beam, in the
/// pendulum angles θ (qⱼ = (cos θⱼ, sin θⱼ) in (y, z)), by hyper-dual numbers through the
/// chain's own terms.
fn angle_hessian(scene: &Scene) -> DMatrix<f64> {
    let chain = Chain::<f64, 2>::from_scene(scene)
        .unwrap()
        .lift::<HyperDual64>();
    let n = chain.n();
    DMatrix::from_fn(n, n, |a, b| {
        let q: Vec<[HyperDual64; 2]> = (0..n)
            .map(|j| {
                let th = HyperDual64::new(
                    0.0,
                    if j == a { 1.0 } else { 0.0 },
                    if j == b { 1.0 } else { 0.0 },
                    0.0,
                );
                [th.cos(), th.sin()]
            })
            .collect();
        chain
            .potential_energy(&q, 0.0, HyperDual64::from(0.0))
            .eps1eps2
    })
}

/// Natural frequencies of the chain linearised about the straight beam with its tip z locked
/// (Σ lⱼ θⱼ = 0): K φ = ω² M φ in the angles of pendulums 1..n−1 (θₙ eliminated), with
/// M = Lᵀ diag(m) L, zᵢ = Σ_{j≤i} lⱼ θⱼ.
fn pinned_frequencies(scene: &Scene) -> Vec<f64> {
    let n = scene.n();
    let l = &scene.beam.lengths;
    let k = angle_hessian(scene);
    assert!(k.iter().all(|x| x.is_finite()));
    let lz = DMatrix::from_fn(n, n, |i, j| if j <= i { l[j] } else { 0.0 });
    let m = lz.transpose() * DMatrix::from_diagonal(&scene.beam.masses.clone().into()) * &lz;
    let b = DMatrix::from_fn(n, n - 1, |i, j| {
        if i < n - 1 {
            if i == j {
                1.0
            } else {
                0.0
            }
        } else {
            -l[j] / l[n - 1]
        }
    });
    let (kr, mr) = (b.transpose() * k * &b, b.transpose() * m * &b);
    let c = mr.cholesky().unwrap();
    let ci = c.l().try_inverse().unwrap();
    let a = &ci * kr * ci.transpose();
    let mut w: Vec<f64> = a.symmetric_eigenvalues().iter().map(|x| x.sqrt()).collect();
    w.sort_by(f64::total_cmp);
    w
}

/// Reference: a pinned-pinned Euler-Bernoulli beam-column under axial tension T has
/// ω_j = (jπ/L)² √(EI/μ) √(1 + T L²/(j²π² EI)) (e.g. Blevins, *Formulas for Natural Frequency
/// and Mode Shape*, Table 8-16). At n = 40, modes 1–3, within 1 %, for T from 0 to
/// a tension-dominated T L²/(π² EI) ≈ 41; and a compression below the Euler load π²EI/L² ≈ 9.87 N (T = −5 N) lowers it as the
/// same formula says.
#[test]
fn tensioned_pinned_beam_column_frequencies() {
    let n = 40;
    for tension in [0.0, 30.0, 400.0, -5.0] {
        let w = pinned_frequencies(&pinned(n, EI, tension, 0.0));
        for j in 1..=3 {
            let jp = j as f64 * PI / L;
            let exact = jp * jp * (EI / MU).sqrt() * (1.0 + tension / (jp * jp * EI)).sqrt();
            let err = w[j - 1] / exact - 1.0;
            println!(
                "T = {tension} N, mode {j}: chain {:.6} rad/s, closed form {exact:.6}, {:+.3} %",
                w[j - 1],
                100.0 * err
            );
            assert!(err.abs() < 0.01, "T {tension} mode {j}: {err}");
        }
    }
}

/// Reference: EI z⁗ − T z″ = q on a pinned beam (z = z″ = 0 at both ends), with α² = T/EI:
/// z(y) = q/(T α²) [cosh(α(y − L/2))/cosh(αL/2) − 1] + q y (L − y)/(2T) (the hyperbolic closed
/// form; it tends to q y(L − y)/(2T) for a string and to the beam's 5qL⁴/(384EI) at mid-span as
/// T → 0). Lumped loads q l on the interior nodes (thesis sign: q > 0 pushes toward −z); the
/// deflection is 10⁻⁴ L, so the chain's geometric non-linearity is below 10⁻⁸.
#[test]
fn tensioned_beam_under_uniform_load_matches_the_hyperbolic_closed_form() {
    let (q, n) = (0.01, 40);
    for tension in [20.0, 100.0, 1000.0] {
        let l = L / n as f64;
        let mut scene = pinned(n, EI, tension, 0.0);
        for i in 1..n {
            scene.loads.points.push(chainbeam::PointLoad::new(i, q * l));
        }
        let sol = static_equilibrium(&scene).unwrap();
        let alpha = (tension / EI).sqrt();
        let exact = |y: f64| {
            q / (tension * alpha * alpha)
                * ((alpha * (y - L / 2.0)).cosh() / (alpha * L / 2.0).cosh() - 1.0)
                + q * y * (L - y) / (2.0 * tension)
        };
        let peak = exact(L / 2.0);
        let worst = sol
            .positions
            .iter()
            .map(|&[y, z]| (-z - exact(y)).abs())
            .fold(0.0, f64::max);
        println!(
            "T = {tension} N: mid-span {peak:.6e} m, worst |chain − closed form| / peak = {:.2e}",
            worst / peak
        );
        assert!(worst < 2e-3 * peak, "T {tension}: {worst} vs {peak}");
    }
}

/// Reference: a taut string (EI = 0) under a uniform lateral load q with the effective tension
/// of a riser, T_e(y) = T − w (L − y) (top tension T, axial weight w): −(T_e z′)′ = q with
/// z(0) = z(L) = 0 integrates to z(y) = (qL/w) ln(1 + w y/a)/ln(T/a) − q y/w, a = T − wL. The
/// chain gets T_e only through the two axial terms and the length constraints, so this checks
/// the tension's sign, the axial weight's sign and its lumping (half a cell at the tip).
#[test]
fn string_with_axial_weight_matches_its_closed_form() {
    let (q, n, tension, w) = (0.01, 80, 100.0, 6.0);
    let l = L / n as f64;
    let mut scene = pinned(n, 0.0, tension, w);
    for i in 1..n {
        scene.loads.points.push(chainbeam::PointLoad::new(i, q * l));
    }
    let sol = static_equilibrium(&scene).unwrap();
    let a = tension - w * L;
    let exact = |y: f64| (q * L / w) * (1.0 + w * y / a).ln() / (tension / a).ln() - q * y / w;
    let peak = (0..=100)
        .map(|i| exact(L * i as f64 / 100.0))
        .fold(0.0, f64::max);
    let worst = sol
        .positions
        .iter()
        .map(|&[y, z]| (-z - exact(y)).abs())
        .fold(0.0, f64::max);
    // The uniform-tension string q y(L − y)/(2 T_mid) differs by several per cent: the test sees w.
    let uniform = |y: f64| q * y * (L - y) / (2.0 * (tension - w * L / 2.0));
    let off = (0..=100)
        .map(|i| (uniform(L * i as f64 / 100.0) - exact(L * i as f64 / 100.0)).abs())
        .fold(0.0, f64::max);
    println!("peak {peak:.6e} m, worst |chain − closed form| / peak = {:.2e}, uniform-tension string off by {:.2e}", worst / peak, off / peak);
    assert!(off > 0.02 * peak);
    assert!(worst < 2e-3 * peak, "{worst} vs {peak}");
}

/// With `tension = 0` and `axial_weight = 0` no term is built: the trajectory is the one of the
/// scene without the keys, bit for bit (and the whole suite's numbers are unchanged).
#[test]
fn zero_axial_loads_change_nothing() {
    let base = chainbeam::catalogue::riser(5);
    let mut with = base.clone();
    with.loads.tension = 0.0;
    with.loads.axial_weight = 0.0;
    let (a, b) = (simulate(&base).unwrap(), simulate(&with).unwrap());
    let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
    assert_eq!(bits(a.moment()), bits(b.moment()));
    assert!(!Chain::<f64, 2>::from_scene(&with)
        .unwrap()
        .has_parameter(chainbeam::Parameter::Tension));
}

/// Bad values are rejected with the key named.
#[test]
fn bad_axial_loads_name_their_key() {
    for (t, w, key) in [
        (f64::NAN, 0.0, "loads.tension"),
        (0.0, 1e13, "loads.axial_weight"),
    ] {
        let mut s = pinned(4, EI, 0.0, 0.0);
        s.loads.tension = t;
        s.loads.axial_weight = w;
        let e = s.validate().unwrap_err();
        assert!(e.to_string().contains(key), "{e}");
    }
}
