//! The box-constrained QP of one stage, solved exactly (m = 1 control per stage: a scalar
//! clamp, no iteration).
//!
//! min_δ ½ a δ² + g δ subject to lo ≤ δ ≤ hi (lo ≤ 0 ≤ hi: the nominal control is feasible).
//! With a > 0 the minimiser is δ* = clamp(−g/a, lo, hi) (the projected Newton step is exact in
//! one dimension: Tassa, Mansard, Todorov, *Control-limited differential dynamic programming*,
//! ICRA 2014, whose projected-Newton box-QP reduces to this for m = 1). When δ* sits on a bound
//! the control is *clamped*: its feedback gain is zero (a perturbation of the state does not
//! move a control held at its bound, to first order).

/// One component of the projected gradient θ − Π_[lo,hi](θ − g), computed without
/// cancellation: g itself where the projection does not bind (θ − g inside the box), the
/// distance θ − lo (θ − hi) to the bound it reaches otherwise. The textbook form
/// θ − clamp(θ − g) loses every |g| below half an ulp of θ: on Table 3.4's rows, controls of
/// ~10³ N with free-control gradients of 10⁻¹⁴ reported a projected gradient of exactly 0, which
/// met even a tolerance of 0.
#[inline]
pub(crate) fn projected_component(theta: f64, g: f64, lo: f64, hi: f64) -> f64 {
    if g > theta - lo {
        theta - lo
    } else if g < theta - hi {
        theta - hi
    } else {
        g
    }
}

/// The solution of one scalar box-QP.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct BoxQpStep {
    /// The step δ*.
    pub step: f64,
    /// Whether δ* is on a bound (or the control is inert): its feedback gain is 0.
    pub clamped: bool,
}

/// Solves min ½ a δ² + g δ on [lo, hi]. Returns `None` when the problem is unbounded below
/// (a ≤ 0 with g pushing toward an infinite bound): the caller then raises the regularisation.
/// An inert control (a ≤ 0 and g = 0, e.g. u_N without effort penalty) stays where it is. With
/// lo = hi (a control the active set fixes) the step is lo, clamped.
pub(crate) fn solve_scalar(a: f64, g: f64, lo: f64, hi: f64) -> Option<BoxQpStep> {
    if hi <= lo {
        // A control fixed by the active set: it moves to the given point, without feedback.
        return Some(BoxQpStep {
            step: lo,
            clamped: true,
        });
    }
    if a > 0.0 {
        let d = -g / a;
        return Some(if d <= lo {
            BoxQpStep {
                step: lo,
                clamped: true,
            }
        } else if d >= hi {
            BoxQpStep {
                step: hi,
                clamped: true,
            }
        } else {
            BoxQpStep {
                step: d,
                clamped: false,
            }
        });
    }
    // Non-positive curvature: the minimum is on a bound in the descent direction, if finite.
    let step = if g > 0.0 {
        lo
    } else if g < 0.0 {
        hi
    } else {
        0.0
    };
    step.is_finite().then_some(BoxQpStep {
        step,
        clamped: true,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Reference: the definition θ − Π(θ − g) evaluated by hand. A free control of 10³ keeps a
    /// gradient of 10⁻¹⁴ (the textbook form rounds it to exactly 0); on a bound with the
    /// gradient pushing outward the component is 0; a step that crosses the bound is cut at it.
    #[test]
    fn projected_component_keeps_small_gradients() {
        // Every value here is exact in f64: compared bit for bit.
        let same = |x: f64, y: f64| assert_eq!(x.to_bits(), y.to_bits(), "{x} vs {y}");
        let (lo, hi) = (-2000.0, 2000.0);
        same(1000.0 - (1000.0f64 - 1e-14).clamp(lo, hi), 0.0);
        same(projected_component(1000.0, 1e-14, lo, hi), 1e-14);
        same(projected_component(lo, 3.0, lo, hi), 0.0);
        same(projected_component(hi, -3.0, lo, hi), 0.0);
        same(projected_component(hi, 3.0, lo, hi), 3.0);
        same(projected_component(1999.0, -3.0, lo, hi), -1.0);
        same(projected_component(-1999.5, 1.0, lo, hi), 0.5);
        let inf = f64::INFINITY;
        same(projected_component(7.0, -5.0, -inf, inf), -5.0);
    }

    /// Reference: the closed-form minimiser of a convex parabola on an interval.
    #[test]
    fn clamps_and_releases() {
        let s = solve_scalar(2.0, -4.0, -1.0, 5.0).unwrap();
        assert_eq!(
            s,
            BoxQpStep {
                step: 2.0,
                clamped: false
            }
        );
        let s = solve_scalar(2.0, -4.0, -1.0, 1.5).unwrap();
        assert_eq!(
            s,
            BoxQpStep {
                step: 1.5,
                clamped: true
            }
        );
        let s = solve_scalar(2.0, 4.0, -0.5, 1.0).unwrap();
        assert_eq!(
            s,
            BoxQpStep {
                step: -0.5,
                clamped: true
            }
        );
        // inert and unbounded
        let inert = solve_scalar(0.0, 0.0, -1.0, 1.0).unwrap();
        assert_eq!(
            inert,
            BoxQpStep {
                step: 0.0,
                clamped: true
            }
        );
        assert!(solve_scalar(0.0, 1.0, f64::NEG_INFINITY, 1.0).is_none());
        let concave = solve_scalar(-1.0, 1.0, -3.0, 1.0).unwrap();
        assert_eq!(
            concave,
            BoxQpStep {
                step: -3.0,
                clamped: true
            }
        );
        // fixed by the active set
        let s = solve_scalar(2.0, -4.0, 0.25, 0.25).unwrap();
        assert_eq!(
            s,
            BoxQpStep {
                step: 0.25,
                clamped: true
            }
        );
    }
}
