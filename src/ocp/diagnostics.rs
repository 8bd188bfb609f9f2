//! Linearisation diagnostics (the tests' handles): the costate gradient, the stage Jacobians
//! and the stage map in tangent coordinates, one Gauss-Newton step and the dense Gauss-Newton
//! Hessian it is checked against.

use faer::Mat;

use super::iterate::RolloutMode;
use super::riccati::StageJacobians;
use super::solver::Solver;
use super::stage::{tangent, JacobiansMut, StageAt, StagePoint};
use crate::error::{Error, OcpError, Result};

impl<const DIM: usize> Solver<DIM> {
    /// ∇J(θ) at the nominal by the costate sweep of the backward pass (exact: the discrete
    /// adjoint in tangent coordinates, planar or spatial).
    pub fn gradient(&mut self) -> Result<Vec<f64>> {
        self.costate()?;
        Ok(self.theta_gradient())
    }
}

impl Solver {
    /// A_k (2n × 2n) and B_k (2n) at the nominal, in the tangent coordinates ξ = (φ, ω).
    pub fn stage_jacobians(&mut self, k: usize) -> Result<(Mat<f64>, Vec<f64>)> {
        self.check_stage(k)?;
        let nxi = self.nxi;
        let mut a = vec![0.0; nxi * nxi];
        let mut b = vec![0.0; nxi];
        let nom = &self.horizon.nominal;
        let x = StagePoint {
            q: nom.q(k),
            p: nom.p(k),
            omega: nom.omega(k),
            mu: nom.lambda(k),
        };
        let at = StageAt {
            model: &self.horizon.model,
            k,
            x,
            u: nom.u[k],
            ux: 0.0,
        };
        let out = JacobiansMut {
            a: &mut a,
            b: &mut b,
        };
        self.store.ws[0].jac.jacobians(at, out)?;
        Ok((Mat::from_fn(nxi, nxi, |i, j| a[j * nxi + i]), b))
    }

    fn check_stage(&self, k: usize) -> Result<()> {
        if k >= self.horizon.steps {
            return Err(OcpError::StageOutOfRange {
                stage: k,
                steps: self.horizon.steps,
            }
            .into());
        }
        Ok(())
    }

    /// The tangent coordinates ξ = (φ₁..φₙ, ω₁..ωₙ) of the nominal x̂_k (absolute angles from e₂
    /// and angular rates).
    pub fn coordinates(&self, k: usize) -> Vec<f64> {
        let q = self.horizon.nominal.q(k);
        let mut x: Vec<f64> = q.iter().map(|q| q[1].atan2(q[0])).collect();
        x.extend_from_slice(self.horizon.nominal.omega(k));
        x
    }

    /// The stage map F_k in tangent coordinates: x̂_k built from ξ (qᵢ = (cos φᵢ, sin φᵢ),
    /// p = M(ωᵢ tᵢ)), one stage with control u, and the coordinates of x̂_{k+1}. The Newton
    /// predictor is the nominal's. (For finite-difference checks of [`Solver::stage_jacobians`].)
    pub fn stage_map(&mut self, k: usize, xi: &[f64], u: f64) -> Result<Vec<f64>> {
        self.check_stage(k)?;
        let n = self.horizon.model.n;
        if xi.len() != 2 * n {
            return Err(Error::WrongLength {
                name: "xi",
                expected: 2 * n,
                got: xi.len(),
            });
        }
        let q: Vec<[f64; 2]> = xi[..n].iter().map(|f| [f.cos(), f.sin()]).collect();
        let v: Vec<[f64; 2]> = (0..n)
            .map(|i| {
                let t = tangent(&q[i]);
                [xi[n + i] * t[0], xi[n + i] * t[1]]
            })
            .collect();
        let hz = &mut self.horizon;
        let st = &mut hz.sim.stepper.state;
        hz.model.apply_mass(&v, &mut st.p);
        st.q.copy_from_slice(&q);
        let mu = hz.nominal.mu(k);
        let m = st.multipliers_mut(mu.len());
        m.mu.copy_from_slice(mu);
        m.lambda.copy_from_slice(mu);
        hz.sim.stepper.advance(k, u)?;
        let st = &hz.sim.stepper.state;
        let mut out: Vec<f64> = st.q.iter().map(|q| q[1].atan2(q[0])).collect();
        let mut w = vec![0.0; n];
        hz.model.rates(&st.q, &st.p, &mut hz.sim.scratch, &mut w);
        out.extend_from_slice(&w);
        Ok(out)
    }

    /// The Gauss-Newton step δθ at the nominal with a proximal weight `mu` (added to every
    /// Q_uu): one Riccati pass and a closed-loop rollout of the *linearised* dynamics
    /// δz_{k+1} = Ã_k δz_k + B̃_k δv_k (without active bounds and with μ = 0, the minimiser of the
    /// Gauss-Newton model). Needs the Jacobians of the whole horizon in memory.
    pub fn gauss_newton_step(&mut self, mu: f64) -> Result<Vec<f64>> {
        self.check_in_memory()?;
        self.qp.at_nominal();
        self.qp.active.fill(false);
        self.prox = mu;
        if !self.sweep(true)? {
            return Err(OcpError::UnboundedStage { mu }.into());
        }
        self.linear_rollout(1.0, RolloutMode::ClosedLoop);
        let stages = &self.horizon.theta_stage;
        Ok(stages.iter().map(|&k| self.qp.dv_t[k]).collect())
    }

    /// The exact Newton step δθ at the nominal with a proximal weight `mu`: as
    /// [`Solver::gauss_newton_step`] with the second-order terms H_k = ∇²(ν_{k+1}·F̃_k) and the
    /// moment's curvature in the stage QPs ([`super::Curvature::Exact`]), i.e. the minimiser of
    /// the quadratic model with the exact Hessian of J(θ) plus μ‖δθ‖²/2 (when every stage QP is
    /// bounded). Per-step controls without rate penalty, every Jacobian in memory.
    pub fn newton_step(&mut self, mu: f64) -> Result<Vec<f64>> {
        self.check_in_memory()?;
        if !self.second.possible {
            return Err(OcpError::NoExactModel.into());
        }
        self.costate_by_reverse_steps()?;
        self.hessians()?;
        self.second.exact = true;
        let step = self.gauss_newton_step(mu);
        self.second.exact = false;
        step
    }

    /// The exact gradient ∂J/∂θ at the nominal by the costate sweep of reverse stage steps
    /// (no Jacobians; the exact model's sweep): equal to [`Solver::gradient`].
    pub fn gradient_by_reverse_steps(&mut self) -> Result<Vec<f64>> {
        if !self.second.possible {
            return Err(OcpError::NoReverseSweep.into());
        }
        self.costate_by_reverse_steps()?;
        Ok(self.theta_gradient())
    }

    fn check_in_memory(&self) -> Result<()> {
        if !self.store.holds_all(self.horizon.steps) {
            return Err(OcpError::JacobiansNotInMemory {
                bytes: self.horizon.steps * 8 * (self.nxi * self.nxi + self.nxi),
            }
            .into());
        }
        Ok(())
    }

    /// The Gauss-Newton Hessian and the gradient of J(θ) at the nominal, assembled densely
    /// from the stage Jacobians: H = Σ_k w_k ∇r_k∇r_kᵀ + 2 e_k PᵀP + rate terms, with
    /// ∇_u r_k = ∂r_k/∂φ₁ · e₁ᵀ A_{k−1}⋯A_{j+1} B_j (c_sum: r_k = M₀(t_k), w_k = 2) and
    /// P = ∂u/∂θ. O(N² n²):
    /// for checking [`Solver::gauss_newton_step`] on small horizons.
    pub fn dense_gauss_newton(&mut self) -> Result<(Mat<f64>, Vec<f64>)> {
        let (steps, nxi) = (self.horizon.steps, self.nxi);
        let m = steps + 1;
        let mut x = Mat::<f64>::zeros(nxi, m);
        let mut hu = Mat::<f64>::zeros(m, m);
        let mut gu = vec![0.0; m];
        let scale = self.horizon.model.moment_scale;
        for k in 0..=steps {
            let hz = &self.horizon;
            if k > 0 {
                self.store.fill(&hz.model, &hz.nominal, k - 1..k)?;
                let StageJacobians { a, b } = self.store.stage(0);
                let xa = Mat::from_fn(nxi, nxi, |i, j| a[j * nxi + i]) * &x;
                x = xa;
                for i in 0..nxi {
                    x[(i, k - 1)] += b[i];
                }
            }
            let w = hz.cost.weight(k);
            let d = hz.nominal.dresidual(k, scale);
            let rk = hz.nominal.residual[k];
            for i in 0..m {
                let ri = d * x[(0, i)];
                gu[i] += w * rk * ri;
                for j in 0..m {
                    hu[(i, j)] += w * ri * d * x[(0, j)];
                }
            }
            let u = hz.nominal.u[k];
            gu[k] += 2.0 * hz.cost.effort(k) * u;
            hu[(k, k)] += 2.0 * hz.cost.effort(k);
            if k > 0 && hz.cost.rate > 0.0 {
                let r = hz.cost.rate;
                let du = u - hz.nominal.u[k - 1];
                gu[k] += 2.0 * r * du;
                gu[k - 1] -= 2.0 * r * du;
                hu[(k, k)] += 2.0 * r;
                hu[(k - 1, k - 1)] += 2.0 * r;
                hu[(k, k - 1)] -= 2.0 * r;
                hu[(k - 1, k)] -= 2.0 * r;
            }
        }
        self.store.invalidate();
        let hz = &self.horizon;
        let p = hz.n_params;
        let mut h = Mat::<f64>::zeros(p, p);
        let mut g = vec![0.0; p];
        for k in 0..m {
            g[hz.piece[k]] += gu[k];
            for l in 0..m {
                h[(hz.piece[k], hz.piece[l])] += hu[(k, l)];
            }
        }
        Ok((h, g))
    }
}
