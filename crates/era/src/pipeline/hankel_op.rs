//! Block-Hankel products without forming the Hankel matrix (docs/src/design.md §7).
//!
//! With `H[r·q+i][c·p+j] = Y_(s+r+c)[i][j]` (`R` block rows, `C` block columns), one
//! output block of `H x` is a sum of correlations of the Markov sequences with the input
//! slices of `x`:
//!
//! ```text
//! (H x)[r·q+i] = Σ_j Σ_c a_ij[r + c] · x[c·p+j],      a_ij[k] = Y_(s+k)[i][j]
//!             = Σ_j (a_ij ⊛ g̃_j)[r + C − 1],          g̃_j[c'] = x[(C−1−c')·p+j]
//! ```
//!
//! a convolution with the reversed slice, read from index `C − 1` on. A circular
//! convolution of length `N ≥ R + C − 1` gives those entries exactly, so the spectra
//! `A_ij = FFT(a_ij)` are computed once (`q·p` real FFTs), and each column of `X` then
//! costs `p` forward FFTs, `q·p` spectral multiply-adds and `q` inverse FFTs:
//! O((p + q) N log N + q p N) per vector and O(q p N) memory, where the dense Hankel
//! needs `R q · C p`. `Hᵀ y` is the same with the roles of outputs and inputs swapped.
//! Columns are processed in parallel with `rayon`.
//!
//! **Made once.** FFT plans come from one process-wide planner (`crate::linalg::fft`), so a
//! length planned once (every identification at the same `ndpts` and `lh`) is never
//! planned again; the spectra `A_ij` live as long as the operator; each worker thread
//! owns its buffers (time signal, input spectra, accumulator, FFT scratch, the operand
//! column) for a whole product, so a product allocates per thread, not per column.

use crate::error::Result;
use crate::linalg::fft::{fast_fft_len, real_fft_plans};
use crate::linalg::LinearOperator;
use crate::pipeline::hankel::HankelShape;
use crate::sources::frf::MarkovSequence;
use faer::{Mat, MatRef};
use num_complex::Complex64;
use rayon::prelude::*;
use realfft::{ComplexToReal, RealToComplex};
use std::sync::Arc;

/// `H` of a [`HankelShape`] over a [`MarkovSequence`], applied by FFT correlations.
pub struct HankelOperator {
    outputs: usize,
    inputs: usize,
    shape: HankelShape,
    fft_len: usize,
    bins: usize,
    /// `A_ij`, pair-major: `spectra[(i·p + j)·bins + f]`.
    spectra: Vec<Complex64>,
    forward: Arc<dyn RealToComplex<f64>>,
    inverse: Arc<dyn ComplexToReal<f64>>,
}

/// Per-thread buffers of one column product.
struct Scratch {
    time: Vec<f64>,
    inputs: Vec<Complex64>,
    acc: Vec<Complex64>,
    fft: Vec<Complex64>,
    /// The operand column, when it is not contiguous in the operand.
    column: Vec<f64>,
}

impl HankelOperator {
    /// Precomputes the spectra of the Markov sequences that `shape` uses.
    ///
    /// # Errors
    /// As [`crate::pipeline::hankel::build`]: a shape that needs samples the sequence lacks.
    pub fn new(markov: &MarkovSequence, shape: HankelShape) -> Result<Self> {
        // Validate exactly as the dense builder does, on a 1×1-block probe of the corner.
        crate::pipeline::hankel::check_shape(markov, shape)?;
        let (q, p) = (markov.outputs(), markov.inputs());
        let span = shape.block_rows + shape.block_cols - 1;
        let fft_len = fast_fft_len(span);
        let bins = fft_len / 2 + 1;
        let (forward, inverse) = real_fft_plans(fft_len);
        let mut spectra = vec![Complex64::new(0.0, 0.0); q * p * bins];
        let mut time = vec![0.0; fft_len];
        let mut scratch = forward.make_scratch_vec();
        for i in 0..q {
            for j in 0..p {
                time.iter_mut().for_each(|v| *v = 0.0);
                for (k, v) in time.iter_mut().take(span).enumerate() {
                    *v = markov.get(shape.first_sample + k, i, j);
                }
                let out = &mut spectra[(i * p + j) * bins..(i * p + j + 1) * bins];
                forward
                    .process_with_scratch(&mut time, out, &mut scratch)
                    .expect("lengths from the plan");
            }
        }
        Ok(HankelOperator {
            outputs: q,
            inputs: p,
            shape,
            fft_len,
            bins,
            spectra,
            forward,
            inverse,
        })
    }

    /// FFT length used.
    pub fn fft_len(&self) -> usize {
        self.fft_len
    }

    fn scratch(&self, channels: usize) -> Scratch {
        Scratch {
            column: Vec::new(),
            time: vec![0.0; self.fft_len],
            inputs: vec![Complex64::new(0.0, 0.0); channels * self.bins],
            acc: vec![Complex64::new(0.0, 0.0); self.bins],
            fft: vec![
                Complex64::new(0.0, 0.0);
                self.forward
                    .get_scratch_len()
                    .max(self.inverse.get_scratch_len())
            ],
        }
    }

    /// One column: `out = H x` (transpose = false) or `out = Hᵀ x` (transpose = true).
    fn column(&self, x: &[f64], out: &mut [f64], transpose: bool, s: &mut Scratch) {
        let (q, p, bins) = (self.outputs, self.inputs, self.bins);
        let (r_blocks, c_blocks) = (self.shape.block_rows, self.shape.block_cols);
        // Input side: p slices of length C (H x), or q slices of length R (Hᵀ y).
        let (in_ch, in_len, out_ch, out_len) = if transpose {
            (q, r_blocks, p, c_blocks)
        } else {
            (p, c_blocks, q, r_blocks)
        };
        for ch in 0..in_ch {
            s.time.iter_mut().for_each(|v| *v = 0.0);
            for k in 0..in_len {
                s.time[k] = x[(in_len - 1 - k) * in_ch + ch];
            }
            let spec = &mut s.inputs[ch * bins..(ch + 1) * bins];
            self.forward
                .process_with_scratch(&mut s.time, spec, &mut s.fft)
                .expect("lengths from the plan");
        }
        let scale = 1.0 / self.fft_len as f64;
        for o in 0..out_ch {
            s.acc.iter_mut().for_each(|v| *v = Complex64::new(0.0, 0.0));
            for ch in 0..in_ch {
                let (i, j) = if transpose { (ch, o) } else { (o, ch) };
                let a = &self.spectra[(i * p + j) * bins..(i * p + j + 1) * bins];
                let g = &s.inputs[ch * bins..(ch + 1) * bins];
                for ((acc, a), g) in s.acc.iter_mut().zip(a).zip(g) {
                    *acc += a * g;
                }
            }
            s.acc[0].im = 0.0;
            if self.fft_len.is_multiple_of(2) {
                s.acc[bins - 1].im = 0.0;
            }
            self.inverse
                .process_with_scratch(&mut s.acc, &mut s.time, &mut s.fft)
                .expect("lengths from the plan");
            for k in 0..out_len {
                out[k * out_ch + o] = s.time[in_len - 1 + k] * scale;
            }
        }
    }

    fn product(&self, x: MatRef<'_, f64>, transpose: bool) -> Mat<f64> {
        let (rows, cols) = (LinearOperator::nrows(self), LinearOperator::ncols(self));
        let (in_dim, out_dim, in_ch) = if transpose {
            (rows, cols, self.outputs)
        } else {
            (cols, rows, self.inputs)
        };
        assert_eq!(x.nrows(), in_dim, "operand rows");
        let b = x.ncols();
        // Written in place, column by column (owned columns are contiguous).
        let mut out = Mat::<f64>::zeros(out_dim, b);
        let work = |s: &mut Scratch, (col, target): (usize, faer::col::ColMut<'_, f64>)| {
            let slice = target
                .try_as_col_major_mut()
                .expect("owned columns are contiguous")
                .as_slice_mut();
            if let Some(column) = x.col(col).try_as_col_major() {
                self.column(column.as_slice(), slice, transpose, s);
            } else {
                let mut column = std::mem::take(&mut s.column);
                column.clear();
                column.extend((0..in_dim).map(|r| x[(r, col)]));
                self.column(&column, slice, transpose, s);
                s.column = column;
            }
        };
        if b > 1 && out_dim * b > 4096 {
            out.par_col_iter_mut()
                .enumerate()
                .for_each_init(|| self.scratch(in_ch), work);
        } else {
            let mut s = self.scratch(in_ch);
            out.col_iter_mut()
                .enumerate()
                .for_each(|item| work(&mut s, item));
        }
        out
    }
}

impl LinearOperator for HankelOperator {
    fn nrows(&self) -> usize {
        self.shape.block_rows * self.outputs
    }
    fn ncols(&self) -> usize {
        self.shape.block_cols * self.inputs
    }
    fn apply(&self, x: MatRef<'_, f64>) -> Mat<f64> {
        self.product(x, false)
    }
    fn apply_transpose(&self, y: MatRef<'_, f64>) -> Mat<f64> {
        self.product(y, true)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::pipeline::hankel::build_naive;
    use era_testkit::{assert_matches_naive, tol, Scale};
    /// The constant of the products' rounding bound `c · ε · n` (n terms per entry).
    const TOL_C: f64 = 2.0;

    #[test]
    fn fast_lengths_are_7_smooth() {
        assert_eq!(fast_fft_len(397), 400);
        assert_eq!(fast_fft_len(1), 1);
        assert_eq!(fast_fft_len(11), 12);
    }

    #[test]
    fn products_equal_the_dense_hankel() {
        for (q, p, r, c, s) in [
            (3, 2, 7, 5, 1),
            (1, 1, 9, 9, 2),
            (2, 4, 4, 11, 0),
            (8, 8, 20, 20, 1),
        ] {
            let samples = s + r + c + 3;
            let markov = MarkovSequence::from_fn(q, p, samples, |k, i, j| {
                ((k * 37 + i * 11 + j * 5) as f64 * 0.7).sin() * 0.9f64.powi(k as i32)
            });
            let shape = HankelShape {
                block_rows: r,
                block_cols: c,
                first_sample: s,
            };
            let dense = build_naive(&markov, shape).unwrap();
            let op = HankelOperator::new(&markov, shape).unwrap();
            let x = Mat::from_fn(c * p, 6, |i, j| ((i * 13 + j * 7) as f64).cos());
            let y = Mat::from_fn(r * q, 6, |i, j| ((i * 3 + j * 17) as f64).sin());
            let hx = op.apply(x.as_ref());
            // A strided operand (a transposed view) takes the copying path: same product.
            let xt = x.transpose().to_owned();
            assert_eq!(op.apply(xt.transpose()), hx, "{q}x{p} strided");
            let hty = op.apply_transpose(y.as_ref());
            let ex = &dense * &x;
            let ety = dense.transpose() * &y;
            // Rounding of the FFT convolution, relative to the product's norm: each entry
            // sums over a row or column of H (c·p or r·q terms).
            assert_matches_naive(
                &format!("{q}x{p} H x"),
                &hx,
                &ex,
                Scale::Norm,
                tol(TOL_C, c * p, 1.0),
            );
            assert_matches_naive(
                &format!("{q}x{p} Hᵀ y"),
                &hty,
                &ety,
                Scale::Norm,
                tol(TOL_C, r * q, 1.0),
            );
        }
    }
}
