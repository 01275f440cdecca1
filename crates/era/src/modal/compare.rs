//! Two FRF sets of one structure compared (thesis Figs. 5.8, 5.9, 5.12): the relative
//! difference of each pair per band, and, given a model of each, each model's fit to
//! its own data and the modes of one matched to the other's by MAC.

use crate::error::Result;
use crate::modal::indicators::mac;
use crate::pipeline::fit::model_frf;
use crate::pipeline::modes::modal_parameters;
use crate::{Complex64, FrfData, StateSpace};

/// The difference of each pair per band, percent.
#[derive(Debug, Clone, PartialEq)]
pub struct BandDifferences {
    /// Each pair (`"i/j"`, 1-based) with its difference in each band.
    pub pairs: Vec<(String, Vec<f64>)>,
    /// The median over pairs, per band (pairs without power in the band left out).
    pub median: Vec<f64>,
    /// The worst pair, per band.
    pub worst: Vec<f64>,
}

/// One side of a model comparison: its FRFs, the model identified from them, and the
/// integrations ERA applied to the FRFs before it fitted the model.
#[derive(Debug, Clone, Copy)]
pub struct Side<'a> {
    /// The FRFs.
    pub frf: &'a FrfData,
    /// The model.
    pub model: &'a StateSpace,
    /// The integrations the model's FRFs underwent.
    pub integrations: usize,
}

/// Two models compared.
#[derive(Debug, Clone, PartialEq)]
pub struct ComparedModels {
    /// A's modes matched to B's: A's frequency (Hz) and damping ratio, B's, the MAC.
    pub modes: Vec<(f64, f64, f64, f64, f64)>,
    /// Each model's fit to its own data, percent (mean relative error over pairs).
    pub fit: (f64, f64),
}

/// Relative RMS difference `‖A − B‖ / ‖B‖` over the lines `lo ≤ f < hi` (NaN when B has
/// no power there).
pub(crate) fn band_difference(
    a: &[Complex64],
    b: &[Complex64],
    f: &[f64],
    lo: f64,
    hi: f64,
) -> f64 {
    let (mut num, mut den) = (0.0, 0.0);
    for k in 0..f.len() {
        if f[k] >= lo && f[k] < hi {
            num += (a[k] - b[k]).norm_sqr();
            den += b[k].norm_sqr();
        }
    }
    if den > 0.0 {
        (num / den).sqrt()
    } else if num == 0.0 {
        0.0
    } else {
        f64::NAN
    }
}

/// The difference of each pair in each band, percent; the median over pairs and the
/// worst pair per band.
pub fn band_differences(ga: &FrfData, gb: &FrfData, bands: &[f64]) -> BandDifferences {
    let (q, p) = (ga.outputs(), ga.inputs());
    let f = ga.frequency_hz();
    let mut differences = Vec::new();
    let mut worst: Vec<f64> = vec![0.0; bands.len() - 1];
    for i in 0..q {
        for j in 0..p {
            let row: Vec<f64> = bands
                .windows(2)
                .map(|w| 100.0 * band_difference(ga.pair(i, j), gb.pair(i, j), f, w[0], w[1]))
                .collect();
            for (w, v) in worst.iter_mut().zip(&row) {
                if v.is_finite() {
                    *w = w.max(*v);
                }
            }
            differences.push((format!("{}/{}", i + 1, j + 1), row));
        }
    }
    let median_band: Vec<f64> = (0..bands.len() - 1)
        .map(|b| {
            let mut v: Vec<f64> = differences
                .iter()
                .map(|d| d.1[b])
                .filter(|x| x.is_finite())
                .collect();
            v.sort_by(f64::total_cmp);
            v.get(v.len() / 2).copied().unwrap_or(f64::NAN)
        })
        .collect();
    BandDifferences {
        pairs: differences,
        median: median_band,
        worst,
    }
}

/// Each model's fit to its own data over `band` (percent), and A's modes matched to
/// B's: among B's modes within 10 % in frequency, the one with the highest MAC.
///
/// # Errors
/// [`crate::EraError`] when a model's response or modes cannot be computed.
pub fn compare_models((a, b): (&Side, &Side), band: (f64, f64)) -> Result<ComparedModels> {
    let da = integrated(a.frf, a.integrations)?;
    let db = integrated(b.frf, b.integrations)?;
    let ma = model_frf(a.model, &da)?;
    let mb = model_frf(b.model, &db)?;
    let fit = (
        100.0 * fit_error(&da, &ma, band),
        100.0 * fit_error(&db, &mb, band),
    );
    let pa = modal_parameters(a.model)?;
    let pb = modal_parameters(b.model)?;
    let mut modes = Vec::new();
    for m in &pa.modes {
        let best = pb
            .modes
            .iter()
            .filter(|n| (n.frequency_hz - m.frequency_hz).abs() <= 0.1 * m.frequency_hz)
            .map(|n| (mac(&m.shape, &n.shape), n))
            .max_by(|x, y| x.0.total_cmp(&y.0));
        if let Some((value, n)) = best {
            modes.push((
                m.frequency_hz,
                m.damping_ratio,
                n.frequency_hz,
                n.damping_ratio,
                value,
            ));
        }
    }
    Ok(ComparedModels { modes, fit })
}

/// `G / (j2πf)^n` on every line above 0 Hz (0 at 0 Hz): what ERA fitted after `n`
/// integrations.
fn integrated(frf: &FrfData, n: usize) -> Result<FrfData> {
    let f = frf.frequency_hz().to_vec();
    let lines = f.len();
    let mut v = frf.values().to_vec();
    for (idx, x) in v.iter_mut().enumerate() {
        let k = idx % lines;
        *x = if f[k] > 0.0 {
            *x / Complex64::new(0.0, 2.0 * std::f64::consts::PI * f[k]).powi(n as i32)
        } else {
            Complex64::new(0.0, 0.0)
        };
    }
    FrfData::new(f, frf.outputs(), frf.inputs(), v, frf.quantity())
}

/// Mean relative error `‖G − Ĝ‖/‖G‖` over pairs, on the lines in `band`.
fn fit_error(data: &FrfData, model: &FrfData, band: (f64, f64)) -> f64 {
    let f = data.frequency_hz();
    let (q, p) = (data.outputs(), data.inputs());
    let mut total = 0.0;
    for i in 0..q {
        for j in 0..p {
            total += band_difference(model.pair(i, j), data.pair(i, j), f, band.0, band.1 + 1e-9);
        }
    }
    total / (q * p) as f64
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_band_difference_is_relative_to_b_and_nan_where_b_has_no_power() {
        let f = [0.0, 1.0, 2.0, 3.0];
        let b = [Complex64::new(1.0, 0.0); 4];
        let mut a = b;
        a[1] = Complex64::new(1.5, 0.0);
        // Lines 1 and 2: ‖A − B‖² = 0.25 over ‖B‖² = 2.
        let d = band_difference(&a, &b, &f, 1.0, 3.0);
        assert!((d - (0.25f64 / 2.0).sqrt()).abs() < 1e-15, "{d}");
        assert_eq!(band_difference(&b, &b, &f, 0.0, 4.0), 0.0);
        let zero = [Complex64::new(0.0, 0.0); 4];
        assert!(band_difference(&a, &zero, &f, 0.0, 4.0).is_nan());
        assert_eq!(band_difference(&zero, &zero, &f, 0.0, 4.0), 0.0);
    }
}
