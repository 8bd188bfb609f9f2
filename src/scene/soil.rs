//! The seabed and the soil around the part of the beam below it (`[soil]`, docs/scene-format.md
//! "[soil]"; docs/conventions.md "Soil springs"): where the mudline lies on the chain, and the
//! lateral modulus of a linear p-y spring per unit length of pile, E_s(d) = E₀ + E₁ d at the depth
//! d below the mudline.
//!
//! **The one place** that maps a height on the chain to the water: [`Soil::water_height`] (and
//! [`water_height`] for a scene that may have no `[soil]`): the height above the mudline, `None`
//! below it. The current and the waves read a node's height through it, so that nodes in the soil
//! take no water load and the water depth is counted from the mudline.

use serde::{Deserialize, Serialize};

use super::error::SceneError;
use super::ranges::{check_range, soil_ranges};

/// The soil below the mudline (`[soil]`): a linear p-y modulus E_s(d) = `modulus` + `gradient`·d
/// \[N/m per m of pile, i.e. N/m²\] at the depth d \[m\] below the mudline, acting laterally on
/// every node of the chain whose cell reaches below the mudline (docs/conventions.md "Soil
/// springs").
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Soil {
    /// Height of the mudline above the chain's foot (node 0) \[m\]: the length of the pile in
    /// the soil. 0 puts the mudline at the foot (no node in the soil).
    pub mudline: f64,
    /// E₀: the p-y modulus at the mudline \[N/m²\] (N/m of lateral force per m of pile and per m
    /// of lateral deflection). [`crate::Parameter::SoilModulus`].
    pub modulus: f64,
    /// E₁: the increase of the modulus with depth \[N/m³\] (default 0: a uniform soil; e.g. a
    /// normally consolidated clay, whose modulus grows about linearly with depth).
    #[serde(default, skip_serializing_if = "is_positive_zero")]
    pub gradient: f64,
}

fn is_positive_zero(x: &f64) -> bool {
    x.to_bits() == 0
}

/// The lateral spring constants of the nodes, k_i = E₀ aᵢ + E₁ bᵢ \[N/m\] (docs/conventions.md
/// "Soil springs"): aᵢ the length of node i's cell below the mudline, bᵢ = dᵢ aᵢ with dᵢ the
/// node's depth below the mudline (0 for a node above it whose cell reaches below).
#[derive(Clone, Debug, PartialEq)]
pub struct SoilLumping {
    /// aᵢ \[m\], one per node 1..=n (0-based index i − 1).
    pub per_modulus: Vec<f64>,
    /// bᵢ = dᵢ aᵢ \[m²\], one per node.
    pub per_gradient: Vec<f64>,
}

impl Soil {
    /// Checks `soil.mudline`, `soil.modulus`, `soil.gradient` against their ranges
    /// (`soil_ranges` in the scene's validation) and the mudline against the beam's length `total`.
    ///
    /// # Errors
    /// [`SceneError`] naming the key.
    pub fn check(&self, total: f64) -> Result<(), SceneError> {
        let [mudline, modulus, gradient] = soil_ranges();
        check_range("soil.mudline", self.mudline, &mudline)?;
        check_range("soil.modulus", self.modulus, &modulus)?;
        check_range("soil.gradient", self.gradient, &gradient)?;
        if self.mudline > total * (1.0 + 1e-12) {
            return Err(SceneError::invalid(
                "soil.mudline",
                format!(
                    "the mudline at {} m lies above the beam's top ({total} m): it is the height \
                     of the seabed above the chain's foot, at most the beam's length",
                    self.mudline
                ),
            ));
        }
        Ok(())
    }

    /// The height of `y` (measured from the chain's foot) above the mudline, `None` below it
    /// (in the soil: no water load). A height within 10⁻⁹ m of the mudline counts as at it.
    #[inline]
    pub fn water_height(&self, y: f64) -> Option<f64> {
        water_height(self.mudline, y)
    }

    /// The node lumping of the springs (see [`SoilLumping`]) for pendulum lengths `lengths`:
    /// node i's cell is [yᵢ − lᵢ/2, yᵢ + lᵢ₊₁/2] (the tip's ends at yₙ), the masses' lumping.
    pub fn lumping(&self, lengths: &[f64]) -> SoilLumping {
        let n = lengths.len();
        let (mut a, mut b) = (vec![0.0; n], vec![0.0; n]);
        let mut y = 0.0;
        for i in 0..n {
            y += lengths[i];
            let next = lengths.get(i + 1).copied().unwrap_or(0.0);
            let (lo, hi) = (y - 0.5 * lengths[i], y + 0.5 * next);
            let below = (hi.min(self.mudline) - lo).max(0.0);
            let depth = (self.mudline - y).max(0.0);
            a[i] = below;
            b[i] = depth * below;
        }
        SoilLumping {
            per_modulus: a,
            per_gradient: b,
        }
    }
}

/// The height of `y` (from the chain's foot) above the mudline at height `mudline` (0 without
/// `[soil]`: the foot is at the seabed), `None` below it. The one place that maps a height on the
/// chain to the water (module docs); a height within 10⁻⁹ m below the mudline counts as at it (0).
#[inline]
pub fn water_height(mudline: f64, y: f64) -> Option<f64> {
    if mudline == 0.0 {
        // Bit for bit the heights of a scene without soil.
        return Some(y);
    }
    let above = y - mudline;
    if above >= -1e-9 {
        Some(above.max(0.0))
    } else {
        None
    }
}
