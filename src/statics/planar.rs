//! The planar chart of the statics' Newton iteration ([`super::newton`]): the absolute angles φⱼ
//! of the pendulums, qⱼ = (cos φⱼ, sin φⱼ) in (y, z); the equations are in the docs of
//! [`crate::statics`].

use super::{newton, Chart, StaticSolution};
use crate::error::Result;
use crate::model::{dot, Chain, Ctx, DualScratch};
use crate::scene::Scene;
use nalgebra::DMatrix;

/// The planar static equilibrium of `scene` under its loads at time t with the control `u`
/// along z (see [`super::static_equilibrium_at`]), Newton in the absolute angles from the
/// straight beam φ = 0.
pub(super) fn solve(scene: &Scene, t: f64, u: f64) -> Result<StaticSolution> {
    let chain = Chain::<f64, 2>::from_scene(scene)?;
    newton(&chain, &mut Angles::new(chain.n(), t, u))
}

/// The iterate φ, the loads' time and control, and the buffers of the Newton system.
struct Angles {
    phi: Vec<f64>,
    /// The time t at which the loads act.
    time: f64,
    /// The control force u along z.
    u: f64,
    q: Vec<[f64; 2]>,
    t: Vec<[f64; 2]>,
    f: Vec<[f64; 2]>,
    v: Vec<[f64; 2]>,
    kv: Vec<[f64; 2]>,
    scratch: DualScratch<f64, 2>,
}

impl Angles {
    /// The straight beam φ = 0 under the loads at `time` with the control `u`.
    fn new(n: usize, time: f64, u: f64) -> Self {
        let z = vec![[0.0; 2]; n];
        Angles {
            phi: vec![0.0; n],
            time,
            u,
            q: z.clone(),
            t: z.clone(),
            f: z.clone(),
            v: z.clone(),
            kv: z,
            scratch: DualScratch::new(n),
        }
    }
}

impl Chart<2> for Angles {
    const COORDS: usize = 1;

    /// ∂U/∂φⱼ = fⱼ·tⱼ (+ ν lⱼ cos φⱼ) into `rhs` and the Hessian tⱼᵀKⱼₖtₖ − δⱼₖ fⱼ·qⱼ
    /// (− ν lⱼ sin φⱼ), bordered by the tip row lⱼ cos φⱼ.
    fn newton_system(
        &mut self,
        chain: &Chain<f64, 2>,
        nu: f64,
        rhs: &mut [f64],
    ) -> Result<DMatrix<f64>> {
        let (phi, t, u) = (&self.phi, self.time, self.u);
        let n = chain.n();
        let bordered = chain.has_tip_constraint();
        let l = chain.lengths();
        for j in 0..n {
            let (s, c) = phi[j].sin_cos();
            self.q[j] = [c, s];
            self.t[j] = [-s, c];
        }
        chain.potential_gradient(&self.q, t, u, 0, &mut self.f)?;
        let ctx = Ctx::new(t, u, 0);
        for (i, f) in self.f.iter_mut().enumerate() {
            if let Some(fd) = chain.dissipative_force(i, &[0.0; 2], &ctx) {
                f.iter_mut().zip(fd).for_each(|(f, fd)| *f -= fd);
            }
        }
        chain.add_node_drag(&vec![[0.0; 2]; n], &ctx, -1.0, &mut self.f);
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
            rhs[n] = (0..n).map(|j| l[j] * phi[j].sin()).sum::<f64>() - chain.static_tip_target();
        }
        // K couples pendulums up to `reach` apart (1: block-tridiagonal; soil springs: all).
        let reach = chain.stiffness_reach();
        let colours = (2 * reach + 1).min(n);
        for color in 0..colours {
            for j in 0..n {
                self.v[j] = if j % colours == color {
                    self.t[j]
                } else {
                    [0.0; 2]
                };
                self.kv[j] = [0.0; 2];
            }
            let s = &mut self.scratch;
            chain.force_jacobian_product(&self.q, &self.v, &ctx, 1.0, &mut self.kv, s)?;
            for j in 0..n {
                for k in j.saturating_sub(reach)..(j + reach + 1).min(n) {
                    if k % colours == color {
                        a[(j, k)] += dot(&self.t[j], &self.kv[j]);
                    }
                }
            }
        }
        Ok(a)
    }

    /// φⱼ ← φⱼ − δⱼ.
    fn step(&mut self, delta: &[f64]) {
        for (p, d) in self.phi.iter_mut().zip(delta) {
            *p -= d;
        }
    }

    /// The nodes by summing lⱼ (cos φⱼ, sin φⱼ) from the base.
    fn solution(&self, chain: &Chain<f64, 2>, nu: f64, residuals: Vec<f64>) -> StaticSolution {
        let phi = &self.phi;
        let l = chain.lengths();
        let mut positions = Vec::with_capacity(phi.len());
        let (mut y, mut z) = (0.0, 0.0);
        for (lj, p) in l.iter().zip(phi) {
            y += lj * p.cos();
            z += lj * p.sin();
            positions.push([y, z]);
        }
        StaticSolution {
            attitudes: phi.iter().map(|p| [0.0, p.cos(), p.sin()]).collect(),
            positions_x: vec![0.0; phi.len()],
            angles: phi.clone(),
            positions,
            spatial: false,
            tip_multiplier: nu,
            iterations: residuals.len() - 1,
            residual: residuals.last().copied().unwrap_or(0.0),
            residuals,
        }
    }
}
