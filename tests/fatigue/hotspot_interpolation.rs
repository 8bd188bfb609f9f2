//! A hot spot between two joints reads their torques interpolated linearly in elevation
//! (`chainbeam::hotspots::interpolation_joints`, docs/conventions.md "Hot spots: the joint
//! torque M_j"), so its moment is the moment at its own elevation and converges in n (the
//! nearest joint jumps along the riser as n changes).
//!
//! References, each independent of the code under test:
//! - statics: a cantilever with a tip force P has joint torques k_j θ_j = P·(y_n − y_{j−1})
//!   exactly at any deflection (the moment balance about node j−1, tests/fatigue/hotspots.rs). Between
//!   two joints the moment of the tip force about the material point at arclength e of the rigid
//!   pendulum is P·(y_n − y(e)) with y(e) = (1 − w)·y_{j−1} + w·y_j, w the point's fraction of
//!   the pendulum: linear in w, so the interpolated torque must equal it to the statics'
//!   tolerance, where the nearest joint's torque is off by P times half a pendulum's rise;
//! - the assessment: the hot spot's damage is `fatigue::assess` of (1 − w)·M_a + w·M_b of the two
//!   joints' torque histories of the same run (`joint_moment_history`), w = (e − s_a)/(s_b − s_a).

use chainbeam::fatigue::{assess, MomentHistory, MomentMeasure};
use chainbeam::hotspots::{
    assess_hot_spots, interpolation_joints, joint_moment, joint_moment_history,
};
use chainbeam::statics::static_equilibrium;
use chainbeam::{Chain, Scene};

/// The cantilever of tests/fatigue/hotspots.rs (10 pendulums of 1 m, tip force 4 N: θ₁ > 0.1 rad): the
/// torque interpolated at 2.5 m and 6.2 m is the tip force's moment about that material point.
#[test]
fn interpolated_torque_is_the_moment_at_the_material_point() {
    let (n, p) = (10, 4.0);
    let text = format!(
        "[beam]\npendulums = {n}\nsupport = \"cantilever\"\nlength = 1.0\nmass = 1.0\n\
         stiffness = 100.0\nbase_stiffness = 200.0\n\
         [[loads.point]]\nnode = {n}\nforce = {p}\n\
         [time]\nstep = 0.01\nsteps = 10\n"
    );
    let scene = Scene::from_toml_str(&text).unwrap();
    let sol = static_equilibrium(&scene).unwrap();
    let chain = Chain::<f64, 2>::from_scene(&scene).unwrap();
    let q: Vec<[f64; 2]> = sol.attitudes.iter().map(|a| [a[1], a[2]]).collect();
    let e2 = [1.0, 0.0];
    let torque = |j: usize| {
        let a = if j == 0 { e2 } else { q[j - 1] };
        joint_moment(&a, &q[j], chain.springs()[j])[1]
    };
    // The deflected height of node j−1 (the foot for j = 0).
    let height = |j: usize| if j == 0 { 0.0 } else { sol.positions[j - 1][0] };
    let top = sol.positions[n - 1][0];
    for e in [2.5, 6.2] {
        let w = interpolation_joints(&scene.beam.lengths, e);
        assert_eq!(w.upper, w.lower + 1, "{e}");
        let frac = e - w.lower as f64;
        assert!((w.weight - frac).abs() < 1e-12, "{e}: {}", w.weight);
        let moment = w.blend(torque(w.lower), torque(w.upper));
        let y = (1.0 - frac) * height(w.lower) + frac * height(w.upper);
        // Thesis sign: F > 0 pushes toward −z and bends the joints negative.
        let exact = -p * (top - y);
        assert!(
            (moment - exact).abs() <= 1e-8 * exact.abs(),
            "{e} m: interpolated {moment}, P (y_n − y(e)) = {exact}"
        );
        let nearest = torque((e + 0.5f64).floor() as usize);
        assert!(
            (nearest - exact).abs() > 0.02 * exact.abs(),
            "{e} m: the nearest joint's {nearest} should be off {exact}"
        );
    }
}

/// The 60 m riser of tests/fatigue/hotspots.rs (6 pendulums of 10 m in a JONSWAP sea and a current) with
/// a hot spot at 21 m (between joints 3 and 4, w = 0.1) and one on joint 3 (20 m): the first's
/// damage is `assess` of the blended torques of the same run, the second's of joint 3's alone.
#[test]
fn hot_spot_damage_is_that_of_the_interpolated_history() {
    let text = "[beam]\npendulums = 6\nsupport = \"riser\"\n\n\
         [pipe]\nlength = 60.0\nouter_diameter = 0.5334\nwall_thickness = 0.0222\n\n\
         [water]\ndepth = 60.0\n\n\
         [loads]\ntension = 1e6\ndrag = 1e-4\n\n\
         [loads.current]\nprofile = \"uniform\"\nspeed = 0.3\n\n\
         [loads.waves]\nspectrum = \"jonswap\"\nhs = 3.0\ntp = 9.0\nseed = 7\n\n\
         [time]\nstep = 0.05\nsteps = 400\n\n\
         [fatigue]\nouter_diameter = 0.5334\nwall_thickness = 0.0222\n\n\
         [[fatigue.hotspot]]\nname = \"between\"\nelevation = 21.0\n\n\
         [[fatigue.hotspot]]\nname = \"on\"\nelevation = 20.0\n";
    let scene = Scene::from_toml_str(text).unwrap();
    let got = assess_hot_spots(&scene, &scene.hotspots, 0).unwrap();
    let h = joint_moment_history(&scene, &[2, 3]).unwrap();
    let w = 0.1;
    let blended: Vec<f64> = h.moment[0]
        .iter()
        .zip(&h.moment[1])
        .map(|(a, b)| (1.0 - w) * a + w * b)
        .collect();
    for (s, moment) in [(0, &blended), (1, &h.moment[0])] {
        let spec = &scene.hotspots[s];
        let a = assess(
            &spec.spec,
            MomentHistory {
                duration_s: h.duration(),
                moment,
                moment_x: None,
                measure: MomentMeasure::Wellhead,
            },
        )
        .unwrap();
        assert!(a.damage > 0.0);
        let d = got[s].assessment.damage;
        assert!(
            (d - a.damage).abs() <= 1e-12 * a.damage,
            "{}: {d} vs {}",
            spec.name,
            a.damage
        );
        assert_eq!(got[s].joint, 2, "{}", spec.name);
    }
    assert_eq!(got[0].interpolation.upper, 3);
    assert_eq!(got[1].interpolation.upper, 2);
    // The blend differs from the nearest joint's torque: the interpolation is read.
    assert_ne!(got[0].assessment.damage, got[1].assessment.damage);
}
