//! What `era simulate fleet` writes: each record as a time-history CSV, the manifest
//! `era batch` takes, and the truth.

use crate::config::fleet::Fleet;
use era::sim::fleet::FleetRecord;
use serde_json::json;
use std::fmt::Write as _;

/// The record's name: `r0001` …, wide enough for the fleet.
pub fn name(index: usize, records: usize) -> String {
    let width = records.to_string().len().max(4);
    format!("r{:0width$}", index + 1)
}

/// A record as a time-history CSV: `time_s` and the channels it holds.
pub fn record_csv(r: &FleetRecord, header: &str) -> String {
    let outputs = &r.record.outputs;
    let n = outputs.first().map_or(0, Vec::len);
    let mut out = String::with_capacity(n * 14 * (outputs.len() + 1));
    let _ = writeln!(out, "# {header}");
    let _ = writeln!(out, "# temperature_c: {:.3}", r.temperature_c);
    out.push_str("time_s");
    for c in &r.channels {
        let _ = write!(out, ",acc{}", c + 1);
    }
    out.push('\n');
    for k in 0..n {
        let _ = write!(out, "{}", k as f64 / r.record.sample_rate_hz);
        for ch in outputs {
            let _ = write!(out, ",{:.7e}", ch[k]);
        }
        out.push('\n');
    }
    out
}

/// The first line of every record and of the manifest.
pub fn header(f: &Fleet) -> String {
    let st = &f.spec.structure;
    format!(
        "era simulate fleet: {} modes {}..{} Hz, {} unmeasured forces, {} % sensor noise, seed {}",
        st.modes,
        st.fmin_hz,
        st.fmax_hz,
        st.inputs,
        100.0 * f.spec.noise,
        st.seed
    )
}

/// The truth of record `r`, named `id`: its time, temperature, channels and modes.
pub fn record_truth(f: &Fleet, id: &str, r: &FleetRecord) -> serde_json::Value {
    let t = &r.record.truth;
    json!({
        "id": id,
        "time": era_io::fleet::format_time(f.start_us + (r.time_s * 1e6).round() as i64),
        "temperature_c": r.temperature_c,
        "channels": r.channels.iter().map(|c| format!("acc{}", c + 1)).collect::<Vec<_>>(),
        "frequencies_hz": t.frequencies_hz,
        "damping_ratios": t.damping_ratios,
    })
}

/// `fleet.toml`: `era oma` on every record, with its own `--outputs` when it lacks
/// channels.
pub fn manifest(f: &Fleet, header: &str, truths: &[serde_json::Value]) -> String {
    let outputs = f.spec.structure.outputs;
    let mut manifest = String::new();
    let _ = writeln!(manifest, "# {header}");
    let _ = writeln!(manifest, "verb = \"oma\"");
    let _ = writeln!(manifest, "args = [\"--outputs\", \"1-{outputs}\"]");
    for t in truths {
        let held = t["channels"].as_array().map_or(0, Vec::len);
        let _ = write!(
            manifest,
            "\n[[record]]\nid = \"{}\"\npath = \"records/{}.csv\"\ntime = {}\n",
            t["id"].as_str().unwrap_or_default(),
            t["id"].as_str().unwrap_or_default(),
            t["time"].as_str().unwrap_or_default()
        );
        if held != outputs {
            let _ = writeln!(manifest, "args = [\"--outputs\", \"1-{held}\"]");
        }
    }
    manifest
}

/// `truth.json`: the fleet's settings and each record's truth.
pub fn truth_json(f: &Fleet, truths: Vec<serde_json::Value>) -> serde_json::Value {
    let s = &f.spec;
    json!({
        "model": "fleet",
        "outputs": s.structure.outputs,
        "forces": s.structure.inputs,
        "sample_rate_hz": s.sample_rate_hz,
        "record_s": s.record_s,
        "interval_s": s.interval_s,
        "noise": s.noise,
        "drift": s.drift,
        "daily_c": s.daily_c,
        "damage": s.damage.map(|(r, loss)| json!({"from_record": r + 1, "loss": loss})),
        "missing": s.missing,
        "seed": s.structure.seed,
        "records": truths,
    })
}

/// The closing line.
pub fn written(f: &Fleet) -> String {
    format!(
        "wrote {} records of {} s at {} Hz in {}, the manifest {} and the truth {}\n",
        f.spec.records,
        f.spec.record_s,
        f.spec.sample_rate_hz,
        f.out.join("records").display(),
        f.out.join("fleet.toml").display(),
        f.out.join("truth.json").display()
    )
}
