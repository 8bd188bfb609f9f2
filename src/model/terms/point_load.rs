//! Point loads F_k at nodes k, constant while switched on (thesis eq. 2.2.2, SPEC §1).

use super::{Ctx, Embed, ForceTerm};
use crate::error::Result;
use crate::model::geometry::zi;
use crate::model::{Parameter, Scalar};

/// One point load as the model uses it.
#[derive(Clone, Debug)]
pub struct PointLoad<D> {
    /// Node 1..=n.
    pub node: usize,
    /// The force F (thesis sign: enters U as +F z).
    pub force: D,
    /// Switched on at this time \[s\].
    pub start: f64,
    /// Switched off at this time \[s\] (∞: never).
    pub end: f64,
    /// Index in the scene's list (for [`Parameter::LoadForce`]).
    pub scene_index: usize,
}

impl<D> PointLoad<D> {
    /// Whether the load acts at time t (half-open window [start, end), with a relative tolerance
    /// of 1e-9 so that t = k h lands on the intended side of a window edge).
    #[inline]
    pub fn active(&self, t: f64) -> bool {
        let tol = 1e-9 * t.abs().max(1.0);
        t + tol >= self.start && t + tol < self.end
    }
}

/// The point loads of a scene: U = Σ_k F_k Σ_{i≤k} lᵢ e₃ᵀqᵢ (eq. 2.2.2), so pendulum j feels
/// l_j (Σ_{k≥j} F_k) e₃.
#[derive(Clone, Debug)]
pub struct PointLoads<D> {
    /// Sorted by node, descending.
    pub(crate) loads: Vec<PointLoad<D>>,
    pub(crate) lengths: Vec<D>,
}

impl<D: Scalar> PointLoads<D> {
    /// The loads on a chain with pendulum lengths `lengths`.
    pub(crate) fn new(mut loads: Vec<PointLoad<D>>, lengths: Vec<D>) -> Self {
        loads.sort_by_key(|l| std::cmp::Reverse(l.node));
        PointLoads { loads, lengths }
    }

    /// The same loads over another scalar (real parts).
    pub(crate) fn lift<D2: Scalar>(&self) -> PointLoads<D2> {
        PointLoads {
            loads: self
                .loads
                .iter()
                .map(|l| PointLoad {
                    node: l.node,
                    force: D2::from(l.force.re()),
                    start: l.start,
                    end: l.end,
                    scene_index: l.scene_index,
                })
                .collect(),
            lengths: self.lengths.iter().map(|x| D2::from(x.re())).collect(),
        }
    }

    /// Calls `f(j, l_j c_j)` for j = n−1..0 with c_j = Σ_{k ≥ j} F_k(t) (0-based j).
    #[inline]
    fn for_each<E: Embed<D>>(&self, ctx: &Ctx<E>, mut f: impl FnMut(usize, E)) {
        let mut acc = E::zero();
        let mut li = 0;
        for j in (0..self.lengths.len()).rev() {
            while li < self.loads.len() && self.loads[li].node == j + 1 {
                let l = &self.loads[li];
                if l.active(ctx.t) {
                    acc += ctx.param(Parameter::LoadForce(l.scene_index), l.force);
                }
                li += 1;
            }
            f(j, E::embed(self.lengths[j]) * acc);
        }
    }
}

impl<D: Scalar, const DIM: usize> ForceTerm<D, DIM> for PointLoads<D> {
    fn name(&self) -> &'static str {
        "point loads"
    }

    fn energy<E: Embed<D>>(&self, q: &[[E; DIM]], ctx: &Ctx<E>) -> E {
        let mut u = E::zero();
        self.for_each(ctx, |j, c| u += c * q[j][zi::<DIM>()]);
        u
    }

    fn force<E: Embed<D>>(
        &self,
        _q: &[[E; DIM]],
        ctx: &Ctx<E>,
        out: &mut [[E; DIM]],
    ) -> Result<()> {
        self.for_each(ctx, |j, c| out[j][zi::<DIM>()] += c);
        Ok(())
    }

    fn depends_on_configuration(&self) -> bool {
        false
    }

    fn has_parameter(&self, p: Parameter) -> bool {
        matches!(p, Parameter::LoadForce(i) if self.loads.iter().any(|l| l.scene_index == i))
    }
}
