//! A stack-up's per-node quantities in the chain's scalar ([`Chain::set_node_quantities`]):
//! the nodes' masses, submerged weights and Morison drag coefficients, and the derivative of
//! the waves' loads they move, so that a dual number seeded on a parameter of the stack-up (a
//! segment's buoyancy diameter) carries its derivative through a whole run.

use std::sync::Arc;

use super::{Chain, ModelError, WaveInertiaTangent};
use crate::base::Scalar;
use crate::error::{Error, Result};

/// The per-node quantities of a stack-up's chain in the chain's scalar
/// ([`Chain::set_node_quantities`]): with D = `Dual64` and a parameter θ seeded, each is
/// xₖ + ε ∂xₖ/∂θ (the real parts those the chain was built with).
#[derive(Clone, Debug)]
pub struct NodeQuantities<D> {
    /// The nodes' masses mₖ with added mass \[kg\].
    pub masses: Vec<D>,
    /// The nodes' submerged weights wₖ \[N\] ([`crate::scene::Layout::node_weights`]).
    pub weights: Vec<D>,
    /// The nodes' Morison drag coefficients κₖ \[kg/m\] ([`crate::scene::Layout::node_drag`]).
    pub drag: Vec<D>,
    /// The derivative of the waves' series, when the chain has waves.
    pub waves: Option<WaveTangent<D>>,
}

/// The derivatives of the nodes' masses and wave inertia coefficients that move the waves'
/// series W (the water's momentum, ∝ m) and G (the inertia load, ∝ c), and the seed they
/// enter with (ε for a dual number).
#[derive(Clone, Debug)]
pub struct WaveTangent<D> {
    /// ∂mₖ/∂θ \[kg per unit of θ\].
    pub masses: Vec<f64>,
    /// ∂cₖ/∂θ, cₖ the node's ρ_w (1 + C_a) A c over its wet cell
    /// ([`crate::scene::Layout::node_inertia`]).
    pub inertia: Vec<f64>,
    /// The seed (ε).
    pub seed: D,
}

impl<D: Scalar, const DIM: usize> Chain<D, DIM> {
    /// Sets the per-node quantities of a stack-up's chain (module docs): the masses mₖ (and
    /// 1/mₖ, the gravity's masses), the axial weight's node weights wₖ, the node-by-node
    /// Morison drag's constants Dₖ = C_d κₖ/mₖ² and its water momentum Pᵢ = lᵢ Σ_{k≥i} mₖ Uₖ
    /// (the current's by suffix sums in the chain's scalar; the waves' share
    /// Wᵢ + seed ∂Wᵢ/∂θ), and the waves' inertia load Gⱼ + seed ∂Gⱼ/∂θ
    /// ([`WaveInertiaTangent`]). With the real parts the chain was built with, a run's real
    /// part is that of the chain as built; with D = `Dual64` and the derivatives of a
    /// parameter, its derivative part is the run's exact derivative (forward mode).
    ///
    /// # Errors
    /// [`ModelError::NodeQuantities`] for vectors not of n values, a chain without the
    /// stack-up's node weights, or with the momentum drag (its constant D and per-pendulum
    /// factors come from the masses once, in real arithmetic); the waves' record refused
    /// ([`crate::ocean::SeaError::TooLarge`], as a scene error).
    pub fn set_node_quantities(&mut self, q: NodeQuantities<D>) -> Result<()> {
        let bad = |reason| Error::from(ModelError::NodeQuantities { reason });
        let n = self.n;
        if q.masses.len() != n || q.weights.len() != n || q.drag.len() != n {
            return Err(bad(
                "masses, weights and drag coefficients need one value per node",
            ));
        }
        if self.drag.is_some() || self.current.is_some() {
            return Err(bad(
                "the momentum drag's constant and factors come from the masses in real \
                 arithmetic: node-by-node quantities need `drag_model = \"morison\"`",
            ));
        }
        match &mut self.axial_weight {
            Some(w) if w.node_weights.len() == n => w.node_weights.clone_from(&q.weights),
            _ => return Err(bad("the chain has no node-by-node weights (a stack-up's)")),
        }
        self.masses.clone_from(&q.masses);
        for i in 0..n {
            self.inv_masses[i] = self.masses[i].recip();
        }
        if let Some(g) = &mut self.gravity {
            g.masses.clone_from(&self.masses);
        }
        let field = match (&q.waves, self.waves()) {
            (Some(t), Some(w)) => {
                if t.masses.len() != n || t.inertia.len() != n {
                    return Err(bad("the waves' derivatives need one value per node"));
                }
                let f = w
                    .with_node_coefficients(&t.masses, &t.inertia)
                    .map_err(|e| crate::scene::sea_error(e, None))?;
                Some((Arc::new(f), t.seed))
            }
            _ => None,
        };
        if let Some(nd) = &mut self.node_drag {
            nd.set_node_coefficients(&q.drag, &self.masses);
            nd.water
                .set_node_masses(&self.lengths, &self.masses, field.clone());
        }
        self.wave_inertia_tangent = field.map(|(field, seed)| WaveInertiaTangent { field, seed });
        Ok(())
    }
}
