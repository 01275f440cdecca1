//! The data the pipeline reads and writes: FRFs ([`frf`]: `FrfData`, what they measure,
//! and the lines a run fits), state-space models ([`statespace`]) and the plain result
//! of an identification ([`identification`]).

pub mod frf;
pub mod identification;
pub mod statespace;
