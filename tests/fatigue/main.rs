//! Fatigue and the sea: rainflow and DNV curves, fatigue as an objective, the scatter diagram,
//! the fatigue study, hot spots, irregular seas and their loads on a riser.
//!
//! One test crate (`cargo test --test fatigue`); each file is a module, so a single file's tests
//! run with `cargo test --test fatigue FILE::` (the file name without `.rs`).

#[path = "../common/fatigue_support.rs"]
mod fatigue_support;

// Shared helpers, declared once for the whole crate (the files `use crate::NAME`).
#[path = "../common/fatigue_cli.rs"]
mod fatigue_cli;
#[path = "../common/gradient_check.rs"]
mod gradient_check;
#[path = "../common/rotation.rs"]
mod rotation;

mod fatigue;
mod fatigue_objective;
mod fatigue_scatter;
mod fatigue_study;
mod fatigue_study_startup;
mod fatigue_wellhead;
mod hotspot_control;
mod hotspot_interpolation;
mod hotspots;
mod profile_speed;
mod sea_domain;
mod sea_fatigue_proptest;
mod sea_loads;
mod wave_record_step;
mod wave_riser;
mod waves;
