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
    batch(&[s(&manifest), "--out", s(&two), "--jobs", "2", "-q"]);
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
                .filter(|f| f.path().extension().is_some_and(|x| x == "json"))
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
