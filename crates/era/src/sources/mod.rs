//! Sources of the Markov sequence, the seam of the pipeline: every source turns its data
//! into one [`MarkovSequence`] (blocks `Y_k` that decay as `C A^(k−1) B`, with their
//! sample time and what they are, [`MarkovKind`]), and everything after it ([`crate::pipeline`]) is shared.
//!
//! - [`frf`]: measured FRFs, preprocessed and inverse-transformed (the thesis's route).
//! - [`okid`]: input and output time histories, through a least-squares observer.
//! - [`correlation`]: output-only records, through their output correlations (NExT).

pub mod correlation;
pub mod frf;
pub mod okid;

pub use frf::{MarkovKind, MarkovSequence};

/// Where the Markov sequence of time histories comes from.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
#[non_exhaustive]
pub enum MarkovSource {
    /// Welch-averaged FRFs, inverse transformed ([`frf`]).
    #[default]
    Frf,
    /// A least-squares observer on the records themselves ([`okid`]).
    Okid,
}

crate::params::names::named!(display MarkovSource, "Markov source", [
    MarkovSource::Frf => "frf",
    MarkovSource::Okid => "okid",
]);
