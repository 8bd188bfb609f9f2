//! Time steppers for the constrained chain, all generic over the scalar and the dimension, each
//! owning its workspace (no allocation per step) and its own state type, so that a state of one
//! method cannot be passed to another.
//!
//! * [`rattle`]: RATTLE (thesis §1.6, eq. 1.6.1), symmetric, symplectic, order 2: the library's
//!   integrator, with the discrete adjoint of [`crate::adjoint`].
//! * [`shake`] and [`rk4`]: SHAKE and projected RK4, for speed-against-accuracy and stability
//!   comparisons.

pub mod rattle;

use crate::error::{Error, Result};
use crate::model::{Chain, Scalar};
use crate::tridiag::ZeroPivot;

pub use rattle::StepStats;

/// One step map (q_k, p_k) → (q_{k+1}, p_{k+1}) of a constrained integrator.
pub trait Stepper<D: Scalar, const DIM: usize> {
    /// The method's state (its own type: states of different methods cannot be mixed up).
    type State;

    /// The model.
    fn chain(&self) -> &Chain<D, DIM>;

    /// The step h.
    fn h(&self) -> f64;

    /// The straight beam at rest at t = 0 with control u_0, ready to step.
    fn initial_state(&mut self, u_0: D) -> Result<Self::State>;

    /// Advances `state` from t_k to t_{k+1} with the controls u_k and u_{k+1}.
    fn step(&mut self, state: &mut Self::State, k: usize, u_k: D, u_k1: D) -> Result<StepStats>;

    /// The attitudes qᵢ of a state.
    fn q<'s>(&self, state: &'s Self::State) -> &'s [[D; DIM]];

    /// The momenta pᵢ of a state.
    fn p<'s>(&self, state: &'s Self::State) -> &'s [[D; DIM]];
}

/// The typed error of a zero pivot met at step `step`.
pub(crate) fn singular(step: usize, zp: ZeroPivot) -> Error {
    Error::SingularSystem {
        step,
        index: zp.index,
        pivot: zp.pivot,
    }
}
