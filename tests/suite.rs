//! The integration tests, one module per file beside this one, in one test binary: one link
//! instead of one per file, and one pool of test threads over all of them, so that a long test
//! does not leave a core idle at the end of its file. Run one file's tests with
//! `cargo test --release --test suite NAME::` (NAME the file's name).
//!
//! `allocation.rs` (a counting global allocator) and `mpi_run.rs` (the feature `mpi`) are test
//! binaries of their own.

mod common;
mod lefm;

mod adaptivity;
mod chaos;
mod checkpoint;
mod cli;
mod cohesive;
mod configs;
mod contact;
mod convergence;
mod damage;
mod disk;
mod docs_links;
mod efficiency;
mod elements;
mod faults;
mod fracture;
mod fuzz;
mod fuzz_inputs;
mod house;
mod interfaces;
mod lefm_sweep;
mod parallel;
mod pitching;
mod plots;
mod rank_events;
mod ranks;
mod reflection;
mod slurm;
mod snapshots;
mod split;
mod study;
mod summary_schema;
