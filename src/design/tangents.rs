//! The node tangents of the buoyancy modules' diameters: what a design's per-node quantity
//! (a segment's [`super::DesignParameter::BuoyancyDiameter`]) brings to a cell's one adjoint sweep,
//! for the default objective (`scatter`) and a hot spot's (`hotspot`) alike.

use num_dual::Dual64;

use crate::adjoint::{NodeTangent, SeededNodes};
use crate::model::{Chain, NodeQuantities, WaveTangent};
use crate::scene::ValidScene;

/// The node tangents of the buoyancy diameters of the stack-up's segments `segments` on
/// `scene` ([`seeded_nodes`], one per segment, in their order) for a cell's adjoint sweep
/// ([`crate::adjoint::ControlProblem::adjoint_with_nodes`]): the default objective's and the hot spot's.
pub(super) fn node_tangents<const DIM: usize>(
    scene: &ValidScene,
    segments: &[usize],
) -> crate::Result<Vec<Box<dyn NodeTangent<f64, DIM>>>> {
    let mut nodes: Vec<Box<dyn NodeTangent<f64, DIM>>> = Vec::with_capacity(segments.len());
    for &segment in segments {
        nodes.push(Box::new(seeded_nodes::<DIM>(scene, segment)?));
    }
    Ok(nodes)
}

/// The node tangents of a cell's scene with respect to the buoyancy diameter of the stack-up's
/// segment `segment` (a design's [`super::DesignParameter::BuoyancyDiameter`]) for its adjoint sweep:
/// the chain in `Dual64` with every node quantity the buoyancy moves seeded with its exact
/// derivative ([`crate::scene::Stackup::buoyancy_tangents`]: mass with added mass, submerged
/// weight, Morison drag coefficient and the waves' inertia coefficient;
/// [`Chain::set_node_quantities`]) and ∂mᵢ/∂D_b ([`SeededNodes`]).
fn seeded_nodes<const DIM: usize>(
    scene: &ValidScene,
    segment: usize,
) -> crate::Result<SeededNodes<DIM>> {
    let Some(st) = scene.stackup.as_ref() else {
        return Err(crate::model::ModelError::NodeQuantities {
            reason: "a buoyancy diameter needs the scene's [stackup]",
        }
        .into());
    };
    let lengths = &scene.beam.lengths;
    let t = st.buoyancy_tangents(segment, lengths, scene.water.density, scene.mudline());
    let dual = |re: &[f64], eps: &[f64]| -> Vec<Dual64> {
        re.iter()
            .zip(eps)
            .map(|(&r, &e)| Dual64::new(r, e))
            .collect()
    };
    let mut chain = Chain::<Dual64, DIM>::from_scene(scene)?;
    chain.set_node_quantities(NodeQuantities {
        masses: dual(&scene.beam.masses, &t.masses),
        weights: dual(&st.layout.node_weights, &t.weights),
        drag: dual(&st.layout.node_drag, &t.drag),
        waves: Some(WaveTangent {
            masses: t.masses.clone(),
            inertia: t.inertia.clone(),
            seed: Dual64::new(0.0, 1.0),
        }),
    })?;
    SeededNodes::new(chain, t.masses)
}
