//! The force bound |θᵢ| ≤ b as a sine reparametrisation θ = b sin(φ/b) (module docs of
//! [`optimize`](super), "Bounded controls"), and the first-order (KKT) measure at a bounded
//! result.

use crate::error::{Error, Result};

/// A start closer than this fraction of the bound to ±b is moved this far inside (the bound is
/// a stationary point of the sine reparametrisation).
pub(crate) const BOUND_PULL_IN: f64 = 1e-4;

/// A component within this fraction of b of ±b counts as on the bound (for
/// [`OptimResult::active_bounds`](super::OptimResult::active_bounds) and the projected
/// gradient).
pub const ACTIVE_BOUND_TOL: f64 = 1e-6;

/// Checks a bound b: positive and finite.
pub(crate) fn check_bound(bound: Option<f64>) -> Result<()> {
    match bound {
        Some(b) if !(b.is_finite() && b > 0.0) => Err(Error::InvalidArgument {
            name: "bound",
            reason: format!("must be positive and finite, got {b}"),
        }),
        _ => Ok(()),
    }
}

/// θ = b sin(φ/b) componentwise (θ = φ without a bound).
pub(crate) fn to_theta(bound: Option<f64>, phi: &[f64]) -> Vec<f64> {
    match bound {
        None => phi.to_vec(),
        Some(b) => phi.iter().map(|&p| b * (p / b).sin()).collect(),
    }
}

/// φ = b asin(θ/b): an error if θ is not finite or outside the bound; components closer than
/// [`BOUND_PULL_IN`]·b to the bound are moved that far inside.
pub(crate) fn to_phi(bound: Option<f64>, theta: &[f64]) -> Result<Vec<f64>> {
    if let Some(i) = theta.iter().position(|x| !x.is_finite()) {
        return Err(Error::InvalidArgument {
            name: "theta0",
            reason: format!("entry {i} is not finite"),
        });
    }
    match bound {
        None => Ok(theta.to_vec()),
        Some(b) => theta
            .iter()
            .enumerate()
            .map(|(i, &t)| {
                if t.abs() > b {
                    return Err(Error::InvalidArgument {
                        name: "theta0",
                        reason: format!(
                            "entry {i} = {t} lies outside the force bound ±{b} (infeasible start)"
                        ),
                    });
                }
                let lim = b * (1.0 - BOUND_PULL_IN);
                Ok(b * (t.clamp(-lim, lim) / b).asin())
            })
            .collect(),
    }
}

/// g_φ = cos(φ/b) ⊙ g_θ (g_θ itself without a bound).
pub(crate) fn grad_phi(bound: Option<f64>, phi: &[f64], grad_theta: &[f64]) -> Vec<f64> {
    match bound {
        None => grad_theta.to_vec(),
        Some(b) => phi
            .iter()
            .zip(grad_theta)
            .map(|(&p, &g)| (p / b).cos() * g)
            .collect(),
    }
}

/// The chain rule of the Hessian under the bound, H_φ v = J ⊙ H_θ (J ⊙ v) + c ⊙ v, as the
/// vectors (J, c) = (cos(φ/b), −g_θ ⊙ θ / b²); `None` without a bound.
pub(crate) fn hessian_chain(
    bound: Option<f64>,
    phi: &[f64],
    theta: &[f64],
    grad_theta: &[f64],
) -> Option<(Vec<f64>, Vec<f64>)> {
    let b = bound?;
    let jac = phi.iter().map(|&x| (x / b).cos()).collect();
    let curv = theta
        .iter()
        .zip(grad_theta)
        .map(|(&t, &g)| -g * t / (b * b))
        .collect();
    Some((jac, curv))
}

/// The projected gradient norm and the active bounds at θ.
pub(crate) fn kkt(theta: &[f64], g: &[f64], bound: Option<f64>) -> (f64, Vec<usize>) {
    let Some(b) = bound else {
        return (super::norm(g), Vec::new());
    };
    let lim = b * (1.0 - ACTIVE_BOUND_TOL);
    let mut active = Vec::new();
    let mut s = 0.0;
    for (i, (&t, &gi)) in theta.iter().zip(g).enumerate() {
        let upper = t >= lim;
        let lower = t <= -lim;
        if upper || lower {
            active.push(i);
        }
        // At the upper bound descent (−g) is blocked when g < 0; at the lower when g > 0.
        if !((upper && gi < 0.0) || (lower && gi > 0.0)) {
            s += gi * gi;
        }
    }
    (s.sqrt(), active)
}
