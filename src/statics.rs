//! Static equilibrium of the planar chain, solved directly (the ground truth a dissipative
//! simulation must settle to, thesis §2.4.4).
//!
//! The solve is independent of the integrator: in the plane the chain is parametrised by the
//! absolute angles φⱼ of the pendulums (qⱼ = (cos φⱼ, sin φⱼ) in (y, z)), so the joint angles are
//! θᵢ = φᵢ − φ_{i−1} (φ₀ = φ_{n+1} = 0) and
//! ```text
//! U(φ) = ½ Σᵢ kᵢ (φᵢ − φ_{i−1})² + Σⱼ lⱼ cⱼ sin φⱼ   [+ ν Σⱼ lⱼ sin φⱼ for a locked tip]
//! ```
//! with cⱼ the load coefficient of pendulum j (point loads, gravity and control, eq. 2.2.2/3.1.1).
//! Newton's method on ∇U = 0 (and the tip constraint Σ lⱼ sin φⱼ = 0) has a tridiagonal Hessian
//! bordered by the constraint. It is solved densely with partial pivoting (nalgebra's LU): for a
//! pinned-pinned beam the tridiagonal block alone is singular at the straight configuration (the
//! rigid rotation is removed only by the border), so the pivot-free bordered elimination of
//! [`crate::tridiag`] does not apply. This is a verification tool, not a hot loop; O(n³) is fine
//! for the n ≤ a few hundred it is used with.

use crate::error::{Error, Result};
use crate::model::Chain;
use crate::scene::Scene;
use crate::simulate::scene_controls;
use crate::tridiag::BorderedTridiag;
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
pub fn static_equilibrium(scene: &Scene) -> Result<StaticSolution> {
    let chain = Chain::<f64, 2>::from_scene(scene)?;
    let u = *scene_controls(scene).last().unwrap_or(&0.0);
    let t = scene.time.step * scene.time.steps as f64;
    let n = chain.n();
    let bordered = chain.has_tip_constraint();
    let k = chain.springs();
    let l = chain.lengths();
    let mut coef = vec![0.0; n];
    chain.for_each_load_coefficient(t, u, |j, c| coef[j] = c);
    let mut phi = vec![0.0f64; n];
    let mut nu = 0.0f64;
    let mut tri = BorderedTridiag::<f64>::new(n, bordered);
    let mut rhs = vec![0.0; n + usize::from(bordered)];
    let mut last = f64::INFINITY;
    let scale = k.iter().fold(0.0f64, |a, &b| a.max(b)).max(1.0);
    for it in 0..100 {
        let ang = |j: usize, phi: &[f64]| if j < n { phi[j] } else { 0.0 };
        let mut rmax: f64 = 0.0;
        for j in 0..n {
            let prev = if j > 0 { phi[j - 1] } else { 0.0 };
            let (s, c) = phi[j].sin_cos();
            let load = coef[j] + if bordered { nu } else { 0.0 };
            let g =
                k[j] * (phi[j] - prev) - k[j + 1] * (ang(j + 1, &phi) - phi[j]) + l[j] * load * c;
            rhs[j] = g;
            rmax = rmax.max(g.abs() / scale);
            tri.diag[j] = k[j] + k[j + 1] - l[j] * load * s;
            if j + 1 < n {
                tri.upper[j] = -k[j + 1];
                tri.lower[j + 1] = -k[j + 1];
            }
            if bordered {
                tri.col[j] = l[j] * c;
                tri.row[j] = l[j] * c;
            }
        }
        if bordered {
            let tip: f64 = (0..n).map(|j| l[j] * phi[j].sin()).sum();
            rhs[n] = tip;
            rmax = rmax.max(tip.abs());
            tri.corner = 0.0;
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
        let m = rhs.len();
        let mut a = DMatrix::<f64>::zeros(m, m);
        for j in 0..n {
            a[(j, j)] = tri.diag[j];
            if j + 1 < n {
                a[(j, j + 1)] = tri.upper[j];
                a[(j + 1, j)] = tri.lower[j + 1];
            }
            if bordered {
                a[(j, n)] = tri.col[j];
                a[(n, j)] = tri.row[j];
            }
        }
        let sol = a
            .lu()
            .solve(&DVector::from_column_slice(&rhs))
            .ok_or(Error::SingularSystem {
                step: 0,
                index: 0,
                pivot: 0.0,
            })?;
        rhs.copy_from_slice(sol.as_slice());
        for j in 0..n {
            phi[j] -= rhs[j];
        }
        if bordered {
            nu -= rhs[n];
        }
    }
    Err(Error::NewtonNotConverged {
        step: 0,
        time: t,
        residual: last,
        iterations: 100,
        tolerance: 1e-14,
        h: None,
    })
}
