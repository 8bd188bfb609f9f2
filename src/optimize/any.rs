//! The control problem of a scene in the model it needs ([`AnyProblem`]: the planar model unless
//! a load, the current or the control has an x component), and the parameters θ₀ a scene's
//! `[control]` gives ([`scene_start`]). The command line and the Python bindings build their
//! problems here, so both evaluate the same code on the same floats.

use serde::Serialize;

use crate::adjoint::{BendingObjective, ControlMap, ControlProblem, Parametrisation};
use crate::error::Result;
use crate::ocp::{IterationObserver, OcpOptions, OcpResult};
use crate::scene::{Scene, SceneError, SceneErrorKind};

use super::{HessianVec, OptimProblem, ProblemShape};

/// The spatial control problem (`DIM = 3`), with a control along z or a 2-axis control.
pub type SpatialProblem = ControlProblem<Parametrisation, BendingObjective, 3>;

/// A control problem (thesis §3.3, J(θ) of eq. 3.3.2 or 3.3.4) in the model its scene needs:
/// "model no more than a scene needs".
// The two variants differ in size (the planar chain stores 2-vectors); a problem is built once
// per run, so boxing the larger one would only add an indirection.
#[allow(clippy::large_enum_variant)]
pub enum AnyProblem {
    /// Every force lies in the yz-plane: the planar model (`DIM = 2`), as in the thesis.
    Planar(ControlProblem),
    /// A load, the current or the control has an x component (or the controls are 2-axis): the
    /// spatial model (`DIM = 3`).
    Spatial(SpatialProblem),
}

impl AnyProblem {
    /// The planar problem, unless the scene needs the spatial model ([`Scene::spatial_key`]) or
    /// the control is 2-axis (`two_axis`: θ = (θ_x; θ_z), 2m parameters for a map of m).
    pub fn new(
        scene: &Scene,
        map: Parametrisation,
        objective: BendingObjective,
        two_axis: bool,
    ) -> Result<Self> {
        Ok(if two_axis || scene.spatial_key().is_some() {
            AnyProblem::Spatial(ControlProblem::spatial(scene, map, objective, two_axis)?)
        } else {
            AnyProblem::Planar(ControlProblem::new(scene, map, objective)?)
        })
    }

    /// The parametrisation (of each component, for a 2-axis control).
    pub fn map(&self) -> &Parametrisation {
        match self {
            AnyProblem::Planar(p) => p.map(),
            AnyProblem::Spatial(p) => p.map(),
        }
    }

    /// Whether the control is 2-axis (θ = (θ_x; θ_z)).
    pub fn is_two_axis(&self) -> bool {
        matches!(self, AnyProblem::Spatial(p) if p.is_two_axis())
    }

    /// The model's name: "planar" or "spatial".
    pub fn model_name(&self) -> &'static str {
        match self {
            AnyProblem::Planar(_) => "planar",
            AnyProblem::Spatial(_) => "spatial",
        }
    }

    /// θ (or a gradient with respect to θ) laid out as a scene file's `control.values`: numbers,
    /// or pairs [x, z] for a 2-axis control.
    pub fn layout(&self, theta: &[f64]) -> Values {
        if !self.is_two_axis() {
            return Values::Numbers(theta.to_vec());
        }
        let (x, z) = theta.split_at(theta.len() / 2);
        Values::Pairs(x.iter().zip(z).map(|(a, b)| [*a, *b]).collect())
    }

    /// The problem as the optimisers see it.
    fn optim(&self) -> &(dyn OptimProblem + Sync) {
        match self {
            AnyProblem::Planar(p) => p,
            AnyProblem::Spatial(p) => p,
        }
    }
}

/// The optimisers' view: every method delegates to the planar or spatial problem (the Riccati
/// and the condensed solver take both).
impl OptimProblem for AnyProblem {
    fn n_params(&self) -> usize {
        self.optim().n_params()
    }
    fn value(&self, theta: &[f64]) -> Result<f64> {
        self.optim().value(theta)
    }
    fn value_and_gradient(&self, theta: &[f64]) -> Result<(f64, Vec<f64>)> {
        self.optim().value_and_gradient(theta)
    }
    fn gradient(&self, theta: &[f64]) -> Result<Vec<f64>> {
        self.optim().gradient(theta)
    }
    fn hessian(&self) -> Option<&dyn HessianVec> {
        match self {
            AnyProblem::Planar(p) => Some(p),
            AnyProblem::Spatial(p) => Some(p),
        }
    }
    fn controls(&self, theta: &[f64]) -> Option<Result<Vec<f64>>> {
        self.optim().controls(theta)
    }
    fn param_scales(&self) -> Vec<f64> {
        self.optim().param_scales()
    }
    fn check_range(&self, theta: &[f64]) -> Result<()> {
        self.optim().check_range(theta)
    }
    fn shape(&self) -> Option<ProblemShape> {
        self.optim().shape()
    }
    fn riccati(
        &self,
        theta0: &[f64],
        options: &OcpOptions,
        observer: Option<IterationObserver<'_>>,
    ) -> Option<Result<OcpResult>> {
        match self {
            AnyProblem::Planar(p) => p.riccati(theta0, options, observer),
            AnyProblem::Spatial(p) => p.riccati(theta0, options, observer),
        }
    }
    fn condensed(
        &self,
        theta0: &[f64],
        options: &OcpOptions,
        observer: Option<IterationObserver<'_>>,
    ) -> Option<Result<OcpResult>> {
        match self {
            AnyProblem::Planar(p) => p.condensed(theta0, options, observer),
            AnyProblem::Spatial(p) => p.condensed(theta0, options, observer),
        }
    }
}

/// Numbers laid out as a scene file's `control.values`: one per value, or pairs [x, z] of a
/// 2-axis control (serialised untagged: an array of numbers or of pairs).
#[derive(Clone, Debug, PartialEq, Serialize)]
#[serde(untagged)]
pub enum Values {
    /// One number per value (a control along z).
    Numbers(Vec<f64>),
    /// One pair [x component, z component] per value (a 2-axis control).
    Pairs(Vec<[f64; 2]>),
}

/// Why `--method riccati` could not run a spatial problem before the Riccati solver took the
/// spatial model (kept for callers that named it; nothing refuses with it now).
pub const RICCATI_PLANAR: &str = crate::error::PLANAR_ONLY;

/// The parametrisation of a scene's own `[control]` and its θ₀: `control.values` (one constant 0
/// without a `[control]`); for a 2-axis control θ₀ = (θ_x; θ_z), the x components first.
///
/// # Errors
/// [`Error::Scene`](crate::Error::Scene) (`control.values`, a [`SceneError`] naming the key) when the number of
/// values does not fit the kind (a validated scene always fits); the errors of
/// [`ControlProblem::from_scene`].
pub fn scene_start(scene: &Scene) -> Result<(Parametrisation, Vec<f64>)> {
    let map = if scene.spatial_key().is_some() {
        *ControlProblem::spatial_from_scene(scene)?.map()
    } else {
        *ControlProblem::from_scene(scene)?.map()
    };
    let (values, values_x) = match &scene.control {
        Some(c) => (c.values.clone(), c.values_x.clone()),
        None => (vec![0.0], None),
    };
    if values.len() != map.n_params() {
        return Err(SceneError::new(SceneErrorKind::WrongCount {
            key: "control.values".into(),
            expected: map.n_params(),
            found: values.len(),
        })
        .into());
    }
    let mut theta0 = values_x.unwrap_or_default();
    theta0.extend(values);
    Ok((map, theta0))
}
