//! Output correlations: the output-only source (NExT, James, Carne & Lauffer 1993).
//!
//! A structure driven by unmeasured, broadband, stationary forces has output correlation
//! functions `R_k = E[y_(t+k) y_refᵀ(t)]` that decay as `C A^(k−1) G` for `k ≥ 1`, with
//! `G = E[x_(t+1) y_refᵀ(t)]` in place of `B`: a Markov sequence of
//! [`MarkovKind::Correlation`], which the pipeline realizes as it realizes impulse
//! responses (NExT-ERA), or through the shift of its observability factor (SSI-cov).
//!
//! **The estimator** is the direct, unbiased one,
//! `R_k = Σ_t y(t+k) y_ref(t) / (N − k)` summed over every record, with each channel's
//! mean removed first. It is computed exactly by FFT, overlap-save in chunks: each chunk
//! of `B` reference samples is correlated with the `B + L − 1` output samples that
//! reach it, in an FFT of `≥ B + L − 1` points, so nothing wraps; the cross-spectra are
//! summed over the chunks of a block and inverse-transformed once per block. Memory is
//! one chunk per channel plus the lags of each block, whatever the record's length.
//! Welch-averaged cross-spectra, inverse-transformed, were not used: the window's own
//! autocorrelation multiplies every lag (an extra, window-dependent decay that shows up
//! as damping) and the segment length wraps the long lags around; the direct estimate
//! has neither, and costs the same by FFT.
//!
//! **Blocks**: the samples are split into `blocks` contiguous pieces (records are laid
//! end to end) whose sums are kept apart, so that the correlations without one block
//! ([`Correlations::leave_out`]) are at hand for a jackknife of the modal parameters.
//!
//! faer has no correlation; `realfft` does the transforms (`crate::linalg::fft`).

pub(crate) mod spectrum;

use crate::error::{EraError, Result};
use crate::linalg::fft::real_fft_plans;
use crate::sources::{MarkovKind, MarkovSequence};
use num_complex::Complex64;
use rayon::prelude::*;

/// Settings of [`correlations`].
#[derive(Debug, Clone, PartialEq)]
#[non_exhaustive]
pub struct CorrelationOptions {
    /// Reference channels (0-based, among the outputs); `None` for every output.
    pub references: Option<Vec<usize>>,
    /// Lags `R_0 … R_(L−1)` to compute.
    pub lags: usize,
    /// Contiguous blocks whose sums are kept apart (for [`Correlations::leave_out`]);
    /// 1 for none.
    pub blocks: usize,
    /// Seconds between samples, which the sequence carries.
    pub sample_time_s: f64,
}

impl CorrelationOptions {
    /// `lags` lags of every output against every output, one block, at `sample_time_s`.
    pub fn new(lags: usize, sample_time_s: f64) -> Self {
        CorrelationOptions {
            references: None,
            lags,
            blocks: 1,
            sample_time_s,
        }
    }
}

/// The most lags [`correlations`] computes.
pub const MAX_LAGS: usize = 1 << 20;

/// The most blocks [`correlations`] keeps apart.
pub const MAX_BLOCKS: usize = 1000;

/// The output correlations of some records, and their blocks.
#[derive(Debug, Clone)]
pub struct Correlations {
    /// `R_0 … R_(L−1)`, outputs × references, of [`MarkovKind::Correlation`].
    pub sequence: MarkovSequence,
    /// The reference channels (0-based, among the outputs).
    pub references: Vec<usize>,
    /// Samples per channel over all records.
    pub samples: usize,
    /// Per block: the raw sums `Σ y(t+k) y_ref(t)`, woven as the sequence is.
    block_sums: Vec<Vec<f64>>,
    /// Per block: the terms of each lag's sum.
    block_counts: Vec<Vec<f64>>,
}

impl Correlations {
    /// Blocks kept apart.
    pub fn blocks(&self) -> usize {
        self.block_sums.len()
    }

    /// The correlations of every block but `block`: the sums of the others over their
    /// terms.
    ///
    /// # Errors
    /// [`EraError::InvalidParameter`] for a block that does not exist, or when the
    /// other blocks have no term at some lag.
    pub fn leave_out(&self, block: usize) -> Result<MarkovSequence> {
        if block >= self.blocks() {
            return Err(EraError::InvalidParameter {
                name: "block",
                value: block.to_string(),
                reason: format!("there are {} blocks", self.blocks()).into(),
            });
        }
        let (q, r, lags) = (
            self.sequence.outputs(),
            self.sequence.inputs(),
            self.sequence.samples(),
        );
        let mut out = MarkovSequence::zeros(q, r, lags)
            .with_sample_time(self.sequence.sample_time_s())
            .with_kind(MarkovKind::Correlation);
        for k in 0..lags {
            let count: f64 = (0..self.blocks())
                .filter(|&b| b != block)
                .map(|b| self.block_counts[b][k])
                .sum();
            if count <= 0.0 {
                return Err(EraError::InvalidParameter {
                    name: "lags",
                    value: lags.to_string(),
                    reason: format!("without block {block} no samples reach lag {k}").into(),
                });
            }
            for j in 0..r {
                for i in 0..q {
                    let at = (j * lags + k) * q + i;
                    let sum: f64 = (0..self.blocks())
                        .filter(|&b| b != block)
                        .map(|b| self.block_sums[b][at])
                        .sum();
                    out.set(k, i, j, sum / count);
                }
            }
        }
        Ok(out)
    }
}

/// Checks the records of an output-only test: at least one, every record the same
/// channels, every channel finite and not constant. Returns the channels.
fn check_records(records: &[&[&[f64]]]) -> Result<usize> {
    let first = records.first().ok_or_else(|| EraError::InvalidParameter {
        name: "records",
        value: "0".into(),
        reason: "give at least one record".into(),
    })?;
    let q = first.len();
    if q == 0 {
        return Err(EraError::InvalidParameter {
            name: "outputs",
            value: "0".into(),
            reason: "a record needs at least one output channel".into(),
        });
    }
    for (n, record) in records.iter().enumerate() {
        if record.len() != q {
            return Err(EraError::ShapeMismatch {
                what: format!("channels of record {}", n + 1),
                expected: q,
                got: record.len(),
            });
        }
        let len = record[0].len();
        for (c, ch) in record.iter().enumerate() {
            if ch.len() != len {
                return Err(EraError::ShapeMismatch {
                    what: format!("samples of output {} in record {}", c + 1, n + 1),
                    expected: len,
                    got: ch.len(),
                });
            }
            if let Some(sample) = ch.iter().position(|v| !v.is_finite()) {
                return Err(EraError::NonFiniteSample {
                    role: "output",
                    channel: c + 1,
                    sample,
                });
            }
        }
    }
    for c in 0..q {
        let varies = records.iter().any(|record| {
            let ch = record[c];
            ch.iter().any(|v| *v != ch[0])
        });
        if !varies {
            return Err(EraError::InvalidParameter {
                name: "outputs",
                value: (c + 1).to_string(),
                reason: format!(
                    "output {} is constant in every record (a dead channel): leave it out",
                    c + 1
                )
                .into(),
            });
        }
    }
    Ok(q)
}

/// The output correlations of `records` (each a set of output channels of one length;
/// all records the same channels) against the references, `options.lags` lags, in
/// `options.blocks` blocks.
///
/// # Errors
/// [`EraError::InvalidParameter`] for no record, no channel, a constant (dead) channel,
/// a reference that is not an output or is given twice, lags of 0 or above
/// [`MAX_LAGS`], blocks of 0 or above [`MAX_BLOCKS`], a block shorter than the lags,
/// or fewer samples than the lags need; [`EraError::ShapeMismatch`] for records or
/// channels of different shapes; [`EraError::NonFiniteSample`] for NaN or infinity.
pub fn correlations(records: &[&[&[f64]]], options: &CorrelationOptions) -> Result<Correlations> {
    let q = check_records(records)?;
    let references = match &options.references {
        None => (0..q).collect::<Vec<_>>(),
        Some(r) => r.clone(),
    };
    check_references(&references, q)?;
    let lags = options.lags;
    if lags == 0 || lags > MAX_LAGS {
        return Err(EraError::InvalidParameter {
            name: "lags",
            value: lags.to_string(),
            reason: format!("must be from 1 to {MAX_LAGS}").into(),
        });
    }
    if !(options.sample_time_s.is_finite() && options.sample_time_s > 0.0) {
        return Err(EraError::InvalidParameter {
            name: "sample_time_s",
            value: options.sample_time_s.to_string(),
            reason: "must be a positive number of seconds".into(),
        });
    }
    let samples: usize = records.iter().map(|r| r[0].len()).sum();
    let longest = records.iter().map(|r| r[0].len()).max().unwrap_or(0);
    if longest < 2 * lags {
        return Err(EraError::InvalidParameter {
            name: "lags",
            value: lags.to_string(),
            reason: format!(
                "the longest record has {longest} samples; {lags} lags need at least {} (twice the lags)",
                2 * lags
            )
            .into(),
        });
    }
    let blocks = options.blocks;
    if blocks == 0 || blocks > MAX_BLOCKS {
        return Err(EraError::InvalidParameter {
            name: "blocks",
            value: blocks.to_string(),
            reason: format!("must be from 1 to {MAX_BLOCKS}").into(),
        });
    }
    if samples / blocks < 2 * lags {
        return Err(EraError::InvalidParameter {
            name: "blocks",
            value: blocks.to_string(),
            reason: format!(
                "{samples} samples in {blocks} blocks leave {} a block, fewer than twice the {lags} lags: use fewer blocks or fewer lags",
                samples / blocks
            )
            .into(),
        });
    }
    let r = references.len();
    let mut acc = Accumulator::new(q, &references, lags, blocks, samples);
    for record in records {
        acc.add_record(record)?;
    }
    let (block_sums, block_counts) = acc.finish()?;
    let mut sequence = MarkovSequence::zeros(q, r, lags)
        .with_sample_time(options.sample_time_s)
        .with_kind(MarkovKind::Correlation);
    for k in 0..lags {
        let count: f64 = block_counts.iter().map(|c| c[k]).sum();
        for j in 0..r {
            for i in 0..q {
                let at = (j * lags + k) * q + i;
                let sum: f64 = block_sums.iter().map(|s| s[at]).sum();
                sequence.set(k, i, j, sum / count);
            }
        }
    }
    Ok(Correlations {
        sequence,
        references,
        samples,
        block_sums,
        block_counts,
    })
}

/// [`EraError::InvalidParameter`] naming `references` unless each is an output, once.
fn check_references(references: &[usize], outputs: usize) -> Result<()> {
    if references.is_empty() {
        return Err(EraError::InvalidParameter {
            name: "references",
            value: String::new(),
            reason: "give at least one reference channel".into(),
        });
    }
    for (n, &c) in references.iter().enumerate() {
        if c >= outputs {
            return Err(EraError::InvalidParameter {
                name: "references",
                value: (c + 1).to_string(),
                reason: format!("is not among the {outputs} outputs").into(),
            });
        }
        if references[..n].contains(&c) {
            return Err(EraError::InvalidParameter {
                name: "references",
                value: (c + 1).to_string(),
                reason: "is given twice".into(),
            });
        }
    }
    Ok(())
}

/// Per block, the lag sums and the lag counts.
type BlockSums = (Vec<Vec<f64>>, Vec<Vec<f64>>);

/// The running sums of the overlap-save correlation, block by block.
struct Accumulator<'r> {
    q: usize,
    references: &'r [usize],
    lags: usize,
    /// FFT length, and reference samples per chunk.
    nfft: usize,
    chunk: usize,
    /// Samples per block (the last takes the rest), and where the next sample falls.
    block_len: usize,
    blocks: usize,
    position: usize,
    /// The open block's cross-spectra `Σ Y_i conj(X_j)`, `[i][j][line]`.
    spectra: Vec<Vec<Vec<Complex64>>>,
    /// The open block's lag counts.
    counts: Vec<f64>,
    open_block: usize,
    block_sums: Vec<Vec<f64>>,
    block_counts: Vec<Vec<f64>>,
}

impl<'r> Accumulator<'r> {
    fn new(q: usize, references: &'r [usize], lags: usize, blocks: usize, samples: usize) -> Self {
        let nfft = (4 * lags).next_power_of_two().max(256);
        let lines = nfft / 2 + 1;
        let r = references.len();
        Accumulator {
            q,
            references,
            lags,
            nfft,
            chunk: nfft - lags + 1,
            block_len: samples / blocks,
            blocks,
            position: 0,
            spectra: vec![vec![vec![Complex64::new(0.0, 0.0); lines]; r]; q],
            counts: vec![0.0; lags],
            open_block: 0,
            block_sums: Vec::with_capacity(blocks),
            block_counts: Vec::with_capacity(blocks),
        }
    }

    /// The block a global sample index falls in.
    fn block_of(&self, position: usize) -> usize {
        (position / self.block_len).min(self.blocks - 1)
    }

    /// Correlates one record, chunk by chunk, closing blocks as their samples end.
    fn add_record(&mut self, record: &[&[f64]]) -> Result<()> {
        let n = record[0].len();
        let means: Vec<f64> = record
            .iter()
            .map(|ch| ch.iter().sum::<f64>() / n as f64)
            .collect();
        let mut start = 0;
        while start < n {
            crate::cancel::check()?;
            // A chunk never straddles two blocks: it ends where the open block ends.
            let block = self.block_of(self.position);
            if block != self.open_block {
                self.close_block()?;
            }
            let block_end = if block + 1 == self.blocks {
                usize::MAX
            } else {
                (block + 1) * self.block_len
            };
            let len = self
                .chunk
                .min(n - start)
                .min(block_end.saturating_sub(self.position));
            self.add_chunk(record, &means, start, len)?;
            start += len;
            self.position += len;
        }
        Ok(())
    }

    /// `Σ_(t in chunk) y(t+k) y_ref(t)` for every lag, into the open block's spectra.
    fn add_chunk(
        &mut self,
        record: &[&[f64]],
        means: &[f64],
        start: usize,
        len: usize,
    ) -> Result<()> {
        let n = record[0].len();
        let (nfft, lags) = (self.nfft, self.lags);
        let (r2c, _) = real_fft_plans(nfft);
        let reach = (len + lags - 1).min(n - start);
        let transform = |c: usize, count: usize| -> Result<Vec<Complex64>> {
            let mut buffer = vec![0.0; nfft];
            for (b, v) in buffer.iter_mut().zip(&record[c][start..start + count]) {
                *b = v - means[c];
            }
            let mut out = r2c.make_output_vec();
            r2c.process(&mut buffer, &mut out)
                .map_err(|e| EraError::Numerical(format!("forward FFT: {e}")))?;
            Ok(out)
        };
        let outs: Vec<Vec<Complex64>> = (0..self.q)
            .into_par_iter()
            .map(|c| transform(c, reach))
            .collect::<Result<_>>()?;
        let refs: Vec<Vec<Complex64>> = self
            .references
            .par_iter()
            .map(|&c| transform(c, len))
            .collect::<Result<_>>()?;
        self.spectra.par_iter_mut().zip(&outs).for_each(|(row, y)| {
            for (acc, x) in row.iter_mut().zip(&refs) {
                for ((a, yv), xv) in acc.iter_mut().zip(y).zip(x) {
                    *a += yv * xv.conj();
                }
            }
        });
        for (k, count) in self.counts.iter_mut().enumerate() {
            // Terms t < len with start + t + k < n.
            *count += len.min((n - start).saturating_sub(k)) as f64;
        }
        Ok(())
    }

    /// Inverse-transforms the open block's spectra into lag sums and starts the next.
    fn close_block(&mut self) -> Result<()> {
        let (q, r, lags, nfft) = (self.q, self.references.len(), self.lags, self.nfft);
        let (_, c2r) = real_fft_plans(nfft);
        let pairs: Vec<(usize, usize)> = (0..q).flat_map(|i| (0..r).map(move |j| (i, j))).collect();
        let series: Vec<Vec<f64>> = pairs
            .par_iter()
            .map(|&(i, j)| {
                let mut spectrum = self.spectra[i][j].clone();
                // The DC and Nyquist lines of a real signal's spectrum are real.
                spectrum[0].im = 0.0;
                let last = spectrum.len() - 1;
                spectrum[last].im = 0.0;
                let mut out = c2r.make_output_vec();
                c2r.process(&mut spectrum, &mut out)
                    .map_err(|e| EraError::Numerical(format!("inverse FFT: {e}")))?;
                Ok(out[..lags].iter().map(|v| v / nfft as f64).collect())
            })
            .collect::<Result<_>>()?;
        let mut sums = vec![0.0; q * r * lags];
        for (&(i, j), s) in pairs.iter().zip(&series) {
            for (k, v) in s.iter().enumerate() {
                sums[(j * lags + k) * q + i] = *v;
            }
        }
        self.block_sums.push(sums);
        self.block_counts
            .push(std::mem::replace(&mut self.counts, vec![0.0; lags]));
        for row in &mut self.spectra {
            for acc in row {
                acc.iter_mut().for_each(|a| *a = Complex64::new(0.0, 0.0));
            }
        }
        self.open_block += 1;
        Ok(())
    }

    /// Closes the last block; the per-block sums and counts.
    fn finish(mut self) -> Result<BlockSums> {
        self.close_block()?;
        Ok((self.block_sums, self.block_counts))
    }
}

/// Fewest lags [`default_lags`] gives: the scan at the default Hankel factor of
/// output-only identification reaches about 100 states (the largest order is tied to
/// the lags, not to the channels), whatever the lowest mode.
pub const MIN_DEFAULT_LAGS: usize = 128;

/// The most rows the scan's Hankel gets from [`default_lags`] (outputs × block rows):
/// enough for dozens of modes, and a dense SVD of well under a second.
pub const DEFAULT_HANKEL_ROWS: usize = 2048;

/// The default number of lags for `records` sampled at `sample_rate_hz`: two periods of
/// the lowest spectral peak (`lowest_peak_hz`), so that the Hankel (half the lags)
/// spans one and has `fs/(2 f_min)` block rows, the usual lower bound for SSI-cov
/// (more lags add the noise of the long lags: on simulated 600 s records, 256 lags
/// found fewer modes with worse damping than 128), rounded up to an even number; no more than keeps the Hankel within
/// [`DEFAULT_HANKEL_ROWS`] rows (a quarter of the lags in block rows, times the outputs)
/// unless that is below [`MIN_DEFAULT_LAGS`]; with one or two `references`, the least
/// lags times `3/references` (the Hankel's columns, a quarter of the lags times the
/// references, must leave the scan room for a few dozen states); and at most a tenth of the
/// longest record (the correlations' variance grows with the lag). Without a clear peak, the lowest frequency is
/// taken as 1 % of the sample rate.
///
/// # Errors
/// As [`correlations`]' checks of the records.
pub fn default_lags(
    records: &[&[&[f64]]],
    sample_rate_hz: f64,
    references: usize,
) -> Result<usize> {
    let q = check_records(records)?;
    let longest = records.iter().map(|r| r[0].len()).max().unwrap_or(0);
    let lowest = lowest_peak_hz(records, sample_rate_hz).unwrap_or(0.01 * sample_rate_hz);
    let wanted = (2.0 * sample_rate_hz / lowest).ceil() as usize;
    // The Hankel's columns are a quarter of the lags times the references: few
    // references need more lags for the scan's states to have room.
    let for_room = MIN_DEFAULT_LAGS * 3 / references.clamp(1, 3);
    let by_rows = 4 * DEFAULT_HANKEL_ROWS / q;
    let lags = wanted
        .min(by_rows)
        .max(MIN_DEFAULT_LAGS)
        .max(for_room)
        .min(longest / 10)
        .next_multiple_of(2);
    Ok(lags.max(2))
}

/// The lowest clear peak of the output spectrum, Hz: the sum over channels of each
/// channel's Welch power spectrum (Hann window, half overlap, segments of a 16th of the
/// longest record rounded down to a power of two, 256 to 8192 samples) over its
/// variance, in decibels, smoothed over five lines; a peak is a local maximum that
/// stands 6 dB above the higher of the lowest points on either side before a higher
/// value, within 50 dB of the highest line, above the third line. `None` when there is
/// none or the records are shorter than a segment.
pub(crate) fn lowest_peak_hz(records: &[&[&[f64]]], sample_rate_hz: f64) -> Option<f64> {
    let longest = records.iter().map(|r| r[0].len()).max()?;
    let seg = spectrum::default_segment(longest);
    if longest < seg {
        return None;
    }
    let (r2c, _) = real_fft_plans(seg);
    let window = crate::estimate::Window::Hann.values(seg);
    let lines = seg / 2 + 1;
    let mut total = vec![0.0; lines];
    for record in records {
        for ch in record.iter() {
            if ch.len() < seg {
                continue;
            }
            let mean = ch.iter().sum::<f64>() / ch.len() as f64;
            let var = ch.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / ch.len() as f64;
            if var <= 0.0 {
                continue;
            }
            let mut psd = vec![0.0; lines];
            let mut count = 0.0;
            let mut start = 0;
            let mut buffer = vec![0.0; seg];
            let mut out = r2c.make_output_vec();
            while start + seg <= ch.len() {
                for ((b, v), w) in buffer.iter_mut().zip(&ch[start..start + seg]).zip(&window) {
                    *b = (v - mean) * w;
                }
                if r2c.process(&mut buffer, &mut out).is_err() {
                    return None;
                }
                for (p, o) in psd.iter_mut().zip(&out) {
                    *p += o.norm_sqr();
                }
                count += 1.0;
                start += seg / 2;
            }
            for (t, p) in total.iter_mut().zip(&psd) {
                *t += p / count / var;
            }
        }
    }
    let db: Vec<f64> = total.iter().map(|v| 10.0 * v.max(1e-300).log10()).collect();
    let smooth: Vec<f64> = (0..lines)
        .map(|i| {
            let (lo, hi) = (i.saturating_sub(2), (i + 3).min(lines));
            db[lo..hi].iter().sum::<f64>() / (hi - lo) as f64
        })
        .collect();
    let top = smooth.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    let df = sample_rate_hz / seg as f64;
    (3..lines - 1)
        .filter(|&i| smooth[i] > smooth[i - 1] && smooth[i] >= smooth[i + 1])
        .filter(|&i| smooth[i] >= top - 50.0)
        .find(|&i| {
            let side = |range: &mut dyn Iterator<Item = usize>| {
                let mut low = smooth[i];
                for j in range {
                    if smooth[j] > smooth[i] {
                        break;
                    }
                    low = low.min(smooth[j]);
                }
                low
            };
            let left = side(&mut (0..i).rev());
            let right = side(&mut (i + 1..lines));
            smooth[i] - left.max(right) >= 6.0
        })
        .map(|i| i as f64 * df)
}

/// The direct definition of [`correlations`] (one block): a double loop, for tests.
#[cfg(test)]
pub(crate) fn correlations_naive(
    records: &[&[&[f64]]],
    references: &[usize],
    lags: usize,
) -> Vec<Vec<Vec<f64>>> {
    let q = records[0].len();
    let mut sums = vec![vec![vec![0.0; lags]; references.len()]; q];
    let mut counts = vec![0.0; lags];
    for record in records {
        let n = record[0].len();
        let means: Vec<f64> = record
            .iter()
            .map(|ch| ch.iter().sum::<f64>() / n as f64)
            .collect();
        for k in 0..lags.min(n) {
            counts[k] += (n - k) as f64;
            for (i, row) in sums.iter_mut().enumerate() {
                for (j, &c) in references.iter().enumerate() {
                    row[j][k] += (0..n - k)
                        .map(|t| (record[i][t + k] - means[i]) * (record[c][t] - means[c]))
                        .sum::<f64>();
                }
            }
        }
    }
    for row in &mut sums {
        for pair in row {
            for (v, c) in pair.iter_mut().zip(&counts) {
                *v /= c;
            }
        }
    }
    sums
}

#[cfg(test)]
mod tests {
    use super::*;

    fn noise(len: usize, seed: u64) -> Vec<f64> {
        let mut g = crate::linalg::rng::Minstd::new(seed);
        (0..len).map(|_| g.normal()).collect()
    }

    #[test]
    fn the_fft_estimate_is_the_direct_sum_over_records_and_blocks() {
        let a: Vec<Vec<f64>> = (0..3).map(|c| noise(700, 11 + c)).collect();
        let b: Vec<Vec<f64>> = (0..3).map(|c| noise(450, 31 + c)).collect();
        let ra: Vec<&[f64]> = a.iter().map(Vec::as_slice).collect();
        let rb: Vec<&[f64]> = b.iter().map(Vec::as_slice).collect();
        let records = [ra.as_slice(), rb.as_slice()];
        let refs = vec![2, 0];
        let naive = correlations_naive(&records, &refs, 40);
        for blocks in [1, 3, 7] {
            let options = CorrelationOptions {
                references: Some(refs.clone()),
                blocks,
                ..CorrelationOptions::new(40, 0.5)
            };
            let c = correlations(&records, &options).unwrap();
            assert_eq!(c.blocks(), blocks);
            assert_eq!(c.sequence.sample_time_s(), 0.5);
            assert_eq!(c.sequence.kind(), MarkovKind::Correlation);
            for (i, row) in naive.iter().enumerate() {
                for (j, pair) in row.iter().enumerate() {
                    for (k, &want) in pair.iter().enumerate() {
                        let got = c.sequence.get(k, i, j);
                        assert!(
                            (got - want).abs() < 1e-12,
                            "blocks {blocks} lag {k} ({i},{j}): {got} vs {want}"
                        );
                    }
                }
            }
        }
    }

    #[test]
    fn leaving_a_block_out_is_the_correlation_of_the_rest() {
        let a: Vec<Vec<f64>> = (0..2).map(|c| noise(900, 5 + c)).collect();
        let ra: Vec<&[f64]> = a.iter().map(Vec::as_slice).collect();
        let options = CorrelationOptions {
            blocks: 3,
            ..CorrelationOptions::new(30, 1.0)
        };
        let c = correlations(&[ra.as_slice()], &options).unwrap();
        // Block 1 is samples 300..600; without it, the sums over 0..300 and 600..900
        // (the first piece's lags reach into block 1's samples, as its sums did).
        let out = c.leave_out(1).unwrap();
        let means: Vec<f64> = a.iter().map(|ch| ch.iter().sum::<f64>() / 900.0).collect();
        for k in [0, 7, 29] {
            let mut sum = 0.0;
            let mut count = 0.0;
            for t in (0..300).chain(600..900) {
                if t + k < 900 {
                    sum += (a[1][t + k] - means[1]) * (a[0][t] - means[0]);
                    count += 1.0;
                }
            }
            assert!((out.get(k, 1, 0) - sum / count).abs() < 1e-12);
        }
        assert!(c.leave_out(3).is_err());
    }

    #[test]
    fn bad_records_and_references_are_named() {
        let good = noise(500, 3);
        let dead = vec![0.25; 500];
        let mut nan = noise(500, 4);
        nan[17] = f64::NAN;
        let options = CorrelationOptions::new(20, 1.0);
        let run = |chs: &[&[f64]], o: &CorrelationOptions| {
            correlations(&[chs], o).unwrap_err().to_string()
        };
        assert!(run(&[&good, &dead], &options).contains("output 2 is constant"));
        assert!(run(&[&good, &nan], &options).contains("17"));
        let refs = CorrelationOptions {
            references: Some(vec![5]),
            ..options.clone()
        };
        assert!(run(&[&good, &good], &refs).contains("not among the 2 outputs"));
        let long = CorrelationOptions::new(300, 1.0);
        assert!(run(&[&good], &long).contains("twice the lags"));
    }
}
