//! The hot-spot stress at the wellhead from the base bending moment (OCEAN.md §4):
//!
//! σ(t) = SCF · M₀(t) · (D_o/2) / I,  I = π/64 (D_o⁴ − D_i⁴),  D_i = D_o − 2t,
//!
//! in MPa (M₀ in N·m, lengths in m, divided by 10⁶). The axial stress T/A_s is constant under a
//! constant tension and does not change the ranges, so it is left out. In a spatial scene the
//! base moment is a vector (M₀ₓ, M₀_z) (docs/conventions.md) and the stress at the point at
//! angle θ around the circumference is
//!
//! σ_θ(t) = SCF · (M₀ₓ(t) sin θ + M₀_z(t) cos θ) · (D_o/2) / I,
//!
//! θ = 0 the point on the +z side. σ_{θ+π} = −σ_θ has the same ranges, so points over [0, π)
//! cover the circumference; [`HotSpot::points`] spaces them evenly.

use std::f64::consts::PI;

use super::{check_positive, FatigueError};

/// Pa per MPa.
const PA_PER_MPA: f64 = 1.0e6;

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

    /// The stress per unit moment, c = SCF · (D_o/2) / I / 10⁶ \[MPa per N·m\]: σ = c · M₀.
    pub fn stress_per_moment(&self) -> f64 {
        self.scf * 0.5 * self.outer_diameter / self.second_moment() / PA_PER_MPA
    }

    /// σ = c · M₀ for a planar moment history (MPa), written into `stress` (same length).
    ///
    /// # Errors
    /// [`FatigueError::LengthMismatch`] if the lengths differ.
    pub fn stress(&self, moment: &[f64], stress: &mut [f64]) -> Result<(), FatigueError> {
        check_len("stress", moment.len(), stress.len())?;
        let c = self.stress_per_moment();
        for (s, m) in stress.iter_mut().zip(moment) {
            *s = c * m;
        }
        Ok(())
    }

    /// σ_θ = c · (M₀ₓ sin θ + M₀_z cos θ) at the point θ (rad) of a spatial history (MPa).
    ///
    /// # Errors
    /// [`FatigueError::LengthMismatch`] if the three lengths differ.
    pub fn stress_at(
        &self,
        moment_x: &[f64],
        moment_z: &[f64],
        theta: f64,
        stress: &mut [f64],
    ) -> Result<(), FatigueError> {
        check_len("moment_x", moment_z.len(), moment_x.len())?;
        check_len("stress", moment_z.len(), stress.len())?;
        let c = self.stress_per_moment();
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
