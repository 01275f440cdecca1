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

mod records;

use crate::config::batch::plan;
use crate::config::Batch;
use crate::output::batch::{prepare_states, report, skipped, write_tables, Outcome, STATE_DIR};
use crate::output::prepare_out_dir;
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
    records::run_records(a, &manifest.verb, &plans, &todo, &states, &mut outcomes)?;
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
