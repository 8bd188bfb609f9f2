//! The `chainbeam` command line: every subcommand, its outputs and its refusals.
//!
//! One test crate (`cargo test --test cli`); each file is a module, so a single file's tests
//! run with `cargo test --test cli FILE::` (the file name without `.rs`).

#[path = "../common/mod.rs"]
mod common;

// Shared helpers, declared once for the whole crate (the files `use crate::NAME`).
#[path = "../common/fatigue_cli.rs"]
mod fatigue_cli;
#[allow(dead_code)] // not every table is read here
#[path = "../../examples/tables/thesis.rs"]
mod thesis;
#[path = "../common/wave_riser4_toml.rs"]
mod wave_riser4_toml;

mod cli;
mod cli_controls;
mod cli_fatigue;
mod cli_fatigue_study;
mod cli_hostile;
mod cli_mpc;
mod cli_objectives;
mod cli_output;
mod cli_riccati;
mod cli_spatial;
mod cli_waves;
