//! Irregular waves on the chain (docs/ocean.md, docs/conventions.md "Waves"): the wave
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
//! suffix sums (O(n N)) and the series on the grid tₖ = k h is one transform per pendulum
//! (both series in one transform, [`crate::ocean::Sea::synthesize`]): the inverse FFT of the
//! repeat period's M points, or, when cheaper, the zoom transform that forms only the record's
//! rows ([`crate::ocean::Sea::synthesis_rows`], P ≈ 2N + rows points): O(n min(M log M,
//! P log P)) for the record instead of O(n N) cosines per step, so a short run of a 3-hour sea
//! sets up in a time that scales with the run, not with the sea's repeat period. Between grid times the series are interpolated
//! linearly (RATTLE's drag reads them at t_k + h/2); beyond the record they are summed directly
//! (O(N) per pendulum and time).
//!
//! **A coarser record** (`[loads.waves] record_step` = r h, r > 1; [`WaveInputs::every`]): the
//! record keeps the times t_j = j r h only, with each series' time derivative (Ẇᵢ = Re Σ iωⱼ Xⱼ
//! e^{iωⱼ t}, the same for Gᵢ and η: two transforms per pendulum, of length M/r when r divides
//! M, [`crate::ocean::Sea::synthesis_every`]), and is read at any t by the cubic Hermite
//! interpolant of the values and derivatives at the two record times around it,
//! p(x) = y₀ + x d₀ + x² (3Δ − 2d₀ − d₁) + x³ (d₀ + d₁ − 2Δ) with x = (t − t_j)/(r h),
//! Δ = y₁ − y₀, d = r h ẏ: error at most (r h)⁴/384 · max |y⁗| ≤ (r h)⁴/384 · Σⱼ |Xⱼ| ωⱼ⁴ for
//! y = Re Σⱼ Xⱼ e^{iωⱼ t}. The memory is 4n + 2 values per record time instead of 2n + 1 per step,
//! (r/2 less), and the reads stay allocation-free. The series are known functions of time that
//! enter the derivatives as constants, so the adjoint and dual numbers differentiate the model as
//! interpolated, exactly.

use std::sync::{Arc, OnceLock};

use super::{Ctx, Embed, ForceTerm};
use crate::base::{Parameter, Scalar};
use crate::error::Result;
use crate::model::geometry::zi;
use crate::ocean::{Complex, Profiles, Sea, SeaError};

mod inertia;

pub use inertia::{WaveInertia, WaveInertiaTangent};

/// What a [`WaveField`] is computed from besides the sea.
#[derive(Clone, Debug)]
pub struct WaveInputs {
    /// Pendulum lengths lᵢ \[m\].
    pub lengths: Vec<f64>,
    /// Node masses mᵢ \[kg\] (the weights of the water momentum, as for the current).
    pub masses: Vec<f64>,
    /// Inertia coefficient per unit length ρ_w (1 + C_a) A_o \[kg/m\] (the Morison inertia term,
    /// docs/ocean.md "The loads of the water on the pipe").
    pub inertia_per_length: f64,
    /// Unit direction (d_x, d_z) of the waves in the transverse plane.
    pub direction: [f64; 2],
    /// Number of record times t_j = j r h, j = 0..rows (steps + 1 when r = 1; ⌈steps/r⌉ + 1
    /// covers t_N when r > 1).
    pub rows: usize,
    /// r: the record keeps every r-th time of the sea's grid (`[loads.waves] record_step` =
    /// r h); 1: every step, read by linear interpolation between steps (the default); r > 1:
    /// values and time derivatives, read by cubic Hermite interpolation (module docs).
    pub every: usize,
    /// The velocity of node k averaged over its cell [y_k − l_k/2, y_k + l_{k+1}/2]
    /// ([`crate::ocean::Sea::cell_velocity_amplitudes`]) instead of taken at y_k
    /// (`[loads.waves] lumping = "cell"`).
    pub cell_average: bool,
    /// The mudline's height above the chain's foot \[m\] (0: the foot is at the seabed): a
    /// node's height in the sea is taken above it ([`crate::scene::water_height`]), and the nodes
    /// below it (in the soil) have no wave kinematics.
    pub mudline: f64,
    /// Per node, the inertia coefficient over its cell ρ_w (1 + C_a) A c_k \[kg\] of a stack-up
    /// ([`crate::scene::Layout::node_inertia`]); `None`: `inertia_per_length` times the cell.
    pub node_inertia: Option<Vec<f64>>,
}

/// The complex amplitudes of node i's velocity (at its height y, or averaged over its cell
/// [y − lᵢ/2, y + next/2]), its heights taken above the mudline by
/// [`crate::scene::water_height`]: zero for a node in the soil; a cell that reaches into the
/// soil averages the water's part over the whole cell (the soil's part moves no water).
fn node_velocity(
    profiles: &mut Profiles<'_>,
    inputs: &WaveInputs,
    (y, next): (f64, f64),
    i: usize,
    v: &mut [Complex<f64>],
) {
    let m = inputs.mudline;
    let above = |h: f64| crate::scene::water_height(m, h);
    if !inputs.cell_average {
        match above(y) {
            Some(h) => profiles.velocity_amplitudes(h, v),
            None => v.iter_mut().for_each(|x| *x = Complex::new(0.0, 0.0)),
        }
        return;
    }
    let (lo, hi) = (y - 0.5 * inputs.lengths[i], y + 0.5 * next);
    if m == 0.0 {
        profiles.cell_velocity_amplitudes((lo, hi), v);
        return;
    }
    match above(hi) {
        Some(h1) if h1 > 0.0 => {
            let h0 = lo - m;
            if h0 >= 0.0 {
                profiles.cell_velocity_amplitudes((h0, h1), v);
            } else {
                profiles.cell_velocity_amplitudes((0.0, h1), v);
                let share = h1 / (hi - lo);
                v.iter_mut().for_each(|x| *x *= share);
            }
        }
        _ => v.iter_mut().for_each(|x| *x = Complex::new(0.0, 0.0)),
    }
}

/// The complex amplitudes of every pendulum's two series (module docs), pendulum by pendulum
/// from the tip down (the suffix sums over the nodes beyond it): `visit(i, Wᵢ's, Gᵢ's)`, N
/// each. O(n N) and O(N) memory: the caller keeps what it needs.
fn pendulum_amplitudes(
    sea: &Sea,
    inputs: &WaveInputs,
    mut visit: impl FnMut(usize, &[Complex<f64>], &[Complex<f64>]),
) {
    let n = inputs.lengths.len();
    let nc = sea.frequencies().len();
    let zero = Complex::new(0.0, 0.0);
    let heights: Vec<f64> = inputs
        .lengths
        .iter()
        .scan(0.0, |y, l| {
            *y += l;
            Some(*y)
        })
        .collect();
    let mut profiles = Profiles::new(sea);
    let (mut sm, mut si, mut v) = (vec![zero; nc], vec![zero; nc], vec![zero; nc]);
    let (mut a, mut b) = (vec![zero; nc], vec![zero; nc]);
    let omega = sea.frequencies();
    for i in (0..n).rev() {
        let next = inputs.lengths.get(i + 1).copied().unwrap_or(0.0);
        node_velocity(&mut profiles, inputs, (heights[i], next), i, &mut v);
        let cell = match &inputs.node_inertia {
            Some(c) => c[i],
            None => 0.5 * (inputs.lengths[i] + next) * inputs.inertia_per_length,
        };
        let l = inputs.lengths[i];
        for j in 0..nc {
            sm[j] += v[j] * inputs.masses[i];
            // u̇ = Re Σ i ωⱼ Vⱼ e^{iωⱼt}
            si[j] += Complex::new(0.0, omega[j]) * v[j] * cell;
            a[j] = sm[j] * l;
            b[j] = si[j] * l;
        }
        visit(i, &a, &b);
    }
}

/// A time located in a [`WaveField`]'s record ([`WaveField::at`]): read every pendulum's series
/// at it without locating the time again.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RecordTime(At);

/// Where a time falls in the record.
#[derive(Clone, Copy, Debug, PartialEq)]
enum At {
    /// On record time k.
    Row(usize),
    /// Between record times k and k + 1 (r = 1), at the fraction given.
    Linear(usize, f64),
    /// Between record times j and j + 1 (r > 1), at x = (t − t_j)/(r h).
    Hermite(usize, f64),
    /// Beyond the record, at time t: the direct sum.
    Beyond(f64),
}

/// The wave kinematics of a chain over a record (module docs): Wᵢ(tₖ), Gᵢ(tₖ) and the surface
/// elevation η(0, tₖ) on the grid, and their complex amplitudes for times beyond it.
#[derive(Clone, Debug)]
pub struct WaveField {
    sea: Arc<Sea>,
    inputs: WaveInputs,
    n: usize,
    /// The record's time step r h.
    h: f64,
    /// Number of record times.
    rows: usize,
    /// The grid index of the record's first time (0; a forecast's window,
    /// [`WaveField::window`], starts later).
    first: usize,
    /// r of [`WaveInputs::every`].
    every: usize,
    /// rows × n pairs (Wᵢ(tₖ), Gᵢ(tₖ)), time-major: the two series a step reads for a
    /// pendulum share a cache line; for r > 1, rows × n quadruples (Wᵢ, Ẇᵢ, Gᵢ, Ġᵢ).
    series: Vec<f64>,
    /// η(0, tₖ); for r > 1, pairs (η, η̇).
    elevation: Vec<f64>,
    /// n × N amplitudes of Wᵢ and Gᵢ, formed when a time beyond the record is read (the
    /// record itself is synthesised pendulum by pendulum as the amplitudes are formed, so a
    /// run that stays within its record never holds them); shared with the field's windows
    /// ([`WaveField::window`]), which read beyond themselves by the same sums.
    amplitudes: Arc<OnceLock<Amplitudes>>,
}

/// The n × N complex amplitudes of every pendulum's Wᵢ and Gᵢ ([`WaveField::amplitudes`]).
#[derive(Clone, Debug)]
struct Amplitudes {
    momentum: Vec<Complex<f64>>,
    inertia: Vec<Complex<f64>>,
}

impl WaveField {
    /// Realises the series of the module docs for `sea` on a chain (`inputs`).
    ///
    /// # Errors
    /// [`SeaError::TooLarge`] when the record's or the amplitudes' memory is refused.
    pub fn new(sea: Arc<Sea>, inputs: WaveInputs) -> std::result::Result<Self, SeaError> {
        let n = inputs.lengths.len();
        let nc = sea.frequencies().len();
        // The amplitudes a read beyond the record forms are held to the record's limit here.
        check_amplitudes(n, nc)?;
        let rows = inputs.rows;
        let every = inputs.every.max(1);
        let width = if every == 1 { 2 } else { 4 };
        let mut field = WaveField {
            n,
            h: sea.step() * every as f64,
            rows,
            first: 0,
            every,
            series: alloc_record(rows * n * width)?,
            elevation: alloc_record(rows * width / 2)?,
            amplitudes: Arc::new(OnceLock::new()),
            inputs,
            sea,
        };
        if every > 1 {
            field.fill_hermite_record();
        } else {
            field.fill_step_record()?;
        }
        Ok(field)
    }

    /// The record of r = 1 (module docs): (Wᵢ, Gᵢ) and η at every step tₖ = k h.
    fn fill_step_record(&mut self) -> std::result::Result<(), SeaError> {
        let (n, rows) = (self.n, self.rows);
        let sea = self.sea.clone();
        let mut plan = sea.synthesis_rows(1, rows);
        // The pendulums in blocks of BLOCK (from the tip down, as their amplitudes come): each
        // one's series into a pendulum-major scratch, then the block into the time-major
        // record, BLOCK pairs (one cache line) per row instead of one scattered write per
        // pendulum and row (the same values).
        const BLOCK: usize = 4;
        let mut scratch = alloc_record(rows * 2 * BLOCK.min(n))?;
        let series = &mut self.series;
        pendulum_amplitudes(&sea, &self.inputs, |i, a, b| {
            // Slot j holds pendulum i0 + j of the block i0..i0 + width.
            let i0 = i - i % BLOCK;
            let width = BLOCK.min(n - i0);
            let j = i - i0;
            let out = &mut scratch[j * rows * 2..(j + 1) * rows * 2];
            sea.synthesize((a, b), rows, &mut plan, |k, x, y| {
                out[2 * k] = x;
                out[2 * k + 1] = y;
            });
            if j == 0 {
                // The block's last pendulum (the amplitudes come from the tip down).
                for k in 0..rows {
                    let row = &mut series[(k * n + i0) * 2..(k * n + i0 + width) * 2];
                    for (j, pair) in row.chunks_exact_mut(2).enumerate() {
                        pair.copy_from_slice(&scratch[(j * rows + k) * 2..(j * rows + k) * 2 + 2]);
                    }
                }
            }
        });
        drop(scratch);
        let el = &mut self.elevation;
        sea.synthesize(
            (sea.elevation_amplitudes(), &[]),
            rows,
            &mut plan,
            |k, x, _| {
                el[k] = x;
            },
        );
        Ok(())
    }

    /// The record of r > 1 (module docs): (Wᵢ, Ẇᵢ, Gᵢ, Ġᵢ) and (η, η̇) at t_j = j r h, each
    /// series with its derivative in one transform of [`Sea::synthesis_every`].
    fn fill_hermite_record(&mut self) {
        let (n, rows) = (self.n, self.rows);
        let nc = self.sea.frequencies().len();
        let sea = self.sea.clone();
        let omega = sea.frequencies();
        let mut plan = sea.synthesis_rows(self.every, rows);
        let mut rate = vec![Complex::new(0.0, 0.0); nc];
        let derivative = |a: &[Complex<f64>], out: &mut [Complex<f64>]| {
            for ((o, x), &w) in out.iter_mut().zip(a).zip(omega) {
                *o = Complex::new(0.0, w) * x;
            }
        };
        let table = &mut self.series;
        pendulum_amplitudes(&sea, &self.inputs, |i, wa, ga| {
            for (a, offset) in [(wa, 0), (ga, 2)] {
                derivative(a, &mut rate);
                sea.synthesize((a, &rate), rows, &mut plan, |k, x, dx| {
                    let at = (k * n + i) * 4 + offset;
                    table[at] = x;
                    table[at + 1] = dx;
                });
            }
        });
        derivative(sea.elevation_amplitudes(), &mut rate);
        let el = &mut self.elevation;
        sea.synthesize(
            (sea.elevation_amplitudes(), &rate),
            rows,
            &mut plan,
            |k, x, dx| {
                el[2 * k] = x;
                el[2 * k + 1] = dx;
            },
        );
    }

    /// The n × N amplitudes of every pendulum's series, formed on first use (a read beyond the
    /// record, [`WaveField::amplitudes`]) by the arithmetic that formed the record's.
    fn stored_amplitudes(&self) -> &Amplitudes {
        self.amplitudes.get_or_init(|| {
            let nc = self.sea.frequencies().len();
            let zero = Complex::new(0.0, 0.0);
            let mut amp = Amplitudes {
                momentum: vec![zero; self.n * nc],
                inertia: vec![zero; self.n * nc],
            };
            pendulum_amplitudes(&self.sea, &self.inputs, |i, a, b| {
                amp.momentum[i * nc..(i + 1) * nc].copy_from_slice(a);
                amp.inertia[i * nc..(i + 1) * nc].copy_from_slice(b);
            });
            amp
        })
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

    /// The same sea on the same chain with the nodes' masses and inertia coefficients replaced
    /// (`node_inertia` in place of the pipe's or the stack-up's): the water's momentum series
    /// Wᵢ = lᵢ Σ_{k≥i} m_k u_k and the inertia series Gᵢ = lᵢ Σ_{k≥i} c_k u̇_k are linear in the
    /// masses and in the coefficients, so that with their derivatives ∂m_k/∂θ, ∂c_k/∂θ with
    /// respect to a parameter θ this field's series are ∂Wᵢ/∂θ and ∂Gᵢ/∂θ exactly
    /// ([`WaveInertiaTangent`], [`crate::Chain::set_node_quantities`]).
    ///
    /// # Errors
    /// [`SeaError::TooLarge`] when the record's memory is refused.
    pub fn with_node_coefficients(
        &self,
        masses: &[f64],
        node_inertia: &[f64],
    ) -> std::result::Result<Self, SeaError> {
        let mut inputs = self.inputs.clone();
        inputs.masses = masses.to_vec();
        inputs.inertia_per_length = 0.0;
        inputs.node_inertia = Some(node_inertia.to_vec());
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

    /// The sea realised, shared (the vessel's motion reads the same realisation).
    pub(crate) fn shared_sea(&self) -> Arc<Sea> {
        self.sea.clone()
    }

    /// The unit direction (d_x, d_z) of the waves in the transverse plane.
    pub fn direction(&self) -> [f64; 2] {
        self.inputs.direction
    }

    /// Where time t falls in the record: the grid row, the two rows around it with the
    /// interpolation's abscissa, or beyond the record. The same for every pendulum's series
    /// (and η), so that a term reading all n pendulums at one time locates t once
    /// ([`WaveField::at`], [`WaveField::momentum_at`], [`WaveField::inertia_at`]).
    #[inline]
    pub fn at(&self, t: f64) -> RecordTime {
        let s = t / self.h;
        if self.every > 1 {
            if s >= 0.0 {
                let j0 = s.floor();
                let x = s - j0;
                // The record's row of grid time j (j itself but in a window).
                let j = (j0 as usize).wrapping_sub(self.first);
                if j < self.rows && j + 1 < self.rows {
                    return RecordTime(At::Hermite(j, x));
                }
                if x <= 1e-9 && j < self.rows {
                    return RecordTime(At::Row(j));
                }
            }
            return RecordTime(At::Beyond(t));
        }
        let rows = self.rows;
        if s >= 0.0 {
            let k0 = s.floor();
            let frac = s - k0;
            // The record's row of grid time k (k itself but in a window; before a window's first
            // time, beyond every row).
            let k = (k0 as usize).wrapping_sub(self.first);
            if frac <= 1e-9 && k < rows {
                return RecordTime(At::Row(k));
            }
            if frac >= 1.0 - 1e-9 && k < rows && k + 1 < rows {
                return RecordTime(At::Row(k + 1));
            }
            if k < rows && k + 1 < rows {
                return RecordTime(At::Linear(k, frac));
            }
        }
        RecordTime(At::Beyond(t))
    }

    /// The series in `table` at the located time `at` (`stride` values per grid time, the
    /// series' value at `offset`, its derivative at `offset + 1` for r > 1): the grid value at
    /// a grid time, linear interpolation between grid times (r = 1), the cubic Hermite
    /// interpolant between the record times around t (r > 1, module docs), `beyond`(t) (the
    /// direct sum) beyond the record.
    #[inline]
    fn read(
        &self,
        table: &[f64],
        (stride, offset): (usize, usize),
        beyond: impl FnOnce(f64) -> f64,
        at: RecordTime,
    ) -> f64 {
        match at.0 {
            At::Row(k) => table[k * stride + offset],
            At::Linear(k, frac) => {
                table[k * stride + offset] * (1.0 - frac) + table[(k + 1) * stride + offset] * frac
            }
            At::Hermite(j, x) => {
                let (a, b) = (j * stride + offset, (j + 1) * stride + offset);
                let (y0, d0) = (table[a], table[a + 1] * self.h);
                let (y1, d1) = (table[b], table[b + 1] * self.h);
                let dy = y1 - y0;
                let c2 = 3.0 * dy - 2.0 * d0 - d1;
                let c3 = d0 + d1 - 2.0 * dy;
                y0 + x * (d0 + x * (c2 + x * c3))
            }
            At::Beyond(t) => beyond(t),
        }
    }

    /// Values per record time and pendulum: 2 (W, G), or 4 (W, Ẇ, G, Ġ) for r > 1.
    #[inline]
    fn width(&self) -> usize {
        if self.every > 1 {
            4
        } else {
            2
        }
    }

    /// A copy of the field that keeps only the grid times `first..first + rows` of the record,
    /// each with `add` added: `add` holds, per record time and pendulum, the values the record
    /// keeps ([`WaveField::record_width`]: (Wᵢ, Gᵢ), or (Wᵢ, Ẇᵢ, Gᵢ, Ġᵢ) for r > 1), time-major
    /// (`rows` × n × width). Read at a time within the window, it is the record's interpolant
    /// of the sums, by the same arithmetic as `self` (an `add` of zeros reads `self`'s values
    /// bit for bit); outside it, the direct sum of `self`'s amplitudes. The forecast of a plan
    /// whose sea has errors ([`crate::mpc`], "What the plan knows"); the elevation is kept.
    ///
    /// # Errors
    /// [`SeaError::Invalid`] naming `window` when the window is not within the record or `add`
    /// has not `rows` × n × width values.
    pub fn window(
        &self,
        first: usize,
        rows: usize,
        add: &[f64],
    ) -> std::result::Result<Self, SeaError> {
        let w = self.width();
        let row = self.n * w;
        let inside = first >= self.first
            && first - self.first + rows <= self.rows
            && add.len() == rows * row
            && rows >= 2;
        if !inside {
            return Err(SeaError::Invalid {
                quantity: "window",
                value: first as f64,
                expected: "rows within the record and rows × n × width values to add",
            });
        }
        let from = (first - self.first) * row;
        let mut series = self.series[from..from + rows * row].to_vec();
        for (s, a) in series.iter_mut().zip(add) {
            *s += a;
        }
        let ew = w / 2;
        let e0 = (first - self.first) * ew;
        Ok(WaveField {
            sea: self.sea.clone(),
            inputs: self.inputs.clone(),
            n: self.n,
            h: self.h,
            rows,
            first,
            every: self.every,
            series,
            elevation: self.elevation[e0..e0 + rows * ew].to_vec(),
            amplitudes: self.amplitudes.clone(),
        })
    }

    /// Values the record keeps per time and pendulum: 2 (Wᵢ, Gᵢ) or, for r > 1, 4
    /// (Wᵢ, Ẇᵢ, Gᵢ, Ġᵢ) ([`WaveField::window`]).
    pub fn record_width(&self) -> usize {
        self.width()
    }

    /// The record's grid index of its first time and its number of times (0 and all of them
    /// but in a window, [`WaveField::window`]).
    pub fn record_rows(&self) -> (usize, usize) {
        (self.first, self.rows)
    }

    /// The number of pendulums n.
    pub fn pendulums(&self) -> usize {
        self.n
    }

    /// The record's time step r h \[s\] (`[loads.waves] record_step`; the plant's step h when
    /// r = 1).
    pub fn record_step(&self) -> f64 {
        self.h
    }

    /// Wᵢ(t) = lᵢ Σ_{k≥i} m_k u_k(t) \[kg m/s · m\]: the waves' share of pendulum i's water
    /// momentum along the mean direction (module docs).
    #[inline]
    pub fn momentum(&self, i: usize, t: f64) -> f64 {
        self.momentum_at(i, self.at(t))
    }

    /// [`WaveField::momentum`] at a located time ([`WaveField::at`]): the same value bit for
    /// bit, without locating t again for every pendulum.
    #[inline]
    pub fn momentum_at(&self, i: usize, at: RecordTime) -> f64 {
        let w = self.width();
        let place = (w * self.n, w * i);
        self.read(&self.series, place, |t| self.sum_beyond(i, false, t), at)
    }

    /// Every pendulum's Wᵢ (`inertia = false`, [`WaveField::momentum_at`]) or Gᵢ (`true`,
    /// [`WaveField::inertia_at`]) at a located time, given to `each`(i, value) for i = 0..n:
    /// the same values bit for bit (the same interpolant's arithmetic), with the located time
    /// matched once for all pendulums instead of once per pendulum (a step reads every
    /// pendulum's two series once each).
    #[inline]
    pub fn read_all(&self, inertia: bool, at: RecordTime, mut each: impl FnMut(usize, f64)) {
        let w = self.width();
        let stride = w * self.n;
        let first = if inertia { w / 2 } else { 0 };
        let table = &self.series;
        match at.0 {
            At::Row(k) => {
                let row = &table[k * stride..(k + 1) * stride];
                for i in 0..self.n {
                    each(i, row[w * i + first]);
                }
            }
            At::Linear(k, frac) => {
                let (r0, r1) = table[k * stride..(k + 2) * stride].split_at(stride);
                for i in 0..self.n {
                    let o = w * i + first;
                    each(i, r0[o] * (1.0 - frac) + r1[o] * frac);
                }
            }
            At::Hermite(j, x) => {
                let (r0, r1) = table[j * stride..(j + 2) * stride].split_at(stride);
                for i in 0..self.n {
                    let o = w * i + first;
                    let (y0, d0) = (r0[o], r0[o + 1] * self.h);
                    let (y1, d1) = (r1[o], r1[o + 1] * self.h);
                    let dy = y1 - y0;
                    let c2 = 3.0 * dy - 2.0 * d0 - d1;
                    let c3 = d0 + d1 - 2.0 * dy;
                    each(i, y0 + x * (d0 + x * (c2 + x * c3)));
                }
            }
            At::Beyond(t) => {
                for i in 0..self.n {
                    each(i, self.sum_beyond(i, inertia, t));
                }
            }
        }
    }

    /// Gᵢ(t) = lᵢ Σ_{k≥i} ρ_w (1 + C_a) A_o c_k u̇_k(t) \[N m\]: the inertia load's generalised
    /// force on pendulum i along the mean direction (module docs).
    #[inline]
    pub fn inertia(&self, i: usize, t: f64) -> f64 {
        self.inertia_at(i, self.at(t))
    }

    /// [`WaveField::inertia`] at a located time ([`WaveField::at`]): the same value bit for
    /// bit.
    #[inline]
    pub fn inertia_at(&self, i: usize, at: RecordTime) -> f64 {
        let w = self.width();
        let place = (w * self.n, w * i + w / 2);
        self.read(&self.series, place, |t| self.sum_beyond(i, true, t), at)
    }

    /// Wᵢ (`inertia = false`) or Gᵢ (`true`) at a time t beyond the record: the direct sum of
    /// its amplitudes ([`Sea::sum_at`], O(N)).
    #[cold]
    fn sum_beyond(&self, i: usize, inertia: bool, t: f64) -> f64 {
        self.sea.sum_at(self.amplitudes(i, inertia), t)
    }

    /// The complex amplitudes of Wᵢ (`inertia = false`) or Gᵢ (`true`), one per component:
    /// the series is Re Σⱼ Xⱼ e^{iωⱼ t} (module docs).
    pub fn amplitudes(&self, i: usize, inertia: bool) -> &[Complex<f64>] {
        let nc = self.sea.frequencies().len();
        let stored = self.stored_amplitudes();
        let amp = if inertia {
            &stored.inertia
        } else {
            &stored.momentum
        };
        &amp[i * nc..(i + 1) * nc]
    }

    /// The surface elevation η(0, t) \[m\] at x = z = 0.
    pub fn elevation(&self, t: f64) -> f64 {
        let amp = self.sea.elevation_amplitudes();
        let w = self.width() / 2;
        let beyond = |t| self.sea.sum_at(amp, t);
        self.read(&self.elevation, (w, 0), beyond, self.at(t))
    }
}

/// Checks that the n × N complex amplitudes of Wᵢ and Gᵢ (formed only if a time beyond the
/// record is read, [`WaveField::amplitudes`]) may be held: refused with [`SeaError::TooLarge`]
/// when either one's memory is over [`crate::ocean::waves::MAX_RECORD_BYTES`] or the allocator refuses
/// to reserve it now (never an abort at construction).
fn check_amplitudes(n: usize, nc: usize) -> std::result::Result<(), SeaError> {
    let limit = crate::ocean::waves::MAX_RECORD_BYTES;
    let bytes = (n as u64).saturating_mul(nc as u64).saturating_mul(16);
    let refuse = || SeaError::TooLarge {
        what: "bytes",
        needed: bytes,
        limit,
    };
    if bytes > limit {
        return Err(refuse());
    }
    let (mut x, mut y): (Vec<Complex<f64>>, Vec<Complex<f64>>) = (Vec::new(), Vec::new());
    x.try_reserve_exact(n * nc).map_err(|_| refuse())?;
    y.try_reserve_exact(n * nc).map_err(|_| refuse())?;
    Ok(())
}

/// A zeroed record buffer of `size` values, refused with [`SeaError::TooLarge`] when the memory
/// cannot be reserved.
fn alloc_record(size: usize) -> std::result::Result<Vec<f64>, SeaError> {
    let mut x = Vec::new();
    x.try_reserve_exact(size).map_err(|_| SeaError::TooLarge {
        what: "bytes",
        needed: (size as u64).saturating_mul(8),
        limit: crate::ocean::waves::MAX_RECORD_BYTES,
    })?;
    x.resize(size, 0.0);
    Ok(x)
}
