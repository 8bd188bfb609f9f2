//! Scene files: parsing, writing and validation, random scene files, the documented keys,
//! and the thesis tables.
//!
//! One test crate (`cargo test --test scene`); each file is a module, so a single file's tests
//! run with `cargo test --test scene FILE::` (the file name without `.rs`).

// Shared helpers, declared once for the whole crate (the files `use crate::NAME`).
#[path = "../../examples/tables/compute.rs"]
mod compute;
#[path = "../common/table_3_4.rs"]
mod table_3_4;
#[path = "../../examples/tables/thesis.rs"]
mod thesis;

mod docs_keys;
mod scene_files;
mod scene_proptest;
mod tables;
