//! A free-decay record read (`era_io::decay_csv`) and its friction estimated, for
//! `era friction estimate|tune`.

use anyhow::Context;
use era::friction::estimate::{estimate_displacement, estimate_velocity, DecayEstimate};
use era_io::decay_csv::read_decay_csv;
use std::path::Path;

pub fn estimate_file(path: &Path, stiffness: f64) -> anyhow::Result<(DecayEstimate, &'static str)> {
    let file = read_decay_csv(path)?;
    let result = match (&file.velocity, &file.displacement) {
        (Some(v), _) => estimate_velocity(&file.time_s, v, stiffness).map(|e| (e, "velocity")),
        (None, Some(x)) => {
            estimate_displacement(&file.time_s, x, stiffness).map(|e| (e, "displacement"))
        }
        (None, None) => unreachable!("the reader requires one of the columns"),
    };
    result.with_context(|| format!("{}", path.display()))
}
