//! The fatigue design: the exact design gradient of the scatter-diagram damage.
//!
//! One test crate (`cargo test --test design`); each file is a module, so a single file's tests
//! run with `cargo test --test design FILE::` (the file name without `.rs`).

// Shared helpers, declared once for the whole crate (the files `use crate::NAME`).
#[path = "../common/gradient_check.rs"]
mod gradient_check;

#[path = "../common/design_study.rs"]
mod design_study;

mod design;
mod design_buoyancy;
mod design_buoyancy_hotspot;
mod design_hotspot;
mod design_node_adjoint;
mod design_stackup;
mod design_vessel;
mod search;
