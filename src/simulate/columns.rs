//! A trajectory's columns (those of `chainbeam simulate`'s CSV) as flat vectors, built in the
//! trajectory's own memory: [`SceneTrajectory::into_columns`].
//!
//! At 10⁵ steps a trajectory holds tens of megabytes; memory fresh from the system costs a page
//! fault per page when first written, comparable to the simulation itself. So the columns reuse
//! what the trajectory already holds: energy, M₀ and the controls move as they are, t_k is
//! written into the tip-target buffer (N + 1 values), and the node positions are computed in
//! place in the buffer of the attitudes q (n·DIM values per step, grown to n·3: by a third in
//! the planar model, not at all in the spatial one) after p, λ and μ have been returned.

use super::{Model, SceneTrajectory, Trajectory};
use crate::error::{Error, Result};
use crate::simulate::{max_trajectory_steps, trajectory_bytes};

/// The columns of a simulated trajectory, k = 0..=N, as flat vectors
/// ([`SceneTrajectory::into_columns`]); every value is finite.
#[derive(Clone, Debug, PartialEq)]
pub struct TrajectoryColumns {
    /// Number of pendulums n.
    pub n: usize,
    /// Times t_k = k h (s), N + 1 values.
    pub t: Vec<f64>,
    /// Total energy H(q_k, p_k; t_k, u_k) (J).
    pub energy: Vec<f64>,
    /// Base bending moment M₀(t_k) = 2 k₁ z₁ / l₁² (Nm) (thesis eq. 3.1.3).
    pub moment: Vec<f64>,
    /// Node positions rᵢ(t_k) = Σ_{j≤i} l_j q_j(t_k) (m) ([`Trajectory::positions`]), row-major
    /// (N + 1)·n·3 values: step k, node i = 1..n, then (x, y, z) (x = 0 in the planar model).
    pub positions: Vec<f64>,
    /// Controls u_k (N) (z components of a 2-axis control).
    pub controls: Vec<f64>,
    /// M₀ₓ(t_k) (Nm) of the spatial model, `None` in the planar one.
    pub moment_x: Option<Vec<f64>>,
    /// u_{x,k} (N) in the spatial model (zeros for a 1-axis control), `None` in the planar one.
    pub controls_x: Option<Vec<f64>>,
}

impl SceneTrajectory {
    /// The trajectory's columns, built in its own memory (module docs): t, energy, M₀, the node
    /// positions, the controls and, in the spatial model, M₀ₓ and u_x — the numbers of
    /// [`SceneTrajectory::time`], [`SceneTrajectory::positions`] and the other accessors, bit for
    /// bit.
    ///
    /// # Errors
    /// [`Error::NonFinite`] naming the first step with a non-finite energy, moment or position
    /// (the controls are finite: the simulation refuses others); [`Error::TrajectoryTooLarge`]
    /// if the allocator refuses the third that the positions need over q in the planar model.
    pub fn into_columns(self) -> Result<TrajectoryColumns> {
        match self.0 {
            Model::Planar(t) => t.into_columns(),
            Model::Spatial(t) => t.into_columns(),
        }
    }
}

impl<const DIM: usize> Trajectory<f64, DIM> {
    /// The trajectory's columns, built in its own memory; see
    /// [`SceneTrajectory::into_columns`].
    ///
    /// # Errors
    /// As [`SceneTrajectory::into_columns`].
    pub fn into_columns(self) -> Result<TrajectoryColumns> {
        let Trajectory {
            n,
            n_constraints,
            h,
            steps,
            q,
            p,
            lambda,
            mu,
            energy,
            moment,
            controls,
            moment_x,
            controls_x,
            tip_target,
            stats,
            lengths,
        } = self;
        // Returned first, so that the positions' growth can take their pages.
        drop((p, lambda, mu, stats));
        let rows = steps + 1;
        let mut t = tip_target;
        t.clear();
        t.extend((0..rows).map(|k| k as f64 * h));
        let mut positions = q.into_flattened();
        positions
            .try_reserve_exact((3 - DIM) * n * rows)
            .map_err(|_| Error::TrajectoryTooLarge {
                n,
                steps,
                bytes: trajectory_bytes::<f64, DIM>(n, n_constraints, steps),
                max_steps: max_trajectory_steps::<f64, DIM>(n, n_constraints),
                refused: true,
            })?;
        positions.resize(3 * n * rows, 0.0);
        // Row k's attitudes lie at [DIM n k, DIM n (k+1)) and its positions go to
        // [3 n k, 3 n (k+1)), at or after every attitude of the rows before it: from the last row
        // down, each row is read (into `row`) before anything overwrites it.
        let mut row = vec![[0.0; DIM]; n];
        let mut first_bad = None;
        for k in (0..rows).rev() {
            let (src, _) = positions[DIM * n * k..DIM * n * (k + 1)].as_chunks::<DIM>();
            row.copy_from_slice(src);
            let (out, _) = positions[3 * n * k..3 * n * (k + 1)].as_chunks_mut::<3>();
            super::node_positions(&row, &lengths, out);
            let finite = energy[k].is_finite()
                && moment[k].is_finite()
                && moment_x.get(k).is_none_or(|m| m.is_finite())
                && out.as_flattened().iter().all(|v| v.is_finite());
            if !finite {
                first_bad = Some(k);
            }
        }
        if let Some(step) = first_bad {
            return Err(Error::NonFinite {
                step,
                quantity: "the energy, base moment or node positions of the trajectory",
            });
        }
        let spatial = DIM == 3;
        let controls_x = spatial.then(|| {
            if controls_x.is_empty() {
                vec![0.0; rows]
            } else {
                controls_x
            }
        });
        Ok(TrajectoryColumns {
            n,
            t,
            energy,
            moment,
            positions,
            controls,
            moment_x: spatial.then_some(moment_x),
            controls_x,
        })
    }
}
