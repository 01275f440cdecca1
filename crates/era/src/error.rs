//! Typed errors of the numeric core.
//!
//! Every variant carries the offending values so that a front end can print a message a
//! user can act on ("Hankel needs 401 Markov samples, the data has 320"). Variants are
//! split into *input* problems (bad data or impossible parameters: a CLI exits 2) and
//! *numerical* failures (a decomposition did not converge: exit 1); see
//! [`EraError::is_input_error`].
//!
//! A parameter is named by a [`Param`], never by one front end's spelling: a front end
//! shows a message through [`EraError::spelled`] with its own spelling of each parameter.

use thiserror::Error;

pub use crate::params::names::{Param, Prose};

/// Everything that can go wrong in the numeric core.
#[derive(Debug, Error, Clone, PartialEq)]
#[non_exhaustive]
pub enum EraError {
    /// The frequency vector is empty or too short to define a spacing.
    #[error("need at least 2 frequency lines, got {lines}")]
    TooFewLines {
        /// Lines supplied.
        lines: usize,
    },
    /// The first line is not 0 Hz (docs/src/design.md §1: the pipeline needs `f_0 = 0`).
    #[error("frequencies must start at 0 Hz, the first line is {first_hz} Hz")]
    FirstLineNotZero {
        /// The first frequency, Hz.
        first_hz: f64,
    },
    /// Frequencies are not uniformly spaced.
    #[error("{}", non_uniform_message(*line, *found_hz, *expected_hz, *spacing_hz))]
    NonUniformFrequencies {
        /// 0-based line index.
        line: usize,
        /// Frequency found, Hz.
        found_hz: f64,
        /// Frequency expected from the spacing of the first two lines, Hz (NaN when that
        /// spacing is not positive).
        expected_hz: f64,
        /// Spacing of the first two lines, Hz.
        spacing_hz: f64,
    },
    /// A frequency or FRF value is NaN or infinite.
    #[error("{}", non_finite_message(what, *output, *input, *line))]
    NonFinite {
        /// Which array.
        what: &'static str,
        /// 1-based output (0 for the frequency vector).
        output: usize,
        /// 1-based input (0 for the frequency vector).
        input: usize,
        /// 0-based line.
        line: usize,
    },
    /// Array sizes do not agree.
    #[error("inconsistent shapes: {what}: expected {expected}, got {got}")]
    ShapeMismatch {
        /// What was being checked.
        what: String,
        /// Expected size.
        expected: usize,
        /// Actual size.
        got: usize,
    },
    /// Every FRF value is zero: there is nothing to identify.
    #[error("every FRF value is zero: there is nothing to identify")]
    AllZero,
    /// An option is outside its allowed range.
    #[error("invalid parameter {name} = {value}: {reason}")]
    InvalidParameter {
        /// The parameter's field name, snake case (`hankel_factor`); a front end spells
        /// the ones that are [`Param`]s its own way.
        name: &'static str,
        /// The value given, as text.
        value: String,
        /// Why it is invalid (what to change, with the parameters it names).
        reason: Prose,
    },
    /// The Hankel matrix asks for more Markov samples than the data has.
    #[error("{}", self.spelled(&|p| p.field().to_string()))]
    NotEnoughMarkovSamples {
        /// Samples needed.
        needed: usize,
        /// Samples available.
        available: usize,
        /// Requested states.
        states: usize,
        /// Requested Hankel factor.
        hankel_factor: usize,
    },
    /// The Hankel matrix is smaller than the requested model order (thesis §1.8 error,
    /// "increase the length of the time series").
    #[error("{}", self.spelled(&|p| p.field().to_string()))]
    HankelTooSmall {
        /// Rows of H0.
        rows: usize,
        /// Columns of H0.
        cols: usize,
        /// min(rows, cols).
        available: usize,
        /// Requested states.
        states: usize,
    },
    /// The data's Hankel matrix has numerical rank below the requested order.
    #[error("{}", self.spelled(&|p| p.field().to_string()))]
    RankDeficient {
        /// Numerical rank.
        rank: usize,
        /// Requested states.
        states: usize,
        /// Threshold used.
        threshold: f64,
    },
    /// A discrete pole has no real logarithm (on or near the negative real axis, or zero).
    #[error("{}", self.spelled(&|p| p.field().to_string()))]
    NoRealLogarithm {
        /// Real part of the pole.
        re: f64,
        /// Imaginary part of the pole.
        im: f64,
    },
    /// The model could not be converted reliably (e.g. defective eigenvectors).
    #[error("{0}")]
    Conversion(String),
    /// The zero-order-hold inverse does not reproduce the discrete model: its
    /// eigenvectors are nearly dependent.
    #[error("{}", self.spelled(&|p| p.field().to_string()))]
    UnreliableContinuous {
        /// Relative difference of `c2d(d2c(A, B))` from `(A, B)`.
        round_trip_error: f64,
    },
    /// A time-history sample is NaN or infinite.
    #[error("non-finite sample in {role} {channel} at sample {sample} (0-based)")]
    NonFiniteSample {
        /// `"input"` or `"output"`.
        role: &'static str,
        /// 1-based channel among the inputs or the outputs.
        channel: usize,
        /// 0-based sample index.
        sample: usize,
    },
    /// An input of a time-history source cannot drive the identification: it has no
    /// energy, or it is a linear combination of the inputs before it.
    #[error("input {input}: {reason}")]
    DeficientInput {
        /// 1-based input channel.
        input: usize,
        /// What is wrong, and what to do.
        reason: String,
    },
    /// The input cross-spectral matrix cannot be inverted (H1, multiple coherence).
    #[error("{}", self.spelled(&|p| p.field().to_string()))]
    SingularInputSpectrum {
        /// Lines where it is singular.
        singular_lines: usize,
        /// Lines in all.
        lines: usize,
        /// Frequency of the first singular line, Hz.
        first_hz: f64,
        /// Smallest eigenvalue of the coherence-normalised matrix at that line (1 = fully
        /// independent inputs, 0 = linearly dependent).
        min_eigenvalue: f64,
        /// What it means: which inputs are coherent, or too few averages.
        reason: Prose,
    },
    /// A size asked for by the data or a parameter is above a resource limit
    /// ([`crate::params::limits`]).
    #[error(transparent)]
    Limit(#[from] crate::params::limits::LimitError),
    /// A parameter a front end passed is refused; the message names it as that front
    /// end does (a flag, a keyword) with its value ([`crate::params`]).
    #[error("{0}")]
    Invalid(String),
    /// A dense decomposition failed to converge.
    #[error("numerical failure: {0}")]
    Numerical(String),
    /// The truncated SVD did not converge (a numerical failure, not the caller's).
    #[error("{}", self.spelled(&|p| p.field().to_string()))]
    SvdNotConverged {
        /// Passes made.
        passes: usize,
        /// Residual reached.
        residual: f64,
        /// Tolerance asked for.
        tolerance: f64,
    },
    /// The caller stopped the call ([`crate::cancel`]): Ctrl-C in Python.
    #[error("interrupted")]
    Interrupted,
}

impl EraError {
    /// The message, with each parameter it names (the refused one, or the one a remedy
    /// asks to change) spelled by `spell`: a front end passes its own spelling (a flag,
    /// a keyword); `Display` uses the field names. Variants that name no parameter read
    /// as their `Display`.
    pub fn spelled(&self, spell: &dyn Fn(Param) -> String) -> String {
        let n = |p: Param| spell(p);
        match self {
            EraError::InvalidParameter {
                name,
                value,
                reason,
            } => refused_parameter(name, value, &reason.spelled(spell), spell),
            EraError::SingularInputSpectrum {
                singular_lines,
                lines,
                first_hz,
                min_eigenvalue,
                reason,
            } => format!(
                "the input cross-spectral matrix is singular at {singular_lines} of {lines} lines (first at {first_hz} Hz, smallest normalised eigenvalue {min_eigenvalue:.3e}): {}",
                reason.spelled(spell)
            ),
            EraError::Limit(limit) => limit.spelled(spell),
            EraError::SvdNotConverged {
                passes,
                residual,
                tolerance,
            } => format!(
                "numerical failure: the truncated SVD did not converge in {passes} passes (residual {residual:.2e}, tolerance {tolerance:.0e}): use {} dense",
                n(Param::Svd)
            ),
            EraError::NotEnoughMarkovSamples {
                needed,
                available,
                states,
                hankel_factor,
            } => format!(
                "the Hankel matrix needs {needed} Markov samples (states {states} x hankel factor {hankel_factor}, plus the direct term), the data gives {available}: lower {} or {}, or pad with {}",
                n(Param::HankelFactor),
                n(Param::States),
                n(Param::PadTo)
            ),
            EraError::HankelTooSmall {
                rows,
                cols,
                available,
                states,
            } => format!(
                "the Hankel matrix is {rows} x {cols}: it has only {available} singular values, fewer than the {states} states requested; increase {}",
                n(Param::HankelFactor)
            ),
            EraError::RankDeficient {
                rank,
                states,
                threshold,
            } => format!(
                "the data supports only {rank} states (singular values beyond that are below {threshold:.3e}), but {states} were requested: lower {}",
                n(Param::States)
            ),
            EraError::UnreliableContinuous { round_trip_error } => format!(
                "the zero-order-hold inverse is unreliable for this model (round trip error {round_trip_error:.2e}): its eigenvectors are nearly dependent; keep {} discrete",
                n(Param::TimeDomain)
            ),
            EraError::NoRealLogarithm { re, im } => format!(
                "the discrete model has a pole at z = {re:+.6e}{im:+.6e}i, which has no real continuous-time equivalent (zero-order-hold inverse undefined): keep {} discrete",
                n(Param::TimeDomain)
            ),
            other => other.to_string(),
        }
    }

    /// True for problems with the caller's data or parameters (exit code 2 in the CLI),
    /// false for internal numerical failures (exit code 1) and an interrupted call.
    pub fn is_input_error(&self) -> bool {
        !matches!(
            self,
            EraError::Numerical(_) | EraError::SvdNotConverged { .. } | EraError::Interrupted
        )
    }
}

/// Whose fault an error is: the caller's (bad data, a refused value, an unreadable
/// file: the CLI exits 2, Python raises `ValueError`) or the program's (exit 1). Every
/// error type of era's crates says it here, so a front end asks one question of any
/// error it meets.
pub trait InputError: std::error::Error {
    /// True when the caller can mend it by changing what it passed.
    fn is_input_error(&self) -> bool;
}

impl InputError for EraError {
    fn is_input_error(&self) -> bool {
        EraError::is_input_error(self)
    }
}

/// A size above a limit is the caller's to lower (or to raise the limit).
impl InputError for crate::params::limits::LimitError {
    fn is_input_error(&self) -> bool {
        true
    }
}

/// `invalid parameter {name} = {value}: {reason}`, the name spelled by `spell` when it is a
/// [`Param`] (a front end's flag or keyword), as given otherwise (`record`, `structure`):
/// the words of every refused parameter, [`EraError`]'s and the friction module's.
pub(crate) fn refused_parameter(
    name: &str,
    value: &str,
    reason: &str,
    spell: &dyn Fn(Param) -> String,
) -> String {
    let shown = Param::from_field(name).map_or_else(|| name.to_string(), spell);
    format!("invalid parameter {shown} = {value}: {reason}")
}

/// Result alias of the core.
pub type Result<T> = std::result::Result<T, EraError>;

/// [`EraError::NonUniformFrequencies`]: a second line at or below 0 Hz has no spacing to
/// expect anything from.
fn non_uniform_message(line: usize, found_hz: f64, expected_hz: f64, spacing_hz: f64) -> String {
    if spacing_hz > 0.0 && expected_hz.is_finite() {
        format!(
            "frequencies are not uniformly spaced: line {line} is {found_hz} Hz, expected {expected_hz} Hz (spacing {spacing_hz} Hz)"
        )
    } else {
        format!("frequencies must increase from 0 Hz: line {line} is {found_hz} Hz")
    }
}

/// [`EraError::NonFinite`]: the frequency vector has lines only (output and input 0).
fn non_finite_message(what: &str, output: usize, input: usize, line: usize) -> String {
    if output == 0 && input == 0 {
        format!("non-finite value in {what} at line {line}")
    } else {
        format!("non-finite value in {what} at output {output}, input {input}, line {line}")
    }
}

#[cfg(test)]
mod tests {

    /// The frequency checks' messages say what is wrong in every case: a second line at
    /// or below 0 Hz has no spacing (no "expected NaN Hz"), and the frequency vector has no
    /// outputs or inputs to name.
    #[test]
    fn frequency_messages_read_right_in_every_case() {
        let decreasing = crate::data::frf::validate_frequencies(&[0.0, -12.5, -25.0]).unwrap_err();
        assert_eq!(
            decreasing.to_string(),
            "frequencies must increase from 0 Hz: line 1 is -12.5 Hz"
        );
        let uneven = crate::data::frf::validate_frequencies(&[0.0, 2.0, 5.0]).unwrap_err();
        assert_eq!(
            uneven.to_string(),
            "frequencies are not uniformly spaced: line 2 is 5 Hz, expected 4 Hz (spacing 2 Hz)"
        );
        let nan = crate::data::frf::validate_frequencies(&[0.0, 1.0, f64::NAN]).unwrap_err();
        assert_eq!(nan.to_string(), "non-finite value in frequency at line 2");
    }
}
