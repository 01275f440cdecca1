//! Stabilization diagram and automatic choice of the physical modes (docs/src/design.md §10).
//!
//! **The scan.** One [`Factorization`] of `H0` at the largest order gives a balanced
//! realization at every order of an [`OrderRange`] for the price of an `n × n` slice
//! each. Every complex pole pair of every order becomes a [`ScanPole`] with its frequency,
//! damping, shape and indicators ([`crate::modal::indicators`]).
//!
//! **The diagram.** Each pole is compared with the poles of the previous order in the
//! range ([`DiagramCriteria`]): the nearest in frequency, if within the frequency
//! tolerance, makes it *stable in frequency*; if its damping also agrees, *in frequency
//! and damping*; if the shapes' MAC also passes, *stable* in all three. Otherwise the
//! pole is *new*. Physical modes show as vertical columns of stable poles; computational
//! modes scatter.
//!
//! **The automatic choice** ([`select`]), in the spirit of the automated modal analysis
//! literature (Magalhães, Cunha & Caetano 2009; Reynders, Houbrechts & De Roeck 2012;
//! Neu et al. 2017), in three steps:
//!
//! 1. *Hard criteria* remove poles no structure has: damping ≤ 0 (unstable or
//!    undamped), damping above [`SelectionCriteria::damping_maximum`], a frequency outside
//!    the fitted band, or a consistent-mode indicator `CMI = EMAC·MPC` below
//!    [`SelectionCriteria::cmi_minimum`].
//! 2. *Clustering* across orders. Orders are visited from low to high; each pole joins
//!    the cluster it is closest to, with distance `d = |Δf|/f + (1 − MAC) + 0.1·|Δζ|/ζ`
//!    (damping keeps apart two modes closer than the noise moves them), if the
//!    frequencies agree within [`SelectionCriteria::frequency_tolerance`] and the shapes
//!    within [`SelectionCriteria::mac_minimum`]. A cluster takes at most one pole per
//!    order (assignment is greedy by increasing distance), so two close modes that are
//!    both present at the same orders stay two clusters. Unmatched poles start clusters.
//! 3. *Recurrence*. A cluster is physical when it has a pole in at least
//!    [`SelectionCriteria::recurrence`] of the orders of the upper half of the range
//!    (where every physical mode has appeared), and never fewer than
//!    [`SelectionCriteria::min_poles`], and when the median MPC and CMI of those poles are
//!    at least [`SelectionCriteria::mpc_minimum`] and [`SelectionCriteria::cmi_minimum`].
//!    The representative is, on exact data, the pole at the
//!    highest order (the least biased by truncation); on noisy data the counted member
//!    nearest the median frequency and damping, so that a noise pole at the top order
//!    does not stand for the mode.
//! 4. *Duplicates*. Noise can split one mode into two clusters; two physical clusters
//!    within the frequency tolerance whose shapes agree (MAC) are one mode, and only the
//!    larger is kept, unless the smaller is far more consistent (median CMI above
//!    `DUPLICATE_CMI_RATIO` times the larger's). A pole can also drift by more than the tolerance between two orders
//!    as the model settles; two clusters with the same shape within three tolerances that
//!    share at most a fifth of the smaller one's orders are that mode, and the one that
//!    reached the higher order is kept. Close modes of a structure have distinct shapes and stay apart.
//!
//! The representatives, with their shapes and participations, form the physical modal
//! model (see [`Order::Auto`](crate::identify::Order::Auto) for how it is assembled into `(A, B, C, D)`).
//!
//! The clustering and the diagram are plain loops over at most a few thousand poles; no
//! crate does this domain-specific matching, so it is written here.

use crate::error::{EraError, Result};
use crate::modal::indicators::mac;
use crate::modal::indicators::{emac_at, mpc};
use crate::pipeline::modes::{continuous_pole, ModalForm};
use crate::pipeline::realize::{DirectTerm, Factorization};
use num_complex::Complex64;
use rayon::prelude::*;

/// Orders `min, min + step, …, ≤ max` of a scan, or an explicit list.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct OrderRange {
    /// Lowest order.
    pub min: usize,
    /// Highest order.
    pub max: usize,
    /// Step between orders (0 for a list).
    pub step: usize,
    /// The orders of a list, ascending without repeats.
    pub list: Option<Vec<usize>>,
}

impl OrderRange {
    /// Parses `MIN..MAX`, `MIN..MAX:STEP` (step 2 by default: poles come in pairs) or a
    /// list `A,B,C`.
    ///
    /// # Errors
    /// [`EraError::InvalidParameter`] naming `orders` for anything else, a step of 0, a
    /// minimum of 0 or above the maximum.
    pub fn parse(text: &str) -> Result<Self> {
        let bad = |reason: &str| EraError::InvalidParameter {
            name: "orders",
            value: text.to_string(),
            reason: reason.to_string().into(),
        };
        if !text.contains("..") && text.contains(',') || text.trim().parse::<usize>().is_ok() {
            let mut list = Vec::new();
            for part in text.split(',') {
                let n = part
                    .trim()
                    .parse::<usize>()
                    .map_err(|_| bad("a list of orders is whole numbers separated by commas"))?;
                if n == 0 {
                    return Err(bad("an order of 0 states is not a model"));
                }
                crate::params::limits::STATES.check("orders", n as u64)?;
                list.push(n);
            }
            list.sort_unstable();
            list.dedup();
            if list.len() > MAX_SCAN_ORDERS {
                return Err(bad(&format!("at most {MAX_SCAN_ORDERS} orders per scan")));
            }
            return Ok(OrderRange {
                min: list[0],
                max: *list.last().expect("not empty"),
                step: 0,
                list: Some(list),
            });
        }
        let (range, step) = match text.split_once(':') {
            Some((r, s)) => (
                r,
                s.trim()
                    .parse::<usize>()
                    .map_err(|_| bad("the step after ':' must be a whole number"))?,
            ),
            None => (text, 2),
        };
        let (lo, hi) = range
            .split_once("..")
            .ok_or_else(|| bad("expected MIN..MAX or MIN..MAX:STEP, e.g. 20..160:4"))?;
        let min = lo
            .trim()
            .parse::<usize>()
            .map_err(|_| bad("MIN must be a whole number of states"))?;
        let max = hi
            .trim()
            .parse::<usize>()
            .map_err(|_| bad("MAX must be a whole number of states"))?;
        Self::new(min, max, step).map_err(|e| match e {
            EraError::InvalidParameter { reason, .. } => bad(&reason.to_string()),
            other => other,
        })
    }

    /// A checked range.
    ///
    /// # Errors
    /// As [`OrderRange::parse`].
    pub fn new(min: usize, max: usize, step: usize) -> Result<Self> {
        let bad = |reason: String| EraError::InvalidParameter {
            name: "orders",
            value: format!("{min}..{max}:{step}"),
            reason: reason.into(),
        };
        if step == 0 {
            return Err(bad("the step must be at least 1".into()));
        }
        if min == 0 {
            return Err(bad("an order of 0 states is not a model".into()));
        }
        if min > max {
            return Err(bad(format!("MIN {min} is above MAX {max}")));
        }
        crate::params::limits::STATES.check("orders", max as u64)?;
        if (max - min) / step + 1 > MAX_SCAN_ORDERS {
            return Err(bad(format!(
                "{} orders; at most {MAX_SCAN_ORDERS} per scan (raise the step)",
                (max - min) / step + 1
            )));
        }
        Ok(OrderRange {
            min,
            max,
            step,
            list: None,
        })
    }

    /// The orders, ascending; the last is `max` rounded down to the step.
    pub fn orders(&self) -> Vec<usize> {
        match &self.list {
            Some(list) => list.clone(),
            None => (self.min..=self.max).step_by(self.step).collect(),
        }
    }
}

/// The most orders one scan realizes.
pub(crate) const MAX_SCAN_ORDERS: usize = 500;

impl std::fmt::Display for OrderRange {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match &self.list {
            Some(list) => {
                let text: Vec<String> = list.iter().map(ToString::to_string).collect();
                write!(f, "{}", text.join(","))
            }
            None => write!(f, "{}..{}:{}", self.min, self.max, self.step),
        }
    }
}

/// How a pole compares with the previous order's poles.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord)]
pub enum PoleStatus {
    /// No pole of the previous order is near it in frequency.
    New,
    /// Stable in frequency only.
    Frequency,
    /// Stable in frequency and damping.
    FrequencyDamping,
    /// Stable in frequency, damping and shape.
    Stable,
}

impl PoleStatus {
    /// Short name used in files.
    pub fn name(self) -> &'static str {
        match self {
            PoleStatus::New => "new",
            PoleStatus::Frequency => "frequency",
            PoleStatus::FrequencyDamping => "frequency+damping",
            PoleStatus::Stable => "stable",
        }
    }
}

/// Tolerances of the diagram's order-to-order comparison.
#[derive(Debug, Clone, Copy, PartialEq)]
#[non_exhaustive]
pub struct DiagramCriteria {
    /// Relative frequency difference.
    pub frequency: f64,
    /// Damping difference relative to the pole's damping.
    pub damping: f64,
    /// Smallest MAC of the shapes.
    pub mac: f64,
}

impl Default for DiagramCriteria {
    /// 1 % in frequency, 5 % in damping, MAC 0.98 (the usual choices of commercial
    /// stabilization diagrams).
    fn default() -> Self {
        DiagramCriteria {
            frequency: 0.01,
            damping: 0.05,
            mac: 0.98,
        }
    }
}

/// One complex pole pair of one order of the scan.
#[derive(Debug, Clone, PartialEq)]
pub struct ScanPole {
    /// Model order it came from.
    pub order: usize,
    /// `|s|/2π`, Hz.
    pub frequency_hz: f64,
    /// `−Re s/|s|`.
    pub damping_ratio: f64,
    /// Continuous pole `s` (positive imaginary part), rad/s.
    pub continuous_pole: Complex64,
    /// Discrete eigenvalue `z`.
    pub eigenvalue: Complex64,
    /// Shape `Cφ`, largest entry 1.
    pub shape: Vec<Complex64>,
    /// Participation `ψB`.
    pub participation: Vec<Complex64>,
    /// Modal phase collinearity.
    pub mpc: f64,
    /// Extended modal amplitude coherence (output × input).
    pub emac: f64,
    /// Comparison with the previous order.
    pub status: PoleStatus,
}

impl ScanPole {
    /// `EMAC · MPC`.
    pub fn cmi(&self) -> f64 {
        self.emac * self.mpc
    }
}

/// Every pole of every order of a scan.
#[derive(Debug, Clone)]
pub struct Scan {
    /// Orders realized, ascending.
    pub orders: Vec<usize>,
    /// Poles, grouped by order in the order of `orders`, each group sorted by frequency.
    pub poles: Vec<ScanPole>,
    /// Orders asked for but not realized (above the numerical rank of `H0`).
    pub skipped: Vec<usize>,
}

impl Scan {
    /// The poles of one order.
    pub fn at(&self, order: usize) -> impl Iterator<Item = &ScanPole> {
        self.poles.iter().filter(move |p| p.order == order)
    }
}

/// Realizes every order of `orders` from `factorization` and builds the diagram.
///
/// `progress` is called after each order with (done, total).
///
/// # Errors
/// [`EraError::InvalidParameter`] when no order of the range can be realized (all above
/// the factorization's largest order or its rank); numerical failures of the eigen
/// solver.
pub(crate) fn scan(
    factorization: &Factorization,
    orders: &OrderRange,
    criteria: &DiagramCriteria,
    progress: &mut dyn FnMut(usize, usize),
) -> Result<Scan> {
    let wanted = orders.orders();
    if orders.max > factorization.max_states() {
        return Err(EraError::InvalidParameter {
            name: "orders",
            value: orders.to_string(),
            reason: format!(
                "the Hankel matrix was factored for at most {} states",
                factorization.max_states()
            )
            .into(),
        });
    }
    let mut done_orders = Vec::new();
    let mut skipped = Vec::new();
    let mut poles: Vec<ScanPole> = Vec::new();
    let mut previous: Vec<ScanPole> = Vec::new();
    // The orders are realized side by side, as many at a time as the pool has threads
    // (each order's work is independent of the others'); their statuses against the
    // order below, and the progress, follow in order.
    let token = crate::cancel::current();
    let at_once = rayon::current_num_threads().max(1);
    let mut done = 0;
    for chunk in wanted.chunks(at_once) {
        crate::cancel::check()?;
        let found: Vec<Result<Option<Vec<ScanPole>>>> = chunk
            .par_iter()
            .map(|&n| {
                crate::cancel::check_token(&token)?;
                if n > factorization.rank() {
                    return Ok(None);
                }
                order_poles(factorization, n).map(Some)
            })
            .collect();
        for (&n, here) in chunk.iter().zip(found) {
            match here? {
                None => skipped.push(n),
                Some(mut here) => {
                    for p in &mut here {
                        p.status = status_against(p, &previous, criteria);
                    }
                    done_orders.push(n);
                    poles.extend(here.iter().cloned());
                    previous = here;
                }
            }
            done += 1;
            progress(done, wanted.len());
        }
    }
    if done_orders.is_empty() {
        return Err(EraError::InvalidParameter {
            name: "orders",
            value: orders.to_string(),
            reason: format!(
                "every order is above the numerical rank {} of the Hankel matrix: the data supports no model in this range",
                factorization.rank()
            ).into(),
        });
    }
    Ok(Scan {
        orders: done_orders,
        poles,
        skipped,
    })
}

/// The poles of the realization at `n` states (status [`PoleStatus::New`]), by
/// frequency.
fn order_poles(factorization: &Factorization, n: usize) -> Result<Vec<ScanPole>> {
    let (model, tails) = factorization.realize_in_place(n, DirectTerm::Zero)?;
    let form = ModalForm::new(&model)?;
    // One pole of each conjugate pair, and its EMAC alone.
    let upper: Vec<usize> = (0..form.eigenvalues.len())
        .filter(|&i| form.eigenvalues[i].im > 0.0)
        .collect();
    let e = emac_at(&form, &tails, upper.iter().copied());
    let mut here: Vec<ScanPole> = upper
        .iter()
        .zip(&e)
        .map(|(&i, e)| {
            let z = &form.eigenvalues[i];
            let s = continuous_pole(*z, model.domain);
            ScanPole {
                order: n,
                frequency_hz: s.norm() / (2.0 * std::f64::consts::PI),
                damping_ratio: -s.re / s.norm(),
                continuous_pole: s,
                eigenvalue: *z,
                shape: form.shapes[i].clone(),
                participation: form.participations[i].clone(),
                mpc: mpc(&form.shapes[i]),
                emac: e.0 * e.1,
                status: PoleStatus::New,
            }
        })
        .collect();
    here.sort_by(|a, b| a.frequency_hz.total_cmp(&b.frequency_hz));
    Ok(here)
}

/// The diagram status of `pole` against the previous order's poles.
pub(crate) fn status_against(
    pole: &ScanPole,
    previous: &[ScanPole],
    criteria: &DiagramCriteria,
) -> PoleStatus {
    let nearest = previous.iter().min_by(|a, b| {
        (a.frequency_hz - pole.frequency_hz)
            .abs()
            .total_cmp(&(b.frequency_hz - pole.frequency_hz).abs())
    });
    let Some(o) = nearest else {
        return PoleStatus::New;
    };
    if (o.frequency_hz - pole.frequency_hz).abs() > criteria.frequency * pole.frequency_hz {
        return PoleStatus::New;
    }
    if (o.damping_ratio - pole.damping_ratio).abs() > criteria.damping * pole.damping_ratio.abs() {
        return PoleStatus::Frequency;
    }
    if mac(&o.shape, &pole.shape) < criteria.mac {
        return PoleStatus::FrequencyDamping;
    }
    PoleStatus::Stable
}

/// Thresholds of the automatic choice (module doc).
#[derive(Debug, Clone, Copy, PartialEq)]
#[non_exhaustive]
pub struct SelectionCriteria {
    /// Largest plausible damping ratio of a structural mode.
    pub damping_maximum: f64,
    /// Smallest median modal phase collinearity of a physical cluster's poles in the
    /// counted orders.
    pub mpc_minimum: f64,
    /// Smallest median consistent-mode indicator `EMAC·MPC` of a physical cluster's poles
    /// in the counted orders.
    pub cmi_minimum: f64,
    /// Relative frequency tolerance of a pole joining a cluster.
    pub frequency_tolerance: f64,
    /// Smallest MAC of a pole joining a cluster.
    pub mac_minimum: f64,
    /// Fraction of the orders of the upper half of the range a physical cluster has a
    /// pole in.
    pub recurrence: f64,
    /// Fewest poles of a physical cluster.
    pub min_poles: usize,
    /// Smallest share of the FRF of a physical mode (checked by the caller, who has the
    /// data; [`Order::Auto`](crate::identify::Order::Auto)).
    pub contribution_minimum: f64,
}

impl Default for SelectionCriteria {
    /// ζ ≤ 20 %, median MPC ≥ 0.5 and CMI ≥ 0.05, 1 % in frequency, MAC ≥ 0.9, in 50 % of the upper half of the
    /// orders and at least 3 poles, contribution ≥ 0.1 %.
    fn default() -> Self {
        SelectionCriteria {
            damping_maximum: 0.2,
            mpc_minimum: 0.5,
            cmi_minimum: 0.05,
            frequency_tolerance: 0.01,
            mac_minimum: 0.9,
            recurrence: 0.5,
            min_poles: 3,
            contribution_minimum: 1e-3,
        }
    }
}

/// Why a pole or cluster is not taken as physical.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Rejection {
    /// Damping ≤ 0.
    NegativeDamping(f64),
    /// Damping above the maximum.
    HighDamping(f64),
    /// Outside the fitted band `[lo, hi]` Hz.
    OutsideBand(f64, f64),
    /// CMI below the minimum.
    LowCmi(f64),
    /// MPC below the minimum.
    LowMpc(f64),
    /// In too few orders: (orders with a pole, orders counted).
    Unstable(usize, usize),
    /// Share of the FRF below the minimum.
    NoContribution(f64),
    /// The same mode as the cluster kept at this frequency, Hz.
    Duplicate(f64),
    /// Explains fewer noise variances per parameter (first) than tell a mode from noise
    /// (second), in a fit of the chosen modes to the data.
    Insignificant(f64, f64),
    /// The fit of the chosen modes to the data dropped its pole (step 5): it coalesced
    /// with another, or turned real.
    Dropped,
    /// A weak, inconsistent pole beside a stronger mode (the identification's step 6).
    Satellite {
        /// The stronger mode's frequency, Hz.
        host_hz: f64,
        /// Its share of the data relative to the stronger mode's.
        share: f64,
        /// Its median CMI.
        cmi: f64,
        /// The stronger mode's median CMI.
        host_cmi: f64,
    },
    /// Not found again in a second estimate of the same test (other frames): a pole
    /// that moves with the estimate's settings is the estimate's, not the structure's.
    Unconfirmed {
        /// The second estimate's frame, samples.
        frame: usize,
        /// Its nearest mode, Hz, when it has any.
        nearest_hz: Option<f64>,
    },
    /// After a refinement: within the half-power band of a stronger mode, with that
    /// mode's shape at the outputs and a small part of its share; the outputs cannot
    /// tell it from a distortion of that mode's peak.
    Unresolved {
        /// The stronger mode's frequency, Hz.
        host_hz: f64,
        /// Its share relative to the stronger mode's.
        share: f64,
        /// MAC of the two shapes at the outputs.
        mac: f64,
    },
}

impl std::fmt::Display for Rejection {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Rejection::NegativeDamping(z) => write!(
                f,
                "negative damping ({:.3} %): an unstable pole fits no passive structure",
                z * 100.0
            ),
            Rejection::HighDamping(z) => {
                write!(f, "damping {:.1} % is implausibly high", z * 100.0)
            }
            Rejection::OutsideBand(lo, hi) => {
                write!(f, "outside the fitted band {lo:.4}–{hi:.4} Hz")
            }
            Rejection::LowCmi(c) => write!(
                f,
                "CMI {c:.2}: not consistent over the record (a computational mode)"
            ),
            Rejection::LowMpc(m) => write!(
                f,
                "MPC {m:.2}: the shape's phases scatter (a computational mode)"
            ),
            Rejection::Unstable(k, of) => {
                write!(f, "not stable across orders (in {k} of {of} orders)")
            }
            Rejection::NoContribution(c) => {
                write!(f, "contributes {:.2e} of the FRF", c)
            }
            Rejection::Duplicate(hz) => {
                write!(f, "the same mode as the cluster kept at {hz:.4} Hz")
            }
            Rejection::Satellite {
                host_hz,
                share,
                cmi,
                host_cmi,
            } => write!(
                f,
                "a satellite of the mode at {host_hz:.4} Hz: {:.1} % of its share and CMI {cmi:.2} against its {host_cmi:.2} (an error of that mode's estimate, not a mode)",
                100.0 * share
            ),
            Rejection::Unconfirmed { frame, nearest_hz } => write!(
                f,
                "not found again in the FRFs estimated from frames of {frame} samples{}: a pole that moves with the frame length is the estimate's, not the structure's",
                nearest_hz.map_or(String::new(), |n| format!(" (their nearest mode is at {n:.4} Hz)"))
            ),
            Rejection::Unresolved { host_hz, share, mac } => write!(
                f,
                "inside the half-power band of the mode at {host_hz:.4} Hz, with its shape (MAC {mac:.3}) and {:.1} % of its share: these outputs cannot tell it from a distortion of that mode's peak (leakage, a window, noise), so it is not a mode of its own",
                100.0 * share
            ),
            Rejection::Dropped => write!(
                f,
                "the fit of the chosen modes to the data dropped its pole (it coalesced with another, or turned real)"
            ),
            Rejection::Insignificant(s, least) => write!(
                f,
                "it explains {s:.2} noise variances per parameter of the data, fewer than the {least:.2} that tell a mode from noise"
            ),
        }
    }
}

/// The hard criteria of step 1 for one pole: `None` when it passes.
pub(crate) fn hard_rejection(
    frequency_hz: f64,
    damping_ratio: f64,
    cmi: Option<f64>,
    band_hz: (f64, f64),
    criteria: &SelectionCriteria,
) -> Option<Rejection> {
    if damping_ratio.is_nan() || damping_ratio <= 0.0 {
        return Some(Rejection::NegativeDamping(damping_ratio));
    }
    if damping_ratio > criteria.damping_maximum {
        return Some(Rejection::HighDamping(damping_ratio));
    }
    if frequency_hz < band_hz.0 || frequency_hz > band_hz.1 {
        return Some(Rejection::OutsideBand(band_hz.0, band_hz.1));
    }
    if let Some(c) = cmi {
        if c < criteria.cmi_minimum {
            return Some(Rejection::LowCmi(c));
        }
    }
    None
}

/// A cluster of poles across orders.
#[derive(Debug, Clone, PartialEq)]
pub struct Cluster {
    /// Indices into [`Scan::poles`], one per order, ascending order.
    pub members: Vec<usize>,
    /// Index of the representative pole (the member at the highest counted order that
    /// agrees with the track's median frequency and damping).
    pub representative: usize,
    /// Orders of the upper half of the range in which the cluster has a pole.
    pub upper_count: usize,
    /// Whether the rules keep it.
    pub physical: bool,
    /// Why not, when not.
    pub rejection: Option<Rejection>,
    /// Median CMI of its poles in the counted orders.
    pub median_cmi: f64,
    /// Median MPC of its poles in the counted orders.
    pub median_mpc: f64,
    /// Median frequency of the members, Hz.
    pub median_frequency_hz: f64,
    /// Median damping of the members.
    pub median_damping_ratio: f64,
    /// Spread of the members' frequencies (max − min) relative to the median.
    pub frequency_spread: f64,
}

/// The automatic choice: clusters and the rule that chose them.
#[derive(Debug, Clone)]
pub struct Selection {
    /// Every cluster, sorted by representative frequency.
    pub clusters: Vec<Cluster>,
    /// Orders counted for recurrence (the upper half of the scanned orders).
    pub counted_orders: Vec<usize>,
    /// Poles removed by the hard criteria, with the reason (index into the scan's poles).
    pub rejected: Vec<(usize, Rejection)>,
    /// The criteria used.
    pub criteria: SelectionCriteria,
}

impl Selection {
    /// Clusters judged physical.
    pub fn physical(&self) -> impl Iterator<Item = &Cluster> {
        self.clusters.iter().filter(|c| c.physical)
    }

    /// The rule in words, with its figures.
    pub fn rule(&self) -> String {
        let c = &self.criteria;
        format!(
            "poles with 0 < damping <= {:.0} % inside the fitted band, clustered across orders (1 pole per order, within {:.1} % in frequency and MAC >= {:.2}); a cluster is physical with poles in >= {:.0} % of the {} upper orders ({}..{}), >= {} poles, median MPC >= {:.2} and median CMI >= {:.2}; of two such clusters with the same shape, the larger",
            c.damping_maximum * 100.0,
            c.frequency_tolerance * 100.0,
            c.mac_minimum,
            c.recurrence * 100.0,
            self.counted_orders.len(),
            self.counted_orders.first().copied().unwrap_or(0),
            self.counted_orders.last().copied().unwrap_or(0),
            // As applied: a short scan asks for no more poles than it counts orders.
            c.min_poles.min(self.counted_orders.len().max(1)),
            c.mpc_minimum,
            c.cmi_minimum
        )
    }
}

/// The pole that stands for a cluster. Of its members in the counted (upper) orders:
/// the one at the highest order that agrees with their median frequency to 1e-6 and
/// damping to 1e-4 (relative) when there is one, which on exact data is the highest
/// order, the least biased by truncation; otherwise, on noisy data, the member nearest
/// those medians. At the top order alone a noise pole that displaced the mode's pole for
/// one order could stand for the mode; the median is what most of the track agrees on.
/// Without three counted members, the member at the highest order.
/// `upper` are the members in the counted orders.
fn representative(scan: &Scan, members: &[usize], upper: &[usize]) -> usize {
    let top = *members.last().expect("clusters are never empty");
    if upper.len() < 3 {
        return top;
    }
    let median = |mut v: Vec<f64>| {
        v.sort_by(f64::total_cmp);
        v[v.len() / 2]
    };
    let f = median(upper.iter().map(|&i| scan.poles[i].frequency_hz).collect());
    let z = median(upper.iter().map(|&i| scan.poles[i].damping_ratio).collect());
    let df = |i: usize| (scan.poles[i].frequency_hz - f).abs() / f;
    let dz = |i: usize| (scan.poles[i].damping_ratio - z).abs() / z;
    let settled = upper
        .iter()
        .rev()
        .copied()
        .find(|&i| df(i) <= 1e-6 && dz(i) <= 1e-4);
    settled.unwrap_or_else(|| {
        // Frequency decides; damping, known to a few per cent at best, breaks ties.
        let distance = |i: usize| df(i) + 0.01 * dz(i);
        upper
            .iter()
            .copied()
            .min_by(|a, b| distance(*a).total_cmp(&distance(*b)))
            .unwrap_or(top)
    })
}

/// Of two clusters of one mode, the smaller is kept when its median CMI is more than
/// this many times the larger's (step 4).
const DUPLICATE_CMI_RATIO: f64 = 1.5;

/// Weight of the relative damping difference in the distance between a pole and a
/// track (step 2): a pair of modes 0.0077 and 0.0137 apart in damping is kept apart, the
/// few per cent by which noise moves one mode's damping barely count.
const DAMPING_WEIGHT: f64 = 0.1;

/// Clusters the poles of `scan` and judges each cluster (module doc, steps 1–3).
/// `band_hz` is the fitted band.
pub fn select(scan: &Scan, band_hz: (f64, f64), criteria: &SelectionCriteria) -> Selection {
    let (candidate, rejected) = screen_poles(scan, band_hz, criteria);
    let clusters = track_clusters(scan, &candidate, criteria);
    // Step 3: recurrence over the upper half of the orders.
    let counted_orders: Vec<usize> = scan.orders[scan.orders.len() / 2..].to_vec();
    let mut out: Vec<Cluster> = clusters
        .into_iter()
        .map(|members| judge_cluster(scan, members, &counted_orders, criteria))
        .collect();
    drop_duplicates(scan, &mut out, criteria);
    out.sort_by(|a, b| {
        scan.poles[a.representative]
            .frequency_hz
            .total_cmp(&scan.poles[b.representative].frequency_hz)
    });
    Selection {
        clusters: out,
        counted_orders,
        rejected,
        criteria: *criteria,
    }
}

/// Step 1: the poles that pass the hard limits (a flag per pole), and the others with
/// the reason.
fn screen_poles(
    scan: &Scan,
    band_hz: (f64, f64),
    criteria: &SelectionCriteria,
) -> (Vec<bool>, Vec<(usize, Rejection)>) {
    let mut rejected = Vec::new();
    let mut candidate = vec![false; scan.poles.len()];
    for (i, p) in scan.poles.iter().enumerate() {
        // CMI is judged per cluster (step 3): a real mode's poles at low orders, before
        // it has settled, often score low.
        match hard_rejection(p.frequency_hz, p.damping_ratio, None, band_hz, criteria) {
            Some(why) => rejected.push((i, why)),
            None => candidate[i] = true,
        }
    }
    (candidate, rejected)
}

/// Step 2: clusters (member indices, ascending order), visiting orders from low to
/// high; a pole is compared with each cluster's latest member.
fn track_clusters(
    scan: &Scan,
    candidate: &[bool],
    criteria: &SelectionCriteria,
) -> Vec<Vec<usize>> {
    let mut clusters: Vec<Vec<usize>> = Vec::new();
    for &order in &scan.orders {
        let here: Vec<usize> = (0..scan.poles.len())
            .filter(|&i| candidate[i] && scan.poles[i].order == order)
            .collect();
        let mut pairs: Vec<(f64, usize, usize)> = Vec::new();
        for &i in &here {
            for (c, members) in clusters.iter().enumerate() {
                if let Some(d) = track_distance(scan, i, members, criteria) {
                    pairs.push((d, i, c));
                }
            }
        }
        pairs.sort_by(|a, b| a.0.total_cmp(&b.0));
        let mut pole_taken = vec![false; scan.poles.len()];
        let mut cluster_taken = vec![false; clusters.len()];
        for (_, i, c) in pairs {
            if pole_taken[i] || cluster_taken[c] {
                continue;
            }
            pole_taken[i] = true;
            cluster_taken[c] = true;
            clusters[c].push(i);
        }
        for &i in &here {
            if !pole_taken[i] {
                clusters.push(vec![i]);
            }
        }
    }
    clusters
}

/// The distance between pole `i` and the track `members` (its latest member), or `None`
/// when they are too far apart in frequency or shape to be one mode.
fn track_distance(
    scan: &Scan,
    i: usize,
    members: &[usize],
    criteria: &SelectionCriteria,
) -> Option<f64> {
    let p = &scan.poles[i];
    let latest = &scan.poles[*members.last().expect("clusters are never empty")];
    let df = (p.frequency_hz - latest.frequency_hz).abs() / latest.frequency_hz;
    if df > criteria.frequency_tolerance {
        return None;
    }
    let m = mac(&p.shape, &latest.shape);
    if m < criteria.mac_minimum {
        return None;
    }
    // Damping tells apart two modes closer in frequency than the noise moves them (and
    // whose shapes mix): without it the greedy assignment swaps their poles between the
    // two tracks from order to order.
    let dz =
        (p.damping_ratio - latest.damping_ratio).abs() / p.damping_ratio.max(latest.damping_ratio);
    Some(df + (1.0 - m) + DAMPING_WEIGHT * dz)
}

/// The median of `v` after sorting it (the upper one of an even count), or 0 when empty.
fn sorted_median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v.get(v.len() / 2).copied().unwrap_or(0.0)
}

/// Step 3: one cluster's medians, representative and verdict; recurrence is counted
/// over `counted_orders` (the upper half of the scan).
fn judge_cluster(
    scan: &Scan,
    members: Vec<usize>,
    counted_orders: &[usize],
    criteria: &SelectionCriteria,
) -> Cluster {
    let lowest_counted = counted_orders.first().copied().unwrap_or(0);
    let counted = counted_orders.len();
    let needed = ((criteria.recurrence * counted as f64).ceil() as usize).max(1);
    // The members in the counted (upper) orders.
    let upper: Vec<usize> = members
        .iter()
        .copied()
        .filter(|&i| scan.poles[i].order >= lowest_counted)
        .collect();
    let upper_count = upper.len();
    let mut f: Vec<f64> = members
        .iter()
        .map(|&i| scan.poles[i].frequency_hz)
        .collect();
    let mut z: Vec<f64> = members
        .iter()
        .map(|&i| scan.poles[i].damping_ratio)
        .collect();
    f.sort_by(f64::total_cmp);
    z.sort_by(f64::total_cmp);
    let median_frequency_hz = f[f.len() / 2];
    let representative = representative(scan, &members, &upper);
    let median_cmi = sorted_median(upper.iter().map(|&i| scan.poles[i].cmi()).collect());
    let median_mpc = sorted_median(upper.iter().map(|&i| scan.poles[i].mpc).collect());
    // A short scan (exact low-order data) cannot ask for more poles than it has counted
    // orders.
    let min_poles = criteria.min_poles.min(counted.max(1));
    let rejection = if upper_count < needed || members.len() < min_poles {
        Some(Rejection::Unstable(upper_count, counted))
    } else if median_mpc < criteria.mpc_minimum {
        Some(Rejection::LowMpc(median_mpc))
    } else if median_cmi < criteria.cmi_minimum {
        Some(Rejection::LowCmi(median_cmi))
    } else {
        None
    };
    Cluster {
        physical: rejection.is_none(),
        rejection,
        median_cmi,
        median_mpc,
        representative,
        upper_count,
        median_frequency_hz,
        median_damping_ratio: z[z.len() / 2],
        frequency_spread: (f[f.len() - 1] - f[0]) / median_frequency_hz,
        members,
    }
}

/// Step 4: one mode split into two clusters by noise (same shape, within the frequency
/// tolerance) keeps only its larger cluster; one mode whose pole drifted by more than
/// the tolerance between orders (same shape, within three tolerances, the two clusters
/// sharing at most one order) keeps the cluster that reached the higher order. Close
/// modes have different shapes.
fn drop_duplicates(scan: &Scan, out: &mut [Cluster], criteria: &SelectionCriteria) {
    let mut by_size: Vec<usize> = (0..out.len()).collect();
    // Larger first; of two the same size, the more consistent (a satellite of a mode
    // can be as stable as the mode).
    by_size.sort_by(|&a, &b| {
        out[b]
            .members
            .len()
            .cmp(&out[a].members.len())
            .then(out[b].median_cmi.total_cmp(&out[a].median_cmi))
    });
    for (rank, &a) in by_size.iter().enumerate() {
        if !out[a].physical {
            continue;
        }
        for &b in &by_size[rank + 1..] {
            if !out[b].physical || !out[a].physical {
                continue;
            }
            let Some(keep_a) = duplicate_pair(scan, &out[a], &out[b], criteria) else {
                continue;
            };
            let (keep, drop) = if keep_a { (a, b) } else { (b, a) };
            let f = scan.poles[out[keep].representative].frequency_hz;
            out[drop].physical = false;
            out[drop].rejection = Some(Rejection::Duplicate(f));
        }
    }
}

/// Whether clusters `a` (the larger) and `b` are one mode (step 4): `None` when they are
/// not, else whether to keep `a` (rather than `b`).
fn duplicate_pair(
    scan: &Scan,
    a: &Cluster,
    b: &Cluster,
    criteria: &SelectionCriteria,
) -> Option<bool> {
    let (pa, pb) = (&scan.poles[a.representative], &scan.poles[b.representative]);
    if mac(&pa.shape, &pb.shape) < criteria.mac_minimum {
        return None;
    }
    let orders_of =
        |c: &Cluster| -> Vec<usize> { c.members.iter().map(|&i| scan.poles[i].order).collect() };
    let df = (pa.frequency_hz - pb.frequency_hz).abs() / pa.frequency_hz;
    let (oa, ob) = (orders_of(a), orders_of(b));
    let shared = oa.iter().filter(|o| ob.contains(o)).count();
    if df <= criteria.frequency_tolerance {
        // The larger, unless the smaller is far more consistent over the record: noise
        // can hold a pole on the mode's track at more orders.
        if b.median_cmi > DUPLICATE_CMI_RATIO * a.median_cmi {
            Some(false)
        } else {
            Some(true)
        }
    } else if df <= 3.0 * criteria.frequency_tolerance && shared * 5 <= oa.len().min(ob.len()) {
        Some(pb.order <= pa.order)
    } else {
        None
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn order_ranges_parse_and_refuse_nonsense() {
        let r = OrderRange::parse("20..30:4").unwrap();
        assert_eq!(r.orders(), vec![20, 24, 28]);
        assert_eq!(OrderRange::parse("4..8").unwrap().orders(), vec![4, 6, 8]);
        for bad in [
            "", "20..", "..30", "30..20", "0..10", "4..8:0", "a..b", "4..8:x",
        ] {
            let e = OrderRange::parse(bad).unwrap_err().to_string();
            assert!(e.contains("orders"), "{bad}: {e}");
        }
        assert!(OrderRange::parse("1..100000:1").is_err());
        let l = OrderRange::parse("70, 50,80,50").unwrap();
        assert_eq!(l.orders(), vec![50, 70, 80]);
        assert_eq!(l.to_string(), "50,70,80");
        for bad in ["50,0", "50,x", "50,,60"] {
            assert!(OrderRange::parse(bad).is_err(), "{bad}");
        }
    }

    fn pole(order: usize, frequency_hz: f64, damping_ratio: f64, shape: [f64; 2]) -> ScanPole {
        ScanPole {
            order,
            frequency_hz,
            damping_ratio,
            continuous_pole: Complex64::new(0.0, 0.0),
            eigenvalue: Complex64::new(0.0, 0.0),
            shape: shape.iter().map(|v| Complex64::new(*v, 0.0)).collect(),
            participation: vec![],
            mpc: 1.0,
            emac: 1.0,
            status: PoleStatus::New,
        }
    }

    /// Two modes closer in frequency than the noise moves them, with shapes mixed into
    /// one but different damping: each track keeps its damping from order to order.
    #[test]
    fn damping_keeps_two_close_modes_on_their_own_tracks() {
        let mut poles = Vec::new();
        for (k, order) in (10..=40).step_by(2).enumerate() {
            let (fa, fb) = if k % 2 == 0 {
                (5.0, 5.001)
            } else {
                (5.001, 5.0)
            };
            poles.push(pole(order, fa, 0.008, [1.0, 0.5]));
            poles.push(pole(order, fb, 0.014, [1.0, 0.5]));
        }
        let scan = Scan {
            orders: (10..=40).step_by(2).collect(),
            poles,
            skipped: vec![],
        };
        // (Step 4 may then call them one mode, their shapes being alike: the tracks are
        // what this checks.)
        let selection = select(&scan, (0.0, 100.0), &SelectionCriteria::default());
        assert_eq!(selection.clusters.len(), 2, "{:?}", selection.clusters);
        for c in &selection.clusters {
            let z0 = scan.poles[c.members[0]].damping_ratio;
            assert_eq!(c.members.len(), 16);
            assert!(c.members.iter().all(|&i| scan.poles[i].damping_ratio == z0));
        }
    }

    /// Exact data: the highest order stands for the track. Noisy data with a noise pole
    /// at the top order: a member near the median does.
    #[test]
    fn the_representative_is_the_top_order_when_settled_and_the_median_when_not() {
        let exact: Vec<ScanPole> = (0..8)
            .map(|k| pole(10 + 2 * k, 5.0 * (1.0 + 1e-9 * k as f64), 0.01, [1.0, 0.5]))
            .collect();
        let members: Vec<usize> = (0..8).collect();
        let scan = Scan {
            orders: (10..=24).step_by(2).collect(),
            poles: exact,
            skipped: vec![],
        };
        assert_eq!(representative(&scan, &members, &members[3..]), 7);
        let noisy: Vec<ScanPole> = [5.001, 4.999, 5.0005, 4.9995, 5.0, 5.0002, 5.0001, 5.02]
            .iter()
            .enumerate()
            .map(|(k, f)| pole(10 + 2 * k, *f, 0.01 + 0.001 * k as f64, [1.0, 0.5]))
            .collect();
        let scan = Scan {
            poles: noisy,
            ..scan
        };
        let r = representative(&scan, &members, &members[3..]);
        assert_ne!(r, 7);
        assert!((scan.poles[r].frequency_hz - 5.0).abs() < 3e-4, "{r}");
    }
}
