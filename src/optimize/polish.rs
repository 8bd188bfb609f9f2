//! The gradient polish (module docs of [`optimize`](super), "Gradient polish"): Newton steps on
//! ∇J = 0 with the gradient norm as merit, after cost-based globalisation stalls at J's
//! round-off.

use super::adapter::ArgminAdapter;
use super::norm;
use super::point::Point;
use super::problem::OptimProblem;
use crate::error::Result;

/// The gradient polish accepts a step that raises J by at most this fraction of |J| (J's
/// round-off; measured 2·10⁻¹³ on the thesis riser, see the module docs).
pub const POLISH_COST_TOL: f64 = 1e-10;
/// Relative residual at which the polish's CG stops.
const POLISH_CG_TOL: f64 = 1e-10;

/// One Newton step of the gradient polish, tried at lengths 1, ½, ¼: `None` if CG meets
/// non-positive curvature first or no length reduces ‖g‖ within the cost allowance (a trial
/// point whose evaluation fails counts as no reduction); an HVP's error otherwise (the caller
/// reports it and keeps the point it has).
pub(crate) fn polish_step<Q: OptimProblem + ?Sized>(
    adapter: &ArgminAdapter<'_, Q>,
    at: &Point,
    max_cg: usize,
) -> Result<Option<Point>> {
    let op = adapter.operator(&at.phi)?;
    let g = &at.grad_phi;
    let gn = norm(g);
    let n = g.len();
    let mut x = vec![0.0; n];
    let mut r: Vec<f64> = g.iter().map(|v| -v).collect();
    let mut d = r.clone();
    let mut rr = gn * gn;
    for it in 0..max_cg {
        let hd = op.apply(&d)?;
        let dhd: f64 = d.iter().zip(&hd).map(|(a, b)| a * b).sum();
        if dhd <= 0.0 || !dhd.is_finite() {
            if it == 0 {
                return Ok(None);
            }
            break;
        }
        let alpha = rr / dhd;
        for i in 0..n {
            x[i] += alpha * d[i];
            r[i] -= alpha * hd[i];
        }
        let rr_new: f64 = r.iter().map(|v| v * v).sum();
        if rr_new.sqrt() <= POLISH_CG_TOL * gn {
            break;
        }
        let beta = rr_new / rr;
        for i in 0..n {
            d[i] = r[i] + beta * d[i];
        }
        rr = rr_new;
    }
    let allowed = at.value + POLISH_COST_TOL * at.value.abs();
    for alpha in [1.0, 0.5, 0.25] {
        let phi: Vec<f64> = at.phi.iter().zip(&x).map(|(a, b)| a + alpha * b).collect();
        if let Ok(next) = adapter.evaluate(&phi) {
            if norm(&next.grad_phi) < gn && next.value <= allowed {
                return Ok(Some(next));
            }
        }
    }
    Ok(None)
}
