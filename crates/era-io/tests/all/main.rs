//! The readers' and writers' integration tests, one binary (one link) with a module per
//! area; the fixtures, golden files and fuzz regressions stay in `tests/`. The hostile
//! readers keep a binary of their own (`tests/hostile_readers.rs`): their allocator
//! records the process's largest allocation.

mod common;
mod data_sets;
mod fuzz_regressions;
mod geometry;
mod mat_time;
mod time_files;
mod uff_golden;
