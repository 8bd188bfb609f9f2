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

/// The solution of a two-control box-QP (a 2-axis control's stage).
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct BoxQpPair {
    /// The step δ*.
    pub step: [f64; 2],
    /// Which components are on a bound (or fixed): their feedback gains are 0.
    pub clamped: [bool; 2],
}

/// Solves min ½ δᵀAδ + gᵀδ on the box lo ≤ δ ≤ hi (two controls; lo ≤ 0 ≤ hi per component,
/// lo = hi for a component the active set fixes), exactly: a fixed component is set and the
/// other solved by [`solve_scalar`]; a diagonal A separates into two scalar problems; with A
/// positive definite the unconstrained minimiser −A⁻¹g if it lies inside the box; otherwise
/// the minimum lies on the box's boundary (a convex quadratic whose minimiser is outside, or a
/// nonconvex one), the best of its (at most four) edges, each a component on a finite bound
/// and the other by [`solve_scalar`]. `None` when the problem is unbounded below (a nonconvex
/// A with an infinite bound, or an edge that is): the caller raises the regularisation.
pub(crate) fn solve_pair(
    a: [[f64; 2]; 2],
    g: [f64; 2],
    lo: [f64; 2],
    hi: [f64; 2],
) -> Option<BoxQpPair> {
    // Component c at x (clamped), the other by its scalar QP.
    let edge = |c: usize, x: f64| -> Option<BoxQpPair> {
        let f = 1 - c;
        let s = solve_scalar(a[f][f], g[f] + a[f][c] * x, lo[f], hi[f])?;
        let (mut step, mut clamped) = ([0.0; 2], [true; 2]);
        step[c] = x;
        step[f] = s.step;
        clamped[f] = s.clamped;
        Some(BoxQpPair { step, clamped })
    };
    for c in 0..2 {
        if hi[c] <= lo[c] {
            return edge(c, lo[c]);
        }
    }
    if a[0][1] == 0.0 && a[1][0] == 0.0 {
        let s0 = solve_scalar(a[0][0], g[0], lo[0], hi[0])?;
        let s1 = solve_scalar(a[1][1], g[1], lo[1], hi[1])?;
        return Some(BoxQpPair {
            step: [s0.step, s1.step],
            clamped: [s0.clamped, s1.clamped],
        });
    }
    let det = a[0][0] * a[1][1] - a[0][1] * a[1][0];
    let convex = a[0][0] > 0.0 && det > 0.0;
    if convex {
        let x = [
            (a[0][1] * g[1] - a[1][1] * g[0]) / det,
            (a[1][0] * g[0] - a[0][0] * g[1]) / det,
        ];
        if (0..2).all(|c| lo[c] < x[c] && x[c] < hi[c]) {
            return Some(BoxQpPair {
                step: x,
                clamped: [false; 2],
            });
        }
    }
    let value = |s: &BoxQpPair| {
        let d = s.step;
        0.5 * (d[0] * (a[0][0] * d[0] + a[0][1] * d[1]) + d[1] * (a[1][0] * d[0] + a[1][1] * d[1]))
            + g[0] * d[0]
            + g[1] * d[1]
    };
    let mut best: Option<(f64, BoxQpPair)> = None;
    for c in 0..2 {
        for x in [lo[c], hi[c]] {
            if !x.is_finite() {
                if convex {
                    continue;
                }
                return None;
            }
            let s = edge(c, x)?;
            let v = value(&s);
            if best.is_none_or(|(b, _)| v < b) {
                best = Some((v, s));
            }
        }
    }
    best.map(|(_, s)| s)
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

    /// Reference: the minimiser of ½ δᵀAδ + gᵀδ over a grid of the box (step 10⁻³, the box's
    /// corners and edges included), against which the exact solution may not be higher; and
    /// the closed-form unconstrained minimiser when it lies inside.
    #[test]
    fn pair_matches_grid_minimum() {
        let a = [[2.0, 0.8], [0.8, 1.0]];
        let value = |d: [f64; 2], g: [f64; 2]| {
            0.5 * (d[0] * (a[0][0] * d[0] + a[0][1] * d[1])
                + d[1] * (a[1][0] * d[0] + a[1][1] * d[1]))
                + g[0] * d[0]
                + g[1] * d[1]
        };
        // Inside: −A⁻¹g = (1, −1) for g = −A (1, −1) = (−1.2, 0.2).
        let s = solve_pair(a, [-1.2, 0.2], [-2.0, -2.0], [2.0, 2.0]).unwrap();
        assert!((s.step[0] - 1.0).abs() < 1e-15 && (s.step[1] + 1.0).abs() < 1e-15);
        assert_eq!(s.clamped, [false, false]);
        for g in [[-5.0, 1.0], [3.0, 3.0], [-0.3, -4.0], [4.0, -0.5]] {
            let (lo, hi) = ([-1.0, -0.5], [0.7, 1.2]);
            let s = solve_pair(a, g, lo, hi).unwrap();
            let mut best = f64::INFINITY;
            for i in 0..=1700 {
                for j in 0..=1700 {
                    let d = [lo[0] + i as f64 * 1e-3, lo[1] + j as f64 * 1e-3];
                    if d[0] <= hi[0] + 1e-12 && d[1] <= hi[1] + 1e-12 {
                        best = best.min(value(d, g));
                    }
                }
            }
            let v = value(s.step, g);
            assert!(v <= best + 1e-12, "g {g:?}: {v} above the grid's {best}");
            assert!(best - v <= 1e-5, "g {g:?}: {v} far below the grid's {best}");
            assert!(s.clamped.iter().any(|&c| c), "g {g:?}: expected a bound");
        }
        // A fixed component: the other by its scalar QP (min ½·1·d² + (0.2 + 0.8·0.5) d).
        let s = solve_pair(a, [1.0, 0.2], [0.5, -3.0], [0.5, 3.0]).unwrap();
        assert_eq!(s.step[0].to_bits(), 0.5f64.to_bits());
        assert!((s.step[1] + 0.6).abs() < 1e-15);
        assert_eq!(s.clamped, [true, false]);
        // Nonconvex with an infinite bound: unbounded.
        assert!(solve_pair(
            [[1.0, 2.0], [2.0, 1.0]],
            [0.0, 1.0],
            [-1.0, f64::NEG_INFINITY],
            [1.0, 1.0]
        )
        .is_none());
    }
}
