//! `era track`: a fleet's modes tables (written here with era_io::fleet::write_modes from
//! the truth of era::sim::fleet plus noise, in two shards) followed over time, and the
//! inputs it refuses.

use crate::common;
use common::{era, expect_input_error, json_of, s};
use era::sim::fleet::{fleet_record, FleetSpec};
use era::sim::ModalSpec;
use era_io::fleet::{write_modes, ModeRow};
use std::path::Path;

const RECORDS: usize = 12;
/// 2026-05-01T00:00:00Z, µs.
const START_US: i64 = 1_777_593_600_000_000;

/// The modes rows of a 12-record fleet (6 modes, 8 channels, some missing, a 2 % drift,
/// records an hour apart), one mode missing from every fourth record, and each row's
/// true frequency.
fn fleet_rows() -> Vec<(ModeRow, f64)> {
    let mut spec = FleetSpec::new(
        ModalSpec {
            fmin_hz: 1.0,
            fmax_hz: 20.0,
            seed: 7,
            ..ModalSpec::new(8, 2, 6)
        },
        RECORDS,
    );
    spec.record_s = 1.0;
    spec.daily_c = 0.0;
    spec.missing = 0.2;
    let mut state = 0x9e37_79b9_7f4a_7c15u64;
    let mut noise = move || {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        (state >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0
    };
    let mut rows = Vec::new();
    for i in 0..RECORDS {
        let r = fleet_record(&spec, i).unwrap();
        let t = &r.record.truth;
        let mut mode = 0;
        for m in 0..t.frequencies_hz.len() {
            if (i + m) % 4 == 3 {
                continue;
            }
            mode += 1;
            let f = t.frequencies_hz[m];
            let phi = &t.output_shapes[m];
            rows.push((
                ModeRow {
                    record_id: format!("rec-{i}"),
                    time_us: Some(START_US + (r.time_s * 1e6) as i64),
                    mode,
                    frequency_hz: f * (1.0 + 0.001 * noise()),
                    damping_ratio: t.damping_ratios[m] * (1.0 + 0.1 * noise()),
                    frequency_std_hz: Some(0.001 * f),
                    damping_ratio_std: Some(0.1 * t.damping_ratios[m]),
                    physical: true,
                    mpc: Some(0.99),
                    emac: None,
                    shape_re: r
                        .channels
                        .iter()
                        .map(|&c| phi[c] + 0.02 * noise())
                        .collect(),
                    shape_im: r.channels.iter().map(|_| 0.01 * noise()).collect(),
                    channels: r.channels.iter().map(|c| format!("acc{}", c + 1)).collect(),
                },
                f,
            ));
        }
    }
    rows
}

/// Two shards (even and odd records) under `dir`, a records.jsonl in the first with
/// one failed record; returns the true (time in days, frequency) of each row by track
/// key (the structure's mode, by truth frequency order in its record).
fn shards(dir: &Path) -> Vec<(ModeRow, f64)> {
    let rows = fleet_rows();
    for (k, name) in ["a", "b"].iter().enumerate() {
        let shard: Vec<ModeRow> = rows
            .iter()
            .filter(|(r, _)| {
                let i: usize = r.record_id[4..].parse().unwrap();
                i % 2 == k
            })
            .map(|(r, _)| r.clone())
            .collect();
        std::fs::create_dir_all(dir.join(name)).unwrap();
        write_modes(&dir.join(name).join("modes.parquet"), &shard).unwrap();
    }
    let mut jsonl = String::new();
    for i in (0..RECORDS).step_by(2) {
        jsonl.push_str(&format!(
            "{{\"id\":\"rec-{i}\",\"status\":\"ok\",\"message\":null,\"seconds\":0.5,\"time\":null,\"files\":[\"r{i}.csv\"]}}\n"
        ));
    }
    jsonl.push_str("{\"id\":\"bad\",\"status\":\"error\",\"message\":\"r99.csv: not a time file\",\"seconds\":0.0,\"time\":null,\"files\":[\"r99.csv\"]}\n");
    std::fs::write(dir.join("a").join("records.jsonl"), jsonl).unwrap();
    rows
}

#[test]
fn the_modes_of_two_shards_followed_over_time() {
    let dir = tempfile::tempdir().unwrap();
    let rows = shards(dir.path());
    let out = dir.path().join("tracks");
    let a = dir.path().join("a");
    let b = dir.path().join("b");
    let v = json_of(&["track", s(&a), s(&b), "--out", s(&out), "--json", "-q"]);
    for f in [
        "tracks.parquet",
        "tracks.json",
        "frequency.png",
        "frequency.svg",
        "damping.png",
        "damping.svg",
        "report.html",
    ] {
        assert!(out.join(f).is_file(), "{f} missing");
    }
    assert_eq!(v["records"], RECORDS);
    assert_eq!(v["trend_per"], "day");
    let tracks = v["tracks"].as_array().unwrap();
    assert_eq!(tracks.len(), 6, "{v:#}");
    // Every row in the table, each record's modes in distinct tracks, and each track
    // one true mode (its true frequencies within 1 % of each other's mean).
    let table = era_io::tracks::read_tracks(&out.join("tracks.parquet")).unwrap();
    assert_eq!(table.len(), rows.len());
    let truth_of = |id: &str, mode: u32| {
        rows.iter()
            .find(|(r, _)| r.record_id == id && r.mode == mode)
            .unwrap()
            .1
    };
    for t in tracks {
        let id = t["track"].as_u64().unwrap() as u32;
        let mine: Vec<_> = table.iter().filter(|r| r.track == id).collect();
        assert_eq!(mine.len() as u64, t["records"].as_u64().unwrap());
        assert!(mine.len() >= 8, "a track of {} records", mine.len());
        let truth: Vec<(f64, f64)> = mine
            .iter()
            .map(|r| (r.x, truth_of(&r.record_id, r.mode)))
            .collect();
        let mean = truth.iter().map(|p| p.1).sum::<f64>() / truth.len() as f64;
        assert!(truth.iter().all(|p| (p.1 / mean - 1.0).abs() < 0.015));
        // The slope of the truth by the same regression; within 20 %.
        let n = truth.len() as f64;
        let mx = truth.iter().map(|p| p.0).sum::<f64>() / n;
        let sxy: f64 = truth.iter().map(|p| (p.0 - mx) * (p.1 - mean)).sum();
        let sxx: f64 = truth.iter().map(|p| (p.0 - mx).powi(2)).sum();
        let expected = sxy / sxx / mean;
        let got = t["trend"]["relative_slope"].as_f64().unwrap();
        assert!(
            (got - expected).abs() < 0.2 * expected.abs(),
            "track {id}: {got} per day, truth {expected}"
        );
        assert_eq!(t["sparse"], false);
    }
    let mut pairs: Vec<(&str, u32)> = table
        .iter()
        .map(|r| (r.record_id.as_str(), r.track))
        .collect();
    pairs.sort_unstable();
    let n = pairs.len();
    pairs.dedup();
    assert_eq!(pairs.len(), n, "a record's two modes in one track");
    let html = std::fs::read_to_string(out.join("report.html")).unwrap();
    assert!(html.contains("<table>") && html.contains("trend (%/day)") && html.contains("<svg"));
    assert!(html.contains("records.jsonl: 1 error, 6 ok"), "{html}");
    // The PNG is a real image of the figure's size.
    let png = image::open(out.join("frequency.png")).unwrap();
    assert_eq!(png.width(), 1200);
}

#[test]
fn bad_folders_and_tables_are_named() {
    let dir = tempfile::tempdir().unwrap();
    shards(dir.path());
    let (a, b) = (dir.path().join("a"), dir.path().join("b"));
    let out = dir.path().join("out");
    let empty = dir.path().join("empty");
    std::fs::create_dir_all(&empty).unwrap();
    expect_input_error(
        &["track", s(&a), s(&empty), "--out", s(&out)],
        "empty: no modes.parquet",
    );
    expect_input_error(
        &["track", s(&a), s(&a), "--out", s(&out)],
        "record rec-0 is in two shards",
    );
    let broken = dir.path().join("broken");
    std::fs::create_dir_all(&broken).unwrap();
    std::fs::write(broken.join("modes.parquet"), b"PAR1 not really").unwrap();
    expect_input_error(
        &["track", s(&broken), "--out", s(&out)],
        "broken/modes.parquet",
    );
    // A duplicate across two different shards names both.
    let c = dir.path().join("c");
    std::fs::create_dir_all(&c).unwrap();
    std::fs::copy(b.join("modes.parquet"), c.join("modes.parquet")).unwrap();
    let e = era()
        .args(["track", s(&a), s(&b), s(&c), "--out", s(&out)])
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&e.stderr);
    assert_eq!(e.status.code(), Some(2), "{stderr}");
    assert!(stderr.contains(s(&b)) && stderr.contains(s(&c)), "{stderr}");
    for (flag, value, needle) in [
        ("--mac-min", "1.2", "--mac-min 1.2"),
        ("--frequency-tolerance", "0", "--frequency-tolerance 0"),
        ("--min-records", "many", "--min-records many"),
        ("--min-records", "1.5", "--min-records 1.5"),
    ] {
        expect_input_error(&["track", s(&a), "--out", s(&out), flag, value], needle);
    }
    // A bad line of records.jsonl is named with its line.
    std::fs::write(
        a.join("records.jsonl"),
        "{\"id\":\"x\",\"status\":\"ok\"}\nnot json\n",
    )
    .unwrap();
    expect_input_error(&["track", s(&a), "--out", s(&out)], "records.jsonl: line 2");
    assert!(!out.join("tracks.parquet").exists());
}

#[test]
fn without_times_the_trends_are_per_record_and_a_high_minimum_makes_every_track_sparse() {
    let dir = tempfile::tempdir().unwrap();
    let a = dir.path().join("a");
    std::fs::create_dir_all(&a).unwrap();
    let rows: Vec<ModeRow> = fleet_rows()
        .into_iter()
        .map(|(mut r, _)| {
            r.time_us = None;
            r
        })
        .collect();
    write_modes(&a.join("modes.parquet"), &rows).unwrap();
    let out = dir.path().join("t");
    let v = json_of(&[
        "track",
        s(&a),
        "--out",
        s(&out),
        "--min-records",
        "12",
        "--json",
        "-q",
    ]);
    assert_eq!(v["trend_per"], "record");
    assert!(v["origin"].is_null());
    assert_eq!(v["options"]["min_records"], 12);
    let tracks = v["tracks"].as_array().unwrap();
    assert_eq!(tracks.len(), 6);
    for t in tracks {
        assert_eq!(t["sparse"], true);
        // 2 % over 11 records, about -0.18 % per record.
        let slope = t["trend"]["relative_slope"].as_f64().unwrap();
        assert!((slope + 0.02 / 11.0).abs() < 0.2 * 0.02 / 11.0, "{slope}");
    }
    // Every track sparse: the figures draw them all rather than nothing.
    let svg = std::fs::read_to_string(out.join("frequency.svg")).unwrap();
    assert!(svg.contains("Track 6") && !svg.contains("no track"));
    let table = era_io::tracks::read_tracks(&out.join("tracks.parquet")).unwrap();
    assert!(table.iter().all(|r| r.sparse && r.time_us.is_none()));
}
