//! Optimal control: the Riccati and condensed solvers, the spatial problems, local and
//! multistart minimisation, and the objectives.
//!
//! One test crate (`cargo test --test ocp`); each file is a module, so a single file's tests
//! run with `cargo test --test ocp FILE::` (the file name without `.rs`).

// Shared helpers, declared once for the whole crate (the files `use crate::NAME`).
#[path = "../common/table_3_4.rs"]
mod table_3_4;
#[allow(dead_code)] // not every table is read here
#[path = "../../examples/tables/thesis.rs"]
mod thesis;
#[path = "../common/turned_riser.rs"]
mod turned_riser;
#[path = "../common/wave_riser4.rs"]
mod wave_riser4;

mod condensed;
mod objectives;
mod ocp;
mod ocp_spatial;
mod optimize;
