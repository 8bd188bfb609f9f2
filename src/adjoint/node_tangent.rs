//! Parameters the chain's per-node quantities carry (a stack-up segment's buoyancy diameter
//! D_b moves the masses mᵢ with added mass, the submerged weights wᵢ, the Morison drag
//! coefficients κᵢ and the waves' inertia coefficients cᵢ of the segment's nodes): their share
//! θ̄ += x̄_{k+1}ᵀ ∂Φ/∂θ of the reverse step (module docs of [`crate::adjoint`], "Per-node
//! quantities").
//!
//! The step Φ reads θ in two ways. Through M⁻¹ (RATTLE's drift q′ = q + h M⁻¹p½ and the
//! projection's Ĝ(q′) M⁻¹p′ = r), whose partials are written by hand from
//! M̄⁻¹ = diag(1/l) Δ diag(1/m) Δᵀ diag(1/l) ([`Chain::inverse_mass_tangent`]); and through
//! the terms (gravity and the axial weight read mᵢ and wᵢ, the waves' inertia cᵢ, Morison's
//! drag Dᵢ = C_d κᵢ/mᵢ² and the water's momentum Pⱼ = lⱼ Σ_{k≥j} mₖUₖ), whose contractions
//! w·∂F/∂θ at fixed state are one evaluation of the terms in `Dual64` with every node quantity
//! seeded with its exact derivative ([`Chain::set_node_quantities`], the layout's tangents
//! [`crate::scene::Stackup::buoyancy_tangents`]), as the library's other parameters' terms are
//! contracted (one `Dual` evaluation with θ seeded).

use num_dual::Dual64;

use crate::base::Scalar;
use crate::error::Result;
use crate::model::{Chain, Ctx};

/// A parameter θ that moves the chain's per-node quantities, as the reverse sweep reads it:
/// ∂mᵢ/∂θ and the terms' contractions at a fixed state.
pub trait NodeTangent<D, const DIM: usize> {
    /// ∂mᵢ/∂θ of every node (its mass with added mass) \[kg per unit of θ\].
    fn mass_tangents(&self) -> &[f64];

    /// w·∂U_q(q; ctx)/∂θ at fixed q: the conservative terms' generalised force
    /// ([`Chain::potential_gradient`]) differentiated in θ alone.
    ///
    /// # Errors
    /// The terms' own ([`crate::Error::Folded`]).
    fn force_contraction(&mut self, q: &[[D; DIM]], w: &[[D; DIM]], ctx: &Ctx<D>) -> Result<D>;

    /// w·∂Q(p; dctx)/∂θ at fixed p for Morison's drag node by node
    /// ([`crate::model::NodeDrag::generalised_force`]; 0 without it).
    fn drag_contraction(&mut self, p: &[[D; DIM]], w: &[[D; DIM]], dctx: &Ctx<D>) -> D;
}

/// [`NodeTangent`] of the `f64` adjoint from the chain in `Dual64` with every node quantity
/// seeded with its derivative (ε ∂xᵢ/∂θ, [`Chain::set_node_quantities`]): the terms evaluated
/// there at the state lifted as constants have the contractions' values in their derivative
/// parts. Its buffers are allocated once ([`SeededNodes::new`]).
pub struct SeededNodes<const DIM: usize> {
    chain: Chain<Dual64, DIM>,
    dm: Vec<f64>,
    x: Vec<[Dual64; DIM]>,
    y: Vec<[Dual64; DIM]>,
    out: Vec<[Dual64; DIM]>,
}

impl<const DIM: usize> SeededNodes<DIM> {
    /// The seeded chain `chain` (the real parts those of the `f64` chain the adjoint sweeps,
    /// the node quantities set with their derivatives) and ∂mᵢ/∂θ = `dm` (n values).
    ///
    /// # Errors
    /// [`crate::model::ModelError::NodeQuantities`] when `dm` has not one value per node.
    pub fn new(chain: Chain<Dual64, DIM>, dm: Vec<f64>) -> Result<Self> {
        let n = chain.n();
        if dm.len() != n {
            return Err(crate::model::ModelError::NodeQuantities {
                reason: "the masses' derivatives need one value per node",
            }
            .into());
        }
        let z = vec![[Dual64::from(0.0); DIM]; n];
        Ok(SeededNodes {
            chain,
            dm,
            x: z.clone(),
            y: z.clone(),
            out: z,
        })
    }

    fn lift(x: &mut [[Dual64; DIM]], v: &[[f64; DIM]]) {
        for (x, v) in x.iter_mut().zip(v) {
            *x = v.map(Dual64::from);
        }
    }

    fn eps_dot(out: &[[Dual64; DIM]], w: &[[f64; DIM]]) -> f64 {
        let mut s = 0.0;
        for (o, w) in out.iter().zip(w) {
            for d in 0..DIM {
                s += o[d].eps * w[d];
            }
        }
        s
    }
}

impl<const DIM: usize> NodeTangent<f64, DIM> for SeededNodes<DIM> {
    fn mass_tangents(&self) -> &[f64] {
        &self.dm
    }

    fn force_contraction(
        &mut self,
        q: &[[f64; DIM]],
        w: &[[f64; DIM]],
        ctx: &Ctx<f64>,
    ) -> Result<f64> {
        Self::lift(&mut self.x, q);
        let u = Dual64::from(ctx.u);
        self.chain
            .potential_gradient(&self.x, ctx.t, u, ctx.step, &mut self.out)?;
        Ok(Self::eps_dot(&self.out, w))
    }

    fn drag_contraction(&mut self, p: &[[f64; DIM]], w: &[[f64; DIM]], dctx: &Ctx<f64>) -> f64 {
        let Some(nd) = self.chain.node_drag() else {
            return 0.0;
        };
        Self::lift(&mut self.x, p);
        let c = Ctx::new(dctx.t, Dual64::from(dctx.u), dctx.step);
        let ls = (self.chain.lengths(), self.chain.inverse_lengths());
        nd.generalised_force(&self.x, ls, &c, &mut self.y, &mut self.out);
        Self::eps_dot(&self.out, w)
    }
}

/// Whether the reverse sweep can carry node tangents through `chain`: the M⁻¹ of joint
/// damping's coupled force and the thrust drive's or reaction tip's masses have no node-by-node
/// partials here.
pub(crate) fn check_chain<D: Scalar, const DIM: usize>(chain: &Chain<D, DIM>) -> Result<()> {
    let reason = if chain.has_coupled_dissipation() {
        Some("the joint damping's M⁻¹ has no node-by-node mass partials in the adjoint")
    } else if chain.reaction_tip().is_some() || chain.thrust_drive().is_some() {
        Some("a driven tip's mass has no node-by-node partials in the adjoint")
    } else if chain.node_drag().is_none() && chain.has_dissipation() {
        Some("node-by-node quantities need Morison's drag node by node")
    } else {
        None
    };
    match reason {
        Some(reason) => Err(crate::model::ModelError::NodeQuantities { reason }.into()),
        None => Ok(()),
    }
}
