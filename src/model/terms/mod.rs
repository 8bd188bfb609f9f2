//! Physical effects as types: each force term is written **once**, generically over the scalar,
//! and every derivative the solvers need is derived from that one definition with dual numbers.
//!
//! A conservative term implements [`ForceTerm`]: its energy U_T(q; t, u) and its generalised force
//! ∂U_T/∂q (docs/conventions.md, thesis eq. 2.2.2-2.2.3), both generic over an evaluation scalar `E` that embeds
//! the chain's scalar `D` ([`Embed`]). The trait then provides, by evaluating the same `force` in
//! `Dual<D>`:
//! * [`ForceTerm::force_jvp`]: K v with K = ∂²U_T/∂q² (seed q + εv);
//! * [`ForceTerm::force_vjp`]: Kᵀ w = K w (K is a Hessian, hence symmetric);
//! * [`ForceTerm::parameter_contraction`]: w · ∂(∂U_T/∂q)/∂θ for a physical parameter θ (the term
//!   reads θ through [`Ctx::param`], which seeds it);
//! * [`ForceTerm::control_contraction`]: w · ∂(∂U_T/∂q)/∂u (seed u), and
//!   [`ForceTerm::control_x_contraction`] for the x component u_x of a 2-axis control (seed u_x).
//!
//! A term may override a derived product with a hand-written fast path (the springs do, for K v,
//! because the step's adjoint calls it twice per step); `tests/model/terms.rs` checks every override
//! against the dual-derived default to 1e-12, and every force against the dual gradient of the
//! energy, for every term in both dimensions and for `f64` and `Dual64` chains.
//!
//! A momentum-dependent (dissipative) term implements [`DissipativeTerm`] (thesis eq. 2.4.4,
//! [`dissipation`](DissipativeTerm)): the still-water [`Drag`], or [`CurrentDrag`] when the scene
//! has a current. They are an open set: [`crate::Chain::visit_dissipation`] lists them and every
//! consumer sums them ([`crate::Chain::dissipative_force`], [`crate::Chain::dissipative_slope`],
//! [`crate::Chain::dissipative_half_step`], [`crate::Chain::dissipative_parameter_derivative`],
//! and RATTLE's per-step forms over every block, [`crate::Chain::dissipative_half_steps`] and
//! [`crate::Chain::dissipative_half_kick`], which a term may speed up by overriding
//! [`DissipativeTerm::implicit_half_steps`] and [`DissipativeTerm::half_kick`]).
//! A dissipative term that couples pendulums (a force linear in the velocities q̇ = M⁻¹p that
//! depends on q, such as the [`JointDamping`]) implements [`CoupledDissipativeTerm`] instead,
//! listed in [`crate::Chain::visit_coupled_dissipation`] and summed beside them
//! ([`crate::Chain::coupled_force`] and its derived products).
//!
//! **Adding a term**: write one type implementing [`ForceTerm`] (or [`DissipativeTerm`]), add it as
//! a field of [`crate::Chain`] (set in `from_scene` and `lift`), list it in
//! [`crate::Chain::visit_terms`] (a dissipative term: in [`crate::Chain::visit_dissipation`]), and
//! give it its scene entry, documentation and checks: README.md, "Adding a force term", lists
//! every place. Every integrator, the adjoint, the statics and the Hessian-vector products then
//! see it with all its derivatives.

mod axial;
mod control;
mod coupled;
mod current;
mod dissipation;
mod drag;
mod gravity;
mod joint_damping;
mod node_drag;
mod point_load;
mod reaction_tip;
mod soil;
mod spring;
mod waves;

pub use crate::scene::current_velocity;
pub use axial::{AxialWeight, TopTension};
pub use control::ControlForce;
pub use coupled::{CoupledAt, CoupledDissipativeTerm, CoupledVisitor};
pub use current::CurrentDrag;
pub use dissipation::{
    block_newton, BlockSym, DissipationVisitor, DissipativeTerm, HalfKick, HalfSteps,
};
pub use drag::{Drag, DragWeights};
pub use gravity::Gravity;
pub use joint_damping::JointDamping;
pub(crate) use node_drag::{IterateInputs, IterateOutputs};
pub use node_drag::{NodeDrag, NodeReverseScratch};
pub use point_load::{ChainPointLoad, HarmonicForce, PointLoads};
pub use reaction_tip::{ReactionTip, ReactionTipBar};
pub use soil::SoilSprings;
pub use spring::Springs;
pub use waves::{RecordTime, WaveField, WaveInertia, WaveInertiaTangent, WaveInputs};

use crate::base::{Parameter, Scalar};
use crate::error::Result;
use num_dual::Dual;

/// A scalar that embeds the chain's scalar `D`: `D` itself, or `Dual<D>` for derivatives taken
/// on top of `D` (nested when `D` is already a dual number, as in Hessian-vector products).
pub trait Embed<D: Scalar>: Scalar {
    /// x as a constant.
    fn embed(x: D) -> Self;
    /// x seeded with derivative 1 (the identity embedding cannot seed and returns x).
    fn seeded(x: D) -> Self;
}

impl<D: Scalar> Embed<D> for D {
    #[inline]
    fn embed(x: D) -> Self {
        x
    }
    #[inline]
    fn seeded(x: D) -> Self {
        x
    }
}

impl<D: Scalar> Embed<D> for Dual<D> {
    #[inline]
    fn embed(x: D) -> Self {
        Dual::from_re(x)
    }
    #[inline]
    fn seeded(x: D) -> Self {
        Dual::new(x, D::one())
    }
}

/// What a term is evaluated at besides q: the time t, the control u = (u_x, u_z), and which
/// physical parameter (if any) carries a derivative seed.
#[derive(Clone, Copy, Debug)]
pub struct Ctx<E> {
    /// Time t \[s\].
    pub t: f64,
    /// The control force's z component u (the thesis's u; the only one of a 1-axis control).
    pub u: E,
    /// The control force's x component u_x (2-axis controls in the spatial model; 0 otherwise,
    /// docs/conventions.md "Two-axis controls").
    pub ux: E,
    /// Step index (for error reports).
    pub step: usize,
    /// The parameter seeded by [`Ctx::param`], if any.
    pub seed: Option<Parameter>,
}

impl<E: Scalar> Ctx<E> {
    /// A context without a seeded parameter and with u_x = 0.
    pub fn new(t: f64, u: E, step: usize) -> Self {
        Ctx {
            t,
            u,
            ux: E::zero(),
            step,
            seed: None,
        }
    }

    /// The same context with the control's x component `ux`.
    pub fn with_ux(mut self, ux: E) -> Self {
        self.ux = ux;
        self
    }

    /// The context over `Dual<E>` with `seed` the seeded parameter and u, u_x constants: where
    /// the derived products evaluate a term once more in dual numbers.
    #[inline]
    pub(crate) fn dual(&self, seed: Option<Parameter>) -> Ctx<Dual<E>> {
        Ctx {
            t: self.t,
            u: Dual::from_re(self.u),
            ux: Dual::from_re(self.ux),
            step: self.step,
            seed,
        }
    }

    /// Reads a physical parameter `p` of value `v` into the evaluation scalar, seeded with
    /// derivative 1 when `p` is the context's seed. Terms read every parameter through this, so
    /// that parameter derivatives come from the same code.
    #[inline]
    pub fn param<D: Scalar>(&self, p: Parameter, v: D) -> E
    where
        E: Embed<D>,
    {
        if self.seed == Some(p) {
            E::seeded(v)
        } else {
            E::embed(v)
        }
    }
}

/// Scratch buffers for the dual-number evaluations of the derived products (sized once, so the
/// products do not allocate).
#[derive(Clone, Debug)]
pub struct DualScratch<D, const DIM: usize> {
    q: Vec<[Dual<D>; DIM]>,
    f: Vec<[Dual<D>; DIM]>,
    /// The velocities of a coupled dissipative term ([`CoupledDissipativeTerm`]).
    v: Vec<[Dual<D>; DIM]>,
}

impl<D: Scalar, const DIM: usize> DualScratch<D, DIM> {
    /// Buffers for a chain of n pendulums.
    pub fn new(n: usize) -> Self {
        let z = [Dual::from_re(D::zero()); DIM];
        DualScratch {
            q: vec![z; n],
            f: vec![z; n],
            v: vec![z; n],
        }
    }

    /// Loads q + ε v (v = None: ε-part zero) and clears the force buffer.
    fn load(&mut self, q: &[[D; DIM]], v: Option<&[[D; DIM]]>) {
        for (i, (s, f)) in self.q.iter_mut().zip(self.f.iter_mut()).enumerate() {
            for d in 0..DIM {
                let eps = v.map_or(D::zero(), |v| v[i][d]);
                s[d] = Dual::new(q[i][d], eps);
                f[d] = Dual::from_re(D::zero());
            }
        }
    }

    /// Loads the velocities v (ε-part zero).
    fn load_v(&mut self, v: &[[D; DIM]]) {
        for (s, x) in self.v.iter_mut().zip(v) {
            *s = x.map(Dual::from_re);
        }
    }

    /// Σ w · real part of the force buffer.
    fn contract_re(&self, w: &[[D; DIM]]) -> D {
        let mut s = D::zero();
        for (f, w) in self.f.iter().zip(w) {
            for d in 0..DIM {
                s += f[d].re * w[d];
            }
        }
        s
    }

    /// Σ w · ε-part of the force buffer.
    fn contract(&self, w: &[[D; DIM]]) -> D {
        let mut s = D::zero();
        for (f, w) in self.f.iter().zip(w) {
            for d in 0..DIM {
                s += f[d].eps * w[d];
            }
        }
        s
    }
}

/// A conservative force term U_T(q; t, u), written once over the evaluation scalar.
///
/// `force` *accumulates* ∂U_T/∂q into `out` (callers zero it). The derived products have default
/// implementations by dual numbers; see the module docs.
pub trait ForceTerm<D: Scalar, const DIM: usize>: Clone + std::fmt::Debug + Send + Sync {
    /// A short name for diagnostics and tests.
    fn name(&self) -> &'static str;

    /// The term's energy U_T(q; t, u).
    fn energy<E: Embed<D>>(&self, q: &[[E; DIM]], ctx: &Ctx<E>) -> E;

    /// Accumulates the generalised force ∂U_T/∂q into `out`.
    ///
    /// # Errors
    /// A term may refuse a configuration outside its model ([`crate::Error::Folded`] for springs).
    fn force<E: Embed<D>>(&self, q: &[[E; DIM]], ctx: &Ctx<E>, out: &mut [[E; DIM]]) -> Result<()>;

    /// Whether ∂U_T/∂q depends on q (if not, K = 0 and [`ForceTerm::force_jvp`] is skipped).
    fn depends_on_configuration(&self) -> bool {
        true
    }

    /// Whether ∂U_T/∂q depends on the control u.
    fn depends_on_control(&self) -> bool {
        false
    }

    /// Whether the term reads the physical parameter `p`.
    fn has_parameter(&self, p: Parameter) -> bool;

    /// Accumulates `scale` · K v into `out`, K = ∂²U_T/∂q², by one `Dual<D>` evaluation of
    /// [`ForceTerm::force`] at q + εv.
    fn force_jvp(
        &self,
        q: &[[D; DIM]],
        v: &[[D; DIM]],
        ctx: &Ctx<D>,
        scale: D,
        out: &mut [[D; DIM]],
        scratch: &mut DualScratch<D, DIM>,
    ) -> Result<()> {
        if !self.depends_on_configuration() {
            return Ok(());
        }
        scratch.load(q, Some(v));
        let c = ctx.dual(None);
        self.force(&scratch.q, &c, &mut scratch.f)?;
        for (o, f) in out.iter_mut().zip(&scratch.f) {
            for d in 0..DIM {
                o[d] += scale * f[d].eps;
            }
        }
        Ok(())
    }

    /// Accumulates `scale` · Kᵀ w into `out`. K is the Hessian of U_T, hence symmetric, so this is
    /// [`ForceTerm::force_jvp`] (the symmetry is tested as ⟨K v, w⟩ = ⟨v, Kᵀw⟩).
    fn force_vjp(
        &self,
        q: &[[D; DIM]],
        w: &[[D; DIM]],
        ctx: &Ctx<D>,
        scale: D,
        out: &mut [[D; DIM]],
        scratch: &mut DualScratch<D, DIM>,
    ) -> Result<()> {
        self.force_jvp(q, w, ctx, scale, out, scratch)
    }

    /// w · ∂(∂U_T/∂q)/∂p, by one `Dual<D>` evaluation with p seeded.
    fn parameter_contraction(
        &self,
        q: &[[D; DIM]],
        w: &[[D; DIM]],
        ctx: &Ctx<D>,
        p: Parameter,
        scratch: &mut DualScratch<D, DIM>,
    ) -> Result<D> {
        if !self.has_parameter(p) {
            return Ok(D::zero());
        }
        scratch.load(q, None);
        let c = ctx.dual(Some(p));
        self.force(&scratch.q, &c, &mut scratch.f)?;
        Ok(scratch.contract(w))
    }

    /// w · ∂(∂U_T/∂q)/∂u, by one `Dual<D>` evaluation with u seeded.
    fn control_contraction(
        &self,
        q: &[[D; DIM]],
        w: &[[D; DIM]],
        ctx: &Ctx<D>,
        scratch: &mut DualScratch<D, DIM>,
    ) -> Result<D> {
        if !self.depends_on_control() {
            return Ok(D::zero());
        }
        control_seeded(self, (q, w), ctx, (D::one(), D::zero()), scratch)
    }

    /// w · ∂(∂U_T/∂q)/∂u_x for the x component of a 2-axis control, by one `Dual<D>` evaluation
    /// with u_x seeded.
    fn control_x_contraction(
        &self,
        q: &[[D; DIM]],
        w: &[[D; DIM]],
        ctx: &Ctx<D>,
        scratch: &mut DualScratch<D, DIM>,
    ) -> Result<D> {
        if !self.depends_on_control() {
            return Ok(D::zero());
        }
        control_seeded(self, (q, w), ctx, (D::zero(), D::one()), scratch)
    }
}

/// w · ∂(∂U_T/∂q)/∂(u, u_x)·(s_u, s_x): one `Dual<D>` evaluation of the term's force with the
/// control components seeded by `seed` (the defaults of [`ForceTerm::control_contraction`] and
/// [`ForceTerm::control_x_contraction`]).
fn control_seeded<D: Scalar, T: ForceTerm<D, DIM>, const DIM: usize>(
    term: &T,
    (q, w): (&[[D; DIM]], &[[D; DIM]]),
    ctx: &Ctx<D>,
    (su, sx): (D, D),
    scratch: &mut DualScratch<D, DIM>,
) -> Result<D> {
    scratch.load(q, None);
    let c = Ctx {
        t: ctx.t,
        u: Dual::new(ctx.u, su),
        ux: Dual::new(ctx.ux, sx),
        step: ctx.step,
        seed: None,
    };
    term.force(&scratch.q, &c, &mut scratch.f)?;
    Ok(scratch.contract(w))
}

/// Visits every term of a chain (see [`crate::Chain::visit_terms`]): the one place that lists them.
pub trait TermVisitor<D: Scalar, const DIM: usize> {
    /// Called once per conservative term present in the model.
    fn visit<T: ForceTerm<D, DIM>>(&mut self, term: &T) -> Result<()>;
}
