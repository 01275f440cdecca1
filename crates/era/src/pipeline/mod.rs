//! The steps of the thesis's `frffilt` after the Markov sequence, in reading order
//! (docs/src/design.md §1):
//!
//! 1. [`filter`]: optional zero-phase Butterworth low-pass on the impulse responses.
//! 2. [`hankel`]: `H0[r][c] = Y_(1+r+c)`, `H1[r][c] = Y_(2+r+c)`; [`hankel_op`] applies
//!    them by FFT correlations without forming them.
//! 3. [`factor`]: `H0 = U S Vᵀ`, dense or truncated, kept in one
//!    [`factor::Factorization`].
//! 4. [`realize`]: `A = S^(−½) Uᵀ H1 V S^(−½)`, `B = S^(½) Vᵀ E_p`, `C = E_qᵀ U S^(½)` at
//!    any order from the factors. [`realize_dc`] is ERA/DC: the same on the correlations
//!    of the Hankel blocks.
//! 5. [`modes`]: eigenvalues to frequencies, damping, shapes and participations.
//! 6. [`fit`]: the model's FRF through its modal form, and the per-pair fit.
//!
//! [`order`] runs them across orders: the scan from one factorization, and the automatic
//! order (with the clustering of [`crate::modal::stabilization`]). The sources
//! ([`crate::sources`]) come before; the refinement ([`crate::refine`]) after.

pub mod factor;
pub mod filter;
pub mod fit;
pub mod hankel;
pub mod hankel_op;
pub mod modes;
pub mod order;
pub mod realize;
pub mod realize_dc;
pub(crate) mod run;
