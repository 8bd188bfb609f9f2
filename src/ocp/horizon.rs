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

/// A problem over its horizon with its two trajectories (module docs), in the planar or the
/// spatial model. A 2-axis control has θ = (θ_x; θ_z) as [`ControlProblem`] (`axes` = 2): the
/// decision of piece j is θ_j for u_z along z with one axis, θ_{m+j} (u_z) and θ_j (u_x) with two.
#[derive(Clone, Debug)]
pub(crate) struct ControlHorizon<const DIM: usize = 2> {
    /// The stage maps and the start.
    pub model: StageModel<DIM>,
    /// ℓ_k.
    pub cost: StageCost,
    pub opts: OcpOptions,
    /// N.
    pub steps: usize,
    /// The number of decisions θ (every axis).
    pub n_params: usize,
    /// Control axes: 1 (along z) or 2 ((u_x, u_z), spatial model).
    pub axes: usize,
    /// θ index of stage k (of the z component; its x component's is θ index − m).
    pub piece: Vec<usize>,
    /// Whether stage k starts a piece (has a decision).
    pub free: Vec<bool>,
    /// The first stage of each piece j (θ_j, and θ_{m+j} with two axes).
    pub theta_stage: Vec<usize>,
    /// The trajectory the model is built about, and the line search's trial.
    pub nominal: Traj<DIM>,
    pub trial: Traj<DIM>,
    /// The simulator of the rollouts.
    pub sim: Simulator<DIM>,
    /// Rollouts of the nonlinear stage maps (nominal and trials).
    pub rollouts: usize,
}

impl<const DIM: usize> ControlHorizon<DIM> {
    /// Validates the options, the model (free tip, a control node), the objective (one
    /// in Gauss-Newton form, [`Objective::gauss_newton`]; in the spatial model one of |M₀|
    /// alone, [`StageCost::check_isotropic`]) and the control map (per-step or piecewise
    /// constant), then the solver's own limits on (N, number of decisions) by `admit` before
    /// anything of the horizon's size is allocated; `solver` names the solver in the
    /// objective's error.
    pub(super) fn new<P: ControlMap, O: Objective>(
        problem: &ControlProblem<P, O, DIM>,
        options: &OcpOptions,
        solver: &'static str,
        admit: fn(usize, usize) -> Result<()>,
    ) -> Result<Self> {
        options.validate()?;
        let steps = problem.steps();
        let h = problem.time_step();
        let two_axis = problem.is_two_axis();
        let model = StageModel::new(problem.chain(), h)?
            .with_start(problem.start())
            .with_axes(two_axis, steps);
        let rate = options.rate_penalty / h;
        let cost = StageCost::new(problem.objective(), steps, h, rate, solver)?;
        if DIM == 3 {
            cost.check_isotropic(problem.objective(), solver)?;
        }
        let n_params = problem.n_params();
        let axes = if two_axis { 2 } else { 1 };
        let m = n_params / axes;
        // θ_j = j on every axis: the controls' z components give the pieces.
        let ids: Vec<f64> = (0..n_params).map(|j| (j % m) as f64).collect();
        let structure = control_structure(&problem.controls(&ids)?, m)?;
        let theta_stage = (0..=steps).filter(|&k| structure.free[k]).collect();
        admit(steps, n_params)?;
        let n = model.n;
        Ok(ControlHorizon {
            sim: Simulator::new(&model)?,
            nominal: Traj::new(n, steps, two_axis),
            trial: Traj::new(n, steps, two_axis),
            model,
            cost,
            opts: options.clone(),
            steps,
            n_params,
            axes,
            piece: structure.piece,
            free: structure.free,
            theta_stage,
            rollouts: 0,
        })
    }

    /// Decisions per axis m.
    #[inline]
    pub(super) fn pieces(&self) -> usize {
        self.n_params / self.axes
    }

    /// The θ index of stage k's control along `axis` (0: z, 1: x of a 2-axis control).
    #[inline]
    pub(super) fn theta_index(&self, k: usize, axis: usize) -> usize {
        let j = self.piece[k];
        match (self.axes, axis) {
            (2, 0) => self.pieces() + j,
            _ => j,
        }
    }

    /// The stage and control axis (0: z, 1: x of a 2-axis control) of θ_i: the decision
    /// k m + axis of the Riccati solver (m = `axes`).
    #[inline]
    pub(super) fn decision(&self, i: usize) -> (usize, usize) {
        let m = self.pieces();
        if self.axes == 2 && i < m {
            (self.theta_stage[i], 1)
        } else {
            (self.theta_stage[i % m], 0)
        }
    }

    /// Simulates θ (projected onto the box) into the trial (`into_trial`) or the nominal and
    /// returns J.
    pub(super) fn simulate(&mut self, theta: &[f64], into_trial: bool) -> Result<f64> {
        let (lo, hi) = (self.opts.lower, self.opts.upper);
        for k in 0..=self.steps {
            let u = theta[self.theta_index(k, 0)].clamp(lo, hi);
            let ux = (self.axes == 2).then(|| theta[self.theta_index(k, 1)].clamp(lo, hi));
            let out = if into_trial {
                &mut self.trial
            } else {
                &mut self.nominal
            };
            out.u[k] = u;
            if let Some(ux) = ux {
                out.ux[k] = ux;
            }
        }
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
        self.rollouts += 1;
        self.sim.rollout(&shooting, None, out)?;
        Ok(out.cost)
    }

    /// Checks θ and makes it (projected onto the box) the nominal; returns J.
    ///
    /// # Errors
    /// [`Error::WrongLength`] or [`Error::NotFinite`] (`theta`) for a wrong length or a
    /// non-finite entry; the simulation's errors.
    pub(super) fn set_point(&mut self, theta: &[f64]) -> Result<f64> {
        check_theta(theta, self.n_params)?;
        self.simulate(theta, false)
    }

    /// The closed-loop rollout u_k = clamp(ū_k + α k_k + K_k δz_k) about the nominal (gains
    /// `gain`, n_z per stage, and feedforward `ff`) into the trial; `false` if the simulation
    /// failed.
    pub(super) fn closed_loop_trial(
        &mut self,
        gain: &[f64],
        ff: &[f64],
        alpha: f64,
        nz: usize,
    ) -> bool {
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
    pub(super) fn take_trial(&mut self) {
        std::mem::swap(&mut self.nominal, &mut self.trial);
    }

    /// θ_i of the nominal.
    #[inline]
    pub(super) fn theta_at(&self, i: usize) -> f64 {
        let m = self.pieces();
        if self.axes == 2 && i < m {
            self.nominal.ux[self.theta_stage[i]]
        } else {
            self.nominal.u[self.theta_stage[i % m]]
        }
    }

    /// θ of the nominal.
    pub(super) fn theta(&self) -> Vec<f64> {
        (0..self.n_params).map(|i| self.theta_at(i)).collect()
    }

    /// Moves the rollouts to another start (state, t₀, pending kick).
    pub(super) fn set_start(&mut self, start: Option<&Start<f64, DIM>>) {
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
