//! What `era track` reads: the fleet's shards (each `DIR/modes.parquet` that `era batch`
//! wrote, with its `records.jsonl` when there is one), checked: a record id in two
//! shards is named with both folders.

use anyhow::Context as _;
use era::modal::track::{TrackMode, TrackRecord};
use era::Complex64;
use era_io::fleet::{read_modes, ModeRow};
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

/// The fleet as read: each record with the shard it came from and its rows.
pub struct Fleet {
    /// The records, as the core takes them.
    pub records: Vec<TrackRecord>,
    /// Per record, the mode number (the `mode` column) of each of its modes.
    pub mode_numbers: Vec<Vec<u32>>,
    /// Per record, its time in µs since 1970 as read.
    pub times_us: Vec<Option<i64>>,
    /// Per shard: its modes.parquet, and the rows and records it gave.
    pub shards: Vec<(PathBuf, usize, usize)>,
    /// What records.jsonl said, per shard that has one: `ok`, `error`, `skipped`.
    pub statuses: BTreeMap<String, usize>,
}

/// A modes table's row as the core's mode.
fn mode_of(row: &ModeRow) -> TrackMode {
    TrackMode {
        frequency_hz: row.frequency_hz,
        damping_ratio: row.damping_ratio,
        frequency_std_hz: row.frequency_std_hz,
        damping_ratio_std: row.damping_ratio_std,
        physical: row.physical,
        shape: row
            .shape_re
            .iter()
            .zip(&row.shape_im)
            .map(|(&re, &im)| Complex64::new(re, im))
            .collect(),
        channels: row.channels.clone(),
    }
}

/// One record being gathered: its index in [`Fleet::records`] and its shard.
struct Seen {
    index: usize,
    shard: usize,
}

/// `DIR/records.jsonl`'s `ok` records (which may have no modes: they still count as
/// records of the fleet) with their times, and the count of each status.
fn jsonl(
    dir: &Path,
    statuses: &mut BTreeMap<String, usize>,
) -> anyhow::Result<Vec<(String, Option<i64>)>> {
    let path = dir.join("records.jsonl");
    if !path.is_file() {
        return Ok(Vec::new());
    }
    let bytes =
        era_io::input::read_input(&path).with_context(|| format!("reading {}", path.display()))?;
    let text = String::from_utf8_lossy(&bytes);
    let mut ok = Vec::new();
    for (k, line) in text.lines().enumerate() {
        if line.trim().is_empty() {
            continue;
        }
        let bad = |what: &str| {
            crate::error::UsageError(format!("{}: line {}: {what}", path.display(), k + 1))
        };
        let v: serde_json::Value =
            serde_json::from_str(line).map_err(|e| bad(&format!("not JSON: {e}")))?;
        let (Some(id), Some(status)) = (v["id"].as_str(), v["status"].as_str()) else {
            return Err(bad("needs a string id and a string status").into());
        };
        *statuses.entry(status.to_string()).or_default() += 1;
        if status == "ok" {
            let time = match v["time"].as_str() {
                Some(t) => Some(era_io::fleet::parse_time(t).map_err(|e| bad(&e))?),
                None => None,
            };
            ok.push((id.to_string(), time));
        }
    }
    Ok(ok)
}

/// Reads every shard; a missing or malformed table is named, and so is a record id
/// found in two shards (with both folders).
pub fn read_fleet(dirs: &[PathBuf]) -> anyhow::Result<Fleet> {
    let mut fleet = Fleet {
        records: Vec::new(),
        mode_numbers: Vec::new(),
        times_us: Vec::new(),
        shards: Vec::new(),
        statuses: BTreeMap::new(),
    };
    let mut seen: BTreeMap<String, Seen> = BTreeMap::new();
    for (shard, dir) in dirs.iter().enumerate() {
        let path = dir.join("modes.parquet");
        if !dir.is_dir() {
            return crate::error::usage(format!(
                "{}: not a folder (era track reads the folders era batch wrote)",
                dir.display()
            ));
        }
        if !path.is_file() {
            return crate::error::usage(format!(
                "{}: no modes.parquet in this folder (era batch --out DIR writes DIR/modes.parquet)",
                dir.display()
            ));
        }
        let rows = read_modes(&path).with_context(|| format!("reading {}", path.display()))?;
        let before = fleet.records.len();
        let mut add = |fleet: &mut Fleet, id: &str, time: Option<i64>| -> anyhow::Result<usize> {
            if let Some(s) = seen.get(id) {
                if s.shard != shard {
                    return crate::error::usage(format!(
                        "record {id} is in two shards: {} and {}; a fleet's shards hold distinct records",
                        dirs[s.shard].display(),
                        dir.display()
                    ));
                }
                return Ok(s.index);
            }
            fleet.records.push(TrackRecord {
                id: id.to_string(),
                time_s: time.map(|us| us as f64 * 1e-6),
                modes: Vec::new(),
            });
            fleet.mode_numbers.push(Vec::new());
            fleet.times_us.push(time);
            let index = fleet.records.len() - 1;
            seen.insert(id.to_string(), Seen { index, shard });
            Ok(index)
        };
        for row in &rows {
            let r = add(&mut fleet, &row.record_id, row.time_us)?;
            fleet.records[r].modes.push(mode_of(row));
            fleet.mode_numbers[r].push(row.mode);
        }
        for (id, time) in jsonl(dir, &mut fleet.statuses)? {
            add(&mut fleet, &id, time)?;
        }
        fleet
            .shards
            .push((path, rows.len(), fleet.records.len() - before));
    }
    if fleet.records.is_empty() {
        return crate::error::usage(format!(
            "no record in {}: nothing to track",
            dirs.iter()
                .map(|d| d.join("modes.parquet").display().to_string())
                .collect::<Vec<_>>()
                .join(", ")
        ));
    }
    Ok(fleet)
}
