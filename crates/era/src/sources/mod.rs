//! Sources of the Markov sequence, the seam of the pipeline: every source turns its data
//! into one [`MarkovSequence`] (blocks `Y_k` that decay as `C A^(k−1) B`, with their
//! sample time), and everything after it ([`crate::pipeline`]) is shared.
//!
//! - [`frf`]: measured FRFs, preprocessed and inverse-transformed (the thesis's route).
//! - [`okid`]: input and output time histories, through a least-squares observer.

pub mod frf;
pub mod okid;

pub use frf::MarkovSequence;
