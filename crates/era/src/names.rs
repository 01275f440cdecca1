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
pub fn parse<T: Named>(text: &str) -> Result<T, UnknownName> {
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
        impl $crate::names::Named for $ty {
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
            type Err = $crate::names::UnknownName;
            fn from_str(text: &str) -> std::result::Result<Self, $crate::names::UnknownName> {
                $crate::names::parse(text)
            }
        }
    };
    (display $ty:ty, $what:literal, [$($table:tt)+]) => {
        $crate::names::named!(@impl $ty, $what, [$($table)+]);
        impl std::fmt::Display for $ty {
            fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
                f.write_str($crate::names::Named::name_of(self))
            }
        }
    };
    ($ty:ty, $what:literal, [$($table:tt)+]) => {
        $crate::names::named!(@impl $ty, $what, [$($table)+]);
    };
}
pub(crate) use named;

#[cfg(test)]
mod tests {
    use super::*;
    use crate::frf::estimate::{Detrend, Estimator, Window};
    use crate::frf::Quantity;
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
