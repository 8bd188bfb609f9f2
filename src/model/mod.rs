//! The chain-of-pendulums model (thesis §2.2, §2.4, §3.1, §3.2; docs/conventions.md), written once over
//! [`Scalar`] so that the same terms evaluate in `f64` and in dual arithmetic.
//!
//! The configuration is q = (q₁, …, qₙ) with qᵢ ∈ S^{DIM−1} ⊂ ℝ^DIM. `DIM = 2` is the planar model
//! (components (y, z), qᵢ ∈ S¹ in the yz-plane) and `DIM = 3` the spatial one (components
//! (x, y, z), qᵢ ∈ S²). Every load of the thesis acts along z and the beam starts straight along
//! +y, so x stays exactly 0 in the spatial model; the planar model therefore reproduces it exactly
//! (tested to 0 difference in `tests/model/core.rs` and, with every kind of point load, in
//! `tests/model/loads.rs`) while storing and computing two components instead of three. A point load
//! with an x component (docs/scene-format.md) needs the spatial model: [`Chain::from_scene`] refuses such a
//! scene for `DIM = 2` ([`Error::NeedsSpatialModel`]), and [`crate::simulate()`] picks the model. The step's cost is dominated by the per-joint scalar work (spring function, Newton
//! and projection solves), so the measured saving is modest: 3D/2D ≈ 1.08 at n = 100
//! (`cargo bench --bench step -- step_dim`).

mod build;
pub mod geometry;
mod mass;
mod nodes;
mod params;
mod start;
pub mod terms;
mod vessel;

pub use geometry::{arccos_squared, joint_angle_squared, spring_s, spring_s_ds, yi, zi};
pub(crate) use geometry::{dot, e2};
pub use terms::{
    AxialWeight, BlockSym, ChainPointLoad, ControlForce, CoupledAt, CoupledDissipativeTerm,
    CoupledVisitor, Ctx, CurrentDrag, DissipationVisitor, DissipativeTerm, Drag, DragWeights,
    DualScratch, Embed, ForceTerm, Gravity, HalfKick, HalfSteps, HarmonicForce, JointDamping,
    NodeDrag, PointLoads, ReactionTip, ReactionTipBar, RecordTime, SoilSprings, Springs,
    TermVisitor, TopTension, WaveField, WaveInertia, WaveInertiaTangent, WaveInputs,
};

pub use crate::base::{Parameter, Scalar, TipCondition};
pub use crate::error::ModelError;
use crate::error::{Error, Result};
pub use nodes::{NodeQuantities, WaveTangent};
pub use vessel::{ThrustDrive, ThrustDriveBar, VesselMotion};

/// The chain of pendulums: its mass distribution, its constraints, and one value of each force
/// term of docs/conventions.md ([`terms`]), generic over the scalar `D` and the dimension `DIM` (2: planar,
/// 3: spatial). Terms a scene does not have are absent and cost nothing.
#[derive(Clone, Debug)]
pub struct Chain<D, const DIM: usize> {
    pub(crate) n: usize,
    pub(crate) lengths: Vec<D>,
    pub(crate) masses: Vec<D>,
    pub(crate) inv_lengths: Vec<D>,
    pub(crate) inv_masses: Vec<D>,
    /// The base spring of the bending moment M₀ = 2 k₁ z₁ / l₁² (eq. 3.1.3).
    pub(crate) moment_stiffness: D,
    pub(crate) tip: TipCondition,
    pub(crate) springs: Springs<D>,
    pub(crate) loads: Option<PointLoads<D>>,
    pub(crate) gravity: Option<Gravity<D>>,
    /// The top tension along +y at the tip (`[loads] tension`).
    pub(crate) tension: Option<TopTension<D>>,
    /// The axial weight along −y on every node (`[loads] axial_weight`).
    pub(crate) axial_weight: Option<AxialWeight<D>>,
    pub(crate) control: Option<ControlForce<D>>,
    /// The x components u_{x,0..N} of a 2-axis control, indexed by step (empty: a 1-axis control
    /// along z, u_x = 0). Read into [`Ctx::ux`] by [`Chain::ctx`].
    pub(crate) control_x: Vec<D>,
    pub(crate) drag: Option<Drag<D>>,
    /// Drag relative to the water (a current, waves or both); replaces `drag` then.
    pub(crate) current: Option<CurrentDrag<D, DIM>>,
    /// The waves' inertia load (`[loads.waves]`).
    pub(crate) wave_inertia: Option<WaveInertia>,
    /// The derivative part of the waves' inertia load under a seeded parameter that moves the
    /// nodes' inertia coefficients ([`Chain::set_node_quantities`]); `None` as built.
    pub(crate) wave_inertia_tangent: Option<WaveInertiaTangent<D>>,
    /// Structural damping at the joints (`[beam] joint_damping`), a coupled dissipative term.
    pub(crate) joint_damping: Option<JointDamping<D>>,
    /// Morison's drag node by node (`[pipe] drag_model = "morison"`), in place of `drag` and
    /// `current`.
    pub(crate) node_drag: Option<NodeDrag<D, DIM>>,
    /// The vessel's motion of the tip ([`TipCondition::Prescribed`]).
    pub(crate) vessel: Option<std::sync::Arc<VesselMotion>>,
    /// The vessel's mean offset Z₀ in the chain's scalar ([`Parameter::VesselOffset`]; its real
    /// part is the `vessel`'s own offset, 0 without a vessel): [`Chain::prescribed_tip`] adds
    /// (Z₀ − Z₀,vessel) ρ(t) to the vessel's Z(t), zero but for a seeded derivative.
    pub(crate) vessel_offset: D,
    /// Lateral p-y springs on the nodes below the mudline (`[soil]`).
    pub(crate) soil: Option<SoilSprings<D>>,
    /// The state the scene's runs start from (`[time] initial`, [`Chain::start_attitudes`]).
    pub(crate) initial: crate::scene::Initial,
    /// The static start's attitudes qⱼ(0) as (x, y, z) (`[time] initial = "static"`, set by
    /// [`crate::statics::set_static_start`]); `None`: not set.
    pub(crate) start: Option<std::sync::Arc<[[f64; 3]]>>,
}

/// Default fold limit: a joint angle of 179° (s = θ/sin θ ≈ 180) is treated as a folded beam.
pub const DEFAULT_FOLD_LIMIT_DEG: f64 = 179.0;

/// Evaluates the generalised force of every term (see [`Chain::potential_gradient`]).
struct ForceSum<'a, D, const DIM: usize> {
    q: &'a [[D; DIM]],
    ctx: Ctx<D>,
    out: &'a mut [[D; DIM]],
}

impl<D: Scalar, const DIM: usize> TermVisitor<D, DIM> for ForceSum<'_, D, DIM> {
    fn visit<T: ForceTerm<D, DIM>>(&mut self, term: &T) -> Result<()> {
        term.force(self.q, &self.ctx, self.out)
    }
}

/// Sums the energy of every term (see [`Chain::potential_energy`]).
struct EnergySum<'a, D, const DIM: usize> {
    q: &'a [[D; DIM]],
    ctx: Ctx<D>,
    sum: D,
}

impl<D: Scalar, const DIM: usize> TermVisitor<D, DIM> for EnergySum<'_, D, DIM> {
    fn visit<T: ForceTerm<D, DIM>>(&mut self, term: &T) -> Result<()> {
        self.sum += term.energy(self.q, &self.ctx);
        Ok(())
    }
}

/// What a [`Products`] visitor computes.
#[derive(Clone, Copy)]
enum Product {
    /// K w, accumulated with a scale.
    Jvp,
    /// w · ∂F/∂θ.
    Parameter(Parameter),
    /// w · ∂F/∂u.
    Control,
    /// w · ∂F/∂u_x.
    ControlX,
}

/// Derived products of every term (see [`Chain::force_jacobian_product`],
/// [`Chain::force_parameter_contraction`], [`Chain::control_contraction`]).
struct Products<'a, D, const DIM: usize> {
    q: &'a [[D; DIM]],
    w: &'a [[D; DIM]],
    ctx: Ctx<D>,
    what: Product,
    scale: D,
    out: Option<&'a mut [[D; DIM]]>,
    sum: D,
    scratch: &'a mut DualScratch<D, DIM>,
}

impl<D: Scalar, const DIM: usize> TermVisitor<D, DIM> for Products<'_, D, DIM> {
    fn visit<T: ForceTerm<D, DIM>>(&mut self, term: &T) -> Result<()> {
        let (q, w, c, s) = (self.q, self.w, &self.ctx, &mut *self.scratch);
        match self.what {
            Product::Jvp => {
                if let Some(out) = self.out.as_deref_mut() {
                    term.force_jvp(q, w, c, self.scale, out, s)?;
                }
            }
            Product::Parameter(p) => self.sum += term.parameter_contraction(q, w, c, p, s)?,
            Product::Control => self.sum += term.control_contraction(q, w, c, s)?,
            Product::ControlX => self.sum += term.control_x_contraction(q, w, c, s)?,
        }
        Ok(())
    }
}

impl<D: Scalar, const DIM: usize> Chain<D, DIM> {
    /// Visits every conservative force term the model has: **the one place that lists them**
    /// (a new term is added here and nowhere else in the solvers).
    pub fn visit_terms<V: TermVisitor<D, DIM>>(&self, v: &mut V) -> Result<()> {
        v.visit(&self.springs)?;
        if let Some(t) = &self.loads {
            v.visit(t)?;
        }
        if let Some(t) = &self.gravity {
            v.visit(t)?;
        }
        if let Some(t) = &self.tension {
            v.visit(t)?;
        }
        if let Some(t) = &self.axial_weight {
            v.visit(t)?;
        }
        if let Some(t) = &self.control {
            v.visit(t)?;
        }
        if let Some(t) = &self.wave_inertia {
            v.visit(t)?;
        }
        if let Some(t) = &self.wave_inertia_tangent {
            v.visit(t)?;
        }
        if let Some(t) = &self.soil {
            v.visit(t)?;
        }
        Ok(())
    }

    /// Number of pendulums n.
    pub fn n(&self) -> usize {
        self.n
    }

    /// What holds the tip.
    pub fn tip_condition(&self) -> TipCondition {
        self.tip
    }

    /// The tip drive of the reaction-force variant ([`TipCondition::Reaction`]), `None` for
    /// other tips.
    pub fn reaction_tip(&self) -> Option<ReactionTip<D>> {
        (self.tip == TipCondition::Reaction).then(|| ReactionTip {
            inv_tip_mass: self.inv_masses[self.n() - 1],
        })
    }

    /// The prescribed tip's (Z(t), Ż(t)) at time t ([`TipCondition::Prescribed`]), `None` for
    /// other tips.
    #[inline]
    pub fn prescribed_tip(&self, t: f64) -> Option<[D; 2]> {
        self.vessel.as_ref().map(|v| {
            let [z, zd] = v.at(t);
            // Z(t) = ρ(t)(Z₀ + d_z X_w) (Z₀ + ρ(t) d_z X_w held for a static start): the
            // offset's own part (Z₀ − Z₀,vessel)(∂Z/∂Z₀, ∂Ż/∂Z₀) is zero in value and carries
            // Z₀'s derivative when it is seeded.
            let (rho, rho_dot) = v.offset_ramp(t);
            let dz = self.vessel_offset - D::from(v.vessel().offset);
            [D::from(z) + dz * rho, D::from(zd) + dz * rho_dot]
        })
    }

    /// The vessel's thrust drive when the control is the thrust on the vessel (`[vessel]` thrust
    /// keys, [`ThrustDrive`]), `None` otherwise.
    #[inline]
    pub fn thrust_drive(&self) -> Option<ThrustDrive> {
        self.vessel.as_ref().and_then(|v| v.thrust().copied())
    }

    /// Whether the tip's target is a state driven by the control: the reaction-force tip
    /// ([`ReactionTip`]) or the vessel under its thrust ([`ThrustDrive`]). The control is then
    /// not a force term, and the adjoint carries the target's cotangent.
    #[inline]
    pub fn has_driven_tip(&self) -> bool {
        self.tip == TipCondition::Reaction || self.thrust_drive().is_some()
    }

    /// Where a static equilibrium holds the tip's z: the vessel's mean offset Z₀ for a
    /// prescribed tip, 0 for a locked one.
    pub fn static_tip_target(&self) -> f64 {
        self.vessel.as_ref().map_or(0.0, |v| v.mean())
    }

    /// Whether a RATTLE step's half-step record (p_{k+½} and W, or the node drag's Ω) is
    /// needed by the adjoint: a dissipative term or the node-by-node Morison drag.
    pub fn records_half_step(&self) -> bool {
        self.has_dissipation() || self.node_drag.is_some()
    }

    /// Refuses a model with a term the structured optimal-control solvers (Riccati, condensed;
    /// so MPC) do not take yet (the node-by-node Morison drag): their stage models call it first.
    ///
    /// # Errors
    /// [`ModelError::NoAdjoint`].
    pub fn check_adjoint(&self) -> Result<()> {
        if self.node_drag.is_some() {
            return Err(ModelError::NoAdjoint {
                term: "node-by-node Morison drag",
            }
            .into());
        }
        Ok(())
    }

    /// The node-by-node Morison drag's generalised force Q(p) ([`NodeDrag::generalised_force`])
    /// added to `out` with the factor `scale`, if the model has that term (allocates: for
    /// the statics, not a step).
    pub fn add_node_drag(&self, p: &[[D; DIM]], ctx: &Ctx<D>, scale: D, out: &mut [[D; DIM]]) {
        if let Some(nd) = &self.node_drag {
            let (mut y, mut f) = (
                vec![[D::zero(); DIM]; self.n],
                vec![[D::zero(); DIM]; self.n],
            );
            nd.generalised_force(p, (&self.lengths, &self.inv_lengths), ctx, &mut y, &mut f);
            for (o, f) in out.iter_mut().zip(&f) {
                for d in 0..DIM {
                    o[d] += f[d] * scale;
                }
            }
        }
    }

    /// Morison's drag node by node, if the model has it.
    pub fn node_drag(&self) -> Option<&NodeDrag<D, DIM>> {
        self.node_drag.as_ref()
    }

    /// Tabulates the node drag's water momenta P(t_k + h/2) of the steps k = 0..steps of a
    /// horizon from `t0` with step `h` (the contexts of [`Chain::dissipation_ctx`]), for a plan
    /// that sweeps the same horizon many times ([`NodeDrag::tabulate_water`]: the same values
    /// bit for bit); nothing without that term. Memory: steps × n × DIM reals.
    pub(crate) fn tabulate_water(&mut self, t0: f64, h: f64, steps: usize) {
        if let Some(mut nd) = self.node_drag.take() {
            let n = self.n;
            nd.tabulate_water(n, steps, |k| self.dissipation_ctx(t0 + k as f64 * h, h, k));
            self.node_drag = Some(nd);
        }
    }

    /// The vessel's motion of the tip, if the vessel holds it.
    pub fn vessel(&self) -> Option<&VesselMotion> {
        self.vessel.as_deref()
    }

    /// Whether the model has the tip constraint row (locked, prescribed or reaction-force tip).
    pub fn has_tip_constraint(&self) -> bool {
        self.tip != TipCondition::Free
    }

    /// Number of constraint multipliers: n length constraints, plus one for the tip.
    pub fn n_constraints(&self) -> usize {
        self.n + usize::from(self.has_tip_constraint())
    }

    /// Whether the model computes drag (still-water or relative to a current).
    pub fn has_drag(&self) -> bool {
        self.drag.is_some() || self.current.is_some()
    }

    /// The still-water drag term, if the scene has drag and no current.
    pub fn drag(&self) -> Option<&Drag<D>> {
        self.drag.as_ref()
    }

    /// The waves' field (kinematics over the record), if the scene has waves.
    pub fn waves(&self) -> Option<&WaveField> {
        self.wave_inertia.as_ref().map(WaveInertia::field)
    }

    /// Replaces what the chain knows of the sea: the waves' field every wave term reads (the
    /// water's momentum of the drag, node by node or per pendulum, and the inertia load) and
    /// the vessel's motion, each when given and the chain has that term. A plan's forecast with
    /// errors ([`crate::mpc`], "What the plan knows"; [`WaveField::window`],
    /// [`VesselMotion::surge_window`]).
    pub fn set_forecast(
        &mut self,
        field: Option<std::sync::Arc<WaveField>>,
        vessel: Option<std::sync::Arc<VesselMotion>>,
    ) {
        if let Some(f) = field {
            if let Some(c) = &mut self.current {
                c.set_waves(&f);
            }
            if let Some(nd) = &mut self.node_drag {
                nd.water.set_waves(&f);
                nd.clear_water_table();
            }
            if let Some(w) = &mut self.wave_inertia {
                w.field = f;
            }
        }
        if let (Some(v), Some(mine)) = (vessel, &mut self.vessel) {
            *mine = v;
        }
    }

    /// The surface elevation η(0, t) \[m\] of the scene's waves at x = z = 0 (`None` without
    /// waves).
    pub fn wave_elevation(&self, t: f64) -> Option<f64> {
        self.waves().map(|w| w.elevation(t))
    }

    /// The drag relative to the current, if the scene has a current.
    pub fn current_drag(&self) -> Option<&CurrentDrag<D, DIM>> {
        self.current.as_ref()
    }

    /// The per-pendulum factors wᵢ of the drag constant, Dᵢ = D wᵢ ([`DragWeights`]; a chain
    /// built from `[pipe]`), `None` when every pendulum takes D (or the model has no drag).
    pub fn drag_weights(&self) -> Option<&[f64]> {
        let w = match (&self.drag, &self.current) {
            (Some(t), _) => &t.weights,
            (None, Some(t)) => &t.weights,
            (None, None) => return None,
        };
        w.as_slice()
    }

    /// Visits every dissipative term the model has: **the one place that lists them** (the
    /// still-water drag, or the drag relative to a current, which replaces it; a new term is
    /// added here and nowhere else in the solvers, which sum what they visit).
    #[inline]
    pub fn visit_dissipation<V: DissipationVisitor<D, DIM>>(&self, v: &mut V) {
        if let Some(t) = &self.drag {
            v.visit(t);
        }
        if let Some(t) = &self.current {
            v.visit(t);
        }
    }

    /// Visits every dissipative term that couples pendulums ([`CoupledDissipativeTerm`]): **the
    /// one place that lists them** (the joint damping), summed beside the block terms of
    /// [`Chain::visit_dissipation`].
    #[inline]
    pub fn visit_coupled_dissipation<V: CoupledVisitor<D, DIM>>(&self, v: &mut V) {
        if let Some(t) = &self.joint_damping {
            v.visit(t);
        }
    }

    /// The joint damping term, if the scene has `[beam] joint_damping` with a damper > 0.
    pub fn joint_damping(&self) -> Option<&JointDamping<D>> {
        self.joint_damping.as_ref()
    }

    /// The largest |j − k| with a nonzero block K_jk of the stiffness K = ∂²U/∂q²: 1 (K is
    /// block-tridiagonal: the springs couple neighbours, the other terms are linear in q) unless
    /// the model has soil springs, whose energy ½ Σ kᵢ |rᵢ⊥|² couples every pendulum below a node
    /// in the soil with every other (n). The statics extract K's blocks by colouring on it.
    pub fn stiffness_reach(&self) -> usize {
        if self.soil.is_some() {
            self.n
        } else {
            1
        }
    }

    /// Whether the model has the spring of joint i (0..=n).
    pub fn has_spring(&self, i: usize) -> bool {
        self.springs.present[i]
    }

    /// The control node, if the model has a control.
    pub fn control_node(&self) -> Option<usize> {
        self.control.as_ref().map(|c| c.node)
    }

    /// Sets (or removes) the node the control acts at (1..=n). In a thrust scene
    /// ([`Chain::thrust_drive`]) the control is the thrust on the vessel and no force term is
    /// added (the node is checked, then ignored).
    pub fn set_control_node(&mut self, node: Option<usize>) -> Result<()> {
        if let Some(c) = node {
            if c == 0 || c > self.n {
                return Err(ModelError::ControlNodeOutOfRange { node: c, n: self.n }.into());
            }
        }
        // The thrust on the vessel is the control of a thrust scene: no force on the riser.
        let node = node.filter(|_| self.thrust_drive().is_none());
        self.control = node.map(|node| ControlForce {
            node,
            lengths: self.lengths.clone(),
        });
        if node.is_none() {
            self.control_x.clear();
        }
        Ok(())
    }

    /// Sets (or, with an empty slice, removes) the x components u_{x,0..N} of a 2-axis control,
    /// one per step k (docs/conventions.md "Two-axis controls"): the control force at t_k is
    /// (u_{x,k}, u_k). Steps beyond the slice have u_x = 0.
    ///
    /// # Errors
    /// [`Error::NeedsSpatialModel`] for the planar model (`DIM = 2`) with a nonempty slice;
    /// [`ModelError::NoControlNode`] without a control node; [`Error::NotFinite`] for a non-finite
    /// value.
    pub fn set_control_x(&mut self, ux: &[D]) -> Result<()> {
        if !ux.is_empty() {
            if DIM == 2 {
                return Err(Error::NeedsSpatialModel {
                    key: "control.values".to_string(),
                });
            }
            if self.control.is_none() {
                return Err(ModelError::NoControlNode.into());
            }
            if let Some(index) = ux.iter().position(|x| !x.re().is_finite()) {
                return Err(Error::NotFinite {
                    name: "control_x",
                    index,
                });
            }
        }
        self.control_x.clear();
        self.control_x.extend_from_slice(ux);
        Ok(())
    }

    /// Whether the model has a 2-axis control (a nonempty x schedule, [`Chain::set_control_x`]).
    pub fn has_control_x(&self) -> bool {
        !self.control_x.is_empty()
    }

    /// The x component u_{x,k} of the control at step k (0 for a 1-axis control).
    #[inline]
    pub fn control_x(&self, k: usize) -> D {
        self.control_x.get(k).copied().unwrap_or_else(D::zero)
    }

    /// The evaluation context at time t, step k, control z component u: [`Ctx::new`] with the
    /// x component u_{x,k} of a 2-axis control ([`Chain::control_x`]).
    #[inline]
    pub fn ctx(&self, t: f64, u: D, k: usize) -> Ctx<D> {
        Ctx::new(t, u, k).with_ux(self.control_x(k))
    }

    /// Sets the fold limit in degrees (default [`DEFAULT_FOLD_LIMIT_DEG`]): a joint angle beyond
    /// it is reported as [`Error::Folded`].
    pub fn set_fold_limit_deg(&mut self, deg: f64) -> Result<()> {
        if !(deg > 0.0 && deg < 180.0) {
            return Err(ModelError::FoldLimitOutOfRange { deg }.into());
        }
        self.springs.fold_cos = deg.to_radians().cos();
        Ok(())
    }

    /// ∂U/∂q at time t with control u: the sum of every term's force ([`ForceTerm::force`];
    /// springs eq. 2.2.3, loads eq. 2.2.2, control eq. 3.1.1, gravity §2.2.2). A joint beyond the
    /// fold limit gives [`Error::Folded`] (with `step` = `step`).
    pub fn potential_gradient(
        &self,
        q: &[[D; DIM]],
        t: f64,
        u: D,
        step: usize,
        out: &mut [[D; DIM]],
    ) -> Result<()> {
        out.iter_mut().for_each(|o| *o = [D::zero(); DIM]);
        let ctx = self.ctx(t, u, step);
        self.visit_terms(&mut ForceSum { q, ctx, out })
    }

    /// Accumulates `scale` · K w into `out`, K = ∂²U/∂q² (symmetric, block-tridiagonal), summed
    /// over the terms ([`ForceTerm::force_jvp`]).
    pub fn force_jacobian_product(
        &self,
        q: &[[D; DIM]],
        w: &[[D; DIM]],
        ctx: &Ctx<D>,
        scale: D,
        out: &mut [[D; DIM]],
        scratch: &mut DualScratch<D, DIM>,
    ) -> Result<()> {
        let what = Product::Jvp;
        let (ctx, sum, out) = (*ctx, D::zero(), Some(out));
        self.visit_terms(&mut Products {
            q,
            w,
            ctx,
            what,
            scale,
            out,
            sum,
            scratch,
        })
    }

    /// w · ∂(∂U/∂q)/∂θ for a physical parameter θ, summed over the terms
    /// ([`ForceTerm::parameter_contraction`]). The mass matrix's dependence on the masses is the
    /// integrator's (and the adjoint's) business, not a force term's.
    pub fn force_parameter_contraction(
        &self,
        q: &[[D; DIM]],
        w: &[[D; DIM]],
        ctx: &Ctx<D>,
        p: Parameter,
        scratch: &mut DualScratch<D, DIM>,
    ) -> Result<D> {
        self.contraction(q, w, ctx, Product::Parameter(p), scratch)
    }

    /// w · ∂(∂U/∂q)/∂u, summed over the terms ([`ForceTerm::control_contraction`]).
    pub fn control_contraction(
        &self,
        q: &[[D; DIM]],
        w: &[[D; DIM]],
        ctx: &Ctx<D>,
        scratch: &mut DualScratch<D, DIM>,
    ) -> Result<D> {
        self.contraction(q, w, ctx, Product::Control, scratch)
    }

    /// w · ∂(∂U/∂q)/∂u_x for the x component of a 2-axis control, summed over the terms
    /// ([`ForceTerm::control_x_contraction`]; 0 in the planar model).
    pub fn control_x_contraction(
        &self,
        q: &[[D; DIM]],
        w: &[[D; DIM]],
        ctx: &Ctx<D>,
        scratch: &mut DualScratch<D, DIM>,
    ) -> Result<D> {
        self.contraction(q, w, ctx, Product::ControlX, scratch)
    }

    /// The control term's force alone, u ∂U_q/∂u + u_x ∂U_q/∂u_x (block j: l_j (u_x, u) for
    /// j below the control node, eq. 3.1.1; u_x only in the spatial model), into `out`
    /// (overwritten; zero without a control node). U_q is affine in the control, so this is
    /// U_q(q; u, u_x) − U_q(q; 0, 0) without the round-off of the other terms.
    pub fn control_force(&self, u: D, ux: D, out: &mut [[D; DIM]]) -> Result<()> {
        out.iter_mut().for_each(|o| *o = [D::zero(); DIM]);
        match &self.control {
            Some(c) => {
                let ctx = Ctx::new(0.0, u, 0).with_ux(ux);
                ForceTerm::<D, DIM>::force(c, &[], &ctx, out)
            }
            None => Ok(()),
        }
    }

    fn contraction(
        &self,
        q: &[[D; DIM]],
        w: &[[D; DIM]],
        ctx: &Ctx<D>,
        what: Product,
        scratch: &mut DualScratch<D, DIM>,
    ) -> Result<D> {
        let mut v = Products {
            q,
            w,
            ctx: *ctx,
            what,
            scale: D::one(),
            out: None,
            sum: D::zero(),
            scratch,
        };
        self.visit_terms(&mut v)?;
        Ok(v.sum)
    }

    /// The largest joint angle θᵢ = ∠(q_{i−1}, qᵢ), i = 1..=n+1, in radians (including the end
    /// joints against e₂ whether or not they carry a spring).
    pub fn max_joint_angle(&self, q: &[[D; DIM]]) -> f64 {
        let e = e2::<D, DIM>();
        let mut m: f64 = 0.0;
        for i in 0..=self.n {
            let a = if i == 0 { &e } else { &q[i - 1] };
            let b = if i == self.n { &e } else { &q[i] };
            m = m.max(joint_angle_squared(a, b).re().sqrt());
        }
        m
    }

    /// Potential energy U(q; t, u): the sum of every term's energy ([`ForceTerm::energy`]), with
    /// the x component of a 2-axis control at step 0 (see [`Chain::potential_energy_at`]).
    pub fn potential_energy(&self, q: &[[D; DIM]], t: f64, u: D) -> D {
        self.potential_energy_at(q, t, u, 0)
    }

    /// Potential energy U(q; t_k, u_k) at step k (the x component of a 2-axis control is
    /// u_{x,k}).
    pub fn potential_energy_at(&self, q: &[[D; DIM]], t: f64, u: D, k: usize) -> D {
        let ctx = self.ctx(t, u, k);
        let mut v = EnergySum {
            q,
            ctx,
            sum: D::zero(),
        };
        // Energies cannot fail (no visitor returns an error).
        let _ = self.visit_terms(&mut v);
        v.sum
    }

    /// Kinetic energy ½ pᵀM⁻¹p; `scratch` has length n.
    pub fn kinetic_energy(&self, p: &[[D; DIM]], scratch: &mut [[D; DIM]]) -> D {
        self.apply_inverse_mass(p, scratch);
        let mut e = D::zero();
        for (a, b) in p.iter().zip(scratch.iter()) {
            e += dot(a, b);
        }
        e * 0.5
    }

    /// Base bending moment M₀ = 2 k₁ z₁ / l₁² with z₁ = l₁ e₃ᵀq₁ (eq. 3.1.3, sign and index
    /// corrected as docs/conventions.md says).
    #[inline]
    pub fn base_moment(&self, q: &[[D; DIM]]) -> D {
        self.moment_stiffness * 2.0 * q[0][zi::<DIM>()] * self.inv_lengths[0]
    }

    /// The base bending moment as a vector M₀ = (M₀ₓ, M₀_z) = (2 k₁ / l₁)(e₁ᵀq₁, e₃ᵀq₁) =
    /// 2 k₁ (x₁, z₁) / l₁² (docs/conventions.md "The bending moment M₀"): each component is the
    /// moment of the base spring that bends the beam toward that axis, with the sign of eq. 3.1.3
    /// (M₀_z is [`Chain::base_moment`]; M₀ₓ = 0 in the planar model). A rotation of the loads about
    /// the beam's axis y rotates (M₀ₓ, M₀_z) with them, so |M₀|² = M₀ₓ² + M₀_z² is invariant.
    #[inline]
    pub fn base_moment_vector(&self, q: &[[D; DIM]]) -> [D; 2] {
        let s = self.moment_stiffness * 2.0 * self.inv_lengths[0];
        let mx = if DIM == 3 { s * q[0][0] } else { D::zero() };
        [mx, s * q[0][zi::<DIM>()]]
    }

    /// Node positions rᵢ = Σ_{j≤i} l_j q_j, i = 1..=n (node 0 is the origin).
    pub fn node_positions(&self, q: &[[D; DIM]], out: &mut [[D; DIM]]) {
        let mut r = [D::zero(); DIM];
        for i in 0..self.n {
            for d in 0..DIM {
                r[d] += self.lengths[i] * q[i][d];
            }
            out[i] = r;
        }
    }

    /// Tip z: l(q) = Σ lᵢ e₃ᵀqᵢ (eq. 2.4.1).
    #[inline]
    pub fn tip_z(&self, q: &[[D; DIM]]) -> D {
        let z = zi::<DIM>();
        let mut s = D::zero();
        for i in 0..self.n {
            s += self.lengths[i] * q[i][z];
        }
        s
    }

    /// Lengths lᵢ.
    pub fn lengths(&self) -> &[D] {
        &self.lengths
    }

    /// The inverse lengths 1/lᵢ.
    pub fn inverse_lengths(&self) -> &[D] {
        &self.inv_lengths
    }

    /// Masses mᵢ.
    pub fn masses(&self) -> &[D] {
        &self.masses
    }

    /// Spring constants k₁..k_{n+1} (zero where the support has none).
    pub fn springs(&self) -> &[D] {
        &self.springs.k
    }
}
