//! The discrete adjoint: the exact gradient of the RATTLE map, planar and with 2-axis controls.
//!
//! One test crate (`cargo test --test adjoint`); each file is a module, so a single file's tests
//! run with `cargo test --test adjoint FILE::` (the file name without `.rs`).

mod adjoint;
mod spatial_control;
