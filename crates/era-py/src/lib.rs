//! # era from Python
//!
//! The native module `era._era` behind the Python package `era` (`python/era`): numpy
//! arrays in, numpy arrays and plain Python objects out, every call going through the same
//! library functions and parameter checks as the `era` command line.
//!
//! - `frf`: `FrfData` (validated like a file the CLI reads), `read_frf`, `write_frf`,
//!   `estimate_frf` (Welch H1/H2/Hv from time histories), the simulators.
//! - `model`: `identify` and its `Identification` (the matrices, singular values, modes,
//!   fit, the model's FRF, `model.json`'s text, a python-control `StateSpace`).
//! - `friction`: `friction_estimate`, the free-decay Coulomb estimate of Eq. 3.12.
//! - `geometry`: `read_geometry`, a test geometry's nodes and lines as numpy arrays.
//!
//! ## Errors
//! A refused value or file is a Python exception carrying the CLI's message: input errors
//! of the core ([`era::EraError::is_input_error`]) and malformed files are `ValueError`;
//! a missing file `FileNotFoundError`, a folder `IsADirectoryError`, an unreadable file
//! `PermissionError` or `OSError`;
//! a numerical failure `RuntimeError`. A panic never crosses into Python as pyo3's
//! `PanicException`: `guarded` turns one into a `RuntimeError` naming it an internal
//! error.
//!
//! ## Threads and copies
//! Every call that computes or reads a file releases the GIL (`Python::allow_threads`),
//! so Python threads identify in parallel. Each call runs in a rayon pool of its own
//! (`threads=`, by default as many threads as rayon's global pool would have), never in
//! the global pool, so that a process forked after a call (a process pool) can call
//! again. Inputs are read in place when numpy's layout
//! allows (a C-contiguous float64 time-history block is borrowed, not copied); FRF values
//! are copied once into the validated [`era::FrfData`] the core owns; results move their
//! Rust buffers into numpy arrays without a copy.
//!
//! Why hand-written glue rather than a generated binding: the API is fixed by issue 17
//! (names, axis order `[output, input, frequency]`, exceptions), and the checks are the
//! CLI's ([`era::params`]), which no generator knows about.

use numpy::{Element, PyArray, PyArray1};
use pyo3::exceptions::{
    PyFileNotFoundError, PyIsADirectoryError, PyOSError, PyPermissionError, PyRuntimeError,
    PyValueError,
};
use pyo3::prelude::*;

/// mimalloc, not the system's: a worker process that runs record after record (a Dask
/// or Ray worker, a process pool) reuses the memory of the last call instead of taking
/// it from the system and faulting it in again each time.
#[global_allocator]
static ALLOCATOR: mimalloc::MiMalloc = mimalloc::MiMalloc;

mod frf;
mod friction;
mod geometry;
mod model;
mod oma;
mod time;

/// An error of the core as a Python exception: `ValueError` for the caller's data or
/// parameters, `RuntimeError` for a numerical failure.
pub(crate) fn era_error(e: era::EraError) -> PyErr {
    // The parameters the core's messages name are spelled as keywords here.
    let message = e.message(era::params::Naming::Keyword);
    if e.is_input_error() {
        PyValueError::new_err(message)
    } else {
        PyRuntimeError::new_err(message)
    }
}

/// A file error as a Python exception: `FileNotFoundError`, `PermissionError` or
/// `OSError` for the operating system's refusals, `ValueError` for malformed content or
/// a size above a limit. The message is the CLI's (it names the file, line, column).
pub(crate) fn io_error(e: era_io::IoError) -> PyErr {
    let message = e.to_string();
    match &e {
        era_io::IoError::Io { error, .. } => match error.kind() {
            std::io::ErrorKind::NotFound => PyFileNotFoundError::new_err(message),
            std::io::ErrorKind::PermissionDenied => PyPermissionError::new_err(message),
            std::io::ErrorKind::IsADirectory => PyIsADirectoryError::new_err(message),
            _ => PyOSError::new_err(message),
        },
        _ => PyValueError::new_err(message),
    }
}

/// `ValueError(message)`.
/// The value of the core's enum that `text` names, for the keyword `keyword`: the core's
/// names and `FromStr` ([`era::params::names`]), as the CLI reads its flags; a `ValueError`
/// naming the keyword and the names expected otherwise.
pub(crate) fn named<T>(keyword: &str, text: &str) -> PyResult<T>
where
    T: std::str::FromStr<Err = era::params::names::UnknownName>,
{
    text.parse::<T>()
        .or_else(|e| value_error(format!("{keyword} {e}")))
}

/// `named(keyword, text)`, or the type's default (the core's) when the keyword is
/// `None`.
pub(crate) fn named_or_default<T>(keyword: &str, text: Option<&str>) -> PyResult<T>
where
    T: std::str::FromStr<Err = era::params::names::UnknownName> + Default,
{
    text.map_or_else(|| Ok(T::default()), |t| named(keyword, t))
}

pub(crate) fn value_error<T>(message: impl Into<String>) -> PyResult<T> {
    Err(PyValueError::new_err(message.into()))
}

/// How often a waiting call looks for Ctrl-C (Python's signal handlers run only on the
/// main thread, with the GIL, so the waiting thread polls them).
const SIGNAL_POLL: std::time::Duration = std::time::Duration::from_millis(50);

/// Stack of the thread a call runs on: the main thread's usual 8 MB, not a spawned
/// thread's 2 MB.
const WORKER_STACK: usize = 8 << 20;

/// Runs `work` with the GIL released, on a thread of its own under a cancel token
/// ([`era::cancel`]), while the calling thread waits and runs Python's signal handlers
/// every [`SIGNAL_POLL`]. Ctrl-C (any exception a handler raises) cancels the token;
/// the core stops at its next check, the worker is joined, and the exception reaches
/// the caller with nothing left running. A panic becomes a `RuntimeError` (a panic is a
/// bug of ours, never an answer to bad input; it must not reach Python as pyo3's
/// `PanicException`, which is not an `Exception`).
pub(crate) fn guarded<T: Send>(
    py: Python<'_>,
    work: impl FnOnce() -> PyResult<T> + Send,
) -> PyResult<T> {
    guarded_in(py, None, work)
}

/// `threads=`, checked as the CLI's `--threads`; `None` for every core.
pub(crate) fn thread_count(threads: Option<Int>) -> PyResult<Option<usize>> {
    match threads {
        None => Ok(None),
        Some(n) => {
            let n = n.size("threads")?;
            era::parallel::check_threads(era::params::Naming::Keyword, n).map_err(era_error)?;
            Ok(Some(n))
        }
    }
}

/// [`guarded`] with `threads` for the call's pool (`None`: [`default_threads`]).
///
/// Every call runs in a rayon pool of its own ([`era::parallel::with_threads`]), never
/// in rayon's global pool: a process forked after the global pool started (a
/// `concurrent.futures` process pool, `multiprocessing`'s default on Linux) inherits it
/// without its threads, and a call there would wait for ever.
pub(crate) fn guarded_in<T: Send>(
    py: Python<'_>,
    threads: Option<usize>,
    work: impl FnOnce() -> PyResult<T> + Send,
) -> PyResult<T> {
    let threads = threads.unwrap_or_else(default_threads);
    let work = move || {
        era::parallel::with_threads(era::params::Naming::Keyword, Some(threads), work)
            .map_err(era_error)
            .and_then(|r| r)
    };
    let token = era::cancel::Cancel::new();
    let token = &token;
    // Set by the worker when it is done; the condition variable wakes the waiter.
    let finished = &(std::sync::Mutex::new(false), std::sync::Condvar::new());
    std::thread::scope(|scope| {
        let worker = std::thread::Builder::new()
            .name("era-call".into())
            .stack_size(WORKER_STACK)
            .spawn_scoped(scope, move || {
                let result =
                    std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| token.run(work)))
                        .unwrap_or_else(|payload| Err(internal_error(payload.as_ref())));
                let (flag, wake) = finished;
                *flag.lock().unwrap_or_else(|e| e.into_inner()) = true;
                wake.notify_all();
                result
            })
            .map_err(|e| PyRuntimeError::new_err(format!("era: cannot start a thread: {e}")))?;
        loop {
            let ready = py.allow_threads(|| {
                let (flag, wake) = finished;
                let guard = flag.lock().unwrap_or_else(|e| e.into_inner());
                let (guard, _) = wake
                    .wait_timeout_while(guard, SIGNAL_POLL, |done| !*done)
                    .unwrap_or_else(|e| e.into_inner());
                *guard
            });
            if ready {
                break;
            }
            if let Err(interrupt) = py.check_signals() {
                token.cancel();
                let _ = py.allow_threads(|| worker.join());
                return Err(interrupt);
            }
        }
        py.allow_threads(|| worker.join())
            .unwrap_or_else(|payload| Err(internal_error(payload.as_ref())))
    })
}

/// The threads of rayon's global pool, without starting it: `RAYON_NUM_THREADS` when it
/// is a positive number, else the cores available, at most [`era::parallel::MAX_THREADS`].
pub(crate) fn default_threads() -> usize {
    std::env::var("RAYON_NUM_THREADS")
        .ok()
        .and_then(|v| v.trim().parse::<usize>().ok())
        .filter(|&n| n > 0)
        .unwrap_or_else(|| std::thread::available_parallelism().map_or(1, |n| n.get()))
        .min(era::parallel::MAX_THREADS)
}

/// A panic's payload as the `RuntimeError` that reports it.
fn internal_error(payload: &(dyn std::any::Any + Send)) -> PyErr {
    let what = payload
        .downcast_ref::<&str>()
        .map(|s| s.to_string())
        .or_else(|| payload.downcast_ref::<String>().cloned())
        .unwrap_or_else(|| "unknown panic".into());
    PyRuntimeError::new_err(format!("era: internal error (please report it): {what}"))
}

/// A whole number given for a count or a seed, checked by the function that takes it
/// (`count`), so that a negative value is a `ValueError` naming the parameter. A value
/// of the wrong type (a float, a string, a bool) is a `TypeError`, as in numpy.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) struct Int(pub i128);

impl<'py> FromPyObject<'py> for Int {
    fn extract_bound(obj: &Bound<'py, PyAny>) -> PyResult<Self> {
        if obj.is_instance_of::<pyo3::types::PyBool>() {
            return Err(pyo3::exceptions::PyTypeError::new_err(
                "expected an integer, got a bool",
            ));
        }
        match obj.extract::<i128>() {
            Ok(v) => Ok(Int(v)),
            Err(e) if e.is_instance_of::<pyo3::exceptions::PyOverflowError>(obj.py()) => {
                // Beyond i128: as large as anything can be, for the limit checks.
                let negative = obj.lt(0).unwrap_or(false);
                Ok(Int(if negative { i128::MIN } else { i128::MAX }))
            }
            Err(e) => Err(e),
        }
    }
}

impl Int {
    /// The value as a count for `name`: `ValueError` when negative; values beyond `u64`
    /// saturate (the limit checks then refuse them with "more than 1.8e19").
    pub fn count(self, name: &str) -> PyResult<u64> {
        if self.0 < 0 {
            let shown = if self.0 == i128::MIN {
                "below -1.7e38".to_string()
            } else {
                self.0.to_string()
            };
            return value_error(format!("{name} {shown}: cannot be negative"));
        }
        Ok(u64::try_from(self.0).unwrap_or(u64::MAX))
    }

    /// [`Int::count`] as a `usize` (saturating on 32-bit targets).
    pub fn size(self, name: &str) -> PyResult<usize> {
        Ok(usize::try_from(self.count(name)?).unwrap_or(usize::MAX))
    }
}

/// Conversion copies above this many bytes are announced with a `UserWarning` (the
/// caller can pass the layout era reads in place and save the copy).
const COPY_WARNING_BYTES: u64 = 256 << 20;

/// `obj` as a C-contiguous numpy array of `dtype` (`"float64"` or `"complex128"`) with
/// one dimension per entry of `axes`, each axis checked against its resource limit and
/// the whole against `total`, before anything is converted or copied.
///
/// - An array that already has that dtype (native byte order) and is C-contiguous is
///   returned as it is: no copy. Anything else (another numeric dtype, the other byte
///   order, Fortran order, a strided or broadcast view, a list) goes through
///   `numpy.ascontiguousarray`, and a copy of more than [`COPY_WARNING_BYTES`] says so
///   with a `UserWarning`.
/// - Booleans, integers and floats are read as real numbers; complex values only where
///   `dtype` is complex. Anything else (complex for a real argument, objects, strings,
///   dates, records) is a `TypeError` naming `what`; a wrong number of dimensions, a
///   ragged list or a size above a limit is a `ValueError` naming it. NaN and inf are
///   left to the core, which refuses them with their place.
pub(crate) fn contiguous<'py, T: Element, D: numpy::ndarray::Dimension>(
    obj: &Bound<'py, PyAny>,
    dtype: &str,
    axes: &[&era::params::limits::Limit],
    total: Option<&era::params::limits::Limit>,
    what: &str,
    shape_words: &str,
) -> PyResult<Bound<'py, PyArray<T, D>>> {
    let py = obj.py();
    let np = py.import("numpy")?;
    let array = np
        .call_method1("asarray", (obj,))
        .map_err(|e| PyValueError::new_err(format!("{what}: cannot be read as an array: {e}")))?;
    let found_dtype = array.getattr("dtype")?;
    let kind: String = found_dtype.getattr("kind")?.extract()?;
    let complex = dtype == "complex128";
    let numeric = matches!(kind.as_str(), "b" | "i" | "u" | "f") || (complex && kind == "c");
    if !numeric {
        let expected = if complex {
            "real or complex numbers"
        } else {
            "real numbers"
        };
        return Err(pyo3::exceptions::PyTypeError::new_err(format!(
            "{what}: expected an array of {expected}, got dtype {}",
            found_dtype.str()?
        )));
    }
    let ndim = axes.len();
    let shape: Vec<usize> = array.getattr("shape")?.extract()?;
    if shape.len() != ndim {
        return value_error(format!(
            "{what}: expected {ndim} dimension{} {shape_words}, got shape {}",
            if ndim == 1 { "" } else { "s" },
            array.getattr("shape")?.str()?
        ));
    }
    let limit_error = |e: era::params::limits::LimitError| PyValueError::new_err(e.to_string());
    for (k, (limit, &n)) in axes.iter().zip(&shape).enumerate() {
        limit
            .check(format!("{what} axis {k} {shape_words}"), n as u64)
            .map_err(limit_error)?;
    }
    if let Some(limit) = total {
        limit
            .check_product(
                format!("{what} {shape_words}"),
                &shape.iter().map(|&n| n as u64).collect::<Vec<_>>(),
            )
            .map_err(limit_error)?;
    }
    let kwargs = pyo3::types::PyDict::new(py);
    kwargs.set_item("dtype", dtype)?;
    let converted = np
        .call_method("ascontiguousarray", (&array,), Some(&kwargs))
        .map_err(|e| PyValueError::new_err(format!("{what}: cannot be read as {dtype}: {e}")))?;
    if !converted.is(&array) {
        let bytes: u64 = converted.getattr("nbytes")?.extract()?;
        if bytes > COPY_WARNING_BYTES {
            let warnings = py.import("warnings")?;
            warnings.call_method1(
                "warn",
                (
                    format!(
                        "{what}: a {} array of shape {} was copied to C-contiguous {dtype} ({:.0} MB); pass that layout to avoid the copy",
                        found_dtype.str()?,
                        array.getattr("shape")?.str()?,
                        bytes as f64 / 1e6
                    ),
                    py.get_type::<pyo3::exceptions::PyUserWarning>(),
                    3,
                ),
            )?;
        }
    }
    converted
        .downcast_into::<PyArray<T, D>>()
        .map_err(|e| PyValueError::new_err(format!("{what}: {e}")))
}

/// The argument `frequency_hz`, shape (lines,), as [`contiguous`] reads it.
pub(crate) fn frequency_lines<'py>(
    frequency_hz: &Bound<'py, PyAny>,
) -> PyResult<Bound<'py, PyArray1<f64>>> {
    contiguous(
        frequency_hz,
        "float64",
        &[&era::params::limits::LINES],
        None,
        "frequency_hz",
        "(lines,)",
    )
}

/// The argument `data`, a time-history block of shape (channels, samples), as
/// [`contiguous`] reads it (in place when it is C-contiguous float64).
pub(crate) fn time_block<'py>(
    data: &Bound<'py, PyAny>,
) -> PyResult<Bound<'py, PyArray<f64, numpy::ndarray::Ix2>>> {
    contiguous(
        data,
        "float64",
        &[
            &era::params::limits::CHANNELS,
            &era::params::limits::SAMPLES,
        ],
        None,
        "data",
        "(channels, samples)",
    )
}

/// A 1-D float64 array of `values` (moved, not copied).
pub(crate) fn vector<'py, T: Element>(py: Python<'py>, values: Vec<T>) -> Bound<'py, PyArray1<T>> {
    PyArray1::from_vec(py, values)
}

/// Marks a numpy array read-only (arrays that mirror immutable Rust data).
pub(crate) fn read_only<T: Element, D: numpy::ndarray::Dimension>(
    array: &Bound<'_, PyArray<T, D>>,
) -> PyResult<()> {
    array.getattr("flags")?.setattr("writeable", false)?;
    Ok(())
}

/// The native module, imported by `python/era/__init__.py`.
#[pymodule]
fn _era(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    m.add_class::<frf::PyFrfData>()?;
    m.add_class::<model::PyIdentification>()?;
    m.add_class::<model::PyMode>()?;
    m.add_function(wrap_pyfunction!(frf::read_frf, m)?)?;
    m.add_function(wrap_pyfunction!(frf::write_frf, m)?)?;
    m.add_function(wrap_pyfunction!(frf::estimate_frf, m)?)?;
    m.add_function(wrap_pyfunction!(frf::read_time, m)?)?;
    m.add_function(wrap_pyfunction!(geometry::read_geometry, m)?)?;
    m.add_function(wrap_pyfunction!(frf::simulate_truth_model, m)?)?;
    m.add_function(wrap_pyfunction!(frf::simulate_modal, m)?)?;
    m.add_function(wrap_pyfunction!(model::identify, m)?)?;
    m.add_function(wrap_pyfunction!(time::identify_time, m)?)?;
    m.add_function(wrap_pyfunction!(oma::oma_py, m)?)?;
    m.add_function(wrap_pyfunction!(friction::friction_estimate, m)?)?;
    Ok(())
}
