//! The core's integration tests, one binary (one link) with a module per area. The
//! allocation-counting test (`tests/compensator_alloc.rs`) keeps a binary of its own: its
//! global allocator must not count for the other tests.

mod common;
mod errors;
mod experiment;
mod filter_golden;
mod frf_estimate;
mod friction;
mod matrix_free;
mod oma;
mod properties;
mod refine;
mod refine_properties;
mod refine_quantity;
mod round_trip;
mod stabilization;
mod thesis_equivalence;
mod track;
mod truth_model;
mod welch_golden;
