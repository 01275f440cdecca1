//! `era batch MANIFEST --out DIR`: every record of a manifest through one verb
//! (`identify` or `oma`) with its flags, in this process.
//!
//! - **Before any work** the manifest is read and every record's flags are parsed as
//!   the verb's own ([`manifest`]); a problem names the manifest's line, exit 2.
//! - **Each record** runs the verb's own function, silently, on one thread; `--jobs N`
//!   runs N of them side by side. A record that fails (an unreadable file, a core error,
//!   even a panic) becomes an `error` row with the message; the batch goes on.
//! - **Progress is kept** record by record in `DIR/.era-batch/<id>.json`, each written
//!   atomically once the record is done, with a fingerprint of the verb, the flags and
//!   the files (size and modification time). `--resume` skips a record whose state says
//!   `ok` under the same fingerprint; a killed batch so continues where it stopped, and
//!   a record half done counts for nothing.
//! - **The tables** (`modes.parquet`, `records.jsonl`) are written at the end through
//!   the safe writer, so a failed or killed batch leaves the earlier tables whole.
//!
//! Exit code: 0 when every record is `ok` (or skipped); 2 when some failed on their
//! input; 1 when one failed inside era.

pub mod manifest;

use crate::config::{Batch, Settings};
use crate::error::UsageError;
use crate::output::{prepare_out_dir, write_output};
use anyhow::Context as _;
use era_io::fleet::ModeRow;
use manifest::Record;
use serde_json::{json, Value};
use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::time::Instant;

/// The folder of the records' states, inside `--out`.
pub const STATE_DIR: &str = ".era-batch";

/// A record to run.
struct Planned {
    record: Record,
    fingerprint: String,
}

/// What became of a record.
#[derive(Debug, Clone)]
struct Outcome {
    status: &'static str,
    message: String,
    seconds: f64,
    /// The verb's modes (its JSON's `modes`) and the channels of their shapes, until
    /// they are saved in the record's state (then only counted).
    found: Option<(Vec<Value>, Vec<String>)>,
    /// Modes, and modes called physical.
    modes: usize,
    physical: usize,
    /// 2 for a failure on the record's input, 1 for one inside era.
    code: u8,
}

/// `era batch`.
pub fn run(a: &Batch) -> anyhow::Result<()> {
    let human = crate::output::report::Human::new(&a.settings);
    if a.jobs == 0 || a.jobs > era::parallel::MAX_THREADS {
        return crate::error::usage(format!(
            "--jobs {}: must be between 1 and {}",
            a.jobs,
            era::parallel::MAX_THREADS
        ));
    }
    let manifest = manifest::read(&a.manifest, a.allow_outside)?;
    let chosen: Vec<&Record> = manifest
        .records
        .iter()
        .enumerate()
        .filter(|(k, _)| a.shard.is_none_or(|(i, n)| k % n == i - 1))
        .map(|(_, r)| r)
        .collect();
    // Each distinct list of flags is parsed once, as its verb's, before any work.
    let mut checked = std::collections::HashSet::new();
    for r in &chosen {
        if checked.insert(&r.args) {
            parse(&manifest.verb, r, a).map_err(|m| {
                UsageError(format!(
                    "{}: line {}: record {:?}: args of era {}: {m}",
                    manifest.path.display(),
                    r.args_line,
                    r.id,
                    manifest.verb
                ))
            })?;
        }
    }
    let plans: Vec<Planned> = chosen
        .iter()
        .map(|r| Planned {
            record: (*r).clone(),
            fingerprint: fingerprint(&manifest.verb, &r.args, &r.files),
        })
        .collect();
    let mut set = prepare_out_dir(&a.out)?;
    let states = a.out.join(STATE_DIR);
    let earlier = prepare_states(&states, a.resume)?;
    let clock = Instant::now();
    let (todo, done): (Vec<usize>, Vec<usize>) = (0..plans.len()).partition(|&k| {
        earlier
            .get(&plans[k].record.id)
            .is_none_or(|s| s["status"] != "ok" || s["fingerprint"] != plans[k].fingerprint)
    });
    human.print(&format!(
        "era batch {}: era {} on {} of its {} records{}{}\n",
        a.manifest.display(),
        manifest.verb,
        plans.len(),
        manifest.records.len(),
        a.shard
            .map(|(i, n)| format!(" in shard {i}/{n}"))
            .unwrap_or_default(),
        if done.is_empty() {
            String::new()
        } else {
            format!(", {} finished earlier (skipped)", done.len())
        }
    ));
    let mut outcomes: Vec<Option<Outcome>> = vec![None; plans.len()];
    for &k in &done {
        outcomes[k] = Some(skipped(&earlier[&plans[k].record.id]));
    }
    run_records(a, &manifest.verb, &plans, &todo, &states, &mut outcomes)?;
    let outcomes: Vec<Outcome> = outcomes
        .into_iter()
        .map(|o| o.expect("every record ran"))
        .collect();
    let rows: usize = outcomes.iter().map(|o| o.modes).sum();
    write_output(&mut set, "modes.parquet", |p| {
        let pieces = plans
            .iter()
            .zip(&outcomes)
            .map(|(plan, o)| record_rows(&states, plan, o));
        Ok(era_io::fleet::write_modes_stream(p, pieces)?)
    })?;
    let lines = record_lines(&plans, &outcomes);
    write_output(&mut set, "records.jsonl", |p| {
        Ok(era_io::atomic::write_atomic(p, lines.as_bytes())?)
    })?;
    set.commit()?;
    report(
        a,
        &plans,
        &outcomes,
        rows,
        clock.elapsed().as_secs_f64(),
        &human,
    )
}

/// A record's flags parsed as its verb's (with the files and, with `--keep-models`, its
/// model folder) and their values checked: what the verb's own run would refuse.
fn parse(verb: &str, r: &Record, a: &Batch) -> Result<crate::args::Cli, String> {
    let mut argv: Vec<std::ffi::OsString> = vec!["era".into(), verb.into()];
    argv.extend(r.files.iter().map(|f| f.clone().into_os_string()));
    argv.extend(r.args.iter().map(Into::into));
    if a.keep_models {
        argv.push("--out".into());
        argv.push(a.out.join("records").join(&r.id).into_os_string());
        if !r.args.iter().any(|x| x == "--no-figures") {
            argv.push("--no-figures".into());
        }
    }
    let cli = <crate::args::Cli as clap::Parser>::try_parse_from(&argv).map_err(|e| {
        let text = e.render().to_string();
        let first = text.lines().next().unwrap_or_default();
        first.strip_prefix("error: ").unwrap_or(first).to_string()
    })?;
    let checked = match &cli.command {
        crate::args::Command::Oma(x) => crate::config::Oma::new(x).map(drop),
        crate::args::Command::Identify(x) => crate::config::Identify::new(x).map(drop),
        _ => unreachable!("the manifest's verb is identify or oma"),
    };
    checked.map_err(|e| crate::message(&e))?;
    Ok(cli)
}

/// The verb, the flags and each file's path, size and modification time: what a
/// record's result depends on.
fn fingerprint(verb: &str, args: &[String], files: &[PathBuf]) -> String {
    let mut f = format!("{verb} {}", serde_json::to_string(args).unwrap_or_default());
    for file in files {
        let (len, modified) = std::fs::metadata(file)
            .map(|m| {
                let t = m
                    .modified()
                    .ok()
                    .and_then(|t| t.duration_since(std::time::UNIX_EPOCH).ok())
                    .map_or(0, |d| d.as_nanos());
                (m.len(), t)
            })
            .unwrap_or_default();
        f.push_str(&format!(" | {} {len} {modified}", file.display()));
    }
    f
}

/// The states folder: made if missing; emptied unless resuming. Returns the earlier
/// states by record id (none unless resuming).
fn prepare_states(states: &Path, resume: bool) -> anyhow::Result<HashMap<String, Value>> {
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
fn skipped(state: &Value) -> Outcome {
    Outcome {
        status: "skipped",
        message: "finished by an earlier run (--resume)".into(),
        seconds: state["seconds"].as_f64().unwrap_or(0.0),
        found: None,
        modes: state["modes"].as_array().map_or(0, Vec::len),
        physical: physical_count(state["modes"].as_array().map_or(&[][..], Vec::as_slice)),
        code: 0,
    }
}

fn strings(v: &Value) -> Vec<String> {
    v.as_array()
        .map(|a| {
            a.iter()
                .filter_map(|s| s.as_str().map(String::from))
                .collect()
        })
        .unwrap_or_default()
}

/// Runs the records `todo` on `--jobs` threads, one thread each, saving each one's
/// state as it finishes.
fn run_records(
    a: &Batch,
    verb: &str,
    plans: &[Planned],
    todo: &[usize],
    states: &Path,
    outcomes: &mut [Option<Outcome>],
) -> anyhow::Result<()> {
    let bar = crate::output::progress::records_bar(&a.settings, todo.len() as u64);
    let next = std::sync::atomic::AtomicUsize::new(0);
    let (send, receive) = std::sync::mpsc::channel::<(usize, Outcome)>();
    let mut failed = 0usize;
    let mut saved: anyhow::Result<()> = Ok(());
    std::thread::scope(|scope| {
        for _ in 0..a.jobs.min(todo.len().max(1)) {
            let send = send.clone();
            let next = &next;
            scope.spawn(move || {
                let work = || loop {
                    let k = next.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
                    let Some(&k) = todo.get(k) else { break };
                    if send.send((k, run_one(&plans[k], verb, a))).is_err() {
                        break;
                    }
                };
                // One thread for rayon and faer inside each record.
                let _ = era::parallel::with_threads(era::params::Naming::Flag, Some(1), work);
            });
        }
        drop(send);
        for (k, outcome) in receive {
            if outcome.status != "ok" {
                failed += 1;
            }
            if saved.is_ok() {
                saved = save_state(states, &plans[k], &outcome);
            }
            // Saved, the modes are counted and let go: the table is written from the
            // states at the end, so memory does not grow with the fleet.
            let mut outcome = outcome;
            if let Some((modes, _)) = outcome.found.take() {
                outcome.modes = modes.len();
                outcome.physical = physical_count(&modes);
            }
            outcomes[k] = Some(outcome);
            bar.set_message(format!("{failed} failed"));
            bar.inc(1);
        }
    });
    bar.finish_and_clear();
    saved
}

/// One record through its verb, timed; any failure (a panic too) is its outcome.
fn run_one(p: &Planned, verb: &str, a: &Batch) -> Outcome {
    let clock = Instant::now();
    let result = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
        let cli = parse(verb, &p.record, a).map_err(UsageError)?;
        match &cli.command {
            crate::args::Command::Oma(x) => {
                let mut c = crate::config::Oma::new(x)?;
                c.settings = Settings::silent();
                super::oma::run(&c)
            }
            crate::args::Command::Identify(x) => {
                let mut c = crate::config::Identify::new(x)?;
                c.settings = Settings::silent();
                super::identify::run(&c)
            }
            _ => unreachable!("the manifest's verb is identify or oma"),
        }
    }));
    let seconds = clock.elapsed().as_secs_f64();
    match result {
        Ok(Ok(done)) => Outcome {
            status: "ok",
            message: String::new(),
            seconds,
            found: Some((
                done.json["modes"].as_array().cloned().unwrap_or_default(),
                done.channels,
            )),
            modes: 0,
            physical: 0,
            code: 0,
        },
        Ok(Err(e)) => Outcome {
            status: "error",
            message: crate::message(&e),
            seconds,
            found: None,
            modes: 0,
            physical: 0,
            code: crate::exit_code(&e),
        },
        Err(panic) => Outcome {
            status: "error",
            message: format!(
                "internal error: {}",
                panic
                    .downcast_ref::<&str>()
                    .map(|s| s.to_string())
                    .or_else(|| panic.downcast_ref::<String>().cloned())
                    .unwrap_or_else(|| "a panic".into())
            ),
            seconds,
            found: None,
            modes: 0,
            physical: 0,
            code: 1,
        },
    }
}

/// Saves a finished record's state (atomically: a record half saved is not saved).
fn save_state(states: &Path, p: &Planned, o: &Outcome) -> anyhow::Result<()> {
    let state = json!({
        "id": p.record.id,
        "status": o.status,
        "message": o.message,
        "seconds": o.seconds,
        "fingerprint": p.fingerprint,
        "channels": o.found.as_ref().map(|f| &f.1),
        "modes": o.found.as_ref().map(|f| &f.0),
    });
    let path = states.join(format!("{}.json", p.record.id));
    era_io::atomic::write_atomic(&path, state.to_string().as_bytes())?;
    Ok(())
}

/// Modes called physical (a mode without the flag counts as physical).
fn physical_count(modes: &[Value]) -> usize {
    modes
        .iter()
        .filter(|m| m["physical"].as_bool().unwrap_or(true))
        .count()
}

/// The modes table's rows of one `ok` (or skipped) record, from its saved state; none
/// for a record that failed.
fn record_rows(states: &Path, p: &Planned, o: &Outcome) -> Result<Vec<ModeRow>, era_io::IoError> {
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
fn mode_row(r: &Record, k: usize, m: &Value, channels: &[String]) -> ModeRow {
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
fn record_lines(plans: &[Planned], outcomes: &[Outcome]) -> String {
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
fn report(
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
