//! Point loads F_k(t) at nodes k (thesis eq. 2.2.2, docs/conventions.md and §6): vectors in the transverse
//! plane (x, z), constant, harmonic, or interpolated from a time series, switched on and off by a
//! window and ramped in.

use std::sync::Arc;

use super::{Ctx, Embed, ForceTerm};
use crate::base::{Parameter, Scalar};
use crate::error::Result;
use crate::model::geometry::zi;
use crate::scene::series::interpolate;

/// One harmonic A sin(2π t/T + φ) of a point load, with A and φ read as the parameters
/// [`Parameter::LoadAmplitude`] and [`Parameter::LoadPhase`].
#[derive(Clone, Debug)]
pub struct HarmonicForce<D> {
    /// Amplitude A \[N\].
    pub amplitude: D,
    /// Period T \[s\].
    pub period: f64,
    /// Phase φ \[rad\].
    pub phase: D,
}

/// One point load as the model uses it: at time t the force vector
/// F(t) = w(t) ρ(t) [(F_x, F_z) + d Σⱼ Aⱼ sin(2π t/Tⱼ + φⱼ) + S(t)] (see [`crate::PointLoad`]).
#[derive(Clone, Debug)]
pub struct ChainPointLoad<D> {
    /// Node 1..=n.
    pub node: usize,
    /// The constant force's z component F_z (thesis sign: enters U as +F z).
    pub force: D,
    /// The constant force's x component F_x (spatial model only; same sign convention).
    pub force_x: D,
    /// Switched on at this time \[s\].
    pub start: f64,
    /// Switched off at this time \[s\] (∞: never).
    pub end: f64,
    /// Ramp-in time \[s\] (0: none).
    pub ramp: f64,
    /// Unit direction (d_x, d_z) of the harmonics.
    pub direction: [f64; 2],
    /// The harmonics along `direction`.
    pub harmonics: Vec<HarmonicForce<D>>,
    /// Rows (t, F_x, F_z) of a time series, interpolated linearly (shared, not copied, by clones).
    pub series: Option<Arc<[[f64; 3]]>>,
    /// Index in the scene's list (for the load parameters).
    pub scene_index: usize,
}

impl<D> ChainPointLoad<D> {
    /// Whether the load acts at time t (half-open window [start, end), with a relative tolerance
    /// of 1e-9 so that t = k h lands on the intended side of a window edge).
    #[inline]
    pub fn active(&self, t: f64) -> bool {
        let tol = 1e-9 * t.abs().max(1.0);
        t + tol >= self.start && t + tol < self.end
    }

    /// The ramp factor ρ(t) = ½(1 − cos(π (t − start)/T_r)) during the ramp-in, `None` (ρ = 1)
    /// after it or without a ramp.
    #[inline]
    pub fn ramp_factor(&self, t: f64) -> Option<f64> {
        let s = t - self.start;
        (self.ramp > 0.0 && s < self.ramp)
            .then(|| 0.5 * (1.0 - (std::f64::consts::PI * s.max(0.0) / self.ramp).cos()))
    }
}

impl<D: Scalar> ChainPointLoad<D> {
    /// The force (F_x, F_z) at the context's time (zero outside the window), its parameters read
    /// through [`Ctx::param`] so that their derivatives come from this one definition.
    #[inline]
    pub fn value<E: Embed<D>>(&self, ctx: &Ctx<E>) -> [E; 2] {
        let t = ctx.t;
        if !self.active(t) {
            return [E::zero(); 2];
        }
        let i = self.scene_index;
        let mut fx = ctx.param(Parameter::LoadForceX(i), self.force_x);
        let mut fz = ctx.param(Parameter::LoadForce(i), self.force);
        if !self.harmonics.is_empty() {
            let mut s = E::zero();
            for (j, h) in self.harmonics.iter().enumerate() {
                let (load, harmonic) = (i, j);
                let a = ctx.param(Parameter::LoadAmplitude { load, harmonic }, h.amplitude);
                let phi = ctx.param(Parameter::LoadPhase { load, harmonic }, h.phase);
                s += a * (phi + std::f64::consts::TAU * t / h.period).sin();
            }
            fx += s * self.direction[0];
            fz += s * self.direction[1];
        }
        if let Some(rows) = &self.series {
            let [sx, sz] = interpolate(rows, t);
            fx += sx;
            fz += sz;
        }
        if let Some(r) = self.ramp_factor(t) {
            fx *= r;
            fz *= r;
        }
        [fx, fz]
    }

    fn lift<D2: Scalar>(&self) -> ChainPointLoad<D2> {
        let l = |x: D| D2::from(x.re());
        ChainPointLoad {
            node: self.node,
            force: l(self.force),
            force_x: l(self.force_x),
            start: self.start,
            end: self.end,
            ramp: self.ramp,
            direction: self.direction,
            harmonics: self
                .harmonics
                .iter()
                .map(|h| HarmonicForce {
                    amplitude: l(h.amplitude),
                    period: h.period,
                    phase: l(h.phase),
                })
                .collect(),
            series: self.series.clone(),
            scene_index: self.scene_index,
        }
    }

    /// Whether the load reads parameter `p` (`spatial`: whether F_x is part of the model).
    fn reads(&self, p: Parameter, spatial: bool) -> bool {
        let i = self.scene_index;
        match p {
            Parameter::LoadForce(k) => k == i,
            Parameter::LoadForceX(k) => k == i && spatial,
            Parameter::LoadAmplitude { load, harmonic }
            | Parameter::LoadPhase { load, harmonic } => {
                load == i && harmonic < self.harmonics.len()
            }
            _ => false,
        }
    }
}

/// The point loads of a scene: U = Σ_k F_k(t) · Σ_{i≤k} lᵢ qᵢ over the transverse components
/// (eq. 2.2.2; x only in the spatial model), so pendulum j feels l_j Σ_{k≥j} F_k(t).
#[derive(Clone, Debug)]
pub struct PointLoads<D> {
    /// Sorted by node, descending.
    pub(crate) loads: Vec<ChainPointLoad<D>>,
    pub(crate) lengths: Vec<D>,
}

impl<D: Scalar> PointLoads<D> {
    /// The loads on a chain with pendulum lengths `lengths`.
    pub(crate) fn new(mut loads: Vec<ChainPointLoad<D>>, lengths: Vec<D>) -> Self {
        loads.sort_by_key(|l| std::cmp::Reverse(l.node));
        PointLoads { loads, lengths }
    }

    /// The same loads over another scalar (real parts).
    pub(crate) fn lift<D2: Scalar>(&self) -> PointLoads<D2> {
        PointLoads {
            loads: self.loads.iter().map(ChainPointLoad::lift).collect(),
            lengths: self.lengths.iter().map(|x| D2::from(x.re())).collect(),
        }
    }

    /// The load of scene index `i`, if the model has it.
    pub(crate) fn by_scene_index(&mut self, i: usize) -> Option<&mut ChainPointLoad<D>> {
        self.loads.iter_mut().find(|l| l.scene_index == i)
    }

    /// Whether some load reads parameter `p` (`spatial`: whether the model has x components).
    pub(crate) fn reads(&self, p: Parameter, spatial: bool) -> bool {
        self.loads.iter().any(|l| l.reads(p, spatial))
    }

    /// Calls `f(j, l_j c_j)` for j = n−1..0 with c_j = Σ_{k ≥ j} F_k(t) (0-based j), c_j as
    /// (x, z).
    #[inline]
    fn for_each<E: Embed<D>>(&self, ctx: &Ctx<E>, mut f: impl FnMut(usize, [E; 2])) {
        let mut acc = [E::zero(); 2];
        let mut li = 0;
        for j in (0..self.lengths.len()).rev() {
            while li < self.loads.len() && self.loads[li].node == j + 1 {
                let [fx, fz] = self.loads[li].value(ctx);
                acc[0] += fx;
                acc[1] += fz;
                li += 1;
            }
            let l = E::embed(self.lengths[j]);
            f(j, [l * acc[0], l * acc[1]]);
        }
    }
}

impl<D: Scalar, const DIM: usize> ForceTerm<D, DIM> for PointLoads<D> {
    fn name(&self) -> &'static str {
        "point loads"
    }

    fn energy<E: Embed<D>>(&self, q: &[[E; DIM]], ctx: &Ctx<E>) -> E {
        let mut u = E::zero();
        self.for_each(ctx, |j, [cx, cz]| {
            u += cz * q[j][zi::<DIM>()];
            if DIM == 3 {
                u += cx * q[j][0];
            }
        });
        u
    }

    fn force<E: Embed<D>>(
        &self,
        _q: &[[E; DIM]],
        ctx: &Ctx<E>,
        out: &mut [[E; DIM]],
    ) -> Result<()> {
        // One length check here instead of a bounds check per node.
        let out = &mut out[..self.lengths.len()];
        self.for_each(ctx, |j, [cx, cz]| {
            out[j][zi::<DIM>()] += cz;
            if DIM == 3 {
                out[j][0] += cx;
            }
        });
        Ok(())
    }

    fn depends_on_configuration(&self) -> bool {
        false
    }

    fn has_parameter(&self, p: Parameter) -> bool {
        self.reads(p, DIM == 3)
    }
}
