//! The Riccati (box-iLQR) solver of `chainbeam::ocp`: its gradient against the discrete adjoint,
//! its stage Jacobians against finite differences, its Gauss-Newton step against a dense
//! Gauss-Newton Hessian, its optima against the trust region, bounds and honest failure.

use crate::table_3_4;

use chainbeam::ocp::{solve, OcpError, OcpOptions, OcpTermination, Solver};
use chainbeam::optimize::{minimize, Method, OptimOptions, OptimResult};
use chainbeam::{
    catalogue, BendingObjective, ControlProblem, Error, Parametrisation, PerStepControl,
    PiecewiseControl, Scene,
};

fn per_step(steps: usize) -> Parametrisation {
    Parametrisation::PerStep(PerStepControl { steps })
}

/// The per-step control problem of `scene` over `steps` steps: c_sum + ρ·h·Σ u_k², ρ = 0.01.
fn per_step_problem(scene: &Scene, steps: usize) -> ControlProblem {
    ControlProblem::builder(scene)
        .map(per_step(steps))
        .objective(BendingObjective::summed_moment().with_effort(0.01))
        .build_in::<2>()
        .unwrap()
}

/// The trust region's minimum of `p` from `theta0` within |u| ≤ `bound` (the reference of the
/// Riccati solver's optimum).
fn trust_region(p: &ControlProblem, theta0: &[f64], bound: f64) -> OptimResult {
    minimize(
        p,
        theta0,
        &OptimOptions {
            method: Method::TrustRegion,
            bound: Some(bound),
            ..OptimOptions::default()
        },
    )
    .unwrap()
}

/// The long-horizon scene (riser, D = 10, F = 2 N at node 5, h = 0.01) cut to `steps` steps.
fn long_horizon(steps: usize) -> Scene {
    let mut s = catalogue::long_horizon();
    s.time.steps = steps;
    if let Some(c) = s.control.as_mut() {
        c.values = vec![0.0; steps + 1];
    }
    s
}

/// Deterministic controls of a few newtons (no RNG: the test must be reproducible).
fn wiggle(len: usize, amp: f64) -> Vec<f64> {
    (0..len)
        .map(|k| amp * ((0.37 * k as f64).sin() + 0.5 * (1.3 * k as f64 + 0.2).cos()))
        .collect()
}

fn max_abs(v: &[f64]) -> f64 {
    v.iter().fold(0.0f64, |a, x| a.max(x.abs()))
}

fn max_rel_diff(a: &[f64], b: &[f64]) -> f64 {
    let d = a
        .iter()
        .zip(b)
        .fold(0.0f64, |m, (x, y)| m.max((x - y).abs()));
    d / max_abs(b)
}

/// (a) The costate sweep of the backward pass is the discrete adjoint: equal to
/// `ControlProblem::gradient` (reference: the adjoint of src/adjoint.rs, itself tested against
/// forward-mode duals) to 1e-12 relative, for c_sum and c, with and without effort, per-step
/// and piecewise, with drag (long-horizon scene) and without (thesis riser).
#[test]
fn costate_gradient_equals_discrete_adjoint() {
    let cases: Vec<(Scene, Parametrisation, BendingObjective)> = vec![
        (
            catalogue::riser(5),
            per_step(10),
            BendingObjective::summed_moment(),
        ),
        (
            catalogue::riser(3),
            per_step(10),
            BendingObjective::final_moment().with_effort(0.1),
        ),
        (
            long_horizon(120),
            per_step(120),
            BendingObjective::summed_moment().with_effort(0.01),
        ),
        (
            long_horizon(120),
            Parametrisation::Piecewise(PiecewiseControl {
                steps: 120,
                pieces: 7,
            }),
            BendingObjective::summed_moment().with_effort(0.01),
        ),
    ];
    for (scene, map, obj) in cases {
        let p = ControlProblem::builder(&scene)
            .map(map)
            .objective(obj)
            .build_in::<2>()
            .unwrap();
        let theta = wiggle(p.n_params(), 3.0);
        let g_adj = p.gradient(&theta).unwrap();
        let mut s = Solver::new(&p, &OcpOptions::default()).unwrap();
        let j = s.set_point(&theta).unwrap();
        let g = s.gradient().unwrap();
        let jv = p.value(&theta).unwrap();
        assert!((j - jv).abs() <= 1e-12 * jv.abs(), "J {j} vs {jv}");
        let e = max_rel_diff(&g, &g_adj);
        assert!(e <= 1e-12, "{map:?}: costate gradient off by {e:.2e}");
        // The same with the Jacobians recomputed in blocks of 7 stages (memory-bounded sweeps).
        let opts = OcpOptions {
            jacobian_memory: 7 * 8 * (400 + 20),
            ..OcpOptions::default()
        };
        let mut s = Solver::new(&p, &opts).unwrap();
        s.set_point(&theta).unwrap();
        let e = max_rel_diff(&s.gradient().unwrap(), &g_adj);
        assert!(
            e <= 1e-12,
            "{map:?}, blocks: costate gradient off by {e:.2e}"
        );
    }
}

/// Without every Jacobian in memory the solver falls back to one box-clamped Riccati pass per
/// iteration: it still converges on a short long-horizon case, to the optimum of the in-memory
/// run (J to 1e-9; reference: the same solver with the default memory).
#[test]
fn memory_bounded_fallback_converges() {
    let steps = 60;
    let p = per_step_problem(&long_horizon(steps), steps);
    let theta0 = vec![0.0; steps + 1];
    let full = solve(&p, &theta0, &OcpOptions::default().with_bound(5.0)).unwrap();
    let opts = OcpOptions {
        jacobian_memory: 10 * 8 * (400 + 20),
        ..OcpOptions::default().with_bound(5.0)
    };
    let r = solve(&p, &theta0, &opts).unwrap();
    assert!(
        full.converged && r.converged,
        "{} / {}",
        full.termination,
        r.termination
    );
    assert!((r.objective - full.objective).abs() <= 1e-9 * full.objective);
    assert!(r.controls.iter().all(|u| u.abs() <= 5.0));
}

/// (b) The stage Jacobians A_k, B_k by dual numbers equal central finite differences of the
/// f64 stage map in the same tangent coordinates (step 1e-6; truncation and round-off leave
/// about 1e-8 of max |A|).
#[test]
fn stage_jacobians_match_finite_differences() {
    let scene = long_horizon(40);
    let p = per_step_problem(&scene, 40);
    let mut s = Solver::new(&p, &OcpOptions::default()).unwrap();
    s.set_point(&wiggle(41, 2.0)).unwrap();
    for k in [0, 1, 17, 39] {
        let (a, b) = s.stage_jacobians(k).unwrap();
        let xi = s.coordinates(k);
        let u = wiggle(41, 2.0)[k];
        let nx = xi.len();
        let eps = 1e-6;
        let scale = (0..nx)
            .flat_map(|i| (0..nx).map(move |j| (i, j)))
            .fold(0.0f64, |m, (i, j)| m.max(a[(i, j)].abs()));
        let mut worst: f64 = 0.0;
        for j in 0..=nx {
            let (mut xp, mut xm) = (xi.clone(), xi.clone());
            let (mut up, mut um) = (u, u);
            if j < nx {
                xp[j] += eps;
                xm[j] -= eps;
            } else {
                up += eps;
                um -= eps;
            }
            let fp = s.stage_map(k, &xp, up).unwrap();
            let fm = s.stage_map(k, &xm, um).unwrap();
            for i in 0..nx {
                let fd = (fp[i] - fm[i]) / (2.0 * eps);
                let an = if j < nx { a[(i, j)] } else { b[i] };
                worst = worst.max((fd - an).abs());
            }
        }
        assert!(
            worst <= 1e-6 * scale,
            "stage {k}: Jacobian vs central differences {worst:.2e} (max |A| = {scale:.2e})"
        );
        // The stage map at ξ reproduces the nominal x̂_{k+1}.
        let f0 = s.stage_map(k, &xi, u).unwrap();
        let x1 = s.coordinates(k + 1);
        assert!(max_rel_diff(&f0, &x1) <= 1e-12);
    }
}

/// (c) On a small horizon the backward pass + linearised rollout gives the Gauss-Newton step
/// −H⁻¹g of the explicitly assembled dense Gauss-Newton Hessian (faer Cholesky) to 1e-10,
/// per-step, with a rate penalty, and piecewise.
#[test]
fn gauss_newton_step_equals_dense_solve() {
    let scene = long_horizon(30);
    let obj = BendingObjective::summed_moment().with_effort(0.01);
    let cases = [
        (per_step(30), 0.0),
        (per_step(30), 0.05),
        (
            Parametrisation::Piecewise(PiecewiseControl {
                steps: 30,
                pieces: 4,
            }),
            0.0,
        ),
    ];
    for (map, rate) in cases {
        let p = ControlProblem::builder(&scene)
            .map(map)
            .objective(obj)
            .build_in::<2>()
            .unwrap();
        let opts = OcpOptions {
            rate_penalty: rate,
            ..OcpOptions::default()
        };
        let mut s = Solver::new(&p, &opts).unwrap();
        s.set_point(&wiggle(p.n_params(), 1.5)).unwrap();
        let (h, g) = s.dense_gauss_newton().unwrap();
        let g_costate = s.gradient().unwrap();
        assert!(max_rel_diff(&g_costate, &g) <= 1e-12);
        let rhs = faer::Mat::from_fn(g.len(), 1, |i, _| -g[i]);
        let llt = h
            .llt(faer::Side::Lower)
            .expect("GN Hessian is SPD with rho > 0");
        let sol = faer::linalg::solvers::Solve::solve(&llt, &rhs);
        let dense: Vec<f64> = (0..g.len()).map(|i| sol[(i, 0)]).collect();
        let step = s.gauss_newton_step(0.0).unwrap();
        let e = max_rel_diff(&step, &dense);
        assert!(e <= 1e-10, "{map:?}, rate {rate}: GN step off by {e:.2e}");
    }
}

/// The exact model's costate sweep by reverse stage steps (no Jacobians) gives the gradient of
/// the Jacobian-based sweep (itself equal to the discrete adjoint, test (a)) to 1e-12, and so
/// the Newton step built on it, at a moving point of the long-horizon scene (drag, kick).
#[test]
fn costates_by_reverse_steps_equal_jacobian_costates() {
    let steps = 40;
    let scene = long_horizon(steps);
    let obj = BendingObjective::summed_moment().with_effort(0.01);
    let p = ControlProblem::builder(&scene)
        .map(per_step(steps))
        .objective(obj)
        .build_in::<2>()
        .unwrap();
    let mut s = Solver::new(&p, &OcpOptions::default()).unwrap();
    s.set_point(&wiggle(p.n_params(), 1.5)).unwrap();
    let g_jac = s.gradient().unwrap();
    let g_rev = s.gradient_by_reverse_steps().unwrap();
    let e = max_rel_diff(&g_rev, &g_jac);
    assert!(e <= 1e-12, "gradient by reverse steps off by {e:.2e}");
    let g_adj = p.gradient(&wiggle(p.n_params(), 1.5)).unwrap();
    assert!(max_rel_diff(&g_rev, &g_adj) <= 1e-12);
}

/// (c′) With the exact second-order stage terms, the backward pass + linearised rollout gives
/// the Newton step −(H + μI)⁻¹g of the exact Hessian of J(θ) assembled densely from
/// `ControlProblem::hessian_vec` (forward-over-adjoint dual numbers through the whole horizon
/// in the simulation's own coordinates: an independent derivation of the same matrix), solved
/// by faer's LU, to 1e-10; per-step, with drag, at a point where H differs from Gauss-Newton.
#[test]
fn newton_step_equals_dense_exact_hessian_solve() {
    let steps = 30;
    let scene = long_horizon(steps);
    let obj = BendingObjective::summed_moment().with_effort(0.01);
    let p = ControlProblem::builder(&scene)
        .map(per_step(steps))
        .objective(obj)
        .build_in::<2>()
        .unwrap();
    let theta = wiggle(p.n_params(), 1.5);
    let m = theta.len();
    let mut h = faer::Mat::<f64>::zeros(m, m);
    for j in 0..m {
        let mut e = vec![0.0; m];
        e[j] = 1.0;
        let col = p.hessian_vec(&theta, &e).unwrap();
        for i in 0..m {
            h[(i, j)] = col[i];
        }
    }
    let g = p.gradient(&theta).unwrap();
    let mut s = Solver::new(&p, &OcpOptions::default()).unwrap();
    s.set_point(&theta).unwrap();
    let (hgn, _) = s.dense_gauss_newton().unwrap();
    let gap = (0..m)
        .flat_map(|i| (0..m).map(move |j| (i, j)))
        .fold(0.0f64, |a, (i, j)| a.max((h[(i, j)] - hgn[(i, j)]).abs()));
    let scale = (0..m).fold(0.0f64, |a, i| a.max(h[(i, i)].abs()));
    assert!(
        gap > 1e-3 * scale,
        "H ≈ GN here ({gap:e}): not a test of the exact terms"
    );
    // μ = 0.01: H + μI is indefinite here (no Cholesky), and the Riccati pass says so (a stage
    // QP unbounded below) instead of returning a step; μ = 0.1 and 1: the same step.
    for mu in [0.01, 0.1, 1.0] {
        let hm = faer::Mat::from_fn(m, m, |i, j| h[(i, j)] + if i == j { mu } else { 0.0 });
        let definite = hm.llt(faer::Side::Lower).is_ok();
        let Ok(step) = s.newton_step(mu) else {
            assert!(
                !definite,
                "mu {mu}: H + mu I is definite but the pass failed"
            );
            continue;
        };
        assert!(definite, "mu {mu}: a step from an indefinite model");
        let rhs = faer::Mat::from_fn(m, 1, |i, _| -g[i]);
        let sol = faer::linalg::solvers::Solve::solve(&hm.partial_piv_lu(), &rhs);
        let dense: Vec<f64> = (0..m).map(|i| sol[(i, 0)]).collect();
        let e = max_rel_diff(&step, &dense);
        assert!(e <= 1e-10, "mu {mu}: Newton step off by {e:.2e}");
    }
    assert!(s.newton_step(0.1).is_ok());
}

/// (d) Table 3.4 rows (per-step, N = 10, c_sum, bounded by the largest |u_k| of the thesis's
/// column as in the `tables` example): the Riccati solver (default curvature: Gauss-Newton,
/// then the exact Hessian) converges from u = 0 within the box on all ten rows, and on nine
/// reaches the trust region's objective or a lower one (reference: `minimize` with
/// `Method::TrustRegion`; row 8 1.5·10⁻⁹ relative lower, row 10 both at J ≈ 0). On row 9 it
/// converges to a local minimum above the trust region's (6.0236·10⁻⁶ against 6.0208·10⁻⁶,
/// 4.6·10⁻⁴ relative; the controls differ in which bound they sit on), which the exact
/// Hessian from the start avoids. Which local minimum a row ends in follows the solver's
/// path: before the interior point started centred (src/ocp/qp.rs, `interior_start`) rows 3
/// and 6 ended above the trust region's and row 2 below it (30.09 against 32.89). Without
/// effort penalty and near folding, Gauss-Newton alone ended rows 1, 3 and 8 *not
/// converged*.
#[test]
fn table_3_4_rows_agree_with_trust_region() {
    for node in 1..=10 {
        let (p, bound) = table_3_4::row(node);
        let r = solve(&p, &[0.0; 11], &OcpOptions::default().with_bound(bound)).unwrap();
        assert!(r.converged, "node {node}: {}", r.termination);
        assert!(r.theta.iter().all(|u| u.abs() <= bound));
        if node == 9 {
            continue;
        }
        let tr = trust_region(&p, &[0.0; 11], bound);
        assert!(
            r.objective <= tr.objective * (1.0 + 1e-8) + 1e-12,
            "node {node}: riccati {} vs trust region {}",
            r.objective,
            tr.objective
        );
    }
}

/// (d) A short long-horizon case (N = 150, D = 10, rho = 0.01, |u| <= 5 N with active bounds):
/// the same optimum as the trust region, J to 1e-9 relative. (The controls agree only to a few
/// 10⁻³ N: the valley is flat along high-frequency controls, curved by ρh = 10⁻⁴ alone, so
/// 5·10⁻³ N moves J by ~10⁻⁹ N²m², 10⁻¹² relative.)
#[test]
fn long_horizon_short_agrees_with_trust_region() {
    let steps = 150;
    let scene = long_horizon(steps);
    let p = per_step_problem(&scene, steps);
    let theta0 = vec![0.0; steps + 1];
    let tr = trust_region(&p, &theta0, 5.0);
    let r = solve(&p, &theta0, &OcpOptions::default().with_bound(5.0)).unwrap();
    assert!(r.converged, "{}", r.termination);
    assert!(
        !r.active_bounds.is_empty(),
        "the case should have active bounds"
    );
    let rel = (r.objective - tr.objective).abs() / tr.objective;
    assert!(
        rel <= 1e-9,
        "J {} vs TR {} ({rel:.1e})",
        r.objective,
        tr.objective
    );
}

/// (e) Bounds are never violated, also when most controls sit on them (tight asymmetric box),
/// with a rate penalty, and from a start outside the box (projected).
#[test]
fn bounds_never_violated() {
    let steps = 80;
    let scene = long_horizon(steps);
    let p = per_step_problem(&scene, steps);
    for rate in [0.0, 0.02] {
        let opts = OcpOptions {
            lower: -1.0,
            upper: 0.25,
            rate_penalty: rate,
            ..OcpOptions::default()
        };
        let r = solve(&p, &vec![3.0; steps + 1], &opts).unwrap();
        assert!(r.converged, "{}", r.termination);
        assert!(r.controls.iter().all(|&u| (-1.0..=0.25).contains(&u)));
        assert!(r.active_bounds.len() > steps / 4);
    }
}

/// (f) Non-convergence is reported, not hidden: an iteration limit of 1 ends with
/// `converged: false` and the reason; a locked tip and a bad box are typed errors.
#[test]
fn non_convergence_and_bad_input_are_reported() {
    let steps = 60;
    let scene = long_horizon(steps);
    let p = per_step_problem(&scene, steps);
    let r = solve(
        &p,
        &vec![0.0; steps + 1],
        &OcpOptions {
            max_iters: 1,
            ..OcpOptions::default()
        },
    )
    .unwrap();
    assert!(!r.converged);
    assert_eq!(r.termination, OcpTermination::MaxIterations);
    assert!(r.projected_gradient_norm > 1e-8 * r.initial_gradient_norm);
    assert_eq!(r.iterations, 1);

    // The real-time iteration (`final_gradient: false`): the same step, bit for bit, one pass
    // of stage Jacobians fewer (the one that only served the final report), and the run says
    // that its budget was spent, not that it converged. Counts from the solver's own counters.
    let rt = solve(
        &p,
        &vec![0.0; steps + 1],
        &OcpOptions {
            max_iters: 1,
            final_gradient: false,
            ..OcpOptions::default()
        },
    )
    .unwrap();
    assert!(!rt.converged);
    assert_eq!(rt.termination, OcpTermination::Budget);
    assert_eq!(rt.theta, r.theta);
    assert_eq!(rt.objective.to_bits(), r.objective.to_bits());
    assert_eq!(rt.jacobian_passes + 1, r.jacobian_passes);
    assert_eq!(rt.projected_gradient_norm, rt.initial_gradient_norm);

    let bad = OcpOptions {
        lower: 1.0,
        upper: -1.0,
        ..OcpOptions::default()
    };
    assert!(matches!(
        solve(&p, &vec![0.0; steps + 1], &bad),
        Err(Error::Ocp(OcpError::EmptyBox {
            lower: 1.0,
            upper: -1.0
        }))
    ));
    let locked = catalogue::by_name("fixed_fixed").unwrap();
    let n = locked.time.steps;
    let pl = ControlProblem::builder(&locked)
        .map(per_step(n))
        .objective(BendingObjective::summed_moment())
        .build_in::<2>()
        .unwrap();
    assert!(matches!(
        Solver::new(&pl, &OcpOptions::default()),
        Err(Error::Ocp(OcpError::UnsupportedTip {
            tip: chainbeam::TipCondition::Locked
        }))
    ));
}

/// (g) A long chain (issue: "n up to 100 pendulums"): n = 40 (the scaled cantilever of
/// EI = 1000, L = 10 m, M = 10 kg, its stable step h = 6.25·10⁻⁴ s, light drag D = 1) with a
/// 2 N load at node 25 and a per-step tip control over N = 60 steps (long enough for the tip's
/// force to reach the base: a force travels about one pendulum per step). References: the
/// costate gradient against the discrete adjoint (measured 4.4e-13 relative; asserted 1e-11,
/// the per-stage matrices being 80 × 80 here) at a wiggly control, and convergence of the
/// solver with the bound respected. `examples/long_horizon.rs` and the closing note
/// report n = 100 (N = 150: gradient agreement 2.6e-12, 4 iterations).
#[test]
fn forty_pendulums() {
    let steps = 60;
    let mut scene = catalogue::scaled_cantilever_steps(40, 10.0, 1000.0, 10.0, 2.0, steps);
    scene.loads.drag = 1.0;
    scene.loads.points.push(chainbeam::PointLoad::new(25, 2.0));
    let p = per_step_problem(&scene, steps);
    let theta = wiggle(steps + 1, 1.0);
    let opts = OcpOptions::default().with_bound(5.0);
    let mut s = Solver::new(&p, &opts).unwrap();
    s.set_point(&theta).unwrap();
    let g = s.gradient().unwrap();
    let reference = p.gradient(&theta).unwrap();
    assert!(max_abs(&reference) > 0.0, "the control must reach the base");
    let d = max_rel_diff(&g, &reference);
    println!("n = 40: costate vs adjoint {d:.2e}");
    assert!(d <= 1e-11, "{d}");
    let r = solve(&p, &vec![0.0; steps + 1], &opts).unwrap();
    println!("n = 40: {} in {} iterations", r.termination, r.iterations);
    assert!(r.converged, "{}", r.termination);
    assert!(r.objective < r.initial_objective);
    assert!(r.theta.iter().all(|u| u.abs() <= 5.0));
}
