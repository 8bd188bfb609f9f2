//! The stage costs of both solvers in the Gauss-Newton form of the problem's objective
//! ([`Objective::gauss_newton`]): ℓ_k = ½ w_k r_k(M₀)² + e_k u_k² + (σ/h)(u_k − u_{k−1})² (the
//! rate term for k ≥ 1), with the residual r_k and its first two derivatives in M₀ from one
//! second-order dual evaluation (`Dual2_64`) of the objective's own code.

use std::fmt;
use std::sync::Arc;

use num_dual::Dual2_64;

use crate::adjoint::{GaussNewton, MomentStage, Objective};
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
    pub fn new<O: Objective>(
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
    pub fn weight(&self, k: usize) -> f64 {
        self.weights[k]
    }

    /// The effort coefficient e_k of u_k².
    #[inline]
    pub fn effort(&self, k: usize) -> f64 {
        self.efforts[k]
    }

    /// r_k and its derivatives at the moment `m` (0 where the form is missing: not after
    /// [`StageCost::new`], which checked every stage).
    #[inline]
    pub fn residual(&self, k: usize, m: f64) -> ResidualAt {
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

    /// ℓ_k for the residual `r`, control `u` and previous control `w`.
    #[inline]
    pub fn value(&self, k: usize, r: f64, u: f64, w: f64) -> f64 {
        let mut l = 0.5 * self.weights[k] * r * r + self.efforts[k] * u * u;
        if k > 0 && self.rate > 0.0 {
            l += self.rate * (u - w) * (u - w);
        }
        l
    }
}
