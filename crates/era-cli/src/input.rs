//! Reading an FRF source: any FRF file format (told apart by content), with the
//! quantity and layout notes the summaries print. `identify`, `plot`, `refine`, `info`
//! and `convert` read FRF files through here; time histories are read and estimated in
//! [`time`], `identify`'s source in [`source`], `batch`'s manifest in [`manifest`],
//! `compare`'s two sets in [`compare`] and `info`'s description of a file in [`info`].

pub mod compare;
pub mod fleet;
pub mod friction;
pub mod info;
pub mod manifest;
pub mod model;
pub mod oma;
pub mod source;
pub mod time;

use crate::args::{FrfReadArgs, UnitsArg};
use era::Quantity;
use era_io::format::{parse_frf_bytes, FrfFormat, ReadOptions};

/// An FRF file as `identify`, `plot` and `convert` see it.
pub struct InputFrf {
    /// The file, its quantity set by `--quantity` when given.
    pub file: era_io::csv::FrfFile,
    /// Format found.
    pub format: FrfFormat,
    /// Where the quantity came from, and the layout found: for the summary line.
    pub note: String,
}

/// The flags that say how to read an FRF file, beyond its name.
#[derive(Debug, Clone, Copy, Default)]
pub struct FrfFlags<'a> {
    /// `--quantity`: overrides the file's tag.
    pub quantity: Option<era::Quantity>,
    /// `--outputs`: the split of a MAT `FRF` matrix.
    pub outputs: Option<usize>,
    /// `--units`: override the file's units (the `response_unit` and `force_unit`
    /// metadata every writer and figure reads).
    pub units: Option<&'a UnitsArg>,
    /// `--freq-variable`: the MAT variable of the frequencies.
    pub frequency_variable: Option<&'a str>,
}

impl<'a> From<&'a FrfReadArgs> for FrfFlags<'a> {
    /// The flags of plot, convert and refine.
    fn from(a: &'a FrfReadArgs) -> Self {
        FrfFlags {
            quantity: a.quantity,
            outputs: a.outputs,
            units: a.facts.units.as_ref(),
            frequency_variable: a.facts.freq_variable.as_deref(),
        }
    }
}

/// Reads an FRF file in any format, told apart by content (the extension is a hint).
/// `--quantity` overrides the file's tag; with neither, acceleration is assumed.
pub fn read_frf_with(path: &std::path::Path, flags: &FrfFlags) -> anyhow::Result<InputFrf> {
    // The file's errors name it: no "reading FILE" context to say it twice.
    let bytes = era_io::input::read_input(path)?;
    read_frf_bytes(&bytes, path, flags)
}

/// [`read_frf_with`] on the bytes of a file already read once (`era info` looks at them
/// twice); `path` names them in messages.
pub fn read_frf_bytes(
    bytes: &[u8],
    path: &std::path::Path,
    flags: &FrfFlags,
) -> anyhow::Result<InputFrf> {
    let opts = ReadOptions {
        default_quantity: Quantity::Acceleration,
        outputs: flags.outputs,
        frequency_variable: flags.frequency_variable.map(str::to_string),
    };
    let (mut file, format) = parse_frf_bytes(bytes, path, &opts)?;
    let quantity = flags.quantity;
    let layout = file
        .metadata
        .get("layout")
        .map(|l| format!(" [{l}]"))
        .unwrap_or_else(|| format!(" [{}]", format.name()));
    let note = match quantity {
        Some(q) => {
            file.frf = file.frf.with_quantity(q);
            file.quantity_given = true;
            format!(" (from --quantity){layout}")
        }
        None if file.quantity_given => layout,
        None => format!(" (assumed: the file does not say; set --quantity){layout}"),
    };
    let mut input = InputFrf { file, format, note };
    set_units(&mut input, flags.units);
    Ok(input)
}

/// `--units` on a file read: sets `response_unit` and `force_unit`, noting what the file
/// said when it differs.
pub fn set_units(input: &mut InputFrf, units: Option<&UnitsArg>) {
    let Some(u) = units else { return };
    let meta = &mut input.file.metadata;
    let said = match (meta.get("response_unit"), meta.get("force_unit")) {
        (Some(r), Some(f)) if (r, f) != (&u.response, &u.force) => {
            format!("; the file says {r} / {f}")
        }
        _ => String::new(),
    };
    meta.insert("response_unit".into(), u.response.clone());
    meta.insert("force_unit".into(), u.force.clone());
    input.note.push_str(&format!(
        " (units {} / {} from --units{said})",
        u.response, u.force
    ));
}

/// `m/s^2 / N` from the metadata, `unit / unit` when the file does not say (never
/// imperial by assumption).
pub fn units_line(input: &InputFrf) -> String {
    let meta = &input.file.metadata;
    let unit = |k: &str| {
        meta.get(k)
            .filter(|u| !u.is_empty() && *u != "NONE")
            .cloned()
            .unwrap_or_else(|| "unit".into())
    };
    format!("{} / {}", unit("response_unit"), unit("force_unit"))
}

/// `8 outputs x 8 inputs, 801 lines, 0 .. 20 Hz at 0.025 Hz, acceleration`.
pub fn shape_line(frf: &era::FrfData) -> String {
    format!(
        "{} outputs x {} inputs, {} lines, 0 .. {} Hz at {} Hz, {}",
        frf.outputs(),
        frf.inputs(),
        frf.lines(),
        frf.frequency_hz()[frf.lines() - 1],
        frf.spacing_hz(),
        frf.quantity()
    )
}

/// The channel table and the notes of a file, as lines for the human summary.
pub fn describe_input(input: &InputFrf) -> String {
    let mut text = format!("  units: {}\n", units_line(input));
    if let Some(table) = &input.file.channels {
        text.push_str("  channels:\n");
        for line in table.describe() {
            text.push_str(&format!("    {line}\n"));
        }
    }
    if let Some(notes) = input.file.metadata.get("notes") {
        for n in notes.split(" | ") {
            text.push_str(&format!("  note: {n}\n"));
        }
    }
    text
}
