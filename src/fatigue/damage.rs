//! The rainflow damage of a base-moment history as a differentiable function of it
//! (docs/fatigue.md, "Fatigue as an objective"):
//! what `[objective] kind = "fatigue"` minimises ([`crate::FatigueObjective`]).
//!
//! For the history M₀(t_k) (and M₀ₓ(t_k) of a spatial run), k = 0..N, the hot-spot stress is
//! σ_k = c · M₀(t_k) with c = [`super::HotSpot::stress_per_unit`] (SCF·(D_o/2)/I times
//! M_w/M₀ = l₁/2, docs/conventions.md "The wellhead moment M_w"), or at the point θ around the
//! circumference σ_k = c · (M₀ₓ sin θ + M₀_z cos θ), and the damage is Miner's sum over its
//! rainflow cycles,
//!
//! D = Σ_c n_c · d(|σ_{e(c)} − σ_{s(c)}|)    ([`super::damage_gradient`], module `gradient`),
//!
//! at the worst of the [`super::FatigueSpec::circumference_points`] points in a spatial run (θ = 0
//! alone in a planar one), exactly as [`super::assess`] computes it: the same stresses, the same
//! cycles in the same order, the same sum, so the value equals `chainbeam fatigue`'s `damage` of
//! the same record bit for bit.
//!
//! **Derivative.** With the pairing (and the worst point) held fixed, D is a smooth function of
//! the turning points' stresses and
//!
//! ∂D/∂M₀(t_k) = c cos θ · ∂D/∂σ_k,  ∂D/∂M₀ₓ(t_k) = c sin θ · ∂D/∂σ_k,
//!
//! ∂D/∂σ_k = Σ_{c: e(c)=k} n_c d′(Δσ_c) sgn(σ_k − σ_{s(c)}) + Σ_{c: s(c)=k} n_c d′(Δσ_c) sgn(σ_k − σ_{e(c)}),
//!
//! non-zero at the turning points of counted cycles only. Everything is evaluated over
//! [`Scalar`] (d′ by a nested dual number of the S-N curve's own d), so the adjoint's
//! Hessian-vector products (dual numbers over this gradient) see the curvature of the current
//! pairing too.
//!
//! **Where the pairing changes** (two compared ranges tie in the three-point rule, a new turning
//! point appears or one vanishes, a range crosses the S-N knee, or another circumference point
//! becomes the worst) D is continuous but its gradient jumps: D is piecewise smooth, and this is
//! the gradient of the pairing found at the current history, one of the one-sided gradients
//! there. Central differences across a change see a kink (they average the two sides); an
//! optimiser can stall at one, as at any kink.

use num_dual::Dual;

use super::rainflow::{rainflow_visit, RainflowWorkspace};
use super::sn::SnCurve;
use super::stress::{HotSpot, MomentMeasure};
use super::{FatigueError, FatigueSpec};
use crate::base::Scalar;

/// The rainflow damage of the wellhead stress as a function of the base-moment history (module
/// docs): the S-N curve, the stress per unit M₀ and the number of circumference points.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct WellheadDamage {
    /// The S-N curve with its thickness correction ([`FatigueSpec::sn_curve`]).
    pub curve: SnCurve,
    /// c: σ = c · M₀ \[MPa per unit of the history\] ([`HotSpot::stress_per_unit`]).
    pub stress_per_unit: f64,
    /// Points around the circumference checked in a spatial history.
    pub circumference_points: usize,
}

/// Where the gradient of [`WellheadDamage::value_and_gradient`] goes: ∂D/∂M₀(t_k) and, for a
/// spatial history, ∂D/∂M₀ₓ(t_k) (same length as the history; `grad_x` is ignored for a planar
/// one).
pub struct DamageGradient<'a, D> {
    /// ∂D/∂M₀(t_k) (overwritten).
    pub grad: &'a mut [D],
    /// ∂D/∂M₀ₓ(t_k) (overwritten when the history is spatial).
    pub grad_x: &'a mut [D],
}

impl WellheadDamage {
    /// The damage of `spec`'s section, hot spot and S-N curve for histories of the measure
    /// `measure` (the scene's [`crate::Scene::moment_measure`] for a simulated M₀).
    ///
    /// # Errors
    /// The spec's [`FatigueError`] (naming its key), or the measure's (`base_length`).
    pub fn new(spec: &FatigueSpec, measure: MomentMeasure) -> Result<Self, FatigueError> {
        spec.validate()?;
        measure.check()?;
        let hot_spot: HotSpot = spec.hot_spot()?;
        Ok(WellheadDamage {
            curve: spec.sn_curve()?,
            stress_per_unit: hot_spot.stress_per_unit(measure),
            circumference_points: spec.circumference_points,
        })
    }

    /// The first (high-range) slope m₁ of the S-N curve: the exponent of the smooth proxy
    /// Σ|M₀|^m that the structured solvers take instead (`kind = "power"`).
    pub fn exponent(&self) -> f64 {
        self.curve.first.m
    }

    /// D of the history (`moment`, and `moment_x` for a spatial one, same length) and its
    /// gradient (module docs) into `out`. Allocates the stress history and the rainflow stack
    /// once per call (O(N)); O(N) per circumference point.
    ///
    /// # Errors
    /// [`FatigueError::LengthMismatch`] for histories or outputs of different lengths,
    /// [`FatigueError::NonFinite`] at the first non-finite stress.
    pub fn value_and_gradient<D: Scalar>(
        &self,
        moment: &[D],
        moment_x: Option<&[D]>,
        out: DamageGradient<'_, D>,
    ) -> Result<D, FatigueError> {
        let n = moment.len();
        let check = |what, got| {
            if got == n {
                Ok(())
            } else {
                Err(FatigueError::LengthMismatch {
                    what,
                    expected: n,
                    got,
                })
            }
        };
        check("gradient", out.grad.len())?;
        if let Some(mx) = moment_x {
            check("moment_x", mx.len())?;
            check("gradient_x", out.grad_x.len())?;
        }
        let c = self.stress_per_unit;
        let mut stress = vec![D::zero(); n];
        let mut workspace = RainflowWorkspace::with_capacity(n);
        // The worst point (assess's rule: the first of the largest damage); θ = 0 when planar.
        let mut theta = 0.0;
        if moment_x.is_some() {
            let mut best: Option<f64> = None;
            for t in HotSpot::points(self.circumference_points) {
                self.stress(moment, moment_x, t, &mut stress);
                let d = self.pairing(&stress, &mut workspace, None)?.re();
                if best.is_none_or(|b| d > b) {
                    (theta, best) = (t, Some(d));
                }
            }
        }
        self.stress(moment, moment_x, theta, &mut stress);
        let mut g = vec![D::zero(); n];
        let damage = self.pairing(&stress, &mut workspace, Some(&mut g))?;
        let (sin, cos) = theta.sin_cos();
        match moment_x {
            Some(_) => {
                for ((gz, gx), gs) in out.grad.iter_mut().zip(out.grad_x.iter_mut()).zip(&g) {
                    *gz = *gs * (c * cos);
                    *gx = *gs * (c * sin);
                }
            }
            None => {
                for (gz, gs) in out.grad.iter_mut().zip(&g) {
                    *gz = *gs * c;
                }
            }
        }
        Ok(damage)
    }

    /// σ_k at the point θ, computed as [`HotSpot::stress`] / [`HotSpot::stress_at`] do.
    fn stress<D: Scalar>(&self, moment: &[D], moment_x: Option<&[D]>, theta: f64, out: &mut [D]) {
        let c = self.stress_per_unit;
        match moment_x {
            Some(mx) => {
                let (sin, cos) = theta.sin_cos();
                for ((s, x), z) in out.iter_mut().zip(mx).zip(moment) {
                    *s = (*x * sin + *z * cos) * c;
                }
            }
            None => {
                for (s, m) in out.iter_mut().zip(moment) {
                    *s = *m * c;
                }
            }
        }
    }

    /// Miner's sum over the rainflow cycles of `stress` (counted on its values), in `D`, and
    /// with `grad` its gradient ∂D/∂σ_k for the pairing found.
    fn pairing<D: Scalar>(
        &self,
        stress: &[D],
        workspace: &mut RainflowWorkspace,
        mut grad: Option<&mut [D]>,
    ) -> Result<D, FatigueError> {
        let mut damage = D::zero();
        let curve = &self.curve;
        rainflow_visit(stress.iter().map(|s| s.re()), workspace, |cy| {
            let delta = stress[cy.end] - stress[cy.start];
            let range = delta.abs();
            damage += curve.cycle_damage(range) * cy.count;
            if let Some(g) = grad.as_deref_mut() {
                // d′(Δσ) in D, by a dual number over D of the curve's own d.
                let slope = curve.cycle_damage(Dual::new(range, D::one())).eps * cy.count;
                let signed = if delta.re() >= 0.0 { slope } else { -slope };
                g[cy.end] += signed;
                g[cy.start] -= signed;
            }
        })?;
        Ok(damage)
    }
}
