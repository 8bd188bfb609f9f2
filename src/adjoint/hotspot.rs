//! The power objective at a hot spot: J = h Σ_{k=0}^{N} |M(t_k)|^p + ρ h Σ |u_k|², M the
//! moment at a named elevation of the riser ([`crate::hotspots`]), not the chain's base moment.
//! What the controllers act on with `[mpc] hotspot` (docs/mpc.md, "The moment a controller acts
//! on").
//!
//! # The moment
//! The hot spot at elevation e reads the joints a and b around it with the upper one's weight w
//! ([`crate::hotspots::interpolation_joints`]):
//! ```text
//! M = (1 − w) k_a θ_a + w k_b θ_b        (M = k_a θ_a when the elevation is joint a's, w = 0)
//! ```
//! with k the joints' springs and θ_j = β_j − β_{j−1} the joint's signed angle, β_p = asin q_{p,z}
//! the angle of pendulum p from the vertical (β = 0 for the supports' vertical beyond either
//! end). The stage cost reads β from the nodes' transverse displacements z_i that the adjoint's
//! stage costs see ([`Stage::z`]): q_{p,z} = (z_p − z_{p−1})/l_p (z₀ = 0 at the base). For
//! every pendulum pointing upward (q_{p,y} > 0, which a riser's tension keeps) this θ_j is the
//! angle atan2(a × b, a · b) of [`crate::hotspots::joint_moment`] exactly, so M is the moment the
//! fatigue study's `hotspots` assess (tests/mpc/hotspot.rs checks the two to 10⁻⁹ on a run).
//! Planar model only (the spatial joint torque has two components).
//!
//! # The gradient
//! The adjoint differentiates the stage cost in z by dual numbers (one evaluation per node,
//! [`Objective::uses_positions`]): dℓ_k/dz_i is non-zero only for the nodes that end the two or
//! three pendulums around the hot spot. |M|^p is differentiable for p > 1 and taken as 0 (with
//! vanishing derivatives) below M² = the smallest normal f64, as [`super::PowerObjective`]'s.
//!
//! # About the plan's mean (`[mpc] moment_about = "mean"`)
//! With [`MomentAbout::Mean`] ([`HotSpotObjective::about`]) the moment term is measured from the
//! horizon's own mean instead of zero, over the N + 1 stages k = 0..N the sum runs over:
//! ```text
//! J = h Σ_{k=0}^{N} |M_k − M̄|^p + ρ h Σ_k |u_k|²,    M̄ = (1/(N+1)) Σ_{k=0}^{N} M_k,
//! ∂J/∂M_j = h p φ(e_j) − (h/(N+1)) Σ_{k=0}^{N} p φ(e_k),    e = M − M̄,  φ(e) = |e|^{p−1} sgn e
//! ```
//! (the second term is M̄'s own dependence on M_j: the plan may move the mean freely, which S-N
//! damage, counting ranges only, does not see). No sum of stage costs is this J: the moment term
//! is the objective's history term ([`Objective::history`] on the signal M_k,
//! [`Objective::history_signal`]); the stage cost keeps the effort ρ h |u_k|² alone, and the
//! adjoint carries ∂J/∂M_j into z through M_j's own dual-number partials. One type with an
//! `about` field rather than a second type: the moment, its joints and its exponent are the
//! same, only the point the moment is measured from differs. [`MomentAbout::Zero`] (the
//! default) is the objective above bit for bit.

use std::sync::Arc;

use super::objective::{History, Objective, Stage};
use crate::base::Scalar;
use crate::error::{MpcError, Result};
use crate::hotspots::{interpolation_joints, pendulum_inclination};
use crate::model::Chain;
use crate::scene::{MomentAbout, Scene};

/// h Σ_{k=0}^{N} |M(t_k)|^p + ρ h Σ_{k=0}^{N} |u_k|², M the moment at a hot spot (module docs):
/// the objective MPC plans on, and the constant thrust is chosen on, with `[mpc] hotspot`.
#[derive(Clone, Debug, PartialEq)]
pub struct HotSpotObjective {
    /// The pendulums' lengths l_p \[m\].
    lengths: Arc<[f64]>,
    /// The joints read (0-based i = j − 1) and their coefficients c_i \[N m/rad\]:
    /// M = Σ c_i θ_i (c = (1 − w) k_a, w k_b; the second 0 when w = 0).
    terms: [(usize, f64); 2],
    /// The exponent p ≥ 2 (the hot spot's S-N slope m).
    pub exponent: f64,
    /// ρ ≥ 0 of the effort penalty ρ h Σ |u_k|².
    pub effort: f64,
    /// What M is measured from: zero (default) or the horizon's mean (module docs, "About the
    /// plan's mean").
    pub about: MomentAbout,
}

/// Below this M² the stage's |M|^p and its derivatives are taken as 0 ([`super::PowerObjective`]'s
/// bound: dual numbers of x^p at x = 0 would give 0·∞ = NaN).
const TINY: f64 = f64::MIN_POSITIVE;

impl HotSpotObjective {
    /// The objective at `elevation` \[m above the chain's base\] of `scene`'s planar chain (its
    /// lengths and springs), exponent p and effort ρ.
    ///
    /// # Errors
    /// [`MpcError::HotSpotSpatial`] for a spatial scene; [`MpcError::HotSpotExponent`] for p not
    /// finite and ≥ 2; the chain's errors.
    pub fn new(scene: &Scene, elevation: f64, exponent: f64, effort: f64) -> Result<Self> {
        if scene.is_spatial() {
            return Err(MpcError::HotSpotSpatial.into());
        }
        if !(exponent.is_finite() && exponent >= 2.0) {
            return Err(MpcError::HotSpotExponent { exponent }.into());
        }
        let chain = Chain::<f64, 2>::from_scene(scene)?;
        let w = interpolation_joints(&scene.beam.lengths, elevation);
        let spring = |i: usize| {
            if chain.has_spring(i) {
                chain.springs()[i]
            } else {
                0.0
            }
        };
        let terms = if w.weight == 0.0 {
            [(w.lower, spring(w.lower)), (w.upper, 0.0)]
        } else {
            [
                (w.lower, (1.0 - w.weight) * spring(w.lower)),
                (w.upper, w.weight * spring(w.upper)),
            ]
        };
        Ok(HotSpotObjective {
            lengths: scene.beam.lengths.clone().into(),
            terms,
            exponent,
            effort,
            about: MomentAbout::Zero,
        })
    }

    /// The objective with its moment measured from `about` (module docs).
    #[must_use]
    pub fn with_about(mut self, about: MomentAbout) -> Self {
        self.about = about;
        self
    }

    /// |x|^p from x² (0 below [`TINY`]: the stage's guard).
    #[allow(clippy::float_cmp)]
    fn power_of_square<D: Scalar>(&self, x2: D) -> D {
        if self.exponent == 2.0 {
            x2
        } else if x2.re() < TINY {
            x2 * 0.0
        } else {
            x2.sqrt().powf(self.exponent)
        }
    }

    /// p φ(e) = p |e|^{p−1} sgn e = p e |e|^{p−2} (0 below [`TINY`] for p > 2).
    #[allow(clippy::float_cmp)]
    fn power_slope<D: Scalar>(&self, e: D) -> D {
        let p = self.exponent;
        if p == 2.0 {
            e * 2.0
        } else {
            let e2 = e * e;
            if e2.re() < TINY {
                e * 0.0
            } else {
                e * e2.sqrt().powf(p - 2.0) * p
            }
        }
    }

    /// β_p = asin q_{p,z} of pendulum p (0 outside 0..n, the supports' vertical).
    fn beta<D: Scalar>(&self, p: Option<usize>, z: &[D]) -> D {
        pendulum_inclination(&self.lengths, p, z)
    }

    /// The hot spot's moment M = Σ c_i (β_i − β_{i−1}) from the node displacements z₁..zₙ
    /// \[N m\] (module docs).
    pub fn moment<D: Scalar>(&self, z: &[D]) -> D {
        let mut m = D::zero();
        for &(i, c) in &self.terms {
            if c != 0.0 {
                m += (self.beta(Some(i), z) - self.beta(i.checked_sub(1), z)) * c;
            }
        }
        m
    }
}

impl HotSpotObjective {
    /// The hot spot's moment M = Σ c_i (β_i − β_{i−1}) from the planar attitudes q_p =
    /// (q_{p,y}, q_{p,z}) \[N m\] (β_p = asin q_{p,z}; module docs): what the PD law at the hot
    /// spot feeds back.
    pub fn moment_of_attitudes<D: Scalar>(&self, q: &[[D; 2]]) -> D {
        let beta = |p: Option<usize>| match p {
            Some(p) if p < q.len() => q[p][1].asin(),
            _ => D::zero(),
        };
        let mut m = D::zero();
        for &(i, c) in &self.terms {
            if c != 0.0 {
                m += (beta(Some(i)) - beta(i.checked_sub(1))) * c;
            }
        }
        m
    }
}

impl Objective for HotSpotObjective {
    /// |M(t_k)|^p h + ρ h |u_k|² (for p = 2, M² h).
    #[allow(clippy::float_cmp)]
    fn stage<D: Scalar>(&self, s: Stage<'_, D>) -> D {
        let u2 = s.control * s.control + s.control_x * s.control_x;
        if self.about == MomentAbout::Mean {
            // The moment term is the history's (module docs).
            return u2 * (self.effort * s.h);
        }
        let m = self.moment(s.z);
        let m2 = m * m;
        let mp = if self.exponent == 2.0 {
            m2
        } else if m2.re() < TINY {
            m2 * 0.0
        } else {
            m2.sqrt().powf(self.exponent)
        };
        mp * s.h + u2 * (self.effort * s.h)
    }
    fn uses_positions(&self) -> bool {
        true
    }
    fn has_history(&self) -> bool {
        self.about == MomentAbout::Mean
    }
    /// The hot spot's moment M_k (about the mean only).
    fn history_signal<D: Scalar>(&self, s: Stage<'_, D>) -> Option<D> {
        (self.about == MomentAbout::Mean).then(|| self.moment(s.z))
    }
    /// h Σ_k |M_k − M̄|^p and ∂/∂M_j = h p φ(e_j) − (h/(N+1)) Σ_k p φ(e_k) (module docs), h
    /// the stage's step (`h.moment` holds M_0..M_N).
    fn history<D: Scalar>(&self, h: History<'_, D>) -> crate::error::Result<D> {
        let n = h.moment.len();
        if n == 0 {
            return Ok(D::zero());
        }
        let step = h.h;
        let count = n as f64;
        let mut mean = D::zero();
        for &m in h.moment {
            mean += m;
        }
        let mean = mean / count;
        let mut value = D::zero();
        let mut slope_sum = D::zero();
        for (g, &m) in h.grad.iter_mut().zip(h.moment) {
            let e = m - mean;
            value += self.power_of_square(e * e);
            let slope = self.power_slope(e);
            slope_sum += slope;
            *g = slope * step;
        }
        let shift = slope_sum * (step / count);
        for g in h.grad.iter_mut() {
            *g -= shift;
        }
        Ok(value * step)
    }
}
