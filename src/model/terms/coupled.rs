//! Dissipative terms that couple pendulums (docs/conventions.md, "Joint damping"): a force
//! F(q, q̇) on the momenta that is linear in the velocities q̇ = M⁻¹p,
//!
//! ```text
//! F(q, q̇) = −B(q) q̇,    B symmetric positive semidefinite (F = −∂R/∂q̇, R = ½ q̇ᵀ B q̇) ,
//! ```
//!
//! but, unlike the block terms of [`super::DissipativeTerm`], reads the velocities of neighbouring
//! pendulums and the attitudes q. They are an open set beside the block terms:
//! [`crate::Chain::visit_coupled_dissipation`] lists them and every consumer sums them (the
//! explicit steppers through [`crate::Chain::coupled_force`], RATTLE's implicit half step and
//! its reverse through the derived products below, which follow from F's linearity in q̇ and
//! the symmetry of B):
//! * ∂F/∂p δp = F(q, M⁻¹ δp) and (∂F/∂p)ᵀ w = M⁻¹ F(q, w);
//! * ∇_q (w·F(q, q̇)) ([`CoupledDissipativeTerm::force_q_vjp`]: by dual numbers, one
//!   evaluation per component, unless a term overrides it with a closed form tested equal);
//! * w·∂F/∂θ by one dual evaluation with θ seeded, and for the mass (q̇ = M⁻¹p with
//!   M⁻¹ ∝ 1/m) −w·F/m.

use super::{Ctx, DualScratch, Embed};
use crate::base::{Parameter, Scalar};
use crate::model::Chain;
use num_dual::Dual;

/// A dissipative force F(q, q̇) = −B(q) q̇ that couples pendulums (module docs), written once
/// over the evaluation scalar.
///
/// **Reach:** Fᵢ may read the attitudes and velocities of pendulums i − 1, i and i + 1 only
/// (B block tridiagonal, as for a force acting at the joints). RATTLE's implicit half step
/// relies on it: its Jacobian I − (h/2) ∂F/∂p = I + (h/2) B M⁻¹ is then block pentadiagonal,
/// assembled by probing and solved as a band matrix in O(n) (`steppers/coupled.rs`).
pub trait CoupledDissipativeTerm<D: Scalar, const DIM: usize>:
    Clone + std::fmt::Debug + Send + Sync
{
    /// A short name for diagnostics and tests.
    fn name(&self) -> &'static str;

    /// Accumulates F(q, v) into `out` (v = q̇ = M⁻¹p; linear in v), parameters read through
    /// [`Ctx::param`].
    fn force<E: Embed<D>>(
        &self,
        q: &[[E; DIM]],
        v: &[[E; DIM]],
        ctx: &Ctx<E>,
        out: &mut [[E; DIM]],
    );

    /// Whether the term reads the physical parameter `p` (other than the mass, which every
    /// coupled term reads through q̇ = M⁻¹p).
    fn has_parameter(&self, p: Parameter) -> bool;

    /// Accumulates `scale` · ∇_q (w·F(q, v)) into `out`, (q, v, w) = `at`. Default: one
    /// `Dual<D>` evaluation of [`CoupledDissipativeTerm::force`] per component of q (O(n²)).
    fn force_q_vjp(
        &self,
        at: CoupledAt<'_, D, DIM>,
        ctx: &Ctx<D>,
        scale: D,
        out: &mut [[D; DIM]],
        scratch: &mut DualScratch<D, DIM>,
    ) {
        let CoupledAt { q, v, w } = at;
        let c = ctx.dual(None);
        scratch.load_v(v);
        for i in 0..q.len() {
            for d in 0..DIM {
                load_seeded(scratch, q, (i, d));
                self.force(&scratch.q, &scratch.v, &c, &mut scratch.f);
                out[i][d] += scratch.contract(w) * scale;
            }
        }
    }
}

/// Loads q with the ε-part 1 on component `d` of block `i` and clears the force buffer.
fn load_seeded<D: Scalar, const DIM: usize>(
    s: &mut DualScratch<D, DIM>,
    q: &[[D; DIM]],
    (i, d): (usize, usize),
) {
    for (j, (sq, f)) in s.q.iter_mut().zip(s.f.iter_mut()).enumerate() {
        for c in 0..DIM {
            let eps = if j == i && c == d {
                D::one()
            } else {
                D::zero()
            };
            sq[c] = Dual::new(q[j][c], eps);
            f[c] = Dual::from_re(D::zero());
        }
    }
}

/// Where a coupled term's products are taken: the attitudes q, the velocities v = M⁻¹p the force
/// is linear in, and the cotangent w the force is contracted with (w·F).
#[derive(Clone, Copy, Debug)]
pub struct CoupledAt<'a, D, const DIM: usize> {
    /// The attitudes q.
    pub q: &'a [[D; DIM]],
    /// The velocities v = M⁻¹p.
    pub v: &'a [[D; DIM]],
    /// The cotangent w.
    pub w: &'a [[D; DIM]],
}

/// Visits every coupled dissipative term of a chain (see
/// [`crate::Chain::visit_coupled_dissipation`]).
pub trait CoupledVisitor<D: Scalar, const DIM: usize> {
    /// Called once per coupled dissipative term present in the model.
    fn visit<T: CoupledDissipativeTerm<D, DIM>>(&mut self, term: &T);
}

/// Counts the terms and collects their names.
struct Names(Vec<&'static str>);

impl<D: Scalar, const DIM: usize> CoupledVisitor<D, DIM> for Names {
    fn visit<T: CoupledDissipativeTerm<D, DIM>>(&mut self, term: &T) {
        self.0.push(term.name());
    }
}

/// Whether some term reads a parameter.
struct Reads(Parameter, bool);

impl<D: Scalar, const DIM: usize> CoupledVisitor<D, DIM> for Reads {
    fn visit<T: CoupledDissipativeTerm<D, DIM>>(&mut self, term: &T) {
        self.1 |= term.has_parameter(self.0);
    }
}

/// Σ_T F_T(q, v) accumulated into `out`.
struct ForceSum<'a, D, const DIM: usize> {
    q: &'a [[D; DIM]],
    v: &'a [[D; DIM]],
    ctx: &'a Ctx<D>,
    out: &'a mut [[D; DIM]],
}

impl<D: Scalar, const DIM: usize> CoupledVisitor<D, DIM> for ForceSum<'_, D, DIM> {
    fn visit<T: CoupledDissipativeTerm<D, DIM>>(&mut self, term: &T) {
        term.force(self.q, self.v, self.ctx, self.out);
    }
}

/// The products that take a dual scratch: `scale`·∇_q(w·F) (`out` given) or w·∂F/∂θ.
struct Products<'a, D, const DIM: usize> {
    at: CoupledAt<'a, D, DIM>,
    ctx: &'a Ctx<D>,
    scale: D,
    out: Option<&'a mut [[D; DIM]]>,
    param: Option<Parameter>,
    /// Σ_T w·∂F_T/∂θ, and Σ_T w·F_T (for the mass).
    sums: (D, D),
    scratch: &'a mut DualScratch<D, DIM>,
}

impl<D: Scalar, const DIM: usize> CoupledVisitor<D, DIM> for Products<'_, D, DIM> {
    fn visit<T: CoupledDissipativeTerm<D, DIM>>(&mut self, term: &T) {
        if let Some(out) = self.out.as_deref_mut() {
            term.force_q_vjp(self.at, self.ctx, self.scale, out, self.scratch);
            return;
        }
        let Some(p) = self.param else { return };
        let seed = term.has_parameter(p).then_some(p);
        let s = &mut *self.scratch;
        s.load(self.at.q, None);
        s.load_v(self.at.v);
        term.force(&s.q, &s.v, &self.ctx.dual(seed), &mut s.f);
        self.sums.0 += s.contract(self.at.w);
        self.sums.1 += s.contract_re(self.at.w);
    }
}

impl<D: Scalar, const DIM: usize> Chain<D, DIM> {
    /// Whether the model has a coupled dissipative term ([`Chain::visit_coupled_dissipation`]).
    #[inline]
    pub fn has_coupled_dissipation(&self) -> bool {
        self.joint_damping.is_some()
    }

    /// The names of the coupled dissipative terms, in the order they are visited.
    pub fn coupled_dissipation_names(&self) -> Vec<&'static str> {
        let mut v = Names(Vec::new());
        self.visit_coupled_dissipation(&mut v);
        v.0
    }

    /// Whether the coupled terms read the parameter `p`: a term's own parameters, and the mass
    /// (through q̇ = M⁻¹p) whenever there is a coupled term.
    pub fn coupled_has_parameter(&self, p: Parameter) -> bool {
        if p == Parameter::Mass {
            return self.has_coupled_dissipation();
        }
        let mut r = Reads(p, false);
        self.visit_coupled_dissipation(&mut r);
        r.1
    }

    /// Accumulates Σ_T F_T(q, v) (module docs; v = q̇ = M⁻¹p) into `out`.
    #[inline]
    pub fn coupled_force(
        &self,
        q: &[[D; DIM]],
        v: &[[D; DIM]],
        ctx: &Ctx<D>,
        out: &mut [[D; DIM]],
    ) {
        self.visit_coupled_dissipation(&mut ForceSum { q, v, ctx, out });
    }

    /// Accumulates `scale` · Σ_T ∇_q (w·F_T(q, v)) into `out`
    /// ([`CoupledDissipativeTerm::force_q_vjp`]).
    pub fn coupled_force_q_vjp(
        &self,
        at: CoupledAt<'_, D, DIM>,
        ctx: &Ctx<D>,
        scale: D,
        out: &mut [[D; DIM]],
        scratch: &mut DualScratch<D, DIM>,
    ) {
        self.visit_coupled_dissipation(&mut Products {
            at,
            ctx,
            scale,
            out: Some(out),
            param: None,
            sums: (D::zero(), D::zero()),
            scratch,
        });
    }

    /// w·∂(Σ_T F_T(q, M⁻¹p))/∂θ at fixed (q, p), with v = M⁻¹p: the terms' own parameters by
    /// dual numbers, and for the (uniform) mass −w·F(q, v)/m (M⁻¹ ∝ 1/m).
    pub fn coupled_parameter_contraction(
        &self,
        at: CoupledAt<'_, D, DIM>,
        ctx: &Ctx<D>,
        p: Parameter,
        scratch: &mut DualScratch<D, DIM>,
    ) -> D {
        let mut pr = Products {
            at,
            ctx,
            scale: D::one(),
            out: None,
            param: Some(p),
            sums: (D::zero(), D::zero()),
            scratch,
        };
        self.visit_coupled_dissipation(&mut pr);
        let (dtheta, wf) = pr.sums;
        if p == Parameter::Mass {
            dtheta - wf * self.inv_masses[0]
        } else {
            dtheta
        }
    }
}
