//! The optimal-control problem on a scene: value, adjoint gradient, parameter gradients and
//! Hessian-vector products (forward-over-adjoint).

use super::{
    adjoint_gradient, forward_value, AdjointResult, BendingObjective, Checkpointing, ControlMap,
    Objective, Parametrisation, PerStepControl, PiecewiseControl,
};
use crate::error::{Error, Result};
use crate::model::{Chain, Parameter, Scalar};
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
        })
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
        forward_value(&self.chain, self.h, self.steps, &u, &self.objective)
    }

    /// (J(θ), ∇J(θ)) by the discrete adjoint.
    pub fn value_and_gradient(&self, theta: &[f64]) -> Result<(f64, Vec<f64>)> {
        let u = self.controls(theta)?;
        self.theta_gradient(&self.chain, &u)
    }

    /// J and ∇_θJ = (∂u/∂θ)ᵀ ∇_u J for controls `u` on `chain`, in any scalar type.
    fn theta_gradient<D: Scalar>(&self, chain: &Chain<D, 2>, u: &[D]) -> Result<(D, Vec<D>)> {
        let r = adjoint_gradient(
            chain,
            self.h,
            self.steps,
            u,
            &self.objective,
            &[],
            self.checkpointing,
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
        adjoint_gradient(
            &self.chain,
            self.h,
            self.steps,
            &u,
            &self.objective,
            params,
            self.checkpointing,
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

    /// The model lifted to another scalar type.
    pub fn chain_as<D: Scalar>(&self) -> Chain<D, 2> {
        self.chain.lift()
    }
}
