//! The hot-spot stress at the wellhead from the base bending moment (docs/fatigue.md):
//!
//! σ(t) = SCF · M_w(t) · (D_o/2) / I,  I = π/64 (D_o⁴ − D_i⁴),  D_i = D_o − 2t,
//!
//! in MPa (M_w in N·m, lengths in m, divided by 10⁶). The axial stress T/A_s is constant under a
//! constant tension and does not change the ranges, so it is left out.
//!
//! **The wellhead moment M_w is not the chain's M₀.** The moment the simulator reports (`moment`,
//! thesis eq. 3.1.3) is M₀ = 2k₁z₁/l₁², the thesis's finite difference with the base spring k₁ in
//! place of EI; it is a bending moment in N·m only in name. The moment the clamp carries is the
//! base spring's torque, M_w = k₁θ₁ ≈ k₁z₁/l₁ (θ₁ ≈ z₁/l₁ the base joint's angle, linearised as
//! M₀ is), so
//!
//! M_w = M₀ · l₁/2   ([`MomentMeasure::ChainM0`]).
//!
//! This is the physical moment: at static equilibrium the base spring balances the moment of every
//! load about the base (a cantilever with a tip force P: k₁θ₁ = P·L exactly, whatever k₁ is), and
//! on a pipe's chain (k₁ = 2EI/l₁ at a clamp, `Pipe::beam`) it is EI·2z₁/l₁², the ghost-node
//! finite difference of EI·w″(0) (docs/conventions.md "The wellhead moment M_w";
//! tests/fatigue/fatigue_wellhead.rs checks P·L at n = 20 and 80 against the Euler-Bernoulli closed form).
//! The thesis's own chains (l₁ = 1 m, k₁ = 2k) have M_w = M₀/2.
//!
//! In a spatial scene the base moment is a vector (M₀ₓ, M₀_z) (docs/conventions.md) and the stress
//! at the point at angle θ around the circumference is
//!
//! σ_θ(t) = SCF · (M_wₓ(t) sin θ + M_w_z(t) cos θ) · (D_o/2) / I,
//!
//! θ = 0 the point on the +z side. σ_{θ+π} = −σ_θ has the same ranges, so points over [0, π)
//! cover the circumference; [`HotSpot::points`] spaces them evenly.

use std::f64::consts::PI;

use super::{check_positive, FatigueError};

/// Pa per MPa.
const PA_PER_MPA: f64 = 1.0e6;

/// What the values of a moment history are (module docs): the chain's M₀ or the wellhead moment
/// M_w itself.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum MomentMeasure {
    /// The chain's M₀ = 2k₁z₁/l₁² (thesis eq. 3.1.3): what `simulate`, the closed loop of
    /// [`crate::mpc`] and a `simulate` CSV's `moment` column report. The wellhead moment is
    /// M_w = k₁z₁/l₁ = M₀ · l₁/2.
    ChainM0 {
        /// The base pendulum's length l₁ \[m\] (`beam.length`'s first value, or the pipe's
        /// length over n).
        base_length: f64,
    },
    /// The wellhead bending moment M_w itself \[N·m\] (a measured record, or a synthetic one).
    Wellhead,
}

impl MomentMeasure {
    /// M_w per unit of the history's values: l₁/2 for [`MomentMeasure::ChainM0`], 1 for
    /// [`MomentMeasure::Wellhead`].
    pub fn wellhead_per_unit(self) -> f64 {
        match self {
            MomentMeasure::ChainM0 { base_length } => 0.5 * base_length,
            MomentMeasure::Wellhead => 1.0,
        }
    }

    /// Checks l₁.
    ///
    /// # Errors
    /// [`FatigueError::InvalidSpec`] naming `base_length` if l₁ is not positive and finite.
    pub fn check(self) -> Result<(), FatigueError> {
        match self {
            MomentMeasure::ChainM0 { base_length } => check_positive("base_length", base_length),
            MomentMeasure::Wellhead => Ok(()),
        }
    }
}

/// The pipe section at the wellhead and the stress concentration factor of the hot spot.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct HotSpot {
    /// Outer diameter D_o \[m\].
    pub outer_diameter: f64,
    /// Wall thickness t \[m\], 0 < t ≤ D_o/2 (t = D_o/2: a solid section).
    pub wall_thickness: f64,
    /// Stress concentration factor SCF ≥ 1 is usual; any positive value is accepted.
    pub scf: f64,
}

impl HotSpot {
    /// A validated hot spot.
    ///
    /// # Errors
    /// [`FatigueError::InvalidSpec`] naming `outer_diameter`, `wall_thickness` or `scf` if one is
    /// not positive and finite, or the wall is thicker than the radius.
    pub fn new(outer_diameter: f64, wall_thickness: f64, scf: f64) -> Result<Self, FatigueError> {
        check_positive("outer_diameter", outer_diameter)?;
        check_positive("wall_thickness", wall_thickness)?;
        check_positive("scf", scf)?;
        if wall_thickness > 0.5 * outer_diameter {
            return Err(FatigueError::InvalidSpec {
                key: "wall_thickness",
                value: wall_thickness,
                reason: "must not exceed half the outer diameter",
            });
        }
        Ok(HotSpot {
            outer_diameter,
            wall_thickness,
            scf,
        })
    }

    /// The second moment of area I = π/64 (D_o⁴ − D_i⁴) \[m⁴\], D_i = D_o − 2t.
    pub fn second_moment(&self) -> f64 {
        let d_o = self.outer_diameter;
        let d_i = d_o - 2.0 * self.wall_thickness;
        PI / 64.0 * (d_o.powi(4) - d_i.powi(4))
    }

    /// The stress per unit wellhead moment, c = SCF · (D_o/2) / I / 10⁶ \[MPa per N·m\]:
    /// σ = c · M_w.
    pub fn stress_per_moment(&self) -> f64 {
        self.scf * 0.5 * self.outer_diameter / self.second_moment() / PA_PER_MPA
    }

    /// The stress per unit of a history's values, c · M_w/unit (c · l₁/2 for the chain's M₀)
    /// \[MPa per unit\]: σ_k = this · moment_k.
    pub fn stress_per_unit(&self, measure: MomentMeasure) -> f64 {
        self.stress_per_moment() * measure.wellhead_per_unit()
    }

    /// σ = c · M_w for a planar moment history of the given measure (MPa), written into
    /// `stress` (same length).
    ///
    /// # Errors
    /// [`FatigueError::LengthMismatch`] if the lengths differ.
    pub fn stress(
        &self,
        moment: &[f64],
        measure: MomentMeasure,
        stress: &mut [f64],
    ) -> Result<(), FatigueError> {
        check_len("stress", moment.len(), stress.len())?;
        let c = self.stress_per_unit(measure);
        for (s, m) in stress.iter_mut().zip(moment) {
            *s = c * m;
        }
        Ok(())
    }

    /// σ_θ = c · (M_wₓ sin θ + M_w_z cos θ) at the point θ (rad) of a spatial history of the
    /// given measure (MPa).
    ///
    /// # Errors
    /// [`FatigueError::LengthMismatch`] if the three lengths differ.
    pub fn stress_at(
        &self,
        moment_x: &[f64],
        moment_z: &[f64],
        theta: f64,
        measure: MomentMeasure,
        stress: &mut [f64],
    ) -> Result<(), FatigueError> {
        check_len("moment_x", moment_z.len(), moment_x.len())?;
        check_len("stress", moment_z.len(), stress.len())?;
        let c = self.stress_per_unit(measure);
        let (sin, cos) = theta.sin_cos();
        for ((s, mx), mz) in stress.iter_mut().zip(moment_x).zip(moment_z) {
            *s = c * (mx * sin + mz * cos);
        }
        Ok(())
    }

    /// `count` evenly spaced points θ_j = jπ/count, j = 0 … count−1, over [0, π) (the other
    /// half of the circumference has the same ranges).
    pub fn points(count: usize) -> impl Iterator<Item = f64> {
        let n = count.max(1);
        (0..n).map(move |j| j as f64 * PI / n as f64)
    }
}

pub(super) fn check_len(
    what: &'static str,
    expected: usize,
    got: usize,
) -> Result<(), FatigueError> {
    if expected != got {
        return Err(FatigueError::LengthMismatch {
            what,
            expected,
            got,
        });
    }
    Ok(())
}
