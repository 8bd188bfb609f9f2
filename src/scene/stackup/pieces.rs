//! The stack-up cut into pieces at the flex joints and the mudline, and the pendulums shared among
//! the pieces in proportion to length × refinement.

use super::*;

/// One uniform stretch of the chain between two forced pendulum ends.
#[derive(Clone, Debug)]
pub(super) struct Piece {
    pub(super) part: usize,
    /// The segment's `refinement` (1 for a body).
    pub(super) refinement: f64,
    pub(super) length: f64,
    /// Mass per length with added mass \[kg/m\] (a body: its total over its height).
    pub(super) mu: f64,
    /// Submerged weight per length \[N/m\].
    pub(super) w: f64,
    /// ½ ρ_w C_d D_h \[kg/m²\].
    pub(super) drag: f64,
    /// ρ_w (1 + C_a) π D_h²/4 \[kg/m\].
    pub(super) inertia: f64,
    pub(super) ei: f64,
    pub(super) body: bool,
}

/// The index of the height in `heights` nearest `at`.
pub(super) fn nearest(heights: &[f64], at: f64) -> usize {
    let mut best = 0;
    for (j, h) in heights.iter().enumerate() {
        if (h - at).abs() < (heights[best] - at).abs() {
            best = j;
        }
    }
    best
}

/// The parts cut at `cuts` (sorted heights) into pieces; a cut inside a body is refused.
pub(super) fn split(parts: &[Piece], cuts: &[f64]) -> Result<Vec<Piece>, SceneError> {
    let mut pieces = Vec::new();
    let mut y0 = 0.0;
    let total: f64 = parts.iter().map(|p| p.length).sum();
    let tol = 1e-9 * total.max(1.0);
    for p in parts {
        let y1 = y0 + p.length;
        let inside: Vec<f64> = cuts
            .iter()
            .copied()
            .filter(|&c| c > y0 + tol && c < y1 - tol)
            .collect();
        if p.body && !inside.is_empty() {
            return Err(SceneError::invalid(
                "stackup.flex_joint",
                format!(
                    "a flex joint or the mudline at {} m lies inside a rigid body ({y0} to {y1} m)",
                    inside[0]
                ),
            ));
        }
        let mut from = y0;
        for c in inside.into_iter().chain(std::iter::once(y1)) {
            pieces.push(Piece {
                length: c - from,
                ..p.clone()
            });
            from = c;
        }
        y0 = y1;
    }
    Ok(pieces)
}

/// Pendulums per piece: one per body; the rest of n shared by the pipe pieces in proportion to
/// their length times their segment's `refinement` (at least one each, largest remainders).
pub(super) fn allocate(n: usize, pieces: &[Piece]) -> Result<Vec<usize>, SceneError> {
    let bodies = pieces.iter().filter(|p| p.body).count();
    let pipes = pieces.len() - bodies;
    if n < pieces.len() {
        return Err(SceneError::invalid(
            "beam.pendulums",
            format!(
                "the stack-up has {} pieces between its forced pendulum ends (segments and \
                 bodies, cut at the flex joints and the mudline): at least {} pendulums, got {n}",
                pieces.len(),
                pieces.len()
            ),
        ));
    }
    let free = n - bodies;
    // The weighted length r·L (r = 1: L exactly, so the shares are those of the plain lengths
    // bit for bit).
    let weighted = |p: &Piece| p.length * p.refinement;
    let pipe_length: f64 = pieces.iter().filter(|p| !p.body).map(weighted).sum();
    let mut counts = vec![1usize; pieces.len()];
    let mut spare = free - pipes;
    // Ideal shares beyond the first pendulum each, then the largest remainders.
    let mut rema: Vec<(f64, usize)> = Vec::new();
    for (i, p) in pieces.iter().enumerate() {
        if p.body {
            continue;
        }
        let ideal = free as f64 * weighted(p) / pipe_length;
        let extra = ((ideal - 1.0).max(0.0).floor() as usize).min(spare);
        counts[i] += extra;
        spare -= extra;
        rema.push((ideal - counts[i] as f64, i));
    }
    rema.sort_by(|a, b| b.0.total_cmp(&a.0).then(a.1.cmp(&b.1)));
    for &(_, i) in rema.iter().cycle().take(spare) {
        counts[i] += 1;
    }
    Ok(counts)
}
