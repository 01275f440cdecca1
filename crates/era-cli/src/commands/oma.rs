//! `era oma FILE...`: operational modal analysis. The time files are read by
//! [`crate::input::oma`], [`era::identify::oma::oma_observed`] does the rest through
//! [`crate::work::oma`]; the files, figures and report are [`crate::output::oma`]'s.

use crate::config::Oma;
use crate::output::oma::OmaRun;
use crate::output::prepare_out_dir;
use crate::output::report::Human;
use std::time::Instant;

/// `era oma`.
pub fn run(a: &Oma) -> anyhow::Result<super::Done> {
    let settings = a.settings;
    let human = Human::new(&settings);
    let outputs = a.out.as_deref().map(prepare_out_dir).transpose()?;
    // The geometry is read and checked before the records: a bad one costs no time.
    let geometry = crate::output::geometry::read(a.geometry.as_deref(), &human)?;
    let spinner = crate::output::progress::spinner(&settings);
    let clock = Instant::now();
    let records = crate::input::oma::read_records(a, &spinner)?;
    let read_s = clock.elapsed().as_secs_f64();
    let mut options = a.options.clone();
    options.sample_rate_hz = records.rate;
    options.references = records.references.clone();
    let found = crate::work::oma(a, &records, &options, spinner)?;
    let run = OmaRun {
        files: &a.files,
        records: &records,
        oma: &found,
        options: &options,
        auto: a.auto,
        geometry: geometry.as_ref(),
    };
    crate::output::oma::hand_on(a, outputs, &run, read_s, &human)
}
