//! Resource limits: every size that comes from a file or a flag is checked here before
//! anything is allocated.
//!
//! A hostile 1 kB file can declare a 10⁸ × 2 dataset, start its frequencies at 10⁷ Hz (and
//! so ask for 10 GB of zero padding), or a flag can ask for 10⁹ lines. Each such size is
//! compared with one of the [`Limit`]s below first, and exceeding one is an input error
//! that says what was asked, what is allowed, and how to raise it.
//!
//! Every limit can be raised (or lowered) for one run with an environment variable, named
//! in the table and in the error message:
//!
//! | limit | default | variable |
//! |---|---|---|
//! | [`LINES`]: frequency lines of an FRF (read, padded, simulated) | 4 194 304 | `ERA_MAX_LINES` |
//! | [`SAMPLES`]: samples of one time-history channel (read or simulated) | 100 000 000 | `ERA_MAX_SAMPLES` |
//! | [`CHANNELS`]: channels, outputs or inputs of one file or model | 4 096 | `ERA_MAX_CHANNELS` |
//! | [`STATES`]: model states (and modes × 2) | 20 000 | `ERA_MAX_STATES` |
//! | [`VALUES`]: complex values of one FRF set (outputs × inputs × lines) | 200 000 000 | `ERA_MAX_VALUES` |
//! | [`INPUT_BYTES`]: bytes read from a pipe, standard input or a device | 1 GiB | `ERA_MAX_INPUT_BYTES` |
//! | [`ITERATIONS`]: iterations or cycles of an iterative routine | 1 000 000 | `ERA_MAX_ITERATIONS` |
//! | [`STEPS`]: integrator steps of one simulation (friction simulate, all tune trials) | 200 000 000 | `ERA_MAX_STEPS` |
//! | [`DENSE`]: values a dense SVD holds at once (the Hankel, workspace, factors) | 268 435 456 (2 GiB) | `ERA_MAX_DENSE_VALUES` |
//!
//! The defaults let every real data set we know through (the thesis set is 8 × 8 × 801; a
//! 28 × 2 × 16 385 analyzer set is 0.9 M values) while keeping the memory any one request
//! can ask for to a few GB.

use thiserror::Error;

/// One resource limit: its default and the environment variable that overrides it.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Limit {
    /// What is counted, plural ("frequency lines").
    pub what: &'static str,
    /// The default maximum.
    pub default: u64,
    /// The environment variable that overrides the default.
    pub env: &'static str,
}

/// Frequency lines of one FRF set.
pub const LINES: Limit = Limit {
    what: "frequency lines",
    default: 1 << 22,
    env: "ERA_MAX_LINES",
};
/// Samples of one time-history channel.
pub const SAMPLES: Limit = Limit {
    what: "samples per channel",
    default: 100_000_000,
    env: "ERA_MAX_SAMPLES",
};
/// Channels, outputs or inputs.
pub const CHANNELS: Limit = Limit {
    what: "channels",
    default: 4096,
    env: "ERA_MAX_CHANNELS",
};
/// Model states.
pub const STATES: Limit = Limit {
    what: "states",
    default: 20_000,
    env: "ERA_MAX_STATES",
};
/// Complex values of one FRF set (outputs × inputs × lines).
pub const VALUES: Limit = Limit {
    what: "FRF values",
    default: 200_000_000,
    env: "ERA_MAX_VALUES",
};
/// Bytes read from a pipe, standard input or a device (a regular file is checked by its
/// real size instead).
pub const INPUT_BYTES: Limit = Limit {
    what: "bytes",
    default: 1 << 30,
    env: "ERA_MAX_INPUT_BYTES",
};
/// Iterations or cycles of an iterative routine.
pub const ITERATIONS: Limit = Limit {
    what: "iterations",
    default: 1_000_000,
    env: "ERA_MAX_ITERATIONS",
};

/// Integrator steps of one friction simulation (`era friction simulate`, or all the
/// bisection trials of `era friction tune` together): a bound on the run time, about
/// ten seconds at the default.
pub const STEPS: Limit = Limit {
    what: "integrator steps",
    default: 200_000_000,
    env: "ERA_MAX_STEPS",
};

/// Values (8 bytes each) a dense SVD holds at once: the Hankel matrix, its workspace and
/// factors. A 3-line FRF padded to 300 000 lines at 2000 states asked a dense SVD of a
/// 4999 × 4999 Hankel (2 GB); under a 4 GB address-space cap an allocation of it
/// aborted the process.
pub const DENSE: Limit = Limit {
    what: "matrix values",
    default: 1 << 28,
    env: "ERA_MAX_DENSE_VALUES",
};

/// A count computed in floating point (samples = rate × duration, steps = cycles ×
/// rate / f_n) as a `u64` for [`Limit::check`]: NaN and values beyond `u64::MAX`
/// saturate at `u64::MAX`, so they are refused rather than wrapped.
pub(crate) fn saturating_count(x: f64) -> u64 {
    if x.is_nan() || x >= u64::MAX as f64 {
        u64::MAX
    } else if x <= 0.0 {
        0
    } else {
        x.ceil() as u64
    }
}

/// A request above a [`Limit`].
#[derive(Debug, Clone, PartialEq, Eq, Error)]
#[error("{}", self.spelled(&|p| p.field().to_string()))]
pub struct LimitError {
    /// What asked: a flag, a file field ("--pad-to", "UFF record 3: number of lines"),
    /// or the core's words naming a parameter, which a front end spells
    /// ([`LimitError::spelled`]).
    pub context: crate::params::names::Prose,
    /// The amount asked for (saturated at `u64::MAX`).
    pub asked: u64,
    /// The limit in force.
    pub allowed: u64,
    /// What is counted.
    pub what: &'static str,
    /// The variable that raises it.
    pub env: &'static str,
}

impl LimitError {
    /// The message with the parameters its context names spelled by `spell` (a front
    /// end's flag or keyword); `Display` writes their field names.
    pub fn spelled(&self, spell: &dyn Fn(crate::params::names::Param) -> String) -> String {
        format!(
            "{}: {} {} asked for, the limit is {} (set {} to raise it)",
            self.context.spelled(spell),
            AskedCount(self.asked),
            self.what,
            self.allowed,
            self.env
        )
    }
}

impl Limit {
    /// The limit in force: the environment variable when it holds a positive integer
    /// (underscores allowed: `ERA_MAX_LINES=10_000_000`), the default otherwise.
    pub fn allowed(&self) -> u64 {
        std::env::var(self.env)
            .ok()
            .and_then(|v| v.trim().replace('_', "").parse::<u64>().ok())
            .filter(|&v| v > 0)
            .unwrap_or(self.default)
    }

    /// `Ok(asked)` when `asked` is within the limit, a [`LimitError`] naming `context`
    /// otherwise.
    ///
    /// # Errors
    /// [`LimitError`] when `asked` exceeds [`Limit::allowed`].
    pub fn check(
        &self,
        context: impl Into<crate::params::names::Prose>,
        asked: u64,
    ) -> Result<u64, LimitError> {
        let allowed = self.allowed();
        if asked > allowed {
            return Err(LimitError {
                context: context.into(),
                asked,
                allowed,
                what: self.what,
                env: self.env,
            });
        }
        Ok(asked)
    }

    /// [`Limit::check`] for a `usize`, or for a product that may overflow: pass the
    /// factors and the product is taken with saturation before the check.
    ///
    /// # Errors
    /// [`LimitError`] when the (saturated) product exceeds [`Limit::allowed`].
    pub fn check_product(
        &self,
        context: impl Into<crate::params::names::Prose>,
        factors: &[u64],
    ) -> Result<usize, LimitError> {
        let asked = factors.iter().fold(1u64, |acc, &f| acc.saturating_mul(f));
        let ok = self.check(context, asked)?;
        // Within the limit, and every limit fits in usize on 64-bit targets; saturate on
        // smaller ones.
        Ok(usize::try_from(ok).unwrap_or(usize::MAX))
    }
}

/// An amount asked for, in a message: a product that saturated at `u64::MAX` is shown
/// as "more than 1.8e19", never as a number that looks like a wrapped integer.
struct AskedCount(u64);

impl std::fmt::Display for AskedCount {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        if self.0 == u64::MAX {
            f.write_str("more than 1.8e19")
        } else {
            write!(f, "{}", self.0)
        }
    }
}

/// A count for a message: `a + b` or `a * b` without wrapping (saturated at
/// `usize::MAX`, printed as "more than 1.8e19" by [`Saturated`], never as a number that
/// looks like a wrapped integer).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Saturated(pub Option<usize>);

impl std::fmt::Display for Saturated {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self.0 {
            Some(v) => write!(f, "{v}"),
            None => f.write_str("more than 1.8e19"),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn within_and_above() {
        let l = Limit {
            what: "things",
            default: 10,
            env: "ERA_TEST_LIMIT_NEVER_SET",
        };
        assert_eq!(l.check("--x", 10).unwrap(), 10);
        let e = l.check("--x", 11).unwrap_err();
        let m = e.to_string();
        assert!(
            m.contains("--x") && m.contains("11") && m.contains("10"),
            "{m}"
        );
        assert!(m.contains("ERA_TEST_LIMIT_NEVER_SET"), "{m}");
    }

    #[test]
    fn float_counts_saturate() {
        assert_eq!(saturating_count(f64::NAN), u64::MAX);
        assert_eq!(saturating_count(f64::INFINITY), u64::MAX);
        assert_eq!(saturating_count(1e300), u64::MAX);
        assert_eq!(saturating_count(-5.0), 0);
        assert_eq!(saturating_count(2.5), 3);
    }

    #[test]
    fn products_saturate_instead_of_wrapping() {
        let e = VALUES
            .check_product("shape", &[u64::MAX, 3, 5])
            .unwrap_err();
        assert_eq!(e.asked, u64::MAX);
        let m = e.to_string();
        assert!(m.contains("more than 1.8e19 FRF values"), "{m}");
        assert!(!m.contains("18446744073709551615"), "{m}");
        assert_eq!(Saturated(None).to_string(), "more than 1.8e19");
        assert_eq!(Saturated(5usize.checked_add(2)).to_string(), "7");
    }
}
