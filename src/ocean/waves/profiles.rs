//! The depth profiles of the waves' horizontal particle velocity (cosh k y / sinh k d at a height,
//! its mean over a cell), where there is water, and [`Profiles`], which forms them for many
//! heights and cells of one sea at a fraction of the cost, bit for bit.

use super::*;

/// How far above the mean surface, relative to the depth d, a height still counts as at the
/// surface: node heights are sums of the lengths, y_k = l₁ + … + l_k, and equal lengths L/n do
/// not always add up to L exactly (1000/300 three hundred times is 1000 + 4.4e-12), so the top
/// node of a riser whose length is the water depth may lie a few ulps above it. 10⁻⁹ d is far
/// above such rounding and far below any height a scene means (the current's tolerance,
/// `scene::current_velocity`).
pub const SURFACE_TOLERANCE: f64 = 1e-9;

/// Whether height y lies above the mean surface y = d (by more than [`SURFACE_TOLERANCE`] d):
/// there is no water there, and the waves' kinematics are zero.
#[inline]
pub fn above_surface(y: f64, depth: f64) -> bool {
    y > depth + SURFACE_TOLERANCE * depth
}

/// The depth profile of the horizontal particle velocity of a component of wavenumber k at
/// height y above the seabed in depth d: cosh(k y)/sinh(k d) (DNV-RP-C205 Table 3-1), evaluated
/// as (e^{k(y−d)} + e^{−k(y+d)}) / (1 − e^{−2kd}) so that it neither overflows in deep water
/// nor loses digits in shallow water. Above the mean surface (y > d, [`above_surface`]) there is
/// no water and the profile is 0 (as the current stops there); a height within
/// [`SURFACE_TOLERANCE`] d above it is at the surface (y = d), one below the seabed at y = 0.
pub fn depth_profile(k: f64, y: f64, depth: f64) -> f64 {
    if above_surface(y, depth) {
        return 0.0;
    }
    let y = y.clamp(0.0, depth);
    (libm::exp(k * (y - depth)) + libm::exp(-k * (y + depth))) / -libm::expm1(-2.0 * k * depth)
}

/// The mean of [`depth_profile`] over the heights [y₀, y₁] (0 ≤ y₀ < y₁):
/// (1/(y₁ − y₀)) ∫ cosh(k y)/sinh(k d) dy = (S(y₁') − S(y₀'))/(k (y₁ − y₀)) with
/// S(y) = sinh(k y)/sinh(k d) = (e^{k(y−d)} − e^{−k(y+d)}) / (1 − e^{−2kd}) and y' = min(y, d):
/// the part of the interval above the mean surface holds no water and adds nothing (the
/// profile is 0 there, [`depth_profile`]), so a cell cut by the surface has the mean of its
/// wet part times its wet fraction. The velocity of a node's cell averaged exactly
/// (`[loads.waves] lumping = "cell"`).
pub fn cell_profile(k: f64, (y0, y1): (f64, f64), depth: f64) -> f64 {
    if above_surface(y0, depth) {
        return 0.0;
    }
    let s = |y: f64| {
        let y = y.clamp(0.0, depth);
        (libm::exp(k * (y - depth)) - libm::exp(-k * (y + depth))) / -libm::expm1(-2.0 * k * depth)
    };
    (s(y1) - s(y0)) / k / (y1 - y0)
}

/// Below this k·y (y the clamped height above the seabed) the second exponential of
/// [`depth_profile`] and [`cell_profile`], e^{−k(y+d)}, is computed; at and above it, it is
/// below an eighth of the unit in the last place of the first, e^{k(y−d)} (their ratio is
/// e^{−2ky} ≤ e^{−40} < 2⁻⁵⁶), so adding or subtracting it cannot change the rounded sum and
/// [`Profiles`] leaves it out, bit for bit.
const NEGLIGIBLE_KY: f64 = 20.0;

/// Above this exponent k(y − d) the first exponential is a normal number at least 2⁻¹⁰⁰⁹, far
/// above the subnormal range where `libm::exp`'s absolute error of 2⁻¹⁰⁷⁴ could reach the unit in
/// the last place of the sum ([`NEGLIGIBLE_KY`] is only used above it).
const NORMAL_EXPONENT: f64 = -700.0;

/// The complex velocity amplitudes of many heights or cells of one sea, each equal bit for bit
/// to [`Sea::velocity_amplitudes`] or [`Sea::cell_velocity_amplitudes`], for a fraction of their
/// cost: the denominator 1 − e^{−2kⱼd} of every component is computed once (not once per
/// height and cell end), e^{−k(y+d)} is left out where it cannot change the rounded result
/// (k y ≥ 20: e^{−2ky} < 2⁻⁵⁶), and a cell end that is bit for bit the end of the cell before it (the
/// cells of neighbouring nodes share their ends) reuses that end's values. A chain's wave field
/// forms n × N amplitudes this way ([`crate::model::WaveField`]), whatever the run's length.
#[derive(Clone, Debug)]
pub struct Profiles<'a> {
    sea: &'a Sea,
    /// −expm1(−2kⱼd) per component.
    den: Vec<f64>,
    /// The two ends of the last cell: their clamped heights (`None`: not yet formed) and
    /// S(y) of every component there.
    ends: [(Option<f64>, Vec<f64>); 2],
}

impl<'a> Profiles<'a> {
    /// The evaluator of `sea`'s amplitudes (O(N): the denominators).
    pub fn new(sea: &'a Sea) -> Self {
        let d = sea.spec.depth;
        let nc = sea.omega.len();
        Profiles {
            sea,
            den: sea.k.iter().map(|&k| -libm::expm1(-2.0 * k * d)).collect(),
            ends: [(None, vec![0.0; nc]), (None, vec![0.0; nc])],
        }
    }

    /// [`Sea::velocity_amplitudes`] at height y into `out`, bit for bit.
    pub fn velocity_amplitudes(&self, y: f64, out: &mut [Complex<f64>]) {
        let sea = self.sea;
        let depth = sea.spec.depth;
        let nc = sea.omega.len();
        if above_surface(y, depth) {
            // The reference's profile is 0 there: each phasor times ωⱼ · 0.
            for (j, o) in out.iter_mut().enumerate().take(nc) {
                *o = sea.phasor[j] * (sea.omega[j] * 0.0);
            }
            return;
        }
        let yc = y.clamp(0.0, depth);
        for (j, o) in out.iter_mut().enumerate().take(nc) {
            let (w, k) = (sea.omega[j], sea.k[j]);
            let arg = k * (yc - depth);
            let a = libm::exp(arg);
            let num = if k * yc >= NEGLIGIBLE_KY && arg > NORMAL_EXPONENT {
                a
            } else {
                a + libm::exp(-k * (yc + depth))
            };
            *o = sea.phasor[j] * (w * (num / self.den[j]));
        }
    }

    /// S(y) = sinh(k y′)/sinh(k d) of every component at the clamped height y′ = `yc` into
    /// `out`, as [`cell_profile`] forms it.
    fn fill_s(sea: &Sea, den: &[f64], yc: f64, out: &mut [f64]) {
        let depth = sea.spec.depth;
        for ((o, &k), &dn) in out.iter_mut().zip(&sea.k).zip(den) {
            let arg = k * (yc - depth);
            let a = libm::exp(arg);
            let num = if k * yc >= NEGLIGIBLE_KY && arg > NORMAL_EXPONENT {
                a
            } else {
                a - libm::exp(-k * (yc + depth))
            };
            *o = num / dn;
        }
    }

    /// The slot of the last cell's ends that holds the clamped height `yc`, bit for bit.
    fn find(&self, yc: f64) -> Option<usize> {
        (0..2).find(|&e| self.ends[e].0.map(f64::to_bits) == Some(yc.to_bits()))
    }

    /// Forms S at the clamped height `yc` in slot `e`.
    fn fill(&mut self, e: usize, yc: f64) {
        Self::fill_s(self.sea, &self.den, yc, &mut self.ends[e].1);
        self.ends[e].0 = Some(yc);
    }

    /// [`Sea::cell_velocity_amplitudes`] over the heights [y₀, y₁] into `out`, bit for bit.
    pub fn cell_velocity_amplitudes(&mut self, (y0, y1): (f64, f64), out: &mut [Complex<f64>]) {
        let sea = self.sea;
        let depth = sea.spec.depth;
        let nc = sea.omega.len();
        if above_surface(y0, depth) {
            // The reference's profile is 0 there: each phasor times ωⱼ · 0.
            for (j, o) in out.iter_mut().enumerate().take(nc) {
                *o = sea.phasor[j] * (sea.omega[j] * 0.0);
            }
            return;
        }
        let (yc0, yc1) = (y0.clamp(0.0, depth), y1.clamp(0.0, depth));
        // An end shared with the last cell keeps its slot; the other end takes the other slot.
        let (e0, e1) = match (self.find(yc0), self.find(yc1)) {
            (Some(a), Some(b)) => (a, b),
            (Some(a), None) => {
                self.fill(1 - a, yc1);
                (a, 1 - a)
            }
            (None, Some(b)) => {
                self.fill(1 - b, yc0);
                (1 - b, b)
            }
            (None, None) => {
                self.fill(0, yc0);
                self.fill(1, yc1);
                (0, 1)
            }
        };
        let (s0, s1) = (&self.ends[e0].1, &self.ends[e1].1);
        let len = y1 - y0;
        for (j, o) in out.iter_mut().enumerate().take(nc) {
            let profile = (s1[j] - s0[j]) / sea.k[j] / len;
            *o = sea.phasor[j] * (sea.omega[j] * profile);
        }
    }
}
