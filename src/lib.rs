//! # chainbeam
//!
//! A differentiable simulator of slender beams modelled as a chain of rigid pendulums joined by
//! torsional springs (Nøst, *Optimal Control of Multibody Dynamics with Applications*, NTNU 2023),
//! integrated with RATTLE and written once over the scalar trait
//! [`num_dual::DualNum<f64>`](https://docs.rs/num-dual/latest/num_dual/trait.DualNum.html), so the
//! same code runs in `f64` and in dual arithmetic, with a discrete adjoint for exact gradients and
//! argmin-based optimal control of a force on the beam.
//!
//! Scenes are TOML files; their format is the [`scene`] module's documentation (in the
//! repository: `docs/scene-format.md`), and the coordinates, sign convention, bending moment and
//! time grid are under [Conventions](#conventions) below (`docs/conventions.md`).
//!
//! ## Simulate a scene
//! ```
//! use chainbeam::{catalogue, simulate};
//! // Thesis §2.2.4: n = 10, l = 1 m, m = 1 kg, k = 1000 Nm/rad, F = 2 N at the tip, h = 0.01 s.
//! let scene = catalogue::thesis_cantilever();
//! let traj = simulate(&scene)?;
//! let tip = traj.positions(traj.steps())[9];
//! assert!(tip[2] < 0.0); // a positive load pushes toward −z (the thesis's sign convention)
//! let drift = (traj.energy()[traj.steps()] - traj.energy()[0]).abs();
//! assert!(drift < 1e-3); // RATTLE is symplectic: no energy drift
//! # Ok::<(), chainbeam::Error>(())
//! ```
//! The same front door takes given per-step controls instead of the scene's own:
//! `simulate(SimulateInput::new(&scene).controls(&u))`, or 2-axis ones (the spatial model)
//! `simulate(SimulateInput::new(&scene).controls_xz(&ux, &uz))`; the result reads the same in
//! either model ([`SceneTrajectory`]).
//!
//! ## Loads in any transverse direction, waves and load histories
//! A load with an x component makes the scene spatial and `simulate` runs the spatial model; a
//! load at 45° between x and z deflects the riser as far as the same load along z, at 45°
//! (the model is symmetric about the beam's axis y).
//! ```
//! use chainbeam::{catalogue, simulate};
//! let oblique = simulate(&catalogue::oblique_riser())?; // F = 2 N at node 5, force = [√2, √2]
//! assert!(oblique.is_spatial());
//! let mut in_plane = catalogue::oblique_riser();
//! in_plane.loads.points[0].force_x = 0.0;
//! in_plane.loads.points[0].force = 2.0;
//! let in_plane = simulate(&in_plane)?;
//! assert!(!in_plane.is_spatial());
//! let (r, r0) = (oblique.positions(200)[9], in_plane.positions(200)[9]); // the tip at t = 2 s
//! assert!((r[0].hypot(r[2]) - r0[2].abs()).abs() < 1e-12 && (r[0] - r[2]).abs() < 1e-12);
//! # Ok::<(), chainbeam::Error>(())
//! ```
//! Harmonic loads (`catalogue::wave_riser`) and load histories read from CSV files
//! (`catalogue::wave_series`) are point loads too, and the gradients with respect to their
//! amplitudes and phases come from the same model ([`Parameter::LoadAmplitude`],
//! [`Parameter::LoadPhase`]).
//!
//! ## Differentiate it: dual numbers and the adjoint agree
//! The same simulation runs in `Dual64`; the adjoint gives the whole gradient in one reverse sweep.
//! ```
//! use chainbeam::{catalogue, simulate_chain, BendingObjective, Chain, ControlProblem, Parametrisation};
//! use num_dual::Dual64;
//! let scene = catalogue::riser(5); // the thesis's optimal-control scene (Table 3.1, system 5)
//! let problem = ControlProblem::builder(&scene) // the planar model: the scene has no x component
//!     .map(Parametrisation::Constant)
//!     .objective(BendingObjective::final_moment())
//!     .build()?;
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
//! ## Optimise a control
//! The constant tip force that minimises c_sum = Σ M₀(t_k)² on the thesis's riser with the load at
//! node 5: thesis Table 3.2 prints c_sum = 2.0774 (reproduced to its last printed digit).
//! ```
//! use chainbeam::optimize::{minimize, OptimOptions};
//! use chainbeam::{catalogue, BendingObjective, ControlProblem, Parametrisation};
//! let scene = catalogue::riser(5);
//! let problem = ControlProblem::builder(&scene)
//!     .map(Parametrisation::Constant)
//!     .objective(BendingObjective::summed_moment())
//!     .build()?;
//! let best = minimize(&problem, &[0.0], &OptimOptions::default())?;
//! assert!((best.objective - 2.0774).abs() <= 5e-5, "c_sum = {}", best.objective);
//! assert!(best.gradient_norm <= 1e-6 * best.initial_gradient_norm);
//! println!("u* = {:.5} N, c_sum = {:.5}", best.theta[0], best.objective);
//! # Ok::<(), chainbeam::Error>(())
//! ```
//!
//! ## Bad input is a typed error that names the key, not a panic
//! ```
//! use chainbeam::Scene;
//! let text = "[beam]\npendulums = 3\nlength = 1.0\nmass = -1.0\nstiffness = 100.0\n\
//!             support = \"cantilever\"\n[time]\nstep = 0.01\nsteps = 10\n";
//! let err = Scene::from_toml_str(text).unwrap_err();
//! assert_eq!(err.key(), Some("beam.mass"));
//! assert_eq!(err.to_string(), "invalid scene: key `beam.mass`: must be positive and finite, got -1");
//! ```
//!
//! ## Modules
//! In the order a scene flows through them:
//! - [`scene`]: scene data, the scene file format, validation, [`SceneBuilder`];
//!   [`catalogue`]: the thesis's scenes by name.
//! - [`model`]: the chain ([`Chain`]): masses, lengths, the O(n) inverse mass matrix, M₀, and its
//!   force terms ([`model::terms`]), each written once over the scalar with every derivative
//!   derived from it by dual numbers.
//! - [`constraints`]: the constraint operator Ĝ and the bordered tridiagonal assembly of
//!   Ĝ M⁻¹ Ĝᵀ (thesis eq. 2.4.1-2.4.2); [`tridiag`]: the O(n) bordered tridiagonal solves.
//! - [`steppers`]: the [`Stepper`](steppers::Stepper) trait; RATTLE (thesis eq. 1.6.1), the
//!   library's integrator, re-exported as [`rattle`] (its types also at the crate root:
//!   [`Rattle`], [`State`], [`StepStats`]); SHAKE and projected RK4 for comparisons.
//! - [`simulate`](mod@simulate): trajectories of a scene (q, p, λ, μ, energy, M₀, node positions).
//! - [`integrators`]: RATTLE, SHAKE and projected RK4 side by side, for comparisons.
//! - [`adjoint`]: objectives, control parametrisations, the discrete adjoint read from a tape,
//!   checkpointing, Hessian-vector products; [`ControlProblem`] (thesis §3.3).
//! - [`optimize`]: the [`OptimProblem`](optimize::OptimProblem) trait and local minimisation with
//!   argmin (L-BFGS, trust region, Newton-CG), force bounds (symmetric or an asymmetric box,
//!   [`Bounds`](optimize::Bounds)), observers, and how a run ended
//!   ([`Termination`](optimize::Termination)).
//! - [`multistart`]: multistart, clustering of minima, second-order certificates, landscapes.
//! - [`ocp`]: the per-step optimal-control problem solved by Gauss-Newton SQP steps with a
//!   Riccati recursion and box constraints on the forces.
//! - [`mpc`]: closed-loop control: a plant stepped with the applied control, receding-horizon
//!   control on the [`ocp`] solver (real-time iterations, warm starts, plant/model mismatch),
//!   and the baselines (no control, best constant force, tuned PD law on M₀); one
//!   [`mpc::run_closed_loop`] for both models, every [`mpc::Controller`] deciding a 2-axis
//!   [`mpc::Force2`] (u_x = 0 in a planar scene).
//! - [`statics`]: static equilibrium, solved directly (planar and spatial scenes).
//! - [`fatigue`]: wellhead fatigue: hot-spot stress from M₀, rainflow counting (ASTM E1049-85),
//!   DNV-RP-C203 S-N curves, Miner's rule, annual damage and life, scatter diagrams, and the
//!   damage's gradient with respect to the stress history.
//! - [`fatigue_study`]: the layer above [`mpc`] and [`fatigue`]: every controller (none, the
//!   best constant force, a PD law, MPC) on every cell of a scatter diagram, combined into
//!   damage per year, life and life extension per controller ([`fatigue_study::run_study`]).
//! - [`euler_bernoulli`]: the Euler-Bernoulli finite-difference beam and the static beam formulas.
//! - [`error`]: the typed errors ([`Error`], [`Result`]).
//!
#![doc = include_str!("../docs/conventions.md")]
#![warn(missing_docs)]
#![warn(unreachable_pub)]
#![deny(clippy::float_cmp)]
// Numerical kernels index several arrays with one loop variable; iterator zips of four or five
// slices would hide the formulas they implement.
#![allow(clippy::needless_range_loop)]

pub mod adjoint;
pub mod banded;
pub mod base;
pub mod cancel;
pub mod catalogue;
pub mod constraints;
pub mod design;
pub mod error;
pub mod euler_bernoulli;
pub mod fatigue;
pub mod fatigue_study;
pub mod hotspots;
// The bounded reader of every input file (re-exported by `scene`): below `scene` and `fatigue`,
// which both read files through it.
mod input;
pub mod integrators;
pub mod model;
pub mod mpc;
pub mod multistart;
pub mod ocean;
pub mod ocp;
pub mod optimize;
pub mod scene;
pub mod simulate;
pub mod statics;
pub mod steppers;
pub mod tridiag;

pub use steppers::rattle;

pub use adjoint::{
    AnyProblem, BendingObjective, Checkpointing, ConstantControl, ControlMap, ControlProblem,
    FatigueObjective, HotSpotObjective, Objective, Parametrisation, PerStepControl,
    PiecewiseControl, PowerObjective, Start, StartKick,
};
pub use error::{Error, Result};
pub use model::{Chain, Parameter, Scalar, TipCondition};
pub use rattle::{Multipliers, Rattle, RattleOptions, State, StepStats};
pub use scene::Initial;
pub use scene::{
    Beam, Control, ControlKind, Harmonic, LoadSeries, Loads, ObjectiveKind, PointLoad, Scene,
    SceneBuilder, SceneError, SceneErrorKind, SceneInput, Support, TimeGrid, ValidScene,
};
pub use scene::{Current, CurrentProfile, Rao, Vessel};
pub use simulate::{
    moment_history, simulate_streaming, MomentSeries, StepObserver, StepView, StreamControls,
    StreamError, StreamSummary,
};
pub use simulate::{
    piecewise_constant_controls, scene_controls, scene_controls_x, simulate, simulate_chain,
    SceneTrajectory, SimulateInput, Trajectory, TrajectoryColumns,
};

/// The README's code runs as a doctest.
#[cfg(doctest)]
#[doc = include_str!("../README.md")]
struct ReadmeDoctests;
