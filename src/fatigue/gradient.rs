//! The rainflow damage as a differentiable function of the stress history, and its smooth proxy
//! (docs/fatigue.md, "Fatigue as an objective").
//!
//! **Rainflow damage.** For a fixed pairing of turning points the damage is
//!
//! D(σ) = Σ_c n_c · d(|σ_{e(c)} − σ_{s(c)}|),
//!
//! n_c ∈ {1, ½} the count, s(c) < e(c) the indices of the cycle's turning points and d the S-N
//! curve's damage per cycle ([`SnCurve::cycle_damage`]). It depends on the turning points only,
//! so its gradient
//!
//! ∂D/∂σ_k = Σ_{c: e(c)=k} n_c d′(Δσ_c) sgn(σ_k − σ_{s(c)}) + Σ_{c: s(c)=k} n_c d′(Δσ_c) sgn(σ_k − σ_{e(c)})
//!
//! is non-zero at turning points only ([`damage_gradient`]). A small perturbation keeps the
//! pairing as long as no two compared ranges tie (X = Y in the three-point rule), no sample
//! ties with its neighbour and no range crosses the knee; there D is smooth and this is its
//! exact gradient.
//!
//! **At a change of pairing** (a tie X = Y, a new turning point appearing, a range crossing the
//! S-N knee) D stays continuous — the rainflow pairs on either side of a tie have the same
//! ranges in the limit, a new turning point brings a cycle of zero range, and the S-N curve is
//! continuous at the knee ([`SnCurve`]) — but its gradient jumps: [`damage_gradient`] returns
//! the gradient of the pairing the count found at σ, i.e. one of the one-sided gradients, and
//! at the knee the governing segment's (the m₁ segment's at Δσ ≥ Δσ*). An optimiser may see a
//! kink there; the tests check both sides of a tie (tests/fatigue/fatigue.rs).
//!
//! **Smooth proxy.** J_m = Σ_k |σ_k|^m with ∂J_m/∂σ_k = m |σ_k|^(m−1) sgn σ_k, m the S-N
//! curve's first slope; as a least-squares sum J_m = Σ_k r_k², r_k = |σ_k|^(m/2).
//!
//! **Chain to the moment.** σ_k = c · M₀(t_k) ([`super::HotSpot::stress_per_moment`]), so an
//! objective built on D receives ∂D/∂M₀(t_k) = c · ∂D/∂σ_k (in a spatial scene, at the point θ:
//! ∂D/∂M₀ₓ = c sin θ ∂D/∂σ_k, ∂D/∂M₀_z = c cos θ ∂D/∂σ_k) per time step, which is what the
//! adjoint takes as the objective's derivative with respect to the moment at step k.

use crate::base::Scalar;

use super::rainflow::{rainflow_visit, Cycle, RainflowWorkspace};
use super::sn::SnCurve;
use super::stress::check_len;
use super::FatigueError;

/// The rainflow damage D(σ) and its gradient ∂D/∂σ_k (the module's docs), written into
/// `gradient` (same length as `stress`, overwritten). Allocation-free once `workspace` is warm;
/// O(N).
///
/// # Errors
/// [`FatigueError::LengthMismatch`] if the lengths differ, [`FatigueError::NonFinite`] at the
/// first non-finite stress.
pub fn damage_gradient(
    stress: &[f64],
    curve: &SnCurve,
    workspace: &mut RainflowWorkspace,
    gradient: &mut [f64],
) -> Result<f64, FatigueError> {
    check_len("gradient", stress.len(), gradient.len())?;
    gradient.fill(0.0);
    let mut damage = 0.0;
    rainflow_visit(stress.iter().copied(), workspace, |c| {
        damage += c.count * curve.cycle_damage(c.range);
        let slope = c.count * curve.cycle_damage_derivative(c.range);
        // Δσ = |σ_e − σ_s|: ∂Δσ/∂σ_e = sgn(σ_e − σ_s) = −∂Δσ/∂σ_s.
        let sign = if stress[c.end] >= stress[c.start] {
            1.0
        } else {
            -1.0
        };
        gradient[c.end] += slope * sign;
        gradient[c.start] -= slope * sign;
    })?;
    Ok(damage)
}

/// D(σ) = Σ_c n_c d(|σ_{e(c)} − σ_{s(c)}|) for a given pairing `cycles` (from a count of the same
/// series), in any scalar: with dual numbers it gives the derivative of the damage with the
/// pairing held fixed, which equals [`damage_gradient`] away from pairing changes.
///
/// # Errors
/// [`FatigueError::LengthMismatch`] (naming `cycles`) if a cycle's index is outside `stress`.
pub fn pairing_damage<D: Scalar>(
    stress: &[D],
    cycles: &[Cycle],
    curve: &SnCurve,
) -> Result<D, FatigueError> {
    let mut damage = D::from(0.0);
    for c in cycles {
        if c.end >= stress.len() {
            return Err(FatigueError::LengthMismatch {
                what: "cycles",
                expected: stress.len(),
                got: c.end + 1,
            });
        }
        let range = (stress[c.end] - stress[c.start]).abs();
        damage += curve.cycle_damage(range) * c.count;
    }
    Ok(damage)
}

/// The smooth proxy J_m = Σ_k |σ_k|^m (the module's docs), in any scalar.
pub fn power_objective<D: Scalar>(stress: &[D], m: f64) -> D {
    stress
        .iter()
        .map(|&s| {
            if s.re() == 0.0 {
                s * 0.0
            } else {
                s.abs().powf(m)
            }
        })
        .fold(D::from(0.0), |a, b| a + b)
}

/// J_m and its gradient ∂J_m/∂σ_k = m |σ_k|^(m−1) sgn σ_k (written into `gradient`).
///
/// # Errors
/// [`FatigueError::LengthMismatch`] if the lengths differ.
pub fn power_gradient(stress: &[f64], m: f64, gradient: &mut [f64]) -> Result<f64, FatigueError> {
    check_len("gradient", stress.len(), gradient.len())?;
    let mut j = 0.0;
    for (g, &s) in gradient.iter_mut().zip(stress) {
        let a = s.abs();
        j += a.powf(m);
        *g = if a == 0.0 {
            0.0
        } else {
            m * a.powf(m - 1.0) * s.signum()
        };
    }
    Ok(j)
}
