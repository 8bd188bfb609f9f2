//! The band solver of the coupled half step against its dense reference (`coupled/dense.rs`, the
//! O((n·DIM)³) dense LU this crate shipped first, which assembles A and J column by column):
//! random damped scenes, planar and spatial, every tip condition, n up to 40, with and without
//! a drag in a current; each solve to 1e-12 relative, and whole RATTLE trajectories (f64, and
//! Dual64 with the dampers' value seeded) to 1e-12. And the adjoint through the band solves with
//! the tip constraints (locked, reaction force) = Dual64 to 1e-12.

use super::dense::DenseHalf;
use super::{solve_half_step, CoupledHalf, DENSE_REFERENCE};
use crate::model::Chain;
use crate::scene::{Current, Scene, SceneBuilder, Support};
use crate::steppers::rattle::{Rattle, State};
use crate::{Parameter, Scalar};
use num_dual::Dual64;

/// A pseudo-random number in [−1, 1) (a fixed LCG: the tests are deterministic).
fn rand(state: &mut u64) -> f64 {
    *state = state
        .wrapping_mul(6364136223846793005)
        .wrapping_add(1442695040888963407);
    ((*state >> 11) as f64 / (1u64 << 53) as f64) * 2.0 - 1.0
}

/// What a test scene has.
#[derive(Clone, Copy, Debug)]
struct Case {
    n: usize,
    spatial: bool,
    support: Support,
    reaction: bool,
    /// A drag in a (sheared) current beside the dampers (the half step is then a Newton solve).
    drag: bool,
    /// Every damper the same (so that [`Parameter::JointDamping`] exists), else random.
    uniform: bool,
    seed: u64,
}

/// The cases: both dimensions, every support and tip condition, n from 1 to 40.
fn cases() -> Vec<Case> {
    use Support::*;
    let mut v = Vec::new();
    let list = [
        (1, Cantilever, false, false),
        (2, FixedFixed, false, true),
        (3, Riser, false, true),
        (7, PinnedPinned, false, false),
        (12, FixedFixed, true, false),
        (20, Cantilever, false, true),
        (33, PinnedPinned, true, true),
        (40, Riser, false, false),
        (40, FixedFixed, false, true),
    ];
    for (k, &(n, support, reaction, drag)) in list.iter().enumerate() {
        for spatial in [false, true] {
            v.push(Case {
                n,
                spatial,
                support,
                reaction,
                drag,
                uniform: false,
                seed: 11 + 7 * k as u64 + u64::from(spatial),
            });
        }
    }
    v
}

/// A random beam (lengths, masses and springs within a factor 2, point loads at two nodes,
/// dampers c ∈ [1, 10] N·m·s/rad) for `case`, with step h = 0.004 s and `steps` steps.
fn scene(case: Case, steps: usize) -> Scene {
    let mut s = case.seed;
    let n = case.n;
    let mut r = |lo: f64, hi: f64| lo + (hi - lo) * 0.5 * (rand(&mut s) + 1.0);
    let lengths = (0..n).map(|_| r(0.5, 1.0)).collect();
    let masses = (0..n).map(|_| r(0.5, 1.0)).collect();
    let springs = (0..n.saturating_sub(1)).map(|_| r(500.0, 1000.0)).collect();
    let (fy, fz) = (r(-20.0, 20.0), r(-20.0, 20.0));
    let mut b = SceneBuilder::new(n)
        .support(case.support)
        .lengths(lengths)
        .masses(masses)
        .stiffnesses(springs)
        .reaction_force(case.reaction)
        .joint_damping(r(1.0, 10.0))
        .step(0.004)
        .steps(steps);
    if matches!(
        case.support,
        Support::Cantilever | Support::Riser | Support::FixedFixed
    ) {
        b = b.base_stiffness(r(1000.0, 2000.0));
    }
    if matches!(case.support, Support::Riser | Support::FixedFixed) {
        b = b.tip_stiffness(r(1000.0, 2000.0));
    }
    let node = n.div_ceil(2);
    b = if case.spatial {
        b.point_load_vector(node, [fy, fz])
            .point_load_vector(n, [fz * 0.3, -fy * 0.5])
    } else {
        b.point_load(node, fz).point_load(n, -fy * 0.4)
    };
    if case.drag {
        let dir = if case.spatial { [0.6, 0.8] } else { [0.0, 1.0] };
        b = b.drag(3.0).current(Current::linear(0.8, 0.3, dir));
    }
    let mut scene = b.build().unwrap_or_else(|e| panic!("{case:?}: {e}"));
    if !case.uniform {
        for c in scene.beam.joint_damping.iter_mut().filter(|c| **c > 0.0) {
            *c *= r(0.2, 2.0);
        }
    }
    scene.validate().unwrap();
    scene
}

/// max |a − b| over max |b| (1 when b vanishes), and max |b|.
fn rel<const DIM: usize>(a: &[[f64; DIM]], b: &[[f64; DIM]]) -> (f64, f64) {
    let scale = b.iter().flatten().fold(0.0f64, |m, x| m.max(x.abs()));
    let diff = a
        .iter()
        .flatten()
        .zip(b.iter().flatten())
        .fold(0.0f64, |m, (x, y)| m.max((x - y).abs()));
    (diff / scale.max(1e-300), scale)
}

fn rel_flat(a: &[f64], b: &[f64]) -> f64 {
    let scale = b.iter().fold(0.0f64, |m, x| m.max(x.abs()));
    let diff = a
        .iter()
        .zip(b)
        .fold(0.0f64, |m, (x, y)| m.max((x - y).abs()));
    diff / scale.max(1e-300)
}

/// Random attitudes near the straight beam (unit vectors), momenta and a moved q′.
fn random_state<const DIM: usize>(n: usize, seed: u64) -> [Vec<[f64; DIM]>; 3] {
    let mut s = seed;
    let mut unit = |scale: f64| -> [f64; DIM] {
        let mut v: [f64; DIM] = std::array::from_fn(|_| scale * rand(&mut s));
        v[DIM - 2] += 1.0;
        let norm = v.iter().map(|x| x * x).sum::<f64>().sqrt();
        v.map(|x| x / norm)
    };
    let q: Vec<[f64; DIM]> = (0..n).map(|_| unit(0.4)).collect();
    let qnew = q
        .iter()
        .map(|qi| {
            let d = unit(1.0);
            std::array::from_fn(|k| qi[k] + 0.01 * d[k])
        })
        .collect();
    let p = (0..n).map(|_| unit(1.0).map(|x| 3.0 * x)).collect();
    [q, p, qnew]
}

/// Every solve of the band path against the dense LU at random states: p_{k+½} (the half step,
/// linear or Newton), Wᵀs, J x = b and Jᵀx = b, each to 1e-12 relative.
fn solves_equal_dense<const DIM: usize>(case: Case) {
    let sc = scene(case, 1);
    let ch = Chain::<f64, DIM>::from_scene(&sc).unwrap();
    let (n, nc, h) = (ch.n(), ch.n_constraints(), sc.time.step);
    assert!(ch.has_coupled_dissipation());
    let mut band = CoupledHalf::new(&ch);
    let mut dense = DenseHalf::new(&ch);
    let [q, c, qnew] = random_state::<DIM>(n, case.seed * 3 + 1);
    let ctx = ch.dissipation_ctx(0.3, h, 2);
    let (mut pb, mut pd) = (c.clone(), c.clone());
    band.solve(&ch, (&q, &c), (h, &ctx), &mut pb).unwrap();
    solve_half_step(&mut dense, &ch, (&q, &c), (h, &ctx), &mut pd).unwrap();
    let (e, scale) = rel(&pb, &pd);
    assert!(e <= 1e-12 && scale > 0.1, "{case:?}: p½ {e:.1e}");
    // The half step moved p: the dampers (and drag) act.
    assert!(rel(&pd, &c).0 > 1e-4, "{case:?}: p½ = c");
    let [s, _, _] = random_state::<DIM>(n, case.seed * 5 + 2);
    let (mut sb, mut sd) = (s.clone(), s);
    band.apply_w_transpose(&mut sb);
    dense.apply_w_transpose(&mut sd);
    let (e, _) = rel(&sb, &sd);
    assert!(e <= 1e-12, "{case:?}: Wᵀs {e:.1e}");
    band.factor_newton(&ch, (&q, &qnew), h).unwrap();
    dense.factor_newton(&ch, (&q, &qnew), h).unwrap();
    let mut st = case.seed;
    let b: Vec<f64> = (0..nc).map(|_| rand(&mut st)).collect();
    for transpose in [false, true] {
        let (mut xb, mut xd) = (b.clone(), b.clone());
        if transpose {
            band.newton_solve_transpose(&mut xb);
            dense.newton_solve_transpose(&mut xd);
        } else {
            band.newton_solve(&mut xb);
            dense.newton_solve(&mut xd);
        }
        let e = rel_flat(&xb, &xd);
        assert!(
            e <= 1e-12,
            "{case:?} transpose {transpose}: J solve {e:.1e}"
        );
    }
}

#[test]
fn band_solves_equal_the_dense_lu() {
    for case in cases() {
        if case.spatial {
            solves_equal_dense::<3>(case);
        } else {
            solves_equal_dense::<2>(case);
        }
    }
}

/// A RATTLE trajectory of `scene` over `D`, with the band path or (`dense`) the dense reference:
/// the states, and the Newton iterations of every step.
fn trajectory<D: Scalar, const DIM: usize>(
    chain: Chain<D, DIM>,
    scene: &Scene,
    dense: bool,
) -> (Vec<State<D, DIM>>, Vec<usize>) {
    DENSE_REFERENCE.with(|d| d.set(dense));
    let built = Rattle::new(chain, scene.time.step);
    DENSE_REFERENCE.with(|d| d.set(false));
    let mut rattle = built.unwrap();
    let mut state = rattle.straight_state();
    let (mut states, mut iterations) = (vec![state.clone()], Vec::new());
    for k in 0..scene.time.steps {
        let stats = rattle.step(&mut state, k, D::zero(), D::zero()).unwrap();
        iterations.push(stats.iterations);
        states.push(state.clone());
    }
    (states, iterations)
}

/// max over the steps of max |a − b|, over the trajectory's max |b|, and that max.
fn rel_steps<const DIM: usize>(a: &[Vec<[f64; DIM]>], b: &[Vec<[f64; DIM]>]) -> (f64, f64) {
    let (mut diff, mut scale): (f64, f64) = (0.0, 0.0);
    for (x, y) in a.iter().zip(b) {
        let (e, s) = rel(x, y);
        diff = diff.max(e * s.max(1e-300));
        scale = scale.max(s);
    }
    (diff / scale.max(1e-300), scale)
}

/// Whole trajectories (200 steps of 0.004 s from the straight beam under the point loads): the
/// band path = the dense reference to 1e-12 relative to the trajectory's size in q and in p
/// (every step), with the same Newton iterations at all but a few steps (at most 5 %); the beam moves (max |p| > 0.01).
fn trajectories_equal_dense<const DIM: usize>(case: Case) {
    let sc = scene(case, 200);
    let ch = Chain::<f64, DIM>::from_scene(&sc).unwrap();
    let (a, ia) = trajectory(ch.clone(), &sc, false);
    let (b, ib) = trajectory(ch, &sc, true);
    // Round-off decides the Newton count where the residual lands at the 1e-14 tolerance.
    let differ = ia.iter().zip(&ib).filter(|(x, y)| x != y).count();
    assert!(
        differ * 20 <= ia.len(),
        "{case:?}: Newton iterations {ia:?} vs {ib:?}"
    );
    let qs = |t: &[State<f64, DIM>]| t.iter().map(|s| s.q.clone()).collect::<Vec<_>>();
    let ps = |t: &[State<f64, DIM>]| t.iter().map(|s| s.p.clone()).collect::<Vec<_>>();
    let (eq, _) = rel_steps(&qs(&a), &qs(&b));
    let (ep, pmax) = rel_steps(&ps(&a), &ps(&b));
    assert!(eq <= 1e-12, "{case:?}: q {eq:.1e}");
    assert!(ep <= 1e-12, "{case:?}: p {ep:.1e}");
    assert!(pmax > 0.01, "{case:?}: the beam moves ({pmax})");
}

#[test]
fn trajectories_equal_the_dense_path() {
    for case in cases() {
        if case.spatial {
            trajectories_equal_dense::<3>(case);
        } else {
            trajectories_equal_dense::<2>(case);
        }
    }
}

/// Over Dual64 with the dampers' common value seeded, the trajectory's derivative parts (∂q/∂c,
/// ∂p/∂c) of the band path = those of the dense reference to 1e-12 relative (real parts as in
/// the f64 test), planar and spatial, with a drag in a current and a locked tip.
#[test]
fn dual_trajectories_equal_the_dense_path() {
    for spatial in [false, true] {
        let case = Case {
            n: 15,
            spatial,
            support: Support::FixedFixed,
            reaction: false,
            drag: true,
            uniform: true,
            seed: 5,
        };
        if spatial {
            dual_equal::<3>(case);
        } else {
            dual_equal::<2>(case);
        }
    }
}

fn dual_equal<const DIM: usize>(case: Case) {
    let sc = scene(case, 100);
    let mut ch = Chain::<f64, DIM>::from_scene(&sc).unwrap().lift::<Dual64>();
    let c = ch.joint_damping().unwrap().dampers()[1].re;
    ch.set_parameter(Parameter::JointDamping, Dual64::new(c, 1.0))
        .unwrap();
    let (a, _) = trajectory(ch.clone(), &sc, false);
    let (b, _) = trajectory(ch, &sc, true);
    let eps = |s: &State<Dual64, DIM>| -> Vec<[f64; DIM]> {
        s.q.iter().chain(&s.p).map(|x| x.map(|v| v.eps)).collect()
    };
    let (ea, eb): (Vec<_>, Vec<_>) = (a.iter().map(eps).collect(), b.iter().map(eps).collect());
    let (e, scale) = rel_steps(&ea, &eb);
    assert!(
        scale > 1e-6,
        "the dampers' derivative is exercised ({scale})"
    );
    assert!(e <= 1e-12, "{case:?}: derivative parts {e:.1e}");
}

/// The adjoint's reverse step through the band solves (Wᵀ = A⁻ᵀ, Jᵀ by the transposed augmented
/// system, bordered by the tip) with the tips tests/model/terms.rs does not cover: a locked tip and the
/// reaction-force tip (fixed-fixed, so that M₀ = 2k₁z₁/l₁² is not zero), planar and spatial, dampers beside a drag in a current. The gradient of
/// J = Σ M₀² along a direction of the per-step controls and with respect to the dampers' value
/// and the mass = forward-mode Dual64 of the same discrete map to 1e-12 relative.
#[test]
fn adjoint_with_tip_constraints_equals_dual_numbers() {
    for (support, reaction) in [(Support::FixedFixed, false), (Support::FixedFixed, true)] {
        adjoint_equals_dual::<2>(support, reaction);
        adjoint_equals_dual::<3>(support, reaction);
    }
}

fn adjoint_equals_dual<const DIM: usize>(support: Support, reaction: bool) {
    use crate::adjoint::{adjoint_gradient, forward_value};
    use crate::{BendingObjective, Checkpointing};
    let (n, steps) = (12, 60);
    let node = if reaction { n } else { n / 2 };
    let dir = if DIM == 3 { [0.6, 0.8] } else { [0.0, 1.0] };
    let sc = SceneBuilder::new(n)
        .support(support)
        .reaction_force(reaction)
        .length(0.8)
        .mass(0.7)
        .stiffness(800.0)
        .joint_damping(4.0)
        .drag(3.0)
        .current(Current::linear(0.8, 0.3, dir))
        .point_load(n / 3, 5.0)
        .control_per_step(node, vec![0.0; steps + 1])
        .step(0.004)
        .steps(steps)
        .build()
        .unwrap();
    let h = sc.time.step;
    let chain = Chain::<f64, DIM>::from_scene(&sc).unwrap();
    assert!(chain.has_tip_constraint());
    let u: Vec<f64> = (0..=steps)
        .map(|k| -4.0 + 3.0 * (0.37 * k as f64).sin())
        .collect();
    let obj = BendingObjective::summed_moment();
    let params = [
        (Parameter::JointDamping, 4.0),
        (Parameter::Mass, chain.masses()[0]),
    ];
    let ps: Vec<Parameter> = params.iter().map(|p| p.0).collect();
    let adj = adjoint_gradient(&chain, h, steps, &u, &obj, &ps, Checkpointing::default()).unwrap();
    let what = format!("DIM {DIM} {support:?} reaction {reaction}");
    let dir: Vec<f64> = (0..=steps).map(|k| (1.3 * k as f64).cos()).collect();
    let g_adj: f64 = adj
        .control_gradient
        .iter()
        .zip(&dir)
        .map(|(g, d)| g * d)
        .sum();
    let ud: Vec<Dual64> = u
        .iter()
        .zip(&dir)
        .map(|(&x, &d)| Dual64::new(x, d))
        .collect();
    let g_fwd = forward_value(&chain.lift::<Dual64>(), h, steps, &ud, &obj)
        .unwrap()
        .eps;
    assert!(g_fwd.abs() > 1e-8, "{what}: exercised");
    assert!(
        (g_adj - g_fwd).abs() <= 1e-12 * g_fwd.abs(),
        "{what}: controls"
    );
    let ud: Vec<Dual64> = u.iter().map(|&x| Dual64::from(x)).collect();
    for (i, &(p, at)) in params.iter().enumerate() {
        let mut ch = chain.lift::<Dual64>();
        ch.set_parameter(p, Dual64::new(at, 1.0)).unwrap();
        let fwd = forward_value(&ch, h, steps, &ud, &obj).unwrap().eps;
        let a = adj.parameter_gradient[i];
        assert!(fwd.abs() > 1e-10, "{what}: {p:?} exercised");
        assert!(
            (a - fwd).abs() <= 1e-12 * fwd.abs(),
            "{what}: {p:?} {a} vs {fwd}"
        );
    }
}
