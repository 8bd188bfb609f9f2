//! The PD law's scaled, bounded tuning ([`super::pd_law`]; module docs of [`super`], "The PD
//! law").
//!
//! The raw gains (u_b \[N\], K_p \[N/(N·m)\], K_d \[N·s/(N·m)\]) differ in scale by 10⁵ on a
//! real riser, and an unscaled tuning from zero stopped at negative, destabilising gains (the
//! README's headline of an earlier build). The tuning here works in three unit-free parameters
//! x ∈ [−[`PD_BOX`], [`PD_BOX`]]³ (a box: [`crate::optimize::Bounds`]):
//! ```text
//! u_b = u_s + (u_max/B) x_b,      K_p = e^{x_p} / k_u,      K_d = e^{x_d} / (k_u ω),
//! ```
//! with k_u = ∂M₀/∂u the static gain of the control on the base moment (the static equilibrium
//! in the scene's steady loads — its current, no waves — at u = 0 and at u = u_max/10,
//! [`crate::statics::static_equilibrium_at`]), u_s = −M₀(0)/k_u the force that cancels the
//! static moment (clamped to ±u_max; 0 for a law about the moment's running mean, which leaves
//! the steady moment alone), ω = 2π/T_p of the scene's sea (1 rad/s without one) and
//! B = [`PD_BOX`]. The loop gains g_p = K_p k_u = e^{x_p} and g_d = K_d k_u ω = e^{x_d} are
//! positive: u = u_b − K_p M₀ − K_d Ṁ₀ then pushes against the moment the force itself makes
//! (negative feedback, statically M = (M_d + k_u u_b)/(1 + g_p)), whatever the sign convention
//! of M₀ and u, and bounded, g ∈ [e^{−B}, e^{B}]: the tuning cannot end at a reversed
//! (destabilising) law, nor at an unbounded gain. The gradient is the chain rule on
//! [`PdTuning`]'s exact dual-number gradient: ∂J/∂x_b = (u_max/B) ∂J/∂u_b,
//! ∂J/∂x_p = K_p ∂J/∂K_p, ∂J/∂x_d = K_d ∂J/∂K_d.

use crate::adjoint::HotSpotObjective;
use crate::error::{MpcError, Requirement, Result};
use crate::model::Chain;
use crate::mpc::PdTuning;
use crate::optimize::OptimProblem;
use crate::scene::{Control, ControlKind, MomentAbout, Scene};
use crate::statics::{calm_scene, static_equilibrium_at};

/// The half-width B of the box of the scaled parameters: loop gains within e^{±4} (0.018 to
/// 55), the bias within u_s ± u_max.
pub const PD_BOX: f64 = 4.0;

/// The tuning's start: the static bias and loop gains e^{−2} ≈ 0.14 (a gentle law; the tuning
/// raises them where they help).
pub const PD_START: [f64; 3] = [0.0, -2.0, -2.0];

/// The scales of the PD law's parameters (module docs).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PdScales {
    /// u_s \[N\]: the force that cancels the static moment.
    pub static_bias: f64,
    /// u_max/B \[N\] per unit of x_b.
    pub bias_step: f64,
    /// 1/k_u \[N/(N·m)\]: K_p per unit loop gain.
    pub kp: f64,
    /// 1/(k_u ω) \[N·s/(N·m)\]: K_d per unit loop gain.
    pub kd: f64,
}

impl PdScales {
    /// The scales of `scene` with the force bound `bound` (module docs).
    ///
    /// # Errors
    /// The statics' errors; [`crate::error::ValueError`] naming `pd_static_gain` when the control
    /// does not move the static moment (k_u zero or not finite).
    pub fn of(scene: &Scene, bound: f64) -> Result<Self> {
        Self::of_at(scene, bound, None)
    }

    /// The scales of [`PdScales::of`] with k_u and u_s of the moment at a hot spot (`spot`,
    /// [`HotSpotObjective::moment_of_attitudes`]) instead of the base moment (`None`: those of
    /// [`PdScales::of`] bit for bit).
    ///
    /// # Errors
    /// As [`PdScales::of`].
    pub fn of_at(scene: &Scene, bound: f64, spot: Option<&HotSpotObjective>) -> Result<Self> {
        let mut calm = calm_scene(scene);
        if calm.control.is_none() {
            calm.control = Some(Control {
                node: scene.n(),
                kind: ControlKind::Constant,
                values: vec![0.0],
                values_x: None,
            });
        }
        let chain = Chain::<f64, 2>::from_scene(&calm)?;
        // A constant thrust F holds the vessel at F/c from its offset (the steady state of
        // (m + m_a) ẍ = F − c ẋ); a force on the riser enters the statics itself.
        let thrust = scene.thrust();
        let moment = |u: f64| -> Result<f64> {
            let (mut held, mut force) = (calm.clone(), u);
            if let (Some(t), Some(v)) = (thrust, held.vessel.as_mut()) {
                v.offset += u / t.damping;
                force = 0.0;
            }
            let s = static_equilibrium_at(&held, 0.0, force)?;
            let q: Vec<[f64; 2]> = s.attitudes.iter().map(|a| [a[1], a[2]]).collect();
            Ok(match spot {
                Some(spot) => spot.moment_of_attitudes(&q),
                None => chain.base_moment(&q),
            })
        };
        let du = 0.1 * bound.min(1e12);
        let m0 = moment(0.0)?;
        let k_u = (moment(du)? - m0) / du;
        Requirement::PositiveFinite
            .check("pd_static_gain", k_u.abs())
            .map_err(MpcError::from)?;
        let omega = scene
            .loads
            .waves
            .map_or(1.0, |w| 2.0 * std::f64::consts::PI / w.tp);
        // About the mean the law spends nothing on the steady moment: its bias starts at zero.
        let about_mean = spot.is_some_and(|s| s.about == MomentAbout::Mean);
        let static_bias = if about_mean { 0.0 } else { -m0 / k_u };
        Ok(PdScales {
            static_bias: static_bias.clamp(-bound, bound),
            bias_step: bound.min(1e12) / PD_BOX,
            kp: 1.0 / k_u,
            kd: 1.0 / (k_u * omega),
        })
    }

    /// The gains (u_b, K_p, K_d) of the scaled parameters x (NaN for a missing entry: the
    /// closed loop then refuses the gains, naming them).
    pub fn gains(&self, x: &[f64]) -> [f64; 3] {
        let x = |i: usize| x.get(i).copied().unwrap_or(f64::NAN);
        [
            self.static_bias + self.bias_step * x(0),
            self.kp * x(1).exp(),
            self.kd * x(2).exp(),
        ]
    }
}

/// [`PdTuning`] in the scaled parameters x (module docs).
#[derive(Clone, Debug)]
pub struct ScaledPdTuning {
    /// The tuning in the raw gains.
    pub tuning: PdTuning,
    /// The scales.
    pub scales: PdScales,
}

impl OptimProblem for ScaledPdTuning {
    fn n_params(&self) -> usize {
        3
    }

    fn value(&self, x: &[f64]) -> Result<f64> {
        self.tuning.value(&self.scales.gains(x))
    }

    fn value_and_gradient(&self, x: &[f64]) -> Result<(f64, Vec<f64>)> {
        let g = self.scales.gains(x);
        let (j, grad) = self.tuning.value_and_gradient(&g)?;
        let chain = [self.scales.bias_step, g[1], g[2]];
        Ok((j, grad.iter().zip(chain).map(|(d, c)| d * c).collect()))
    }
}
