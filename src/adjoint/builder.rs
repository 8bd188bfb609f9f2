//! The one way to build a [`ControlProblem`]: [`ControlProblem::builder`] on a scene, then the
//! parts that differ from the scene's own (`map`, `objective`, `two_axis`, `checkpointing`), then
//! [`ProblemBuilder::build`], which builds the problem in the model the scene needs
//! ([`AnyProblem`]), or [`ProblemBuilder::build_in`] for code written over one model.
//!
//! ```
//! use chainbeam::{catalogue, BendingObjective, ControlProblem, Parametrisation};
//!
//! let scene = catalogue::riser(5);
//! let problem = ControlProblem::builder(&scene)
//!     .map(Parametrisation::Constant)
//!     .objective(BendingObjective::summed_moment())
//!     .build()?;
//! let (j, grad) = problem.value_and_gradient(&[0.0])?;
//! assert!(j > 0.0 && grad.len() == 1);
//! # Ok::<(), chainbeam::Error>(())
//! ```

use super::{
    BendingObjective, Checkpointing, ControlMap, ControlProblem, Objective, Parametrisation,
    PerStepControl, PiecewiseControl,
};
use crate::base::Parameter;
use crate::error::{Error, Result};
use crate::scene::{Checked, ControlKind, ObjectiveKind, Scene, SceneInput, Validate};

/// The parts of a [`ControlProblem`] before it is built ([`ControlProblem::builder`]): the
/// scene, the parametrisation θ ↦ u_k (`P`), the objective (`O`), whether the control is 2-axis
/// and the adjoint's checkpointing. Each part starts as the scene says (its `[control]` and
/// `[objective]`) and each method replaces one.
#[derive(Clone, Debug)]
pub struct ProblemBuilder<'s, P = Parametrisation, O = BendingObjective> {
    scene: &'s Scene,
    /// The proof of the scene's validation when it came as a [`crate::ValidScene`].
    valid: Option<Checked<'s>>,
    map: P,
    objective: O,
    two_axis: bool,
    checkpointing: Checkpointing,
}

/// The parametrisation a scene's `[control]` asks for (default: constant).
pub(crate) fn scene_map(scene: &Scene) -> Parametrisation {
    match scene.control.as_ref().map(|c| c.kind) {
        Some(ControlKind::PerStep) => Parametrisation::PerStep(PerStepControl {
            steps: scene.time.steps,
        }),
        Some(ControlKind::Piecewise) => Parametrisation::Piecewise(PiecewiseControl {
            steps: scene.time.steps,
            pieces: scene.control.as_ref().map_or(1, |c| c.values.len()),
        }),
        _ => Parametrisation::Constant,
    }
}

/// The objective a scene's `[objective]` asks for (default: final), without effort penalty.
fn scene_objective(scene: &Scene) -> BendingObjective {
    BendingObjective {
        kind: scene.objective.unwrap_or(ObjectiveKind::Final),
        effort: 0.0,
    }
}

impl ControlProblem {
    /// The builder of the control problem on `scene`, its parts as the scene says: the
    /// parametrisation of its `[control]` (kind and number of values; without one, one constant
    /// force), its `[objective]` (default: the final moment) without effort penalty, a 2-axis
    /// control when `[control]` gives x components, the control at the scene's control node
    /// (default: the tip n), checkpointing [`Checkpointing::Auto`]. A [`Scene`] is validated
    /// when the problem is built, a [`crate::ValidScene`] was when it was made
    /// ([`SceneInput`]).
    pub fn builder<S: SceneInput + ?Sized>(scene: &S) -> ProblemBuilder<'_> {
        let (valid, scene) = (scene.known_valid(), scene.scene());
        ProblemBuilder {
            scene,
            valid,
            map: scene_map(scene),
            objective: scene_objective(scene),
            two_axis: scene.has_two_axis_control(),
            checkpointing: Checkpointing::default(),
        }
    }
}

impl<'s, P: ControlMap, O: Objective> ProblemBuilder<'s, P, O> {
    /// The parametrisation θ ↦ u_0..u_N (of each component, for a 2-axis control).
    pub fn map<Q: ControlMap>(self, map: Q) -> ProblemBuilder<'s, Q, O> {
        ProblemBuilder {
            scene: self.scene,
            valid: self.valid,
            map,
            objective: self.objective,
            two_axis: self.two_axis,
            checkpointing: self.checkpointing,
        }
    }

    /// The objective J(θ) = Σ ℓ_k.
    pub fn objective<R: Objective>(self, objective: R) -> ProblemBuilder<'s, P, R> {
        ProblemBuilder {
            scene: self.scene,
            valid: self.valid,
            map: self.map,
            objective,
            two_axis: self.two_axis,
            checkpointing: self.checkpointing,
        }
    }

    /// Whether the control is 2-axis, u_k = (u_{x,k}, u_{z,k}) with θ = (θ_x; θ_z), 2m
    /// parameters for a map of m (docs/conventions.md "Two-axis controls"); a 2-axis control
    /// needs the spatial model.
    pub fn two_axis(mut self, two_axis: bool) -> Self {
        self.two_axis = two_axis;
        self
    }

    /// The adjoint's checkpointing strategy (default [`Checkpointing::Auto`]).
    pub fn checkpointing(mut self, checkpointing: Checkpointing) -> Self {
        self.checkpointing = checkpointing;
        self
    }

    /// The problem in the model the scene needs: the spatial model (`DIM = 3`) when a load, the
    /// current or the control has an x component ([`Scene::spatial_key`]) or the control is
    /// 2-axis, the planar model (`DIM = 2`) otherwise.
    ///
    /// # Errors
    /// As [`ProblemBuilder::build_in`].
    pub fn build(self) -> Result<AnyProblem<P, O>> {
        Ok(if self.two_axis || self.scene.spatial_key().is_some() {
            AnyProblem::Spatial(self.build_in::<3>()?)
        } else {
            AnyProblem::Planar(self.build_in::<2>()?)
        })
    }

    /// The problem in the model of dimension `DIM` (2: planar, 3: spatial), for code written
    /// over one model or generic in it (the receding horizon of [`crate::mpc`] plans in the
    /// model of its controller). Any scene runs in the spatial model; the planar model refuses
    /// a scene that needs the spatial one.
    ///
    /// # Errors
    /// [`Error::NeedsSpatialModel`] naming the key for a 2-axis control (`control.values`) or a
    /// spatial scene in the planar model; [`Scene::check_stored_trajectory`]'s (naming
    /// `time.steps`) for a scene whose trajectory is over the stored-trajectory budget (the
    /// optimisers keep per-step quantities of that order); the model's errors.
    pub fn build_in<const DIM: usize>(self) -> Result<ControlProblem<P, O, DIM>> {
        if self.two_axis && DIM == 2 {
            return Err(Error::NeedsSpatialModel {
                key: "control.values".to_string(),
            });
        }
        let scene = match self.valid {
            Some(checked) => checked,
            None => self.scene.checked()?,
        };
        ControlProblem::assemble(
            scene,
            self.map,
            self.objective,
            self.two_axis,
            self.checkpointing,
        )
    }
}

/// A control problem in the model its scene needs ([`ProblemBuilder::build`]): the planar
/// model unless a load, the current or the control has an x component. Its methods are those
/// of [`ControlProblem`] in either model; match the variants for the rest (the model's chain,
/// a start state in the model's dimension).
// The two variants differ in size (the planar chain stores 2-vectors); a problem is built once
// per run, so boxing the larger one would only add an indirection.
#[allow(clippy::large_enum_variant)]
#[derive(Clone, Debug)]
pub enum AnyProblem<P = Parametrisation, O = BendingObjective> {
    /// Every force lies in the yz-plane: the planar model (`DIM = 2`), as in the thesis.
    Planar(ControlProblem<P, O, 2>),
    /// A load, the current or the control has an x component (or the control is 2-axis): the
    /// spatial model (`DIM = 3`).
    Spatial(ControlProblem<P, O, 3>),
}

/// `$body` with `$p` the problem of either variant.
macro_rules! either {
    ($self:expr, $p:ident => $body:expr) => {
        match $self {
            AnyProblem::Planar($p) => $body,
            AnyProblem::Spatial($p) => $body,
        }
    };
}

impl<P: ControlMap, O: Objective> AnyProblem<P, O> {
    /// The model's name: "planar" or "spatial".
    pub fn model_name(&self) -> &'static str {
        match self {
            AnyProblem::Planar(_) => "planar",
            AnyProblem::Spatial(_) => "spatial",
        }
    }

    /// The parametrisation (of each component, for a 2-axis control).
    pub fn map(&self) -> &P {
        either!(self, p => p.map())
    }

    /// Whether the control is 2-axis (θ = (θ_x; θ_z)).
    pub fn is_two_axis(&self) -> bool {
        either!(self, p => p.is_two_axis())
    }

    /// Number of parameters θ (2m for a 2-axis control of a map of m).
    pub fn n_params(&self) -> usize {
        either!(self, p => p.n_params())
    }

    /// J(θ) by one forward simulation ([`ControlProblem::value`]).
    ///
    /// # Errors
    /// As [`ControlProblem::value`].
    pub fn value(&self, theta: &[f64]) -> Result<f64> {
        either!(self, p => p.value(theta))
    }

    /// (J(θ), ∇J(θ)) by the discrete adjoint ([`ControlProblem::value_and_gradient`]).
    ///
    /// # Errors
    /// As [`ControlProblem::value_and_gradient`].
    pub fn value_and_gradient(&self, theta: &[f64]) -> Result<(f64, Vec<f64>)> {
        either!(self, p => p.value_and_gradient(theta))
    }

    /// ∇J(θ) by the discrete adjoint.
    ///
    /// # Errors
    /// As [`ControlProblem::gradient`].
    pub fn gradient(&self, theta: &[f64]) -> Result<Vec<f64>> {
        either!(self, p => p.gradient(theta))
    }

    /// ∂J/∂θ_phys for physical parameters ([`ControlProblem::parameter_gradient`]).
    ///
    /// # Errors
    /// As [`ControlProblem::parameter_gradient`].
    pub fn parameter_gradient(&self, theta: &[f64], params: &[Parameter]) -> Result<Vec<f64>> {
        either!(self, p => p.parameter_gradient(theta, params))
    }
}
