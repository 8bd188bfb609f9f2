//! Alternative integrators for the constrained chain, for speed-against-accuracy and stability
//! comparisons with RATTLE (thesis §1.6; issue "paper_figures").
//!
//! Three methods share one stepping interface, [`Integrator`], over the planar `f64` model
//! ([`Chain<f64, 2>`]); every force, mass and constraint term comes from [`Chain`] and the linear
//! algebra of [`crate::rattle`] (nothing physical is re-implemented here):
//!
//! * [`Method::Rattle`]: the library's RATTLE ([`Rattle`]), symmetric, symplectic, order 2.
//! * [`Method::Shake`]: SHAKE (thesis §1.6), the two-step recursion
//!   `q_{k+1} − 2q_k + q_{k−1} = −h² M⁻¹ (U_q(q_k) + Ĝ(q_k)ᵀλ_k)`, `ĝ(q_{k+1}) = 0`, with the
//!   momentum recovered as `p_k = M (q_{k+1} − q_{k−1}) / 2h` (not projected onto the hidden
//!   constraint Ĝ M⁻¹ p = 0). Started by one RATTLE-type half step. Without drag its positions
//!   are those of RATTLE up to round-off (the two methods are equivalent in q); its momenta are
//!   not, so its energy error is larger. With drag, the drag force at t_k is evaluated at the
//!   momentum extrapolated from the two previous half-step momenta (second order, explicit).
//! * [`Method::ProjectedRk4`]: the classical explicit Runge–Kutta method of order 4 on the
//!   index-1 formulation (the constraints differentiated twice, λ(q, p) from
//!   Ĝ M⁻¹ Ĝᵀ λ = Ĝ M⁻¹ f + (‖vᵢ‖²)ᵢ), followed after every step by a projection of q onto
//!   ĝ(q) = 0 (along M⁻¹Ĝᵀ, Newton) and of p onto Ĝ M⁻¹ p = 0. Neither symplectic nor
//!   symmetric: its energy error drifts, and it is only conditionally stable (h ω ≲ 2.8).
//!
//! Failures are typed [`Error`]s: a Newton solve that does not converge
//! ([`Error::NewtonNotConverged`]), a folded joint ([`Error::Folded`], θ → π), a singular
//! constraint system, or a non-finite state ([`Error::NonFinite`], the explicit method blowing up).
//! The reaction-force tip ([`TipCondition::Reaction`]) is only supported by RATTLE.

use crate::error::{Error, Result};
use crate::model::{Chain, TipCondition};
use crate::model::{Ctx, DissipativeTerm};
use crate::rattle::{projection_solve, Rattle, RattleOptions, State};
use crate::scene::{ControlKind, Scene};
use crate::tridiag::{BorderedTridiag, ZeroPivot};

/// The planar attitude/momentum block.
type V2 = [f64; 2];

/// Which integrator.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Method {
    /// RATTLE (the library's integrator, [`Rattle`]).
    Rattle,
    /// SHAKE (thesis §1.6) with central-difference momenta.
    Shake,
    /// Explicit RK4 on the index-1 equations with projection onto the constraints.
    ProjectedRk4,
}

impl Method {
    /// Every method, in a stable order.
    pub const ALL: [Method; 3] = [Method::Rattle, Method::Shake, Method::ProjectedRk4];

    /// A short human-readable name.
    pub fn name(self) -> &'static str {
        match self {
            Method::Rattle => "RATTLE",
            Method::Shake => "SHAKE",
            Method::ProjectedRk4 => "projected RK4",
        }
    }
}

/// Scratch memory shared by the methods.
#[derive(Clone, Debug)]
struct Work {
    force: Vec<V2>,
    tmp: Vec<V2>,
    tmp2: Vec<V2>,
    qnew: Vec<V2>,
    rhs: Vec<f64>,
    scal: Vec<f64>,
    tri: BorderedTridiag<f64>,
}

impl Work {
    fn new(ch: &Chain<f64, 2>) -> Self {
        let n = ch.n();
        let nc = ch.n_constraints();
        let v = vec![[0.0; 2]; n];
        Work {
            force: v.clone(),
            tmp: v.clone(),
            tmp2: v.clone(),
            qnew: v,
            rhs: vec![0.0; nc],
            scal: vec![0.0; n],
            tri: BorderedTridiag::new(n, ch.has_tip_constraint()),
        }
    }
}

/// Per-step buffers kept apart from [`Work`] (which the constrained solve borrows whole), so a
/// step allocates nothing.
#[derive(Clone, Debug)]
struct Buffers {
    a: Vec<V2>,
    qc: Vec<V2>,
    phalf: Vec<V2>,
    pd: Vec<V2>,
    lam: Vec<f64>,
}

impl Buffers {
    fn new(ch: &Chain<f64, 2>) -> Self {
        let v = vec![[0.0; 2]; ch.n()];
        Buffers {
            a: v.clone(),
            qc: v.clone(),
            phalf: v.clone(),
            pd: v,
            lam: vec![0.0; ch.n_constraints()],
        }
    }
}

/// Method-specific state.
#[derive(Clone, Debug)]
enum Inner {
    Rattle(Box<Rattle<f64, 2>>, State<f64, 2>),
    Shake {
        /// q_{k+1} (SHAKE runs one configuration ahead of the reported state).
        next: Vec<V2>,
        /// q_{k−1}.
        prev: Vec<V2>,
        /// The half-step momentum p_{k−½} = M (q_k − q_{k−1}) / h before the last one.
        phalf_prev: Vec<V2>,
        /// λ of the last solve (Newton predictor).
        lam: Vec<f64>,
    },
    Rk4 {
        k: [Vec<V2>; 8],
        qs: Vec<V2>,
        ps: Vec<V2>,
    },
}

/// One integrator advancing the chain from the straight beam at rest with a constant control.
#[derive(Clone, Debug)]
pub struct Integrator {
    method: Method,
    chain: Chain<f64, 2>,
    h: f64,
    u: f64,
    k: usize,
    q: Vec<V2>,
    p: Vec<V2>,
    newton: usize,
    options: RattleOptions,
    ws: Work,
    buf: Buffers,
    inner: Inner,
}

fn singular(step: usize, zp: ZeroPivot) -> Error {
    Error::SingularSystem {
        step,
        index: zp.index,
        pivot: zp.pivot,
    }
}

/// The constant control of a scene (0 without one).
fn constant_control(scene: &Scene) -> Result<f64> {
    match &scene.control {
        None => Ok(0.0),
        Some(c) if c.kind == ControlKind::Constant => Ok(c.values[0]),
        Some(_) => Err(Error::InvalidArgument {
            name: "control",
            reason: "the alternative integrators support a constant control only".into(),
        }),
    }
}

impl Integrator {
    /// An integrator for `scene`'s chain with step `h`, starting from the straight beam at rest at
    /// t = 0, with the scene's constant control (0 without one). The scene's own time grid is
    /// ignored.
    ///
    /// # Errors
    /// [`Error::InvalidArgument`] if `h` is not positive and finite, if the scene has a per-step
    /// control, or if `method` is not RATTLE and the scene uses the reaction-force tip; the
    /// scene's own validation errors; and any error of the first step's set-up (SHAKE's starter).
    pub fn new(scene: &Scene, method: Method, h: f64) -> Result<Self> {
        let mut chain = Chain::<f64, 2>::from_scene(scene)?;
        let u = constant_control(scene)?;
        if scene.control.is_none() {
            chain.set_control_node(None)?;
        }
        Self::from_chain(chain, method, h, u)
    }

    /// As [`Integrator::new`], from a chain and a constant control `u`.
    ///
    /// # Errors
    /// As [`Integrator::new`].
    pub fn from_chain(chain: Chain<f64, 2>, method: Method, h: f64, u: f64) -> Result<Self> {
        if !(h > 0.0 && h.is_finite()) {
            return Err(Error::InvalidArgument {
                name: "h",
                reason: format!("the step must be positive and finite, got {h}"),
            });
        }
        if !u.is_finite() {
            return Err(Error::InvalidArgument {
                name: "u",
                reason: format!("the control must be finite, got {u}"),
            });
        }
        if method != Method::Rattle && chain.tip_condition() == TipCondition::Reaction {
            return Err(Error::InvalidArgument {
                name: "method",
                reason: format!(
                    "{} does not support the reaction-force tip; use RATTLE",
                    method.name()
                ),
            });
        }
        let n = chain.n();
        let ws = Work::new(&chain);
        let straight = State::<f64, 2>::straight(n, chain.n_constraints());
        let q = straight.q.clone();
        let p = straight.p.clone();
        let inner = match method {
            Method::Rattle => {
                let mut r = Rattle::new(chain.clone(), h)?;
                let mut st = straight;
                r.prepare(&mut st, 0, u)?;
                Inner::Rattle(Box::new(r), st)
            }
            Method::Shake => Inner::Shake {
                next: q.clone(),
                prev: q.clone(),
                phalf_prev: p.clone(),
                lam: vec![0.0; chain.n_constraints()],
            },
            Method::ProjectedRk4 => Inner::Rk4 {
                k: std::array::from_fn(|_| vec![[0.0; 2]; n]),
                qs: q.clone(),
                ps: p.clone(),
            },
        };
        let buf = Buffers::new(&chain);
        let mut it = Integrator {
            method,
            chain,
            h,
            u,
            k: 0,
            q,
            p,
            newton: 0,
            options: RattleOptions::default(),
            buf,
            ws,
            inner,
        };
        if method == Method::Shake {
            it.shake_start()?;
        }
        Ok(it)
    }

    /// The method.
    pub fn method(&self) -> Method {
        self.method
    }

    /// The model.
    pub fn chain(&self) -> &Chain<f64, 2> {
        &self.chain
    }

    /// Step index k of the current state.
    pub fn step_index(&self) -> usize {
        self.k
    }

    /// Time t_k = k h of the current state.
    pub fn time(&self) -> f64 {
        self.k as f64 * self.h
    }

    /// Attitudes q_k.
    pub fn q(&self) -> &[V2] {
        &self.q
    }

    /// Momenta p_k.
    pub fn p(&self) -> &[V2] {
        &self.p
    }

    /// Total Newton iterations so far (0 for the explicit method's dynamics; it counts its
    /// projection iterations).
    pub fn newton_iterations(&self) -> usize {
        self.newton
    }

    /// Total energy H(q_k, p_k; t_k, u) = ½ pᵀM⁻¹p + U.
    pub fn energy(&self) -> f64 {
        let mut scratch = vec![[0.0; 2]; self.chain.n()];
        self.chain.kinetic_energy(&self.p, &mut scratch)
            + self.chain.potential_energy(&self.q, self.time(), self.u)
    }

    /// Node positions (y, z) of nodes 1..=n.
    pub fn positions(&self) -> Vec<V2> {
        let mut out = vec![[0.0; 2]; self.chain.n()];
        self.chain.node_positions(&self.q, &mut out);
        out
    }

    /// The largest constraint violation max(|½(‖qᵢ‖² − 1)|, |tip z| / L) of the current state.
    pub fn constraint_residual(&self) -> f64 {
        let mut r = self
            .q
            .iter()
            .map(|q| (0.5 * (q[0] * q[0] + q[1] * q[1] - 1.0)).abs())
            .fold(0.0, f64::max);
        if self.chain.has_tip_constraint() {
            let total: f64 = self.chain.lengths().iter().sum();
            r = r.max(self.chain.tip_z(&self.q).abs() / total);
        }
        r
    }

    /// Advances the state by one step.
    ///
    /// # Errors
    /// A typed [`Error`] naming the step: Newton not converged, folded joint, singular system,
    /// or a non-finite state.
    pub fn step(&mut self) -> Result<()> {
        match self.method {
            Method::Rattle => self.rattle_step(),
            Method::Shake => self.shake_step(),
            Method::ProjectedRk4 => self.rk4_step(),
        }?;
        self.k += 1;
        if self
            .q
            .iter()
            .chain(self.p.iter())
            .any(|v| !(v[0].is_finite() && v[1].is_finite()))
        {
            return Err(Error::NonFinite {
                step: self.k,
                quantity: "the state (q, p)",
            });
        }
        Ok(())
    }

    /// Advances `steps` steps.
    ///
    /// # Errors
    /// The first error of [`Integrator::step`].
    pub fn advance(&mut self, steps: usize) -> Result<()> {
        for _ in 0..steps {
            self.step()?;
        }
        Ok(())
    }

    fn rattle_step(&mut self) -> Result<()> {
        let k = self.k;
        let u = self.u;
        if let Inner::Rattle(r, st) = &mut self.inner {
            let s = r.step(st, k, u, u)?;
            self.newton += s.iterations;
            self.q.copy_from_slice(&st.q);
            self.p.copy_from_slice(&st.p);
        }
        Ok(())
    }

    /// Solves ĝ(a − c M⁻¹ Ĝ(q_base)ᵀ λ) = 0 for λ (predictor in `lam`) by Newton; the solution
    /// configuration is left in `ws.qnew`. Returns the iterations.
    #[allow(clippy::too_many_arguments)]
    fn constrained_solve(
        ch: &Chain<f64, 2>,
        ws: &mut Work,
        options: &RattleOptions,
        q_base: &[V2],
        a: &[V2],
        c: f64,
        lam: &mut [f64],
        step: usize,
        time: f64,
    ) -> Result<usize> {
        let n = ch.n();
        let bordered = ch.has_tip_constraint();
        let total: f64 = ch.lengths().iter().sum();
        let h_eff = (2.0 * c).sqrt();
        let mut iterations = 0;
        loop {
            // tmp = Ĝ(q_base)ᵀ λ, qnew = a − c M⁻¹ tmp
            for i in 0..n {
                for d in 0..2 {
                    ws.tmp[i][d] = lam[i] * q_base[i][d];
                }
                if bordered {
                    ws.tmp[i][1] += lam[n] * ch.lengths()[i];
                }
            }
            ch.apply_inverse_mass(&ws.tmp, &mut ws.tmp2);
            for i in 0..n {
                for d in 0..2 {
                    ws.qnew[i][d] = a[i][d] - c * ws.tmp2[i][d];
                }
            }
            let mut rmax: f64 = 0.0;
            for i in 0..n {
                let qi = ws.qnew[i];
                let r = 0.5 * (qi[0] * qi[0] + qi[1] * qi[1] - 1.0);
                rmax = rmax.max(r.abs());
                ws.rhs[i] = r;
            }
            if bordered {
                let r = ch.tip_z(&ws.qnew);
                rmax = rmax.max(r.abs() / total);
                ws.rhs[n] = r;
            }
            if !rmax.is_finite() {
                return Err(Error::NonFinite {
                    step,
                    quantity: "the positions of the Newton iterate",
                });
            }
            if rmax <= options.tolerance {
                return Ok(iterations);
            }
            if iterations >= options.max_iterations {
                return Err(Error::NewtonNotConverged {
                    step,
                    time,
                    residual: rmax,
                    iterations,
                    tolerance: options.tolerance,
                    h: None,
                });
            }
            ch.constraints().assemble_newton(
                (q_base, &ws.qnew),
                None,
                h_eff,
                &mut ws.tri,
                &mut ws.scal,
            );
            ws.tri.solve(&mut ws.rhs).map_err(|zp| singular(step, zp))?;
            for (l, r) in lam.iter_mut().zip(ws.rhs.iter()) {
                *l -= *r;
            }
            iterations += 1;
        }
    }

    /// f = U_q(q; t, u) + D p ⊙ |p| (the force with the sign of U_q) into `ws.force`.
    fn force_into(
        ch: &Chain<f64, 2>,
        q: &[V2],
        p: &[V2],
        t: f64,
        u: f64,
        step: usize,
        out: &mut [V2],
    ) -> Result<()> {
        ch.potential_gradient(q, t, u, step, out)?;
        if let Some(d) = ch.drag() {
            let ctx = Ctx::new(t, u, step);
            for (o, pi) in out.iter_mut().zip(p.iter()) {
                for c in 0..2 {
                    o[c] -= d.force_component(pi[c], &ctx);
                }
            }
        }
        Ok(())
    }

    /// M v (M = M̄ ⊗ I, M̄ = diag(l) Tᵀ diag(m) T diag(l), T lower-triangular ones).
    fn apply_mass(ch: &Chain<f64, 2>, v: &[V2], out: &mut [V2]) {
        let n = ch.n();
        let l = ch.lengths();
        let m = ch.masses();
        let mut acc = [0.0; 2];
        for i in 0..n {
            for d in 0..2 {
                acc[d] += l[i] * v[i][d];
                out[i][d] = m[i] * acc[d];
            }
        }
        let mut rev = [0.0; 2];
        for i in (0..n).rev() {
            for d in 0..2 {
                rev[d] += out[i][d];
                out[i][d] = l[i] * rev[d];
            }
        }
    }

    /// SHAKE's starter: q_1 = q_0 + h M⁻¹ p_0 − h²/2 M⁻¹ (f_0 + Ĝᵀλ), ĝ(q_1) = 0.
    fn shake_start(&mut self) -> Result<()> {
        let h = self.h;
        let n = self.chain.n();
        Self::force_into(
            &self.chain,
            &self.q,
            &self.p,
            0.0,
            self.u,
            0,
            &mut self.ws.force,
        )?;
        self.chain.apply_inverse_mass(&self.p, &mut self.ws.tmp);
        self.chain
            .apply_inverse_mass(&self.ws.force, &mut self.ws.tmp2);
        let a = &mut self.buf.a;
        for i in 0..n {
            for d in 0..2 {
                a[i][d] = self.q[i][d] + h * self.ws.tmp[i][d] - 0.5 * h * h * self.ws.tmp2[i][d];
            }
        }
        let Inner::Shake {
            next,
            prev,
            phalf_prev,
            lam,
        } = &mut self.inner
        else {
            return Ok(());
        };
        let it = Self::constrained_solve(
            &self.chain,
            &mut self.ws,
            &self.options,
            &self.q,
            a,
            0.5 * h * h,
            lam,
            0,
            0.0,
        )?;
        self.newton += it;
        next.copy_from_slice(&self.ws.qnew);
        prev.copy_from_slice(&self.q);
        // p_{½} for the drag extrapolation
        for i in 0..n {
            for d in 0..2 {
                self.ws.tmp[i][d] = (next[i][d] - self.q[i][d]) / h;
            }
        }
        Self::apply_mass(&self.chain, &self.ws.tmp, phalf_prev);
        Ok(())
    }

    fn shake_step(&mut self) -> Result<()> {
        let h = self.h;
        let n = self.chain.n();
        let k1 = self.k + 1;
        let Inner::Shake {
            next,
            prev,
            phalf_prev,
            lam,
        } = &mut self.inner
        else {
            return Ok(());
        };
        // current: q_{k+1} = next; compute q_{k+2}
        let Buffers {
            a, qc, phalf, pd, ..
        } = &mut self.buf;
        qc.copy_from_slice(next);
        // p_{k+½} = M (q_{k+1} − q_k) / h
        for i in 0..n {
            for d in 0..2 {
                self.ws.tmp[i][d] = (qc[i][d] - self.q[i][d]) / h;
            }
        }
        Self::apply_mass(&self.chain, &self.ws.tmp, phalf);
        // drag momentum at t_{k+1}: extrapolated p_{k+½} + (p_{k+½} − p_{k−½})/2
        pd.copy_from_slice(phalf);
        if self.chain.has_drag() {
            for i in 0..n {
                for d in 0..2 {
                    pd[i][d] += 0.5 * (phalf[i][d] - phalf_prev[i][d]);
                }
            }
        }
        Self::force_into(
            &self.chain,
            qc,
            pd,
            k1 as f64 * h,
            self.u,
            k1,
            &mut self.ws.force,
        )?;
        self.chain
            .apply_inverse_mass(&self.ws.force, &mut self.ws.tmp2);
        for i in 0..n {
            for d in 0..2 {
                a[i][d] = 2.0 * qc[i][d] - self.q[i][d] - h * h * self.ws.tmp2[i][d];
            }
        }
        let it = Self::constrained_solve(
            &self.chain,
            &mut self.ws,
            &self.options,
            qc,
            a,
            h * h,
            lam,
            k1,
            k1 as f64 * h,
        )?;
        self.newton += it;
        // p_{k+1} = M (q_{k+2} − q_k) / 2h
        for i in 0..n {
            for d in 0..2 {
                self.ws.tmp[i][d] = (self.ws.qnew[i][d] - self.q[i][d]) / (2.0 * h);
            }
        }
        Self::apply_mass(&self.chain, &self.ws.tmp, &mut self.p);
        prev.copy_from_slice(&self.q);
        self.q.copy_from_slice(qc);
        next.copy_from_slice(&self.ws.qnew);
        phalf_prev.copy_from_slice(phalf);
        Ok(())
    }

    /// (q̇, ṗ) of the index-1 equations at (q, p, t): q̇ = M⁻¹p, ṗ = −f − Ĝᵀλ with
    /// Ĝ M⁻¹ Ĝᵀ λ = −Ĝ M⁻¹ f + (‖vᵢ‖²)ᵢ (tip row: −L M⁻¹ f).
    #[allow(clippy::too_many_arguments)]
    fn rhs(
        ch: &Chain<f64, 2>,
        ws: &mut Work,
        q: &[V2],
        p: &[V2],
        t: f64,
        u: f64,
        step: usize,
        qdot: &mut [V2],
        pdot: &mut [V2],
    ) -> Result<()> {
        let n = ch.n();
        let bordered = ch.has_tip_constraint();
        Self::force_into(ch, q, p, t, u, step, &mut ws.force)?;
        ch.apply_inverse_mass(p, qdot);
        ch.apply_inverse_mass(&ws.force, &mut ws.tmp);
        for i in 0..n {
            let v = qdot[i];
            ws.rhs[i] =
                -(q[i][0] * ws.tmp[i][0] + q[i][1] * ws.tmp[i][1]) + v[0] * v[0] + v[1] * v[1];
        }
        if bordered {
            ws.rhs[n] = -(0..n).map(|i| ch.lengths()[i] * ws.tmp[i][1]).sum::<f64>();
        }
        // assemble_newton with q' = q and h = √2 assembles −Ĝ M⁻¹ Ĝᵀ.
        ch.constraints().assemble_newton(
            (q, q),
            None,
            std::f64::consts::SQRT_2,
            &mut ws.tri,
            &mut ws.scal,
        );
        ws.tri.solve(&mut ws.rhs).map_err(|zp| singular(step, zp))?;
        // λ = −solution
        for i in 0..n {
            let lam = -ws.rhs[i];
            for d in 0..2 {
                pdot[i][d] = -ws.force[i][d] - lam * q[i][d];
            }
            if bordered {
                pdot[i][1] += ws.rhs[n] * ch.lengths()[i];
            }
        }
        Ok(())
    }

    fn rk4_step(&mut self) -> Result<()> {
        let h = self.h;
        let n = self.chain.n();
        let k = self.k;
        let t = k as f64 * h;
        let u = self.u;
        let Inner::Rk4 { k: kk, qs, ps } = &mut self.inner else {
            return Ok(());
        };
        let [kq1, kp1, kq2, kp2, kq3, kp3, kq4, kp4] = kk;
        let ch = &self.chain;
        let ws = &mut self.ws;
        Self::rhs(ch, ws, &self.q, &self.p, t, u, k, kq1, kp1)?;
        let stage =
            |qs: &mut [V2], ps: &mut [V2], dq: &[V2], dp: &[V2], c: f64, q: &[V2], p: &[V2]| {
                for i in 0..n {
                    for d in 0..2 {
                        qs[i][d] = q[i][d] + c * dq[i][d];
                        ps[i][d] = p[i][d] + c * dp[i][d];
                    }
                }
            };
        stage(qs, ps, kq1, kp1, 0.5 * h, &self.q, &self.p);
        Self::rhs(ch, ws, qs, ps, t + 0.5 * h, u, k, kq2, kp2)?;
        stage(qs, ps, kq2, kp2, 0.5 * h, &self.q, &self.p);
        Self::rhs(ch, ws, qs, ps, t + 0.5 * h, u, k, kq3, kp3)?;
        stage(qs, ps, kq3, kp3, h, &self.q, &self.p);
        Self::rhs(ch, ws, qs, ps, t + h, u, k, kq4, kp4)?;
        for i in 0..n {
            for d in 0..2 {
                qs[i][d] = self.q[i][d]
                    + h / 6.0 * (kq1[i][d] + 2.0 * kq2[i][d] + 2.0 * kq3[i][d] + kq4[i][d]);
                ps[i][d] = self.p[i][d]
                    + h / 6.0 * (kp1[i][d] + 2.0 * kp2[i][d] + 2.0 * kp3[i][d] + kp4[i][d]);
            }
        }
        if qs
            .iter()
            .chain(ps.iter())
            .any(|v| !(v[0].is_finite() && v[1].is_finite()))
        {
            return Err(Error::NonFinite {
                step: k + 1,
                quantity: "the RK4 stage (q, p)",
            });
        }
        // Project q onto ĝ = 0 along M⁻¹Ĝ(q̃)ᵀ, then p onto Ĝ M⁻¹ p = 0.
        let lam = &mut self.buf.lam;
        lam.iter_mut().for_each(|l| *l = 0.0);
        let qt: &[V2] = qs;
        let it = Self::constrained_solve(ch, ws, &self.options, qt, qt, 1.0, lam, k + 1, t + h)?;
        self.newton += it;
        self.q.copy_from_slice(&ws.qnew);
        projection_solve(ch, &self.q, ps, 0.0, &mut ws.tmp, &mut ws.tri, &mut ws.rhs)
            .map_err(|zp| singular(k + 1, zp))?;
        let bordered = ch.has_tip_constraint();
        for i in 0..n {
            let y = ws.rhs[i];
            for d in 0..2 {
                self.p[i][d] = ps[i][d] - y * self.q[i][d];
            }
            if bordered {
                self.p[i][1] -= ws.rhs[n] * ch.lengths()[i];
            }
        }
        // A fold is an error, not garbage: check the joint angles of the new configuration.
        ch.potential_gradient(&self.q, t + h, u, k + 1, &mut ws.force)?;
        Ok(())
    }
}

/// Integrates `scene` with `method` and step `h` for `steps` steps, calling `observe` on every
/// `every`-th state (k = 0, every, 2·every, … and the last).
///
/// # Errors
/// As [`Integrator::new`] and [`Integrator::step`].
pub fn integrate(
    scene: &Scene,
    method: Method,
    h: f64,
    steps: usize,
    every: usize,
    mut observe: impl FnMut(&Integrator),
) -> Result<Integrator> {
    let every = every.max(1);
    let mut it = Integrator::new(scene, method, h)?;
    observe(&it);
    for k in 1..=steps {
        it.step()?;
        if k % every == 0 || k == steps {
            observe(&it);
        }
    }
    Ok(it)
}
