//! A steady current along the depth (`[loads.current]`, docs/scene-format.md): its profile U(y),
//! the file form, and its validation.

use serde::{Deserialize, Serialize};

use super::ranges::CURRENT_SPEED_RANGE;
use super::validate::{check_finite, check_positive};
use super::{SceneError, SceneErrorKind};

/// Largest exponent α of a power-law profile.
pub const MAX_POWER_EXPONENT: f64 = 10.0;

/// A steady current: the water velocity U(y) at height y above the base (the seabed), in the
/// transverse plane (x, z). Depth is measured down from the free surface at height
/// [`Current::surface`]: d = y_s − y. Above the surface (d < 0) there is no current.
///
/// With a current the drag acts on the velocity relative to the water ([`crate::model::CurrentDrag`],
/// docs/conventions.md); it needs the drag constant `loads.drag` D > 0.
#[derive(Clone, Debug, PartialEq)]
pub struct Current {
    /// How the speed varies with depth.
    pub profile: CurrentProfile,
    /// Direction (d_x, d_z) of the current in the transverse plane, normalised by the model
    /// (default (0, 1): along +z). Not used by [`CurrentProfile::Table`], whose rows give it.
    pub direction: [f64; 2],
    /// Height y_s of the free surface above the base \[m\] (`None`: the beam's length, so the top
    /// node is at the surface).
    pub surface: Option<f64>,
}

/// The speed profile of a [`Current`] (d the depth below the surface, H = y_s the water depth at
/// the base, y = H − d the height above the base).
#[derive(Clone, Debug, PartialEq)]
pub enum CurrentProfile {
    /// U = `speed` at every depth.
    Uniform {
        /// \[m/s\]
        speed: f64,
    },
    /// Linear shear from `speed` at the surface to `bottom_speed` at the base:
    /// U = `speed` + (`bottom_speed` − `speed`)·d/H.
    Linear {
        /// At the surface \[m/s\].
        speed: f64,
        /// At the base (the seabed) \[m/s\].
        bottom_speed: f64,
    },
    /// Power law U = `speed`·(y/H)^α (α = 1/7 is the classical tidal profile): `speed` at the
    /// surface, 0 at the base.
    PowerLaw {
        /// At the surface \[m/s\].
        speed: f64,
        /// α > 0.
        exponent: f64,
    },
    /// Rows (depth d \[m\], speed \[m/s\], direction ψ \[°\]) with strictly increasing depths ≥ 0;
    /// ψ is measured in the transverse plane from +z toward +x (0°: along +z, 90°: along +x).
    /// The velocities (U sin ψ, U cos ψ) are interpolated linearly in depth and held constant
    /// beyond the first and the last row.
    Table {
        /// The rows.
        rows: Vec<[f64; 3]>,
    },
}

/// The unit direction (d_x, d_z) of an angle ψ \[°\] from +z toward +x, exact at multiples of 90°
/// (so that ψ = 180° stays in the y–z plane).
pub fn direction_of_angle(degrees: f64) -> [f64; 2] {
    let quarters = degrees.rem_euclid(360.0) / 90.0;
    if quarters.fract() == 0.0 {
        // an exact multiple of 90°: 0, 1, 2 or 3 quarter turns
        return [[0.0, 1.0], [1.0, 0.0], [0.0, -1.0], [-1.0, 0.0]][quarters as usize % 4];
    }
    let (s, c) = degrees.to_radians().sin_cos();
    [s, c]
}

impl Current {
    /// A uniform current of `speed` \[m/s\] along `direction` (d_x, d_z).
    pub fn uniform(speed: f64, direction: [f64; 2]) -> Self {
        Current {
            profile: CurrentProfile::Uniform { speed },
            direction,
            surface: None,
        }
    }

    /// A linearly sheared current, `speed` at the surface and `bottom_speed` at the base.
    pub fn linear(speed: f64, bottom_speed: f64, direction: [f64; 2]) -> Self {
        Current {
            profile: CurrentProfile::Linear {
                speed,
                bottom_speed,
            },
            direction,
            surface: None,
        }
    }

    /// A power-law current `speed`·(y/H)^`exponent`.
    pub fn power_law(speed: f64, exponent: f64, direction: [f64; 2]) -> Self {
        Current {
            profile: CurrentProfile::PowerLaw { speed, exponent },
            direction,
            surface: None,
        }
    }

    /// A tabulated current, rows (depth \[m\], speed \[m/s\], direction \[°\]).
    pub fn table(rows: Vec<[f64; 3]>) -> Self {
        Current {
            profile: CurrentProfile::Table { rows },
            direction: [0.0, 1.0],
            surface: None,
        }
    }

    /// The same current with the free surface at height `surface` \[m\] above the base.
    pub fn with_surface(mut self, surface: f64) -> Self {
        self.surface = Some(surface);
        self
    }

    /// The speed parameter (`speed` of the uniform, linear and power-law profiles;
    /// [`crate::Parameter::CurrentSpeed`]), `None` for a table.
    pub fn speed(&self) -> Option<f64> {
        match self.profile {
            CurrentProfile::Uniform { speed }
            | CurrentProfile::Linear { speed, .. }
            | CurrentProfile::PowerLaw { speed, .. } => Some(speed),
            CurrentProfile::Table { .. } => None,
        }
    }

    /// The key that makes the current spatial, if any: a `direction` with d_x ≠ 0 (whatever the
    /// speed, which is a parameter), or a table row whose velocity has an x component.
    pub fn spatial_key(&self) -> Option<&'static str> {
        match &self.profile {
            CurrentProfile::Table { rows } => rows
                .iter()
                .any(|r| r[1] * direction_of_angle(r[2])[0] != 0.0)
                .then_some("loads.current.table"),
            _ => (self.direction[0] != 0.0).then_some("loads.current.direction"),
        }
    }

    /// The rules of docs/scene-format.md, `[loads.current]` (`drag`: the scene's D).
    pub(super) fn check(&self, drag: f64) -> Result<(), SceneError> {
        if drag <= 0.0 {
            return Err(SceneError::invalid(
                "loads.drag",
                "must be positive when the scene has a current ([loads.current]): the current \
                 acts through the drag F = −D (p − P)|p − P|, got 0",
            ));
        }
        let speed = |key: &str, v: f64| check_speed(&format!("loads.current.{key}"), v);
        match &self.profile {
            CurrentProfile::Uniform { speed: s } => speed("speed", *s)?,
            CurrentProfile::Linear {
                speed: s,
                bottom_speed,
            } => {
                speed("speed", *s)?;
                speed("bottom_speed", *bottom_speed)?;
            }
            CurrentProfile::PowerLaw { speed: s, exponent } => {
                speed("speed", *s)?;
                check_positive("loads.current.exponent", *exponent)?;
                if *exponent > MAX_POWER_EXPONENT {
                    return Err(SceneError::invalid(
                        "loads.current.exponent",
                        format!("must be at most {MAX_POWER_EXPONENT}, got {exponent}"),
                    ));
                }
            }
            CurrentProfile::Table { rows } => check_rows(rows)?,
        }
        if let Some(s) = self.surface {
            check_positive("loads.current.surface", s)?;
        }
        let [dx, dz] = self.direction;
        if !(dx.is_finite() && dz.is_finite() && dx.hypot(dz) > 0.0) {
            return Err(SceneError::invalid(
                "loads.current.direction",
                format!("must be a finite vector [dx, dz] of non-zero length, got [{dx}, {dz}]"),
            ));
        }
        Ok(())
    }
}

impl Current {
    /// The steady force Dᵢ·|Pᵢ|² of the current on each pendulum at rest (Pᵢ = lᵢ Σ_{k≥i} m_k U_k,
    /// [`crate::model::CurrentDrag`]; Dᵢ = D wᵢ with the `weights` of a pipe's chain,
    /// [`crate::scene::drag_weights`], else D), for the load number of the step check.
    pub(super) fn steady_forces(
        &self,
        drag: f64,
        weights: Option<&[f64]>,
        (lengths, masses): (&[f64], &[f64]),
        mudline: f64,
    ) -> Vec<f64> {
        let surface = self
            .surface
            .unwrap_or_else(|| lengths.iter().sum::<f64>() - mudline);
        let s = self.speed().unwrap_or(0.0);
        let mut y = 0.0;
        let velocities: Vec<[f64; 2]> = lengths
            .iter()
            .map(|l| {
                y += l;
                let (a, b) = super::water_height(mudline, y)
                    .map_or(([0.0; 2], [0.0; 2]), |y| current_velocity(self, y, surface));
                [s * a[0] + b[0], s * a[1] + b[1]]
            })
            .collect();
        let mut acc = [0.0; 2];
        let mut out = vec![0.0; lengths.len()];
        for i in (0..lengths.len()).rev() {
            acc[0] += masses[i] * velocities[i][0];
            acc[1] += masses[i] * velocities[i][1];
            let p = lengths[i] * acc[0].hypot(acc[1]);
            let d = weights.map_or(drag, |w| drag * w[i]);
            out[i] = d * p * p;
        }
        out
    }
}

fn check_speed(key: &str, v: f64) -> Result<(), SceneError> {
    check_finite(key, v)?;
    if !CURRENT_SPEED_RANGE.contains(v) {
        return Err(SceneError::invalid(
            key,
            format!(
                "must be a speed in [0, {}] m/s (the direction gives the sense), got {v}",
                CURRENT_SPEED_RANGE.max
            ),
        ));
    }
    Ok(())
}

/// Table rows: at least one, depths finite, ≥ 0 and strictly increasing, speeds in range,
/// directions finite.
fn check_rows(rows: &[[f64; 3]]) -> Result<(), SceneError> {
    if rows.is_empty() {
        return Err(SceneError::invalid(
            "loads.current.table",
            "needs at least one row [depth, speed, direction]",
        ));
    }
    for (j, r) in rows.iter().enumerate() {
        let key = format!("loads.current.table[{j}]");
        let [depth, speed, dir] = *r;
        check_finite(&key, depth)?;
        if depth < 0.0 {
            return Err(SceneError::invalid(
                key,
                format!(
                    "depth must be 0 or more (it is measured down from the surface), got {depth}"
                ),
            ));
        }
        if j > 0 && depth <= rows[j - 1][0] {
            return Err(SceneError::invalid(
                key,
                format!(
                    "depths must increase strictly: {depth} after {} (row {})",
                    rows[j - 1][0],
                    j - 1
                ),
            ));
        }
        check_speed(&key, speed)?;
        check_finite(&key, dir)?;
    }
    Ok(())
}

/// The profile names of a file.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
enum ProfileKind {
    Uniform,
    Linear,
    Power,
    Table,
}

/// `[loads.current]` as written in a file.
#[derive(Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RawCurrent {
    profile: ProfileKind,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    speed: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    bottom_speed: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    exponent: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    surface: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    direction: Option<Vec<f64>>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    table: Option<Vec<Vec<f64>>>,
}

/// Default exponent of a power-law profile (the one-seventh law).
pub const DEFAULT_POWER_EXPONENT: f64 = 1.0 / 7.0;

impl RawCurrent {
    pub(super) fn from_current(c: &Current) -> Self {
        let mut raw = RawCurrent {
            profile: ProfileKind::Table,
            speed: c.speed(),
            bottom_speed: None,
            exponent: None,
            surface: c.surface,
            direction: None,
            table: None,
        };
        match &c.profile {
            CurrentProfile::Uniform { .. } => raw.profile = ProfileKind::Uniform,
            CurrentProfile::Linear { bottom_speed, .. } => {
                raw.profile = ProfileKind::Linear;
                raw.bottom_speed = Some(*bottom_speed);
            }
            CurrentProfile::PowerLaw { exponent, .. } => {
                raw.profile = ProfileKind::Power;
                raw.exponent = Some(*exponent);
            }
            CurrentProfile::Table { rows } => {
                raw.table = Some(rows.iter().map(|r| r.to_vec()).collect());
            }
        }
        if !matches!(c.profile, CurrentProfile::Table { .. }) {
            raw.direction = Some(c.direction.to_vec());
        }
        raw
    }

    /// The current; a key that the profile does not use, or a missing one, names the key.
    pub(super) fn into_current(self) -> Result<Current, SceneError> {
        let key = |k: &str| format!("loads.current.{k}");
        let name = match self.profile {
            ProfileKind::Uniform => "uniform",
            ProfileKind::Linear => "linear",
            ProfileKind::Power => "power",
            ProfileKind::Table => "table",
        };
        let unused = |k: &str, given: bool| -> Result<(), SceneError> {
            if given {
                return Err(SceneError::invalid(
                    key(k),
                    format!("is not used by profile = \"{name}\""),
                ));
            }
            Ok(())
        };
        let is_table = self.profile == ProfileKind::Table;
        unused(
            "bottom_speed",
            self.profile != ProfileKind::Linear && self.bottom_speed.is_some(),
        )?;
        unused(
            "exponent",
            self.profile != ProfileKind::Power && self.exponent.is_some(),
        )?;
        unused("table", !is_table && self.table.is_some())?;
        unused("speed", is_table && self.speed.is_some())?;
        unused("direction", is_table && self.direction.is_some())?;
        let required = |k: &str, v: Option<f64>| {
            v.ok_or_else(|| {
                SceneError::from(SceneErrorKind::MissingKey {
                    key: key(k),
                    note: Some(format!("required by profile = \"{name}\"")),
                })
            })
        };
        let profile = match self.profile {
            ProfileKind::Uniform => CurrentProfile::Uniform {
                speed: required("speed", self.speed)?,
            },
            ProfileKind::Linear => CurrentProfile::Linear {
                speed: required("speed", self.speed)?,
                bottom_speed: self.bottom_speed.unwrap_or(0.0),
            },
            ProfileKind::Power => CurrentProfile::PowerLaw {
                speed: required("speed", self.speed)?,
                exponent: self.exponent.unwrap_or(DEFAULT_POWER_EXPONENT),
            },
            ProfileKind::Table => CurrentProfile::Table {
                rows: table_rows(self.table)?,
            },
        };
        let direction = match self.direction.as_deref() {
            None => [0.0, 1.0],
            Some(&[dx, dz]) => [dx, dz],
            Some(v) => {
                return Err(SceneError::invalid(
                    key("direction"),
                    format!(
                        "a direction has 2 components [dx, dz] (transverse to the beam), got {} \
                         values",
                        v.len()
                    ),
                ))
            }
        };
        Ok(Current {
            profile,
            direction,
            surface: self.surface,
        })
    }
}

fn table_rows(table: Option<Vec<Vec<f64>>>) -> Result<Vec<[f64; 3]>, SceneError> {
    let Some(table) = table else {
        return Err(SceneErrorKind::MissingKey {
            key: "loads.current.table".into(),
            note: Some("required by profile = \"table\"".into()),
        }
        .into());
    };
    table
        .into_iter()
        .enumerate()
        .map(|(j, r)| match r[..] {
            [d, s, psi] => Ok([d, s, psi]),
            _ => Err(SceneError::invalid(
                format!("loads.current.table[{j}]"),
                format!(
                    "a row has 3 values [depth, speed, direction], got {}",
                    r.len()
                ),
            )),
        })
        .collect()
}

/// How far above the surface, relative to its height y_s, a node still counts as at the surface
/// (depth 0): the nodes' heights are sums of the lengths, y_k = l₁ + … + l_k, and equal lengths
/// L/n do not always add up to L exactly (1000/300 three hundred times is 1000 + 4.4e-12), which
/// left the top node of a riser whose water depth is its length without current. 1e-9 y_s is
/// far above such rounding and far below any height a scene means.
const SURFACE_TOLERANCE: f64 = 1e-9;

/// The current's velocity at height y above the base, split as U(y) = s·a(y) + b(y) with s the
/// speed parameter ([`crate::base::Parameter::CurrentSpeed`]): returns (a, b), each as (U_x, U_z). `surface`
/// is the height y_s of the free surface; above it (y > y_s (1 + 10⁻⁹)) there is no current, and a
/// node less than 10⁻⁹ y_s above it is at the surface (depth 0: the node heights are sums of the
/// lengths, and L/n added n times can exceed L by rounding).
pub fn current_velocity(current: &Current, y: f64, surface: f64) -> ([f64; 2], [f64; 2]) {
    let depth = surface - y;
    if depth < -SURFACE_TOLERANCE * surface {
        return ([0.0; 2], [0.0; 2]);
    }
    let depth = depth.max(0.0);
    let [dx, dz] = current.direction;
    let norm = dx.hypot(dz);
    let dir = [dx / norm, dz / norm];
    let scaled = |f: f64| [f * dir[0], f * dir[1]];
    let xi = depth / surface;
    match &current.profile {
        CurrentProfile::Uniform { .. } => (dir, [0.0; 2]),
        CurrentProfile::Linear { bottom_speed, .. } => {
            (scaled(1.0 - xi), scaled(bottom_speed * xi))
        }
        CurrentProfile::PowerLaw { exponent, .. } => {
            (scaled((y.min(surface) / surface).powf(*exponent)), [0.0; 2])
        }
        CurrentProfile::Table { rows } => ([0.0; 2], table_velocity(rows, depth)),
    }
}

/// Linear interpolation in depth of the rows' velocities (U sin ψ, U cos ψ), constant beyond
/// the first and last rows.
fn table_velocity(rows: &[[f64; 3]], depth: f64) -> [f64; 2] {
    let vel = |r: &[f64; 3]| {
        let [sx, sz] = direction_of_angle(r[2]);
        [r[1] * sx, r[1] * sz]
    };
    let j = rows.partition_point(|r| r[0] <= depth);
    if j == 0 {
        return vel(&rows[0]);
    }
    if j == rows.len() {
        return vel(&rows[j - 1]);
    }
    let (a, b) = (&rows[j - 1], &rows[j]);
    let w = (depth - a[0]) / (b[0] - a[0]);
    let (va, vb) = (vel(a), vel(b));
    [va[0] + w * (vb[0] - va[0]), va[1] + w * (vb[1] - va[1])]
}

#[cfg(test)]
mod tests {
    use crate::model::{Chain, Ctx};
    use crate::scene::Scene;

    /// The load number's steady current force (`steady_forces`, the scene check) is the model's
    /// drag at rest |Fᵢ(0)| = Dᵢ|Pᵢ|² ([`crate::model::CurrentDrag`], an independent code path),
    /// to 1e-12, on a `[pipe]` scene (Dᵢ = D wᵢ) and on the same chain given by its masses (one D).
    #[test]
    fn the_load_numbers_current_force_is_the_models() {
        let text = "[beam]\npendulums = 8\nsupport = \"riser\"\n\n\
                    [pipe]\nlength = 80.0\nouter_diameter = 0.5\nwall_thickness = 0.02\n\n\
                    [loads]\ndrag = 1e-5\n\n\
                    [loads.current]\nprofile = \"linear\"\nspeed = 0.8\nbottom_speed = 0.2\n\n\
                    [time]\nstep = 0.01\nsteps = 10\n";
        let piped: Scene = text.parse().unwrap();
        let mut plain = piped.clone();
        plain.pipe = None;
        for (scene, weighted) in [(&piped, true), (&plain, false)] {
            let chain = Chain::<f64, 2>::from_scene(scene).unwrap();
            assert_eq!(chain.drag_weights().is_some(), weighted);
            let b = &scene.beam;
            let c = scene.loads.current.as_ref().unwrap();
            let w = scene.drag_weights();
            let steady =
                c.steady_forces(scene.loads.drag, w.as_deref(), (&b.lengths, &b.masses), 0.0);
            let ctx = Ctx::new(0.0, 0.0, 0);
            for (i, s) in steady.iter().enumerate() {
                let f = chain.dissipative_force(i, &[0.0; 2], &ctx).unwrap();
                let model = f[0].hypot(f[1]);
                assert!(
                    (s - model).abs() <= 1e-12 * model,
                    "pendulum {i}: {s} vs {model}"
                );
            }
        }
    }
}
