//! The adjoint's node tangents (`adjoint::adjoint_gradient_with_nodes`, `SeededNodes`) below the
//! design study: the per-node masses' partial of M⁻¹ (`Chain::inverse_mass_tangent`) against
//! five-point differences of M⁻¹ itself, and the sweep with node tangents in the spatial model
//! against the forward mode (the run in `Dual64` with the node quantities seeded), with its
//! other parameters' gradient and value untouched by the tangents, linear in the tangent, and
//! the same for every checkpointing.
//!
//! The scene: the reduced riser system of tests/design/design_buoyancy.rs (8 pendulums,
//! h = 0.02 s, 750 steps, its own sea, the buoyant segment `riser_buoyant`).

use chainbeam::adjoint::{
    adjoint_gradient_with_nodes, forward_value, Checkpointing, NodeTangent, SeededNodes,
};
use chainbeam::fatigue::WellheadDamage;
use chainbeam::model::{NodeQuantities, WaveTangent};
use chainbeam::scene::NodeTangents;
use chainbeam::{Chain, FatigueObjective, Parameter, Scene};
use num_dual::Dual64;

fn scene() -> Scene {
    let design = "[design]\n[[design.parameter]]\n\
                  name = \"stackup.segment.riser_buoyant.buoyancy_diameter\"\n\
                  lower = 0.6\nupper = 1.5\n";
    Scene::from_toml_str(&crate::design_vessel::scene_text("", design)).unwrap()
}

/// The layout's derivatives of every node quantity with respect to the buoyant segment's D_b.
fn tangents(scene: &Scene) -> NodeTangents {
    let st = scene.stackup.as_ref().unwrap();
    let segment = st
        .segments
        .iter()
        .position(|s| s.name == "riser_buoyant")
        .unwrap();
    st.buoyancy_tangents(
        segment,
        &scene.beam.lengths,
        scene.water.density,
        scene.mudline(),
    )
}

/// The chain of `scene` in `Dual64` with every node quantity seeded with `scale` times its
/// derivative.
fn seeded<const DIM: usize>(scene: &Scene, t: &NodeTangents, scale: f64) -> Chain<Dual64, DIM> {
    let st = scene.stackup.as_ref().unwrap();
    let dual = |re: &[f64], eps: &[f64]| -> Vec<Dual64> {
        re.iter()
            .zip(eps)
            .map(|(&r, &e)| Dual64::new(r, scale * e))
            .collect()
    };
    let mut chain = Chain::<Dual64, DIM>::from_scene(scene).unwrap();
    chain
        .set_node_quantities(NodeQuantities {
            masses: dual(&scene.beam.masses, &t.masses),
            weights: dual(&st.layout.node_weights, &t.weights),
            drag: dual(&st.layout.node_drag, &t.drag),
            waves: Some(WaveTangent {
                masses: t.masses.iter().map(|m| scale * m).collect(),
                inertia: t.inertia.iter().map(|c| scale * c).collect(),
                seed: Dual64::new(0.0, 1.0),
            }),
        })
        .unwrap();
    chain
}

/// aᵀ(∂M⁻¹/∂D_b)b = the five-point difference of aᵀM⁻¹b over the masses m + kδ ∂m/∂D_b,
/// k = ±1, ±2 (δ = 10⁻⁴ m of D_b; M⁻¹ applied by `Chain::apply_inverse_mass` on the chain with
/// the masses set), to 10⁻⁹ relative. The buoyant nodes' ∂m/m is about 2.5 per m of D_b, so a
/// central difference's truncation O((δ ∂m/m)²) would be 6·10⁻⁸ (it measured 1.2·10⁻⁸); the
/// five-point stencil's is O((δ ∂m/m)⁴) ≈ 10⁻¹⁴, its round-off about 10⁻¹¹ here. Two pairs
/// (a, b), one of them b = a.
#[test]
fn inverse_mass_tangent_matches_five_point_differences() {
    let scene = scene();
    let t = tangents(&scene);
    assert!(t.masses.iter().any(|&m| m != 0.0));
    let n = scene.n();
    let st = scene.stackup.as_ref().unwrap();
    let chain_at = |d: f64| {
        let masses: Vec<f64> = scene
            .beam
            .masses
            .iter()
            .zip(&t.masses)
            .map(|(m, dm)| m + d * dm)
            .collect();
        let mut c = Chain::<f64, 2>::from_scene(&scene).unwrap();
        c.set_node_quantities(NodeQuantities {
            masses,
            weights: st.layout.node_weights.clone(),
            drag: st.layout.node_drag.clone(),
            waves: None,
        })
        .unwrap();
        c
    };
    let a: Vec<[f64; 2]> = (0..n)
        .map(|i| [(1.3 * i as f64).sin(), (0.7 * i as f64 + 0.2).cos()])
        .collect();
    let b: Vec<[f64; 2]> = (0..n)
        .map(|i| [(0.4 * i as f64 + 1.0).cos(), 0.5 - (1.9 * i as f64).sin()])
        .collect();
    let form = |c: &Chain<f64, 2>, a: &[[f64; 2]], b: &[[f64; 2]]| {
        let mut out = vec![[0.0; 2]; n];
        c.apply_inverse_mass(b, &mut out);
        a.iter()
            .zip(&out)
            .map(|(x, y)| x[0] * y[0] + x[1] * y[1])
            .sum::<f64>()
    };
    let delta = 1e-4;
    let at = chain_at(0.0);
    let points = [-2.0, -1.0, 1.0, 2.0].map(|k| chain_at(k * delta));
    for (a, b) in [(&a, &b), (&a, &a)] {
        let exact = at.inverse_mass_tangent(a, b, &t.masses);
        let f = points.each_ref().map(|c| form(c, a, b));
        let diff = (f[0] - 8.0 * f[1] + 8.0 * f[2] - f[3]) / (12.0 * delta);
        assert!(exact != 0.0);
        eprintln!(
            "aᵀ ∂M⁻¹/∂D_b b = {exact:e}, five-point {diff:e}, relative {:e}",
            (exact - diff).abs() / diff.abs()
        );
        assert!(
            (exact - diff).abs() <= 1e-9 * diff.abs(),
            "aᵀ ∂M⁻¹/∂D_b b = {exact:e}, central difference {diff:e}"
        );
    }
}

/// In the spatial model (the planar scene run with DIM = 3): the sweep's ∂J/∂D_b = the
/// derivative part of the run in `Dual64` with the node quantities seeded (forward mode, the
/// reference) to 10⁻¹² relative; a second tangent twice the first gives twice the derivative
/// (to 10⁻¹⁴: the tangent enters linearly); the tension's adjoint gradient and J are those of
/// the sweep without node tangents bit for bit; checkpointing every 7 steps = storing every
/// state, bit for bit.
#[test]
fn node_tangents_in_the_spatial_model_equal_the_forward_mode() {
    let scene = scene();
    let t = tangents(&scene);
    let spec = scene.fatigue_spec().unwrap();
    let objective = FatigueObjective {
        damage: WellheadDamage::new(&spec, scene.moment_measure()).unwrap(),
        effort: 0.0,
    };
    let (h, steps) = (scene.time.step, scene.time.steps);
    let chain = Chain::<f64, 3>::from_scene(&scene).unwrap();
    let u = vec![0.0; steps + 1];
    let params = [Parameter::Tension];
    let run = |checkpointing| {
        let nodes: Vec<Box<dyn NodeTangent<f64, 3>>> = vec![
            Box::new(SeededNodes::new(seeded::<3>(&scene, &t, 1.0), t.masses.clone()).unwrap()),
            Box::new(
                SeededNodes::new(
                    seeded::<3>(&scene, &t, 2.0),
                    t.masses.iter().map(|m| 2.0 * m).collect(),
                )
                .unwrap(),
            ),
        ];
        adjoint_gradient_with_nodes(
            &chain,
            (h, steps),
            (&u, &objective),
            &params,
            nodes,
            checkpointing,
            None,
        )
        .unwrap()
    };
    let (r, g) = run(Checkpointing::StoreAll);
    let (r7, g7) = run(Checkpointing::Every(7));
    assert_eq!(g.len(), 2);
    assert_eq!(g7, g);
    assert_eq!(r7.parameter_gradient, r.parameter_gradient);
    let plain = adjoint_gradient_with_nodes(
        &chain,
        (h, steps),
        (&u, &objective),
        &params,
        Vec::new(),
        Checkpointing::StoreAll,
        None,
    )
    .unwrap()
    .0;
    assert_eq!(r.value.to_bits(), plain.value.to_bits());
    assert_eq!(r.parameter_gradient, plain.parameter_gradient);
    let ud = vec![Dual64::from(0.0); steps + 1];
    let d = forward_value(&seeded::<3>(&scene, &t, 1.0), h, steps, &ud, &objective).unwrap();
    let rel = (g[0] - d.eps).abs() / d.eps.abs();
    eprintln!(
        "DIM = 3: dJ/dD_b adjoint {:e}, forward mode {:e}, relative {rel:e}",
        g[0], d.eps
    );
    assert!(d.eps != 0.0);
    assert!(rel < 1e-12, "adjoint {:e}, forward mode {:e}", g[0], d.eps);
    assert!(
        (g[1] - 2.0 * g[0]).abs() <= 1e-14 * g[0].abs(),
        "{:e} against 2 × {:e}",
        g[1],
        g[0]
    );
}
