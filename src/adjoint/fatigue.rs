//! The fatigue objective (docs/fatigue.md, "Fatigue as an objective"): the rainflow Miner
//! damage D(θ) of the
//! wellhead stress, J = D(M₀(t_0), …, M₀(t_N)) + ρ h Σ |u_k|², scene `[objective] kind =
//! "fatigue"` with the scene's `[fatigue]` table.

use super::objective::{History, Objective, Stage};
use crate::base::Scalar;
use crate::error::Result;
use crate::fatigue::{DamageGradient, WellheadDamage};

/// J = D + ρ h Σ_{k=0}^{N} |u_k|², D the rainflow damage of the wellhead stress over the run
/// ([`WellheadDamage`]: σ_k = SCF · M_w(t_k) · (D_o/2)/I with M_w = M₀ · l₁/2, rainflow per ASTM
/// E1049-85, Miner's sum on the DNV-RP-C203 curve; at the worst circumference point in the
/// spatial model). D is the `damage` `chainbeam fatigue` reports for the same trajectory, bit for
/// bit.
///
/// D is not a sum of stage costs: it is the objective's history term ([`Objective::history`]),
/// whose gradient ∂D/∂M₀(t_k), non-zero at the turning points of counted cycles only, the adjoint
/// carries back like a stage cost's. It is piecewise smooth: where the pairing of turning points
/// changes (module docs of [`crate::fatigue::damage`]) the gradient is the current pairing's and
/// central differences across the change see a kink. Gradient methods (L-BFGS, the trust region,
/// `auto`, which chooses L-BFGS) take it; the structured solvers (Riccati, condensed, hence
/// `mpc`) need a Gauss-Newton form it does not have and refuse it
/// ([`crate::error::OcpError::NeedsPowerProxy`]), naming the smooth stand-in Σ|M₀|^m
/// ([`crate::PowerObjective`] with m = the S-N curve's slope, [`Objective::power_proxy`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FatigueObjective {
    /// The damage of the history.
    pub damage: WellheadDamage,
    /// ρ ≥ 0 of the control-effort penalty ρ h Σ |u_k|².
    pub effort: f64,
}

impl Objective for FatigueObjective {
    /// The effort penalty ρ h |u_k|² only (D is the history term).
    fn stage<D: Scalar>(&self, s: Stage<'_, D>) -> D {
        if self.effort > 0.0 {
            (s.control * s.control + s.control_x * s.control_x) * (self.effort * s.h)
        } else {
            D::zero()
        }
    }
    fn has_history(&self) -> bool {
        true
    }
    /// D and ∂D/∂M₀(t_k) ([`WellheadDamage::value_and_gradient`]).
    fn history<D: Scalar>(&self, h: History<'_, D>) -> Result<D> {
        let spatial = !h.moment_x.is_empty();
        let out = DamageGradient {
            grad: h.grad,
            grad_x: h.grad_x,
        };
        Ok(self
            .damage
            .value_and_gradient(h.moment, spatial.then_some(h.moment_x), out)?)
    }
    /// m₁ of the S-N curve.
    fn power_proxy(&self) -> Option<f64> {
        Some(self.damage.exponent())
    }
}
