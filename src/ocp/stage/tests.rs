//! Tests of the stage Jacobians ([`super::JacobianWorkspace`]).
use super::*;
use crate::catalogue;

/// The implicit function theorem (the dual step started at the nominal's converged λ: one
/// derivative-only Newton update, ∂λ/∂θ = −R_λ⁻¹ R_θ) against dual numbers carried through
/// the whole Newton iteration from the predictor μ (derivative parts iterated to
/// convergence): the same A_k and B_k to round-off, on the long-horizon scene (drag) at a
/// moving state.
#[test]
fn ift_jacobians_equal_iterated_dual_newton() {
    let scene = catalogue::long_horizon();
    let chain = Chain::<f64, 2>::from_scene(&scene).unwrap();
    let model = StageModel::new(&chain, scene.time.step).unwrap();
    let k = 20;
    let fixture::Point {
        q,
        p,
        omega,
        mu,
        lambda,
        u,
    } = fixture::point(&model, k);
    // The predictor μ is not the converged λ: the second run iterates.
    assert!(lambda
        .iter()
        .zip(&mu)
        .any(|(l, m)| (l - m).abs() > 1e-9 * l.abs()));
    let nx = model.nx();
    let mut ws = JacobianWorkspace::new(&model).unwrap();
    let (mut a1, mut b1) = (vec![0.0; nx * nx], vec![0.0; nx]);
    let (mut a2, mut b2) = (a1.clone(), b1.clone());
    let at = |mu| StageAt {
        model: &model,
        k,
        x: StagePoint {
            q: &q,
            p: &p,
            omega: &omega,
            mu,
        },
        u,
        ux: 0.0,
    };
    let out = |a, b| JacobiansMut { a, b };
    ws.jacobians(at(&lambda), out(&mut a1, &mut b1)).unwrap();
    ws.jacobians(at(&mu), out(&mut a2, &mut b2)).unwrap();
    let rel = |x: &[f64], y: &[f64]| {
        let scale = y.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        x.iter()
            .zip(y)
            .fold(0.0f64, |m, (a, b)| m.max((a - b).abs()))
            / scale
    };
    assert!(rel(&a1, &a2) <= 1e-12, "A: {:e}", rel(&a1, &a2));
    assert!(rel(&b1, &b2) <= 1e-12, "B: {:e}", rel(&b1, &b2));
}
