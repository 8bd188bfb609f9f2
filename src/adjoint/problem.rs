//! The optimal-control problem on a scene: value, adjoint gradient, parameter gradients and
//! Hessian-vector products (forward-over-adjoint).

use super::{
    adjoint_gradient_from, forward_value_from, AdjointResult, BendingObjective, Checkpointing,
    ControlMap, Objective, Parametrisation, PerStepControl, PiecewiseControl, Start,
};
use crate::error::{Error, Result};
use crate::model::{Chain, Parameter, Scalar};
use crate::rattle::State;
use crate::scene::{ControlKind, ObjectiveKind, Scene};
use num_dual::Dual64;

/// An optimal-control problem on a scene: J(θ) = Σ ℓ_k(M₀(t_k), u_k(θ)) over the RATTLE
/// trajectory, with exact gradients by the discrete adjoint and Hessian-vector products by
/// forward-over-adjoint.
#[derive(Clone, Debug)]
pub struct ControlProblem<P = Parametrisation, O = BendingObjective> {
    chain: Chain<f64, 2>,
    h: f64,
    steps: usize,
    map: P,
    objective: O,
    checkpointing: Checkpointing,
    start: Option<Start<f64, 2>>,
}

impl ControlProblem<Parametrisation, BendingObjective> {
    /// The problem a scene file describes: its `[control]` (node and kind; default: constant at
    /// the tip) and `[objective]` (default: final), without effort penalty.
    pub fn from_scene(scene: &Scene) -> Result<Self> {
        let map = match scene.control.as_ref().map(|c| c.kind) {
            Some(ControlKind::PerStep) => Parametrisation::PerStep(PerStepControl {
                steps: scene.time.steps,
            }),
            Some(ControlKind::Piecewise) => Parametrisation::Piecewise(PiecewiseControl {
                steps: scene.time.steps,
                pieces: scene.control.as_ref().map_or(1, |c| c.values.len()),
            }),
            _ => Parametrisation::Constant,
        };
        let obj = BendingObjective {
            kind: scene.objective.unwrap_or(ObjectiveKind::Final),
            effort: 0.0,
        };
        ControlProblem::new(scene, map, obj)
    }
}

impl<P: ControlMap, O: Objective> ControlProblem<P, O> {
    /// A problem with the given parametrisation and objective; the control acts at the scene's
    /// control node (default: the tip n).
    pub fn new(scene: &Scene, map: P, objective: O) -> Result<Self> {
        let mut chain = Chain::<f64, 2>::from_scene(scene)?;
        if chain.control_node().is_none() {
            chain.set_control_node(Some(scene.n()))?;
        }
        Ok(ControlProblem {
            chain,
            h: scene.time.step,
            steps: scene.time.steps,
            map,
            objective,
            checkpointing: Checkpointing::default(),
            start: None,
        })
    }

    /// The same problem on a horizon that starts from `state` at time `t0` (instead of the
    /// straight beam at rest at t = 0): step k runs from t₀ + k h with the controls u_k, u_{k+1}
    /// of θ (indexed from 0 on this horizon), so the tail of a longer run from its state at step m
    /// is this problem with t₀ = m h. The state's μ is the first step's Newton predictor (all
    /// zero: computed). The state is data: gradients are with respect to θ only.
    ///
    /// # Errors
    /// [`Error::WrongLength`] / [`Error::NotFinite`] naming the part of the state (or the start
    /// time), [`Error::InvalidArgument`] when the state is off the constraint manifold
    /// (ĝ(q) = 0 and Ĝ(q) M⁻¹ p = 0 to [`crate::adjoint::START_TOLERANCE`]).
    pub fn starting_from(mut self, state: State<f64, 2>, t0: f64) -> Result<Self> {
        let start = Start { state, t0 };
        start.check(&self.chain)?;
        self.start = Some(start);
        Ok(self)
    }

    /// The start of the horizon (None: the straight beam at rest at t = 0).
    pub fn start(&self) -> Option<&Start<f64, 2>> {
        self.start.as_ref()
    }

    /// Sets the checkpointing strategy (default [`Checkpointing::Auto`]).
    pub fn with_checkpointing(mut self, c: Checkpointing) -> Self {
        self.checkpointing = c;
        self
    }

    /// Number of parameters θ.
    pub fn n_params(&self) -> usize {
        self.map.n_params()
    }

    /// Number of steps N.
    pub fn steps(&self) -> usize {
        self.steps
    }

    /// The time step h.
    pub fn time_step(&self) -> f64 {
        self.h
    }

    /// The objective.
    pub fn objective(&self) -> &O {
        &self.objective
    }

    /// The model (f64).
    pub fn chain(&self) -> &Chain<f64, 2> {
        &self.chain
    }

    /// The parametrisation.
    pub fn map(&self) -> &P {
        &self.map
    }

    fn check_theta(&self, theta: &[f64], name: &'static str) -> Result<()> {
        if theta.len() != self.map.n_params() {
            return Err(Error::WrongLength {
                name,
                expected: self.map.n_params(),
                got: theta.len(),
            });
        }
        match theta.iter().position(|x| !x.is_finite()) {
            Some(index) => Err(Error::NotFinite { name, index }),
            None => Ok(()),
        }
    }

    /// The per-step controls u_0..u_N of θ.
    pub fn controls(&self, theta: &[f64]) -> Result<Vec<f64>> {
        self.check_theta(theta, "theta")?;
        let mut u = vec![0.0; self.steps + 1];
        self.map.controls(theta, &mut u);
        Ok(u)
    }

    /// J(θ) by one forward simulation (no storage).
    pub fn value(&self, theta: &[f64]) -> Result<f64> {
        let u = self.controls(theta)?;
        forward_value_from(
            &self.chain,
            self.h,
            self.steps,
            &u,
            &self.objective,
            self.start.as_ref(),
        )
    }

    /// (J(θ), ∇J(θ)) by the discrete adjoint.
    pub fn value_and_gradient(&self, theta: &[f64]) -> Result<(f64, Vec<f64>)> {
        let u = self.controls(theta)?;
        self.theta_gradient(&self.chain, &u)
    }

    /// J and ∇_θJ = (∂u/∂θ)ᵀ ∇_u J for controls `u` on `chain`, in any scalar type.
    fn theta_gradient<D: Scalar>(&self, chain: &Chain<D, 2>, u: &[D]) -> Result<(D, Vec<D>)> {
        let start = self.start_as::<D>();
        let r = adjoint_gradient_from(
            chain,
            self.h,
            self.steps,
            u,
            &self.objective,
            &[],
            self.checkpointing,
            start.as_ref(),
        )?;
        let mut g = vec![D::zero(); self.map.n_params()];
        self.map.transpose(&r.control_gradient, &mut g);
        Ok((r.value, g))
    }

    /// ∇J(θ) by the discrete adjoint.
    pub fn gradient(&self, theta: &[f64]) -> Result<Vec<f64>> {
        Ok(self.value_and_gradient(theta)?.1)
    }

    /// The full adjoint result at θ, with gradients for the physical parameters `params` too.
    pub fn adjoint(&self, theta: &[f64], params: &[Parameter]) -> Result<AdjointResult<f64>> {
        let u = self.controls(theta)?;
        adjoint_gradient_from(
            &self.chain,
            self.h,
            self.steps,
            &u,
            &self.objective,
            params,
            self.checkpointing,
            self.start.as_ref(),
        )
    }

    /// ∂J/∂θ_phys for physical parameters (stiffnesses, mass, drag, load magnitudes).
    pub fn parameter_gradient(&self, theta: &[f64], params: &[Parameter]) -> Result<Vec<f64>> {
        Ok(self.adjoint(theta, params)?.parameter_gradient)
    }

    /// The Hessian-vector product ∇²J(θ) v by forward-over-adjoint: the forward and adjoint sweeps
    /// run in `Dual64` with θ seeded along v.
    pub fn hessian_vec(&self, theta: &[f64], v: &[f64]) -> Result<Vec<f64>> {
        self.check_theta(theta, "theta")?;
        self.check_theta(v, "v")?;
        let th: Vec<Dual64> = theta
            .iter()
            .zip(v)
            .map(|(&t, &d)| Dual64::new(t, d))
            .collect();
        let mut u = vec![Dual64::from(0.0); self.steps + 1];
        self.map.controls(&th, &mut u);
        let (_, g) = self.theta_gradient(&self.chain_as::<Dual64>(), &u)?;
        Ok(g.iter().map(|x| x.eps).collect())
    }

    /// The start lifted to another scalar type.
    fn start_as<D: Scalar>(&self) -> Option<Start<D, 2>> {
        self.start.as_ref().map(|s| Start {
            state: s.state.lift(),
            t0: s.t0,
        })
    }

    /// The model lifted to another scalar type.
    pub fn chain_as<D: Scalar>(&self) -> Chain<D, 2> {
        self.chain.lift()
    }
}
