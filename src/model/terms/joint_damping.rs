//! Structural (joint) damping (docs/conventions.md, "Joint damping"): a rotational damper beside
//! each spring, the torque −c_j θ̇_j at joint j acting equal and opposite on the two pendulums it
//! joins.
//!
//! Pendulum i turns with the angular velocity ωᵢ = qᵢ × q̇ᵢ (a vector normal to qᵢ; in the planar
//! model its x component ωᵢ = y_i ż_i − z_i ẏ_i, the rate of the pendulum's angle in the
//! yz-plane), and joint j (between pendulums j − 1 and j, 0-based, the supports' e₂ at rest:
//! ω₋₁ = ωₙ = 0) has the relative angular velocity θ̇_j = ω_j − ω_{j−1}. Rayleigh's dissipation
//! function R = ½ Σ_j c_j |θ̇_j|² gives the generalised force on the momenta
//!
//! ```text
//! Fᵢ = −∂R/∂q̇ᵢ = qᵢ × τᵢ,     τᵢ = c_i θ̇_i − c_{i+1} θ̇_{i+1}   (the net damper torque on pendulum i),
//! ```
//!
//! linear in the velocities q̇ = M⁻¹ p: F = −B(q) q̇ with B = Gᵀ C G symmetric positive
//! semidefinite (G: q̇ ↦ θ̇), so the power F·q̇ = −Σ_j c_j |θ̇_j|² ≤ 0. At rest F = 0: the statics
//! never see it. For small motion about the straight beam θ̇_j is the rate of the spring's angle
//! θ_j, so dampers with c_j/k_j = α at every spring are stiffness-proportional (Rayleigh) damping
//! C = α K, under which mode j decays with ζ_j = α ω_j / 2 (tests/model/joint_damping.rs).

use super::coupled::{CoupledAt, CoupledDissipativeTerm};
use super::{Ctx, Embed};
use crate::base::{Parameter, Scalar};

/// Joint dampers c₁..c_{n+1} (index 0..=n, joint j between pendulums j − 1 and j; zero where the
/// support has no spring): the force of the module docs, read through
/// [`Parameter::JointDamping`] at the joints that have a spring.
#[derive(Clone, Debug)]
pub struct JointDamping<D> {
    pub(crate) c: Vec<D>,
    /// The joints with a spring (the parameter's joints).
    pub(crate) present: Vec<bool>,
}

impl<D: Scalar> JointDamping<D> {
    /// The same term over another scalar (real parts).
    pub(crate) fn lift<D2: Scalar>(&self) -> JointDamping<D2> {
        JointDamping {
            c: self.c.iter().map(|x| D2::from(x.re())).collect(),
            present: self.present.clone(),
        }
    }

    /// The dampers c₁..c_{n+1} \[N·m·s/rad\].
    pub fn dampers(&self) -> &[D] {
        &self.c
    }

    /// Whether every damper at a joint with a spring has the same value (then
    /// [`Parameter::JointDamping`] is their common value).
    pub fn is_uniform(&self) -> bool {
        let mut first: Option<f64> = None;
        for (c, &on) in self.c.iter().zip(&self.present) {
            if on {
                let c = c.re();
                match first {
                    None => first = Some(c),
                    Some(f) if (c - f).abs() > 1e-15 * f.abs() => return false,
                    Some(_) => {}
                }
            }
        }
        true
    }

    /// c_j as the evaluation scalar, seeded for [`Parameter::JointDamping`] at the joints with a
    /// spring.
    #[inline]
    fn damper<E: Embed<D>>(&self, j: usize, ctx: &Ctx<E>) -> E {
        if self.present[j] {
            ctx.param(Parameter::JointDamping, self.c[j])
        } else {
            E::embed(self.c[j])
        }
    }

    /// The torques τᵢ of the module docs for the velocities `v`, pendulum by pendulum: calls
    /// `each(i, τᵢ)` (3-vectors; planar: x component only).
    #[inline]
    fn torques<E: Embed<D>, const DIM: usize>(
        &self,
        q: &[[E; DIM]],
        v: &[[E; DIM]],
        ctx: &Ctx<E>,
        mut each: impl FnMut(usize, [E; 3]),
    ) {
        let n = q.len();
        let zero = [E::zero(); 3];
        let omega = |i: usize| cross(&to3(&q[i]), &to3(&v[i]));
        let mut w_cur = omega(0);
        // c_j θ̇_j of joint j = i (the base joint for i = 0, ω₋₁ = 0).
        let mut rate_cur = scale3(self.damper(0, ctx), &w_cur);
        for i in 0..n {
            let w_next = if i + 1 < n { omega(i + 1) } else { zero };
            let c_next = self.damper(i + 1, ctx);
            let rate_next = scale3(c_next, &sub3(&w_next, &w_cur));
            each(i, sub3(&rate_cur, &rate_next));
            w_cur = w_next;
            rate_cur = rate_next;
        }
    }

    /// The dissipated power Σ_j c_j |θ̇_j|² = −F·q̇ ≥ 0 at velocities `v` \[W\].
    pub fn dissipated_power<const DIM: usize>(&self, q: &[[D; DIM]], v: &[[D; DIM]]) -> D {
        let ctx = Ctx::new(0.0, D::zero(), 0);
        let mut s = D::zero();
        self.torques(q, v, &ctx, |i, tau| {
            // τᵢ·ωᵢ summed over i is Σ_j c_j |θ̇_j|² (summation by parts).
            let w = cross(&to3(&q[i]), &to3(&v[i]));
            s += dot3(&tau, &w);
        });
        s
    }
}

impl<D: Scalar, const DIM: usize> CoupledDissipativeTerm<D, DIM> for JointDamping<D> {
    fn name(&self) -> &'static str {
        "joint damping"
    }

    #[inline]
    fn force<E: Embed<D>>(
        &self,
        q: &[[E; DIM]],
        v: &[[E; DIM]],
        ctx: &Ctx<E>,
        out: &mut [[E; DIM]],
    ) {
        self.torques(q, v, ctx, |i, tau| {
            let f: [E; DIM] = from3(cross(&to3(&q[i]), &tau));
            for d in 0..DIM {
                out[i][d] += f[d];
            }
        });
    }

    fn has_parameter(&self, p: Parameter) -> bool {
        p == Parameter::JointDamping
    }

    /// Closed form of ∇_q (w·F(q, v)): w·F = −Σ_j c_j θ̇_j(w)·θ̇_j(v) is bilinear and symmetric
    /// in (w, v), and ∂(qᵢ × aᵢ)·X/∂qᵢ = aᵢ × X, so block i is −(wᵢ × τᵢ(v) + vᵢ × τᵢ(w));
    /// tested equal to the trait's dual-number default (tests/model/terms.rs).
    fn force_q_vjp(
        &self,
        at: CoupledAt<'_, D, DIM>,
        ctx: &Ctx<D>,
        scale: D,
        out: &mut [[D; DIM]],
        _scratch: &mut super::DualScratch<D, DIM>,
    ) {
        let CoupledAt { q, v, w } = at;
        self.torques(q, v, ctx, |i, tau| {
            let g: [D; DIM] = from3(cross(&to3(&w[i]), &tau));
            for d in 0..DIM {
                out[i][d] -= g[d] * scale;
            }
        });
        self.torques(q, w, ctx, |i, tau| {
            let g: [D; DIM] = from3(cross(&to3(&v[i]), &tau));
            for d in 0..DIM {
                out[i][d] -= g[d] * scale;
            }
        });
    }
}

/// A block as a 3-vector (x, y, z): the planar (y, z) with x = 0.
#[inline]
fn to3<E: Scalar, const DIM: usize>(a: &[E; DIM]) -> [E; 3] {
    if DIM == 3 {
        [a[0], a[1], a[2]]
    } else {
        [E::zero(), a[0], a[1]]
    }
}

/// The model's components of a 3-vector (planar: (y, z)).
#[inline]
fn from3<E: Scalar, const DIM: usize>(a: [E; 3]) -> [E; DIM] {
    std::array::from_fn(|d| a[d + 3 - DIM])
}

#[inline]
fn cross<E: Scalar>(a: &[E; 3], b: &[E; 3]) -> [E; 3] {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

#[inline]
fn sub3<E: Scalar>(a: &[E; 3], b: &[E; 3]) -> [E; 3] {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

#[inline]
fn scale3<E: Scalar>(s: E, a: &[E; 3]) -> [E; 3] {
    [a[0] * s, a[1] * s, a[2] * s]
}

#[inline]
fn dot3<E: Scalar>(a: &[E; 3], b: &[E; 3]) -> E {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}
