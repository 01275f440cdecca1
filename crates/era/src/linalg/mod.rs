//! Linear algebra and numerics the pipeline shares: the truncated SVD ([`tsvd`]) over a
//! [`LinearOperator`], one FFT plan cache ([`fft`]) and the random generator ([`rng`]).

pub(crate) mod dense;
pub mod fft;
mod operator;
pub mod rng;
pub mod tsvd;

pub use operator::LinearOperator;
