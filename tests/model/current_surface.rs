//! The free surface of a current and the node heights' rounding (`chainbeam::scene::current_velocity`).
//!
//! A node's height is the sum of the lengths below it, y_k = l₁ + … + l_k, and n equal lengths L/n
//! need not add up to L: for L = 1000 m and n = 300 the top node is at 1000 + 4.4e-12 m. With the
//! water depth equal to the riser's length (`[water] depth = 1000`, as in
//! `examples/scenes/riser_1000m.toml`) that node used to count as above the surface and got no
//! current, which moved riser_1000m's wellhead moment at n = 300 by −0.34 % off the smooth
//! convergence of n = 100, 150, 200, 250 and 400 (docs/scene-format.md "Real-scale risers").

use chainbeam::statics::static_equilibrium;
use chainbeam::Scene;

/// A bare 21-inch riser in 1000 m of water in a uniform current, as `n` pendulums; `depth` is the
/// `[water]` table's line (empty: the current's surface is the top node, the sum of the lengths).
fn riser(n: usize, water: &str) -> Scene {
    let l = 1000.0 / n as f64;
    // D = ½ ρ_w C_d D_o / (l μ² L) with μ = 779.2 kg/m (the scene file's drag constant).
    let drag = 0.5 * 1025.0 * 0.5334 / (l * 779.2f64.powi(2) * 1000.0);
    let text = format!(
        "[beam]\npendulums = {n}\nsupport = \"riser\"\n\n\
         [pipe]\nlength = 1000.0\nouter_diameter = 0.5334\nwall_thickness = 0.022225\n\
         contents_density = 1437.912\ndrag_coefficient = 1.0\nadded_mass_coefficient = 1.0\n\n\
         {water}\
         [loads]\ndrag = {drag:e}\ntension = 4.094e6\naxial_weight = 3149.1\n\n\
         [loads.current]\nprofile = \"uniform\"\nspeed = 0.5\n\n\
         [time]\nstep = 0.005\nsteps = 10\n"
    );
    text.parse().unwrap()
}

/// The static wellhead moment k₁ z₁/l₁ \[N m\] (statics: the current's steady drag, no waves).
fn wellhead_moment(scene: &Scene) -> f64 {
    let s = static_equilibrium(scene).unwrap();
    scene.beam.base_stiffness * s.positions[0][1] / scene.beam.lengths[0]
}

/// With the water depth equal to the length, the top node (4.4e-12 m above 1000 m by rounding) is
/// at the surface: the wellhead moment is the one with the surface placed exactly at the top node
/// (the current's default, `surface` = Σ lᵢ, the same sum: no rounding question), to 1e-12. The
/// top node's current is not negligible at this size: with the surface 1 mm below the top node
/// (so the top node is above it) the moment is 0.3 % smaller.
#[test]
fn a_node_at_the_surface_by_rounding_keeps_the_current() {
    let n = 300;
    let l = 1000.0 / n as f64;
    let top: f64 = std::iter::repeat_n(l, n).sum();
    assert!(top > 1000.0, "the case this test is about: {top}");
    let at_depth = wellhead_moment(&riser(n, "[water]\ndepth = 1000.0\n\n"));
    let at_top = wellhead_moment(&riser(n, ""));
    assert!(
        (at_depth / at_top - 1.0).abs() < 1e-12,
        "{at_depth} vs {at_top}"
    );
    let below = wellhead_moment(&riser(n, "[water]\ndepth = 999.999\n\n"));
    assert!(below < at_top * 0.998, "{below} vs {at_top}");
}
