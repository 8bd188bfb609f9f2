//! Static equilibrium of the chain, solved directly (the ground truth a dissipative simulation
//! must settle to, thesis §2.4.4), in the model the scene needs: the planar one (qⱼ ∈ S¹) for a
//! scene whose loads lie in the y–z plane, the spatial one (qⱼ ∈ S²) for a scene with loads or a
//! current along x ([`Scene::is_spatial`]), like [`crate::simulate()`].
//!
//! The energy and its derivatives come from the model's force terms ([`crate::model::terms`]):
//! f = ∂U/∂q ([`Chain::potential_gradient`]) and K = ∂²U/∂q² ([`Chain::force_jacobian_product`],
//! symmetric and block-tridiagonal, so a few products seeded on every third pendulum give all of
//! it; with soil springs it is dense below the mudline, [`Chain::stiffness_reach`], and one
//! product per pendulum gives it). A current's drag enters as its steady force at rest, Fᵢ(0) = Dᵢ Pᵢ|Pᵢ|
//! ([`crate::model::CurrentDrag`], read from the model, so with the per-pendulum Dᵢ = D wᵢ of a
//! `[pipe]` scene, [`Scene::drag_weights`]): independent of q, it adds −F(0) to f and nothing to
//! K (the still-water drag has F(0) = 0). A locked tip (fixed-fixed, pinned-pinned, and the
//! reaction-force variant at its rest target 0) adds ν l(q) to the energy, with
//! l(q) = Σ lⱼ e₃ᵀqⱼ the tip's z: the constraint the model imposes (in the spatial model too,
//! where the tip's x stays free, as in the dynamics); ν is the tip multiplier.
//!
//! # Planar: Newton in the absolute angles
//!
//! In the plane the chain is parametrised by the absolute angles φⱼ of the pendulums
//! (qⱼ = (cos φⱼ, sin φⱼ) in (y, z)), so the joint angles are θᵢ = φᵢ − φ_{i−1}
//! (φ₀ = φ_{n+1} = 0) and
//! ```text
//! U(φ) = ½ Σᵢ kᵢ (φᵢ − φ_{i−1})² + Σⱼ lⱼ cⱼ sin φⱼ   [+ ν Σⱼ lⱼ sin φⱼ for a locked tip]
//! ```
//! with cⱼ the load coefficient of pendulum j (point loads, gravity and control, eq. 2.2.2/3.1.1).
//! With tⱼ = ∂qⱼ/∂φⱼ the gradient is ∂U/∂φⱼ = fⱼ·tⱼ and the Hessian
//! ∂²U/∂φⱼ∂φₖ = tⱼᵀKⱼₖtₖ − δⱼₖ fⱼ·qⱼ (three products of K). Newton's method on ∇U = 0 (and the
//! tip constraint Σ lⱼ sin φⱼ = 0) has a tridiagonal Hessian bordered by the constraint.
//!
//! # Spatial: Newton on the product of spheres
//!
//! In the spatial model qⱼ ∈ S² has no global angle chart, so each Newton step works in a local
//! chart around the current iterate: Tⱼ = (aⱼ, bⱼ) is an orthonormal basis of the tangent plane
//! of qⱼ (aⱼ the unit vector of the x–qⱼ plane orthogonal to qⱼ, bⱼ = aⱼ × qⱼ: (e₁, e₃) on the
//! straight beam, and bⱼ the planar tangent tⱼ when qⱼ lies in the y–z plane), with two
//! coordinates δⱼ ∈ ℝ² per pendulum and the retraction
//! ```text
//! qⱼ(δ) = (qⱼ + Tⱼδⱼ) / |qⱼ + Tⱼδⱼ| = qⱼ + Tⱼδⱼ − ½|δⱼ|² qⱼ + O(|δ|³).
//! ```
//! Inserting this expansion into the Taylor expansion of U about the iterate,
//! ```text
//! U(q(δ)) = U + Σⱼ fⱼ·(qⱼ(δ) − qⱼ) + ½ Σⱼₖ (qⱼ(δ) − qⱼ)ᵀKⱼₖ(qₖ(δ) − qₖ) + O(|δ|³)
//!         = U + Σⱼ fⱼᵀTⱼδⱼ + ½ Σⱼₖ δⱼᵀTⱼᵀKⱼₖTₖδₖ − ½ Σⱼ (fⱼ·qⱼ)|δⱼ|² + O(|δ|³),
//! ```
//! gives the Riemannian gradient and Hessian of U on the product of spheres,
//! ```text
//! ∂U/∂δⱼ = Tⱼᵀfⱼ ,    ∂²U/∂δⱼ∂δₖ = TⱼᵀKⱼₖTₖ − δⱼₖ (fⱼ·qⱼ) I₂ ,
//! ```
//! the second term the sphere's curvature (the normal component of the force, which the length
//! constraints carry, bends the chart). In the plane (δⱼ = (0, φ-increment)) this is the planar
//! Hessian above. With a locked tip f is the Lagrangian's gradient f + ν lⱼ e₃ and the system is
//! bordered by the constraint row ∂l/∂δⱼ = lⱼ Tⱼᵀe₃. The step solves the (2n (+1))² system
//! H δ = −∇U (δⱼₖ above is Kronecker's) and retracts, qⱼ ← qⱼ(δ), then re-centres the chart at
//! the new iterate (new bases Tⱼ). The retraction agrees with the sphere's geodesics to second
//! order, so this is Newton's method on the manifold and converges quadratically (measured in
//! tests/model/statics_spatial.rs: 2 to 6 iterations from the straight beam). K is seeded on the
//! tangent directions aⱼ and bⱼ of every third pendulum: six products give every block.
//!
//! A spatial beam without end springs (pinned-pinned) has no isolated equilibrium: its tip is
//! locked only in z, so the whole beam turns freely about the z axis through the base. Its
//! spatial statics is refused ([`Error::StaticNotIsolated`]).
//!
//! Both systems are solved densely with partial pivoting (nalgebra's LU): for a pinned-pinned
//! beam the planar tridiagonal block alone is singular at the straight configuration (the rigid
//! rotation is removed only by the border), so the pivot-free bordered elimination of
//! [`crate::tridiag`] does not apply. This is a verification tool, not a hot loop; O(n³) is fine
//! for the n ≤ a few hundred it is used with.

mod planar;
mod spatial;
mod start;

pub use start::{calm_scene, set_static_start, static_start};

use crate::error::{Error, Result};
use crate::model::Chain;
use crate::scene::Scene;
use nalgebra::{DMatrix, DVector};

/// Newton iterations before [`Error::StaticNotConverged`].
const MAX_ITERATIONS: usize = 100;

/// The scaled residual below which Newton stops (gradient over the largest spring constant, and
/// the tip's z in metres).
const TOLERANCE: f64 = 1e-14;

/// A static equilibrium of the chain.
///
/// A planar solution has x = 0 at every node; `positions` holds (y, z) in both models, so code
/// written for the planar statics reads a spatial solution's in-plane coordinates unchanged, and
/// `positions_x` (or [`StaticSolution::positions_xyz`]) adds x.
#[derive(Clone, Debug, PartialEq)]
pub struct StaticSolution {
    /// The angle of each pendulum from +y toward +z, atan2(e₃ᵀqⱼ, e₂ᵀqⱼ) \[rad\]: the absolute
    /// angle φⱼ of the planar chain (for a spatial solution, of qⱼ's projection onto the y–z
    /// plane; see `attitudes`).
    pub angles: Vec<f64>,
    /// Node positions (y, z) of nodes 1..=n.
    pub positions: Vec<[f64; 2]>,
    /// Node x coordinates of nodes 1..=n (all 0 for a planar solution).
    pub positions_x: Vec<f64>,
    /// The pendulums' unit vectors qⱼ as (x, y, z).
    pub attitudes: Vec<[f64; 3]>,
    /// Whether the spatial model (qⱼ ∈ S²) was solved.
    pub spatial: bool,
    /// The tip multiplier ν (the tip reaction force, thesis sign), 0 for a free tip.
    pub tip_multiplier: f64,
    /// Newton iterations used.
    pub iterations: usize,
    /// Final max-norm of the gradient residual (scaled by the largest spring constant).
    pub residual: f64,
    /// The scaled residual at each Newton iterate, from the straight beam to the solution
    /// (`iterations + 1` values, the last is `residual`): quadratic convergence shows as
    /// rₖ₊₁ ≲ C rₖ².
    pub residuals: Vec<f64>,
}

impl StaticSolution {
    /// Node positions (x, y, z) of nodes 1..=n.
    pub fn positions_xyz(&self) -> Vec<[f64; 3]> {
        let yz = self.positions.iter().zip(&self.positions_x);
        yz.map(|(&[y, z], &x)| [x, y, z]).collect()
    }
}

/// Solves the static equilibrium of a scene's beam under its loads, as they act at the final time
/// t_N, with the final control (u_{x,N}, u_N), in the model the scene needs (module docs): the
/// planar one unless [`Scene::is_spatial`].
///
/// # Errors
/// [`Error::StaticNotConverged`] if Newton does not converge in 100 iterations,
/// [`Error::StaticSingular`], [`Error::StaticFolded`] for an iterate that folds the beam,
/// [`Error::StaticNotIsolated`] for a spatial pinned-pinned scene, and the scene's errors.
pub fn static_equilibrium(scene: &Scene) -> Result<StaticSolution> {
    // u_N is the last value of every kind of control (constant, per-step, the last piece).
    let last = |v: Option<&Vec<f64>>| v.and_then(|v| v.last().copied()).unwrap_or(0.0);
    let u = last(scene.control.as_ref().map(|c| &c.values));
    let ux = last(scene.control.as_ref().and_then(|c| c.values_x.as_ref()));
    let t = scene.time.step * scene.time.steps as f64;
    if scene.is_spatial() {
        static_equilibrium_spatial(scene, t, [ux, u])
    } else {
        planar::solve(scene, t, u)
    }
}

/// The static equilibrium under the loads as they act at time `t` (time-varying point loads
/// frozen at t) with the control force `u` along z at the control node, in the model the scene
/// needs (a 2-axis control's x component is 0 here: see [`static_equilibrium_spatial`]).
///
/// A current's drag enters as its steady force at rest: ṗ = 0 and p = 0 leave
/// Fᵢ(0) = Dᵢ Pᵢ|Pᵢ| ([`crate::model::CurrentDrag`]), a force independent of q, so it adds −F(0) to
/// ∂U/∂q and nothing to K (the still-water drag has F(0) = 0).
///
/// # Errors
/// As [`static_equilibrium`].
pub fn static_equilibrium_at(scene: &Scene, t: f64, u: f64) -> Result<StaticSolution> {
    if scene.is_spatial() {
        static_equilibrium_spatial(scene, t, [0.0, u])
    } else {
        planar::solve(scene, t, u)
    }
}

/// The static equilibrium in the spatial model (qⱼ ∈ S², Newton on the product of spheres,
/// module docs) under the loads at time `t` with the control `u` = (u_x, u_z) at the control
/// node, for any scene: a planar scene gives the planar equilibrium (x = 0) by the other method.
///
/// # Errors
/// As [`static_equilibrium`]; [`Error::StaticNotIsolated`] for a beam without end springs
/// (pinned-pinned), [`crate::model::ModelError::NoControlNode`] for u_x ≠ 0 in a scene without a control.
pub fn static_equilibrium_spatial(scene: &Scene, t: f64, u: [f64; 2]) -> Result<StaticSolution> {
    spatial::solve(scene, t, u)
}

/// The largest spring constant (at least 1): the scale of the gradient residual.
fn residual_scale(springs: &[f64]) -> f64 {
    springs.iter().fold(0.0f64, |a, &b| a.max(b)).max(1.0)
}

/// Appends the scaled residual max |rhs[..m]| / scale (and |rhs[m]|, the tip's z, if present) to
/// `history` and returns it, `None` if it is not finite.
fn record_residual(rhs: &[f64], m: usize, scale: f64, history: &mut Vec<f64>) -> Option<f64> {
    let r = rhs[..m].iter().fold(0.0f64, |a, g| a.max(g.abs() / scale));
    let r = rhs[m..].iter().fold(r, |a, c| a.max(c.abs()));
    history.push(r);
    r.is_finite().then_some(r)
}

/// A chart of the configuration manifold for one Newton iteration, in `D` dimensions: the
/// planar chain's absolute angles (one coordinate per pendulum, [`planar`]) or the spatial
/// chain's tangent planes of S² (two, [`spatial`]). [`newton`] is the one iteration over both.
trait Chart<const D: usize> {
    /// Coordinates per pendulum.
    const COORDS: usize;

    /// The gradient of the Lagrangian in the chart's coordinates (into `rhs`, the tip's z last
    /// for a locked tip) and the dense Hessian, bordered by the tip constraint, at the current
    /// iterate and tip multiplier ν.
    fn newton_system(
        &mut self,
        chain: &Chain<f64, D>,
        nu: f64,
        rhs: &mut [f64],
    ) -> Result<DMatrix<f64>>;

    /// Moves the iterate by −δ for the Newton solution δ of H δ = ∇U (its first
    /// `COORDS · n` entries) and re-centres the chart.
    fn step(&mut self, delta: &[f64]);

    /// The converged iterate as a [`StaticSolution`].
    fn solution(&self, chain: &Chain<f64, D>, nu: f64, residuals: Vec<f64>) -> StaticSolution;
}

/// Newton's method on ∇U = 0 (and the tip constraint) from the chart's iterate: at most
/// [`MAX_ITERATIONS`] dense bordered solves, stopping at the scaled residual [`TOLERANCE`].
fn newton<const D: usize, C: Chart<D>>(
    chain: &Chain<f64, D>,
    chart: &mut C,
) -> Result<StaticSolution> {
    let m = C::COORDS * chain.n();
    let bordered = chain.has_tip_constraint();
    let mut nu = 0.0f64;
    let mut rhs = vec![0.0; m + usize::from(bordered)];
    let mut residuals = Vec::new();
    let scale = residual_scale(chain.springs());
    for it in 0..MAX_ITERATIONS {
        let a = chart
            .newton_system(chain, nu, &mut rhs)
            .map_err(|e| folded_at(e, it))?;
        let r = record_residual(&rhs, m, scale, &mut residuals);
        if r.is_some_and(|r| r < TOLERANCE) {
            return Ok(chart.solution(chain, nu, residuals));
        }
        if r.is_none() {
            break;
        }
        let sol = a
            .lu()
            .solve(&DVector::from_column_slice(&rhs))
            .ok_or(Error::StaticSingular { iteration: it })?;
        chart.step(&sol.as_slice()[..m]);
        if bordered {
            nu -= sol[m];
        }
    }
    Err(Error::StaticNotConverged {
        iterations: MAX_ITERATIONS,
        residual: residuals.last().copied().unwrap_or(f64::NAN),
    })
}

/// A folded iterate as the statics' error (the terms report [`Error::Folded`] at "step 0").
pub(crate) fn folded_at(e: Error, iteration: usize) -> Error {
    match e {
        Error::Folded {
            joint,
            angle_deg,
            limit_deg,
            ..
        } => Error::StaticFolded {
            iteration,
            joint,
            angle_deg,
            limit_deg,
        },
        e => e,
    }
}
