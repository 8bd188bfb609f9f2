//! `optimize` and `mpc`: the library calls of the command line's `optimize` and `mpc`
//! (src/bin/chainbeam/cmd_optimize.rs, cmd_mpc.rs) with the same defaults.

use numpy::{PyArray1, PyReadonlyArray1};
use pyo3::prelude::*;
use pyo3::types::PyDict;

use chainbeam::mpc::{
    run_closed_loop, ClosedLoopResult, ConstantForce, Controller, Force2, Horizon, Mpc, MpcOptions,
    MpcSolver, NoControl, Observation, PdLaw, PdTuning, Summary,
};
use chainbeam::multistart::{multistart, StartDesign};
use chainbeam::ocp::OcpOptions;
use chainbeam::optimize::{minimize, Bounds, Method, OptimOptions, OptimProblem, OptimResult};
use chainbeam::scene::MpcTable;

use crate::calls::{build_problem, Controls};
use crate::errors::{check, Failure};
use crate::run::{watched, with_pool, Ticker};

use std::sync::Arc;

use crate::scene::Scene;
use chainbeam::optimize::argmin::core::{Error as ArgminError, KV};
use chainbeam::optimize::{Minimizer, Observe, ObservedState, ObserverMode};

/// The settings of `optimize` (the command line's flags of the same names).
struct OptimizeArgs {
    method: Method,
    bound: Option<f64>,
    bounds: Option<Bounds>,
    starts: usize,
    seed: u64,
    max_iters: Option<usize>,
    gtol: Option<f64>,
    effort: f64,
}

/// `method=` by the command line's names.
fn method(name: &str) -> Result<Method, Failure> {
    Ok(match name {
        "auto" => Method::Auto,
        "lbfgs" => Method::Lbfgs,
        "trust-region" => Method::TrustRegion,
        "riccati" => Method::Riccati,
        "condensed" => Method::Condensed,
        other => {
            return Err(Failure::argument(
                "method",
                format!(
                    "unknown method {other:?}; expected \"auto\", \"lbfgs\", \"trust-region\", \
                     \"riccati\" or \"condensed\""
                ),
            ))
        }
    })
}

/// The solver's options (the command line's `SolverArgs::options`).
fn options(a: &OptimizeArgs) -> Result<OptimOptions, Failure> {
    if let Some(g) = a.gtol {
        if !(g.is_finite() && g >= 0.0) {
            return Err(Failure::argument(
                "gtol",
                format!("must be finite and non-negative, got {g}"),
            ));
        }
    }
    if let Some(b) = a.bound {
        if !(b.is_finite() && b > 0.0) {
            return Err(Failure::argument(
                "bound",
                format!("must be positive and finite, got {b}"),
            ));
        }
    }
    if a.max_iters == Some(0) {
        return Err(Failure::argument("max_iters", "must be at least 1"));
    }
    if a.starts == 0 {
        return Err(Failure::argument("starts", "must be at least 1"));
    }
    let defaults = OptimOptions::default();
    Ok(OptimOptions {
        method: a.method,
        max_iters: a.max_iters.unwrap_or(defaults.max_iters),
        grad_tol: a.gtol.unwrap_or(defaults.grad_tol),
        bound: a.bound,
        bounds: a.bounds,
        ..defaults
    })
}

/// An optimiser's observer that counts its iterations on the call's [`Ticker`] (the progress
/// of `optimize(..., progress=...)`) and stops it when the call is cancelled (Ctrl-C): the
/// iteration returns an error, which nobody receives.
struct Watch(Arc<Ticker>);

impl Observe<ObservedState> for Watch {
    fn observe_iter(&mut self, _state: &ObservedState, _kv: &KV) -> Result<(), ArgminError> {
        self.0.tick();
        if chainbeam::cancel::is_cancelled() {
            return Err(ArgminError::msg("the computation was cancelled"));
        }
        Ok(())
    }
}

/// The best result, the minima found and the failed starts (the command line's `run_optimize`).
/// Progress: the iterations of a single start (out of `max_iters`), else the starts done.
fn run_optimize(
    scene: &chainbeam::Scene,
    controls: Option<&Controls>,
    a: &OptimizeArgs,
    ticker: &Arc<Ticker>,
) -> Result<(OptimResult, f64, usize, usize, bool), Failure> {
    let opts = options(a)?;
    let (problem, theta0) = build_problem(scene, controls, a.effort)?;
    if let Some(b) = opts.force_bounds()? {
        if let Some(i) = theta0.iter().position(|&t| !b.contains(t)) {
            return Err(Failure::argument(
                "bound",
                format!(
                    "the start value {} of θ[{i}] lies outside the force limit [{}, {}]",
                    theta0[i],
                    b.lower(),
                    b.upper()
                ),
            ));
        }
    }
    problem.check_range(&theta0)?;
    let initial = problem.value(&theta0)?;
    let two_axis = problem.is_two_axis();
    if a.starts == 1 {
        ticker.set_total(opts.max_iters as u64);
        // `Minimizer::run` is what `minimize` runs, with the observer added.
        let r = Minimizer::new(&problem, opts.clone())
            .add_observer(Watch(ticker.clone()), ObserverMode::Always)
            .run(&theta0)?;
        return Ok((r, initial, 1, 0, two_axis));
    }
    ticker.set_total(a.starts as u64);
    // The scene's own start, then K − 1 points of the command line's default design.
    let design = StartDesign::LatinHypercube {
        lo: -600.0,
        hi: 600.0,
    };
    let own = minimize(&problem, &theta0, &opts);
    ticker.tick();
    chainbeam::cancel::check()?;
    let report = multistart(&problem, &design, a.starts - 1, a.seed, 0, &opts)?;
    for _ in 1..a.starts {
        ticker.tick();
    }
    let mut failed = report.failures.len();
    let mut candidates: Vec<&OptimResult> = report.results.iter().collect();
    let own = match own {
        Ok(r) => Some(r),
        Err(e) if report.results.is_empty() => return Err(e.into()),
        Err(_) => {
            failed += 1;
            None
        }
    };
    candidates.extend(own.as_ref());
    let best = candidates
        .into_iter()
        .filter(|r| r.objective.is_finite())
        .min_by(|x, y| x.objective.total_cmp(&y.objective))
        .cloned();
    match best {
        Some(b) => Ok((b, initial, report.minima.len(), failed, two_axis)),
        None => Err(match report.failures.into_iter().next() {
            Some(f) => f.error.into(),
            None => Failure::Internal("every start failed".into()),
        }),
    }
}

/// Minimises the scene's objective over its controls; see `chainbeam.optimize`.
#[pyfunction]
#[pyo3(signature = (scene, method="auto", bound=None, lower=None, upper=None, starts=1, seed=0,
                    max_iters=None, gtol=None, effort=0.0, controls=None, controls_x=None,
                    progress=None))]
#[allow(clippy::too_many_arguments)] // Python keyword arguments, collected at once below
pub fn optimize<'py>(
    py: Python<'py>,
    scene: &Scene,
    method: &str,
    bound: Option<f64>,
    lower: Option<f64>,
    upper: Option<f64>,
    starts: usize,
    seed: u64,
    max_iters: Option<usize>,
    gtol: Option<f64>,
    effort: f64,
    controls: Option<PyReadonlyArray1<'py, f64>>,
    controls_x: Option<PyReadonlyArray1<'py, f64>>,
    progress: Option<Bound<'py, PyAny>>,
) -> PyResult<Bound<'py, PyDict>> {
    let bounds = match (bound, lower, upper) {
        (Some(_), Some(_), _) | (Some(_), _, Some(_)) => Err(Failure::argument(
            "bound",
            "give either bound (a symmetric limit) or lower and upper (a box), not both",
        )),
        (None, Some(l), Some(u)) => Bounds::new(l, u).map(Some).map_err(|_| {
            Failure::argument(
                "lower",
                format!("lower/upper: need finite L < U, got L = {l}, U = {u}"),
            )
        }),
        (None, Some(_), None) | (None, None, Some(_)) => Err(Failure::argument(
            "lower",
            "one-sided force limits are not supported: give both lower and upper",
        )),
        (_, None, None) => Ok(None),
    };
    let args = OptimizeArgs {
        method: check(py, method_of(method))?,
        bound,
        bounds: check(py, bounds)?,
        starts,
        seed,
        max_iters,
        gtol,
        effort,
    };
    let controls = Controls::from_arrays(controls, controls_x)?;
    let s = scene.inner.clone();
    let progress = progress.as_ref().filter(|p| !p.is_none());
    let out = watched(py, progress, move |ticker| {
        with_pool(|| run_optimize(&s, controls.as_ref(), &args, ticker))
            .map_err(Failure::Internal)?
    })?;
    let (r, initial, minima, failed, two_axis) = check(py, out)?;
    let d = PyDict::new(py);
    d.set_item("objective", r.objective)?;
    d.set_item("theta", PyArray1::from_vec(py, r.theta))?;
    d.set_item("forces", PyArray1::from_vec(py, r.controls))?;
    d.set_item("two_axis", two_axis)?;
    d.set_item("converged", r.converged)?;
    d.set_item("termination", r.termination.to_string())?;
    d.set_item("iterations", r.iterations)?;
    d.set_item("gradient_norm", r.gradient_norm)?;
    d.set_item("projected_gradient_norm", r.projected_gradient_norm)?;
    d.set_item("initial_gradient_norm", r.initial_gradient_norm)?;
    d.set_item("initial_objective", initial)?;
    d.set_item("active_bounds", r.active_bounds)?;
    d.set_item("method", r.method.name())?;
    d.set_item("starts", starts)?;
    d.set_item("minima_found", minima)?;
    d.set_item("failed_starts", failed)?;
    Ok(d)
}

/// [`method`] (named apart from the argument it parses).
fn method_of(name: &str) -> Result<Method, Failure> {
    method(name)
}

/// The settings of `mpc` (the command line's flags of the same names and defaults): `given`
/// the arguments of the scene's `[mpc]` keys (`None`: the table's key, else the default;
/// [`MpcTable::resolve`], the command line's precedence).
struct MpcArgs {
    given: MpcTable,
    solver: MpcSolver,
    first_iterations: usize,
    rate_penalty: f64,
    baselines: bool,
}

/// The closed loops: MPC and, with `baselines`, no control, the best constant force and the
/// tuned PD law (with its gains [bias, K_p, K_d]).
type Loops = (ClosedLoopResult, Option<([ClosedLoopResult; 3], [f64; 3])>);

/// A controller whose decisions are counted on the call's [`Ticker`] (the progress of
/// `mpc(..., progress=...)`); it decides as the controller it wraps.
struct Counted<'a, C: ?Sized> {
    inner: &'a mut C,
    ticker: &'a Ticker,
}

impl<C: Controller + ?Sized> Controller for Counted<'_, C> {
    fn name(&self) -> String {
        self.inner.name()
    }

    fn control(&mut self, obs: &Observation<'_>) -> chainbeam::Result<Force2> {
        let u = self.inner.control(obs);
        self.ticker.tick();
        u
    }

    fn last_iterations(&self) -> Option<usize> {
        self.inner.last_iterations()
    }

    fn last_rollouts(&self) -> Option<usize> {
        self.inner.last_rollouts()
    }

    fn spatial(&self) -> bool {
        self.inner.spatial()
    }
}

/// The closed loop of `controller`, its decisions counted.
fn counted_loop(
    scene: &chainbeam::Scene,
    interval: f64,
    controller: &mut dyn Controller,
    ticker: &Ticker,
) -> chainbeam::Result<ClosedLoopResult> {
    let mut c = Counted {
        inner: controller,
        ticker,
    };
    run_closed_loop(scene, interval, &mut c)
}

fn run_mpc(
    scene: &chainbeam::Scene,
    model: &chainbeam::Scene,
    a: &MpcArgs,
    ticker: &Ticker,
) -> Result<Loops, Failure> {
    let s = a.given.resolve(scene.mpc.as_ref());
    // One decision every `interval` over T = N h, for each closed loop run.
    let decisions = (scene.time.steps as f64 * scene.time.step / s.interval).round();
    let loops = if a.baselines { 4.0 } else { 1.0 };
    if decisions.is_finite() && decisions >= 0.0 {
        ticker.set_total((decisions * loops) as u64);
    }
    let options = MpcOptions {
        horizon: Horizon::Seconds(s.horizon),
        iterations: s.iterations,
        first_iterations: a.first_iterations,
        solver: a.solver,
        effort: s.effort,
        objective: s
            .plan_objective(scene, model)
            .map_err(chainbeam::Error::from)?,
        ocp: OcpOptions {
            rate_penalty: a.rate_penalty,
            ..OcpOptions::default().with_bound(s.bound)
        },
        plan_pendulums: s.plan_pendulums,
        plan_step: s.plan_step,
        ..MpcOptions::default()
    };
    let mut mpc = Mpc::new(model, s.interval, options)?;
    let closed = counted_loop(scene, s.interval, &mut mpc, ticker)?;
    if !a.baselines {
        return Ok((closed, None));
    }
    let none = counted_loop(scene, s.interval, &mut NoControl, ticker)?;
    let (mut constant, _) = ConstantForce::best(scene, s.bound, s.effort)?;
    let constant = counted_loop(scene, s.interval, &mut constant, ticker)?;
    let tuning = PdTuning::new(scene, s.interval, s.bound, s.effort)?;
    let opts = OptimOptions {
        max_iters: 200,
        first_step: 0.01,
        ..OptimOptions::default()
    };
    let (mut pd, _) = PdLaw::tune(&tuning, &[0.0; 3], &opts)?;
    let gains = [pd.bias.z, pd.kp, pd.kd];
    let pd = counted_loop(scene, s.interval, &mut pd, ticker)?;
    Ok((closed, Some(([none, constant, pd], gains))))
}

/// A summary as a dict (the JSON of `chainbeam mpc --summary`).
fn summary<'py>(py: Python<'py>, s: &Summary) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    d.set_item("controller", &s.controller)?;
    d.set_item("c_sum", s.c_sum)?;
    d.set_item("max_abs_moment", s.max_abs_moment)?;
    d.set_item("max_abs_control", s.max_abs_control)?;
    d.set_item("effort", s.effort)?;
    d.set_item("simulated_seconds", s.simulated_seconds)?;
    d.set_item("decisions", s.decisions)?;
    d.set_item("initial_decision_seconds", s.initial_decision_seconds)?;
    d.set_item("mean_replan_seconds", s.mean_replan_seconds)?;
    d.set_item("worst_replan_seconds", s.worst_replan_seconds)?;
    d.set_item("mean_iterations", s.mean_iterations)?;
    d.set_item("mean_rollouts", s.mean_rollouts)?;
    d.set_item("real_time_factor", s.real_time_factor)?;
    d.set_item("loop_real_time_factor", s.loop_real_time_factor)?;
    Ok(d)
}

/// Receding-horizon control in closed loop; see `chainbeam.mpc`.
#[pyfunction]
#[pyo3(signature = (scene, model=None, horizon=None, interval=None, iterations=None,
                    solver="auto", first_iterations=50, bound=None, effort=None, rate_penalty=0.0,
                    baselines=false, plan_pendulums=None, plan_step=None, progress=None))]
#[allow(clippy::too_many_arguments)] // Python keyword arguments, collected at once below
pub fn mpc<'py>(
    py: Python<'py>,
    scene: &Scene,
    model: Option<&Scene>,
    horizon: Option<f64>,
    interval: Option<f64>,
    iterations: Option<usize>,
    solver: &str,
    first_iterations: usize,
    bound: Option<f64>,
    effort: Option<f64>,
    rate_penalty: f64,
    baselines: bool,
    plan_pendulums: Option<usize>,
    plan_step: Option<f64>,
    progress: Option<Bound<'py, PyAny>>,
) -> PyResult<Bound<'py, PyDict>> {
    let solver = match solver {
        "auto" => MpcSolver::Auto,
        "condensed" => MpcSolver::Condensed,
        "riccati" => MpcSolver::Riccati,
        other => {
            return Err(Failure::argument(
                "solver",
                format!(
                    "unknown solver {other:?}; expected \"auto\", \"condensed\" or \"riccati\""
                ),
            )
            .into_py(py))
        }
    };
    let a = MpcArgs {
        given: MpcTable {
            interval,
            horizon,
            iterations,
            bound,
            effort,
            plan_pendulums,
            plan_step,
            ..MpcTable::default()
        },
        solver,
        first_iterations,
        rate_penalty,
        baselines,
    };
    let s = scene.inner.clone();
    let m = model.map_or_else(|| s.clone(), |m| m.inner.clone());
    let progress = progress.as_ref().filter(|p| !p.is_none());
    let out = watched(py, progress, move |ticker| {
        with_pool(|| run_mpc(&s, &m, &a, ticker)).map_err(Failure::Internal)?
    })?;
    let (closed, base) = check(py, out)?;
    let d = PyDict::new(py);
    d.set_item("t", PyArray1::from_vec(py, closed.t))?;
    d.set_item("moment", PyArray1::from_vec(py, closed.moment))?;
    d.set_item("control", PyArray1::from_vec(py, closed.control))?;
    d.set_item("tip", PyArray1::from_vec(py, closed.tip))?;
    d.set_item("summary", summary(py, &closed.summary)?)?;
    if let Some(([none, constant, pd], gains)) = base {
        d.set_item("moment_none", PyArray1::from_slice(py, &none.moment))?;
        d.set_item(
            "moment_constant",
            PyArray1::from_slice(py, &constant.moment),
        )?;
        d.set_item(
            "control_constant",
            PyArray1::from_slice(py, &constant.control),
        )?;
        d.set_item("moment_pd", PyArray1::from_slice(py, &pd.moment))?;
        d.set_item("control_pd", PyArray1::from_slice(py, &pd.control))?;
        let sums = [
            summary(py, &none.summary)?,
            summary(py, &constant.summary)?,
            summary(py, &pd.summary)?,
        ];
        d.set_item("baselines", sums.to_vec())?;
        d.set_item("pd_gains", gains.to_vec())?;
    }
    Ok(d)
}
