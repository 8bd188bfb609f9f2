//! The one gradient check of the tests: a derivative against its reference (forward-mode dual
//! numbers through the same simulation, a central difference, or a closed form), component by
//! component, within a stated tolerance, reporting the worst component and where its reference
//! comes from. Used by the adjoint, verification, current, load and wave tests.
//!
//! Also the physical-parameter check of a J = c_sum run shared by `tests/model/current.rs`,
//! `tests/model/loads.rs` and `tests/fatigue/wave_riser.rs`: the discrete adjoint against
//! forward-mode dual numbers (1e-12 relative, the exactness the adjoint promises) and a
//! five-point central difference against them (1e-6 relative).
#![allow(dead_code)]

use chainbeam::adjoint::{adjoint_gradient, forward_value};
use chainbeam::*;
use num_dual::Dual64;

/// The central difference (f(x + d) − f(x − d))/(2d): truncation O(d²) for a smooth f.
pub fn central(f: &dyn Fn(f64) -> f64, x: f64, d: f64) -> f64 {
    (f(x + d) - f(x - d)) / (2.0 * d)
}

/// The central differences of f in each component of x, step `d`: the gradient's reference for
/// a function of several parameters.
pub fn central_gradient(f: &dyn Fn(&[f64]) -> f64, x: &[f64], d: f64) -> Vec<f64> {
    (0..x.len())
        .map(|i| {
            let at = |t: f64| {
                let mut y = x.to_vec();
                y[i] = t;
                f(&y)
            };
            central(&at, x[i], d)
        })
        .collect()
}

/// The five-point central difference (8(f(x + d) − f(x − d)) − (f(x + 2d) − f(x − 2d)))/(12d):
/// truncation O(d⁴) for a smooth f.
pub fn five_point(f: &dyn Fn(f64) -> f64, x: f64, d: f64) -> f64 {
    (8.0 * (f(x + d) - f(x - d)) - (f(x + 2.0 * d) - f(x - 2.0 * d))) / (12.0 * d)
}

/// What a component's error is measured against.
#[derive(Clone, Copy, Debug)]
pub enum Scale {
    /// |reference_i|: relative to the component itself.
    Component,
    /// A fixed scale, such as the gradient's largest component max_k |g_k|.
    Fixed(f64),
    /// max(|reference_i|, s): relative to the component, but never to less than s.
    AtLeast(f64),
}

/// A component passes when |got_i − reference_i| ≤ `rel` · scale_i + `abs`, scale_i by [`Scale`].
#[derive(Clone, Copy, Debug)]
pub struct Tolerance {
    pub rel: f64,
    pub scale: Scale,
    pub abs: f64,
}

impl Tolerance {
    /// `rel` relative to each component.
    pub fn relative(rel: f64) -> Self {
        Tolerance {
            rel,
            scale: Scale::Component,
            abs: 0.0,
        }
    }

    /// `rel` of the fixed scale `s`.
    pub fn of_scale(rel: f64, s: f64) -> Self {
        Tolerance {
            rel,
            scale: Scale::Fixed(s),
            abs: 0.0,
        }
    }

    /// `rel` of max(|reference_i|, `s`).
    pub fn at_least(rel: f64, s: f64) -> Self {
        Tolerance {
            rel,
            scale: Scale::AtLeast(s),
            abs: 0.0,
        }
    }

    /// The same with an absolute floor `abs` added to the bound.
    pub fn plus(self, abs: f64) -> Self {
        Tolerance { abs, ..self }
    }

    fn scale_of(&self, reference: f64) -> f64 {
        match self.scale {
            Scale::Component => reference.abs(),
            Scale::Fixed(s) => s,
            Scale::AtLeast(s) => reference.abs().max(s),
        }
    }
}

/// Asserts every component of `got` within `tol` of `reference` (same length); `source` says
/// where the reference comes from ("forward-mode Dual64", "central difference, step 1e-5 θ",
/// ...). A failure names `label`, the worst component (by error over its bound), both values,
/// the error and the bound. Returns the worst error in units of its scale (|e_i| / scale_i), the
/// number the tests print next to their tolerance. A non-finite value or error fails.
pub fn assert_close(
    label: &str,
    got: &[f64],
    reference: &[f64],
    source: &str,
    tol: Tolerance,
) -> f64 {
    assert_eq!(
        got.len(),
        reference.len(),
        "{label}: {} components against {} of the reference ({source})",
        got.len(),
        reference.len()
    );
    let mut worst_scaled = 0.0f64;
    // (index, error / bound); a NaN error counts as infinitely far.
    let mut worst: Option<(usize, f64)> = None;
    for (i, (&g, &r)) in got.iter().zip(reference).enumerate() {
        let e = (g - r).abs();
        let scale = tol.scale_of(r);
        let bound = tol.rel * scale + tol.abs;
        let ratio = if e <= bound {
            if bound > 0.0 {
                e / bound
            } else {
                0.0
            }
        } else if e.is_nan() || bound.is_nan() {
            f64::INFINITY
        } else {
            // over the bound (also when the bound is 0): at least 1.
            (e / bound).max(1.0 + f64::EPSILON)
        };
        if worst.is_none_or(|(_, w)| ratio > w) {
            worst = Some((i, ratio));
        }
        worst_scaled = worst_scaled.max(e / scale.max(f64::MIN_POSITIVE));
    }
    if let Some((i, ratio)) = worst {
        let (g, r) = (got[i], reference[i]);
        let e = (g - r).abs();
        let bound = tol.rel * tol.scale_of(r) + tol.abs;
        assert!(
            ratio <= 1.0,
            "{label}: worst component {i} of {}: {g:e} vs {r:e} ({source}): |difference| {e:.2e} > \
             bound {bound:.2e} ({tol:?})",
            got.len()
        );
    }
    worst_scaled
}

/// Asserts one derivative dJ/d`label`: it acts (|fwd| > 1e-8), the adjoint's `adjoint` equals
/// forward-mode Dual64's `fwd` to 1e-12 and the central difference `fd` equals it to 1e-6
/// (relative), by [`assert_close`].
pub fn assert_derivative(label: &str, adjoint: f64, fwd: f64, fd: f64) {
    println!(
        "dJ/d{label} = {fwd:.12e}: |adjoint − forward| {:.1e}, |FD − forward| {:.1e} (relative)",
        (adjoint - fwd).abs() / fwd.abs(),
        (fd - fwd).abs() / fwd.abs()
    );
    assert!(fwd.abs() > 1e-8, "{label} is exercised");
    let label = format!("dJ/d{label}");
    assert_close(
        &format!("{label}, adjoint"),
        &[adjoint],
        &[fwd],
        "forward-mode Dual64",
        Tolerance::relative(1e-12),
    );
    assert_close(
        &format!("{label}, five-point central difference"),
        &[fd],
        &[fwd],
        "forward-mode Dual64",
        Tolerance::relative(1e-6),
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

/// The nominal value at which the adjoint tests seed a physical parameter (the thesis riser's
/// springs and mass, the scene's drag, a 2 N load): forward mode reads J's derivative there.
pub fn nominal_parameter(p: Parameter, drag: f64) -> f64 {
    match p {
        Parameter::InteriorStiffness => 1000.0,
        Parameter::BaseStiffness | Parameter::TipStiffness => 2000.0,
        Parameter::Mass => 1.0,
        Parameter::Drag => drag,
        Parameter::LoadForce(_) => 2.0,
        other => panic!("no nominal value for {other:?} (not among the parameters tested here)"),
    }
}

/// dJ/dp for each of `params` by forward-mode dual numbers, the reference of an adjoint's
/// `parameter_gradient`: a copy of the problem's chain lifted to Dual64 with p seeded (ε = 1) at
/// [`nominal_parameter`], run over the problem's horizon of step `h` with the controls of θ; J's
/// ε part.
pub fn forward_parameter_gradient<O: chainbeam::adjoint::Objective + Clone>(
    prob: &ControlProblem<Parametrisation, O>,
    theta: &[f64],
    params: &[Parameter],
    drag: f64,
    h: f64,
    objective: &O,
) -> Vec<f64> {
    let u: Vec<Dual64> = prob
        .controls(theta)
        .unwrap()
        .into_iter()
        .map(Dual64::from)
        .collect();
    params
        .iter()
        .map(|&p| {
            let mut ch = prob.chain_as::<Dual64>();
            ch.set_parameter(p, Dual64::new(nominal_parameter(p, drag), 1.0))
                .unwrap();
            forward_value(&ch, h, prob.steps(), &u, objective)
                .unwrap()
                .eps
        })
        .collect()
}
