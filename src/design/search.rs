//! The bounded quasi-Newton search of the design (module docs of [`crate::design`], "The
//! optimiser"): a projected L-BFGS on the unit box u ∈ \[0, 1\]^m with an active set, in the
//! manner of L-BFGS-B (Byrd, Lu, Nocedal and Zhu 1995) without its generalised Cauchy point.
//!
//! # The iteration
//! At u with f = f(u) and g = ∇f(u):
//! - the projected gradient's norm ‖P(u − g) − u‖_∞ (P the projection on the box) is the
//!   stopping test: it is zero exactly where the first-order (KKT) conditions hold, a variable
//!   on a bound with its gradient pushing outward counting as converged;
//! - a variable is *active* when it lies on a bound and its gradient component points out of
//!   the box (u_i = 0, g_i > 0 or u_i = 1, g_i < 0): it keeps its bound this iteration;
//! - the direction on the free variables is the L-BFGS two-loop product −H g (the stored pairs'
//!   components on the free variables, H₀ = (s·y/y·y) I of the latest pair); with no usable pair
//!   (the first iteration, or after a reset) it is the steepest descent scaled by the box,
//!   d = −g/‖g‖_∞ on the free variables: its longest component spans the whole range of its
//!   variable, so that a monotone objective reaches its bound in one step;
//! - the trial point is the projected step u(α) = P(u + α d), α = 1 first, accepted by Armijo's
//!   condition on the projected path f(u(α)) ≤ f + c₁ g·(u(α) − u), c₁ = 10⁻⁴; a trial that
//!   lands beyond a bound lands on it (and the variable is then active while its gradient
//!   pushes outward). The first trial asks for the gradient with the value (it is usually
//!   accepted, and the next iteration needs it); a rejected trial is followed by trials that ask
//!   for the value alone (α halved, or the minimiser of the quadratic through f, g·d and the
//!   rejected value when that lies in \[α/10, α/2\]), then the gradient at the accepted one;
//! - the pair (s, y) = (u₊ − u, g₊ − g) is kept when s·y > 10⁻¹² ‖s‖ ‖y‖ (positive curvature),
//!   at most [`BoxSearch::memory`] of them; a direction that is not a descent direction resets
//!   the memory.
//!
//! The search stops converged when the projected gradient's norm is at most the tolerance; not
//! converged after `max_iterations` iterations, or when no trial along the direction decreases
//! f (a kink of the objective, or round-off) or the projected step does not move u.

use std::collections::VecDeque;

use super::{DesignError, Want};

/// What an evaluation of the search's objective returns: f(u) and, when asked for
/// ([`Want::Gradient`]), ∇f(u) (empty otherwise).
#[derive(Clone, Debug, PartialEq)]
pub struct BoxValue {
    /// f(u).
    pub value: f64,
    /// ∇f(u) (empty for [`Want::Value`]).
    pub gradient: Vec<f64>,
}

/// The search's settings.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BoxSearch {
    /// Iterations at most (each one accepted step).
    pub max_iterations: usize,
    /// Stop when ‖P(u − g) − u‖_∞ ≤ `tolerance` (module docs).
    pub tolerance: f64,
    /// L-BFGS pairs kept.
    pub memory: usize,
    /// Trials of one line search at most.
    pub max_trials: usize,
}

impl Default for BoxSearch {
    /// 30 iterations, tolerance 10⁻⁴, 5 pairs, 12 trials (the last a step of 2⁻¹¹ of the
    /// first at least).
    fn default() -> Self {
        BoxSearch {
            max_iterations: 30,
            tolerance: 1e-4,
            memory: 5,
            max_trials: 12,
        }
    }
}

/// An accepted point of the search (the start is iteration 0).
#[derive(Clone, Debug, PartialEq)]
pub struct BoxStep {
    /// The iteration (0: the start).
    pub iteration: usize,
    /// u.
    pub u: Vec<f64>,
    /// f(u).
    pub value: f64,
    /// ∇f(u).
    pub gradient: Vec<f64>,
    /// ‖P(u − g) − u‖_∞.
    pub projected_gradient_norm: f64,
    /// Evaluations with the gradient so far (the start's included).
    pub gradient_evaluations: usize,
    /// Evaluations of the value alone so far.
    pub value_evaluations: usize,
}

/// Why the search stopped.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum BoxTermination {
    /// ‖P(u − g) − u‖_∞ ≤ the tolerance: converged.
    ProjectedGradient,
    /// The iteration limit.
    MaxIterations,
    /// No trial of the line search decreased f enough (Armijo's condition).
    NoDecrease,
    /// The projected step does not move u (every free variable's step is below round-off).
    NoMove,
}

impl BoxTermination {
    /// Whether this is convergence.
    pub fn converged(self) -> bool {
        self == BoxTermination::ProjectedGradient
    }
}

impl std::fmt::Display for BoxTermination {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            BoxTermination::ProjectedGradient => {
                "the projected gradient's norm reached the tolerance"
            }
            BoxTermination::MaxIterations => "the iteration limit was reached",
            BoxTermination::NoDecrease => {
                "no trial along the search direction decreased the objective (a kink or \
                 round-off)"
            }
            BoxTermination::NoMove => "the projected step no longer moves the design",
        })
    }
}

/// The search's result.
#[derive(Clone, Debug, PartialEq)]
pub struct BoxOutcome {
    /// Every accepted point, the start first, the last the result.
    pub steps: Vec<BoxStep>,
    /// Why it stopped.
    pub termination: BoxTermination,
}

impl BoxOutcome {
    /// The last accepted point (the result).
    pub fn last(&self) -> &BoxStep {
        // `minimise_box` always records the start.
        &self.steps[self.steps.len() - 1]
    }
}

/// ‖P(u − g) − u‖_∞ on the unit box.
pub fn projected_gradient_norm(u: &[f64], g: &[f64]) -> f64 {
    u.iter()
        .zip(g)
        .map(|(&u, &g)| ((u - g).clamp(0.0, 1.0) - u).abs())
        .fold(0.0, f64::max)
}

fn dot(a: &[f64], b: &[f64], free: &[bool]) -> f64 {
    a.iter()
        .zip(b)
        .zip(free)
        .filter(|(_, &f)| f)
        .map(|((a, b), _)| a * b)
        .sum()
}

/// The L-BFGS direction −H g on the free variables (zero on the others), `None` without a usable
/// pair (module docs).
fn lbfgs_direction(
    g: &[f64],
    free: &[bool],
    pairs: &VecDeque<(Vec<f64>, Vec<f64>)>,
) -> Option<Vec<f64>> {
    let usable: Vec<(&Vec<f64>, &Vec<f64>, f64)> = pairs
        .iter()
        .filter_map(|(s, y)| {
            let sy = dot(s, y, free);
            let (ss, yy) = (dot(s, s, free), dot(y, y, free));
            (sy > 1e-12 * (ss * yy).sqrt() && yy > 0.0).then_some((s, y, 1.0 / sy))
        })
        .collect();
    let &(s_last, y_last, _) = usable.last()?;
    let mut q: Vec<f64> = g
        .iter()
        .zip(free)
        .map(|(&g, &f)| if f { g } else { 0.0 })
        .collect();
    let mut alpha = vec![0.0; usable.len()];
    for (i, (s, y, rho)) in usable.iter().enumerate().rev() {
        alpha[i] = rho * dot(s, &q, free);
        for ((qi, yi), f) in q.iter_mut().zip(y.iter()).zip(free) {
            if *f {
                *qi -= alpha[i] * yi;
            }
        }
    }
    let gamma = dot(s_last, y_last, free) / dot(y_last, y_last, free);
    for qi in &mut q {
        *qi *= gamma;
    }
    for (i, (s, y, rho)) in usable.iter().enumerate() {
        let beta = rho * dot(y, &q, free);
        for ((qi, si), f) in q.iter_mut().zip(s.iter()).zip(free) {
            if *f {
                *qi += (alpha[i] - beta) * si;
            }
        }
    }
    Some(q.into_iter().map(|x| -x).collect())
}

/// The steepest descent scaled by the box: −g/‖g‖_∞ on the free variables (module docs).
fn scaled_descent(g: &[f64], free: &[bool]) -> Vec<f64> {
    let big = g
        .iter()
        .zip(free)
        .filter(|(_, &f)| f)
        .map(|(g, _)| g.abs())
        .fold(0.0, f64::max);
    g.iter()
        .zip(free)
        .map(|(&g, &f)| if f && big > 0.0 { -g / big } else { 0.0 })
        .collect()
}

/// f(u) (and ∇f(u) when asked for [`Want::Gradient`]) at a point u of the unit box: the function
/// [`minimise_box`] minimises.
pub(super) type BoxObjective<'a> = dyn FnMut(&[f64], Want) -> Result<BoxValue, DesignError> + 'a;

/// Minimises f on the unit box \[0, 1\]^m from `start` (module docs), `eval` giving f(u) (and
/// ∇f(u) when asked for [`Want::Gradient`]); `first` is f and ∇f at the start when the caller has
/// them (else the start is evaluated), and `on_step` sees every accepted point as it is accepted.
///
/// # Errors
/// `eval`'s first error; [`DesignError::BadValues`] for a start outside the box, a gradient of
/// the wrong length, or a value or gradient that is not finite.
pub fn minimise_box(
    eval: &mut BoxObjective<'_>,
    start: &[f64],
    first: Option<BoxValue>,
    settings: BoxSearch,
    on_step: &mut dyn FnMut(&BoxStep),
) -> Result<BoxOutcome, DesignError> {
    let m = start.len();
    if start.iter().any(|u| !(0.0..=1.0).contains(u)) {
        return Err(DesignError::BadValues {
            reason: format!("the search's start {start:?} lies outside the unit box"),
        });
    }
    let (mut n_grad, mut n_value) = (0usize, 0usize);
    let mut checked = |u: &[f64], want: Want, n_grad: &mut usize, n_value: &mut usize| {
        match want {
            Want::Gradient => *n_grad += 1,
            Want::Value => *n_value += 1,
        }
        let r = eval(u, want)?;
        check_value(&r, want, m)?;
        Ok::<BoxValue, DesignError>(r)
    };
    let first = match first {
        Some(f) => {
            n_grad += 1;
            check_value(&f, Want::Gradient, m)?;
            f
        }
        None => checked(start, Want::Gradient, &mut n_grad, &mut n_value)?,
    };
    let mut u = start.to_vec();
    let (mut f, mut g) = (first.value, first.gradient);
    let mut pairs: VecDeque<(Vec<f64>, Vec<f64>)> = VecDeque::new();
    let mut steps = Vec::new();
    let mut record = |it: usize, u: &[f64], f: f64, g: &[f64], n_grad: usize, n_value: usize| {
        let step = BoxStep {
            iteration: it,
            u: u.to_vec(),
            value: f,
            gradient: g.to_vec(),
            projected_gradient_norm: projected_gradient_norm(u, g),
            gradient_evaluations: n_grad,
            value_evaluations: n_value,
        };
        on_step(&step);
        let norm = step.projected_gradient_norm;
        steps.push(step);
        norm
    };
    let mut norm = record(0, &u, f, &g, n_grad, n_value);
    let mut iteration = 0;
    let termination = loop {
        if norm <= settings.tolerance {
            break BoxTermination::ProjectedGradient;
        }
        if iteration >= settings.max_iterations {
            break BoxTermination::MaxIterations;
        }
        let free: Vec<bool> = (0..m)
            .map(|i| !((u[i] <= 0.0 && g[i] > 0.0) || (u[i] >= 1.0 && g[i] < 0.0)))
            .collect();
        let mut d = lbfgs_direction(&g, &free, &pairs).unwrap_or_else(|| scaled_descent(&g, &free));
        if dot(&g, &d, &free) >= 0.0 || d.iter().any(|x| !x.is_finite()) {
            pairs.clear();
            d = scaled_descent(&g, &free);
        }
        let trial_at = |alpha: f64| -> Vec<f64> {
            (0..m)
                .map(|i| (u[i] + alpha * d[i]).clamp(0.0, 1.0))
                .collect()
        };
        let mut alpha = 1.0;
        let mut accepted: Option<(Vec<f64>, BoxValue)> = None;
        let mut moved = false;
        for trial in 0..settings.max_trials {
            let ut = trial_at(alpha);
            if ut == u {
                break;
            }
            moved = true;
            let predicted: f64 = g
                .iter()
                .zip(&ut)
                .zip(&u)
                .map(|((g, a), b)| g * (a - b))
                .sum();
            let want = if trial == 0 {
                Want::Gradient
            } else {
                Want::Value
            };
            let r = checked(&ut, want, &mut n_grad, &mut n_value)?;
            if r.value <= f + 1e-4 * predicted {
                accepted = Some((ut, r));
                break;
            }
            // The minimiser of the quadratic through f, the slope g·d and f(u(α)) (the
            // slope of the projected path is g·d at α = 0 on the free variables), kept in
            // [α/10, α/2].
            let slope = dot(&g, &d, &free);
            let q = -slope * alpha * alpha / (2.0 * (r.value - f - slope * alpha));
            alpha = if q.is_finite() {
                q.clamp(alpha / 10.0, alpha / 2.0)
            } else {
                alpha / 2.0
            };
        }
        let Some((ut, mut r)) = accepted else {
            break if moved {
                BoxTermination::NoDecrease
            } else {
                BoxTermination::NoMove
            };
        };
        if r.gradient.is_empty() {
            r = checked(&ut, Want::Gradient, &mut n_grad, &mut n_value)?;
        }
        let s: Vec<f64> = ut.iter().zip(&u).map(|(a, b)| a - b).collect();
        let y: Vec<f64> = r.gradient.iter().zip(&g).map(|(a, b)| a - b).collect();
        pairs.push_back((s, y));
        while pairs.len() > settings.memory.max(1) {
            pairs.pop_front();
        }
        iteration += 1;
        u = ut;
        f = r.value;
        g = r.gradient;
        norm = record(iteration, &u, f, &g, n_grad, n_value);
    };
    Ok(BoxOutcome { steps, termination })
}

/// Refuses an evaluation with a non-finite value or gradient, or a gradient of the wrong length.
fn check_value(r: &BoxValue, want: Want, m: usize) -> Result<(), DesignError> {
    let n = if want == Want::Gradient {
        m
    } else {
        r.gradient.len()
    };
    if !r.value.is_finite() || r.gradient.len() != n || r.gradient.iter().any(|g| !g.is_finite()) {
        return Err(DesignError::BadValues {
            reason: format!(
                "the search's objective gave the value {} and {} gradient components (expected \
                 {n}, finite)",
                r.value,
                r.gradient.len()
            ),
        });
    }
    Ok(())
}
