//! Euler-Bernoulli reference beam (thesis §2.1, §2.3, §2.4.4): closed-form static deflections and
//! a finite-difference discretisation of the dynamic beam equation.
//!
//! # Conventions
//! The undeformed beam has length L and lies along +y from y = 0; deflections z are along the z-axis.
//! Loads follow the thesis sign (docs/conventions.md): a point load F enters the energy as +F z, so a **positive
//! F deflects the beam toward −z** and its nodal force is −F.
//!
//! # Closed forms (eq. 2.4.5-2.4.7, with the docs/conventions.md errata applied)
//! [`static_cantilever`], [`static_fixed_fixed`] and [`static_pinned_pinned`]. The thesis prints
//! eq. 2.4.6/2.4.7 split at "y ≤ L" and the pinned-pinned formula with a + sign; the forms here split
//! at y ≤ L/2 and deflect toward −z for positive F in all three cases.
//!
//! # Finite differences (eq. 2.1.5 discretised as eq. 2.3.1)
//! [`EulerBernoulli`] discretises μ z̈ = −EI ∂⁴z/∂y⁴ + w on the nodes yᵢ = i d, i = 0..=n, d = L/n,
//! with the point masses m = μ d per node of the thesis, so each free node obeys
//!
//! m z̈ᵢ = −(EI/d³) (z_{i−2} − 4z_{i−1} + 6zᵢ − 4z_{i+1} + z_{i+2}) + fᵢ,   fᵢ = −Fᵢ,
//!
//! i.e. eq. 2.3.1 multiplied by d (w = f/d is the load per unit length). The end conditions use ghost
//! nodes outside the beam:
//!
//! | end | conditions | ghost nodes |
//! |-----|------------|-------------|
//! | clamped, y = 0 | z = 0, z′ = 0 | z₀ = 0, z₋₁ = z₁ |
//! | pinned, y = 0 | z = 0, z″ = 0 | z₀ = 0, z₋₁ = −z₁ |
//! | clamped, y = L | z = 0, z′ = 0 | zₙ = 0, z_{n+1} = z_{n−1} |
//! | pinned, y = L | z = 0, z″ = 0 | zₙ = 0, z_{n+1} = −z_{n−1} |
//! | free, y = L | z″ = 0 (no moment), z‴ = 0 (no shear) | z_{n+1} = 2zₙ − z_{n−1}, z_{n+2} = z_{n−2} − 4z_{n−1} + 4zₙ |
//!
//! The free-end ghosts come from the central differences z″(L) ≈ (z_{n+1} − 2zₙ + z_{n−1})/d² = 0
//! and z‴(L) ≈ (z_{n+2} − 2z_{n+1} + 2z_{n−1} − z_{n−2})/(2d³) = 0; both are exact for cubics.
//! Substituting them gives the free-end rows (in units of EI/d³)
//! row n−1: z_{n−3} − 4z_{n−2} + 5z_{n−1} − 2zₙ, row n: 2z_{n−2} − 4z_{n−1} + 2zₙ.
//!
//! **The thesis's free end was wrong** (§2.3.1, §2.4.4, Fig. 2.16: its static finite-difference
//! cantilever disagrees with eq. 2.4.5 and its dynamic one is too stiff). With the zero-moment and
//! zero-shear conditions above and the lumping below, the static solution converges to eq. 2.4.5 at
//! second order in d.
//!
//! ## Lumping at the free end (the choice made here)
//! The free tip node carries only half a cell, [L − d/2, L]. Its ghost-node row above is therefore the
//! balance of *twice* that half cell: dividing it by 2 gives the row (z_{n−2} − 2z_{n−1} + zₙ) EI/d³,
//! which makes the stiffness matrix symmetric (it is the Hessian of the trapezoidal bending energy
//! ½ EI Σ′ (Δ²zᵢ/d²)² d) and pairs it with the half-cell mass **m/2** at the tip. A point load at the tip
//! is a concentrated force (the shear condition EI z‴(L) = F of the continuous beam) and enters that
//! half-cell balance **in full**: f_n = −F. (Putting m and −F on the unhalved ghost row instead halves
//! the tip load, and the static tip deflection comes out at half of eq. 2.4.5.) Interior nodes and loads
//! are unchanged; supported nodes (z = 0) are not degrees of freedom.
//!
//! With this, the discrete system is M z̈ = −K z + f with K symmetric positive definite and M
//! diagonal, a linear Hamiltonian system with energy E = ½ żᵀM ż + ½ zᵀK z − fᵀz.

use std::ops::RangeInclusive;

use nalgebra::DMatrix;

mod error;

pub use error::EulerBernoulliError;

/// Static cantilever under a tip load F (thesis eq. 2.4.5):
///
/// z(y) = −F y² (3L − y) / (6 EI),   0 ≤ y ≤ L,
///
/// clamped at y = 0, free at y = L; the tip deflection is z(L) = −F L³/(3EI). Positive F deflects
/// toward −z (thesis sign).
///
/// The formula is evaluated as written: no argument is checked and nothing panics; y outside
/// [0, L] gives the polynomial's continuation and `ei = 0` gives ±∞ or NaN.
#[must_use]
pub fn static_cantilever(y: f64, force: f64, ei: f64, length: f64) -> f64 {
    -force * y * y * (3.0 * length - y) / (6.0 * ei)
}

/// Static fixed-fixed (clamped-clamped) beam under a central load F (thesis eq. 2.4.6, corrected per
/// docs/conventions.md to split at L/2):
///
/// z(y) = −F y² (3L − 4y) / (48 EI)   for y ≤ L/2,  mirrored z(y) = z(L − y) for y > L/2,
///
/// so the centre deflection is z(L/2) = −F L³/(192 EI). Positive F deflects toward −z.
///
/// The formula is evaluated as written: no argument is checked and nothing panics (see
/// [`static_cantilever`]).
#[must_use]
pub fn static_fixed_fixed(y: f64, force: f64, ei: f64, length: f64) -> f64 {
    let s = if y <= 0.5 * length { y } else { length - y };
    -force * s * s * (3.0 * length - 4.0 * s) / (48.0 * ei)
}

/// Static pinned-pinned (simply supported) beam under a central load F (thesis eq. 2.4.7, corrected
/// per docs/conventions.md: split at L/2 and the sign made the same as eq. 2.4.5/2.4.6):
///
/// z(y) = −F y (3L² − 4y²) / (48 EI)   for y ≤ L/2,  mirrored z(y) = z(L − y) for y > L/2,
///
/// so the centre deflection is z(L/2) = −F L³/(48 EI). Positive F deflects toward −z.
///
/// The formula is evaluated as written: no argument is checked and nothing panics (see
/// [`static_cantilever`]).
#[must_use]
pub fn static_pinned_pinned(y: f64, force: f64, ei: f64, length: f64) -> f64 {
    let s = if y <= 0.5 * length { y } else { length - y };
    -force * s * (3.0 * length * length - 4.0 * s * s) / (48.0 * ei)
}

/// End conditions of the finite-difference beam (thesis §2.4.1, Fig. 2.11).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum EbSupport {
    /// Clamped at y = 0 (z = z′ = 0), free at y = L (z″ = z‴ = 0): eq. 2.4.5's beam.
    Cantilever,
    /// Clamped at both ends (z = z′ = 0): eq. 2.4.6's beam.
    FixedFixed,
    /// Pinned at both ends (z = z″ = 0): eq. 2.4.7's beam.
    PinnedPinned,
}

/// A trajectory of the finite-difference beam from [`EulerBernoulli::simulate_states`].
#[derive(Clone, Debug, PartialEq)]
pub struct EbTrajectory {
    /// Time step h \[s\]; row k is the state at t_k = k h.
    pub step: f64,
    /// Node deflections z₀..zₙ \[m\] at each time (supported nodes are 0).
    pub z: Vec<Vec<f64>>,
    /// Node velocities ż₀..żₙ \[m/s\] at each time (supported nodes are 0).
    pub v: Vec<Vec<f64>>,
}

/// Finite-difference Euler-Bernoulli beam (thesis eq. 2.1.5 discretised as eq. 2.3.1), with the
/// ghost-node end conditions and the half-cell lumping at a free end described in the
/// [module documentation](self):
///
/// M z̈ = −K z + f,   K = (EI/d³)·(1, −4, 6, −4, 1)-stencil with boundary rows,   fᵢ = −Fᵢ.
///
/// The unknowns are the deflections of the free nodes ([`EulerBernoulli::free_nodes`]); K is stored
/// as a symmetric pentadiagonal band.
#[derive(Clone, Debug, PartialEq)]
pub struct EulerBernoulli {
    n: usize,
    length: f64,
    ei: f64,
    mass: f64,
    support: EbSupport,
    /// Nodal force fᵢ = −Σ Fᵢ on every node 0..=n (thesis sign applied).
    nodal_force: Vec<f64>,
    /// K_{j,j} over free dofs j (dof j is node j + 1).
    band0: Vec<f64>,
    /// K_{j,j+1}.
    band1: Vec<f64>,
    /// K_{j,j+2}.
    band2: Vec<f64>,
    /// Lumped masses of the free dofs.
    masses: Vec<f64>,
}

/// Largest number of segments [`EulerBernoulli::new`] accepts (a guard against absurd allocations;
/// the band storage is O(n)).
pub const MAX_SEGMENTS: usize = 10_000_000;

fn positive_finite(name: &'static str, value: f64) -> Result<(), EulerBernoulliError> {
    if value.is_finite() && value > 0.0 {
        Ok(())
    } else {
        Err(EulerBernoulliError::NotPositive { name, value })
    }
}

impl EulerBernoulli {
    /// Builds the finite-difference beam of eq. 2.3.1 with `n_segments` cells of width d = L/n
    /// (nodes 0..=n, node 0 at the base), flexural rigidity `ei` = EI, point mass `mass_per_node`
    /// = m = μ d at every free node (m/2 at a free tip, see the module documentation), the given
    /// `support` and point loads `(node, F)` with the thesis sign (nodal force −F; loads at the same
    /// node add up).
    ///
    /// # Errors
    /// [`EulerBernoulliError`] if `n_segments < 2` (the five-point stencil with its ghost nodes
    /// needs nodes 0..=2 at least) or `n_segments >` [`MAX_SEGMENTS`], if `length`, `ei` or
    /// `mass_per_node` is not positive and finite, if the stiffness scale EI/d³ overflows, if a load's
    /// node is outside 0..=n or is held by the support (z = 0 there, so the load would have no
    /// effect), or if a force (or the sum of the forces at a node) is not finite.
    pub fn new(
        n_segments: usize,
        length: f64,
        ei: f64,
        mass_per_node: f64,
        support: EbSupport,
        loads: &[(usize, f64)],
    ) -> Result<Self, EulerBernoulliError> {
        if n_segments < 2 {
            return Err(EulerBernoulliError::TooFewSegments { n_segments });
        }
        if n_segments > MAX_SEGMENTS {
            return Err(EulerBernoulliError::TooManySegments {
                n_segments,
                max: MAX_SEGMENTS,
            });
        }
        positive_finite("length", length)?;
        positive_finite("ei", ei)?;
        positive_finite("mass_per_node", mass_per_node)?;
        let n = n_segments;
        let d = length / n as f64;
        let scale = ei / (d * d * d);
        if !(scale.is_finite() && scale > 0.0 && (16.0 * scale / mass_per_node).is_finite()) {
            return Err(EulerBernoulliError::StiffnessScale { scale, d });
        }
        let last = match support {
            EbSupport::Cantilever => n,
            EbSupport::FixedFixed | EbSupport::PinnedPinned => n - 1,
        };
        let mut nodal_force = vec![0.0; n + 1];
        for &(node, force) in loads {
            if node > n {
                return Err(EulerBernoulliError::LoadNodeOutside { node, n });
            }
            if node == 0 || node > last {
                return Err(EulerBernoulliError::LoadNodeHeld {
                    node,
                    support,
                    last,
                });
            }
            if !force.is_finite() {
                return Err(EulerBernoulliError::NonFiniteForce { node, force });
            }
            nodal_force[node] -= force;
            if !nodal_force[node].is_finite() {
                return Err(EulerBernoulliError::NonFiniteForceSum { node });
            }
        }

        // Assemble the rows of the free nodes 1..=last by ghost-node substitution.
        let dofs = last; // dof j ↔ node j + 1
        let mut rows = vec![[0.0_f64; 5]; dofs]; // offsets −2..=2 in dof index
        const STENCIL: [f64; 5] = [1.0, -4.0, 6.0, -4.0, 1.0];
        for (j, row) in rows.iter_mut().enumerate() {
            let i = j + 1; // node
            for (o, &c) in STENCIL.iter().enumerate() {
                let idx = i as isize + o as isize - 2;
                for (node, coeff) in Self::resolve(idx, n, support) {
                    if node == 0 || node > last {
                        continue; // supported node: z = 0
                    }
                    // node − i ∈ −2..=2 for every substitution (checked by construction)
                    let off = node as isize - i as isize + 2;
                    row[off as usize] += c * coeff;
                }
            }
            if support == EbSupport::Cantilever && i == n {
                // half-cell balance at the free tip (see module docs)
                for v in row.iter_mut() {
                    *v *= 0.5;
                }
            }
        }
        let band0: Vec<f64> = rows.iter().map(|r| scale * r[2]).collect();
        let band1: Vec<f64> = rows.iter().map(|r| scale * r[3]).collect();
        let band2: Vec<f64> = rows.iter().map(|r| scale * r[4]).collect();
        debug_assert!((0..dofs).all(|j| {
            (j + 1 >= dofs || (rows[j][3] - rows[j + 1][1]).abs() < 1e-12)
                && (j + 2 >= dofs || (rows[j][4] - rows[j + 2][0]).abs() < 1e-12)
        }));
        let mut masses = vec![mass_per_node; dofs];
        if support == EbSupport::Cantilever {
            masses[dofs - 1] = 0.5 * mass_per_node;
        }
        Ok(Self {
            n,
            length,
            ei,
            mass: mass_per_node,
            support,
            nodal_force,
            band0,
            band1,
            band2,
            masses,
        })
    }

    /// Expresses the deflection at node index `idx` (possibly a ghost node, −1, n+1 or n+2) as a
    /// combination of real nodes, by the ghost-node formulas of the module documentation.
    fn resolve(idx: isize, n: usize, support: EbSupport) -> Vec<(usize, f64)> {
        let ni = n as isize;
        if (0..=ni).contains(&idx) {
            return vec![(idx as usize, 1.0)];
        }
        match (idx, support) {
            // base: clamped z₋₁ = z₁, pinned z₋₁ = −z₁
            (-1, EbSupport::Cantilever | EbSupport::FixedFixed) => vec![(1, 1.0)],
            (-1, EbSupport::PinnedPinned) => vec![(1, -1.0)],
            // tip: clamped z_{n+1} = z_{n−1}, pinned z_{n+1} = −z_{n−1}
            (i, EbSupport::FixedFixed) if i == ni + 1 => vec![(n - 1, 1.0)],
            (i, EbSupport::PinnedPinned) if i == ni + 1 => vec![(n - 1, -1.0)],
            // free: z_{n+1} = 2zₙ − z_{n−1}, z_{n+2} = z_{n−2} − 4z_{n−1} + 4zₙ
            (i, EbSupport::Cantilever) if i == ni + 1 => vec![(n, 2.0), (n - 1, -1.0)],
            (i, EbSupport::Cantilever) if i == ni + 2 => {
                vec![(n - 2, 1.0), (n - 1, -4.0), (n, 4.0)]
            }
            // never reached: rows exist only for free nodes, whose stencils reach these ghosts only
            _ => Vec::new(),
        }
    }

    /// Number of segments n (the nodes are 0..=n).
    #[must_use]
    pub fn n_segments(&self) -> usize {
        self.n
    }

    /// Beam length L \[m\].
    #[must_use]
    pub fn length(&self) -> f64 {
        self.length
    }

    /// Grid spacing d = L/n \[m\].
    #[must_use]
    pub fn spacing(&self) -> f64 {
        self.length / self.n as f64
    }

    /// Flexural rigidity EI \[Nm²\].
    #[must_use]
    pub fn ei(&self) -> f64 {
        self.ei
    }

    /// Point mass m per node \[kg\] as given (the free tip carries m/2, see [`Self::lumped_masses`]).
    #[must_use]
    pub fn mass_per_node(&self) -> f64 {
        self.mass
    }

    /// End conditions.
    #[must_use]
    pub fn support(&self) -> EbSupport {
        self.support
    }

    /// The free nodes, whose deflections are the unknowns: 1..=n for the cantilever, 1..=n−1 for
    /// fixed-fixed and pinned-pinned. Row/column j of [`Self::stiffness_matrix`] is node j + 1.
    #[must_use]
    pub fn free_nodes(&self) -> RangeInclusive<usize> {
        1..=self.band0.len()
    }

    /// Node positions yᵢ = i d, i = 0..=n \[m\].
    #[must_use]
    pub fn node_positions(&self) -> Vec<f64> {
        let d = self.spacing();
        (0..=self.n).map(|i| i as f64 * d).collect()
    }

    /// Diagonal of the lumped mass matrix M over the free nodes: m everywhere, m/2 at a free tip
    /// (half cell, see the module documentation).
    #[must_use]
    pub fn lumped_masses(&self) -> Vec<f64> {
        self.masses.clone()
    }

    /// Nodal load vector f over the free nodes, fᵢ = −Σ Fᵢ (thesis sign: eq. 2.1.3's work term with
    /// +F z in the energy).
    #[must_use]
    pub fn load_vector(&self) -> Vec<f64> {
        self.nodal_force[self.free_nodes()].to_vec()
    }

    /// Stiffness matrix K over the free nodes (eq. 2.3.1 times d: (EI/d³)·(1, −4, 6, −4, 1) in the
    /// interior, ghost-node rows at the ends, the free-tip row halved), as a dense symmetric positive
    /// definite matrix. It is pentadiagonal; the solvers here use the band, this dense copy is for
    /// inspection.
    #[must_use]
    pub fn stiffness_matrix(&self) -> DMatrix<f64> {
        let m = self.band0.len();
        DMatrix::from_fn(m, m, |j, c| self.k_entry(j, c))
    }

    /// K x over the free dofs, using the band.
    fn apply_k(&self, x: &[f64], out: &mut [f64]) {
        let m = x.len();
        for j in 0..m {
            let mut s = self.band0[j] * x[j];
            if j + 1 < m {
                s += self.band1[j] * x[j + 1];
            }
            if j + 2 < m {
                s += self.band2[j] * x[j + 2];
            }
            if j >= 1 {
                s += self.band1[j - 1] * x[j - 1];
            }
            if j >= 2 {
                s += self.band2[j - 2] * x[j - 2];
            }
            out[j] = s;
        }
    }

    /// Static deflections z₀..zₙ solving K z = f (the static equation 2.1.4 discretised,
    /// EI Δ⁴z/d⁴ = w), supported nodes 0.
    ///
    /// Direct solve by a banded Cholesky factorisation K = L Lᵀ (bandwidth 2, O(n) work and memory);
    /// K is symmetric positive definite for all three supports.
    #[must_use]
    pub fn static_solution(&self) -> Vec<f64> {
        let m = self.band0.len();
        // L has diagonal l0, first subdiagonal l1 (l1[j] = L[j][j−1]), second l2 (L[j][j−2]).
        let mut l0 = vec![0.0; m];
        let mut l1 = vec![0.0; m];
        let mut l2 = vec![0.0; m];
        for j in 0..m {
            if j >= 2 {
                l2[j] = self.band2[j - 2] / l0[j - 2];
            }
            if j >= 1 {
                let prod = if j >= 2 { l2[j] * l1[j - 1] } else { 0.0 };
                l1[j] = (self.band1[j - 1] - prod) / l0[j - 1];
            }
            let piv = self.band0[j] - l1[j] * l1[j] - l2[j] * l2[j];
            l0[j] = piv.sqrt();
        }
        let f = self.load_vector();
        // forward: L y = f
        let mut y = vec![0.0; m];
        for j in 0..m {
            let mut s = f[j];
            if j >= 1 {
                s -= l1[j] * y[j - 1];
            }
            if j >= 2 {
                s -= l2[j] * y[j - 2];
            }
            y[j] = s / l0[j];
        }
        // backward: Lᵀ x = y
        let mut x = vec![0.0; m];
        for j in (0..m).rev() {
            let mut s = y[j];
            if j + 1 < m {
                s -= l1[j + 1] * x[j + 1];
            }
            if j + 2 < m {
                s -= l2[j + 2] * x[j + 2];
            }
            x[j] = s / l0[j];
        }
        self.to_nodes(&x)
    }

    /// Free-dof vector → all nodes 0..=n (supported nodes 0).
    fn to_nodes(&self, x: &[f64]) -> Vec<f64> {
        let mut z = vec![0.0; self.n + 1];
        z[self.free_nodes()].copy_from_slice(x);
        z
    }

    /// Upper bound on λ_max, the largest eigenvalue of M⁻¹K (the largest squared angular frequency
    /// ω² of the discrete beam), by Gershgorin's theorem applied to the similar symmetric matrix
    /// M^{−1/2} K M^{−1/2}: λ_max ≤ maxⱼ Σₖ |K_{jk}| / √(mⱼ mₖ). In the interior this is
    /// 16 EI/(m d³), which the true λ_max approaches as n grows, so the bound is nearly sharp.
    #[must_use]
    pub fn max_eigenvalue_bound(&self) -> f64 {
        let m = self.band0.len();
        (0..m)
            .map(|j| {
                let lo = j.saturating_sub(2);
                let hi = (j + 2).min(m - 1);
                (lo..=hi)
                    .map(|c| self.k_entry(j, c).abs() / (self.masses[j] * self.masses[c]).sqrt())
                    .sum::<f64>()
            })
            .fold(0.0, f64::max)
    }

    /// K_{jc} from the band (0 outside it).
    fn k_entry(&self, j: usize, c: usize) -> f64 {
        let (a, b) = if j <= c { (j, c) } else { (c, j) };
        match b - a {
            0 => self.band0[a],
            1 => self.band1[a],
            2 => self.band2[a],
            _ => 0.0,
        }
    }

    /// Largest step accepted by [`Self::simulate`]: Störmer–Verlet on M z̈ = −K z + f is stable
    /// for h < 2/√λ_max (each mode ω is stable iff h ω < 2); this returns 2/√λ̄ with λ̄ the
    /// Gershgorin bound [`Self::max_eigenvalue_bound`] ≥ λ_max, a sufficient (slightly conservative)
    /// limit.
    #[must_use]
    pub fn stability_limit(&self) -> f64 {
        2.0 / self.max_eigenvalue_bound().sqrt()
    }

    /// Energy of the discrete system (a linear Hamiltonian system):
    ///
    /// E = ½ żᵀ M ż + ½ zᵀ K z − fᵀ z,
    ///
    /// kinetic + bending (eq. 2.1.2, trapezoidal) + load potential (eq. 2.1.3's −F z term in the
    /// thesis sign, +F z). `z` and `v` hold all nodes 0..=n; the entries of supported nodes are
    /// ignored.
    ///
    /// # Errors
    /// [`EulerBernoulliError`] if `z` or `v` does not have n + 1 entries.
    pub fn energy(&self, z: &[f64], v: &[f64]) -> Result<f64, EulerBernoulliError> {
        for (name, x) in [("z", z), ("v", v)] {
            if x.len() != self.n + 1 {
                return Err(EulerBernoulliError::WrongNodeCount {
                    name,
                    expected: self.n + 1,
                    got: x.len(),
                });
            }
        }
        let zf = &z[self.free_nodes()];
        let vf = &v[self.free_nodes()];
        let mut kz = vec![0.0; zf.len()];
        self.apply_k(zf, &mut kz);
        let f = &self.nodal_force[self.free_nodes()];
        let e = (0..zf.len())
            .map(|j| 0.5 * self.masses[j] * vf[j] * vf[j] + 0.5 * zf[j] * kz[j] - f[j] * zf[j])
            .sum();
        Ok(e)
    }

    /// Time integration of M z̈ = −K z + f (eq. 2.3.1) from rest at z = 0 with the loads switched on
    /// at t = 0, by the Störmer–Verlet (velocity Verlet, leapfrog) method, explicit, symplectic and
    /// second order:
    ///
    /// v_{k+½} = v_k + (h/2) M⁻¹(f − K z_k),  z_{k+1} = z_k + h v_{k+½},
    /// v_{k+1} = v_{k+½} + (h/2) M⁻¹(f − K z_{k+1}).
    ///
    /// Returns the node deflections z₀..zₙ at t_k = k h, k = 0..=`steps` (`steps` + 1 rows).
    ///
    /// # Errors
    /// [`EulerBernoulliError`] if `h` is not positive and finite, if h ≥ [`Self::stability_limit`]
    /// (the method is unstable for h ≥ 2/√λ_max), or if `steps` + 1 rows cannot be allocated.
    pub fn simulate(&self, h: f64, steps: usize) -> Result<Vec<Vec<f64>>, EulerBernoulliError> {
        Ok(self.integrate(h, steps, false)?.0)
    }

    /// As [`Self::simulate`], also returning the velocities (for instance to evaluate
    /// [`Self::energy`], which Störmer–Verlet conserves up to O(h²) without drift).
    ///
    /// # Errors
    /// As [`Self::simulate`].
    pub fn simulate_states(
        &self,
        h: f64,
        steps: usize,
    ) -> Result<EbTrajectory, EulerBernoulliError> {
        let (z, v) = self.integrate(h, steps, true)?;
        Ok(EbTrajectory { step: h, z, v })
    }

    #[allow(clippy::type_complexity)]
    fn integrate(
        &self,
        h: f64,
        steps: usize,
        keep_v: bool,
    ) -> Result<(Vec<Vec<f64>>, Vec<Vec<f64>>), EulerBernoulliError> {
        positive_finite("h", h)?;
        let limit = self.stability_limit();
        if h >= limit {
            return Err(EulerBernoulliError::Unstable {
                h,
                limit,
                lambda_max: self.max_eigenvalue_bound(),
            });
        }
        let rows = steps
            .checked_add(1)
            .ok_or(EulerBernoulliError::StepsOverflow { steps })?;
        let too_many = |_| EulerBernoulliError::RowsNotAllocated { rows };
        let mut zs: Vec<Vec<f64>> = Vec::new();
        zs.try_reserve_exact(rows).map_err(too_many)?;
        let mut vs: Vec<Vec<f64>> = Vec::new();
        if keep_v {
            vs.try_reserve_exact(rows).map_err(too_many)?;
        }

        let m = self.band0.len();
        let f = self.load_vector();
        let mut z = vec![0.0; m];
        let mut v = vec![0.0; m];
        let mut kz = vec![0.0; m];
        let accel = |kz: &[f64], a: &mut [f64]| {
            for j in 0..m {
                a[j] = (f[j] - kz[j]) / self.masses[j];
            }
        };
        let mut a = vec![0.0; m];
        self.apply_k(&z, &mut kz);
        accel(&kz, &mut a);
        zs.push(self.to_nodes(&z));
        if keep_v {
            vs.push(self.to_nodes(&v));
        }
        for _ in 0..steps {
            for j in 0..m {
                v[j] += 0.5 * h * a[j];
                z[j] += h * v[j];
            }
            self.apply_k(&z, &mut kz);
            accel(&kz, &mut a);
            for j in 0..m {
                v[j] += 0.5 * h * a[j];
            }
            zs.push(self.to_nodes(&z));
            if keep_v {
                vs.push(self.to_nodes(&v));
            }
        }
        Ok((zs, vs))
    }
}
