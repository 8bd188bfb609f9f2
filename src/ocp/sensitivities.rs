//! The dense sensitivities S_kj = ∂M₀(t_k)/∂θ_j of the condensed solver ([`super::condensed`]):
//! the decisions in chunks of [`CHUNK`] dual-number directions, each chunk swept by forward dual
//! steps from its first decision's stage to N, and the rows gathered per time step.
//!
//! In the spatial model a chunk carries both moment components (z, x), and the gradients of
//! the vector residual are ∇R_{k,c} = Σ_d (∂R_c/∂M₀_d) S_{k,d}.

use nalgebra::SVector;
use num_dual::Derivative;

use super::cost::ResidualVector;
use super::horizon::ControlHorizon;
use super::stage::{Dv, Stepper, CHUNK};
use crate::error::Result;

/// The sensitivities of the decisions θ_first … θ_{first+len−1} (one dual-number chunk).
#[derive(Clone, Debug)]
pub(super) struct SensChunk<const DIM: usize> {
    /// Index of the chunk's first decision in θ.
    pub(super) first: usize,
    /// The number of decisions in the chunk (≤ CHUNK).
    pub(super) len: usize,
    /// The first stage any of the chunk's decisions acts on.
    pub(super) start: usize,
    /// The dual-number stepper the chunk sweeps with.
    pub(super) stepper: Stepper<Dv, DIM>,
    /// Row (DIM − 1)k + c: ∂M₀_c(t_k)/∂θ_{first+s} in slot s, k = 0..=N, c = 0 (z) and, in the
    /// spatial model, 1 (x).
    pub(super) rows: Vec<[f64; CHUNK]>,
}

impl<const DIM: usize> SensChunk<DIM> {
    /// Rows S_k of this chunk's decisions: dual numbers seeded on u_k (and u_{x,k}) from the
    /// chunk's first stage, real parts held at the nominal's and each step started at its
    /// converged multipliers (one derivative-only Newton update).
    pub(super) fn sweep(&mut self, hz: &ControlHorizon<DIM>) -> Result<()> {
        let (model, nom, s0) = (&hz.model, &hz.nominal, self.start);
        let (n, na) = (model.n, DIM - 1);
        let steps = hz.steps;
        self.rows[..(s0 + 1) * na].fill([0.0; CHUNK]);
        let st = &mut self.stepper.state;
        for (q, p) in st.q.iter_mut().zip(st.p.iter_mut()) {
            *q = [Dv::from_re(0.0); DIM];
            *p = [Dv::from_re(0.0); DIM];
        }
        let chunk = self.first..self.first + self.len;
        let seeded = |value: f64, j: usize| {
            let mut seed = [0.0; CHUNK];
            if chunk.contains(&j) {
                seed[j - chunk.start] = 1.0;
            }
            Dv::new(value, Derivative::some(SVector::from(seed)))
        };
        for k in s0..steps {
            let st = &mut self.stepper.state;
            for (i, (q, p)) in st.q.iter_mut().zip(st.p.iter_mut()).enumerate() {
                for d in 0..DIM {
                    q[d].re = nom.q(k)[i][d];
                    p[d].re = nom.p(k)[i][d];
                }
            }
            let m = st.multipliers_mut(n);
            for ((ml, mm), &v) in m.lambda.iter_mut().zip(m.mu.iter_mut()).zip(nom.lambda(k)) {
                (*ml, *mm) = (Dv::from_re(v), Dv::from_re(v));
            }
            st.tip_target = [Dv::from_re(0.0); 2];
            if hz.axes == 2 {
                let ux = seeded(nom.ux[k], hz.theta_index(k, 1));
                self.stepper.set_control_x(k, ux);
            }
            let u = seeded(nom.u[k], hz.theta_index(k, 0));
            self.stepper.advance(k, u)?;
            let q1 = &self.stepper.state.q[0];
            for (c, axis) in [DIM - 1, 0].into_iter().take(na).enumerate() {
                let row = &mut self.rows[(k + 1) * na + c];
                *row = [0.0; CHUNK];
                if let Some(e) = q1[axis].eps.0.as_ref() {
                    for (r, v) in row.iter_mut().zip(e.iter()) {
                        *r = model.moment_scale * v;
                    }
                }
            }
        }
        Ok(())
    }
}

/// S_{k,c}, the sensitivities of the moment's component c (0: z, 1: x) at t_k to θ, gathered
/// from the chunks into `out`.
pub(super) fn sens_row<const DIM: usize>(
    chunks: &[SensChunk<DIM>],
    k: usize,
    c: usize,
    out: &mut [f64],
) {
    let r = k * (DIM - 1) + c;
    for ch in chunks {
        out[ch.first..ch.first + ch.len].copy_from_slice(&ch.rows[r][..ch.len]);
    }
}

/// The gradients ∇R_{k,c} = Σ_d (∂R_c/∂M₀_d) S_{k,d} of the spatial vector residual `rv` at
/// t_k, c = 0 (z), 1 (x), into `out`.
pub(super) fn residual_gradients<const DIM: usize>(
    chunks: &[SensChunk<DIM>],
    rv: &ResidualVector,
    k: usize,
    out: [&mut [f64]; 2],
) {
    let [g0, g1] = out;
    sens_row(chunks, k, 0, g0);
    sens_row(chunks, k, 1, g1);
    let j = rv.jac;
    for (a, b) in g0.iter_mut().zip(g1.iter_mut()) {
        let (sz, sx) = (*a, *b);
        *a = j[0][0] * sz + j[0][1] * sx;
        *b = j[1][0] * sz + j[1][1] * sx;
    }
}

/// The chunks ordered longest, shortest, second longest, second shortest, …: the chunk of
/// θ_first runs from θ_first's stage to N, so the recursive halving of rayon's parallel
/// iterator hands each thread about the same number of steps.
pub(super) fn balanced<const DIM: usize>(mut chunks: Vec<SensChunk<DIM>>) -> Vec<SensChunk<DIM>> {
    let mut out = Vec::with_capacity(chunks.len());
    let mut front = true;
    while !chunks.is_empty() {
        out.push(if front {
            chunks.remove(0)
        } else {
            chunks.pop().expect("not empty")
        });
        front = !front;
    }
    out
}
