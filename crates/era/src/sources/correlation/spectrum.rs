//! The output spectral matrix of output-only records and its singular values: frequency
//! domain decomposition's first look (Brincker, Zhang & Andersen 2001). Each peak of the
//! largest singular value is a mode; a second value rising beside it, a close pair.
//!
//! The estimate is Welch's: Hann-windowed segments, half overlapping, each channel's
//! mean removed, the cross-spectra `G_ij = Σ Y_i Y_j*` averaged over the segments of
//! every record. At each line the matrix is Hermitian and positive semidefinite, so its
//! singular values are its eigenvalues (faer's self-adjoint solver).

use crate::error::{EraError, Result};
use crate::linalg::fft::real_fft_plans;
use faer::{Mat, Side};
use num_complex::Complex64;
use rayon::prelude::*;

/// The singular values of the output spectral matrix at each line.
#[derive(Debug, Clone, PartialEq)]
pub struct OutputSpectrum {
    /// Line frequencies, Hz, from 0 to the Nyquist frequency.
    pub frequency_hz: Vec<f64>,
    /// `[line][k]`, largest first (power per hertz, in the records' units squared).
    pub singular_values: Vec<Vec<f64>>,
    /// Samples per segment.
    pub segment: usize,
    /// Segments averaged.
    pub averages: usize,
}

/// The default segment: a sixteenth of the longest record rounded down to a power of
/// two, from 256 to 8192 samples (at least eight averages with half overlap on long
/// records, and lines fine enough to part modes a few lines apart).
pub(crate) fn default_segment(longest: usize) -> usize {
    let seg = (longest / 16).clamp(256, 8192);
    1usize << (usize::BITS - 1 - seg.leading_zeros())
}

/// The largest number of lines × channels² the spectral matrix may hold in memory
/// (about 1.5 GB of complex values).
pub(crate) const MAX_SPECTRAL_ENTRIES: usize = 100_000_000;

/// The output spectrum of `records` (each a set of output channels of one length; the
/// same channels in each) sampled at `sample_rate_hz`, in segments of `segment`
/// samples ([`default_segment`] when `None`).
///
/// # Errors
/// [`EraError::InvalidParameter`] for no record or channel, a segment below 16 or longer
/// than every record, a spectral matrix above [`MAX_SPECTRAL_ENTRIES`], or a sample
/// rate that is not positive; [`EraError::Numerical`] when a transform fails.
pub(crate) fn output_spectrum(
    records: &[&[&[f64]]],
    sample_rate_hz: f64,
    segment: Option<usize>,
) -> Result<OutputSpectrum> {
    let q = records.first().map_or(0, |r| r.len());
    if q == 0 {
        return Err(EraError::InvalidParameter {
            name: "outputs",
            value: "0".into(),
            reason: "give at least one record with one output channel".into(),
        });
    }
    if !(sample_rate_hz.is_finite() && sample_rate_hz > 0.0) {
        return Err(EraError::InvalidParameter {
            name: "sample_rate_hz",
            value: sample_rate_hz.to_string(),
            reason: "must be a positive number of samples per second".into(),
        });
    }
    let longest = records.iter().map(|r| r[0].len()).max().unwrap_or(0);
    let seg = segment.unwrap_or_else(|| default_segment(longest));
    if seg < 16 || seg > longest {
        return Err(EraError::InvalidParameter {
            name: "segment",
            value: seg.to_string(),
            reason: format!("must be from 16 to the longest record, {longest} samples").into(),
        });
    }
    let lines = seg / 2 + 1;
    if lines.saturating_mul(q * q) > MAX_SPECTRAL_ENTRIES {
        return Err(EraError::InvalidParameter {
            name: "segment",
            value: seg.to_string(),
            reason: format!(
                "{lines} lines x {q}² channel pairs exceed {MAX_SPECTRAL_ENTRIES} spectral entries: use a shorter segment"
            )
            .into(),
        });
    }
    let (r2c, _) = real_fft_plans(seg);
    let window = crate::estimate::Window::Hann.values(seg);
    // g[i][j][line], i ≥ j (the lower triangle; the matrix is Hermitian).
    let mut g = vec![vec![vec![Complex64::new(0.0, 0.0); lines]; q]; q];
    let mut averages = 0;
    for record in records {
        let n = record[0].len();
        let means: Vec<f64> = record
            .iter()
            .map(|c| c.iter().sum::<f64>() / n as f64)
            .collect();
        let mut start = 0;
        while start + seg <= n {
            crate::cancel::check()?;
            let spectra: Vec<Vec<Complex64>> = (0..q)
                .into_par_iter()
                .map(|c| {
                    let mut buffer: Vec<f64> = record[c][start..start + seg]
                        .iter()
                        .zip(&window)
                        .map(|(v, w)| (v - means[c]) * w)
                        .collect();
                    let mut out = r2c.make_output_vec();
                    r2c.process(&mut buffer, &mut out)
                        .map_err(|e| EraError::Numerical(format!("forward FFT: {e}")))?;
                    Ok(out)
                })
                .collect::<Result<_>>()?;
            g.par_iter_mut().enumerate().for_each(|(i, row)| {
                for (j, acc) in row.iter_mut().enumerate().take(i + 1) {
                    for ((a, x), y) in acc.iter_mut().zip(&spectra[i]).zip(&spectra[j]) {
                        *a += x * y.conj();
                    }
                }
            });
            averages += 1;
            start += seg / 2;
        }
    }
    // One-sided density: 2 / (fs Σw²) per average.
    let power: f64 = window.iter().map(|w| w * w).sum();
    let scale = 2.0 / (sample_rate_hz * power * averages.max(1) as f64);
    let singular_values = (0..lines)
        .into_par_iter()
        .map(|k| {
            let m = Mat::<Complex64>::from_fn(q, q, |a, b| {
                if a >= b {
                    g[a][b][k] * scale
                } else {
                    g[b][a][k].conj() * scale
                }
            });
            let mut e = m
                .self_adjoint_eigenvalues(Side::Lower)
                .unwrap_or_else(|_| vec![f64::NAN; q]);
            e.iter_mut().for_each(|v| *v = v.max(0.0));
            e.reverse();
            e
        })
        .collect();
    let df = sample_rate_hz / seg as f64;
    Ok(OutputSpectrum {
        frequency_hz: (0..lines).map(|k| k as f64 * df).collect(),
        singular_values,
        segment: seg,
        averages,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_sine_in_two_channels_is_one_rank_one_peak_at_its_line() {
        let fs = 100.0;
        let n = 8192;
        let f0 = 12.5;
        let a: Vec<f64> = (0..n)
            .map(|t| (2.0 * std::f64::consts::PI * f0 * t as f64 / fs).sin())
            .collect();
        let b: Vec<f64> = a.iter().map(|v| -2.0 * v).collect();
        let s = output_spectrum(&[&[&a, &b]], fs, Some(512)).unwrap();
        assert_eq!(s.averages, 31);
        let peak = (0..s.frequency_hz.len())
            .max_by(|&x, &y| s.singular_values[x][0].total_cmp(&s.singular_values[y][0]))
            .unwrap();
        assert!((s.frequency_hz[peak] - f0).abs() < fs / 512.0);
        // Rank one: the second value is rounding.
        assert!(s.singular_values[peak][1] < 1e-12 * s.singular_values[peak][0]);
        // Parseval: the first value's integral is the two channels' total variance.
        let df = s.frequency_hz[1];
        let total: f64 = s.singular_values.iter().map(|v| v[0] + v[1]).sum::<f64>() * df;
        assert!((total / 2.5 - 1.0).abs() < 0.05, "{total}");
    }

    #[test]
    fn bad_segments_are_named() {
        let a = vec![1.0, 2.0, 3.0];
        let e = output_spectrum(&[&[&a]], 10.0, Some(8)).unwrap_err();
        assert!(e.to_string().contains("segment"));
        assert!(output_spectrum(&[&[&a]], 0.0, Some(2)).is_err());
    }
}
