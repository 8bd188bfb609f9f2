//! A riser described as a pipe (`[pipe]`, `[water]`; docs/ocean.md "From a pipe to a chain"): the chain's lᵢ, mᵢ (with
//! added mass, half a cell at the free tip) and kᵢ = EI/l (2EI/l at a clamp) from the section and
//! materials. Its first frequency converges to Euler-Bernoulli's at order 2 in n; the thesis-style
//! lumping with a full cell at the tip (`catalogue::scaled_cantilever`) only at order 1.

use chainbeam::{catalogue, Chain, Scene, SceneErrorKind};
use nalgebra::DMatrix;
use num_dual::{DualNum, HyperDual64};
use std::f64::consts::PI;

/// β₁L of a cantilever (Rao, *Vibration of Continuous Systems*, Table 11.1).
const BETA1_L: f64 = 1.875_104_068_711_961;

fn pipe_scene(n: usize) -> Scene {
    format!(
        "[beam]\npendulums = {n}\nsupport = \"cantilever\"\n\
         [pipe]\nlength = 300.0\nouter_diameter = 0.5334\nwall_thickness = 0.0254\n\
         contents_density = 1200.0\ndrag_coefficient = 1.1\nadded_mass_coefficient = 1.0\n\
         [water]\ndepth = 300.0\n[time]\nstep = 0.01\nsteps = 10\n"
    )
    .parse()
    .unwrap()
}

/// First natural frequency of the free-tip chain linearised about the straight beam: K φ = ω² M φ
/// in the pendulum angles, K = ∂²U/∂θ² by hyper-dual numbers through the chain's own terms,
/// M = Lᵀ diag(m) L (zᵢ = Σ_{j≤i} lⱼ θⱼ).
fn first_frequency(scene: &Scene) -> f64 {
    let chain = Chain::<f64, 2>::from_scene(scene)
        .unwrap()
        .lift::<HyperDual64>();
    let n = chain.n();
    let k = DMatrix::from_fn(n, n, |a, b| {
        let q: Vec<[HyperDual64; 2]> = (0..n)
            .map(|j| {
                let th = HyperDual64::new(0.0, f64::from(j == a), f64::from(j == b), 0.0);
                [th.cos(), th.sin()]
            })
            .collect();
        chain
            .potential_energy(&q, 0.0, HyperDual64::from(0.0))
            .eps1eps2
    });
    let l = &scene.beam.lengths;
    let lz = DMatrix::from_fn(n, n, |i, j| if j <= i { l[j] } else { 0.0 });
    let m = lz.transpose() * DMatrix::from_diagonal(&scene.beam.masses.clone().into()) * &lz;
    let ci = m.cholesky().unwrap().l().try_inverse().unwrap();
    let a = &ci * k * ci.transpose();
    a.symmetric_eigenvalues().min().sqrt()
}

/// Reference: ω₁ = (β₁L)² √(EI/(μ L⁴)) with the pipe's EI and μ = ρ_s A_s + ρ_c A_i + C_a ρ_w A_o,
/// computed here from the section (docs/ocean.md "From a pipe to a chain"), independently of the library's `Pipe`.
#[test]
fn pipe_first_frequency_converges_at_order_two() {
    let (do_, t, len) = (0.5334f64, 0.0254f64, 300.0);
    let di = do_ - 2.0 * t;
    let ei = 207e9 * PI / 64.0 * (do_.powi(4) - di.powi(4));
    let mu = 7850.0 * PI / 4.0 * (do_ * do_ - di * di)
        + 1200.0 * PI / 4.0 * di * di
        + 1025.0 * PI / 4.0 * do_ * do_;
    let exact = BETA1_L * BETA1_L * (ei / (mu * len.powi(4))).sqrt();
    let ns = [10, 20, 40, 80];
    let errs: Vec<f64> = ns
        .iter()
        .map(|&n| first_frequency(&pipe_scene(n)) / exact - 1.0)
        .collect();
    let orders: Vec<f64> = errs
        .windows(2)
        .map(|e| (e[0] / e[1]).abs().log2())
        .collect();
    println!("pipe: ω₁ exact {exact:.6e} rad/s, errors {errs:?}, orders {orders:?}");
    for p in &orders {
        assert!((p - 2.0).abs() < 0.1, "order {p}");
    }
    // The numbers (dimensionless: the same for any uniform beam): −0.84 % at n = 10 and
    // −0.013 % at n = 80.
    assert!((100.0 * errs[0] + 0.84).abs() < 0.01, "{}", errs[0]);
    assert!((100.0 * errs[3] + 0.013).abs() < 0.001, "{}", errs[3]);
    // The same beam lumped with a full cell at the tip (catalogue::scaled_cantilever, base 2EI/l):
    // order 1, −9.4 % at n = 10 and −1.24 % at n = 80.
    let full: Vec<f64> = ns
        .iter()
        .map(|&n| {
            first_frequency(&catalogue::scaled_cantilever(n, len, ei, mu * len, 2.0)) / exact - 1.0
        })
        .collect();
    let full_orders: Vec<f64> = full
        .windows(2)
        .map(|e| (e[0] / e[1]).abs().log2())
        .collect();
    println!("full tip cell: errors {full:?}, orders {full_orders:?}");
    assert!((full_orders[2] - 1.0).abs() < 0.1, "{full_orders:?}");
    assert!((100.0 * full[0] + 9.4).abs() < 0.1 && (100.0 * full[3] + 1.24).abs() < 0.01);
}

#[test]
fn pipe_gives_the_chain_of_ocean_md() {
    let s = pipe_scene(30);
    let p = s.pipe.unwrap();
    let l = 10.0;
    let mu = p.mass_per_length(1025.0);
    let k = p.bending_stiffness() / l;
    assert!(s.beam.lengths.iter().all(|&x| (x - l).abs() < 1e-12));
    assert!(s.beam.masses[..29]
        .iter()
        .all(|&m| (m - mu * l).abs() < 1e-9 * mu * l));
    assert!((s.beam.masses[29] - 0.5 * mu * l).abs() < 1e-9 * mu * l);
    assert!(s.beam.stiffness.iter().all(|&x| (x - k).abs() < 1e-9 * k));
    assert!((s.beam.base_stiffness - 2.0 * k).abs() < 1e-9 * k);
    assert_eq!(s.water.depth, Some(300.0));
    // The scene writes back as a pipe and reads to the same scene.
    let again: Scene = s.to_toml_string().parse().unwrap();
    assert_eq!(again, s);
}

#[test]
fn pipe_and_beam_keys_are_exclusive_and_bad_values_named() {
    let base = "[beam]\npendulums = 4\nsupport = \"cantilever\"\n[time]\nstep = 0.01\nsteps = 10\n";
    let pipe = "[pipe]\nlength = 10.0\nouter_diameter = 0.5\nwall_thickness = 0.02\n";
    let both = base.replace("support", "length = 1.0\nsupport") + pipe;
    let e = both.parse::<Scene>().unwrap_err();
    assert!(
        matches!(&e.kind, SceneErrorKind::ExclusiveKeys { key, other, .. } if key == "beam.length" && other == "pipe"),
        "{e}"
    );
    assert!(
        e.to_string()
            .contains("cannot be given together with `pipe`"),
        "{e}"
    );
    let none = base.parse::<Scene>().unwrap_err();
    assert_eq!(none.key(), Some("beam.length"), "{none}");
    for (bad, key) in [
        ("wall_thickness = 0.02", "wall_thickness = 0.3"),
        ("outer_diameter = 0.5", "outer_diameter = -0.5"),
    ] {
        let text = base.to_string() + &pipe.replace(bad, key);
        let e = text.parse::<Scene>().unwrap_err();
        let name = key.split(' ').next().unwrap();
        assert_eq!(e.key(), Some(format!("pipe.{name}").as_str()), "{e}");
    }
    let water = base.to_string() + pipe + "[water]\ndensity = -3.0\n";
    assert_eq!(
        water.parse::<Scene>().unwrap_err().key(),
        Some("water.density")
    );
    // One water depth: a current's surface that disagrees with it is refused, naming it.
    let current = base.to_string()
        + pipe
        + "[water]\ndepth = 9.0\n[loads]\ndrag = 1.0\n[loads.current]\nprofile = \"uniform\"\nspeed = 0.5\nsurface = 8.0\n";
    let e = current.parse::<Scene>().unwrap_err();
    assert_eq!(e.key(), Some("loads.current.surface"), "{e}");
    let agree = current.replace("surface = 8.0", "");
    let s: Scene = agree.parse().unwrap();
    assert_eq!(s.loads.current.unwrap().surface, Some(9.0));
}
