//! The Gauss-Newton QP of one iteration (module docs, "The step"): the warm face and the
//! primal-dual interior-point method whose Newton systems are Riccati passes, run over the
//! solver's parts — the QP iterate ([`super::iterate`]), the interior point
//! ([`super::interior`]) and the backward pass.

use super::horizon::ControlHorizon;
use super::interior::{Controls, StepLengths};
use super::iterate::{LinearModel, RolloutMode};
use super::solver::Solver;
use crate::error::Result;

/// The interior point stops at this fraction of its starting mean complementarity.
const GAP_FLOOR: f64 = 1e-15;
/// Interior-point iterations of one QP solve.
const MAX_QP_ITERS: usize = 40;

/// The controls at the model point δv of the horizon's nominal.
fn controls<'a, const DIM: usize>(hz: &'a ControlHorizon<DIM>, dv: &'a [f64]) -> Controls<'a> {
    Controls {
        nominal: &hz.nominal.u,
        nominal_x: &hz.nominal.ux,
        dv,
        free: &hz.free,
        lower: hz.opts.lower,
        upper: hz.opts.upper,
    }
}

/// One interior-point iteration's outcome: the new model value without the proximal term and
/// the step lengths taken.
struct InteriorStep {
    value: f64,
    lengths: StepLengths,
}

impl<const DIM: usize> Solver<DIM> {
    /// The linearised rollout of [`super::iterate::QpIterate::linearised`] on the current
    /// nominal, stored Jacobians and Riccati pass.
    fn linearised(&mut self, alpha: f64, mode: RolloutMode) -> f64 {
        let (steps, nz) = (self.horizon.steps, self.nz);
        let second = &self.second;
        let lm = LinearModel {
            horizon: &self.horizon,
            store: &self.store,
            gain: &self.riccati.gain,
            ff: &self.riccati.ff,
            second: second.exact.then(|| second.view(&[], steps, nz)),
        };
        self.qp.linearised(&lm, alpha, mode)
    }

    /// A closed-loop (or projected) rollout of the *linearised* dynamics from the model point
    /// with step length α, written to the iterate's trial; returns the model of J there
    /// without the proximal term. Needs every stage Jacobian in memory. For the direction
    /// alone see [`Solver::direction_rollout`].
    pub(super) fn linear_rollout(&mut self, alpha: f64, mode: RolloutMode) -> f64 {
        debug_assert!(
            mode != RolloutMode::Direction,
            "no value for a direction: direction_rollout"
        );
        self.linearised(alpha, mode)
    }

    /// The interior point's direction: the rollout of [`Solver::linear_rollout`] in
    /// [`RolloutMode::Direction`] mode at α = 1, without the model value (its caller gets the value
    /// from the Newton step, [`Solver::advance`]; with the exact model the value would read
    /// every H_k once more).
    fn direction_rollout(&mut self) {
        self.linearised(1.0, RolloutMode::Direction);
    }

    /// The QP's solution on a guessed face: the controls of the nominal that sit exactly on a
    /// bound stay there, the others take the exact Newton step of the model with them fixed
    /// (one Riccati pass). Accepted when the model's projected gradient at the result is at
    /// most `tol`, i.e. when the face was the right one (the usual case once the active set
    /// has settled: 1 pass instead of the interior point's 5–15). Returns the model value
    /// without the proximal term, or `None` (then [`Solver::solve_qp`] runs).
    pub(super) fn warm_qp(&mut self, tol: f64) -> Result<Option<f64>> {
        let (lo, hi) = (self.horizon.opts.lower, self.horizon.opts.upper);
        if !(lo.is_finite() || hi.is_finite()) {
            return Ok(None);
        }
        self.qp.at_nominal();
        let mut any = false;
        let m = self.ncu;
        for i in 0..(self.horizon.steps + 1) * m {
            let u = self.horizon.nominal.control(i / m, i % m);
            self.qp.active[i] = self.horizon.free[i / m] && (u <= lo || u >= hi);
            self.qp.fixed[i] = 0.0;
            any |= self.qp.active[i];
        }
        if !any || !self.sweep(true)? {
            return Ok(None);
        }
        let q_plain = self.linear_rollout(1.0, RolloutMode::ClosedLoop);
        self.qp.take_trial();
        // The model gradient at the new point (the gains of the Riccati pass are kept).
        self.qp.active.fill(false);
        self.sweep(false)?;
        if !(q_plain.is_finite() && self.projected_norm() <= tol) {
            return Ok(None);
        }
        self.qp.store_feedforward(&self.riccati.gain);
        Ok(Some(q_plain))
    }

    /// Solves the box-constrained Gauss-Newton QP of the nominal (with the proximal weight
    /// `self.prox`) by a primal-dual interior-point method whose Newton systems are Riccati
    /// passes (Rao, Wright, Rawlings 1998; the scheme of HPIPM): with slacks s = v − lo,
    /// s' = hi − v and multipliers z, z′ ≥ 0, each iteration solves the LQR with
    /// Q_uu += z/s + z′/s′ and l_u += −τ/s + τ/s′ (τ = σ·mean complementarity, σ = 0.1), steps
    /// to 99.5 % of the distance to the boundary, and stops when the model's projected
    /// gradient is at most `tol`. The iterates stay strictly inside the box; the solution is
    /// left in `dv`, `dz` with the gains of the last pass (controls on a bound get K ≈ 0 from
    /// their large barrier curvature). Returns the model value without the proximal term, or
    /// `None` if a pass broke down.
    pub(super) fn solve_qp(&mut self, tol: f64) -> Result<Option<f64>> {
        let mut q_plain = self.interior_start()?;
        let steps = self.horizon.steps;
        let (lo, hi) = (self.horizon.opts.lower, self.horizon.opts.upper);
        let nb = (0..=steps).filter(|&k| self.horizon.free[k]).count()
            * self.ncu
            * (usize::from(lo.is_finite()) + usize::from(hi.is_finite()));
        let mut sigma = 0.1;
        let mut gap0 = 0.0;
        for it in 0..MAX_QP_ITERS {
            // After the first iteration `riccati.grad` is the update of [`Solver::advance`];
            // a solution is accepted on a swept gradient only.
            let mut pg = self.projected_norm();
            if it > 0 && pg <= tol && q_plain < self.horizon.nominal.cost {
                self.sweep(false)?;
                pg = self.projected_norm();
            }
            let gap = self.complementarity();
            let mean_gap = if nb > 0 { gap / nb as f64 } else { 0.0 };
            if it == 0 {
                gap0 = mean_gap;
            }
            // Converged, or at the floating-point floor of the complementarity: 10⁻¹⁵ of the
            // start's, where the barrier terms z/s reach the limits of f64 (row 8 of Table 3.4
            // went on to NaN at 10⁻¹⁹ of it; the model's projected gradient had stalled at
            // its round-off three passes earlier).
            // A solution must also lower the model below its value at δ = 0 (J itself): on
            // long horizons (N = 10⁵, 40 % of the controls on a bound, curvature ρh = 10⁻⁴ along
            // the flat directions) the projected-gradient test alone was met by points above it,
            // whose steps no line search could accept (6 iterations of 10 failed rollouts each).
            if (it > 0 && pg <= tol && q_plain < self.horizon.nominal.cost)
                || !(mean_gap.is_finite())
                || (nb > 0 && mean_gap <= GAP_FLOOR * gap0)
            {
                break;
            }
            let Some(step) = self.interior_step(sigma * mean_gap, q_plain)? else {
                return Ok(None);
            };
            q_plain = step.value;
            let StepLengths { primal, dual } = step.lengths;
            sigma = if primal.min(dual) > 0.9 { 0.01 } else { 0.1 };
        }
        let finite = self.qp.dv.iter().chain(&self.qp.dz).all(|x| x.is_finite());
        if !(q_plain.is_finite() && finite) {
            return Ok(None);
        }
        self.snap_to_bounds();
        self.qp.store_feedforward(&self.riccati.gain);
        Ok(Some(q_plain))
    }

    /// The complementarity gap of the interior point at the model point.
    pub(super) fn complementarity(&self) -> f64 {
        self.ip
            .complementarity(&controls(&self.horizon, &self.qp.dv))
    }

    /// One interior-point iteration with barrier parameter τ from the current point (model
    /// value `q_plain` without the proximal term): the Riccati pass with the barrier terms, the
    /// direction Δ (one linearised rollout), the step lengths to the boundary, and the new
    /// point with its model gradient and value ([`Solver::advance`]) and multipliers. Returns
    /// the new model value and the primal and dual step lengths, or `None` if some stage QP
    /// was unbounded.
    fn interior_step(&mut self, tau: f64, q_plain: f64) -> Result<Option<InteriorStep>> {
        self.ip
            .barrier_terms(&controls(&self.horizon, &self.qp.dv), tau);
        self.ip.on = true;
        let ok = self.sweep(true);
        self.ip.on = false;
        if !ok? {
            return Ok(None);
        }
        self.direction_rollout();
        let c = controls(&self.horizon, &self.qp.dv);
        let lengths = self.ip.fraction_to_boundary(&c, &self.qp.dir, tau);
        let value = self.advance(lengths.primal, q_plain);
        let c = controls(&self.horizon, &self.qp.dv);
        self.ip.step_multipliers(&c, lengths.dual);
        Ok(Some(InteriorStep { value, lengths }))
    }

    /// Moves the model point to δ + αΔ (Δ = the Direction rollout's `dv_t − dv`,
    /// `dz_t − dz`: the state's response is linear in the decisions, and no control meets a
    /// bound for α within the fraction to the boundary, so this is the closed-loop rollout at
    /// α without one), with its model gradient and value, and returns that value q(α) without
    /// the proximal term.
    ///
    /// Gradient: the Riccati pass at δ left G = g(δ) + l_b in `riccati.grad` (l_b = −τ/s + τ/s′
    /// the barrier gradient it adds to l_u), and Δ is the Newton step of the model plus the
    /// barrier's quadratic l_bΔv + ½ q_bΔv² (q_b = z/s + z′/s′): the gradient of that sum
    /// vanishes at δ + Δ, so g(δ + Δ) = −l_b − q_bΔv. The model's gradient is affine in the
    /// decisions (a quadratic model over linear dynamics), hence
    /// g(δ + αΔ) = (1 − α) g(δ) + α g(δ + Δ) = (G − l_b) − α (G + q_bΔv).
    /// Value: q is quadratic along Δ with slopes s₀ = (g(δ) − μδv)·Δv at α = 0 and
    /// s₁ = (g(δ + Δ) − μ(δv + Δv))·Δv at α = 1 (μ the proximal weight, which g includes and q
    /// does not), so q(α) = q(0) + α s₀ + ½ α² (s₁ − s₀).
    ///
    /// No backward sweep and no second rollout through the Jacobians (at N = 10⁴ each streams
    /// the 32 MB of A_k and, for the exact model, 35 MB of H_k from memory): exact up to the
    /// Riccati solve's round-off; [`Solver::solve_qp`] confirms a solution with a swept
    /// gradient.
    fn advance(&mut self, alpha: f64, q0: f64) -> f64 {
        let (mut s0, mut s1) = (0.0, 0.0);
        let qp = &mut self.qp;
        let m = self.ncu;
        for i in 0..(self.horizon.steps + 1) * m {
            if self.horizon.free[i / m] {
                let (g, dv, step) = (self.riccati.grad[i], qp.dv[i], qp.dir[i]);
                let (lb, qb) = (self.ip.lu[i], self.ip.quu[i]);
                let g1 = -lb - qb * step;
                s0 += (g - lb - self.prox * dv) * step;
                s1 += (g1 - self.prox * (dv + step)) * step;
                self.riccati.grad[i] = (g - lb) - alpha * (g + qb * step);
            }
        }
        for (x, t) in qp.dv.iter_mut().zip(&qp.dv_t) {
            *x += alpha * (t - *x);
        }
        for (x, t) in qp.dz.iter_mut().zip(&qp.dz_t) {
            *x += alpha * (t - *x);
        }
        q0 + alpha * s0 + 0.5 * alpha * alpha * (s1 - s0)
    }

    /// The interior point's start: the nominal moved κ = 1 % of the box width inside (strictly
    /// interior), its linearised rollout, the model gradient there (one Riccati sweep) and
    /// centred bound multipliers: every finite bound's complementarity s·z equal to
    /// τ₀ = κ max |g|, i.e. z = τ₀/max(s, κ) (0 for an infinite bound), so a control a width
    /// from its bound starts with a small multiplier and one pushed to κ from it with max |g|.
    /// Returns the model value there without the proximal term.
    ///
    /// Centred, as interior-point methods start (Nocedal and Wright, *Numerical Optimization*,
    /// §14.2; HPIPM's μ₀): the earlier uniform z = max |g| left products s·z spread by the
    /// slacks (up to 100× here), which the path-following steps spent their first iterations
    /// evening out. Measured (`long_horizon`, Riccati passes and time against the uniform
    /// start): N = 10³ 36 passes instead of 48, 10⁴ 37 instead of 42, 10⁵ 39 instead of 53
    /// (farm-bench wall ratio 0.86), `--curvature exact` 72 instead of 106, `--rate 0.01` 19
    /// instead of 40; the outer iterations change by −5 to +2 across the variants (the
    /// inexact QP solutions differ), one more at N = 10³–10⁴, where time is unchanged or
    /// lower (farm-bench 0.94 and 1.00).
    pub(super) fn interior_start(&mut self) -> Result<f64> {
        let (lo, hi) = (self.horizon.opts.lower, self.horizon.opts.upper);
        let width = if (hi - lo).is_finite() { hi - lo } else { 1.0 };
        let kappa = 1e-2 * width;
        let m = self.ncu;
        for i in 0..(self.horizon.steps + 1) * m {
            let u = self.horizon.nominal.control(i / m, i % m);
            self.qp.dir[i] = if self.horizon.free[i / m] {
                let (l, h) = (lo - u, hi - u);
                let c = if h - l > 2.0 * kappa {
                    0.0f64.clamp(l + kappa, h - kappa)
                } else {
                    0.5 * (l + h)
                };
                if c.is_finite() {
                    c
                } else {
                    0.0
                }
            } else {
                0.0
            };
        }
        self.qp.at_nominal();
        let q_plain = self.linear_rollout(1.0, RolloutMode::Projected);
        self.qp.take_trial();
        self.qp.active.fill(false);
        self.sweep(false)?;
        let gscale = self
            .riccati
            .grad
            .iter()
            .fold(0.0f64, |m, g| m.max(g.abs()))
            .max(1e-12);
        let tau0 = kappa * gscale;
        self.ip
            .centre(&controls(&self.horizon, &self.qp.dv), tau0, kappa);
        Ok(q_plain)
    }

    /// Controls the interior point left within 10⁻⁶ of the box width of a bound whose
    /// multiplier exceeds the slack go exactly onto the bound, without feedback: bounds are then
    /// met with equality, not approached.
    fn snap_to_bounds(&mut self) {
        let (lo, hi) = (self.horizon.opts.lower, self.horizon.opts.upper);
        let width = if (hi - lo).is_finite() { hi - lo } else { 1.0 };
        let (nz, m) = (self.nz, self.ncu);
        for i in 0..(self.horizon.steps + 1) * m {
            if !self.horizon.free[i / m] {
                continue;
            }
            let snap = self
                .ip
                .snap(&controls(&self.horizon, &self.qp.dv), i, width);
            if let Some(b) = snap {
                self.qp.dv[i] = b - self.horizon.nominal.control(i / m, i % m);
                self.riccati.gain[i * nz..(i + 1) * nz].fill(0.0);
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::super::iterate::RolloutMode;
    use super::super::{OcpOptions, Solver};
    use super::InteriorStep;
    use crate::{catalogue, BendingObjective, ControlProblem, Parametrisation, PerStepControl};

    /// The new iterate of [`Solver::advance`] against the costate sweep and the linearised
    /// rollout at the same point (the references: the discrete adjoint of the linearised model
    /// and the model's value summed stage by stage), over the first interior-point iterations
    /// of a Gauss-Newton QP on the long-horizon scene shortened to N = 80 with |u| ≤ 0.5 N,
    /// where the QP's steps reach the bounds (some shortened by the fraction to the boundary).
    /// Agreement to the round-off of the Riccati solve: 10⁻¹⁰ of the gradient's largest entry,
    /// 10⁻¹² of the value.
    #[test]
    fn interior_step_gradient_and_value_equal_the_swept_ones() {
        let steps = 80;
        let mut scene = catalogue::long_horizon();
        scene.time.steps = steps;
        if let Some(c) = scene.control.as_mut() {
            c.values = vec![0.0; steps + 1];
        }
        let map = Parametrisation::PerStep(PerStepControl { steps });
        let objective = BendingObjective::summed_moment().with_effort(0.01);
        let problem = ControlProblem::builder(&scene)
            .map(map)
            .objective(objective)
            .build_in::<2>()
            .unwrap();
        let opts = OcpOptions::default().with_bound(0.5);
        let mut s = Solver::new(&problem, &opts).unwrap();
        s.set_point(&vec![0.0; steps + 1]).unwrap();
        s.costate().unwrap();
        s.prox = 1e-6 * s.quu_scale;
        let mut q = s.interior_start().unwrap();
        let (mut sigma, mut shortened) = (0.1, 0);
        for _ in 0..6 {
            let tau = sigma * s.complementarity() / (2 * (steps + 1)) as f64;
            let InteriorStep { value, lengths } =
                s.interior_step(tau, q).unwrap().expect("bounded QP");
            let (q_next, ap, ad) = (value, lengths.primal, lengths.dual);
            q = q_next;
            shortened += usize::from(ap < 1.0);
            sigma = if ap.min(ad) > 0.9 { 0.01 } else { 0.1 };
            let updated = s.riccati.grad.clone();
            s.sweep(false).unwrap();
            let scale = updated.iter().fold(0.0f64, |m, g| m.max(g.abs()));
            let err = updated
                .iter()
                .zip(&s.riccati.grad)
                .fold(0.0f64, |m, (a, b)| m.max((a - b).abs()));
            assert!(
                scale > 0.0 && err <= 1e-10 * scale,
                "error {err:e}, scale {scale:e}"
            );
            let q_rollout = s.linear_rollout(0.0, RolloutMode::Projected);
            assert!(
                (q - q_rollout).abs() <= 1e-12 * q_rollout.abs(),
                "{q} against {q_rollout}"
            );
        }
        assert!(shortened > 0, "no step was shortened: α < 1 untested");
        let on_bound = (0..=steps)
            .filter(|&k| (s.horizon.nominal.u[k] + s.qp.dv[k]).abs() > 0.45)
            .count();
        assert!(
            on_bound > 0,
            "the bounds never came near: the test tests nothing"
        );
    }
}
