//! `model.json` and `fit.json` (docs/design.md §4).
//!
//! `model.json`: `outputs`, `inputs`, `states`, `time_domain` (`"discrete"` or
//! `"continuous"`), `sample_time_s` (null when continuous), `a`, `b`, `c`, `d` (row-major
//! nested arrays), `singular_values` (all of them), `modes` (one per complex pair,
//! positive imaginary part, by frequency: `frequency_hz`, `damping_ratio`,
//! `eigenvalue_re`, `eigenvalue_im`, plus `shape_re/_im` = `Cφ` and
//! `participation_re/_im` = `ψB`), `real_poles`, `parameters` (every flag), `hankel`
//! (size and path), `warnings`, and `timings_s` when timings were asked for.
//!
//! A refined model (`era identify --refine`, `era refine`) adds `refinement`
//! (`iterations`, `converged`, `cost_before`, `cost_after`, `fit_before`, `fit_after`, `added_hz`,
//! the residual terms, the dropped modes, `rank_one`) and, per mode, `frequency_std_hz` and
//! `damping_ratio_std`. `frf_lines` records the lines of the FRF the model was fitted
//! to, so that `era refine` can check a file against it.

use crate::atomic::write_atomic;
use crate::IoError;
use era::data::identification::{Identification, StageTimings};
use era::identify::EraOptions;
use era::pipeline::fit::FitReport;
use era::pipeline::modes::{ModalParameters, Mode};
use era::{Complex64, StateSpace, TimeDomain};
use faer::Mat;
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;
use std::path::Path;

/// One mode as stored.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ModeJson {
    /// Hz.
    pub frequency_hz: f64,
    /// Fraction.
    pub damping_ratio: f64,
    /// Real part of the eigenvalue of `A`.
    pub eigenvalue_re: f64,
    /// Imaginary part of the eigenvalue of `A` (positive).
    pub eigenvalue_im: f64,
    /// `Re(Cφ)`, largest entry scaled to 1.
    #[serde(default)]
    pub shape_re: Vec<f64>,
    /// `Im(Cφ)`.
    #[serde(default)]
    pub shape_im: Vec<f64>,
    /// `Re(ψB)`.
    #[serde(default)]
    pub participation_re: Vec<f64>,
    /// `Im(ψB)`.
    #[serde(default)]
    pub participation_im: Vec<f64>,
    /// Judged a mode of the structure (docs/design.md §10); absent in older files.
    #[serde(skip_serializing_if = "Option::is_none", default)]
    pub physical: Option<bool>,
    /// Why not, when `physical` is false.
    #[serde(skip_serializing_if = "Option::is_none", default)]
    pub reason: Option<String>,
    /// MPC, EMAC, CMI and the share of the FRF.
    #[serde(skip_serializing_if = "Option::is_none", default)]
    pub indicators: Option<IndicatorsJson>,
    /// Orders of the scan in which the mode's cluster has a pole.
    #[serde(skip_serializing_if = "Option::is_none", default)]
    pub stable_orders: Option<usize>,
    /// Standard deviation of the frequency, Hz (refined models).
    #[serde(skip_serializing_if = "Option::is_none", default)]
    pub frequency_std_hz: Option<f64>,
    /// Standard deviation of the damping ratio (refined models).
    #[serde(skip_serializing_if = "Option::is_none", default)]
    pub damping_ratio_std: Option<f64>,
    /// Output-only runs (`era oma`): the standard deviation of each shape entry over the
    /// record's blocks, null when the blocks did not give one.
    #[serde(
        skip_serializing_if = "Option::is_none",
        default,
        deserialize_with = "present"
    )]
    pub shape_std: Option<Option<Vec<f64>>>,
    /// Output-only runs: the blocks in which the mode was found again, null as above.
    #[serde(
        skip_serializing_if = "Option::is_none",
        default,
        deserialize_with = "present"
    )]
    pub blocks_found: Option<Option<usize>>,
}

/// A key that is present, null or not: `Some(None)` for null, where a missing key is
/// `None` (the field's default).
fn present<'de, T, D>(d: D) -> Result<Option<Option<T>>, D::Error>
where
    T: Deserialize<'de>,
    D: serde::Deserializer<'de>,
{
    Option::<T>::deserialize(d).map(Some)
}

/// A mode's quality indicators as stored.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct IndicatorsJson {
    /// Modal phase collinearity.
    pub mpc: f64,
    /// Extended modal amplitude coherence (null when not known).
    pub emac: Option<f64>,
    /// EMAC × MPC.
    pub cmi: Option<f64>,
    /// Share of the measured FRF.
    pub contribution: Option<f64>,
}

impl ModeJson {
    /// The shape `Cφ` as complex numbers (`shape_re + i shape_im`; the shorter list
    /// decides the length).
    pub fn shape(&self) -> Vec<Complex64> {
        self.shape_re
            .iter()
            .zip(&self.shape_im)
            .map(|(&re, &im)| Complex64::new(re, im))
            .collect()
    }

    /// From a library mode.
    pub fn from_mode(m: &Mode) -> Self {
        ModeJson {
            frequency_hz: m.frequency_hz,
            damping_ratio: m.damping_ratio,
            eigenvalue_re: m.eigenvalue.re,
            eigenvalue_im: m.eigenvalue.im,
            shape_re: m.shape.iter().map(|c| c.re).collect(),
            shape_im: m.shape.iter().map(|c| c.im).collect(),
            participation_re: m.participation.iter().map(|c| c.re).collect(),
            participation_im: m.participation.iter().map(|c| c.im).collect(),
            physical: None,
            reason: None,
            indicators: None,
            stable_orders: None,
            frequency_std_hz: None,
            damping_ratio_std: None,
            shape_std: None,
            blocks_found: None,
        }
    }

    /// From a library mode and its quality.
    pub fn from_mode_quality(m: &Mode, q: &era::data::identification::ModeQuality) -> Self {
        let i = &q.indicators;
        ModeJson {
            physical: Some(q.physical),
            reason: q.reason.clone(),
            indicators: Some(IndicatorsJson {
                mpc: i.mpc,
                emac: i.emac,
                cmi: i.cmi,
                contribution: i.contribution,
            }),
            stable_orders: q.stable_orders,
            frequency_std_hz: q.frequency_std_hz,
            damping_ratio_std: q.damping_ratio_std,
            ..Self::from_mode(m)
        }
    }
}

/// A real pole as stored.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct RealPoleJson {
    /// Eigenvalue of `A`.
    pub eigenvalue: f64,
    /// `|s|/2π`, Hz.
    pub frequency_hz: f64,
}

/// Size and path of the Hankel step.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct HankelJson {
    /// Rows of `H0`.
    pub rows: usize,
    /// Columns of `H0`.
    pub cols: usize,
    /// `"dense"` (thin SVD of the formed Hankel) or `"matrix-free"` (FFT products and a
    /// truncated SVD).
    pub path: String,
    /// Iterations of the truncated SVD (matrix-free path).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub svd_iterations: Option<usize>,
}

/// `model.json`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ModelJson {
    /// `q`.
    pub outputs: usize,
    /// `p`.
    pub inputs: usize,
    /// `n`.
    pub states: usize,
    /// `"discrete"` or `"continuous"`.
    pub time_domain: String,
    /// Sample time, s; null for a continuous model.
    pub sample_time_s: Option<f64>,
    /// n×n, row-major.
    pub a: Vec<Vec<f64>>,
    /// n×p.
    pub b: Vec<Vec<f64>>,
    /// q×n.
    pub c: Vec<Vec<f64>>,
    /// q×p.
    pub d: Vec<Vec<f64>>,
    /// All singular values of `H0`, largest first.
    pub singular_values: Vec<f64>,
    /// Modes by frequency.
    pub modes: Vec<ModeJson>,
    /// Real poles.
    pub real_poles: Vec<RealPoleJson>,
    /// Every parameter of the run, by flag name: typed when written, every key of the
    /// file (in [`ModelParameters::earlier`]) when read.
    pub parameters: ModelParameters,
    /// Hankel size and path.
    pub hankel: HankelJson,
    /// Warnings of the run.
    #[serde(default)]
    pub warnings: Vec<String>,
    /// Stage wall times, s, when asked for.
    #[serde(skip_serializing_if = "Option::is_none", default)]
    pub timings_s: Option<BTreeMap<String, f64>>,
    /// The stability check across model orders (`era identify --orders`), when run.
    #[serde(skip_serializing_if = "Option::is_none", default)]
    pub stability: Option<serde_json::Value>,
    /// The stabilization diagram's data and the automatic choice (`--orders`,
    /// `--states auto`), when run.
    #[serde(skip_serializing_if = "Option::is_none", default)]
    pub stabilization: Option<serde_json::Value>,
    /// How the refinement went (`--refine`, `era refine`), when one ran.
    #[serde(skip_serializing_if = "Option::is_none", default)]
    pub refinement: Option<RefinementJson>,
    /// The lines of the FRF the model was identified from (absent in older files).
    #[serde(skip_serializing_if = "Option::is_none", default)]
    pub frf_lines: Option<FrfLinesJson>,
    /// What an output-only run (`era oma`) adds: its method, channels, lags, blocks and
    /// records, at the top level of the file.
    #[serde(flatten, skip_serializing_if = "Option::is_none")]
    pub output_only: Option<OutputOnlyJson>,
}

/// The facts of an output-only run (`era oma`) that `model.json` holds beside the model.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct OutputOnlyJson {
    /// `next-era` or `ssi-cov`.
    pub method: String,
    /// The outputs' columns in the files, 1-based.
    pub outputs_columns: Vec<usize>,
    /// The references' columns in the files, 1-based.
    pub references: Vec<usize>,
    /// Correlation lags.
    pub lags: usize,
    /// Blocks the records were cut into for the spread.
    pub blocks: usize,
    /// Samples per record.
    pub samples: usize,
    /// Hz.
    pub sample_rate_hz: f64,
    /// The record files.
    pub records: Vec<std::path::PathBuf>,
    /// `unscaled`: with no measured input there is no modal mass.
    pub shapes: String,
}

/// The lines of an FRF: enough to tell whether another file has the same ones.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct FrfLinesJson {
    /// Number of lines.
    pub lines: usize,
    /// First line, Hz.
    pub first_hz: f64,
    /// Last line, Hz.
    pub last_hz: f64,
    /// The quantity of the data the model describes (after the integrations).
    pub quantity: String,
}

impl FrfLinesJson {
    /// Of an FRF set.
    pub fn of(frf: &era::FrfData) -> Self {
        let f = frf.frequency_hz();
        FrfLinesJson {
            lines: f.len(),
            first_hz: f.first().copied().unwrap_or(f64::NAN),
            last_hz: f.last().copied().unwrap_or(f64::NAN),
            quantity: frf.quantity().name().into(),
        }
    }

    /// `None` when `frf` has these lines (first and last within 1e-9 relative), or what
    /// differs.
    pub fn differs_from(&self, frf: &era::FrfData) -> Option<String> {
        let other = Self::of(frf);
        let close = |a: f64, b: f64| (a - b).abs() <= 1e-9 * a.abs().max(b.abs()).max(1e-300);
        if self.lines != other.lines {
            return Some(format!(
                "the model was fitted to {} lines, the file has {}",
                self.lines, other.lines
            ));
        }
        if !close(self.first_hz, other.first_hz) || !close(self.last_hz, other.last_hz) {
            return Some(format!(
                "the model was fitted to lines {} .. {} Hz, the file has {} .. {} Hz",
                self.first_hz, self.last_hz, other.first_hz, other.last_hz
            ));
        }
        None
    }
}

/// `refinement` of `model.json`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct RefinementJson {
    /// Accepted Levenberg–Marquardt steps.
    pub iterations: usize,
    /// Whether the cost stopped decreasing before the iterations ran out.
    pub converged: bool,
    /// Weighted cost at the start poles.
    pub cost_before: f64,
    /// Weighted cost at the end.
    pub cost_after: f64,
    /// `‖G − Ĝ‖/‖G‖` over the band at the start poles (best residues for them).
    pub fit_before: f64,
    /// `‖G − Ĝ‖/‖G‖` over the band at the end.
    pub fit_after: f64,
    /// Noise variance per real observation, from the residual.
    pub noise_variance: Option<f64>,
    /// `"z"` (zero-order-hold image at the sample time) or `"s"` (continuous).
    pub model: String,
    /// Lines fitted, 0-based `[first, end)`.
    pub band: [usize; 2],
    /// Start poles (ERA's modes).
    pub start_modes: usize,
    /// The lower residual as a q × p matrix (row-major), when fitted.
    pub lower_residual: Option<Vec<Vec<f64>>>,
    /// The upper residual, when fitted.
    pub upper_residual: Option<Vec<Vec<f64>>>,
    /// Integrator states of the lower residual in the model.
    pub residual_states: usize,
    /// Start modes dropped: `"the mode at f Hz was dropped: why"`.
    pub dropped: Vec<String>,
    /// Frequencies (Hz) of the poles added for modes the start missed, found in the
    /// residual of the fit.
    #[serde(default)]
    pub added_hz: Vec<f64>,
    /// Whether each residue is a shape times a participation (two states per mode);
    /// false for free residues (`--free-residues`, or weights that vary by line).
    #[serde(default)]
    pub rank_one: bool,
}

impl RefinementJson {
    /// From the pipeline's record.
    pub fn of(r: &era::data::identification::Refined) -> Self {
        let f = &r.refinement;
        RefinementJson {
            iterations: f.iterations,
            converged: f.converged,
            cost_before: f.cost_before,
            cost_after: f.cost_after,
            fit_before: f.fit_before,
            fit_after: f.fit_after,
            noise_variance: f.noise_variance.is_finite().then_some(f.noise_variance),
            model: if f.sample_time_s.is_some() { "z" } else { "s" }.into(),
            band: [f.band.0, f.band.1],
            start_modes: r.start_modes(),
            lower_residual: f.lower.as_ref().map(rows),
            upper_residual: f.upper.as_ref().map(rows),
            residual_states: r.residual_states,
            dropped: r.dropped_lines(),
            added_hz: r.added_hz().to_vec(),
            rank_one: f.rank_one,
        }
    }
}

/// Row-major nested vectors of a matrix.
pub fn rows(m: &Mat<f64>) -> Vec<Vec<f64>> {
    (0..m.nrows())
        .map(|i| (0..m.ncols()).map(|j| m[(i, j)]).collect())
        .collect()
}

fn matrix(name: &str, rows: &[Vec<f64>], nrows: usize, ncols: usize) -> Result<Mat<f64>, String> {
    if rows.len() != nrows || rows.iter().any(|r| r.len() != ncols) {
        return Err(format!("matrix {name} must be {nrows}x{ncols}"));
    }
    Ok(Mat::from_fn(nrows, ncols, |i, j| rows[i][j]))
}

/// Modes and real poles as stored.
pub fn modal_json(modal: &ModalParameters) -> (Vec<ModeJson>, Vec<RealPoleJson>) {
    (
        modal.modes.iter().map(ModeJson::from_mode).collect(),
        modal
            .real_poles
            .iter()
            .map(|r| RealPoleJson {
                eigenvalue: r.eigenvalue,
                frequency_hz: r.frequency_hz,
            })
            .collect(),
    )
}

/// Records the refinement's settings in `params` (model.json's `parameters`), as
/// `era identify --refine`, `era refine` and the Python package write them.
fn refine_parameters(
    o: &era::refine::RefineOptions,
    params: &mut BTreeMap<String, serde_json::Value>,
) {
    use serde_json::json;
    params.insert("refine".into(), json!(true));
    params.insert(
        "residuals".into(),
        json!(format!("{:?}", o.residuals).to_lowercase()),
    );
    params.insert("reciprocal".into(), json!(o.reciprocal));
    params.insert("rank_one".into(), json!(o.rank_one));
    params.insert("added_modes".into(), json!(o.add_missed));
    params.insert(
        "weighting".into(),
        json!(match o.weighting {
            era::refine::Weighting::Uniform => "uniform",
            era::refine::Weighting::PairNoise => "pair-noise",
            era::refine::Weighting::Coherence(_) => "coherence",
            era::refine::Weighting::InverseVariance(_) => "inverse-variance",
        }),
    );
    params.insert("max_iterations".into(), json!(o.max_iterations));
}

/// Every parameter by its JSON name (docs/design.md §1 table): the `parameters`
/// of `model.json`, written alike by the CLI and the Python package.
fn parameters(o: &EraOptions) -> BTreeMap<String, serde_json::Value> {
    use serde_json::json;
    let mut m = BTreeMap::new();
    m.insert("states".into(), json!(o.order.states().unwrap_or(0)));
    m.insert("hankel_factor".into(), json!(o.hankel_factor));
    m.insert("integrations".into(), json!(o.integrations));
    m.insert("lowpass_order".into(), json!(o.lowpass.map(|l| l.0)));
    m.insert("lowpass_hz".into(), json!(o.lowpass.map(|l| l.1)));
    m.insert("zero_lines".into(), json!(o.zero_lines));
    m.insert("pad_to".into(), json!(o.pad_to));
    m.insert(
        "time_domain".into(),
        json!(match o.domain {
            era::ModelDomain::Discrete => "discrete",
            era::ModelDomain::Continuous => "continuous",
        }),
    );
    m.insert("svd".into(), json!(o.svd.name()));
    m.insert(
        "direct_term".into(),
        json!(match o.direct_term {
            era::pipeline::realize::DirectTerm::Zero => "zero",
            era::pipeline::realize::DirectTerm::FirstMarkov => "markov0",
        }),
    );
    if o.realizer != era::identify::Realizer::Era {
        m.insert("realizer".into(), json!(o.realizer.to_string()));
    }
    m
}

/// model.json's `parameters`, typed: what a run sets, written as one flat map (ERA's
/// options, then the refinement's; the names are the flags'). Both front ends
/// fill one; a model.json read back holds its map in [`ModelParameters::earlier`].
#[derive(Debug, Clone, Default)]
#[non_exhaustive]
pub struct ModelParameters {
    /// The parameters of the model a refinement started from, as its model.json gives
    /// them (`era refine`); the settings below are written over them.
    pub earlier: BTreeMap<String, serde_json::Value>,
    /// ERA's options as run.
    pub era: Option<EraOptions>,
    /// The order was chosen from a stabilization diagram: `states` is `"auto"`.
    pub automatic_order: bool,
    /// The orders scanned, `MIN..MAX:STEP` or a list.
    pub orders: Option<String>,
    /// The route's preset.
    pub preset: Option<String>,
    /// The refinement's settings, when the model is refined.
    pub refinement: Option<era::refine::RefineOptions>,
    /// The model.json a refinement started from (`era refine`).
    pub refined_from: Option<std::path::PathBuf>,
    /// The states of the model written, when they are not ERA's `states`.
    pub model_states: Option<usize>,
    /// Where the Markov parameters of time histories came from (`--markov`), when
    /// recorded.
    pub markov: Option<era::sources::MarkovSource>,
    /// The Welch frame the FRFs of time histories were estimated with, when recorded.
    pub frame: Option<usize>,
    /// OKID's observer, when it gave the Markov parameters.
    pub okid: Option<OkidJson>,
}

/// Written as the flat map of [`ModelParameters::to_map`].
impl Serialize for ModelParameters {
    fn serialize<S: serde::Serializer>(&self, serializer: S) -> Result<S::Ok, S::Error> {
        self.to_map().serialize(serializer)
    }
}

/// Read as the map it is: every key in [`ModelParameters::earlier`].
impl<'de> Deserialize<'de> for ModelParameters {
    fn deserialize<D: serde::Deserializer<'de>>(deserializer: D) -> Result<Self, D::Error> {
        Ok(ModelParameters::refining(BTreeMap::deserialize(
            deserializer,
        )?))
    }
}

/// Equal when they write the same map.
impl PartialEq for ModelParameters {
    fn eq(&self, other: &Self) -> bool {
        self.to_map() == other.to_map()
    }
}

impl ModelParameters {
    /// The parameters of a run of ERA with `options`.
    pub fn new(options: &EraOptions) -> Self {
        ModelParameters {
            era: Some(options.clone()),
            ..ModelParameters::default()
        }
    }

    /// The parameters of a refinement of a model whose model.json gave `earlier`.
    pub fn refining(earlier: BTreeMap<String, serde_json::Value>) -> Self {
        ModelParameters {
            earlier,
            ..ModelParameters::default()
        }
    }

    /// The flat map model.json stores.
    pub fn to_map(&self) -> BTreeMap<String, serde_json::Value> {
        use serde_json::json;
        let mut m = self.earlier.clone();
        if let Some(o) = &self.era {
            m.extend(parameters(o));
        }
        if self.automatic_order {
            m.insert("states".into(), json!("auto"));
        }
        if let Some(orders) = &self.orders {
            m.insert("orders".into(), json!(orders));
        }
        if let Some(preset) = &self.preset {
            m.insert("preset".into(), json!(preset));
        }
        if let Some(r) = &self.refinement {
            refine_parameters(r, &mut m);
        }
        if let Some(path) = &self.refined_from {
            m.insert("refined_from".into(), json!(path));
        }
        if let Some(n) = self.model_states {
            m.insert("model_states".into(), json!(n));
        }
        if let Some(source) = self.markov {
            m.insert("markov".into(), json!(source.to_string()));
        }
        if let Some(frame) = self.frame {
            m.insert("frame".into(), json!(frame));
        }
        if let Some(okid) = &self.okid {
            m.insert("okid".into(), json!(okid));
        }
        m
    }

    /// The value written under `key`.
    pub fn get(&self, key: &str) -> Option<serde_json::Value> {
        self.to_map().remove(key)
    }
}

/// Stage timings by name (`read` and `write` are added by the caller).
pub fn timings_map(t: &StageTimings) -> BTreeMap<String, f64> {
    [
        ("preprocess", t.preprocess),
        ("markov", t.markov),
        ("hankel_svd", t.hankel_svd),
        ("realize", t.realize),
        ("modes", t.modes),
        ("fit", t.fit),
        ("scan", t.scan),
        ("selection", t.selection),
    ]
    .into_iter()
    // The scan's stages only where a scan ran.
    .filter(|&(k, v)| v > 0.0 || !matches!(k, "scan" | "selection"))
    .map(|(k, v)| (k.to_string(), v))
    .collect()
}

impl ModelJson {
    /// From an identification and the parameters that produced it.
    pub fn from_identification(
        found: &Identification,
        parameters: ModelParameters,
        timings_s: Option<BTreeMap<String, f64>>,
    ) -> Self {
        let m = &found.model;
        let (mut modes, real_poles) = modal_json(&found.modal);
        if found.quality.len() == found.modal.modes.len() {
            modes = found
                .modal
                .modes
                .iter()
                .zip(&found.quality)
                .map(|(m, q)| ModeJson::from_mode_quality(m, q))
                .collect();
        }
        ModelJson {
            outputs: m.outputs(),
            inputs: m.inputs(),
            states: m.states(),
            time_domain: match m.domain {
                TimeDomain::Discrete { .. } => "discrete".into(),
                TimeDomain::Continuous => "continuous".into(),
            },
            sample_time_s: m.sample_time_s(),
            a: rows(&m.a),
            b: rows(&m.b),
            c: rows(&m.c),
            d: rows(&m.d),
            singular_values: found.realization.singular_values.clone(),
            modes,
            real_poles,
            parameters,
            hankel: HankelJson {
                rows: found.realization.hankel_size.0,
                cols: found.realization.hankel_size.1,
                path: found.realization.svd_path.name().into(),
                svd_iterations: found.realization.svd_iterations,
            },
            // model.json is the command line's file: its flags are named.
            warnings: found.warnings(era::params::Naming::Flag),
            timings_s,
            stability: None,
            stabilization: found.stabilization.as_ref().map(stabilization_json),
            refinement: found.refinement.as_ref().map(RefinementJson::of),
            frf_lines: Some(FrfLinesJson::of(&found.processed)),
            output_only: None,
        }
    }

    /// From an identification and the typed parameters of its run.
    pub fn from_run(found: &Identification, parameters: &ModelParameters) -> Self {
        Self::from_identification(found, parameters.clone(), None)
    }

    /// The state-space model stored.
    ///
    /// # Errors
    /// A message when shapes disagree or the time domain is unknown.
    pub fn state_space(&self) -> Result<StateSpace, String> {
        let (n, p, q) = (self.states, self.inputs, self.outputs);
        let domain = match (self.time_domain.as_str(), self.sample_time_s) {
            ("discrete", Some(ts)) if ts > 0.0 => TimeDomain::Discrete { sample_time_s: ts },
            ("discrete", _) => return Err("a discrete model needs a positive sample_time_s".into()),
            ("continuous", _) => TimeDomain::Continuous,
            (other, _) => return Err(format!("unknown time_domain '{other}'")),
        };
        Ok(StateSpace::new(
            matrix("a", &self.a, n, n)?,
            matrix("b", &self.b, n, p)?,
            matrix("c", &self.c, q, n)?,
            matrix("d", &self.d, q, p)?,
            domain,
        ))
    }

    /// Reads `model.json`.
    ///
    /// # Errors
    /// [`IoError`] naming the file and the JSON line for unreadable or malformed files.
    pub fn read(path: &Path) -> Result<Self, IoError> {
        let bytes = crate::input::read_input(path)?;
        Self::parse(crate::input::utf8(&bytes, path)?, path)
    }

    /// Parses the text of a `model.json` and checks its shapes; `path` names the file in
    /// messages.
    ///
    /// # Errors
    /// [`IoError`] naming the file and the JSON line for malformed text.
    pub fn parse(text: &str, path: &Path) -> Result<Self, IoError> {
        let text = text.strip_prefix('\u{feff}').unwrap_or(text);
        let model: ModelJson = serde_json::from_str(text)
            .map_err(|e| IoError::format(path, format!("line {}: ", e.line()), e.to_string()))?;
        model
            .state_space()
            .map_err(|e| IoError::format(path, "", e))?;
        Ok(model)
    }

    /// Writes `model.json` atomically.
    ///
    /// # Errors
    /// [`IoError::Io`] naming the file.
    pub fn write(&self, path: &Path) -> Result<(), IoError> {
        write_json(path, self)
    }
}

/// One pair in `fit.json` (1-based indices).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct PairFitJson {
    /// 1-based output.
    pub output: usize,
    /// 1-based input.
    pub input: usize,
    /// Collocated pair.
    pub collocated: bool,
    /// `‖G_meas − G_model‖₂ / ‖G_meas‖₂`.
    pub relative_error: Option<f64>,
    /// RMS log-magnitude error, dB.
    pub rms_log_magnitude_db: Option<f64>,
}

/// `fit.json`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct FitJson {
    /// First line of the band (0-based).
    pub first_line: usize,
    /// Lines compared.
    pub lines: usize,
    /// Per pair.
    pub pairs: Vec<PairFitJson>,
    /// Mean over collocated pairs.
    pub collocated_mean_relative_error: Option<f64>,
    /// Mean over non-collocated pairs.
    pub noncollocated_mean_relative_error: Option<f64>,
    /// Mean RMS log-magnitude error over collocated pairs, dB.
    pub collocated_mean_db: Option<f64>,
    /// Mean RMS log-magnitude error over non-collocated pairs, dB.
    pub noncollocated_mean_db: Option<f64>,
}

fn finite(v: f64) -> Option<f64> {
    v.is_finite().then_some(v)
}

impl FitJson {
    /// From the library's report.
    pub fn from_report(r: &FitReport) -> Self {
        FitJson {
            first_line: r.first_line,
            lines: r.lines,
            pairs: r
                .pairs
                .iter()
                .map(|p| PairFitJson {
                    output: p.output + 1,
                    input: p.input + 1,
                    collocated: p.collocated,
                    relative_error: finite(p.relative_error),
                    rms_log_magnitude_db: finite(p.rms_log_magnitude_db),
                })
                .collect(),
            collocated_mean_relative_error: r.collocated_mean_relative_error,
            noncollocated_mean_relative_error: r.noncollocated_mean_relative_error,
            collocated_mean_db: r.collocated_mean_db,
            noncollocated_mean_db: r.noncollocated_mean_db,
        }
    }

    /// Writes `fit.json` atomically.
    ///
    /// # Errors
    /// [`IoError::Io`] naming the file.
    pub fn write(&self, path: &Path) -> Result<(), IoError> {
        write_json(path, self)
    }
}

/// Pretty JSON, atomically.
///
/// # Errors
/// [`IoError::Io`] naming the file.
pub fn write_json<T: Serialize>(path: &Path, value: &T) -> Result<(), IoError> {
    let mut text = serde_json::to_string_pretty(value)
        .map_err(|e| IoError::format(path, "", format!("cannot serialise: {e}")))?;
    text.push('\n');
    write_atomic(path, text.as_bytes())
}

/// The scan as stored: the range, the rule, the clusters and every pole (the diagram's
/// data), the factored singular values and the CMIF.
pub fn stabilization_json(st: &era::data::identification::Stabilization) -> serde_json::Value {
    use serde_json::json;
    let poles: Vec<serde_json::Value> = st
        .scan
        .poles
        .iter()
        .map(|p| {
            json!({"order": p.order, "frequency_hz": p.frequency_hz, "damping_ratio": p.damping_ratio,
                "status": p.status.name(), "mpc": p.mpc, "emac": p.emac})
        })
        .collect();
    let clusters: Vec<serde_json::Value> = st
        .selection
        .clusters
        .iter()
        .filter(|c| c.members.len() >= 2)
        .map(|c| {
            let rep = &st.scan.poles[c.representative];
            json!({"frequency_hz": rep.frequency_hz, "damping_ratio": rep.damping_ratio,
                "representative_order": rep.order, "poles": c.members.len(), "upper_orders": c.upper_count,
                "median_frequency_hz": c.median_frequency_hz, "median_damping_ratio": c.median_damping_ratio,
                "frequency_spread": c.frequency_spread, "median_mpc": c.median_mpc, "median_cmi": c.median_cmi,
                "physical": c.physical, "reason": c.rejection.map(|r| r.to_string())})
        })
        .collect();
    json!({
        "orders": st.scan.orders,
        "range": st.range.to_string(),
        "skipped_orders": st.scan.skipped,
        "rule": st.selection.rule(),
        "model": st.model_note,
        "physical_modes": st.selection.physical().count(),
        "hankel": {"rows": st.hankel_size.0, "cols": st.hankel_size.1},
        "singular_values": st.singular_values,
        "seconds": st.seconds,
        "clusters": clusters,
        "poles": poles,
        "cmif": st.cmif,
    })
}

/// model.json's record of OKID's observer (`parameters.okid`): its order and whether
/// it was chosen, the Markov blocks, the regression's size and rank, the observer's
/// largest root and how the system's Markov parameters came from it, and the one-step
/// residual of each output relative to its RMS.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct OkidJson {
    /// Lags of the observer.
    pub observer_order: usize,
    /// Whether the order was chosen by the information criterion.
    pub observer_order_chosen: bool,
    /// Markov blocks returned.
    pub markov_samples: usize,
    /// Equations (samples) of the regression.
    pub equations: usize,
    /// Unknowns per output.
    pub regressors: usize,
    /// Numerical rank of the regressors.
    pub rank: usize,
    /// Largest modulus of the observer's roots.
    pub observer_radius: f64,
    /// `recursion` or `unit_circle`.
    pub route: &'static str,
    /// Points on the unit circle, on that route.
    pub unit_circle_points: Option<usize>,
    /// One-step residual of each output, relative to its RMS.
    pub residual: Vec<f64>,
}

/// [`OkidJson`] of an OKID run.
pub fn okid_json(o: &era::sources::okid::Okid) -> OkidJson {
    use era::sources::okid::MarkovRoute;
    let (route, points) = match o.route {
        MarkovRoute::Recursion => ("recursion", None),
        MarkovRoute::UnitCircle { points } => ("unit_circle", Some(points)),
        _ => ("other", None),
    };
    OkidJson {
        observer_order: o.observer_order,
        observer_order_chosen: !o.criterion.is_empty(),
        markov_samples: o.markov.samples(),
        equations: o.equations,
        regressors: o.regressors,
        rank: o.rank,
        observer_radius: o.observer_radius,
        route,
        unit_circle_points: points,
        residual: o.residual.clone(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use era::identify::{identify, EraOptions};
    use era::sim::truth_model_frf;

    #[test]
    fn model_json_round_trips_the_state_space() {
        let found = identify(
            &truth_model_frf(None).unwrap(),
            &EraOptions::thesis_truth_model(),
        )
        .unwrap();
        let mut params = BTreeMap::new();
        params.insert("states".to_string(), serde_json::json!(8));
        let json = ModelJson::from_identification(&found, ModelParameters::refining(params), None);
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("model.json");
        json.write(&path).unwrap();
        let back = ModelJson::read(&path).unwrap();
        assert_eq!(back, json);
        assert_eq!(back.state_space().unwrap(), found.model);
        assert_eq!(back.modes.len(), 4);
        assert_eq!(back.singular_values.len(), 45);
        let text = std::fs::read_to_string(&path).unwrap();
        assert!(!text.contains("timings_s"));
    }

    #[test]
    fn an_output_only_model_round_trips_its_facts_and_spreads() {
        let found = identify(
            &truth_model_frf(None).unwrap(),
            &EraOptions::thesis_truth_model(),
        )
        .unwrap();
        let mut json = ModelJson::from_identification(
            &found,
            ModelParameters::refining(BTreeMap::new()),
            None,
        );
        json.modes[0].shape_std = Some(Some(vec![0.01, 0.02]));
        json.modes[0].blocks_found = Some(Some(7));
        json.modes[1].shape_std = Some(None);
        json.modes[1].blocks_found = Some(None);
        json.output_only = Some(OutputOnlyJson {
            method: "ssi-cov".into(),
            outputs_columns: vec![2, 3],
            references: vec![3],
            lags: 64,
            blocks: 8,
            samples: 4096,
            sample_rate_hz: 256.0,
            records: vec!["a.csv".into()],
            shapes: "unscaled".into(),
        });
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("model.json");
        json.write(&path).unwrap();
        let text = std::fs::read_to_string(&path).unwrap();
        // The facts sit at the top level; a mode without a spread says null.
        let value: serde_json::Value = serde_json::from_str(&text).unwrap();
        assert_eq!(value["method"], "ssi-cov");
        assert_eq!(value["references"], serde_json::json!([3]));
        assert!(value["modes"][1]["shape_std"].is_null());
        assert!(value["modes"][1].get("shape_std").is_some());
        assert!(value["modes"][2].get("shape_std").is_none());
        assert_eq!(ModelJson::read(&path).unwrap(), json);
    }

    #[test]
    fn malformed_model_json_names_the_file() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("bad.json");
        std::fs::write(&path, "{\"outputs\": 1,\n \"inputs\": }").unwrap();
        let err = ModelJson::read(&path).unwrap_err().to_string();
        assert!(err.contains("bad.json") && err.contains("line 2"), "{err}");
    }
}
