//! A thin comparison layer over the [`crate::steppers`] (RATTLE, SHAKE, projected RK4), for
//! speed-against-accuracy and stability comparisons (`paper_figures`, `tests/steppers/integrators.rs`).
//!
//! The methods themselves live in [`crate::steppers`], one file each, generic over the scalar and
//! the dimension; see their module docs for the maths. This module adds:
//! * [`Run`]: any [`Stepper`] together with **its own** state, a constant control and a step
//!   counter, with the quantities the comparisons read (energy, node positions, constraint
//!   residual, Newton work);
//! * [`Integrator`]: one [`Run`] per [`IntegratorMethod`], for picking a method at run time over the planar
//!   `f64` model. Each variant holds its stepper and that stepper's state together, so no method
//!   can be handed another method's state.
//!
//! Failures are the steppers' typed [`crate::Error`]s: a Newton solve that does not converge, a
//! folded joint, a singular constraint system, a non-finite state. The reaction-force tip
//! ([`crate::TipCondition::Reaction`]) is only supported by RATTLE; SHAKE and projected RK4
//! refuse it at construction.

use crate::base::Scalar;
use crate::error::Result;
use crate::model::Chain;
use crate::scene::{ControlKind, Scene};
use crate::steppers::{
    check_finite, ProjectedRk4, Rattle, Shake, StepStats, Stepper, StepperError,
};

/// Which integrator.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum IntegratorMethod {
    /// RATTLE (the library's integrator, [`Rattle`]).
    Rattle,
    /// SHAKE (thesis §1.6) with central-difference momenta ([`Shake`]).
    Shake,
    /// Explicit RK4 on the index-1 equations with projection onto the constraints
    /// ([`ProjectedRk4`]).
    ProjectedRk4,
}

impl IntegratorMethod {
    /// Every method, in a stable order.
    pub const ALL: [IntegratorMethod; 3] = [
        IntegratorMethod::Rattle,
        IntegratorMethod::Shake,
        IntegratorMethod::ProjectedRk4,
    ];

    /// A short human-readable name.
    pub fn name(self) -> &'static str {
        match self {
            IntegratorMethod::Rattle => "RATTLE",
            IntegratorMethod::Shake => "SHAKE",
            IntegratorMethod::ProjectedRk4 => "projected RK4",
        }
    }
}

/// A stepper `S` with its own state, advancing from the straight beam at rest with a constant
/// control u.
pub struct Run<D: Scalar, const DIM: usize, S: Stepper<D, DIM>> {
    stepper: S,
    state: S::State,
    u: D,
    k: usize,
    newton: usize,
}

impl<D: Scalar, const DIM: usize, S> Clone for Run<D, DIM, S>
where
    S: Stepper<D, DIM> + Clone,
    S::State: Clone,
{
    fn clone(&self) -> Self {
        Run {
            stepper: self.stepper.clone(),
            state: self.state.clone(),
            u: self.u,
            k: self.k,
            newton: self.newton,
        }
    }
}

impl<D: Scalar, const DIM: usize, S> std::fmt::Debug for Run<D, DIM, S>
where
    S: Stepper<D, DIM> + std::fmt::Debug,
    S::State: std::fmt::Debug,
{
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Run")
            .field("stepper", &self.stepper)
            .field("state", &self.state)
            .field("u", &self.u)
            .field("k", &self.k)
            .field("newton", &self.newton)
            .finish()
    }
}

impl<D: Scalar, const DIM: usize, S: Stepper<D, DIM>> Run<D, DIM, S> {
    /// The stepper's initial state ([`Stepper::initial_state`]) with the constant control `u`.
    ///
    /// # Errors
    /// [`StepperError::NonFiniteControl`] if `u` is not finite; the errors of the initial state's set-up
    /// (SHAKE's starter).
    pub fn new(mut stepper: S, u: D) -> Result<Self> {
        if !u.re().is_finite() {
            return Err(StepperError::NonFiniteControl { u: u.re() }.into());
        }
        let state = stepper.initial_state(u)?;
        Ok(Run {
            stepper,
            state,
            u,
            k: 0,
            newton: 0,
        })
    }

    /// The stepper.
    pub fn stepper(&self) -> &S {
        &self.stepper
    }

    /// The current state.
    pub fn state(&self) -> &S::State {
        &self.state
    }

    /// The model.
    pub fn chain(&self) -> &Chain<D, DIM> {
        self.stepper.chain()
    }

    /// Step index k of the current state.
    pub fn step_index(&self) -> usize {
        self.k
    }

    /// Time t_k = k h of the current state.
    pub fn time(&self) -> f64 {
        self.k as f64 * self.stepper.h()
    }

    /// Attitudes q_k.
    pub fn q(&self) -> &[[D; DIM]] {
        self.stepper.q(&self.state)
    }

    /// Momenta p_k.
    pub fn p(&self) -> &[[D; DIM]] {
        self.stepper.p(&self.state)
    }

    /// Total Newton iterations (linear solves) so far, including SHAKE's starter (projected RK4
    /// counts its projection iterations).
    pub fn newton_iterations(&self) -> usize {
        self.newton
    }

    /// Total energy H(q_k, p_k; t_k, u) = ½ pᵀM⁻¹p + U.
    pub fn energy(&self) -> D {
        let ch = self.chain();
        let mut scratch = vec![[D::zero(); DIM]; ch.n()];
        ch.kinetic_energy(self.p(), &mut scratch)
            + ch.potential_energy(self.q(), self.time(), self.u)
    }

    /// Node positions rᵢ of nodes 1..=n.
    pub fn positions(&self) -> Vec<[D; DIM]> {
        let mut out = vec![[D::zero(); DIM]; self.chain().n()];
        self.chain().node_positions(self.q(), &mut out);
        out
    }

    /// The largest constraint violation max(|½(‖qᵢ‖² − 1)|, |tip z| / L) of the current state.
    pub fn constraint_residual(&self) -> f64 {
        let ch = self.chain();
        let mut r = vec![D::zero(); ch.n_constraints()];
        ch.constraints().residual(self.q(), D::zero(), &mut r)
    }

    /// Advances the state by one step.
    ///
    /// # Errors
    /// The stepper's typed errors (naming the step), and [`crate::Error::NonFinite`] for a non-finite
    /// new state.
    pub fn step(&mut self) -> Result<StepStats> {
        let s = self.stepper.step(&mut self.state, self.k, self.u, self.u)?;
        self.k += 1;
        self.newton += s.iterations;
        check_finite(self.q(), self.p(), self.k)?;
        Ok(s)
    }

    /// Advances `steps` steps.
    ///
    /// # Errors
    /// The first error of [`Run::step`].
    pub fn advance(&mut self, steps: usize) -> Result<()> {
        for _ in 0..steps {
            self.step()?;
        }
        Ok(())
    }
}

/// One of the three methods on the planar `f64` model, each variant holding its stepper and its
/// own state (boxed: the runs differ in size).
#[derive(Clone, Debug)]
pub enum Integrator {
    /// RATTLE.
    Rattle(Box<Run<f64, 2, Rattle<f64, 2>>>),
    /// SHAKE.
    Shake(Box<Run<f64, 2, Shake<f64, 2>>>),
    /// Projected RK4.
    ProjectedRk4(Box<Run<f64, 2, ProjectedRk4<f64, 2>>>),
}

/// Evaluates `$e` with `$r` bound to the variant's [`Run`] (each arm its own stepper type).
macro_rules! each {
    ($self:expr, $r:ident => $e:expr) => {
        match $self {
            Integrator::Rattle($r) => $e,
            Integrator::Shake($r) => $e,
            Integrator::ProjectedRk4($r) => $e,
        }
    };
}

/// The constant control of a scene (0 without one).
fn constant_control(scene: &Scene) -> Result<f64> {
    match &scene.control {
        None => Ok(0.0),
        Some(c) if c.kind == ControlKind::Constant => Ok(c.values[0]),
        Some(_) => Err(StepperError::NonConstantControl.into()),
    }
}

impl Integrator {
    /// An integrator for `scene`'s chain with step `h`, starting from the straight beam at rest at
    /// t = 0, with the scene's constant control (0 without one). The scene's own time grid is
    /// ignored.
    ///
    /// # Errors
    /// [`StepperError::StepNotPositive`] if `h` is not positive and finite,
    /// [`StepperError::NonConstantControl`] if the scene has a per-step control,
    /// [`StepperError::ReactionTipUnsupported`] / [`StepperError::PrescribedTipUnsupported`] if
    /// `method` is not RATTLE and the scene uses the reaction-force tip / a tip held by the
    /// vessel; the
    /// scene's own validation errors; and any error of the first step's set-up (SHAKE's starter).
    pub fn new(scene: &Scene, method: IntegratorMethod, h: f64) -> Result<Self> {
        let mut chain = Chain::<f64, 2>::from_scene(scene)?;
        crate::statics::set_static_start(&mut chain, scene)?;
        let u = constant_control(scene)?;
        if scene.control.is_none() {
            chain.set_control_node(None)?;
        }
        Self::from_chain(chain, method, h, u)
    }

    /// As [`Integrator::new`], from a chain and a constant control `u`.
    ///
    /// # Errors
    /// As [`Integrator::new`], and [`StepperError::NonFiniteControl`] for a non-finite `u`.
    pub fn from_chain(
        chain: Chain<f64, 2>,
        method: IntegratorMethod,
        h: f64,
        u: f64,
    ) -> Result<Self> {
        Ok(match method {
            IntegratorMethod::Rattle => {
                Integrator::Rattle(Box::new(Run::new(Rattle::new(chain, h)?, u)?))
            }
            IntegratorMethod::Shake => {
                Integrator::Shake(Box::new(Run::new(Shake::new(chain, h)?, u)?))
            }
            IntegratorMethod::ProjectedRk4 => {
                Integrator::ProjectedRk4(Box::new(Run::new(ProjectedRk4::new(chain, h)?, u)?))
            }
        })
    }

    /// The method.
    pub fn method(&self) -> IntegratorMethod {
        match self {
            Integrator::Rattle(_) => IntegratorMethod::Rattle,
            Integrator::Shake(_) => IntegratorMethod::Shake,
            Integrator::ProjectedRk4(_) => IntegratorMethod::ProjectedRk4,
        }
    }

    /// The model.
    pub fn chain(&self) -> &Chain<f64, 2> {
        each!(self, r => r.chain())
    }

    /// Step index k of the current state.
    pub fn step_index(&self) -> usize {
        each!(self, r => r.step_index())
    }

    /// Time t_k = k h of the current state.
    pub fn time(&self) -> f64 {
        each!(self, r => r.time())
    }

    /// Attitudes q_k.
    pub fn q(&self) -> &[[f64; 2]] {
        each!(self, r => r.q())
    }

    /// Momenta p_k.
    pub fn p(&self) -> &[[f64; 2]] {
        each!(self, r => r.p())
    }

    /// Total Newton iterations so far ([`Run::newton_iterations`]).
    pub fn newton_iterations(&self) -> usize {
        each!(self, r => r.newton_iterations())
    }

    /// Total energy H(q_k, p_k; t_k, u) = ½ pᵀM⁻¹p + U.
    pub fn energy(&self) -> f64 {
        each!(self, r => r.energy())
    }

    /// Node positions (y, z) of nodes 1..=n.
    pub fn positions(&self) -> Vec<[f64; 2]> {
        each!(self, r => r.positions())
    }

    /// The largest constraint violation max(|½(‖qᵢ‖² − 1)|, |tip z| / L) of the current state.
    pub fn constraint_residual(&self) -> f64 {
        each!(self, r => r.constraint_residual())
    }

    /// Advances the state by one step.
    ///
    /// # Errors
    /// A typed [`Error`](crate::Error) naming the step: Newton not converged, folded joint, singular system,
    /// or a non-finite state.
    pub fn step(&mut self) -> Result<StepStats> {
        each!(self, r => r.step())
    }

    /// Advances `steps` steps.
    ///
    /// # Errors
    /// The first error of [`Integrator::step`].
    pub fn advance(&mut self, steps: usize) -> Result<()> {
        each!(self, r => r.advance(steps))
    }
}

/// Integrates `scene` with `method` and step `h` for `steps` steps, calling `observe` on every
/// `every`-th state (k = 0, every, 2·every, … and the last).
///
/// # Errors
/// As [`Integrator::new`] and [`Integrator::step`].
pub fn integrate(
    scene: &Scene,
    method: IntegratorMethod,
    h: f64,
    steps: usize,
    every: usize,
    mut observe: impl FnMut(&Integrator),
) -> Result<Integrator> {
    let every = every.max(1);
    let mut it = Integrator::new(scene, method, h)?;
    observe(&it);
    for k in 1..=steps {
        it.step()?;
        if k % every == 0 || k == steps {
            observe(&it);
        }
    }
    Ok(it)
}
