//! `identify` and what it returns.
//!
//! `identify(frf, states, ...)` runs docs/design.md §1 (the thesis's `frffilt`): integrate
//! `ni` times, pad to `ndpts + 1` lines, zero `nz` leading lines, inverse-FFT to the
//! Markov blocks `Y_k = C A^(k−1) B`, build the Hankel `H0[r][c] = Y_(1+r+c)` of
//! `M = ns·lh` samples, `H0 = U S Vᵀ`, and realize
//! `A = S^(−½) Uᵀ H1 V S^(−½)`, `B = S^(½) Vᵀ E_p`, `C = E_qᵀ U S^(½)`; the modes come from
//! `s = ln(z)/Ts`: frequency `|s|/2π`, damping `−Re s/|s|`, shapes `Cφ`, participations
//! `ψB`. The parameters are the CLI's `era identify` flags under their Python names,
//! checked by [`era::EraOptions::check`] with the CLI's messages.

use crate::frf::PyFrfData;
use crate::{era_error, guarded, guarded_in, thread_count, value_error, vector, Int};
use era::data::identification::Identification;
use era::identify::{
    identify as run_identify, identify_supplied, EraOptions, ModelDomain, Order, ScanOptions,
};
use era::params::Naming;
use era::pipeline::realize::{DirectTerm, SvdPath};
use era::{Complex64, TimeDomain};
use era_io::model_json::{FitJson, ModelJson, ModelParameters};
use numpy::{PyArray1, PyArray2, PyArray3, PyArrayMethods};
use pyo3::exceptions::PyImportError;
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList};

/// One mode: a complex pole pair of the model, by its positive-frequency member.
///
/// `frequency_hz` (`|s|/2π`), `damping_ratio` (`−Re s/|s|`), `eigenvalue` (of `A`:
/// discrete `z` or continuous `s`), `continuous_pole` (`s`, rad/s), `shape` (`Cφ`,
/// largest entry 1, complex (q,)), `participation` (`ψB`, complex (p,)). `physical` and
/// `indicators` are `None` unless the identification computed them (automatic order
/// selection and refinement do).
#[pyclass(module = "era", name = "Mode", frozen, get_all)]
pub struct PyMode {
    /// Hz.
    frequency_hz: f64,
    /// Fraction of critical.
    damping_ratio: f64,
    /// Eigenvalue of `A`.
    eigenvalue: Complex64,
    /// `s`, rad/s.
    continuous_pole: Complex64,
    /// `Cφ`.
    shape: Py<PyArray1<Complex64>>,
    /// `ψB`.
    participation: Py<PyArray1<Complex64>>,
    /// Whether the mode is judged physical, when that was computed.
    physical: Option<bool>,
    /// Mode indicators by name, when computed.
    indicators: Option<Py<PyDict>>,
    /// Standard deviation of the frequency, Hz (refined models, `refine=True`).
    frequency_std_hz: Option<f64>,
    /// Standard deviation of the damping ratio (refined models).
    damping_ratio_std: Option<f64>,
}

#[pymethods]
impl PyMode {
    fn __repr__(&self) -> String {
        format!(
            "Mode(frequency_hz={}, damping_ratio={})",
            self.frequency_hz, self.damping_ratio
        )
    }
}

/// What an output-only run adds to its identification.
#[derive(Debug, Clone)]
pub struct OmaFacts {
    /// `ssi-cov` or `next-era`.
    pub method: String,
    /// The output channels (0-based, axis 0 of the data).
    pub outputs: Vec<usize>,
    /// The reference channels (0-based, axis 0 of the data).
    pub references: Vec<usize>,
    /// Correlation lags.
    pub lags: usize,
    /// Jackknife blocks.
    pub blocks: usize,
    /// Samples per channel over all records.
    pub samples: usize,
    /// Samples per second.
    pub sample_rate_hz: f64,
    /// Per mode, the standard deviation of each shape entry (`None`: no spread).
    pub shape_std: Vec<Option<Vec<f64>>>,
}

impl OmaFacts {
    /// As a dict: every field, and `shapes = 'unscaled'`.
    pub fn dict<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let d = PyDict::new(py);
        d.set_item("method", &self.method)?;
        d.set_item("outputs", &self.outputs)?;
        d.set_item("references", &self.references)?;
        d.set_item("lags", self.lags)?;
        d.set_item("blocks", self.blocks)?;
        d.set_item("samples", self.samples)?;
        d.set_item("sample_rate_hz", self.sample_rate_hz)?;
        d.set_item("shape_std", self.shape_std.clone())?;
        d.set_item("shapes", "unscaled")?;
        Ok(d)
    }
}

/// What `identify` found: the model `(A, B, C, D)`, its Hankel singular values, modes
/// and fit.
#[pyclass(module = "era", name = "Identification", frozen)]
pub struct PyIdentification {
    pub(crate) found: Identification,
    pub(crate) options: EraOptions,
    /// The refinement's settings, when `refine=True`.
    pub(crate) refine: Option<era::refine::RefineOptions>,
    /// The route taken (era::identify::route), with its reasons.
    pub(crate) route: era::identify::route::Route,
    /// What the Markov parameters' source adds to `parameters` (the source, the Welch
    /// frame, OKID's observer); nothing else is set in it.
    pub(crate) source: ModelParameters,
    /// What an output-only run (`era.oma`) adds: method, channels, lags, blocks,
    /// samples, shape standard deviations.
    pub(crate) oma: Option<OmaFacts>,
}

fn matrix<'py>(py: Python<'py>, m: &faer::Mat<f64>) -> PyResult<Bound<'py, PyArray2<f64>>> {
    let (r, c) = (m.nrows(), m.ncols());
    let mut v = Vec::with_capacity(r * c);
    for i in 0..r {
        for j in 0..c {
            v.push(m[(i, j)]);
        }
    }
    vector(py, v).reshape([r, c])
}

#[pymethods]
impl PyIdentification {
    /// Each mode's displacement at the nodes of a geometry: `geometry` is a path (a
    /// UFF or geometry CSV, as `read_geometry` reads it) or the dict `read_geometry`
    /// returns; `channels` one `(node, direction)` per output (direction `"+X"`,
    /// `"-Z"` ... or its UFF number), era's numbering when left out (output `i` at node
    /// `i`, +Z). Returns a dict:
    ///
    /// - `ids` int64 (n,), `xyz` float64 (n, 3): the nodes;
    /// - `displacement` complex128 (modes, n, 3): at each node the sum of the shape's
    ///   entries times their global directions (unscaled, as `Mode.shape`); NaN at a
    ///   node without a channel (not measured, not zero);
    /// - `measured` bool (n,): which nodes carry a channel;
    /// - `not_drawn_outputs` int64: the outputs (0-based) on no node, or on a scalar or
    ///   rotational direction; `not_drawn` one sentence each saying why.
    ///
    /// Raises `ValueError` when the geometry is malformed or carries none of the
    /// outputs, or `channels` does not give one pair per output.
    #[pyo3(signature = (geometry, channels=None))]
    fn shapes_on<'py>(
        &self,
        py: Python<'py>,
        geometry: &Bound<'py, PyAny>,
        channels: Option<&Bound<'py, PyAny>>,
    ) -> PyResult<Bound<'py, PyDict>> {
        crate::geometry::shapes_on(py, &self.found, geometry, channels)
    }
    /// State matrix A (n, n).
    #[getter]
    fn a<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray2<f64>>> {
        matrix(py, &self.found.model.a)
    }
    /// Input matrix B (n, p).
    #[getter]
    fn b<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray2<f64>>> {
        matrix(py, &self.found.model.b)
    }
    /// Output matrix C (q, n).
    #[getter]
    fn c<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray2<f64>>> {
        matrix(py, &self.found.model.c)
    }
    /// Direct term D (q, p).
    #[getter]
    fn d<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray2<f64>>> {
        matrix(py, &self.found.model.d)
    }
    /// Sample time of the impulse responses (the discrete model's), s:
    /// `Ts = 1/(2Δf(N−1))` after padding.
    #[getter]
    fn sample_time_s(&self) -> f64 {
        self.found.sample_time_s
    }
    /// "discrete" or "continuous".
    #[getter]
    fn time_domain(&self) -> &'static str {
        match self.found.model.domain {
            TimeDomain::Discrete { .. } => "discrete",
            TimeDomain::Continuous => "continuous",
        }
    }
    /// Model order n.
    #[getter]
    fn states(&self) -> usize {
        self.found.model.states()
    }
    /// All singular values of H0, largest first.
    #[getter]
    fn singular_values<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        vector(py, self.found.realization.singular_values.clone())
    }
    /// Natural frequencies of the modes, Hz, ascending.
    #[getter]
    fn frequency_hz<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        vector(
            py,
            self.found
                .modal
                .modes
                .iter()
                .map(|m| m.frequency_hz)
                .collect(),
        )
    }
    /// Damping ratios of the modes (fractions), in the order of `frequency_hz`.
    #[getter]
    fn damping_ratio<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        vector(
            py,
            self.found
                .modal
                .modes
                .iter()
                .map(|m| m.damping_ratio)
                .collect(),
        )
    }
    /// Eigenvalues of A of the modes (positive imaginary part), complex.
    #[getter]
    fn eigenvalues<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<Complex64>> {
        vector(
            py,
            self.found
                .modal
                .modes
                .iter()
                .map(|m| m.eigenvalue)
                .collect(),
        )
    }
    /// Real eigenvalues of A (not modes).
    #[getter]
    fn real_poles<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        vector(
            py,
            self.found
                .modal
                .real_poles
                .iter()
                .map(|r| r.eigenvalue)
                .collect(),
        )
    }
    /// The modes, by frequency.
    #[getter]
    fn modes<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyList>> {
        let modes = self
            .found
            .modal
            .modes
            .iter()
            .enumerate()
            .map(|(k, m)| {
                let quality = self.found.quality.get(k);
                let indicators = match quality {
                    Some(q) => {
                        let d = PyDict::new(py);
                        d.set_item("mpc", q.indicators.mpc)?;
                        d.set_item("emac", q.indicators.emac)?;
                        d.set_item("cmi", q.indicators.cmi)?;
                        d.set_item("contribution", q.indicators.contribution)?;
                        d.set_item("reason", q.reason.clone())?;
                        Some(d.unbind())
                    }
                    None => None,
                };
                Py::new(
                    py,
                    PyMode {
                        frequency_hz: m.frequency_hz,
                        damping_ratio: m.damping_ratio,
                        eigenvalue: m.eigenvalue,
                        continuous_pole: m.continuous_pole,
                        shape: vector(py, m.shape.clone()).unbind(),
                        participation: vector(py, m.participation.clone()).unbind(),
                        physical: quality.map(|q| q.physical),
                        indicators,
                        frequency_std_hz: quality.and_then(|q| q.frequency_std_hz),
                        damping_ratio_std: quality.and_then(|q| q.damping_ratio_std),
                    },
                )
            })
            .collect::<PyResult<Vec<_>>>()?;
        PyList::new(py, modes)
    }
    /// An output-only run's facts (`era.oma`): `method`, `outputs` and `references`
    /// (0-based channels), `lags`, `blocks`, `samples`, `sample_rate_hz`, per mode
    /// `shape_std`, and `shapes = 'unscaled'`; `None` for other runs.
    #[getter]
    fn oma<'py>(&self, py: Python<'py>) -> PyResult<Option<Bound<'py, PyDict>>> {
        self.oma.as_ref().map(|o| o.dict(py)).transpose()
    }
    /// Size of H0, (rows, columns).
    #[getter]
    fn hankel_size(&self) -> (usize, usize) {
        self.found.realization.hankel_size
    }
    /// Warnings of the run: cautions about the route's explicit choices, the
    /// realization's, then suspect results (a Hankel too short for the lowest mode,
    /// negative damping, poles outside the unit circle, zeroed leading lines with the
    /// size of their effect, modes at the band's edge).
    #[getter]
    fn warnings(&self) -> Vec<String> {
        let mut all = self.route.cautions.clone();
        all.extend(self.found.warnings(era::params::Naming::Keyword));
        all
    }
    /// The route taken: each choice the preset or the caller made, as
    /// `(name, value, reason)`; then the cautions about explicit choices, as
    /// `("caution", text, "")`.
    #[getter]
    fn route(&self) -> Vec<(String, String, String)> {
        self.route
            .choices
            .iter()
            .map(|c| (c.name.to_string(), c.value.clone(), c.reason.clone()))
            .chain(
                self.route
                    .cautions
                    .iter()
                    .map(|c| ("caution".to_string(), c.clone(), String::new())),
            )
            .collect()
    }
    /// Every parameter of the run by its model.json name.
    #[getter]
    fn parameters<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let mut params = self.source.clone();
        params.era = Some(self.options.clone());
        params.preset = Some(self.route.preset.name().to_string());
        let text = serde_json::to_string(&params)
            .map_err(|e| pyo3::exceptions::PyRuntimeError::new_err(e.to_string()))?;
        py.import("json")?.call_method1("loads", (text,))
    }
    /// The fit against the processed measurement: fit.json's fields (`pairs` with
    /// 1-based `output`, `input`, `relative_error` = ‖G_meas − G_model‖₂/‖G_meas‖₂,
    /// `rms_log_magnitude_db`; the collocated and non-collocated means), plus
    /// `relative_error` and `rms_log_magnitude_db` as (q, p) arrays.
    #[getter]
    fn fit<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let text = serde_json::to_string(&FitJson::from_report(&self.found.fit))
            .map_err(|e| pyo3::exceptions::PyRuntimeError::new_err(e.to_string()))?;
        let dict = py.import("json")?.call_method1("loads", (text,))?;
        let (q, p) = (self.found.model.outputs(), self.found.model.inputs());
        let mut rel = vec![f64::NAN; q * p];
        let mut db = vec![f64::NAN; q * p];
        for pair in &self.found.fit.pairs {
            rel[pair.output * p + pair.input] = pair.relative_error;
            db[pair.output * p + pair.input] = pair.rms_log_magnitude_db;
        }
        dict.set_item("relative_error", vector(py, rel).reshape([q, p])?)?;
        dict.set_item("rms_log_magnitude_db", vector(py, db).reshape([q, p])?)?;
        Ok(dict)
    }
    /// The measurement after the same integrations (what the fit compares with).
    #[getter]
    fn processed(&self) -> PyFrfData {
        PyFrfData::wrap(self.found.processed.clone())
    }
    /// The model's FRF at `frequency_hz` (any finite frequencies, Hz), complex (q, p, L)
    /// in the quantity of the processed data.
    fn response<'py>(
        &self,
        py: Python<'py>,
        frequency_hz: &Bound<'py, PyAny>,
    ) -> PyResult<Bound<'py, PyArray3<Complex64>>> {
        let f = crate::frequency_lines(frequency_hz)?;
        let f = f.readonly().as_slice()?.to_vec();
        if let Some(k) = f.iter().position(|x| !x.is_finite()) {
            return value_error(format!(
                "frequency_hz: non-finite value {} at index {k}",
                f[k]
            ));
        }
        let model = &self.found.model;
        let (q, p, l) = (model.outputs(), model.inputs(), f.len());
        let values = guarded(py, || {
            Ok(era::pipeline::fit::frequency_response_blocks(model, &f))
        })?;
        vector(py, values).reshape([q, p, l])
    }
    /// model.json's text (as `era identify --out` writes it, without timings).
    fn to_json(&self) -> PyResult<String> {
        let mut params = ModelParameters::new(&self.options);
        params.preset = Some(self.route.preset.name().to_string());
        // As the CLI writes them: the automatic order and its scan.
        if self.route.states.is_none() {
            params.automatic_order = true;
            params.model_states = Some(self.found.model.states());
        }
        params.orders = self
            .found
            .stabilization
            .as_ref()
            .map(|st| st.range.to_string());
        if let Some(r) = &self.refine {
            params.refinement = Some(r.clone());
            params.model_states = Some(self.found.model.states());
        }
        let model = ModelJson::from_run(&self.found, &params);
        let mut text = serde_json::to_string_pretty(&model)
            .map_err(|e| pyo3::exceptions::PyRuntimeError::new_err(e.to_string()))?;
        text.push('\n');
        Ok(text)
    }
    /// A python-control `StateSpace` of the model (`dt` = the sample time for a
    /// discrete model, 0 for a continuous one).
    ///
    /// Raises ImportError when python-control is not installed.
    fn to_control<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let control = py.import("control").map_err(|e| {
            PyImportError::new_err(format!(
                "Identification.to_control() needs python-control: pip install control ({e})"
            ))
        })?;
        let dt = match self.found.model.domain {
            TimeDomain::Discrete { sample_time_s } => sample_time_s,
            TimeDomain::Continuous => 0.0,
        };
        control.call_method1(
            "ss",
            (self.a(py)?, self.b(py)?, self.c(py)?, self.d(py)?, dt),
        )
    }
    fn __repr__(&self) -> String {
        format!(
            "Identification({} states, {} outputs x {} inputs, {} modes, {})",
            self.found.model.states(),
            self.found.model.outputs(),
            self.found.model.inputs(),
            self.found.modal.modes.len(),
            self.time_domain()
        )
    }
}

/// The number of states from `states`: an int, or `None` for "auto" (automatic order,
/// docs/design.md §10).
pub(crate) fn states_of(states: &Bound<'_, PyAny>) -> PyResult<Option<usize>> {
    if let Ok(text) = states.extract::<String>() {
        return if text.trim().eq_ignore_ascii_case("auto") {
            Ok(None)
        } else {
            value_error(format!(
                "states '{text}': expected a number of states (an int) or 'auto'"
            ))
        };
    }
    states.extract::<Int>()?.size("states").map(Some)
}

/// Identifies a state-space model from FRFs (docs/design.md §1; the thesis's
/// `frffilt`). Thesis names: `states` = ns, `hankel_factor` = lh, `integrations` = ni,
/// `zero_lines` = nz, `pad_to` = ndpts, `lowpass` = (ford, Hzbreak),
/// `time_domain` = cord.
///
/// `preset` fills the choices left as `None`, as `era identify --preset` does:
/// 'measured' (the default) is the route measured FRFs need (the order from the
/// stabilization diagram, refinement, a continuous-time model, `D` = Y0 for
/// accelerance and 0 otherwise); 'thesis' is plain ERA with the thesis's settings
/// (no refinement, discrete time, `D` = 0). Explicit keywords override either; scripts
/// that want the thesis's numbers pass `preset="thesis"`. The route taken, with its
/// reasons, is in `Identification.route`.
///
/// `band=(lo_hz, hi_hz)` is the band the test excited: modes outside it are not
/// physical, and the refinement fits only its lines.
///
/// `refine=True` refines the model against the FRFs (poles, residues and residual
/// terms by maximum likelihood, `era identify --refine`): `residuals` ('none', 'lower',
/// 'upper', 'both'), `reciprocal`, `weighting` ('pair-noise', 'uniform') and
/// `max_iterations` set it; the modes then carry `frequency_std_hz` and
/// `damping_ratio_std`. By default the refinement adds poles for modes the start
/// missed, found in its residual; `added_modes=False` fits the start's modes only
/// (`--no-added-modes`).
///
/// `era_dc=True` realizes by ERA/DC (ERA on the shifted correlations of the Hankel
/// blocks) instead of ERA, at a fixed order or the automatic one.
///
/// `threads` sets the threads of this call (rayon's and faer's together); by default
/// every core.
///
/// A keyword left out (or `None`) takes the core's default ([`EraOptions::default`],
/// [`era::refine::RefineOptions::default`]); the text signature shows those values.
#[pyfunction]
#[pyo3(
    signature = (frf, states=None, hankel_factor=None, integrations=None, zero_lines=None, pad_to=None, lowpass=None, time_domain=None, direct_term=None, svd=None, era_dc=None, refine=None, residuals=None, reciprocal=None, weighting=None, max_iterations=None, added_modes=None, band=None, preset=None, threads=None),
    text_signature = "(frf, states='auto', hankel_factor=5, integrations=0, zero_lines=0, pad_to=0, lowpass=None, time_domain=None, direct_term=None, svd='auto', era_dc=False, refine=None, residuals='both', reciprocal=False, weighting='pair-noise', max_iterations=100, added_modes=True, band=None, preset='measured', threads=None)"
)]
#[allow(clippy::too_many_arguments)]
pub fn identify(
    py: Python<'_>,
    frf: &Bound<'_, PyFrfData>,
    states: Option<&Bound<'_, PyAny>>,
    hankel_factor: Option<Int>,
    integrations: Option<Int>,
    zero_lines: Option<Int>,
    pad_to: Option<Int>,
    lowpass: Option<&Bound<'_, PyAny>>,
    time_domain: Option<&str>,
    direct_term: Option<&str>,
    svd: Option<&str>,
    era_dc: Option<bool>,
    refine: Option<bool>,
    residuals: Option<&str>,
    reciprocal: Option<bool>,
    weighting: Option<&str>,
    max_iterations: Option<Int>,
    added_modes: Option<bool>,
    band: Option<(f64, f64)>,
    preset: Option<&str>,
    threads: Option<Int>,
) -> PyResult<PyIdentification> {
    let threads = thread_count(threads)?;
    let chosen = match states {
        Some(s) if !s.is_none() => states_of(s)?,
        _ => None,
    };
    let states = chosen.unwrap_or(0);
    let request = route_request(preset, chosen, refine, time_domain, direct_term, band)?;
    let mut options = era_options(states, hankel_factor, lowpass, svd, era_dc)?;
    let size = |given: Option<Int>, keyword: &str, default: usize| {
        given.map_or(Ok(default), |n| n.size(keyword))
    };
    options.integrations = size(integrations, "integrations", options.integrations)?;
    let route = request.resolve(frf.get().inner.quantity(), options.integrations);
    let refine = route.refine;
    let mut refine_options = refine_options_of(
        (frf.get().inner.outputs(), frf.get().inner.inputs()),
        residuals,
        weighting,
        reciprocal,
        added_modes,
        max_iterations,
    )?;
    options.zero_lines = size(zero_lines, "zero_lines", options.zero_lines)?;
    options.pad_to = size(pad_to, "pad_to", options.pad_to)?;
    options.domain = route.domain;
    options.direct_term = route.direct_term;
    let checked = {
        let mut o = options.clone();
        o.order = era::Order::Fixed(states.max(usize::from(chosen.is_none())));
        o
    };
    checked.check(Naming::Keyword).map_err(era_error)?;
    let data = frf.get().inner.clone();
    // The refinement fits measured lines only (never leading zero lines: a padded
    // start, or zero_lines), inside the band when one is given: as the CLI does.
    let fit = era::data::frf::fit_lines(&data, options.zero_lines, band).or_else(|why| {
        let (lo, hi) = band.unwrap_or_default();
        value_error(format!("band ({lo}, {hi}): {why}"))
    })?;
    refine_options.band = fit.lines;
    let scan_options = {
        let mut o = ScanOptions::default();
        o.band_hz = fit.band_hz;
        o
    };
    let era_run = {
        let mut o = options.clone();
        o.domain = route.realization_domain();
        o
    };
    let run = Run {
        data: &data,
        supplied: None,
        era: &era_run,
        fixed_order: chosen.is_some(),
        scan: &scan_options,
        refine: refine.then_some(&refine_options),
        domain: route.domain,
        fitted_hz: fit.fitted_hz,
    };
    // One pool for the whole call: identification and refinement alike.
    let found = guarded_in(py, threads, || run.identify().map_err(era_error))?;
    Ok(PyIdentification {
        found,
        options,
        refine: refine.then_some(refine_options),
        route,
        source: Default::default(),
        oma: None,
    })
}

/// ERA's options from the keywords both `identify` and `identify_time` take, each
/// `None` the core's default ([`EraOptions::default`]).
pub(crate) fn era_options(
    states: usize,
    hankel_factor: Option<Int>,
    lowpass: Option<&Bound<'_, PyAny>>,
    svd: Option<&str>,
    era_dc: Option<bool>,
) -> PyResult<EraOptions> {
    let mut options = EraOptions::default();
    options.order = era::Order::Fixed(states);
    if let Some(h) = hankel_factor {
        options.hankel_factor = h.size("hankel_factor")?;
    }
    options.lowpass = lowpass_of(lowpass)?;
    if let Some(svd) = svd {
        options.svd = svd_path(svd)?;
    }
    match era_dc {
        Some(true) => options.realizer = era::identify::Realizer::EraDc,
        Some(false) => options.realizer = era::identify::Realizer::Era,
        None => {}
    }
    Ok(options)
}

/// The route asked for: `preset` with the choices given (`None` leaves one to the
/// preset). An FrfData carries no coherence and no window metadata.
pub(crate) fn route_request(
    preset: Option<&str>,
    states: Option<usize>,
    refine: Option<bool>,
    time_domain: Option<&str>,
    direct_term: Option<&str>,
    band: Option<(f64, f64)>,
) -> PyResult<era::identify::route::RouteRequest> {
    let preset: era::identify::route::Preset = crate::named_or_default("preset", preset)?;
    let mut request = era::identify::route::RouteRequest::new(preset);
    // An FrfData carries no coherence and no window metadata: neither is used, and
    // the route says so.
    request.without_metadata = true;
    request.band_hz = band;
    request.states = states;
    request.refine = refine;
    request.domain = time_domain
        .map(|t| crate::named::<ModelDomain>("time_domain", t))
        .transpose()?;
    request.direct_term = direct_term
        .map(|t| crate::named::<DirectTerm>("direct_term", t))
        .transpose()?;
    Ok(request)
}

/// The refinement's settings from the keywords, each `None` the core's default
/// ([`era::refine::RefineOptions::default`]; its band is set once the lines are known);
/// `reciprocal=True` needs a square set.
pub(crate) fn refine_options_of(
    (outputs, inputs): (usize, usize),
    residuals: Option<&str>,
    weighting: Option<&str>,
    reciprocal: Option<bool>,
    added_modes: Option<bool>,
    max_iterations: Option<Int>,
) -> PyResult<era::refine::RefineOptions> {
    let mut refine_options = era::refine::RefineOptions::default();
    if let Some(r) = residuals {
        refine_options.residuals = crate::named("residuals", r)?;
    }
    if let Some(w) = weighting {
        refine_options.weighting = crate::named("weighting", w)?;
    }
    refine_options.reciprocal = reciprocal.unwrap_or(refine_options.reciprocal);
    refine_options.add_missed = added_modes.unwrap_or(refine_options.add_missed);
    if let Some(max_iterations) = max_iterations {
        let iterations = max_iterations.size("max_iterations")?;
        if iterations == 0 {
            return value_error("max_iterations 0: the refinement needs at least one iteration");
        }
        era::params::limits::ITERATIONS
            .check("max_iterations", iterations as u64)
            .map_err(|e| pyo3::exceptions::PyValueError::new_err(e.to_string()))?;
        refine_options.max_iterations = iterations;
    }
    let reciprocal = refine_options.reciprocal;
    if reciprocal && outputs != inputs {
        return value_error(format!(
            "reciprocal=True: the set has {outputs} outputs x {inputs} inputs; reciprocity needs a square (collocated) set"
        ));
    }
    Ok(refine_options)
}

/// `lowpass=`: a cut-off in Hz (order 4), `(order, cut-off Hz)`, or `None`.
pub(crate) fn lowpass_of(lowpass: Option<&Bound<'_, PyAny>>) -> PyResult<Option<(usize, f64)>> {
    Ok(match lowpass {
        None => None,
        Some(obj) if obj.is_none() => None,
        Some(obj) => match obj.extract::<(Int, f64)>() {
            Ok((order, hz)) => Some((order.size("lowpass order")?, hz)),
            Err(_) => match obj.extract::<f64>() {
                Ok(hz) => Some((EraOptions::DEFAULT_LOWPASS_ORDER, hz)),
                Err(_) => {
                    return value_error(format!(
                        "lowpass {}: expected a cut-off in Hz or (order, cut-off Hz)",
                        obj.repr()?
                    ))
                }
            },
        },
    })
}

/// `svd=`: 'auto', 'dense' or 'matrix-free'.
pub(crate) fn svd_path(svd: &str) -> PyResult<SvdPath> {
    crate::named("svd", svd)
}

/// One identification as `identify` runs it, every input checked.
pub(crate) struct Run<'a> {
    pub(crate) data: &'a era::FrfData,
    /// Markov parameters from a source other than the FRFs (OKID's).
    pub(crate) supplied: Option<&'a era::sources::MarkovSequence>,
    /// The realization's options (its domain the route's realization domain).
    pub(crate) era: &'a EraOptions,
    /// A fixed order (`states=` an int), else the automatic order.
    pub(crate) fixed_order: bool,
    pub(crate) scan: &'a ScanOptions,
    /// The refinement's settings, when the route refines.
    pub(crate) refine: Option<&'a era::refine::RefineOptions>,
    /// The domain of the model returned.
    pub(crate) domain: ModelDomain,
    /// The band identified over, Hz, for the band-edge suspects.
    pub(crate) fitted_hz: (f64, f64),
}

impl Run<'_> {
    /// ERA at the fixed or automatic order, the refinement when asked, then the
    /// suspects of a zero start and of the band's edges.
    pub(crate) fn identify(&self) -> era::Result<Identification> {
        let (stage, order) = (&mut |_| {}, &mut |_, _| {});
        let mut options = self.era.clone();
        options.scan = self.scan.clone();
        if !self.fixed_order {
            options.order = Order::Auto;
        }
        let found = match self.supplied {
            None => run_identify(self.data, &options),
            Some(m) => identify_supplied(self.data, m, &options, stage, order),
        }?;
        let mut at_order = self.era.clone();
        at_order.order = Order::Fixed(found.realization.model.states());
        let zero_start = era::identify::zero_start(&found, &at_order, self.refine.is_some());
        let mut found = match self.refine {
            Some(options) => era::refine::identification::refine_identification_in(
                found,
                self.data,
                options,
                Some(self.domain),
                &mut |_| {},
                &mut |_, _| {},
            )?,
            None => found,
        };
        found.suspects.extend(zero_start);
        let edges = era::identify::suspect::band_edges(&found, self.fitted_hz);
        found.suspects.extend(edges);
        Ok(found)
    }
}
