//! The stage costs of both solvers in the Gauss-Newton form of the problem's objective
//! ([`Objective::gauss_newton`]): ℓ_k = ½ w_k r_k(M₀)² + e_k u_k² + (σ/h)(u_k − u_{k−1})² (the
//! rate term for k ≥ 1), with the residual r_k and its first two derivatives in M₀ from one
//! second-order dual evaluation (`Dual2_64`) of the objective's own code.

use std::fmt;
use std::sync::Arc;

use num_dual::Dual2_64;

use crate::adjoint::{GaussNewton, MomentStage, Objective, Stage};
use crate::error::{OcpError, Result};

/// The residual r_k(M₀) of an objective, type-erased (the solvers are not generic over it).
trait Residual: Send + Sync {
    fn at(&self, s: MomentStage<Dual2_64>) -> Option<GaussNewton<Dual2_64>>;
}

struct Of<O>(O);

impl<O: Objective> Residual for Of<O> {
    fn at(&self, s: MomentStage<Dual2_64>) -> Option<GaussNewton<Dual2_64>> {
        self.0.gauss_newton(s)
    }
}

/// r_k(M₀) with dr/dM₀ and d²r/dM₀².
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct ResidualAt {
    pub r: f64,
    pub dr: f64,
    pub d2r: f64,
}

/// The spatial model's vector residual R_k = r_k(|M₀|) M₀/|M₀| (z component first) and its
/// Jacobian `jac[c][d]` = ∂R_c/∂M₀_d (module docs).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub(crate) struct ResidualVector {
    pub r: [f64; 2],
    pub jac: [[f64; 2]; 2],
}

/// The moments |M₀| at which [`StageCost::check_isotropic`] compares an objective's stage cost
/// along x and along z (N m).
const ISOTROPY_PROBES: [f64; 3] = [0.37, 2.9, 41.0];

/// The stage costs (module docs).
#[derive(Clone)]
pub(crate) struct StageCost {
    /// σ/h: the coefficient of (u_k − u_{k−1})².
    pub rate: f64,
    /// N.
    pub steps: usize,
    h: f64,
    /// w_k and e_k of every stage.
    weights: Vec<f64>,
    efforts: Vec<f64>,
    residual: Arc<dyn Residual>,
}

impl fmt::Debug for StageCost {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("StageCost")
            .field("rate", &self.rate)
            .field("steps", &self.steps)
            .field("weights", &self.weights)
            .field("efforts", &self.efforts)
            .finish_non_exhaustive()
    }
}

impl StageCost {
    /// The stage costs of `objective` over N = `steps` steps of `h`, with the rate penalty
    /// σ/h = `rate`.
    ///
    /// # Errors
    /// [`OcpError::NoGaussNewtonForm`] when the objective has no Gauss-Newton form at some
    /// stage ([`OcpError::NeedsPowerProxy`] when it is a history term with a power proxy: the
    /// rainflow damage), [`OcpError::InvalidGaussNewtonForm`] for a negative or non-finite weight or
    /// effort; `solver` names the solver.
    pub(crate) fn new<O: Objective>(
        objective: &O,
        steps: usize,
        h: f64,
        rate: f64,
        solver: &'static str,
    ) -> Result<Self> {
        let (mut weights, mut efforts) =
            (Vec::with_capacity(steps + 1), Vec::with_capacity(steps + 1));
        let ok = |x: f64| x.is_finite() && x >= 0.0;
        for k in 0..=steps {
            let s = MomentStage {
                k,
                steps,
                h,
                moment: 0.0,
            };
            let g = objective.gauss_newton(s).ok_or_else(|| {
                match objective.power_proxy().filter(|_| objective.has_history()) {
                    Some(exponent) => OcpError::NeedsPowerProxy { solver, exponent },
                    None => OcpError::NoGaussNewtonForm { solver },
                }
            })?;
            if !ok(g.weight) || !ok(g.effort) {
                return Err(OcpError::InvalidGaussNewtonForm {
                    solver,
                    stage: k,
                    weight: g.weight,
                    effort: g.effort,
                }
                .into());
            }
            weights.push(g.weight);
            efforts.push(g.effort);
        }
        Ok(StageCost {
            rate,
            steps,
            h,
            weights,
            efforts,
            residual: Arc::new(Of(objective.clone())),
        })
    }

    /// The weight w_k of the residual.
    #[inline]
    pub(crate) fn weight(&self, k: usize) -> f64 {
        self.weights[k]
    }

    /// The effort coefficient e_k of u_k².
    #[inline]
    pub(crate) fn effort(&self, k: usize) -> f64 {
        self.efforts[k]
    }

    /// r_k and its derivatives at the moment `m` (0 where the form is missing: not after
    /// [`StageCost::new`], which checked every stage).
    #[inline]
    pub(crate) fn residual(&self, k: usize, m: f64) -> ResidualAt {
        let s = MomentStage {
            k,
            steps: self.steps,
            h: self.h,
            moment: Dual2_64::from_re(m).derivative(),
        };
        match self.residual.at(s) {
            Some(g) => ResidualAt {
                r: g.residual.re,
                dr: g.residual.v1,
                d2r: g.residual.v2,
            },
            None => ResidualAt {
                r: 0.0,
                dr: 0.0,
                d2r: 0.0,
            },
        }
    }

    /// The spatial model's vector residual at the moment m = (M₀_z, M₀ₓ): with the objective's
    /// residual r_k of the magnitude |M₀| and g = r_k(|M₀|)/|M₀|, û = M₀/|M₀|,
    /// ```text
    /// R_k = g M₀,   ∂R_k/∂M₀ = g I + (r_k′(|M₀|) − g) û ûᵀ,
    /// ```
    /// so ½ w_k |R_k|² = ½ w_k r_k(|M₀|)² is the objective's stage cost of the vector moment
    /// (c_sum: R = M₀, ½·2|M₀|² = M₀ₓ² + M₀_z²; power: R = |M₀|^{p/2−1} M₀, |R|² = |M₀|^p), the
    /// planar residual where M₀ₓ = 0 (r_k is odd in M₀ for every objective the solvers take,
    /// [`StageCost::check_isotropic`]). Below |M₀|² = 10⁻³⁰⁸ (the straight beam of t₀):
    /// R = r_k′(0) M₀, ∂R/∂M₀ = r_k′(0) I, the limit.
    pub(crate) fn residual_vector(&self, k: usize, m: [f64; 2]) -> ResidualVector {
        let mag = m[0].hypot(m[1]);
        let at = self.residual(k, mag);
        if mag * mag < f64::MIN_POSITIVE {
            return ResidualVector {
                r: [at.dr * m[0], at.dr * m[1]],
                jac: [[at.dr, 0.0], [0.0, at.dr]],
            };
        }
        let g = at.r / mag;
        let u = [m[0] / mag, m[1] / mag];
        let c = at.dr - g;
        ResidualVector {
            r: [g * m[0], g * m[1]],
            jac: [
                [g + c * u[0] * u[0], c * u[0] * u[1]],
                [c * u[1] * u[0], g + c * u[1] * u[1]],
            ],
        }
    }

    /// ℓ_k of the spatial model for the vector residual `r`, the control `u` = (u_z, u_x) and
    /// the previous control `w`: ½ w_k |r|² + e_k |u|² + (σ/h)|u − w|² (k ≥ 1).
    #[inline]
    pub(crate) fn value_axes(&self, k: usize, r: [f64; 2], u: [f64; 2], w: [f64; 2]) -> f64 {
        let sq = |a: [f64; 2]| a[0] * a[0] + a[1] * a[1];
        let mut l = 0.5 * self.weights[k] * sq(r) + self.efforts[k] * sq(u);
        if k > 0 && self.rate > 0.0 {
            l += self.rate * sq([u[0] - w[0], u[1] - w[1]]);
        }
        l
    }

    /// Refuses, for the spatial model, an objective whose stage cost is not a function of |M₀|
    /// alone: [`StageCost::residual_vector`] assumes it. The stage cost (controls 0) with the
    /// moment along x and along z must agree to 10⁻¹² relative at the first and last stages and
    /// three magnitudes ([`ISOTROPY_PROBES`]); an objective of the node positions is refused.
    ///
    /// # Errors
    /// [`OcpError::AnisotropicObjective`] naming `solver`.
    pub(crate) fn check_isotropic<O: Objective>(
        &self,
        objective: &O,
        solver: &'static str,
    ) -> Result<()> {
        for &a in &ISOTROPY_PROBES {
            if objective.uses_positions() {
                return Err(OcpError::AnisotropicObjective {
                    solver,
                    moment: a,
                    along_x: f64::NAN,
                    along_z: f64::NAN,
                }
                .into());
            }
            for k in [0, self.steps] {
                let at = |moment: f64, moment_x: f64| {
                    objective.stage(Stage {
                        k,
                        steps: self.steps,
                        h: self.h,
                        moment,
                        moment_x,
                        control: 0.0,
                        control_x: 0.0,
                        z: &[],
                    })
                };
                let (along_z, along_x) = (at(a, 0.0), at(0.0, a));
                let scale = along_z.abs().max(along_x.abs());
                if (along_z - along_x).abs() > 1e-12 * scale || !along_z.is_finite() {
                    return Err(OcpError::AnisotropicObjective {
                        solver,
                        moment: a,
                        along_x,
                        along_z,
                    }
                    .into());
                }
            }
        }
        Ok(())
    }

    /// ℓ_k for the residual `r`, control `u` and previous control `w`.
    #[inline]
    pub(crate) fn value(&self, k: usize, r: f64, u: f64, w: f64) -> f64 {
        let mut l = 0.5 * self.weights[k] * r * r + self.efforts[k] * u * u;
        if k > 0 && self.rate > 0.0 {
            l += self.rate * (u - w) * (u - w);
        }
        l
    }
}
