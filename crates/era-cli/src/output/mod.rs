//! Everything a run writes: the `--out` folder as one [`OutputSet`] (every file staged
//! and committed together, `era_io::atomic`), the names of the files, what went into a
//! run ([`RunInput`]), the bundle of an identification ([`identification`]), the figures
//! ([`figures`], drawn by era-plot) and the terminal ([`report`], [`progress`]).

pub mod batch;
pub mod compare;
pub mod demo;
pub mod estimate;
pub mod experiment;
pub mod figures;
pub mod fleet;
pub mod friction;
pub mod geometry;
pub mod identification;
pub mod identify;
pub mod oma;
pub mod plot;
pub mod progress;
pub mod refine;
pub mod report;
pub mod shapes;
pub mod simulate;
pub mod track;

use anyhow::Context;
use era::Quantity;
use era_io::atomic::OutputSet;
use era_io::uff::ChannelTable;
use era_plot::report::{ChannelRow, InputSection};
use era_plot::{FrfUnits, PhaseView};
use std::path::Path;

/// Coherence the input carries (`identify --from-time` estimates it), for the report.
pub struct InputCoherence {
    /// The lines, Hz.
    pub frequency_hz: Vec<f64>,
    /// One (title, values) per curve.
    pub curves: Vec<(String, Vec<f64>)>,
    /// The figure's title.
    pub title: String,
    /// What the curves are.
    pub caption: String,
}

impl InputCoherence {
    /// The multiple coherence of each output of an estimate (with one input, its
    /// ordinary coherence): the share of the output's power the inputs explain.
    pub fn multiple(estimate: &era::estimate::FrfEstimate) -> Self {
        let q = estimate.frf.outputs();
        InputCoherence {
            frequency_hz: estimate.frf.frequency_hz().to_vec(),
            curves: (0..q)
                .map(|i| (format!("Y{}", i + 1), estimate.multiple(i).to_vec()))
                .collect(),
            title: "Multiple coherence of each output".into(),
            caption: format!(
                "Multiple coherence of each output with the {} input(s), from the Welch estimate: the part of the output's power the inputs explain (1 = all). Low coherence marks lines where noise, leakage or unmeasured inputs dominate; the FRF is less certain there.",
                estimate.frf.inputs()
            ),
        }
    }
}

impl InputCoherence {
    /// The coherence file `era frf` (and `simulate experiment`) writes beside an FRF
    /// file (`NAME.coherence.csv`), when there is one: the multiple coherence of each
    /// output (`mcoh<i>` columns), or else the ordinary coherence of each pair
    /// (`coh<i>_<j>`). `Ok(None)` without such a file; `Err` (a note for the report)
    /// when it does not fit `frf`: other lines, other outputs, unreadable values.
    pub fn companion(frf_path: &Path, frf: &era::FrfData) -> Result<Option<Self>, String> {
        let path = crate::output::coherence_path(frf_path);
        if !path.is_file() {
            return Ok(None);
        }
        let name = path.display().to_string();
        let bytes = era_io::input::read_input(&path).map_err(|e| format!("{name}: {e}"))?;
        let text = std::str::from_utf8(&bytes).map_err(|_| format!("{name}: not UTF-8 text"))?;
        let mut rows = text
            .lines()
            .filter(|l| !l.starts_with('#') && !l.trim().is_empty());
        let header: Vec<&str> = rows
            .next()
            .ok_or_else(|| format!("{name}: no header"))?
            .split(',')
            .map(str::trim)
            .collect();
        let (q, p) = (frf.outputs(), frf.inputs());
        let find = |column: String| header.iter().position(|h| *h == column);
        let multiple: Option<Vec<usize>> = (1..=q).map(|i| find(format!("mcoh{i}"))).collect();
        let (columns, titles, caption) = match multiple {
            Some(c) => (
                c,
                (1..=q).map(|i| format!("Y{i}")).collect::<Vec<_>>(),
                "Multiple coherence of each output",
            ),
            None => {
                let ordinary: Option<Vec<usize>> = (1..=q)
                    .flat_map(|i| (1..=p).map(move |j| (i, j)))
                    .map(|(i, j)| find(format!("coh{i}_{j}")))
                    .collect();
                let c = ordinary.ok_or_else(|| {
                    format!("{name}: no mcoh<i> or coh<i>_<j> columns for {q} outputs x {p} inputs")
                })?;
                let titles = (1..=q)
                    .flat_map(|i| (1..=p).map(move |j| format!("Y{i} / F{j}")))
                    .collect();
                (c, titles, "Ordinary coherence of each pair")
            }
        };
        let mut frequency_hz = Vec::with_capacity(frf.lines());
        let mut values = vec![Vec::with_capacity(frf.lines()); columns.len()];
        for (k, row) in rows.enumerate() {
            let cells: Vec<&str> = row.split(',').map(str::trim).collect();
            let number = |c: usize| -> Result<f64, String> {
                cells
                    .get(c)
                    .and_then(|v| v.parse::<f64>().ok())
                    .filter(|v| v.is_finite())
                    .ok_or_else(|| {
                        format!(
                            "{name}: data row {}: column {} is not a number",
                            k + 1,
                            c + 1
                        )
                    })
            };
            frequency_hz.push(number(0)?);
            for (curve, &c) in values.iter_mut().zip(&columns) {
                curve.push(number(c)?);
            }
        }
        let f = frf.frequency_hz();
        if frequency_hz.len() != f.len()
            || frequency_hz
                .iter()
                .zip(f)
                .any(|(a, b)| (a - b).abs() > 1e-6 * (1.0 + b.abs()))
        {
            return Err(format!(
                "{name}: {} lines that are not the FRF file's {} lines; not shown",
                frequency_hz.len(),
                f.len()
            ));
        }
        Ok(Some(InputCoherence {
            frequency_hz,
            curves: titles.into_iter().zip(values).collect(),
            title: caption.to_string(),
            caption: format!("{caption}, from {name} (the estimate beside the FRF file): 1 where the inputs explain all of the output's power; low coherence marks lines where noise, leakage or unmeasured inputs dominate, and the FRF is less certain there."),
        }))
    }
}

/// `frf.csv` → `frf.coherence.csv`.
pub fn coherence_path(out: &Path) -> std::path::PathBuf {
    let stem = out
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_else(|| "frf".into());
    out.with_file_name(format!("{stem}.coherence.csv"))
}

/// What went into a run, as the report and the figures need it: the input section,
/// the FRFs' quantity and units as read, the channel table, the coherence and how to
/// draw the phase.
pub struct RunInput {
    /// File, format, units, channel table, command line, version and date.
    pub section: InputSection,
    /// The quantity of the FRFs as read (before integrations).
    pub quantity: Quantity,
    /// Their units as read.
    pub units: FrfUnits,
    /// Nodes and directions of the outputs and inputs, when known.
    pub channels: Option<ChannelTable>,
    /// Coherence, when the input carries it.
    pub coherence: Option<InputCoherence>,
    /// Phase view of the figures.
    pub phase: PhaseView,
    /// The pairs overlaid one by one (`--pairs`).
    pub pairs: era_plot::PairSelection,
    /// The FRFs and options of a fixed-order ERA run, from which the singular-value
    /// figure computes the values past the order that the run did not
    /// ([`era::identify::hankel_singular_values`]).
    pub hankel: Option<(era::FrfData, era::EraOptions)>,
    /// The test geometry (`--geometry`), written into modes.uff.
    pub geometry: Option<era_io::geometry::Geometry>,
}

impl RunInput {
    /// An FRF file as read by [`crate::input::read_frf_with`].
    pub fn from_file(path: &Path, input: &crate::input::InputFrf) -> Self {
        let file = &input.file;
        let units = FrfUnits::from_metadata(&file.metadata);
        let notes = file
            .metadata
            .get("notes")
            .map(|n| n.split(" | ").map(str::to_string).collect())
            .unwrap_or_default();
        let quantity = file.frf.quantity();
        let mut notes: Vec<String> = notes;
        let coherence = InputCoherence::companion(path, &file.frf).unwrap_or_else(|e| {
            notes.push(format!("coherence file ignored: {e}"));
            None
        });
        RunInput {
            section: InputSection {
                file: path.display().to_string(),
                format: input.format.name().to_string(),
                quantity: format!("{}{}", quantity.name(), input.note),
                units: units.label(),
                channels: file.channels.as_ref().map(channel_rows).unwrap_or_default(),
                notes,
                ..stamped()
            },
            quantity,
            units,
            channels: file.channels.clone(),
            coherence,
            phase: PhaseView::Wrapped,
            pairs: era_plot::PairSelection::All,
            hankel: None,
            geometry: None,
        }
    }

    /// A synthetic set (the demo's truth model), its description, quantity and units.
    pub fn synthetic(description: &str, quantity: Quantity, units: FrfUnits) -> Self {
        RunInput {
            section: InputSection {
                file: description.to_string(),
                format: "synthetic (simulated in era)".into(),
                quantity: quantity.name().into(),
                units: units.label(),
                ..stamped()
            },
            quantity,
            units,
            channels: None,
            coherence: None,
            phase: PhaseView::Wrapped,
            pairs: era_plot::PairSelection::All,
            hankel: None,
            geometry: None,
        }
    }
}

/// The report's channel table rows of `table`.
pub fn channel_rows(table: &ChannelTable) -> Vec<ChannelRow> {
    let rows = |role: &'static str, channels: &[era_io::uff::Channel]| {
        channels
            .iter()
            .enumerate()
            .map(move |(k, c)| ChannelRow {
                role,
                index: k + 1,
                node: c.dof.node,
                direction: era_io::frf_file::direction_name(c.dof.direction),
                entity: c.entity_name().map(str::to_string),
            })
            .collect::<Vec<_>>()
    };
    let mut out = rows("output", &table.outputs);
    out.extend(rows("input", &table.inputs));
    out
}

/// An [`InputSection`] with what every run fills the same way: the command line,
/// the era version and the date.
fn stamped() -> InputSection {
    InputSection {
        command_line: command_line(),
        version: env!("CARGO_PKG_VERSION").to_string(),
        date: utc_now(),
        ..InputSection::default()
    }
}

/// The command line as typed, arguments with spaces quoted.
fn command_line() -> String {
    std::env::args_os()
        .map(|a| {
            let a = a.to_string_lossy().into_owned();
            if a.is_empty() || a.contains([' ', '\t', '"', '\'']) {
                format!("'{}'", a.replace('\'', "'\\''"))
            } else {
                a
            }
        })
        .collect::<Vec<_>>()
        .join(" ")
}

/// The time now, UTC, as `2026-11-23 05:04:07 UTC`.
pub fn utc_now() -> String {
    let seconds = std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map_or(0, |d| d.as_secs());
    utc_string(seconds)
}

/// Seconds since 1970-01-01 as a UTC date and time. The days become a civil date by
/// the proleptic Gregorian calendar (H. Hinnant's `civil_from_days`), written out here
/// so that no date crate is needed for one line of the report.
pub fn utc_string(seconds: u64) -> String {
    let days = (seconds / 86_400) as i64;
    let rest = seconds % 86_400;
    let z = days + 719_468;
    let era = z.div_euclid(146_097);
    let doe = z - era * 146_097;
    let yoe = (doe - doe / 1460 + doe / 36_524 - doe / 146_096) / 365;
    let doy = doe - (365 * yoe + yoe / 4 - yoe / 100);
    let mp = (5 * doy + 2) / 153;
    let day = doy - (153 * mp + 2) / 5 + 1;
    let month = if mp < 10 { mp + 3 } else { mp - 9 };
    let year = yoe + era * 400 + i64::from(month <= 2);
    format!(
        "{year:04}-{month:02}-{day:02} {:02}:{:02}:{:02} UTC",
        rest / 3600,
        rest / 60 % 60,
        rest % 60
    )
}

/// Creates `--out DIR` and opens the run's [`OutputSet`] there (a private staging
/// folder), before any long work: a folder that cannot take files is refused now.
pub fn prepare_out_dir(dir: &Path) -> anyhow::Result<OutputSet> {
    std::fs::create_dir_all(dir).map_err(|e| {
        crate::error::UsageError(format!(
            "--out {}: cannot create the folder: {e}",
            dir.display()
        ))
    })?;
    OutputSet::new(dir).map_err(|e| {
        crate::error::UsageError(format!("--out {}: cannot write there: {e}", dir.display())).into()
    })
}

/// Stages the output `name` of `set` and runs `write` on its staged path; an error
/// names the output's final place.
pub fn write_output(
    set: &mut OutputSet,
    name: impl AsRef<Path>,
    write: impl FnOnce(&Path) -> anyhow::Result<()>,
) -> anyhow::Result<()> {
    let name = name.as_ref();
    let staged = set.stage(name)?;
    write(&staged).with_context(|| format!("writing {}", set.target(name).display()))
}

/// The file name of an output file given on the command line, for [`OutputSet::stage`].
pub fn output_name<'a>(flag: &str, path: &'a Path) -> anyhow::Result<&'a std::ffi::OsStr> {
    path.file_name().ok_or_else(|| {
        crate::error::UsageError(format!("{flag} {}: not a file name", path.display())).into()
    })
}

/// Per-pair relative fit error as an outputs × inputs grid (up to 64 pairs).
pub fn pair_fit_table(fit: &era::pipeline::fit::FitReport, q: usize, p: usize) -> String {
    use std::fmt::Write as _;
    if q * p > 64 {
        return format!("  per-pair fit: {} pairs, see fit.json (--out)\n", q * p);
    }
    let mut s = String::from(
        "relative fit error per pair (rows: outputs, columns: inputs; * collocated)\n",
    );
    let _ = write!(s, "{:>8}", "");
    for j in 1..=p {
        let _ = write!(s, " {:>10}", format!("in {j}"));
    }
    s.push('\n');
    for i in 0..q {
        let _ = write!(s, "{:>8}", format!("out {}", i + 1));
        for j in 0..p {
            match fit.pairs.iter().find(|f| f.output == i && f.input == j) {
                Some(f) => {
                    let mark = if f.collocated { "*" } else { " " };
                    let _ = write!(s, " {:>9.3e}{mark}", f.relative_error);
                }
                None => {
                    let _ = write!(s, " {:>10}", "-");
                }
            }
        }
        s.push('\n');
    }
    s
}

/// What an identifying verb (`identify`, `oma`) hands back besides its files: the JSON
/// it prints with `--json` and the name of each output channel (the entries of a shape),
/// for `era batch`'s tables.
pub struct Done {
    /// model.json as written (and printed with `--json`).
    pub model: era_io::model_json::ModelJson,
    /// One name per output channel: the file's channel name, else its 1-based number.
    pub channels: Vec<String>,
}
