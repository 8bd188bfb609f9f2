//! The two halves of the RATTLE step that carry its arithmetic: the Newton solve for the
//! multipliers λ that put q_{k+1} on the constraints ([`Rattle::solve_positions`]), and the second
//! half kick with its projection onto the velocity constraints ([`Rattle::second_half`]).

use super::*;

impl<D: Scalar, const DIM: usize> Rattle<D, DIM> {
    /// Newton for λ (predictor μ_{k−1}) on ĝ(q_{k+1}(λ)) = 0; leaves q_{k+1} in `state.q`, λ in
    /// `state.lambda` and p_{k+½}, W in the workspace. `COUPLED`: whether the model's coupled
    /// dissipative terms are read (the workspace has them exactly when the model does).
    pub(super) fn solve_positions<const COUPLED: bool>(
        &mut self,
        state: &mut State<D, DIM>,
        k: usize,
        zeta_next: D,
    ) -> Result<StepStats> {
        let h = self.h;
        let ch = &self.chain;
        let ops = ch.constraints();
        let ws = &mut self.ws;
        match &state.multipliers {
            Some(m) => m.predictor(&mut ws.lam),
            None => ws.lam.copy_from_slice(&ws.mu0),
        }
        let keep_gaps = keeps_gaps(ch);
        let updates = derivative_updates::<D>();
        let mut extra_done = 0;
        let mut iterations = 0;
        // The dissipative terms are read at t_k + h/2 in both halves; the node drag's water
        // momentum P(t_k + h/2) once for the step (not per node and iteration).
        let dctx = ch.dissipation_ctx(self.t0 + k as f64 * h, h, k);
        if let Some(nd) = ch.node_drag() {
            nd.water_momenta(&dctx, &mut ws.water);
        }
        // Σ lᵢ, the tip row's scale in the residual's max-norm (as the residual sums it).
        let total_length: f64 = ch.lengths().iter().map(|l| l.re()).sum();
        loop {
            // c = a − h/2 Ĝ(q_k)ᵀ λ;  p_{k+½} = c or the drag root;  q' = q_k + h M⁻¹ p_{k+½}
            let fused = ws.fused.as_mut().filter(|_| updates == 0 && !COUPLED);
            if let (Some(nd), Some(scratch)) = (ch.node_drag(), fused) {
                // The same values by the fused passes (NodeDrag::half_step_iterate).
                let inputs = IterateInputs {
                    q: &state.q,
                    a: &ws.a,
                    lam: &ws.lam,
                    water: &ws.water,
                    lengths: ch.lengths(),
                    inv_lengths: ch.inverse_lengths(),
                    inv_masses: &ch.inv_masses,
                    bordered: ops.bordered(),
                    tip_target: zeta_next,
                    total_length,
                    h,
                };
                let mut outputs = IterateOutputs {
                    c: &mut ws.half.c,
                    phalf: &mut ws.half.phalf,
                    omega: &mut ws.half.w,
                    minv_p: &mut ws.tmp,
                    qnew: &mut ws.qnew,
                    residual: &mut ws.rhs,
                };
                let rmax = nd.half_step_iterate(&dctx, &inputs, &mut outputs);
                if !rmax.is_finite() {
                    return Err(Error::NonFinite {
                        step: k,
                        quantity: "the positions q_{k+1} of the Newton iterate",
                    });
                }
                // (f64: no derivative-only updates.)
                if rmax <= self.options.tolerance {
                    record_lambda(state, &ws.lam, &ws.mu0, keep_gaps);
                    ws.mu0_ready = false;
                    std::mem::swap(&mut state.q, &mut ws.qnew);
                    return Ok(StepStats {
                        iterations,
                        residual: rmax,
                    });
                }
                if iterations >= self.options.max_iterations {
                    return Err(self.not_converged(k, rmax, iterations));
                }
                let (q, qn, w) = (&state.q, &ws.qnew, &ws.half.w);
                let solved = fused::newton_nodes_solve(ch, (q, qn), w, h, scratch, &mut ws.rhs)
                    .map_err(|zp| singular(k, zp))?;
                if !solved {
                    ops.assemble_newton_nodes((q, qn), w, h, &mut ws.tri);
                    ws.tri.solve(&mut ws.rhs).map_err(|zp| singular(k, zp))?;
                }
                for (l, r) in ws.lam.iter_mut().zip(ws.rhs.iter()) {
                    *l -= *r;
                }
                iterations += 1;
                continue;
            }
            match ws.coupled.as_mut().filter(|_| COUPLED) {
                None => half_step_momentum(
                    ch,
                    &state.q,
                    (&ws.a, &ws.lam),
                    (h, &dctx, &ws.water),
                    &mut ws.half,
                ),
                Some(cpl) => {
                    let half = &mut ws.half;
                    half.c.copy_from_slice(&ws.a);
                    ops.add_transpose(&state.q, &ws.lam, D::from(-0.5 * h), &mut half.c);
                    cpl.solve(ch, (&state.q, &half.c), (h, &dctx), &mut half.phalf)
                        .map_err(|zp| singular(k, zp))?;
                }
            }
            ch.apply_inverse_mass(&ws.half.phalf, &mut ws.tmp);
            for i in 0..ch.n() {
                ws.qnew[i] = std::array::from_fn(|d| state.q[i][d] + ws.tmp[i][d] * h);
            }
            let rmax = ops.residual(&ws.qnew, zeta_next, &mut ws.rhs);
            if !rmax.is_finite() {
                return Err(Error::NonFinite {
                    step: k,
                    quantity: "the positions q_{k+1} of the Newton iterate",
                });
            }
            if rmax <= self.options.tolerance {
                if extra_done == updates {
                    record_lambda(state, &ws.lam, &ws.mu0, keep_gaps);
                    ws.mu0_ready = false;
                    std::mem::swap(&mut state.q, &mut ws.qnew);
                    return Ok(StepStats {
                        iterations,
                        residual: rmax,
                    });
                }
                extra_done += 1;
            }
            // (The derivative-only updates after convergence are allowed past the limit.)
            if iterations >= self.options.max_iterations && extra_done == 0 {
                return Err(self.not_converged(k, rmax, iterations));
            }
            if let Some(cpl) = ws.coupled.as_mut().filter(|_| COUPLED) {
                // The coupled path (steppers::coupled): J's band system with its derivative parts.
                cpl.factor_newton(ch, (&state.q, &ws.qnew), h)
                    .map_err(|zp| singular(k, zp))?;
                cpl.newton_solve(&mut ws.rhs);
                for (l, r) in ws.lam.iter_mut().zip(ws.rhs.iter()) {
                    *l -= if extra_done > 0 { *r - r.re() } else { *r };
                }
                iterations += 1;
                continue;
            }
            // The derivative-only update of first-order duals is the implicit function theorem,
            // Δλ' = R_λ⁻¹ R': R_λ's real part suffices (its derivative multiplies the converged
            // residual), so the matrix is assembled and factored without derivative parts and
            // only the right-hand side carries them.
            let (q, qn, w): (&[_], &[_], &[_]) = if extra_done > 0 && updates == 1 {
                let [q_re, qn_re] = &mut ws.real;
                real_parts(&state.q, q_re);
                real_parts(&ws.qnew, qn_re);
                for (o, w) in ws.real_w.iter_mut().zip(&ws.half.w) {
                    *o = w.real_part();
                }
                (q_re, qn_re, &ws.real_w)
            } else {
                (&state.q, &ws.qnew, &ws.half.w)
            };
            if ch.node_drag().is_some() {
                ops.assemble_newton_nodes((q, qn), w, h, &mut ws.tri);
            } else {
                let w = ch.has_dissipation().then_some(w);
                ops.assemble_newton((q, qn), w, h, &mut ws.tri, &mut ws.scal);
            }
            ws.tri.solve(&mut ws.rhs).map_err(|zp| singular(k, zp))?;
            for (l, r) in ws.lam.iter_mut().zip(ws.rhs.iter()) {
                // After convergence, Δ − re(Δ): a real part of exactly 0 keeps the real parts
                // bit-for-bit those of the f64 run while the derivative parts converge.
                *l -= if extra_done > 0 { *r - r.re() } else { *r };
            }
            iterations += 1;
        }
    }

    /// Second half-step: force at q_{k+1} with u_{k+1} (cached for the next step), then the
    /// projection for (p_{k+1}, μ_k); `COUPLED` as in [`Rattle::solve_positions`].
    pub(super) fn second_half<const COUPLED: bool>(
        &mut self,
        state: &mut State<D, DIM>,
        k: usize,
        u_k1: D,
        v_half: D,
        zeta_next: D,
    ) -> Result<()> {
        let (h, hh) = (self.h, 0.5 * self.h);
        let ch = &self.chain;
        let ws = &mut self.ws;
        let t1 = self.t0 + (k + 1) as f64 * h;
        ch.potential_gradient(&state.q, t1, u_k1, k + 1, &mut ws.force)?;
        let dctx = ch.dissipation_ctx(self.t0 + k as f64 * h, h, k);
        // b = p_{k+½} − h/2 U_q(q_{k+1}; u_{k+1}) + h/2 Σ_T F_T(p_{k+½})
        let kick = HalfKick {
            p: &ws.half.phalf,
            g: &ws.force,
            s: hh,
        };
        ch.dissipative_half_kick(kick, &dctx, &mut ws.a);
        if let (Some(nd), Some(_)) = (ch.node_drag(), ws.fused.as_ref().filter(|_| !COUPLED)) {
            // The same values in one pass (NodeDrag::kick_in).
            let ls = (ch.lengths(), ch.inverse_lengths());
            let water = (&dctx, ws.water.as_slice());
            nd.kick_in(&ws.half.phalf, ls, water, hh, &mut ws.a);
        } else if let Some(nd) = ch.node_drag() {
            // + h/2 Q(p½), Q = A⁻¹ F(A(p½ − P)) (model::NodeDrag); tmp and qnew are scratch here.
            let ls = (ch.lengths(), ch.inverse_lengths());
            let water = (&dctx, ws.water.as_slice());
            nd.generalised_force_in(&ws.half.phalf, ls, water, &mut ws.tmp, &mut ws.qnew);
            for (a, f) in ws.a.iter_mut().zip(&ws.qnew) {
                for d in 0..DIM {
                    a[d] += f[d] * hh;
                }
            }
        }
        if let Some(cpl) = ws.coupled.as_mut().filter(|_| COUPLED) {
            // The coupled terms at (q_{k+1}, p_{k+½}) (steppers::coupled).
            let f = cpl.coupled_force(ch, &state.q, &ws.half.phalf, &dctx);
            for (a, f) in ws.a.iter_mut().zip(f) {
                for d in 0..DIM {
                    a[d] += f[d] * hh;
                }
            }
        }
        let v_next = match (ch.reaction_tip(), ch.thrust_drive(), ch.prescribed_tip(t1)) {
            (Some(tip), _, _) => {
                let v = tip.second_half(v_half, u_k1, h);
                state.tip_target = [zeta_next, v];
                v
            }
            // The vessel under thrust: Ż_{k+1} = Ṗ(t_{k+1}) + its surge velocity.
            (None, Some(drive), Some([p, pdot])) => {
                let v = drive.second_half(v_half, (zeta_next, p, pdot), u_k1, h);
                state.tip_target = [zeta_next, v];
                v
            }
            // The vessel's Ż(t_{k+1}): Ĝ(q_{k+1}) M⁻¹ p_{k+1} = Ż on the tip row.
            (None, None, Some([z, v])) => {
                state.tip_target = [z, v];
                v
            }
            (None, _, None) => D::zero(),
        };
        if let Some(scratch) = ws.fused.as_mut().filter(|_| !COUPLED) {
            // The same values by the fused passes (steppers::fused).
            let nc = ws.rhs.len();
            state.multipliers_mut(nc);
            let State {
                q, p, multipliers, ..
            } = state;
            if let Some(m) = multipliers.as_mut() {
                let x = Projection {
                    q,
                    b: &ws.a,
                    v_tip: v_next,
                    hh,
                };
                let mut o = Projected {
                    tmp: &mut ws.tmp,
                    rhs: &mut ws.rhs,
                    p,
                    mu: &mut m.mu,
                };
                if fused::project(ch, &x, scratch, &mut o).map_err(|zp| singular(k, zp))? {
                    return Ok(());
                }
            }
        }
        projection_solve(
            ch,
            &state.q,
            &ws.a,
            v_next,
            &mut ws.tmp,
            &mut ws.tri,
            &mut ws.rhs,
        )
        .map_err(|zp| singular(k, zp))?;
        // p_{k+1} = b − Ĝᵀ y, μ = y / (h/2)
        ch.constraints()
            .subtract_transpose(&ws.a, &state.q, &ws.rhs, &mut state.p);
        let mu = &mut state.multipliers_mut(ws.rhs.len()).mu;
        for (m, y) in mu.iter_mut().zip(ws.rhs.iter()) {
            *m = *y / hh;
        }
        Ok(())
    }
}

/// Stores the converged λ_{k+1} in `state` (with its gap to μ_k when `keep_gaps`; μ_k is the
/// state's, or `mu0`, the consistent multiplier, for an initial state without multipliers).
fn record_lambda<D: Scalar, const DIM: usize>(
    state: &mut State<D, DIM>,
    lambda: &[D],
    mu0: &[D],
    keep_gaps: bool,
) {
    let initial = state.multipliers.is_none();
    let m = state.multipliers_mut(lambda.len());
    m.record(lambda, initial.then_some(mu0), keep_gaps);
}
