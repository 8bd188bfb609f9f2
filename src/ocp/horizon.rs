//! What both solvers ([`super::Solver`], [`super::Condensed`]) hold of a problem: the stage
//! model from its start, the stage costs, the options, the control structure
//! u_k = θ_{piece(k)}, and the nominal and trial trajectories with the simulator that rolls
//! them out.

use super::line_search::{Feedback, Shooting, Simulator, Traj};
use super::options::OcpOptions;
use super::riccati::StageCost;
use super::stage::StageModel;
use crate::adjoint::{ControlMap, ControlProblem, Objective, Start};
use crate::error::{Error, OcpError, Result};

/// A problem over its horizon with its two trajectories (module docs).
#[derive(Clone, Debug)]
pub(crate) struct ControlHorizon {
    /// The stage maps and the start.
    pub model: StageModel,
    /// ℓ_k.
    pub cost: StageCost,
    pub opts: OcpOptions,
    /// N.
    pub steps: usize,
    /// The number of decisions θ.
    pub n_params: usize,
    /// θ index of stage k.
    pub piece: Vec<usize>,
    /// Whether stage k starts a piece (has a decision).
    pub free: Vec<bool>,
    /// The first stage of θ_j.
    pub theta_stage: Vec<usize>,
    /// The trajectory the model is built about, and the line search's trial.
    pub nominal: Traj,
    pub trial: Traj,
    /// The simulator of the rollouts.
    pub sim: Simulator,
    /// Rollouts of the nonlinear stage maps (nominal and trials).
    pub rollouts: usize,
}

impl ControlHorizon {
    /// Validates the options, the model (planar, free tip, a control node), the objective (one
    /// in Gauss-Newton form, [`Objective::gauss_newton`]) and the control map (per-step or piecewise
    /// constant), then the solver's own limits on (N, number of decisions) by `admit` before
    /// anything of the horizon's size is allocated; `solver` names the solver in the
    /// objective's error.
    pub fn new<P: ControlMap, O: Objective>(
        problem: &ControlProblem<P, O>,
        options: &OcpOptions,
        solver: &'static str,
        admit: fn(usize, usize) -> Result<()>,
    ) -> Result<Self> {
        options.validate()?;
        let steps = problem.steps();
        let h = problem.time_step();
        let model = StageModel::new(problem.chain(), h)?.with_start(problem.start());
        let rate = options.rate_penalty / h;
        let cost = StageCost::new(problem.objective(), steps, h, rate, solver)?;
        let n_params = problem.n_params();
        let structure = control_structure(&problem.controls(&ids(n_params))?, n_params)?;
        let theta_stage = (0..=steps).filter(|&k| structure.free[k]).collect();
        admit(steps, n_params)?;
        let n = model.n;
        Ok(ControlHorizon {
            sim: Simulator::new(&model)?,
            nominal: Traj::new(n, steps),
            trial: Traj::new(n, steps),
            model,
            cost,
            opts: options.clone(),
            steps,
            n_params,
            piece: structure.piece,
            free: structure.free,
            theta_stage,
            rollouts: 0,
        })
    }

    /// Simulates θ (projected onto the box) into the trial (`into_trial`) or the nominal and
    /// returns J.
    pub fn simulate(&mut self, theta: &[f64], into_trial: bool) -> Result<f64> {
        let (lo, hi) = (self.opts.lower, self.opts.upper);
        let shooting = Shooting {
            model: &self.model,
            cost: &self.cost,
            free: &self.free,
            lower: lo,
            upper: hi,
        };
        let out = if into_trial {
            &mut self.trial
        } else {
            &mut self.nominal
        };
        for k in 0..=self.steps {
            out.u[k] = theta[self.piece[k]].clamp(lo, hi);
        }
        self.rollouts += 1;
        self.sim.rollout(&shooting, None, out)?;
        Ok(out.cost)
    }

    /// Checks θ and makes it (projected onto the box) the nominal; returns J.
    ///
    /// # Errors
    /// [`Error::WrongLength`] or [`Error::NotFinite`] (`theta`) for a wrong length or a
    /// non-finite entry; the simulation's errors.
    pub fn set_point(&mut self, theta: &[f64]) -> Result<f64> {
        check_theta(theta, self.n_params)?;
        self.simulate(theta, false)
    }

    /// The closed-loop rollout u_k = clamp(ū_k + α k_k + K_k δz_k) about the nominal (gains
    /// `gain`, n_z per stage, and feedforward `ff`) into the trial; `false` if the simulation
    /// failed.
    pub fn closed_loop_trial(&mut self, gain: &[f64], ff: &[f64], alpha: f64, nz: usize) -> bool {
        let fb = Feedback {
            nominal: &self.nominal,
            gain,
            ff,
            alpha,
            nz,
        };
        let shooting = Shooting {
            model: &self.model,
            cost: &self.cost,
            free: &self.free,
            lower: self.opts.lower,
            upper: self.opts.upper,
        };
        self.rollouts += 1;
        self.sim
            .rollout(&shooting, Some(&fb), &mut self.trial)
            .is_ok()
    }

    /// The trial becomes the nominal.
    pub fn take_trial(&mut self) {
        std::mem::swap(&mut self.nominal, &mut self.trial);
    }

    /// θ of the nominal.
    pub fn theta(&self) -> Vec<f64> {
        self.theta_stage
            .iter()
            .map(|&k| self.nominal.u[k])
            .collect()
    }

    /// Moves the rollouts to another start (state, t₀, pending kick).
    pub fn set_start(&mut self, start: Option<&Start<f64, 2>>) {
        self.model.start = start.cloned();
        self.sim.stepper.set_start(start);
    }
}

/// θ has `n_params` finite entries ([`Error::WrongLength`] or [`Error::NotFinite`] naming
/// `theta` otherwise).
fn check_theta(theta: &[f64], n_params: usize) -> Result<()> {
    if theta.len() != n_params {
        return Err(Error::WrongLength {
            name: "theta",
            expected: n_params,
            got: theta.len(),
        });
    }
    if let Some(i) = theta.iter().position(|x| !x.is_finite()) {
        return Err(Error::NotFinite {
            name: "theta",
            index: i,
        });
    }
    Ok(())
}

/// θ_j = j, to read the control structure off the control map.
fn ids(n_params: usize) -> Vec<f64> {
    (0..n_params).map(|j| j as f64).collect()
}

/// The control structure u_k = θ_{piece(k)}.
struct ControlStructure {
    /// θ index of stage k.
    piece: Vec<usize>,
    /// Whether stage k starts a piece (has a decision).
    free: Vec<bool>,
}

/// The control structure of the controls `u` of θ_j = j: contiguous pieces 0, 1, …,
/// n_params − 1 (per-step, piecewise or constant); `free[k]` when stage k starts a piece.
fn control_structure(u: &[f64], n_params: usize) -> Result<ControlStructure> {
    let not_piecewise = || Error::from(OcpError::NotPiecewise);
    let (mut piece, mut free) = (Vec::with_capacity(u.len()), Vec::with_capacity(u.len()));
    for (k, &x) in u.iter().enumerate() {
        let j = x as usize;
        let prev = if k > 0 { piece[k - 1] } else { 0 };
        let ok = if k == 0 {
            j == 0
        } else {
            j == prev || j == prev + 1
        };
        if (j as f64 - x).abs() > 0.0 || !ok {
            return Err(not_piecewise());
        }
        free.push(k == 0 || j != prev);
        piece.push(j);
    }
    if piece.last().map(|p| p + 1) != Some(n_params) {
        return Err(not_piecewise());
    }
    Ok(ControlStructure { piece, free })
}

/// Threads for the stage derivatives when `OcpOptions::threads` is 0: rayon's pool with the
/// `parallel` feature, else 1.
pub(crate) fn available_threads() -> usize {
    #[cfg(feature = "parallel")]
    {
        rayon::current_num_threads()
    }
    #[cfg(not(feature = "parallel"))]
    {
        1
    }
}
