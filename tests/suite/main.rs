//! cbvh's integration tests, as one test binary.
//!
//! Each module below was a test target of its own; one binary links the
//! crate and its dependencies once instead of two dozen times, which keeps
//! a cold `cargo test` within a small disk and a short build. The one
//! other test binary, `tests/mutation.rs`, measures the process's largest
//! allocation and so runs alone. Run one part
//! with its module path, e.g. `cargo test --features sims --test suite contacts::`.
//!
//! The modules that run the command-line binaries or write image files need
//! the `app` feature (`cargo test --features app`); without it the rest
//! still runs.

mod common;
mod pairs;

mod builder_depth;
mod ccd;
mod characters;
mod clbvh;
#[cfg(feature = "app")]
mod cli_flags;
mod closed_mass;
#[cfg(feature = "app")]
mod codec_files;
mod codec_suite;
mod contacts;
mod edge_bends;
mod edge_flags;
mod far_from_origin;
mod hcc;
mod hcc_ooc;
mod hcc_ooc_stream;
mod mesh_io;
mod native_pairs;
mod orientation;
mod parry_integration;
mod physics;
mod plain;
mod racbvh;
mod racbvh_stream;
#[cfg(feature = "app")]
mod render;
mod scaling;
mod scene_gen;
mod scene_queries;
mod shape_queries;
#[cfg(feature = "app")]
mod sims;
