//! The RATTLE integrator (thesis §1.6, eq. 1.6.1; SPEC §2) for the constrained chain, generic over
//! the scalar [`Scalar`] and the dimension.
//!
//! One step (q_k, p_k) → (q_{k+1}, p_{k+1}) with controls u_k, u_{k+1}:
//! ```text
//! p_{k+½} = p_k − h/2 (U_q(q_k; u_k) + Ĝ(q_k)ᵀ λ_k) − h/2 D p_{k+½} ⊙ |p_{k+½}|
//! q_{k+1} = q_k + h M⁻¹ p_{k+½},                 ĝ(q_{k+1}) = 0
//! p_{k+1} = p_{k+½} − h/2 (U_q(q_{k+1}; u_{k+1}) + Ĝ(q_{k+1})ᵀ μ_k) − h/2 D p_{k+½} ⊙ |p_{k+½}|
//! 0       = Ĝ(q_{k+1}) M⁻¹ p_{k+1}
//! ```
//! ĝ stacks the length constraints gᵢ = ½(‖qᵢ‖² − 1) and, for locked tips, l(q) = Σ lᵢ e₃ᵀqᵢ.
//! The drag term is evaluated at p_{k+½} in both halves (SPEC §2); in the first half it is
//! implicit, and each component solves p + (hD/2) p|p| = c in closed form,
//! p = 2c / (1 + √(1 + 2hD|c|)).
//!
//! **Newton solve for λ.** q_{k+1}(λ) is explicit, so Newton runs on ĝ(q_{k+1}(λ)) = 0 only. Its
//! Jacobian −h²/2 Ĝ(q_{k+1}) M⁻¹ W Ĝ(q_k)ᵀ (W = ∂p_{k+½}/∂c, the identity without drag) is
//! tridiagonal in the length constraints because M̄⁻¹ is, bordered by the tip row and column, and is
//! solved in O(n) by [`BorderedTridiag`]. The predictor is μ_{k−1}, the multiplier of the previous
//! projection (at step 0, the consistent multiplier of the initial state), which leaves Newton 1-2
//! iterations per step on the thesis scenes. When `D` carries derivatives, one more update is
//! applied after the real part has converged, with its real part removed: the derivative parts
//! (which Newton converges only linearly, at the rate of the residual) become exact, and the real
//! parts stay bit-for-bit those of the `f64` run.
//!
//! **Projection for (p_{k+1}, μ_k)** is linear with the symmetric tridiagonal (bordered) matrix
//! Ĝ(q_{k+1}) M⁻¹ Ĝ(q_{k+1})ᵀ.
//!
//! **Reaction-force tip** ([`TipCondition::Reaction`], eq. 3.2.1/3.2.2): the tip's z follows
//! m_n ζ̈ = −u (the reaction cancels every other force on it), integrated by Störmer–Verlet
//! v_{k+½} = v_k − h/(2 m_n) u_k, ζ_{k+1} = ζ_k + h v_{k+½}, v_{k+1} = v_{k+½} − h/(2 m_n) u_{k+1},
//! and imposed as the rheonomic constraints l(q_{k+1}) = ζ_{k+1}, L M⁻¹ p_{k+1} = v_{k+1}. With
//! u = 0 this is exactly the locked beam. The control then needs no potential term: its force lies
//! along Lᵀ and would be absorbed by the tip multiplier.

use crate::error::{Error, Result};
use crate::model::{carries_derivatives, dot, e2, zi, Chain, Scalar, TipCondition};
use crate::tridiag::{BorderedTridiag, ZeroPivot};

/// Newton settings of the RATTLE step.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RattleOptions {
    /// Convergence tolerance on the max-norm of the constraint residual ½(‖qᵢ‖² − 1) (the tip row
    /// is scaled by the beam length).
    pub tolerance: f64,
    /// Maximum Newton iterations per step.
    pub max_iterations: usize,
}

impl Default for RattleOptions {
    fn default() -> Self {
        RattleOptions {
            tolerance: 1e-14,
            max_iterations: 25,
        }
    }
}

/// The state at time t_k, with the multipliers of the step that produced it.
#[derive(Clone, Debug, PartialEq)]
pub struct State<D, const DIM: usize> {
    /// Attitudes qᵢ.
    pub q: Vec<[D; DIM]>,
    /// Conjugate momenta pᵢ.
    pub p: Vec<[D; DIM]>,
    /// λ of the last step (length n, +1 with a tip constraint).
    pub lambda: Vec<D>,
    /// μ of the last step (length n, +1 with a tip constraint).
    pub mu: Vec<D>,
    /// Reaction-force variant: the tip target ζ_k and velocity v_k (zero otherwise).
    pub tip_target: [D; 2],
}

impl<D: Scalar, const DIM: usize> State<D, DIM> {
    /// The straight beam at rest, qᵢ = e₂, p = 0 (the initial state of every thesis scene).
    pub fn straight(n: usize, n_constraints: usize) -> Self {
        State {
            q: vec![e2::<D, DIM>(); n],
            p: vec![[D::zero(); DIM]; n],
            lambda: vec![D::zero(); n_constraints],
            mu: vec![D::zero(); n_constraints],
            tip_target: [D::zero(); 2],
        }
    }
}

/// Statistics of one step.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct StepStats {
    /// Newton iterations (linear solves) for λ.
    pub iterations: usize,
    /// Final max-norm constraint residual.
    pub residual: f64,
}

/// Scratch memory of a step, allocated once per chain.
#[derive(Clone, Debug)]
struct Workspace<D, const DIM: usize> {
    force: Vec<[D; DIM]>,
    a: Vec<[D; DIM]>,
    c: Vec<[D; DIM]>,
    phalf: Vec<[D; DIM]>,
    w: Vec<[D; DIM]>,
    qnew: Vec<[D; DIM]>,
    tmp: Vec<[D; DIM]>,
    lam: Vec<D>,
    rhs: Vec<D>,
    scal: Vec<D>,
    tri: BorderedTridiag<D>,
    force_ready: bool,
}

/// RATTLE for a [`Chain`], with its workspace. `step` does not allocate.
#[derive(Clone, Debug)]
pub struct Rattle<D, const DIM: usize> {
    chain: Chain<D, DIM>,
    h: f64,
    options: RattleOptions,
    ws: Workspace<D, DIM>,
}

impl<D: Scalar, const DIM: usize> Rattle<D, DIM> {
    /// An integrator with step `h` (must be positive and finite).
    pub fn new(chain: Chain<D, DIM>, h: f64) -> Result<Self> {
        if !(h > 0.0 && h.is_finite()) {
            return Err(Error::InvalidArgument {
                name: "h",
                reason: format!("the step must be positive and finite, got {h}"),
            });
        }
        let n = chain.n();
        let nc = chain.n_constraints();
        let v = vec![[D::zero(); DIM]; n];
        let ws = Workspace {
            force: v.clone(),
            a: v.clone(),
            c: v.clone(),
            phalf: v.clone(),
            w: vec![[D::one(); DIM]; n],
            qnew: v.clone(),
            tmp: v,
            lam: vec![D::zero(); nc],
            rhs: vec![D::zero(); nc],
            scal: vec![D::zero(); n],
            tri: BorderedTridiag::new(n, chain.has_tip_constraint()),
            force_ready: false,
        };
        Ok(Rattle {
            chain,
            h,
            options: RattleOptions::default(),
            ws,
        })
    }

    /// Replaces the Newton options.
    pub fn with_options(mut self, options: RattleOptions) -> Self {
        self.options = options;
        self
    }

    /// The model.
    pub fn chain(&self) -> &Chain<D, DIM> {
        &self.chain
    }

    /// Mutable access to the model (e.g. to seed a parameter); invalidates the cached force.
    pub fn chain_mut(&mut self) -> &mut Chain<D, DIM> {
        self.ws.force_ready = false;
        &mut self.chain
    }

    /// The step h.
    pub fn h(&self) -> f64 {
        self.h
    }

    /// The straight beam at rest.
    pub fn straight_state(&self) -> State<D, DIM> {
        State::straight(self.chain.n(), self.chain.n_constraints())
    }

    /// Prepares a step from `state` at step index `k` with control u_k: evaluates U_q(q_k; u_k)
    /// and, when `state` has no multipliers yet (all zero), the consistent multiplier used as the
    /// Newton predictor. Called automatically by [`Rattle::step`] when needed.
    pub fn prepare(&mut self, state: &mut State<D, DIM>, k: usize, u_k: D) -> Result<()> {
        let t = k as f64 * self.h;
        self.chain
            .potential_gradient(&state.q, t, u_k, k, &mut self.ws.force)?;
        self.ws.force_ready = true;
        if state.mu.iter().all(|m| m.re() == 0.0) {
            // Consistent multiplier: Ĝ M⁻¹ (U_q + Ĝᵀλ) = Ĝ-curvature terms; at rest (and as a
            // predictor in general) solve Ĝ M⁻¹ Ĝᵀ λ = −Ĝ M⁻¹ U_q.
            let ws = &mut self.ws;
            for (o, f) in ws.a.iter_mut().zip(ws.force.iter()) {
                for d in 0..DIM {
                    o[d] = -f[d];
                }
            }
            let target = D::zero();
            projection_solve(
                &self.chain,
                &state.q,
                &ws.a,
                target,
                &mut ws.tmp,
                &mut ws.tri,
                &mut ws.rhs,
            )
            .map_err(|zp| singular(k, zp))?;
            state.mu.copy_from_slice(&ws.rhs);
        }
        Ok(())
    }

    /// Evaluates and caches U_q(q_k; u_k) for the next [`Rattle::step`] without touching the
    /// multipliers (the Newton predictor stays `state.mu`), so that a step recomputed from a stored
    /// state repeats the original arithmetic bit for bit.
    pub fn prepare_force(&mut self, state: &State<D, DIM>, k: usize, u_k: D) -> Result<()> {
        let t = k as f64 * self.h;
        self.chain
            .potential_gradient(&state.q, t, u_k, k, &mut self.ws.force)?;
        self.ws.force_ready = true;
        Ok(())
    }

    /// Advances `state` from t_k to t_{k+1} with controls u_k (at t_k) and u_{k+1} (at t_{k+1}).
    ///
    /// The caller must pass the same u_k that the previous step received as its u_{k+1} (the force
    /// at q_k is cached between steps); use [`Rattle::prepare`] after changing the state by hand.
    ///
    /// # Errors
    /// [`Error::NewtonNotConverged`] (with the step and the residual), [`Error::Folded`] when a
    /// joint passes the fold limit, [`Error::SingularSystem`], [`Error::NonFinite`]. After an
    /// error `state` is not a valid state of the trajectory (it may hold q_{k+1} with p_k): restart
    /// from a stored state.
    pub fn step(
        &mut self,
        state: &mut State<D, DIM>,
        k: usize,
        u_k: D,
        u_k1: D,
    ) -> Result<StepStats> {
        if !self.ws.force_ready {
            self.prepare(state, k, u_k)?;
        }
        let h = self.h;
        let hh = 0.5 * h;
        let n = self.chain.n();
        let z = zi::<DIM>();
        let tip = self.chain.tip_condition();
        let bordered = self.chain.has_tip_constraint();
        let drag = self.chain.drag;
        let ch = &self.chain;
        let ws = &mut self.ws;

        // a = p_k − h/2 U_q(q_k; u_k)
        for i in 0..n {
            for d in 0..DIM {
                ws.a[i][d] = state.p[i][d] - ws.force[i][d] * hh;
            }
        }
        // Tip target of the reaction-force variant (Störmer–Verlet for m_n ζ̈ = −u).
        let inv_mn = ch.inv_masses[n - 1];
        let (zeta_next, v_half) = if tip == TipCondition::Reaction {
            let v_half = state.tip_target[1] - u_k * inv_mn * hh;
            (state.tip_target[0] + v_half * h, v_half)
        } else {
            (D::zero(), D::zero())
        };
        let total_length: f64 = ch.lengths.iter().map(|l| l.re()).sum();

        // Newton for λ, predictor μ_{k−1}.
        ws.lam.copy_from_slice(&state.mu);
        let want_extra = carries_derivatives::<D>();
        let mut extra_done = false;
        let mut iterations = 0;
        let residual;
        loop {
            // c = a − h/2 Ĝ(q_k)ᵀ λ;  p_{k+½} = c or the drag root;  q' = q_k + h M⁻¹ p_{k+½}
            half_step_momentum(
                ch,
                &state.q,
                &ws.a,
                &ws.lam,
                h,
                &mut ws.c,
                &mut ws.phalf,
                &mut ws.w,
            );
            ch.apply_inverse_mass(&ws.phalf, &mut ws.tmp);
            for i in 0..n {
                for d in 0..DIM {
                    ws.qnew[i][d] = state.q[i][d] + ws.tmp[i][d] * h;
                }
            }
            // residual
            let mut rmax: f64 = 0.0;
            for i in 0..n {
                let r = (dot(&ws.qnew[i], &ws.qnew[i]) - 1.0) * 0.5;
                rmax = rmax.max(r.re().abs());
                ws.rhs[i] = r;
            }
            if bordered {
                let r = ch.tip_z(&ws.qnew) - zeta_next;
                rmax = rmax.max(r.re().abs() / total_length);
                ws.rhs[n] = r;
            }
            if !rmax.is_finite() {
                return Err(Error::NonFinite {
                    step: k,
                    quantity: "the positions q_{k+1} of the Newton iterate",
                });
            }
            if rmax <= self.options.tolerance {
                if !want_extra || extra_done {
                    residual = rmax;
                    break;
                }
                extra_done = true;
            }
            // (The derivative-only update after convergence is allowed past the limit.)
            if iterations >= self.options.max_iterations && !extra_done {
                return Err(Error::NewtonNotConverged {
                    step: k,
                    time: k as f64 * h,
                    residual: rmax,
                    iterations,
                    tolerance: self.options.tolerance,
                    h: Some(h),
                });
            }
            newton_jacobian(ch, &state.q, &ws.qnew, &ws.w, h, &mut ws.tri, &mut ws.scal);
            let tri = &mut ws.tri;
            tri.solve(&mut ws.rhs).map_err(|zp| singular(k, zp))?;
            if extra_done {
                // The derivative-only update: Δ − re(Δ) has a real part of exactly 0, so the real
                // parts stay bit-for-bit those of the f64 run while the derivative parts converge.
                for (l, r) in ws.lam.iter_mut().zip(ws.rhs.iter()) {
                    *l -= *r - r.re();
                }
            } else {
                for (l, r) in ws.lam.iter_mut().zip(ws.rhs.iter()) {
                    *l -= *r;
                }
            }
            iterations += 1;
        }
        state.lambda.copy_from_slice(&ws.lam);
        std::mem::swap(&mut state.q, &mut ws.qnew);

        // Second half: force at q_{k+1} with u_{k+1} (cached for the next step).
        ch.potential_gradient(&state.q, (k + 1) as f64 * h, u_k1, k + 1, &mut ws.force)?;
        for i in 0..n {
            for d in 0..DIM {
                let mut b = ws.phalf[i][d] - ws.force[i][d] * hh;
                if let Some(dr) = drag {
                    let p = ws.phalf[i][d];
                    b -= dr * p * p.abs() * hh;
                }
                ws.a[i][d] = b;
            }
        }
        let v_next = if tip == TipCondition::Reaction {
            let v = v_half - u_k1 * inv_mn * hh;
            state.tip_target = [zeta_next, v];
            v
        } else {
            D::zero()
        };
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
        for i in 0..n {
            let y = ws.rhs[i];
            for d in 0..DIM {
                state.p[i][d] = ws.a[i][d] - y * state.q[i][d];
            }
            if bordered {
                state.p[i][z] -= ws.rhs[n] * ch.lengths[i];
            }
        }
        for (m, y) in state.mu.iter_mut().zip(ws.rhs.iter()) {
            *m = *y / hh;
        }
        Ok(StepStats {
            iterations,
            residual,
        })
    }
}

/// c = a − h/2 Ĝ(q_k)ᵀλ and p_{k+½} solving p + (hD/2) p ⊙ |p| = c (p = c without drag), with
/// W = ∂p_{k+½}/∂c = 1/(1 + hD|p|) componentwise (left at 1 without drag).
#[allow(clippy::too_many_arguments)]
pub(crate) fn half_step_momentum<D: Scalar, const DIM: usize>(
    ch: &Chain<D, DIM>,
    q: &[[D; DIM]],
    a: &[[D; DIM]],
    lam: &[D],
    h: f64,
    c: &mut [[D; DIM]],
    phalf: &mut [[D; DIM]],
    w: &mut [[D; DIM]],
) {
    let n = ch.n();
    let hh = 0.5 * h;
    let z = zi::<DIM>();
    for i in 0..n {
        let li = lam[i];
        for d in 0..DIM {
            c[i][d] = a[i][d] - li * q[i][d] * hh;
        }
        if ch.has_tip_constraint() {
            c[i][z] -= lam[n] * ch.lengths[i] * hh;
        }
    }
    if let Some(dr) = ch.drag {
        let two_hd = dr * (2.0 * h);
        for i in 0..n {
            for d in 0..DIM {
                let ci = c[i][d];
                let root = (two_hd * ci.abs() + 1.0).sqrt() + 1.0;
                let p = ci * 2.0 * root.recip();
                phalf[i][d] = p;
                w[i][d] = (dr * h * p.abs() + 1.0).recip();
            }
        }
    } else {
        phalf.copy_from_slice(c);
    }
}

/// Assembles the Newton matrix J = ∂ĝ(q_{k+1}(λ))/∂λ = −h²/2 Ĝ(q_{k+1}) M⁻¹ W Ĝ(q_k)ᵀ into the
/// bordered tridiagonal `tri`: J_{ij} = −h²/2 M̄⁻¹_{ij} q′ᵢ·(W_j ⊙ q_j) (|i − j| ≤ 1); tip column
/// −h²/2 q′_{i,z} (M̄⁻¹(l ⊙ W_z))ᵢ; tip row −h²/2 δ_{jn} (W_n ⊙ q_n)_z/(m_n l_n), using
/// Σᵢ lᵢ M̄⁻¹_{ij} = δ_{jn}/(m_n l_n); corner −h²/2 W_{n,z}/m_n. `scal` is scratch of length n.
pub(crate) fn newton_jacobian<D: Scalar, const DIM: usize>(
    ch: &Chain<D, DIM>,
    q: &[[D; DIM]],
    qnew: &[[D; DIM]],
    w: &[[D; DIM]],
    h: f64,
    tri: &mut BorderedTridiag<D>,
    scal: &mut [D],
) {
    let n = ch.n();
    let z = zi::<DIM>();
    let has_drag = ch.has_drag();
    let s = -(h * h * 0.5);
    for i in 0..n {
        let (dii, off) = ch.minv_entries(i);
        let wq = wmul(&w[i], &q[i], has_drag);
        tri.diag[i] = dot(&qnew[i], &wq) * dii * s;
        if i + 1 < n {
            let wq1 = wmul(&w[i + 1], &q[i + 1], has_drag);
            tri.upper[i] = dot(&qnew[i], &wq1) * off * s;
            tri.lower[i + 1] = dot(&qnew[i + 1], &wq) * off * s;
        }
    }
    if ch.has_tip_constraint() {
        for j in 0..n {
            scal[j] = ch.lengths[j] * w[j][z];
        }
        for i in 0..n {
            let (dii, off) = ch.minv_entries(i);
            let mut v = dii * scal[i];
            if i + 1 < n {
                v += off * scal[i + 1];
            }
            if i > 0 {
                let (_, offm) = ch.minv_entries(i - 1);
                v += offm * scal[i - 1];
            }
            tri.col[i] = qnew[i][z] * v * s;
            tri.row[i] = D::zero();
        }
        let inv_mn = ch.inv_masses[n - 1];
        tri.row[n - 1] = w[n - 1][z] * q[n - 1][z] * inv_mn * ch.inv_lengths[n - 1] * s;
        tri.corner = w[n - 1][z] * inv_mn * s;
    }
}

#[inline]
fn wmul<D: Scalar, const DIM: usize>(w: &[D; DIM], q: &[D; DIM], has_drag: bool) -> [D; DIM] {
    if has_drag {
        let mut o = *q;
        for d in 0..DIM {
            o[d] *= w[d];
        }
        o
    } else {
        *q
    }
}

fn singular(step: usize, zp: ZeroPivot) -> Error {
    Error::SingularSystem {
        step,
        index: zp.index,
        pivot: zp.pivot,
    }
}

/// Solves Ĝ(q) M⁻¹ Ĝ(q)ᵀ y = Ĝ(q) M⁻¹ b − (0, …, 0, v_tip) for y (returned in `rhs`), so that
/// p = b − Ĝ(q)ᵀ y satisfies Ĝ(q) M⁻¹ p = (0, …, 0, v_tip). O(n).
pub(crate) fn projection_solve<D: Scalar, const DIM: usize>(
    ch: &Chain<D, DIM>,
    q: &[[D; DIM]],
    b: &[[D; DIM]],
    v_tip: D,
    tmp: &mut [[D; DIM]],
    tri: &mut BorderedTridiag<D>,
    rhs: &mut [D],
) -> std::result::Result<(), ZeroPivot> {
    let n = ch.n();
    let z = zi::<DIM>();
    ch.apply_inverse_mass(b, tmp);
    for i in 0..n {
        rhs[i] = dot(&q[i], &tmp[i]);
        let (dii, off) = ch.minv_entries(i);
        tri.diag[i] = dot(&q[i], &q[i]) * dii;
        if i + 1 < n {
            let v = dot(&q[i], &q[i + 1]) * off;
            tri.upper[i] = v;
            tri.lower[i + 1] = v;
        }
    }
    if ch.has_tip_constraint() {
        let mut lb = D::zero();
        for i in 0..n {
            lb += ch.lengths[i] * tmp[i][z];
            tri.col[i] = D::zero();
            tri.row[i] = D::zero();
        }
        rhs[n] = lb - v_tip;
        let inv_mn = ch.inv_masses[n - 1];
        let v = q[n - 1][z] * inv_mn * ch.inv_lengths[n - 1];
        tri.col[n - 1] = v;
        tri.row[n - 1] = v;
        tri.corner = inv_mn;
    }
    tri.solve(rhs)
}
