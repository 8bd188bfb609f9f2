//! The baselines a receding-horizon controller is measured against: no control, the best
//! constant force, and a PD law on the measured base moment with tuned gains.

use num_dual::DualSVec64;

use super::{interval_steps, Controller, Force2, Observation, Plant};
use crate::adjoint::{BendingObjective, ControlProblem, HotSpotObjective, PiecewiseControl};
use crate::base::Scalar;
use crate::error::{Error, MpcError, Requirement, Result};
use crate::ocp::{self, OcpOptions, OcpResult};
use crate::optimize::{minimize, OptimOptions, OptimProblem, OptimResult};
use crate::scene::{MomentAbout, Scene, SceneInput, ValidScene};

/// u = 0 at every step.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct NoControl;

impl Controller for NoControl {
    fn name(&self) -> String {
        "none".into()
    }
    fn control(&mut self, _: &Observation<'_>) -> Result<Force2> {
        Ok(Force2::default())
    }
}

/// One force (u_x, u_z) for the whole run (u_x = 0 in a planar scene).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct ConstantForce {
    /// The force (N).
    pub u: Force2,
    /// Whether it was found in the spatial model ([`Controller::spatial`]: the loop then runs
    /// the plant in it).
    pub spatial: bool,
}

impl ConstantForce {
    /// The best constant force on `scene`, in the scene's model (spatial when
    /// [`Scene::spatial_key`] names a key): min_u c_sum + ρ h Σ |u|² =
    /// Σ_k |M₀(t_k)|² + ρ h (N + 1) |u|² subject to |u_x|, |u_z| ≤ `bound`, by the condensed
    /// Gauss-Newton solver on the one-piece problem (θ = u_z in the planar model, (u_x, u_z) in
    /// the spatial one; an offline optimum over the whole run, with the plant's own model and
    /// loads). One piece is one sensitivity direction through the run, about two simulations
    /// per iteration; the Riccati solver, which linearises every step in 2n + 1 directions,
    /// took minutes per 600 s cell of the n = 80 riser (the choice of
    /// [`super::MpcSolver::Auto`] for one piece).
    ///
    /// # Errors
    /// The problem's and the solver's errors.
    pub fn best(scene: &Scene, bound: f64, effort: f64) -> Result<(Self, OcpResult)> {
        if scene.spatial_key().is_some() {
            return ConstantForce::best_spatial(scene, bound, effort);
        }
        let steps = scene.time.steps;
        let map = PiecewiseControl { steps, pieces: 1 };
        let objective = BendingObjective::summed_moment().with_effort(effort);
        let problem = ControlProblem::builder(scene)
            .map(map)
            .objective(objective)
            .build_in::<2>()?;
        let options = OcpOptions::default().with_bound(bound);
        let r = ocp::Condensed::new(&problem, &options)?.solve(&[0.0])?;
        let u = Force2::z(r.theta[0]);
        Ok((ConstantForce { u, spatial: false }, r))
    }

    /// [`ConstantForce::best`] in the spatial model whatever the scene: for a loop whose plant
    /// runs in the spatial model because its controller plans there (a planar plant scene
    /// with a spatial model scene), θ = (u_x, u_z).
    ///
    /// # Errors
    /// The problem's and the solver's errors.
    pub fn best_spatial(scene: &Scene, bound: f64, effort: f64) -> Result<(Self, OcpResult)> {
        let steps = scene.time.steps;
        let map = PiecewiseControl { steps, pieces: 1 };
        let objective = BendingObjective::summed_moment().with_effort(effort);
        let problem = ControlProblem::builder(scene)
            .map(map)
            .objective(objective)
            .two_axis(true)
            .build_in::<3>()?;
        let opts = OcpOptions::default().with_bound(bound);
        let r = ocp::Condensed::new(&problem, &opts)?.solve(&[0.0; 2])?;
        let u = Force2 {
            x: r.theta[0],
            z: r.theta[1],
        };
        Ok((ConstantForce { u, spatial: true }, r))
    }

    /// The best constant thrust of a scene whose control is the thrust on the vessel
    /// ([`crate::scene::Thrust`]): the same problem, min_F Σ_k M₀(t_k)² + ρ h (N + 1) F²,
    /// |F| ≤ `bound`, by [`minimize`] on the adjoint gradient (the structured solvers do not take
    /// the vessel's tip yet: [`crate::error::OcpError::UnsupportedTip`]). The optimum is that of
    /// the thrust held from t = 0; the plant then ramps to it at the rate bound.
    ///
    /// # Errors
    /// The problem's and the optimiser's errors.
    pub fn best_thrust(scene: &Scene, bound: f64, effort: f64) -> Result<(Self, OptimResult)> {
        let steps = scene.time.steps;
        let map = PiecewiseControl { steps, pieces: 1 };
        let objective = BendingObjective::summed_moment().with_effort(effort);
        let problem = ControlProblem::builder(scene)
            .map(map)
            .objective(objective)
            .build_in::<2>()?;
        let options = OptimOptions {
            bounds: Some(crate::optimize::Bounds::symmetric(bound)?),
            first_step: 0.01 * bound,
            trust_radius: 0.1 * bound,
            max_trust_radius: bound,
            ..OptimOptions::default()
        };
        let r = minimize(&problem, &[0.0], &options)?;
        let u = Force2::z(r.theta[0]);
        Ok((ConstantForce { u, spatial: false }, r))
    }
}

impl Controller for ConstantForce {
    fn name(&self) -> String {
        "constant".into()
    }
    fn control(&mut self, _: &Observation<'_>) -> Result<Force2> {
        Ok(self.u)
    }
    fn spatial(&self) -> bool {
        self.spatial
    }
}

/// A PD law on the measured base moment, sampled at the control interval:
/// u_z = clamp(u_{b,z} − K_p M₀_z − K_d Ṁ₀_z, −u_max, u_max), and in the spatial model the same
/// law on the x axis with its own bias and the common gains (the model is the same in every
/// transverse direction): u_x = clamp(u_{b,x} − K_p M₀ₓ − K_d Ṁ₀ₓ); u_x = 0 in a planar plant.
///
/// Why the base moment and not the tip displacement: M₀ is the quantity to keep small, and a
/// wellhead moment is what riser monitoring measures; a law on the tip displacement regulates the
/// platform's position, which the wave moves together with the whole beam, and only indirectly
/// the moment at the seabed. The bias u_b is the feedforward a control engineer adds against a
/// steady load (a current): without it a PD law leaves a steady moment.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct PdLaw {
    /// (u_{b,x}, u_{b,z}) (N; u_{b,x} unused by a planar plant).
    pub bias: Force2,
    /// K_p (N per Nm).
    pub kp: f64,
    /// K_d (N s per Nm).
    pub kd: f64,
    /// u_max (N; infinite: no limit), on each component.
    pub bound: f64,
    /// Whether it was tuned in the spatial model ([`Controller::spatial`]: the loop then runs
    /// the plant in it).
    pub spatial: bool,
}

/// The law at one sample, in any scalar (the clamp passes no derivative on the bound).
pub(crate) fn pd<D: Scalar>(gains: &[D; 3], moment: D, rate: D, bound: f64) -> D {
    let u = gains[0] - gains[1] * moment - gains[2] * rate;
    if u.re() > bound {
        D::from(bound)
    } else if u.re() < -bound {
        D::from(-bound)
    } else {
        u
    }
}

impl PdLaw {
    /// The gains minimising the closed-loop J = Σ |M₀|² + ρ h Σ |u_k|² of `tuning`'s scene
    /// ([`pd_closed_loop_cost`], [`pd_closed_loop_cost_spatial`]) from `start`, by [`minimize`]
    /// with `options`: θ = (u_b, K_p, K_d) in the planar model, (u_{b,x}, u_{b,z}, K_p, K_d) in
    /// the spatial one ([`PdTuning`]).
    ///
    /// # Errors
    /// [`Error::WrongLength`] naming `gains` for a `start` of another length than the model's;
    /// the closed loop's and the optimiser's errors.
    pub fn tune(
        tuning: &PdTuning,
        start: &[f64],
        options: &OptimOptions,
    ) -> Result<(PdLaw, OptimResult)> {
        let expected = tuning.n_params();
        if start.len() != expected {
            return Err(Error::WrongLength {
                name: "gains",
                expected,
                got: start.len(),
            });
        }
        let r = minimize(tuning, start, options)?;
        let (bias, gains) = if tuning.spatial {
            let bias = Force2 {
                x: r.theta[0],
                z: r.theta[1],
            };
            (bias, &r.theta[2..])
        } else {
            (Force2::z(r.theta[0]), &r.theta[1..])
        };
        let law = PdLaw {
            bias,
            kp: gains[0],
            kd: gains[1],
            bound: tuning.bound,
            spatial: tuning.spatial,
        };
        Ok((law, r))
    }

    /// The gains as the tuning's θ: (u_b, K_p, K_d), or (u_{b,x}, u_{b,z}, K_p, K_d) for a
    /// law tuned in the spatial model.
    pub fn gains(&self) -> Vec<f64> {
        if self.spatial {
            vec![self.bias.x, self.bias.z, self.kp, self.kd]
        } else {
            vec![self.bias.z, self.kp, self.kd]
        }
    }
}

impl Controller for PdLaw {
    fn name(&self) -> String {
        "pd".into()
    }
    fn control(&mut self, obs: &Observation<'_>) -> Result<Force2> {
        let (kp, kd, b) = (self.kp, self.kd, self.bound);
        let z = pd(&[self.bias.z, kp, kd], obs.moment, obs.moment_rate, b);
        if !obs.spatial() {
            return Ok(Force2::z(z));
        }
        let x = pd(&[self.bias.x, kp, kd], obs.moment_x, obs.moment_rate_x, b);
        Ok(Force2 { x, z })
    }
    fn spatial(&self) -> bool {
        self.spatial
    }
}

/// The closed-loop cost of a PD law's gains θ = (u_b, K_p, K_d) on a scene, as an
/// [`OptimProblem`]: J(θ) = Σ_{k=0}^{N} [M₀(t_k)² + ρ h u_k²] of the loop of [`super::run_closed_loop`]
/// with [`PdLaw`] (the same plant, sampling and hold), its gradient by forward-mode dual numbers
/// (`DualSVec64<3>`) through the RATTLE steps of the loop; or, on a spatial scene (or built by
/// [`PdTuning::spatial`]), of the gains θ = (u_{b,x}, u_{b,z}, K_p, K_d) of a [`PdLaw`] in the
/// spatial model (J = Σ |M₀|² + ρ h Σ |u|², `DualSVec64<4>`).
#[derive(Clone, Debug)]
pub struct PdTuning {
    /// Validated once here: every cost evaluation builds a plant from it.
    scene: ValidScene,
    interval_steps: usize,
    bound: f64,
    effort: f64,
    spatial: bool,
    /// The hot spot whose moment the law feeds back and the tuning weighs
    /// ([`PdTuning::at_hot_spot`]); `None`: the base moment.
    hotspot: Option<HotSpotObjective>,
}

impl PdTuning {
    /// The tuning problem of a PD law on the moment at a hot spot ([`pd_closed_loop_cost_at`]):
    /// J = Σ_k [M(t_k)² + ρ h u_k²], M the moment `spot` reads (its exponent and effort are not
    /// used); planar only.
    pub fn at_hot_spot(mut self, spot: HotSpotObjective) -> Self {
        self.hotspot = Some(spot);
        self
    }

    /// The tuning problem of `scene` with decisions every `interval` seconds, |u| ≤ `bound`
    /// (infinite: none) and effort weight ρ = `effort`, in the scene's model (the spatial one,
    /// four gains, when [`Scene::spatial_key`] names a key).
    ///
    /// # Errors
    /// [`MpcError::IntervalNotMultiple`]; [`ValueError::OutOfRange`](crate::error::ValueError::OutOfRange) naming `bound` (not positive)
    /// or `effort` (not finite and ≥ 0).
    pub fn new<S: SceneInput + ?Sized>(
        scene: &S,
        interval: f64,
        bound: f64,
        effort: f64,
    ) -> Result<Self> {
        let scene = scene.to_valid()?;
        let m = interval_steps(interval, scene.time.step)?;
        for (name, requirement, value) in [
            ("bound", Requirement::Positive, bound),
            ("effort", Requirement::FiniteNonNegative, effort),
        ] {
            requirement.check(name, value).map_err(MpcError::from)?;
        }
        Ok(PdTuning {
            spatial: scene.spatial_key().is_some(),
            scene,
            interval_steps: m,
            bound,
            effort,
            hotspot: None,
        })
    }

    /// The tuning problem of [`PdTuning::new`] in the spatial model whatever the scene (four
    /// gains, [`pd_closed_loop_cost_spatial`]): for a loop whose plant runs in the spatial model
    /// because its controller plans there.
    ///
    /// # Errors
    /// As [`PdTuning::new`].
    pub fn spatial<S: SceneInput + ?Sized>(
        scene: &S,
        interval: f64,
        bound: f64,
        effort: f64,
    ) -> Result<Self> {
        let mut t = PdTuning::new(scene, interval, bound, effort)?;
        t.spatial = true;
        Ok(t)
    }
}

impl OptimProblem for PdTuning {
    fn n_params(&self) -> usize {
        if self.spatial {
            4
        } else {
            3
        }
    }

    fn value(&self, theta: &[f64]) -> Result<f64> {
        if self.spatial {
            let g = gains::<f64, 4>(theta, |x, _| x)?;
            let (m, b, e) = (self.interval_steps, self.bound, self.effort);
            return pd_closed_loop_cost_spatial(&self.scene, m, &g, b, e);
        }
        let g = gains::<f64, 3>(theta, |x, _| x)?;
        pd_closed_loop_cost_at(
            &self.scene,
            self.interval_steps,
            &g,
            self.bound,
            self.effort,
            self.hotspot.as_ref(),
        )
    }

    fn value_and_gradient(&self, theta: &[f64]) -> Result<(f64, Vec<f64>)> {
        if self.spatial {
            let seed = |x, i| DualSVec64::<4>::from_re(x).derivative(i);
            let g = gains::<DualSVec64<4>, 4>(theta, seed)?;
            let (m, b, e) = (self.interval_steps, self.bound, self.effort);
            let j = pd_closed_loop_cost_spatial(&self.scene, m, &g, b, e)?;
            let grad = match j.eps.0 {
                Some(v) => v.iter().copied().collect(),
                None => vec![0.0; 4],
            };
            return Ok((j.re, grad));
        }
        let g = gains::<DualSVec64<3>, 3>(theta, |x, i| DualSVec64::<3>::from_re(x).derivative(i))?;
        let j = pd_closed_loop_cost_at(
            &self.scene,
            self.interval_steps,
            &g,
            self.bound,
            self.effort,
            self.hotspot.as_ref(),
        )?;
        let grad = match j.eps.0 {
            Some(v) => v.iter().copied().collect(),
            None => vec![0.0; 3],
        };
        Ok((j.re, grad))
    }
}

/// The `N` gains of θ in a scalar type (`seed(x, i)` lifts θᵢ).
fn gains<D: Scalar, const N: usize>(
    theta: &[f64],
    seed: impl Fn(f64, usize) -> D,
) -> Result<[D; N]> {
    if theta.len() != N {
        return Err(Error::WrongLength {
            name: "gains",
            expected: N,
            got: theta.len(),
        });
    }
    if let Some(index) = theta.iter().position(|x| !x.is_finite()) {
        return Err(Error::NotFinite {
            name: "gains",
            index,
        });
    }
    Ok(std::array::from_fn(|i| seed(theta[i], i)))
}

/// J = Σ_{k=0}^{N} [M₀(t_k)² + ρ h u_k²] of the PD loop u_j = clamp(u_b − K_p M₀ − K_d Ṁ₀) sampled
/// every `interval_steps` steps on `scene`'s plant, in any scalar: with dual gains, the exact
/// derivative of the discrete closed loop (the clamp passes none on the bound).
///
/// # Errors
/// The plant's errors (an unstable law folds the beam: [`Error::Folded`], or Newton fails).
pub fn pd_closed_loop_cost<D: Scalar, S: SceneInput + ?Sized>(
    scene: &S,
    interval_steps: usize,
    gains: &[D; 3],
    bound: f64,
    effort: f64,
) -> Result<D> {
    let mut plant = Plant::<D>::new(scene)?;
    let rho_h = effort * plant.h();
    let stage = |p: &Plant<D>| {
        let (m, u) = (p.moment(), p.control());
        m * m + u * u * rho_h
    };
    let mut j = D::zero();
    while plant.step_index() < plant.steps() {
        let rate = plant.moment_rate();
        plant.set_control(pd(gains, plant.moment(), rate, bound))?;
        for _ in 0..interval_steps.min(plant.steps() - plant.step_index()) {
            j += stage(&plant);
            plant.advance()?;
        }
    }
    Ok(j + stage(&plant))
}

/// J = Σ_{k=0}^{N} [M(t_k)² + ρ h u_k²] of the PD loop u_j = clamp(u_b − K_p M − K_d Ṁ) on the
/// moment M at a hot spot (`spot`, [`HotSpotObjective::moment_of_attitudes`]), its rate the
/// difference over the last step Ṁ(t_k) = (M(t_k) − M(t_{k−1}))/h (0 at k = 0), in any scalar;
/// with `spot` = `None` [`pd_closed_loop_cost`] bit for bit.
///
/// With `spot`'s [`HotSpotObjective::about`] [`MomentAbout::Mean`] the law and the cost act on
/// the moment's fluctuation about its running mean M̄ ([`running_mean`], updated at each
/// decision, held between): u_j = clamp(u_b − K_p (M − M̄_j) − K_d Ṁ) and
/// J = Σ_k [(M(t_k) − M̄_j)² + ρ h u_k²], M̄_j the mean of the decision step k follows.
///
/// # Errors
/// As [`pd_closed_loop_cost`].
pub fn pd_closed_loop_cost_at<D: Scalar, S: SceneInput + ?Sized>(
    scene: &S,
    interval_steps: usize,
    gains: &[D; 3],
    bound: f64,
    effort: f64,
    spot: Option<&HotSpotObjective>,
) -> Result<D> {
    let Some(spot) = spot else {
        return pd_closed_loop_cost(scene, interval_steps, gains, bound, effort);
    };
    let mut plant = Plant::<D>::new(scene)?;
    let (h, rho_h) = (plant.h(), effort * plant.h());
    let about_mean = spot.about == MomentAbout::Mean;
    let dt = interval_steps as f64 * h;
    let moment = |p: &Plant<D>| spot.moment_of_attitudes(&p.state().q);
    let stage = |p: &Plant<D>, mean: D| {
        let (m, u) = (moment(p) - mean, p.control());
        m * m + u * u * rho_h
    };
    let (mut j, mut mean) = (D::zero(), None);
    while plant.step_index() < plant.steps() {
        let m = moment(&plant);
        let rate = match plant.previous_state() {
            Some(prev) => (m - spot.moment_of_attitudes(&prev.q)) / h,
            None => D::zero(),
        };
        if about_mean {
            mean = Some(running_mean(mean, m, dt));
        }
        let about = mean.unwrap_or_else(D::zero);
        plant.set_control(pd(gains, m - about, rate, bound))?;
        for _ in 0..interval_steps.min(plant.steps() - plant.step_index()) {
            j += stage(&plant, about);
            plant.advance()?;
        }
    }
    Ok(j + stage(&plant, mean.unwrap_or_else(D::zero)))
}

/// The time constant τ \[s\] of the running mean a PD law about the mean feeds back from
/// ([`running_mean`]): three periods of a drilling riser's first mode (≈ 20 s), longer than the
/// waves' (8–17 s). The filter's gain on the fluctuation, |iωτ/(1 + iωτ)|, is 0.998 at 20 s and
/// 0.95 at a DP loop's 120 s: what the law sees is every cycle S-N damage counts, without the
/// steady moment a constant thrust would have to hold (docs/mpc.md "The moment a controller
/// acts on"). Fixed before any run, not tuned.
pub const PD_MEAN_TIME: f64 = 60.0;

/// The running mean of a moment sampled every `dt` seconds, the exponential mean of time
/// constant [`PD_MEAN_TIME`] by backward Euler:
/// ```text
/// M̄_j = M̄_{j−1} + a (M_j − M̄_{j−1}),   a = Δt / (τ + Δt),   M̄_0 = M_0
/// ```
/// (`previous` = `None` at the first sample), in any scalar. A constant moment is its own mean;
/// a unit step from 0 leaves 1 − (1 − a)^j after j samples:
/// ```
/// use chainbeam::mpc::{running_mean, PD_MEAN_TIME};
/// let dt = 0.5;
/// let a = dt / (PD_MEAN_TIME + dt);
/// let mut mean = running_mean(None, 0.0, dt);
/// for _ in 0..40 {
///     mean = running_mean(Some(mean), 1.0, dt);
/// }
/// assert!((mean - (1.0 - (1.0 - a).powi(40))).abs() < 1e-14);
/// assert_eq!(running_mean(Some(2.5), 2.5, dt), 2.5);
/// ```
pub fn running_mean<D: Scalar>(previous: Option<D>, m: D, dt: f64) -> D {
    match previous {
        None => m,
        Some(mean) => mean + (m - mean) * (dt / (PD_MEAN_TIME + dt)),
    }
}

/// J = Σ_{k=0}^{N} [|M₀(t_k)|² + ρ h |u_k|²] of the spatial PD loop of [`PdLaw`] with the
/// gains (u_{b,x}, u_{b,z}, K_p, K_d) sampled every `interval_steps` steps on `scene`'s spatial
/// plant, in any scalar (as [`pd_closed_loop_cost`]).
///
/// # Errors
/// The plant's errors.
pub fn pd_closed_loop_cost_spatial<D: Scalar, S: SceneInput + ?Sized>(
    scene: &S,
    interval_steps: usize,
    gains: &[D; 4],
    bound: f64,
    effort: f64,
) -> Result<D> {
    let mut plant = Plant::<D, 3>::new(scene)?;
    let rho_h = effort * plant.h();
    let stage = |p: &Plant<D, 3>| {
        let ([mx, mz], (ux, uz)) = (p.moment_vector(), (p.control_x(), p.control()));
        mx * mx + mz * mz + (ux * ux + uz * uz) * rho_h
    };
    let [bx, bz, kp, kd] = *gains;
    let mut j = D::zero();
    while plant.step_index() < plant.steps() {
        let ([rx, rz], [mx, mz]) = (plant.moment_vector_rate(), plant.moment_vector());
        let u = [
            pd(&[bx, kp, kd], mx, rx, bound),
            pd(&[bz, kp, kd], mz, rz, bound),
        ];
        plant.set_controls(u)?;
        for _ in 0..interval_steps.min(plant.steps() - plant.step_index()) {
            j += stage(&plant);
            plant.advance()?;
        }
    }
    Ok(j + stage(&plant))
}
