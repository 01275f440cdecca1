//! What the era workspace's tests share, so that each test says only what it checks.
//!
//! - [`paths`]: files of the repository, and the real data sets under `data/` (a missing
//!   one fails the test with its path: no test skips silently).
//! - [`files`]: writing and reading the small text, JSON and golden CSV files of a test.
//! - [`cli`]: running the `era` binary, checking its exit code and stderr, and the
//!   argument lists the CLI tests repeat (the truth model at the thesis's settings).
//! - [`naive`]: one assertion, [`assert_matches_naive`], for every fast path that has a
//!   naive reference, with tolerances scaled by ε, size and conditioning ([`tol`]).
//!
//! This crate names none of `era`'s types: era's unit tests use it too, and a
//! dependency on `era` here would build a second copy of era's types for them.

pub mod cli;
pub mod files;
pub mod naive;
pub mod paths;

pub use naive::{assert_matches_naive, difference, tol, Difference, Scale, Values};
pub use paths::{data_file, repo_file, workspace_root};
