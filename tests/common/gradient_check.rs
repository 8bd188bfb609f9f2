//! A physical parameter's derivative of J = c_sum checked three ways, shared by
//! `tests/model/current.rs`, `tests/model/loads.rs` and `tests/fatigue/wave_riser.rs`: the discrete adjoint against
//! forward-mode dual numbers through the same simulation (1e-12 relative, the exactness the
//! adjoint promises) and a five-point central difference against them (1e-6 relative).
#![allow(dead_code)]

use chainbeam::adjoint::{adjoint_gradient, forward_value};
use chainbeam::*;
use num_dual::Dual64;

/// The five-point central difference (8(f(x + d) − f(x − d)) − (f(x + 2d) − f(x − 2d)))/(12d):
/// truncation O(d⁴) for a smooth f.
pub fn five_point(f: &dyn Fn(f64) -> f64, x: f64, d: f64) -> f64 {
    (8.0 * (f(x + d) - f(x - d)) - (f(x + 2.0 * d) - f(x - 2.0 * d))) / (12.0 * d)
}

/// Asserts one derivative dJ/d`label`: it acts (|fwd| > 1e-8), the adjoint's `adjoint` equals
/// forward-mode Dual64's `fwd` to 1e-12 and the central difference `fd` equals it to 1e-6
/// (relative).
pub fn assert_derivative(label: &str, adjoint: f64, fwd: f64, fd: f64) {
    println!(
        "dJ/d{label} = {fwd:.12e}: |adjoint − forward| {:.1e}, |FD − forward| {:.1e} (relative)",
        (adjoint - fwd).abs() / fwd.abs(),
        (fd - fwd).abs() / fwd.abs()
    );
    assert!(fwd.abs() > 1e-8, "{label} is exercised");
    assert!(
        (adjoint - fwd).abs() <= 1e-12 * fwd.abs(),
        "{label}: {adjoint} vs {fwd}"
    );
    assert!(
        (fd - fwd).abs() <= 1e-6 * fwd.abs(),
        "{label}: FD {fd} vs {fwd}"
    );
}

/// dJ/dθ for every (θ, value) of `params` on `chain` (J = c_sum of `steps` steps of `h` under the
/// controls `u`): the adjoint (`adjoint_gradient`) against forward-mode Dual64 with θ seeded and
/// against [`five_point`] with the step `fd_step(value)`, by [`assert_derivative`].
pub fn check_parameters<const DIM: usize>(
    chain: &Chain<f64, DIM>,
    u: &[f64],
    params: &[(Parameter, f64)],
    (h, steps): (f64, usize),
    fd_step: impl Fn(f64) -> f64,
) {
    let obj = BendingObjective::summed_moment();
    let ps: Vec<Parameter> = params.iter().map(|p| p.0).collect();
    let adjoint = adjoint_gradient(chain, h, steps, u, &obj, &ps, Checkpointing::default())
        .unwrap()
        .parameter_gradient;
    let ud: Vec<Dual64> = u.iter().map(|&x| Dual64::from(x)).collect();
    for (i, &(p, value)) in params.iter().enumerate() {
        let mut ch = chain.lift::<Dual64>();
        ch.set_parameter(p, Dual64::new(value, 1.0)).unwrap();
        let fwd = forward_value(&ch, h, steps, &ud, &obj).unwrap().eps;
        let at = |v: f64| {
            let mut ch = chain.clone();
            ch.set_parameter(p, v).unwrap();
            forward_value(&ch, h, steps, u, &obj).unwrap()
        };
        let fd = five_point(&at, value, fd_step(value));
        println!("DIM {DIM}:");
        assert_derivative(&format!("{p:?}"), adjoint[i], fwd, fd);
    }
}
