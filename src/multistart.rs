//! Deterministic parallel multistart, clustering of local minima, a second-order certificate,
//! and objective landscapes along 1-D and 2-D slices (thesis §3.3.1, Fig. 3.7-3.13).
//!
//! Everything here takes any [`OptimProblem`] (a [`ControlProblem`](crate::ControlProblem) or
//! another differentiable objective); the certificate and the inert-parameter test need its
//! Hessian-vector products ([`OptimProblem::hessian`]).
//!
//! # Determinism and the `parallel` feature
//! Start points come from a SplitMix64 generator seeded from (seed, start index) (and, for the
//! Latin hypercube's permutations, from (seed, dimension)), all drawn before any solver runs.
//! Each start is then minimised by [`minimize`] on one thread from beginning to end, and the
//! results are collected in start order, so a report is bit-for-bit the same for every thread
//! count (except the wall-clock `seconds`). With the `parallel` feature (default) the starts, the
//! certificate's Hessian columns and the landscape points run on a rayon pool; without it they
//! run one after the other in the same order, with bit-for-bit the same results, and `threads`
//! is checked but otherwise ignored.
//!
//! # Parameters without effect
//! A start whose parameters cannot act on J ([`ineffective_params`](crate::optimize::ineffective_params))
//! fails with [`Error::NoEffect`] and is listed among the failures, never as a minimum; when every
//! start fails that way, [`multistart`] returns the error itself.
//!
//! # Clustering
//! Converged results only (a result stopped by the iteration limit or for lack of progress is not
//! a verified minimum; it stays in [`MultistartReport::results`]). Results are taken in start
//! order; one joins the first minimum found so far whose representative (its member with the
//! lowest objective) it matches in both
//! ```text
//! ‖θ_a − θ_b‖ ≤ theta_rel · max(‖θ_a‖, ‖θ_b‖) + theta_abs,
//! |J_a − J_b| ≤ objective_rel · max(|J_a|, |J_b|) + objective_abs,
//! ```
//! and otherwise starts a new one; minima are sorted by objective. Components of θ that do not act
//! on J at all ([`inert_components`], e.g. u_N of an unpenalised per-step control) are left out
//! of both norms: starts differing only there end at the same minimum. Defaults
//! ([`ClusterTolerances::default`]): theta_rel = 10⁻⁵, theta_abs = 10⁻⁶ N — far above how well
//! converged runs pin θ down (L-BFGS and the trust region agree to 3·10⁻⁸ on the per-step thesis
//! problem with effort penalty), far below the distance between distinct minima; objective_rel =
//! 10⁻⁸, objective_abs = 10⁻¹⁴ N²m² — above J's round-off (2·10⁻¹³ relative on the thesis riser),
//! so that minima whose value is zero up to round-off (Table 3.1) compare equal.
//!
//! # Certificate
//! When every converged start reached one minimum, [`certify`] checks its second-order condition:
//! the Hessian from n exact Hessian-vector products (one per unit vector; only for n ≤
//! [`MAX_CERTIFICATE_PARAMS`]), symmetrised, restricted to the components whose force bound is not
//! active, and its eigenvalues by [`nalgebra::SymmetricEigen`]. All positive means a strict local
//! minimum (with the active bounds, under strict complementarity).

use nalgebra::DMatrix;
#[cfg(feature = "parallel")]
use rayon::prelude::*;

pub use crate::error::MultistartError;
use crate::error::{Error, Result};
use crate::optimize::{minimize, Bounds, OptimOptions, OptimProblem, OptimResult};

/// Largest number of parameters for which a certificate is computed (n HVPs and a dense n × n
/// eigenproblem).
pub const MAX_CERTIFICATE_PARAMS: usize = 200;

/// How the start points are drawn.
#[derive(Clone, Debug, PartialEq)]
pub enum StartDesign {
    /// Independent uniform draws in the box [lo, hi]ⁿ.
    RandomBox {
        /// Lower end of every coordinate.
        lo: f64,
        /// Upper end of every coordinate.
        hi: f64,
    },
    /// A Latin hypercube in [lo, hi]ⁿ: each coordinate's range is cut into `starts` equal cells
    /// and every cell holds exactly one start (uniformly placed inside it).
    LatinHypercube {
        /// Lower end of every coordinate.
        lo: f64,
        /// Upper end of every coordinate.
        hi: f64,
    },
    /// center + U(−radius, radius)ⁿ: the thesis's Ỹ₀ + U(−0.1, 0.1) of §3.3.1 applied to the
    /// controls.
    Perturb {
        /// The point perturbed (n values).
        center: Vec<f64>,
        /// Half-width of the uniform perturbation (≥ 0).
        radius: f64,
    },
}

/// When two local minima are the same (module docs).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ClusterTolerances {
    /// Relative tolerance on ‖θ_a − θ_b‖. Default 10⁻⁵.
    pub theta_rel: f64,
    /// Absolute tolerance on ‖θ_a − θ_b‖ (units of θ, N). Default 10⁻⁶.
    pub theta_abs: f64,
    /// Relative tolerance on |J_a − J_b|. Default 10⁻⁸.
    pub objective_rel: f64,
    /// Absolute tolerance on |J_a − J_b| (units of J). Default 10⁻¹⁴.
    pub objective_abs: f64,
}

impl Default for ClusterTolerances {
    fn default() -> Self {
        ClusterTolerances {
            theta_rel: 1e-5,
            theta_abs: 1e-6,
            objective_rel: 1e-8,
            objective_abs: 1e-14,
        }
    }
}

impl ClusterTolerances {
    /// Whether two results are the same minimum, measuring ‖θ_a − θ_b‖ over all components but
    /// the `inert` ones (see [`inert_components`]).
    pub fn same(
        &self,
        theta_a: &[f64],
        j_a: f64,
        theta_b: &[f64],
        j_b: f64,
        inert: &[usize],
    ) -> bool {
        let masked = |t: &[f64]| -> f64 {
            t.iter()
                .enumerate()
                .filter(|(i, _)| !inert.contains(i))
                .map(|(_, x)| x * x)
                .sum::<f64>()
                .sqrt()
        };
        let d = theta_a
            .iter()
            .zip(theta_b)
            .enumerate()
            .filter(|(i, _)| !inert.contains(i))
            .map(|(_, (a, b))| (a - b) * (a - b))
            .sum::<f64>()
            .sqrt();
        let scale = masked(theta_a).max(masked(theta_b));
        d <= self.theta_rel * scale + self.theta_abs
            && (j_a - j_b).abs()
                <= self.objective_rel * j_a.abs().max(j_b.abs()) + self.objective_abs
    }
}

/// The components of θ that do not act on J at θ: ∂J/∂θᵢ is exactly 0 and so is the Hessian
/// column H eᵢ (one exact HVP each). Structurally inert parameters pass this test bit for bit,
/// e.g. u_N of a per-step control without effort penalty, which only reaches p_N (thesis §3.3.1):
/// starts that differ only there reach the same minimum, and [`cluster`] must not count them as
/// distinct. (Exact zeros, not small values: a weak but real influence is not inert.)
///
/// Without Hessian-vector products ([`OptimProblem::hessian`]) no component is reported.
///
/// # Errors
/// The simulation's or HVP's error.
pub fn inert_components<Q: OptimProblem + ?Sized>(
    problem: &Q,
    theta: &[f64],
) -> Result<Vec<usize>> {
    let Some(hvp) = problem.hessian() else {
        return Ok(Vec::new());
    };
    let g = problem.gradient(theta)?;
    let mut inert = Vec::new();
    for (i, gi) in g.iter().enumerate() {
        if gi.abs() > 0.0 {
            continue;
        }
        let mut e = vec![0.0; theta.len()];
        e[i] = 1.0;
        if hvp.hessian_vec(theta, &e)?.iter().all(|h| h.abs() == 0.0) {
            inert.push(i);
        }
    }
    Ok(inert)
}

/// One local minimum found by one or more starts.
#[derive(Clone, Debug, PartialEq)]
pub struct Minimum {
    /// The lowest objective among its starts.
    pub objective: f64,
    /// θ of that start.
    pub theta: Vec<f64>,
    /// How many converged starts reached it.
    pub count: usize,
    /// The start (index into the start points) that gave `objective`.
    pub best_start: usize,
    /// All starts that reached it, in order.
    pub starts: Vec<usize>,
}

/// The second-order check at a minimum (module docs).
#[derive(Clone, Debug, PartialEq)]
pub struct Certificate {
    /// θ at which the Hessian was taken.
    pub theta: Vec<f64>,
    /// J(θ).
    pub objective: f64,
    /// Eigenvalues (ascending) of the symmetrised Hessian on the free components.
    pub eigenvalues: Vec<f64>,
    /// The components whose force bound is not active (all, without a bound).
    pub free: Vec<usize>,
    /// ‖H − Hᵀ‖_F / ‖H‖_F of the assembled Hessian before symmetrisation (round-off of the HVPs).
    pub asymmetry: f64,
    /// Whether every eigenvalue is positive.
    pub positive_definite: bool,
    /// Hessian-vector products used (n).
    pub hvp_evals: usize,
}

/// A start that failed with an error (invalid or infeasible start, simulation failure, HVP
/// failure).
#[derive(Clone, Debug, PartialEq)]
pub struct StartFailure {
    /// Index of the start.
    pub start: usize,
    /// The error.
    pub error: Error,
}

/// The outcome of [`multistart`].
#[derive(Clone, Debug, PartialEq)]
pub struct MultistartReport {
    /// The distinct local minima, lowest objective first.
    pub minima: Vec<Minimum>,
    /// Components of θ that do not act on J ([`inert_components`] at the first converged
    /// result); distances between minima ignore them.
    pub inert: Vec<usize>,
    /// The results of the starts that did not fail, in start order.
    pub results: Vec<OptimResult>,
    /// For each entry of `results`, its start index.
    pub result_starts: Vec<usize>,
    /// The start points θ₀ (clamped into the force bound, if any), in start order.
    pub start_points: Vec<Vec<f64>>,
    /// The starts that failed.
    pub failures: Vec<StartFailure>,
    /// Given when at least one start converged, all converged starts reached one minimum, and
    /// the problem has Hessian-vector products and at most [`MAX_CERTIFICATE_PARAMS`]
    /// parameters.
    pub certificate: Option<Certificate>,
    /// Wall-clock time in seconds.
    pub seconds: f64,
}

// ---------------------------------------------------------------------------------------------
// Random numbers
// ---------------------------------------------------------------------------------------------

/// SplitMix64 (Steele, Lea, Flood 2014): a 64-bit state, one addition and a bijective mix per
/// draw; passes BigCrush. Enough for start points, and no dependency.
#[derive(Clone, Debug)]
struct SplitMix64(u64);

const GOLDEN: u64 = 0x9E37_79B9_7F4A_7C15;

fn mix(mut z: u64) -> u64 {
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

impl SplitMix64 {
    /// The stream for (seed, index, tag): independent of any other stream's use.
    fn stream(seed: u64, index: u64, tag: u64) -> Self {
        SplitMix64(mix(mix(seed ^ GOLDEN) ^ mix(index.wrapping_add(GOLDEN))) ^ mix(tag))
    }
    fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(GOLDEN);
        mix(self.0)
    }
    /// Uniform in [0, 1) with 53 random bits.
    fn uniform(&mut self) -> f64 {
        (self.next_u64() >> 11) as f64 * (1.0 / (1u64 << 53) as f64)
    }
    /// Uniform in 0..n (n ≥ 1), by rejection (no modulo bias).
    fn below(&mut self, n: u64) -> u64 {
        let zone = u64::MAX - u64::MAX % n;
        loop {
            let x = self.next_u64();
            if x < zone {
                return x % n;
            }
        }
    }
}

const TAG_POINT: u64 = 1;
const TAG_PERMUTATION: u64 = 2;

/// The `starts` start points of `design` in n dimensions for `seed` (what [`multistart`] uses,
/// before clamping into a force bound).
///
/// # Errors
/// [`MultistartError::EmptyBox`] for an empty or non-finite range, [`MultistartError::BadRadius`]
/// for a negative radius, [`MultistartError::BadCenter`] for a center of the wrong length.
pub fn start_points(
    design: &StartDesign,
    n: usize,
    starts: usize,
    seed: u64,
) -> Result<Vec<Vec<f64>>> {
    let check_box = |lo: f64, hi: f64| {
        if lo.is_finite() && hi.is_finite() && lo < hi {
            Ok(())
        } else {
            Err(MultistartError::EmptyBox { lo, hi })
        }
    };
    match design {
        StartDesign::RandomBox { lo, hi } => {
            check_box(*lo, *hi)?;
            Ok((0..starts)
                .map(|i| {
                    let mut r = SplitMix64::stream(seed, i as u64, TAG_POINT);
                    (0..n).map(|_| lo + (hi - lo) * r.uniform()).collect()
                })
                .collect())
        }
        StartDesign::LatinHypercube { lo, hi } => {
            check_box(*lo, *hi)?;
            let perms: Vec<Vec<usize>> = (0..n)
                .map(|d| {
                    let mut r = SplitMix64::stream(seed, d as u64, TAG_PERMUTATION);
                    let mut p: Vec<usize> = (0..starts).collect();
                    for i in (1..starts).rev() {
                        let j = r.below(i as u64 + 1) as usize;
                        p.swap(i, j);
                    }
                    p
                })
                .collect();
            let cell = (hi - lo) / starts.max(1) as f64;
            Ok((0..starts)
                .map(|i| {
                    let mut r = SplitMix64::stream(seed, i as u64, TAG_POINT);
                    (0..n)
                        .map(|d| lo + cell * (perms[d][i] as f64 + r.uniform()))
                        .collect()
                })
                .collect())
        }
        StartDesign::Perturb { center, radius } => {
            if center.len() != n || center.iter().any(|x| !x.is_finite()) {
                return Err(MultistartError::BadCenter {
                    expected: n,
                    got: center.len(),
                }
                .into());
            }
            if !(radius.is_finite() && *radius >= 0.0) {
                return Err(MultistartError::BadRadius { radius: *radius }.into());
            }
            Ok((0..starts)
                .map(|i| {
                    let mut r = SplitMix64::stream(seed, i as u64, TAG_POINT);
                    center
                        .iter()
                        .map(|c| c + radius * (2.0 * r.uniform() - 1.0))
                        .collect()
                })
                .collect())
        }
    }
}

// ---------------------------------------------------------------------------------------------
// Multistart
// ---------------------------------------------------------------------------------------------

/// The largest thread count [`multistart`] accepts: far above any machine's cores, far below
/// the count whose thread creation alone takes minutes (10⁵).
pub const MAX_THREADS: usize = 1024;

/// Runs `f` for 0..n, in order of index in the result: on a rayon pool of `threads` threads (0:
/// rayon's default) with the `parallel` feature, one after the other without it.
fn map_indexed<T, F>(threads: usize, n: usize, f: F) -> Result<Vec<T>>
where
    T: Send,
    F: Fn(usize) -> T + Sync + Send,
{
    if threads > MAX_THREADS {
        return Err(MultistartError::TooManyThreads {
            threads,
            max: MAX_THREADS,
        }
        .into());
    }
    #[cfg(feature = "parallel")]
    {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .map_err(|e| MultistartError::ThreadPool {
                message: e.to_string(),
            })?;
        Ok(pool.install(|| (0..n).into_par_iter().map(f).collect()))
    }
    #[cfg(not(feature = "parallel"))]
    {
        Ok((0..n).map(f).collect())
    }
}

/// `f` over `items` in order: on rayon's current pool with the `parallel` feature, one after the
/// other without it.
fn map_items<I, T, F>(items: &[I], f: F) -> Vec<T>
where
    I: Sync,
    T: Send,
    F: Fn(&I) -> T + Sync + Send,
{
    #[cfg(feature = "parallel")]
    {
        items.par_iter().map(f).collect()
    }
    #[cfg(not(feature = "parallel"))]
    {
        items.iter().map(f).collect()
    }
}

/// Minimises `problem` from `starts` points of `design` on a pool of `threads` threads (0:
/// rayon's default, the number of cores; at most [`MAX_THREADS`]), clusters the converged
/// results into local minima and, when they all reached one, certifies it ([`certify`]).
/// Deterministic: see the module docs.
///
/// # Errors
/// [`MultistartError`] for an invalid design, `starts = 0` ([`MultistartError::NoStarts`]), more
/// than [`MAX_THREADS`] threads, or a thread pool that cannot be built; the options' errors; [`Error::NoEffect`] when every
/// start failed with it; the certificate's HVP error. Any other failing start does not fail the
/// run: it is listed in [`MultistartReport::failures`].
pub fn multistart<Q: OptimProblem + Sync + ?Sized>(
    problem: &Q,
    design: &StartDesign,
    starts: usize,
    seed: u64,
    threads: usize,
    opts: &OptimOptions,
) -> Result<MultistartReport> {
    let clock = std::time::Instant::now();
    opts.validate()?;
    if starts == 0 {
        return Err(MultistartError::NoStarts.into());
    }
    let mut points = start_points(design, problem.n_params(), starts, seed)?;
    if let Some(b) = opts.force_bounds()? {
        for x in points.iter_mut().flatten() {
            *x = x.clamp(b.lower(), b.upper());
        }
    }
    let outcomes: Vec<Result<OptimResult>> = map_indexed(threads, points.len(), |i| {
        minimize(problem, &points[i], opts)
    })?;
    let mut results = Vec::new();
    let mut result_starts = Vec::new();
    let mut failures = Vec::new();
    for (start, outcome) in outcomes.into_iter().enumerate() {
        match outcome {
            Ok(r) => {
                results.push(r);
                result_starts.push(start);
            }
            Err(error) => failures.push(StartFailure { start, error }),
        }
    }
    if results.is_empty()
        && failures
            .iter()
            .all(|f| matches!(f.error, Error::NoEffect { .. }))
    {
        if let Some(f) = failures.first() {
            return Err(f.error.clone());
        }
    }
    let inert = match results.iter().find(|r| r.converged) {
        Some(r) => inert_components(problem, &r.theta)?,
        None => Vec::new(),
    };
    let minima = cluster(
        &results,
        &result_starts,
        &ClusterTolerances::default(),
        &inert,
    );
    let certificate = match minima.as_slice() {
        [m] if problem.n_params() <= MAX_CERTIFICATE_PARAMS && problem.hessian().is_some() => {
            let m = &m.theta;
            let mut c = map_indexed(threads, 1, |_| certify(problem, m, opts.force_bounds()?))?;
            Some(c.pop().expect("one certificate")?)
        }
        _ => None,
    };
    Ok(MultistartReport {
        minima,
        inert,
        results,
        result_starts,
        start_points: points,
        failures,
        certificate,
        seconds: clock.elapsed().as_secs_f64(),
    })
}

/// Groups the converged `results` (from starts `result_starts`) into distinct minima, lowest
/// objective first (module docs).
pub fn cluster(
    results: &[OptimResult],
    result_starts: &[usize],
    tol: &ClusterTolerances,
    inert: &[usize],
) -> Vec<Minimum> {
    let mut minima: Vec<Minimum> = Vec::new();
    for (r, &start) in results.iter().zip(result_starts) {
        if !r.converged {
            continue;
        }
        let found = minima
            .iter_mut()
            .find(|m| tol.same(&m.theta, m.objective, &r.theta, r.objective, inert));
        match found {
            Some(m) => {
                m.count += 1;
                m.starts.push(start);
                if r.objective < m.objective {
                    m.objective = r.objective;
                    m.theta.clone_from(&r.theta);
                    m.best_start = start;
                }
            }
            None => minima.push(Minimum {
                objective: r.objective,
                theta: r.theta.clone(),
                count: 1,
                best_start: start,
                starts: vec![start],
            }),
        }
    }
    minima.sort_by(|a, b| {
        a.objective
            .total_cmp(&b.objective)
            .then(a.best_start.cmp(&b.best_start))
    });
    minima
}

/// The second-order certificate at θ (module docs): n HVPs (on the current rayon pool with the
/// `parallel` feature), symmetrised, restricted to the components not on the force bound.
///
/// # Errors
/// [`MultistartError::CertificateTooLarge`] if n exceeds [`MAX_CERTIFICATE_PARAMS`],
/// [`MultistartError::NoHessian`] if the problem has no Hessian-vector products; θ's errors; the simulation's or HVP's error.
pub fn certify<Q: OptimProblem + Sync + ?Sized>(
    problem: &Q,
    theta: &[f64],
    bounds: Option<Bounds>,
) -> Result<Certificate> {
    let n = problem.n_params();
    if problem.hessian().is_none() {
        return Err(MultistartError::NoHessian.into());
    }
    if n > MAX_CERTIFICATE_PARAMS {
        return Err(MultistartError::CertificateTooLarge {
            n,
            max: MAX_CERTIFICATE_PARAMS,
        }
        .into());
    }
    let objective = problem.value(theta)?;
    let indices: Vec<usize> = (0..n).collect();
    let columns: Vec<Vec<f64>> = map_items(&indices, |&j| {
        let mut e = vec![0.0; n];
        e[j] = 1.0;
        match problem.hessian() {
            Some(h) => h.hessian_vec(theta, &e),
            None => Err(crate::optimize::adapter::no_hessian()),
        }
    })
    .into_iter()
    .collect::<Result<_>>()?;
    if columns.iter().flatten().any(|x| !x.is_finite()) {
        return Err(Error::NonFiniteObjective {
            quantity: "Hessian-vector product",
        });
    }
    let h = DMatrix::from_fn(n, n, |i, j| columns[j][i]);
    let sym = (&h + h.transpose()) * 0.5;
    let hn = h.norm();
    let asymmetry = if hn > 0.0 {
        (&h - h.transpose()).norm() / hn
    } else {
        0.0
    };
    let free: Vec<usize> = match bounds {
        None => (0..n).collect(),
        Some(b) => (0..n)
            .filter(|&i| b.at_bounds(theta[i]) == (false, false))
            .collect(),
    };
    let reduced = DMatrix::from_fn(free.len(), free.len(), |i, j| sym[(free[i], free[j])]);
    let mut eigenvalues: Vec<f64> = if free.is_empty() {
        Vec::new()
    } else {
        reduced.symmetric_eigenvalues().iter().copied().collect()
    };
    eigenvalues.sort_by(f64::total_cmp);
    Ok(Certificate {
        theta: theta.to_vec(),
        objective,
        positive_definite: eigenvalues.iter().all(|&l| l > 0.0),
        eigenvalues,
        free,
        asymmetry,
        hvp_evals: n,
    })
}

// ---------------------------------------------------------------------------------------------
// Landscapes
// ---------------------------------------------------------------------------------------------

/// The unit vector e_i in n dimensions (a coordinate direction for the landscapes).
pub fn axis(n: usize, i: usize) -> Vec<f64> {
    let mut e = vec![0.0; n];
    if i < n {
        e[i] = 1.0;
    }
    e
}

fn grid(range: (f64, f64), points: usize, name: &'static str) -> Result<Vec<f64>> {
    let (a, b) = range;
    if !(a.is_finite() && b.is_finite()) || points == 0 {
        return Err(MultistartError::BadGrid {
            name,
            range,
            points,
        }
        .into());
    }
    Ok(if points == 1 {
        vec![a]
    } else {
        (0..points)
            .map(|k| a + (b - a) * k as f64 / (points - 1) as f64)
            .collect()
    })
}

fn check_dir(n: usize, d: &[f64], name: &'static str) -> Result<()> {
    if d.len() != n || d.iter().any(|x| !x.is_finite()) {
        return Err(MultistartError::BadVector {
            name,
            expected: n,
            got: d.len(),
        }
        .into());
    }
    Ok(())
}

/// J(center + t·direction) at `points` equally spaced t in `range` (ends included), as (t, J)
/// pairs in order; evaluated in parallel on rayon's current pool (with the `parallel` feature). With `direction = axis(n, i)`
/// this is the landscape along parameter i (Fig. 3.7, 3.10: J against a constant u).
///
/// # Errors
/// [`MultistartError::BadVector`] for mismatched lengths, [`MultistartError::BadGrid`] for a
/// non-finite range or no points; the first
/// simulation error along the slice.
pub fn landscape_1d<Q: OptimProblem + Sync + ?Sized>(
    problem: &Q,
    center: &[f64],
    direction: &[f64],
    range: (f64, f64),
    points: usize,
) -> Result<Vec<(f64, f64)>> {
    let n = problem.n_params();
    check_dir(n, center, "center")?;
    check_dir(n, direction, "direction")?;
    let ts = grid(range, points, "range")?;
    map_items(&ts, |&t| {
        let th: Vec<f64> = center
            .iter()
            .zip(direction)
            .map(|(c, d)| c + t * d)
            .collect();
        problem.value(&th).map(|j| (t, j))
    })
    .into_iter()
    .collect()
}

/// J(center + s·d₁ + t·d₂) on a `points[0]` × `points[1]` grid over `ranges`, as [s, t, J] rows
/// with t varying fastest; evaluated in parallel on rayon's current pool (with the `parallel`
/// feature).
///
/// # Errors
/// As [`landscape_1d`].
pub fn landscape_2d<Q: OptimProblem + Sync + ?Sized>(
    problem: &Q,
    center: &[f64],
    directions: [&[f64]; 2],
    ranges: [(f64, f64); 2],
    points: [usize; 2],
) -> Result<Vec<[f64; 3]>> {
    let n = problem.n_params();
    check_dir(n, center, "center")?;
    check_dir(n, directions[0], "directions")?;
    check_dir(n, directions[1], "directions")?;
    let ss = grid(ranges[0], points[0], "ranges")?;
    let ts = grid(ranges[1], points[1], "ranges")?;
    let pairs: Vec<(f64, f64)> = ss
        .iter()
        .flat_map(|&s| ts.iter().map(move |&t| (s, t)))
        .collect();
    map_items(&pairs, |&(s, t)| {
        let th: Vec<f64> = (0..n)
            .map(|i| center[i] + s * directions[0][i] + t * directions[1][i])
            .collect();
        problem.value(&th).map(|j| [s, t, j])
    })
    .into_iter()
    .collect()
}
