//! The second-order model (module docs, "Second-order model"): the exact Hessian's stage terms
//! H_k = ∇²(ν_{k+1}·F̃_k) ([`super::hessian`]) and the stage cost's own curvature beyond Gauss-Newton (−2c_k M₀(t_k)² for c and c_sum),
//! the costates ν_k they are weighted by, and when the iterations use them ([`Curvature`]).

#[cfg(feature = "parallel")]
use rayon::prelude::*;

use super::hessian::{
    gradient_entry, stage_vjp, HessianWorkspace, Reverse, SecondOrderMut, VjpStage, VjpWorkspace,
};
use super::horizon::ControlHorizon;
use super::jacobians::{JacobianStore, WholeStore};
use super::options::{Curvature, OcpOptions};
use super::riccati::{self, StageInput};
use super::stage::{Dv, JacobiansMut, StageAt, StageModel, StagePoint};
use crate::error::{Error, OcpError, Result};
use crate::model::Chain;
use std::any::Any;

/// The exact model's stores and switches. Its storage (H_k of every stage, the costates) is
/// allocated at its first use.
#[derive(Clone, Debug)]
pub(crate) struct SecondOrderModel {
    /// The planar model's dual chain of the reverse steps, and its stage map and buffers of the
    /// costate sweep by reverse steps (`None` in the spatial model, where the exact model is
    /// not available: Gauss-Newton throughout).
    planar: Option<PlanarReverse>,
    /// The costates ν_k (2n per stage): the multipliers of the second-order terms.
    nu: Vec<f64>,
    /// H_k per stage ((2n + 1)², column-major).
    pub h: Vec<f64>,
    /// The cost's extra curvature per stage.
    pub curv: Vec<f64>,
    /// Whether the current model uses the terms.
    pub exact: bool,
    /// Whether the iterations from now on use the exact model ([`Curvature`]).
    pub on: bool,
    /// Whether `h` holds H_k at the current nominal (a failed line search keeps it).
    pub valid: bool,
    /// Whether the exact model is available: per-step controls without rate penalty (no
    /// augmented state, `aug` = 0), H_k and the Jacobians of every stage within
    /// `jacobian_memory`, and a curvature other than Gauss-Newton.
    pub possible: bool,
}

/// The planar reverse steps of the exact model.
#[derive(Clone, Debug)]
struct PlanarReverse {
    chain_dv: Chain<Dv, 2>,
    vjp: VjpWorkspace<f64>,
}

impl SecondOrderModel {
    /// The (empty) model of a horizon of `steps` stages of `model`; `aug` is 1 with the
    /// augmented state w_k = u_{k−1}. The exact model's reverse steps are planar: in the
    /// spatial model (`DIM = 3`, found by a checked downcast of `model`) it is not possible
    /// and the solver runs Gauss-Newton throughout.
    pub(super) fn new<const DIM: usize>(
        model: &StageModel<DIM>,
        options: &OcpOptions,
        steps: usize,
        aug: usize,
    ) -> Result<Self> {
        let nxi = model.nx();
        let planar = match (model as &dyn Any).downcast_ref::<StageModel<2>>() {
            Some(m) => Some(PlanarReverse {
                chain_dv: m.chain.lift::<Dv>(),
                vjp: VjpWorkspace::new(m)?,
            }),
            None => None,
        };
        // The exact model keeps H_k beside every A_k, B_k: both within `jacobian_memory`.
        let exact_bytes = JacobianStore::<2>::stage_bytes(nxi) + 8 * (nxi + 1) * (nxi + 1);
        let possible = planar.is_some()
            && aug == 0
            && options.jacobian_memory / exact_bytes >= steps
            && options.curvature != Curvature::GaussNewton;
        Ok(SecondOrderModel {
            planar,
            nu: Vec::new(),
            h: Vec::new(),
            curv: vec![0.0; steps + 1],
            exact: false,
            on: false,
            valid: false,
            possible,
        })
    }

    /// The start of a run: the exact model from the first iteration with
    /// [`Curvature::Exact`].
    pub(super) fn begin(&mut self, curvature: Curvature) {
        self.on = curvature == Curvature::Exact && self.possible;
    }

    /// [`Curvature::Auto`]: the exact model from the first step the Gauss-Newton model did not
    /// predict well (`good`: taken in full with actual ≥ ½ predicted decrease) on.
    pub(super) fn switch(&mut self, curvature: Curvature, good: bool) {
        if curvature == Curvature::Auto && !good && self.possible {
            self.on = true;
        }
    }

    /// The terms as the backward pass and the linearised rollouts read them, at the model
    /// point `dz` (δz per stage; empty for the value alone).
    pub(super) fn view<'a>(&'a self, dz: &'a [f64], steps: usize, nz: usize) -> SecondOrder<'a> {
        SecondOrder {
            on: self.exact,
            steps,
            nz,
            h: &self.h,
            curv: &self.curv,
            dz,
        }
    }

    /// Allocates the storage (H_k per stage, the costates) at its first use.
    fn storage(&mut self, steps: usize, nxi: usize) {
        let nd = nxi + 1;
        if self.h.is_empty() {
            self.h = vec![0.0; steps * nd * nd];
            self.nu = vec![0.0; (steps + 1) * nxi];
        }
    }

    /// The exact gradient (per stage, into `grad`) and the costates ν_k at the nominal without
    /// the stage Jacobians: ν_N = l_x, then ν_k = l_x + A_kᵀν_{k+1} and g_k = l_u + B_kᵀν_{k+1}
    /// as one reverse step of each stage in f64 (`hessian::stage_vjp`: the stage recomputed
    /// from the stored x̂_k, then the adjoint's reverse step), O(N) sequential, about two
    /// simulations. For the exact model (no augmented state), whose H_k pass then computes
    /// A_k and B_k as well.
    pub(super) fn costates(&mut self, hz: &ControlHorizon, grad: &mut [f64]) -> Result<()> {
        let (steps, nxi) = (hz.steps, hz.model.nx());
        self.storage(steps, nxi);
        let Some(planar) = self.planar.as_mut() else {
            return Err(OcpError::NoReverseSweep.into());
        };
        let vjp = &mut planar.vjp;
        let mut rev = Reverse::new(&hz.model.chain, &hz.model, steps);
        let scale = hz.model.moment_scale;
        for k in (0..=steps).rev() {
            let nom = &hz.nominal;
            let (w, u) = (hz.cost.weight(k), nom.u[k]);
            let lx0 = w * nom.residual[k] * nom.dresidual(k, scale);
            let lu = 2.0 * hz.cost.effort(k) * u;
            let (done, rest) = self.nu.split_at_mut((k + 1) * nxi);
            let nu_k = &mut done[k * nxi..];
            nu_k.fill(0.0);
            nu_k[0] = lx0;
            grad[k] = lu;
            if k == steps {
                continue;
            }
            let st = &mut vjp.stepper.state;
            st.q.copy_from_slice(nom.q(k));
            st.p.copy_from_slice(nom.p(k));
            let m = st.multipliers_mut(nom.lambda(k).len());
            m.lambda.copy_from_slice(nom.lambda(k));
            m.mu.copy_from_slice(nom.lambda(k));
            st.tip_target = [0.0; 2];
            vjp.bufs.omega0.copy_from_slice(nom.omega(k));
            let stage = VjpStage {
                model: &hz.model,
                k,
                u,
                nu: &rest[..nxi],
            };
            stage_vjp(&mut vjp.stepper, &mut vjp.bufs, stage, &mut rev)?;
            for (r, v) in nu_k.iter_mut().enumerate() {
                *v += gradient_entry(&vjp.bufs, &rev, k, r);
            }
            grad[k] += gradient_entry(&vjp.bufs, &rev, k, nxi);
        }
        Ok(())
    }

    /// H_k = ∇²(ν_{k+1}·F̃_k) and the Jacobians A_k, B_k of every stage at the nominal (into
    /// `store`), in one parallel pass of forward and reverse dual steps (`hessian`), and the
    /// cost's curvature beyond Gauss-Newton (−2c_k M₀(t_k)² for c and c_sum); needs the costates of
    /// [`SecondOrderModel::costates`].
    pub(super) fn compute(&mut self, hz: &ControlHorizon, store: &mut JacobianStore) -> Result<()> {
        let (steps, nxi) = (hz.steps, hz.model.nx());
        let nd = nxi + 1;
        let per = nd * nd;
        let WholeStore { ws, a, b } = store.whole(steps);
        let chunk = steps.div_ceil(ws.len()).max(1);
        let Some(planar) = self.planar.as_ref() else {
            return Err(OcpError::NoExactModel.into());
        };
        let (model, nom, chain) = (&hz.model, &hz.nominal, &planar.chain_dv);
        let nu = &self.nu;
        let work =
            |c: usize, hs: &mut [f64], a: &mut [f64], b: &mut [f64], ws: &mut HessianWorkspace| {
                let mut rev = Reverse::new(chain, model, steps);
                let mut grad = vec![0.0; nd];
                let stages = hs
                    .chunks_mut(per)
                    .zip(a.chunks_mut(nxi * nxi).zip(b.chunks_mut(nxi)));
                for (i, (h, (ai, bi))) in stages.enumerate() {
                    let k = c * chunk + i;
                    let x = StagePoint {
                        q: nom.q(k),
                        p: nom.p(k),
                        omega: nom.omega(k),
                        mu: nom.lambda(k),
                    };
                    let nu1 = &nu[(k + 1) * nxi..(k + 2) * nxi];
                    let at = StageAt {
                        model,
                        k,
                        x,
                        u: nom.u[k],
                        ux: 0.0,
                    };
                    let out = SecondOrderMut {
                        hess: h,
                        grad: &mut grad[..],
                        jac: JacobiansMut { a: ai, b: bi },
                    };
                    ws.second_order(at, nu1, &mut rev, out)?;
                }
                Ok::<(), Error>(())
            };
        let hs = &mut self.h[..steps * per];
        #[cfg(feature = "parallel")]
        if ws.len() > 1 {
            hs.par_chunks_mut(chunk * per)
                .zip(a.par_chunks_mut(chunk * nxi * nxi))
                .zip(b.par_chunks_mut(chunk * nxi))
                .zip(ws.par_iter_mut())
                .enumerate()
                .try_for_each(|(c, (((h, a), b), ws))| work(c, h, a, b, ws))?;
        } else {
            work(0, hs, a, b, &mut ws[0])?;
        }
        #[cfg(not(feature = "parallel"))]
        for (c, (((h, a), b), ws)) in hs
            .chunks_mut(chunk * per)
            .zip(a.chunks_mut(chunk * nxi * nxi))
            .zip(b.chunks_mut(chunk * nxi))
            .zip(ws.iter_mut())
            .enumerate()
        {
            work(c, h, a, b, ws)?;
        }
        store.filled_whole(steps);
        let scale = hz.model.moment_scale;
        for k in 0..=steps {
            let nom = &hz.nominal;
            let (m, dm) = (nom.moment[k], nom.dmoment(k, scale));
            let (r, dr, d2r) = (nom.residual[k], nom.dresidual_dm[k], nom.d2residual_dm2[k]);
            // w r (r″ M₀_φ² + r′ M₀_φφ), M₀_φφ = −M₀: −2M₀² for c_sum.
            self.curv[k] = hz.cost.weight(k) * r * (d2r * dm * dm - dr * m);
        }
        self.valid = true;
        Ok(())
    }
}

/// The second-order terms of the stages, as the backward pass reads them.
pub(crate) struct SecondOrder<'a> {
    on: bool,
    steps: usize,
    nz: usize,
    h: &'a [f64],
    curv: &'a [f64],
    dz: &'a [f64],
}

/// (H_k δ)_j = H_k[.., j]·δz + H_k[n_z, j] δv of a stage's H_k = `h` (n_z + 1 columns of
/// n_z + 1, symmetric) at δ = (δz, δv) = (`dz`, `dv`). Always inlined: as a closure of
/// [`SecondOrder::value`] it was a call per entry since cc205e1 (1.9 M instructions per
/// `ocp_newton` pass, docs/architecture.md "Benches").
#[inline(always)]
fn h_row(h: &[f64], (nz, j): (usize, usize), dz: &[f64], dv: f64) -> f64 {
    let c = &h[j * (nz + 1)..(j + 1) * (nz + 1)];
    riccati::dot(&c[..nz], dz) + c[nz] * dv
}

impl<'a> SecondOrder<'a> {
    /// H_k of every stage ((2n + 1)² each).
    pub(super) fn h(&self) -> &'a [f64] {
        self.h
    }

    /// ½ δᵀH_kδ + ½ curv_k δφ₁² at the model point δ = (δz_k, δv_k): stage k's second-order
    /// terms in the model's value.
    #[inline]
    pub(super) fn value(&self, k: usize, dz: &[f64], dv: f64) -> f64 {
        let (nz, nd) = (self.nz, self.nz + 1);
        let mut v = 0.5 * self.curv[k] * dz[0] * dz[0];
        if k < self.steps {
            let h = &self.h[k * nd * nd..(k + 1) * nd * nd];
            let hx = |j: usize| h_row(h, (nz, j), dz, dv);
            v += 0.5 * ((0..nz).map(|j| dz[j] * hx(j)).sum::<f64>() + dv * hx(nz));
        }
        v
    }

    /// Attaches stage k's terms to its input (nothing for Gauss-Newton).
    pub(super) fn attach(&self, inp: &mut StageInput<'a>) {
        if !self.on {
            return;
        }
        let (k, nz) = (inp.k, self.nz);
        let nd = nz + 1;
        inp.curv = self.curv[k];
        inp.dz = &self.dz[k * nz..(k + 1) * nz];
        if k < self.steps {
            inp.hess = Some(&self.h[k * nd * nd..(k + 1) * nd * nd]);
        }
    }
}
