//! The receding-horizon plan of a scene whose control is the thrust on the vessel
//! ([`crate::scene::Thrust`]): the thrusters as the plant applies them ([`Actuator`]), and the
//! plan's problem over the horizon's commands ([`ThrustPlan`]), solved with the exact adjoint
//! gradient by a bounded L-BFGS with a fixed iteration budget ([`crate::mpc`], "MPC through the
//! vessel's thrust").

use crate::adjoint::{BendingObjective, ControlProblem, Objective, PerStepControl};
use crate::error::Result;
use crate::optimize::OptimProblem;

/// The thrusters between the command and the thrust (the plant's [`super::Plant`], "The vessel
/// under thrust"): the thrust at a step is the command clipped to ±F_max, moved from the
/// thrust of the step before by at most Ḟ_max h,
/// ```text
/// c = clamp(command, −F_max, F_max),   F_i = F_{i−1} + clamp(c − F_{i−1}, −Ḟ_max h, Ḟ_max h).
/// ```
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Actuator {
    /// F_max \[N\].
    pub bound: f64,
    /// Ḟ_max h \[N per step\].
    pub change: f64,
}

impl Actuator {
    /// (F_i, whether F_i reached the clipped command c) from F_{i−1} and the command; ties go
    /// to the command, as in the plant.
    pub(super) fn step(&self, prev: f64, command: f64) -> (f64, bool) {
        let c = command.clamp(-self.bound, self.bound);
        let d = c - prev;
        if d > self.change {
            (prev + self.change, false)
        } else if d < -self.change {
            (prev - self.change, false)
        } else {
            (c, true)
        }
    }
}

/// The plan of one re-plan as an [`OptimProblem`] over the commands θ_0..θ_{P−1} of the
/// horizon's P control intervals (|θ_j| ≤ F_max): the per-step thrusts are the actuator's
/// response to the commands held over their intervals,
/// ```text
/// u_i = F_i (i = lead..N_p) from F_{lead−1} = `before`,   command of step i: θ_{min((i − lead)/m, P − 1)},
/// ```
/// with the first `lead` steps' thrusts fixed (u_0 = the thrust already applied when the plan
/// starts one step back, [`crate::mpc`] "MPC through the vessel's thrust"), and
/// ```text
/// J(θ) = J_u(u(θ)) + σ Σ_j (θ_j − u_{e(j)})²
/// ```
/// where J_u is the moment objective with its effort term over the horizon's steps (the
/// [`ControlProblem`]), u_{e(j)} the thrust at the last step of interval j, and σ > 0 a weight.
/// The penalty vanishes whenever a command is reached within its interval, and a command the
/// thrust cannot reach (the rate clips the whole interval) can be replaced by the thrust it
/// ends at without changing one thrust: it leaves the optimal thrusts unchanged and removes
/// the flat directions along which J_u does not depend on an unreachable command (where its
/// gradient is 0). The gradient: ∇_u J_u by the discrete adjoint, then the transpose of the
/// actuator's map (∂u_i/∂θ_j = 1 where the command is reached, ∂u_i/∂u_{i−1} = 1 where the rate
/// clips; exact wherever no clip switches, as the PD law's clamp), plus the penalty's terms.
pub(crate) struct ThrustPlan<'a, O = BendingObjective> {
    /// The moment objective over the per-step thrusts of the horizon (its start set).
    pub problem: &'a ControlProblem<PerStepControl, O>,
    /// The thrusters.
    pub actuator: Actuator,
    /// Steps m of a control interval.
    pub m: usize,
    /// Steps whose thrust is fixed at `before` (0 or 1).
    pub lead: usize,
    /// The thrust before the first planned step \[N\].
    pub before: f64,
    /// The number of commands P.
    pub pieces: usize,
    /// The penalty's weight σ.
    pub sigma: f64,
}

impl<O: Objective> ThrustPlan<'_, O> {
    fn steps(&self) -> usize {
        self.problem.steps()
    }

    /// The command's interval of plan step i ≥ `lead`.
    fn piece(&self, i: usize) -> usize {
        ((i - self.lead) / self.m).min(self.pieces - 1)
    }

    /// The last step of interval j (the horizon's last for the last interval).
    fn end_of(&self, j: usize) -> usize {
        if j + 1 == self.pieces {
            self.steps()
        } else {
            self.lead + (j + 1) * self.m - 1
        }
    }

    /// The per-step thrusts u_0..u_{N_p} of the commands θ and, per step, whether its command
    /// was reached (type docs).
    pub(super) fn thrusts(&self, theta: &[f64]) -> (Vec<f64>, Vec<bool>) {
        let n = self.steps();
        let mut u = vec![self.before; n + 1];
        let mut reached = vec![false; n + 1];
        let mut prev = if self.lead == 0 { 0.0 } else { self.before };
        for i in self.lead..=n {
            let (f, r) = self.actuator.step(prev, theta[self.piece(i)]);
            u[i] = f;
            reached[i] = r;
            prev = f;
        }
        (u, reached)
    }

    /// The command penalty σ Σ_j (θ_j − u_{e(j)})² of J (type docs).
    pub(super) fn penalty(&self, theta: &[f64], u: &[f64]) -> f64 {
        (0..self.pieces)
            .map(|j| (theta[j] - u[self.end_of(j)]).powi(2))
            .sum::<f64>()
            * self.sigma
    }
}

impl<O: Objective> OptimProblem for ThrustPlan<'_, O> {
    fn n_params(&self) -> usize {
        self.pieces
    }

    fn value(&self, theta: &[f64]) -> Result<f64> {
        let (u, _) = self.thrusts(theta);
        Ok(self.problem.value(&u)? + self.penalty(theta, &u))
    }

    fn value_and_gradient(&self, theta: &[f64]) -> Result<(f64, Vec<f64>)> {
        let (u, reached) = self.thrusts(theta);
        let (j, mut gu) = self.problem.value_and_gradient(&u)?;
        let mut g = vec![0.0; self.pieces];
        for (jj, gj) in g.iter_mut().enumerate() {
            let e = self.end_of(jj);
            let r = 2.0 * self.sigma * (theta[jj] - u[e]);
            *gj += r;
            gu[e] -= r;
        }
        // The actuator's transpose, from the last step back.
        let mut carry = 0.0;
        for i in (self.lead..=self.steps()).rev() {
            let ubar = gu[i] + carry;
            if reached[i] {
                g[self.piece(i)] += ubar;
                carry = 0.0;
            } else {
                carry = ubar;
            }
        }
        Ok((j + self.penalty(theta, &u), g))
    }

    fn controls(&self, theta: &[f64]) -> Option<Result<Vec<f64>>> {
        Some(Ok(self.thrusts(theta).0))
    }

    /// F_max for every command: how far a command may sensibly move.
    fn param_scales(&self) -> Vec<f64> {
        vec![self.actuator.bound; self.pieces]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The actuator clips the amplitude, then the change; ties reach the command.
    #[test]
    fn actuator_clips_amplitude_then_rate() {
        let a = Actuator {
            bound: 2.0,
            change: 0.5,
        };
        assert_eq!(a.step(0.0, 5.0), (0.5, false));
        assert_eq!(a.step(1.8, 5.0), (2.0, true));
        assert_eq!(a.step(0.0, 0.5), (0.5, true));
        assert_eq!(a.step(0.0, -0.2), (-0.2, true));
        assert_eq!(a.step(-1.0, -5.0), (-1.5, false));
    }
}
