//! Lateral soil springs on the nodes below the mudline (docs/conventions.md "Soil springs";
//! `[soil]`, [`crate::scene::Soil`]): a linear p-y model of the pile (conductor) in the soil.

use super::{Ctx, Embed, ForceTerm};
use crate::base::{Parameter, Scalar};
use crate::error::Result;
use crate::model::geometry::zi;

/// Linear p-y springs: node i (its cell below the mudline) is held laterally by a spring
/// kᵢ = E₀ aᵢ + E₁ bᵢ \[N/m\] toward its position on the undeformed (straight, vertical) beam,
/// x = z = 0 ([`crate::scene::SoilLumping`]: aᵢ the cell's length in the soil, bᵢ = dᵢ aᵢ with
/// dᵢ the node's depth below the mudline). With the node positions rᵢ = Σ_{j≤i} l_j q_j,
///
/// ```text
/// U = ½ Σᵢ kᵢ |rᵢ⊥|² ,     rᵢ⊥ = (xᵢ, zᵢ)  (zᵢ alone in the planar model),
/// ∂U/∂q_j = l_j Σ_{i≥j} kᵢ rᵢ⊥          (prefix sums for r, suffix sums for the force: O(n)).
/// ```
///
/// The springs act on the lateral components only: the pile's axial support is the chain's foot
/// (node 0, fixed). Reads E₀ as [`Parameter::SoilModulus`].
#[derive(Clone, Debug)]
pub struct SoilSprings<D> {
    pub(crate) modulus: D,
    pub(crate) gradient: D,
    pub(crate) lengths: Vec<D>,
    /// aᵢ (nodes 1..=n as 0..n).
    pub(crate) per_modulus: Vec<D>,
    /// bᵢ.
    pub(crate) per_gradient: Vec<D>,
    /// The first node (0-based) with a spring: every node from it on is skipped once the cells
    /// leave the soil, so the loops run over the nodes in the soil only (`last` one past).
    pub(crate) last: usize,
}

impl<D: Scalar> SoilSprings<D> {
    /// The same term over another scalar (real parts).
    pub(crate) fn lift<D2: Scalar>(&self) -> SoilSprings<D2> {
        let l = |v: &[D]| v.iter().map(|x| D2::from(x.re())).collect();
        SoilSprings {
            modulus: D2::from(self.modulus.re()),
            gradient: D2::from(self.gradient.re()),
            lengths: l(&self.lengths),
            per_modulus: l(&self.per_modulus),
            per_gradient: l(&self.per_gradient),
            last: self.last,
        }
    }

    /// The springs of nodes `0..last` (0-based) from the lumping of a scene's soil: the nodes
    /// beyond the last one whose cell reaches the soil carry none.
    pub(crate) fn new(
        soil: &crate::scene::Soil,
        lumping: crate::scene::SoilLumping,
        lengths: &[D],
    ) -> Self {
        let last = lumping
            .per_modulus
            .iter()
            .rposition(|&a| a > 0.0)
            .map_or(0, |i| i + 1);
        let lift = |v: Vec<f64>| v.into_iter().map(D::from).collect();
        SoilSprings {
            modulus: D::from(soil.modulus),
            gradient: D::from(soil.gradient),
            lengths: lengths.to_vec(),
            per_modulus: lift(lumping.per_modulus),
            per_gradient: lift(lumping.per_gradient),
            last,
        }
    }

    /// kᵢ = E₀ aᵢ + E₁ bᵢ in the evaluation scalar (E₀ read through [`Ctx::param`]).
    #[inline]
    fn spring<E: Embed<D>>(&self, i: usize, e0: E) -> E {
        e0 * E::embed(self.per_modulus[i]) + E::embed(self.gradient * self.per_gradient[i])
    }

    /// The lateral components of the model: z, and x in the spatial model.
    #[inline]
    fn lateral<const DIM: usize>() -> [usize; 2] {
        [zi::<DIM>(), 0]
    }
}

impl<D: Scalar, const DIM: usize> ForceTerm<D, DIM> for SoilSprings<D> {
    fn name(&self) -> &'static str {
        "soil"
    }

    fn energy<E: Embed<D>>(&self, q: &[[E; DIM]], ctx: &Ctx<E>) -> E {
        let e0 = ctx.param(Parameter::SoilModulus, self.modulus);
        let comps = if DIM == 3 { 2 } else { 1 };
        let lat = Self::lateral::<DIM>();
        let mut r = [E::zero(); 2];
        let mut u = E::zero();
        for i in 0..self.last {
            let k = self.spring(i, e0);
            let l = E::embed(self.lengths[i]);
            for (c, &d) in lat.iter().take(comps).enumerate() {
                r[c] += l * q[i][d];
                u += k * r[c] * r[c] * 0.5;
            }
        }
        u
    }

    fn force<E: Embed<D>>(&self, q: &[[E; DIM]], ctx: &Ctx<E>, out: &mut [[E; DIM]]) -> Result<()> {
        let e0 = ctx.param(Parameter::SoilModulus, self.modulus);
        let comps = if DIM == 3 { 2 } else { 1 };
        let lat = Self::lateral::<DIM>();
        // rᵢ⊥ at the last node in the soil, then walked down: r_{i−1} = rᵢ − lᵢ qᵢ.
        let mut r = [E::zero(); 2];
        for i in 0..self.last {
            let l = E::embed(self.lengths[i]);
            for (c, &d) in lat.iter().take(comps).enumerate() {
                r[c] += l * q[i][d];
            }
        }
        let mut acc = [E::zero(); 2];
        for i in (0..self.last).rev() {
            let k = self.spring(i, e0);
            let l = E::embed(self.lengths[i]);
            for (c, &d) in lat.iter().take(comps).enumerate() {
                acc[c] += k * r[c];
                out[i][d] += l * acc[c];
                r[c] -= l * q[i][d];
            }
        }
        Ok(())
    }

    fn has_parameter(&self, p: Parameter) -> bool {
        p == Parameter::SoilModulus
    }
}
