//! Block Hankel matrices of Markov parameters (docs/src/design.md §1.7; thesis `mimohank`,
//! Appendix J.1.2).
//!
//! A general block Hankel of `r` block rows, `c` block columns starting at sample `s` is
//! `H[row][col] = Y_(s + row + col)`, a `(r·q) × (c·p)` matrix. The thesis uses two of
//! them, `H0` (start 1) and `H1` (start 2), with `m − 1` block rows and columns where
//! `m = M/2` and `M = ns·lh` rounded down to a multiple of 4 ([`ThesisHankel`]).
//!
//! [`build`] fills one column per copy from the woven [`MarkovSequence`];
//! [`build_naive`] is the element-by-element reference it is tested against.

use crate::error::{EraError, Result};
use crate::sources::frf::MarkovSequence;
use faer::Mat;

/// Shape of a general block Hankel matrix.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct HankelShape {
    /// Block rows `r`.
    pub block_rows: usize,
    /// Block columns `c`.
    pub block_cols: usize,
    /// Markov index of the top-left block, `s`.
    pub first_sample: usize,
}

impl HankelShape {
    /// Largest Markov index used, `s + r + c − 2`.
    pub(crate) fn last_sample(&self) -> usize {
        self.first_sample + self.block_rows + self.block_cols - 2
    }

    pub(crate) fn check(&self, markov: &MarkovSequence) -> Result<()> {
        if self.block_rows == 0 || self.block_cols == 0 {
            return Err(EraError::InvalidParameter {
                name: "hankel shape",
                value: format!("{}x{} blocks", self.block_rows, self.block_cols),
                reason: "a block Hankel needs at least one block row and column".into(),
            });
        }
        if self.last_sample() >= markov.samples() {
            return Err(EraError::ShapeMismatch {
                what: format!(
                    "Markov samples for a {}x{}-block Hankel starting at Y_{}",
                    self.block_rows, self.block_cols, self.first_sample
                ),
                expected: self.last_sample() + 1,
                got: markov.samples(),
            });
        }
        Ok(())
    }
}

/// Checks that `shape` is non-empty and fits in the sequence.
///
/// # Errors
/// As [`build`].
pub(crate) fn check_shape(markov: &MarkovSequence, shape: HankelShape) -> Result<()> {
    shape.check(markov)
}

/// Builds the block Hankel of `shape`, one contiguous column copy at a time.
///
/// # Errors
/// [`EraError::ShapeMismatch`] when the shape needs samples the sequence lacks.
pub fn build(markov: &MarkovSequence, shape: HankelShape) -> Result<Mat<f64>> {
    shape.check(markov)?;
    let (q, p) = (markov.outputs(), markov.inputs());
    let mut h = Mat::<f64>::zeros(shape.block_rows * q, shape.block_cols * p);
    for c in 0..shape.block_cols {
        for j in 0..p {
            let run = markov.input_run(j, shape.first_sample + c, shape.block_rows);
            h.col_as_slice_mut(c * p + j).copy_from_slice(run);
        }
    }
    Ok(h)
}

/// Element-by-element reference of [`build`]: `H[r·q+i][c·p+j] = Y_(s+r+c)[i][j]`.
///
/// # Errors
/// As [`build`].
pub fn build_naive(markov: &MarkovSequence, shape: HankelShape) -> Result<Mat<f64>> {
    shape.check(markov)?;
    let (q, p) = (markov.outputs(), markov.inputs());
    let mut h = Mat::<f64>::zeros(shape.block_rows * q, shape.block_cols * p);
    for r in 0..shape.block_rows {
        for c in 0..shape.block_cols {
            for i in 0..q {
                for j in 0..p {
                    h[(r * q + i, c * p + j)] = markov.get(shape.first_sample + r + c, i, j);
                }
            }
        }
    }
    Ok(h)
}

/// The thesis's pair of Hankel shapes (docs/src/design.md §1.7).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct ThesisHankel {
    /// Markov samples taken, `M = ns·lh` rounded down to a multiple of 4.
    pub markov_samples: usize,
    /// `m = M/2`; `H0` and `H1` have `m − 1` block rows and columns.
    pub half: usize,
    /// Shape of `H0` (starts at `Y_1`).
    pub h0: HankelShape,
    /// Shape of `H1` (starts at `Y_2`).
    pub h1: HankelShape,
}

impl ThesisHankel {
    /// Shapes for `states` (ns) and `hankel_factor` (lh).
    ///
    /// # Errors
    /// [`EraError::InvalidParameter`] when `ns·lh < 8` (no room for a 1-block `H0`).
    pub fn new(states: usize, hankel_factor: usize) -> Result<Self> {
        crate::params::limits::STATES.check("states", states as u64)?;
        // The Markov samples are samples of the impulse responses: a product above the
        // sample limit cannot be filled from any data a limit lets through. Refusing it
        // here also keeps the product (and every message that prints it) from wrapping.
        let product = crate::params::limits::SAMPLES.check_product(
            "Markov samples (states x hankel factor)",
            &[states as u64, hankel_factor as u64],
        )?;
        let markov_samples = product / 4 * 4;
        let half = markov_samples / 2;
        if half < 2 {
            return Err(EraError::InvalidParameter {
                name: "hankel_factor",
                value: hankel_factor.to_string(),
                reason: format!(
                    "states x hankel factor = {product} is below 8: the Hankel matrix would be empty"
                ).into(),
            });
        }
        let blocks = half - 1;
        let h0 = HankelShape {
            block_rows: blocks,
            block_cols: blocks,
            first_sample: 1,
        };
        let h1 = HankelShape {
            first_sample: 2,
            ..h0
        };
        Ok(ThesisHankel {
            markov_samples,
            half,
            h0,
            h1,
        })
    }

    /// Markov samples the thesis passes in (`Y_0 … Y_M`, of which `Y_(M-1)`, `Y_M` go
    /// unused): the sequence must have more than `M` samples.
    pub(crate) fn samples_needed(&self) -> usize {
        self.markov_samples + 1
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use era_testkit::Scale;

    #[test]
    fn thesis_dta_shape_is_1592_square() {
        let t = ThesisHankel::new(80, 5).unwrap();
        assert_eq!(t.markov_samples, 400);
        assert_eq!(t.h0.block_rows * 8, 1592);
        let t = ThesisHankel::new(8, 4).unwrap();
        assert_eq!(t.h0.block_rows * 3, 45);
    }

    #[test]
    fn fast_equals_naive() {
        let m = MarkovSequence::from_fn(3, 2, 20, |k, i, j| (k * 100 + i * 10 + j) as f64);
        let shape = HankelShape {
            block_rows: 4,
            block_cols: 6,
            first_sample: 3,
        };
        let a = build(&m, shape).unwrap();
        let b = build_naive(&m, shape).unwrap();
        // A copy of the same numbers: equal to the bit.
        era_testkit::assert_matches_naive("block Hankel", &a, &b, Scale::Absolute, 0.0);
        assert_eq!(a[(3 * 3 + 2, 5 * 2 + 1)], (3 + 3 + 5) as f64 * 100.0 + 21.0);
        let too_long = HankelShape {
            block_rows: 10,
            block_cols: 10,
            first_sample: 2,
        };
        assert!(build(&m, too_long).is_err());
    }
}
