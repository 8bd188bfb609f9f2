//! An [`OptimProblem`] as an argmin problem: [`ArgminAdapter`] (cost, gradient, Hessian) and the
//! matrix-free [`HessianOperator`], over `Vec<f64>` in the solver variables φ (module docs of
//! [`optimize`](super): the argmin problem, scaling, the bound).

use std::cell::{Cell, RefCell};
use std::fmt;
use std::rc::Rc;

use argmin::core::{CostFunction, Gradient, Hessian};
use argmin_math::ArgminDot;

use super::bounds::{self, Bounds};
use super::observers::Relay;
use super::point::{same_bits, Point};
use super::problem::OptimProblem;
use super::ArgminError;
use crate::error::{Error, OptimizeError, Result};

/// HVP products remembered by one [`HessianOperator`] (Steihaug asks for d·(H d) and then H d).
const HVP_CACHE: usize = 4;

/// Evaluation counts of an [`ArgminAdapter`] (shared with its Hessian operators).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct EvalCounts {
    /// Calls of [`CostFunction::cost`].
    pub cost_requests: usize,
    /// Calls of [`Gradient::gradient`].
    pub gradient_requests: usize,
    /// Evaluations of J and ∇J run (cache misses): adjoint sweeps for a control problem.
    pub sweeps: usize,
    /// Hessian-vector products run.
    pub hvps: usize,
    /// Evaluations that failed (a failed simulation, a point outside the resolved range).
    pub failures: usize,
    /// Iterations counted by [`minimize`](super::minimize)'s supervisor.
    pub iterations: usize,
}

/// State shared by an adapter, its clones, its Hessian operators, the supervisor and the
/// observer bridge of one [`minimize`](super::minimize) run.
#[derive(Default)]
pub(crate) struct Shared {
    /// The last point evaluated (one evaluation answers cost and gradient).
    pub(crate) cache: RefCell<Option<Point>>,
    /// The point with the lowest J evaluated so far.
    pub(crate) best: RefCell<Option<Point>>,
    /// The solver's current iterate, kept by the supervisor when observers listen.
    pub(crate) current: RefCell<Option<Point>>,
    pub(crate) counts: Cell<EvalCounts>,
    pub(crate) last_failure: RefCell<Option<Error>>,
    /// The first failed Hessian-vector product: ends the run with this error.
    pub(crate) fatal: RefCell<Option<Error>>,
    /// The user's observers (module [`observers`](super::observers)).
    pub(crate) relay: RefCell<Option<Relay>>,
    /// The message of an observer that stopped the run.
    pub(crate) observer_stop: RefCell<Option<String>>,
}

impl Shared {
    pub(crate) fn bump(&self, f: impl FnOnce(&mut EvalCounts)) {
        let mut c = self.counts.get();
        f(&mut c);
        self.counts.set(c);
    }
    pub(crate) fn fatal(&self) -> Option<Error> {
        self.fatal.borrow().clone()
    }
    pub(crate) fn observing(&self) -> bool {
        self.relay.borrow().is_some()
    }
}

/// An [`OptimProblem`] as an argmin problem over `Vec<f64>`, in the solver variables φ (φ = θ
/// without bounds, θ = c + r sin((φ − c)/r) within a box [c − r, c + r]; module docs of
/// [`optimize`](super)).
///
/// Evaluations are cached by point (one evaluation answers cost and gradient); the counts and
/// the first fatal error live in state shared with the [`HessianOperator`]s it hands out. Not
/// `Send` (the shared state is an `Rc`): build one per thread.
pub struct ArgminAdapter<'a, Q: ?Sized> {
    problem: &'a Q,
    bounds: Option<Bounds>,
    scale: f64,
    extended_value: bool,
    cg_cap: usize,
    pub(crate) shared: Rc<Shared>,
}

impl<Q: ?Sized> Clone for ArgminAdapter<'_, Q> {
    fn clone(&self) -> Self {
        ArgminAdapter {
            problem: self.problem,
            bounds: self.bounds,
            scale: self.scale,
            extended_value: self.extended_value,
            cg_cap: self.cg_cap,
            shared: Rc::clone(&self.shared),
        }
    }
}

impl<'a, Q: OptimProblem + ?Sized> ArgminAdapter<'a, Q> {
    /// The adapter for `problem` with an optional force bound |θ_i| ≤ b (b > 0, finite).
    ///
    /// # Errors
    /// [`ValueError::OutOfRange`](crate::error::ValueError::OutOfRange) (`bound`) for a bound
    /// that is not positive and finite.
    pub fn new(problem: &'a Q, bound: Option<f64>) -> Result<Self> {
        let bounds = bound.map(Bounds::symmetric).transpose()?;
        Ok(Self::with_bounds(problem, bounds))
    }

    /// The adapter for `problem` with an optional box L ≤ θ_i ≤ U ([`Bounds`]).
    pub fn with_bounds(problem: &'a Q, bounds: Option<Bounds>) -> Self {
        ArgminAdapter {
            problem,
            bounds,
            scale: 1.0,
            extended_value: false,
            cg_cap: usize::MAX,
            shared: Rc::new(Shared::default()),
        }
    }

    /// Makes the argmin problem s·J (cost, gradient and Hessian products all scaled by s > 0,
    /// finite); [`minimize`](super::minimize) uses s = 1/‖∇J(θ₀)‖. Default 1.
    pub fn with_scale(mut self, s: f64) -> Self {
        if s.is_finite() && s > 0.0 {
            self.scale = s;
        }
        self
    }

    /// When `true`, a cost request whose evaluation fails answers +∞ (for trust regions, which
    /// then reject the step) instead of an error. Default `false`.
    pub fn with_extended_value(mut self, on: bool) -> Self {
        self.extended_value = on;
        self
    }

    /// Distinct products one [`HessianOperator`] computes before it answers zeros (a truncation
    /// that makes a CG loop see zero curvature and stop; argmin's Newton-CG has no inner
    /// iteration limit). Default unlimited.
    pub fn with_hvp_cap(mut self, cap: usize) -> Self {
        self.cg_cap = cap.max(1);
        self
    }

    /// The problem.
    pub fn problem(&self) -> &'a Q {
        self.problem
    }

    /// The scale s of the argmin problem s·J.
    pub fn scale(&self) -> f64 {
        self.scale
    }

    /// θ of the solver variables φ.
    pub fn to_theta(&self, phi: &[f64]) -> Vec<f64> {
        bounds::to_theta(self.bounds, phi)
    }

    /// φ of θ: an error if θ is not finite or outside the bounds; components closer than
    /// 10⁻⁴·r to a bound are moved that far inside (the bound is stationary in φ).
    ///
    /// # Errors
    /// [`Error::NotFinite`] (`theta0`) for a non-finite entry, [`OptimizeError::InfeasibleStart`]
    /// for one outside the bounds.
    pub fn to_phi(&self, theta: &[f64]) -> Result<Vec<f64>> {
        bounds::to_phi(self.bounds, theta)
    }

    /// The counts so far.
    pub fn counts(&self) -> EvalCounts {
        self.shared.counts.get()
    }

    /// The fatal error (from an HVP) that stopped the run, if any; clears it.
    pub fn take_error(&self) -> Option<Error> {
        self.shared.fatal.borrow_mut().take()
    }

    /// J, ∇_θ J and ∇_φ J at φ by one evaluation, or from the cache. A θ outside the problem's
    /// resolved range ([`OptimProblem::check_range`]) fails like a failed simulation.
    pub(crate) fn evaluate(&self, phi: &[f64]) -> Result<Point> {
        if let Some(p) = self.shared.cache.borrow().as_ref() {
            if same_bits(&p.phi, phi) {
                return Ok(p.clone());
            }
        }
        if let Some(e) = self.shared.fatal() {
            return Err(e);
        }
        let theta = self.to_theta(phi);
        self.problem.check_range(&theta)?;
        let (value, grad_theta) = self.problem.value_and_gradient(&theta)?;
        self.shared.bump(|c| c.sweeps += 1);
        if grad_theta.len() != theta.len() {
            return Err(OptimizeError::GradientLength {
                got: grad_theta.len(),
                expected: theta.len(),
            }
            .into());
        }
        if !value.is_finite() {
            return Err(Error::NonFiniteObjective {
                quantity: "objective",
            });
        }
        if grad_theta.iter().any(|g| !g.is_finite()) {
            return Err(Error::NonFiniteObjective {
                quantity: "gradient",
            });
        }
        let grad_phi = bounds::grad_phi(self.bounds, phi, &grad_theta);
        let point = Point {
            phi: phi.to_vec(),
            theta,
            value,
            grad_theta,
            grad_phi,
        };
        {
            let mut best = self.shared.best.borrow_mut();
            if best.as_ref().is_none_or(|b| point.value < b.value) {
                *best = Some(point.clone());
            }
        }
        *self.shared.cache.borrow_mut() = Some(point.clone());
        Ok(point)
    }

    fn failed(&self, e: Error) -> ArgminError {
        self.shared.bump(|c| c.failures += 1);
        *self.shared.last_failure.borrow_mut() = Some(e.clone());
        ArgminError::from(e)
    }

    /// The Hessian operator at φ (evaluates J and ∇J there, or takes them from the cache).
    ///
    /// # Errors
    /// The evaluation's error; [`OptimizeError::NoHessian`] if the problem has no Hessian-vector
    /// products.
    pub fn operator(&self, phi: &[f64]) -> Result<HessianOperator<'a, Q>> {
        if self.problem.hessian().is_none() {
            return Err(no_hessian());
        }
        let p = self.evaluate(phi)?;
        let chain = bounds::hessian_chain(self.bounds, phi, &p.theta, &p.grad_theta);
        Ok(HessianOperator {
            problem: self.problem,
            theta: p.theta,
            scale: self.scale,
            chain,
            cap: self.cg_cap,
            products: Cell::new(0),
            cache: RefCell::new(Vec::with_capacity(HVP_CACHE)),
            shared: Rc::clone(&self.shared),
        })
    }
}

pub(crate) fn no_hessian() -> Error {
    OptimizeError::NoHessian.into()
}

impl<Q: OptimProblem + ?Sized> CostFunction for ArgminAdapter<'_, Q> {
    type Param = Vec<f64>;
    type Output = f64;

    fn cost(&self, phi: &Vec<f64>) -> std::result::Result<f64, ArgminError> {
        self.shared.bump(|c| c.cost_requests += 1);
        match self.evaluate(phi) {
            Ok(p) => Ok(p.value * self.scale),
            Err(e) if self.extended_value && self.shared.fatal().is_none() => {
                let _ = self.failed(e);
                Ok(f64::INFINITY)
            }
            Err(e) => Err(self.failed(e)),
        }
    }
}

impl<Q: OptimProblem + ?Sized> Gradient for ArgminAdapter<'_, Q> {
    type Param = Vec<f64>;
    type Gradient = Vec<f64>;

    fn gradient(&self, phi: &Vec<f64>) -> std::result::Result<Vec<f64>, ArgminError> {
        self.shared.bump(|c| c.gradient_requests += 1);
        let s = self.scale;
        self.evaluate(phi)
            .map(|p| p.grad_phi.iter().map(|g| g * s).collect())
            .map_err(|e| self.failed(e))
    }
}

impl<'a, Q: OptimProblem + ?Sized> Hessian for ArgminAdapter<'a, Q> {
    type Param = Vec<f64>;
    type Hessian = HessianOperator<'a, Q>;

    fn hessian(&self, phi: &Vec<f64>) -> std::result::Result<Self::Hessian, ArgminError> {
        self.operator(phi).map_err(|e| self.failed(e))
    }
}

/// ∇²J at one point as a linear operator v ↦ H v, by exact Hessian-vector products
/// ([`HessianVec`](super::HessianVec), chain-ruled to φ under a bound, times the adapter's scale
/// in the argmin product). Never forms H.
///
/// Implements [`ArgminDot<Vec<f64>, Vec<f64>>`](ArgminDot); `Vec<f64>`'s blanket
/// `ArgminWeightedDot` (p·(H v)) follows. A product that fails stores its error in the adapter's
/// shared state and answers zeros (as do all later products), and the adapter's next cost or
/// gradient request fails, so the run ends and [`minimize`](super::minimize) returns the error.
pub struct HessianOperator<'a, Q: ?Sized> {
    problem: &'a Q,
    theta: Vec<f64>,
    scale: f64,
    /// (J, c) of the bound's chain rule.
    chain: Option<(Vec<f64>, Vec<f64>)>,
    cap: usize,
    products: Cell<usize>,
    cache: RefCell<Vec<(Vec<f64>, Vec<f64>)>>,
    shared: Rc<Shared>,
}

impl<Q: ?Sized> Clone for HessianOperator<'_, Q> {
    fn clone(&self) -> Self {
        HessianOperator {
            problem: self.problem,
            theta: self.theta.clone(),
            scale: self.scale,
            chain: self.chain.clone(),
            cap: self.cap,
            products: self.products.clone(),
            cache: self.cache.clone(),
            shared: Rc::clone(&self.shared),
        }
    }
}

impl<Q: ?Sized> fmt::Debug for HessianOperator<'_, Q> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("HessianOperator")
            .field("theta", &self.theta)
            .field("bounded", &self.chain.is_some())
            .field("products", &self.products.get())
            .finish()
    }
}

impl<Q: OptimProblem + ?Sized> HessianOperator<'_, Q> {
    /// θ at which the Hessian is taken.
    pub fn theta(&self) -> &[f64] {
        &self.theta
    }

    /// H v (of J itself in the solver variables φ, not scaled), or the HVP's error.
    ///
    /// # Errors
    /// The problem's HVP error; [`Error::NonFiniteObjective`] for a non-finite product.
    pub fn apply(&self, v: &[f64]) -> Result<Vec<f64>> {
        if let Some(e) = self.shared.fatal() {
            return Err(e);
        }
        if v.iter().all(|x| x.to_bits() << 1 == 0) {
            return Ok(vec![0.0; v.len()]);
        }
        let hvp = self.problem.hessian().ok_or_else(no_hessian)?;
        let w: Vec<f64> = match &self.chain {
            None => v.to_vec(),
            Some((j, _)) => j.iter().zip(v).map(|(a, b)| a * b).collect(),
        };
        let hw = hvp.hessian_vec(&self.theta, &w)?;
        self.shared.bump(|c| c.hvps += 1);
        let out: Vec<f64> = match &self.chain {
            Some((j, c)) => (0..v.len()).map(|i| j[i] * hw[i] + c[i] * v[i]).collect(),
            None => hw,
        };
        if out.len() != v.len() || out.iter().any(|x| !x.is_finite()) {
            return Err(Error::NonFiniteObjective {
                quantity: "Hessian-vector product",
            });
        }
        Ok(out)
    }
}

impl<Q: OptimProblem + ?Sized> ArgminDot<Vec<f64>, Vec<f64>> for HessianOperator<'_, Q> {
    fn dot(&self, v: &Vec<f64>) -> Vec<f64> {
        if let Some((_, hv)) = self.cache.borrow().iter().find(|(x, _)| same_bits(x, v)) {
            return hv.clone();
        }
        let zeros = || vec![0.0; v.len()];
        if self.shared.fatal().is_some() || self.products.get() >= self.cap {
            return zeros();
        }
        self.products.set(self.products.get() + 1);
        match self.apply(v) {
            Ok(mut hv) => {
                hv.iter_mut().for_each(|x| *x *= self.scale);
                let mut cache = self.cache.borrow_mut();
                if cache.len() == HVP_CACHE {
                    cache.remove(0);
                }
                cache.push((v.clone(), hv.clone()));
                hv
            }
            Err(e) => {
                self.shared.fatal.borrow_mut().get_or_insert(e);
                zeros()
            }
        }
    }
}
