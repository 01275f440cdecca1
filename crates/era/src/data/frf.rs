//! Frequency response data: the input of the pipeline (docs/src/design.md §1 and §4).

use crate::error::{EraError, Result};
use num_complex::Complex64;

/// What an FRF measures per unit force.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
pub enum Quantity {
    /// Acceleration per unit force (accelerance, e.g. (in/s²)/lbf): what a file that
    /// does not say measures, and what the front ends assume by default.
    #[default]
    Acceleration,
    /// Velocity per unit force (mobility).
    Velocity,
    /// Displacement per unit force (receptance).
    Displacement,
}

impl Quantity {
    /// The quantity after one integration (`G/(jω)`), or `None` past displacement.
    pub fn integrated(self) -> Option<Quantity> {
        match self {
            Quantity::Acceleration => Some(Quantity::Velocity),
            Quantity::Velocity => Some(Quantity::Displacement),
            Quantity::Displacement => None,
        }
    }

    /// Lower-case name as used in files and on the command line.
    pub fn name(self) -> &'static str {
        crate::params::names::Named::name_of(&self)
    }

    /// Parses `acceleration`, `velocity` or `displacement` (case-insensitive).
    pub fn parse(text: &str) -> Option<Quantity> {
        crate::params::names::parse(text).ok()
    }
}

impl std::fmt::Display for Quantity {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

/// Measured (or simulated) FRFs `G[i][j](f_k)` of a structure with `q` outputs and `p`
/// inputs, at uniformly spaced lines `f_k = k·Δf` starting at 0 Hz.
///
/// Public axis order is `[output][input][line]` (docs/src/design.md §4); the values are stored in
/// exactly that order, so [`FrfData::pair`] is one contiguous slice per output/input
/// pair, which is what the FFT of the next stage wants.
///
/// Construct with `FrfData::new`, which validates everything the pipeline relies on.
#[derive(Debug, Clone, PartialEq)]
pub struct FrfData {
    frequency_hz: Vec<f64>,
    outputs: usize,
    inputs: usize,
    values: Vec<Complex64>,
    quantity: Quantity,
}

/// The lines `[first, end)` of `frequency_hz` inside `band_hz` (both edges included),
/// from line `from` on and above 0 Hz: the lines a fit over that band uses. `end <=
/// first` when none is inside.
pub fn band_lines(frequency_hz: &[f64], band_hz: (f64, f64), from: usize) -> (usize, usize) {
    let first = (from..frequency_hz.len())
        .find(|&k| frequency_hz[k] > 0.0 && frequency_hz[k] >= band_hz.0)
        .unwrap_or(frequency_hz.len());
    let end = frequency_hz
        .iter()
        .rposition(|&f| f <= band_hz.1)
        .map_or(0, |k| k + 1);
    (first, end)
}

/// Where a refinement of some FRFs fits, from [`fit_lines`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FitLines {
    /// The first measured line: past the leading lines that are zero in every pair (a
    /// padded late start) and past the lines zeroed on purpose.
    pub measured_from: usize,
    /// The band given, Hz, its top clipped to the last line.
    pub band_hz: Option<(f64, f64)>,
    /// The lines `[first, end)` the refinement fits; `None` leaves them to the
    /// identification (no band, and no line past 0 Hz zero).
    pub lines: Option<(usize, usize)>,
    /// The band identified over, Hz: the band given, or the measured lines'.
    pub fitted_hz: (f64, f64),
}

/// Where a refinement of `frf` fits: its measured lines (past the leading lines zero in
/// every pair and past `zero_lines`), inside `band_hz` (LO, HI in Hz) when one is
/// given. The CLI and the Python package both ask here, so that they fit the same
/// lines.
///
/// # Errors
/// The reason, for the front end to word with its name of the band: a band that is
/// not `0 <= lo < hi`, one above the data's last line, or one with fewer than two
/// measured lines in it.
pub fn fit_lines(
    frf: &FrfData,
    zero_lines: usize,
    band_hz: Option<(f64, f64)>,
) -> std::result::Result<FitLines, String> {
    let freq = frf.frequency_hz();
    let top = freq.last().copied().unwrap_or(0.0);
    let measured_from = leading_zero_lines(frf)
        .max(zero_lines)
        .min(freq.len().saturating_sub(1));
    let Some((lo, hi)) = band_hz else {
        return Ok(FitLines {
            measured_from,
            band_hz: None,
            lines: (measured_from > 1).then_some((measured_from, freq.len())),
            fitted_hz: (freq[measured_from], top),
        });
    };
    if !(lo.is_finite() && hi.is_finite() && 0.0 <= lo && lo < hi) {
        return Err("need 0 <= lo < hi, in Hz".into());
    }
    if lo >= top {
        return Err(format!("the data's lines end at {top} Hz, below the band"));
    }
    let hi = hi.min(top);
    let (first, end) = band_lines(freq, (lo, hi), measured_from);
    if end <= first + 1 {
        return Err(format!(
            "the data has {} measured line(s) in it (lines from {} Hz at {} Hz spacing)",
            end.saturating_sub(first),
            freq[measured_from],
            frf.spacing_hz()
        ));
    }
    Ok(FitLines {
        measured_from,
        band_hz: Some((lo, hi)),
        lines: Some((first, end)),
        fitted_hz: (lo, hi),
    })
}

/// Relative tolerance on the spacing of the frequency lines (analyzers print 6–10
/// significant digits).
pub const FREQUENCY_SPACING_TOLERANCE: f64 = 1e-6;

impl FrfData {
    /// The same lines, channels and quantity with other `values` (same layout as
    /// [`FrfData::values`]), validated as `FrfData::new` validates them.
    pub(crate) fn with_values(&self, values: Vec<Complex64>) -> Result<Self> {
        FrfData::new(
            self.frequency_hz().to_vec(),
            self.outputs(),
            self.inputs(),
            values,
            self.quantity(),
        )
    }

    /// Validates and wraps FRFs.
    ///
    /// `values[(i·p + j)·L + k]` is output `i`, input `j`, line `k`.
    ///
    /// # Errors
    /// [`EraError::TooFewLines`], [`EraError::FirstLineNotZero`],
    /// [`EraError::NonUniformFrequencies`] (relative tolerance
    /// [`FREQUENCY_SPACING_TOLERANCE`] of the spacing), [`EraError::NonFinite`],
    /// [`EraError::ShapeMismatch`] when `values.len() != q·p·L` or `q` or `p` is 0.
    pub fn new(
        frequency_hz: Vec<f64>,
        outputs: usize,
        inputs: usize,
        values: Vec<Complex64>,
        quantity: Quantity,
    ) -> Result<Self> {
        let lines = frequency_hz.len();
        if outputs == 0 || inputs == 0 {
            return Err(EraError::ShapeMismatch {
                what: "number of outputs and inputs (at least 1 each)".into(),
                expected: 1,
                got: outputs.min(inputs),
            });
        }
        if values.len() != outputs * inputs * lines {
            return Err(EraError::ShapeMismatch {
                what: format!("FRF values for {outputs} outputs x {inputs} inputs x {lines} lines"),
                expected: outputs * inputs * lines,
                got: values.len(),
            });
        }
        validate_frequencies(&frequency_hz)?;
        for (index, value) in values.iter().enumerate() {
            if !value.re.is_finite() || !value.im.is_finite() {
                let pair = index / lines;
                return Err(EraError::NonFinite {
                    what: "FRF",
                    output: pair / inputs + 1,
                    input: pair % inputs + 1,
                    line: index % lines,
                });
            }
        }
        Ok(FrfData {
            frequency_hz,
            outputs,
            inputs,
            values,
            quantity,
        })
    }

    /// Builds from a function of (output, input, line), all 0-based.
    pub fn from_fn(
        frequency_hz: Vec<f64>,
        outputs: usize,
        inputs: usize,
        quantity: Quantity,
        mut value: impl FnMut(usize, usize, usize) -> Complex64,
    ) -> Result<Self> {
        let lines = frequency_hz.len();
        let mut values = Vec::with_capacity(outputs * inputs * lines);
        for i in 0..outputs {
            for j in 0..inputs {
                for k in 0..lines {
                    values.push(value(i, j, k));
                }
            }
        }
        Self::new(frequency_hz, outputs, inputs, values, quantity)
    }

    /// Number of outputs (sensors), `q`.
    pub fn outputs(&self) -> usize {
        self.outputs
    }
    /// Number of inputs (actuators), `p`.
    pub fn inputs(&self) -> usize {
        self.inputs
    }
    /// Number of frequency lines, `L`.
    pub fn lines(&self) -> usize {
        self.frequency_hz.len()
    }
    /// The frequency lines, Hz.
    pub fn frequency_hz(&self) -> &[f64] {
        &self.frequency_hz
    }
    /// Line spacing Δf, Hz (from the first two lines).
    pub fn spacing_hz(&self) -> f64 {
        self.frequency_hz[1] - self.frequency_hz[0]
    }
    /// What the FRFs measure per unit force.
    pub fn quantity(&self) -> Quantity {
        self.quantity
    }
    /// All values, `[output][input][line]`.
    pub fn values(&self) -> &[Complex64] {
        &self.values
    }
    /// The FRF of output `i` from input `j` (0-based) over all lines.
    ///
    /// # Panics
    /// If `i` or `j` is out of range.
    #[track_caller]
    pub fn pair(&self, output: usize, input: usize) -> &[Complex64] {
        assert!(
            output < self.outputs && input < self.inputs,
            "pair out of range"
        );
        let lines = self.lines();
        let start = (output * self.inputs + input) * lines;
        &self.values[start..start + lines]
    }
    /// True when every value is exactly zero.
    pub(crate) fn is_all_zero(&self) -> bool {
        self.values.iter().all(|v| v.re == 0.0 && v.im == 0.0)
    }
    /// Returns the same data with another quantity tag (no conversion).
    pub fn with_quantity(mut self, quantity: Quantity) -> Self {
        self.quantity = quantity;
        self
    }
}

/// Checks that lines start at 0 Hz and are uniform (docs/src/design.md §1).
pub(crate) fn validate_frequencies(frequency_hz: &[f64]) -> Result<()> {
    let lines = frequency_hz.len();
    for (line, f) in frequency_hz.iter().enumerate() {
        if !f.is_finite() {
            return Err(EraError::NonFinite {
                what: "frequency",
                output: 0,
                input: 0,
                line,
            });
        }
    }
    if lines < 2 {
        return Err(EraError::TooFewLines { lines });
    }
    if frequency_hz[0] != 0.0 {
        return Err(EraError::FirstLineNotZero {
            first_hz: frequency_hz[0],
        });
    }
    let spacing = frequency_hz[1];
    if spacing <= 0.0 {
        return Err(EraError::NonUniformFrequencies {
            line: 1,
            found_hz: spacing,
            expected_hz: f64::NAN,
            spacing_hz: spacing,
        });
    }
    for (line, f) in frequency_hz.iter().enumerate() {
        let expected = line as f64 * spacing;
        if (f - expected).abs() > FREQUENCY_SPACING_TOLERANCE * spacing {
            return Err(EraError::NonUniformFrequencies {
                line,
                found_hz: *f,
                expected_hz: expected,
                spacing_hz: spacing,
            });
        }
    }
    Ok(())
}

/// The largest `|re|` or `|im|` among the finite values of `values` (0 when none is).
pub(crate) fn largest_component<'a>(values: impl IntoIterator<Item = &'a Complex64>) -> f64 {
    values
        .into_iter()
        .map(|z| z.re.abs().max(z.im.abs()))
        .filter(|m| m.is_finite())
        .fold(0.0f64, f64::max)
}

/// The exponent `e` for which `largest · 2^e` is nearest 1, kept within ±1000 so that
/// `2^e` is a normal double: scaling by it is exact, and keeps squares of such values
/// from overflowing or underflowing.
pub(crate) fn exponent_toward_one(largest: f64) -> i32 {
    (-(largest.log2().round() as i32)).clamp(-1000, 1000)
}

/// `n` uniformly spaced lines `0, Δf, …, (n-1)Δf`.
pub fn uniform_lines(lines: usize, spacing_hz: f64) -> Vec<f64> {
    (0..lines).map(|k| k as f64 * spacing_hz).collect()
}

/// Coherence below which a line carries little information (more noise than signal
/// in the output: `γ² < 0.5` means the noise power exceeds the coherent power).
pub const BAND_COHERENCE: f64 = 0.5;

/// Lines of the running median that smooths the coherence before the band is read.
const BAND_MEDIAN_LINES: usize = 9;

/// The band where the data carries information, from coherence: per line the largest
/// of `curves` (the multiple coherence of each output, say), smoothed by a running
/// median of 9 lines (a notch at a single line, an antiresonance, does not cut the
/// band), and the band runs from the first to the last line where it is at least
/// [`BAND_COHERENCE`]. `None` when that is every line above 0 Hz (nothing to cut), or
/// when no line qualifies.
pub fn coherence_band(frequency_hz: &[f64], curves: &[Vec<f64>]) -> Option<(f64, f64)> {
    let n = frequency_hz.len();
    if n < 3 || curves.is_empty() || curves.iter().any(|c| c.len() != n) {
        return None;
    }
    let best: Vec<f64> = (0..n)
        .map(|k| {
            curves
                .iter()
                .map(|c| c[k])
                .filter(|v| v.is_finite())
                .fold(0.0, f64::max)
        })
        .collect();
    let half = BAND_MEDIAN_LINES / 2;
    let smooth = |k: usize| {
        let mut w: Vec<f64> = best[k.saturating_sub(half)..(k + half + 1).min(n)].to_vec();
        w.sort_by(f64::total_cmp);
        w[w.len() / 2]
    };
    let good: Vec<usize> = (0..n)
        .filter(|&k| frequency_hz[k] > 0.0 && smooth(k) >= BAND_COHERENCE)
        .collect();
    let (first, last) = (*good.first()?, *good.last()?);
    let first_positive = frequency_hz.iter().position(|&f| f > 0.0)?;
    if first <= first_positive && last == n - 1 {
        return None;
    }
    Some((frequency_hz[first], frequency_hz[last]))
}

/// Leading lines of `frf` that are zero in every pair.
pub(crate) fn leading_zero_lines(frf: &FrfData) -> usize {
    let lines = frf.lines();
    let pairs = frf.outputs() * frf.inputs();
    (0..lines)
        .take_while(|&k| (0..pairs).all(|s| frf.values()[s * lines + k] == Complex64::ZERO))
        .count()
}

crate::params::names::named!(Quantity, "quantity", [
    Quantity::Acceleration => "acceleration" | "accel",
    Quantity::Velocity => "velocity" | "vel",
    Quantity::Displacement => "displacement" | "disp",
]);

#[cfg(test)]
mod tests {
    #[test]
    fn the_coherence_band_ignores_single_notches_and_cuts_the_noisy_ends() {
        let f: Vec<f64> = (0..101).map(f64::from).collect();
        let mut c: Vec<f64> = f
            .iter()
            .map(|&x| {
                if (20.0..=80.0).contains(&x) {
                    0.98
                } else {
                    0.1
                }
            })
            .collect();
        c[50] = 0.05; // an antiresonance
        assert_eq!(super::coherence_band(&f, &[c.clone()]), Some((20.0, 80.0)));
        // A second output coherent further up widens the band.
        let other: Vec<f64> = f
            .iter()
            .map(|&x| if x >= 30.0 { 0.9 } else { 0.2 })
            .collect();
        assert_eq!(super::coherence_band(&f, &[c, other]), Some((20.0, 100.0)));
        // Coherent everywhere: nothing to cut.
        assert_eq!(super::coherence_band(&f, &[vec![0.99; 101]]), None);
        assert_eq!(super::coherence_band(&f, &[vec![0.1; 101]]), None);
    }

    use super::*;

    fn ones(lines: usize) -> Vec<Complex64> {
        vec![Complex64::new(1.0, 0.0); lines]
    }

    #[test]
    fn accepts_uniform_lines_from_zero() {
        let f = uniform_lines(5, 0.025);
        let d = FrfData::new(f, 1, 1, ones(5), Quantity::Velocity).unwrap();
        assert_eq!(d.lines(), 5);
        assert!((d.spacing_hz() - 0.025).abs() < 1e-15);
    }

    #[test]
    fn rejects_nonzero_start_and_nonuniform_spacing() {
        let err = FrfData::new(vec![1.0, 2.0, 3.0], 1, 1, ones(3), Quantity::Velocity);
        assert!(matches!(err, Err(EraError::FirstLineNotZero { .. })));
        let err = FrfData::new(vec![0.0, 1.0, 2.5], 1, 1, ones(3), Quantity::Velocity);
        assert!(matches!(
            err,
            Err(EraError::NonUniformFrequencies { line: 2, .. })
        ));
    }

    #[test]
    fn rejects_nan_and_bad_shape() {
        let mut v = ones(6);
        v[4] = Complex64::new(f64::NAN, 0.0);
        let err = FrfData::new(uniform_lines(3, 1.0), 1, 2, v, Quantity::Velocity);
        assert_eq!(
            err,
            Err(EraError::NonFinite {
                what: "FRF",
                output: 1,
                input: 2,
                line: 1
            })
        );
        let err = FrfData::new(uniform_lines(3, 1.0), 2, 2, ones(6), Quantity::Velocity);
        assert!(matches!(
            err,
            Err(EraError::ShapeMismatch {
                expected: 12,
                got: 6,
                ..
            })
        ));
    }

    #[test]
    fn pair_is_output_major() {
        let d = FrfData::from_fn(
            uniform_lines(2, 1.0),
            2,
            3,
            Quantity::Velocity,
            |i, j, k| Complex64::new((10 * i + j) as f64, k as f64),
        )
        .unwrap();
        assert_eq!(d.pair(1, 2)[1], Complex64::new(12.0, 1.0));
    }
}
