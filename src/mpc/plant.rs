//! The plant: a scene simulated interval by interval by RATTLE with the control the loop applies,
//! stepped through the [`Stepper`] trait (its steps, its restart from a stored state and its
//! closing control half-kick).

use crate::base::Scalar;
use crate::error::{Error, MpcError, Result};
use crate::model::Chain;
use crate::scene::{Scene, SceneInput};
use crate::steppers::rattle::{Rattle, State};
use crate::steppers::Stepper;

/// The true system of a closed loop: the planar RATTLE map (thesis eq. 1.6.1) of a scene, from
/// the scene's start at t = 0 (`[time] initial`: straight at rest, or static), advanced step by step with the control force u_k at the
/// scene's control node (default: the tip n). Generic over the scalar, so that a closed loop can
/// be differentiated with respect to a feedback law's gains by dual numbers.
///
/// # The control at a switching time
/// A RATTLE step k → k+1 takes u_k in its first and u_{k+1} in its second half-kick, and
/// p_{k+1} depends on u_{k+1}. A controller decides u_k from the state at t_k, so the plant first
/// takes the step into t_k with the held control u_{k+1} = u_k−1, the controller observes that
/// state, and [`Plant::set_control`] re-takes that last step with the decided u_k. The trajectory
/// is therefore exactly the open-loop RATTLE trajectory of the applied per-step controls
/// u_0..u_N (what [`crate::simulate()`] computes with them, [`crate::SimulateInput::controls`]).
///
/// # The state before the control's half-kick
/// Which p_k a controller sees at t_k depends on a control it has not decided yet. After the
/// projection onto the hidden constraint the second half-kick is affine in the control: with
/// b = ∂U_q/∂u (block j: l_j e₃ for j below the control node, eq. 3.1.1) and
/// P(q) = I − Ĝᵀ(Ĝ M⁻¹ Ĝᵀ)⁻¹ Ĝ M⁻¹,
/// ```text
/// p_k = p̂_k − (h/2) u_k P(q_k) b,
/// ```
/// where p̂_k, the momentum of the step into t_k taken with zero control in its second
/// half-kick, does not depend on u_k. [`Plant::state_before_kick`] is (q_k, p̂_k), computed as
/// p̂_k = p_k + (h/2) u P(q_k) b from the state and the control u its step took
/// ([`Stepper::control_kick`]); a controller that plans from it with the kick
/// pending ([`crate::ControlProblem::starting_before_kick`]) lets its first force act on both
/// sides of t_k exactly as the plant then applies it. At k = 0 there is no step into t₀ (the
/// beam is at rest, p_0 = 0 whatever u_0) and there is no such state; nor for a reaction-force
/// tip, whose control is not a force term.
///
/// # The vessel under thrust
/// In a scene whose control is the thrust on the vessel ([`crate::scene::Thrust`]) the plant is
/// the actuator as well: the control a controller sets is the thrust it commands, and the thrust
/// applied at t_k is that command clipped to ±F_max and then moved from the thrust of t_{k−1}
/// by at most Ḟ_max h (the thrust before t₀ is 0). Between decisions the applied thrust keeps
/// moving toward the command at that rate. So |F_k| ≤ F_max and |F_k − F_{k−1}| ≤ Ḟ_max h at
/// every step whatever a controller asks for; [`Plant::control`] is the applied thrust. In
/// other scenes the command is applied as it is, bit for bit as before.
///
/// # The spatial plant
/// `DIM = 3` is the spatial model of a scene whose loads or current have an x component, with a
/// 2-axis control u = (u_x, u_z) ([`Plant::set_controls`]): the x components are the chain's x
/// schedule (held like u between decisions), and the state before the kick takes
/// p̂_k = p_k + (h/2) P(q_k)(u b + u_x b_x).
#[derive(Clone, Debug)]
pub struct Plant<D: Scalar, const DIM: usize = 2> {
    stepper: Rattle<D, DIM>,
    state: State<D, DIM>,
    /// The state at t_{k−1}, from which the last step is re-taken.
    prev: State<D, DIM>,
    k: usize,
    steps: usize,
    /// u_k (the control at the current t_k, its z component) and u_{k−1}.
    u: D,
    u_prev: D,
    /// M⁻¹p, for Ṁ₀.
    velocity: Vec<[D; DIM]>,
    /// (q_k, p̂_k) and the step k it was computed at ([`Plant::update_state_before_kick`]).
    before_kick: State<D, DIM>,
    before_kick_at: Option<usize>,
    /// The vessel's thrust limits (F_max, Ḟ_max h) in a thrust scene (type docs).
    limits: Option<(f64, f64)>,
    /// The commanded control (the applied one is `u`, through `limits`).
    command: D,
}

impl<D: Scalar, const DIM: usize> Plant<D, DIM> {
    /// The plant of a scene at t = 0 with u_0 = 0 (the scene's `[control]` values are not
    /// applied: the loop's controller decides them), in the planar (`DIM = 2`) or the spatial
    /// (`DIM = 3`, with a 2-axis control) model.
    ///
    /// # Errors
    /// The scene's model errors; [`Error::NeedsSpatialModel`] for a planar plant of a scene with
    /// loads along x.
    pub fn new<S: SceneInput + ?Sized>(scene: &S) -> Result<Self> {
        let checked = scene.checked()?;
        let scene = checked.scene();
        let mut chain = Chain::<f64, DIM>::from_scene(&checked)?;
        give_plant_control_and_start(&mut chain, scene)?;
        let mut chain = chain.lift::<D>();
        if DIM == 3 {
            chain.set_control_x(&vec![D::zero(); scene.time.steps + 1])?;
        }
        let mut stepper = Rattle::new(chain, scene.time.step)?;
        let state = stepper.initial_state(D::zero())?;
        Ok(Plant {
            prev: state.clone(),
            before_kick: state.clone(),
            state,
            stepper,
            k: 0,
            steps: scene.time.steps,
            u: D::zero(),
            u_prev: D::zero(),
            velocity: vec![[D::zero(); DIM]; scene.n()],
            before_kick_at: None,
            limits: scene
                .thrust()
                .map(|t| (t.bound, t.rate_bound * scene.time.step)),
            command: D::zero(),
        })
    }

    /// The thrust applied after `prev` toward the command (type docs, "The vessel under
    /// thrust"); the command itself without limits. The clips pass no derivative.
    fn limited(&self, prev: D) -> D {
        let Some((bound, change)) = self.limits else {
            return self.command;
        };
        let c = self.command.re();
        let target = if c > bound {
            D::from(bound)
        } else if c < -bound {
            D::from(-bound)
        } else {
            self.command
        };
        let d = target.re() - prev.re();
        if d > change {
            prev + D::from(change)
        } else if d < -change {
            prev - D::from(change)
        } else {
            target
        }
    }

    /// The current step index k.
    pub fn step_index(&self) -> usize {
        self.k
    }

    /// The scene's number of steps N.
    pub fn steps(&self) -> usize {
        self.steps
    }

    /// The step h.
    pub fn h(&self) -> f64 {
        Stepper::h(&self.stepper)
    }

    /// t_k = k h.
    pub fn time(&self) -> f64 {
        self.k as f64 * self.h()
    }

    /// The state at t_k.
    pub fn state(&self) -> &State<D, DIM> {
        &self.state
    }

    /// Computes (q_k, p̂_k), the state at t_k before the control's half-kick (type docs), for
    /// [`Plant::state_before_kick`]: p̂_k = p_k + (h/2) u P(q_k) b with u the control of the
    /// step into t_k. Nothing to compute at k = 0 or for a reaction-force tip. O(n), no
    /// allocation.
    ///
    /// # Errors
    /// [`Error::SingularSystem`] from the projection.
    pub fn update_state_before_kick(&mut self) -> Result<()> {
        if self.k == 0 || self.before_kick_at == Some(self.k) || self.chain().has_driven_tip() {
            return Ok(());
        }
        let (hat, st) = (&mut self.before_kick, &self.state);
        hat.q.copy_from_slice(&st.q);
        hat.tip_target = st.tip_target;
        // The multipliers (the next step's Newton predictor), in place after the first time.
        match (&mut hat.multipliers, &st.multipliers) {
            (Some(h), Some(m)) => {
                h.lambda.copy_from_slice(&m.lambda);
                h.mu.copy_from_slice(&m.mu);
                h.gaps.clone_from(&m.gaps);
            }
            (h, m) => h.clone_from(m),
        }
        let ux = self.control_x();
        let p = &mut self.before_kick.p;
        if DIM == 3 {
            self.stepper
                .control_half_kick(&self.state.q, (self.u, ux), p)?;
        } else {
            self.stepper.control_kick(&self.state, self.u, p)?;
        }
        for (ph, pk) in p.iter_mut().zip(&self.state.p) {
            // p̂ = p_k − (−(h/2) P(q_k)(u b + u_x b_x))
            for d in 0..DIM {
                ph[d] = pk[d] - ph[d];
            }
        }
        self.before_kick_at = Some(self.k);
        Ok(())
    }

    /// (q_k, p̂_k), the state at t_k with the momentum of the step into t_k taken with zero
    /// control in its second half-kick (type docs), if [`Plant::update_state_before_kick`]
    /// computed it at this step; `None` at k = 0, for a reaction-force tip and for the vessel
    /// under thrust (whose control is not a force on the riser). It does not
    /// depend on the control set at t_k.
    pub fn state_before_kick(&self) -> Option<&State<D, DIM>> {
        (self.before_kick_at == Some(self.k)).then_some(&self.before_kick)
    }

    /// The state at t_{k−1}, from which [`Plant::set_control`] re-takes the step into t_k;
    /// `None` at k = 0.
    pub fn previous_state(&self) -> Option<&State<D, DIM>> {
        (self.k > 0).then_some(&self.prev)
    }

    /// The control applied at t_{k−1} (zero at k = 0).
    pub fn previous_control(&self) -> D {
        if self.k == 0 {
            D::zero()
        } else {
            self.u_prev
        }
    }

    /// The vessel's thrust limits (F_max \[N\], Ḟ_max h \[N per step\]) in a thrust scene (type
    /// docs, "The vessel under thrust"); `None` otherwise.
    pub fn thrust_limits(&self) -> Option<(f64, f64)> {
        self.limits
    }

    /// The model.
    pub fn chain(&self) -> &Chain<D, DIM> {
        Stepper::chain(&self.stepper)
    }

    /// The control u_k applied at t_k (its z component in the spatial model).
    pub fn control(&self) -> D {
        self.u
    }

    /// The x component u_{x,k} of the control applied at t_k (0 in the planar model).
    pub fn control_x(&self) -> D {
        self.chain().control_x(self.k)
    }

    /// The base moment vector (M₀ₓ, M₀_z)(t_k) ([`Chain::base_moment_vector`]; M₀ₓ = 0 in the
    /// planar model).
    pub fn moment_vector(&self) -> [D; 2] {
        self.chain().base_moment_vector(&self.state.q)
    }

    /// Its rate (Ṁ₀ₓ, Ṁ₀_z) with q̇ = M⁻¹p (M₀ is linear in q₁).
    pub fn moment_vector_rate(&mut self) -> [D; 2] {
        let ch = Stepper::chain(&self.stepper);
        ch.apply_inverse_mass(&self.state.p, &mut self.velocity);
        ch.base_moment_vector(&self.velocity)
    }

    /// The base bending moment M₀(t_k) = 2 k₁ z₁ / l₁² (thesis eq. 3.1.3).
    pub fn moment(&self) -> D {
        self.chain().base_moment(&self.state.q)
    }

    /// Its rate Ṁ₀ = 2 k₁ ż₁ / l₁² with q̇ = M⁻¹p (M₀ is linear in z₁).
    pub fn moment_rate(&mut self) -> D {
        let ch = Stepper::chain(&self.stepper);
        ch.apply_inverse_mass(&self.state.p, &mut self.velocity);
        ch.base_moment(&self.velocity)
    }

    /// The tip displacement z_n = Σ lᵢ qᵢ,z.
    pub fn tip(&self) -> D {
        self.chain().tip_z(&self.state.q)
    }

    /// Sets u_k at the current t_k. At k = 0 the beam is at rest and only the force is
    /// recomputed; at k > 0 the step k−1 → k is re-taken with (u_{k−1}, u_k), so the
    /// trajectory is the RATTLE trajectory of the applied controls (type docs).
    ///
    /// # Errors
    /// [`Error::NotFinite`] for a non-finite u; the step's errors.
    pub fn set_control(&mut self, u: D) -> Result<()> {
        if !u.re().is_finite() {
            return Err(Error::NotFinite {
                name: "control",
                index: self.k,
            });
        }
        self.command = u;
        self.u = self.limited(if self.k == 0 { D::zero() } else { self.u_prev });
        self.apply()
    }

    /// Sets the 2-axis control (u_x, u_z) at the current t_k (the spatial model; as
    /// [`Plant::set_control`] otherwise).
    ///
    /// # Errors
    /// [`Error::NotFinite`] for a non-finite component; [`Error::NeedsSpatialModel`] for
    /// u_x ≠ 0 in the planar model; the step's errors.
    pub fn set_controls(&mut self, [ux, u]: [D; 2]) -> Result<()> {
        if !(u.re().is_finite() && ux.re().is_finite()) {
            return Err(Error::NotFinite {
                name: "control",
                index: self.k,
            });
        }
        if DIM == 2 {
            if ux.re().abs() > 0.0 {
                return Err(Error::NeedsSpatialModel {
                    key: "control".into(),
                });
            }
        } else {
            let k = self.k;
            self.stepper.chain_mut().control_x[k] = ux;
        }
        self.command = u;
        self.u = self.limited(if self.k == 0 { D::zero() } else { self.u_prev });
        self.apply()
    }

    /// Applies the control just set: at k = 0 the initial state's force, at k > 0 the step
    /// k−1 → k re-taken.
    fn apply(&mut self) -> Result<()> {
        if self.k == 0 {
            self.state = self.stepper.initial_state(self.u)?;
            Ok(())
        } else {
            self.retake()
        }
    }

    /// Re-takes the step k−1 → k from the stored state with (u_{k−1}, u_k).
    fn retake(&mut self) -> Result<()> {
        let k = self.k - 1;
        self.state.clone_from(&self.prev);
        self.stepper.resume(&self.state, k, self.u_prev)?;
        Stepper::step(&mut self.stepper, &mut self.state, k, self.u_prev, self.u)?;
        Ok(())
    }

    /// Advances one step to t_{k+1} holding the control (u_{k+1} = u_k).
    ///
    /// # Errors
    /// [`MpcError::PastEnd`] past t_N; the step's errors.
    pub fn advance(&mut self) -> Result<()> {
        if self.k >= self.steps {
            return Err(MpcError::PastEnd { steps: self.steps }.into());
        }
        // Every closed loop and PD cost steps through here: a cancelled run stops within a batch.
        crate::cancel::check_at(self.k)?;
        self.prev.clone_from(&self.state);
        if DIM == 3 {
            // Hold u_x as u: u_{x,k+1} = u_{x,k}.
            let (k, ux) = (self.k, self.control_x());
            self.stepper.chain_mut().control_x[k + 1] = ux;
        }
        let next = self.limited(self.u);
        Stepper::step(&mut self.stepper, &mut self.state, self.k, self.u, next)?;
        self.u_prev = self.u;
        self.u = next;
        self.k += 1;
        Ok(())
    }
}

/// The chain of the plant of `scene`: its model with the control at the scene's node (the top
/// by default, where a thrust's vessel holds the riser) and the scene's start (`[time]
/// initial`, [`crate::statics::set_static_start`]).
///
/// # Errors
/// The model's and the static start's errors.
pub(crate) fn plant_chain<const DIM: usize>(scene: &Scene) -> Result<Chain<f64, DIM>> {
    let mut chain = Chain::<f64, DIM>::from_scene(scene)?;
    give_plant_control_and_start(&mut chain, scene)?;
    Ok(chain)
}

/// Sets the control node of `chain` (built from `scene`) to the top when the scene names none,
/// and gives it the scene's start.
fn give_plant_control_and_start<const DIM: usize>(
    chain: &mut Chain<f64, DIM>,
    scene: &Scene,
) -> Result<()> {
    if chain.control_node().is_none() {
        chain.set_control_node(Some(scene.n()))?;
    }
    crate::statics::set_static_start(chain, scene)
}
