//! Streaming simulation: the states t_k, k = 0..=N, handed to an observer as they are produced
//! ([`simulate_streaming`]), so that a long run holds O(n) memory instead of the O(N·n) of a
//! stored [`Trajectory`](super::Trajectory) (a 3-hour sea state of the 300 m
//! riser, `examples/scenes/riser_300m.toml`, is 864 000 steps of 60 pendulums, ≈ 2.5 GB as a
//! planar trajectory of q, p, λ and μ at 48 bytes per pendulum and step). [`moment_history`]
//! keeps only the base moment (O(N) values), which is all the fatigue path reads.
//!
//! Every number is that of [`simulate()`](super::simulate) bit for bit: the same RATTLE steps
//! from the same state with the same controls, and the same formulas for the energy, the moment
//! and the node positions ([`StepView`]).

use super::{check_controls, node_positions, piece_index};
use crate::base::StepStats;
use crate::error::{Error, Result};
use crate::model::Chain;
use crate::scene::{Checked, ControlKind, Scene, SceneInput};
use crate::steppers::rattle::{Rattle, State};

/// The controls a streamed run applies.
#[derive(Clone, Copy, Debug)]
pub enum StreamControls<'a> {
    /// The scene's own `[control]` at its node, computed step by step (no N-long vector):
    /// what [`simulate()`](super::simulate) applies.
    Scene,
    /// Per-step controls u_0..u_N (N + 1 values) at the scene's control node (default: the
    /// tip), in the model the scene needs ([`SimulateInput::controls`](super::SimulateInput::controls)).
    Given(&'a [f64]),
    /// Per-step 2-axis controls (u_{x,k}, u_k), N + 1 values each, in the spatial model
    /// ([`SimulateInput::controls_xz`](super::SimulateInput::controls_xz)).
    GivenXz {
        /// u_{x,0..N}.
        x: &'a [f64],
        /// u_{0..N} (z components).
        z: &'a [f64],
    },
}

/// The control u_k of step k, without an N-long vector for a scene's constant or piecewise
/// control (the values of [`super::scene_controls`], bit for bit).
#[derive(Clone, Copy, Debug)]
enum ControlAt<'a> {
    Zero,
    Slice(&'a [f64]),
    Constant(f64),
    Piecewise { values: &'a [f64], steps: usize },
}

impl ControlAt<'_> {
    #[inline]
    fn at(&self, k: usize) -> f64 {
        match *self {
            ControlAt::Zero => 0.0,
            ControlAt::Slice(u) => u[k],
            ControlAt::Constant(u) => u,
            ControlAt::Piecewise { values, steps } => values[piece_index(k, steps, values.len())],
        }
    }

    /// The scene's z controls (as [`super::scene_controls`] expands them).
    fn of_scene(scene: &Scene) -> ControlAt<'_> {
        let steps = scene.time.steps;
        match &scene.control {
            None => ControlAt::Zero,
            Some(c) => match c.kind {
                ControlKind::Constant => ControlAt::Constant(c.values[0]),
                ControlKind::PerStep => ControlAt::Slice(&c.values),
                ControlKind::Piecewise => ControlAt::Piecewise {
                    values: &c.values,
                    steps,
                },
            },
        }
    }

    /// [`check_controls`] on the values this draws from (N + 1 of them for a slice).
    fn check(&self, steps: usize) -> Result<()> {
        match *self {
            ControlAt::Zero => Ok(()),
            ControlAt::Slice(u) => check_controls(u, steps),
            ControlAt::Constant(u) => finite(&[u]),
            ControlAt::Piecewise { values, .. } => finite(values),
        }
    }
}

/// [`Error::NotFinite`] naming the first non-finite control value.
fn finite(values: &[f64]) -> Result<()> {
    match values.iter().position(|x| !x.is_finite()) {
        Some(index) => Err(Error::NotFinite {
            name: "controls",
            index,
        }),
        None => Ok(()),
    }
}

/// The state at t_k = k h of a streamed run, lent to a [`StepObserver`]: the attitudes and
/// momenta, and what `chainbeam simulate` writes, computed on demand with the formulas of
/// [`Trajectory`](super::Trajectory) (so a quantity the observer does not ask for costs
/// nothing).
pub struct StepView<'a, const DIM: usize> {
    k: usize,
    h: f64,
    control: f64,
    state: &'a State<f64, DIM>,
    chain: &'a Chain<f64, DIM>,
    /// λ_k, μ_k of the step that ended at k (the consistent multiplier at k = 0).
    multipliers: (&'a [f64], &'a [f64]),
    stats: Option<StepStats>,
    lengths: &'a [f64],
    scratch: &'a mut [[f64; DIM]],
}

impl<const DIM: usize> StepView<'_, DIM> {
    /// The step index k.
    pub fn k(&self) -> usize {
        self.k
    }
    /// The time t_k = k h \[s\] ([`Trajectory::time`](super::Trajectory::time)).
    pub fn time(&self) -> f64 {
        self.k as f64 * self.h
    }
    /// Number of pendulums n.
    pub fn n(&self) -> usize {
        self.state.q.len()
    }
    /// Attitudes qᵢ(t_k).
    pub fn q(&self) -> &[[f64; DIM]] {
        &self.state.q
    }
    /// Momenta pᵢ(t_k).
    pub fn p(&self) -> &[[f64; DIM]] {
        &self.state.p
    }
    /// λ of the step that ended at k (at k = 0 the consistent initial multiplier).
    pub fn lambda(&self) -> &[f64] {
        self.multipliers.0
    }
    /// μ of the step that ended at k (at k = 0 the consistent initial multiplier).
    pub fn mu(&self) -> &[f64] {
        self.multipliers.1
    }
    /// The Newton statistics of the step that ended at k (`None` at k = 0).
    pub fn stats(&self) -> Option<StepStats> {
        self.stats
    }
    /// The control u_k \[N\] (its z component for a 2-axis control).
    pub fn control(&self) -> f64 {
        self.control
    }
    /// The x component u_{x,k} \[N\] of a 2-axis control (0 for a 1-axis control).
    pub fn control_x(&self) -> f64 {
        self.chain.control_x(self.k)
    }
    /// The base moment vector (M₀ₓ, M₀) = 2 k₁ (x₁, z₁) / l₁² \[N m\] (eq. 3.1.3,
    /// [`Chain::base_moment_vector`]); M₀ₓ = 0 in the planar model.
    pub fn moment_vector(&self) -> [f64; 2] {
        self.chain.base_moment_vector(&self.state.q)
    }
    /// The total energy H(q_k, p_k; t_k, u_k) = ½pᵀM⁻¹p + U \[J\].
    pub fn energy(&mut self) -> f64 {
        let (q, p) = (&self.state.q, &self.state.p);
        self.chain.kinetic_energy(p, self.scratch)
            + self
                .chain
                .potential_energy_at(q, self.time(), self.control, self.k)
    }
    /// Node positions rᵢ = Σ_{j≤i} l_j q_j, i = 1..n, as (x, y, z) into `out` (n entries;
    /// x = 0 in the planar model).
    pub fn positions(&self, out: &mut [[f64; 3]]) {
        node_positions(&self.state.q, self.lengths, out);
    }
    /// The tip's target at t_k: ζ_k of the reaction-force variant, the vessel's Z(t_k) of a tip
    /// the vessel holds, zero otherwise ([`Trajectory::tip_target`](super::Trajectory::tip_target)).
    pub fn tip_target(&self) -> f64 {
        self.state.tip_target[0]
    }
    /// The model.
    pub fn chain(&self) -> &Chain<f64, DIM> {
        self.chain
    }
}

/// What a streamed run hands its states to ([`simulate_streaming`]), in order k = 0, 1, …, N.
/// The method is generic over the model's dimension (2: planar, 3: spatial), which the scene
/// chooses.
pub trait StepObserver {
    /// The observer's own error (e.g. an I/O error of a writer), which stops the run.
    type Error;

    /// Receives the state at t_k.
    ///
    /// # Errors
    /// The observer's; the run stops and returns it as [`StreamError::Observer`].
    fn observe<const DIM: usize>(
        &mut self,
        step: &mut StepView<'_, DIM>,
    ) -> std::result::Result<(), Self::Error>;
}

/// Why a streamed run stopped.
#[derive(Debug)]
pub enum StreamError<E> {
    /// The simulation failed (scene, controls or a step: [`Error`]); the states k before the
    /// failing step have been observed.
    Simulation(Error),
    /// The observer returned an error.
    Observer(E),
}

impl<E> From<Error> for StreamError<E> {
    fn from(e: Error) -> Self {
        StreamError::Simulation(e)
    }
}

impl<E: std::fmt::Display> std::fmt::Display for StreamError<E> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            StreamError::Simulation(e) => e.fmt(f),
            StreamError::Observer(e) => e.fmt(f),
        }
    }
}

impl<E: std::fmt::Debug + std::fmt::Display> std::error::Error for StreamError<E> {}

/// What a streamed run did.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct StreamSummary {
    /// Whether the spatial model ran ([`Scene::is_spatial`]).
    pub spatial: bool,
    /// Number of steps N (N + 1 states were observed).
    pub steps: usize,
    /// The step h \[s\].
    pub h: f64,
    /// Total Newton iterations.
    pub newton_iterations: usize,
}

/// Simulates `scene` from the straight beam at rest with `controls`, in the model it needs
/// (planar or spatial, as [`simulate()`](super::simulate)), and hands every state t_k,
/// k = 0..=N, to `observer` as soon as it is computed: O(n) memory whatever N (besides what the
/// scene's model holds, e.g. its wave record). The states are those of `simulate` bit for bit.
///
/// # Errors
/// [`StreamError::Simulation`] with the errors of [`simulate()`](super::simulate) and its
/// variants (controls of the wrong length or not finite, a failed step) except
/// [`Error::TrajectoryTooLarge`], which a streamed run cannot meet;
/// [`StreamError::Observer`] with the observer's error. Either stops the run.
pub fn simulate_streaming<S: SceneInput + ?Sized, O: StepObserver>(
    scene: &S,
    controls: StreamControls<'_>,
    observer: &mut O,
) -> std::result::Result<StreamSummary, StreamError<O::Error>> {
    let scene = scene.checked().map_err(Error::from)?;
    fn run<const DIM: usize, O: StepObserver>(
        checked: Checked<'_>,
        controls: StreamControls<'_>,
        observer: &mut O,
    ) -> std::result::Result<StreamSummary, StreamError<O::Error>> {
        let mut chain = Chain::<f64, DIM>::from_checked(checked)?;
        let scene = checked.scene();
        crate::statics::set_static_start(&mut chain, scene)?;
        let u = match controls {
            StreamControls::Scene => {
                if let Some(c) = &scene.control {
                    if let Some(vx) = &c.values_x {
                        chain.set_control_x(&super::expand_controls(
                            c.kind,
                            vx,
                            scene.time.steps,
                        ))?;
                    }
                }
                ControlAt::of_scene(scene)
            }
            StreamControls::Given(u) | StreamControls::GivenXz { z: u, .. } => {
                if chain.control_node().is_none() {
                    chain.set_control_node(Some(scene.n()))?;
                }
                if let StreamControls::GivenXz { x, .. } = controls {
                    check_controls(x, scene.time.steps)?;
                    chain.set_control_x(x)?;
                }
                ControlAt::Slice(u)
            }
        };
        stream_chain(chain, (scene.time.step, scene.time.steps), u, observer)
    }
    let spatial = matches!(controls, StreamControls::GivenXz { .. }) || scene.is_spatial();
    if spatial {
        run::<3, O>(scene, controls, observer)
    } else {
        run::<2, O>(scene, controls, observer)
    }
}

/// The loop of [`simulate_streaming`] on a chain: [`super::simulate_chain`]'s steps, observed
/// instead of stored.
fn stream_chain<const DIM: usize, O: StepObserver>(
    chain: Chain<f64, DIM>,
    (h, steps): (f64, usize),
    u: ControlAt<'_>,
    observer: &mut O,
) -> std::result::Result<StreamSummary, StreamError<O::Error>> {
    u.check(steps)?;
    let n = chain.n();
    let lengths: Vec<f64> = chain.lengths().to_vec();
    let mut rattle = Rattle::new(chain, h)?;
    let mut state: State<f64, DIM> = rattle.start_state()?;
    rattle.prepare(&mut state, 0, u.at(0))?;
    let mut scratch = vec![[0.0; DIM]; n];
    let mu0 = rattle.consistent_multiplier().to_vec();
    let mut view = StepView {
        k: 0,
        h,
        control: u.at(0),
        state: &state,
        chain: rattle.chain(),
        multipliers: (&mu0, &mu0),
        stats: None,
        lengths: &lengths,
        scratch: &mut scratch,
    };
    observer.observe(&mut view).map_err(StreamError::Observer)?;
    let mut newton_iterations = 0;
    for k in 0..steps {
        crate::cancel::check_at(k).map_err(StreamError::from)?;
        let (uk, uk1) = (u.at(k), u.at(k + 1));
        let s = rattle.step(&mut state, k, uk, uk1)?;
        newton_iterations += s.iterations;
        let m = state
            .multipliers
            .as_ref()
            .expect("a step leaves its multipliers");
        let mut view = StepView {
            k: k + 1,
            h,
            control: uk1,
            state: &state,
            chain: rattle.chain(),
            multipliers: (&m.lambda, &m.mu),
            stats: Some(s),
            lengths: &lengths,
            scratch: &mut scratch,
        };
        observer.observe(&mut view).map_err(StreamError::Observer)?;
    }
    Ok(StreamSummary {
        spatial: DIM == 3,
        steps,
        h,
        newton_iterations,
    })
}

/// The base moment history of a simulated scene: M₀(t_k) and, in the spatial model, M₀ₓ(t_k),
/// k = 0..=N ([`moment_history`]).
#[derive(Clone, Debug, PartialEq)]
pub struct MomentSeries {
    /// The step h \[s\].
    pub h: f64,
    /// M₀(t_k) = 2 k₁ z₁ / l₁² \[N m\] (eq. 3.1.3), N + 1 values.
    pub moment: Vec<f64>,
    /// M₀ₓ(t_k) \[N m\] of the spatial model, `None` in the planar one.
    pub moment_x: Option<Vec<f64>>,
}

impl MomentSeries {
    /// Number of steps N.
    pub fn steps(&self) -> usize {
        self.moment.len().saturating_sub(1)
    }
    /// The simulated duration t_N = N h \[s\].
    pub fn duration(&self) -> f64 {
        self.steps() as f64 * self.h
    }
}

/// Collects the moments of a streamed run.
struct MomentSink {
    moment: Vec<f64>,
    moment_x: Vec<f64>,
}

impl StepObserver for MomentSink {
    type Error = std::convert::Infallible;
    fn observe<const DIM: usize>(
        &mut self,
        step: &mut StepView<'_, DIM>,
    ) -> std::result::Result<(), Self::Error> {
        let [mx, mz] = step.moment_vector();
        self.moment.push(mz);
        if DIM == 3 {
            self.moment_x.push(mx);
        }
        Ok(())
    }
}

/// The base moment history of `scene` with its own controls (what
/// [`simulate()`](super::simulate) gives as [`SceneTrajectory::moment`](super::SceneTrajectory::moment)
/// and [`SceneTrajectory::moment_x`](super::SceneTrajectory::moment_x), bit for bit), from a
/// streamed run that holds 8 or 16 bytes per step instead of the whole trajectory: what the
/// fatigue path needs (M₀ and M₀ₓ only).
///
/// # Errors
/// As [`simulate()`](super::simulate); [`Error::TrajectoryTooLarge`] if the allocator refuses
/// the N + 1 values.
pub fn moment_history<S: SceneInput + ?Sized>(scene: &S) -> Result<MomentSeries> {
    let scene = scene.checked()?;
    let steps = scene.time.steps;
    let spatial = scene.is_spatial();
    let values = (steps + 1) * if spatial { 2 } else { 1 };
    let too_large = || Error::TrajectoryTooLarge {
        n: scene.n(),
        steps,
        bytes: 8 * values as u64,
        max_steps: crate::scene::MAX_STEPS,
        refused: true,
    };
    let mut sink = MomentSink {
        moment: Vec::new(),
        moment_x: Vec::new(),
    };
    sink.moment
        .try_reserve_exact(steps + 1)
        .map_err(|_| too_large())?;
    if spatial {
        sink.moment_x
            .try_reserve_exact(steps + 1)
            .map_err(|_| too_large())?;
    }
    match simulate_streaming(&scene, StreamControls::Scene, &mut sink) {
        Ok(_) => {}
        Err(StreamError::Simulation(e)) => return Err(e),
        Err(StreamError::Observer(never)) => match never {},
    }
    Ok(MomentSeries {
        h: scene.time.step,
        moment: sink.moment,
        moment_x: spatial.then_some(sink.moment_x),
    })
}
