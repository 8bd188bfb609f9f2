//! The stack-up's buoyancy as a design parameter: the derivatives of every node's mass, weight,
//! drag and inertia coefficient with respect to one segment's buoyancy diameter
//! ([`NodeTangents`]), and the scene laid out again after the diameter changed.

use super::*;

/// The derivatives of a stack-up's per-node quantities with respect to one segment's buoyancy
/// diameter D_b ([`Stackup::buoyancy_tangents`]), node by node as [`Layout`] and the beam's
/// masses hold them.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct NodeTangents {
    /// ∂mᵢ/∂D_b \[kg/m\]: the node's mass with added mass.
    pub masses: Vec<f64>,
    /// ∂wᵢ/∂D_b \[N/m\]: the node's submerged weight ([`Layout::node_weights`]).
    pub weights: Vec<f64>,
    /// ∂κᵢ/∂D_b \[kg/m²\]: the node's Morison drag coefficient ([`Layout::node_drag`]).
    pub drag: Vec<f64>,
    /// ∂cᵢ/∂D_b \[kg/m\]: the node's wave inertia coefficient ([`Layout::node_inertia`]).
    pub inertia: Vec<f64>,
}

impl Stackup {
    /// The derivatives with respect to the buoyancy diameter D_b of segment `segment` (an
    /// index into `segments`, a segment with buoyancy modules) of every node's mass, weight,
    /// drag and inertia coefficient, on the chain of `lengths` this stack-up was laid out on
    /// ([`Stackup::beam`]; its [`Layout::parts`]). Per length of the segment, with the foam's
    /// density ρ_f, the water's ρ_w, g, C_a, C_d and D_h = D_b unless the segment gives
    /// `hydrodynamic_diameter` (then ∂D_h/∂D_b = 0):
    /// ```text
    /// ∂μ/∂D_b = ρ_f π D_b/2 + C_a ρ_w π D_h/2 · ∂D_h/∂D_b        (foam, added mass)
    /// ∂w/∂D_b = g (ρ_f − ρ_w) π D_b/2                             (foam less displaced water)
    /// ∂κ/∂D_b = ½ ρ_w C_d ∂D_h/∂D_b,   ∂c/∂D_b = ρ_w (1 + C_a) π D_h/2 · ∂D_h/∂D_b
    /// ```
    /// spread to the nodes as the layout spreads the quantities themselves (half of each
    /// pendulum of the segment to each of its end nodes, drag and inertia over the wet
    /// pendulums): every node quantity is linear in the per-length ones and the pendulums do
    /// not move with D_b, so these are the exact derivatives of the layout. D_b ≥ D_o: at
    /// D_b = D_o, the displaced area's kink, the derivative from above.
    pub fn buoyancy_tangents(
        &self,
        segment: usize,
        lengths: &[f64],
        water_density: f64,
        mudline: f64,
    ) -> NodeTangents {
        let n = lengths.len();
        let mut t = NodeTangents {
            masses: vec![0.0; n],
            weights: vec![0.0; n],
            drag: vec![0.0; n],
            inertia: vec![0.0; n],
        };
        let Some(s) = self.segments.get(segment) else {
            return t;
        };
        let (Some(b), Some(rho_f)) = (s.buoyancy_diameter, s.buoyancy_density) else {
            return t;
        };
        let rho_w = water_density;
        let dh = s.hydrodynamic();
        let ddh = if s.hydrodynamic_diameter.is_some() {
            0.0
        } else {
            1.0
        };
        let dmu = rho_f * PI * b / 2.0 + s.added_mass_coefficient * rho_w * PI * dh / 2.0 * ddh;
        let dw = STANDARD_GRAVITY * (rho_f - rho_w) * PI * b / 2.0;
        let ddrag = 0.5 * rho_w * s.drag_coefficient * ddh;
        let dinertia = rho_w * (1.0 + s.added_mass_coefficient) * PI * dh / 2.0 * ddh;
        let mut y = 0.0;
        for (j, &l) in lengths.iter().enumerate() {
            let wet = y + 0.5 * l > mudline;
            y += l;
            if self.layout.parts.get(j) != Some(&s.name) {
                continue;
            }
            for node in [j.checked_sub(1), Some(j)].into_iter().flatten() {
                t.masses[node] += 0.5 * dmu * l;
                t.weights[node] += 0.5 * dw * l;
                if wet {
                    t.drag[node] += 0.5 * ddrag * l;
                    t.inertia[node] += 0.5 * dinertia * l;
                }
            }
        }
        t
    }
}

impl super::super::Scene {
    /// Lays the stack-up out on the chain again after a segment's buoyancy changed (a design's
    /// `stackup.segment.<name>.buoyancy_diameter`, [`crate::scene::DesignParameter::BuoyancyDiameter`]):
    /// [`Stackup::beam`] for the scene's pendulum count, support, water density and mudline,
    /// whose masses (with added mass) replace the beam's and whose layout (the nodes' weights,
    /// drag and inertia coefficients) the stack-up keeps; with the momentum drag
    /// (`drag_model = "momentum"`) `loads.drag` is its constant again
    /// ([`Stackup::drag_constants`]), as when the scene was read. The lengths and springs are
    /// the beam's own: the buoyancy moves neither a pendulum's end nor a section's E I (the
    /// pendulums are shared in proportion to length × refinement).
    ///
    /// # Errors
    /// [`Stackup::beam`]'s, naming the `stackup.*` key (a buoyancy diameter below the pipe's
    /// outer diameter or out of range). The scene is left as it was on an error but for the
    /// stack-up's segment.
    pub fn relayout_stackup(&mut self) -> Result<(), SceneError> {
        let mudline = self.mudline();
        let (n, support, density) = (
            self.beam.lengths.len(),
            self.beam.support,
            self.water.density,
        );
        let Some(st) = self.stackup.as_mut() else {
            return Ok(());
        };
        let beam = st.beam(n, support, density, mudline)?;
        if st.drag_model == super::DragModel::Momentum {
            self.loads.drag = st.drag_constants(&beam.lengths, &beam.masses, mudline).0;
        }
        self.beam.masses = beam.masses;
        Ok(())
    }
}
