//! Newton's method on the product of spheres (qⱼ ∈ S²) for the spatial model; the equations are
//! in the docs of [`crate::statics`].

use super::{newton, Chart, StaticSolution};
use crate::error::{Error, Result};
use crate::model::{dot, Chain, Ctx, DualScratch};
use crate::scene::Scene;
use nalgebra::DMatrix;

/// The spatial static equilibrium of `scene` under its loads at time t with the control
/// (u_x, u_z) = `u` (see [`super::static_equilibrium_spatial`]).
pub(super) fn solve(scene: &Scene, t: f64, u: [f64; 2]) -> Result<StaticSolution> {
    let mut chain = Chain::<f64, 3>::from_scene(scene)?;
    let n = chain.n();
    if !chain.has_spring(0) && !chain.has_spring(n) {
        return Err(Error::StaticNotIsolated {
            support: scene.beam.support,
            tip: chain.tip_condition(),
        });
    }
    if u[0] != 0.0 {
        chain.set_control_x(&[u[0]])?;
    }
    let ctx = chain.ctx(t, u[1], 0);
    newton(&chain, &mut Spheres::new(n, ctx))
}

/// An orthonormal basis (aⱼ, bⱼ) of the tangent plane of S² at `q`, with aⱼ in the x–q plane
/// and bⱼ = aⱼ × qⱼ: on the straight beam (e_x, e_z), and for qⱼ = (0, cos φ, sin φ) in the y–z
/// plane (e_x, (0, −sin φ, cos φ)), the planar tangent. Near ±e_x, e_z stands in for e_x.
fn tangent_basis(q: &[f64; 3]) -> [[f64; 3]; 2] {
    let e = if q[0].abs() < 0.5 {
        [1.0, 0.0, 0.0]
    } else {
        [0.0, 0.0, 1.0]
    };
    let c = dot(&e, q);
    let a = normalised([e[0] - c * q[0], e[1] - c * q[1], e[2] - c * q[2]]);
    let b = [
        a[1] * q[2] - a[2] * q[1],
        a[2] * q[0] - a[0] * q[2],
        a[0] * q[1] - a[1] * q[0],
    ];
    [a, b]
}

fn normalised(v: [f64; 3]) -> [f64; 3] {
    let r = dot(&v, &v).sqrt();
    [v[0] / r, v[1] / r, v[2] / r]
}

/// The iterate qⱼ ∈ S², its tangent bases, the loads' context and the buffers of the Newton
/// system.
struct Spheres {
    /// The time, control and step at which the loads act.
    ctx: Ctx<f64>,
    q: Vec<[f64; 3]>,
    basis: Vec<[[f64; 3]; 2]>,
    f: Vec<[f64; 3]>,
    v: Vec<[f64; 3]>,
    kv: Vec<[f64; 3]>,
    scratch: DualScratch<f64, 3>,
}

impl Spheres {
    /// The straight beam qⱼ = e₂ under the loads of `ctx`.
    fn new(n: usize, ctx: Ctx<f64>) -> Self {
        let z = vec![[0.0; 3]; n];
        let q = vec![[0.0, 1.0, 0.0]; n];
        Spheres {
            ctx,
            basis: q.iter().map(tangent_basis).collect(),
            q,
            f: z.clone(),
            v: z.clone(),
            kv: z,
            scratch: DualScratch::new(n),
        }
    }

    /// qⱼ ← normalise(qⱼ − Tⱼ δⱼ) for the Newton solution δ (the step solves H δ = g), and the
    /// new tangent bases.
    fn retract(&mut self, sol: &[f64]) {
        for (j, (q, [a, b])) in self.q.iter_mut().zip(&self.basis).enumerate() {
            let (s, t) = (sol[2 * j], sol[2 * j + 1]);
            *q = normalised([0, 1, 2].map(|d| q[d] - s * a[d] - t * b[d]));
        }
        for (t, q) in self.basis.iter_mut().zip(&self.q) {
            *t = tangent_basis(q);
        }
    }

    /// gⱼ = ∂L/∂qⱼ of the Lagrangian L = U + ν Σ lⱼ e₃ᵀqⱼ − F(0)·q (the current's drag at rest)
    /// into `self.f`.
    fn lagrangian_gradient(
        &mut self,
        chain: &Chain<f64, 3>,
        nu: f64,
        ctx: &Ctx<f64>,
    ) -> Result<()> {
        chain.potential_gradient(&self.q, ctx.t, ctx.u, 0, &mut self.f)?;
        for (i, f) in self.f.iter_mut().enumerate() {
            if let Some(fd) = chain.dissipative_force(i, &[0.0; 3], ctx) {
                f.iter_mut().zip(fd).for_each(|(f, fd)| *f -= fd);
            }
        }
        let n = self.f.len();
        chain.add_node_drag(&vec![[0.0; 3]; n], ctx, -1.0, &mut self.f);
        if chain.has_tip_constraint() {
            for (f, l) in self.f.iter_mut().zip(chain.lengths()) {
                f[2] += nu * l;
            }
        }
        Ok(())
    }

    /// Adds TⱼᵀKⱼₖTₖ: K is block-tridiagonal (without soil springs, [`Chain::stiffness_reach`]),
    /// so seeding the tangent direction s of every third pendulum (3 colours × 2 directions = 6
    /// products of [`Chain::force_jacobian_product`]) gives every block; with soil springs K is
    /// dense below the mudline and every pendulum is its own colour (2n products).
    fn add_stiffness(
        &mut self,
        chain: &Chain<f64, 3>,
        ctx: &Ctx<f64>,
        a: &mut DMatrix<f64>,
    ) -> Result<()> {
        let n = chain.n();
        let reach = chain.stiffness_reach();
        let colours = (2 * reach + 1).min(n);
        for color in 0..colours {
            for s in 0..2 {
                for j in 0..n {
                    let on = j % colours == color;
                    self.v[j] = if on { self.basis[j][s] } else { [0.0; 3] };
                    self.kv[j] = [0.0; 3];
                }
                let sc = &mut self.scratch;
                chain.force_jacobian_product(&self.q, &self.v, ctx, 1.0, &mut self.kv, sc)?;
                for j in 0..n {
                    let near = j.saturating_sub(reach)..(j + reach + 1).min(n);
                    for k in near.filter(|k| k % colours == color) {
                        for r in 0..2 {
                            a[(2 * j + r, 2 * k + s)] += dot(&self.basis[j][r], &self.kv[j]);
                        }
                    }
                }
            }
        }
        Ok(())
    }
}

impl Chart<3> for Spheres {
    const COORDS: usize = 2;

    /// The Riemannian gradient Tⱼᵀgⱼ (into `rhs`, with the tip residual Σ lⱼ e₃ᵀqⱼ last) and the
    /// dense Hessian TⱼᵀKⱼₖTₖ − δⱼₖ (gⱼ·qⱼ) I₂, bordered by the tip row lⱼ Tⱼᵀe₃.
    fn newton_system(
        &mut self,
        chain: &Chain<f64, 3>,
        nu: f64,
        rhs: &mut [f64],
    ) -> Result<DMatrix<f64>> {
        let n = chain.n();
        let ctx = self.ctx;
        self.lagrangian_gradient(chain, nu, &ctx)?;
        let mut a = DMatrix::<f64>::zeros(rhs.len(), rhs.len());
        for j in 0..n {
            let curvature = dot(&self.f[j], &self.q[j]);
            for r in 0..2 {
                let i = 2 * j + r;
                rhs[i] = dot(&self.basis[j][r], &self.f[j]);
                a[(i, i)] = -curvature;
                if chain.has_tip_constraint() {
                    let c = chain.lengths()[j] * self.basis[j][r][2];
                    a[(i, 2 * n)] = c;
                    a[(2 * n, i)] = c;
                }
            }
        }
        if chain.has_tip_constraint() {
            rhs[2 * n] = chain.tip_z(&self.q) - chain.static_tip_target();
        }
        self.add_stiffness(chain, &ctx, &mut a)?;
        Ok(a)
    }

    /// qⱼ ← normalise(qⱼ − Tⱼ δⱼ), and the new tangent bases.
    fn step(&mut self, delta: &[f64]) {
        self.retract(delta);
    }

    /// The converged iterate as a [`StaticSolution`].
    fn solution(&self, chain: &Chain<f64, 3>, nu: f64, residuals: Vec<f64>) -> StaticSolution {
        let mut nodes = vec![[0.0; 3]; chain.n()];
        chain.node_positions(&self.q, &mut nodes);
        StaticSolution {
            angles: self.q.iter().map(|q| q[2].atan2(q[1])).collect(),
            positions: nodes.iter().map(|r| [r[1], r[2]]).collect(),
            positions_x: nodes.iter().map(|r| r[0]).collect(),
            attitudes: self.q.clone(),
            spatial: true,
            tip_multiplier: if chain.has_tip_constraint() { nu } else { 0.0 },
            iterations: residuals.len() - 1,
            residual: residuals.last().copied().unwrap_or(0.0),
            residuals,
        }
    }
}
