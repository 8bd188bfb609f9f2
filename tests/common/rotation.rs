//! A spatial run against the planar run turned about the beam's axis y, shared by
//! `tests/model/drag_rotation.rs` and `tests/fatigue/wave_riser.rs` (the model is invariant under rotations
//! about y, so the turned scene's exact discrete trajectory is the planar one turned).

use chainbeam::*;

/// max over the steps 0..=`steps` and the nodes of |R_ψ r_planar − r_turned| (componentwise;
/// R_ψ takes z to (sin ψ, 0, cos ψ), `sin_cos` = [sin ψ, cos ψ]) and the largest transverse
/// deflection |z| of the planar run, whose every node has x = 0 (asserted).
pub fn rotated_gap(
    planar: &SceneTrajectory,
    turned: &SceneTrajectory,
    [s, c]: [f64; 2],
    steps: usize,
) -> (f64, f64) {
    let (mut worst, mut reach): (f64, f64) = (0.0, 0.0);
    for k in 0..=steps {
        for (a, b) in planar.positions(k).into_iter().zip(turned.positions(k)) {
            assert_eq!(a[0], 0.0);
            let want = [a[2] * s, a[1], a[2] * c];
            for d in 0..3 {
                worst = worst.max((want[d] - b[d]).abs());
            }
            reach = reach.max(a[2].abs());
        }
    }
    (worst, reach)
}
