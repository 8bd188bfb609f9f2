//! The model: the chain's terms and loads (drag, current, axial load, soil, stack-up, pipe,
//! vessel, joint damping), statics in space, and the riser scenes built from them.
//!
//! One test crate (`cargo test --test model`); each file is a module, so a single file's tests
//! run with `cargo test --test model FILE::` (the file name without `.rs`).

// Shared helpers, declared once for the whole crate (the files `use crate::NAME`).
#[path = "../common/beam_column.rs"]
mod beam_column;
#[path = "../common/gradient_check.rs"]
mod gradient_check;
#[path = "../common/rotation.rs"]
mod rotation;
#[path = "../common/settle.rs"]
mod settle;
#[path = "../common/turned_riser.rs"]
mod turned_riser;

mod axial;
mod core;
mod current;
mod current_surface;
mod drag_rotation;
mod joint_damping;
mod loads;
mod pipe;
mod pipe_drag;
mod riser_scenes;
mod riser_system;
mod soil;
mod stackup;
mod static_start;
mod statics_spatial;
mod terms;
mod vessel_thrust;
