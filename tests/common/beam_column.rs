//! The one natural-frequency check of the riser tests: the chain's own frequencies linearised
//! about the straight beam, and an independent finite-element beam-column model to compare them
//! with. Used by tests/model/riser_system.rs (a uniform pipe: riser_300m.toml, its top free or
//! held) and tests/model/riser_scenes.rs (a stack-up: the conductor in its soil, the BOP and
//! LMRP, the flex joints, the top held by the vessel); each builds its elements from its own
//! scene and calls [`BeamColumn::frequencies`].
//!
//! The beam-column model: EI w⁗ − (T_e w′)′ + k_s w + μ ẅ = 0 in Hermite cubic elements
//! (stiffness EI/l³ [12, 6l, …], geometric stiffness T_e/(30 l) [36, 3l, …], consistent mass
//! μl/420 [156, 22l, …] and Winkler soil k_s l/420 [156, 22l, …]; e.g. Przemieniecki, *Theory of
//! Matrix Structural Analysis*, §5, §11), with lumped masses at element ends, hinges with
//! rotational springs, the foot clamped and the top held or free, its rotation clamped, free or
//! held by a spring.
#![allow(dead_code)]

use chainbeam::{Chain, Scene};
use nalgebra::DMatrix;
use num_dual::{DualNum, HyperDual64};

/// ω of K φ = ω² M φ (M positive definite), ascending: Cholesky M = C Cᵀ, the symmetric
/// eigenvalues of C⁻¹ K C⁻ᵀ (symmetrised), negative round-off clipped to 0.
pub fn generalized_eigen(k: DMatrix<f64>, m: DMatrix<f64>) -> Vec<f64> {
    let ci = m.cholesky().unwrap().l().try_inverse().unwrap();
    let a = &ci * k * ci.transpose();
    let a = (&a + a.transpose()) * 0.5;
    let mut w: Vec<f64> = a
        .symmetric_eigenvalues()
        .iter()
        .map(|x| x.max(0.0).sqrt())
        .collect();
    w.sort_by(f64::total_cmp);
    w
}

/// The chain's natural frequencies ω (ascending) linearised about the straight beam: K φ = ω² M φ
/// in the pendulum angles θ (qⱼ = (cos θⱼ, sin θⱼ)), K the Hessian of the chain's own potential
/// energy by hyper-dual numbers (springs, soil, tension, weights), M = Lᵀ diag(m) L with
/// zᵢ = Σ_{j≤i} lⱼθⱼ; a tip held by the vessel or a fixed-fixed support (Σ lⱼθⱼ = 0) eliminates
/// θₙ.
pub fn chain_frequencies(scene: &Scene) -> Vec<f64> {
    let chain = Chain::<f64, 2>::from_scene(scene)
        .unwrap()
        .lift::<HyperDual64>();
    let n = chain.n();
    let l = &scene.beam.lengths;
    let k = DMatrix::from_fn(n, n, |a, b| {
        let q: Vec<[HyperDual64; 2]> = (0..n)
            .map(|j| {
                let e = |c: usize| f64::from(u8::from(j == c));
                let th = HyperDual64::new(0.0, e(a), e(b), 0.0);
                [th.cos(), th.sin()]
            })
            .collect();
        chain
            .potential_energy(&q, 0.0, HyperDual64::from(0.0))
            .eps1eps2
    });
    let lz = DMatrix::from_fn(n, n, |i, j| if j <= i { l[j] } else { 0.0 });
    let m = lz.transpose() * DMatrix::from_diagonal(&scene.beam.masses.clone().into()) * &lz;
    let (k, m) = if scene.beam.support.holds_tip() {
        let b = DMatrix::from_fn(n, n - 1, |i, j| match i {
            i if i == n - 1 => -l[j] / l[n - 1],
            i => f64::from(u8::from(i == j)),
        });
        (b.transpose() * k * &b, b.transpose() * m * &b)
    } else {
        (k, m)
    };
    generalized_eigen(k, m)
}

/// One Hermite cubic element, from node i to node i + 1 (the elements listed from the foot up).
#[derive(Clone, Copy, Debug)]
pub struct Element {
    /// Length l \[m\].
    pub length: f64,
    /// Bending stiffness EI \[N·m²\].
    pub ei: f64,
    /// Mass per length μ (with added mass) \[kg/m\].
    pub mu: f64,
    /// Effective tension T_e \[N\], constant over the element (the caller's value at its middle).
    pub tension: f64,
    /// Winkler soil modulus k_s \[N/m²\], constant over the element.
    pub soil: f64,
    /// A lumped mass \[kg\] added half to each end node's deflection (a rigid body's).
    pub end_mass: f64,
}

/// How the top's rotation is held.
#[derive(Clone, Copy, Debug)]
pub enum TopRotation {
    /// Held (w′ = 0 at the top).
    Clamped,
    /// Free (no moment at the top).
    Free,
    /// Turned against a fixed direction by a rotational spring \[N·m/rad\] (a flex joint to a
    /// vessel that does not turn).
    Spring(f64),
}

/// A beam-column of [`Element`]s, the foot clamped (w = w′ = 0).
#[derive(Clone, Debug)]
pub struct BeamColumn {
    /// The elements from the foot up.
    pub elements: Vec<Element>,
    /// Hinges at interior nodes (node index, 1..elements.len()): a second rotation for the
    /// elements above, tied to the one below by a rotational spring \[N·m/rad\].
    pub hinges: Vec<(usize, f64)>,
    /// The top's deflection held (w = 0).
    pub top_held: bool,
    /// The top's rotation.
    pub top_rotation: TopRotation,
}

impl BeamColumn {
    /// The natural frequencies ω (ascending) of the assembled K φ = ω² M φ, the fixed degrees of
    /// freedom removed and the massless rotations (inside rigid bodies carried by end masses)
    /// condensed out statically, exactly: K = K_mm − K_ms K_ss⁻¹ K_sm.
    pub fn frequencies(&self) -> Vec<f64> {
        let ne = self.elements.len();
        let hinge = |node: usize| self.hinges.iter().find(|h| h.0 == node).map(|h| h.1);
        // Dofs per node: w, θ (below); a hinge node a second rotation for the elements above.
        let mut w_dof = Vec::with_capacity(ne + 1);
        let mut th_below = Vec::with_capacity(ne + 1);
        let mut th_above = Vec::with_capacity(ne + 1);
        let mut dofs = 0;
        for node in 0..=ne {
            w_dof.push(dofs);
            th_below.push(dofs + 1);
            dofs += 2;
            if node > 0 && node < ne && hinge(node).is_some() {
                th_above.push(dofs);
                dofs += 1;
            } else {
                th_above.push(dofs - 1);
            }
        }
        let (mut k, mut m) = (DMatrix::zeros(dofs, dofs), DMatrix::zeros(dofs, dofs));
        for (i, e) in self.elements.iter().enumerate() {
            let l = e.length;
            let ke = [
                [12.0, 6.0 * l, -12.0, 6.0 * l],
                [6.0 * l, 4.0 * l * l, -6.0 * l, 2.0 * l * l],
                [-12.0, -6.0 * l, 12.0, -6.0 * l],
                [6.0 * l, 2.0 * l * l, -6.0 * l, 4.0 * l * l],
            ];
            let kg = [
                [36.0, 3.0 * l, -36.0, 3.0 * l],
                [3.0 * l, 4.0 * l * l, -3.0 * l, -l * l],
                [-36.0, -3.0 * l, 36.0, -3.0 * l],
                [3.0 * l, -l * l, -3.0 * l, 4.0 * l * l],
            ];
            let me = [
                [156.0, 22.0 * l, 54.0, -13.0 * l],
                [22.0 * l, 4.0 * l * l, 13.0 * l, -3.0 * l * l],
                [54.0, 13.0 * l, 156.0, -22.0 * l],
                [-13.0 * l, -3.0 * l * l, -22.0 * l, 4.0 * l * l],
            ];
            let idx = [w_dof[i], th_above[i], w_dof[i + 1], th_below[i + 1]];
            for a in 0..4 {
                for b in 0..4 {
                    let (r, c) = (idx[a], idx[b]);
                    k[(r, c)] += e.ei / (l * l * l) * ke[a][b]
                        + e.tension / (30.0 * l) * kg[a][b]
                        + e.soil * l / 420.0 * me[a][b];
                    m[(r, c)] += e.mu * l / 420.0 * me[a][b];
                }
            }
            if e.end_mass != 0.0 {
                m[(w_dof[i], w_dof[i])] += 0.5 * e.end_mass;
                m[(w_dof[i + 1], w_dof[i + 1])] += 0.5 * e.end_mass;
            }
        }
        for &(node, kf) in &self.hinges {
            let (a, b) = (th_below[node], th_above[node]);
            k[(a, a)] += kf;
            k[(b, b)] += kf;
            k[(a, b)] -= kf;
            k[(b, a)] -= kf;
        }
        let mut fixed = vec![w_dof[0], th_above[0]];
        match self.top_rotation {
            TopRotation::Clamped => fixed.push(th_below[ne]),
            TopRotation::Free => {}
            TopRotation::Spring(kf) => k[(th_below[ne], th_below[ne])] += kf,
        }
        if self.top_held {
            fixed.push(w_dof[ne]);
        }
        let free: Vec<usize> = (0..dofs).filter(|d| !fixed.contains(d)).collect();
        let massless = |d: usize| (0..dofs).all(|e| m[(d, e)] == 0.0);
        let (dyn_dofs, stat): (Vec<usize>, Vec<usize>) = free.iter().partition(|&&d| !massless(d));
        let sub = |a: &DMatrix<f64>, r: &[usize], c: &[usize]| {
            DMatrix::from_fn(r.len(), c.len(), |i, j| a[(r[i], c[j])])
        };
        let kmm = sub(&k, &dyn_dofs, &dyn_dofs);
        let kc = if stat.is_empty() {
            kmm
        } else {
            let kss = sub(&k, &stat, &stat).try_inverse().unwrap();
            kmm - sub(&k, &dyn_dofs, &stat) * kss * sub(&k, &stat, &dyn_dofs)
        };
        generalized_eigen(kc, sub(&m, &dyn_dofs, &dyn_dofs))
    }
}
