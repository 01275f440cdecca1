//! `era track DIR... --out DIR2`: the modes of a fleet followed over time. Every
//! `DIR/modes.parquet` (the shards `era batch` wrote) is read and checked (a record id
//! in two shards is named with both folders), [`era::modal::track::track`] clusters the
//! modes into tracks, and [`crate::output::track`] writes the table, the JSON, the
//! figures and the report.

use crate::config::Track;
use crate::output::prepare_out_dir;
use crate::output::report::{print_json, Human};
use crate::output::track::{track_table, tracks_json, write_track, Fleet, TrackRun};
use anyhow::Context as _;
use era::modal::track::{track, TrackMode, TrackRecord};
use era::Complex64;
use era_io::fleet::{read_modes, ModeRow};
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

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

/// `era track`.
pub fn run(a: &Track) -> anyhow::Result<()> {
    let settings = a.settings;
    let human = Human::new(&settings);
    let mut set = prepare_out_dir(&a.out)?;
    let fleet = read_fleet(&a.dirs)?;
    let tracking = track(&fleet.records, &a.options).context("tracking the modes")?;
    let run = TrackRun {
        dirs: &a.dirs,
        fleet: &fleet,
        tracking: &tracking,
        options: &a.options,
    };
    human.print(&format!(
        "era track {}\n",
        a.dirs
            .iter()
            .map(|d| d.display().to_string())
            .collect::<Vec<_>>()
            .join(" ")
    ));
    human.print(&run.summary());
    human.print(&track_table(&run));
    let json = tracks_json(&run);
    write_track(&mut set, &run, &json)?;
    set.commit()?;
    human.print(&format!(
        "\nwrote {0}/tracks.parquet, {0}/tracks.json, {0}/report.html and figures (frequency, damping)\n",
        a.out.display()
    ));
    if settings.json {
        print_json(&json)?;
    }
    Ok(())
}
