//! Simulation of a scene into a [`Trajectory`] (q, p, λ, μ per step, node positions, energy,
//! base bending moment M₀(t_k) and solver statistics), or streamed to an observer state by state
//! in O(n) memory ([`simulate_streaming`], [`moment_history`]).
//!
//! A trajectory stores every state, so its size ([`trajectory_bytes`]) is checked against
//! [`MAX_TRAJECTORY_BYTES`] before anything of size N is allocated, and its buffers are reserved
//! fallibly: a scene's trajectory that does not fit is refused by
//! [`Scene::check_stored_trajectory`] (an [`Error::Scene`] naming `time.steps`, the bytes and the
//! limit), a chain's by [`simulate_chain`] ([`Error::TrajectoryTooLarge`], naming the same), never
//! an allocation abort. The check belongs to the run that stores: a scene over the budget is
//! valid and streams ([`simulate_streaming`], [`moment_history`], `chainbeam simulate`).

use crate::base::Scalar;
use crate::error::{Error, Result};
use crate::model::Chain;
pub use crate::scene::{max_trajectory_steps, trajectory_bytes};
use crate::scene::{ControlKind, Scene, MAX_TRAJECTORY_BYTES};
use crate::steppers::rattle::{Rattle, State, StepStats};

mod columns;
mod stream;
pub use columns::TrajectoryColumns;
pub use stream::{
    moment_history, simulate_streaming, MomentSeries, StepObserver, StepView, StreamControls,
    StreamError, StreamSummary,
};

/// A simulated trajectory on the grid t_k = k h, k = 0..=N.
#[derive(Clone, Debug)]
pub struct Trajectory<D, const DIM: usize> {
    n: usize,
    n_constraints: usize,
    h: f64,
    steps: usize,
    q: Vec<[D; DIM]>,
    p: Vec<[D; DIM]>,
    lambda: Vec<D>,
    mu: Vec<D>,
    /// Total energy H(q_k, p_k; t_k, u_k) = ½pᵀM⁻¹p + U, k = 0..=N.
    pub energy: Vec<D>,
    /// Base bending moment M₀(t_k) (eq. 3.1.3), k = 0..=N.
    pub moment: Vec<D>,
    /// Controls u_k used, k = 0..=N.
    pub controls: Vec<D>,
    /// The x component M₀ₓ(t_k) of the base moment vector
    /// ([`Chain::base_moment_vector`]), k = 0..=N; empty in the planar model.
    pub moment_x: Vec<D>,
    /// The x components u_{x,k} of a 2-axis control, k = 0..=N; empty for a 1-axis control.
    pub controls_x: Vec<D>,
    /// The tip's target: ζ_k of the reaction-force variant, the vessel's Z(t_k) of a tip the
    /// vessel holds, zero otherwise.
    pub tip_target: Vec<D>,
    /// Per-step Newton statistics, k = 0..N−1.
    pub stats: Vec<StepStats>,
    lengths: Vec<f64>,
}

impl<D: Scalar, const DIM: usize> Trajectory<D, DIM> {
    /// Number of pendulums.
    pub fn n(&self) -> usize {
        self.n
    }
    /// Number of steps N (there are N + 1 states).
    pub fn steps(&self) -> usize {
        self.steps
    }
    /// Step h.
    pub fn h(&self) -> f64 {
        self.h
    }
    /// Time t_k = k h.
    pub fn time(&self, k: usize) -> f64 {
        k as f64 * self.h
    }
    /// Attitudes q at step k.
    pub fn q(&self, k: usize) -> &[[D; DIM]] {
        &self.q[k * self.n..(k + 1) * self.n]
    }
    /// Momenta p at step k.
    pub fn p(&self, k: usize) -> &[[D; DIM]] {
        &self.p[k * self.n..(k + 1) * self.n]
    }
    /// λ of the step that ended at k (k ≥ 1; at k = 0 the consistent initial multiplier).
    pub fn lambda(&self, k: usize) -> &[D] {
        &self.lambda[k * self.n_constraints..(k + 1) * self.n_constraints]
    }
    /// μ of the step that ended at k (k ≥ 1; at k = 0 the consistent initial multiplier).
    pub fn mu(&self, k: usize) -> &[D] {
        &self.mu[k * self.n_constraints..(k + 1) * self.n_constraints]
    }
    /// Node positions r₁..rₙ at step k as (x, y, z) (x = 0 in the planar model).
    pub fn positions(&self, k: usize) -> Vec<[f64; 3]> {
        let mut r = vec![[0.0; 3]; self.n];
        node_positions(self.q(k), &self.lengths, &mut r);
        r
    }
    /// Total Newton iterations.
    pub fn newton_iterations(&self) -> usize {
        self.stats.iter().map(|s| s.iterations).sum()
    }
    /// |M₀(t_k)| = √(M₀ₓ² + M₀_z²), the magnitude of the base moment vector, k = 0..=N (|M₀_z|
    /// in the planar model).
    pub fn moment_magnitude(&self) -> Vec<f64> {
        (0..=self.steps)
            .map(|k| {
                let mx = self.moment_x.get(k).map_or(0.0, |m| m.re());
                mx.hypot(self.moment[k].re())
            })
            .collect()
    }
}

/// Node positions rᵢ = Σ_{j≤i} l_j q_j (the base at the origin) as (x, y, z), x = 0 in the
/// planar model, into `out` (one entry per pendulum).
fn node_positions<D: Scalar, const DIM: usize>(
    q: &[[D; DIM]],
    lengths: &[f64],
    out: &mut [[f64; 3]],
) {
    let mut r = [0.0; 3];
    for ((qi, l), o) in q.iter().zip(lengths).zip(out) {
        for d in 0..DIM {
            r[3 - DIM + d] += l * qi[d].re();
        }
        *o = r;
    }
}

/// The piece of step k in a piecewise-constant control with `pieces` = P pieces over N = `steps`
/// steps (docs/conventions.md, "Piecewise controls"): the N effective steps k = 0..N−1 are split
/// evenly, piece j covering the k with ⌊k·P/N⌋ = j, i.e. k ∈ [⌈jN/P⌉, ⌈(j+1)N/P⌉); u_N, which
/// reaches no configuration, takes the last piece. Piece lengths differ by at most one and the
/// longer pieces come first (N = 10, P = 3: 4, 3, 3 steps), because piece j starts at the first
/// grid time at or after j·T/P. P = N gives one piece per step, P = 1 a constant.
pub fn piece_index(k: usize, steps: usize, pieces: usize) -> usize {
    if k >= steps {
        pieces.saturating_sub(1)
    } else {
        // k < N ≤ 10⁷ and P ≤ N in a valid scene: k·P < 10¹⁴ cannot overflow (u128 for any P).
        ((k as u128 * pieces as u128) / steps as u128) as usize
    }
}

/// The per-step controls u_0..u_N of a scene: its `[control]` values expanded (constant → N + 1
/// copies, piecewise → [`piece_index`]), or zeros without a control. For a 2-axis control these
/// are the z components (see [`scene_controls_x`]).
pub fn scene_controls(scene: &Scene) -> Vec<f64> {
    let steps = scene.time.steps;
    match &scene.control {
        None => vec![0.0; steps + 1],
        Some(c) => expand_controls(c.kind, &c.values, steps),
    }
}

/// The x components u_{x,0..N} of a scene's 2-axis control, expanded like [`scene_controls`];
/// empty for a 1-axis control or none.
pub fn scene_controls_x(scene: &Scene) -> Vec<f64> {
    match &scene.control {
        Some(c) => c
            .values_x
            .as_ref()
            .map_or_else(Vec::new, |vx| expand_controls(c.kind, vx, scene.time.steps)),
        None => Vec::new(),
    }
}

/// Per-step controls u_0..u_N from a scene's control values of kind `kind`.
fn expand_controls(kind: ControlKind, values: &[f64], steps: usize) -> Vec<f64> {
    let n1 = steps + 1;
    match kind {
        ControlKind::Constant => vec![values[0]; n1],
        ControlKind::PerStep => values.to_vec(),
        ControlKind::Piecewise => (0..n1)
            .map(|k| values[piece_index(k, steps, values.len())])
            .collect(),
    }
}

/// Checks that `u` has N + 1 finite values.
pub(crate) fn check_controls<D: Scalar>(u: &[D], steps: usize) -> Result<()> {
    if u.len() != steps + 1 {
        return Err(Error::WrongLength {
            name: "controls",
            expected: steps + 1,
            got: u.len(),
        });
    }
    match u.iter().position(|x| !x.re().is_finite()) {
        Some(index) => Err(Error::NotFinite {
            name: "controls",
            index,
        }),
        None => Ok(()),
    }
}

/// An empty vector with room for `len` values, or [`Error::TrajectoryTooLarge`] if the allocator
/// refuses.
fn try_with_capacity<T>(len: usize, too_large: &Error) -> Result<Vec<T>> {
    let mut v = Vec::new();
    v.try_reserve_exact(len).map_err(|_| too_large.clone())?;
    Ok(v)
}

/// The size of a trajectory to reserve: n pendulums, n_c constraints, step h, N steps, and
/// whether it records the x components of the controls (the spatial model's M₀ₓ is recorded
/// whenever DIM = 3).
#[derive(Clone, Copy, Debug)]
struct Shape {
    n: usize,
    n_constraints: usize,
    h: f64,
    steps: usize,
    controls_x: bool,
}

impl<D, const DIM: usize> Trajectory<D, DIM> {
    /// The empty trajectory of `shape` with room for the whole run, allocated fallibly: each
    /// series (N + 1 values per time, n or n_c per node, N step statistics) reserved exactly,
    /// `too_large` when the allocator refuses.
    fn reserve(shape: Shape, lengths: Vec<f64>, too_large: &Error) -> Result<Self> {
        let Shape {
            n,
            n_constraints: nc,
            h,
            steps,
            controls_x,
        } = shape;
        let e = too_large;
        let (states, multipliers) = ((steps + 1) * n, (steps + 1) * nc);
        let spatial = if DIM == 3 { steps + 1 } else { 0 };
        Ok(Trajectory {
            n,
            n_constraints: nc,
            h,
            steps,
            q: try_with_capacity(states, e)?,
            p: try_with_capacity(states, e)?,
            lambda: try_with_capacity(multipliers, e)?,
            mu: try_with_capacity(multipliers, e)?,
            energy: try_with_capacity(steps + 1, e)?,
            moment: try_with_capacity(steps + 1, e)?,
            controls: try_with_capacity(steps + 1, e)?,
            moment_x: try_with_capacity(spatial, e)?,
            controls_x: try_with_capacity(if controls_x { spatial } else { 0 }, e)?,
            tip_target: try_with_capacity(steps + 1, e)?,
            stats: try_with_capacity(steps, e)?,
            lengths,
        })
    }
}

/// The trajectory of a scene in the model it needs: planar (`DIM = 2`) when every load lies in
/// the yz-plane, spatial (`DIM = 3`) when some load has an x component ([`Scene::is_spatial`]).
/// Everything is read through the methods, in either model (time grid, energy, M₀ and M₀ₓ,
/// the controls, node positions as (x, y, z)); [`SceneTrajectory::as_planar`] and
/// [`SceneTrajectory::as_spatial`] give the model's own [`Trajectory`] (attitudes and momenta).
#[derive(Clone, Debug)]
pub struct SceneTrajectory(Model);

/// The trajectory inside a [`SceneTrajectory`], in the model's dimension.
#[derive(Clone, Debug)]
enum Model {
    /// The planar model's trajectory (qᵢ ∈ S¹ in the yz-plane; x = 0).
    Planar(Trajectory<f64, 2>),
    /// The spatial model's trajectory (qᵢ ∈ S²).
    Spatial(Trajectory<f64, 3>),
}

/// Calls `$body` on the trajectory inside a [`SceneTrajectory`], whatever its dimension.
macro_rules! either {
    ($s:expr, $t:ident => $body:expr) => {
        match &$s.0 {
            Model::Planar($t) => $body,
            Model::Spatial($t) => $body,
        }
    };
}

impl From<Trajectory<f64, 2>> for SceneTrajectory {
    /// A planar model's trajectory.
    fn from(t: Trajectory<f64, 2>) -> Self {
        SceneTrajectory(Model::Planar(t))
    }
}

impl From<Trajectory<f64, 3>> for SceneTrajectory {
    /// A spatial model's trajectory.
    fn from(t: Trajectory<f64, 3>) -> Self {
        SceneTrajectory(Model::Spatial(t))
    }
}

impl SceneTrajectory {
    /// Whether the spatial model ran.
    pub fn is_spatial(&self) -> bool {
        matches!(self.0, Model::Spatial(_))
    }
    /// The dimension of the model: 2 (planar) or 3 (spatial).
    pub fn dim(&self) -> usize {
        if self.is_spatial() {
            3
        } else {
            2
        }
    }
    /// Number of pendulums.
    pub fn n(&self) -> usize {
        either!(self, t => t.n())
    }
    /// Number of steps N (there are N + 1 states).
    pub fn steps(&self) -> usize {
        either!(self, t => t.steps())
    }
    /// Step h.
    pub fn h(&self) -> f64 {
        either!(self, t => t.h())
    }
    /// Time t_k = k h.
    pub fn time(&self, k: usize) -> f64 {
        either!(self, t => t.time(k))
    }
    /// Node positions r₁..rₙ at step k as (x, y, z) (x = 0 in the planar model).
    pub fn positions(&self, k: usize) -> Vec<[f64; 3]> {
        either!(self, t => t.positions(k))
    }
    /// Total energy H(q_k, p_k; t_k, u_k), k = 0..=N.
    pub fn energy(&self) -> &[f64] {
        either!(self, t => &t.energy)
    }
    /// Base bending moment M₀(t_k) = 2 k₁ z₁ / l₁² (eq. 3.1.3), k = 0..=N.
    pub fn moment(&self) -> &[f64] {
        either!(self, t => &t.moment)
    }
    /// Controls u_k used, k = 0..=N (z components of a 2-axis control).
    pub fn controls(&self) -> &[f64] {
        either!(self, t => &t.controls)
    }
    /// The x component M₀ₓ(t_k) of the base moment vector, k = 0..=N (empty in the planar
    /// model).
    pub fn moment_x(&self) -> &[f64] {
        either!(self, t => &t.moment_x)
    }
    /// |M₀(t_k)| = √(M₀ₓ² + M₀_z²), k = 0..=N.
    pub fn moment_magnitude(&self) -> Vec<f64> {
        either!(self, t => t.moment_magnitude())
    }
    /// The x components u_{x,k} of a 2-axis control, k = 0..=N (empty for a 1-axis control).
    pub fn controls_x(&self) -> &[f64] {
        either!(self, t => &t.controls_x)
    }
    /// The tip's target: ζ_k of the reaction-force variant, the vessel's Z(t_k) of a tip the
    /// vessel holds, zero otherwise.
    pub fn tip_target(&self) -> &[f64] {
        either!(self, t => &t.tip_target)
    }
    /// Per-step Newton statistics, k = 0..N−1.
    pub fn stats(&self) -> &[StepStats] {
        either!(self, t => &t.stats)
    }
    /// Total Newton iterations.
    pub fn newton_iterations(&self) -> usize {
        either!(self, t => t.newton_iterations())
    }
    /// The planar trajectory, if the planar model ran.
    pub fn as_planar(&self) -> Option<&Trajectory<f64, 2>> {
        match &self.0 {
            Model::Planar(t) => Some(t),
            Model::Spatial(_) => None,
        }
    }
    /// The spatial trajectory, if the spatial model ran.
    pub fn as_spatial(&self) -> Option<&Trajectory<f64, 3>> {
        match &self.0 {
            Model::Spatial(t) => Some(t),
            Model::Planar(_) => None,
        }
    }
    /// The planar trajectory, for code written for the planar model.
    ///
    /// # Errors
    /// [`Error::NeedsSpatialModel`] if the scene was spatial.
    pub fn into_planar(self) -> Result<Trajectory<f64, 2>> {
        match self.0 {
            Model::Planar(t) => Ok(t),
            Model::Spatial(_) => Err(Error::NeedsSpatialModel {
                key: "loads.point".to_string(),
            }),
        }
    }
}

/// What [`simulate()`] runs: a scene, with its own `[control]` or with given per-step controls
/// ([`StreamControls`]: u_z only, or 2-axis (u_x, u_z)). A `&Scene` is the scene with its own
/// controls, so `simulate(&scene)` reads as before.
#[derive(Clone, Copy, Debug)]
pub struct SimulateInput<'a> {
    /// The scene.
    pub scene: &'a Scene,
    /// The controls it runs with.
    pub controls: StreamControls<'a>,
}

impl<'a> SimulateInput<'a> {
    /// `scene` with its own `[control]` (none: zero).
    pub fn new(scene: &'a Scene) -> Self {
        SimulateInput {
            scene,
            controls: StreamControls::Scene,
        }
    }

    /// The run with the per-step controls u_0..u_N (N + 1 values) at the scene's control node
    /// (default: the tip), in the model the scene needs.
    pub fn controls(self, controls: &'a [f64]) -> Self {
        SimulateInput {
            controls: StreamControls::Given(controls),
            ..self
        }
    }

    /// The run with per-step 2-axis controls (u_{x,k}, u_{z,k}), N + 1 values each, at the
    /// scene's control node (default: the tip), in the spatial model.
    pub fn controls_xz(self, x: &'a [f64], z: &'a [f64]) -> Self {
        SimulateInput {
            controls: StreamControls::GivenXz { x, z },
            ..self
        }
    }
}

impl<'a> From<&'a Scene> for SimulateInput<'a> {
    fn from(scene: &'a Scene) -> Self {
        SimulateInput::new(scene)
    }
}

/// Simulates a scene in `f64` from the straight beam at rest, in the model it needs: the
/// planar one when all loads lie in the yz-plane and the control (if any) acts along z (every
/// thesis scene), the spatial one otherwise ([`Scene::is_spatial`]; docs/scene-format.md
/// "model no more than a scene needs") or for 2-axis controls. `input` is a `&Scene` (its own
/// controls) or a [`SimulateInput`] with given controls:
/// ```
/// use chainbeam::{catalogue, simulate, SimulateInput};
/// let scene = catalogue::riser(5); // the thesis's riser, its load at node 5, control at the tip
/// let free = simulate(&scene)?;
/// let u = vec![-1.5; scene.time.steps + 1];
/// let pushed = simulate(SimulateInput::new(&scene).controls(&u))?;
/// let (m0, m1) = (free.moment()[scene.time.steps], pushed.moment()[scene.time.steps]);
/// assert!(m0 != m1 && !pushed.is_spatial());
/// let ux = vec![0.5; scene.time.steps + 1]; // a 2-axis control runs the spatial model
/// let turned = simulate(SimulateInput::new(&scene).controls_xz(&ux, &u))?;
/// assert!(turned.is_spatial() && turned.moment_x()[scene.time.steps] != 0.0);
/// # Ok::<(), chainbeam::Error>(())
/// ```
/// The run is the stream of [`simulate_streaming`] with a recorder observing it: every number is
/// the streamed run's, stored.
///
/// # Errors
/// [`Scene::check_stored_trajectory`]'s (the trajectory over [`MAX_TRAJECTORY_BYTES`], naming
/// `time.steps`) before anything of size N is allocated; [`Error::WrongLength`] or
/// [`Error::NotFinite`] naming `controls` for given controls of the wrong length or not finite;
/// [`Error::TrajectoryTooLarge`] if the allocator refuses the trajectory; the step's errors.
pub fn simulate<'a>(input: impl Into<SimulateInput<'a>>) -> Result<SceneTrajectory> {
    let SimulateInput { scene, controls } = input.into();
    scene.check_stored_trajectory()?;
    fn stored<const DIM: usize>(
        scene: &Scene,
        controls: StreamControls<'_>,
    ) -> Result<Trajectory<f64, DIM>> {
        let mut recorder = Recorder::<DIM> {
            h: scene.time.step,
            steps: scene.time.steps,
            trajectory: None,
        };
        match simulate_streaming(scene, controls, &mut recorder) {
            Ok(_) => {}
            Err(StreamError::Simulation(e) | StreamError::Observer(e)) => return Err(e),
        }
        recorder.trajectory.ok_or_else(|| model_mismatch(DIM))
    }
    // The model simulate_streaming runs: the spatial one for 2-axis controls or a spatial scene.
    Ok(
        if matches!(controls, StreamControls::GivenXz { .. }) || scene.is_spatial() {
            SceneTrajectory(Model::Spatial(stored::<3>(scene, controls)?))
        } else {
            SceneTrajectory(Model::Planar(stored::<2>(scene, controls)?))
        },
    )
}

/// The error of a recorder whose model is not the stream's (not met: both follow the scene).
fn model_mismatch(dim: usize) -> Error {
    Error::WrongLength {
        name: "dimension",
        expected: dim,
        got: 5 - dim,
    }
}

/// Stores the states of a streamed run into a [`Trajectory`] of the model's dimension, reserved
/// fallibly at the first state (when the chain's size is known) for all N + 1.
struct Recorder<const DIM: usize> {
    h: f64,
    steps: usize,
    trajectory: Option<Trajectory<f64, DIM>>,
}

impl<const DIM: usize> Recorder<DIM> {
    /// The empty trajectory of `chain` with room for the run.
    fn reserve(&self, chain: &Chain<f64, DIM>) -> Result<Trajectory<f64, DIM>> {
        let (n, nc, steps) = (chain.n(), chain.n_constraints(), self.steps);
        let bytes = trajectory_bytes::<f64, DIM>(n, nc, steps);
        let e = &Error::TrajectoryTooLarge {
            n,
            steps,
            bytes,
            max_steps: max_trajectory_steps::<f64, DIM>(n, nc),
            refused: bytes <= MAX_TRAJECTORY_BYTES,
        };
        if bytes > MAX_TRAJECTORY_BYTES {
            return Err(e.clone());
        }
        let shape = Shape {
            n,
            n_constraints: nc,
            h: self.h,
            steps,
            controls_x: chain.has_control_x(),
        };
        Trajectory::reserve(shape, chain.lengths().to_vec(), e)
    }
}

impl<const DIM: usize> StepObserver for Recorder<DIM> {
    type Error = Error;

    fn observe<const D: usize>(&mut self, step: &mut StepView<'_, D>) -> Result<()> {
        let chain: &dyn std::any::Any = step.chain();
        if let (0, Some(chain)) = (step.k(), chain.downcast_ref::<Chain<f64, DIM>>()) {
            self.trajectory = Some(self.reserve(chain)?);
        }
        let t = self
            .trajectory
            .as_mut()
            .map(|t| t as &mut dyn std::any::Any);
        let Some(t) = t.and_then(|t| t.downcast_mut::<Trajectory<f64, D>>()) else {
            return Err(model_mismatch(DIM));
        };
        t.q.extend_from_slice(step.q());
        t.p.extend_from_slice(step.p());
        t.lambda.extend_from_slice(step.lambda());
        t.mu.extend_from_slice(step.mu());
        let e = step.energy();
        t.energy.push(e);
        let [mx, mz] = step.moment_vector();
        t.moment.push(mz);
        t.controls.push(step.control());
        if D == 3 {
            t.moment_x.push(mx);
        }
        if step.chain().has_control_x() {
            t.controls_x.push(step.control_x());
        }
        t.tip_target.push(step.tip_target());
        if let Some(s) = step.stats() {
            t.stats.push(s);
        }
        Ok(())
    }
}

/// Simulates `chain` from the straight beam at rest for `steps` steps of size `h` with controls
/// u_0..u_N (and the x components of a 2-axis control the chain holds,
/// [`Chain::set_control_x`]), generic over the scalar (dual numbers give forward-mode
/// derivatives of the whole trajectory) and the dimension.
///
/// # Errors
/// [`Error::WrongLength`] or [`Error::NotFinite`] for controls of the wrong length or not
/// finite;
/// [`Error::TrajectoryTooLarge`] when the trajectory exceeds [`MAX_TRAJECTORY_BYTES`] or the
/// allocator refuses it; the step's errors ([`Rattle::step`]).
pub fn simulate_chain<D: Scalar, const DIM: usize>(
    chain: Chain<D, DIM>,
    h: f64,
    steps: usize,
    controls: &[D],
) -> Result<Trajectory<D, DIM>> {
    check_controls(controls, steps)?;
    let n = chain.n();
    let nc = chain.n_constraints();
    // The size check and the fallible allocation come before anything of size N is allocated.
    let bytes = trajectory_bytes::<D, DIM>(n, nc, steps);
    let too_large = |refused| Error::TrajectoryTooLarge {
        n,
        steps,
        bytes,
        max_steps: max_trajectory_steps::<D, DIM>(n, nc),
        refused,
    };
    if bytes > MAX_TRAJECTORY_BYTES {
        return Err(too_large(false));
    }
    let e = &too_large(true);
    let shape = Shape {
        n,
        n_constraints: nc,
        h,
        steps,
        controls_x: DIM == 3,
    };
    let lengths = chain.lengths().iter().map(|l| l.re()).collect();
    let mut traj = Trajectory::reserve(shape, lengths, e)?;
    traj.controls.extend_from_slice(controls);
    if chain.has_control_x() {
        traj.controls_x
            .extend((0..=steps).map(|k| chain.control_x(k)));
    }
    let mut rattle = Rattle::new(chain, h)?;
    let mut state: State<D, DIM> = rattle.start_state()?;
    rattle.prepare(&mut state, 0, controls[0])?;
    let mut scratch = vec![[D::zero(); DIM]; n];
    let record = |traj: &mut Trajectory<D, DIM>,
                  (st, k): (&State<D, DIM>, usize),
                  (lambda, mu): (&[D], &[D]),
                  scratch: &mut [[D; DIM]],
                  ch: &Chain<D, DIM>| {
        traj.q.extend_from_slice(&st.q);
        traj.p.extend_from_slice(&st.p);
        traj.lambda.extend_from_slice(lambda);
        traj.mu.extend_from_slice(mu);
        let t = k as f64 * h;
        let e =
            ch.kinetic_energy(&st.p, scratch) + ch.potential_energy_at(&st.q, t, controls[k], k);
        traj.energy.push(e);
        let [mx, mz] = ch.base_moment_vector(&st.q);
        traj.moment.push(mz);
        if DIM == 3 {
            traj.moment_x.push(mx);
        }
        traj.tip_target.push(st.tip_target[0]);
    };
    // The initial state has no multipliers: λ_0 = μ_0 = the consistent multiplier.
    let mu0 = rattle.consistent_multiplier().to_vec();
    let first = (&mu0[..], &mu0[..]);
    record(&mut traj, (&state, 0), first, &mut scratch, rattle.chain());
    for k in 0..steps {
        crate::cancel::check_at(k)?;
        let s = rattle.step(&mut state, k, controls[k], controls[k + 1])?;
        traj.stats.push(s);
        let m = state
            .multipliers
            .as_ref()
            .expect("a step leaves its multipliers");
        let lm = (&m.lambda[..], &m.mu[..]);
        record(&mut traj, (&state, k + 1), lm, &mut scratch, rattle.chain());
    }
    Ok(traj)
}

/// Samples a piecewise-constant control u(t) = uⱼ on [aⱼ, bⱼ) (0 elsewhere) onto the grid as the
/// averages of u over the part of [0, t_N] that u_k acts on in RATTLE: u_k enters the half-steps
/// on both sides of t_k, so it stands for [t_k − h/2, t_k + h/2] ∩ [0, t_N] (only half a cell at
/// t_0 and t_N). With these values the discrete impulse h/2 Σ (u_k + u_{k+1}) equals the exact
/// impulse ∫ u dt, and a push followed by an equal and opposite push stops the tip exactly
/// (thesis Fig. 3.4, right).
///
/// This is not the scene file's `kind = "piecewise"`, which splits the N steps into equal pieces
/// on the grid ([`piece_index`]); here the pieces are arbitrary time intervals, averaged over the
/// half cells each u_k acts on, so that the impulse is exact.
pub fn piecewise_constant_controls(h: f64, steps: usize, pieces: &[(f64, f64, f64)]) -> Vec<f64> {
    let t_end = steps as f64 * h;
    (0..=steps)
        .map(|k| {
            let lo = ((k as f64 - 0.5) * h).max(0.0);
            let hi = ((k as f64 + 0.5) * h).min(t_end);
            if hi <= lo {
                return 0.0;
            }
            pieces
                .iter()
                .map(|&(a, b, u)| u * (hi.min(b) - lo.max(a)).max(0.0))
                .sum::<f64>()
                / (hi - lo)
        })
        .collect()
}
