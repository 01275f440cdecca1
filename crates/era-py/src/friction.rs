//! `era.friction.estimate`: the Coulomb friction force of an actuator from one
//! free-decay velocity record (thesis §III.3, Eq. 3.12: `F_C = Δẏ k / (8π f_n)` per cycle,
//! from the straight-line drop of the velocity amplitudes), with the viscous
//! (exponential) fit beside it, as `era friction estimate` reports it.

use crate::{contiguous, guarded, value_error};
use era::params::Naming;
use numpy::ndarray::Ix1;
use numpy::PyArrayMethods;
use pyo3::prelude::*;

/// Friction estimate of one free-decay record: a dict with the CLI's JSON fields.
#[pyfunction]
#[pyo3(signature = (time_s, velocity, stiffness))]
pub fn friction_estimate<'py>(
    py: Python<'py>,
    time_s: &Bound<'py, PyAny>,
    velocity: &Bound<'py, PyAny>,
    stiffness: f64,
) -> PyResult<Bound<'py, PyAny>> {
    era::friction::check_stiffness(Naming::Keyword, stiffness).map_err(crate::era_error)?;
    let samples = [&era::params::limits::SAMPLES];
    let t = contiguous::<f64, Ix1>(time_s, "float64", &samples, None, "time_s", "(samples,)")?;
    let v = contiguous::<f64, Ix1>(
        velocity,
        "float64",
        &samples,
        None,
        "velocity",
        "(samples,)",
    )?;
    let (t, v) = (t.readonly(), v.readonly());
    let (t, v) = (t.as_slice()?, v.as_slice()?);
    let found = guarded(py, || {
        era::friction::estimate::estimate_velocity(t, v, stiffness)
            .map_err(|e| pyo3::exceptions::PyValueError::new_err(e.to_string()))
    })?;
    let mut map = era_io::decay_csv::estimate_json(&found, "velocity");
    map.insert("stiffness".into(), serde_json::json!(stiffness));
    let text = serde_json::to_string(&map).or_else(|e| value_error(e.to_string()))?;
    py.import("json")?.call_method1("loads", (text,))
}
