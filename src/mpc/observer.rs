//! What MPC sees of the plant when it does not see the whole state (`[mpc] observe =
//! "sensors"`, [`crate::mpc`] "What the controller sees"): a named set of sensors with their
//! measurement noise, and a Kalman filter on the plan's linearised model that turns their
//! readings into the state the plan starts from.
//!
//! # The sensors ([`SensorSet`])
//! A drilling riser is monitored by a few instruments, not by the angle and momentum of every
//! pendulum. On a scene whose control is the vessel's thrust and whose riser is a `[stackup]`
//! with at least two flex joints and a body under the lowest one (the LMRP under the lower flex
//! joint), the controller reads, at the start of each control interval,
//! ```text
//! y₁ = Z            the vessel's position (the top's z, m)          σ = 0.1 m
//! y₂ = Ż            the vessel's velocity (m/s)                    σ = 0.02 m/s
//! y₃ = θ_top        the top flex joint's angle (rad)                σ = 0.1° = 1.75·10⁻³ rad
//! y₄ = θ_bottom     the bottom flex joint's angle (rad)             σ = 0.1°
//! y₅ = φ_LMRP       the LMRP's inclination from the vertical (rad)  σ = 0.05° = 8.7·10⁻⁴ rad
//! ```
//! each with an independent Gaussian error of the standard deviation σ ([`SensorNoise`]), drawn
//! from a seeded ChaCha20 stream (Box–Muller), so a run is reproducible. The numbers are typical
//! instrument accuracies, reasoned rather than measured here: a dynamically positioned vessel's
//! position reference is a differential GNSS (decimetre-level with precise corrections, 0.1 m),
//! whose Doppler velocity is good to a few cm/s (0.02 m/s); a flex joint's angle is read as the
//! difference of two inclinometers (or a riser angle sensor) of about 0.05–0.1° each, taken as
//! 0.1°; the LMRP's inclinometer, a single subsea MEMS inclinometer, 0.05°. A flex joint's angle
//! is the joint angle of the chain (φ_{j+1} − φ_j for the joint between pendulums j and j + 1;
//! φ₁ at the base spring; φ_n at the tip spring, the top pendulum against the vessel's vertical),
//! an inclination the absolute angle φ_j (q_j = (cos φ_j, sin φ_j) in (y, z)): every sensor but
//! the vessel's position is linear in the state (φ, ω) (ω_j = φ̇_j), and Z = Σ l_j sin φ_j is
//! linearised about the equilibrium. On another scene "sensors" is refused
//! ([`MpcError::ObserveNeedsThrust`], [`MpcError::ObserveSensors`], both naming `observe`): the
//! set is that of a riser held by a vessel under thrust.
//!
//! # The filter ([`Observer`])
//! The state is x = (φ₁..φ_n, ω₁..ω_n): in a thrust scene the vessel's (Z, Ż) is the top's,
//! Z = Σ l_j sin φ_j, Ż = Σ l_j cos φ_j ω_j, so the 2n angles and rates are the whole state.
//! - **The mean** is predicted by the planning model itself (the plan's own scene with the
//!   forecast's sea, [`crate::mpc::Forecast`], RATTLE at the plant's step) over each control
//!   interval from the last estimate, with the thrusts the thrusters applied (the commands sent,
//!   through the thrusters' clipping, as the plan models them): the waves the forecast knows are
//!   a known input.
//! - **The covariance** is propagated by the linearised map of one interval, Φ = A^m, with A the
//!   exact Jacobian of one RATTLE step of the model in x (dual numbers, 2n directions) at the
//!   static equilibrium of the calm sea (the mean offset and the current; thrust 0), after the
//!   vessel's ramp.
//! - **The process noise** is what the forecast misses: an unforecast angular acceleration of
//!   every pendulum, white with spectral density s² (s = [`ObserverOptions::process_noise`],
//!   default 2·10⁻³ rad·s^{−3/2}), whose covariance over an interval T is the continuous white-noise
//!   acceleration model's
//!   ```text
//!   Q = s² [ T³/3 I   T²/2 I ;  T²/2 I   T I ].
//!   ```
//!   The default is the order of what a fully unforecast sea does to the top pendulum in the
//!   most probable sea state of the shipped scenes (H_s ≈ 1.4 m, T_p ≈ 7.7 s): the vessel's
//!   wave surge (a few cm) accelerates a 7.6 m pendulum by about 4·10⁻³ rad/s², over a
//!   correlation time of about T_p, s ≈ 4·10⁻³ √8 ≈ 10⁻² for the top and less below; 2·10⁻³ is
//!   a fifth of the top's figure, every pendulum alike (fixed by this reasoning, not by a run).
//! - **The gain** is the steady-state Kalman gain of (Φ, C, Q, R): the prior covariance P⁻ solves
//!   the discrete algebraic Riccati equation
//!   ```text
//!   P⁻ = Φ (P⁻ − P⁻Cᵀ (C P⁻ Cᵀ + R)⁻¹ C P⁻) Φᵀ + Q,
//!   ```
//!   solved by the structure-preserving doubling algorithm (quadratically convergent; its
//!   residual checked to 10⁻⁶ relative, else [`MpcError::ObserverNotConverged`]), then
//!   S = C P⁻ Cᵀ + R, K = P⁻ Cᵀ S⁻¹, P⁺ = (I − K C) P⁻. Steady state rather than time-varying
//!   because the linearisation is fixed: the time-varying gain of the same (Φ, C, Q, R)
//!   converges to it within a few intervals, and the loop then does no matrix work beyond
//!   K ν — O(2n·5) per interval, no allocation, against O((2n)³) for a covariance update.
//! - **The update** at each decision: ν = y − h(x̂⁻) (the sensors of the predicted estimate, Z
//!   nonlinear), x̂⁺ = x̂⁻ + K ν in (φ, ω), and the state rebuilt from the angles
//!   (q_j = (cos φ_j, sin φ_j), q̇_j = ω_j (−sin φ_j, cos φ_j), p = M q̇, (Z, Ż) from the top), so
//!   it satisfies every constraint of the model.
//!
//! # When
//! The plan through the thrust starts one step back, from the state at t_{k−1} with its thrust
//! fixed ([`crate::mpc`], "MPC through the vessel's thrust"). The filter therefore runs on the
//! grid t_{jm−1}: the sensors are read at t_{k−1} (one plant step, a few milliseconds, before the
//! decision at t_k), the estimate there is the plan's start, and the next prediction runs from
//! it. At t₀ the plan starts from the scene's start (`[time] initial`: the straight riser at rest,
//! or the static equilibrium), as the plant does (the initial condition, known to the
//! controller); the estimate starts there too.
//!
//! The filter's linear error map (I − K C) Φ and its covariances are exposed
//! ([`Observer::error_map`], [`Observer::posterior`]) so that a test can compare the estimate's
//! error with what the filter predicts (tests/mpc/observe.rs).

use nalgebra::{DMatrix, DVector};
use num_dual::Dual64;
use rand_chacha::rand_core::{RngCore, SeedableRng};
use rand_chacha::ChaCha20Rng;

use super::thrust::Actuator;
use super::{interval_steps, ModelObservation};
use crate::base::Scalar;
use crate::error::{MpcError, Result};
use crate::model::Chain;
use crate::scene::{Scene, Support};
use crate::statics::{calm_scene, static_equilibrium_at};
use crate::steppers::rattle::{Rattle, State};
use crate::steppers::Stepper;

/// The number of sensors of [`SensorSet`].
pub const SENSORS: usize = 5;

/// The standard deviations of the sensors' errors (module docs, "The sensors").
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SensorNoise {
    /// The vessel's position \[m\] (default 0.1: a differential GNSS with precise corrections).
    pub vessel_position: f64,
    /// The vessel's velocity \[m/s\] (default 0.02: GNSS Doppler).
    pub vessel_velocity: f64,
    /// A flex joint's angle \[rad\] (default 0.1°).
    pub flex_joint: f64,
    /// The LMRP's inclinometer \[rad\] (default 0.05°).
    pub inclinometer: f64,
}

impl Default for SensorNoise {
    fn default() -> Self {
        SensorNoise {
            vessel_position: 0.1,
            vessel_velocity: 0.02,
            flex_joint: 0.1_f64.to_radians(),
            inclinometer: 0.05_f64.to_radians(),
        }
    }
}

impl SensorNoise {
    /// σ of the sensors in [`SensorSet`]'s order (Z, Ż, θ_top, θ_bottom, φ_LMRP).
    pub fn sigmas(&self) -> [f64; SENSORS] {
        [
            self.vessel_position,
            self.vessel_velocity,
            self.flex_joint,
            self.flex_joint,
            self.inclinometer,
        ]
    }
}

/// Settings of the [`Observer`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ObserverOptions {
    /// The sensors' error standard deviations (what the filter assumes, and, with `noisy`, what
    /// the readings carry).
    pub noise: SensorNoise,
    /// Whether the readings carry their noise (default `true`); `false` reads the sensors
    /// exactly (the filter is the same), for a test of the estimate's convergence.
    pub noisy: bool,
    /// s, the spectral density's square root of the unforecast angular acceleration of every
    /// pendulum \[rad·s^{−3/2}\] (module docs, "The filter"; default 2·10⁻³).
    pub process_noise: f64,
    /// The seed of the sensors' noise; `None` (default): the model scene's sea seed
    /// (`[loads.waves] seed`, 0 without waves), so each sea of a study gets its own readings.
    pub seed: Option<u64>,
}

impl Default for ObserverOptions {
    fn default() -> Self {
        ObserverOptions {
            noise: SensorNoise::default(),
            noisy: true,
            process_noise: 2e-3,
            seed: None,
        }
    }
}

/// Where the sensors sit on the chain (module docs, "The sensors"): joints 0..=n as
/// [`crate::scene::Layout::flex_joints`] numbers them, pendulums 0-based.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct SensorSet {
    /// The top flex joint (the highest).
    pub top_joint: usize,
    /// The bottom flex joint (the lowest).
    pub bottom_joint: usize,
    /// The LMRP's pendulum (0-based): the body just under the bottom flex joint.
    pub lmrp: usize,
}

impl SensorSet {
    /// The sensors of `scene`.
    ///
    /// # Errors
    /// [`MpcError::ObserveNeedsThrust`] for a scene whose control is not the vessel's thrust;
    /// [`MpcError::ObserveSensors`] for one without a `[stackup]` with two flex joints and a
    /// body under the lowest.
    pub fn of(scene: &Scene) -> Result<Self> {
        if scene.thrust().is_none() || scene.beam.support != Support::Vessel {
            return Err(MpcError::ObserveNeedsThrust.into());
        }
        let missing = |what: &'static str| MpcError::ObserveSensors { missing: what };
        let stackup = scene
            .stackup
            .as_ref()
            .ok_or_else(|| missing("a [stackup] table"))?;
        let joints = &stackup.layout.flex_joints;
        let (Some(&bottom), Some(&top)) = (joints.iter().min(), joints.iter().max()) else {
            return Err(missing("two flex joints").into());
        };
        if joints.len() < 2 || top == bottom {
            return Err(missing("two flex joints").into());
        }
        // The pendulum under the bottom joint (joint j sits on top of pendulum j, 1-based).
        let body = bottom
            .checked_sub(1)
            .filter(|&j| {
                stackup
                    .layout
                    .parts
                    .get(j)
                    .is_some_and(|part| stackup.bodies.iter().any(|b| &b.name == part))
            })
            .ok_or_else(|| missing("a body (the LMRP) under the lowest flex joint"))?;
        Ok(SensorSet {
            top_joint: top,
            bottom_joint: bottom,
            lmrp: body,
        })
    }

    /// The readings (Z, Ż, θ_top, θ_bottom, φ_LMRP) of a state with angles `phi` and the
    /// vessel's (Z, Ż) = `tip`.
    fn read(&self, phi: &[f64], tip: [f64; 2]) -> [f64; SENSORS] {
        [
            tip[0],
            tip[1],
            joint_angle(phi, self.top_joint),
            joint_angle(phi, self.bottom_joint),
            phi[self.lmrp],
        ]
    }

    /// The rows of C (5 × 2n) at the angles `phi` (rates zero).
    fn jacobian(&self, lengths: &[f64], phi: &[f64]) -> DMatrix<f64> {
        let n = phi.len();
        let mut c = DMatrix::zeros(SENSORS, 2 * n);
        for j in 0..n {
            c[(0, j)] = lengths[j] * phi[j].cos();
            c[(1, n + j)] = lengths[j] * phi[j].cos();
        }
        for (row, joint) in [(2, self.top_joint), (3, self.bottom_joint)] {
            match joint {
                0 => c[(row, 0)] = 1.0,
                j if j >= n => c[(row, n - 1)] = 1.0,
                j => {
                    c[(row, j)] = 1.0;
                    c[(row, j - 1)] = -1.0;
                }
            }
        }
        c[(4, self.lmrp)] = 1.0;
        c
    }
}

/// The angle of joint `j` (0: the base spring, φ₁; n: the tip spring, φ_n against the vessel's
/// vertical; else φ_{j+1} − φ_j).
fn joint_angle(phi: &[f64], j: usize) -> f64 {
    let n = phi.len();
    match j {
        0 => phi[0],
        j if j >= n => phi[n - 1],
        j => phi[j] - phi[j - 1],
    }
}

/// The Kalman filter of `observe = "sensors"` (module docs).
#[derive(Clone, Debug)]
pub struct Observer {
    stepper: Rattle<f64, 2>,
    actuator: Actuator,
    sensors: SensorSet,
    /// The estimate at `grid`.
    estimate: State<f64, 2>,
    grid: usize,
    /// The thrust applied at `grid` and the command in force after it.
    thrust: f64,
    command: f64,
    /// K (2n × 5), row by row.
    gain: Vec<[f64; SENSORS]>,
    prior: DMatrix<f64>,
    posterior: DMatrix<f64>,
    /// S⁻¹ = (C P⁻ Cᵀ + R)⁻¹.
    innovation_inverse: [[f64; SENSORS]; SENSORS],
    error_map: DMatrix<f64>,
    sigma: [f64; SENSORS],
    noisy: bool,
    rng: ChaCha20Rng,
    /// The last innovation ν and νᵀS⁻¹ν.
    innovation: Option<([f64; SENSORS], f64)>,
    /// Scratch: angles, rates, velocities.
    phi: Vec<f64>,
    omega: Vec<f64>,
    qdot: Vec<[f64; 2]>,
    moment_rate: f64,
}

/// The angles φ and rates ω of a planar state (q̇ = M⁻¹p, ω_j = q_j × q̇_j), `qdot` scratch.
fn minimal<D: Scalar>(
    chain: &Chain<D, 2>,
    state: &State<D, 2>,
    phi: &mut [D],
    omega: &mut [D],
    qdot: &mut [[D; 2]],
) {
    chain.apply_inverse_mass(&state.p, qdot);
    for (j, (q, v)) in state.q.iter().zip(qdot.iter()).enumerate() {
        phi[j] = q[1].atan2(q[0]);
        omega[j] = q[0] * v[1] - q[1] * v[0];
    }
}

/// The state of angles φ and rates ω (module docs, "The update"): q, p = M q̇ and the vessel's
/// (Z, Ż) of the top; the multipliers are kept (Newton's predictor).
fn rebuild<D: Scalar>(
    chain: &Chain<D, 2>,
    phi: &[D],
    omega: &[D],
    state: &mut State<D, 2>,
    qdot: &mut [[D; 2]],
) {
    let (mut z, mut zd) = (D::zero(), D::zero());
    let lengths = chain.lengths();
    for j in 0..phi.len() {
        let (s, c) = (phi[j].sin(), phi[j].cos());
        state.q[j] = [c, s];
        qdot[j] = [-omega[j] * s, omega[j] * c];
        z += lengths[j] * s;
        zd += lengths[j] * c * omega[j];
    }
    chain.apply_mass(qdot, &mut state.p);
    state.tip_target = [z, zd];
}

impl Observer {
    /// The filter of a plan on `model` (the controller's scene, its sea the forecast's) for a
    /// run of `steps` plant steps with decisions every `interval` seconds (module docs). Builds
    /// the linearisation and solves the Riccati equation (O((2n)³), once).
    ///
    /// # Errors
    /// [`SensorSet::of`]'s; [`MpcError::ObserverNotConverged`] when the Riccati equation has no
    /// stabilising solution within its iterations; the model's, the statics' and the steps'
    /// errors.
    pub fn new(
        model: &Scene,
        steps: usize,
        interval: f64,
        options: ObserverOptions,
    ) -> Result<Self> {
        let sensors = SensorSet::of(model)?;
        let thrust = model.thrust().ok_or(MpcError::ObserveNeedsThrust)?;
        let h = model.time.step;
        let m = interval_steps(interval, h)?;
        let n = model.n();
        // The filter's model over the run.
        let mut scene = model.clone();
        scene.time.steps = steps.max(1);
        let stepper = Rattle::new(control_chain(&scene)?, h)?;
        let estimate = stepper.start_state()?;
        // The calm sea's equilibrium after the ramp, and one step's Jacobian there.
        let ramp = model.vessel.as_ref().map_or(0.0, |v| v.ramp.max(0.0));
        let k_eq = ((ramp + 10.0) / h).ceil() as usize;
        let mut calm = calm_scene(model);
        calm.time.steps = k_eq + 2;
        let t_eq = k_eq as f64 * h;
        let eq = static_equilibrium_at(&calm, t_eq, 0.0)?;
        let calm_chain = control_chain(&calm)?;
        let lengths: Vec<f64> = calm_chain.lengths().to_vec();
        let a = step_jacobian(&calm_chain, h, k_eq, &eq.angles)?;
        let phi_m = matrix_power(&a, m);
        let c = sensors.jacobian(&lengths, &eq.angles);
        let sigma = options.noise.sigmas();
        let r = DMatrix::from_diagonal(&DVector::from_iterator(
            SENSORS,
            sigma.iter().map(|s| s * s),
        ));
        let q = process_noise(n, interval, options.process_noise);
        let prior = dare(&phi_m, &c, &q, &r)?;
        let s = &c * &prior * c.transpose() + &r;
        let s_inv = s
            .clone()
            .try_inverse()
            .ok_or(MpcError::ObserverNotConverged)?;
        let k = &prior * c.transpose() * &s_inv;
        let ikc = DMatrix::identity(2 * n, 2 * n) - &k * &c;
        let mut posterior = &ikc * &prior;
        symmetrise(&mut posterior);
        let error_map = &ikc * &phi_m;
        let gain = (0..2 * n)
            .map(|i| std::array::from_fn(|s| k[(i, s)]))
            .collect();
        let innovation_inverse = std::array::from_fn(|i| std::array::from_fn(|j| s_inv[(i, j)]));
        let seed = options
            .seed
            .unwrap_or_else(|| model.loads.waves.as_ref().map_or(0, |w| w.seed));
        Ok(Observer {
            stepper,
            actuator: Actuator {
                bound: thrust.bound,
                change: thrust.rate_bound * h,
            },
            sensors,
            estimate,
            grid: 0,
            thrust: 0.0,
            command: 0.0,
            gain,
            prior,
            posterior,
            innovation_inverse,
            error_map,
            sigma,
            noisy: options.noisy,
            rng: ChaCha20Rng::seed_from_u64(seed),
            innovation: None,
            phi: vec![0.0; n],
            omega: vec![0.0; n],
            qdot: vec![[0.0; 2]; n],
            moment_rate: 0.0,
        })
    }

    /// Where the sensors sit.
    pub fn sensors(&self) -> SensorSet {
        self.sensors
    }

    /// The estimate (at [`Observer::estimate_step`]).
    pub fn estimate(&self) -> &State<f64, 2> {
        &self.estimate
    }

    /// The plant step the estimate is of: k − 1 after the decision at t_k (0 before the first).
    pub fn estimate_step(&self) -> usize {
        self.grid
    }

    /// The steady-state prior covariance P⁻ (2n × 2n, in (φ, ω)).
    pub fn prior(&self) -> &DMatrix<f64> {
        &self.prior
    }

    /// The steady-state posterior covariance P⁺ = (I − K C) P⁻.
    pub fn posterior(&self) -> &DMatrix<f64> {
        &self.posterior
    }

    /// The linear map of the estimate's error from one update to the next, e⁺ ↦ (I − K C) Φ e⁺
    /// (noise-free sensors, a perfect model).
    pub fn error_map(&self) -> &DMatrix<f64> {
        &self.error_map
    }

    /// The sensors' standard deviations the filter assumes.
    pub fn sigmas(&self) -> [f64; SENSORS] {
        self.sigma
    }

    /// The last innovation ν = y − h(x̂⁻) and its normalised square νᵀ S⁻¹ ν (χ² with 5 degrees
    /// of freedom for a consistent filter); `None` before the first update.
    pub fn innovation(&self) -> Option<([f64; SENSORS], f64)> {
        self.innovation
    }

    /// The estimate's minimal coordinates (φ, ω) into `phi` and `omega` (`qdot` the scratch).
    fn estimate_to_minimal(&mut self) {
        let chain = Stepper::chain(&self.stepper);
        minimal(
            chain,
            &self.estimate,
            &mut self.phi,
            &mut self.omega,
            &mut self.qdot,
        );
    }

    /// Adds (δφ, δω) to the estimate (a prior that is wrong by that much; for tests of the
    /// filter's convergence).
    pub fn offset_estimate(&mut self, dphi: &[f64], domega: &[f64]) {
        self.estimate_to_minimal();
        for (p, d) in self.phi.iter_mut().zip(dphi) {
            *p += d;
        }
        for (w, d) in self.omega.iter_mut().zip(domega) {
            *w += d;
        }
        rebuild(
            Stepper::chain(&self.stepper),
            &self.phi,
            &self.omega,
            &mut self.estimate,
            &mut self.qdot,
        );
    }

    /// The estimate's error x̂ − x against the plant's `truth` (at the same step), in (φ, ω):
    /// `out` (2n) gets (φ̂ − φ, ω̂ − ω).
    pub fn deviation(&mut self, truth: &State<f64, 2>, out: &mut [f64]) {
        let n = self.phi.len();
        let chain = Stepper::chain(&self.stepper);
        minimal(chain, truth, &mut self.phi, &mut self.omega, &mut self.qdot);
        out[..n].copy_from_slice(&self.phi);
        out[n..2 * n].copy_from_slice(&self.omega);
        minimal(
            chain,
            &self.estimate,
            &mut self.phi,
            &mut self.omega,
            &mut self.qdot,
        );
        for j in 0..n {
            out[j] = self.phi[j] - out[j];
            out[n + j] = self.omega[j] - out[n + j];
        }
    }

    /// One standard normal draw (Box–Muller on two uniform (0, 1] draws of the stream).
    fn normal(&mut self) -> f64 {
        let uniform = |x: u64| ((x >> 11) as f64 + 1.0) * (1.0 / (1u64 << 53) as f64);
        let u1 = uniform(self.rng.next_u64());
        let u2 = uniform(self.rng.next_u64());
        (-2.0 * u1.ln()).sqrt() * (std::f64::consts::TAU * u2).cos()
    }

    /// The filter's step at the decision `obs` (module docs, "When"): predicts the estimate to
    /// t_{k−1} with the thrusts applied, reads the sensors of the plant's state there and
    /// updates. Nothing at k = 0. No allocation.
    ///
    /// # Errors
    /// The model's step errors.
    pub fn observe(&mut self, obs: &ModelObservation<'_, 2>) -> Result<()> {
        let Some(truth) = obs.previous_state.filter(|_| obs.k > 0) else {
            return Ok(());
        };
        let target = obs.k - 1;
        if target > self.grid {
            self.stepper
                .resume(&self.estimate, self.grid, self.thrust)?;
            while self.grid < target {
                let (next, _) = self.actuator.step(self.thrust, self.command);
                Stepper::step(
                    &mut self.stepper,
                    &mut self.estimate,
                    self.grid,
                    self.thrust,
                    next,
                )?;
                self.thrust = next;
                self.grid += 1;
            }
        }
        // The readings of the plant at t_{k−1}, then the estimate's.
        minimal(
            Stepper::chain(&self.stepper),
            truth,
            &mut self.phi,
            &mut self.omega,
            &mut self.qdot,
        );
        let mut y = self.sensors.read(&self.phi, truth.tip_target);
        if self.noisy {
            for s in 0..SENSORS {
                y[s] += self.sigma[s] * self.normal();
            }
        }
        self.estimate_to_minimal();
        let predicted = self.sensors.read(&self.phi, self.estimate.tip_target);
        let nu: [f64; SENSORS] = std::array::from_fn(|s| y[s] - predicted[s]);
        let n = self.phi.len();
        for (i, k) in self.gain.iter().enumerate() {
            let dx: f64 = k.iter().zip(&nu).map(|(a, b)| a * b).sum();
            if i < n {
                self.phi[i] += dx;
            } else {
                self.omega[i - n] += dx;
            }
        }
        let chain = Stepper::chain(&self.stepper);
        rebuild(
            chain,
            &self.phi,
            &self.omega,
            &mut self.estimate,
            &mut self.qdot,
        );
        let nis = (0..SENSORS)
            .map(|i| {
                (0..SENSORS)
                    .map(|j| nu[i] * self.innovation_inverse[i][j] * nu[j])
                    .sum::<f64>()
            })
            .sum();
        self.innovation = Some((nu, nis));
        chain.apply_inverse_mass(&self.estimate.p, &mut self.qdot);
        self.moment_rate = chain.base_moment(&self.qdot);
        Ok(())
    }

    /// The command sent at the decision at t_k: the thrusters move toward it from the next
    /// step on (at k = 0 from rest: the thrust at t₀ is the first step toward it).
    pub fn commanded(&mut self, k: usize, command: f64) {
        if k == 0 {
            self.thrust = self.actuator.step(0.0, command).0;
        }
        self.command = command;
    }

    /// What the plan sees at the decision `obs`: the estimate as the state at t_{k−1} (and as
    /// `state`, of which a thrust plan reads only the size), the moments and the tip of the
    /// estimate, the thrusts applied (the thrusters' own readings) and the loop's timing.
    pub fn observation<'a>(&'a self, obs: &ModelObservation<'a, 2>) -> ModelObservation<'a, 2> {
        let chain = Stepper::chain(&self.stepper);
        let started = obs.k > 0;
        let mut seen = obs.observation;
        seen.moment = chain.base_moment(&self.estimate.q);
        seen.moment_rate = if started { self.moment_rate } else { 0.0 };
        seen.tip = chain.tip_z(&self.estimate.q);
        seen.moment_x = 0.0;
        seen.moment_rate_x = 0.0;
        seen.control_x = 0.0;
        let previous = started.then_some(&self.estimate);
        ModelObservation::with_states(seen, &self.estimate, None, previous)
    }
}

/// The chain of a scene with its control node (the top's, where the thrust's vessel holds the
/// riser, unless the scene names one), as the plant builds it.
fn control_chain(scene: &Scene) -> Result<Chain<f64, 2>> {
    super::plant::plant_chain(scene)
}

/// The exact Jacobian A (2n × 2n) of one RATTLE step k → k + 1 with thrust 0 in (φ, ω), at the
/// angles `phi` at rest: one dual-number step per direction.
fn step_jacobian(chain: &Chain<f64, 2>, h: f64, k: usize, phi: &[f64]) -> Result<DMatrix<f64>> {
    let n = phi.len();
    let dual = chain.lift::<Dual64>();
    let mut stepper = Rattle::new(dual.clone(), h)?;
    let mut a = DMatrix::zeros(2 * n, 2 * n);
    let mut state = State::<Dual64, 2>::straight(n);
    let mut qdot = vec![[Dual64::from(0.0); 2]; n];
    let (mut p, mut w) = (vec![Dual64::from(0.0); n], vec![Dual64::from(0.0); n]);
    for dir in 0..2 * n {
        for j in 0..n {
            p[j] = Dual64::new(phi[j], if dir == j { 1.0 } else { 0.0 });
            w[j] = Dual64::new(0.0, if dir == n + j { 1.0 } else { 0.0 });
        }
        state.multipliers = None;
        rebuild(&dual, &p, &w, &mut state, &mut qdot);
        let zero = Dual64::from(0.0);
        stepper.resume(&state, k, zero)?;
        Rattle::step(&mut stepper, &mut state, k, zero, zero)?;
        minimal(&dual, &state, &mut p, &mut w, &mut qdot);
        for j in 0..n {
            a[(j, dir)] = p[j].eps;
            a[(n + j, dir)] = w[j].eps;
        }
    }
    Ok(a)
}

/// A^m by repeated squaring.
fn matrix_power(a: &DMatrix<f64>, mut m: usize) -> DMatrix<f64> {
    let mut result = DMatrix::identity(a.nrows(), a.ncols());
    let mut base = a.clone();
    while m > 0 {
        if m & 1 == 1 {
            result = &result * &base;
        }
        m >>= 1;
        if m > 0 {
            base = &base * &base;
        }
    }
    result
}

/// Q of the continuous white-noise angular acceleration of density s² over T (module docs).
fn process_noise(n: usize, t: f64, s: f64) -> DMatrix<f64> {
    let mut q = DMatrix::zeros(2 * n, 2 * n);
    let s2 = s * s;
    for j in 0..n {
        q[(j, j)] = s2 * t * t * t / 3.0;
        q[(j, n + j)] = s2 * t * t / 2.0;
        q[(n + j, j)] = s2 * t * t / 2.0;
        q[(n + j, n + j)] = s2 * t;
    }
    q
}

fn symmetrise(m: &mut DMatrix<f64>) {
    let t = m.transpose();
    *m += t;
    *m *= 0.5;
}

/// Doubling iterations of [`dare`] before giving up.
const DARE_ITERATIONS: usize = 100;

/// The prior covariance P of the filter's Riccati equation
/// P = Φ P (I + G P)⁻¹ Φᵀ + Q, G = Cᵀ R⁻¹ C (module docs), by the structure-preserving
/// doubling algorithm: with A₀ = Φᵀ, G₀ = G, H₀ = Q,
/// ```text
/// W = I + G_k H_k,  A_{k+1} = A_k W⁻¹ A_k,  G_{k+1} = G_k + A_k W⁻¹ G_k A_kᵀ,
/// H_{k+1} = H_k + A_kᵀ H_k W⁻¹ A_k  →  P.
/// ```
/// The result's residual is checked (relative 10⁻⁶: the round-off of Φ = A^m, whose norm is
/// 10²–10³, leaves about 10⁻⁸).
fn dare(
    phi: &DMatrix<f64>,
    c: &DMatrix<f64>,
    q: &DMatrix<f64>,
    r: &DMatrix<f64>,
) -> Result<DMatrix<f64>> {
    let dim = phi.nrows();
    let r_inv = r
        .clone()
        .try_inverse()
        .ok_or(MpcError::ObserverNotConverged)?;
    let mut a = phi.transpose();
    let mut g = c.transpose() * r_inv * c;
    let mut hm = q.clone();
    let eye = DMatrix::<f64>::identity(dim, dim);
    for _ in 0..DARE_ITERATIONS {
        let w = &eye + &g * &hm;
        let lu = w.lu();
        let wa = lu.solve(&a).ok_or(MpcError::ObserverNotConverged)?;
        let wg = lu.solve(&g).ok_or(MpcError::ObserverNotConverged)?;
        let mut h_next = &hm + a.transpose() * &hm * &wa;
        symmetrise(&mut h_next);
        let mut g_next = &g + &a * &wg * a.transpose();
        symmetrise(&mut g_next);
        a = &a * &wa;
        let change = (&h_next - &hm).norm();
        hm = h_next;
        g = g_next;
        if !change.is_finite() {
            return Err(MpcError::ObserverNotConverged.into());
        }
        if change <= 1e-14 * hm.norm() {
            break;
        }
    }
    // The residual of P = Φ (P − P Cᵀ S⁻¹ C P) Φᵀ + Q.
    let s = c * &hm * c.transpose() + r;
    let s_inv = s.try_inverse().ok_or(MpcError::ObserverNotConverged)?;
    let post = &hm - &hm * c.transpose() * s_inv * c * &hm;
    let residual = (phi * post * phi.transpose() + q - &hm).norm();
    if residual.is_nan() || residual > 1e-6 * hm.norm() {
        return Err(MpcError::ObserverNotConverged.into());
    }
    Ok(hm)
}
