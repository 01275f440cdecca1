//! From dataset-58 records to one FRF matrix with its channel table.

use super::*;
use crate::IoError;
use era::{Complex64, FrfData, Quantity};
use std::collections::{BTreeMap, HashMap};
use std::path::Path;

use crate::frf_file::FrfFile;
/// The quantity an axis's specific data type names (8, 11, 12), if any.
pub fn quantity_of(data_type: i64) -> Option<Quantity> {
    match data_type {
        8 => Some(Quantity::Displacement),
        11 => Some(Quantity::Velocity),
        12 => Some(Quantity::Acceleration),
        _ => None,
    }
}

/// How FRF records fill a matrix: the channel table (DOFs in order of first
/// appearance), the record of each output/input pair, and what is missing or repeated.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct FrfLayout {
    /// Outputs (response DOFs) and inputs (reference DOFs).
    pub table: ChannelTable,
    /// For pair `i·p + j`, the index (among the records given) of its record.
    pub slot: Vec<Option<usize>>,
    /// "output 2 (12:+Z) from input 1 (101:+Z)" for each pair without a record.
    pub missing: Vec<String>,
    /// One line per pair given more than once, with the record numbers.
    pub duplicates: Vec<String>,
}

impl FrfLayout {
    /// The layout of the given FRF records.
    pub fn of<'a>(records: impl Iterator<Item = &'a Function58>) -> Self {
        let records: Vec<&Function58> = records.collect();
        let mut table = ChannelTable::default();
        let mut out_index: HashMap<&Dof, usize> = HashMap::new();
        let mut in_index: HashMap<&Dof, usize> = HashMap::new();
        for f in &records {
            out_index.entry(&f.response).or_insert_with(|| {
                table.outputs.push(Channel {
                    dof: f.response.clone(),
                    entity: f.response_entity.clone(),
                });
                table.outputs.len() - 1
            });
            in_index.entry(&f.reference).or_insert_with(|| {
                table.inputs.push(Channel {
                    dof: f.reference.clone(),
                    entity: f.reference_entity.clone(),
                });
                table.inputs.len() - 1
            });
        }
        let (q, p) = (table.outputs.len(), table.inputs.len());
        let mut slot: Vec<Option<usize>> = vec![None; q * p];
        let mut duplicates = Vec::new();
        for (n, f) in records.iter().enumerate() {
            let s = out_index[&f.response] * p + in_index[&f.reference];
            match slot[s] {
                Some(first) => duplicates.push(format!(
                    "{} from {} in records {} and {}",
                    f.response, f.reference, records[first].record, f.record
                )),
                None => slot[s] = Some(n),
            }
        }
        let missing = slot
            .iter()
            .enumerate()
            .filter(|(_, s)| s.is_none())
            .map(|(s, _)| {
                format!(
                    "output {} ({}) from input {} ({})",
                    s / p + 1,
                    table.outputs[s / p].dof,
                    s % p + 1,
                    table.inputs[s % p].dof
                )
            })
            .collect();
        FrfLayout {
            table,
            slot,
            missing,
            duplicates,
        }
    }
}

/// Builds one FRF matrix from the FRF records of a file read with its data (see the
/// module doc), with its channel table. FRFs are tagged with the quantity of the
/// ordinate axis (8, 11, 12) when the records say, else `default_quantity`.
///
/// When the lines start above 0 Hz at a whole number of increments, the missing low
/// lines are added as zeros (ERA needs lines from 0 Hz) and a note says so.
///
/// # Errors
/// [`IoError`] naming the file and the records: no FRF records, unknown function
/// types, missing or duplicate pairs, abscissas that disagree, an uneven or
/// non-uniform abscissa, disagreeing quantities.
pub fn frf_from_uff(
    path: &Path,
    contents: &UffContents,
    default_quantity: Quantity,
) -> Result<FrfFile, IoError> {
    let fail = |m: String| IoError::format(path, "", m);
    let mut notes: Vec<String> = contents.notes.clone();
    let frfs = frf_records(path, contents, &mut notes)?;
    let (table, slot) = complete_pairs(path, &frfs)?;
    let (q, p) = (table.outputs.len(), table.inputs.len());
    let first = &frfs[0].0;
    let abscissa = common_abscissa(path, &frfs)?;
    let (quantity, quantity_given) = response_quantity(path, &frfs, default_quantity)?;
    // Lines from 0 Hz: a whole number of increments above is padded with zero lines
    // (as CSV and MAT files are), another start is refused with the remedy.
    let mut frequency_hz = abscissa;
    let mut pad = 0usize;
    let location = format!("record {}: ", first.record);
    // An uneven abscissa has no grid to pad on: the frequency checks refuse it below.
    let start = if first.even {
        crate::frf_file::zero_start(path, &location, &frequency_hz, q * p)?
    } else {
        None
    };
    if let Some(start) = start {
        notes.push(start.note());
        pad = start.added;
        frequency_hz = start.frequency_hz;
    }
    let lines = frequency_hz.len();
    let mut values = vec![Complex64::new(0.0, 0.0); q * p * lines];
    for (s, n) in slot.iter().enumerate() {
        let d = frfs[n.expect("every pair present")]
            .1
            .as_ref()
            .expect("read with data");
        values[s * lines + pad..(s + 1) * lines].copy_from_slice(&d.values);
    }
    let frf = FrfData::new(frequency_hz, q, p, values, quantity).map_err(|e| {
        let uneven = if first.even {
            ""
        } else {
            " (the records have an uneven abscissa)"
        };
        fail(format!(
            "records {}…: ERA needs uniformly spaced lines from 0 Hz{uneven}: {e}",
            first.record
        ))
    })?;
    let metadata = uff_metadata(first, frfs.len(), (q, p), &notes);
    Ok(FrfFile {
        frf,
        quantity_given,
        metadata,
        channels: Some(table),
    })
}

/// The FRF records of the file (function type 4), refusing unknown function types and a
/// file without FRFs; the records skipped (other functions, other datasets) go to `notes`.
fn frf_records<'a>(
    path: &Path,
    contents: &'a UffContents,
    notes: &mut Vec<String>,
) -> Result<Vec<&'a (Function58, Option<Data58>)>, IoError> {
    let fail = |m: String| IoError::format(path, "", m);
    let unknown: Vec<String> = contents
        .functions
        .iter()
        .filter(|(f, _)| function_type_name(f.function_type).is_none())
        .map(|(f, _)| format!("record {} has function type {}", f.record, f.function_type))
        .collect();
    if !unknown.is_empty() {
        return Err(fail(format!(
            "unknown function types (0-28 are defined): {}",
            listed(&unknown)
        )));
    }
    let frfs: Vec<&(Function58, Option<Data58>)> = contents
        .functions
        .iter()
        .filter(|(f, _)| f.function_type == FUNCTION_FRF)
        .collect();
    let others: BTreeMap<&str, usize> = contents
        .functions
        .iter()
        .filter(|(f, _)| f.function_type != FUNCTION_FRF)
        .fold(BTreeMap::new(), |mut m, (f, _)| {
            *m.entry(function_type_name(f.function_type).unwrap_or("?"))
                .or_insert(0) += 1;
            m
        });
    if frfs.is_empty() {
        let found = if others.is_empty() {
            "none of dataset 58".to_string()
        } else {
            others
                .iter()
                .map(|(k, n)| format!("{n} {k}"))
                .collect::<Vec<_>>()
                .join(", ")
        };
        return Err(fail(format!(
            "no FRF records (dataset 58, function type 4); the file has: {found}"
        )));
    }
    if !others.is_empty() {
        notes.push(format!(
            "skipped records that are not FRFs: {}",
            others
                .iter()
                .map(|(k, n)| format!("{n} {k}"))
                .collect::<Vec<_>>()
                .join(", ")
        ));
    }
    if !contents.skipped.is_empty() {
        notes.push(format!(
            "skipped records of other datasets: {}",
            contents
                .skipped
                .iter()
                .map(|(d, n)| format!("{n} of dataset {d}"))
                .collect::<Vec<_>>()
                .join(", ")
        ));
    }
    Ok(frfs)
}

/// The channel table and the record of each pair, refusing a pair given twice or missing.
fn complete_pairs(
    path: &Path,
    frfs: &[&(Function58, Option<Data58>)],
) -> Result<(ChannelTable, Vec<Option<usize>>), IoError> {
    let fail = |m: String| IoError::format(path, "", m);
    let layout = FrfLayout::of(frfs.iter().map(|r| &r.0));
    if !layout.duplicates.is_empty() {
        return Err(fail(format!(
            "duplicate FRF pairs: {}",
            listed(&layout.duplicates)
        )));
    }
    if !layout.missing.is_empty() {
        return Err(fail(format!(
            "missing FRF pairs ({} of {}): {}",
            layout.missing.len(),
            layout.table.outputs.len() * layout.table.inputs.len(),
            listed(&layout.missing)
        )));
    }
    let FrfLayout { table, slot, .. } = layout;
    Ok((table, slot))
}

/// The one abscissa every record shares (within 1e-9 of its largest value), in frequency.
fn common_abscissa(
    path: &Path,
    frfs: &[&(Function58, Option<Data58>)],
) -> Result<Vec<f64>, IoError> {
    let fail = |m: String| IoError::format(path, "", m);
    let (first, first_data) = frfs[0];
    let describe = |f: &Function58| {
        if f.even {
            format!(
                "{} points from {} step {}",
                f.points, f.abscissa_min, f.abscissa_inc
            )
        } else {
            format!("{} points, uneven abscissa", f.points)
        }
    };
    let data_of = |f: &Function58, d: &Option<Data58>| -> Result<Vec<f64>, IoError> {
        d.as_ref().map(|d| d.abscissa.clone()).ok_or_else(|| {
            fail(format!(
                "record {}: values were not read (header-only read)",
                f.record
            ))
        })
    };
    let abscissa = data_of(first, first_data)?;
    let scale = abscissa
        .iter()
        .fold(0.0f64, |m, x| m.max(x.abs()))
        .max(f64::MIN_POSITIVE);
    let mut mismatched = Vec::new();
    for (f, d) in frfs.iter().skip(1).map(|r| (&r.0, &r.1)) {
        let x = data_of(f, d)?;
        let same = x.len() == abscissa.len()
            && x.iter()
                .zip(&abscissa)
                .all(|(a, b)| (a - b).abs() <= 1e-9 * scale);
        if !same {
            mismatched.push(format!(
                "record {} ({} from {}): {}",
                f.record,
                f.response,
                f.reference,
                describe(f)
            ));
        }
    }
    if !mismatched.is_empty() {
        return Err(fail(format!(
            "abscissas disagree with record {} ({}): {}",
            first.record,
            describe(first),
            listed(&mismatched)
        )));
    }
    if let Some(f) = frfs
        .iter()
        .map(|r| &r.0)
        .find(|f| f.axes[0].data_type == 17)
    {
        return Err(fail(format!(
            "record {}: the abscissa is time (data type 17): FRFs need frequency",
            f.record
        )));
    }
    Ok(abscissa)
}

/// The response quantity the records' ordinate axes agree on, or `default_quantity` when
/// none says (and whether any did).
fn response_quantity(
    path: &Path,
    frfs: &[&(Function58, Option<Data58>)],
    default_quantity: Quantity,
) -> Result<(Quantity, bool), IoError> {
    let tagged: Vec<(usize, Quantity)> = frfs
        .iter()
        .filter_map(|r| quantity_of(r.0.axes[1].data_type).map(|q| (r.0.record, q)))
        .collect();
    let quantity = match tagged.first() {
        Some(&(_, q0)) => {
            let differ: Vec<String> = tagged
                .iter()
                .filter(|(_, q)| *q != q0)
                .map(|(r, q)| format!("record {r} is {q}"))
                .collect();
            if !differ.is_empty() {
                return Err(IoError::format(
                    path,
                    "",
                    format!(
                        "records disagree on the response quantity: record {} is {q0}; {}",
                        tagged[0].0,
                        listed(&differ)
                    ),
                ));
            }
            q0
        }
        None => default_quantity,
    };
    Ok((quantity, !tagged.is_empty()))
}

/// The file's metadata: the units of the first record's axes, the layout, the notes.
fn uff_metadata(
    first: &Function58,
    records: usize,
    (q, p): (usize, usize),
    notes: &[String],
) -> BTreeMap<String, String> {
    let mut metadata = BTreeMap::new();
    let units = |a: &Axis| (!a.units.is_empty() && a.units != "NONE").then(|| a.units.clone());
    if let Some(u) = units(&first.axes[1]) {
        metadata.insert("response_unit".to_string(), u);
    }
    if let Some(u) = units(&first.axes[2]) {
        metadata.insert("force_unit".to_string(), u);
    }
    metadata.insert(
        "layout".to_string(),
        format!(
            "UFF 58{}, {records} FRF records, {q} x {p}",
            if first.binary.is_some() { "b" } else { "" },
        ),
    );
    if !notes.is_empty() {
        metadata.insert("notes".to_string(), notes.join(" | "));
    }
    metadata
}

/// Reads FRFs from a UFF file: [`read_uff`] then [`frf_from_uff`].
///
/// # Errors
/// As those two.
pub fn read_frf_uff(path: &Path, default_quantity: Quantity) -> Result<FrfFile, IoError> {
    let contents = read_uff(path, true)?;
    frf_from_uff(path, &contents, default_quantity)
}
