//! # chainbeam
//!
//! A differentiable simulator of slender beams modelled as a chain of rigid pendulums joined by
//! torsional springs (Nøst, *Optimal Control of Multibody Dynamics with Applications*, NTNU 2023),
//! integrated with RATTLE and written once over [`num_dual::DualNum`] so the same code runs in
//! `f64` and in dual arithmetic.
#![warn(missing_docs)]
#![deny(clippy::float_cmp)]
// Numerical kernels index several arrays with one loop variable; iterator zips of four or five
// slices would hide the formulas they implement.
#![allow(clippy::needless_range_loop)]

pub mod adjoint;
pub mod catalogue;
pub mod error;
pub mod euler_bernoulli;
pub mod model;
pub mod rattle;
pub mod scene;
pub mod simulate;
pub mod statics;
pub mod tridiag;

pub use adjoint::{
    BendingObjective, Checkpointing, ConstantControl, ControlMap, ControlProblem, Objective,
    Parametrisation, PerStepControl, PiecewiseControl,
};
pub use error::{Error, Result};
pub use model::{Chain, Parameter, Scalar, TipCondition};
pub use rattle::{Rattle, RattleOptions, State, StepStats};
pub use scene::{
    Beam, Control, ControlKind, Loads, ObjectiveKind, PointLoad, Scene, SceneBuilder, SceneError,
    SceneErrorKind, Support, TimeGrid,
};
pub use simulate::{
    piecewise_constant_controls, scene_controls, simulate, simulate_chain, simulate_with_controls,
    Trajectory,
};

/// The README's code runs as a doctest.
#[cfg(doctest)]
#[doc = include_str!("../README.md")]
struct ReadmeDoctests;
