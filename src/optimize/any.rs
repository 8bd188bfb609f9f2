//! The optimisers' view of a control problem in the model its scene needs
//! ([`AnyProblem`], built by
//! [`ProblemBuilder::build`](crate::adjoint::ProblemBuilder::build)), and the parameters θ₀ a
//! scene's `[control]` gives ([`scene_start`]). The command line and the Python bindings build
//! their problems through the same builder, so both evaluate the same code on the same floats.

use serde::Serialize;

use crate::adjoint::{AnyProblem, ControlMap, Objective, Parametrisation};
use crate::error::Result;
use crate::ocp::{IterationObserver, OcpOptions, OcpResult};
use crate::scene::{SceneError, SceneErrorKind, SceneInput};

use super::{HessianVec, OptimProblem, ProblemShape};

impl<P: ControlMap, O: Objective> AnyProblem<P, O> {
    /// θ (or a gradient with respect to θ) laid out as a scene file's `control.values`: numbers,
    /// or pairs [x, z] for a 2-axis control.
    pub fn layout(&self, theta: &[f64]) -> Values {
        if !self.is_two_axis() {
            return Values::Numbers(theta.to_vec());
        }
        let (x, z) = theta.split_at(theta.len() / 2);
        Values::Pairs(x.iter().zip(z).map(|(a, b)| [*a, *b]).collect())
    }
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

/// The optimisers' view: every method delegates to the planar or spatial problem (the Riccati
/// and the condensed solver take both).
impl<P: ControlMap, O: Objective> OptimProblem for AnyProblem<P, O> {
    fn n_params(&self) -> usize {
        either!(self, p => OptimProblem::n_params(p))
    }
    fn value(&self, theta: &[f64]) -> Result<f64> {
        either!(self, p => OptimProblem::value(p, theta))
    }
    fn value_and_gradient(&self, theta: &[f64]) -> Result<(f64, Vec<f64>)> {
        either!(self, p => OptimProblem::value_and_gradient(p, theta))
    }
    fn gradient(&self, theta: &[f64]) -> Result<Vec<f64>> {
        either!(self, p => OptimProblem::gradient(p, theta))
    }
    fn hessian(&self) -> Option<&dyn HessianVec> {
        either!(self, p => Some(p as &dyn HessianVec))
    }
    fn controls(&self, theta: &[f64]) -> Option<Result<Vec<f64>>> {
        either!(self, p => OptimProblem::controls(p, theta))
    }
    fn param_scales(&self) -> Vec<f64> {
        either!(self, p => p.param_scales())
    }
    fn check_range(&self, theta: &[f64]) -> Result<()> {
        either!(self, p => p.check_range(theta))
    }
    fn shape(&self) -> Option<ProblemShape> {
        either!(self, p => p.shape())
    }
    fn riccati(
        &self,
        theta0: &[f64],
        options: &OcpOptions,
        observer: Option<IterationObserver<'_>>,
    ) -> Option<Result<OcpResult>> {
        either!(self, p => p.riccati(theta0, options, observer))
    }
    fn condensed(
        &self,
        theta0: &[f64],
        options: &OcpOptions,
        observer: Option<IterationObserver<'_>>,
    ) -> Option<Result<OcpResult>> {
        either!(self, p => p.condensed(theta0, options, observer))
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
/// [`Error::Scene`](crate::Error::Scene): a [`Scene`](crate::Scene)'s validation errors, or
/// `control.values` (a [`SceneError`] naming the key) when the number of values does not fit
/// the kind (a validated scene always fits). No model is built: the parametrisation is the
/// one [`ControlProblem::builder`](crate::adjoint::ControlProblem::builder) takes from the
/// scene.
pub fn scene_start<S: SceneInput + ?Sized>(scene: &S) -> Result<(Parametrisation, Vec<f64>)> {
    let scene = scene.checked()?;
    let map = crate::adjoint::scene_map(&scene);
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
