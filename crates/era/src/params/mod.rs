//! Checks of the parameters a front end passes, shared by the command line and the
//! Python package so that both refuse the same values with the same words.
//!
//! A front end names a parameter its own way: the CLI as a flag (`--hankel-factor`),
//! Python as a keyword (`hankel_factor`). Each check takes a [`Naming`] and quotes the
//! parameter as the caller wrote it, with the value it gave:
//! `--states 0: the model needs at least one state` from the CLI,
//! `states 0: the model needs at least one state` from Python.
//!
//! Messages built deeper in the core (an [`EraError`] raised while realizing, a
//! warning) name a parameter as a [`crate::params::names::Param`] inside a
//! [`crate::params::names::Prose`], and a front end spells it with [`EraError::message`]
//! (`--hankel-factor`, or `hankel_factor`): no text is rewritten after the fact.
//!
//! A refused value is [`EraError::Invalid`] (an input error: exit code 2 in the CLI,
//! `ValueError` in Python), or [`EraError::Limit`] when a size is above one of
//! [`crate::params::limits`].

pub mod limits;
pub mod names;

use crate::error::{EraError, Param, Result};

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
    /// `param` as this front end spells it.
    pub(crate) fn spell(self, param: Param) -> String {
        self.name(param.field())
    }

    /// The name of the parameter `key` (snake case, as in [`crate::EraOptions`]) for this
    /// front end.
    pub(crate) fn name(self, key: &str) -> String {
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

impl EraError {
    /// The message with the parameters it names spelled as `naming`'s front end spells
    /// them (`--hankel-factor` for [`Naming::Flag`], `hankel_factor` for
    /// [`Naming::Keyword`]); see [`EraError::spelled`].
    pub fn message(&self, naming: Naming) -> String {
        self.spelled(&|p| naming.spell(p))
    }
}

impl crate::params::names::Prose {
    /// The text with the parameters it names spelled as `naming`'s front end spells
    /// them.
    pub fn message(&self, naming: Naming) -> String {
        self.spelled(&|p| naming.spell(p))
    }
}

impl crate::params::limits::LimitError {
    /// The message with the parameters its context names spelled as `naming`'s front
    /// end spells them.
    pub fn message(&self, naming: Naming) -> String {
        self.spelled(&|p| naming.spell(p))
    }
}

/// `Err(EraError::Invalid)` with `message`.
pub(crate) fn invalid<T>(message: impl Into<String>) -> Result<T> {
    Err(EraError::Invalid(message.into()))
}

/// A positive, finite number: `{name} {value}: must be a positive {what}`.
///
/// # Errors
/// [`EraError::Invalid`] for zero, negative, NaN or infinite values.
pub(crate) fn check_positive(naming: Naming, key: &str, value: f64, what: &str) -> Result<()> {
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

    /// A message naming parameters ([`crate::params::names::Prose`]) spells them per front
    /// end, and `Display` writes their field names.
    #[test]
    fn prose_spells_its_parameters_per_front_end() {
        use crate::params::names::{Param, Prose};
        let m = Prose::from("lower ")
            .param(Param::HankelFactor)
            .text(" or give ")
            .param(Param::States)
            .text(" N, or lower ")
            .param(Param::LowpassOrder);
        assert_eq!(
            m.message(Naming::Flag),
            "lower --hankel-factor or give --states N, or lower --lowpass-order"
        );
        assert_eq!(
            m.message(Naming::Keyword),
            "lower hankel_factor or give states N, or lower lowpass order"
        );
        assert_eq!(
            m.to_string(),
            "lower hankel_factor or give states N, or lower lowpass_order"
        );
        let e = EraError::InvalidParameter {
            name: "states",
            value: "auto".into(),
            reason: m,
        };
        assert_eq!(
            e.message(Naming::Flag),
            "invalid parameter --states = auto: lower --hankel-factor or give --states N, or lower --lowpass-order"
        );
    }

    /// A refused parameter is the CLI's flag for the CLI, the keyword for Python and the
    /// field name in `Display`.
    #[test]
    fn refused_parameters_are_named_as_the_front_end_does() {
        let e = EraError::InvalidParameter {
            name: "lowpass_hz",
            value: "-3".into(),
            reason: "must be positive".into(),
        };
        assert_eq!(
            e.message(Naming::Flag),
            "invalid parameter --lowpass-hz = -3: must be positive"
        );
        assert_eq!(
            e.to_string(),
            "invalid parameter lowpass_hz = -3: must be positive"
        );
        assert_eq!(
            e.message(Naming::Keyword),
            "invalid parameter lowpass = -3: must be positive"
        );
    }

    #[test]
    fn remedies_name_options_as_the_front_end_does() {
        let e = EraError::NotEnoughMarkovSamples {
            needed: 401,
            available: 320,
            states: 8,
            hankel_factor: 50,
        };
        let flag = e.message(Naming::Flag);
        assert!(
            flag.ends_with("lower --hankel-factor or --states, or pad with --pad-to"),
            "{flag}"
        );
        let shown = e.to_string();
        assert!(
            shown.ends_with("lower hankel_factor or states, or pad with pad_to"),
            "{shown}"
        );
        assert!(!shown.contains("--"), "{shown}");
        let e = EraError::NoRealLogarithm { re: -0.5, im: 0.0 };
        assert!(e
            .message(Naming::Flag)
            .ends_with("keep --time-domain discrete"));
        assert!(e.to_string().ends_with("keep time_domain discrete"));
        let e = EraError::UnreliableContinuous {
            round_trip_error: 3e-6,
        };
        assert!(e
            .message(Naming::Flag)
            .ends_with("keep --time-domain discrete"));
        assert!(e.to_string().contains("round trip error 3.00e-6"));
        // Variants without a remedy read the same either way.
        assert_eq!(
            EraError::AllZero.message(Naming::Flag),
            EraError::AllZero.to_string()
        );
    }
}
