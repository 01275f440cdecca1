//! `FrfData`, the FRF files, the Welch estimate and the simulators.
//!
//! `FrfData(frequency_hz, values, quantity)` holds `G[i][j](f_k)`, output `i`, input `j`,
//! line `k` at `f_k = k·Δf` from 0 Hz, exactly as [`era::FrfData`] and the files do
//! (docs/design.md §4). It is validated by [`era::FrfData::new`], the check every file
//! reader of the CLI ends in, so a Python array is refused with the words a file would
//! be: lines from 0 Hz and uniform, every value finite, the shapes agreeing.

use crate::{contiguous, era_error, guarded, io_error, read_only, value_error, vector, Int};
use era::estimate::{estimate, Detrend, Estimator, WelchOptions, Window};
use era::params::Naming;
use era::{Complex64, FrfData, Quantity};
use era_io::format::{read_frf_file, write_frf_file, FrfFormat, ReadOptions};
use era_io::frf_file::FrfFile;
use era_io::uff::UffWriteOptions;
use numpy::ndarray::Ix3;
use numpy::{PyArray1, PyArray3, PyArrayMethods, PyUntypedArrayMethods};
use pyo3::prelude::*;
use pyo3::sync::GILOnceCell;
use pyo3::types::PyType;
use std::path::PathBuf;
use std::sync::Arc;

/// Parses a quantity name for the keyword `name`.
pub(crate) fn quantity(name: &str, text: &str) -> PyResult<Quantity> {
    crate::named::<Quantity>(name, text)
}

/// Measured or simulated FRFs, axis order `[output, input, frequency]`.
///
/// `FrfData(frequency_hz, values, quantity="acceleration")`: `frequency_hz` (L,) from
/// 0 Hz, uniformly spaced (a start at a whole number of spacings above 0 Hz is padded
/// with zero lines, with a `UserWarning`, as `era identify` pads a file); `values` complex128 (q, p, L); `quantity` what the outputs
/// measure per unit force. Validated as the CLI validates a file (same `ValueError`
/// messages). `values` and `frequency_hz` read back as read-only numpy arrays.
#[pyclass(module = "era", name = "FrfData", frozen)]
pub struct PyFrfData {
    pub(crate) inner: Arc<FrfData>,
    values: GILOnceCell<Py<PyArray3<Complex64>>>,
    frequency: GILOnceCell<Py<PyArray1<f64>>>,
}

impl PyFrfData {
    /// Wraps validated data.
    pub(crate) fn wrap(frf: FrfData) -> Self {
        PyFrfData {
            inner: Arc::new(frf),
            values: GILOnceCell::new(),
            frequency: GILOnceCell::new(),
        }
    }
}

#[pymethods]
impl PyFrfData {
    #[new]
    #[pyo3(signature = (frequency_hz, values, quantity="acceleration"))]
    fn new(
        py: Python<'_>,
        frequency_hz: &Bound<'_, PyAny>,
        values: &Bound<'_, PyAny>,
        quantity: &str,
    ) -> PyResult<Self> {
        let q_tag = crate::frf::quantity("quantity", quantity)?;
        let f = crate::frequency_lines(frequency_hz)?;
        let v = contiguous::<Complex64, Ix3>(
            values,
            "complex128",
            &[
                &era::params::limits::CHANNELS,
                &era::params::limits::CHANNELS,
                &era::params::limits::LINES,
            ],
            Some(&era::params::limits::VALUES),
            "values",
            "(outputs, inputs, lines)",
        )?;
        let shape = v.shape().to_vec();
        let (outputs, inputs, lines) = (shape[0], shape[1], shape[2]);
        let freq = f.readonly().as_slice()?.to_vec();
        if lines != freq.len() {
            return Err(era_error(era::EraError::ShapeMismatch {
                what: format!(
                    "frequency lines: values has shape ({outputs}, {inputs}, {lines}) and frequency_hz {} lines",
                    freq.len()
                ),
                expected: freq.len(),
                got: lines,
            }));
        }
        // The one copy: the core owns its validated data (and Python may change the
        // array afterwards, or while the GIL is released).
        let mut data = v.readonly().as_slice()?.to_vec();
        let mut freq = freq;
        // A late start on the grid is padded with zero lines, as the files are (with
        // the same note, as a warning); one off the grid is refused with the remedy.
        let start = era_io::frf_file::zero_start(
            std::path::Path::new("frequency_hz"),
            "",
            &freq,
            outputs * inputs,
        )
        .map_err(|e| pyo3::exceptions::PyValueError::new_err(e.to_string()))?;
        if let Some(start) = start {
            data = start.pad_values(&data, outputs * inputs);
            let warnings = py.import("warnings")?;
            warnings.call_method1(
                "warn",
                (
                    start.note(),
                    py.get_type::<pyo3::exceptions::PyUserWarning>(),
                    2,
                ),
            )?;
            freq = start.frequency_hz;
        }
        let frf = py
            .allow_threads(|| FrfData::new(freq, outputs, inputs, data, q_tag))
            .map_err(era_error)?;
        Ok(Self::wrap(frf))
    }

    /// The frequency lines, Hz, shape (L,).
    #[getter]
    fn frequency_hz<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray1<f64>>> {
        let a = self.frequency.get_or_try_init(py, || -> PyResult<_> {
            let a = PyArray1::from_slice(py, self.inner.frequency_hz());
            read_only(&a)?;
            Ok(a.unbind())
        })?;
        Ok(a.bind(py).clone())
    }

    /// The FRFs, complex128, shape (outputs, inputs, lines).
    #[getter]
    fn values<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray3<Complex64>>> {
        let a = self.values.get_or_try_init(py, || -> PyResult<_> {
            let f = &self.inner;
            let a = PyArray1::from_slice(py, f.values()).reshape([
                f.outputs(),
                f.inputs(),
                f.lines(),
            ])?;
            read_only(&a)?;
            Ok(a.unbind())
        })?;
        Ok(a.bind(py).clone())
    }

    /// What the outputs measure per unit force: "acceleration", "velocity" or
    /// "displacement".
    #[getter]
    fn quantity(&self) -> &'static str {
        self.inner.quantity().name()
    }

    /// Number of outputs (sensors), q.
    #[getter]
    fn outputs(&self) -> usize {
        self.inner.outputs()
    }

    /// Number of inputs (actuators), p.
    #[getter]
    fn inputs(&self) -> usize {
        self.inner.inputs()
    }

    /// Number of frequency lines, L.
    #[getter]
    fn lines(&self) -> usize {
        self.inner.lines()
    }

    /// Line spacing Δf, Hz.
    #[getter]
    fn spacing_hz(&self) -> f64 {
        self.inner.spacing_hz()
    }

    /// The same data with another quantity tag (no conversion).
    fn with_quantity(&self, quantity: &str) -> PyResult<Self> {
        let q = crate::frf::quantity("quantity", quantity)?;
        Ok(Self::wrap((*self.inner).clone().with_quantity(q)))
    }

    fn __eq__(&self, other: &Bound<'_, PyAny>) -> bool {
        match other.downcast::<PyFrfData>() {
            Ok(o) => *o.get().inner == *self.inner,
            Err(_) => false,
        }
    }

    fn __repr__(&self) -> String {
        let f = &self.inner;
        format!(
            "FrfData({} outputs x {} inputs, {} lines, 0 .. {} Hz at {} Hz, {})",
            f.outputs(),
            f.inputs(),
            f.lines(),
            f.frequency_hz()[f.lines() - 1],
            f.spacing_hz(),
            f.quantity()
        )
    }

    /// Pickling (process pools, Dask, Ray): rebuilt from its arrays and quantity.
    #[allow(clippy::type_complexity)]
    fn __reduce__<'py>(
        slf: &Bound<'py, Self>,
    ) -> PyResult<(
        Bound<'py, PyType>,
        (
            Bound<'py, PyArray1<f64>>,
            Bound<'py, PyArray3<Complex64>>,
            &'static str,
        ),
    )> {
        let py = slf.py();
        let this = slf.get();
        Ok((
            slf.get_type(),
            (this.frequency_hz(py)?, this.values(py)?, this.quantity()),
        ))
    }
}

/// Reads FRFs from a CSV, UFF 58/58b or MAT v5 file, told apart by content.
///
/// `quantity` overrides the file's tag (acceleration is assumed when neither says);
/// `outputs` is the number of outputs of a MAT file's FRF matrix when the file does
/// not say and the set is not square; `freq_variable` names a MAT file's frequency
/// variable when it is not `FreqV`.
#[pyfunction]
#[pyo3(signature = (path, quantity=None, outputs=None, freq_variable=None))]
pub fn read_frf(
    py: Python<'_>,
    path: PathBuf,
    quantity: Option<&str>,
    outputs: Option<Int>,
    freq_variable: Option<String>,
) -> PyResult<PyFrfData> {
    let tag = quantity
        .map(|q| crate::frf::quantity("quantity", q))
        .transpose()?;
    let outputs = outputs.map(|o| o.size("outputs")).transpose()?;
    let opts = ReadOptions {
        default_quantity: Quantity::Acceleration,
        outputs,
        frequency_variable: freq_variable,
    };
    let frf = guarded(py, || {
        let (file, _) = read_frf_file(&path, &opts).map_err(io_error)?;
        Ok(match tag {
            Some(q) => file.frf.with_quantity(q),
            None => file.frf,
        })
    })?;
    Ok(PyFrfData::wrap(frf))
}

/// Writes FRFs in the format the extension names: `.csv`, `.uff`/`.unv` (UFF 58,
/// ASCII; binary 58b with `binary=True`) or `.mat`. The file appears whole or not at
/// all (written to a temporary file and renamed). CSV and UFF files carry the quantity;
/// a MAT file (`FRF` + `FreqV`) does not, so `read_frf` is told it again.
#[pyfunction]
#[pyo3(signature = (path, frf, binary=false))]
pub fn write_frf(
    py: Python<'_>,
    path: PathBuf,
    frf: &Bound<'_, PyFrfData>,
    binary: bool,
) -> PyResult<()> {
    if binary {
        match FrfFormat::from_extension(&path) {
            Some(FrfFormat::Uff) => {}
            other => {
                return value_error(format!(
                    "binary=True applies to UFF output (.uff, .unv), not to {} ({})",
                    other.map_or("an unknown format", |f| f.name()),
                    path.display()
                ))
            }
        }
    }
    let data = frf.get().inner.clone();
    guarded(py, move || {
        let file = FrfFile {
            frf: (*data).clone(),
            quantity_given: true,
            metadata: Default::default(),
            channels: None,
        };
        write_frf_file(
            &path,
            &file,
            UffWriteOptions {
                binary,
                single: false,
            },
        )
        .map_err(io_error)
    })
}

/// The Welch keywords of `estimate_frf` and `identify_time`, checked.
pub(crate) struct WelchKeywords {
    pub(crate) sample_rate_hz: f64,
    pub(crate) window: Window,
    pub(crate) overlap: f64,
    pub(crate) estimator: Estimator,
    pub(crate) detrend: Detrend,
    pub(crate) quantity: era::Quantity,
}

impl WelchKeywords {
    /// The keywords, each `None` the core's default ([`WelchOptions::new`] and the
    /// enums' `Default`).
    pub(crate) fn parse(
        sample_rate_hz: f64,
        window: Option<&str>,
        overlap: Option<f64>,
        estimator: Option<&str>,
        detrend: Option<&str>,
        quantity: Option<&str>,
    ) -> PyResult<Self> {
        let keywords = WelchKeywords {
            sample_rate_hz,
            window: crate::named_or_default("window", window)?,
            overlap: overlap.unwrap_or(WelchOptions::DEFAULT_OVERLAP),
            estimator: crate::named_or_default("estimator", estimator)?,
            detrend: crate::named_or_default("detrend", detrend)?,
            quantity: match quantity {
                Some(q) => crate::frf::quantity("quantity", q)?,
                None => era::Quantity::default(),
            },
        };
        if !(sample_rate_hz.is_finite() && sample_rate_hz > 0.0) {
            return value_error(format!(
                "sample_rate_hz {sample_rate_hz}: must be a positive number of samples per second"
            ));
        }
        Ok(keywords)
    }

    /// The Welch options at `frame` samples per frame.
    pub(crate) fn options(&self, frame: usize) -> WelchOptions {
        let mut o = WelchOptions::new(self.sample_rate_hz, frame);
        o.overlap = self.overlap;
        o.window = self.window;
        o.detrend = self.detrend;
        o
    }
}

/// Rows `channels` of a C-contiguous (channels, samples) block, borrowed in place.
pub(crate) fn rows<'a>(flat: &'a [f64], samples: usize, channels: &[usize]) -> Vec<&'a [f64]> {
    channels
        .iter()
        .map(|&c| &flat[c * samples..(c + 1) * samples])
        .collect()
}

pub(crate) fn channels(name: &str, list: &[Int], available: usize) -> PyResult<Vec<usize>> {
    if list.is_empty() {
        return value_error(format!("{name}: give at least one channel"));
    }
    let mut out = Vec::with_capacity(list.len());
    for c in list {
        let c = c.size(name)?;
        if c >= available {
            return value_error(format!(
                "{name}: channel {c} is out of range: data has {available} channels (0-based, axis 0)"
            ));
        }
        out.push(c);
    }
    Ok(out)
}

/// FRFs and ordinary coherence estimated from time histories (Welch averaging).
///
/// `data` is (channels, samples) float64; `inputs` and `outputs` are 0-based channel
/// indices into axis 0. Returns `(FrfData, coherence)` with coherence (q, p, L).
#[pyfunction]
#[pyo3(
    signature = (data, sample_rate_hz, inputs, outputs, frame, window=None, overlap=None, estimator=None, detrend=None, quantity=None),
    text_signature = "(data, sample_rate_hz, inputs, outputs, frame, window='hann', overlap=0.5, estimator='h1', detrend='mean', quantity='acceleration')"
)]
#[allow(clippy::too_many_arguments)]
pub fn estimate_frf<'py>(
    py: Python<'py>,
    data: &Bound<'py, PyAny>,
    sample_rate_hz: f64,
    inputs: Vec<Int>,
    outputs: Vec<Int>,
    frame: Int,
    window: Option<&str>,
    overlap: Option<f64>,
    estimator: Option<&str>,
    detrend: Option<&str>,
    quantity: Option<&str>,
) -> PyResult<(PyFrfData, Bound<'py, PyArray3<f64>>)> {
    let welch = WelchKeywords::parse(
        sample_rate_hz,
        window,
        overlap,
        estimator,
        detrend,
        quantity,
    )?;
    let frame = frame.size("frame")?;
    let array = crate::time_block(data)?;
    let (n_channels, samples) = (array.shape()[0], array.shape()[1]);
    let inputs = channels("inputs", &inputs, n_channels)?;
    let outputs = channels("outputs", &outputs, n_channels)?;
    let options = welch.options(frame);
    let view = array.readonly();
    let flat = view.as_slice()?;
    let (xs, ys) = (rows(flat, samples, &inputs), rows(flat, samples, &outputs));
    let found = guarded(py, || {
        estimate(&xs, &ys, &options, welch.estimator, welch.quantity).map_err(era_error)
    })?;
    let (q, p, l) = (found.frf.outputs(), found.frf.inputs(), found.frf.lines());
    let coherence = vector(py, found.ordinary_coherence).reshape([q, p, l])?;
    Ok((PyFrfData::wrap(found.frf), coherence))
}

/// The thesis's 4-mass truth model (Table 5.2): 3 × 3 displacement FRFs, 1025 lines
/// 0 … 12.8 kHz, with `noise` (a fraction of each FRF's RMS, e.g. 0.15) of seeded
/// complex Gaussian noise when given.
#[pyfunction]
#[pyo3(signature = (noise=None, seed=Int(1)), text_signature = "(noise=None, seed=1)")]
pub fn simulate_truth_model(py: Python<'_>, noise: Option<f64>, seed: Int) -> PyResult<PyFrfData> {
    let seed = seed.count("seed")?;
    if let Some(n) = noise {
        era::sim::check_noise(Naming::Keyword, n).map_err(era_error)?;
    }
    let noise = noise.filter(|&n| n > 0.0).map(|n| (n, seed));
    let frf = guarded(py, || era::sim::truth_model_frf(noise).map_err(era_error))?;
    Ok(PyFrfData::wrap(frf))
}

/// A seeded lightly damped structure with real normal modes (docs/design.md §3), as
/// `era simulate modal`: `modes` modes between `fmin` and `fmax` Hz, damping ratios
/// drawn in `damping = (min, max)`, FRFs on `lines` lines at `df` Hz.
#[pyfunction]
#[pyo3(
    signature = (outputs=Int(8), inputs=Int(8), modes=Int(40), fmin=0.5, fmax=14.0, damping=(0.005, 0.02), lines=Int(801), df=0.025, quantity="acceleration", collocated=false, noise=0.0, seed=Int(1)),
    text_signature = "(outputs=8, inputs=8, modes=40, fmin=0.5, fmax=14.0, damping=(0.005, 0.02), lines=801, df=0.025, quantity='acceleration', collocated=False, noise=0.0, seed=1)"
)]
#[allow(clippy::too_many_arguments)]
pub fn simulate_modal(
    py: Python<'_>,
    outputs: Int,
    inputs: Int,
    modes: Int,
    fmin: f64,
    fmax: f64,
    damping: (f64, f64),
    lines: Int,
    df: f64,
    quantity: &str,
    collocated: bool,
    noise: f64,
    seed: Int,
) -> PyResult<PyFrfData> {
    let tag = crate::frf::quantity("quantity", quantity)?;
    era::sim::check_noise(Naming::Keyword, noise).map_err(era_error)?;
    let request = era::sim::ModalRequest::new(
        era::sim::ModalSpec {
            outputs: outputs.size("outputs")?,
            inputs: inputs.size("inputs")?,
            modes: modes.size("modes")?,
            fmin_hz: fmin,
            fmax_hz: fmax,
            damping_min: damping.0,
            damping_max: damping.1,
            collocated,
            seed: seed.count("seed")?,
        },
        lines.size("lines")?,
        df,
    );
    request.check(Naming::Keyword).map_err(era_error)?;
    let frf = guarded(py, || {
        let structure = era::sim::ModalStructure::random(&request.spec).map_err(era_error)?;
        let mut frf = structure
            .frf(request.lines, request.df_hz, tag)
            .map_err(era_error)?;
        if noise > 0.0 {
            frf = era::sim::add_noise(&frf, noise, request.spec.seed).map_err(era_error)?;
        }
        Ok(frf)
    })?;
    Ok(PyFrfData::wrap(frf))
}

/// Reads time histories from a CSV, MAT v5 or HDF5 file (as `era frf` does).
///
/// `variables` picks MAT variables (side by side), `datasets` HDF5 datasets; `threads`
/// the threads of the CSV reader (default: every core; 1 for a task beside others).
/// Returns `(data, sample_rate_hz, names)`: `data` float64 (channels, samples), the
/// sample rate the file gives (None when it gives none), and the channel names (None
/// when absent).
#[pyfunction]
#[pyo3(signature = (path, variables=Vec::new(), datasets=Vec::new(), threads=None))]
#[allow(clippy::type_complexity)]
pub fn read_time<'py>(
    py: Python<'py>,
    path: PathBuf,
    variables: Vec<String>,
    datasets: Vec<String>,
    threads: Option<Int>,
) -> PyResult<(
    Bound<'py, numpy::PyArray2<f64>>,
    Option<f64>,
    Option<Vec<String>>,
)> {
    let selection = era_io::time::TimeSelection {
        variables,
        datasets,
    };
    let threads = crate::thread_count(threads)?;
    let history = crate::guarded_in(py, threads, || {
        era_io::time::read_time_file(&path, &selection).map_err(io_error)
    })?;
    let (channels, samples) = (history.channels(), history.samples());
    let flat: Vec<f64> = history.columns.into_iter().flatten().collect();
    let data = vector(py, flat).reshape([channels, samples])?;
    Ok((data, history.sample_rate.map(|(r, _)| r), history.names))
}
