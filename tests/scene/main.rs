//! Scene files: parsing, writing and validation, random scene files, the documented keys,
//! and the thesis tables.
//!
//! One test crate (`cargo test --test scene`); each file is a module, so a single file's tests
//! run with `cargo test --test scene FILE::` (the file name without `.rs`).

mod docs_keys;
mod scene_files;
mod scene_proptest;
mod tables;
