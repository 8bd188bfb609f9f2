//! The Jacobian store: the stage Jacobians A_k, B_k at the nominal ([`super::stage`]),
//! computed in parallel (one dual-number workspace per thread: stages are independent given the
//! trajectory) into a store of at most `OcpOptions::jacobian_memory` bytes — the whole horizon,
//! or blocks of stages that the backward pass computes ahead of itself.

use std::ops::Range;

#[cfg(feature = "parallel")]
use rayon::prelude::*;

use super::hessian::HessianWorkspace;
use super::horizon::available_threads;
use super::line_search::Traj;
use super::options::OcpOptions;
use super::riccati::{self, StageJacobians};
use super::stage::{JacobiansMut, StageAt, StageModel, StagePoint};
use crate::error::{Error, Result};

/// How many stages ahead of the current one the passes over the stored Jacobians prefetch
/// ([`riccati::prefetch`]).
pub(crate) const PREFETCH_AHEAD: usize = 4;

/// The stage Jacobians at the nominal and the workspaces that compute them, in the planar or
/// the spatial model.
#[derive(Clone, Debug)]
pub(crate) struct JacobianStore<const DIM: usize = 2> {
    nxi: usize,
    /// Controls per stage (columns of B_k).
    ncu: usize,
    /// One workspace per thread (the second-order pass uses them too).
    pub ws: Vec<HessianWorkspace<DIM>>,
    a: Vec<f64>,
    b: Vec<f64>,
    /// Stages per block of the store.
    pub block: usize,
    /// The stages whose Jacobians at the nominal are in the store.
    range: Option<Range<usize>>,
    /// Passes run (blocks of stages, or the second-order pass).
    pub passes: usize,
}

/// The whole store for a pass that writes every stage's Jacobians (the second-order pass):
/// the per-thread workspaces and A_k, B_k of stages 0..N.
pub(crate) struct WholeStore<'a, const DIM: usize = 2> {
    pub ws: &'a mut [HessianWorkspace<DIM>],
    pub a: &'a mut [f64],
    pub b: &'a mut [f64],
}

impl<const DIM: usize> JacobianStore<DIM> {
    /// The store of a horizon of `steps` stages of `model` (n_ξ tangent coordinates `nxi`,
    /// `ncu` controls per stage): `options.threads` workspaces (0: the thread pool's), as many
    /// stages as `options.jacobian_memory` holds.
    pub(super) fn new(model: &StageModel<DIM>, options: &OcpOptions, steps: usize) -> Result<Self> {
        let (nxi, ncu) = (model.nx(), model.controls());
        let threads = if options.threads == 0 {
            available_threads()
        } else {
            options.threads
        }
        .clamp(1, steps.max(1));
        let ws = (0..threads)
            .map(|_| HessianWorkspace::new(model))
            .collect::<Result<Vec<_>>>()?;
        let per = Self::stage_bytes(nxi) + 8 * (ncu - 1) * nxi;
        let block = (options.jacobian_memory / per).clamp(1, steps.max(1));
        Ok(JacobianStore {
            nxi,
            ncu,
            ws,
            a: vec![0.0; block * nxi * nxi],
            b: vec![0.0; block * nxi * ncu],
            block,
            range: None,
            passes: 0,
        })
    }

    /// Bytes of one stage's A_k and B_k with one control.
    pub(super) fn stage_bytes(nxi: usize) -> usize {
        8 * (nxi * nxi + nxi)
    }

    /// Whether every stage of a horizon of `steps` fits in the store.
    pub(super) fn holds_all(&self, steps: usize) -> bool {
        self.block >= steps
    }

    /// The nominal moved: nothing in the store is valid.
    pub(super) fn invalidate(&mut self) {
        self.range = None;
    }

    /// The Jacobians of the stages `stages` at the nominal `nom` into the store (slot i holds
    /// stage `stages.start + i`), in parallel; nothing when they are there already.
    pub(super) fn fill(
        &mut self,
        model: &StageModel<DIM>,
        nom: &Traj<DIM>,
        stages: Range<usize>,
    ) -> Result<()> {
        if self.range.as_ref() == Some(&stages) {
            return Ok(());
        }
        let (nxi, count, lo) = (self.nxi, stages.len(), stages.start);
        let (per_a, per_b) = (nxi * nxi, nxi * self.ncu);
        let chunk = count.div_ceil(self.ws.len()).max(1);
        let work = |c: usize, a: &mut [f64], b: &mut [f64], ws: &mut HessianWorkspace<DIM>| {
            for (i, (ai, bi)) in a.chunks_mut(per_a).zip(b.chunks_mut(per_b)).enumerate() {
                let k = lo + c * chunk + i;
                let x = StagePoint {
                    q: nom.q(k),
                    p: nom.p(k),
                    omega: nom.omega(k),
                    mu: nom.lambda(k),
                };
                let at = StageAt {
                    model,
                    k,
                    x,
                    u: nom.u[k],
                    ux: nom.ux(k),
                };
                ws.jac.jacobians(at, JacobiansMut { a: ai, b: bi })?;
            }
            Ok::<(), Error>(())
        };
        let a = &mut self.a[..count * per_a];
        let b = &mut self.b[..count * per_b];
        #[cfg(feature = "parallel")]
        if self.ws.len() > 1 {
            a.par_chunks_mut(chunk * per_a)
                .zip(b.par_chunks_mut(chunk * per_b))
                .zip(self.ws.par_iter_mut())
                .enumerate()
                .try_for_each(|(c, ((a, b), ws))| work(c, a, b, ws))?;
        } else {
            work(0, a, b, &mut self.ws[0])?;
        }
        #[cfg(not(feature = "parallel"))]
        for (c, ((a, b), ws)) in a
            .chunks_mut(chunk * per_a)
            .zip(b.chunks_mut(chunk * per_b))
            .zip(self.ws.iter_mut())
            .enumerate()
        {
            work(c, a, b, ws)?;
        }
        self.range = Some(stages);
        self.passes += 1;
        Ok(())
    }

    /// The workspaces and the store of stages 0..`steps` (every stage in memory), for a pass
    /// that writes them all; [`JacobianStore::filled_whole`] marks them valid afterwards.
    pub(super) fn whole(&mut self, steps: usize) -> WholeStore<'_, DIM> {
        let nxi = self.nxi;
        WholeStore {
            ws: &mut self.ws,
            a: &mut self.a[..steps * nxi * nxi],
            b: &mut self.b[..steps * nxi * self.ncu],
        }
    }

    /// Stages 0..`steps` hold the Jacobians at the nominal (after a pass over
    /// [`JacobianStore::whole`]).
    pub(super) fn filled_whole(&mut self, steps: usize) {
        self.range = Some(0..steps);
        self.passes += 1;
    }

    /// A_k and B_k in store slot `slot`.
    #[inline]
    pub(super) fn stage(&self, slot: usize) -> StageJacobians<'_> {
        let (nxi, per_b) = (self.nxi, self.nxi * self.ncu);
        StageJacobians {
            a: &self.a[slot * nxi * nxi..(slot + 1) * nxi * nxi],
            b: &self.b[slot * per_b..(slot + 1) * per_b],
        }
    }

    /// Prefetches A_k (in store slot `slot`) and, when given, H_k of stage `k` from the
    /// second-order store `h` ((2n + 1)² per stage).
    #[inline]
    pub(super) fn prefetch(&self, slot: usize, h: Option<&[f64]>, k: usize) {
        let nxi = self.nxi;
        let per = nxi * nxi;
        riccati::prefetch(&self.a[slot * per..(slot + 1) * per]);
        if let Some(h) = h {
            let nd = (nxi + 1) * (nxi + 1);
            riccati::prefetch(&h[k * nd..(k + 1) * nd]);
        }
    }
}
