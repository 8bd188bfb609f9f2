//! The chain-of-pendulums model (thesis §2.2, §2.4, §3.1, §3.2; SPEC §1), written once over
//! [`Scalar`] so that the same terms evaluate in `f64` and in dual arithmetic.
//!
//! The configuration is q = (q₁, …, qₙ) with qᵢ ∈ S^{DIM−1} ⊂ ℝ^DIM. `DIM = 2` is the planar model
//! (components (y, z), qᵢ ∈ S¹ in the yz-plane) and `DIM = 3` the spatial one (components
//! (x, y, z), qᵢ ∈ S²). Every load of the thesis acts along z and the beam starts straight along
//! +y, so x stays exactly 0 in the spatial model; the planar model therefore reproduces it exactly
//! (tested to 0 difference in `tests/core.rs`) while storing and computing two components instead
//! of three. The step's cost is dominated by the per-joint scalar work (spring function, Newton
//! and projection solves), so the measured saving is modest: 3D/2D ≈ 1.08 at n = 100
//! (`cargo bench --bench step -- step_dim`).

use crate::error::{Error, Result};
use crate::scene::{Scene, Support};
use num_dual::DualNum;

/// The scalar type every model term is written over: `f64`, `Dual64`, `DualSVec64<N>`, … .
///
/// This is `num_dual::DualNum<Primitive = f64> + Copy` with the thread-safety bounds the
/// multistart code needs; it is implemented for every such type.
pub trait Scalar: DualNum<Primitive = f64> + Copy + Send + Sync + 'static {}
impl<T: DualNum<Primitive = f64> + Copy + Send + Sync + 'static> Scalar for T {}

/// Whether `D` carries derivative parts. A dual number is larger than its `f64` real part, so the
/// size decides it at compile time. Newton iterations use it to apply one final update after the
/// real part has converged, so that derivative parts converge too (Newton on dual numbers is
/// linearly, not quadratically, convergent in the derivative parts).
#[inline]
pub(crate) fn carries_derivatives<D>() -> bool {
    std::mem::size_of::<D>() > std::mem::size_of::<f64>()
}

/// Index of the z component in a `DIM`-vector (planar: 1, spatial: 2).
#[inline]
pub const fn zi<const DIM: usize>() -> usize {
    DIM - 1
}

/// Index of the y component in a `DIM`-vector.
#[inline]
pub const fn yi<const DIM: usize>() -> usize {
    DIM - 2
}

/// The undeformed direction e₂ = (0, 1, 0) (planar: (1, 0)).
#[inline]
pub(crate) fn e2<D: Scalar, const DIM: usize>() -> [D; DIM] {
    let mut v = [D::zero(); DIM];
    v[yi::<DIM>()] = D::one();
    v
}

/// Dot product.
#[inline]
pub(crate) fn dot<D: Scalar, const DIM: usize>(a: &[D; DIM], b: &[D; DIM]) -> D {
    let mut s = a[0] * b[0];
    for i in 1..DIM {
        s += a[i] * b[i];
    }
    s
}

/// ‖a × b‖², computed from the cross product's components (exact to relative precision even
/// when a ∥ b, unlike ‖a‖²‖b‖² − (a·b)²).
#[inline]
pub(crate) fn cross_norm2<D: Scalar, const DIM: usize>(a: &[D; DIM], b: &[D; DIM]) -> D {
    if DIM == 2 {
        let c = a[0] * b[1] - a[1] * b[0];
        c * c
    } else {
        let cx = a[1] * b[2] - a[2] * b[1];
        let cy = a[2] * b[0] - a[0] * b[2];
        let cz = a[0] * b[1] - a[1] * b[0];
        cx * cx + cy * cy + cz * cz
    }
}

/// Below this w = (1 − x)/2 the series of [`spring_s`] is used (θ ≲ 11.5°); 10 terms give
/// round-off accuracy there (c₁₀ w¹⁰ < 3·10⁻²¹).
const S_SERIES_MAX_W: f64 = 0.01;

/// Taylor coefficients of s around x = 1 in w = (1 − x)/2: c_k = 4ᵏ(k!)²/(2k+1)!, i.e.
/// c_k = c_{k−1}·2k/(2k+1).
const C: [f64; 10] = [
    1.0,
    2.0 / 3.0,
    8.0 / 15.0,
    16.0 / 35.0,
    128.0 / 315.0,
    256.0 / 693.0,
    1024.0 / 3003.0,
    2048.0 / 6435.0,
    32768.0 / 109395.0,
    65536.0 / 230945.0,
];

/// s(x) = arccos(x)/√(1 − x²) = θ/sin θ with x = cos θ (thesis eq. 2.2.1 and the line before it).
///
/// s is analytic at x = 1 (θ/sin θ is even in θ, hence analytic in cos θ): near x = 1 it is
/// evaluated by its Taylor series s = Σₖ cₖ wᵏ, w = (1 − x)/2, cₖ = 4ᵏ(k!)²/(2k+1)!, so that the
/// value and all its derivatives, in dual arithmetic too, are finite and exact at the straight
/// configuration (s(1) = 1, s'(1) = −1/3). The series also covers x slightly above 1 (round-off).
#[inline]
pub fn spring_s<D: Scalar>(x: D) -> D {
    let w = (-x + 1.0) * 0.5;
    if w.re() <= S_SERIES_MAX_W {
        // Horner on c_k, c_k = c_{k-1} * 2k/(2k+1).
        let mut s = D::from(C[9]);
        for &c in C[..9].iter().rev() {
            s = s * w + c;
        }
        s
    } else {
        x.acos() * (-(x * x) + 1.0).sqrt().recip()
    }
}

/// s(x) and s′(x) together (for Jacobian products of the spring force, eq. 2.2.3 differentiated).
/// Near x = 1 both come from the series of [`spring_s`] (s′(1) = −1/3); elsewhere
/// s′ = (x s − 1)/(1 − x²).
#[inline]
pub fn spring_s_ds<D: Scalar>(x: D) -> (D, D) {
    let w = (-x + 1.0) * 0.5;
    if w.re() <= S_SERIES_MAX_W {
        let mut s = D::from(C[9]);
        for &c in C[..9].iter().rev() {
            s = s * w + c;
        }
        // ds/dw = Σ k c_k w^{k−1} (the exact derivative of the same polynomial); dw/dx = −1/2
        let mut ds = D::from(9.0 * C[9]);
        for k in (1..9).rev() {
            ds = ds * w + (k as f64) * C[k];
        }
        (s, ds * (-0.5))
    } else {
        let s = x.acos() * (-(x * x) + 1.0).sqrt().recip();
        let ds = (x * s - 1.0) * (-(x * x) + 1.0).recip();
        (s, ds)
    }
}

/// The squared joint angle θ² = ∠(a, b)² of two unit vectors, accurate at small and large angles
/// and differentiable at θ = 0 (used for the spring energy ½ k θ², eq. 2.2.2).
///
/// For a·b > 0, θ = arcsin(‖a×b‖) and θ² = y A(y)², y = ‖a×b‖², A(y) = arcsin(√y)/√y, which is
/// analytic in y (series near 0). For a·b ≤ 0, θ = atan2(‖a×b‖, a·b).
pub fn joint_angle_squared<D: Scalar, const DIM: usize>(a: &[D; DIM], b: &[D; DIM]) -> D {
    let x = dot(a, b);
    let y = cross_norm2(a, b);
    if x.re() > 0.0 {
        let amp = if y.re() <= 0.01 {
            // a_k = a_{k-1} (2k-1)^2 / (2k (2k+1)).
            const A: [f64; 10] = [
                1.0,
                1.0 / 6.0,
                3.0 / 40.0,
                5.0 / 112.0,
                35.0 / 1152.0,
                63.0 / 2816.0,
                231.0 / 13312.0,
                143.0 / 10240.0,
                6435.0 / 557056.0,
                12155.0 / 1245184.0,
            ];
            let mut s = D::from(A[9]);
            for &c in A[..9].iter().rev() {
                s = s * y + c;
            }
            s
        } else {
            let r = y.sqrt();
            r.asin() * r.recip()
        };
        y * amp * amp
    } else {
        let th = y.sqrt().atan2(x);
        th * th
    }
}

/// What holds the tip's z coordinate.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum TipCondition {
    /// The tip is free (cantilever, riser).
    Free,
    /// The tip's z is locked by l(q) = Σ lᵢ e₃ᵀqᵢ = 0 (fixed-fixed, pinned-pinned; eq. 2.4.1).
    Locked,
    /// Reaction-force variant (eq. 3.2.1/3.2.2): the reaction λ_l cancels every force on the tip's
    /// z except the control, so m_n z̈_n = −u. Discretised as a rheonomic tip constraint
    /// l(q_k) = ζ_k whose target ζ follows the control by Störmer–Verlet (see [`crate::rattle`]).
    Reaction,
}

/// A physical parameter of the chain, for parameter derivatives (seeded with dual numbers or
/// differentiated by the adjoint).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Parameter {
    /// All interior spring constants k₂..kₙ, set to one common value.
    InteriorStiffness,
    /// The base spring k₁ (also the k₁ of the bending moment, eq. 3.1.3).
    BaseStiffness,
    /// The tip spring k_{n+1}.
    TipStiffness,
    /// All masses m₁..mₙ, set to one common value.
    Mass,
    /// The drag constant D (eq. 2.4.4).
    Drag,
    /// The magnitude of the `i`-th point load of the scene (0-based, in scene order).
    LoadForce(usize),
}

/// A point load as the model uses it.
#[derive(Clone, Debug)]
pub(crate) struct LoadTerm<D> {
    /// Node 1..=n.
    pub node: usize,
    pub force: D,
    pub start: f64,
    pub end: f64,
    /// Index in the scene's list (for [`Parameter::LoadForce`]).
    pub scene_index: usize,
}

/// The chain of pendulums: parameters and the model terms of SPEC §1, generic over the scalar
/// `D` and the dimension `DIM` (2: planar, 3: spatial).
#[derive(Clone, Debug)]
pub struct Chain<D, const DIM: usize> {
    pub(crate) n: usize,
    pub(crate) lengths: Vec<D>,
    pub(crate) masses: Vec<D>,
    pub(crate) inv_lengths: Vec<D>,
    pub(crate) inv_masses: Vec<D>,
    /// k₁..k_{n+1} (index 0..=n); zero where the support has no spring.
    pub(crate) springs: Vec<D>,
    /// Which of k₁..k_{n+1} exist structurally (computed only where true).
    pub(crate) has_spring: Vec<bool>,
    /// The base spring of the bending moment M₀ = 2 k₁ z₁ / l₁² (eq. 3.1.3).
    pub(crate) moment_stiffness: D,
    pub(crate) tip: TipCondition,
    /// Sorted by node, descending.
    pub(crate) loads: Vec<LoadTerm<D>>,
    pub(crate) gravity: Option<D>,
    pub(crate) drag: Option<D>,
    pub(crate) control_node: Option<usize>,
    /// cos of the fold limit: a joint with cos θ below it is an error.
    pub(crate) fold_cos: f64,
}

/// Default fold limit: a joint angle of 179° (s = θ/sin θ ≈ 180) is treated as a folded beam.
pub const DEFAULT_FOLD_LIMIT_DEG: f64 = 179.0;

impl<D: Scalar, const DIM: usize> Chain<D, DIM> {
    /// Builds the model of a scene (validating it first). The control node is taken from the
    /// scene's `[control]` (default: none, so no control term is computed).
    pub fn from_scene(scene: &Scene) -> Result<Self> {
        scene.validate()?;
        let n = scene.n();
        let b = &scene.beam;
        let lift = |v: &[f64]| v.iter().map(|&x| D::from(x)).collect::<Vec<D>>();
        let mut springs = vec![D::zero(); n + 1];
        let mut has_spring = vec![false; n + 1];
        for i in 1..n {
            springs[i] = D::from(b.stiffness[i - 1]);
            has_spring[i] = true;
        }
        let (base, tip_spring) = match b.support {
            Support::Cantilever => (true, false),
            Support::Riser => (true, true),
            Support::FixedFixed => (true, true),
            Support::PinnedPinned => (false, false),
        };
        if base {
            springs[0] = D::from(b.base_stiffness);
            has_spring[0] = true;
        }
        if tip_spring {
            springs[n] = D::from(b.tip_stiffness);
            has_spring[n] = true;
        }
        let tip = match (b.support, b.reaction_force) {
            (Support::FixedFixed | Support::PinnedPinned, false) => TipCondition::Locked,
            (Support::FixedFixed | Support::PinnedPinned, true) => TipCondition::Reaction,
            _ => TipCondition::Free,
        };
        let mut loads: Vec<LoadTerm<D>> = scene
            .loads
            .points
            .iter()
            .enumerate()
            .map(|(i, pl)| LoadTerm {
                node: pl.node,
                force: D::from(pl.force),
                start: pl.start,
                end: pl.end.unwrap_or(f64::INFINITY),
                scene_index: i,
            })
            .collect();
        loads.sort_by_key(|l| std::cmp::Reverse(l.node));
        let control_node = scene.control.as_ref().map(|c| c.node);
        if tip == TipCondition::Reaction {
            if let Some(c) = control_node {
                if c != n {
                    return Err(Error::InvalidArgument {
                        name: "control.node",
                        reason: format!(
                            "the reaction-force variant moves the tip: the control must act at \
                             node {n}, not {c}"
                        ),
                    });
                }
            }
        }
        let lengths = lift(&b.lengths);
        let masses = lift(&b.masses);
        let mut chain = Chain {
            n,
            inv_lengths: lengths.iter().map(|l| l.recip()).collect(),
            inv_masses: masses.iter().map(|m| m.recip()).collect(),
            lengths,
            masses,
            springs,
            has_spring,
            moment_stiffness: D::from(if base { b.base_stiffness } else { 0.0 }),
            tip,
            loads,
            gravity: (scene.loads.gravity != 0.0).then(|| D::from(scene.loads.gravity)),
            drag: (scene.loads.drag > 0.0).then(|| D::from(scene.loads.drag)),
            control_node,
            fold_cos: DEFAULT_FOLD_LIMIT_DEG.to_radians().cos(),
        };
        chain.refresh_inverses();
        Ok(chain)
    }

    fn refresh_inverses(&mut self) {
        for i in 0..self.n {
            self.inv_lengths[i] = self.lengths[i].recip();
            self.inv_masses[i] = self.masses[i].recip();
        }
    }

    /// The same model over another scalar type (parameters lifted with `D2::from`).
    pub fn lift<D2: Scalar>(&self) -> Chain<D2, DIM> {
        let l = |v: &[D]| v.iter().map(|x| D2::from(x.re())).collect::<Vec<D2>>();
        Chain {
            n: self.n,
            lengths: l(&self.lengths),
            masses: l(&self.masses),
            inv_lengths: l(&self.inv_lengths),
            inv_masses: l(&self.inv_masses),
            springs: l(&self.springs),
            has_spring: self.has_spring.clone(),
            moment_stiffness: D2::from(self.moment_stiffness.re()),
            tip: self.tip,
            loads: self
                .loads
                .iter()
                .map(|t| LoadTerm {
                    node: t.node,
                    force: D2::from(t.force.re()),
                    start: t.start,
                    end: t.end,
                    scene_index: t.scene_index,
                })
                .collect(),
            gravity: self.gravity.map(|g| D2::from(g.re())),
            drag: self.drag.map(|g| D2::from(g.re())),
            control_node: self.control_node,
            fold_cos: self.fold_cos,
        }
    }

    /// Number of pendulums n.
    pub fn n(&self) -> usize {
        self.n
    }

    /// What holds the tip.
    pub fn tip_condition(&self) -> TipCondition {
        self.tip
    }

    /// Whether the model has the tip constraint row (locked or reaction-force tip).
    pub fn has_tip_constraint(&self) -> bool {
        self.tip != TipCondition::Free
    }

    /// Number of constraint multipliers: n length constraints, plus one for the tip.
    pub fn n_constraints(&self) -> usize {
        self.n + usize::from(self.has_tip_constraint())
    }

    /// Whether the model computes drag.
    pub fn has_drag(&self) -> bool {
        self.drag.is_some()
    }

    /// The control node, if the model has a control.
    pub fn control_node(&self) -> Option<usize> {
        self.control_node
    }

    /// Sets (or removes) the node the control acts at (1..=n).
    pub fn set_control_node(&mut self, node: Option<usize>) -> Result<()> {
        if let Some(c) = node {
            if c == 0 || c > self.n {
                return Err(Error::InvalidArgument {
                    name: "control node",
                    reason: format!("must be in 1..={}, got {c}", self.n),
                });
            }
        }
        self.control_node = node;
        Ok(())
    }

    /// Sets the fold limit in degrees (default [`DEFAULT_FOLD_LIMIT_DEG`]): a joint angle beyond
    /// it is reported as [`Error::Folded`].
    pub fn set_fold_limit_deg(&mut self, deg: f64) -> Result<()> {
        if !(deg > 0.0 && deg < 180.0) {
            return Err(Error::InvalidArgument {
                name: "fold limit",
                reason: format!("must be in (0, 180) degrees, got {deg}"),
            });
        }
        self.fold_cos = deg.to_radians().cos();
        Ok(())
    }

    /// Sets a physical parameter (see [`Parameter`]); seed it with a dual number to obtain
    /// forward-mode derivatives of a whole simulation with respect to it.
    pub fn set_parameter(&mut self, p: Parameter, value: D) -> Result<()> {
        let n = self.n;
        match p {
            Parameter::InteriorStiffness => (1..n).for_each(|i| self.springs[i] = value),
            Parameter::BaseStiffness => {
                if !self.has_spring[0] {
                    return Err(self.no_param("base stiffness", "the support has no base spring"));
                }
                self.springs[0] = value;
                self.moment_stiffness = value;
            }
            Parameter::TipStiffness => {
                if !self.has_spring[n] {
                    return Err(self.no_param("tip stiffness", "the support has no tip spring"));
                }
                self.springs[n] = value;
            }
            Parameter::Mass => {
                self.masses.iter_mut().for_each(|m| *m = value);
                self.refresh_inverses();
            }
            Parameter::Drag => {
                if self.drag.is_none() {
                    return Err(self.no_param("drag", "the scene has no drag (D = 0)"));
                }
                self.drag = Some(value);
            }
            Parameter::LoadForce(i) => {
                let l = self.loads.iter_mut().find(|l| l.scene_index == i);
                match l {
                    Some(l) => l.force = value,
                    None => return Err(self.no_param("load force", "no such point load")),
                }
            }
        }
        Ok(())
    }

    fn no_param(&self, name: &'static str, reason: &str) -> Error {
        Error::InvalidArgument {
            name,
            reason: reason.to_string(),
        }
    }

    /// Applies M⁻¹ = M̄⁻¹ ⊗ I in O(n): M̄⁻¹ = diag(1/l) Δ diag(1/m) Δᵀ diag(1/l) with Δ the
    /// lower-bidiagonal difference matrix (SPEC §1). `out` may not alias `v`.
    #[inline]
    pub fn apply_inverse_mass(&self, v: &[[D; DIM]], out: &mut [[D; DIM]]) {
        let n = self.n;
        // u = diag(1/m) Δᵀ diag(1/l) v, stored in out; then out = diag(1/l) Δ u.
        let mut next = [D::zero(); DIM];
        for i in (0..n).rev() {
            let mut cur = v[i];
            for c in cur.iter_mut() {
                *c *= self.inv_lengths[i];
            }
            for d in 0..DIM {
                out[i][d] = (cur[d] - next[d]) * self.inv_masses[i];
            }
            next = cur;
        }
        let mut prev = [D::zero(); DIM];
        for i in 0..n {
            let cur = out[i];
            for d in 0..DIM {
                out[i][d] = (cur[d] - prev[d]) * self.inv_lengths[i];
            }
            prev = cur;
        }
    }

    /// The tridiagonal entries of M̄⁻¹ in row i (0-based): `(diag_i, off_i)` with
    /// off_i = M̄⁻¹_{i,i+1} = −1/(lᵢ l_{i+1} mᵢ) and M̄⁻¹_{ii} = (1/lᵢ²)(1/mᵢ + 1/m_{i−1}) (no
    /// m₀ term for the first pendulum). From M̄⁻¹ = diag(1/l) Δ diag(1/m) Δᵀ diag(1/l).
    #[inline]
    pub(crate) fn minv_entries(&self, i: usize) -> (D, D) {
        let li = self.inv_lengths[i];
        let mi = self.inv_masses[i];
        let d = if i > 0 {
            li * li * (mi + self.inv_masses[i - 1])
        } else {
            li * li * mi
        };
        let off = if i + 1 < self.n {
            -(li * self.inv_lengths[i + 1] * mi)
        } else {
            D::zero()
        };
        (d, off)
    }

    /// The generalised load coefficient of pendulum j at time t with control u:
    /// c_j = Σ_{k ≥ j} F_k(t) + g Σ_{i ≥ j} m_i + u [j ≤ c], so that the load, gravity and control
    /// terms of U contribute l_j c_j e₃ to ∂U/∂q_j (eq. 2.2.3, §2.2.2, eq. 3.1.1 with 2.2.2's form).
    /// Calls `f(j, c_j)` for each j = n..1 (0-based j).
    #[inline]
    pub(crate) fn for_each_load_coefficient(&self, t: f64, u: D, mut f: impl FnMut(usize, D)) {
        let tol = 1e-9 * t.abs().max(1.0);
        let mut acc = D::zero();
        let mut li = 0;
        for j in (0..self.n).rev() {
            while li < self.loads.len() && self.loads[li].node == j + 1 {
                let l = &self.loads[li];
                if t + tol >= l.start && t + tol < l.end {
                    acc += l.force;
                }
                li += 1;
            }
            if let Some(g) = self.gravity {
                acc += g * self.masses[j];
            }
            let cj = match self.control_node {
                Some(c) if j < c => acc + u,
                _ => acc,
            };
            f(j, cj);
        }
    }

    /// Whether any load, gravity or control term is present.
    #[inline]
    fn has_load_terms(&self) -> bool {
        !self.loads.is_empty() || self.gravity.is_some() || self.control_node.is_some()
    }

    /// ∂U/∂q at time t with control u (eq. 2.2.3 extended with tip spring, gravity and control):
    /// the spring part −k_i s(q_{i−1}ᵀqᵢ)(q_{i−1} on block i, qᵢ on block i−1) with q₀ = q_{n+1} = e₂,
    /// plus l_j c_j e₃ on block j. Only terms the scene has are computed. A joint beyond the fold
    /// limit gives [`Error::Folded`] (with `step` = `step`).
    pub fn potential_gradient(
        &self,
        q: &[[D; DIM]],
        t: f64,
        u: D,
        step: usize,
        out: &mut [[D; DIM]],
    ) -> Result<()> {
        let n = self.n;
        for o in out.iter_mut() {
            *o = [D::zero(); DIM];
        }
        let e = e2::<D, DIM>();
        for i in 0..=n {
            if !self.has_spring[i] {
                continue;
            }
            let a = if i == 0 { &e } else { &q[i - 1] };
            let b = if i == n { &e } else { &q[i] };
            let x = dot(a, b);
            if x.re() < self.fold_cos {
                return Err(self.folded(step, i, a, b));
            }
            let ks = self.springs[i] * spring_s(x);
            if i > 0 {
                for d in 0..DIM {
                    out[i - 1][d] -= ks * b[d];
                }
            }
            if i < n {
                for d in 0..DIM {
                    out[i][d] -= ks * a[d];
                }
            }
        }
        if self.has_load_terms() {
            let z = zi::<DIM>();
            self.for_each_load_coefficient(t, u, |j, c| {
                out[j][z] += self.lengths[j] * c;
            });
        }
        Ok(())
    }

    /// The product K w of the force Jacobian K = ∂(∂U/∂q)/∂q (symmetric, block-tridiagonal: only
    /// the springs depend on q) with a vector w, accumulated into `out` with factor `scale`:
    /// for the spring between a and b (x = a·b), with σ = b·w_a + a·w_b,
    /// (K w)_a = −k [s w_b + s′ σ b], (K w)_b = −k [s w_a + s′ σ a].
    pub fn force_jacobian_product(
        &self,
        q: &[[D; DIM]],
        w: &[[D; DIM]],
        scale: D,
        out: &mut [[D; DIM]],
    ) {
        let n = self.n;
        let e = e2::<D, DIM>();
        let zero = [D::zero(); DIM];
        for i in 0..=n {
            if !self.has_spring[i] {
                continue;
            }
            let (a, wa) = if i == 0 {
                (&e, &zero)
            } else {
                (&q[i - 1], &w[i - 1])
            };
            let (b, wb) = if i == n { (&e, &zero) } else { (&q[i], &w[i]) };
            let (s, ds) = spring_s_ds(dot(a, b));
            let sigma = dot(b, wa) + dot(a, wb);
            let k = -self.springs[i] * scale;
            if i > 0 {
                for d in 0..DIM {
                    out[i - 1][d] += k * (s * wb[d] + ds * sigma * b[d]);
                }
            }
            if i < n {
                for d in 0..DIM {
                    out[i][d] += k * (s * wa[d] + ds * sigma * a[d]);
                }
            }
        }
    }

    /// The contraction w · ∂(∂U/∂q)/∂θ of the force with respect to a parameter at time t, for
    /// the parameters the force is linear in (stiffnesses, load magnitudes) or, for
    /// [`Parameter::Mass`], its gravity part (the mass matrix part is the adjoint's business).
    /// [`Parameter::Drag`] does not enter the force (0).
    pub fn force_parameter_contraction(
        &self,
        q: &[[D; DIM]],
        t: f64,
        w: &[[D; DIM]],
        p: Parameter,
    ) -> D {
        let n = self.n;
        let z = zi::<DIM>();
        let e = e2::<D, DIM>();
        let zero = [D::zero(); DIM];
        let spring = |i: usize| -> D {
            if !self.has_spring[i] {
                return D::zero();
            }
            let (a, wa) = if i == 0 {
                (&e, &zero)
            } else {
                (&q[i - 1], &w[i - 1])
            };
            let (b, wb) = if i == n { (&e, &zero) } else { (&q[i], &w[i]) };
            -spring_s(dot(a, b)) * (dot(b, wa) + dot(a, wb))
        };
        match p {
            Parameter::InteriorStiffness => (1..n).map(spring).fold(D::zero(), |a, b| a + b),
            Parameter::BaseStiffness => spring(0),
            Parameter::TipStiffness => spring(n),
            Parameter::Mass => match self.gravity {
                Some(g) => (0..n)
                    .map(|j| g * ((n - j) as f64) * self.lengths[j] * w[j][z])
                    .fold(D::zero(), |a, b| a + b),
                None => D::zero(),
            },
            Parameter::Drag => D::zero(),
            Parameter::LoadForce(i) => {
                let tol = 1e-9 * t.abs().max(1.0);
                match self.loads.iter().find(|l| l.scene_index == i) {
                    Some(l) if t + tol >= l.start && t + tol < l.end => (0..l.node)
                        .map(|j| self.lengths[j] * w[j][z])
                        .fold(D::zero(), |a, b| a + b),
                    _ => D::zero(),
                }
            }
        }
    }

    /// Whether all masses are equal (parameter derivatives with respect to [`Parameter::Mass`]
    /// are taken at a common mass).
    pub fn has_uniform_mass(&self) -> bool {
        let m0 = self.masses[0].re();
        self.masses
            .iter()
            .all(|m| (m.re() - m0).abs() <= 1e-15 * m0.abs())
    }

    fn folded(&self, step: usize, joint0: usize, a: &[D; DIM], b: &[D; DIM]) -> Error {
        let x = dot(a, b).re().clamp(-1.0, 1.0);
        Error::Folded {
            step,
            joint: joint0 + 1,
            angle_deg: x.acos().to_degrees(),
            limit_deg: self.fold_cos.acos().to_degrees(),
        }
    }

    /// The largest joint angle θᵢ = ∠(q_{i−1}, qᵢ), i = 1..=n+1, in radians (including the end
    /// joints against e₂ whether or not they carry a spring).
    pub fn max_joint_angle(&self, q: &[[D; DIM]]) -> f64 {
        let e = e2::<D, DIM>();
        let mut m: f64 = 0.0;
        for i in 0..=self.n {
            let a = if i == 0 { &e } else { &q[i - 1] };
            let b = if i == self.n { &e } else { &q[i] };
            m = m.max(joint_angle_squared(a, b).re().sqrt());
        }
        m
    }

    /// Potential energy U(q; t, u): springs ½ Σ kᵢ θᵢ² (θᵢ by [`joint_angle_squared`]), loads and
    /// control Σ_j l_j c_j e₃ᵀq_j, and gravity's constant part Σᵢ Σ_{j≤i} mᵢ g l_j (§2.2.2).
    pub fn potential_energy(&self, q: &[[D; DIM]], t: f64, u: D) -> D {
        let n = self.n;
        let e = e2::<D, DIM>();
        let mut energy = D::zero();
        for i in 0..=n {
            if !self.has_spring[i] {
                continue;
            }
            let a = if i == 0 { &e } else { &q[i - 1] };
            let b = if i == n { &e } else { &q[i] };
            energy += self.springs[i] * joint_angle_squared(a, b) * 0.5;
        }
        let z = zi::<DIM>();
        self.for_each_load_coefficient(t, u, |j, c| {
            energy += self.lengths[j] * c * q[j][z];
        });
        if let Some(g) = self.gravity {
            // Σ_i m_i g Σ_{j≤i} l_j
            let mut cum = D::zero();
            for i in 0..n {
                cum += self.lengths[i];
                energy += self.masses[i] * g * cum;
            }
        }
        energy
    }

    /// Kinetic energy ½ pᵀM⁻¹p; `scratch` has length n.
    pub fn kinetic_energy(&self, p: &[[D; DIM]], scratch: &mut [[D; DIM]]) -> D {
        self.apply_inverse_mass(p, scratch);
        let mut e = D::zero();
        for (a, b) in p.iter().zip(scratch.iter()) {
            e += dot(a, b);
        }
        e * 0.5
    }

    /// Base bending moment M₀ = 2 k₁ z₁ / l₁² with z₁ = l₁ e₃ᵀq₁ (eq. 3.1.3, sign and index
    /// corrected as SPEC §4 says).
    #[inline]
    pub fn base_moment(&self, q: &[[D; DIM]]) -> D {
        self.moment_stiffness * 2.0 * q[0][zi::<DIM>()] * self.inv_lengths[0]
    }

    /// Node positions rᵢ = Σ_{j≤i} l_j q_j, i = 1..=n (node 0 is the origin).
    pub fn node_positions(&self, q: &[[D; DIM]], out: &mut [[D; DIM]]) {
        let mut r = [D::zero(); DIM];
        for i in 0..self.n {
            for d in 0..DIM {
                r[d] += self.lengths[i] * q[i][d];
            }
            out[i] = r;
        }
    }

    /// Tip z: l(q) = Σ lᵢ e₃ᵀqᵢ (eq. 2.4.1).
    #[inline]
    pub fn tip_z(&self, q: &[[D; DIM]]) -> D {
        let z = zi::<DIM>();
        let mut s = D::zero();
        for i in 0..self.n {
            s += self.lengths[i] * q[i][z];
        }
        s
    }

    /// Lengths lᵢ.
    pub fn lengths(&self) -> &[D] {
        &self.lengths
    }

    /// Masses mᵢ.
    pub fn masses(&self) -> &[D] {
        &self.masses
    }

    /// Spring constants k₁..k_{n+1} (zero where the support has none).
    pub fn springs(&self) -> &[D] {
        &self.springs
    }
}
