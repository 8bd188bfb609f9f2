//! Axial loads along the beam's axis y (docs/ocean.md "From a pipe to a chain",
//! docs/conventions.md "Axial loads"): the top
//! tension at the tip and the submerged weight on every node. Neither adds a stiffness of its own:
//! the lateral stiffening of the effective tension T_e(y) = T − w (L − y) comes from the length
//! constraints, through the geometry.

use super::{Ctx, Embed, ForceTerm};
use crate::base::{Parameter, Scalar};
use crate::error::Result;
use crate::model::geometry::yi;

/// A constant force T \[N\] along +y at the tip node (the top tensioner):
/// U = −T (y_n − L) = T Σⱼ lⱼ (1 − e₂ᵀqⱼ), so pendulum j feels ∂U/∂qⱼ = −T lⱼ e₂. Reads T as
/// [`Parameter::Tension`].
#[derive(Clone, Debug)]
pub struct TopTension<D> {
    pub(crate) tension: D,
    pub(crate) lengths: Vec<D>,
}

impl<D: Scalar> TopTension<D> {
    /// The same term over another scalar (real parts).
    pub(crate) fn lift<D2: Scalar>(&self) -> TopTension<D2> {
        TopTension {
            tension: D2::from(self.tension.re()),
            lengths: self.lengths.iter().map(|x| D2::from(x.re())).collect(),
        }
    }
}

impl<D: Scalar, const DIM: usize> ForceTerm<D, DIM> for TopTension<D> {
    fn name(&self) -> &'static str {
        "tension"
    }

    fn energy<E: Embed<D>>(&self, q: &[[E; DIM]], ctx: &Ctx<E>) -> E {
        let t = ctx.param(Parameter::Tension, self.tension);
        let mut u = E::zero();
        for (j, l) in self.lengths.iter().enumerate() {
            u += t * E::embed(*l) * (E::one() - q[j][yi::<DIM>()]);
        }
        u
    }

    fn force<E: Embed<D>>(
        &self,
        _q: &[[E; DIM]],
        ctx: &Ctx<E>,
        out: &mut [[E; DIM]],
    ) -> Result<()> {
        let t = ctx.param(Parameter::Tension, self.tension);
        for (j, l) in self.lengths.iter().enumerate() {
            out[j][yi::<DIM>()] -= t * E::embed(*l);
        }
        Ok(())
    }

    fn depends_on_configuration(&self) -> bool {
        false
    }

    fn has_parameter(&self, p: Parameter) -> bool {
        p == Parameter::Tension
    }
}

/// A weight w \[N/m\] per unit length along −y (the submerged weight of a riser), lumped on the
/// nodes as the masses of a pipe are (docs/conventions.md): node i < n carries w (lᵢ + lᵢ₊₁)/2 and
/// the tip node n half a cell, w lₙ/2, so that the axial force in pendulum j is
/// w Σ_{i≥j} (cell of node i) = w (L − y at the middle of pendulum j), the continuum's value.
/// U = Σᵢ Fᵢ (yᵢ − yᵢ⁰) = Σⱼ lⱼ (Σ_{i≥j} Fᵢ) (e₂ᵀqⱼ − 1). Reads w as [`Parameter::AxialWeight`].
///
/// A chain built from `[stackup]` gives every node its own weight Fᵢ instead
/// ([`crate::scene::Layout::node_weights`]: half of each adjacent pendulum's submerged weight,
/// segment by segment, and half of a body's at each of its ends), so that the effective tension
/// is T_e(y) = T − ∫_y^L w dy of the stack-up's own weights; it has no single w, and no
/// [`Parameter::AxialWeight`].
#[derive(Clone, Debug)]
pub struct AxialWeight<D> {
    pub(crate) weight: D,
    pub(crate) lengths: Vec<D>,
    /// The per-node weights Fᵢ \[N\] of a stack-up (empty: w times the node's cell).
    pub(crate) node_weights: Vec<D>,
}

impl<D: Scalar> AxialWeight<D> {
    /// The same term over another scalar (real parts).
    pub(crate) fn lift<D2: Scalar>(&self) -> AxialWeight<D2> {
        AxialWeight {
            weight: D2::from(self.weight.re()),
            lengths: self.lengths.iter().map(|x| D2::from(x.re())).collect(),
            node_weights: self.node_weights.iter().map(|x| D2::from(x.re())).collect(),
        }
    }

    /// Calls `f(j, lⱼ Σ_{i≥j} Fᵢ)` for j = n−1..0 (0-based pendulums; node i ends pendulum i).
    #[inline]
    fn for_each<E: Embed<D>>(&self, ctx: &Ctx<E>, mut f: impl FnMut(usize, E)) {
        let n = self.lengths.len();
        if !self.node_weights.is_empty() {
            let mut acc = E::zero();
            for j in (0..n).rev() {
                acc += E::embed(self.node_weights[j]);
                f(j, E::embed(self.lengths[j]) * acc);
            }
            return;
        }
        let w = ctx.param(Parameter::AxialWeight, self.weight);
        let mut acc = E::zero();
        for j in (0..n).rev() {
            let next = if j + 1 < n {
                self.lengths[j + 1]
            } else {
                D::zero()
            };
            acc += w * E::embed((self.lengths[j] + next) * 0.5);
            f(j, E::embed(self.lengths[j]) * acc);
        }
    }
}

impl<D: Scalar, const DIM: usize> ForceTerm<D, DIM> for AxialWeight<D> {
    fn name(&self) -> &'static str {
        "axial_weight"
    }

    fn energy<E: Embed<D>>(&self, q: &[[E; DIM]], ctx: &Ctx<E>) -> E {
        let mut u = E::zero();
        self.for_each(ctx, |j, c| u += c * (q[j][yi::<DIM>()] - 1.0));
        u
    }

    fn force<E: Embed<D>>(
        &self,
        _q: &[[E; DIM]],
        ctx: &Ctx<E>,
        out: &mut [[E; DIM]],
    ) -> Result<()> {
        self.for_each(ctx, |j, c| out[j][yi::<DIM>()] += c);
        Ok(())
    }

    fn depends_on_configuration(&self) -> bool {
        false
    }

    fn has_parameter(&self, p: Parameter) -> bool {
        p == Parameter::AxialWeight && self.node_weights.is_empty()
    }
}
