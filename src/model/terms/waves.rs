//! Irregular waves on the chain (OCEAN.md §2–3, docs/conventions.md "Waves"): the wave
//! kinematics of every pendulum over the whole record, precomputed by inverse FFT, and the
//! Froude-Krylov + added-mass inertia load. The waves' drag is the drag relative to the water
//! ([`super::CurrentDrag`]), whose water momentum P(t) gains the waves' share.
//!
//! Node k (1-based) sits at the height y_k = l₁ + … + l_k of the undeformed beam (as for the
//! current) and x = z = 0; its horizontal particle velocity along the mean direction e is
//! u_k(t) = Re Σⱼ V_{jk} e^{iωⱼ t} (linear Airy theory, [`crate::ocean::Sea::velocity_amplitudes`]).
//! Per pendulum i (0-based) the two series the terms read are, with suffix sums over the nodes
//! beyond it,
//!
//! ```text
//! Wᵢ(t) = lᵢ Σ_{k≥i} m_k u_k(t)                    (the waves' share of the water momentum Pᵢ)
//! Gᵢ(t) = lᵢ Σ_{k≥i} ρ_w (1 + C_a) A_o c_k u̇_k(t)   (the inertia load's generalised force)
//! ```
//!
//! with c_k the node's cell (l_k + l_{k+1})/2, half a cell l_n/2 at the tip (the lumping of the
//! pipe's masses). Each is Re Σⱼ (lᵢ Σ_{k≥i} w_k V_{jk}) e^{iωⱼ t}: its complex amplitudes are
//! suffix sums (O(n N)) and the series on the grid tₖ = k h is one inverse FFT per pendulum
//! (both series in one transform, [`crate::ocean::Sea::synthesize`]): O(n M log M) for the
//! record instead of O(n N) cosines per step. Between grid times the series are interpolated
//! linearly (RATTLE's drag reads them at t_k + h/2); beyond the record they are summed directly
//! (O(N) per pendulum and time).

use std::sync::Arc;

use super::{Ctx, Embed, ForceTerm};
use crate::base::{Parameter, Scalar};
use crate::error::Result;
use crate::model::geometry::zi;
use crate::ocean::{Complex, Sea, SeaError};

/// What a [`WaveField`] is computed from besides the sea.
#[derive(Clone, Debug)]
pub struct WaveInputs {
    /// Pendulum lengths lᵢ \[m\].
    pub lengths: Vec<f64>,
    /// Node masses mᵢ \[kg\] (the weights of the water momentum, as for the current).
    pub masses: Vec<f64>,
    /// Inertia coefficient per unit length ρ_w (1 + C_a) A_o \[kg/m\] (OCEAN.md §3).
    pub inertia_per_length: f64,
    /// Unit direction (d_x, d_z) of the waves in the transverse plane.
    pub direction: [f64; 2],
    /// Number of grid times tₖ = k h, k = 0..rows, of the record (steps + 1).
    pub rows: usize,
    /// The velocity of node k averaged over its cell [y_k − l_k/2, y_k + l_{k+1}/2]
    /// ([`crate::ocean::Sea::cell_velocity_amplitudes`]) instead of taken at y_k
    /// (`[loads.waves] lumping = "cell"`).
    pub cell_average: bool,
}

/// The wave kinematics of a chain over a record (module docs): Wᵢ(tₖ), Gᵢ(tₖ) and the surface
/// elevation η(0, tₖ) on the grid, and their complex amplitudes for times beyond it.
#[derive(Clone, Debug)]
pub struct WaveField {
    sea: Arc<Sea>,
    inputs: WaveInputs,
    n: usize,
    h: f64,
    /// Number of grid times of the record.
    rows: usize,
    /// rows × n pairs (Wᵢ(tₖ), Gᵢ(tₖ)), time-major: the two series a step reads for a
    /// pendulum share a cache line.
    series: Vec<f64>,
    elevation: Vec<f64>,
    /// n × N amplitudes of Wᵢ and Gᵢ.
    momentum_amp: Vec<Complex<f64>>,
    inertia_amp: Vec<Complex<f64>>,
}

impl WaveField {
    /// Realises the series of the module docs for `sea` on a chain (`inputs`).
    ///
    /// # Errors
    /// [`SeaError::TooLarge`] when the record's memory is refused.
    pub fn new(sea: Arc<Sea>, inputs: WaveInputs) -> std::result::Result<Self, SeaError> {
        let n = inputs.lengths.len();
        let nc = sea.frequencies().len();
        let zero = Complex::new(0.0, 0.0);
        let (mut momentum_amp, mut inertia_amp) = (vec![zero; n * nc], vec![zero; n * nc]);
        let heights: Vec<f64> = inputs
            .lengths
            .iter()
            .scan(0.0, |y, l| {
                *y += l;
                Some(*y)
            })
            .collect();
        let (mut sm, mut si, mut v) = (vec![zero; nc], vec![zero; nc], vec![zero; nc]);
        let omega = sea.frequencies();
        for i in (0..n).rev() {
            let next = inputs.lengths.get(i + 1).copied().unwrap_or(0.0);
            if inputs.cell_average {
                let cell = (
                    heights[i] - 0.5 * inputs.lengths[i],
                    heights[i] + 0.5 * next,
                );
                sea.cell_velocity_amplitudes(cell, &mut v);
            } else {
                sea.velocity_amplitudes(heights[i], &mut v);
            }
            let cell = 0.5 * (inputs.lengths[i] + next) * inputs.inertia_per_length;
            let l = inputs.lengths[i];
            for j in 0..nc {
                sm[j] += v[j] * inputs.masses[i];
                // u̇ = Re Σ i ωⱼ Vⱼ e^{iωⱼt}
                si[j] += Complex::new(0.0, omega[j]) * v[j] * cell;
                momentum_amp[i * nc + j] = sm[j] * l;
                inertia_amp[i * nc + j] = si[j] * l;
            }
        }
        let rows = inputs.rows;
        let alloc = |size: usize| -> std::result::Result<Vec<f64>, SeaError> {
            let mut x = Vec::new();
            x.try_reserve_exact(size).map_err(|_| SeaError::TooLarge {
                what: "bytes",
                needed: (size as u64).saturating_mul(8),
                limit: crate::ocean::waves::MAX_RECORD_BYTES,
            })?;
            x.resize(size, 0.0);
            Ok(x)
        };
        let mut field = WaveField {
            n,
            h: sea.step(),
            rows,
            series: alloc(rows * n * 2)?,
            elevation: alloc(rows)?,
            momentum_amp,
            inertia_amp,
            inputs,
            sea,
        };
        let mut plan = field.sea.synthesis();
        // The pendulums in blocks of BLOCK: each one's series into a pendulum-major scratch,
        // then the block into the time-major record, BLOCK pairs (one cache line) per row
        // instead of one scattered write per pendulum and row (the same values).
        const BLOCK: usize = 4;
        let mut scratch = alloc(rows * 2 * BLOCK.min(n))?;
        for i0 in (0..n).step_by(BLOCK) {
            let width = BLOCK.min(n - i0);
            for j in 0..width {
                let i = i0 + j;
                let (a, b) = (
                    &field.momentum_amp[i * nc..(i + 1) * nc],
                    &field.inertia_amp[i * nc..(i + 1) * nc],
                );
                let out = &mut scratch[j * rows * 2..(j + 1) * rows * 2];
                field.sea.synthesize((a, b), rows, &mut plan, |k, x, y| {
                    out[2 * k] = x;
                    out[2 * k + 1] = y;
                });
            }
            for k in 0..rows {
                let row = &mut field.series[(k * n + i0) * 2..(k * n + i0 + width) * 2];
                for (j, pair) in row.chunks_exact_mut(2).enumerate() {
                    pair.copy_from_slice(&scratch[(j * rows + k) * 2..(j * rows + k) * 2 + 2]);
                }
            }
        }
        drop(scratch);
        let el = &mut field.elevation;
        field.sea.synthesize(
            (field.sea.elevation_amplitudes(), &[]),
            rows,
            &mut plan,
            |k, x, _| {
                el[k] = x;
            },
        );
        Ok(field)
    }

    /// The same field for new node masses (the water momentum's weights): recomputed.
    ///
    /// # Errors
    /// As [`WaveField::new`].
    pub fn with_masses(&self, masses: &[f64]) -> std::result::Result<Self, SeaError> {
        let mut inputs = self.inputs.clone();
        inputs.masses = masses.to_vec();
        WaveField::new(self.sea.clone(), inputs)
    }

    /// The node masses the water momentum was computed with.
    pub fn masses(&self) -> &[f64] {
        &self.inputs.masses
    }

    /// The sea realised.
    pub fn sea(&self) -> &Sea {
        &self.sea
    }

    /// The unit direction (d_x, d_z) of the waves in the transverse plane.
    pub fn direction(&self) -> [f64; 2] {
        self.inputs.direction
    }

    /// The series in `table` at time t (`stride` values per grid time, the series' value at
    /// `offset`): the grid value at a grid time, linear interpolation between grid times, the
    /// direct sum of `amp` (pendulum `i`'s amplitudes) beyond the record.
    #[inline]
    fn sample(
        &self,
        table: &[f64],
        (stride, offset): (usize, usize),
        (amp, i): (&[Complex<f64>], usize),
        t: f64,
    ) -> f64 {
        let rows = self.rows;
        let s = t / self.h;
        if s >= 0.0 {
            let k0 = s.floor();
            let frac = s - k0;
            let k = k0 as usize;
            if frac <= 1e-9 && k < rows {
                return table[k * stride + offset];
            }
            if frac >= 1.0 - 1e-9 && k + 1 < rows {
                return table[(k + 1) * stride + offset];
            }
            if k + 1 < rows {
                return table[k * stride + offset] * (1.0 - frac)
                    + table[(k + 1) * stride + offset] * frac;
            }
        }
        let nc = self.sea.frequencies().len();
        self.sea.sum_at(&amp[i * nc..(i + 1) * nc], t)
    }

    /// Wᵢ(t) = lᵢ Σ_{k≥i} m_k u_k(t) \[kg m/s · m\]: the waves' share of pendulum i's water
    /// momentum along the mean direction (module docs).
    #[inline]
    pub fn momentum(&self, i: usize, t: f64) -> f64 {
        let at = (2 * self.n, 2 * i);
        self.sample(&self.series, at, (&self.momentum_amp, i), t)
    }

    /// Gᵢ(t) = lᵢ Σ_{k≥i} ρ_w (1 + C_a) A_o c_k u̇_k(t) \[N m\]: the inertia load's generalised
    /// force on pendulum i along the mean direction (module docs).
    #[inline]
    pub fn inertia(&self, i: usize, t: f64) -> f64 {
        let at = (2 * self.n, 2 * i + 1);
        self.sample(&self.series, at, (&self.inertia_amp, i), t)
    }

    /// The surface elevation η(0, t) \[m\] at x = z = 0.
    pub fn elevation(&self, t: f64) -> f64 {
        let amp = self.sea.elevation_amplitudes();
        self.sample(&self.elevation, (1, 0), (amp, 0), t)
    }
}

/// The Froude-Krylov + added-mass inertia load of the waves (OCEAN.md §3): the force
/// F_k = ρ_w (1 + C_a) A_o c_k u̇_k(t) e on node k along the mean direction e, a known function
/// of time and depth. Conservative in q: U = −Σ_k F_k · r_k with r_k = Σ_{j≤k} l_j q_j, so
/// U = −Σⱼ Gⱼ(t) e · qⱼ and ∂U/∂qⱼ = −Gⱼ(t) e (transverse components) with Gⱼ of
/// [`WaveField::inertia`]. It reads no parameter (its coefficient comes from `[pipe]`).
#[derive(Clone, Debug)]
pub struct WaveInertia {
    pub(crate) field: Arc<WaveField>,
}

impl WaveInertia {
    /// The load of `field`.
    pub fn new(field: Arc<WaveField>) -> Self {
        WaveInertia { field }
    }

    /// Its field.
    pub fn field(&self) -> &WaveField {
        &self.field
    }

    /// The direction e in the model's components (x only in the spatial model).
    #[inline]
    fn unit<const DIM: usize>(&self) -> [f64; DIM] {
        let [dx, dz] = self.field.direction();
        let mut e = [0.0; DIM];
        e[zi::<DIM>()] = dz;
        if DIM == 3 {
            e[0] = dx;
        }
        e
    }
}

impl<D: Scalar, const DIM: usize> ForceTerm<D, DIM> for WaveInertia {
    fn name(&self) -> &'static str {
        "wave inertia"
    }

    fn energy<E: Embed<D>>(&self, q: &[[E; DIM]], ctx: &Ctx<E>) -> E {
        let e = self.unit::<DIM>();
        let mut u = E::zero();
        for (j, qj) in q.iter().enumerate() {
            let g = self.field.inertia(j, ctx.t);
            for d in 0..DIM {
                if e[d] != 0.0 {
                    u -= qj[d] * (g * e[d]);
                }
            }
        }
        u
    }

    fn force<E: Embed<D>>(
        &self,
        _q: &[[E; DIM]],
        ctx: &Ctx<E>,
        out: &mut [[E; DIM]],
    ) -> Result<()> {
        let e = self.unit::<DIM>();
        for (j, o) in out.iter_mut().enumerate() {
            let g = self.field.inertia(j, ctx.t);
            for d in 0..DIM {
                if e[d] != 0.0 {
                    o[d] -= E::from(g * e[d]);
                }
            }
        }
        Ok(())
    }

    fn depends_on_configuration(&self) -> bool {
        false
    }

    fn has_parameter(&self, _p: Parameter) -> bool {
        false
    }
}
