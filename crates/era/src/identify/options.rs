//! The options of an identification: every parameter of the pipeline ([`EraOptions`],
//! docs/src/design.md §1 table) and of a scan across orders ([`ScanOptions`]).

use crate::error::Result;
use crate::modal::stabilization::{DiagramCriteria, OrderRange, SelectionCriteria};
use crate::pipeline::factor::SvdPath;
use crate::pipeline::realize::DirectTerm;

/// Model returned (thesis `cord`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum ModelDomain {
    /// The discrete model ERA gives (thesis `cord = 2`).
    #[default]
    Discrete,
    /// Its zero-order-hold inverse (thesis `cord = 1`).
    Continuous,
}

/// Every parameter of the pipeline (docs/src/design.md §1 table).
#[derive(Debug, Clone, PartialEq)]
#[non_exhaustive]
pub struct EraOptions {
    /// The model order: fixed (thesis `ns`), fixed and judged against a scan, or
    /// automatic.
    pub order: Order,
    /// How a scan across orders runs ([`Order::Scan`] and [`Order::Auto`]).
    pub scan: ScanOptions,
    /// Hankel factor (thesis `lh`).
    pub hankel_factor: usize,
    /// Integrations of the FRFs (thesis `ni`).
    pub integrations: usize,
    /// Zero-phase Butterworth `(order, cut-off Hz)` on the impulse responses (thesis
    /// `ford`, `Hzbreak`); `None` for no filter.
    pub lowpass: Option<(usize, f64)>,
    /// Leading lines set to zero (thesis `nz`).
    pub zero_lines: usize,
    /// Pad to `pad_to + 1` lines; 0 for none (thesis `ndpts`).
    pub pad_to: usize,
    /// Model returned (thesis `cord`).
    pub domain: ModelDomain,
    /// `D = 0` or `Y_0`.
    pub direct_term: DirectTerm,
    /// Dense, matrix-free or automatic SVD.
    pub svd: SvdPath,
    /// ERA, or ERA/DC on the correlations of the Hankel blocks.
    pub realizer: Realizer,
}

/// How the model is realized from the Markov sequence.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
#[non_exhaustive]
pub enum Realizer {
    /// ERA on the Hankel matrix (the thesis's).
    #[default]
    Era,
    /// ERA/DC on its shifted correlations ([`crate::pipeline::realize_dc`]).
    EraDc,
    /// The shift structure of the observability factor: `A` is the least-squares
    /// solution of `O↑ A = O↓`, with `O = U_n S_n^(½)` and `O↑`, `O↓` its rows
    /// without the last and the first block row (covariance-driven SSI, Peeters &
    /// De Roeck 1999). `H1` is not used for `A`; `B` and `C` are ERA's.
    Shift,
}

/// The model order of an identification.
///
/// ```
/// use era::identify::{identify, EraOptions, Order};
///
/// let frf = era::sim::truth_model_frf(None).unwrap();
/// let mut options = EraOptions::thesis_truth_model();
/// options.order = Order::Auto;
/// let found = identify(&frf, &options).unwrap();
/// let diagram = found.stabilization.as_ref().expect("a scan ran");
/// assert!(found.modal.modes.len() >= 1 && diagram.range.max >= 8);
/// ```
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[non_exhaustive]
pub enum Order {
    /// This many states (thesis `ns`).
    Fixed(usize),
    /// `states` states, with a scan across the orders of [`EraOptions::scan`] (its
    /// stabilization diagram): each mode of the model is judged physical only when a
    /// physical cluster of the scan matches it (within the cluster tolerances) and it
    /// passes the hard criteria.
    Scan {
        /// The model's order.
        states: usize,
    },
    /// The order the data supports: a scan across the orders of [`EraOptions::scan`],
    /// the physical modes chosen by clustering
    /// ([`crate::modal::stabilization::select`]), and a modal model of them (each pole
    /// taken from the highest order its cluster reached).
    Auto,
}

impl Order {
    /// The fixed number of states (of [`Order::Fixed`] and [`Order::Scan`]); `None` for
    /// [`Order::Auto`].
    pub fn states(&self) -> Option<usize> {
        match *self {
            Order::Fixed(n) | Order::Scan { states: n } => Some(n),
            Order::Auto => None,
        }
    }
}

/// The defaults a front end offers: the thesis's ERA (`EraOptions::new`) at a Hankel
/// factor of [`EraOptions::DEFAULT_HANKEL_FACTOR`], with the order chosen from the data
/// ([`Order::Auto`]); a front end sets the order the user gives.
impl Default for EraOptions {
    fn default() -> Self {
        EraOptions {
            order: Order::Auto,
            ..EraOptions::new(0, Self::DEFAULT_HANKEL_FACTOR)
        }
    }
}

impl EraOptions {
    /// The Hankel factor when a front end is given none (thesis `lh = 5`).
    pub const DEFAULT_HANKEL_FACTOR: usize = 5;
    /// The Butterworth order of a low-pass given by its cut-off alone.
    pub const DEFAULT_LOWPASS_ORDER: usize = 4;
}

impl EraOptions {
    /// Options with the thesis's defaults for everything but the Hankel factor, at a
    /// fixed order of `states` ([`Order::Fixed`]).
    pub fn new(states: usize, hankel_factor: usize) -> Self {
        EraOptions {
            order: Order::Fixed(states),
            scan: ScanOptions::default(),
            hankel_factor,
            integrations: 0,
            lowpass: None,
            zero_lines: 0,
            pad_to: 0,
            domain: ModelDomain::Discrete,
            direct_term: DirectTerm::Zero,
            svd: SvdPath::Auto,
            realizer: Realizer::Era,
        }
    }
    /// The thesis's DTA settings (Appendix J): `ns 80, lh 5, ni 1, nz 3, ndpts 1024`.
    pub fn thesis_dta() -> Self {
        EraOptions {
            integrations: 1,
            zero_lines: 3,
            pad_to: 1024,
            ..Self::new(80, 5)
        }
    }
    /// The thesis's truth-model settings (Appendix J.2.2): `ns 8, lh 4, ni 0, nz 0,
    /// ndpts 1024`.
    pub fn thesis_truth_model() -> Self {
        EraOptions {
            pad_to: 1024,
            ..Self::new(8, 4)
        }
    }
}

impl EraOptions {
    /// Checks what a front end asked for before anything is read or allocated: at least
    /// one state (an automatic order is checked as one state), a Hankel factor of at least 1, the states, Markov samples
    /// (`states × hankel_factor`) and padded lines within [`crate::params::limits`], and a
    /// Butterworth low-pass of order 1 to 20 at a positive cut-off. Messages name each
    /// parameter as `naming` does (the CLI's `--states`, Python's `states`).
    ///
    /// The stages check their own parameters again for library users; this is the
    /// check a front end makes first, so that a bad flag is refused with its own name.
    ///
    /// # Errors
    /// [`EraError::Invalid`](crate::EraError::Invalid) or [`EraError::Limit`](crate::EraError::Limit).
    pub fn check(&self, naming: crate::params::Naming) -> Result<()> {
        use crate::params::invalid;
        use crate::params::limits::{LINES, SAMPLES, STATES};
        let name = |key: &str| naming.name(key);
        let states = self.order.states().unwrap_or(1);
        if states == 0 {
            return invalid(format!(
                "{} 0: the model needs at least one state",
                name("states")
            ));
        }
        if self.hankel_factor == 0 {
            return invalid(format!("{} 0: must be at least 1", name("hankel_factor")));
        }
        STATES.check(name("states"), states as u64)?;
        SAMPLES.check_product(
            format!(
                "{} x {} (Markov samples)",
                name("states"),
                name("hankel_factor")
            ),
            &[states as u64, self.hankel_factor as u64],
        )?;
        if self.pad_to != 0 {
            LINES.check(
                format!("{} (lines, pad-to + 1)", name("pad_to")),
                (self.pad_to as u64).saturating_add(1),
            )?;
        }
        if let Some((order, hz)) = self.lowpass {
            if !(1..=20).contains(&order) {
                return invalid(format!(
                    "{} {order}: the Butterworth order must be 1 to 20",
                    name("lowpass_order")
                ));
            }
            if !(hz.is_finite() && hz > 0.0) {
                return invalid(format!(
                    "{} {hz}: must be a positive frequency",
                    name("lowpass_hz")
                ));
            }
        }
        Ok(())
    }
}

/// The default [`ScanOptions::svd_floor_fraction`].
pub(crate) const SCAN_FLOOR_FRACTION: f64 = 0.3;

/// Settings of a scan across orders.
#[derive(Debug, Clone, PartialEq)]
#[non_exhaustive]
pub struct ScanOptions {
    /// Orders to scan; `None` for the default range of the data (`default_orders`).
    pub orders: Option<OrderRange>,
    /// Residual tolerance of the truncated SVD on the matrix-free path, relative to `σ₁`
    /// (1e-6: the scan needs the leading subspace, not 12 digits of the noise floor; on
    /// noise-free DTA-like sets the poles still come out to 1e-11).
    pub svd_tolerance: f64,
    /// The truncated SVD also stops once its residuals are below this fraction of the
    /// smallest singular value it keeps. Used only by a default scan whose top order is
    /// at least 1.5 times the order the probe found, so that this value lies in the
    /// noise floor: the triplets are then exact for the data plus a perturbation this fraction
    /// of the noise's own, and more passes would move the poles by less than their noise
    /// spread without bringing them nearer the truth, though past the signal's order more
    /// noise poles then look stable in the diagram (the book's performance chapter
    /// measures all three; [`crate::linalg::tsvd::TruncatedSvdOptions::floor_fraction`]; 0:
    /// the tolerance alone; explicit orders and the output-only scan use the tolerance
    /// alone).
    pub svd_floor_fraction: f64,
    /// Diagram tolerances.
    pub diagram: DiagramCriteria,
    /// Automatic-choice thresholds.
    pub selection: SelectionCriteria,
    /// The band where the data carries information, Hz: modes outside it are not
    /// physical (default: every fitted line).
    pub band_hz: Option<(f64, f64)>,
    /// Judge each chosen mode against the noise of the data (step 5 of the automatic
    /// choice; default true).
    pub significance: bool,
}

impl Default for ScanOptions {
    fn default() -> Self {
        ScanOptions {
            orders: None,
            svd_tolerance: 1e-6,
            svd_floor_fraction: SCAN_FLOOR_FRACTION,
            diagram: DiagramCriteria::default(),
            selection: SelectionCriteria::default(),
            band_hz: None,
            significance: true,
        }
    }
}

crate::params::names::named!(display Realizer, "realizer", [
    Realizer::Era => "era",
    Realizer::EraDc => "era-dc",
    Realizer::Shift => "shift",
]);

crate::params::names::named!(display ModelDomain, "time domain", [
    ModelDomain::Discrete => "discrete",
    ModelDomain::Continuous => "continuous",
]);
