//! Force bounds L ≤ θᵢ ≤ U as a sine reparametrisation θ = c + r sin((φ − c)/r) with centre
//! c = (L + U)/2 and half-width r = (U − L)/2 (module docs of [`optimize`](super), "Bounded
//! controls"), and the first-order (KKT) measure at a bounded result. The symmetric bound
//! |θᵢ| ≤ b is the box [−b, b] ([`Bounds::symmetric`]), where the map is θ = b sin(φ/b).

use crate::error::{Error, OptimizeError, Requirement, Result};

/// A start closer than this fraction of the half-width r to a bound is moved this far inside
/// (the bound is a stationary point of the sine reparametrisation).
pub(crate) const BOUND_PULL_IN: f64 = 1e-4;

/// A component within this fraction of the half-width r of a bound counts as on the bound (for
/// [`OptimResult::active_bounds`](super::OptimResult::active_bounds) and the projected
/// gradient).
pub const ACTIVE_BOUND_TOL: f64 = 1e-6;

/// A box L ≤ θᵢ ≤ U on every parameter (for a control problem with a built-in
/// parametrisation: on every force u_k, in N), with finite L < U.
///
/// ```
/// use chainbeam::optimize::Bounds;
///
/// let b = Bounds::new(-2.0, 6.0)?;
/// assert_eq!((b.centre(), b.radius()), (2.0, 4.0));
/// assert_eq!(Bounds::symmetric(3.0)?, Bounds::new(-3.0, 3.0)?);
/// assert!(Bounds::new(1.0, 1.0).is_err()); // empty interior
/// # Ok::<(), chainbeam::Error>(())
/// ```
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Bounds {
    lower: f64,
    upper: f64,
}

impl Bounds {
    /// The box [lower, upper].
    ///
    /// # Errors
    /// [`OptimizeError::EmptyBox`] unless both are finite and lower < upper (with U − L
    /// finite, so the half-width is).
    pub fn new(lower: f64, upper: f64) -> Result<Self> {
        if !(lower.is_finite() && upper.is_finite() && lower < upper && (upper - lower).is_finite())
        {
            return Err(OptimizeError::EmptyBox { lower, upper }.into());
        }
        Ok(Bounds { lower, upper })
    }

    /// The symmetric box [−b, b].
    ///
    /// # Errors
    /// [`ValueError::OutOfRange`](crate::error::ValueError::OutOfRange) (`bound`) unless b is positive and finite.
    pub fn symmetric(b: f64) -> Result<Self> {
        check_bound(Some(b))?;
        Ok(Bounds {
            lower: -b,
            upper: b,
        })
    }

    /// L.
    pub fn lower(&self) -> f64 {
        self.lower
    }

    /// U.
    pub fn upper(&self) -> f64 {
        self.upper
    }

    /// The centre c = (L + U)/2 (computed as L/2 + U/2, which cannot overflow).
    pub fn centre(&self) -> f64 {
        0.5 * self.lower + 0.5 * self.upper
    }

    /// The half-width r = (U − L)/2.
    pub fn radius(&self) -> f64 {
        0.5 * (self.upper - self.lower)
    }

    /// Whether L ≤ x ≤ U.
    pub fn contains(&self, x: f64) -> bool {
        self.lower <= x && x <= self.upper
    }

    /// Whether x is within [`ACTIVE_BOUND_TOL`]·r of U (first) or of L (second).
    pub fn at_bounds(&self, x: f64) -> (bool, bool) {
        let tol = ACTIVE_BOUND_TOL * self.radius();
        (x >= self.upper - tol, x <= self.lower + tol)
    }
}

/// Checks a bound b: positive and finite.
pub(crate) fn check_bound(bound: Option<f64>) -> Result<()> {
    match bound {
        Some(b) => Ok(Requirement::PositiveFinite
            .check("bound", b)
            .map_err(OptimizeError::from)?),
        None => Ok(()),
    }
}

/// θ = c + r sin((φ − c)/r) componentwise, clamped into [L, U] against rounding (θ = φ without
/// bounds).
pub(crate) fn to_theta(bounds: Option<Bounds>, phi: &[f64]) -> Vec<f64> {
    match bounds {
        None => phi.to_vec(),
        Some(b) => {
            let (c, r) = (b.centre(), b.radius());
            phi.iter()
                .map(|&p| (c + r * ((p - c) / r).sin()).clamp(b.lower, b.upper))
                .collect()
        }
    }
}

/// φ = c + r asin((θ − c)/r): an error if θ is not finite or outside the box; components closer
/// than [`BOUND_PULL_IN`]·r to a bound are moved that far inside.
pub(crate) fn to_phi(bounds: Option<Bounds>, theta: &[f64]) -> Result<Vec<f64>> {
    if let Some(i) = theta.iter().position(|x| !x.is_finite()) {
        return Err(Error::NotFinite {
            name: "theta0",
            index: i,
        });
    }
    let Some(b) = bounds else {
        return Ok(theta.to_vec());
    };
    let (c, r) = (b.centre(), b.radius());
    let lim = 1.0 - BOUND_PULL_IN;
    theta
        .iter()
        .enumerate()
        .map(|(i, &t)| {
            if !b.contains(t) {
                return Err(OptimizeError::InfeasibleStart {
                    index: i,
                    value: t,
                    lower: b.lower,
                    upper: b.upper,
                }
                .into());
            }
            Ok(c + r * ((t - c) / r).clamp(-lim, lim).asin())
        })
        .collect()
}

/// g_φ = cos((φ − c)/r) ⊙ g_θ (g_θ itself without bounds).
pub(crate) fn grad_phi(bounds: Option<Bounds>, phi: &[f64], grad_theta: &[f64]) -> Vec<f64> {
    match bounds {
        None => grad_theta.to_vec(),
        Some(b) => {
            let (c, r) = (b.centre(), b.radius());
            phi.iter()
                .zip(grad_theta)
                .map(|(&p, &g)| ((p - c) / r).cos() * g)
                .collect()
        }
    }
}

/// The chain rule of the Hessian under bounds, H_φ v = J ⊙ H_θ (J ⊙ v) + c ⊙ v, as the vectors
/// (J, c) = (cos((φ − c)/r), −g_θ ⊙ (θ − c) / r²); `None` without bounds.
pub(crate) fn hessian_chain(
    bounds: Option<Bounds>,
    phi: &[f64],
    theta: &[f64],
    grad_theta: &[f64],
) -> Option<(Vec<f64>, Vec<f64>)> {
    let b = bounds?;
    let (c, r) = (b.centre(), b.radius());
    let jac = phi.iter().map(|&x| ((x - c) / r).cos()).collect();
    let curv = theta
        .iter()
        .zip(grad_theta)
        .map(|(&t, &g)| -g * (t - c) / (r * r))
        .collect();
    Some((jac, curv))
}

/// The projected gradient norm and the active bounds at θ.
pub(crate) fn kkt(theta: &[f64], g: &[f64], bounds: Option<Bounds>) -> (f64, Vec<usize>) {
    let Some(b) = bounds else {
        return (super::norm(g), Vec::new());
    };
    let mut active = Vec::new();
    let mut s = 0.0;
    for (i, (&t, &gi)) in theta.iter().zip(g).enumerate() {
        let (upper, lower) = b.at_bounds(t);
        if upper || lower {
            active.push(i);
        }
        // At the upper bound descent (−g) is blocked when g < 0; at the lower when g > 0.
        if !((upper && gi < 0.0) || (lower && gi > 0.0)) {
            s += gi * gi;
        }
    }
    (s.sqrt(), active)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The map and its inverse: θ(φ(θ)) = θ inside the box, and the symmetric box reduces to
    /// θ = b sin(φ/b) bit for bit (c = 0).
    #[test]
    fn map_round_trips_and_reduces_to_the_symmetric_sine() {
        let b = Bounds::new(-1.0, 7.0).unwrap();
        let theta = [-0.5, 0.0, 3.0, 6.5];
        let back = to_theta(Some(b), &to_phi(Some(b), &theta).unwrap());
        for (x, y) in theta.iter().zip(&back) {
            assert!((x - y).abs() < 1e-14, "{x} vs {y}");
        }
        let s = Bounds::symmetric(2.5).unwrap();
        let phi: [f64; 4] = [-3.0, -0.1, 0.7, 4.0];
        let expected: Vec<f64> = phi.iter().map(|&p| 2.5 * (p / 2.5).sin()).collect();
        assert_eq!(to_theta(Some(s), &phi), expected);
    }

    /// Every φ maps into [L, U], including the extremes φ = c ± rπ/2 (where rounding of c ± r
    /// could step outside without the clamp).
    #[test]
    fn every_phi_maps_into_the_box() {
        let b = Bounds::new(0.1, 0.7).unwrap();
        let (c, r) = (b.centre(), b.radius());
        let h = std::f64::consts::FRAC_PI_2;
        let phi: Vec<f64> = (-400..=400).map(|k| c + r * h * k as f64 / 100.0).collect();
        assert!(to_theta(Some(b), &phi).iter().all(|&t| b.contains(t)));
    }

    /// A start outside the box is refused, naming the entry and the box.
    #[test]
    fn start_outside_the_box_is_refused() {
        let b = Bounds::new(1.0, 3.0).unwrap();
        let e = to_phi(Some(b), &[2.0, 0.0]).unwrap_err().to_string();
        assert!(e.contains("entry 1 = 0") && e.contains("[1, 3]"), "{e}");
    }
}
