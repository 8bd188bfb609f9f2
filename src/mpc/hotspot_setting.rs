//! The hot spot an `[mpc]` table names ([`MpcSettings::hotspot`](crate::scene::MpcSettings::hotspot)),
//! resolved against the scene's `[[fatigue.hotspot]]` entries. Here, not in `scene`, so that
//! reading a scene does not depend on the controllers' errors.

use crate::error::MpcError;
use crate::scene::{HotSpotSpec, MomentAbout, MpcSettings, Scene};

impl MpcSettings {
    /// The `[[fatigue.hotspot]]` of `scene` that [`MpcSettings::hotspot`](crate::scene::MpcSettings::hotspot) names (`None`
    /// without one).
    ///
    /// # Errors
    /// [`MpcError::HotSpotUnknown`] for a name that is not one of `scene`'s hot
    /// spots; [`MpcError::HotSpotSpatial`] for a spatial scene;
    /// [`MpcError::MomentAboutNeedsHotSpot`] for [`MomentAbout::Mean`] without a hot spot.
    pub fn hotspot_spec(&self, scene: &Scene) -> Result<Option<HotSpotSpec>, MpcError> {
        let Some(name) = self.hotspot.as_deref() else {
            if self.moment_about == MomentAbout::Mean {
                return Err(MpcError::MomentAboutNeedsHotSpot);
            }
            return Ok(None);
        };
        if scene.is_spatial() {
            return Err(MpcError::HotSpotSpatial);
        }
        match scene.hotspots.iter().find(|h| h.name == name) {
            Some(h) => Ok(Some(h.clone())),
            None => Err(MpcError::HotSpotUnknown {
                name: name.to_string(),
                known: scene
                    .hotspots
                    .iter()
                    .map(|h| h.name.as_str())
                    .collect::<Vec<_>>()
                    .join(", "),
            }),
        }
    }
}
