//! # chainbeam
//!
//! A differentiable simulator of slender beams modelled as a chain of rigid pendulums joined by
//! torsional springs (Nøst, *Optimal Control of Multibody Dynamics with Applications*, NTNU 2023),
//! integrated with RATTLE and written once over [`num_dual::DualNum`] so the same code runs in
//! `f64` and in dual arithmetic, with a discrete adjoint for exact gradients.
//!
//! ## Simulate a scene
//! ```
//! use chainbeam::{catalogue, simulate};
//! // Thesis §2.2.4: n = 10, l = 1 m, m = 1 kg, k = 1000 Nm/rad, F = 2 N at the tip, h = 0.01 s.
//! let scene = catalogue::thesis_cantilever();
//! let traj = simulate(&scene)?;
//! let tip = traj.positions(traj.steps())[9];
//! assert!(tip[2] < 0.0); // a positive load pushes toward −z (the thesis's sign convention)
//! let drift = (traj.energy[traj.steps()] - traj.energy[0]).abs();
//! assert!(drift < 1e-3); // RATTLE is symplectic: no energy drift
//! # Ok::<(), chainbeam::Error>(())
//! ```
//!
//! ## Differentiate it: dual numbers and the adjoint agree
//! The same simulation runs in `Dual64`; the adjoint gives the whole gradient in one reverse sweep.
//! ```
//! use chainbeam::{catalogue, simulate_chain, BendingObjective, Chain, ControlProblem, Parametrisation};
//! use num_dual::Dual64;
//! let scene = catalogue::riser(5); // SPEC §4: the thesis's optimal-control scene
//! let problem = ControlProblem::new(&scene, Parametrisation::Constant, BendingObjective::final_moment())?;
//! let (c, g) = problem.value_and_gradient(&[-33.4])?;
//!
//! // Forward mode: seed u with a derivative of 1 and run the f64 code path in Dual64.
//! let mut chain = Chain::<Dual64, 2>::from_scene(&scene)?;
//! chain.set_control_node(Some(10))?;
//! let u = vec![Dual64::new(-33.4, 1.0); 11];
//! let traj = simulate_chain(chain, 0.01, 10, &u)?;
//! let m = traj.moment[10];
//! let dc_du = 2.0 * m.re * m.eps; // c = M₀(T)²
//! assert!((c - m.re * m.re).abs() <= 1e-15 * c);
//! assert!((g[0] - dc_du).abs() <= 1e-12 * dc_du.abs());
//! # Ok::<(), chainbeam::Error>(())
//! ```
//!
//! ## Bad input is a typed error, not a panic
//! ```
//! use chainbeam::{Error, Scene};
//! let err = Scene::from_toml_str("[beam]\npendulums = 0").unwrap_err();
//! assert!(err.to_string().contains("beam"));
//! ```
//!
//! ## Modules
//! [`model`] (the chain, SPEC §1), [`rattle`] (the integrator, SPEC §2), [`adjoint`] (gradients,
//! SPEC §3), [`simulate`](mod@simulate), [`statics`], [`euler_bernoulli`], [`scene`] and [`catalogue`] (SPEC §4-5).
#![warn(missing_docs)]
#![deny(clippy::float_cmp)]
// Numerical kernels index several arrays with one loop variable; iterator zips of four or five
// slices would hide the formulas they implement.
#![allow(clippy::needless_range_loop)]

pub mod adjoint;
pub mod catalogue;
pub mod error;
pub mod euler_bernoulli;
pub mod integrators;
pub mod model;
pub mod multistart;
pub mod ocp;
pub mod optimize;
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
