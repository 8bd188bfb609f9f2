//! The turned riser shared by `tests/model/drag_rotation.rs` and `tests/ocp/ocp_spatial.rs`: a 10-pendulum
//! riser (base and tip springs 2000 N·m/rad, drag 3.0) in a linearly sheared current (0.3 m/s at
//! the surface, 0.05 m/s at the base) with a 2 N point load on pendulum 5, both turned by ψ from
//! the z axis in the horizontal plane, so that direction (sin ψ, cos ψ) carries the whole load.

use chainbeam::*;

/// The scene builder of the turned riser at `psi_deg` degrees, time step 0.01 s and `steps`
/// steps; the caller adds its control.
pub fn builder(psi_deg: f64, steps: usize) -> SceneBuilder {
    let (s, c) = psi_deg.to_radians().sin_cos();
    SceneBuilder::new(10)
        .support(Support::Riser)
        .base_stiffness(2000.0)
        .tip_stiffness(2000.0)
        .drag(3.0)
        .current(Current::linear(0.3, 0.05, [s, c]))
        .point_load_vector(5, [2.0 * s, 2.0 * c])
        .step(0.01)
        .steps(steps)
}
