//! Linear algebra and numerics the pipeline shares: the truncated SVD ([`tsvd`]) over a
//! [`LinearOperator`], one FFT plan cache (`fft`), the random generator ([`rng`]), the
//! balanced eigendecomposition (`eigen`) and the matrix exponential (`expm`).

pub(crate) mod dense;
pub(crate) mod eigen;
pub(crate) mod expm;
pub(crate) mod fft;
mod operator;
pub mod rng;
pub mod tsvd;

pub use operator::LinearOperator;
