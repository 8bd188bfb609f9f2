//! Static equilibrium of the planar chain, solved directly (the ground truth a dissipative
//! simulation must settle to, thesis §2.4.4).
//!
//! The solve is independent of the integrator: in the plane the chain is parametrised by the
//! absolute angles φⱼ of the pendulums (qⱼ = (cos φⱼ, sin φⱼ) in (y, z)), so the joint angles are
//! θᵢ = φᵢ − φ_{i−1} (φ₀ = φ_{n+1} = 0) and
//! ```text
//! U(φ) = ½ Σᵢ kᵢ (φᵢ − φ_{i−1})² + Σⱼ lⱼ cⱼ sin φⱼ   [+ ν Σⱼ lⱼ sin φⱼ for a locked tip]
//! ```
//! with cⱼ the load coefficient of pendulum j (point loads, gravity and control, eq. 2.2.2/3.1.1),
//! plus a current's steady drag at rest (see [`static_equilibrium_at`]).
//! Newton's method on ∇U = 0 (and the tip constraint Σ lⱼ sin φⱼ = 0) has a tridiagonal Hessian
//! bordered by the constraint. It is solved densely with partial pivoting (nalgebra's LU): for a
//! pinned-pinned beam the tridiagonal block alone is singular at the straight configuration (the
//! rigid rotation is removed only by the border), so the pivot-free bordered elimination of
//! [`crate::tridiag`] does not apply. This is a verification tool, not a hot loop; O(n³) is fine
//! for the n ≤ a few hundred it is used with.

use crate::error::{Error, Result};
use crate::model::{dot, Chain, Ctx, DissipativeTerm, DualScratch};
use crate::scene::Scene;
use crate::simulate::scene_controls;
use nalgebra::{DMatrix, DVector};

/// A static equilibrium of the chain.
#[derive(Clone, Debug, PartialEq)]
pub struct StaticSolution {
    /// Absolute pendulum angles φⱼ \[rad\] (from +y toward +z).
    pub angles: Vec<f64>,
    /// Node positions (y, z) of nodes 1..=n.
    pub positions: Vec<[f64; 2]>,
    /// The tip multiplier ν (the tip reaction force, thesis sign), 0 for a free tip.
    pub tip_multiplier: f64,
    /// Newton iterations used.
    pub iterations: usize,
    /// Final max-norm of the gradient residual.
    pub residual: f64,
}

/// Solves the static equilibrium of a scene's beam under its loads, as they act at the final time
/// t_N, with the final control u_N. Errors if Newton does not converge in 100 iterations.
///
/// The energy and its derivatives come from the model's force terms ([`crate::model::terms`]):
/// with qⱼ = (cos φⱼ, sin φⱼ) and tⱼ = ∂qⱼ/∂φⱼ, the gradient is ∂U/∂φⱼ = fⱼ·tⱼ (f = ∂U/∂q,
/// [`Chain::potential_gradient`]) and the Hessian ∂²U/∂φⱼ∂φₖ = tⱼᵀKⱼₖtₖ − δⱼₖ fⱼ·qⱼ (K = ∂²U/∂q²,
/// [`Chain::force_jacobian_product`], block-tridiagonal, so three products seeded on every third
/// pendulum give all of it). The tip constraint adds ν Σ lⱼ sin φⱼ.
pub fn static_equilibrium(scene: &Scene) -> Result<StaticSolution> {
    let u = *scene_controls(scene).last().unwrap_or(&0.0);
    let t = scene.time.step * scene.time.steps as f64;
    static_equilibrium_at(scene, t, u)
}

/// The static equilibrium under the loads as they act at time `t` (time-varying point loads
/// frozen at t) with the control force `u` at the control node.
///
/// A current's drag enters as its steady force at rest: ṗ = 0 and p = 0 leave
/// F(0) = D P⊙|P| ([`crate::model::CurrentDrag`]), a force independent of q, so it adds −F(0) to
/// ∂U/∂q and nothing to K (the still-water drag has F(0) = 0).
///
/// # Errors
/// As [`static_equilibrium`].
pub fn static_equilibrium_at(scene: &Scene, t: f64, u: f64) -> Result<StaticSolution> {
    let chain = Chain::<f64, 2>::from_scene(scene)?;
    let n = chain.n();
    let bordered = chain.has_tip_constraint();
    let l = chain.lengths().to_vec();
    let mut phi = vec![0.0f64; n];
    let mut nu = 0.0f64;
    let mut rhs = vec![0.0; n + usize::from(bordered)];
    let mut last = f64::INFINITY;
    let scale = chain
        .springs()
        .iter()
        .fold(0.0f64, |a, &b| a.max(b))
        .max(1.0);
    let mut work = Work::new(n);
    for it in 0..100 {
        let a = work.newton_system(&chain, (&phi, nu), (t, u), &mut rhs)?;
        let mut rmax = rhs[..n].iter().fold(0.0f64, |m, g| m.max(g.abs() / scale));
        if bordered {
            rmax = rmax.max(rhs[n].abs());
        }
        last = rmax;
        if !rmax.is_finite() {
            break;
        }
        if rmax < 1e-14 {
            let mut positions = Vec::with_capacity(n);
            let (mut y, mut z) = (0.0, 0.0);
            for j in 0..n {
                y += l[j] * phi[j].cos();
                z += l[j] * phi[j].sin();
                positions.push([y, z]);
            }
            return Ok(StaticSolution {
                angles: phi,
                positions,
                tip_multiplier: nu,
                iterations: it,
                residual: rmax,
            });
        }
        let sol = a
            .lu()
            .solve(&DVector::from_column_slice(&rhs))
            .ok_or(Error::StaticSingular { iteration: it })?;
        for j in 0..n {
            phi[j] -= sol[j];
        }
        if bordered {
            nu -= sol[n];
        }
    }
    Err(Error::StaticNotConverged {
        iterations: 100,
        residual: last,
    })
}

/// Buffers of the static Newton iteration.
struct Work {
    q: Vec<[f64; 2]>,
    t: Vec<[f64; 2]>,
    f: Vec<[f64; 2]>,
    v: Vec<[f64; 2]>,
    kv: Vec<[f64; 2]>,
    scratch: DualScratch<f64, 2>,
}

impl Work {
    fn new(n: usize) -> Self {
        let z = vec![[0.0; 2]; n];
        Work {
            q: z.clone(),
            t: z.clone(),
            f: z.clone(),
            v: z.clone(),
            kv: z,
            scratch: DualScratch::new(n),
        }
    }

    /// The gradient (into `rhs`) and the dense Hessian, bordered by the tip constraint, at
    /// (φ, ν) for the loads at (t, u).
    fn newton_system(
        &mut self,
        chain: &Chain<f64, 2>,
        (phi, nu): (&[f64], f64),
        (t, u): (f64, f64),
        rhs: &mut [f64],
    ) -> Result<DMatrix<f64>> {
        let n = chain.n();
        let bordered = chain.has_tip_constraint();
        let l = chain.lengths();
        for j in 0..n {
            let (s, c) = phi[j].sin_cos();
            self.q[j] = [c, s];
            self.t[j] = [-s, c];
        }
        chain.potential_gradient(&self.q, t, u, 0, &mut self.f)?;
        if let Some(drag) = chain.dissipation() {
            let ctx = Ctx::new(t, u, 0);
            for (i, f) in self.f.iter_mut().enumerate() {
                for (d, fd) in f.iter_mut().enumerate() {
                    *fd -= drag.force_component(i, d, 0.0, &ctx);
                }
            }
        }
        let mut a = DMatrix::<f64>::zeros(rhs.len(), rhs.len());
        for j in 0..n {
            let (s, c) = phi[j].sin_cos();
            let tip = if bordered { nu } else { 0.0 };
            rhs[j] = dot(&self.f[j], &self.t[j]) + tip * l[j] * c;
            a[(j, j)] = -dot(&self.f[j], &self.q[j]) - tip * l[j] * s;
            if bordered {
                a[(j, n)] = l[j] * c;
                a[(n, j)] = l[j] * c;
            }
        }
        if bordered {
            rhs[n] = (0..n).map(|j| l[j] * phi[j].sin()).sum();
        }
        let ctx = Ctx::new(t, u, 0);
        for color in 0..3 {
            for j in 0..n {
                self.v[j] = if j % 3 == color { self.t[j] } else { [0.0; 2] };
                self.kv[j] = [0.0; 2];
            }
            let s = &mut self.scratch;
            chain.force_jacobian_product(&self.q, &self.v, &ctx, 1.0, &mut self.kv, s)?;
            for j in 0..n {
                for k in j.saturating_sub(1)..(j + 2).min(n) {
                    if k % 3 == color {
                        a[(j, k)] += dot(&self.t[j], &self.kv[j]);
                    }
                }
            }
        }
        Ok(a)
    }
}
