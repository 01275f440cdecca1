//! What an identification found: plain data, filled by the pipeline ([`mod@crate::identify`])
//! and checked by [`crate::identify::suspect`]. Nothing here runs a stage.

use crate::data::frf::FrfData;
use crate::data::statespace::StateSpace;
use crate::error::Result;
use crate::modal::indicators::ModeIndicators;
use crate::modal::stabilization::{OrderRange, Scan, Selection};
use crate::pipeline::fit::FitReport;
use crate::pipeline::modes::ModalParameters;
use crate::pipeline::realize::Realization;

/// A stage of the pipeline, reported to an observer as it starts
/// ([`crate::identify::identify_observed`]); front ends turn these into progress displays.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Stage {
    /// Integration, padding, zeroing.
    Preprocess,
    /// Inverse FFT (and filter).
    Markov,
    /// Hankel and SVD (the long one).
    HankelSvd,
    /// Realization products and continuous conversion.
    Realize,
    /// Eigendecomposition and modes.
    Modes,
    /// Model FRF and fit.
    Fit,
    /// Refinement of the poles and residues against the FRFs ([`crate::refine::identification::refine_identification`]).
    Refine,
}

impl Stage {
    /// The pipeline enters this stage: `observer` is told, and a cancelled call
    /// ([`crate::cancel`]) stops here.
    ///
    /// # Errors
    /// [`crate::EraError::Interrupted`] when the call's token was cancelled.
    pub(crate) fn enter(self, observer: &mut dyn FnMut(Stage)) -> crate::Result<()> {
        observer(self);
        crate::cancel::check()
    }

    /// Human name.
    pub fn name(self) -> &'static str {
        match self {
            Stage::Preprocess => "preprocessing",
            Stage::Markov => "Markov parameters",
            Stage::HankelSvd => "Hankel + SVD",
            Stage::Realize => "realization",
            Stage::Modes => "modes",
            Stage::Fit => "fit",
            Stage::Refine => "refinement",
        }
    }
}

/// Wall time of each stage, seconds.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct StageTimings {
    /// Integration, padding, zeroing.
    pub preprocess: f64,
    /// Inverse FFT (and filter) to Markov parameters.
    pub markov: f64,
    /// Hankel construction and SVD.
    pub hankel_svd: f64,
    /// The realization products of §1.9, and the continuous conversion when asked.
    pub realize: f64,
    /// Eigendecomposition and modal parameters.
    pub modes: f64,
    /// Model FRF and fit metrics.
    pub fit: f64,
    /// The refinement ([`crate::refine::identification::refine_identification`]), 0 when none ran.
    pub refine: f64,
    /// The order scan's realizations and eigenvalues (after its factorization, which is
    /// counted in `hankel_svd` and `realize`), 0 when no scan ran.
    pub scan: f64,
    /// The automatic order's choice: clustering, significance, the modal model of the
    /// chosen poles; the scan's matching of a fixed-order model. 0 when no scan ran.
    pub selection: f64,
}

/// Everything `identify` found.
#[derive(Debug, Clone)]
pub struct Identification {
    /// The identified model (discrete, or continuous on request).
    pub model: StateSpace,
    /// The realization diagnostics (singular values, Hankel size, warnings); its model
    /// is the discrete one.
    pub realization: Realization,
    /// Modes and real poles.
    pub modal: ModalParameters,
    /// Fit against the processed measurement.
    pub fit: FitReport,
    /// The measurement after the same integrations, on its own lines (the zeroed
    /// leading lines kept): the data a refinement fits.
    pub processed: FrfData,
    /// `processed` with its leading lines zeroed: what the fit compared and what every
    /// plot overlays (docs/src/design.md §1.10). Built here once, for every consumer.
    pub measured: FrfData,
    /// First line of `measured` in the fit (the zeroed lines, and the 0 Hz line of
    /// integrated data, are left out).
    pub first_line: usize,
    /// Sample time of the impulse responses, s.
    pub sample_time_s: f64,
    /// The model's FRF on the lines of `measured`, `[output][input][line]` as in
    /// [`FrfData::values`], evaluated from `model`'s (A, B, C, D): what the fit compared,
    /// kept for plots ([`Identification::model_frf`]).
    pub model_response: Vec<crate::Complex64>,
    /// Stage times.
    pub timings: StageTimings,
    /// Per mode of `modal.modes` (same order): indicators, and whether to trust it.
    pub quality: Vec<ModeQuality>,
    /// The fitted band, Hz: the frequencies of the first and last fitted lines.
    pub band_hz: (f64, f64),
    /// The scan across orders, when one was asked for (`--orders` or `--states auto`).
    pub stabilization: Option<Stabilization>,
    /// The refinement that gave `model`, when one ran ([`crate::refine::identification::refine_identification`]).
    pub refinement: Option<Refined>,
    /// Results to treat with care ([`crate::identify::suspect`]): a Hankel too short for the
    /// lowest mode, negative damping, poles outside the unit circle.
    pub suspects: Vec<SuspectResult>,
}

impl Identification {
    /// `model_response` as an [`FrfData`] on the lines of `measured`: the model's side of
    /// every overlay.
    ///
    /// # Errors
    /// None in practice: the shapes are the identification's own.
    pub fn model_frf(&self) -> Result<FrfData> {
        self.measured.with_values(self.model_response.clone())
    }
}

/// A refinement in the pipeline: the fit, and what it started from.
#[derive(Debug, Clone)]
pub struct Refined {
    /// The fit ([`crate::refine::refine`]).
    pub refinement: crate::refine::Refinement,
    /// Frequencies of the start poles (ERA's modes), Hz, in the refinement's start order,
    /// then of the poles it added for modes the start missed
    /// ([`crate::refine::Refinement::added`]): [`crate::refine::Refinement::dropped`]
    /// and [`crate::refine::RefinedMode::start`] index them.
    pub start_frequency_hz: Vec<f64>,
    /// Integrator states of the lower residual in the model (they are its real poles at
    /// `s = 0`).
    pub residual_states: usize,
    /// The domain of the fit, chosen for the data, and why.
    pub fit_domain: FitDomain,
    /// Seconds of the fit's rounds (`crate::refine::refine_rounds`): the first fit,
    /// then each look for missed modes with what follows it (a refit, or the run-on of a
    /// fit stopped for the look). The rest of
    /// [`StageTimings::refine`] is the choice of domain and the judgement of the modes.
    pub round_seconds: Vec<f64>,
}

impl Refined {
    /// The caller's start poles (ERA's modes), without the ones added for missed modes.
    pub fn start_modes(&self) -> usize {
        self.start_frequency_hz.len() - self.refinement.added.len()
    }

    /// `"the mode at 12.3456 Hz was dropped: why"` for every dropped start pole.
    pub fn dropped_lines(&self) -> Vec<String> {
        self.refinement
            .dropped
            .iter()
            .map(|(k, why)| {
                format!(
                    "the mode at {:.4} Hz was dropped: {why}",
                    self.start_frequency_hz.get(*k).copied().unwrap_or(f64::NAN)
                )
            })
            .collect()
    }

    /// Frequencies (Hz) of the poles the refinement added for modes the start missed
    /// (the end of [`Refined::start_frequency_hz`]).
    pub fn added_hz(&self) -> &[f64] {
        &self.start_frequency_hz[self.start_modes()..]
    }

    /// What the refinement did to its start, a line each: `"the residual showed …"` when
    /// poles were added for modes the start missed, then [`Refined::dropped_lines`].
    pub fn start_lines(&self) -> Vec<String> {
        let added = self.added_hz();
        let added_line = (!added.is_empty()).then(|| {
            let list: Vec<String> = added.iter().map(|f| format!("{f:.4}")).collect();
            format!(
                "the residual showed {} mode(s) the start missed: poles added at {} Hz",
                added.len(),
                list.join(", ")
            )
        });
        added_line.into_iter().chain(self.dropped_lines()).collect()
    }
}

/// Whether a mode is to be trusted, and why not.
#[derive(Debug, Clone, PartialEq)]
pub struct ModeQuality {
    /// Judged a mode of the structure.
    pub physical: bool,
    /// Why not, when not.
    pub reason: Option<String>,
    /// The indicators.
    pub indicators: ModeIndicators,
    /// Orders of the scan in which the mode's cluster has a pole, when a scan ran.
    pub stable_orders: Option<usize>,
    /// Standard deviation of the frequency, Hz, when a refinement estimated it.
    pub frequency_std_hz: Option<f64>,
    /// Standard deviation of the damping ratio, when a refinement estimated it.
    pub damping_ratio_std: Option<f64>,
}

/// A scan across orders, its diagram and (for `--states auto`) the automatic choice.
#[derive(Debug, Clone)]
pub struct Stabilization {
    /// The orders asked for.
    pub range: OrderRange,
    /// Every pole of every order.
    pub scan: Scan,
    /// The clusters and the rule.
    pub selection: Selection,
    /// Singular values of the factored `H0`: all (dense) or the largest order plus
    /// [`crate::pipeline::realize::EXTRA_SINGULAR_VALUES`] (matrix-free).
    pub singular_values: Vec<f64>,
    /// `H0` size of the factorization.
    pub hankel_size: (usize, usize),
    /// The CMIF: singular values of the measured FRF matrix at each line of the
    /// processed data, `[line][k]`, largest first.
    pub cmif: Vec<Vec<f64>>,
    /// Wall time of the scan (factorization, realizations, diagram), s.
    pub seconds: f64,
    /// Of which the factorization of `H0` (Hankel, SVD, `H1` product), s.
    pub factor_seconds: f64,
    /// Iterations of the truncated SVD (matrix-free path).
    pub svd_iterations: Option<usize>,
    /// How the model of `--states auto` was built, in words (`None` for a scan beside a
    /// fixed order).
    pub model_note: Option<String>,
}

/// Which model the refinement fits, and why (chosen by the refinement in the pipeline).
#[derive(Debug, Clone, PartialEq)]
pub struct FitDomain {
    /// `Some(Ts)` for the zero-order-hold image (a sampled system's FRFs), `None` for a
    /// continuous pole–residue model (FRFs of a physical structure).
    pub sample_time_s: Option<f64>,
    /// Relative error of each at ERA's poles with free residues: (continuous, ZOH).
    pub probe_fit: (f64, f64),
    /// The choice in words, with its figures.
    pub reason: String,
}

/// A result to treat with care.
#[derive(Debug, Clone, PartialEq)]
pub enum SuspectResult {
    /// The Hankel's window is shorter than the period of the lowest mode.
    ShortHankel {
        /// The window `(r + c)·Ts`, s.
        window_s: f64,
        /// The lowest mode's frequency, Hz.
        lowest_hz: f64,
    },
    /// Modes with negative damping, as (frequency in Hz, damping ratio).
    NegativeDamping(Vec<(f64, f64)>),
    /// Real poles outside the unit circle: their continuous `Re s > 0`, rad/s.
    UnstableRealPoles(Vec<f64>),
    /// The leading lines are zero (padded or zeroed), and this shifts ERA's modes.
    ZeroStart {
        /// The first line that is not zero, Hz.
        first_hz: f64,
        /// The mode shifted most: its frequency (Hz), then the relative shift of its
        /// damping and of its frequency.
        mode_hz: f64,
        /// Relative shift of that mode's damping, `ζ_zeroed/ζ − 1`.
        damping_shift: f64,
        /// Relative shift of its frequency.
        frequency_shift: f64,
        /// Whether the model reported was refined over the measured lines only.
        refined: bool,
    },
    /// A physical mode whose half-power band reaches past an edge of the band.
    BandEdge {
        /// The mode's frequency, Hz.
        mode_hz: f64,
        /// Its damping ratio.
        damping_ratio: f64,
        /// The edge, Hz.
        edge_hz: f64,
        /// Whether it is the low edge and the lowest physical mode.
        lowest: bool,
    },
}
