//! Reading an FRF source: any FRF file format (told apart by content), with the
//! quantity and layout notes the summaries print. `identify`, `plot`, `refine`, `info`
//! and `convert` read through here; time histories go through `frf`.

use crate::args::QuantityArg;
use anyhow::Context;
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

/// Reads an FRF file in any format, told apart by content (the extension is a hint).
/// `--quantity` overrides the file's tag; with neither, acceleration is assumed.
pub fn read_frf(
    path: &std::path::Path,
    quantity: Option<QuantityArg>,
    outputs: Option<usize>,
) -> anyhow::Result<InputFrf> {
    let bytes =
        era_io::input::read_input(path).with_context(|| format!("reading {}", path.display()))?;
    read_frf_bytes(&bytes, path, quantity, outputs)
}

/// [`read_frf`] on the bytes of a file already read once (`era info` looks at them
/// twice); `path` names them in messages.
pub fn read_frf_bytes(
    bytes: &[u8],
    path: &std::path::Path,
    quantity: Option<QuantityArg>,
    outputs: Option<usize>,
) -> anyhow::Result<InputFrf> {
    let opts = ReadOptions {
        default_quantity: Quantity::Acceleration,
        outputs,
    };
    let (mut file, format) = parse_frf_bytes(bytes, path, &opts)
        .with_context(|| format!("reading {}", path.display()))?;
    let layout = file
        .metadata
        .get("layout")
        .map(|l| format!(" [{l}]"))
        .unwrap_or_else(|| format!(" [{}]", format.name()));
    let note = match quantity {
        Some(q) => {
            file.frf = file.frf.with_quantity(q.into());
            file.quantity_given = true;
            format!(" (from --quantity){layout}")
        }
        None if file.quantity_given => layout,
        None => format!(" (assumed: the file does not say; set --quantity){layout}"),
    };
    Ok(InputFrf { file, format, note })
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
    let mut text = String::new();
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
