//! One spelling per option value: every enum a front end offers as a word (`hann`,
//! `matrix-free`, `pair-noise`) is named here once, and read back by [`std::str::FromStr`].
//! The CLI offers [`Named::NAMES`] as its possible values and parses with `FromStr`;
//! Python does the same with its keyword strings. Parsing ignores case and takes `_` for
//! `-`; a few enums also take the other names their users write (`hanning`, `accel`).

/// An enum of named values.
pub trait Named: Sized + 'static {
    /// What the values are, for messages: `window`, `estimator`.
    const WHAT: &'static str;
    /// Every name, in the order a front end lists them.
    const NAMES: &'static [&'static str];
    /// The value of a name (already lower case, `_` read as `-`), aliases included.
    fn from_name(name: &str) -> Option<Self>;
    /// The value's name.
    fn name_of(&self) -> &'static str;
}

/// A word that names no value: `'hanning2': expected 'hann', 'rectangular' or
/// 'flat-top'`. A front end puts its own name of the parameter before it.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct UnknownName {
    /// What was being named (`window`).
    pub what: &'static str,
    /// The word given.
    pub given: String,
    /// The names expected.
    pub expected: &'static [&'static str],
}

impl std::fmt::Display for UnknownName {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "'{}': expected ", self.given)?;
        let n = self.expected.len();
        for (k, name) in self.expected.iter().enumerate() {
            let sep = match (k, n - k) {
                (0, _) => "",
                (_, 1) => " or ",
                _ => ", ",
            };
            write!(f, "{sep}'{name}'")?;
        }
        Ok(())
    }
}

impl std::error::Error for UnknownName {}

/// Parses `text` as a `T` (case ignored, `_` read as `-`).
///
/// # Errors
/// [`UnknownName`] when no value of `T` has that name.
pub(crate) fn parse<T: Named>(text: &str) -> Result<T, UnknownName> {
    let key = text.trim().to_ascii_lowercase().replace('_', "-");
    T::from_name(&key).ok_or_else(|| UnknownName {
        what: T::WHAT,
        given: text.to_string(),
        expected: T::NAMES,
    })
}

/// `Named`, `FromStr` and (unless the type has it) `Display` from one table of names:
/// `Type, "what", [Variant => "name" | "alias", ...]`.
macro_rules! named {
    (@impl $ty:ty, $what:literal, [$($var:path => $name:literal $(| $alias:literal)*),+ $(,)?]) => {
        impl $crate::params::names::Named for $ty {
            const WHAT: &'static str = $what;
            const NAMES: &'static [&'static str] = &[$($name),+];
            fn from_name(name: &str) -> Option<Self> {
                match name {
                    $($name $(| $alias)* => Some($var),)+
                    _ => None,
                }
            }
            #[allow(unreachable_patterns)]
            fn name_of(&self) -> &'static str {
                match self {
                    $($var => $name,)+
                    _ => "",
                }
            }
        }
        impl std::str::FromStr for $ty {
            type Err = $crate::params::names::UnknownName;
            fn from_str(text: &str) -> std::result::Result<Self, $crate::params::names::UnknownName> {
                $crate::params::names::parse(text)
            }
        }
    };
    (display $ty:ty, $what:literal, [$($table:tt)+]) => {
        $crate::params::names::named!(@impl $ty, $what, [$($table)+]);
        impl std::fmt::Display for $ty {
            fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
                f.write_str($crate::params::names::Named::name_of(self))
            }
        }
    };
    ($ty:ty, $what:literal, [$($table:tt)+]) => {
        $crate::params::names::named!(@impl $ty, $what, [$($table)+]);
    };
}
pub(crate) use named;

/// A parameter of the core's options, as the core names it: by its field
/// ([`Param::field`], snake case, as in [`crate::EraOptions`] and Python's keywords).
/// A front end spells it its own way (the CLI as a flag, Python as a keyword) through
/// [`crate::EraError::spelled`].
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[non_exhaustive]
pub enum Param {
    /// Model order.
    States,
    /// Hankel size factor.
    HankelFactor,
    /// Integrations of the FRFs.
    Integrations,
    /// Low-pass cut-off, Hz.
    LowpassHz,
    /// Low-pass Butterworth order.
    LowpassOrder,
    /// Zeroed leading lines.
    ZeroLines,
    /// Padding of the FRFs.
    PadTo,
    /// Time domain of the model.
    TimeDomain,
    /// Direct term of the model.
    DirectTerm,
    /// SVD method.
    Svd,
    /// Orders of a scan.
    Orders,
    /// Samples per Welch frame.
    Frame,
    /// Overlap of Welch frames.
    Overlap,
    /// Line spacing, Hz.
    Df,
    /// Frequency lines.
    Lines,
    /// Duration, s.
    Duration,
    /// Cycles.
    Cycles,
    /// Worker threads.
    Threads,
    /// Sample time of impulse responses, s.
    SampleTime,
    /// Sample rate of time histories, Hz.
    SampleRate,
    /// Highest line kept, Hz.
    MaxHz,
    /// Rate of the compensator's controller, Hz.
    CompensatorRate,
    /// Viscous damping ratio of an oscillator.
    ViscousDampingRatio,
    /// `accel_noise`.
    AccelNoise,
    /// `actuators`.
    Actuators,
    /// `averages`.
    Averages,
    /// `band`.
    Band,
    /// `burst_on`.
    BurstOn,
    /// `collocated`.
    Collocated,
    /// `compensation`.
    Compensation,
    /// `coulomb_force`.
    CoulombForce,
    /// `damping`.
    Damping,
    /// `dead_zone`.
    DeadZone,
    /// `estimator`.
    Estimator,
    /// `excitation`.
    Excitation,
    /// `fmax`.
    Fmax,
    /// `fraction`.
    Fraction,
    /// `hold`.
    Hold,
    /// `lvt_noise`.
    LvtNoise,
    /// `max_iterations`.
    MaxIterations,
    /// `model`.
    Model,
    /// `modes`.
    Modes,
    /// `natural_frequency_hz`.
    NaturalFrequencyHz,
    /// `noise`.
    Noise,
    /// `period`.
    Period,
    /// `pulse_width`.
    PulseWidth,
    /// `quantity`.
    Quantity,
    /// `reciprocal`.
    Reciprocal,
    /// `refine`.
    Refine,
    /// `stiffness`.
    Stiffness,
    /// `weighting`.
    Weighting,
    /// `x0`.
    X0,
    /// `analyzer_rate`.
    AnalyzerRate,
    /// `lvt_rate`.
    LvtRate,
    /// `motor_force_per_volt`.
    MotorForcePerVolt,
    /// Lags of the OKID observer.
    ObserverOrder,
    /// Markov blocks a time-history source returns.
    MarkovSamples,
}

impl Param {
    /// Every parameter, in declaration order.
    pub(crate) const ALL: &'static [Param] = &[
        Param::States,
        Param::HankelFactor,
        Param::Integrations,
        Param::LowpassHz,
        Param::LowpassOrder,
        Param::ZeroLines,
        Param::PadTo,
        Param::TimeDomain,
        Param::DirectTerm,
        Param::Svd,
        Param::Orders,
        Param::Frame,
        Param::Overlap,
        Param::Df,
        Param::Lines,
        Param::Duration,
        Param::Cycles,
        Param::Threads,
        Param::SampleTime,
        Param::SampleRate,
        Param::MaxHz,
        Param::CompensatorRate,
        Param::ViscousDampingRatio,
        Param::AccelNoise,
        Param::Actuators,
        Param::Averages,
        Param::Band,
        Param::BurstOn,
        Param::Collocated,
        Param::Compensation,
        Param::CoulombForce,
        Param::Damping,
        Param::DeadZone,
        Param::Estimator,
        Param::Excitation,
        Param::Fmax,
        Param::Fraction,
        Param::Hold,
        Param::LvtNoise,
        Param::MaxIterations,
        Param::Model,
        Param::Modes,
        Param::NaturalFrequencyHz,
        Param::Noise,
        Param::Period,
        Param::PulseWidth,
        Param::Quantity,
        Param::Reciprocal,
        Param::Refine,
        Param::Stiffness,
        Param::Weighting,
        Param::X0,
        Param::AnalyzerRate,
        Param::LvtRate,
        Param::MotorForcePerVolt,
        Param::ObserverOrder,
        Param::MarkovSamples,
    ];

    /// The field name: `hankel_factor`, `lowpass_hz`.
    pub const fn field(self) -> &'static str {
        match self {
            Param::States => "states",
            Param::HankelFactor => "hankel_factor",
            Param::Integrations => "integrations",
            Param::LowpassHz => "lowpass_hz",
            Param::LowpassOrder => "lowpass_order",
            Param::ZeroLines => "zero_lines",
            Param::PadTo => "pad_to",
            Param::TimeDomain => "time_domain",
            Param::DirectTerm => "direct_term",
            Param::Svd => "svd",
            Param::Orders => "orders",
            Param::Frame => "frame",
            Param::Overlap => "overlap",
            Param::Df => "df",
            Param::Lines => "lines",
            Param::Duration => "duration",
            Param::Cycles => "cycles",
            Param::Threads => "threads",
            Param::SampleTime => "sample_time",
            Param::SampleRate => "sample_rate",
            Param::MaxHz => "max_hz",
            Param::CompensatorRate => "compensator_rate",
            Param::ViscousDampingRatio => "viscous_damping_ratio",
            Param::AccelNoise => "accel_noise",
            Param::Actuators => "actuators",
            Param::Averages => "averages",
            Param::Band => "band",
            Param::BurstOn => "burst_on",
            Param::Collocated => "collocated",
            Param::Compensation => "compensation",
            Param::CoulombForce => "coulomb_force",
            Param::Damping => "damping",
            Param::DeadZone => "dead_zone",
            Param::Estimator => "estimator",
            Param::Excitation => "excitation",
            Param::Fmax => "fmax",
            Param::Fraction => "fraction",
            Param::Hold => "hold",
            Param::LvtNoise => "lvt_noise",
            Param::MaxIterations => "max_iterations",
            Param::Model => "model",
            Param::Modes => "modes",
            Param::NaturalFrequencyHz => "natural_frequency_hz",
            Param::Noise => "noise",
            Param::Period => "period",
            Param::PulseWidth => "pulse_width",
            Param::Quantity => "quantity",
            Param::Reciprocal => "reciprocal",
            Param::Refine => "refine",
            Param::Stiffness => "stiffness",
            Param::Weighting => "weighting",
            Param::X0 => "x0",
            Param::AnalyzerRate => "analyzer_rate",
            Param::LvtRate => "lvt_rate",
            Param::MotorForcePerVolt => "motor_force_per_volt",
            Param::ObserverOrder => "observer_order",
            Param::MarkovSamples => "markov_samples",
        }
    }

    /// The parameter whose field name is `field`.
    pub(crate) fn from_field(field: &str) -> Option<Param> {
        Param::ALL.iter().copied().find(|p| p.field() == field)
    }
}

impl std::fmt::Display for Param {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.field())
    }
}

/// A message whose words name parameters: plain text, and [`Param`]s that each front
/// end spells its own way ([`Prose::spelled`]: the CLI's `--lowpass-order`, Python's
/// `lowpass order`). `Display` writes the field names. A remedy is written as
/// `Prose::from("lower ").param(Param::HankelFactor)`, never as a name inside the text.
#[derive(Debug, Clone, PartialEq, Eq, Default)]
pub struct Prose(Vec<Piece>);

/// One piece of a [`Prose`].
#[derive(Debug, Clone, PartialEq, Eq)]
enum Piece {
    Text(String),
    Param(Param),
}

impl Prose {
    /// `self` followed by `text`.
    pub(crate) fn text(mut self, text: impl Into<String>) -> Self {
        self.0.push(Piece::Text(text.into()));
        self
    }

    /// `self` followed by `param`, spelled by the front end.
    pub(crate) fn param(mut self, param: Param) -> Self {
        self.0.push(Piece::Param(param));
        self
    }

    /// The text with each parameter spelled by `spell`.
    pub fn spelled(&self, spell: &dyn Fn(Param) -> String) -> String {
        self.0
            .iter()
            .map(|piece| match piece {
                Piece::Text(t) => t.clone(),
                Piece::Param(p) => spell(*p),
            })
            .collect()
    }
}

impl From<String> for Prose {
    fn from(text: String) -> Self {
        Prose(vec![Piece::Text(text)])
    }
}

impl From<&str> for Prose {
    fn from(text: &str) -> Self {
        Prose::from(text.to_string())
    }
}

impl std::fmt::Display for Prose {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.spelled(&|p| p.field().to_string()))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::data::frf::Quantity;
    use crate::estimate::{Detrend, Estimator, Window};
    use crate::identify::route::Preset;
    use crate::identify::ModelDomain;
    use crate::pipeline::realize::{DirectTerm, SvdPath};
    use crate::refine::{Residuals, Weighting};

    /// Every name reads back as the value that prints it, and the inherent `name()`
    /// spellings agree with the table.
    fn round_trip<T: Named + std::str::FromStr<Err = UnknownName> + PartialEq + std::fmt::Debug>() {
        for name in T::NAMES {
            let value: T = name.parse().unwrap();
            assert_eq!(value.name_of(), *name);
            let upper: T = name.to_ascii_uppercase().replace('-', "_").parse().unwrap();
            assert_eq!(upper, value);
        }
    }

    #[test]
    fn every_name_round_trips() {
        round_trip::<Quantity>();
        round_trip::<Window>();
        round_trip::<Estimator>();
        round_trip::<Detrend>();
        round_trip::<Preset>();
        round_trip::<ModelDomain>();
        round_trip::<DirectTerm>();
        round_trip::<SvdPath>();
        round_trip::<Residuals>();
        round_trip::<Weighting>();
        for q in [
            Quantity::Acceleration,
            Quantity::Velocity,
            Quantity::Displacement,
        ] {
            assert_eq!(q.name(), q.name_of());
        }
        for w in [Window::Hann, Window::Rectangular, Window::FlatTop] {
            assert_eq!(w.name(), w.to_string());
        }
        for s in [SvdPath::Auto, SvdPath::Dense, SvdPath::MatrixFree] {
            assert_eq!(s.name(), s.to_string());
        }
        for p in [Preset::Measured, Preset::Thesis] {
            assert_eq!(p.name(), p.to_string());
        }
        assert_eq!("hanning".parse::<Window>(), Ok(Window::Hann));
        assert_eq!("pair_noise".parse::<Weighting>(), Ok(Weighting::PairNoise));
    }

    #[test]
    fn an_unknown_word_lists_the_names() {
        let e = "hamming".parse::<Window>().unwrap_err();
        assert_eq!(
            e.to_string(),
            "'hamming': expected 'hann', 'rectangular' or 'flat-top'"
        );
        assert_eq!(e.what, "window");
        let e = "x".parse::<ModelDomain>().unwrap_err();
        assert_eq!(e.to_string(), "'x': expected 'discrete' or 'continuous'");
    }
}
