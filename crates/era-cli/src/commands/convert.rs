//! `era convert IN OUT`: the FRFs of a file in another format.

use crate::config::Convert;
use crate::input::{describe_input, read_frf_with, shape_line};
use crate::output::report::{finish_output, Human};
use anyhow::Context;
use era_io::format::{write_frf_file, FrfFormat};
use era_io::uff::UffWriteOptions;
use serde_json::json;
use std::time::Instant;

/// `era convert`.
pub fn run(a: &Convert) -> anyhow::Result<()> {
    let settings = a.settings;
    let human = Human::new(&settings);
    let target = FrfFormat::from_extension(&a.output).ok_or_else(|| {
        crate::error::UsageError(format!(
            "{}: cannot tell the output format from the extension: use .csv, .uff (or .unv) or .mat",
            a.output.display()
        ))
    })?;
    if (a.binary || a.single) && target != FrfFormat::Uff {
        return crate::error::usage(format!(
            "--binary and --single apply to UFF output, not to {}",
            a.output.display()
        ));
    }
    let clock = Instant::now();
    let input = read_frf_with(&a.input, &a.read)?;
    let read_s = clock.elapsed().as_secs_f64();
    let frf = &input.file.frf;
    let clock = Instant::now();
    let opts = UffWriteOptions {
        binary: a.binary,
        single: a.single,
    };
    write_frf_file(&a.output, &input.file, opts)
        .with_context(|| format!("writing {}", a.output.display()))?;
    let write_s = clock.elapsed().as_secs_f64();
    let kind = match (target, a.binary, a.single) {
        (FrfFormat::Uff, true, true) => "UFF 58b, single",
        (FrfFormat::Uff, true, false) => "UFF 58b, double",
        (FrfFormat::Uff, false, true) => "UFF 58 ASCII, single",
        (FrfFormat::Uff, false, false) => "UFF 58 ASCII, double",
        (f, _, _) => f.name(),
    };
    human.print(&format!(
        "era convert {} ({}) -> {} ({kind})\n  {}{}\n{}",
        a.input.display(),
        input.format.name(),
        a.output.display(),
        shape_line(frf),
        input.note,
        describe_input(&input),
    ));
    finish_output(
        &human,
        &settings,
        json!({
            "input": a.input, "input_format": input.format.name(),
            "output": a.output, "output_format": kind,
            "outputs": frf.outputs(), "inputs": frf.inputs(), "lines": frf.lines(),
            "spacing_hz": frf.spacing_hz(), "quantity": frf.quantity().name(),
        }),
        &[("read", read_s), ("write", write_s)],
    )
}
