//! `era info FILE`: what an FRF file holds ([`crate::input::info`]).

use crate::config::Info;
use crate::output::report::{finish_output, Human};
use era_io::format::FrfFormat;
use std::time::Instant;

/// `era info`.
pub fn run(a: &Info) -> anyhow::Result<()> {
    let settings = a.settings;
    let human = Human::new(&settings);
    let clock = Instant::now();
    // Read once: a pipe or `/dev/stdin` cannot be read a second time.
    // The file's errors name it: no "reading FILE" context to say it twice.
    let bytes = era_io::input::read_input(&a.file)?;
    let format = FrfFormat::detect_bytes(&bytes, &a.file)?;
    let (text, summary) = crate::input::info::describe(a, &bytes, format)?;
    human.print(&text);
    finish_output(
        &human,
        &settings,
        summary,
        &[("info", clock.elapsed().as_secs_f64())],
    )
}
