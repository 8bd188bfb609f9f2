//! The `f64` RATTLE step of a chain with Morison's drag node by node runs fused passes (the
//! plant's hot loop: `NodeDrag::half_step_iterate`, `NodeDrag::kick_in` and the fused bordered
//! tridiagonal solves of `src/steppers/fused.rs`), which must give the separate passes' values
//! bit for bit.
//!
//! Reference: the same chain over `Dual64` with nothing seeded. A dual step takes the separate
//! passes (the fused ones are `f64` only), and its real parts are the `f64` arithmetic's bit for
//! bit: the dual operations' real parts are the `f64` operations, the Newton matrix and the
//! projection are factorised from the real parts in `f64` (`tridiag`'s first-order path), and
//! the derivative-only Newton update after convergence has a real part of exactly 0
//! (`steppers::rattle`). So every q, p, λ and μ of the two runs is compared with `to_bits`, step
//! by step, with the tip row (the vessel's prescribed top) and without it (the free top of
//! riser_300m.toml's pipe, its drag switched to Morison's), waves and current on.

use chainbeam::{Chain, Rattle, Scene, State};
use num_dual::Dual64;

/// Runs both and returns the `f64` run's Newton updates and its steps that took none.
fn run_both(scene: &Scene, steps: usize) -> (usize, usize) {
    let chain = Chain::<f64, 2>::from_scene(scene).unwrap();
    assert!(chain.node_drag().is_some(), "the scene has the node drag");
    let dual = chain.lift::<Dual64>();
    let h = scene.time.step;
    let mut plain = Rattle::new(chain, h).unwrap();
    let mut reference = Rattle::new(dual, h).unwrap();
    let mut s = State::<f64, 2>::straight(scene.n());
    let mut r = State::<Dual64, 2>::straight(scene.n());
    plain.prepare(&mut s, 0, 0.0).unwrap();
    reference.prepare(&mut r, 0, Dual64::from(0.0)).unwrap();
    let zero = Dual64::from(0.0);
    let bits = |x: &[[f64; 2]]| -> Vec<u64> { x.iter().flatten().map(|v| v.to_bits()).collect() };
    let re_bits =
        |x: &[[Dual64; 2]]| -> Vec<u64> { x.iter().flatten().map(|v| v.re.to_bits()).collect() };
    let scalar = |x: &[f64]| -> Vec<u64> { x.iter().map(|v| v.to_bits()).collect() };
    let re_scalar = |x: &[Dual64]| -> Vec<u64> { x.iter().map(|v| v.re.to_bits()).collect() };
    let (mut iterations, mut without_update) = (0, 0);
    for k in 0..steps {
        let a = plain.step(&mut s, k, 0.0, 0.0).unwrap();
        let b = reference.step(&mut r, k, zero, zero).unwrap();
        iterations += a.iterations;
        without_update += usize::from(a.iterations == 0);
        // The dual run's count includes its derivative-only update.
        assert_eq!(
            a.iterations + 1,
            b.iterations,
            "Newton iterations at step {k}"
        );
        assert_eq!(bits(&s.q), re_bits(&r.q), "q at step {k}");
        assert_eq!(bits(&s.p), re_bits(&r.p), "p at step {k}");
        let (ms, mr) = (
            s.multipliers.as_ref().unwrap(),
            r.multipliers.as_ref().unwrap(),
        );
        assert_eq!(scalar(&ms.lambda), re_scalar(&mr.lambda), "λ at step {k}");
        assert_eq!(scalar(&ms.mu), re_scalar(&mr.mu), "μ at step {k}");
        assert_eq!(
            scalar(&ms.gaps),
            re_scalar(&mr.gaps),
            "the gaps at step {k}"
        );
    }
    eprintln!("{steps} steps, {iterations} Newton iterations, {without_update} steps without one");
    (iterations, without_update)
}

/// The riser system held by its vessel (the tip row): the first 250 steps (1 s: the vessel's
/// ramp, the waves and the current acting on a chain that starts straight).
#[test]
fn riser_system_step_equals_the_separate_passes_bit_for_bit() {
    let scene = Scene::from_file(crate::common::scene("riser_300m_system.toml")).unwrap();
    let (iterations, without_update) = run_both(&scene, 250);
    // Both exits of the Newton loop were compared: steps that took an update, and steps whose
    // extrapolated predictor met the tolerance at once (measured when written: 247 and 3).
    assert!(iterations > 0, "Newton updated: {iterations} iterations");
    assert!(without_update > 0, "a step converged at its predictor");
}

/// riser_300m.toml's free-top pipe (no tip row) with Morison's drag node by node, 30
/// pendulums, 200 steps of its 0.0125 s (its extrapolated predictor misses the tolerance
/// at this coarse step: every step takes an update).
#[test]
fn free_top_pipe_step_equals_the_separate_passes_bit_for_bit() {
    let text = std::fs::read_to_string(crate::common::scene("riser_300m.toml")).unwrap();
    let text = text
        .replace("pendulums = 80", "pendulums = 30")
        .replace(
            "added_mass_coefficient = 1.0",
            "added_mass_coefficient = 1.0\ndrag_model = \"morison\"",
        )
        .replace("drag = 4.0020e-7 ", "drag = 0.0 ");
    let text = text.split("[mpc]").next().unwrap();
    let scene = Scene::from_toml_str(text).unwrap();
    let (iterations, _) = run_both(&scene, 200);
    assert!(iterations > 0, "Newton updated: {iterations} iterations");
}

/// The Newton iterations of the plant's step over a 60 s record of riser_300m_system.toml
/// (15 000 steps of h = 0.004 s from the straight chain at rest, the vessel's ramp, waves and
/// current on): the `StepStats` count of every step (the Newton updates; each step also
/// evaluates the half step once more than it updates). With the predictor μ_{k−1} alone every
/// step took exactly one update (15 000 of 15 000 when this test was first written, and
/// docs/benchmarks.md); the chain's predictor now adds the extrapolated gap 2γ_k − γ_{k−1}
/// ([`chainbeam::Multipliers::gaps`]), which meets the tolerance 1e-14 at once on some steps
/// and never needs more than the one update (measured when written: 13 434 updates, 1 566 steps
/// without one, mean 0.896; over 600 s 0.607 and over the 3-hour record 0.515 per step, as
/// the start-up's transient fades).
#[test]
fn riser_system_step_takes_at_most_one_newton_update_over_60_s() {
    let scene = Scene::from_file(crate::common::scene("riser_300m_system.toml")).unwrap();
    let chain = Chain::<f64, 2>::from_scene(&scene).unwrap();
    let mut rattle = Rattle::new(chain, scene.time.step).unwrap();
    let mut s = State::<f64, 2>::straight(scene.n());
    rattle.prepare(&mut s, 0, 0.0).unwrap();
    let steps = 15_000;
    let mut histogram = [0usize; 4];
    let (mut total, mut max) = (0usize, 0usize);
    for k in 0..steps {
        let it = rattle.step(&mut s, k, 0.0, 0.0).unwrap().iterations;
        total += it;
        max = max.max(it);
        histogram[it.min(3)] += 1;
    }
    eprintln!(
        "{steps} steps: {total} Newton updates, mean {:.4}, max {max}, steps with 0/1/2/3+: {histogram:?}",
        total as f64 / steps as f64
    );
    assert_eq!(max, 1, "steps by update count: {histogram:?}");
    assert!(
        total < steps,
        "the predictor saved no update: {histogram:?}"
    );
}
