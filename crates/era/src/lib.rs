pub mod error;
pub mod filter;
pub mod frf;
pub mod hankel;
pub mod markov;
pub mod preprocess;
pub mod realize;
pub mod statespace;
pub use error::{EraError, Result};
