//! Optimal control: the Riccati and condensed solvers, the spatial problems, local and
//! multistart minimisation, and the objectives.
//!
//! One test crate (`cargo test --test ocp`); each file is a module, so a single file's tests
//! run with `cargo test --test ocp FILE::` (the file name without `.rs`).

mod condensed;
mod objectives;
mod ocp;
mod ocp_spatial;
mod optimize;
