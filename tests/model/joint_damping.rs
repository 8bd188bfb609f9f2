//! Structural (joint) damping (docs/conventions.md "Joint damping"): the torque
//! −c_j θ̇_j at every joint.
//!
//! Reference: the closed form of stiffness-proportional (Rayleigh) damping. The springs' energy
//! is ½ Σ k_j θ_j², so small planar motion about the straight beam has the stiffness matrix
//! K = Δᵀ diag(k) Δ in the pendulum angles φ (θ_j = φ_j − φ_{j−1}) and the mass matrix M̄ of the
//! chain (docs/conventions.md); dampers c_j = α k_j give the damping matrix C = α K, which the
//! modes of K φ = ω² M̄ φ diagonalise, and mode j decays with ζ_j = α ω_j / 2. A free decay
//! started in mode 1 (shape and ω₁ from that generalised eigenproblem, solved with nalgebra) is
//! integrated by RATTLE and ζ measured from its logarithmic decrement.

use chainbeam::steppers::rattle::State;
use chainbeam::steppers::{ProjectedRk4, Rattle, Shake, Stepper};
use chainbeam::*;
use nalgebra::{DMatrix, SymmetricEigen};

/// A cantilever of n = 20 pendulums, l = 0.5 m, m = 1 kg, k = 1000 N·m/rad, base spring 2000.
fn cantilever() -> Scene {
    SceneBuilder::new(20)
        .support(Support::Cantilever)
        .length(0.5)
        .mass(1.0)
        .stiffness(1000.0)
        .base_stiffness(2000.0)
        .step(0.01)
        .steps(10)
        .build()
        .unwrap()
}

/// The linearised chain's matrices in the angles φ: M̄_ij = l_i l_j Σ_{k ≥ max(i,j)} m_k and
/// K = Δᵀ diag(k₁..k_{n+1}) Δ (φ₋₁ = 0 at the base; the model's springs, zero where absent).
fn linearised(chain: &Chain<f64, 2>) -> (DMatrix<f64>, DMatrix<f64>) {
    let n = chain.n();
    let (l, m, k) = (chain.lengths(), chain.masses(), chain.springs());
    let mbar = DMatrix::from_fn(n, n, |i, j| l[i] * l[j] * m[i.max(j)..].iter().sum::<f64>());
    let mut kk = DMatrix::zeros(n, n);
    for (j, &kj) in k.iter().enumerate() {
        // joint j couples φ_{j−1} (if j > 0) and φ_j (if j < n)
        let idx: Vec<(usize, f64)> = [(j.wrapping_sub(1), -1.0), (j, 1.0)]
            .into_iter()
            .filter(|(i, _)| *i < n)
            .collect();
        for &(a, sa) in &idx {
            for &(b, sb) in &idx {
                kk[(a, b)] += kj * sa * sb;
            }
        }
    }
    (mbar, kk)
}

/// The generalised eigenproblem K φ = ω² M̄ φ: (ω ascending, mode shapes as columns).
fn modes(mbar: &DMatrix<f64>, kk: &DMatrix<f64>) -> (Vec<f64>, DMatrix<f64>) {
    let l = mbar.clone().cholesky().unwrap().l();
    let linv = l.clone().try_inverse().unwrap();
    let s = &linv * kk * linv.transpose();
    let s = (&s + s.transpose()) * 0.5;
    let dim = s.nrows();
    let eig = SymmetricEigen::new(s);
    let mut order: Vec<usize> = (0..eig.eigenvalues.len()).collect();
    order.sort_by(|&a, &b| eig.eigenvalues[a].total_cmp(&eig.eigenvalues[b]));
    let omegas = order.iter().map(|&i| eig.eigenvalues[i].sqrt()).collect();
    let shapes = DMatrix::from_fn(dim, order.len(), |r, c| eig.eigenvectors[(r, order[c])]);
    (omegas, linv.transpose() * shapes)
}

/// With c_j/k_j = α at every spring, a free decay from mode 1's shape (tip deflection ≈ 1 mm)
/// decays with ζ₁ = α ω₁/2 within 2 % (the bound), measured by the logarithmic decrement
/// over three damped periods (peak heights refined by a parabola through the three samples
/// around each peak); the damped period 2π/(ω₁√(1 − ζ₁²)) within 1 %.
#[test]
fn rayleigh_damping_ratio_of_the_first_mode() {
    let base = cantilever();
    let chain0 = Chain::<f64, 2>::from_scene(&base).unwrap();
    let (mbar, kk) = linearised(&chain0);
    let (omegas, shapes) = modes(&mbar, &kk);
    let (w1, wmax) = (omegas[0], *omegas.last().unwrap());
    // ζ₁ = 2 %: α = 2 ζ₁ / ω₁.
    let zeta = 0.02;
    let alpha = 2.0 * zeta / w1;
    let mut scene = base.clone();
    scene.beam.joint_damping = chain0.springs().iter().map(|k| alpha * k).collect();
    // RATTLE's stiff springs: ω_max h = 1 (the explicit kick needs ω h < 2).
    let h = 1.0 / wmax;
    scene.time.step = h;
    scene.validate().unwrap();
    let chain = Chain::<f64, 2>::from_scene(&scene).unwrap();
    assert_eq!(chain.coupled_dissipation_names(), ["joint damping"]);
    let n = chain.n();
    let l = chain.lengths().to_vec();
    let shape: Vec<f64> = (0..n).map(|i| shapes[(i, 0)]).collect();
    let tip_of = |phi: &[f64]| phi.iter().zip(&l).map(|(p, l)| l * p).sum::<f64>();
    let eps = 1e-3 / tip_of(&shape);
    let mut state = State::<f64, 2>::straight(n);
    for (q, s) in state.q.iter_mut().zip(&shape) {
        *q = [(eps * s).cos(), (eps * s).sin()];
    }
    let mut r = Rattle::new(chain.clone(), h).unwrap();
    r.prepare(&mut state, 0, 0.0).unwrap();
    let period = 2.0 * std::f64::consts::PI / (w1 * (1.0 - zeta * zeta).sqrt());
    let steps = (3.3 * period / h) as usize;
    let mut z = Vec::with_capacity(steps + 1);
    z.push(chain.tip_z(&state.q));
    for k in 0..steps {
        r.step(&mut state, k, 0.0, 0.0).unwrap();
        z.push(chain.tip_z(&state.q));
    }
    // Peaks (t, z) after t = 0, refined by a parabola through three samples.
    let mut peaks = vec![(0.0, z[0])];
    for k in 1..z.len() - 1 {
        if z[k] > z[k - 1] && z[k] >= z[k + 1] && z[k] > 0.0 {
            let (a, b, c) = (z[k - 1], z[k], z[k + 1]);
            let curv = a - 2.0 * b + c;
            let off = 0.5 * (a - c) / curv;
            peaks.push(((k as f64 + off) * h, b - 0.25 * (a - c) * off));
        }
    }
    assert!(peaks.len() >= 4, "three damped periods: {peaks:?}");
    let m = 3;
    let delta = (peaks[0].1 / peaks[m].1).ln() / m as f64;
    let measured = delta / (4.0 * std::f64::consts::PI.powi(2) + delta * delta).sqrt();
    let td = (peaks[m].0 - peaks[0].0) / m as f64;
    println!(
        "n = {n}: ω₁ = {w1:.6} rad/s, ω_max = {wmax:.2}, h = {h:.3e} s, α = c/k = {alpha:.4e} s; \
         ζ₁ measured {measured:.8} vs α ω₁/2 = {zeta} (relative {:+.2e}); damped period \
         {td:.6} s vs {period:.6} s (relative {:+.2e})",
        measured / zeta - 1.0,
        td / period - 1.0
    );
    assert!(
        (measured / zeta - 1.0).abs() <= 0.02,
        "ζ₁ {measured} vs {zeta}"
    );
    assert!((td / period - 1.0).abs() <= 0.01, "T_d {td} vs {period}");
}

/// The dampers dissipate: the power −F·q̇ = Σ_j c_j |θ̇_j|² ≥ 0 of the term equals the rate the
/// energy falls at in the same decay (energy balance of the undriven chain, to the step's
/// O(h²)); and with the dampers absent the energy stays constant (RATTLE's bounded error).
#[test]
fn the_energy_falls_at_the_dissipated_power() {
    let mut scene = cantilever();
    scene.beam.joint_damping = vec![5.0; 21];
    scene.beam.joint_damping[20] = 0.0; // the free tip has no joint
    scene.validate().unwrap();
    let chain = Chain::<f64, 2>::from_scene(&scene).unwrap();
    let n = chain.n();
    let h = 2e-3;
    let mut state = State::<f64, 2>::straight(n);
    for (i, q) in state.q.iter_mut().enumerate() {
        let a = 0.02 * (i as f64 / n as f64).powi(2);
        *q = [a.cos(), a.sin()];
    }
    let mut r = Rattle::new(chain.clone(), h).unwrap();
    r.prepare(&mut state, 0, 0.0).unwrap();
    let mut scratch = vec![[0.0; 2]; n];
    let energy = |s: &State<f64, 2>, scratch: &mut Vec<[f64; 2]>| {
        chain.kinetic_energy(&s.p, scratch) + chain.potential_energy(&s.q, 0.0, 0.0)
    };
    let jd = chain.joint_damping().unwrap();
    let mut v = vec![[0.0; 2]; n];
    let mut power_at = |s: &State<f64, 2>| {
        chain.apply_inverse_mass(&s.p, &mut v);
        jd.dissipated_power(&s.q, &v)
    };
    // ∫ power dt by the trapezoidal rule over the steps.
    let mut dissipated_total = 0.0;
    let e0 = energy(&state, &mut scratch);
    let mut before = power_at(&state);
    for k in 0..400 {
        r.step(&mut state, k, 0.0, 0.0).unwrap();
        let after = power_at(&state);
        assert!(after >= 0.0);
        dissipated_total += 0.5 * (before + after) * h;
        before = after;
    }
    let lost = e0 - energy(&state, &mut scratch);
    println!("energy lost {lost:.6e} J, ∫ Σ c θ̇² dt {dissipated_total:.6e} J");
    assert!(lost > 0.0);
    assert!((lost / dissipated_total - 1.0).abs() < 0.02);
}

/// Every stepper sums the joint damping: a tip load of 2 N on the damped cantilever (c = 5 at
/// every spring), 1 s at h = 1 ms from the straight beam at rest. Reference: projected RK4 (order
/// 4, an independent method that evaluates the damping explicitly through the ODE's force);
/// RATTLE (implicit, the dense half step) and SHAKE agree with it to 2e-6 of the tip deflection
/// (measured: 3e-7 and 4e-7), while the dampers move the tip by 5e-3 of it (against the
/// undamped run; asserted ≥ 2e-3, a thousand times the tolerance).
#[test]
fn every_stepper_sees_the_dampers() {
    let with = |c: f64| {
        let mut s = cantilever();
        s.loads.points.push(chainbeam::PointLoad::new(20, 2.0));
        if c > 0.0 {
            // The builder's number form: c at every joint with a spring (not the free tip).
            let built = SceneBuilder::new(20)
                .length(0.5)
                .stiffness(1000.0)
                .base_stiffness(2000.0)
                .joint_damping(c)
                .build()
                .unwrap();
            assert_eq!(built.beam.joint_damping[..20], [c; 20]);
            assert_eq!(built.beam.joint_damping[20], 0.0);
            s.beam.joint_damping = built.beam.joint_damping;
        }
        s.validate().unwrap();
        Chain::<f64, 2>::from_scene(&s).unwrap()
    };
    fn tip<S: Stepper<f64, 2>>(mut st: S, steps: usize) -> f64 {
        let mut s = st.initial_state(0.0).unwrap();
        for k in 0..steps {
            st.step(&mut s, k, 0.0, 0.0).unwrap();
        }
        st.chain().tip_z(st.q(&s))
    }
    let (h, steps) = (1e-3, 1000);
    let rk4 = tip(ProjectedRk4::new(with(5.0), h).unwrap(), steps);
    let rattle = tip(Rattle::new(with(5.0), h).unwrap(), steps);
    let shake = tip(Shake::new(with(5.0), h).unwrap(), steps);
    let undamped = tip(Rattle::new(with(0.0), h).unwrap(), steps);
    println!("tip z at 1 s: RK4 {rk4:.9e}, RATTLE {rattle:.9e}, SHAKE {shake:.9e}, undamped {undamped:.9e}");
    let scale = rk4.abs();
    assert!(
        (rattle - rk4).abs() <= 2e-6 * scale,
        "RATTLE {rattle} vs RK4 {rk4}"
    );
    assert!(
        (shake - rk4).abs() <= 2e-6 * scale,
        "SHAKE {shake} vs RK4 {rk4}"
    );
    assert!((undamped - rk4).abs() >= 2e-3 * scale, "the dampers matter");
}
