//! One file per verb: read the input, call the library, hand a typed result to
//! [`crate::output`]. The flags arrive as typed settings from [`crate::config`].

pub mod batch;
pub mod compare;
pub mod convert;
pub mod demo;
pub mod experiment;
pub mod fleet;
pub mod frf;
pub mod friction;
pub mod identify;
pub mod info;
pub mod oma;
pub mod plot;
pub mod refine;
pub mod shaker;
pub mod simulate;
pub mod track;

pub use crate::output::Done;
