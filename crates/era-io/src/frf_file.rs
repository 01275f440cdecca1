//! The types every FRF format shares: [`FrfFile`] (data, metadata, channel table), the
//! [`ChannelTable`] of node/direction [`Dof`]s, and the channel-table metadata lines a
//! CSV carries (`# output_1: node 12 +Z`), with what every reader takes
//! ([`ReadOptions`]) and says ([`time_hint`]). Of this crate only the error and the text
//! helpers are imported here, so every format can use these without a cycle.

use era::{FrfData, Quantity};
use std::collections::BTreeMap;
use std::path::Path;

/// What a reader needs beyond the path.
#[derive(Debug, Clone)]
pub struct ReadOptions {
    /// Tag for files that do not say what they measure.
    pub default_quantity: Quantity,
    /// How many of a MAT `FRF` matrix's columns are outputs, when the file does not say.
    pub outputs: Option<usize>,
    /// The MAT variable holding the frequencies (Hz), when not `FreqV`.
    pub frequency_variable: Option<String>,
}

impl Default for ReadOptions {
    fn default() -> Self {
        ReadOptions {
            default_quantity: Quantity::Acceleration,
            outputs: None,
            frequency_variable: None,
        }
    }
}

/// An FRF file's data and metadata.
#[derive(Debug, Clone)]
pub struct FrfFile {
    /// The FRFs.
    pub frf: FrfData,
    /// Whether the file said what quantity it holds (otherwise the default was used).
    pub quantity_given: bool,
    /// Every `# key: value` line, keys lower-case.
    pub metadata: BTreeMap<String, String>,
    /// Node and direction of each output and input, when the file says.
    pub channels: Option<ChannelTable>,
}

/// A node and direction (records 6): the place a function was measured.
#[derive(Debug, Clone, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct Dof {
    /// Node number.
    pub node: i64,
    /// 0 scalar, ±1..±3 translation X, Y, Z, ±4..±6 rotation about X, Y, Z.
    pub direction: i64,
}

impl std::fmt::Display for Dof {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{}:{}", self.node, direction_name(self.direction))
    }
}

/// `+X`, `-Z`, `+RY`, `S` (scalar) or the number itself when out of range.
pub fn direction_name(direction: i64) -> String {
    let sign = if direction < 0 { "-" } else { "+" };
    match direction.abs() {
        0 => "S".into(),
        1 => format!("{sign}X"),
        2 => format!("{sign}Y"),
        3 => format!("{sign}Z"),
        4 => format!("{sign}RX"),
        5 => format!("{sign}RY"),
        6 => format!("{sign}RZ"),
        _ => direction.to_string(),
    }
}

/// A channel of an FRF matrix: the DOF and entity name it came from.
#[derive(Debug, Clone, PartialEq)]
pub struct Channel {
    /// Node and direction.
    pub dof: Dof,
    /// Entity name (`NONE` when unused).
    pub entity: String,
}

impl Channel {
    /// The entity name, unless blank or `NONE`.
    pub fn entity_name(&self) -> Option<&str> {
        (!self.entity.is_empty() && self.entity != "NONE").then_some(self.entity.as_str())
    }
}

/// Which DOF each output and input of an FRF matrix is.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct ChannelTable {
    /// Outputs (response DOFs), in matrix order.
    pub outputs: Vec<Channel>,
    /// Inputs (reference DOFs), in matrix order.
    pub inputs: Vec<Channel>,
}

impl ChannelTable {
    /// Outputs at nodes 1..q and inputs at nodes 1001..1000+p, all `+Z`: the
    /// numbering `era` uses when a file does not say.
    pub fn numbered(outputs: usize, inputs: usize) -> Self {
        let ch = |node: usize| Channel {
            dof: Dof {
                node: node as i64,
                direction: 3,
            },
            entity: "NONE".into(),
        };
        ChannelTable {
            outputs: (1..=outputs).map(ch).collect(),
            inputs: (1001..1001 + inputs).map(ch).collect(),
        }
    }

    /// The table as text lines: `output 1 = node 12 +Z (entity)`.
    pub fn describe(&self) -> Vec<String> {
        let row = |kind: &str, k: usize, c: &Channel| {
            let entity = c
                .entity_name()
                .map(|e| format!(" ({e})"))
                .unwrap_or_default();
            format!(
                "{kind} {} = node {} {}{entity}",
                k + 1,
                c.dof.node,
                direction_name(c.dof.direction)
            )
        };
        self.outputs
            .iter()
            .enumerate()
            .map(|(k, c)| row("output", k, c))
            .chain(
                self.inputs
                    .iter()
                    .enumerate()
                    .map(|(k, c)| row("input", k, c)),
            )
            .collect()
    }
}

/// The first few items joined with "; ", then how many more.
pub fn listed(items: &[String]) -> String {
    const SHOWN: usize = 8;
    let mut s = items
        .iter()
        .take(SHOWN)
        .cloned()
        .collect::<Vec<_>>()
        .join("; ");
    if items.len() > SHOWN {
        s.push_str(&format!("; … and {} more", items.len() - SHOWN));
    }
    s
}

/// `output_1: node 12 +Z` metadata lines for a channel table.
pub fn channel_metadata(table: &ChannelTable) -> Vec<(String, String)> {
    let line = |c: &Channel| {
        let entity = c.entity_name().map(|e| format!(" {e}")).unwrap_or_default();
        format!(
            "node {} {}{entity}",
            c.dof.node,
            direction_name(c.dof.direction)
        )
    };
    let outputs = table
        .outputs
        .iter()
        .enumerate()
        .map(|(k, c)| (format!("output_{}", k + 1), line(c)));
    let inputs = table
        .inputs
        .iter()
        .enumerate()
        .map(|(k, c)| (format!("input_{}", k + 1), line(c)));
    outputs.chain(inputs).collect()
}

/// A direction as written in a channel table (`+X`, `-Z`, `Y`, `RZ`, `S`, or its number)
/// as its UFF number; `None` when it is none of these.
pub fn parse_direction(text: &str) -> Option<i64> {
    let t = text.to_ascii_uppercase();
    if t == "S" {
        return Some(0);
    }
    let (sign, rest) = match t.as_bytes().first()? {
        b'+' => (1, &t[1..]),
        b'-' => (-1, &t[1..]),
        _ => (1, t.as_str()),
    };
    let magnitude = match rest {
        "X" => 1,
        "Y" => 2,
        "Z" => 3,
        "RX" => 4,
        "RY" => 5,
        "RZ" => 6,
        other => return other.parse::<i64>().ok().map(|d| d * sign),
    };
    Some(sign * magnitude)
}

fn parse_channel(text: &str) -> Option<Channel> {
    let mut words = text.split_whitespace();
    if words.next()? != "node" {
        return None;
    }
    let node = words.next()?.parse::<i64>().ok()?;
    let direction = parse_direction(words.next()?)?;
    let entity = words.collect::<Vec<_>>().join(" ");
    Some(Channel {
        dof: Dof { node, direction },
        entity: if entity.is_empty() {
            "NONE".into()
        } else {
            entity
        },
    })
}

/// The channel table from `output_k`/`input_k` metadata, when complete for `q × p`.
pub fn channels_from_metadata(
    metadata: &BTreeMap<String, String>,
    outputs: usize,
    inputs: usize,
) -> Option<ChannelTable> {
    let take = |kind: &str, n: usize| -> Option<Vec<Channel>> {
        (1..=n)
            .map(|k| parse_channel(metadata.get(&format!("{kind}_{k}"))?))
            .collect()
    };
    Some(ChannelTable {
        outputs: take("output", outputs)?,
        inputs: take("input", inputs)?,
    })
}

/// Lines that start above 0 Hz, made to start at 0 Hz.
///
/// ERA reads the FRF as the DFT of the Markov sequence, `H(f_k) = Σ_n Y_n e^{−2πi k n / N}`
/// with `f_k = k Δf` for `k = 0, 1, …` (docs/design.md §1): the inverse FFT needs every line
/// from `k = 0`. Analysers often leave the lowest lines out (`f_0 = n₀ Δf`, `n₀ ≥ 1`);
/// when `n₀` is a whole number those lines are added as zeros, which is what the thesis
/// does with the lines it cannot trust (`nz`, the leading lines set to zero). A start
/// that is not a whole number of increments lies on another grid and is refused, with
/// the remedy: no line can be added without resampling.
#[derive(Debug, Clone, PartialEq)]
pub struct ZeroStart {
    /// Zero lines added before the file's first line.
    pub added: usize,
    /// The file's first line, Hz.
    pub first_hz: f64,
    /// The added lines `k Δf`, then the file's own.
    pub frequency_hz: Vec<f64>,
}

impl ZeroStart {
    /// The note a summary prints: which lines were added.
    pub fn note(&self) -> String {
        format!(
            "the lines start at {} Hz; the {} lines below were added as zeros (ERA needs lines from 0 Hz)",
            self.first_hz, self.added
        )
    }

    /// `values` (pair-major: pair `s`, line `k` at `s · lines + k`) with the added
    /// zero lines in front of each pair.
    pub fn pad_values(&self, values: &[era::Complex64], pairs: usize) -> Vec<era::Complex64> {
        if self.added == 0 {
            return values.to_vec();
        }
        let old = values.len() / pairs.max(1);
        let new = old + self.added;
        let mut out = vec![era::Complex64::new(0.0, 0.0); pairs * new];
        for s in 0..pairs {
            out[s * new + self.added..(s + 1) * new]
                .copy_from_slice(&values[s * old..(s + 1) * old]);
        }
        out
    }
}

/// Decides whether `frequency_hz` (the file's lines) can be padded to start at 0 Hz
/// (see [`ZeroStart`]), judging by the first line and the step to the second; `None`
/// when they already start at 0 Hz or there is no step to judge by (the frequency checks
/// of [`era::FrfData`] then speak, and they also check every later line). `pairs` sizes
/// the padded set, checked against [`era::params::limits`] before anything is allocated (a file
/// starting at 10⁷ Hz would ask for millions of lines).
///
/// # Errors
/// [`crate::IoError`] naming the file and `location` for a start that is not a whole
/// number of increments (with the remedy), or a padded size over a limit.
pub fn zero_start(
    path: &std::path::Path,
    location: &str,
    frequency_hz: &[f64],
    pairs: usize,
) -> Result<Option<ZeroStart>, crate::IoError> {
    let (first_hz, spacing_hz) = match frequency_hz {
        [f0, f1, ..] => (*f0, f1 - f0),
        _ => return Ok(None),
    };
    if first_hz == 0.0 || !first_hz.is_finite() || !(spacing_hz > 0.0 && spacing_hz.is_finite()) {
        return Ok(None);
    }
    let increments = first_hz / spacing_hz;
    let whole = increments.round();
    if first_hz < 0.0 || (increments - whole).abs() > 1e-6 || whole < 1.0 {
        return Err(crate::IoError::format(
            path,
            location,
            format!(
                "the first line is {first_hz} Hz, {increments:.4} increments of the {spacing_hz} Hz spacing: ERA needs lines k x {spacing_hz} Hz from 0 Hz, and this start is not on that grid; export the FRFs from 0 Hz, or resample them onto whole multiples of the spacing"
            ),
        ));
    }
    // At most 2^53: beyond, the count is not exact in f64 (and far past any limit).
    let added = whole.min(9.0e15) as u64;
    let padded = added.saturating_add(frequency_hz.len() as u64);
    era::params::limits::LINES
        .check(
            format!("the lines start at {first_hz} Hz (line {added} at {spacing_hz} Hz spacing); padding to 0 Hz"),
            padded,
        )
        .map_err(|e| crate::IoError::limit(path, e))?;
    era::params::limits::VALUES
        .check_product("FRF values after padding to 0 Hz", &[padded, pairs as u64])
        .map_err(|e| crate::IoError::limit(path, e))?;
    let added = added as usize;
    let mut padded_hz: Vec<f64> = (0..added).map(|k| k as f64 * spacing_hz).collect();
    padded_hz.extend_from_slice(frequency_hz);
    Ok(Some(ZeroStart {
        added,
        first_hz,
        frequency_hz: padded_hz,
    }))
}

/// Adds a note to a file's `notes` metadata (notes are joined by ` | `, as the CLI
/// prints them one a line).
pub fn add_note(metadata: &mut BTreeMap<String, String>, note: String) {
    metadata
        .entry("notes".to_string())
        .and_modify(|n| {
            n.push_str(" | ");
            n.push_str(&note);
        })
        .or_insert(note);
}

/// What to do with the time histories in `path`, given where FRFs are expected.
pub fn time_hint(path: &Path) -> String {
    let f = crate::text::escaped_message(&path.display().to_string());
    format!(
        "estimate the FRFs with `era frf {f} --inputs CHANNELS --outputs CHANNELS --out frf.csv`, or identify from the time histories directly with `era identify --from-time {f} --inputs CHANNELS --outputs CHANNELS`"
    )
}
