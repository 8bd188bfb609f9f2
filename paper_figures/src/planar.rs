//! The thesis's scenes are planar: `chainbeam::simulate` picks the planar model for them, and the
//! figures read its attitudes, so they take the planar trajectory directly.

use chainbeam::{Result, Scene, SimulateInput, Trajectory};

/// [`chainbeam::simulate`] of a planar scene, as the planar trajectory.
pub fn simulate(scene: &Scene) -> Result<Trajectory<f64, 2>> {
    chainbeam::simulate(scene)?.into_planar()
}

/// [`chainbeam::simulate`] of a planar scene with per-step controls, as the planar trajectory.
pub fn simulate_with_controls(scene: &Scene, controls: &[f64]) -> Result<Trajectory<f64, 2>> {
    chainbeam::simulate(SimulateInput::new(scene).controls(controls))?.into_planar()
}
