//! The discrete adjoint: the exact gradient of the RATTLE map, planar and with 2-axis controls.
//!
//! One test crate (`cargo test --test adjoint`); each file is a module, so a single file's tests
//! run with `cargo test --test adjoint FILE::` (the file name without `.rs`).

// Shared helpers, declared once for the whole crate (the files `use crate::NAME`).
#[path = "../common/gradient_check.rs"]
mod gradient_check;

mod adjoint;
mod spatial_control;
