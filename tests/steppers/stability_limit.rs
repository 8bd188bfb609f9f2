//! RATTLE's explicit stability limit on the riser system's stack-up
//! (examples/scenes/riser_300m_system.toml, 60 pendulums, the conductor's top in 3 m pendulums).
//!
//! RATTLE is Störmer–Verlet with constraints: on a linear mode of angular frequency ω its step
//! has the eigenvalues λ = e^{±iθ} with cos θ = 1 − (hω)²/2 while hω < 2, and a real pair with
//! |λ| > 1 beyond (the explicit method's stability limit; e.g. E. Hairer, C. Lubich, G. Wanner,
//! "Geometric Numerical Integration", 2nd ed., Springer 2006, I.5 and XIII). So the exact
//! Jacobian of one step of the chain linearised at rest (one dual-number step per direction, in
//! the angles φ and rates ω of the pendulums) tells both: its spectral radius (≤ 1 when every
//! mode is resolved, > 1 when one is past the limit), and from its largest eigen-angle θ the
//! stiffest mode's frequency ω_max = 2 sin(θ/2)/h, to compare with 2/h.
//!
//! The scene runs at h = 0.004 s; at h = 0.005 s its Newton solve fails at step 68 (t = 0.34 s,
//! docs/riser-system.md "Speed"): this test checks that the failure is the stability limit of
//! the stiffest joint mode, not Newton's.

use chainbeam::statics::static_equilibrium_at;
use chainbeam::{Chain, Rattle, Scene, State};
use nalgebra::{Complex, DMatrix, DVector};
use num_dual::{Dual64, DualNum};

/// The exact Jacobian (2n × 2n, in (φ, ω)) of RATTLE's step k → k + 1 with step `h` and control
/// 0 from the angles `phi` at rest.
fn step_jacobian(chain: &Chain<f64, 2>, h: f64, k: usize, phi: &[f64]) -> DMatrix<f64> {
    let n = phi.len();
    let dual = chain.lift::<Dual64>();
    let lengths: Vec<Dual64> = dual.lengths().to_vec();
    let mut stepper = Rattle::new(dual.clone(), h).unwrap();
    let mut a = DMatrix::zeros(2 * n, 2 * n);
    let zero = Dual64::from(0.0);
    let mut qdot = vec![[zero; 2]; n];
    for dir in 0..2 * n {
        let mut state = State::<Dual64, 2>::straight(n);
        let (mut z, mut zd) = (zero, zero);
        for j in 0..n {
            let p = Dual64::new(phi[j], if dir == j { 1.0 } else { 0.0 });
            let w = Dual64::new(0.0, if dir == n + j { 1.0 } else { 0.0 });
            let (s, c) = (p.sin(), p.cos());
            state.q[j] = [c, s];
            qdot[j] = [-w * s, w * c];
            z += lengths[j] * s;
            zd += lengths[j] * c * w;
        }
        dual.apply_mass(&qdot, &mut state.p);
        state.tip_target = [z, zd];
        stepper.prepare(&mut state, k, zero).unwrap();
        stepper.step(&mut state, k, zero, zero).unwrap();
        dual.apply_inverse_mass(&state.p, &mut qdot);
        for j in 0..n {
            let (q, v) = (state.q[j], qdot[j]);
            a[(j, dir)] = q[1].atan2(q[0]).eps;
            a[(n + j, dir)] = (q[0] * v[1] - q[1] * v[0]).eps;
        }
    }
    a
}

/// (spectral radius, ω_max = 2 sin(θ_max/2)/h over the eigenvalues near the unit circle: the
/// drag at rest damps a mode slightly, |λ| < 1; the constraint's directions have λ ≈ 0).
fn spectrum(a: &DMatrix<f64>, h: f64) -> (f64, f64) {
    let eig = a.complex_eigenvalues();
    let radius = eig.iter().map(|l| l.norm()).fold(0.0, f64::max);
    let theta = eig
        .iter()
        .filter(|l| l.norm() > 0.5)
        .map(|l| l.arg().abs())
        .fold(0.0, f64::max);
    (radius, 2.0 * (0.5 * theta).sin() / h)
}

/// At the calm sea's equilibrium (waves off, the current and the vessel's mean offset on): at
/// the file's h = 0.004 s every mode is inside the limit (spectral radius ≤ 1), at 0.005 s one is
/// past it (radius > 1, a real eigenvalue below −1), and the stiffest mode's ω_max, read from the
/// eigen-angles at 0.004 s, lies between the two steps' limits 2/0.005 = 400 and 2/0.004 = 500
/// rad/s. (Measured when written: radii 0.999997 and 1.241, ω_max = 402.3 rad/s, so
/// ω_max h = 1.61 and 2.01: the failure at 0.005 s is a mode just past the limit.)
#[test]
fn riser_system_step_is_set_by_the_stiffest_joint_mode() {
    let mut scene = Scene::from_file(crate::common::scene("riser_300m_system.toml")).unwrap();
    scene.loads.waves = None;
    let ramp = scene.vessel.as_ref().map_or(0.0, |v| v.ramp.max(0.0));
    let mut radii = Vec::new();
    let mut omegas = Vec::new();
    for h in [0.004, 0.005] {
        scene.time.step = h;
        let k_eq = ((ramp + 10.0) / h).ceil() as usize;
        scene.time.steps = k_eq + 2;
        let eq = static_equilibrium_at(&scene, k_eq as f64 * h, 0.0).unwrap();
        let chain = Chain::<f64, 2>::from_scene(&scene).unwrap();
        let a = step_jacobian(&chain, h, k_eq, &eq.angles);
        let (radius, omega) = spectrum(&a, h);
        eprintln!("h = {h}: spectral radius {radius:.6}, omega_max (unit circle) {omega:.1} rad/s, 2/h = {:.0}", 2.0 / h);
        radii.push(radius);
        omegas.push(omega);
    }
    assert!(radii[0] <= 1.0 + 1e-9, "h = 0.004 s unstable: {}", radii[0]);
    assert!(radii[1] > 1.0 + 1e-3, "h = 0.005 s stable: {}", radii[1]);
    assert!(
        omegas[0] > 2.0 / 0.005 && omegas[0] < 2.0 / 0.004,
        "omega_max = {} rad/s",
        omegas[0]
    );
}

/// The file's scene at rest in the calm sea at step `h`: (its chain, the step index of the
/// equilibrium, the equilibrium's angles), as in the test above.
fn at_rest(text: &str, h: f64) -> (Chain<f64, 2>, usize, Vec<f64>) {
    let mut scene = Scene::from_toml_str(text).unwrap();
    scene.loads.waves = None;
    let ramp = scene.vessel.as_ref().map_or(0.0, |v| v.ramp.max(0.0));
    scene.time.step = h;
    let k_eq = ((ramp + 10.0) / h).ceil() as usize;
    scene.time.steps = k_eq + 2;
    let eq = static_equilibrium_at(&scene, k_eq as f64 * h, 0.0).unwrap();
    (
        Chain::<f64, 2>::from_scene(&scene).unwrap(),
        k_eq,
        eq.angles,
    )
}

/// The eigenvalue of `a` with the largest angle among those near the unit circle (the stiffest
/// resolved mode) and its eigenvector by inverse iteration (shift λ(1 + 10⁻⁹), five solves).
fn stiffest_mode(a: &DMatrix<f64>) -> (Complex<f64>, DVector<Complex<f64>>) {
    let eig = a.complex_eigenvalues();
    let lambda = eig
        .iter()
        .filter(|l| l.norm() > 0.5)
        .copied()
        .max_by(|x, y| x.arg().abs().total_cmp(&y.arg().abs()))
        .unwrap();
    let m = a.nrows();
    let mut b: DMatrix<Complex<f64>> = a.map(|x| Complex::new(x, 0.0));
    let shift = lambda * (1.0 + 1e-9);
    for i in 0..m {
        b[(i, i)] -= shift;
    }
    let lu = b.lu();
    let mut x = DVector::from_element(m, Complex::new(1.0, 0.0));
    for _ in 0..5 {
        x = lu.solve(&x).unwrap();
        let norm = x.norm();
        x.unscale_mut(norm);
    }
    (lambda, x)
}

/// Which joint mode sets ω_max, and whether the soil's springs do: the stiffest mode's
/// eigenvector (of the step's Jacobian at h = 0.004 s, as above) in the pendulums' angles, and
/// ω_max again with the soil's p-y springs nearly off (modulus 10⁻³ N/m², no gradient) and with
/// the conductor's top 15 m in four 3.75 m pendulums instead of five 3 m ones (its segment's
/// `refinement` 0.8; the layout a coarser conductor would take).
///
/// Expected from the stack-up (riser_300m_system.toml): the conductor (36 in × 1.5 in,
/// EI ≈ 2.1e9 N m², ≈ 2 300 kg/m with contents and added mass) in 3 m pendulums has the highest
/// √(EI/μ)/l² of the chain; the riser's 3.048 m pendulums (EI ≈ 2.4e8 N m²) are about 3× softer.
/// The soil's lateral stiffness over a 3 m pendulum near the mudline, E_s l ≈ (3.35e5 + 1e5 ·
/// 5) · 3 ≈ 2.5e6 N/m, is some 30× below a 3 m conductor joint's bending stiffness EI/l³ ≈ 7.7e7
/// N/m, so the soil should move ω_max by a few per cent at most; and ω_max ∝ 1/l² puts the
/// 3.75 m layout near 0.64 × the file's, if the conductor's pendulums set it.
///
/// Measured when written: the stiffest mode (λ = −0.295 − 0.955i, ω_max = 402.3 rad/s) bends the
/// conductor's 3 m pendulums from 48 m up to the mudline at 60 m (|Δφ| 0.72–1.00 of the
/// largest), the lowest one (45–48 m) at 0.33 and the wellhead's 3 m pendulum at 0.35; without the soil
/// ω_max = 401.9 rad/s (−0.11 %); with 3.75 m conductor pendulums 274.2 rad/s (0.682 × the
/// file's, 2/ω_max = 0.0073 s).
#[test]
fn the_stiffest_mode_is_the_conductors_bending_below_the_mudline() {
    let text = std::fs::read_to_string(crate::common::scene("riser_300m_system.toml")).unwrap();
    let h = 0.004;
    let (chain, k_eq, phi) = at_rest(&text, h);
    let n = chain.n();
    let a = step_jacobian(&chain, h, k_eq, &phi);
    let (_, omega_file) = spectrum(&a, h);
    let (lambda, x) = stiffest_mode(&a);
    // The inverse iteration converged: ‖A x − λ x‖ small against ‖x‖ = 1.
    let ax = a.map(|v| Complex::new(v, 0.0)) * &x;
    let residual = (ax - x.map(|v| v * lambda)).norm();
    assert!(residual < 1e-8, "eigenvector residual {residual:e}");
    // Elevation of each pendulum's lower and upper node above the conductor's foot.
    let mut bottom = 0.0;
    let mut ranges = Vec::new();
    for l in chain.lengths() {
        ranges.push((bottom, bottom + l));
        bottom += l;
    }
    let mut amp: Vec<(usize, f64)> = (0..n).map(|j| (j, x[j].norm())).collect();
    amp.sort_by(|p, q| q.1.total_cmp(&p.1));
    let top = amp[0].1;
    for &(j, v) in amp.iter().take(6) {
        eprintln!(
            "pendulum {j} ({:.3}-{:.3} m): |dphi| {:.3} of the largest",
            ranges[j].0,
            ranges[j].1,
            v / top
        );
    }
    eprintln!(
        "stiffest mode: lambda = {lambda}, omega_max = {omega_file:.1} rad/s (2 sin(theta/2)/h = {:.1})",
        2.0 * (0.5 * lambda.arg().abs()).sin() / h
    );
    // The pendulums carrying half or more of the largest angle amplitude.
    let carrying: Vec<(f64, f64)> = amp
        .iter()
        .filter(|(_, v)| *v >= 0.5 * top)
        .map(|&(j, _)| ranges[j])
        .collect();
    let mudline = 60.0;
    assert!(
        carrying.iter().all(|&(lo, hi)| lo >= 45.0 - 1e-9 && hi <= mudline + 3.0 + 1e-9),
        "the stiffest mode's largest angles outside the conductor's top and the wellhead: {carrying:?}"
    );

    let soft = text
        .replace("modulus = 3.35e5", "modulus = 1e-3")
        .replace("gradient = 1.0e5", "gradient = 0.0");
    assert_ne!(soft, text);
    let (chain, k_eq, phi) = at_rest(&soft, h);
    let (_, omega_soft) = spectrum(&step_jacobian(&chain, h, k_eq, &phi), h);

    let coarse = text.replacen(
        "name = \"conductor_top\"",
        "name = \"conductor_top\"\nrefinement = 0.8",
        1,
    );
    assert_ne!(coarse, text);
    let (chain, k_eq, phi) = at_rest(&coarse, h);
    // The lengths of the pendulums whose top lies in the conductor's top 15 m.
    let mut upper = 0.0;
    let mut short = Vec::new();
    for l in chain.lengths() {
        upper += l;
        if upper > 45.0 + 1e-9 && upper <= mudline + 1e-9 {
            short.push(*l);
        }
    }
    let (_, omega_coarse) = spectrum(&step_jacobian(&chain, h, k_eq, &phi), h);
    eprintln!(
        "omega_max: file {omega_file:.1}, soil off {omega_soft:.1} ({:+.2} %), conductor top in {short:?} m pendulums {omega_coarse:.1} rad/s ({:.3} of the file's)",
        100.0 * (omega_soft / omega_file - 1.0),
        omega_coarse / omega_file
    );
    assert!(short.iter().all(|l| (l - 3.75).abs() < 1e-9), "{short:?}");
    assert!(
        (omega_soft / omega_file - 1.0).abs() < 0.05,
        "the soil moves omega_max by more than 5 %: {omega_soft} against {omega_file}"
    );
    assert!(
        omega_coarse < 0.8 * omega_file,
        "longer conductor pendulums do not lower omega_max: {omega_coarse} against {omega_file}"
    );
}
