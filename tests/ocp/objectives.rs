//! Objectives as one type everywhere (`Objective`), proved with the power objective
//! Σ_k |M₀(t_k)|^p (`PowerObjective`, scene `[objective] kind = "power", exponent = p`):
//! its adjoint gradient against forward dual numbers (1e-12) and central differences (1e-6),
//! its Hessian-vector products against differences of the adjoint gradient, the Riccati
//! solver's gradient and exact Newton step against the adjoint and the dense Hessian, every
//! method of `optimize` on Table 3.4's scene (p = 2 bit for bit c_sum, p = 4 at the trust
//! region's objective), `mpc`, the command line, and bad exponents.

use crate::thesis;
use crate::wave_riser4;

use chainbeam::adjoint::forward_value;
use chainbeam::mpc::{run_closed_loop, Horizon, Mpc, MpcOptions, MpcSolver};
use chainbeam::ocp::{self, Condensed, OcpOptions, Solver};
use chainbeam::optimize::{minimize, Method, OptimOptions};
use chainbeam::{
    catalogue, BendingObjective, ControlMap, ControlProblem, Error, Objective, ObjectiveKind,
    Parametrisation, PerStepControl, PiecewiseControl, PowerObjective, Scene, SceneErrorKind,
};
use num_dual::Dual64;

fn per_step(steps: usize) -> Parametrisation {
    Parametrisation::PerStep(PerStepControl { steps })
}

fn power(p: f64) -> PowerObjective {
    PowerObjective::new(p).unwrap()
}

/// Deterministic controls of a few newtons.
fn wiggle(len: usize, amp: f64) -> Vec<f64> {
    (0..len)
        .map(|k| amp * ((0.37 * k as f64).sin() + 0.5 * (1.3 * k as f64 + 0.2).cos()))
        .collect()
}

fn max_abs(v: &[f64]) -> f64 {
    v.iter().fold(0.0f64, |m, x| m.max(x.abs()))
}

fn max_rel_diff(a: &[f64], b: &[f64]) -> f64 {
    assert_eq!(a.len(), b.len());
    let scale = max_abs(b).max(f64::MIN_POSITIVE);
    a.iter()
        .zip(b)
        .fold(0.0f64, |m, (x, y)| m.max((x - y).abs() / scale))
}

fn bits(v: &[f64]) -> Vec<u64> {
    v.iter().map(|x| x.to_bits()).collect()
}

/// The thesis riser (load F = 2 N at node 5) with drag `drag`, N steps, the control at the tip.
fn riser(drag: f64, steps: usize) -> Scene {
    let mut s = catalogue::riser(5);
    s.loads.drag = drag;
    s.time.steps = steps;
    s
}

/// Row `node` of Table 3.4 (per-step, N = 10, no effort) with objective `obj`, and the bound the
/// `tables` example gives it: the largest |u_k| of the thesis's printed row.
fn table_3_4_row<O: Objective>(node: usize, obj: O) -> (ControlProblem<Parametrisation, O>, f64) {
    let p = ControlProblem::builder(&catalogue::riser(node))
        .map(per_step(10))
        .objective(obj)
        .build_in::<2>()
        .unwrap();
    let bound = max_abs(&thesis::TABLE_3_4[node - 1].0);
    (p, bound)
}

/// With p = 2 the power objective is c_sum bit for bit: value, adjoint gradient and
/// Hessian-vector product (planar and spatial, with effort), the Riccati solver's costate
/// gradient and the condensed solver's Gauss-Newton model, and the optima of every method.
#[test]
fn power_two_is_c_sum_bit_for_bit() {
    let s = riser(10.0, 15);
    let theta = wiggle(16, 1.5);
    let v = wiggle(16, 0.7);
    let sum = BendingObjective::summed_moment().with_effort(0.1);
    let p2 = power(2.0).with_effort(0.1);
    let a = ControlProblem::builder(&s)
        .map(per_step(15))
        .objective(sum)
        .build_in::<2>()
        .unwrap();
    let b = ControlProblem::builder(&s)
        .map(per_step(15))
        .objective(p2)
        .build_in::<2>()
        .unwrap();
    assert_eq!(
        a.value(&theta).unwrap().to_bits(),
        b.value(&theta).unwrap().to_bits()
    );
    assert_eq!(
        bits(&a.gradient(&theta).unwrap()),
        bits(&b.gradient(&theta).unwrap())
    );
    assert_eq!(
        bits(&a.hessian_vec(&theta, &v).unwrap()),
        bits(&b.hessian_vec(&theta, &v).unwrap())
    );
    // The spatial model with a 2-axis control: |M₀|² = M₀ₓ² + M₀².
    let th2 = wiggle(32, 1.1);
    let a3 = ControlProblem::builder(&s)
        .map(per_step(15))
        .objective(sum)
        .two_axis(true)
        .build_in::<3>()
        .unwrap();
    let b3 = ControlProblem::builder(&s)
        .map(per_step(15))
        .objective(p2)
        .two_axis(true)
        .build_in::<3>()
        .unwrap();
    let (ja, ga) = a3.value_and_gradient(&th2).unwrap();
    let (jb, gb) = b3.value_and_gradient(&th2).unwrap();
    assert_eq!(ja.to_bits(), jb.to_bits());
    assert_eq!(bits(&ga), bits(&gb));
    // The structured solvers' derivatives.
    let opts = OcpOptions::default();
    let (mut ra, mut rb) = (
        Solver::new(&a, &opts).unwrap(),
        Solver::new(&b, &opts).unwrap(),
    );
    ra.set_point(&theta).unwrap();
    rb.set_point(&theta).unwrap();
    assert_eq!(ra.objective().to_bits(), rb.objective().to_bits());
    assert_eq!(bits(&ra.gradient().unwrap()), bits(&rb.gradient().unwrap()));
    let (mut ca, mut cb) = (
        Condensed::new(&a, &opts).unwrap(),
        Condensed::new(&b, &opts).unwrap(),
    );
    ca.set_point(&theta).unwrap();
    cb.set_point(&theta).unwrap();
    let ((ha, ga), (hb, gb)) = (ca.gauss_newton().unwrap(), cb.gauss_newton().unwrap());
    assert_eq!(bits(&ga), bits(&gb));
    let flat = |m: &faer::Mat<f64>| -> Vec<u64> {
        (0..16 * 16)
            .map(|i| m[(i / 16, i % 16)].to_bits())
            .collect()
    };
    assert_eq!(flat(&ha), flat(&hb));
    // Every method on Table 3.4's rows 3 and 8: the same optimum bit for bit.
    for node in [3, 8] {
        for method in [
            Method::Lbfgs,
            Method::TrustRegion,
            Method::Riccati,
            Method::Condensed,
        ] {
            assert_power_two_is_c_sum(node, method);
        }
    }
}

/// Table 3.4's row `node` minimised from u = 0 by `method` (bounded by the thesis's largest |u|
/// of the row) on c_sum and on Σ|M₀|²: the same objective, θ and iterations bit for bit.
fn assert_power_two_is_c_sum(node: usize, method: Method) {
    let (pa, bound) = table_3_4_row(node, BendingObjective::summed_moment());
    let (pb, _) = table_3_4_row(node, power(2.0));
    let o = OptimOptions {
        method,
        bound: Some(bound),
        max_iters: 2000,
        ..OptimOptions::default()
    };
    let (x, y) = (
        minimize(&pa, &[0.0; 11], &o).unwrap(),
        minimize(&pb, &[0.0; 11], &o).unwrap(),
    );
    let at = format!("row {node}, {method}");
    assert_eq!(x.objective.to_bits(), y.objective.to_bits(), "{at}");
    assert_eq!(bits(&x.theta), bits(&y.theta), "{at}");
    assert_eq!(x.iterations, y.iterations, "{at}");
}

/// dJ/dθ of Σ|M₀|^p by the adjoint against forward-mode `Dual64` through the same simulation
/// (1e-12 of the gradient's largest entry) and central differences of J (1e-6), for
/// p = 2.5, 3, 4, 6 on the drag-free and the D = 10 riser, per-step and piecewise, with effort,
/// and on a spatial scene (an oblique load) with a 2-axis control.
#[test]
fn power_gradient_equals_dual64_and_central_differences() {
    let pw = Parametrisation::Piecewise(PiecewiseControl {
        steps: 20,
        pieces: 4,
    });
    for p in [2.5, 3.0, 4.0, 6.0] {
        for (drag, map) in [(0.0, per_step(20)), (10.0, per_step(20)), (10.0, pw)] {
            let s = riser(drag, 20);
            let obj = power(p).with_effort(0.05);
            let prob = ControlProblem::builder(&s)
                .map(map)
                .objective(obj)
                .build_in::<2>()
                .unwrap();
            let theta = wiggle(map.n_params(), 1.5);
            let g = prob.gradient(&theta).unwrap();
            let scale = max_abs(&g);
            assert!(scale > 0.0);
            let chain = prob.chain_as::<Dual64>();
            let (mut worst_fwd, mut worst_fd) = (0.0f64, 0.0f64);
            for j in 0..theta.len() {
                let th: Vec<Dual64> = theta
                    .iter()
                    .enumerate()
                    .map(|(i, &t)| Dual64::new(t, f64::from(u8::from(i == j))))
                    .collect();
                let mut u = vec![Dual64::from(0.0); 21];
                map.controls(&th, &mut u);
                let fwd = forward_value(&chain, s.time.step, 20, &u, &obj)
                    .unwrap()
                    .eps;
                worst_fwd = worst_fwd.max((g[j] - fwd).abs() / scale);
                let eps = 1e-5 * theta[j].abs().max(1.0);
                let (mut tp, mut tm) = (theta.clone(), theta.clone());
                tp[j] += eps;
                tm[j] -= eps;
                let fd = (prob.value(&tp).unwrap() - prob.value(&tm).unwrap()) / (2.0 * eps);
                worst_fd = worst_fd.max((g[j] - fd).abs() / scale);
            }
            println!(
                "p = {p}, D = {drag}, {} params: adjoint vs Dual64 {worst_fwd:.1e}, vs central \
                 differences {worst_fd:.1e} (of max|g| = {scale:.3e})",
                theta.len()
            );
            assert!(worst_fwd <= 1e-12, "p {p}, D {drag}: {worst_fwd:e}");
            assert!(worst_fd <= 1e-6, "p {p}, D {drag}: {worst_fd:e}");
        }
    }
    // Spatial: a load turned 40° out of the yz-plane, a 2-axis control.
    let mut s = riser(10.0, 12);
    s.loads.points[0].direction = [40f64.to_radians().sin(), 40f64.to_radians().cos()];
    let obj = power(3.0).with_effort(0.05);
    let prob = ControlProblem::builder(&s)
        .map(per_step(12))
        .objective(obj)
        .two_axis(true)
        .build_in::<3>()
        .unwrap();
    let theta = wiggle(26, 1.2);
    let g = prob.gradient(&theta).unwrap();
    let scale = max_abs(&g);
    let mut worst = 0.0f64;
    for j in 0..theta.len() {
        let eps = 1e-5;
        let (mut tp, mut tm) = (theta.clone(), theta.clone());
        tp[j] += eps;
        tm[j] -= eps;
        let fd = (prob.value(&tp).unwrap() - prob.value(&tm).unwrap()) / (2.0 * eps);
        worst = worst.max((g[j] - fd).abs() / scale);
    }
    println!("spatial p = 3, 2-axis: adjoint vs central differences {worst:.1e}");
    assert!(worst <= 1e-6);
}

/// Hessian-vector products (forward over adjoint) of Σ|M₀|^p against central differences of
/// the adjoint gradient (1e-6 of the product's largest entry), and symmetric (vᵀHw = wᵀHv to
/// 1e-10), p = 3 and 4, the D = 10 riser, per-step controls, from the beam at rest (where
/// M₀(t₀) = 0 and the stage cost's second derivative p(p−1)|M₀|^{p−2} must not be 0·∞).
#[test]
fn power_hessian_vector_products() {
    for p in [3.0, 4.0] {
        let s = riser(10.0, 15);
        let prob = ControlProblem::builder(&s)
            .map(per_step(15))
            .objective(power(p).with_effort(0.1))
            .build_in::<2>()
            .unwrap();
        let theta = wiggle(16, 1.5);
        let (v, w) = (
            wiggle(16, 0.3),
            (0..16)
                .map(|j| 0.2 * (j as f64).cos())
                .collect::<Vec<f64>>(),
        );
        let hv = prob.hessian_vec(&theta, &v).unwrap();
        let hw = prob.hessian_vec(&theta, &w).unwrap();
        let eps = 1e-5;
        let shift = |d: f64| -> Vec<f64> { theta.iter().zip(&v).map(|(t, x)| t + d * x).collect() };
        let (gp, gm) = (
            prob.gradient(&shift(eps)).unwrap(),
            prob.gradient(&shift(-eps)).unwrap(),
        );
        let fd: Vec<f64> = gp
            .iter()
            .zip(&gm)
            .map(|(a, b)| (a - b) / (2.0 * eps))
            .collect();
        let e = max_rel_diff(&hv, &fd);
        let vhw: f64 = v.iter().zip(&hw).map(|(a, b)| a * b).sum();
        let whv: f64 = w.iter().zip(&hv).map(|(a, b)| a * b).sum();
        println!("p = {p}: Hv vs differences of the gradient {e:.1e}; v'Hw {vhw:e}, w'Hv {whv:e}");
        assert!(hv.iter().all(|x| x.is_finite()));
        assert!(e <= 1e-6, "p {p}: {e:e}");
        assert!((vhw - whv).abs() <= 1e-10 * vhw.abs().max(whv.abs()));
    }
}

/// The structured solvers see the power objective through its Gauss-Newton form: the Riccati
/// solver's costate gradient and the condensed solver's gradient equal the discrete adjoint's
/// (1e-12), and the Riccati solver's exact Newton step (with the residual's own curvature
/// w r r″ and the moment's) equals −(H + μI)⁻¹g of the dense exact Hessian assembled from
/// `ControlProblem::hessian_vec` (1e-10), p = 3 and 4, the D = 10 riser, per-step.
#[test]
fn structured_solvers_derivatives_of_the_power_objective() {
    for p in [3.0, 4.0] {
        let s = riser(10.0, 20);
        let prob = ControlProblem::builder(&s)
            .map(per_step(20))
            .objective(power(p).with_effort(0.01))
            .build_in::<2>()
            .unwrap();
        let theta = wiggle(21, 1.5);
        let g = prob.gradient(&theta).unwrap();
        let mut solver = Solver::new(&prob, &OcpOptions::default()).unwrap();
        solver.set_point(&theta).unwrap();
        let e_ric = max_rel_diff(&solver.gradient().unwrap(), &g);
        let mut cond = Condensed::new(&prob, &OcpOptions::default()).unwrap();
        cond.set_point(&theta).unwrap();
        let e_con = max_rel_diff(&cond.gauss_newton().unwrap().1, &g);
        let m = theta.len();
        let mut h = faer::Mat::<f64>::zeros(m, m);
        for j in 0..m {
            let mut e = vec![0.0; m];
            e[j] = 1.0;
            let col = prob.hessian_vec(&theta, &e).unwrap();
            for i in 0..m {
                h[(i, j)] = col[i];
            }
        }
        let mu = 1.0;
        let hm = faer::Mat::from_fn(m, m, |i, j| h[(i, j)] + if i == j { mu } else { 0.0 });
        let rhs = faer::Mat::from_fn(m, 1, |i, _| -g[i]);
        let sol = faer::linalg::solvers::Solve::solve(&hm.partial_piv_lu(), &rhs);
        let dense: Vec<f64> = (0..m).map(|i| sol[(i, 0)]).collect();
        let e_newton = max_rel_diff(&solver.newton_step(mu).unwrap(), &dense);
        println!(
            "p = {p}: Riccati gradient {e_ric:.1e}, condensed gradient {e_con:.1e}, Newton step \
             {e_newton:.1e}"
        );
        assert!(e_ric <= 1e-12 && e_con <= 1e-12);
        assert!(e_newton <= 1e-10);
    }
}

/// Every method on every row of Table 3.4's scene (per-step, N = 10, bounded by the thesis
/// row's largest |u_k|, from u = 0) for Σ M₀⁴. Reference: the trust region on exact
/// Hessian-vector products, converged. `--method riccati` converges by itself on every row and
/// `condensed` on all but a few (whose stalls `minimize` hands to the trust region, as for
/// c_sum); each run reaches the trust region's objective (1e-6 relative) or a lower one, or
/// ends at another local minimum of this nonconvex problem (as for c_sum, `ocp` module docs:
/// row 9), which the check below certifies: the trust region started at its point lowers J by
/// at most 1e-9 relative. How many rows reach it is printed and bounded below.
#[test]
fn structured_solvers_reach_the_trust_region_on_table_3_4_with_p_4() {
    // Σ M₀⁴ is flat where the moments are small (its curvature 12 M₀² vanishes with them):
    // row 8 ends at J ≈ 1.5e-7, and the default ‖g‖ ≤ 1e-8 ‖g₀‖ left the Riccati solver's J
    // 5e-5 above the minimum there; the methods under test run to 1e-10, the reference to the
    // default (at 1e-10 it stalls at J's round-off on row 10, where J ≈ 0).
    const REL_GRAD_TOL: f64 = 1e-10;
    let (mut reached, mut by_itself) = ([0usize; 2], [0usize; 2]);
    for node in 1..=10 {
        let (prob, bound) = table_3_4_row(node, power(4.0));
        let run = |method, start: &[f64], rel_grad_tol| {
            let o = OptimOptions {
                method,
                bound: Some(bound),
                max_iters: 2000,
                rel_grad_tol,
                ..OptimOptions::default()
            };
            minimize(&prob, start, &o).unwrap()
        };
        let tr = run(
            Method::TrustRegion,
            &[0.0; 11],
            OptimOptions::default().rel_grad_tol,
        );
        assert!(tr.converged, "node {node}: {}", tr.termination);
        for (i, method) in [Method::Riccati, Method::Condensed, Method::Lbfgs]
            .into_iter()
            .enumerate()
        {
            let r = run(method, &[0.0; 11], REL_GRAD_TOL);
            let rel = (r.objective - tr.objective) / tr.objective;
            let from_there = run(Method::TrustRegion, &r.theta, REL_GRAD_TOL);
            let drop = (r.objective - from_there.objective) / r.objective;
            println!(
                "3.4 node {node}, p = 4: {method} J = {:.10e} (ended by {}, converged {}, {} \
                 iterations), trust region {:.10e}: relative {rel:+.1e}; the trust region from \
                 there lowers J by {drop:.1e}",
                r.objective, r.method, r.converged, r.iterations, tr.objective
            );
            assert!(r.theta.iter().all(|u| u.abs() <= bound));
            if method == Method::Lbfgs {
                continue;
            }
            if r.method == method {
                assert!(r.converged, "node {node} {method}: {}", r.termination);
                by_itself[i] += 1;
            }
            if rel <= 1e-6 {
                reached[i] += 1;
            } else {
                assert!(drop <= 1e-9, "node {node} {method}: not a local minimum");
            }
        }
    }
    println!(
        "(riccati, condensed): converged by itself on {by_itself:?} rows, at or below the trust \
         region's objective on {reached:?}"
    );
    assert_eq!(by_itself[0], 10);
    assert!(
        by_itself[1] >= 8 && reached.iter().all(|&r| r >= 7),
        "{reached:?}"
    );
}

/// With p = 2 every row of Table 3.4 gives c_sum's result bit for bit with `--method riccati`
/// and `condensed` (objective, θ, iterations; the reference: the same run on
/// `BendingObjective::summed_moment()`, tests/scene/tables.rs and tests/ocp/ocp.rs compare those with
/// the trust region).
#[test]
fn table_3_4_with_p_2_is_c_sum_bit_for_bit() {
    for node in 1..=10 {
        for method in [Method::Riccati, Method::Condensed] {
            assert_power_two_is_c_sum(node, method);
        }
    }
}

/// The small riser (n = 4, D = 10) under a ramped wave at node 2, controlled at the tip: the
/// scene of tests/mpc/mpc.rs.
fn wave_scene(steps: usize) -> Scene {
    wave_riser4::scene(steps)
}

/// `mpc` plans on the power objective: with the horizon to the end and a perfect model its
/// decisions reproduce the open-loop optimum of Σ M₀⁴ + ρhΣu² (principle of optimality, as
/// tests/mpc/mpc.rs shows for c_sum): J to 1e-8 relative and the forces to 1e-5 of their largest,
/// with both solvers (every plan and the reference solved to ‖g‖ ≤ 1e-10 ‖g₀‖; Σ M₀⁴ is flat
/// where the moments are small, so the forces are resolved about as the square root of J's
/// accuracy: measured 1.1e-6 and 9.1e-10 with the condensed solver, 9.2e-7 and 6.0e-10 with the Riccati solver); and its closed loop has a
/// lower Σ M₀⁴ than the c_sum planner's.
#[test]
fn mpc_plans_on_the_power_objective() {
    const EFFORT: f64 = 0.01;
    const TOL: f64 = 1e-10;
    let s = wave_scene(100);
    let map = PiecewiseControl {
        steps: 100,
        pieces: 10,
    };
    let obj = power(4.0).with_effort(EFFORT);
    let problem = ControlProblem::builder(&s)
        .map(map)
        .objective(obj)
        .build_in::<2>()
        .unwrap();
    let ocp_opts = OcpOptions {
        rel_grad_tol: TOL,
        ..OcpOptions::default()
    }
    .with_bound(5.0);
    let open = ocp::solve(&problem, &[0.0; 10], &ocp_opts).unwrap();
    assert!(open.converged, "{}", open.termination);
    let mpc = |solver, objective| {
        let mut o = MpcOptions {
            horizon: Horizon::ToEnd,
            first_iterations: 200,
            iterations: 200,
            effort: EFFORT,
            solver,
            objective,
            ocp: OcpOptions::default().with_bound(5.0),
            ..MpcOptions::default()
        };
        o.ocp.rel_grad_tol = TOL;
        let mut c = Mpc::new(&s, 0.1, o).unwrap();
        run_closed_loop(&s, 0.1, &mut c).unwrap()
    };
    let m4 = |m: &[f64]| m.iter().map(|x| x.powi(4)).sum::<f64>();
    let scale = max_abs(&open.theta);
    for solver in [MpcSolver::Condensed, MpcSolver::Riccati] {
        let r = mpc(solver, ObjectiveKind::Power { exponent: 4.0 });
        let gap = r
            .decisions
            .iter()
            .zip(&open.theta)
            .fold(0.0f64, |a, (d, t)| a.max((d.control - t).abs() / scale));
        let j = m4(&r.moment) + EFFORT * r.summary.effort;
        let dj = (j - open.objective).abs() / open.objective;
        let by_sum = mpc(solver, ObjectiveKind::Sum);
        println!(
            "{solver:?}: force gap {gap:.2e}, J gap {dj:.2e}; closed-loop Σ M⁴ {:.6e} (planned \
             on Σ M²: {:.6e})",
            m4(&r.moment),
            m4(&by_sum.moment)
        );
        assert!(gap <= 1e-5, "{solver:?}: {gap:e}");
        assert!(dj <= 1e-8, "{solver:?}: {dj:e}");
        assert!(m4(&r.moment) < m4(&by_sum.moment));
    }
}

/// A bad exponent is a typed error naming `objective.exponent`: p < 2, non-finite, missing
/// with kind = "power", given with another kind; from a scene file, a built scene, the
/// library's constructor and the MPC's options.
#[test]
fn bad_exponents_are_typed_errors_naming_the_key() {
    let text = std::fs::read_to_string(
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("examples/scenes/riser_5.toml"),
    )
    .unwrap();
    let with = |objective: &str| text.replace("kind = \"final\"", objective);
    let key_of = |e: chainbeam::SceneError| -> (String, SceneErrorKind) {
        (e.key().unwrap_or("").to_string(), e.kind)
    };
    for bad in ["1.5", "0", "-3", "nan", "inf", "-inf"] {
        let e = Scene::from_toml_str(&with(&format!("kind = \"power\"\nexponent = {bad}")))
            .unwrap_err();
        let (key, kind) = key_of(e);
        assert_eq!(key, "objective.exponent", "{bad}");
        assert!(
            matches!(kind, SceneErrorKind::InvalidValue { .. }),
            "{bad}: {kind:?}"
        );
    }
    let (key, kind) = key_of(Scene::from_toml_str(&with("kind = \"power\"")).unwrap_err());
    assert_eq!(key, "objective.exponent");
    assert!(matches!(kind, SceneErrorKind::MissingKey { .. }));
    let (key, _) = key_of(Scene::from_toml_str(&with("kind = \"sum\"\nexponent = 3")).unwrap_err());
    assert_eq!(key, "objective.exponent");
    // An integer exponent is a number.
    let ok = Scene::from_toml_str(&with("kind = \"power\"\nexponent = 4")).unwrap();
    assert_eq!(ok.objective, Some(ObjectiveKind::Power { exponent: 4.0 }));
    // A built scene is validated the same way.
    let mut built = catalogue::riser(5);
    built.objective = Some(ObjectiveKind::Power { exponent: 1.0 });
    assert_eq!(
        built.validate().unwrap_err().key(),
        Some("objective.exponent")
    );
    assert_eq!(
        PowerObjective::new(f64::NAN).unwrap_err().key(),
        Some("objective.exponent")
    );
    let o = MpcOptions {
        objective: ObjectiveKind::Power { exponent: 1.9 },
        ..MpcOptions::default()
    };
    match Mpc::new(&wave_scene(10), 0.1, o) {
        Err(Error::Scene(e)) => assert_eq!(e.key(), Some("objective.exponent")),
        other => panic!("{:?}", other.err()),
    }
}
