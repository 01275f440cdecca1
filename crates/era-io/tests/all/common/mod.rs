//! Helpers shared by the era-io integration tests (from era-testkit).
#![allow(unused_imports)]

pub use era_testkit::data_file;
