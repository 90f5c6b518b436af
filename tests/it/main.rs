//! The integration tests, one test crate (one binary, one link) with a
//! module per subject. They drive the library and the `tracer` binary.
//!
//! All tests share one process and run in parallel: a test that measures
//! time takes [`common::serial()`], one that keeps the cores busy takes
//! [`common::heavy()`] (see `common/serial.rs`). Run a subset by name, e.g.
//! `cargo test --test it progressive::` or `cargo test --test it chi`.

mod common;

mod agreement;
mod analytic;
mod bench_cli;
mod bsdf;
mod bvh;
mod cache;
mod caustics;
mod cli;
mod determinism;
mod furnace;
mod fuzz;
mod lights;
mod mtl;
mod outputs;
mod progressive;
mod reliability;
mod scene_errors;
mod strategies;
mod trs_import;
mod vcm;
mod warps;
