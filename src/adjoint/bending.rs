//! The scene's bending-moment objective: the thesis's c and c_sum (§3.3, eq. 3.3.2/3.3.4) and the
//! power objective Σ|M₀|^p, dispatched by the scene's [`ObjectiveKind`]. Its own file so that the
//! objective trait (`objective.rs`) does not import the objectives built on it (no import circle).

use super::fatigue::FatigueObjective;
use super::objective::{GaussNewton, History, MomentStage, Objective, Stage};
use super::power::PowerObjective;
use crate::base::Scalar;
use crate::scene::ObjectiveKind;

/// The bending-moment objective a scene's `[objective]` names: the thesis's (§3.3) on the squared
/// norm |M₀|² = M₀ₓ² + M₀_z² of the base moment vector (M₀² in the planar model, where M₀ₓ = 0
/// and the sum is bit-for-bit M₀²) or, with [`ObjectiveKind::Power`], the [`PowerObjective`]
/// Σ|M₀|^p; with an optional effort penalty ρ h Σ |u_k|² (|u|² = u_x² + u_z²).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BendingObjective {
    /// c = |M₀(t_N)|² (eq. 3.3.2), c_sum = Σ_{k=0}^{N} |M₀(t_k)|² (eq. 3.3.4) or Σ|M₀(t_k)|^p.
    pub kind: ObjectiveKind,
    /// ρ ≥ 0 of the control-effort penalty ρ h Σ_{k=0}^{N} |u_k|² \[N²m²/(N² s)\].
    pub effort: f64,
}

impl BendingObjective {
    /// c = M₀(t_N)² (eq. 3.3.2).
    pub fn final_moment() -> Self {
        BendingObjective {
            kind: ObjectiveKind::Final,
            effort: 0.0,
        }
    }
    /// c_sum = Σ M₀(t_k)² (eq. 3.3.4).
    pub fn summed_moment() -> Self {
        BendingObjective {
            kind: ObjectiveKind::Sum,
            effort: 0.0,
        }
    }
    /// Adds the effort penalty ρ h Σ u_k².
    pub fn with_effort(mut self, rho: f64) -> Self {
        self.effort = rho;
        self
    }
    /// The [`PowerObjective`] of kind [`ObjectiveKind::Power`], with this effort.
    fn power(&self, exponent: f64) -> PowerObjective {
        PowerObjective {
            exponent,
            effort: self.effort,
        }
    }
}

impl BendingObjective {
    /// The [`FatigueObjective`] of kind [`ObjectiveKind::Fatigue`], with this effort.
    fn fatigue(&self) -> Option<FatigueObjective> {
        match self.kind {
            ObjectiveKind::Fatigue(damage) => Some(FatigueObjective {
                damage,
                effort: self.effort,
            }),
            _ => None,
        }
    }
}

impl Objective for BendingObjective {
    /// [`ObjectiveKind::Fatigue`]: the rainflow damage's history term.
    fn has_history(&self) -> bool {
        self.fatigue().is_some()
    }
    fn history<D: Scalar>(&self, h: History<'_, D>) -> crate::error::Result<D> {
        match self.fatigue() {
            Some(f) => f.history(h),
            None => Ok(D::zero()),
        }
    }
    fn power_proxy(&self) -> Option<f64> {
        self.fatigue().and_then(|f| f.power_proxy())
    }
    /// w_k = 2c_k (c_k = 1 for c_sum, [k = N] for c), r_k = M₀, e_k = ρh: ½ w r² = c_k M₀²
    /// bit for bit. [`ObjectiveKind::Power`]: that of [`PowerObjective`].
    fn gauss_newton<D: Scalar>(&self, s: MomentStage<D>) -> Option<GaussNewton<D>> {
        match self.kind {
            ObjectiveKind::Power { exponent } => return self.power(exponent).gauss_newton(s),
            ObjectiveKind::Fatigue(_) => return None,
            _ => {}
        }
        let c = match self.kind {
            ObjectiveKind::Final if s.k != s.steps => 0.0,
            _ => 1.0,
        };
        Some(GaussNewton {
            weight: 2.0 * c,
            residual: s.moment,
            effort: self.effort * s.h,
        })
    }
    fn stage<D: Scalar>(&self, s: Stage<'_, D>) -> D {
        let m = match self.kind {
            ObjectiveKind::Final if s.k != s.steps => D::zero(),
            ObjectiveKind::Power { exponent } => return self.power(exponent).stage(s),
            ObjectiveKind::Fatigue(_) => D::zero(),
            _ => s.moment * s.moment + s.moment_x * s.moment_x,
        };
        if self.effort > 0.0 {
            let u2 = s.control * s.control + s.control_x * s.control_x;
            m + u2 * (self.effort * s.h)
        } else {
            m
        }
    }
}
