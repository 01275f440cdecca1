//! `era batch` over a simulated fleet (`era simulate fleet`): shards, a corrupt record,
//! `--resume` after a finished and after a killed batch, `--jobs`, and the manifests it
//! refuses before any work.

use crate::common;
use common::{era, expect_input_error, s};
use era_io::fleet::{read_modes, ModeRow};
use serde_json::Value;
use std::path::{Path, PathBuf};

/// A fleet of `records` records of 300 s (6 modes, 8 channels, 2 % drift, seed 1) plus a
/// corrupt record `bad` at the end of the manifest. Returns the manifest and the truth.
fn fleet(dir: &Path, records: usize) -> (PathBuf, Value) {
    let out = dir.join("fleet");
    let n = records.to_string();
    let run = era()
        .args([
            "simulate",
            "fleet",
            "--records",
            &n,
            "--record-length",
            "300",
        ])
        .args(["--seed", "1", "--out", s(&out), "-q"])
        .output()
        .unwrap();
    common::assert_success(&run);
    std::fs::write(
        out.join("records/bad.csv"),
        b"time_s,acc1,acc2\n0,1,2\n0.015625,\x00\xff,3\n",
    )
    .unwrap();
    let manifest = out.join("fleet.toml");
    let mut text = std::fs::read_to_string(&manifest).unwrap();
    text.push_str("\n[[record]]\nid = \"bad\"\npath = \"records/bad.csv\"\n");
    std::fs::write(&manifest, text).unwrap();
    let truth =
        serde_json::from_str(&std::fs::read_to_string(out.join("truth.json")).unwrap()).unwrap();
    (manifest, truth)
}

/// `era batch ARGS`: its exit code and stderr.
fn batch(args: &[&str]) -> (Option<i32>, String) {
    let out = era().arg("batch").args(args).output().unwrap();
    (
        out.status.code(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

/// The lines of `DIR/records.jsonl`.
fn records(dir: &Path) -> Vec<Value> {
    std::fs::read_to_string(dir.join("records.jsonl"))
        .unwrap()
        .lines()
        .map(|l| serde_json::from_str(l).unwrap())
        .collect()
}

fn count(lines: &[Value], status: &str) -> usize {
    lines.iter().filter(|l| l["status"] == status).count()
}

#[test]
fn a_fleet_in_two_shards_with_a_corrupt_record_then_resumed() {
    let dir = tempfile::tempdir().unwrap();
    let (manifest, truth) = fleet(dir.path(), 12);
    let (s1, s2) = (dir.path().join("s1"), dir.path().join("s2"));
    // 13 records: shard 1 takes records 1, 3, …, 13 (the corrupt one), shard 2 the rest.
    let (code, err) = batch(&[s(&manifest), "--out", s(&s1), "--shard", "1/2", "-q"]);
    assert_eq!(code, Some(2), "{err}");
    assert!(err.contains("1 of 7 records failed"), "{err}");
    let (code, err) = batch(&[
        s(&manifest),
        "--out",
        s(&s2),
        "--shard",
        "2/2",
        "--jobs",
        "2",
    ]);
    assert_eq!(code, Some(0), "{err}");
    let lines: Vec<Value> = records(&s1).into_iter().chain(records(&s2)).collect();
    assert_eq!((count(&lines, "ok"), count(&lines, "error")), (12, 1));
    let bad = lines.iter().find(|l| l["status"] == "error").unwrap();
    assert_eq!(bad["id"], "bad");
    assert!(
        bad["message"].as_str().unwrap().contains("bad.csv"),
        "{bad}"
    );
    // Every record's physical modes are the truth's, within 1 % in frequency.
    let rows: Vec<ModeRow> = [&s1, &s2]
        .iter()
        .flat_map(|d| read_modes(&d.join("modes.parquet")).unwrap())
        .collect();
    for t in truth["records"].as_array().unwrap() {
        let id = t["id"].as_str().unwrap();
        let found: Vec<f64> = rows
            .iter()
            .filter(|r| r.record_id == id && r.physical)
            .map(|r| r.frequency_hz)
            .collect();
        let mut hits = 0;
        for f in t["frequencies_hz"].as_array().unwrap() {
            let f = f.as_f64().unwrap();
            hits += usize::from(found.iter().any(|g| (g / f - 1.0).abs() < 0.01));
        }
        assert!(hits >= 5, "record {id}: {hits} of 6 modes, found {found:?}");
        let time = rows.iter().find(|r| r.record_id == id).unwrap().time_us;
        assert_eq!(
            time.map(era_io::fleet::format_time).as_deref(),
            t["time"].as_str()
        );
    }
    // A resumed shard redoes nothing that finished: the same tables, every ok record
    // skipped, the corrupt one tried again.
    let before = read_modes(&s1.join("modes.parquet")).unwrap();
    let (code, _) = batch(&[s(&manifest), "--out", s(&s1), "--shard", "1/2", "--resume"]);
    assert_eq!(code, Some(2));
    let again = records(&s1);
    assert_eq!(
        (
            count(&again, "ok"),
            count(&again, "skipped"),
            count(&again, "error")
        ),
        (0, 6, 1)
    );
    assert_eq!(read_modes(&s1.join("modes.parquet")).unwrap(), before);
    // A changed record (its file rewritten) is not taken from the earlier run.
    let first = manifest.parent().unwrap().join("records/r0001.csv");
    let text = std::fs::read_to_string(&first).unwrap();
    std::fs::write(&first, format!("{text}\n")).unwrap();
    let (code, _) = batch(&[s(&manifest), "--out", s(&s1), "--shard", "1/2", "--resume"]);
    assert_eq!(code, Some(2));
    let third = records(&s1);
    assert_eq!((count(&third, "ok"), count(&third, "skipped")), (1, 5));
    assert_eq!(third[0]["id"], "r0001");
    assert_eq!(third[0]["status"], "ok");
}

#[test]
fn jobs_side_by_side_give_the_same_table_and_a_killed_batch_resumes() {
    let dir = tempfile::tempdir().unwrap();
    let (manifest, _) = fleet(dir.path(), 6);
    let (one, two) = (dir.path().join("one"), dir.path().join("two"));
    batch(&[s(&manifest), "--out", s(&one), "-q"]);
    // The corrupt record makes the exit 2; the summary is on stdout all the same.
    let run = era()
        .args([
            "batch",
            s(&manifest),
            "--out",
            s(&two),
            "--jobs",
            "2",
            "--json",
            "-q",
        ])
        .output()
        .unwrap();
    assert_eq!(run.status.code(), Some(2));
    let summary: Value = serde_json::from_slice(&run.stdout).unwrap();
    assert_eq!(
        (summary["ok"].as_u64(), summary["error"].as_u64()),
        (Some(6), Some(1))
    );
    let a = read_modes(&one.join("modes.parquet")).unwrap();
    assert!(a.len() >= 6 * 6, "{} rows", a.len());
    assert_eq!(a, read_modes(&two.join("modes.parquet")).unwrap());

    // Killed after its first record: no tables, and a resume runs only the rest.
    let killed = dir.path().join("killed");
    let mut child = std::process::Command::new(assert_cmd::cargo::cargo_bin("era"))
        .args(["batch", s(&manifest), "--out", s(&killed), "-q"])
        .spawn()
        .unwrap();
    let states = killed.join(".era-batch");
    let deadline = std::time::Instant::now() + std::time::Duration::from_secs(120);
    let saved = |d: &Path| {
        std::fs::read_dir(d).map_or(0, |e| {
            e.flatten()
                .filter(|f| {
                    let name = f.file_name().to_string_lossy().into_owned();
                    name.ends_with(".json") && !name.starts_with('.')
                })
                .count()
        })
    };
    while saved(&states) == 0 && std::time::Instant::now() < deadline {
        std::thread::sleep(std::time::Duration::from_millis(20));
    }
    child.kill().unwrap();
    let status = child.wait().unwrap();
    let done = saved(&states);
    assert!(done >= 1, "no record finished before the deadline");
    if status.success() {
        // The batch finished before the kill landed: nothing to resume from.
        return;
    }
    assert!(!killed.join("modes.parquet").exists());
    let (code, _) = batch(&[s(&manifest), "--out", s(&killed), "--resume", "-q"]);
    assert_eq!(code, Some(2), "the corrupt record fails again");
    let lines = records(&killed);
    assert_eq!(count(&lines, "skipped"), done);
    assert_eq!(count(&lines, "ok"), 6 - done);
    assert_eq!(read_modes(&killed.join("modes.parquet")).unwrap(), a);
}

#[test]
fn a_bad_manifest_is_refused_before_any_work() {
    let root = tempfile::tempdir().unwrap();
    let dir = root.path().join("sub");
    std::fs::create_dir(&dir).unwrap();
    // `../a.csv` exists, outside the manifest's folder.
    for f in [root.path().join("a.csv"), dir.join("a.csv")] {
        std::fs::write(f, "time_s,y\n0,1\n").unwrap();
    }
    let manifest = dir.join("m.toml");
    let out = dir.join("out");
    let good =
        "verb = \"oma\"\nargs = [\"--outputs\", \"1\"]\n[[record]]\nid = \"a\"\npath = \"a.csv\"\n";
    let cases = [
        (good.replace("a.csv\"\n", "missing.csv\"\n"), "line 5"),
        (
            good.replace("\"1\"]", "\"1\", \"--frobnicate\"]"),
            "--frobnicate",
        ),
        (good.replace("\"oma\"", "\"dance\""), "line 1"),
        (
            format!("{good}[[record]]\nid = \"a\"\npath = \"a.csv\"\n"),
            "twice",
        ),
        (good.replace("[[record]]", "[[record]"), "line 3"),
        (good.replace("\"a.csv\"", "\"../a.csv\""), "--allow-outside"),
        (
            good.replace("\"1\"]", "\"1\", \"--time-lags\", \"99999999999\"]"),
            "--time-lags 99999999999",
        ),
    ];
    for (text, needle) in cases {
        std::fs::write(&manifest, &text).unwrap();
        expect_input_error(&["batch", s(&manifest), "--out", s(&out)], needle);
        assert!(!out.exists(), "{text}: the batch began");
    }
    expect_input_error(
        &["batch", s(&manifest), "--out", s(&out), "--shard", "3/2"],
        "--shard",
    );
    expect_input_error(
        &["batch", s(&manifest), "--out", s(&out), "--jobs", "0"],
        "--jobs",
    );
    expect_input_error(
        &["batch", s(&manifest), "--out", s(&out), "--threads", "2"],
        "--jobs N",
    );
    // A FIFO as the manifest is read as a stream (bounded), not hung on.
    let fifo = dir.join("fifo.toml");
    let c = std::ffi::CString::new(fifo.to_str().unwrap()).unwrap();
    // SAFETY: mkfifo with a valid NUL-terminated path.
    assert_eq!(unsafe { libc::mkfifo(c.as_ptr(), 0o600) }, 0);
    let writer = std::thread::spawn({
        let fifo = fifo.clone();
        move || std::fs::write(fifo, "verb = 3\n")
    });
    expect_input_error(&["batch", s(&fifo), "--out", s(&out)], "verb");
    writer.join().unwrap().unwrap();
}

/// The fleet from the records to the tracks: 12 output-only records (10 minutes
/// at 64 Hz, 8 channels, 6 modes) whose frequencies fall 2 % over the fleet as the
/// structure warms, plus a corrupt record, in two shards; `era track` over both.
#[test]
fn a_fleet_from_its_records_to_its_tracks() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("fleet");
    let run = era()
        .args(["simulate", "fleet", "--records", "12", "--seed", "2"])
        .args(["--out", s(&out), "-q"])
        .output()
        .unwrap();
    common::assert_success(&run);
    std::fs::write(out.join("records/bad.csv"), b"\x00garbage\n").unwrap();
    let manifest = out.join("fleet.toml");
    let mut text = std::fs::read_to_string(&manifest).unwrap();
    text.push_str("\n[[record]]\nid = \"bad\"\npath = \"records/bad.csv\"\n");
    std::fs::write(&manifest, text).unwrap();
    let truth: Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("truth.json")).unwrap()).unwrap();
    let shards = [dir.path().join("part-1"), dir.path().join("part-2")];
    for (k, shard) in shards.iter().enumerate() {
        let spec = format!("{}/2", k + 1);
        batch(&[s(&manifest), "--out", s(shard), "--shard", &spec, "-q"]);
    }
    let lines: Vec<Value> = shards.iter().flat_map(|d| records(d)).collect();
    assert_eq!((count(&lines, "ok"), count(&lines, "error")), (12, 1));
    let tracks_dir = dir.path().join("tracks");
    let v = common::json_of(&[
        "track",
        s(&shards[0]),
        s(&shards[1]),
        "--out",
        s(&tracks_dir),
        "--json",
        "-q",
    ]);
    let table = era_io::tracks::read_tracks(&tracks_dir.join("tracks.parquet")).unwrap();
    let records = truth["records"].as_array().unwrap();
    let true_f = |id: &str, m: usize| -> f64 {
        let r = records.iter().find(|r| r["id"] == id).unwrap();
        r["frequencies_hz"][m].as_f64().unwrap()
    };
    // Every true mode (each is in all 12 records) has a track in at least 11 records
    // that follows it: the slope of its frequencies within 20 % of the truth's slope by
    // the same regression over the same records.
    for m in 0..6 {
        let f0 = true_f("r0001", m);
        let track = v["tracks"]
            .as_array()
            .unwrap()
            .iter()
            .filter(|t| (t["frequency_mean_hz"].as_f64().unwrap() / f0 - 1.0).abs() < 0.02)
            .max_by_key(|t| t["records"].as_u64().unwrap())
            .unwrap_or_else(|| panic!("no track near {f0} Hz: {v:#}"));
        assert!(track["records"].as_u64().unwrap() >= 11, "{track}");
        let id = track["track"].as_u64().unwrap() as u32;
        let points: Vec<(f64, f64)> = table
            .iter()
            .filter(|r| r.track == id)
            .map(|r| (r.x, true_f(&r.record_id, m)))
            .collect();
        let n = points.len() as f64;
        let (mx, my) = (
            points.iter().map(|p| p.0).sum::<f64>() / n,
            points.iter().map(|p| p.1).sum::<f64>() / n,
        );
        let sxy: f64 = points.iter().map(|p| (p.0 - mx) * (p.1 - my)).sum();
        let sxx: f64 = points.iter().map(|p| (p.0 - mx).powi(2)).sum();
        let expected = sxy / sxx / my;
        let got = track["trend"]["relative_slope"].as_f64().unwrap();
        assert!(
            (got / expected - 1.0).abs() < 0.2,
            "mode at {f0} Hz: slope {got} per day, the truth's {expected}"
        );
    }
}

/// The study of the fleet chapter, smaller: 36 hourly records (5 minutes each) with a
/// daily temperature cycle, and a 5 % stiffness loss from record 24. `era track` finds
/// the change at record 24; the same fleet without the damage has none.
#[test]
fn a_damage_is_found_where_it_happened_and_nowhere_without_one() {
    let dir = tempfile::tempdir().unwrap();
    for damage in [true, false] {
        let out = dir.path().join(format!("fleet-{damage}"));
        let mut args = vec![
            "simulate",
            "fleet",
            "--records",
            "36",
            "--record-length",
            "300",
        ];
        args.extend(["--seed", "7", "--out", s(&out), "-q"]);
        if damage {
            args.extend(["--damage", "24:0.05"]);
        }
        common::assert_success(&era().args(&args).output().unwrap());
        let results = dir.path().join(format!("results-{damage}"));
        let (code, err) = batch(&[s(&out.join("fleet.toml")), "--out", s(&results), "-q"]);
        assert_eq!(code, Some(0), "{err}");
        let tracks = dir.path().join(format!("tracks-{damage}"));
        let v = common::json_of(&["track", s(&results), "--out", s(&tracks), "--json", "-q"]);
        let change = &v["change"];
        assert_eq!(change["significant"], damage, "{change:#}");
        if damage {
            assert_eq!(change["first_record"], "r0024", "{change:#}");
            // Every mode falls (by 1 to 5 % of its stiffness: 0.5 to 2.5 % in frequency).
            for st in change["steps"].as_array().unwrap() {
                let r = st["relative_step"].as_f64().unwrap();
                assert!((-0.03..-0.003).contains(&r), "{st}");
            }
        }
    }
}
