//! The command line of `chainbeam mpc`: its arguments and the `[mpc]` settings' flags, which
//! `chainbeam fatigue` shares.

use super::*;

/// `mpc`'s flags.
#[derive(Args)]
pub struct MpcArgs {
    #[arg(value_name = "SCENE.toml", help = SCENE_HELP)]
    pub scene: PathBuf,
    /// The controller's model (a scene file with the same number of pendulums); default: the
    /// scene itself (a perfect model). Its [time] length and [control] values are not used.
    #[arg(long, value_name = "MODEL.toml")]
    pub model: Option<PathBuf>,
    #[command(flatten)]
    pub mpc: MpcFlags,
    /// The solver of each plan: `condensed` (sensitivities to the plan's forces, a dense QP;
    /// the faster for horizons of a few seconds), `riccati` (stage Jacobians and Riccati
    /// passes; linear in the horizon) or `auto` (condensed up to 4(2n+1) forces per plan).
    #[arg(long, value_enum, default_value_t = SolverArg::Auto)]
    pub solver: SolverArg,
    /// Iterations of the first (cold) plan at t = 0.
    #[arg(long, value_name = "K", default_value_t = 50)]
    pub first_iterations: usize,
    /// Rate penalty σ of (σ/h)·Σ (u_k − u_{k−1})².
    #[arg(long, value_name = "SIGMA", default_value_t = 0.0)]
    pub rate_penalty: f64,
    /// Also run no control, the best constant force and a tuned PD law.
    #[arg(long)]
    pub baselines: bool,
    /// Write the JSON summary to FILE (written like --output).
    #[arg(long, value_name = "FILE")]
    pub summary: Option<PathBuf>,
    #[arg(long, short, value_name = "FILE", help = OUTPUT_HELP)]
    pub output: Option<PathBuf>,
}

/// The closed-loop flags `chainbeam mpc` and `chainbeam fatigue` share: one per key of the
/// scene's `[mpc]` table but `pd_training` and `objective` (`fatigue`'s alone), each overriding
/// its key when given ([`MpcTable::resolve`]).
#[derive(Args)]
pub struct MpcFlags {
    /// Control interval [s] of every controller (MPC, the constant force, the PD law), a
    /// multiple of time.step that divides the run [default: the scene's mpc.interval, else
    /// 0.1].
    #[arg(long, value_name = "S")]
    pub interval: Option<f64>,
    /// Horizon of each MPC plan [s], a whole number of intervals [default: mpc.horizon, else
    /// 3].
    #[arg(long, value_name = "S")]
    pub horizon: Option<f64>,
    /// MPC's Gauss-Newton iterations per re-plan [default: mpc.iterations, else 1].
    #[arg(long, value_name = "K")]
    pub iterations: Option<usize>,
    /// Force bound |u| ≤ U [N] of every controller (MPC, the constant force, the PD law)
    /// [default: mpc.bound, else 5].
    #[arg(long, value_name = "U")]
    pub bound: Option<f64>,
    /// Effort weight ρ of ρ·h·Σ u_k² in what the controllers minimise [default: mpc.effort,
    /// else 0.01].
    #[arg(long, value_name = "RHO")]
    pub effort: Option<f64>,
    /// MPC plans on a reduced model: the model's [pipe] or [stackup] rebuilt with N pendulums
    /// (the plant keeps its own; through the vessel's thrust with the same vessel); the observed
    /// state is mapped onto it [default: mpc.plan_pendulums, else plan on the model as it is].
    #[arg(long, value_name = "N")]
    pub plan_pendulums: Option<usize>,
    /// The step [s] of MPC's planning model (the interval must be a multiple of it; through the
    /// vessel's thrust a whole multiple of time.step) [default: mpc.plan_step, else the model's
    /// time.step].
    #[arg(long, value_name = "S")]
    pub plan_step: Option<f64>,
    /// What MPC's plan knows of the sea ahead: `perfect` = the model scene's waves, `none` = a
    /// calm sea beyond the observed state, `noisy` = the model scene's waves with errors growing
    /// with lead time (--forecast-error) (the plant always runs the true sea) [default:
    /// mpc.forecast, else perfect].
    #[arg(long, value_name = "KIND")]
    pub forecast: Option<ForecastArg>,
    /// The noisy forecast's error growth e: each wave component's relative amplitude and phase
    /// (rad) errors have the standard deviation min(e·τ/T_p, 1/√2) at lead time τ, in [0, 100]
    /// [default: mpc.forecast_error, else 0.1].
    #[arg(long, value_name = "E")]
    pub forecast_error: Option<f64>,
    /// What MPC's plan starts from: `state` = the plant's whole state, `sensors` = a Kalman
    /// filter's estimate from the vessel's position and velocity, the top and bottom flex
    /// joints' angles and the LMRP's inclination, each with its measurement noise (a thrust
    /// scene with a [stackup]; docs/mpc.md "What the controller sees") [default: mpc.observe,
    /// else state].
    #[arg(long, value_name = "KIND")]
    pub observe: Option<ObserveArg>,
    /// The `name` of the scene's `[[fatigue.hotspot]]` whose moment the controllers act on
    /// (MPC through the vessel's thrust plans on h·Σ|M|^m there; in `fatigue` also the PD law
    /// and the constant force, and the reported damage and life are that hot spot's;
    /// docs/mpc.md "The moment a controller acts on") [default: mpc.hotspot, else the chain's
    /// base moment].
    #[arg(long, value_name = "NAME")]
    pub hotspot: Option<String>,
    /// What the hot spot's moment is measured from in MPC's plan: `zero` = h·Σ|M|^m, `mean` =
    /// h·Σ|M − M̄|^m with M̄ the plan's own mean over its horizon (S-N damage counts ranges,
    /// which the mean does not change; needs --hotspot; docs/mpc.md "The moment a controller
    /// acts on") [default: mpc.moment_about, else zero].
    #[arg(long, value_name = "KIND")]
    pub moment_about: Option<MomentAboutArg>,
}

/// `--moment-about`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum MomentAboutArg {
    /// the moment about zero, h·Σ|M|^m
    Zero,
    /// the moment about the plan's own mean, h·Σ|M − M̄|^m
    Mean,
}

/// `--observe`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum ObserveArg {
    /// the plant's whole state
    State,
    /// a Kalman filter's estimate from the riser's sensors
    Sensors,
}

/// `--forecast`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum ForecastArg {
    /// the model scene's waves ahead
    Perfect,
    /// no waves ahead: the plan runs on a calm sea from the observed state
    None,
    /// the model scene's waves with errors growing with lead time (--forecast-error)
    Noisy,
}

impl MpcFlags {
    /// `--forecast-error` within its range ([`chainbeam::scene::check_forecast_error`]).
    ///
    /// # Errors
    /// [`CliError`] naming `--forecast-error`.
    pub fn check_forecast_error(&self) -> Result<(), CliError> {
        if let Some(e) = self.forecast_error {
            chainbeam::scene::check_forecast_error("--forecast-error", e)
                .map_err(|e| CliError::msg(e.to_string()))?;
        }
        Ok(())
    }

    /// The flags as an `[mpc]` table (`None`: not given), the values that override the scene's
    /// table ([`MpcTable::resolve`]); `pd_training` and `objective` not given.
    pub fn table(&self) -> MpcTable {
        MpcTable {
            interval: self.interval,
            horizon: self.horizon,
            iterations: self.iterations,
            bound: self.bound,
            effort: self.effort,
            plan_pendulums: self.plan_pendulums,
            plan_step: self.plan_step,
            forecast: self.forecast.map(|f| match f {
                ForecastArg::Perfect => Forecast::Perfect,
                ForecastArg::None => Forecast::None,
                ForecastArg::Noisy => Forecast::Noisy,
            }),
            forecast_error: self.forecast_error,
            observe: self.observe.map(|o| match o {
                ObserveArg::State => Observe::State,
                ObserveArg::Sensors => Observe::Sensors,
            }),
            hotspot: self.hotspot.clone(),
            moment_about: self.moment_about.map(|m| match m {
                MomentAboutArg::Zero => MomentAbout::Zero,
                MomentAboutArg::Mean => MomentAbout::Mean,
            }),
            ..MpcTable::default()
        }
    }
}

/// `--solver`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum SolverArg {
    /// condensed up to 4(2n+1) forces per plan (n pendulums), riccati beyond
    Auto,
    /// sensitivities of M₀ to the plan's forces and a dense QP (cost ∝ steps × forces)
    Condensed,
    /// stage Jacobians and Riccati passes (cost ∝ steps)
    Riccati,
}
