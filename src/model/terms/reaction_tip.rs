//! The reaction-force tip drive (thesis §3.2, eq. 3.2.1/3.2.2): the tip's height follows the
//! control alone.

use crate::base::Scalar;

/// The "move and lock" variant of a fixed-fixed or pinned-pinned beam: the tip's z-coordinate
/// ζ is not held at 0 but driven by the control through the tip mass, m_n ζ̈ = −u (the reaction
/// λ_l cancels every other force on the tip, eq. 3.2.1/3.2.2). ζ is then imposed as the
/// rheonomic constraint l(q_{k+1}) = ζ_{k+1}, L M⁻¹ p_{k+1} = v_{k+1} by
/// [`crate::constraints::ConstraintOperator`]; with u = 0 this is exactly the locked beam.
///
/// Unlike the force terms it has no energy: the control's force lies along Lᵀ and would be
/// absorbed by the tip multiplier, so the effect of u enters only through the target (ζ, v),
/// integrated with the same Störmer–Verlet split as RATTLE:
/// ```text
/// v_{k+½} = v_k − h/(2 m_n) u_k,   ζ_{k+1} = ζ_k + h v_{k+½},   v_{k+1} = v_{k+½} − h/(2 m_n) u_{k+1}.
/// ```
/// The map is linear in (ζ, v, u), so its transpose ([`ReactionTip::reverse`]) is written by
/// hand; `tests/model/terms.rs` checks it against the Dual64 derivatives of the forward map.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ReactionTip<D> {
    /// 1/m_n, the inverse tip mass.
    pub inv_tip_mass: D,
}

/// Cotangents of one reverse step of [`ReactionTip`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ReactionTipBar<D> {
    /// (ζ̄_k, v̄_k): the cotangent of the target at step k.
    pub target: [D; 2],
    /// (ū_k, ū_{k+1}): contributions to the control cotangents.
    pub controls: (D, D),
    /// ∂/∂(1/m_n) of ⟨(ζ̄_{k+1}, v̄_{k+1}), (ζ_{k+1}, v_{k+1})⟩.
    pub inv_tip_mass: D,
}

impl<D: Scalar> ReactionTip<D> {
    /// First half: (ζ_{k+1}, v_{k+½}) from the target (ζ_k, v_k) and u_k.
    pub fn first_half(&self, [zeta, v]: [D; 2], u_k: D, h: f64) -> (D, D) {
        let v_half = v - u_k * self.inv_tip_mass * (0.5 * h);
        (zeta + v_half * h, v_half)
    }

    /// Second half: v_{k+1} = v_{k+½} − h/(2 m_n) u_{k+1}.
    pub fn second_half(&self, v_half: D, u_k1: D, h: f64) -> D {
        v_half - u_k1 * self.inv_tip_mass * (0.5 * h)
    }

    /// The transpose of one step (ζ_k, v_k, u_k, u_{k+1}) ↦ (ζ_{k+1}, v_{k+1}) applied to the
    /// cotangent (ζ̄_{k+1}, v̄_{k+1}):
    /// v̄_{k+½} = v̄_{k+1} + h ζ̄_{k+1}, ζ̄_k = ζ̄_{k+1}, v̄_k = v̄_{k+½},
    /// ū_k = −h/(2 m_n) v̄_{k+½}, ū_{k+1} = −h/(2 m_n) v̄_{k+1}.
    pub fn reverse(
        &self,
        [zeta_bar, v_bar]: [D; 2],
        (u_k, u_k1): (D, D),
        h: f64,
    ) -> ReactionTipBar<D> {
        let hh = 0.5 * h;
        let v_half_bar = v_bar + zeta_bar * h;
        ReactionTipBar {
            target: [zeta_bar, v_half_bar],
            controls: (
                -(v_half_bar * self.inv_tip_mass * hh),
                -(v_bar * self.inv_tip_mass * hh),
            ),
            inv_tip_mass: -((v_bar * u_k1 + v_half_bar * u_k) * hh),
        }
    }
}
