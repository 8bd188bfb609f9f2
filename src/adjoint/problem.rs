//! The optimal-control problem on a scene: value, adjoint gradient, parameter gradients and
//! Hessian-vector products (forward-over-adjoint).

use super::{
    adjoint_gradient_from, forward_value_from, AdjointResult, BendingObjective, Checkpointing,
    ControlMap, Objective, Parametrisation, Start, StartKick,
};
use crate::base::{Parameter, Scalar};
use crate::error::{Error, Result};
use crate::model::Chain;
use crate::scene::Checked;
use crate::steppers::rattle::State;
use num_dual::Dual64;

/// An optimal-control problem on a scene: J(θ) = Σ ℓ_k(M₀(t_k), u_k(θ)) over the RATTLE
/// trajectory, with exact gradients by the discrete adjoint and Hessian-vector products by
/// forward-over-adjoint.
///
/// Built one way, [`ControlProblem::builder`]: the scene chooses the model
/// ([`ProblemBuilder::build`](super::ProblemBuilder::build) gives an
/// [`AnyProblem`](super::AnyProblem), planar or spatial), or code written over one model asks
/// for it ([`ProblemBuilder::build_in`](super::ProblemBuilder::build_in)). `DIM = 2` (the
/// default) is the planar model, `DIM = 3` the spatial one, whose control may be 2-axis. A
/// 2-axis control u_k = (u_{x,k}, u_{z,k}) has θ = (θ_x; θ_z): the map's m parameters of the x
/// components first, then the m of the z components (2m in all, docs/conventions.md "Two-axis
/// controls").
#[derive(Clone, Debug)]
pub struct ControlProblem<P = Parametrisation, O = BendingObjective, const DIM: usize = 2> {
    chain: Chain<f64, DIM>,
    h: f64,
    steps: usize,
    map: P,
    objective: O,
    checkpointing: Checkpointing,
    two_axis: bool,
    start: Option<Start<f64, DIM>>,
}

impl<P: ControlMap, O: Objective, const DIM: usize> ControlProblem<P, O, DIM> {
    /// The same problem on `chain`, a chain of the same scene whose loads are realised over a
    /// longer record than the horizon (its wave kinematics tabulated further): a receding-horizon
    /// controller whose horizons start at t₀ > 0 then reads the tables instead of summing every
    /// wave component beyond a horizon-long record (src/mpc/receding.rs).
    pub(crate) fn with_chain(mut self, chain: Chain<f64, DIM>) -> Self {
        debug_assert_eq!(chain.n(), self.chain.n());
        self.chain = chain;
        self
    }

    /// The problem of [`ProblemBuilder::build_in`](super::ProblemBuilder::build_in): the
    /// scene's chain in the model `DIM`, the control at the scene's control node (default: the
    /// tip n).
    ///
    /// # Errors
    /// [`Scene::check_stored_trajectory`]'s; the model's.
    pub(super) fn assemble(
        checked: Checked<'_>,
        map: P,
        objective: O,
        two_axis: bool,
        checkpointing: Checkpointing,
    ) -> Result<Self> {
        let scene = checked.scene();
        scene.check_stored_trajectory()?;
        let mut chain = Chain::<f64, DIM>::from_checked(checked)?;
        if chain.control_node().is_none() {
            chain.set_control_node(Some(scene.n()))?;
        }
        crate::statics::set_static_start(&mut chain, scene)?;
        Ok(ControlProblem {
            chain,
            h: scene.time.step,
            steps: scene.time.steps,
            map,
            objective,
            checkpointing,
            two_axis,
            start: None,
        })
    }

    /// The same problem on a horizon that starts from `state` at time `t0` (instead of the
    /// straight beam at rest at t = 0): step k runs from t₀ + k h with the controls u_k, u_{k+1}
    /// of θ (indexed from 0 on this horizon), so the tail of a longer run from its state at step m
    /// is this problem with t₀ = m h. The state's momentum is p₀ itself, with the control's
    /// half-kick at t₀ in it ([`StartKick::Included`]): the horizon's u₀ acts through the first
    /// half-kick of step 0 only, so ∂J/∂u₀ is not the run's ∂J/∂u_m (for a start whose kick the
    /// horizon's u₀ supplies, [`ControlProblem::starting_before_kick`]). The state's
    /// multipliers, if any, give the first step's Newton predictor (`None`: the consistent
    /// multiplier). The state is data: gradients are with respect to θ only.
    ///
    /// # Errors
    /// [`Error::WrongLength`] / [`Error::NotFinite`] naming the part of the state (or the start
    /// time), [`StartError::OffManifold`](super::StartError::OffManifold) when the state is off the constraint manifold
    /// (ĝ(q) = 0 and Ĝ(q) M⁻¹ p = 0 to [`crate::adjoint::START_TOLERANCE`]).
    pub fn starting_from(self, state: State<f64, DIM>, t0: f64) -> Result<Self> {
        self.with_start(state, t0, StartKick::Included)
    }

    /// The same problem on a horizon that starts from `state_hat` = (q₀, p̂₀) at time `t0` with
    /// the control's half-kick at t₀ still pending ([`StartKick::Pending`]): p̂₀ is the momentum
    /// of the step into t₀ taken with zero control in its second half-kick, and the horizon's
    /// first force supplies that half-kick,
    /// ```text
    /// p₀ = p̂₀ − (h/2) P(q₀)(u₀ b + u_{x,0} b_x),   P(q) = I − Ĝᵀ(Ĝ M⁻¹ Ĝᵀ)⁻¹ Ĝ M⁻¹,
    /// ```
    /// b = ∂U_q/∂u, b_x = ∂U_q/∂u_x (docs of [`Start`]). So the tail of a longer run from step m
    /// is this problem with θ's u₀ = the run's u_m, and ∂J/∂u₀ is the run's ∂J/∂u_m from the
    /// tail's stages (unlike [`ControlProblem::starting_from`], where u₀ acts only through the
    /// first half-kick of step 0). Value, gradient, Hessian-vector products and the Riccati
    /// solver [`crate::ocp`] all honour it.
    ///
    /// # Errors
    /// As [`ControlProblem::starting_from`]; [`StartError::PendingKickWithReactionTip`](super::StartError::PendingKickWithReactionTip) for a
    /// reaction-force tip, whose control is not a force term.
    pub fn starting_before_kick(self, state_hat: State<f64, DIM>, t0: f64) -> Result<Self> {
        self.with_start(state_hat, t0, StartKick::Pending)
    }

    fn with_start(mut self, state: State<f64, DIM>, t0: f64, kick: StartKick) -> Result<Self> {
        let start = Start { state, t0, kick };
        start.check(&self.chain)?;
        self.start = Some(start);
        Ok(self)
    }

    /// The start of the horizon (None: the straight beam at rest at t = 0).
    pub fn start(&self) -> Option<&Start<f64, DIM>> {
        self.start.as_ref()
    }

    /// The start lifted to another scalar type.
    fn start_as<D: Scalar>(&self) -> Option<Start<D, DIM>> {
        self.start.as_ref().map(|s| Start {
            state: s.state.lift(),
            t0: s.t0,
            kick: s.kick,
        })
    }

    /// Number of parameters θ (2m for a 2-axis control of a map of m).
    pub fn n_params(&self) -> usize {
        self.map.n_params() * if self.two_axis { 2 } else { 1 }
    }

    /// Whether the control is 2-axis (θ = (θ_x; θ_z)).
    pub fn is_two_axis(&self) -> bool {
        self.two_axis
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
    pub fn chain(&self) -> &Chain<f64, DIM> {
        &self.chain
    }

    /// The parametrisation.
    pub fn map(&self) -> &P {
        &self.map
    }

    fn check_theta(&self, theta: &[f64], name: &'static str) -> Result<()> {
        if theta.len() != self.n_params() {
            return Err(Error::WrongLength {
                name,
                expected: self.n_params(),
                got: theta.len(),
            });
        }
        match theta.iter().position(|x| !x.is_finite()) {
            Some(index) => Err(Error::NotFinite { name, index }),
            None => Ok(()),
        }
    }

    /// (θ_x, θ_z): the blocks of a 2-axis θ, or (∅, θ).
    fn split<'t, D>(&self, theta: &'t [D]) -> (&'t [D], &'t [D]) {
        if self.two_axis {
            theta.split_at(self.map.n_params())
        } else {
            (&[], theta)
        }
    }

    /// The per-step controls u_0..u_N of θ (their z components for a 2-axis control).
    pub fn controls(&self, theta: &[f64]) -> Result<Vec<f64>> {
        self.check_theta(theta, "theta")?;
        let mut u = vec![0.0; self.steps + 1];
        self.map.controls(self.split(theta).1, &mut u);
        Ok(u)
    }

    /// The x components u_{x,0..N} of a 2-axis control of θ (empty for a 1-axis control).
    pub fn controls_x(&self, theta: &[f64]) -> Result<Vec<f64>> {
        self.check_theta(theta, "theta")?;
        Ok(self.expand_x(self.split(theta).0))
    }

    /// The magnitudes |u_k| = √(u_{x,k}² + u_{z,k}²), k = 0..=N.
    pub fn control_magnitudes(&self, theta: &[f64]) -> Result<Vec<f64>> {
        let (u, ux) = (self.controls(theta)?, self.controls_x(theta)?);
        let x = |k: usize| ux.get(k).copied().unwrap_or(0.0);
        Ok(u.iter().enumerate().map(|(k, z)| x(k).hypot(*z)).collect())
    }

    /// u_x = the map of θ_x (empty for a 1-axis control), in any scalar.
    fn expand_x<D: Scalar>(&self, theta_x: &[D]) -> Vec<D> {
        if !self.two_axis {
            return Vec::new();
        }
        let mut ux = vec![D::zero(); self.steps + 1];
        self.map.controls(theta_x, &mut ux);
        ux
    }

    /// The model over `D` with the x components `ux` of a 2-axis control.
    fn chain_with_x<D: Scalar>(&self, ux: &[D]) -> Result<Chain<D, DIM>> {
        let mut chain = self.chain.lift::<D>();
        chain.set_control_x(ux)?;
        Ok(chain)
    }

    /// J(θ) by one forward simulation (no storage).
    pub fn value(&self, theta: &[f64]) -> Result<f64> {
        let u = self.controls(theta)?;
        let ux = self.expand_x(self.split(theta).0);
        let (h, n, obj, s) = (self.h, self.steps, &self.objective, self.start.as_ref());
        if ux.is_empty() {
            return forward_value_from(&self.chain, h, n, &u, obj, s);
        }
        let chain = self.chain_with_x(&ux)?;
        forward_value_from(&chain, h, n, &u, obj, s)
    }

    /// (J(θ), ∇J(θ)) by the discrete adjoint.
    pub fn value_and_gradient(&self, theta: &[f64]) -> Result<(f64, Vec<f64>)> {
        let r = self.adjoint(theta, &[])?;
        Ok((r.value, self.theta_bar(&r)))
    }

    /// ∇_θJ = (∂u/∂θ)ᵀ ∇_u J (both blocks for a 2-axis control), in any scalar type.
    fn theta_bar<D: Scalar>(&self, r: &AdjointResult<D>) -> Vec<D> {
        let m = self.map.n_params();
        let mut g = vec![D::zero(); self.n_params()];
        let (gx, gz) = g.split_at_mut(if self.two_axis { m } else { 0 });
        self.map.transpose(&r.control_gradient, gz);
        if self.two_axis {
            self.map.transpose(&r.control_gradient_x, gx);
        }
        g
    }

    /// ∇J(θ) by the discrete adjoint.
    pub fn gradient(&self, theta: &[f64]) -> Result<Vec<f64>> {
        Ok(self.value_and_gradient(theta)?.1)
    }

    /// The full adjoint result at θ, with gradients for the physical parameters `params` too
    /// (and ∂J/∂u_{x,k} for a 2-axis control).
    pub fn adjoint(&self, theta: &[f64], params: &[Parameter]) -> Result<AdjointResult<f64>> {
        let u = self.controls(theta)?;
        let ux = self.expand_x(self.split(theta).0);
        let (h, n, obj, c) = (self.h, self.steps, &self.objective, self.checkpointing);
        let s = self.start.as_ref();
        if ux.is_empty() {
            return adjoint_gradient_from(&self.chain, (h, n), &u, obj, params, c, s);
        }
        let chain = self.chain_with_x(&ux)?;
        adjoint_gradient_from(&chain, (h, n), &u, obj, params, c, s)
    }

    /// [`ControlProblem::adjoint`] with parameters the chain's per-node quantities carry too
    /// (`nodes`, [`super::adjoint_gradient_with_nodes`]): the adjoint result and ∂J/∂θ for each
    /// of `nodes`, from the same sweep. The seeded chains of [`super::SeededNodes`] must be this
    /// problem's chain in their real parts.
    ///
    /// # Errors
    /// [`ControlProblem::adjoint`]'s and [`super::adjoint_gradient_with_nodes`]'s.
    pub fn adjoint_with_nodes(
        &self,
        theta: &[f64],
        params: &[Parameter],
        nodes: Vec<Box<dyn super::NodeTangent<f64, DIM> + '_>>,
    ) -> Result<(AdjointResult<f64>, Vec<f64>)> {
        let u = self.controls(theta)?;
        let ux = self.expand_x(self.split(theta).0);
        let (h, n, obj, c) = (self.h, self.steps, &self.objective, self.checkpointing);
        let s = self.start.as_ref();
        let run = super::adjoint_gradient_with_nodes;
        if ux.is_empty() {
            return run(&self.chain, (h, n), (&u, obj), params, nodes, c, s);
        }
        let chain = self.chain_with_x(&ux)?;
        run(&chain, (h, n), (&u, obj), params, nodes, c, s)
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
        let (thx, thz) = self.split(&th);
        let mut u = vec![Dual64::from(0.0); self.steps + 1];
        self.map.controls(thz, &mut u);
        let chain = self.chain_with_x(&self.expand_x(thx))?;
        let (h, n, obj, c) = (self.h, self.steps, &self.objective, self.checkpointing);
        let start = self.start_as::<Dual64>();
        let r = adjoint_gradient_from(&chain, (h, n), &u, obj, &[], c, start.as_ref())?;
        Ok(self.theta_bar(&r).iter().map(|x| x.eps).collect())
    }

    /// The model lifted to another scalar type (without the x components of a 2-axis control,
    /// which the problem sets per evaluation).
    pub fn chain_as<D: Scalar>(&self) -> Chain<D, DIM> {
        self.chain.lift()
    }
}
