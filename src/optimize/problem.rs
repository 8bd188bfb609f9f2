//! What [`minimize`](super::minimize) and [`multistart`](crate::multistart) optimise: a
//! differentiable objective J(θ) of a parameter vector θ ∈ ℝⁿ ([`OptimProblem`]), with
//! Hessian-vector products as a separate capability ([`HessianVec`]), and the start-point checks
//! every run makes: parameters without effect ([`ineffective_params`]) and the range where the
//! objective is resolved ([`OptimProblem::check_range`]).
//!
//! [`ControlProblem`] implements both traits; a calibration of physical parameters (in
//! `paper_figures`) implements [`OptimProblem`] alone.

use crate::adjoint::{ControlMap, ControlProblem, Objective};
use crate::error::{Error, Result};
use crate::ocp::{IterationObserver, OcpOptions, OcpResult};

/// A differentiable objective J(θ) of n real parameters: what the optimisers need.
///
/// Only [`n_params`](Self::n_params) and [`value_and_gradient`](Self::value_and_gradient) are
/// required. The others have defaults: no Hessian-vector products (then only
/// [`Method::Lbfgs`](super::Method::Lbfgs) runs and the gradient polish is skipped), no controls
/// to report, unit parameter scales and no range limit.
///
/// # Example: a quadratic
/// ```
/// use chainbeam::optimize::{minimize, OptimOptions, OptimProblem};
/// use chainbeam::Result;
///
/// /// J(θ) = Σ (θᵢ − i)².
/// struct Bowl(usize);
///
/// impl OptimProblem for Bowl {
///     fn n_params(&self) -> usize {
///         self.0
///     }
///     fn value_and_gradient(&self, theta: &[f64]) -> Result<(f64, Vec<f64>)> {
///         let d: Vec<f64> = theta.iter().enumerate().map(|(i, t)| t - i as f64).collect();
///         Ok((d.iter().map(|x| x * x).sum(), d.iter().map(|x| 2.0 * x).collect()))
///     }
/// }
///
/// let r = minimize(&Bowl(3), &[5.0, 5.0, 5.0], &OptimOptions::default())?;
/// assert!(r.converged, "{}", r.termination);
/// assert!((r.theta[2] - 2.0).abs() < 1e-8);
/// assert!(r.controls.is_empty()); // not a control problem
/// # Ok::<(), chainbeam::Error>(())
/// ```
pub trait OptimProblem {
    /// The number of parameters n.
    fn n_params(&self) -> usize;

    /// J(θ). The default takes it from [`value_and_gradient`](Self::value_and_gradient);
    /// override it when J alone is cheaper (a forward simulation without the adjoint).
    ///
    /// # Errors
    /// The problem's own error (e.g. a failed simulation).
    fn value(&self, theta: &[f64]) -> Result<f64> {
        self.value_and_gradient(theta).map(|(v, _)| v)
    }

    /// J(θ) and ∇J(θ) (a vector of length n).
    ///
    /// # Errors
    /// The problem's own error (e.g. a failed simulation).
    fn value_and_gradient(&self, theta: &[f64]) -> Result<(f64, Vec<f64>)>;

    /// ∇J(θ). The default takes it from [`value_and_gradient`](Self::value_and_gradient).
    ///
    /// # Errors
    /// As [`value_and_gradient`](Self::value_and_gradient).
    fn gradient(&self, theta: &[f64]) -> Result<Vec<f64>> {
        self.value_and_gradient(theta).map(|(_, g)| g)
    }

    /// The Hessian-vector-product capability, if the problem has one (default `None`). A problem
    /// that implements [`HessianVec`] returns `Some(self)`.
    fn hessian(&self) -> Option<&dyn HessianVec> {
        None
    }

    /// The forces u_0..u_N that θ stands for, reported in
    /// [`OptimResult::controls`](super::OptimResult::controls) and checked against a force
    /// bound; `None` (the default) for a problem that is not a control problem.
    fn controls(&self, _theta: &[f64]) -> Option<Result<Vec<f64>>> {
        None
    }

    /// A typical magnitude sᵢ of each parameter: how far θᵢ may sensibly move. The no-effect
    /// test ([`ineffective_params`]) asks whether moving θᵢ by sᵢ changes J beyond round-off.
    /// Default 1 for every parameter (right for log-parameters and other unit-free scales).
    fn param_scales(&self) -> Vec<f64> {
        vec![1.0; self.n_params()]
    }

    /// Checks that θ lies where the objective is resolved (default: everywhere). [`minimize`]
    /// refuses a start that fails it and treats a trial point that fails it like one whose
    /// simulation failed.
    ///
    /// [`minimize`]: super::minimize
    ///
    /// # Errors
    /// The problem's typed error naming the offending parameter.
    fn check_range(&self, _theta: &[f64]) -> Result<()> {
        Ok(())
    }

    /// Runs the structured Riccati solver ([`Method::Riccati`](super::Method::Riccati),
    /// [`crate::ocp`]) from θ₀, if the problem has one (default `None`: refused).
    ///
    /// `observer`, if given, is called after every accepted iteration and may stop the run
    /// ([`IterationObserver`]).
    ///
    /// # Errors
    /// The solver's typed error (e.g. an unsupported objective, tip or control map).
    fn riccati(
        &self,
        _theta0: &[f64],
        _options: &OcpOptions,
        _observer: Option<IterationObserver<'_>>,
    ) -> Option<Result<OcpResult>> {
        None
    }

    /// Runs the condensed Gauss-Newton solver ([`Method::Condensed`](super::Method::Condensed),
    /// [`crate::ocp::Condensed`]) from θ₀, if the problem has one (default `None`: refused).
    ///
    /// `observer` as for [`OptimProblem::riccati`].
    ///
    /// # Errors
    /// The solver's typed error (as [`OptimProblem::riccati`]).
    fn condensed(
        &self,
        _theta0: &[f64],
        _options: &OcpOptions,
        _observer: Option<IterationObserver<'_>>,
    ) -> Option<Result<OcpResult>> {
        None
    }

    /// What the automatic choice of method ([`Method::Auto`](super::Method::Auto),
    /// [`choose_method`](super::choose_method)) looks at; `None` (the default) for a problem
    /// that is not a control problem.
    fn shape(&self) -> Option<ProblemShape> {
        None
    }
}

/// The shape of a control problem, as the automatic choice of method sees it
/// ([`choose_method`](super::choose_method)).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ProblemShape {
    /// The number of parameters θ.
    pub params: usize,
    /// The number of time steps N.
    pub steps: usize,
    /// The number of pendulums n.
    pub pendulums: usize,
    /// The model's dimension (2: planar, 3: spatial).
    pub dim: usize,
    /// Whether the structured solvers ([`OptimProblem::riccati`], [`OptimProblem::condensed`])
    /// take the problem: an objective in Gauss-Newton form, a free tip, a control node.
    pub structured: bool,
}

/// Hessian-vector products v ↦ ∇²J(θ) v: the capability the trust region, Newton-CG, the
/// gradient polish, the no-effect test and the multistart certificate need.
pub trait HessianVec {
    /// ∇²J(θ) v.
    ///
    /// # Errors
    /// The problem's own error (e.g. a failed simulation).
    fn hessian_vec(&self, theta: &[f64], v: &[f64]) -> Result<Vec<f64>>;
}

// ---------------------------------------------------------------------------------------------
// The control problem
// ---------------------------------------------------------------------------------------------

/// The largest control force the discrete dynamics of `problem` resolves, π m_c l_c / h² (m_c,
/// l_c: the control node's mass and link length; h: the time step).
///
/// Why this force: a force F on the control node alone (springs and constraints aside) raises
/// its velocity by hF/m_c per step, so one step later the node moves h²F/m_c further, which
/// turns its link by about h²F/(m_c l_c) radians. At F = π m_c l_c / h² that is half a turn per
/// step: consecutive configurations are no longer close, the discrete motion aliases (a turn by
/// φ and by 2π − φ end in the same place) and RATTLE's constraint solve has no meaningful nearby
/// root, so nothing beyond it is physics the time grid resolves. The constraints and springs
/// only slow the node down, so the bound errs on the generous side. On the thesis riser (m = 1
/// kg, l = 1 m, h = 0.01 s) it is 3.14·10⁴ N, twice the largest force any unbounded Table 3.4
/// run reaches (1.5·10⁴ N, with the chain already folded) and 10²⁸ times below the −1.46·10³²
/// N that round-off once sent L-BFGS to on a control that could not act.
pub fn resolved_control_limit<P: ControlMap, O: Objective, const DIM: usize>(
    problem: &ControlProblem<P, O, DIM>,
) -> f64 {
    let chain = problem.chain();
    let c = chain
        .control_node()
        .unwrap_or(chain.n())
        .clamp(1, chain.n());
    let m = chain.masses()[c - 1];
    let l = chain.lengths()[c - 1];
    let h = problem.time_step();
    std::f64::consts::PI * m * l / (h * h)
}

/// [`OptimProblem`] for the planar (`DIM = 2`) and the spatial (`DIM = 3`) control problems:
/// the same methods, both with [`OptimProblem::riccati`] and [`OptimProblem::condensed`].
macro_rules! impl_optim_problem {
    ($dim:literal) => {
        impl<P: ControlMap, O: Objective> OptimProblem for ControlProblem<P, O, $dim> {
            fn n_params(&self) -> usize {
                ControlProblem::n_params(self)
            }
            /// One forward simulation, no adjoint.
            fn value(&self, theta: &[f64]) -> Result<f64> {
                ControlProblem::value(self, theta)
            }
            fn value_and_gradient(&self, theta: &[f64]) -> Result<(f64, Vec<f64>)> {
                ControlProblem::value_and_gradient(self, theta)
            }
            fn gradient(&self, theta: &[f64]) -> Result<Vec<f64>> {
                ControlProblem::gradient(self, theta)
            }
            fn hessian(&self) -> Option<&dyn HessianVec> {
                Some(self)
            }
            fn controls(&self, theta: &[f64]) -> Option<Result<Vec<f64>>> {
                Some(ControlProblem::controls(self, theta))
            }
            /// sᵢ = F_max / aᵢ with F_max = [`resolved_control_limit`] and aᵢ = max_k |u_k(eᵢ)| (the
            /// magnitude of a 2-axis control; how
            /// strongly θᵢ reaches the forces; 1 for every built-in parametrisation): the largest
            /// resolved force, in θᵢ's units. (For a nonlinear [`ControlMap`], aᵢ is its response to a
            /// unit θᵢ at θ = 0.)
            fn param_scales(&self) -> Vec<f64> {
                let limit = resolved_control_limit(self);
                let n = ControlProblem::n_params(self);
                (0..n)
                    .map(|i| {
                        let mut e = vec![0.0; n];
                        e[i] = 1.0;
                        let a = ControlProblem::control_magnitudes(self, &e)
                            .map(|u| u.iter().fold(0.0f64, |m, x| m.max(x.abs())))
                            .unwrap_or(0.0);
                        if a > 0.0 && a.is_finite() {
                            limit / a
                        } else {
                            limit
                        }
                    })
                    .collect()
            }
            /// Every force |u_k| ≤ [`resolved_control_limit`] (|u_k| = √(u_{x,k}² + u_{z,k}²) for a
            /// 2-axis control); otherwise [`Error::ControlOutOfRange`].
            fn check_range(&self, theta: &[f64]) -> Result<()> {
                let u = if self.is_two_axis() {
                    ControlProblem::control_magnitudes(self, theta)?
                } else {
                    ControlProblem::controls(self, theta)?
                };
                let limit = resolved_control_limit(self);
                match u.iter().position(|x| x.abs() > limit) {
                    Some(k) => Err(Error::ControlOutOfRange {
                        index: k,
                        value: u[k],
                        limit,
                    }),
                    None => Ok(()),
                }
            }
            fn shape(&self) -> Option<ProblemShape> {
                let chain = self.chain();
                Some(ProblemShape {
                    params: ControlProblem::n_params(self),
                    steps: self.steps(),
                    pendulums: chain.n(),
                    dim: $dim,
                    structured: self
                        .objective()
                        .gauss_newton(crate::adjoint::MomentStage {
                            k: 0,
                            steps: self.steps(),
                            h: self.time_step(),
                            moment: 0.0,
                        })
                        .is_some()
                        && chain.tip_condition() == crate::TipCondition::Free
                        && chain.control_node().is_some(),
                })
            }
            /// [`crate::ocp::solve`]: per-step, piecewise and constant controls of an objective in
            /// Gauss-Newton form ([`Objective::gauss_newton`]); in the spatial model the 2-axis
            /// control (two controls per stage) and the vector moment.
            fn riccati(
                &self,
                theta0: &[f64],
                options: &OcpOptions,
                observer: Option<IterationObserver<'_>>,
            ) -> Option<Result<OcpResult>> {
                Some(
                    crate::ocp::Solver::new(self, options).and_then(|mut s| match observer {
                        Some(o) => s.solve_observed(theta0, o),
                        None => s.solve(theta0),
                    }),
                )
            }
            /// [`crate::ocp::Condensed`]: the same problems as the Riccati solver.
            fn condensed(
                &self,
                theta0: &[f64],
                options: &OcpOptions,
                observer: Option<IterationObserver<'_>>,
            ) -> Option<Result<OcpResult>> {
                Some(
                    crate::ocp::Condensed::new(self, options).and_then(|mut c| match observer {
                        Some(o) => c.solve_observed(theta0, o),
                        None => c.solve(theta0),
                    }),
                )
            }
        }
    };
}

impl_optim_problem!(2);
impl_optim_problem!(3);

impl<P: ControlMap, O: Objective, const DIM: usize> HessianVec for ControlProblem<P, O, DIM> {
    /// Forward-over-adjoint ([`ControlProblem::hessian_vec`]).
    fn hessian_vec(&self, theta: &[f64], v: &[f64]) -> Result<Vec<f64>> {
        ControlProblem::hessian_vec(self, theta, v)
    }
}

// ---------------------------------------------------------------------------------------------
// Parameters without effect
// ---------------------------------------------------------------------------------------------

/// The relative change of J below which a parameter has no effect ([`ineffective_params`]).
///
/// A control that matters changes J by a sizeable fraction of itself across its range; one that
/// cannot act (a force on a node the supports lock) changes it by round-off only. Measured on
/// the fixed-fixed beam with a tip control (thesis §2.4.2 scene, whose tip is locked): the
/// adjoint's round-off gradient predicts changes of 2·10⁻¹³ to 3·10⁻¹⁰ of J across the resolved
/// range (3·10⁴ N), the Hessian column 10⁻³⁰ or exactly 0. On the thesis riser, every control
/// that acts (loads at nodes 1-10, constant and per-step, c and c_sum, at u = 0) predicts a
/// first-order change of 8·10⁻⁶ to 5·10⁴ of J. 10⁻⁸ lies between the two, thirty times above the
/// round-off and eight hundred times below the weakest working control (which the Hessian test
/// would clear in any case).
pub const NO_EFFECT_TOL: f64 = 1e-8;

/// The outcome of [`ineffective_params`].
#[derive(Clone, Debug, Default, PartialEq)]
pub struct NoEffectCheck {
    /// The parameters found without effect.
    pub params: Vec<usize>,
    /// The largest first- plus second-order relative change of J among them.
    pub relative_change: f64,
    /// The number of parameters (all of them, or only some).
    pub n_params: usize,
    /// Hessian-vector products spent.
    pub hvps: usize,
}

impl NoEffectCheck {
    /// Whether a run must be refused: no parameter acts, or one without effect has a nonzero
    /// (round-off) gradient in `g0`, which an optimiser would chase.
    pub fn refuses(&self, g0: &[f64]) -> bool {
        !self.params.is_empty()
            && (self.params.len() == self.n_params || self.params.iter().any(|&i| g0[i] != 0.0))
    }
}

/// The parameters of `problem` that have no effect on J at θ₀, given J₀ = J(θ₀) and g₀ = ∇J(θ₀).
///
/// θᵢ has no effect when moving it across its scale sᵢ ([`OptimProblem::param_scales`]) changes
/// J by at most [`NO_EFFECT_TOL`]·|J₀| to first *and* second order:
/// ```text
/// |g₀ᵢ| sᵢ ≤ τ |J₀|   and   ½ ‖H eᵢ‖∞ sᵢ² ≤ τ |J₀|,   τ = NO_EFFECT_TOL.
/// ```
/// The first test is free; only the parameters that pass it cost a Hessian-vector product, and
/// only when that can matter: a parameter whose gradient is exactly zero while another one
/// fails the first test is left alone (a step of L-BFGS or Newton never moves an exactly zero
/// component, e.g. u_N of a per-step control, thesis §3.3.1). [`minimize`](super::minimize)
/// refuses the start when [`NoEffectCheck::refuses`]. Without Hessian-vector products nothing is
/// reported: a small gradient alone does not tell a flat start from a parameter without effect.
///
/// # Errors
/// A failed Hessian-vector product.
pub fn ineffective_params<Q: OptimProblem + ?Sized>(
    problem: &Q,
    theta0: &[f64],
    j0: f64,
    g0: &[f64],
) -> Result<NoEffectCheck> {
    let mut check = NoEffectCheck {
        n_params: g0.len(),
        ..NoEffectCheck::default()
    };
    let Some(hvp) = problem.hessian() else {
        return Ok(check);
    };
    let scales = problem.param_scales();
    let allowed = NO_EFFECT_TOL * j0.abs();
    let suspects: Vec<usize> = (0..g0.len())
        .filter(|&i| g0[i].abs() * scales[i] <= allowed)
        .collect();
    let all = suspects.len() == g0.len();
    for i in suspects {
        if !all && g0[i] == 0.0 {
            continue;
        }
        let mut e = vec![0.0; g0.len()];
        e[i] = 1.0;
        let h = hvp.hessian_vec(theta0, &e)?;
        check.hvps += 1;
        let hmax = h.iter().fold(0.0f64, |m, x| m.max(x.abs()));
        let s = scales[i];
        let second = 0.5 * hmax * s * s;
        if second <= allowed {
            check.params.push(i);
            let change = g0[i].abs() * s + second;
            let rel = if j0 != 0.0 { change / j0.abs() } else { 0.0 };
            check.relative_change = check.relative_change.max(rel);
        }
    }
    Ok(check)
}
