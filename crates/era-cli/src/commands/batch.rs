//! `era batch MANIFEST --out DIR`: every record of a manifest through one verb
//! (`identify` or `oma`) with its flags, in this process.
//!
//! - **Before any work** the manifest is read and every record's flags are parsed as
//!   the verb's own ([`crate::input::manifest`], [`crate::config::batch`]); a problem names the manifest's line, exit 2.
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

use crate::config::batch::{parse, plan, Planned};
use crate::config::{Batch, Settings};
use crate::error::UsageError;
use crate::output::batch::{
    physical_count, prepare_states, report, save_state, skipped, write_tables, Outcome, STATE_DIR,
};
use crate::output::prepare_out_dir;
use std::path::Path;
use std::time::Instant;

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
    let manifest = crate::input::manifest::read(&a.manifest, a.allow_outside)?;
    let plans = plan(a, &manifest)?;
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
    let rows = write_tables(&mut set, &states, &plans, &outcomes)?;
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
