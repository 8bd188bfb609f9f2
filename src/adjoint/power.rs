//! The power objective J = Σ_{k=0}^{N} |M₀(t_k)|^p (+ ρh Σ |u_k|²), p ≥ 2: c_sum (eq. 3.3.4)
//! for p = 2, and for p = m the smooth fatigue proxy Σ|σ_k|^m of an S-N curve of slope m
//! (Miner's rule on the stress amplitudes, issue "wellhead fatigue"), up to the constant factor
//! of σ = M₀/Z.

use super::objective::{GaussNewton, MomentStage, Objective, Stage};
use crate::base::Scalar;
use crate::scene::{ObjectiveKind, SceneError};

/// Σ_{k=0}^{N} |M₀(t_k)|^p + ρ h Σ_{k=0}^{N} |u_k|², with |M₀| the norm of the base moment vector
/// (M₀ₓ, M₀_z) (|M₀_z| in the planar model) and p ≥ 2 (scene `[objective] kind = "power",
/// exponent = p`). With p = 2 every value and derivative is c_sum's
/// ([`BendingObjective::summed_moment`](crate::BendingObjective::summed_moment)) bit for bit:
/// the stage cost is then the same expression M₀_z² + M₀ₓ².
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PowerObjective {
    /// The exponent p (finite, ≥ 2).
    pub exponent: f64,
    /// ρ ≥ 0 of the control-effort penalty ρ h Σ |u_k|².
    pub effort: f64,
}

impl PowerObjective {
    /// Σ|M₀(t_k)|^p without effort penalty.
    ///
    /// # Errors
    /// [`SceneError`] naming `objective.exponent` ([`crate::SceneErrorKind::InvalidValue`]) for
    /// p < 2 or a non-finite p.
    pub fn new(exponent: f64) -> Result<Self, SceneError> {
        ObjectiveKind::Power { exponent }.check()?;
        Ok(PowerObjective {
            exponent,
            effort: 0.0,
        })
    }

    /// Adds the effort penalty ρ h Σ |u_k|².
    pub fn with_effort(mut self, rho: f64) -> Self {
        self.effort = rho;
        self
    }
}

/// Below this |M₀|² (the smallest normal f64) the stage's |M₀|^p, p > 2, and its first and
/// second derivatives are taken as 0: exact at M₀ = 0 (the straight beam at rest of t₀), and
/// below 10⁻³⁰⁰ N·m otherwise; dual numbers of x^p at x = 0 would give 0·∞ = NaN.
const TINY: f64 = f64::MIN_POSITIVE;

/// x^a for x = |y| ≥ 0 (a dual number: abs is differentiable away from 0), `a ≥ 1`: x itself
/// for a = 1; 0 with vanishing derivatives for x² below [`TINY`] and a > 1 (then x^a's first
/// derivative vanishes at 0, and so does x^a·(x^a)'' for a > ½).
// Exact comparisons: a = 1 and p = 2 are the exponents whose results are defined bit for bit
// (x itself, c_sum's M₀_z² + M₀ₓ²), not approximations.
#[allow(clippy::float_cmp)]
fn pow_abs<D: Scalar>(x: D, a: f64) -> D {
    if a == 1.0 {
        x
    } else if x.re() * x.re() < TINY {
        x * 0.0
    } else {
        x.powf(a)
    }
}

impl Objective for PowerObjective {
    #[allow(clippy::float_cmp)]
    /// |M₀(t_k)|^p + ρh|u_k|², with |M₀|² = M₀_z² + M₀ₓ² (for p = 2 that sum itself).
    fn stage<D: Scalar>(&self, s: Stage<'_, D>) -> D {
        let m2 = s.moment * s.moment + s.moment_x * s.moment_x;
        let m = if self.exponent == 2.0 {
            m2
        } else if m2.re() < TINY {
            m2 * 0.0
        } else {
            m2.sqrt().powf(self.exponent)
        };
        if self.effort > 0.0 {
            let u2 = s.control * s.control + s.control_x * s.control_x;
            m + u2 * (self.effort * s.h)
        } else {
            m
        }
    }

    /// w_k = 2, r_k = sgn(M₀)|M₀|^{p/2} (increasing in M₀), e_k = ρh: ½ w r² = |M₀|^p, and at
    /// p = 2 r = M₀, r′ = 1, r″ = 0 bit for bit, c_sum's form (so also the condensed solver's
    /// secant term Σ w r (∇r₊ − ∇r), which |M₀|^{p/2} would flip with the sign of M₀). The
    /// Gauss-Newton curvature w r′² = (p²/2)|M₀|^{p−2} is below the exact p(p − 1)|M₀|^{p−2} for
    /// p > 2; the Riccati solver's exact phase adds the difference w r r″.
    fn gauss_newton<D: Scalar>(&self, s: MomentStage<D>) -> Option<GaussNewton<D>> {
        let sign = if s.moment.re().is_sign_negative() {
            -1.0
        } else {
            1.0
        };
        Some(GaussNewton {
            weight: 2.0,
            residual: pow_abs(s.moment.abs(), 0.5 * self.exponent) * sign,
            effort: self.effort * s.h,
        })
    }
}
