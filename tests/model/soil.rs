//! Soil springs (`[soil]`, docs/conventions.md "Soil springs") against the closed form of a beam on
//! an elastic foundation.
//!
//! Reference: M. Hetényi, *Beams on Elastic Foundation* (University of Michigan Press, 1946),
//! §II.10: a semi-infinite beam (bending stiffness EI) on a Winkler foundation of modulus k
//! (force per unit length per unit deflection), loaded at its free end by a lateral force P, has
//! at the distance x from the end, with β = (k / 4EI)^{1/4},
//!
//! ```text
//! w(x) = (2 P β / k) e^{−βx} cos βx ,      M(x) = −(P / β) e^{−βx} sin βx .
//! ```
//!
//! The pile here is a conductor 36" × 1.5" (0.9144 m × 38.1 mm, steel E = 207 GPa) in a soil of
//! modulus E_s = 5 MN/m² (a stiff clay's initial p-y modulus), 60 m long: βL = 9.4, so the foot
//! (the chain's node 0, held in place, no base spring) changes the head's deflection by
//! ~ e^{−βL} ≈ 1e-4 of it. The head load 100 kN deflects the head by 6 mm (joint angles ~1e-3 rad:
//! the chain's geometric nonlinearity is ~1e-6 of the response). The chain's equilibrium is taken
//! from the static solver (Newton on ∇U = 0 to 1e-14, [`chainbeam::statics::static_equilibrium`]): the
//! soil term is conservative, so the equilibrium is exactly what a damped dynamic run would
//! settle to, without the run's slow (soil-damped) approach and its stopping error.

use chainbeam::scene::Soil;
use chainbeam::statics::static_equilibrium;
use chainbeam::{Chain, Parameter, Scene, Support};

const E: f64 = 207e9;
const OD: f64 = 0.9144;
const WALL: f64 = 0.0381;
const ES: f64 = 5e6;
const LENGTH: f64 = 60.0;
const HEAD_LOAD: f64 = 1e5;

fn bending_stiffness() -> f64 {
    let di = OD - 2.0 * WALL;
    E * std::f64::consts::PI / 64.0 * (OD.powi(4) - di.powi(4))
}

/// The pile as n pendulums entirely below the mudline (its head, the tip node n, at the
/// mudline), loaded at the head by HEAD_LOAD along z.
fn pile(n: usize) -> Scene {
    let l = LENGTH / n as f64;
    Scene::builder(n)
        .support(Support::Cantilever)
        .length(l)
        .mass(1.0)
        .stiffness(bending_stiffness() / l)
        .base_stiffness(0.0)
        .point_load(n, HEAD_LOAD)
        .soil(Soil {
            mudline: LENGTH,
            modulus: ES,
            gradient: 0.0,
        })
        .build()
        .expect("valid pile")
}

/// Worst errors of the chain's deflections (at its nodes) and moments (at its joints) relative
/// to the head's deflection and the largest moment of the closed form, and the errors of those
/// two numbers themselves.
struct Errors {
    deflection: f64,
    moment: f64,
    head: f64,
    max_moment: f64,
}

fn errors(n: usize) -> Errors {
    let scene = pile(n);
    let sol = static_equilibrium(&scene).expect("the pile's equilibrium");
    let ei = bending_stiffness();
    let beta = (ES / (4.0 * ei)).powf(0.25);
    let l = LENGTH / n as f64;
    // Thesis sign: F > 0 pushes the node toward −z.
    let w = |x: f64| -(2.0 * HEAD_LOAD * beta / ES) * (-beta * x).exp() * (beta * x).cos();
    let m = |x: f64| (HEAD_LOAD / beta) * (-beta * x).exp() * (beta * x).sin();
    let head = w(0.0).abs();
    let m_max = m(std::f64::consts::FRAC_PI_4 / beta); // at βx = π/4
    let mut e = Errors {
        deflection: 0.0,
        moment: 0.0,
        head: (sol.positions[n - 1][1] - w(0.0)).abs() / head,
        max_moment: 0.0,
    };
    for (i, p) in sol.positions.iter().enumerate() {
        let x = LENGTH - (i + 1) as f64 * l;
        e.deflection = e.deflection.max((p[1] - w(x)).abs() / head);
    }
    // The moment at joint j (between pendulums j and j + 1, at node j) is the spring's torque
    // k θ_j with θ_j = φ_{j+1} − φ_j; its sign convention against M(x) is fixed by the largest.
    let k = ei / l;
    let chain_moments: Vec<f64> = (1..n)
        .map(|j| k * (sol.angles[j] - sol.angles[j - 1]))
        .collect();
    let sign = if chain_moments
        .iter()
        .fold(0.0f64, |a, &b| if b.abs() > a.abs() { b } else { a })
        > 0.0
    {
        1.0
    } else {
        -1.0
    };
    let mut chain_max = 0.0f64;
    for (j0, &mc) in chain_moments.iter().enumerate() {
        let x = LENGTH - (j0 + 1) as f64 * l;
        e.moment = e.moment.max((sign * mc - m(x)).abs() / m_max);
        chain_max = chain_max.max(sign * mc);
    }
    e.max_moment = (chain_max - m_max).abs() / m_max;
    e
}

/// The chain's pile under a head load matches Hetényi's closed form: deflection and moment
/// within 1 % (of the head deflection and the largest moment) at every node and joint, at
/// n = 240 (l = 0.25 m, βl = 0.039); and the error falls at second order in l (n = 120 → 240:
/// a factor ≈ 4), the order of the lumped cells.
#[test]
fn pile_under_a_head_load_matches_hetenyi() {
    let coarse = errors(120);
    let fine = errors(240);
    println!(
        "n = 120: w {:.2e} M {:.2e} head {:.2e} M_max {:.2e}",
        coarse.deflection, coarse.moment, coarse.head, coarse.max_moment
    );
    println!(
        "n = 240: w {:.2e} M {:.2e} head {:.2e} M_max {:.2e}",
        fine.deflection, fine.moment, fine.head, fine.max_moment
    );
    for (what, e) in [
        ("deflection", fine.deflection),
        ("moment", fine.moment),
        ("head deflection", fine.head),
        ("largest moment", fine.max_moment),
    ] {
        assert!(e < 0.01, "{what}: {e:.2e} of the closed form's scale");
    }
    let ratio = coarse.deflection / fine.deflection;
    assert!(
        (3.0..5.0).contains(&ratio),
        "deflection error ratio n = 120 → 240: {ratio:.2} (second order: 4)"
    );
}

/// A scene without nodes in the soil has no soil parameter; one with it has, and the modulus can
/// be set.
#[test]
fn soil_modulus_is_a_parameter() {
    let scene = pile(20);
    let mut chain = Chain::<f64, 2>::from_scene(&scene).unwrap();
    assert!(chain.has_parameter(Parameter::SoilModulus));
    chain.set_parameter(Parameter::SoilModulus, 1e6).unwrap();
    let mut dry = scene.clone();
    dry.soil = None;
    let mut chain = Chain::<f64, 2>::from_scene(&dry).unwrap();
    assert!(!chain.has_parameter(Parameter::SoilModulus));
    assert!(chain.set_parameter(Parameter::SoilModulus, 1e6).is_err());
}
