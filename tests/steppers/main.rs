//! Runs of the model: RATTLE and the alternative integrators, starting from a given state,
//! derivatives away from small angles, the Euler-Bernoulli reference beam, streamed and stored
//! runs and their columns.
//!
//! One test crate (`cargo test --test steppers`); each file is a module, so a single file's tests
//! run with `cargo test --test steppers FILE::` (the file name without `.rs`).

#[path = "../common/mod.rs"]
mod common;

// Shared helpers, declared once for the whole crate (the files `use crate::NAME`).
#[path = "../common/gradient_check.rs"]
mod gradient_check;

mod columns;
mod euler_bernoulli;
mod fused_node_step;
mod integrators;
mod stability_limit;
mod start;
mod stream_budget;
mod streaming;
mod verification;
