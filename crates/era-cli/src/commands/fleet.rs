//! `era simulate fleet --out DIR`: a fleet of output-only records of one structure
//! ([`era::sim::fleet`]), written as `era batch` takes it: `DIR/records/rNNNN.csv`,
//! the manifest `DIR/fleet.toml` and the truth `DIR/truth.json`.
//!
//! A record's CSV names its channels by the structure's (`acc1` … `acc8`), so a record
//! that lacks `acc3` still calls `acc4` by its name; such a record gets its own
//! `--outputs` in the manifest.

use crate::config::fleet::Fleet;
use crate::output::fleet::{header, manifest, name, record_csv, record_truth, truth_json, written};
use crate::output::report::Human;
use crate::output::write_output;
use crate::work::fleet_record;
use era_io::atomic::write_atomic;
use rayon::prelude::*;

/// `era simulate fleet`.
pub fn run(f: &Fleet) -> anyhow::Result<()> {
    let human = Human::new(&f.settings);
    let records = f.spec.records;
    // The spec is checked (and the first record made) before anything is written.
    let first = fleet_record(&f.spec, 0)?;
    let mut set = crate::output::prepare_out_dir(&f.out)?;
    let names: Vec<String> = (0..records).map(|k| name(k, records)).collect();
    let mut staged = Vec::with_capacity(records);
    for n in &names {
        staged.push(set.stage(format!("records/{n}.csv"))?);
    }
    let header = header(f);
    let bar = crate::output::progress::bar(&f.settings, records as u64, "records");
    let truths = (0..records)
        .into_par_iter()
        .map(|k| -> anyhow::Result<serde_json::Value> {
            let r = if k == 0 {
                first.clone()
            } else {
                fleet_record(&f.spec, k)?
            };
            std::fs::write(&staged[k], record_csv(&r, &header)).map_err(|e| {
                let path = f.out.join("records").join(&names[k]);
                anyhow::anyhow!("writing {}: {e}", path.display())
            })?;
            bar.inc(1);
            Ok(record_truth(f, &names[k], &r))
        })
        .collect::<anyhow::Result<Vec<_>>>()?;
    bar.finish_and_clear();
    let manifest = manifest(f, &header, &truths);
    let truth = truth_json(f, truths);
    write_output(&mut set, "fleet.toml", |p| {
        Ok(write_atomic(p, manifest.as_bytes())?)
    })?;
    let text = serde_json::to_string_pretty(&truth)?;
    write_output(&mut set, "truth.json", |p| {
        Ok(write_atomic(p, text.as_bytes())?)
    })?;
    set.commit()?;
    human.print(&written(f));
    if f.settings.json {
        crate::output::report::print_json(&truth)?;
    }
    Ok(())
}
