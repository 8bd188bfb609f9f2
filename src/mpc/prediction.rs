//! How well a plan predicts the plant: the planning model's bending moment over one horizon
//! against the plant's, from the plant's own states, under the same controls and the same sea
//! (a perfect forecast), for the total moment and for the response to the control.
//!
//! # The measurement ([`predict`])
//! The plant (the scene as given: n pendulums at step h) runs from the straight riser at rest
//! twice to t_end = max t₀ + T: once unforced (u = 0) and once under a forcing u(t) ([`Forcing`]:
//! pieces of a seeded uniform draw in [−A, A], each held for a control interval, clipped to the
//! vessel's thrust bound and moved at most at its rate bound in a thrust scene, as
//! [`crate::mpc::Plant`] applies a thrust). At each start time t₀ the plant's state of each
//! run is mapped onto the plan ([`StateMap`]) and the plan (n_p pendulums at step h_p, a whole
//! multiple of h: [`planning_scene`], or the plant's scene itself) is rolled out over the
//! horizon T with the same controls, sampled on its grid (u_p,K = u(t₀ + K h_p)), and the same
//! sea. On the plan's grid t_K = t₀ + K h_p, K = 0..=T/h_p, with M the moment at the chosen
//! elevation, blended linearly in elevation between the two joints around it as a hot spot's is
//! ([`crate::hotspots::interpolation_joints`]; a joint's own moment when one sits there, joint 1
//! at elevation 0: the wellhead moment M_w = k₁θ₁ of the base spring;
//! [`crate::hotspots::joint_moment`]),
//! ```text
//! e_total    = rms_K(M_plan,f − M_plant,f) / rms_K(M_plant,f)
//! e_response = rms_K(ΔM_plan − ΔM_plant) / rms_K(ΔM_plant),   ΔM = M_f − M_u,
//! e_unforced = rms_K(M_plan,u − M_plant,u) / rms_K(M_plant,u)
//! ```
//! per start, and over all starts with the sums of squares pooled (the overall figure is
//! √(Σ_starts Σ_K err²) / √(Σ_starts Σ_K ref²)). The response to the control, ΔM, is what a
//! controller acts through: a plan that gets the total moment right but the response wrong
//! chooses wrong forces.
//!
//! With n_p = n and h_p = h the map is the identity up to round-off and the plan's rollout
//! repeats the plant's steps: every error is at round-off level (tests/mpc/plan_prediction.rs).
//!
//! # The cost
//! [`PredictionReport::plant_seconds`] and [`PredictionReport::plan_seconds`] are the wall
//! times of one horizon of each (the plant's from its whole run, per step, times T/h; the
//! plan's the mean of its rollouts): what one rollout of a planner costs on either model.
//!
//! The library prints nothing; `examples/plan_prediction.rs` prints the table.

use std::time::Instant;

use rand_chacha::rand_core::{RngCore, SeedableRng};
use rand_chacha::ChaCha20Rng;

use super::planning::{planning_scene, StateMap};
use crate::hotspots::{interpolation_joints, joint_elevations, joint_moment, JointInterpolation};
use crate::model::Chain;
use crate::scene::Scene;
use crate::steppers::rattle::{Rattle, State};
use crate::steppers::Stepper;

/// The most plant steps one measurement runs (each run keeps one moment per plan step and the
/// states at the start times; this bounds the time it may take).
pub const MAX_PREDICTION_STEPS: usize = 10_000_000;

/// The plan whose prediction is measured.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum PlanModel {
    /// The plant's scene itself (n_p = n, h_p = h).
    Plant,
    /// The reduced planning model of [`planning_scene`] with these pendulums and step \[s\].
    Reduced {
        /// n_p.
        pendulums: usize,
        /// h_p \[s\], a whole multiple of the plant's step.
        step: f64,
    },
}

/// The forcing under which the response to the control is measured: pieces u_j drawn uniformly
/// in [−`amplitude`, `amplitude`] from the ChaCha20 stream of `seed` (u_j = A(2 r_j/2⁶⁴ − 1),
/// r_j the stream's 64-bit words in order), u(t) = u_j for j·`interval` ≤ t < (j+1)·`interval`,
/// then, in a thrust scene, clipped to ±F_max and moved per step by at most Ḟ_max h.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Forcing {
    /// The pieces' length \[s\] (MPC's control interval).
    pub interval: f64,
    /// A \[N\] (the scene's control bound).
    pub amplitude: f64,
    /// The seed of the draw.
    pub seed: u64,
    /// A rate bound \[N/s\] of the forcing's own (each step moves u by at most it times h), or
    /// `None`: pieces with jumps (a thrust scene's rate bound applies in either case).
    pub rate: Option<f64>,
}

/// What to measure ([`predict`]).
#[derive(Clone, Debug, PartialEq)]
pub struct PredictionSetup {
    /// The plan.
    pub plan: PlanModel,
    /// The horizon T \[s\], a whole number of plan steps.
    pub horizon: f64,
    /// The start times t₀ \[s\], each on the plan's grid.
    pub starts: Vec<f64>,
    /// The forcing of the forced runs.
    pub forcing: Forcing,
    /// The elevation \[m\] above the chain's base of the moment compared (blended between the
    /// two joints around it in each chain; 0: the wellhead moment of the base spring).
    pub elevation: f64,
}

/// The errors from one start time (module docs).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct StartError {
    /// t₀ \[s\].
    pub time: f64,
    /// e_total, forced runs.
    pub total: f64,
    /// e_response.
    pub response: f64,
    /// e_unforced.
    pub unforced: f64,
    /// rms of the plant's forced moment over the horizon \[N·m\].
    pub plant_rms: f64,
    /// rms of the plant's response ΔM over the horizon \[N·m\].
    pub plant_response_rms: f64,
}

/// The result of [`predict`].
#[derive(Clone, Debug, PartialEq)]
pub struct PredictionReport {
    /// The plant's n and h \[s\].
    pub plant_pendulums: usize,
    /// h.
    pub plant_step: f64,
    /// The plan's n_p.
    pub plan_pendulums: usize,
    /// h_p \[s\].
    pub plan_step: f64,
    /// The elevations \[m\] of the moments compared, plant and plan (the blend's: the chosen
    /// elevation within the chain, else its end joint).
    pub joint_elevations: [f64; 2],
    /// Per start.
    pub starts: Vec<StartError>,
    /// e_total over all starts (pooled).
    pub total: f64,
    /// e_response over all starts (pooled).
    pub response: f64,
    /// e_unforced over all starts (pooled).
    pub unforced: f64,
    /// rms and peak |u| of the forcing applied \[N\].
    pub forcing_rms: f64,
    /// Peak |u| \[N\].
    pub forcing_peak: f64,
    /// Wall time of one horizon of the plant \[s\].
    pub plant_seconds: f64,
    /// Wall time of one horizon of the plan \[s\].
    pub plan_seconds: f64,
}

/// A measurement that cannot be made.
#[derive(Debug, thiserror::Error)]
pub enum PredictionError {
    /// A number of the setup out of its range.
    #[error("`{name}` must be {requirement}, got {value}")]
    Value {
        /// `horizon`, `starts`, `interval`, `amplitude`, `rate` or `elevation`.
        name: &'static str,
        /// The value given.
        value: f64,
        /// What it must be.
        requirement: &'static str,
    },
    /// No start time.
    #[error("`starts` must hold at least one start time")]
    NoStarts,
    /// The plan's step is not a whole multiple of the plant's.
    #[error(
        "the plan's step {plan_step} s must be a whole multiple of the plant's {plant_step} s"
    )]
    StepRatio {
        /// h_p.
        plan_step: f64,
        /// h.
        plant_step: f64,
    },
    /// A start time or the horizon is not on the plan's grid.
    #[error("`{name}` = {value} s is not a whole number of the plan's steps of {step} s")]
    OffGrid {
        /// `starts` or `horizon`.
        name: &'static str,
        /// The value.
        value: f64,
        /// h_p.
        step: f64,
    },
    /// The runs would take more than [`MAX_PREDICTION_STEPS`] plant steps.
    #[error("the runs need {steps} plant steps, more than the limit {limit}")]
    TooLong {
        /// Steps needed.
        steps: f64,
        /// The limit.
        limit: usize,
    },
    /// The plant's moment vanishes over a horizon, so no relative error exists.
    #[error("the plant's {what} is zero over the horizon from t = {time} s: no relative error")]
    ZeroReference {
        /// `moment`, `response` or `unforced moment`.
        what: &'static str,
        /// t₀.
        time: f64,
    },
    /// The scene, the planning model or a step failed.
    #[error(transparent)]
    Model(#[from] crate::error::Error),
}

/// One run of the plant: its moment at every step and its states at the start steps.
#[derive(Clone, Debug)]
struct Run {
    /// M(t_k), k = 0..=N.
    moment: Vec<f64>,
    states: Vec<State<f64, 2>>,
    seconds: f64,
}

/// The plant's two runs of a measurement (forced and unforced), which every plan measured
/// against them shares ([`PlantRuns::new`], [`PlantRuns::predict`]).
#[derive(Clone, Debug)]
pub struct PlantRuns {
    /// The plant's scene, its `time.steps` set to the runs' N.
    scene: Scene,
    setup: PredictionSetup,
    /// The forcing u_k, k = 0..=N.
    forced: Vec<f64>,
    /// The start steps k₀ on the plant's grid.
    start_steps: Vec<usize>,
    /// The horizon in plant steps.
    horizon_steps: usize,
    plant_joint: JointInterpolation,
    runs: [Run; 2],
}

/// Measures how well the plan of `setup` predicts the plant `scene` (module docs):
/// [`PlantRuns::new`] then [`PlantRuns::predict`]. Planar scenes.
///
/// # Errors
/// As [`PlantRuns::new`] and [`PlantRuns::predict`].
pub fn predict(
    scene: &Scene,
    setup: &PredictionSetup,
) -> Result<PredictionReport, PredictionError> {
    PlantRuns::new(scene, setup)?.predict(setup.plan)
}

/// Checks a setup value: finite and `ok`.
fn check(
    name: &'static str,
    value: f64,
    ok: bool,
    requirement: &'static str,
) -> Result<(), PredictionError> {
    if ok && value.is_finite() {
        Ok(())
    } else {
        Err(PredictionError::Value {
            name,
            value,
            requirement,
        })
    }
}

/// `t` as a whole number of steps `step` (round-off forgiven), or [`PredictionError::OffGrid`].
fn on_grid(name: &'static str, t: f64, step: f64) -> Result<usize, PredictionError> {
    let k = (t / step).round();
    if (k * step - t).abs() > 1e-9 * step.max(t) {
        Err(PredictionError::OffGrid {
            name,
            value: t,
            step,
        })
    } else {
        Ok(k as usize)
    }
}

/// The setup's values: a positive horizon, forcing interval, amplitude and rate, a non-negative
/// elevation, at least one start and each non-negative; all finite.
fn check_setup(setup: &PredictionSetup) -> Result<(), PredictionError> {
    check(
        "horizon",
        setup.horizon,
        setup.horizon > 0.0,
        "positive and finite [s]",
    )?;
    let f = setup.forcing;
    check(
        "interval",
        f.interval,
        f.interval > 0.0,
        "positive and finite [s]",
    )?;
    check(
        "amplitude",
        f.amplitude,
        f.amplitude > 0.0,
        "positive and finite [N]",
    )?;
    if let Some(rate) = f.rate {
        check("rate", rate, rate > 0.0, "positive and finite [N/s]")?;
    }
    check(
        "elevation",
        setup.elevation,
        setup.elevation >= 0.0,
        "non-negative and finite [m]",
    )?;
    if setup.starts.is_empty() {
        return Err(PredictionError::NoStarts);
    }
    for &t in &setup.starts {
        check("starts", t, t >= 0.0, "non-negative and finite [s]")?;
    }
    Ok(())
}

/// [error², reference²] of the total moment, the forced response and the unforced moment over
/// one horizon: the plan's forced and unforced moments `plan` = [M_f, M_u] at its steps i
/// against the plant's `plant` at its steps k = `start` + i r (r plant steps per plan step):
/// Σ (M_f − P_f)², Σ P_f², Σ ((M_f − M_u) − (P_f − P_u))², Σ (P_f − P_u)², Σ (M_u − P_u)², Σ P_u².
fn squared_errors(plan: [&[f64]; 2], plant: [&[f64]; 2], start: usize, r: usize) -> [f64; 6] {
    let [mf, mu] = plan;
    let [run_f, run_u] = plant;
    let mut e = [0.0; 6];
    for i in 0..mf.len() {
        let k = start + i * r;
        let (pf, pu) = (run_f[k], run_u[k]);
        e[0] += (mf[i] - pf).powi(2);
        e[1] += pf * pf;
        e[2] += ((mf[i] - mu[i]) - (pf - pu)).powi(2);
        e[3] += (pf - pu).powi(2);
        e[4] += (mu[i] - pu).powi(2);
        e[5] += pu * pu;
    }
    e
}

impl PlantRuns {
    /// Runs the plant `scene` forced and unforced to max t₀ + T (module docs); `setup.plan` is
    /// not used here.
    ///
    /// # Errors
    /// [`PredictionError`]: a setup value out of range, a start or horizon off the plant's
    /// grid, runs beyond [`MAX_PREDICTION_STEPS`]; the chain's and the steps' errors (a spatial
    /// scene: the planar chain's refusal).
    pub fn new(scene: &Scene, setup: &PredictionSetup) -> Result<Self, PredictionError> {
        check_setup(setup)?;
        let h = scene.time.step;
        let horizon_steps = on_grid("horizon", setup.horizon, h)?;
        if horizon_steps == 0 {
            return Err(PredictionError::OffGrid {
                name: "horizon",
                value: setup.horizon,
                step: h,
            });
        }
        let start_steps = setup
            .starts
            .iter()
            .map(|&t| on_grid("starts", t, h))
            .collect::<Result<Vec<_>, _>>()?;
        let needed = start_steps.iter().max().copied().unwrap_or(0) as f64 + horizon_steps as f64;
        if needed > MAX_PREDICTION_STEPS as f64 {
            return Err(PredictionError::TooLong {
                steps: needed,
                limit: MAX_PREDICTION_STEPS,
            });
        }
        let n_steps = needed as usize;
        let mut plant = scene.clone();
        plant.time.steps = n_steps;
        let forced = forcing(scene, &setup.forcing, n_steps);
        let zero = vec![0.0; n_steps + 1];
        let plant_joint = interpolation_joints(&plant.beam.lengths, setup.elevation);
        let runs = [
            run(&plant, &forced, plant_joint, &start_steps)?,
            run(&plant, &zero, plant_joint, &start_steps)?,
        ];
        Ok(PlantRuns {
            scene: plant,
            setup: setup.clone(),
            forced,
            start_steps,
            horizon_steps,
            plant_joint,
            runs,
        })
    }

    /// Measures the plan `plan` against these runs (module docs).
    ///
    /// # Errors
    /// [`PredictionError`]: a plan step that is not a whole multiple of the plant's, a start or
    /// the horizon off the plan's grid, a plant moment that vanishes over a horizon; the
    /// planning model's, the map's and the steps' errors.
    pub fn predict(&self, plan: PlanModel) -> Result<PredictionReport, PredictionError> {
        let scene = &self.scene;
        let setup = &self.setup;
        let h = scene.time.step;
        let mut plan = match plan {
            PlanModel::Plant => scene.clone(),
            PlanModel::Reduced { pendulums, step } => planning_scene(scene, pendulums, step)?,
        };
        let hp = plan.time.step;
        let ratio = (hp / h).round();
        if ratio < 1.0 || (ratio * h - hp).abs() > 1e-9 * hp {
            return Err(PredictionError::StepRatio {
                plan_step: hp,
                plant_step: h,
            });
        }
        let r = ratio as usize;
        let kh = on_grid("horizon", setup.horizon, hp)?;
        let k0s = setup
            .starts
            .iter()
            .map(|&t| on_grid("starts", t, hp))
            .collect::<Result<Vec<_>, _>>()?;
        let k_end = k0s.iter().max().copied().unwrap_or(0) + kh;
        plan.time.steps = k_end;
        let plan_joint = interpolation_joints(&plan.beam.lengths, setup.elevation);
        let elevations = [
            blended_elevation(&scene.beam.lengths, self.plant_joint),
            blended_elevation(&plan.beam.lengths, plan_joint),
        ];
        let [run_f, run_u] = &self.runs;
        let n_steps = scene.time.steps;
        let plant_seconds = 0.5 * (run_f.seconds + run_u.seconds) / n_steps.max(1) as f64
            * self.horizon_steps as f64;

        let plan_u_forced: Vec<f64> = (0..=k_end).map(|k| self.forced[k * r]).collect();
        let plan_u_zero = vec![0.0; k_end + 1];
        let mut map = StateMap::<2>::new(scene, &plan)?;
        let mut roller = Roller::new(&plan, plan_joint, kh)?;
        let mut starts = Vec::with_capacity(k0s.len());
        let mut sums = [0.0; 6];
        let mut plan_seconds = 0.0;
        let mut mf = vec![0.0; kh + 1];
        let mut mu = vec![0.0; kh + 1];
        for (s, &k0) in k0s.iter().enumerate() {
            let clock = Instant::now();
            roller.roll(&mut map, &run_f.states[s], k0, &plan_u_forced, &mut mf)?;
            plan_seconds += clock.elapsed().as_secs_f64();
            roller.roll(&mut map, &run_u.states[s], k0, &plan_u_zero, &mut mu)?;
            let plant = [&run_f.moment[..], &run_u.moment[..]];
            let e = squared_errors([&mf, &mu], plant, self.start_steps[s], r);
            let time = setup.starts[s];
            let ratio = |err: f64, reference: f64, what| {
                if reference > 0.0 {
                    Ok((err / reference).sqrt())
                } else {
                    Err(PredictionError::ZeroReference { what, time })
                }
            };
            let samples = (kh + 1) as f64;
            starts.push(StartError {
                time,
                total: ratio(e[0], e[1], "moment")?,
                response: ratio(e[2], e[3], "response")?,
                unforced: ratio(e[4], e[5], "unforced moment")?,
                plant_rms: (e[1] / samples).sqrt(),
                plant_response_rms: (e[3] / samples).sqrt(),
            });
            for (a, b) in sums.iter_mut().zip(e) {
                *a += b;
            }
        }
        let forced = &self.forced;
        let peak = forced.iter().fold(0.0f64, |a, u| a.max(u.abs()));
        let rms = (forced.iter().map(|u| u * u).sum::<f64>() / forced.len() as f64).sqrt();
        Ok(PredictionReport {
            plant_pendulums: scene.n(),
            plant_step: h,
            plan_pendulums: plan.n(),
            plan_step: hp,
            joint_elevations: elevations,
            starts,
            total: (sums[0] / sums[1]).sqrt(),
            response: (sums[2] / sums[3]).sqrt(),
            unforced: (sums[4] / sums[5]).sqrt(),
            forcing_rms: rms,
            forcing_peak: peak,
            plant_seconds,
            plan_seconds: plan_seconds / k0s.len() as f64,
        })
    }
}

/// The forcing on the plant's grid, u_k = u(k h), k = 0..=N ([`Forcing`]).
fn forcing(scene: &Scene, f: &Forcing, n_steps: usize) -> Vec<f64> {
    let h = scene.time.step;
    let mut rng = ChaCha20Rng::seed_from_u64(f.seed);
    let pieces = ((n_steps as f64 * h) / f.interval).floor() as usize + 1;
    let draws: Vec<f64> = (0..pieces)
        .map(|_| f.amplitude * (2.0 * (rng.next_u64() as f64 / 2f64.powi(64)) - 1.0))
        .collect();
    let thrust = scene.thrust().map(|t| (t.bound, t.rate_bound * h));
    let own = f.rate.map(|r| (f64::INFINITY, r * h));
    let limits = match (thrust, own) {
        (Some((b, c)), Some((_, d))) => Some((b, c.min(d))),
        (t, o) => t.or(o),
    };
    let mut u = Vec::with_capacity(n_steps + 1);
    let mut prev = 0.0;
    for k in 0..=n_steps {
        // Forgiving the round-off of k h / T at a piece's start.
        let j = ((k as f64 * h / f.interval) * (1.0 + 1e-12)).floor() as usize;
        let mut v = draws[j.min(pieces - 1)];
        if let Some((bound, change)) = limits {
            v = v.clamp(-bound, bound);
            v = v.clamp(prev - change, prev + change);
        }
        u.push(v);
        prev = v;
    }
    u
}

/// The elevation \[m\] of the blend `w` on a chain of pendulum lengths `lengths`.
fn blended_elevation(lengths: &[f64], w: JointInterpolation) -> f64 {
    let s = joint_elevations(lengths);
    w.blend(s[w.lower], s[w.upper])
}

/// The moment at the blend `w` of two joints of `chain` at the attitudes `q`,
/// (1 − w) M_lower + w M_upper.
fn moment(chain: &Chain<f64, 2>, q: &[[f64; 2]], w: JointInterpolation) -> f64 {
    w.blend(
        joint_torque(chain, q, w.lower),
        joint_torque(chain, q, w.upper),
    )
}

/// The moment of joint `joint` (0-based) of `chain` at the attitudes `q`.
fn joint_torque(chain: &Chain<f64, 2>, q: &[[f64; 2]], joint: usize) -> f64 {
    let n = q.len();
    let e2 = [1.0, 0.0];
    let k = if chain.has_spring(joint) {
        chain.springs()[joint]
    } else {
        0.0
    };
    let a = if joint == 0 { &e2 } else { &q[joint - 1] };
    let b = if joint == n { &e2 } else { &q[joint] };
    joint_moment(a, b, k)[1]
}

/// The stepper of a scene with its control at the scene's node (the top by default; the thrust
/// in a thrust scene).
fn stepper(scene: &Scene) -> Result<Rattle<f64, 2>, PredictionError> {
    let chain = super::plant::plant_chain::<2>(scene)?;
    Ok(Rattle::new(chain, scene.time.step)?)
}

/// The plant's run under the per-step controls `u`: its moment at every step and its states at
/// `starts` (plant steps).
fn run(
    scene: &Scene,
    u: &[f64],
    joint: JointInterpolation,
    starts: &[usize],
) -> Result<Run, PredictionError> {
    let mut stepper = stepper(scene)?;
    let n_steps = scene.time.steps;
    let mut moments = Vec::with_capacity(n_steps + 1);
    let mut states = vec![State::straight(scene.n()); starts.len()];
    let clock = Instant::now();
    let mut state = stepper.initial_state(u[0])?;
    for k in 0..=n_steps {
        if k > 0 {
            stepper.step(&mut state, k - 1, u[k - 1], u[k])?;
        }
        moments.push(moment(stepper.chain(), &state.q, joint));
        for (s, &ks) in starts.iter().enumerate() {
            if ks == k {
                states[s].clone_from(&state);
            }
        }
    }
    Ok(Run {
        moment: moments,
        states,
        seconds: clock.elapsed().as_secs_f64(),
    })
}

/// The plan's rollouts from mapped states, with their scratch memory.
struct Roller {
    stepper: Rattle<f64, 2>,
    state: State<f64, 2>,
    joint: JointInterpolation,
    steps: usize,
}

impl Roller {
    fn new(plan: &Scene, joint: JointInterpolation, steps: usize) -> Result<Self, PredictionError> {
        Ok(Roller {
            stepper: stepper(plan)?,
            state: State::straight(plan.n()),
            joint,
            steps,
        })
    }

    /// Maps `plant` onto the plan, rolls it from plan step `k0` over the horizon with the
    /// per-plan-step controls `u`, and writes the moments at K = 0..=T/h_p into `out`.
    fn roll(
        &mut self,
        map: &mut StateMap<2>,
        plant: &State<f64, 2>,
        k0: usize,
        u: &[f64],
        out: &mut [f64],
    ) -> Result<(), PredictionError> {
        map.map(plant, &mut self.state)?;
        self.stepper.resume(&self.state, k0, u[k0])?;
        out[0] = moment(self.stepper.chain(), &self.state.q, self.joint);
        for i in 0..self.steps {
            let k = k0 + i;
            self.stepper.step(&mut self.state, k, u[k], u[k + 1])?;
            out[i + 1] = moment(self.stepper.chain(), &self.state.q, self.joint);
        }
        Ok(())
    }
}
