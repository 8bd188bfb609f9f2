//! One evaluated point of a [`minimize`](super::minimize) run, in the solver variables φ and in
//! θ: what the adapter caches, the supervisor keeps and the observers are shown.

/// One evaluated point: φ and θ = θ(φ), J(θ), ∇_θJ and ∇_φ(s·J) (module docs of
/// [`optimize`](super): the solver variables).
#[derive(Clone, Debug)]
pub(crate) struct Point {
    pub(crate) phi: Vec<f64>,
    pub(crate) theta: Vec<f64>,
    pub(crate) value: f64,
    pub(crate) grad_theta: Vec<f64>,
    pub(crate) grad_phi: Vec<f64>,
}

/// Whether two points have the same bits (the cache's identity of a point).
pub(crate) fn same_bits(a: &[f64], b: &[f64]) -> bool {
    a.len() == b.len() && a.iter().zip(b).all(|(x, y)| x.to_bits() == y.to_bits())
}
