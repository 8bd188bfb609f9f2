//! Closed-loop control: the receding-horizon controller and its reduced planning model.
//!
//! One test crate (`cargo test --test mpc`); each file is a module, so a single file's tests
//! run with `cargo test --test mpc FILE::` (the file name without `.rs`).

// Shared helpers, declared once for the whole crate (the files `use crate::NAME`).
#[path = "../common/gradient_check.rs"]
mod gradient_check;
#[path = "../common/vessel_riser.rs"]
mod vessel_riser;
#[path = "../common/wave_riser4.rs"]
mod wave_riser4;

mod forecast_noisy;
mod hotspot;
mod moment_about;
mod mpc;
mod mpc_planning;
mod mpc_vessel;
mod observe;
mod one_loop;
mod plan_prediction;
mod thrust_plan_step;
mod thrust_reduced;
