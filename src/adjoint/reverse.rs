//! One reverse step k + 1 → k of the discrete adjoint: the vector-Jacobian product of the
//! recorded RATTLE step, built from the model's operators (the terms' derived products and the
//! constraint operator). See the module docs of [`crate::adjoint`] for the equations.

use super::node_tangent::NodeTangent;
use super::tape::StateView;
use crate::base::{Parameter, Scalar};
use crate::error::Result;
use crate::model::terms::NodeReverseScratch;
use crate::model::{BlockSym, Chain, CoupledAt, Ctx, DualScratch, NodeDrag, ReactionTip};
use crate::steppers::coupled::CoupledHalf;
use crate::steppers::singular;
use crate::tridiag::BorderedTridiag;

/// The cotangents carried backwards: q̄, p̄ and the tip target's (ζ̄, v̄) at the current step, and
/// the accumulated ∂J/∂u_k (∂J/∂u_{x,k}) and ∂J/∂θ.
pub(crate) struct Cotangents<D, const DIM: usize> {
    pub qbar: Vec<[D; DIM]>,
    pub pbar: Vec<[D; DIM]>,
    pub tip_bar: [D; 2],
    pub ubar: Vec<D>,
    /// ∂J/∂u_{x,k} of a 2-axis control (empty for a 1-axis control).
    pub uxbar: Vec<D>,
    pub thbar: Vec<D>,
}

/// What every reverse step of one sweep shares: the model, h, the requested parameters, and the
/// scratch memory (allocated once per sweep).
pub(crate) struct ReverseSweep<'a, D, const DIM: usize> {
    ch: &'a Chain<D, DIM>,
    h: f64,
    params: &'a [Parameter],
    mass_param: Option<usize>,
    /// The index of the vessel's mean offset Z₀ in the request ([`Parameter::VesselOffset`]).
    offset_param: Option<usize>,
    /// The requested parameters some dissipative term reads (drag D, current speed, mass).
    drag_params: Vec<(usize, Parameter)>,
    tmp: Vec<[D; DIM]>,
    tmp2: Vec<[D; DIM]>,
    bbar: Vec<[D; DIM]>,
    phbar: Vec<[D; DIM]>,
    cbar: Vec<[D; DIM]>,
    rhs: Vec<D>,
    scal: Vec<D>,
    tri: BorderedTridiag<D>,
    scratch: DualScratch<D, DIM>,
    /// The band matrices of a model with coupled dissipative terms (joint damping), the
    /// requested parameters they read (their own and the mass), and M⁻¹p_{k+½}.
    coupled: Option<CoupledHalf<D, DIM>>,
    coupled_params: Vec<(usize, Parameter)>,
    vhalf: Vec<[D; DIM]>,
    /// Morison's drag node by node: the reverse products' scratch and the requested parameters
    /// it reads (C_d, the current's speed).
    node: Option<NodeReverseScratch<D, DIM>>,
    node_params: Vec<(usize, Parameter)>,
    /// Parameters the per-node quantities carry (a segment's buoyancy diameter): their index
    /// in the cotangent θ̄ (after the library's parameters) and their tangents
    /// ([`super::node_tangent`]).
    nodes: Vec<(usize, Box<dyn NodeTangent<D, DIM> + 'a>)>,
    /// Start time t₀ of the horizon (step k at t₀ + k h).
    pub t0: f64,
}

impl<'a, D: Scalar, const DIM: usize> ReverseSweep<'a, D, DIM> {
    /// Scratch for a sweep over `ch` with step `h`, differentiating also for `params`.
    pub(crate) fn new(ch: &'a Chain<D, DIM>, h: f64, params: &'a [Parameter]) -> Self {
        let n = ch.n();
        let v = vec![[D::zero(); DIM]; n];
        ReverseSweep {
            ch,
            h,
            t0: 0.0,
            params,
            mass_param: params.iter().position(|p| *p == Parameter::Mass),
            offset_param: params
                .iter()
                .position(|p| *p == Parameter::VesselOffset)
                .filter(|_| ch.vessel().is_some()),
            drag_params: params
                .iter()
                .enumerate()
                .filter(|(_, p)| ch.dissipation_has_parameter(**p))
                .map(|(i, p)| (i, *p))
                .collect(),
            coupled: ch.has_coupled_dissipation().then(|| CoupledHalf::new(ch)),
            coupled_params: params
                .iter()
                .enumerate()
                .filter(|(_, p)| ch.coupled_has_parameter(**p))
                .map(|(i, p)| (i, *p))
                .collect(),
            node: ch.node_drag().map(|_| NodeReverseScratch::new(n)),
            node_params: params
                .iter()
                .enumerate()
                .filter(|(_, p)| ch.node_drag().is_some_and(|d| d.has_parameter(**p)))
                .map(|(i, p)| (i, *p))
                .collect(),
            nodes: Vec::new(),
            vhalf: v.clone(),
            tmp: v.clone(),
            tmp2: v.clone(),
            bbar: v.clone(),
            phbar: v.clone(),
            cbar: v,
            rhs: vec![D::zero(); ch.n_constraints()],
            scal: vec![D::zero(); n],
            tri: BorderedTridiag::new(n, ch.has_tip_constraint()),
            scratch: DualScratch::new(n),
        }
    }

    /// Adds parameters the per-node quantities carry, the i-th at index `first + i` of the
    /// cotangent θ̄ ([`super::node_tangent`]).
    pub(crate) fn with_node_tangents(
        mut self,
        first: usize,
        tangents: Vec<Box<dyn NodeTangent<D, DIM> + 'a>>,
    ) -> Self {
        self.nodes = tangents
            .into_iter()
            .enumerate()
            .map(|(i, t)| (first + i, t))
            .collect();
        self
    }

    /// One reverse step k + 1 → k: reads the states at k and k + 1 (and the half-step record of
    /// step k), updates the cotangents in place.
    pub(crate) fn step(
        &mut self,
        k: usize,
        (sk, sk1): (&StateView<'_, D, DIM>, &StateView<'_, D, DIM>),
        (u_k, u_k1): (D, D),
        cot: &mut Cotangents<D, DIM>,
    ) -> Result<()> {
        self.projection(k, sk1, cot)?;
        let ctx1 = self.ch.ctx(self.t0 + (k + 1) as f64 * self.h, u_k1, k + 1);
        self.second_half(sk1, &ctx1, cot)?;
        self.newton(k, sk.q, sk1, cot)?;
        let ctx0 = self.ch.ctx(self.t0 + k as f64 * self.h, u_k, k);
        self.first_half(sk, sk1, &ctx0, cot)?;
        if let Some(tip) = self.ch.reaction_tip() {
            self.tip_target(&tip, k, (u_k, u_k1), cot);
        } else if let Some(drive) = self.ch.thrust_drive() {
            if let (Some(ip), Some(v)) = (self.offset_param, self.ch.vessel()) {
                // Z₀ enters the drive's step through its prescribed part P(t) = ρ(t)(Z₀ + …):
                // θ̄ += (Z̄_{k+1}, Ż̄_{k+1}) · ∂(Z_{k+1}, Ż_{k+1})/∂Z₀ at fixed (Z_k, Ż_k).
                let ramp = |j: usize| v.offset_ramp(self.t0 + j as f64 * self.h);
                let d = drive.offset_derivative(ramp(k), ramp(k + 1), self.h);
                cot.thbar[ip] += cot.tip_bar[0] * d[0] + cot.tip_bar[1] * d[1];
            }
            // The vessel under thrust (model::ThrustDrive): its linear map's transpose.
            let bar = drive.reverse(cot.tip_bar, self.h);
            cot.ubar[k] += bar.controls.0;
            cot.ubar[k + 1] += bar.controls.1;
            cot.tip_bar = bar.target;
        }
        Ok(())
    }

    /// The reverse of a momentum projection p = c − Ĝ(q)ᵀy with Ĝ(q) M⁻¹ p = 0 at the state `s`
    /// (its q, p and y = (h/2)·`s.mu`): with p̄ in `cot.pbar`, adds the projection's share to
    /// `cot.qbar` and returns c̄ = p̄ − M⁻¹Ĝᵀŷ, A ŷ = Ĝ p̄. The step's final projection; the
    /// Riccati solver's stage map applies it to the control's half-kick ([`crate::ocp`]).
    pub(crate) fn projection_reverse(
        &mut self,
        k: usize,
        s: &StateView<'_, D, DIM>,
        cot: &mut Cotangents<D, DIM>,
    ) -> Result<&[[D; DIM]]> {
        self.projection(k, s, cot)?;
        Ok(&self.bbar)
    }

    /// Projection: A ŷ = Ĝ(q′) p̄′ (A = Ĝ M⁻¹ Ĝᵀ at q′), b̄ = p̄′ − M⁻¹ Ĝᵀ ŷ,
    /// q̄′ += −(h/2) μᵢ b̄ᵢ − ŷᵢ (M⁻¹p′)ᵢ. Leaves ŷ in `rhs`.
    fn projection(
        &mut self,
        k: usize,
        sk1: &StateView<'_, D, DIM>,
        cot: &mut Cotangents<D, DIM>,
    ) -> Result<()> {
        let (ch, ops, hh) = (self.ch, self.ch.constraints(), 0.5 * self.h);
        ops.apply(sk1.q, &cot.pbar, &mut self.rhs);
        ops.assemble_projection(sk1.q, &mut self.tri);
        self.tri
            .solve(&mut self.rhs)
            .map_err(|zp| singular(k, zp))?;
        self.tmp.iter_mut().for_each(|t| *t = [D::zero(); DIM]);
        ops.add_transpose(sk1.q, &self.rhs, D::one(), &mut self.tmp);
        ch.apply_inverse_mass(&self.tmp, &mut self.tmp2);
        for i in 0..ch.n() {
            self.bbar[i] = std::array::from_fn(|d| cot.pbar[i][d] - self.tmp2[i][d]);
        }
        ch.apply_inverse_mass(sk1.p, &mut self.tmp2);
        for i in 0..ch.n() {
            let y = sk1.mu[i] * hh;
            for d in 0..DIM {
                cot.qbar[i][d] -= y * self.bbar[i][d] + self.rhs[i] * self.tmp2[i][d];
            }
        }
        // Per-node masses: Ĝ(q′) M⁻¹p′ = r with p′ = c − Ĝᵀy gives
        // θ̄ += −(Ĝᵀŷ)ᵀ (∂M⁻¹/∂θ) p′ (`tmp` holds Ĝᵀŷ).
        for (ip, t) in &self.nodes {
            cot.thbar[*ip] -= ch.inverse_mass_tangent(&self.tmp, sk1.p, t.mass_tangents());
        }
        if ch.has_driven_tip() {
            let n = ch.n();
            cot.tip_bar[1] += self.rhs[n];
            if let Some(ip) = self.mass_param {
                cot.thbar[ip] += self.rhs[n] * sk1.tip[1] * ch.inv_masses[0];
            }
        } else if let (Some(ip), Some(v)) = (self.offset_param, ch.vessel()) {
            // The prescribed tip's rate Ż(t_{k+1}) = ρ̇(Z₀ + …) + ρ d_z Ẋ_w on the tip row:
            // its cotangent ŷ_n times ∂Ż/∂Z₀ = ρ̇(t_{k+1}) (the state is that of step k + 1).
            let (_, rho_dot) = v.offset_ramp(self.t0 + (k + 1) as f64 * self.h);
            cot.thbar[ip] += self.rhs[ch.n()] * rho_dot;
        }
        Ok(())
    }

    /// Second half-step b = p½ − h/2 U_q(q′; u_{k+1}) + h/2 F(p½) (F = Σ_T F_T, block by
    /// block): p̄½ = (I + h/2 ∂F/∂p)ᵀ b̄ (each block symmetric, [`BlockSym`]),
    /// q̄′ −= h/2 K(q′) b̄, and the control and parameter contractions of b̄.
    fn second_half(
        &mut self,
        sk1: &StateView<'_, D, DIM>,
        ctx1: &Ctx<D>,
        cot: &mut Cotangents<D, DIM>,
    ) -> Result<()> {
        let (ch, hh) = (self.ch, 0.5 * self.h);
        self.phbar.copy_from_slice(&self.bbar);
        if ch.has_dissipation() {
            // The dissipative force of step k → k + 1 is read at its midpoint (both halves).
            let k = ctx1.step - 1;
            let dctx = ch.dissipation_ctx(self.t0 + k as f64 * self.h, self.h, k);
            for i in 0..ch.n() {
                if let Some((_, slope)) = ch.dissipative_slope(i, &sk1.phalf[i], &dctx) {
                    self.phbar[i] = slope.identity_plus_scaled_apply(hh, &self.bbar[i]);
                }
            }
            dissipation_contraction(
                ch,
                &self.drag_params,
                (sk1.phalf, &self.bbar),
                &dctx,
                hh,
                cot,
            );
        }
        if self.coupled.is_some() {
            self.coupled_second_half(sk1, ctx1.step - 1, cot);
        }
        if ch.node_drag().is_some() {
            self.node_second_half(sk1, ctx1.step - 1, cot);
            // Per-node quantities in Q(p½): θ̄ += h/2 b̄·∂Q/∂θ.
            let k = ctx1.step - 1;
            let dctx = ch.dissipation_ctx(self.t0 + k as f64 * self.h, self.h, k);
            for (ip, t) in &mut self.nodes {
                cot.thbar[*ip] += t.drag_contraction(sk1.phalf, &self.bbar, &dctx) * hh;
            }
        }
        self.force_terms(sk1.q, ctx1, Half::Second, cot)
    }

    /// The node-by-node Morison drag's share of the second half's reverse (b = … + h/2 Q(p½)):
    /// p̄½ += h/2 (∂Q/∂p)ᵀ b̄ and θ̄ += h/2 b̄·∂Q/∂θ ([`crate::model::NodeDrag`]).
    fn node_second_half(
        &mut self,
        sk1: &StateView<'_, D, DIM>,
        k: usize,
        cot: &mut Cotangents<D, DIM>,
    ) {
        let (ch, hh) = (self.ch, 0.5 * self.h);
        let (Some(nd), Some(scratch)) = (ch.node_drag(), self.node.as_mut()) else {
            return;
        };
        let dctx = ch.dissipation_ctx(self.t0 + k as f64 * self.h, self.h, k);
        let ls = (ch.lengths(), ch.inverse_lengths());
        self.tmp.copy_from_slice(&self.bbar);
        nd.slope_transpose_apply(sk1.phalf, ls, &dctx, &mut self.tmp, scratch);
        for (p, t) in self.phbar.iter_mut().zip(&self.tmp) {
            for d in 0..DIM {
                p[d] += t[d] * hh;
            }
        }
        for &(ip, param) in &self.node_params {
            let g = nd.parameter_contraction(sk1.phalf, ls, (&dctx, param), &self.bbar, scratch);
            cot.thbar[ip] += g * hh;
        }
    }

    /// The coupled terms' share of the second half's reverse (b = … + h/2 F_J(q′, M⁻¹p½)):
    /// p̄½ += h/2 (∂F_J/∂p)ᵀ b̄ = h/2 M⁻¹ F_J(q′, b̄) (F_J = −B M⁻¹p, B symmetric),
    /// q̄′ += h/2 ∇_{q′}(b̄·F_J(q′, v½)) and θ̄ += h/2 b̄·∂F_J/∂θ.
    fn coupled_second_half(
        &mut self,
        sk1: &StateView<'_, D, DIM>,
        k: usize,
        cot: &mut Cotangents<D, DIM>,
    ) {
        let (ch, hh) = (self.ch, 0.5 * self.h);
        let dctx = ch.dissipation_ctx(self.t0 + k as f64 * self.h, self.h, k);
        self.tmp.iter_mut().for_each(|t| *t = [D::zero(); DIM]);
        ch.coupled_force(sk1.q, &self.bbar, &dctx, &mut self.tmp);
        ch.apply_inverse_mass(&self.tmp, &mut self.tmp2);
        for (p, t) in self.phbar.iter_mut().zip(&self.tmp2) {
            for d in 0..DIM {
                p[d] += t[d] * hh;
            }
        }
        self.coupled_contractions((sk1.q, sk1.phalf), Half::Second, &dctx, cot);
    }

    /// q̄ += h/2 ∇_q(w·F_J(q, M⁻¹p½)) and θ̄ += h/2 w·∂F_J/∂θ for the coupled terms, with
    /// w = b̄ at q′ (second half) or c̄ at q_k (first half, through p½'s implicit equation).
    fn coupled_contractions(
        &mut self,
        (q, phalf): (&[[D; DIM]], &[[D; DIM]]),
        half: Half,
        dctx: &Ctx<D>,
        cot: &mut Cotangents<D, DIM>,
    ) {
        let (ch, hh) = (self.ch, 0.5 * self.h);
        ch.apply_inverse_mass(phalf, &mut self.vhalf);
        let w = match half {
            Half::First => &self.cbar,
            Half::Second => &self.bbar,
        };
        let s = &mut self.scratch;
        let qvw = CoupledAt {
            q,
            v: &self.vhalf,
            w,
        };
        ch.coupled_force_q_vjp(qvw, dctx, D::from(hh), &mut cot.qbar, s);
        for &(ip, param) in &self.coupled_params {
            cot.thbar[ip] += ch.coupled_parameter_contraction(qvw, dctx, param, s) * hh;
        }
    }

    /// The force terms' share of a half-step's reverse: q̄ −= h/2 K(q) w, ū −= h/2 w·∂F/∂u
    /// (ū_x −= h/2 w·∂F/∂u_x for a 2-axis control),
    /// θ̄ −= h/2 w·∂F/∂θ, with w = b̄ (second half) or c̄ (first half).
    fn force_terms(
        &mut self,
        q: &[[D; DIM]],
        ctx: &Ctx<D>,
        half: Half,
        cot: &mut Cotangents<D, DIM>,
    ) -> Result<()> {
        let (ch, hh) = (self.ch, 0.5 * self.h);
        let w = match half {
            Half::First => &self.cbar,
            Half::Second => &self.bbar,
        };
        let s = &mut self.scratch;
        ch.force_jacobian_product(q, w, ctx, D::from(-hh), &mut cot.qbar, s)?;
        cot.ubar[ctx.step] -= ch.control_contraction(q, w, ctx, s)? * hh;
        if let Some(uxb) = cot.uxbar.get_mut(ctx.step) {
            *uxb -= ch.control_x_contraction(q, w, ctx, s)? * hh;
        }
        for (tb, p) in cot.thbar.iter_mut().zip(self.params) {
            *tb -= ch.force_parameter_contraction(q, w, ctx, *p, s)? * hh;
        }
        for (ip, t) in &mut self.nodes {
            cot.thbar[*ip] -= t.force_contraction(q, w, ctx)? * hh;
        }
        Ok(())
    }

    /// Newton system (implicit function theorem): λ̄ = −h/2 Ĝ(q_k)(Wᵀ S), S = p̄½ + h M⁻¹ q̄′;
    /// Jᵀν = λ̄; q̄′ −= Ĝ(q′)ᵀν; then c̄ = Wᵀ(p̄½ + h M⁻¹ q̄′) into `cbar`.
    fn newton(
        &mut self,
        k: usize,
        q: &[[D; DIM]],
        sk1: &StateView<'_, D, DIM>,
        cot: &mut Cotangents<D, DIM>,
    ) -> Result<()> {
        let (ch, ops, h, hh) = (self.ch, self.ch.constraints(), self.h, 0.5 * self.h);
        let dctx = ch.dissipation_ctx(self.t0 + k as f64 * h, h, k);
        let w = (ch.has_dissipation() && self.coupled.is_none()).then_some(sk1.w);
        if let Some(cpl) = &mut self.coupled {
            // W = A⁻¹ and J at (q_k, p½), as band LUs (steppers::coupled).
            cpl.factor_at(ch, (q, sk1.phalf), h, &dctx)
                .map_err(|zp| singular(k, zp))?;
            cpl.factor_newton(ch, (q, sk1.q), h)
                .map_err(|zp| singular(k, zp))?;
        }
        self.s_through_w(&cot.qbar, w, sk1.w);
        ops.apply(q, &self.tmp, &mut self.rhs);
        self.rhs.iter_mut().for_each(|r| *r = -*r * hh);
        if let Some(cpl) = &mut self.coupled {
            cpl.newton_solve_transpose(&mut self.rhs);
        } else if ch.node_drag().is_some() {
            ops.assemble_newton_nodes((q, sk1.q), sk1.w, h, &mut self.tri);
            self.tri
                .solve_transpose(&mut self.rhs)
                .map_err(|zp| singular(k, zp))?;
        } else {
            ops.assemble_newton((q, sk1.q), w, h, &mut self.tri, &mut self.scal);
            self.tri
                .solve_transpose(&mut self.rhs)
                .map_err(|zp| singular(k, zp))?;
        }
        ops.add_transpose(sk1.q, &self.rhs, -D::one(), &mut cot.qbar);
        if ch.has_driven_tip() {
            cot.tip_bar[0] += self.rhs[ch.n()];
        } else if let (Some(ip), Some(v)) = (self.offset_param, ch.vessel()) {
            // The prescribed tip's Z(t_{k+1}) = ρ(Z₀ + d_z X_w) held by Newton's tip row: its
            // cotangent ν_n times ∂Z/∂Z₀ = ρ(t_{k+1}).
            let (rho, _) = v.offset_ramp(self.t0 + (k + 1) as f64 * self.h);
            cot.thbar[ip] += self.rhs[ch.n()] * rho;
        }
        if let Some(ip) = self.mass_param {
            // q′ = q + h M⁻¹ p½ with M⁻¹ ∝ 1/m: ∂q′/∂m = −(q′ − q)/m.
            let mut s = D::zero();
            for i in 0..ch.n() {
                for d in 0..DIM {
                    s += cot.qbar[i][d] * (sk1.q[i][d] - q[i][d]);
                }
            }
            cot.thbar[ip] -= s * ch.inv_masses[0];
        }
        // Per-node masses: q′ = q + h M⁻¹p½ gives θ̄ += h q̄′ᵀ (∂M⁻¹/∂θ) p½.
        for (ip, t) in &self.nodes {
            let g = ch.inverse_mass_tangent(&cot.qbar, sk1.phalf, t.mass_tangents());
            cot.thbar[*ip] += g * h;
        }
        self.s_through_w(&cot.qbar, w, sk1.w);
        self.cbar.copy_from_slice(&self.tmp);
        if ch.has_dissipation() {
            dissipation_contraction(
                ch,
                &self.drag_params,
                (sk1.phalf, &self.cbar),
                &dctx,
                hh,
                cot,
            );
        }
        if self.coupled.is_some() {
            // p½ − h/2 F(q_k, p½) = c: q_k (and θ) reach p½ through F_J with the cotangent c̄.
            self.coupled_contractions((q, sk1.phalf), Half::First, &dctx, cot);
        }
        if let (Some(nd), Some(scratch)) = (ch.node_drag(), self.node.as_mut()) {
            // p½ − h/2 Q(p½; θ) = c: θ reaches p½ through Q with the cotangent c̄.
            let ls = (ch.lengths(), ch.inverse_lengths());
            for &(ip, param) in &self.node_params {
                let g =
                    nd.parameter_contraction(sk1.phalf, ls, (&dctx, param), &self.cbar, scratch);
                cot.thbar[ip] += g * hh;
            }
            // Per-node quantities in Q(p½): θ̄ += h/2 c̄·∂Q/∂θ.
            for (ip, t) in &mut self.nodes {
                cot.thbar[*ip] += t.drag_contraction(sk1.phalf, &self.cbar, &dctx) * hh;
            }
        }
        Ok(())
    }

    /// tmp = Wᵀ (p̄½ + h M⁻¹ q̄′) (W = I when `w` is None; each block of W is symmetric; with the
    /// node-by-node Morison drag `w` holds its node slopes Ω and Wᵀ = Aᵀ Ω A⁻ᵀ).
    fn w_times_s(&mut self, qbar: &[[D; DIM]], w: Option<&[BlockSym<D, DIM>]>) {
        let h = self.h;
        self.ch.apply_inverse_mass(qbar, &mut self.tmp);
        for i in 0..self.ch.n() {
            let s: [D; DIM] = std::array::from_fn(|d| self.phbar[i][d] + self.tmp[i][d] * h);
            self.tmp[i] = match w {
                Some(w) => w[i].apply(&s),
                None => s,
            };
        }
        if let Some(cpl) = &mut self.coupled {
            cpl.apply_w_transpose(&mut self.tmp);
        }
    }

    /// tmp = Wᵀ (p̄½ + h M⁻¹ q̄′) for the model's W: the node drag's ([`Self::node_w_times_s`],
    /// `recorded` its Ω) or the blocks' ([`Self::w_times_s`]).
    fn s_through_w(
        &mut self,
        qbar: &[[D; DIM]],
        w: Option<&[BlockSym<D, DIM>]>,
        recorded: &[BlockSym<D, DIM>],
    ) {
        if self.ch.node_drag().is_some() {
            self.node_w_times_s(qbar, recorded);
        } else {
            self.w_times_s(qbar, w);
        }
    }

    /// tmp = Wᵀ (p̄½ + h M⁻¹ q̄′) with the node drag's W = A⁻¹ Ω A (Ω = `omega`).
    fn node_w_times_s(&mut self, qbar: &[[D; DIM]], omega: &[BlockSym<D, DIM>]) {
        let h = self.h;
        let ch = self.ch;
        ch.apply_inverse_mass(qbar, &mut self.tmp);
        for (t, p) in self.tmp.iter_mut().zip(&self.phbar) {
            *t = std::array::from_fn(|d| p[d] + t[d] * h);
        }
        NodeDrag::w_transpose_apply(omega, (ch.lengths(), ch.inverse_lengths()), &mut self.tmp);
    }

    /// First half-step c = p_k − h/2 U_q(q_k; u_k) − h/2 Ĝ(q_k)ᵀλ: p̄_k = c̄,
    /// q̄_k = q̄′ − h/2 λᵢ c̄ᵢ − h/2 K(q_k) c̄, and the contractions of c̄.
    fn first_half(
        &mut self,
        sk: &StateView<'_, D, DIM>,
        sk1: &StateView<'_, D, DIM>,
        ctx0: &Ctx<D>,
        cot: &mut Cotangents<D, DIM>,
    ) -> Result<()> {
        let hh = 0.5 * self.h;
        for i in 0..self.ch.n() {
            let l = sk1.lambda[i] * hh;
            for d in 0..DIM {
                cot.pbar[i][d] = self.cbar[i][d];
                cot.qbar[i][d] -= l * self.cbar[i][d];
            }
        }
        self.force_terms(sk.q, ctx0, Half::First, cot)
    }

    /// Tip target dynamics of the reaction-force variant (Störmer–Verlet for m_n ζ̈ = −u).
    fn tip_target(
        &mut self,
        tip: &ReactionTip<D>,
        k: usize,
        u: (D, D),
        cot: &mut Cotangents<D, DIM>,
    ) {
        let bar = tip.reverse(cot.tip_bar, u, self.h);
        cot.ubar[k] += bar.controls.0;
        cot.ubar[k + 1] += bar.controls.1;
        if let Some(ip) = self.mass_param {
            // d(1/m_n)/dm = −1/m_n² (the mass parameter scales every mass).
            let inv_mn = tip.inv_tip_mass;
            cot.thbar[ip] -= bar.inv_tip_mass * inv_mn * inv_mn;
        }
        cot.tip_bar = bar.target;
    }
}

/// θ̄ += h/2 Σᵢ_d w_{i,d} ∂F_{i,d}(p½)/∂θ (F = Σ_T F_T) for each requested parameter θ a
/// dissipative term reads (`params`: (index in the request, θ)); w = b̄ (second half) or c̄
/// (first half).
fn dissipation_contraction<D: Scalar, const DIM: usize>(
    ch: &Chain<D, DIM>,
    params: &[(usize, Parameter)],
    (phalf, w): (&[[D; DIM]], &[[D; DIM]]),
    ctx: &Ctx<D>,
    hh: f64,
    cot: &mut Cotangents<D, DIM>,
) {
    for &(ip, param) in params {
        let mut s = D::zero();
        for (i, (p, w)) in phalf.iter().zip(w).enumerate() {
            let g = ch.dissipative_parameter_derivative(i, p, ctx, param);
            for d in 0..DIM {
                s += w[d] * g[d];
            }
        }
        cot.thbar[ip] += s * hh;
    }
}

/// Which half-step a reverse contraction belongs to.
#[derive(Clone, Copy)]
enum Half {
    First,
    Second,
}
