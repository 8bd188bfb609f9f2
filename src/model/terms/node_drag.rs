//! Morison's drag node by node (`[pipe] drag_model = "morison"`; docs/conventions.md "Morison's
//! drag node by node").
//!
//! Node k (1-based, at rₖ = Σ_{j≤k} lⱼqⱼ) moves at vₖ = Σ_{j≤k} lⱼq̇ⱼ through water moving at Uₖ
//! (current and waves, [`super::CurrentDrag::momentum`]); over its cell cₖ (half of each
//! neighbouring pendulum, half a pendulum at the tip) it feels Morison's drag
//!
//! ```text
//! Fₖ = −κₖ |v_r⊥| v_r⊥,   v_r = vₖ − Uₖ,   κₖ = ½ ρ_w C_d D_o cₖ,
//! ```
//!
//! transverse to the beam's axis y (the Euclidean norm over (x, z); no drag along the axis).
//! Its generalised force is Qⱼ = lⱼ Σ_{k≥j} Fₖ. With q̇ = M⁻¹p and M̄⁻¹ = Aᵀ diag(1/m) A, where
//! (A x)ₖ = xₖ/lₖ − xₖ₊₁/lₖ₊₁ is upper bidiagonal, the node momenta are mₖvₖ = (A p)ₖ, and
//! A⁻¹ = diag(l) Tᵀ (suffix sums), so
//!
//! ```text
//! Q(p) = A⁻¹ F(y),   y = A (p − P),   Fₖ(y) = −Dₖ |yₖ⊥| yₖ⊥,   Dₖ = κₖ/mₖ²,
//! ```
//!
//! P the water's momentum (Pⱼ = lⱼ Σ_{k≥j} mₖUₖ, so that A P = m ⊙ U). RATTLE's implicit half
//! step p − (h/2) Q(p) = c becomes, multiplied by A, y − (h/2) F(y) = A(c − P) =: b: **one
//! closed-form root per node** (the thesis drag's, `root_of`), then p = A⁻¹ y + P by suffix
//! sums, O(n). Its Jacobian W = ∂p/∂c = A⁻¹ Ω A with Ω = diag(Ωₖ) the nodes' root slopes, so
//! M⁻¹W = Aᵀ diag(Ωₖ/mₖ) A is tridiagonal like M⁻¹ itself: the Newton matrix
//! Ĝ(q′) M⁻¹ W Ĝ(q)ᵀ keeps its bordered tridiagonal form
//! ([`crate::constraints::ConstraintOperator::assemble_newton_nodes`]).

use super::current::CurrentDrag;
use super::drag::{root_of, slope_of};
use super::{BlockSym, Ctx, Embed};
use crate::base::{Parameter, Scalar};
use crate::model::geometry::dot;
use num_dual::Dual;
use std::sync::Arc;

/// Morison's drag node by node (module docs), over the water of a [`CurrentDrag`] (whose own drag
/// constant is not used).
#[derive(Clone, Debug)]
pub struct NodeDrag<D, const DIM: usize> {
    /// C_d (the parameter [`Parameter::DragCoefficient`]).
    pub(crate) cd: D,
    /// Dₖ/C_d = ½ ρ_w D_o cₖ / mₖ² per node.
    pub(crate) per_cd: Vec<f64>,
    /// Dₖ/C_d in the chain's scalar, when the nodes' drag coefficients and masses carry a
    /// parameter's derivative ([`NodeDrag::set_node_coefficients`]); read in place of
    /// `per_cd` (whose values are its real parts). `None` as built.
    per_cd_nodes: Option<Vec<D>>,
    /// The water's momentum P (current and waves).
    pub(crate) water: CurrentDrag<D, DIM>,
    /// P at the midpoints of a horizon's steps, tabulated once for many sweeps over it
    /// ([`NodeDrag::tabulate_water`]); `None` unless asked for.
    table: Option<Arc<WaterTable<D, DIM>>>,
}

/// The water's momenta P(t_k + h/2) of the steps k = 0..steps of one horizon, as
/// [`NodeDrag::water_momenta`] computes them (the same values bit for bit): a receding-horizon
/// plan sweeps the same horizon forward and backward a dozen times per re-plan, and P is a known
/// function of time.
#[derive(Debug)]
struct WaterTable<D, const DIM: usize> {
    /// The midpoint time t_k + h/2 of each row, as the step's context holds it: a row is read
    /// only for a context at exactly that time (and no seeded parameter).
    times: Vec<f64>,
    /// steps × n momenta, step-major.
    rows: Vec<[D; DIM]>,
}

impl<D: Scalar, const DIM: usize> NodeDrag<D, DIM> {
    /// The term for drag coefficient `cd`, drag per unit length and coefficient ½ ρ_w D_o
    /// (`half_rho_d`), on a chain with these lengths and masses, in the water of `water`.
    pub(crate) fn new(
        cd: f64,
        half_rho_d: f64,
        lengths: &[f64],
        masses: &[f64],
        water: CurrentDrag<D, DIM>,
    ) -> Self {
        let n = lengths.len();
        let per_cd = (0..n)
            .map(|k| {
                let next = lengths.get(k + 1).copied().unwrap_or(0.0);
                let cell = 0.5 * (lengths[k] + next);
                half_rho_d * cell / (masses[k] * masses[k])
            })
            .collect();
        NodeDrag {
            cd: D::from(cd),
            per_cd,
            per_cd_nodes: None,
            water,
            table: None,
        }
    }

    /// The term from each node's own drag coefficient κₖ = ½ ρ_w C_d D_h cₖ \[kg/m\] (a
    /// stack-up's [`crate::scene::Layout::node_drag`]: per segment its C_d and hydrodynamic
    /// diameter over the node's wet cell, and a body's ½ ρ_w C_dA split to its end nodes), on a
    /// chain with these masses: Dₖ = κₖ/mₖ². The parameter [`Parameter::DragCoefficient`] is then
    /// a factor on every κₖ (1 as built), ∂J/∂factor = Σ_segments C_d ∂J/∂C_d.
    pub(crate) fn from_node_coefficients(
        kappa: &[f64],
        masses: &[f64],
        water: CurrentDrag<D, DIM>,
    ) -> Self {
        NodeDrag {
            cd: D::one(),
            per_cd: kappa.iter().zip(masses).map(|(k, m)| k / (m * m)).collect(),
            per_cd_nodes: None,
            water,
            table: None,
        }
    }

    /// Takes the nodes' drag coefficients κₖ and masses mₖ in the chain's scalar (a
    /// stack-up's, seeded with their derivatives with respect to a parameter,
    /// [`crate::Chain::set_node_quantities`]): Dₖ/C_d = κₖ/mₖ², as
    /// [`NodeDrag::from_node_coefficients`] forms it (the same real parts bit for bit).
    pub(crate) fn set_node_coefficients(&mut self, kappa: &[D], masses: &[D]) {
        let nodes: Vec<D> = kappa
            .iter()
            .zip(masses)
            .map(|(&k, &m)| k / (m * m))
            .collect();
        self.per_cd = nodes.iter().map(|x| x.re()).collect();
        self.per_cd_nodes = Some(nodes);
        self.table = None;
    }

    /// The same term over another scalar (real parts).
    pub(crate) fn lift<D2: Scalar>(&self) -> NodeDrag<D2, DIM> {
        NodeDrag {
            cd: D2::from(self.cd.re()),
            per_cd: self.per_cd.clone(),
            per_cd_nodes: None,
            water: self.water.lift(),
            table: None,
        }
    }

    /// Whether the term reads parameter `p`: C_d, and the current's speed.
    pub fn has_parameter(&self, p: Parameter) -> bool {
        p == Parameter::DragCoefficient
            || (p == Parameter::CurrentSpeed && self.water.reads_speed())
    }

    /// Dₖ = C_d ⋅ ½ ρ_w D_o cₖ / mₖ².
    #[inline]
    fn node_constant<E: Embed<D>>(&self, k: usize, ctx: &Ctx<E>) -> E {
        let cd = ctx.param(Parameter::DragCoefficient, self.cd);
        match &self.per_cd_nodes {
            Some(nodes) => cd * E::embed(nodes[k]),
            None => cd * self.per_cd[k],
        }
    }

    /// y = A (p − P) (module docs) into `y`.
    pub fn node_momenta<E: Embed<D>>(
        &self,
        p: &[[E; DIM]],
        inv_lengths: &[D],
        ctx: &Ctx<E>,
        y: &mut [[E; DIM]],
    ) {
        let n = p.len();
        let mut next = [E::zero(); DIM];
        for k in (0..n).rev() {
            let il = E::embed(inv_lengths[k]);
            let cur: [E; DIM] =
                std::array::from_fn(|d| (p[k][d] - self.water.momentum(k, d, ctx)) * il);
            y[k] = std::array::from_fn(|d| cur[d] - next[d]);
            next = cur;
        }
    }

    /// The water's momentum P at the context's time (current and waves) into `out`, P_k as
    /// [`CurrentDrag::momentum`] gives it: a known function of time, the same for every
    /// evaluation of one step's half steps (both read it at t_k + h/2), so the step reads it
    /// once per step for [`NodeDrag::implicit_half_step`] and
    /// [`NodeDrag::generalised_force_in`] instead of once per node, Newton iteration and pass.
    /// With a table (`NodeDrag::tabulate_water`, filled once per MPC re-plan) whose row for
    /// the context's step holds this very time, that row is copied instead.
    pub fn water_momenta(&self, ctx: &Ctx<D>, out: &mut [[D; DIM]]) {
        if let Some(t) = &self.table {
            let n = out.len();
            if ctx.seed.is_none()
                && t.times.get(ctx.step).map(|x| x.to_bits()) == Some(ctx.t.to_bits())
            {
                out.copy_from_slice(&t.rows[ctx.step * n..(ctx.step + 1) * n]);
                return;
            }
        }
        self.water.momenta(ctx, out);
    }

    /// Tabulates P(t_k + h/2) for the steps k = 0..steps of a horizon whose step k has the
    /// context `ctx_of(k)` ([`crate::Chain::dissipation_ctx`]), so that every later sweep over
    /// it copies them ([`NodeDrag::water_momenta`]); the values are those of the direct
    /// evaluation bit for bit (they are it). Replaces any earlier table.
    pub(crate) fn tabulate_water(
        &mut self,
        n: usize,
        steps: usize,
        ctx_of: impl Fn(usize) -> Ctx<D>,
    ) {
        self.table = None;
        let mut times = Vec::with_capacity(steps);
        let mut rows = vec![[D::zero(); DIM]; steps * n];
        for (k, row) in rows.chunks_exact_mut(n.max(1)).enumerate().take(steps) {
            let ctx = ctx_of(k);
            self.water.momenta(&ctx, row);
            times.push(if ctx.seed.is_none() { ctx.t } else { f64::NAN });
        }
        self.table = Some(Arc::new(WaterTable { times, rows }));
    }

    /// Drops the table of [`NodeDrag::tabulate_water`] (the water or a parameter changed).
    pub(crate) fn clear_water_table(&mut self) {
        self.table = None;
    }

    /// y = A (p − P) with P given (`water`, [`NodeDrag::water_momenta`]): the same arithmetic
    /// as [`NodeDrag::node_momenta`], bit for bit.
    fn node_momenta_in(p: &[[D; DIM]], inv_lengths: &[D], water: &[[D; DIM]], y: &mut [[D; DIM]]) {
        let n = p.len();
        let mut next = [D::zero(); DIM];
        for k in (0..n).rev() {
            let il = inv_lengths[k];
            let cur: [D; DIM] = std::array::from_fn(|d| (p[k][d] - water[k][d]) * il);
            y[k] = std::array::from_fn(|d| cur[d] - next[d]);
            next = cur;
        }
    }

    /// Q(p) of [`NodeDrag::generalised_force`] with the water's momentum P given (`water`,
    /// [`NodeDrag::water_momenta`] at the context's time): the same values bit for bit.
    pub fn generalised_force_in(
        &self,
        p: &[[D; DIM]],
        (lengths, inv_lengths): (&[D], &[D]),
        (ctx, water): (&Ctx<D>, &[[D; DIM]]),
        y: &mut [[D; DIM]],
        out: &mut [[D; DIM]],
    ) {
        Self::node_momenta_in(p, inv_lengths, water, y);
        self.node_forces(y, ctx, out);
        suffix_scale(out, lengths);
    }

    /// a += s Q(p) with Q = A⁻¹ F(A(p − P)) and P given (`water`): RATTLE's second half kick
    /// of this drag in one reverse pass, y = A(p − P) ([`NodeDrag::node_momenta_in`]), the node
    /// forces ([`NodeDrag::node_forces`]) and their suffix sums (`suffix_scale`) carried from
    /// the tip down; each value is [`NodeDrag::generalised_force_in`]'s, and the kick's
    /// aᵢ + Qᵢ s, bit for bit.
    pub(crate) fn kick_in(
        &self,
        p: &[[D; DIM]],
        (lengths, inv_lengths): (&[D], &[D]),
        (ctx, water): (&Ctx<D>, &[[D; DIM]]),
        s: f64,
        a: &mut [[D; DIM]],
    ) {
        let n = p.len();
        let mut next = [D::zero(); DIM];
        let mut sum = [D::zero(); DIM];
        for k in (0..n).rev() {
            let il = inv_lengths[k];
            let cur: [D; DIM] = std::array::from_fn(|d| (p[k][d] - water[k][d]) * il);
            let y: [D; DIM] = std::array::from_fn(|d| cur[d] - next[d]);
            next = cur;
            let f = transverse_morison(self.node_constant(k, ctx), &y);
            for d in 0..DIM {
                sum[d] += f[d];
                a[k][d] += sum[d] * lengths[k] * s;
            }
        }
    }

    /// The node forces F(y) (transverse Morison, no axial part) into `f`.
    pub fn node_forces<E: Embed<D>>(&self, y: &[[E; DIM]], ctx: &Ctx<E>, f: &mut [[E; DIM]]) {
        for (k, (f, y)) in f.iter_mut().zip(y).enumerate() {
            *f = transverse_morison(self.node_constant(k, ctx), y);
        }
    }

    /// Q(p) = A⁻¹ F(A(p − P)) (module docs) into `out`, `y` scratch of length n.
    pub fn generalised_force<E: Embed<D>>(
        &self,
        p: &[[E; DIM]],
        (lengths, inv_lengths): (&[D], &[D]),
        ctx: &Ctx<E>,
        y: &mut [[E; DIM]],
        out: &mut [[E; DIM]],
    ) {
        self.node_momenta(p, inv_lengths, ctx, y);
        self.node_forces(y, ctx, out);
        suffix_scale(out, lengths);
    }

    /// The root of node k's implicit half step (the transverse drag's root of
    /// y − (h/2) F(y) = b, the axial component passed through) and Ωₖ = ∂yₖ/∂bₖ (axial 1):
    /// the per-node arithmetic of [`NodeDrag::implicit_half_step`], written once for it and for
    /// [`NodeDrag::half_step_iterate`].
    #[inline(always)]
    fn node_root(
        &self,
        k: usize,
        b: &[D; DIM],
        h: f64,
        ctx: &Ctx<D>,
    ) -> ([D; DIM], BlockSym<D, DIM>) {
        let ax = DIM - 2;
        let (mut r, mut om) = root_of(self.node_constant(k, ctx), b, h);
        r[ax] = b[ax];
        om.diag[ax] = D::one();
        (r, om)
    }

    /// One Newton iterate of RATTLE's first half step with this drag, in two passes over the
    /// chain instead of the ten of its parts (the plant's hot loop, `steppers::rattle`): from
    /// λ, c = a − (h/2) Ĝ(q)ᵀλ, the half step p_{k+½} of [`NodeDrag::implicit_half_step`]
    /// (b = A(c − P), a root per node, p = A⁻¹y + P) with Ω, M⁻¹p_{k+½} and
    /// q′ = q + h M⁻¹p_{k+½}, and the constraint residual ĝ(q′) − (0, …, 0, ζ) with its
    /// max-norm (the tip row scaled by the beam's length), which it returns. Every value is
    /// formed by the arithmetic of the separate passes (`ConstraintOperator::add_transpose`,
    /// `implicit_half_step`, `Chain::apply_inverse_mass`, `ConstraintOperator::residual`), in
    /// the same order, so the outputs are theirs bit for bit; the reverse pass carries
    /// (c − P)/l, the roots' suffix sum and p/l of the node above, the forward pass M⁻¹'s
    /// running difference and the tip's Σ lᵢ q′ᵢ,z.
    pub(crate) fn half_step_iterate(
        &self,
        ctx: &Ctx<D>,
        x: &IterateInputs<'_, D, DIM>,
        o: &mut IterateOutputs<'_, D, DIM>,
    ) -> f64 {
        let n = x.q.len();
        let z = DIM - 1;
        let h = x.h;
        let scale = D::from(-0.5 * h);
        let lam_tip = if x.bordered { x.lam[n] } else { D::zero() };
        // (c − P)/l of node k + 1, the roots' suffix sum, p/l of pendulum k + 1.
        let mut next = [D::zero(); DIM];
        let mut sum = [D::zero(); DIM];
        let mut next_p = [D::zero(); DIM];
        for k in (0..n).rev() {
            let (q, w, l, il) = (&x.q[k], &x.water[k], x.lengths[k], x.inv_lengths[k]);
            let mut c = x.a[k];
            for d in 0..DIM {
                c[d] += x.lam[k] * q[d] * scale;
            }
            if x.bordered {
                c[z] += lam_tip * l * scale;
            }
            o.c[k] = c;
            let cur: [D; DIM] = std::array::from_fn(|d| (c[d] - w[d]) * il);
            let b: [D; DIM] = std::array::from_fn(|d| cur[d] - next[d]);
            next = cur;
            let (r, om) = self.node_root(k, &b, h, ctx);
            o.omega[k] = om;
            let mut p = [D::zero(); DIM];
            for d in 0..DIM {
                sum[d] += r[d];
                p[d] = sum[d] * l;
            }
            for d in 0..DIM {
                p[d] += w[d];
            }
            o.phalf[k] = p;
            // M⁻¹'s first pass: uₖ = (pₖ/lₖ − pₖ₊₁/lₖ₊₁)/mₖ.
            let mut pl = p;
            for v in pl.iter_mut() {
                *v *= il;
            }
            o.minv_p[k] = std::array::from_fn(|d| (pl[d] - next_p[d]) * x.inv_masses[k]);
            next_p = pl;
        }
        let mut prev = [D::zero(); DIM];
        let mut rmax: f64 = 0.0;
        let mut tip = D::zero();
        for k in 0..n {
            let u = o.minv_p[k];
            let v: [D; DIM] = std::array::from_fn(|d| (u[d] - prev[d]) * x.inv_lengths[k]);
            prev = u;
            o.minv_p[k] = v;
            let qn: [D; DIM] = std::array::from_fn(|d| x.q[k][d] + v[d] * h);
            o.qnew[k] = qn;
            let r = (dot(&qn, &qn) - 1.0) * 0.5;
            rmax = rmax.max(r.re().abs());
            o.residual[k] = r;
            tip += x.lengths[k] * qn[z];
        }
        if x.bordered {
            let r = tip - x.tip_target;
            rmax = rmax.max(r.re().abs() / x.total_length);
            o.residual[n] = r;
        }
        rmax
    }

    /// The implicit half step p − (h/2) Q(p) = c: b = A(c − P), yₖ the drag's root of
    /// y − (h/2) F(y) = b at each node, p = A⁻¹ y + P; `omega` gets Ωₖ = ∂yₖ/∂bₖ (axial 1).
    /// `water` is P at the context's time ([`NodeDrag::water_momenta`]).
    pub fn implicit_half_step(
        &self,
        c: &[[D; DIM]],
        (lengths, inv_lengths): (&[D], &[D]),
        (h, ctx, water): (f64, &Ctx<D>, &[[D; DIM]]),
        p: &mut [[D; DIM]],
        omega: &mut [BlockSym<D, DIM>],
    ) {
        Self::node_momenta_in(c, inv_lengths, water, p);
        for (k, (y, w)) in p.iter_mut().zip(omega.iter_mut()).enumerate() {
            let b = *y;
            (*y, *w) = self.node_root(k, &b, h, ctx);
        }
        suffix_scale(p, lengths);
        for (pk, w) in p.iter_mut().zip(water) {
            for d in 0..DIM {
                pk[d] += w[d];
            }
        }
    }
}

/// What one fused Newton iterate of the half step reads ([`NodeDrag::half_step_iterate`]).
#[derive(Clone, Copy, Debug)]
pub(crate) struct IterateInputs<'a, D, const DIM: usize> {
    /// q_k.
    pub q: &'a [[D; DIM]],
    /// a = p_k − (h/2) U_q(q_k).
    pub a: &'a [[D; DIM]],
    /// The Newton iterate λ (n, + 1 with the tip row).
    pub lam: &'a [D],
    /// The water's momentum P(t_k + h/2) ([`NodeDrag::water_momenta`]).
    pub water: &'a [[D; DIM]],
    /// lᵢ.
    pub lengths: &'a [D],
    /// 1/lᵢ.
    pub inv_lengths: &'a [D],
    /// 1/mᵢ.
    pub inv_masses: &'a [D],
    /// Whether the tip row is present.
    pub bordered: bool,
    /// The tip row's target ζ_{k+1}.
    pub tip_target: D,
    /// Σ lᵢ (real parts, summed as `ConstraintOperator::residual` sums them), the tip row's
    /// scale in the max-norm.
    pub total_length: f64,
    /// The step h.
    pub h: f64,
}

/// What one fused Newton iterate writes ([`NodeDrag::half_step_iterate`]).
#[derive(Debug)]
pub(crate) struct IterateOutputs<'a, D, const DIM: usize> {
    /// c = a − (h/2) Ĝ(q_k)ᵀλ.
    pub c: &'a mut [[D; DIM]],
    /// p_{k+½}.
    pub phalf: &'a mut [[D; DIM]],
    /// The nodes' root slopes Ωₖ (W = A⁻¹ΩA).
    pub omega: &'a mut [BlockSym<D, DIM>],
    /// M⁻¹ p_{k+½}.
    pub minv_p: &'a mut [[D; DIM]],
    /// q′ = q_k + h M⁻¹ p_{k+½}.
    pub qnew: &'a mut [[D; DIM]],
    /// ĝ(q′) − (0, …, 0, ζ).
    pub residual: &'a mut [D],
}

/// Scratch of the reverse products of a [`NodeDrag`] (allocated once per sweep).
#[derive(Clone, Debug)]
pub struct NodeReverseScratch<D, const DIM: usize> {
    y: Vec<[D; DIM]>,
    water: Vec<[D; DIM]>,
    dp: Vec<[Dual<D>; DIM]>,
    dy: Vec<[Dual<D>; DIM]>,
    dq: Vec<[Dual<D>; DIM]>,
}

impl<D: Scalar, const DIM: usize> NodeReverseScratch<D, DIM> {
    /// For a chain of `n` pendulums.
    pub fn new(n: usize) -> Self {
        NodeReverseScratch {
            y: vec![[D::zero(); DIM]; n],
            water: vec![[D::zero(); DIM]; n],
            dp: vec![[Dual::from_re(D::zero()); DIM]; n],
            dy: vec![[Dual::from_re(D::zero()); DIM]; n],
            dq: vec![[Dual::from_re(D::zero()); DIM]; n],
        }
    }
}

impl<D: Scalar, const DIM: usize> NodeDrag<D, DIM> {
    /// x ← (∂Q/∂p)ᵀ x = Aᵀ F′(y) A⁻ᵀ x at p (y = A(p − P); F′ symmetric per node, no axial
    /// part): the second half step's reverse, p̄½ = b̄ + (h/2)(∂Q/∂p)ᵀ b̄.
    pub(crate) fn slope_transpose_apply(
        &self,
        p: &[[D; DIM]],
        (lengths, inv_lengths): (&[D], &[D]),
        ctx: &Ctx<D>,
        x: &mut [[D; DIM]],
        scratch: &mut NodeReverseScratch<D, DIM>,
    ) {
        // P once for all nodes (or from the horizon's table): the same values as
        // `node_momenta`'s node by node reads, bit for bit.
        self.water_momenta(ctx, &mut scratch.water);
        Self::node_momenta_in(p, inv_lengths, &scratch.water, &mut scratch.y);
        prefix_scale(x, lengths);
        let ax = DIM - 2;
        for (k, (x, y)) in x.iter_mut().zip(&scratch.y).enumerate() {
            let (_, mut j) = slope_of(self.node_constant(k, ctx), y);
            j.diag[ax] = D::zero();
            *x = j.apply(x);
        }
        difference_scale(x, inv_lengths);
    }

    /// x ← Wᵀ x = Aᵀ Ω A⁻ᵀ x (W = A⁻¹ Ω A of the half step, Ω recorded by it, each block
    /// symmetric).
    pub(crate) fn w_transpose_apply(
        omega: &[BlockSym<D, DIM>],
        (lengths, inv_lengths): (&[D], &[D]),
        x: &mut [[D; DIM]],
    ) {
        prefix_scale(x, lengths);
        for (x, w) in x.iter_mut().zip(omega) {
            *x = w.apply(x);
        }
        difference_scale(x, inv_lengths);
    }

    /// w·∂Q/∂θ at p for the parameter θ (C_d, or the current's speed through P), by one
    /// `Dual<D>` evaluation of Q with θ seeded.
    pub(crate) fn parameter_contraction(
        &self,
        p: &[[D; DIM]],
        ls: (&[D], &[D]),
        (ctx, param): (&Ctx<D>, Parameter),
        w: &[[D; DIM]],
        scratch: &mut NodeReverseScratch<D, DIM>,
    ) -> D {
        if !self.has_parameter(param) {
            return D::zero();
        }
        let c = ctx.dual(Some(param));
        for (o, p) in scratch.dp.iter_mut().zip(p) {
            *o = p.map(Dual::from_re);
        }
        let NodeReverseScratch { dp, dy, dq, .. } = scratch;
        self.generalised_force(dp, ls, &c, dy, dq);
        let out = &*dq;
        let mut s = D::zero();
        for (o, w) in out.iter().zip(w) {
            for d in 0..DIM {
                s += o[d].eps * w[d];
            }
        }
        s
    }
}

/// x ← A⁻ᵀ x = T diag(l) x: xₖ ← Σ_{j≤k} lⱼ xⱼ (prefix sums).
fn prefix_scale<D: Scalar, const DIM: usize>(x: &mut [[D; DIM]], lengths: &[D]) {
    let mut s = [D::zero(); DIM];
    for (x, l) in x.iter_mut().zip(lengths) {
        for (s, x) in s.iter_mut().zip(x.iter()) {
            *s += *x * *l;
        }
        *x = s;
    }
}

/// x ← Aᵀ x: xⱼ ← (xⱼ − xⱼ₋₁)/lⱼ (x₋₁ = 0).
fn difference_scale<D: Scalar, const DIM: usize>(x: &mut [[D; DIM]], inv_lengths: &[D]) {
    let mut prev = [D::zero(); DIM];
    for (x, il) in x.iter_mut().zip(inv_lengths) {
        let cur = *x;
        for d in 0..DIM {
            x[d] = (cur[d] - prev[d]) * *il;
        }
        prev = cur;
    }
}

/// Fₖ = −D |y⊥| y⊥ with no axial part ([`super::drag::morison`] without its y component).
#[inline]
fn transverse_morison<S: Scalar, const DIM: usize>(drag: S, y: &[S; DIM]) -> [S; DIM] {
    let mut f = super::drag::morison(drag, y);
    f[DIM - 2] = S::zero();
    f
}

/// x ← A⁻¹ x = diag(l) Tᵀ x: xⱼ ← lⱼ Σ_{k≥j} xₖ (suffix sums).
pub(crate) fn suffix_scale<E: Embed<D>, D: Scalar, const DIM: usize>(
    x: &mut [[E; DIM]],
    lengths: &[D],
) {
    let mut s = [E::zero(); DIM];
    for j in (0..x.len()).rev() {
        for d in 0..DIM {
            s[d] += x[j][d];
            x[j][d] = s[d] * E::embed(lengths[j]);
        }
    }
}
