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
use nalgebra::DMatrix;
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
