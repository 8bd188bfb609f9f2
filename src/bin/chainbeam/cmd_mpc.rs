//! `chainbeam mpc`: receding-horizon control of the scene in closed loop (CSV trajectory and
//! JSON summary), with the baselines beside it.

use std::io::Write;
use std::path::{Path, PathBuf};

use clap::{Args, ValueEnum};
use serde::Serialize;

use chainbeam::mpc::{
    run_closed_loop, ClosedLoopResult, ConstantForce, Controller, Force2, Horizon, Mpc, MpcOptions,
    MpcSolver, NoControl, Observation, PdLaw, PdTuning, Summary,
};
use chainbeam::ocp::OcpOptions;
use chainbeam::optimize::{OptimOptions, OptimProblem};
use chainbeam::scene::{
    Forecast, MomentAbout, MpcSettings, MpcTable, Observe, MAX_STEPS, MPC_KEYS,
};
use chainbeam::{ObjectiveKind, Scene, ValidScene};

use crate::output::{push_f64, refuse_overwrite, Inputs, Output};
use crate::progress::Progress;
use crate::{check_finite, check_force_flag, lib_error, to_json, CliError};
use crate::{OUTPUT_HELP, SCENE_HELP};

mod args;

pub use args::{MpcArgs, MpcFlags, SolverArg};

/// `mpc --help`.
pub const LONG_ABOUT: &str = "\
Run the scene in closed loop under a receding-horizon (model predictive) controller: every \
--interval seconds the controller observes the beam's state, solves the optimal-control problem \
min Σ M₀(t_k)² + ρ·h·Σ u_k² (Σ |M₀(t_k)|^p + ρ·h·Σ u_k² when the model's [objective] is \
kind = \"power\", exponent = p; with kind = \"fatigue\" the plans take its smooth stand-in, p = the \
S-N curve's slope m, and the summary reports the rainflow damage of the run) over the next --horizon seconds of its model (the scene itself, or \
--model FILE: another drag, a forecast of the loads with errors) by a Gauss-Newton solver \
(--solver), warm-started from its previous plan and limited to --iterations iterations (real-time \
iteration), and applies the plan's first force, held over the interval, at control.node \
(default: the tip). The plant is the scene: RATTLE from its start ([time] initial: the straight beam \
at rest by default), t in [0, N·h]. \
The first plan (at t = 0, cold) gets --first-iterations.

The settings --interval, --horizon, --iterations, --bound, --effort, --plan-pendulums and \
--plan-step default to the scene's [mpc] table (docs/scene-format.md; the keys in snake case, \
as `chainbeam fatigue` reads them): a flag given overrides its key, a key given in neither takes \
the default. The table's objective = \"power\" makes the plans minimise Σ|M₀(t_k)|^m + ρ·h·Σ u_k², \
m the first slope of the S-N curve of the scene's [fatigue] table (the fatigue proxy of \
`chainbeam fatigue`), and \"sum\" Σ M₀(t_k)² + ρ·h·Σ u_k², whatever the model's [objective]; \
its pd_training is `chainbeam fatigue`'s alone (the baselines here are tuned over the whole run).

With --baselines the same loop also runs without control, with the best constant force \
(optimised over the whole scene) and with a PD law u = clamp(u_b − K_p·M₀ − K_d·dM₀/dt) on the \
measured base moment whose gains are tuned over the scene's closed-loop c_sum.

A spatial scene (a load or the current with an x component; or a --model that is spatial) runs \
in the spatial model: the controller plans a 2-axis force (u_x, u_z) per interval on the vector \
moment, min Σ |M₀(t_k)|² + ρ·h·Σ |u_k|² (|M₀|² = M₀ₓ² + M₀_z², each force component within \
--bound), with the solver of --solver as in the planar model (two controls per stage); the baselines \
are 2-axis: the best constant (u_x, u_z), and a PD law per axis u_x = clamp(u_b,x − K_p·M₀ₓ − \
K_d·dM₀ₓ/dt), u_z likewise, with common gains.

CSV (--output; default standard output): one row per t_k, k = 0..N:
  t        time t_k [s]
  moment   base bending moment M₀(t_k) [Nm] under MPC
  control  the force u_k [N] applied by MPC
  tip      tip displacement z_n(t_k) [m] under MPC
  with --baselines also moment_none, moment_constant, control_constant, moment_pd, control_pd.
  A spatial run adds moment_x (M₀ₓ) and control_x (u_x) after tip, and with --baselines \
moment_x_none, moment_x_constant, control_x_constant, moment_x_pd, control_x_pd at the end.

JSON (--summary FILE): settings, and per controller: c_sum = Σ M₀(t_k)² [N²m²], max_abs_moment, \
max_abs_control, effort h·Σ u² [N²s], decisions, initial_decision_seconds, mean_replan_seconds, \
worst_replan_seconds (the decisions after the first), mean_iterations, mean_rollouts (the plan \
model's simulations per decision after the first), real_time_factor \
(simulated time / controller wall time), loop_real_time_factor; real_time (worst re-plan ≤ \
interval); with --baselines the ratios of MPC's c_sum to the constant force's and the PD law's, \
and pd_gains [u_b, K_p, K_d] (spatial: [u_b,x, u_b,z, K_p, K_d]); a spatial run has model = \
\"spatial\" (c_sum = Σ |M₀|², max_abs_control and effort of |u|); \
fatigue_damage (the scene's [objective] is kind = \"fatigue\"): the rainflow Miner damage of \
MPC's moment, as `chainbeam fatigue --series` of the CSV reports it.

Exit status 0 also when re-plans stop at their iteration budget (that is the method); 1 on \
invalid settings (naming the flag) or a failed step or solve.";

#[derive(Serialize)]
struct Settings {
    horizon: f64,
    solver: SolverArg,
    interval: f64,
    iterations: usize,
    first_iterations: usize,
    bound: f64,
    effort: f64,
    rate_penalty: f64,
    model: Option<String>,
    /// What MPC's plan started from ("state" or "sensors").
    observe: &'static str,
    /// The hot spot MPC planned on (absent: the chain's base moment).
    #[serde(skip_serializing_if = "Option::is_none")]
    hotspot: Option<String>,
    /// What the hot spot's moment was measured from ("mean"; absent: "zero", as before).
    #[serde(skip_serializing_if = "Option::is_none")]
    moment_about: Option<&'static str>,
}

#[derive(Serialize)]
struct Report {
    /// "spatial" for a spatial run (absent for a planar one, whose JSON is as before).
    #[serde(skip_serializing_if = "Option::is_none")]
    model: Option<&'static str>,
    settings: Settings,
    mpc: Summary,
    real_time: bool,
    baselines: Vec<Summary>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pd_gains: Option<Vec<f64>>,
    /// MPC's c_sum over the uncontrolled run's: above 1, the controller made the moment worse
    /// ([`worse_than_none`] says so on stderr).
    #[serde(skip_serializing_if = "Option::is_none")]
    c_sum_ratio_to_none: Option<f64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    c_sum_ratio_to_constant: Option<f64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    c_sum_ratio_to_pd: Option<f64>,
    /// The rainflow damage of MPC's moment when the scene's objective is kind = "fatigue".
    #[serde(skip_serializing_if = "Option::is_none")]
    fatigue_damage: Option<f64>,
}

/// The runs of the baselines: none, constant, PD (with its gains).
struct Baselines {
    runs: [ClosedLoopResult; 3],
    gains: Vec<f64>,
}

/// A run's flags and the closed-loop settings they resolve to with the scene's `[mpc]` table.
struct Setup<'a> {
    a: &'a MpcArgs,
    /// The flags of the `[mpc]` keys (`None`: not given).
    flags: MpcTable,
    /// The scene's `[mpc]` table.
    table: Option<MpcTable>,
    /// Each flag, else the table's key, else the default ([`MpcTable::resolve`]).
    settings: MpcSettings,
}

impl<'a> Setup<'a> {
    fn new(a: &'a MpcArgs, scene: &Scene) -> Self {
        let flags = a.mpc.table();
        let settings = flags.resolve(scene.mpc.as_ref());
        Setup {
            a,
            flags,
            table: scene.mpc.clone(),
            settings,
        }
    }

    /// How an error names the setting `key` (an `[mpc]` key): its flag, or `mpc.KEY` when the
    /// value is the scene's.
    fn name(&self, key: &str) -> String {
        setting_name(&self.flags, self.table.as_ref(), key)
    }
}

/// How an error names the closed-loop setting `key` (one of [`MPC_KEYS`]): `mpc.KEY` when the
/// run took it from the scene's `[mpc]` table ([`MpcTable::defers_to`]), else its flag
/// (`--plan-pendulums`). `chainbeam mpc` and `chainbeam fatigue` both.
pub fn setting_name(flags: &MpcTable, table: Option<&MpcTable>, key: &str) -> String {
    if flags.defers_to(table, key) {
        format!("mpc.{key}")
    } else if key == "objective" {
        "--mpc-objective".into()
    } else {
        format!("--{}", key.replace('_', "-"))
    }
}

/// `settings.moment_about` in the JSON: "mean", absent for "zero" (the JSON as before).
pub fn moment_about_json(m: MomentAbout) -> Option<&'static str> {
    (m != MomentAbout::Zero).then(|| m.name())
}

/// Runs `mpc`.
pub fn run(a: &MpcArgs, progress: Progress) -> Result<(), CliError> {
    if let Some(bound) = a.mpc.bound.filter(|b| b.is_finite()) {
        check_force_flag("--bound", bound)?;
    }
    a.mpc.check_forecast_error()?;
    let out = Output::prepare(a.output.as_deref())?;
    let summary_out = Output::prepare(a.summary.as_deref())?;
    let mut inputs = Inputs::new();
    let scene = inputs.load_scene(&a.scene)?;
    let model = match &a.model {
        Some(path) => inputs.load_scene(path)?,
        None => scene.clone(),
    };
    refuse_overwrite(&[("--output", &out), ("--summary", &summary_out)], &inputs)?;
    let setup = Setup::new(a, &scene);
    let s = &setup.settings;
    let options = MpcOptions {
        horizon: Horizon::Seconds(s.horizon),
        iterations: s.iterations,
        first_iterations: a.first_iterations,
        solver: match a.solver {
            SolverArg::Auto => MpcSolver::Auto,
            SolverArg::Condensed => MpcSolver::Condensed,
            SolverArg::Riccati => MpcSolver::Riccati,
        },
        effort: s.effort,
        objective: s
            .plan_objective(&scene, &model)
            .map_err(|e| lib_error(&a.scene, e.into()))?,
        ocp: OcpOptions {
            rate_penalty: a.rate_penalty,
            ..OcpOptions::default().with_bound(s.bound)
        },
        plan_pendulums: s.plan_pendulums,
        plan_step: s.plan_step,
        forecast: s.forecast,
        forecast_error: s.forecast_error,
        forecast_seed: s.forecast_seed,
        observe: s.observe,
        hotspot: s
            .hotspot_spec(&scene)
            .map_err(|e| mpc_error(&setup, &a.scene, e.into()))?,
        moment_about: s.moment_about,
        ..MpcOptions::default()
    };
    let model_file = a.model.as_deref().unwrap_or(&a.scene);
    check_plan_length(&setup, model_file, &model)?;
    let spatial = scene.spatial_key().is_some() || model.spatial_key().is_some();
    let loop_of = Loop {
        setup: &setup,
        scene: &scene,
        model_file,
    };
    let closed = if spatial {
        loop_of.run(Mpc::spatial(&model, s.interval, options), &progress)?
    } else {
        loop_of.run(Mpc::new(&model, s.interval, options), &progress)?
    };
    let baselines = match a.baselines {
        false => None,
        true => Some(run_baselines(&setup, &scene, spatial, &progress)?),
    };
    check_run(&a.scene, &closed)?;
    let mut report = report(&setup, closed.summary.clone(), baselines.as_ref());
    report.fatigue_damage = fatigue_damage(&a.scene, &scene, &closed)?;
    report.model = spatial.then_some("spatial");
    let json = to_json(&report)?;
    if let Some(b) = &baselines {
        let none = b.runs[0].summary.c_sum;
        if let Some(w) = worse_than_none(&a.scene, report.mpc.c_sum, none) {
            eprintln!("{w}");
        }
    }
    let mut sink = out.open()?;
    if let Err(e) = write_csv(sink.writer(), &closed, baselines.as_ref()) {
        return Err(sink.error(&e));
    }
    sink.finish()?;
    if a.summary.is_some() {
        summary_out.write_all(&json)?;
    }
    Ok(())
}

/// The closed loop of a run: the plant's scene and the controller's model.
struct Loop<'a> {
    setup: &'a Setup<'a>,
    scene: &'a ValidScene,
    model_file: &'a Path,
}

impl Loop<'_> {
    /// Runs the controller `mpc` (as built, or its error: the model's) in closed loop (in the
    /// planar or the spatial model, as the scene and the controller ask), blaming a failure on
    /// the model's file when the controller failed and on the plant's otherwise.
    fn run<C: Controller>(
        &self,
        mpc: chainbeam::Result<C>,
        progress: &Progress,
    ) -> Result<ClosedLoopResult, CliError> {
        let (a, s) = (self.setup.a, &self.setup.settings);
        let mut mpc = mpc.map_err(|e| mpc_error(self.setup, self.model_file, e))?;
        let seconds = self.scene.time.steps as f64 * self.scene.time.step;
        // A bar over the decisions (one every interval; a wrong interval fails the loop, which
        // then says why).
        let decisions = (seconds / s.interval).round().max(0.0) as u64;
        let bar = progress.bar(
            decisions,
            format!(
                "closed loop: {seconds} s, a plan every {} s over {} s",
                s.interval, s.horizon
            ),
        );
        let mut blamed = Blamed {
            inner: &mut mpc,
            failed: false,
            bar: &bar,
        };
        let closed = run_closed_loop(self.scene, s.interval, &mut blamed);
        bar.finish_and_clear();
        // The controller's failures are the model's (its scene, its step); the others the
        // plant's.
        let failed_file = if blamed.failed {
            self.model_file
        } else {
            &a.scene
        };
        closed.map_err(|e| mpc_error(self.setup, failed_file, e))
    }
}

/// The controller, remembering whether it failed: its errors come from the `--model` scene, the
/// loop's other errors from the plant's; each decision advances the progress bar.
struct Blamed<'a, C> {
    inner: &'a mut C,
    failed: bool,
    bar: &'a indicatif::ProgressBar,
}

impl<C: Controller> Controller for Blamed<'_, C> {
    fn name(&self) -> String {
        self.inner.name()
    }

    fn control(&mut self, obs: &Observation<'_>) -> chainbeam::Result<Force2> {
        let u = self.inner.control(obs);
        self.failed = u.is_err();
        self.bar.inc(1);
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

/// The flag (or the scene's `mpc.KEY` it came from) of an option of [`MpcOptions`] or of the
/// loop (the library's argument name).
fn flag_of(s: &Setup<'_>, name: &str) -> Option<String> {
    Some(match name {
        "first_iterations" => "--first-iterations".into(),
        "rate_penalty" => "--rate-penalty".into(),
        "solver" => "--solver".into(),
        "bounds" => s.name("bound"),
        key if MPC_KEYS.contains(&key) => s.name(key),
        _ => return None,
    })
}

/// A library error of the run, naming `file` (the plant's scene or the controller's model) or,
/// for a quantity the flags (or the scene's `[mpc]` table) set, the flag (or `mpc.KEY`).
fn mpc_error(s: &Setup<'_>, file: &Path, e: chainbeam::Error) -> CliError {
    // The flag that set the argument at fault, and what is wrong with it.
    let flagged = e
        .argument_fault()
        .and_then(|(name, reason)| flag_of(s, name).map(|f| (f, reason)));
    if let Some((flag, reason)) = flagged {
        return CliError::msg(format!("{}: {flag}: {reason}", file.display()));
    }
    match &e {
        // The plan's scene has the model's beam and a length set by the flags.
        chainbeam::Error::Scene(se) if se.key() == Some("time.steps") => CliError::msg(format!(
            "{}: {} {} s (plans of horizon/interval intervals of {} s): the plan {}",
            file.display(),
            s.name("horizon"),
            s.settings.horizon,
            s.settings.interval,
            se.kind
        )),
        _ => lib_error(file, e),
    }
}

/// Refuses a horizon whose plans would have more steps than a scene may (`--horizon`/
/// `--interval` intervals of the model's `time.step`), before any plan is built.
fn check_plan_length(s: &Setup<'_>, model_file: &Path, model: &Scene) -> Result<(), CliError> {
    let horizon = s.settings.horizon;
    let steps = (horizon / model.time.step).round();
    if steps.is_finite() && steps <= MAX_STEPS as f64 {
        return Ok(());
    }
    let name = s.name("horizon");
    Err(CliError::msg(format!(
        "{}: {name} {horizon} s: a plan of {steps:e} steps of the model's time.step = {} s, over \
         the {MAX_STEPS} steps a plan may have; give a shorter horizon",
        model_file.display(),
        model.time.step
    )))
}

/// The L-BFGS options of the PD baseline's tuning (planar and spatial).
fn pd_tuning_options() -> OptimOptions {
    OptimOptions {
        max_iters: 200,
        first_step: 0.01,
        ..OptimOptions::default()
    }
}

/// The baselines (no control, the best constant force, a PD law tuned over the closed-loop
/// c_sum), each run checked finite; with `spatial` in the spatial model (also for a planar plant
/// scene whose `--model` is spatial): the best constant 2-axis force and a PD law per axis with
/// common gains ([`PdLaw`], tuned over the closed-loop Σ |M₀|²).
fn run_baselines(
    s: &Setup<'_>,
    scene: &ValidScene,
    spatial: bool,
    progress: &Progress,
) -> Result<Baselines, CliError> {
    let err = |e| mpc_error(s, &s.a.scene, e);
    let MpcSettings {
        interval,
        bound,
        effort,
        ..
    } = s.settings;
    // A planar plant scene whose `--model` is spatial runs every baseline in the spatial model.
    let run = |c: &mut dyn Controller| {
        let mut c = InModel { inner: c, spatial };
        run_closed_loop(scene, interval, &mut c).map_err(err)
    };
    let opts = pd_tuning_options();
    let spinner = progress.spinner("baselines: no control, best constant force, tuned PD law");
    let (mut constant, _) = if spatial {
        ConstantForce::best_spatial(scene, bound, effort)
    } else {
        ConstantForce::best(scene, bound, effort)
    }
    .map_err(err)?;
    let tuning = if spatial {
        PdTuning::spatial(scene, interval, bound, effort)
    } else {
        PdTuning::new(scene, interval, bound, effort)
    }
    .map_err(err)?;
    let start = vec![0.0; tuning.n_params()];
    let (mut pd, _) = PdLaw::tune(&tuning, &start, &opts).map_err(err)?;
    let gains = pd.gains();
    let runs = [run(&mut NoControl)?, run(&mut constant)?, run(&mut pd)?];
    spinner.finish_and_clear();
    for r in &runs {
        check_run(&s.a.scene, r)?;
    }
    Ok(Baselines { runs, gains })
}

/// A controller run in the spatial model when `spatial` is set, whatever its own model
/// ([`Controller::spatial`]).
struct InModel<'c> {
    inner: &'c mut dyn Controller,
    spatial: bool,
}

impl Controller for InModel<'_> {
    fn name(&self) -> String {
        self.inner.name()
    }

    fn control(&mut self, obs: &Observation<'_>) -> chainbeam::Result<Force2> {
        self.inner.control(obs)
    }

    fn last_iterations(&self) -> Option<usize> {
        self.inner.last_iterations()
    }

    fn last_rollouts(&self) -> Option<usize> {
        self.inner.last_rollouts()
    }

    fn spatial(&self) -> bool {
        self.spatial || self.inner.spatial()
    }
}

/// The rainflow damage of the closed loop's moment (`chainbeam fatigue`'s assessment of it) when
/// the scene's objective is kind = "fatigue".
fn fatigue_damage(
    path: &Path,
    scene: &Scene,
    r: &ClosedLoopResult,
) -> Result<Option<f64>, CliError> {
    let (Some(ObjectiveKind::Fatigue(_)), Some(spec)) = (scene.objective, scene.fatigue_spec())
    else {
        return Ok(None);
    };
    let history = chainbeam::fatigue::MomentHistory {
        duration_s: r.summary.simulated_seconds,
        moment: &r.moment,
        moment_x: (!r.moment_x.is_empty()).then_some(&r.moment_x[..]),
        measure: scene.moment_measure(),
    };
    let a = chainbeam::fatigue::assess(&spec, history)
        .map_err(|e| CliError::msg(format!("{}: fatigue_damage: {e}", path.display())))?;
    check_finite(path, "fatigue_damage", &[a.damage])?;
    Ok(Some(a.damage))
}

fn report(setup: &Setup<'_>, mpc: Summary, b: Option<&Baselines>) -> Report {
    let (a, s) = (setup.a, &setup.settings);
    let ratio = |i: usize| b.map(|b| mpc.c_sum / b.runs[i].summary.c_sum);
    Report {
        model: None,
        settings: Settings {
            horizon: s.horizon,
            solver: a.solver,
            interval: s.interval,
            iterations: s.iterations,
            first_iterations: a.first_iterations,
            bound: s.bound,
            effort: s.effort,
            rate_penalty: a.rate_penalty,
            model: a.model.as_ref().map(|p| p.display().to_string()),
            observe: s.observe.name(),
            hotspot: s.hotspot.clone(),
            moment_about: moment_about_json(s.moment_about),
        },
        real_time: mpc.worst_replan_seconds <= s.interval,
        c_sum_ratio_to_none: ratio(0),
        c_sum_ratio_to_constant: ratio(1),
        c_sum_ratio_to_pd: ratio(2),
        pd_gains: b.map(|b| b.gains.clone()),
        fatigue_damage: None,
        baselines: b.map_or_else(Vec::new, |b| {
            b.runs.iter().map(|r| r.summary.clone()).collect()
        }),
        mpc,
    }
}

/// The warning for a closed loop whose c_sum = Σ M₀² is above the uncontrolled run's (the
/// baseline "none"): the controller made the bending moment worse. A run still exits 0 (its
/// outputs are what was computed, and `c_sum_ratio_to_none` says the same), but it is never
/// reported as a success in silence.
fn worse_than_none(scene: &Path, mpc: f64, none: f64) -> Option<String> {
    (mpc > none).then(|| {
        format!(
            "{}: warning: MPC's closed loop has c_sum = {mpc:.6e} N²m², above the uncontrolled \
             run's {none:.6e} (ratio {:.4}): the controller made the bending moment worse \
             (try a longer --horizon, more --iterations, or the full model)",
            scene.display(),
            mpc / none
        )
    })
}

/// Never write NaN: the run's columns and summary are checked before anything is written.
fn check_run(path: &Path, r: &ClosedLoopResult) -> Result<(), CliError> {
    check_finite(path, "moment", &r.moment)?;
    check_finite(path, "control", &r.control)?;
    check_finite(path, "tip", &r.tip)?;
    check_finite(path, "moment_x", &r.moment_x)?;
    check_finite(path, "control_x", &r.control_x)?;
    let s = &r.summary;
    check_finite(
        path,
        "summary",
        &[s.c_sum, s.max_abs_moment, s.max_abs_control, s.effort],
    )
}

fn write_csv(
    w: &mut dyn Write,
    r: &ClosedLoopResult,
    b: Option<&Baselines>,
) -> std::io::Result<()> {
    let spatial = !r.moment_x.is_empty();
    let mut header = String::from("t,moment,control,tip");
    if spatial {
        header.push_str(",moment_x,control_x");
    }
    if b.is_some() {
        header.push_str(",moment_none,moment_constant,control_constant,moment_pd,control_pd");
        if spatial {
            header.push_str(
                ",moment_x_none,moment_x_constant,control_x_constant,moment_x_pd,control_x_pd",
            );
        }
    }
    header.push('\n');
    w.write_all(header.as_bytes())?;
    let mut line = Vec::with_capacity(256);
    let mut buf = zmij::Buffer::new();
    for k in 0..r.t.len() {
        line.clear();
        let mut values = vec![r.t[k], r.moment[k], r.control[k], r.tip[k]];
        if spatial {
            values.extend([r.moment_x[k], r.control_x[k]]);
        }
        if let Some(b) = b {
            let [none, constant, pd] = &b.runs;
            values.extend([
                none.moment[k],
                constant.moment[k],
                constant.control[k],
                pd.moment[k],
                pd.control[k],
            ]);
            if spatial {
                values.extend([
                    none.moment_x[k],
                    constant.moment_x[k],
                    constant.control_x[k],
                    pd.moment_x[k],
                    pd.control_x[k],
                ]);
            }
        }
        for (j, v) in values.iter().enumerate() {
            if j > 0 {
                line.push(b',');
            }
            push_f64(&mut line, &mut buf, *v);
        }
        line.push(b'\n');
        w.write_all(&line)?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::worse_than_none;
    use std::path::Path;

    /// The warning names the scene, both sums and their ratio when MPC's c_sum is above the
    /// uncontrolled run's, and there is none when it is at or below it.
    #[test]
    fn worse_than_none_warns_only_above_the_uncontrolled_run() {
        let w = worse_than_none(Path::new("s.toml"), 3.0e4, 2.0e4).unwrap();
        assert!(w.starts_with("s.toml: warning:"), "{w}");
        assert!(w.contains("3.000000e4") && w.contains("2.000000e4"), "{w}");
        assert!(w.contains("ratio 1.5000"), "{w}");
        assert_eq!(worse_than_none(Path::new("s.toml"), 2.0e4, 2.0e4), None);
        assert_eq!(worse_than_none(Path::new("s.toml"), 1.0e4, 2.0e4), None);
    }
}
