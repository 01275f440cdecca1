//! `era batch`'s records run: each through its verb's own function, silently, on one
//! thread, `--jobs` of them side by side; each one's state saved as it finishes, and a
//! failure (a panic too) its outcome.

use crate::config::batch::{parse, Planned};
use crate::config::{Batch, Settings};
use crate::error::UsageError;
use crate::output::batch::{physical_count, save_state, Outcome};
use std::path::Path;
use std::time::Instant;

/// Runs the records `todo` on `--jobs` threads, one thread each, saving each one's
/// state as it finishes.
pub fn run_records(
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
                outcome.physical = physical_count(modes.iter().map(|m| m.physical));
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
                crate::commands::oma::run(&c)
            }
            crate::args::Command::Identify(x) => {
                let mut c = crate::config::Identify::new(x)?;
                c.settings = Settings::silent();
                crate::commands::identify::run(&c)
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
            found: Some((done.model.modes, done.channels)),
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
