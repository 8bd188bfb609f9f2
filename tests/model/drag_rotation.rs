//! Morison's drag is the same in every transverse direction (
//! docs/conventions.md "Drag"): it acts on the transverse relative momentum with its Euclidean
//! norm, so turning every load, the current and the control about the beam's axis y by ψ turns
//! the whole motion by ψ.
//!
//! Reference: the planar trajectory (the spatial model with x = 0 reproduces the thesis's
//! elementwise drag bit for bit, tests/model/core.rs, tests/model/current.rs), rotated by ψ in the (x, z)
//! plane; the spatial run must equal it to 1e-9 m at every node and step (the model is exactly
//! rotation-invariant, so the difference is round-off over deflections of 0.05 m and more). The
//! thesis's per-component drag missed this by 5e-3 m at 45°.

use chainbeam::*;

use crate::rotation;
use crate::turned_riser;

const STEPS: usize = 400;

fn control(k: usize) -> f64 {
    -0.8 * (k as f64 * 0.02).sin()
}

/// The thesis riser (n = 10, l = 1 m, m = 1 kg, k = 1000 N·m/rad, k₁ = k₁₁ = 2000) with drag
/// D = 3 in a sheared current (0.3 m/s at the surface, 0.05 at the seabed), a point load of 2 N
/// at node 5 and a varying control at the tip, all along the direction ψ from +z toward +x: a
/// 2-axis control (spatial model), or with `planar` (ψ = 0) the 1-axis control of the planar
/// model.
fn scene(psi_deg: f64, planar: bool) -> Scene {
    let (s, c) = psi_deg.to_radians().sin_cos();
    let b = turned_riser::builder(psi_deg, STEPS);
    let b = if planar {
        b.control_per_step(10, (0..=STEPS).map(control).collect())
    } else {
        let pairs: Vec<[f64; 2]> = (0..=STEPS)
            .map(|k| [control(k) * s, control(k) * c])
            .collect();
        b.control_two_axis(10, ControlKind::PerStep, &pairs)
    };
    b.build().unwrap()
}

/// max over steps and nodes of |R_ψ r_planar − r_spatial| (componentwise) and the largest
/// transverse deflection of the planar run.
fn rotated_difference(psi_deg: f64) -> (f64, f64) {
    let (s, c) = psi_deg.to_radians().sin_cos();
    let planar = simulate(&scene(0.0, true)).unwrap();
    assert!(!planar.is_spatial());
    let turned = simulate(&scene(psi_deg, false)).unwrap();
    assert!(turned.is_spatial());
    rotation::rotated_gap(&planar, &turned, [s, c], STEPS)
}

#[test]
fn loads_current_and_control_turned_about_the_axis_turn_the_motion() {
    for psi in [30.0, 45.0, 120.0] {
        let (worst, reach) = rotated_difference(psi);
        println!("ψ = {psi}°: {worst:.1e} m off the rotated planar run (deflection {reach:.3} m)");
        assert!(reach > 0.05, "the beam deflects ({reach} m)");
        assert!(
            worst <= 1e-9,
            "ψ = {psi}°: {worst:e} m off the rotated planar trajectory"
        );
    }
}

/// The planar scene itself (ψ = 0, spatial model): x stays 0 and the motion is the planar one
/// exactly (`==`), the thesis's drag bit for bit.
#[test]
fn unturned_spatial_run_is_the_planar_run_exactly() {
    let (worst, _) = rotated_difference(0.0);
    assert_eq!(worst, 0.0);
}
