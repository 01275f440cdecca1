//! Checks of the parameters a front end passes, shared by the command line and the
//! Python package so that both refuse the same values with the same words.
//!
//! A front end names a parameter its own way: the CLI as a flag (`--hankel-factor`),
//! Python as a keyword (`hankel_factor`). Each check takes a [`Naming`] and quotes the
//! parameter as the caller wrote it, with the value it gave:
//! `--states 0: the model needs at least one state` from the CLI,
//! `states 0: the model needs at least one state` from Python.
//!
//! A refused value is [`EraError::Invalid`] (an input error: exit code 2 in the CLI,
//! `ValueError` in Python), or [`EraError::Limit`] when a size is above one of
//! [`crate::limits`].

use crate::error::{EraError, Result};

/// How the calling front end names its parameters.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Naming {
    /// Command-line flags: `--hankel-factor`, `--lowpass-hz`.
    Flag,
    /// Python keywords: `hankel_factor`, and `lowpass` for the cut-off (the order is
    /// `lowpass=(order, hz)` there).
    Keyword,
}

impl Naming {
    /// The name of the parameter `key` (snake case, as in [`crate::EraOptions`]) for this
    /// front end.
    pub fn name(self, key: &str) -> String {
        match self {
            Naming::Flag => format!("--{}", key.replace('_', "-")),
            Naming::Keyword => match key {
                "lowpass_hz" => "lowpass".into(),
                "lowpass_order" => "lowpass order".into(),
                other => other.into(),
            },
        }
    }
}

/// `Err(EraError::Invalid)` with `message`.
pub fn invalid<T>(message: impl Into<String>) -> Result<T> {
    Err(EraError::Invalid(message.into()))
}

/// A positive, finite number: `{name} {value}: must be a positive {what}`.
///
/// # Errors
/// [`EraError::Invalid`] for zero, negative, NaN or infinite values.
pub fn check_positive(naming: Naming, key: &str, value: f64, what: &str) -> Result<()> {
    if !(value.is_finite() && value > 0.0) {
        return invalid(format!(
            "{} {value}: must be a positive {what}",
            naming.name(key)
        ));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_follow_the_front_end() {
        assert_eq!(Naming::Flag.name("hankel_factor"), "--hankel-factor");
        assert_eq!(Naming::Keyword.name("hankel_factor"), "hankel_factor");
        assert_eq!(Naming::Flag.name("lowpass_hz"), "--lowpass-hz");
        assert_eq!(Naming::Keyword.name("lowpass_hz"), "lowpass");
        let e = check_positive(Naming::Keyword, "df", -1.0, "line spacing in Hz").unwrap_err();
        assert_eq!(
            e.to_string(),
            "df -1: must be a positive line spacing in Hz"
        );
        assert!(e.is_input_error());
        assert!(check_positive(Naming::Flag, "df", f64::NAN, "x").is_err());
        assert!(check_positive(Naming::Flag, "df", 0.5, "x").is_ok());
    }
}
