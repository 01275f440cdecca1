//! `era frf`: FRFs and coherence from time histories ([`crate::input::time`]), written
//! with their coherence by [`crate::output::estimate`].

use crate::config::Frf;
use crate::input::shape_line;
use crate::input::time::estimate_from_time;
use crate::output::report::{finish_output, Human};
use serde_json::json;
use std::time::Instant;

/// `era frf`.
pub fn run(a: &Frf) -> anyhow::Result<()> {
    let settings = a.settings;
    let human = Human::new(&settings);
    // Refuse a bad --out before reading anything.
    let set = crate::output::estimate::prepare_estimate(&a.out, a.binary)?;
    let mut found = estimate_from_time(
        &a.files, &a.inputs, &a.outputs, &a.welch, a.quantity, false, &settings,
    )?;
    // Time files seldom say their units; --units writes them into the FRF file, where
    // identify, plot and the report find them.
    crate::input::set_units(&mut found.input, a.units);
    human.print(&format!(
        "era frf {}\n{}  FRFs: {}\n",
        a.files
            .iter()
            .map(|p| p.display().to_string())
            .collect::<Vec<_>>()
            .join(" "),
        found.summary,
        shape_line(&found.input.file.frf)
    ));
    let clock = Instant::now();
    let coherence = crate::output::estimate::write_estimate(
        set,
        &a.out,
        &found.input.file,
        &found.estimate,
        a.binary,
    )?;
    let write_s = clock.elapsed().as_secs_f64();
    human.print(&format!(
        "wrote {} and {}\n",
        a.out.display(),
        coherence.display()
    ));
    let mut out = found.json.clone();
    out["output"] = json!(a.out);
    out["coherence_file"] = json!(coherence);
    finish_output(
        &human,
        &settings,
        out,
        &[
            ("read", found.timings.0),
            ("estimate", found.timings.1),
            ("write", write_s),
        ],
    )
}
