//! The static start of a run (`[time] initial = "static"`, docs/conventions.md "The start of a
//! run"): the run starts at rest (p = 0) in the static equilibrium of the scene's steady loads
//! at t = 0, the calm sea's ([`calm_scene`]: the scene without its waves) with the control 0,
//!
//! ```text
//! ∂U/∂q (q₀; t = 0, u = 0) − F(0) ∈ span of the constraints' gradients,   p₀ = 0,
//! ```
//!
//! F(0) the current's drag at rest, U the springs, soil, gravity and buoyancy, tension and point
//! loads at t = 0, and the vessel's top held at its mean offset Z₀ (not ramped with this start,
//! [`crate::model::VesselMotion::holding_offset`]). Until the waves act, that state is an
//! equilibrium of the dynamics: a step from it stays there (tests/model/static_start.rs).

use super::{static_equilibrium_at, StaticSolution};
use crate::base::Scalar;
use crate::error::{Error, Result};
use crate::model::Chain;
use crate::scene::{Initial, Scene};

/// The scene of the calm sea: `scene` without `[loads.waves]`. The current, the vessel's
/// offset, every other load and `[time] initial` stay (the statics of a static scene's calm sea
/// are solved on its chain as built, [`Chain::from_scene`], which solves nothing itself).
pub fn calm_scene(scene: &Scene) -> Scene {
    let mut calm = scene.clone();
    calm.loads.waves = None;
    calm
}

/// The static equilibrium a run of `scene` with `[time] initial = "static"` starts from: that of
/// the calm sea ([`calm_scene`]) under the loads at t = 0 with the control 0
/// ([`static_equilibrium_at`]), in the model the calm scene needs (module docs).
///
/// # Errors
/// [`Error::StaticStart`] naming `time.initial`, with the statics' error (not converged,
/// singular, folded, not isolated) or the scene's.
pub fn static_start(scene: &Scene) -> Result<StaticSolution> {
    static_equilibrium_at(&calm_scene(scene), 0.0, 0.0).map_err(|e| Error::StaticStart {
        source: Box::new(e),
    })
}

/// Gives `chain` (built from `scene`) the static start the scene asks for: with
/// `[time] initial = "static"` the attitudes of [`static_start`] ([`Chain::set_static_start`]);
/// nothing with `"rest"`. Every forward run of a scene calls it on the chain it builds.
///
/// # Errors
/// [`static_start`]'s; [`Chain::set_static_start`]'s.
pub fn set_static_start<D: Scalar, const DIM: usize>(
    chain: &mut Chain<D, DIM>,
    scene: &Scene,
) -> Result<()> {
    if scene.time.initial != Initial::Static || chain.has_static_start() {
        return Ok(());
    }
    let s = static_start(scene)?;
    chain.set_static_start(&s.attitudes)
}
