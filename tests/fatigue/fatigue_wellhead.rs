//! The wellhead moment of the fatigue assessment (docs/conventions.md "The wellhead moment M_w"):
//! the stress comes from M_w = k₁z₁/l₁ = M₀·l₁/2, the base spring's torque, not from the chain's
//! M₀ = 2k₁z₁/l₁² (thesis eq. 3.1.3).
//!
//! Reference, independent of the chain: a cantilever of length L with a tip force P carries the
//! wellhead moment P·L (moment balance about the base), which is also EI·w″(0) of the
//! Euler-Bernoulli closed form (thesis eq. 2.4.5, `euler_bernoulli::static_cantilever`), so the
//! hot-spot stress is σ = SCF·P·L·(D_o/2)/I. The chain's static equilibrium (`static_equilibrium`)
//! under that force, its M₀ (`Chain::base_moment`, the `moment` `simulate` reports) and the
//! fatigue path (`assess` with the scene's `moment_measure`) must give that σ as the cycles'
//! range, on a steel pipe (`[pipe]`, k₁ = 2EI/l at the clamp) at n = 20 and n = 80, and on a
//! thesis-sized chain (l₁ = 1 m, k₁ = 2k), where M₀ itself is 2·P·L.
//!
//! Tolerance: M_w = k₁ sin θ₁ and the load's lever arm is the deflected tip's height y_n, both
//! P·L to O(θ²); the loads below keep every joint angle under 10⁻³ rad, so the relative
//! difference is below 10⁻⁶ (θ²/6 and the tip's shortening Σθ²/2 ≲ 10⁻⁷), far from the factors
//! 2/l₁ (the chain's M₀) or l₁/2 that a wrong conversion would make.

use chainbeam::euler_bernoulli::static_cantilever;
use chainbeam::fatigue::{assess, FatigueSpec, MomentHistory};
use chainbeam::statics::static_equilibrium;
use chainbeam::{Chain, Scene};

/// EI·w″(0) of the closed-form cantilever by a central second difference (exact for the cubic
/// up to round-off): −P·L with the thesis sign (P > 0 bends toward −z).
fn euler_bernoulli_wellhead_moment(force: f64, ei: f64, length: f64) -> f64 {
    let d = 1e-3 * length;
    let w = |y: f64| static_cantilever(y, force, ei, length);
    ei * (w(d) - 2.0 * w(0.0) + w(-d)) / (d * d)
}

/// The chain's M₀ at its static equilibrium under the scene's loads.
fn static_m0(scene: &Scene) -> f64 {
    let sol = static_equilibrium(scene).unwrap();
    assert!(!sol.spatial);
    let chain = Chain::<f64, 2>::from_scene(scene).unwrap();
    // Planar attitudes are (y, z).
    let q: Vec<[f64; 2]> = sol.attitudes.iter().map(|a| [a[1], a[2]]).collect();
    let max_angle = sol.angles.iter().fold(0.0_f64, |m, a| m.max(a.abs()));
    assert!(max_angle < 1e-3, "joint angle {max_angle} rad: not small");
    chain.base_moment(&q)
}

/// The cycles of the stress history 0, M₀, 0, M₀, 0 (two full cycles of range |σ|, plus half
/// cycles of the residue) through `assess`: every range must be SCF·P·L·(D_o/2)/I.
fn check_stress(scene: &Scene, force: f64, length: f64, ei: f64) {
    let spec = scene.fatigue.expect("[fatigue]");
    let m0 = static_m0(scene);
    let moment = [0.0, m0, 0.0, m0, 0.0];
    let a = assess(
        &spec,
        MomentHistory {
            duration_s: 4.0,
            moment: &moment,
            moment_x: None,
            measure: scene.moment_measure(),
        },
    )
    .unwrap();
    let m_eb = euler_bernoulli_wellhead_moment(force, ei, length);
    assert!(
        (m_eb + force * length).abs() <= 1e-9 * force * length,
        "EI w''(0) = {m_eb}, P L = {}",
        force * length
    );
    let hot_spot = spec.hot_spot().unwrap();
    let sigma = spec.scf * m_eb.abs() * 0.5 * spec.outer_diameter / hot_spot.second_moment() / 1e6;
    let l1 = scene.beam.lengths[0];
    println!(
        "n = {}: M0 = {m0:.9e}, M0 l1/2 = {:.9e}, EI w''(0) = {m_eb:.9e}, sigma = {sigma:.9e} MPa",
        scene.n(),
        m0 * l1 / 2.0
    );
    assert!(!a.cycles.is_empty());
    for c in &a.cycles {
        assert!(
            (c.range - sigma).abs() <= 1e-6 * sigma,
            "n = {}: range {} MPa vs SCF P L (D_o/2)/I = {sigma} MPa",
            scene.n(),
            c.range
        );
    }
}

/// A steel pipe cantilever (`[pipe]`: 21" × 22.2 mm, 100 m, k₁ = 2EI/l at the clamp, no weight)
/// with P = 10 N at the tip.
fn pipe_cantilever(n: usize) -> Scene {
    let text = format!(
        "[beam]\npendulums = {n}\nsupport = \"cantilever\"\n\
         [pipe]\nlength = 100.0\nouter_diameter = 0.5334\nwall_thickness = 0.022225\n\
         [[loads.point]]\nnode = {n}\nforce = 10.0\n\
         [time]\nstep = 0.001\nsteps = 10\n\
         [fatigue]\nouter_diameter = 0.5334\nwall_thickness = 0.022225\nscf = 1.3\n"
    );
    Scene::from_toml_str(&text).unwrap()
}

#[test]
fn pipe_cantilever_wellhead_stress_is_p_l_at_n_20_and_80() {
    for n in [20, 80] {
        let scene = pipe_cantilever(n);
        let pipe = scene.pipe.as_ref().unwrap();
        let ei = pipe.bending_stiffness();
        // The chain's base spring is the clamp's half cell.
        let l1 = scene.beam.lengths[0];
        assert!((scene.beam.base_stiffness - 2.0 * ei / l1).abs() <= 1e-12 * 2.0 * ei / l1);
        check_stress(&scene, 10.0, 100.0, ei);
    }
}

/// The thesis's cantilever constants (n = 10, l = 1 m, k = 100 N·m/rad, k₁ = 2k, so EI = k·l =
/// 100 N·m²) with a tip force small enough to stay linear (1 mN): M₀ = 2·P·L, twice the
/// wellhead moment, so the stress is that of M₀/2.
#[test]
fn thesis_chain_m0_is_twice_the_wellhead_moment() {
    let text = "[beam]\npendulums = 10\nsupport = \"cantilever\"\nlength = 1.0\nmass = 1.0\n\
                stiffness = 100.0\nbase_stiffness = 200.0\n\
                [[loads.point]]\nnode = 10\nforce = 0.001\n\
                [time]\nstep = 0.01\nsteps = 10\n\
                [fatigue]\nouter_diameter = 0.02\nwall_thickness = 0.002\n";
    let scene = Scene::from_toml_str(text).unwrap();
    let (force, length) = (0.001, 10.0);
    let m0 = static_m0(&scene);
    assert!(
        (m0 + 2.0 * force * length).abs() <= 1e-6 * 2.0 * force * length,
        "M0 = {m0}, 2 P L = {}",
        2.0 * force * length
    );
    check_stress(&scene, force, length, 100.0);
    // A non-positive base length is refused, naming `base_length`.
    let spec: FatigueSpec = scene.fatigue.unwrap();
    let err = assess(
        &spec,
        MomentHistory {
            duration_s: 1.0,
            moment: &[0.0, 1.0],
            moment_x: None,
            measure: chainbeam::fatigue::MomentMeasure::ChainM0 { base_length: 0.0 },
        },
    )
    .unwrap_err();
    assert!(
        matches!(
            err,
            chainbeam::fatigue::FatigueError::InvalidSpec {
                key: "base_length",
                ..
            }
        ),
        "{err}"
    );
}
