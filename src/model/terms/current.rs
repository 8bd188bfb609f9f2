//! Drag relative to a steady current along the depth (docs/conventions.md, "Drag in a current").
//!
//! The thesis's still-water drag F_D(p) = −D p⊙|p| (eq. 2.4.4) acts on the conjugate momenta
//! pᵢ = ∂T/∂q̇ᵢ. With T = ½ Σ_k m_k |v_k|² and node velocities v_k = Σ_{i≤k} lᵢ q̇ᵢ,
//!
//! ```text
//! pᵢ = lᵢ Σ_{k≥i} m_k v_k ,
//! ```
//!
//! the momentum of the chain's motion. A current moves the water with velocity U_k = U(y_k) at
//! node k; the drag acts on the motion relative to the water, whose momentum is p − P with
//!
//! ```text
//! Pᵢ = lᵢ Σ_{k≥i} m_k U_k        (the momenta the chain would have moving with the water),
//! F(p) = F_D(p − P)      (Morison's drag of [`super::Drag`] on the relative momentum) .
//! ```
//!
//! p − P = lᵢ Σ_{k≥i} m_k (v_k − U_k) is linear in the relative velocities, so this is the
//! Morison-type drag on v − U in the thesis's momentum form: with U = 0 it *is* eq. 2.4.4 (P = 0
//! and p − 0 = p exactly, so the simulation is equal in IEEE arithmetic, tests/model/current.rs), and
//! at rest (p = 0) it is the steady force D |P_⊥| P_⊥ along the current (transversally).
//!
//! On a chain built from `[pipe]` D is the per-pendulum Dᵢ = D wᵢ ([`super::DragWeights`],
//! docs/conventions.md "Equivalent drag constant, per pendulum").
//!
//! The depth of node k is taken on the undeformed beam, y_k = l₁ + … + l_k (small deflections:
//! the node's height changes only to second order in the angles), so P is a constant of the
//! model, F stays a function of each pendulum's own momentum, and RATTLE's implicit half step
//! keeps its closed form.

use std::sync::Arc;

use super::drag::{morison, root_of, slope_of, DragWeights};
use super::waves::{RecordTime, WaveField};
use super::{BlockSym, Ctx, DissipativeTerm, Embed, HalfKick, HalfSteps};
use crate::base::{Parameter, Scalar};
use crate::model::geometry::zi;
use crate::scene::{current_velocity, water_height, Current};

/// Drag relative to a current (module docs): F(p) = F_D(p − P) (Morison's form of
/// [`super::Drag`]) with Pᵢ = lᵢ Σ_{k≥i} m_k U(y_k), added to ṗ. It replaces [`super::Drag`] when the
/// scene has a current. P = s·A + B is stored as its two parts (s the speed parameter), so that
/// the speed, the drag constant and the (uniform) mass are parameters with dual-number
/// derivatives.
///
/// With waves (`[loads.waves]`) the water velocity is the current's plus the waves' particle
/// velocity, U_k(t) = U(y_k) + u_k(t) e, and P gains the time-dependent share Wᵢ(t) e
/// ([`WaveField::momentum`], read at the context's time): one term, the same drag.
///
/// On a chain built from `[pipe]` pendulum i takes Dᵢ = D wᵢ ([`DragWeights`]).
#[derive(Clone, Debug)]
pub struct CurrentDrag<D, const DIM: usize> {
    pub(crate) d: D,
    /// The per-pendulum factors of D.
    pub(crate) weights: DragWeights,
    /// The speed parameter s (0 for a table, which has none).
    pub(crate) speed: D,
    reads_speed: bool,
    /// Node velocities a_k, b_k in the model's components (y component 0).
    unit: Vec<[f64; DIM]>,
    fixed: Vec<[f64; DIM]>,
    /// Aᵢ = lᵢ Σ_{k≥i} m_k a_k and Bᵢ likewise.
    per_speed: Vec<[D; DIM]>,
    offset: Vec<[D; DIM]>,
    /// m₁, for the mass seed (P ∝ m for uniform masses).
    mass: D,
    /// The waves' share of P, if the scene has waves.
    waves: Option<Arc<WaveField>>,
    /// The waves' direction e in the model's components.
    wave_unit: [f64; DIM],
    /// m₁ / re(m₁): the derivative of the waves' share under a dual mass.
    wave_scale: D,
    /// The derivative part of the waves' share under a seeded parameter that moves the nodes'
    /// masses one by one ([`CurrentDrag::set_node_masses`]): the field of the masses'
    /// derivatives (its momentum series ∂Wᵢ/∂θ) and the seed; `None` as built.
    wave_tangent: Option<(Arc<WaveField>, D)>,
}

impl<D: Scalar, const DIM: usize> CurrentDrag<D, DIM> {
    /// The term for `current` (none: still water) and `waves` (none: no waves) with drag
    /// constant `drag` (times `weights` per pendulum) on a chain with these lengths and masses.
    ///
    /// A node's height is taken above the mudline at `mudline` (0: the chain's foot) by
    /// [`water_height`]; a node below it, in the soil, has no water velocity.
    pub(crate) fn new(
        current: Option<&Current>,
        waves: Option<Arc<WaveField>>,
        drag: D,
        weights: DragWeights,
        (lengths, masses): (&[D], &[D]),
        mudline: f64,
    ) -> Self {
        let still = Current::uniform(0.0, [0.0, 1.0]);
        let reads_speed = current.is_some_and(|c| c.speed().is_some());
        let current = current.unwrap_or(&still);
        let total: f64 = lengths.iter().map(|l| l.re()).sum();
        let surface = current.surface.unwrap_or(total - mudline);
        let embed = |v: [f64; 2]| {
            let mut out = [0.0; DIM];
            out[zi::<DIM>()] = v[1];
            if DIM == 3 {
                out[0] = v[0];
            }
            out
        };
        let mut y = 0.0;
        let (mut unit, mut fixed) = (Vec::new(), Vec::new());
        for l in lengths {
            y += l.re();
            let (a, b) = water_height(mudline, y).map_or(([0.0; 2], [0.0; 2]), |y| {
                current_velocity(current, y, surface)
            });
            unit.push(embed(a));
            fixed.push(embed(b));
        }
        let n = lengths.len();
        let wave_unit = waves.as_ref().map_or([0.0; DIM], |w| embed(w.direction()));
        let mut term = CurrentDrag {
            d: drag,
            weights,
            speed: D::from(current.speed().unwrap_or(0.0)),
            reads_speed,
            unit,
            fixed,
            per_speed: vec![[D::zero(); DIM]; n],
            offset: vec![[D::zero(); DIM]; n],
            mass: masses[0],
            waves,
            wave_unit,
            wave_scale: D::one(),
            wave_tangent: None,
        };
        term.suffix_sums(lengths, masses);
        term
    }

    /// Takes node-by-node masses in the chain's scalar (a stack-up's, seeded with their
    /// derivatives with respect to a parameter, [`crate::Chain::set_node_quantities`]): the
    /// current's parts Aᵢ, Bᵢ by the suffix sums with these masses, and the waves' share
    /// Wᵢ + seed · ∂Wᵢ/∂θ with `wave_tangent` = (the field of the masses' derivatives
    /// [`WaveField::with_node_coefficients`], seed); the waves' own field keeps the masses' real
    /// parts (equal to those it was built with).
    pub(crate) fn set_node_masses(
        &mut self,
        lengths: &[D],
        masses: &[D],
        wave_tangent: Option<(Arc<WaveField>, D)>,
    ) {
        self.suffix_sums(lengths, masses);
        self.mass = masses[0];
        self.wave_scale = D::one();
        self.wave_tangent = wave_tangent.filter(|_| self.waves.is_some());
    }

    /// Recomputes A and B for new lengths and masses (O(n): suffix sums), and the waves' share
    /// (an FFT per pendulum, [`WaveField::with_masses`]).
    ///
    /// # Errors
    /// [`crate::ocean::SeaError::TooLarge`] when the new record's memory is refused.
    pub(crate) fn refresh(
        &mut self,
        lengths: &[D],
        masses: &[D],
    ) -> std::result::Result<(), crate::ocean::SeaError> {
        if let Some(w) = &self.waves {
            let m: Vec<f64> = masses.iter().map(|m| m.re()).collect();
            if m != w.masses() {
                self.waves = Some(Arc::new(w.with_masses(&m)?));
            }
            // The series are computed with the masses' real parts; their derivative enters
            // through P ∝ m (uniform masses, the only ones the mass parameter sets).
            self.wave_scale = masses[0] / D::from(masses[0].re());
        }
        self.suffix_sums(lengths, masses);
        self.mass = masses[0];
        Ok(())
    }

    /// Aᵢ = lᵢ Σ_{k≥i} m_k a_k and Bᵢ = lᵢ Σ_{k≥i} m_k b_k (module docs: P = s·A + B), by suffix
    /// sums in O(n).
    fn suffix_sums(&mut self, lengths: &[D], masses: &[D]) {
        let (mut sa, mut sb) = ([D::zero(); DIM], [D::zero(); DIM]);
        for i in (0..lengths.len()).rev() {
            for d in 0..DIM {
                sa[d] += masses[i] * self.unit[i][d];
                sb[d] += masses[i] * self.fixed[i][d];
                self.per_speed[i][d] = lengths[i] * sa[d];
                self.offset[i][d] = lengths[i] * sb[d];
            }
        }
    }

    /// The same term over another scalar (real parts).
    pub(crate) fn lift<D2: Scalar>(&self) -> CurrentDrag<D2, DIM> {
        let l = |v: &[[D; DIM]]| {
            v.iter()
                .map(|x| x.map(|c| D2::from(c.re())))
                .collect::<Vec<_>>()
        };
        CurrentDrag {
            d: D2::from(self.d.re()),
            weights: self.weights.clone(),
            speed: D2::from(self.speed.re()),
            reads_speed: self.reads_speed,
            unit: self.unit.clone(),
            fixed: self.fixed.clone(),
            per_speed: l(&self.per_speed),
            offset: l(&self.offset),
            mass: D2::from(self.mass.re()),
            waves: self.waves.clone(),
            wave_unit: self.wave_unit,
            wave_scale: D2::from(self.wave_scale.re()),
            wave_tangent: None,
        }
    }

    /// Replaces the waves' field the water's momentum reads (a forecast's,
    /// [`crate::model::Chain::set_forecast`]); nothing without waves.
    pub(crate) fn set_waves(&mut self, field: &Arc<WaveField>) {
        if self.waves.is_some() {
            self.waves = Some(field.clone());
        }
    }

    /// Whether the water's momentum reads the current's speed parameter.
    pub(crate) fn reads_speed(&self) -> bool {
        self.reads_speed
    }

    /// The waves' field, if the scene has waves.
    pub fn waves(&self) -> Option<&WaveField> {
        self.waves.as_deref()
    }

    /// The current's momentum Pᵢ_d = s·Aᵢ_d + Bᵢ_d, its parameters read through [`Ctx::param`].
    #[inline]
    pub fn momentum<E: Embed<D>>(&self, i: usize, d: usize, ctx: &Ctx<E>) -> E {
        self.momentum_located(i, d, ctx, None)
    }

    /// The water's momentum P of every pendulum at the context's time into `out`, each
    /// component [`CurrentDrag::momentum`]'s bit for bit, with the waves' record located once
    /// for all pendulums ([`WaveField::at`]) instead of once per pendulum and component.
    pub fn momenta(&self, ctx: &Ctx<D>, out: &mut [[D; DIM]]) {
        if ctx.seed == Some(Parameter::Mass) {
            let at = self.waves.as_ref().map(|w| w.at(ctx.t));
            for (i, o) in out.iter_mut().enumerate() {
                *o = std::array::from_fn(|d| self.momentum_located(i, d, ctx, at));
            }
            return;
        }
        // momentum_located's arithmetic, with the waves' series read for every pendulum at
        // once (WaveField::read_all): s·Aᵢ_d + Bᵢ_d, then + m-scale · (Wᵢ e_d).
        let s = ctx.param(Parameter::CurrentSpeed, self.speed);
        for (o, (a, b)) in out.iter_mut().zip(self.per_speed.iter().zip(&self.offset)) {
            *o = std::array::from_fn(|d| s * a[d] + b[d]);
        }
        if let Some(w) = &self.waves {
            let at = w.at(ctx.t);
            let (unit, scale) = (self.wave_unit, self.wave_scale);
            w.read_all(false, at, |i, v| {
                for d in 0..DIM {
                    if unit[d] != 0.0 {
                        out[i][d] += scale * (v * unit[d]);
                    }
                }
            });
            // A design parameter's seeded share (momentum_located's last term), same order.
            if let Some((t, seed)) = &self.wave_tangent {
                let seed = *seed;
                t.read_all(false, at, |i, v| {
                    for d in 0..DIM {
                        if unit[d] != 0.0 {
                            out[i][d] += seed * (v * unit[d]);
                        }
                    }
                });
            }
        }
    }

    /// [`CurrentDrag::momentum`] with the waves' record time `at` located already (`None`:
    /// located here, at the context's time).
    #[inline]
    fn momentum_located<E: Embed<D>>(
        &self,
        i: usize,
        d: usize,
        ctx: &Ctx<E>,
        at: Option<RecordTime>,
    ) -> E {
        let s = ctx.param(Parameter::CurrentSpeed, self.speed);
        let mut p = s * E::embed(self.per_speed[i][d]) + E::embed(self.offset[i][d]);
        if let Some(w) = &self.waves {
            if self.wave_unit[d] != 0.0 {
                let at = at.unwrap_or_else(|| w.at(ctx.t));
                p += E::embed(self.wave_scale) * (w.momentum_at(i, at) * self.wave_unit[d]);
                if let Some((t, seed)) = &self.wave_tangent {
                    p += E::embed(*seed) * (t.momentum_at(i, at) * self.wave_unit[d]);
                }
            }
        }
        if ctx.seed == Some(Parameter::Mass) {
            // P ∝ m for uniform masses: P(m) = P · m/m₁ with m seeded.
            return p * ctx.param(Parameter::Mass, self.mass) / E::embed(self.mass);
        }
        p
    }
}

impl<D: Scalar, const DIM: usize> DissipativeTerm<D, DIM> for CurrentDrag<D, DIM> {
    fn name(&self) -> &'static str {
        if self.waves.is_some() {
            "water drag"
        } else {
            "current drag"
        }
    }

    #[inline]
    fn force<E: Embed<D>>(&self, i: usize, p: &[E; DIM], ctx: &Ctx<E>) -> [E; DIM] {
        let drag = self.weights.apply(i, ctx.param(Parameter::Drag, self.d));
        self.force_with(drag, i, p, ctx)
    }

    fn has_parameter(&self, p: Parameter) -> bool {
        match p {
            Parameter::Drag | Parameter::Mass => true,
            Parameter::CurrentSpeed => self.reads_speed,
            _ => false,
        }
    }

    /// Closed form with r = p − P: (F, F′) = (−D r|r|, −2D|r|), equal to the default's
    /// `Dual<D>` evaluation (tested).
    #[inline]
    fn force_and_slope(
        &self,
        i: usize,
        p: &[D; DIM],
        ctx: &Ctx<D>,
    ) -> ([D; DIM], BlockSym<D, DIM>) {
        let plain = Ctx { seed: None, ..*ctx };
        let r: [D; DIM] = std::array::from_fn(|d| p[d] - self.momentum(i, d, &plain));
        slope_of(self.weights.apply(i, self.d), &r)
    }

    /// Closed form: r = p − P solves r + (hD/2) r|r| = c − P, the still-water root
    /// ([`super::Drag`]) shifted by P; W = ∂p/∂c = 1/(1 + hD|r|) (tested equal to the default
    /// Newton solve).
    #[inline]
    fn implicit_half_step(
        &self,
        i: usize,
        c: &[D; DIM],
        h: f64,
        ctx: &Ctx<D>,
    ) -> ([D; DIM], BlockSym<D, DIM>) {
        let big: [D; DIM] = std::array::from_fn(|d| self.momentum(i, d, ctx));
        shifted_root(self.weights.apply(i, self.d), c, &big, h)
    }

    /// [`CurrentDrag::implicit_half_step`] on every block, Dᵢ by `DragWeights::each` and Pᵢ by
    /// `CurrentDrag::block_momentum` (the same arithmetic per block).
    #[inline]
    fn implicit_half_steps(&self, blocks: HalfSteps<'_, D, DIM>, h: f64, ctx: &Ctx<D>) {
        let HalfSteps { c, p, w } = blocks;
        let n = c.len();
        let plain = self.is_plain(ctx);
        self.weights.each(
            n,
            self.d,
            #[inline(always)]
            |i, d| {
                let big = self.block_momentum(i, ctx, plain);
                (p[i], w[i]) = shifted_root(d, &c[i], &big, h);
            },
        );
    }

    /// [`DissipativeTerm::half_kick`] on every block ([`CurrentDrag::force`]), Dᵢ by
    /// `DragWeights::each` and Pᵢ by `CurrentDrag::block_momentum`.
    #[inline]
    fn half_kick(&self, kick: HalfKick<'_, D, DIM>, ctx: &Ctx<D>, out: &mut [[D; DIM]]) {
        let HalfKick { p, g, s } = kick;
        let n = p.len();
        let (g, out) = (&g[..n], &mut out[..n]);
        let drag = ctx.param(Parameter::Drag, self.d);
        let plain = self.is_plain(ctx);
        self.weights.each(
            n,
            drag,
            #[inline(always)]
            |i, d| {
                let big = self.block_momentum(i, ctx, plain);
                let r: [D; DIM] = std::array::from_fn(|k| p[i][k] - big[k]);
                let f = morison(d, &r);
                for k in 0..DIM {
                    out[i][k] = p[i][k] - g[i][k] * s + f[k] * s;
                }
            },
        );
    }
}

/// The root p of p − (h/2) F_D(p − P) = c: r = p − P solves the still-water root for c − P
/// ([`root_of`]), p = r + P, W = ∂p/∂c that of r.
#[inline(always)]
fn shifted_root<D: Scalar, const DIM: usize>(
    drag: D,
    c: &[D; DIM],
    big: &[D; DIM],
    h: f64,
) -> ([D; DIM], BlockSym<D, DIM>) {
    let shifted: [D; DIM] = std::array::from_fn(|d| c[d] - big[d]);
    let (r, w) = root_of(drag, &shifted, h);
    (std::array::from_fn(|d| r[d] + big[d]), w)
}

impl<D: Scalar, const DIM: usize> CurrentDrag<D, DIM> {
    /// Fᵢ(p) = F_D(p − Pᵢ) with the block's drag constant `drag` = Dᵢ.
    #[inline]
    fn force_with<E: Embed<D>>(&self, drag: E, i: usize, p: &[E; DIM], ctx: &Ctx<E>) -> [E; DIM] {
        let r: [E; DIM] = std::array::from_fn(|d| p[d] - self.momentum(i, d, ctx));
        morison(drag, &r)
    }

    /// Whether [`CurrentDrag::momentum`] reduces to P = s·A + B in this context: no seeded
    /// parameter and no waves (then the batched loops skip its per-block checks).
    #[inline]
    fn is_plain<E>(&self, ctx: &Ctx<E>) -> bool {
        ctx.seed.is_none() && self.waves.is_none()
    }

    /// Pᵢ = [`CurrentDrag::momentum`] of block i, computed as s·Aᵢ + Bᵢ directly when `plain`
    /// ([`CurrentDrag::is_plain`]: the same operations without the checks).
    #[inline(always)]
    fn block_momentum(&self, i: usize, ctx: &Ctx<D>, plain: bool) -> [D; DIM] {
        if plain {
            std::array::from_fn(|d| self.speed * self.per_speed[i][d] + self.offset[i][d])
        } else {
            std::array::from_fn(|d| self.momentum(i, d, ctx))
        }
    }
}
