//! The small wave-driven riser shared by tests/mpc/mpc.rs and tests/ocp/objectives.rs.

use chainbeam::{Harmonic, ObjectiveKind, PointLoad, Scene, Support};

/// A small riser (n = 4, k₁ = k₅ = 2000, D = 10 kg/m) under a wave of period 2 s at node 2,
/// ramped in over 0.5 s, controlled at the tip, h = 0.01 s, objective c_sum: short enough for
/// the test profile.
pub fn scene(steps: usize) -> Scene {
    let wave = Harmonic {
        amplitude: 2.0,
        period: 2.0,
        phase: 0.0,
    };
    Scene::builder(4)
        .length(1.0)
        .mass(1.0)
        .stiffness(1000.0)
        .step(0.01)
        .support(Support::Riser)
        .base_stiffness(2000.0)
        .tip_stiffness(2000.0)
        .drag(10.0)
        .load(PointLoad::harmonic(2, [0.0, 1.0], vec![wave]).ramped(0.5))
        .control_constant(4, 0.0)
        .objective(ObjectiveKind::Sum)
        .steps(steps)
        .build()
        .unwrap()
}
