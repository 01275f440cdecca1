//! # era — the Eigensystem Realization Algorithm for lightly damped structures
//!
//! Measured frequency response functions (FRFs) in, a state-space model `(A, B, C, D)`,
//! its Hankel singular values, modal parameters and fit out. The pipeline restates the
//! thesis's `frffilt` (Woods 1994, §III.2 and Appendix J; Juang & Pappa 1985), as
//! docs/src/design.md §1 lists it:
//!
//! The house has one seam: a **source** turns its data into a [`sources::MarkovSequence`],
//! and the **pipeline** after it is shared.
//!
//! 1. [`sources::frf`]: the FRF source. [`sources::frf::preprocess`] integrates `ni`
//!    times, `G ← G/(j2πf)`, pads to `ndpts + 1` lines (sample time
//!    `Ts = 1/(2Δf(N−1))`) and zeroes the first `nz` lines; the Hermitian extension of
//!    each FRF, inverse-FFT'd with the `1/n` factor, gives the Markov blocks
//!    `Y_k = C A^(k−1) B`.
//! 2. [`pipeline::filter`]: optional zero-phase Butterworth low-pass on the impulse
//!    responses.
//! 3. [`pipeline::hankel`]: `H0[r][c] = Y_(1+r+c)`, `H1[r][c] = Y_(2+r+c)`, `m − 1`
//!    blocks each way, `m = M/2`, `M = ns·lh` rounded down to a multiple of 4
//!    ([`pipeline::hankel_op`] applies them without forming them).
//! 4. [`pipeline::factor`]: `H0 = U S Vᵀ`, dense or truncated; [`pipeline::realize`]:
//!    `A = S^(−½) Uᵀ H1 V S^(−½)`, `B = S^(½) Vᵀ E_p`, `C = E_qᵀ U S^(½)` at any order.
//! 5. [`data::statespace`]: `d2c` (zero-order-hold inverse, `log`) and `c2d` (`exp`).
//! 6. [`pipeline::modes`]: `s = ln(z)/Ts`; frequency `|s|/2π`, damping `−Re s/|s|`,
//!    shapes `Cφ`, participations `ψB`.
//! 7. [`pipeline::fit`]: the model's FRF through its modal form, and the per-pair fit.
//!
//! The order ([`Order`]) is fixed, or chosen by [`pipeline::order`] from a scan across
//! orders. After the pipeline: [`modal`] (indicators, the stabilization clustering),
//! [`refine`] (maximum likelihood) and [`identify::suspect`] (results to treat with care);
//! the result is plain data ([`data::identification`]), as are the FRFs and models
//! ([`data`]). [`linalg`] holds the truncated SVD, the FFT plan cache and the random
//! generator; [`estimate`] the Welch estimate of FRFs from time histories; [`params`]
//! the options' names, checks and limits.
//!
//! [`identify::identify`] runs them all; [`identify::identify_supplied`] runs them from
//! another source's sequence; [`identify::identify_naive`] runs the naive reference of
//! every stage. [`sim`] holds the truth model of Table 5.2 and seeded
//! synthetic structures.
//!
//! ```
//! use era::identify::{identify, EraOptions};
//! use era::sim::truth_model_frf;
//!
//! let frf = truth_model_frf(None).unwrap();
//! let found = identify(&frf, &EraOptions::thesis_truth_model()).unwrap();
//! let first = &found.modal.modes[0];
//! assert!((first.frequency_hz - 1748.64).abs() < 0.01);
//! ```
#![warn(missing_docs)]

pub mod cancel;
pub mod data;
pub mod error;
pub mod estimate;
pub mod friction;
pub mod identify;
pub mod linalg;
pub mod modal;
pub mod parallel;
pub mod params;
pub mod pipeline;
pub mod refine;
pub mod sim;
pub mod sources;

#[cfg(test)]
mod test_support;

pub use data::frf::{FrfData, Quantity};
pub use data::identification::{Identification, Stage};
pub use data::statespace::{StateSpace, TimeDomain};
pub use error::{EraError, Result};
pub use identify::oma::{oma, Oma, OmaMethod, OmaOptions};
pub use identify::{
    identify, identify_observed, identify_supplied, EraOptions, ModelDomain, Order,
};
pub use num_complex::Complex64;
