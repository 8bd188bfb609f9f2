//! The scaled cantilever of the `step` and `adjoint` benches and of examples/bench_probe.rs.

use chainbeam::{Scene, Support};

/// A cantilever of n pendulums with a point load F = 2 N at the tip, scaled from the n = 10 beam
/// (l = 1, m = 1, k = 1000, h = 0.01) so that the continuum beam is the same: total length 10
/// and mass 10 (l = 10/n, m = 10/n), bending stiffness k·l = 1000 (k = 1000/l for every
/// interior spring), the base spring `base`·k. The highest chain frequency grows like n², so
/// h = 0.01·min(1, (10/n)²) keeps h·ω_max (and hence the Newton convergence) the same for every
/// n. `steps` steps.
///
/// These are the parameters of `catalogue::scaled_cantilever(n, 10.0, 1000.0, 10.0, base)`, built
/// here with the steps a bench takes: the catalogue scene keeps t ∈ [0, 10] s, which at n = 1000
/// is N = 10⁷ steps, (N + 1)·n over the stored-state limit, so it is refused.
pub fn scaled_cantilever(n: usize, base: f64, steps: usize) -> Scene {
    let l = 10.0 / n as f64;
    let k = 1000.0 / l;
    Scene::builder(n)
        .length(l)
        .mass(10.0 / n as f64)
        .stiffness(k)
        .base_stiffness(base * k)
        .support(Support::Cantilever)
        .point_load(n, 2.0)
        .step(0.01 * (10.0 / n as f64).powi(2).min(1.0))
        .steps(steps)
        .build()
        .unwrap_or_else(|e| panic!("bench cantilever n = {n} is invalid: {e}"))
}
