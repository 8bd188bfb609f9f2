//! The size limits of a scene (docs/scene-format.md, "Size limits"): the most pendulums and steps,
//! the largest step number, and the memory budget of a stored trajectory, checked before anything
//! of size n or N is allocated.

use super::{Scene, SceneError, Support};
use crate::base::StepStats;
use crate::input::human_bytes;

/// Largest number of pendulums n a scene may have.
pub const MAX_PENDULUMS: usize = 1_000_000;
/// Largest number of time steps N a scene may have.
pub const MAX_STEPS: usize = 10_000_000;
/// Memory budget of a stored trajectory: 8 GiB, a third of a 24 GiB machine (the rest is left
/// for the operating system, the optimiser's vectors and the output). It is checked where a
/// trajectory is stored, not when a scene is read (a streamed run, [`crate::simulate_streaming`],
/// stores none): a scene whose planar `f64` trajectory ([`trajectory_bytes`]) needs more is
/// refused by [`Scene::check_stored_trajectory`] naming `time.steps`, which
/// [`crate::simulate()`] and [`crate::ControlProblem`] call, and
/// [`crate::simulate::simulate_chain`] checks every scalar type and dimension against the same
/// budget and allocates fallibly.
pub const MAX_TRAJECTORY_BYTES: u64 = 8 << 30;
/// Largest step number h²·k/(m·l²) (springs) and h²·F·l/(m·l²) (loads) a scene may have: the
/// dimensionless angle one step turns a pendulum through. RATTLE resolves the motion only when
/// it is well below 1 (its Newton solve fails long before 10¹²); the limit keeps every quantity
/// the step forms far inside the `f64` range, so a valid scene cannot overflow.
pub const MAX_STEP_NUMBER: f64 = 1e12;

/// Number of constraints of a planar chain with this support: one length constraint per pendulum,
/// plus the tip constraint of fixed-fixed and pinned-pinned beams (also in the reaction-force
/// variant, where it is the moving target).
fn n_constraints(n: usize, support: Support) -> usize {
    n + usize::from(support.holds_tip())
}

/// The size limits ([`MAX_PENDULUMS`], [`MAX_STEPS`]), checked before anything of size n or N is
/// allocated. The stored trajectory's budget is [`check_trajectory_budget`]'s, for runs that store
/// one.
pub(super) fn check_size(n: usize, steps: usize) -> Result<(), SceneError> {
    if n == 0 {
        return Err(SceneError::invalid(
            "beam.pendulums",
            "must be at least 1, got 0",
        ));
    }
    if n > MAX_PENDULUMS {
        return Err(SceneError::invalid(
            "beam.pendulums",
            format!("at most {MAX_PENDULUMS} pendulums are supported, got {n}"),
        ));
    }
    if steps == 0 {
        return Err(SceneError::invalid(
            "time.steps",
            "must be at least 1, got 0",
        ));
    }
    if steps > MAX_STEPS {
        return Err(SceneError::invalid(
            "time.steps",
            format!("at most {MAX_STEPS} steps are supported, got {steps}"),
        ));
    }
    Ok(())
}

/// The stored trajectory's budget: the planar `f64` trajectory of N = `steps` steps of n
/// pendulums ([`trajectory_bytes`]) must fit [`MAX_TRAJECTORY_BYTES`], else an error naming
/// `time.steps`, the bytes, the limit and the largest N that fits.
pub(super) fn check_trajectory_budget(
    n: usize,
    steps: usize,
    support: Support,
) -> Result<(), SceneError> {
    let nc = n_constraints(n, support);
    let bytes = trajectory_bytes::<f64, 2>(n, nc, steps);
    if bytes > MAX_TRAJECTORY_BYTES {
        let max_steps = max_trajectory_steps::<f64, 2>(n, nc);
        return Err(SceneError::invalid(
            "time.steps",
            format!(
                "the trajectory of N = {steps} steps of n = {n} pendulums needs {} (q, p, λ, μ \
                 per node and time), over the memory limit of {}; reduce `time.steps` (at most \
                 {max_steps} for this beam) or `beam.pendulums`",
                human_bytes(bytes),
                human_bytes(MAX_TRAJECTORY_BYTES)
            ),
        ));
    }
    Ok(())
}

impl Scene {
    /// Whether a run that stores this scene's trajectory may: its planar `f64` trajectory
    /// ([`trajectory_bytes`]: q, p, λ, μ per node and time, (N + 1)(6n + 4)·8 bytes and more)
    /// fits [`MAX_TRAJECTORY_BYTES`]. [`crate::simulate()`] and its variants and
    /// [`crate::ControlProblem`] (the adjoint and the optimisers) check it before anything of
    /// size N is allocated; a streamed run ([`crate::simulate_streaming`],
    /// [`crate::moment_history`], `chainbeam simulate`) stores no trajectory and does not.
    ///
    /// # Errors
    /// [`SceneErrorKind::InvalidValue`](super::SceneErrorKind::InvalidValue) naming `time.steps`, with the bytes needed, the limit and
    /// the largest N that fits this beam.
    pub fn check_stored_trajectory(&self) -> Result<(), SceneError> {
        check_trajectory_budget(self.n(), self.time.steps, self.beam.support)
    }
}

/// Bytes [`crate::simulate::simulate_chain`] stores for a trajectory of N = `steps` steps of n pendulums with
/// `n_constraints` multipliers in scalar `D` and dimension `DIM`: per time t_k (N + 1 of them) q
/// and p (2·n·DIM scalars), λ and μ (2·n_c scalars), energy, moment, control and tip target
/// (4 scalars; 6 in the spatial model, with M₀ₓ and u_x); per step its [`StepStats`]; plus the n lengths. Saturates at `u64::MAX`.
pub fn trajectory_bytes<D, const DIM: usize>(n: usize, n_constraints: usize, steps: usize) -> u64 {
    let per_time = per_time_bytes::<D, DIM>(n, n_constraints);
    let total = (steps as u128 + 1) * per_time
        + steps as u128 * std::mem::size_of::<StepStats>() as u128
        + n as u128 * std::mem::size_of::<f64>() as u128;
    u64::try_from(total).unwrap_or(u64::MAX)
}

fn per_time_bytes<D, const DIM: usize>(n: usize, n_constraints: usize) -> u128 {
    let d = std::mem::size_of::<D>() as u128;
    let extra = if DIM == 3 { 2 } else { 0 };
    (2 * n as u128 * DIM as u128 + 2 * n_constraints as u128 + 4 + extra) * d
}

/// The largest N whose trajectory ([`trajectory_bytes`]) fits [`MAX_TRAJECTORY_BYTES`].
pub fn max_trajectory_steps<D, const DIM: usize>(n: usize, n_constraints: usize) -> usize {
    let per_step =
        per_time_bytes::<D, DIM>(n, n_constraints) + std::mem::size_of::<StepStats>() as u128;
    let fixed = per_time_bytes::<D, DIM>(n, n_constraints) + 8 * n as u128;
    let budget = MAX_TRAJECTORY_BYTES as u128;
    if budget < fixed {
        return 0;
    }
    usize::try_from((budget - fixed) / per_step).unwrap_or(usize::MAX)
}
