//! What `era batch` keeps and writes: each record's state as it finishes (read back by
//! `--resume`), the tables at the end (`modes.parquet`, `records.jsonl`), and the
//! closing lines, whose exit says whether a record failed.

use crate::config::batch::Planned;
use crate::config::Batch;
use crate::error::UsageError;
use crate::input::manifest::Record;
use anyhow::Context as _;
use era_io::fleet::ModeRow;
use era_io::model_json::ModeJson;
use serde_json::{json, Value};
use std::collections::HashMap;
use std::path::Path;

/// The folder of the records' states, inside `--out`.
pub const STATE_DIR: &str = ".era-batch";

/// What became of a record.
#[derive(Debug, Clone)]
pub struct Outcome {
    /// `ok`, `error` or `skipped`.
    pub status: &'static str,
    /// Why it failed.
    pub message: String,
    /// Its seconds.
    pub seconds: f64,
    /// The verb's modes (its model.json's) and the channels of their shapes, until they
    /// are saved in the record's state (then only counted).
    pub found: Option<(Vec<ModeJson>, Vec<String>)>,
    /// Modes.
    pub modes: usize,
    /// Modes called physical.
    pub physical: usize,
    /// 2 for a failure on the record's input, 1 for one inside era.
    pub code: u8,
}

/// The states folder: made if missing; emptied unless resuming. Returns the earlier
/// states by record id (none unless resuming).
pub fn prepare_states(states: &Path, resume: bool) -> anyhow::Result<HashMap<String, Value>> {
    if !resume && states.exists() {
        std::fs::remove_dir_all(states)
            .with_context(|| format!("clearing {}", states.display()))?;
    }
    std::fs::create_dir_all(states).with_context(|| format!("creating {}", states.display()))?;
    // Temporary files of a killed run's saves go; the states themselves stay.
    era_io::atomic::remove_stale(states);
    let mut earlier = HashMap::new();
    if resume {
        for entry in std::fs::read_dir(states)
            .with_context(|| format!("reading {}", states.display()))?
            .flatten()
        {
            let path = entry.path();
            if path.extension().is_none_or(|e| e != "json") {
                continue;
            }
            // A state that cannot be read counts for nothing: the record runs again.
            let Ok(text) = std::fs::read_to_string(&path) else {
                continue;
            };
            let Ok(state) = serde_json::from_str::<Value>(&text) else {
                continue;
            };
            // Only `<id>.json` itself: a temporary file of a save that a kill cut short
            // (hidden, its name random) may hold a whole state that never took its place.
            let named = path.file_stem().and_then(|s| s.to_str());
            if let Some(id) = state["id"].as_str().filter(|id| named == Some(*id)) {
                earlier.insert(id.to_string(), state);
            }
        }
    }
    Ok(earlier)
}

/// A record finished by an earlier run.
pub fn skipped(state: &Value) -> Outcome {
    Outcome {
        status: "skipped",
        message: "finished by an earlier run (--resume)".into(),
        seconds: state["seconds"].as_f64().unwrap_or(0.0),
        found: None,
        modes: state["modes"].as_array().map_or(0, Vec::len),
        physical: state["modes"].as_array().map_or(0, |modes| {
            physical_count(modes.iter().map(|m| m["physical"].as_bool()))
        }),
        code: 0,
    }
}

pub fn strings(v: &Value) -> Vec<String> {
    v.as_array()
        .map(|a| {
            a.iter()
                .filter_map(|s| s.as_str().map(String::from))
                .collect()
        })
        .unwrap_or_default()
}

/// Saves a finished record's state (atomically: a record half saved is not saved).
pub fn save_state(states: &Path, p: &Planned, o: &Outcome) -> anyhow::Result<()> {
    let state = RecordState {
        id: &p.record.id,
        status: o.status,
        message: &o.message,
        seconds: o.seconds,
        fingerprint: &p.fingerprint,
        channels: o.found.as_ref().map(|f| f.1.as_slice()),
        modes: o.found.as_ref().map(|f| f.0.as_slice()),
    };
    // Through a `Value`: its keys in alphabetical order, as the states have always been.
    let text = serde_json::to_value(&state)?.to_string();
    let path = states.join(format!("{}.json", p.record.id));
    era_io::atomic::write_atomic(&path, text.as_bytes())?;
    Ok(())
}

/// A record's state in `.era-batch/<id>.json`, as saved. It is read back as a JSON value
/// (by `--resume` and for the tables), so that a number written as null (a NaN) reads
/// as a missing value rather than failing the record.
#[derive(serde::Serialize)]
struct RecordState<'a> {
    id: &'a str,
    status: &'a str,
    message: &'a str,
    seconds: f64,
    fingerprint: &'a str,
    channels: Option<&'a [String]>,
    modes: Option<&'a [ModeJson]>,
}

/// Modes called physical, from each mode's flag (a mode without one counts as physical).
pub fn physical_count(flags: impl Iterator<Item = Option<bool>>) -> usize {
    flags.filter(|f| f.unwrap_or(true)).count()
}

/// The modes table's rows of one `ok` (or skipped) record, from its saved state; none
/// for a record that failed.
pub fn record_rows(
    states: &Path,
    p: &Planned,
    o: &Outcome,
) -> Result<Vec<ModeRow>, era_io::IoError> {
    if o.status == "error" {
        return Ok(Vec::new());
    }
    let path = states.join(format!("{}.json", p.record.id));
    let bytes = era_io::input::read_input(&path)?.into_vec();
    let state: Value = serde_json::from_slice(&bytes).map_err(|e| era_io::IoError::Io {
        path: path.clone(),
        error: std::io::Error::new(std::io::ErrorKind::InvalidData, e),
    })?;
    let channels = strings(&state["channels"]);
    Ok(state["modes"]
        .as_array()
        .map(|modes| {
            modes
                .iter()
                .enumerate()
                .map(|(k, m)| mode_row(&p.record, k, m, &channels))
                .collect()
        })
        .unwrap_or_default())
}

/// One mode of a verb's JSON as a table row.
pub fn mode_row(r: &Record, k: usize, m: &Value, channels: &[String]) -> ModeRow {
    let num = |v: &Value| v.as_f64();
    let list = |name: &str| -> Vec<f64> {
        m[name]
            .as_array()
            .map(|a| a.iter().map(|x| x.as_f64().unwrap_or(f64::NAN)).collect())
            .unwrap_or_default()
    };
    let shape_re = list("shape_re");
    let mut shape_im = list("shape_im");
    shape_im.resize(shape_re.len(), 0.0);
    let channels = if channels.len() == shape_re.len() {
        channels.to_vec()
    } else {
        (1..=shape_re.len()).map(|c| c.to_string()).collect()
    };
    ModeRow {
        record_id: r.id.clone(),
        time_us: r.time_us,
        mode: u32::try_from(k + 1).unwrap_or(u32::MAX),
        frequency_hz: num(&m["frequency_hz"]).unwrap_or(f64::NAN),
        damping_ratio: num(&m["damping_ratio"]).unwrap_or(f64::NAN),
        frequency_std_hz: num(&m["frequency_std_hz"]),
        damping_ratio_std: num(&m["damping_ratio_std"]),
        physical: m["physical"].as_bool().unwrap_or(true),
        mpc: num(&m["indicators"]["mpc"]),
        emac: num(&m["indicators"]["emac"]),
        shape_re,
        shape_im,
        channels,
    }
}

/// `records.jsonl`: one line per record of the run, in the manifest's order.
pub fn record_lines(plans: &[Planned], outcomes: &[Outcome]) -> String {
    let mut text = String::new();
    for (p, o) in plans.iter().zip(outcomes) {
        let line = json!({
            "id": p.record.id,
            "status": o.status,
            "message": o.message,
            "seconds": o.seconds,
            "time": p.record.time_us.map(era_io::fleet::format_time),
            "files": p.record.files.iter().map(|f| f.display().to_string()).collect::<Vec<_>>(),
            "modes": o.modes,
            "physical": o.physical,
        });
        text.push_str(&line.to_string());
        text.push('\n');
    }
    text
}

/// The closing lines, and the exit: an error when a record failed.
pub fn report(
    a: &Batch,
    plans: &[Planned],
    outcomes: &[Outcome],
    rows: usize,
    seconds: f64,
    human: &crate::output::report::Human,
) -> anyhow::Result<()> {
    let count = |s: &str| outcomes.iter().filter(|o| o.status == s).count();
    let (ok, failed, skipped) = (count("ok"), count("error"), count("skipped"));
    let mut text = format!(
        "{ok} ok, {failed} failed, {skipped} skipped in {seconds:.2} s ({:.2} records/s)\n",
        (ok + failed) as f64 / seconds.max(1e-9)
    );
    for (p, o) in plans
        .iter()
        .zip(outcomes)
        .filter(|(_, o)| o.status == "error")
        .take(10)
    {
        text.push_str(&format!("  {}: {}\n", p.record.id, o.message));
    }
    if failed > 10 {
        text.push_str(&format!("  … and {} more\n", failed - 10));
    }
    text.push_str(&format!(
        "wrote {} ({rows} rows) and {}\n",
        a.out.join("modes.parquet").display(),
        a.out.join("records.jsonl").display()
    ));
    human.print(&text);
    let records_s: f64 = outcomes
        .iter()
        .filter(|o| o.status != "skipped")
        .map(|o| o.seconds)
        .sum();
    if a.settings.timings {
        human.print(&format!(
            "timings: {seconds:.3} s in all, {records_s:.3} s in the records themselves ({:+.1} % batch overhead)\n",
            100.0 * (seconds / records_s.max(1e-9) - 1.0)
        ));
    }
    if a.settings.json {
        let mut v = json!({
            "manifest": a.manifest.display().to_string(),
            "out": a.out.display().to_string(),
            "shard": a.shard.map(|(i, n)| format!("{i}/{n}")),
            "records": plans.len(),
            "ok": ok,
            "error": failed,
            "skipped": skipped,
            "mode_rows": rows,
            "seconds": seconds,
            "records_per_s": (ok + failed) as f64 / seconds.max(1e-9),
        });
        if a.settings.timings {
            v["timings_s"] = json!({"all": seconds, "records": records_s});
        }
        crate::output::report::print_json(&v)?;
    }
    if failed == 0 {
        return Ok(());
    }
    let message = format!(
        "{failed} of {} records failed: their rows in {} say why; the tables hold the others",
        plans.len(),
        a.out.join("records.jsonl").display()
    );
    if outcomes.iter().all(|o| o.code != 1) {
        return Err(UsageError(message).into());
    }
    Err(anyhow::anyhow!(message))
}

/// The tables, staged in `set`: `modes.parquet` from the records' saved states (so that
/// memory does not grow with the fleet) and `records.jsonl`. Returns the mode rows.
pub fn write_tables(
    set: &mut era_io::atomic::OutputSet,
    states: &Path,
    plans: &[Planned],
    outcomes: &[Outcome],
) -> anyhow::Result<usize> {
    let rows: usize = outcomes.iter().map(|o| o.modes).sum();
    crate::output::write_output(set, "modes.parquet", |p| {
        let pieces = plans
            .iter()
            .zip(outcomes)
            .map(|(plan, o)| record_rows(states, plan, o));
        Ok(era_io::fleet::write_modes_stream(p, pieces)?)
    })?;
    let lines = record_lines(plans, outcomes);
    crate::output::write_output(set, "records.jsonl", |p| {
        Ok(era_io::atomic::write_atomic(p, lines.as_bytes())?)
    })?;
    Ok(rows)
}
