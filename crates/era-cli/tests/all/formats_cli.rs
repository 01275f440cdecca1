//! `era info`, `era convert`, UFF/MAT input to `identify`, and the malformed-file cases
//! of issue 3: each exits 2 naming the file and the record or line, without a panic.

use crate::common;
use common::{expect_input_error, s, stdout_of};
use std::path::{Path, PathBuf};

use era_testkit::paths::{io_fixture as fixture, uff_golden as golden};

/// The golden ASCII file with `edit` applied to its text.
fn edited(dir: &Path, name: &str, edit: impl Fn(&str) -> String) -> PathBuf {
    let text = std::fs::read_to_string(golden("ascii_complex_double_even.uff")).unwrap();
    let path = dir.join(name);
    std::fs::write(&path, edit(&text)).unwrap();
    path
}

#[test]
fn info_lists_channels_lines_quantity_and_units() {
    let text = stdout_of(&["info", s(&golden("ascii_complex_double_even.uff"))]);
    for needle in [
        "FRF matrix: 2 outputs x 2 inputs",
        "lines: 33 from 0 to 8 Hz, spacing 0.25 Hz",
        "quantity: acceleration",
        "units: m/s^2 / N",
        "output 2 = node 12 -Y",
        "input 2 = node 102 +Z",
        "dataset 151: 1 record (skipped)",
    ] {
        assert!(text.contains(needle), "'{needle}' in:\n{text}");
    }
    let json: serde_json::Value = serde_json::from_str(&stdout_of(&[
        "info",
        s(&golden("binary_complex_double_even.uff")),
        "--json",
    ]))
    .unwrap();
    assert_eq!(json["outputs"], 2);
    assert_eq!(json["binary_58b"], 4);
    assert_eq!(json["spacing_hz"], 0.25);
    let mat = stdout_of(&["info", s(&fixture("time_two.mat"))]);
    assert!(
        mat.contains("T: 200x3 real") && mat.contains("u: 200x1 real"),
        "{mat}"
    );
}

#[test]
fn convert_round_trips_and_era_writes_the_files_pyuff_checked() {
    let dir = tempfile::tempdir().unwrap();
    let source = golden("era/era_source.csv");
    // scripts/uff_peer.sh check: pyuff read these files with equal values. era must
    // still write them byte for byte.
    for (name, flags) in [
        ("era_ascii_double.uff", vec![]),
        ("era_binary_double.uff", vec!["--binary"]),
        ("era_ascii_single.uff", vec!["--single"]),
        ("era_binary_single.uff", vec!["--binary", "--single"]),
    ] {
        let out = dir.path().join(name);
        let mut args = vec!["convert", "-q"];
        args.extend(flags);
        args.extend([s(&source), s(&out)]);
        stdout_of(&args);
        assert_eq!(
            std::fs::read(&out).unwrap(),
            std::fs::read(golden(&format!("era/{name}"))).unwrap(),
            "{name}"
        );
    }
    // UFF -> CSV keeps the values exactly and the channel table.
    let csv = dir.path().join("back.csv");
    let mat = dir.path().join("back.mat");
    stdout_of(&[
        "convert",
        "-q",
        s(&dir.path().join("era_binary_double.uff")),
        s(&csv),
    ]);
    assert_eq!(
        std::fs::read_to_string(&csv).unwrap(),
        std::fs::read_to_string(&source).unwrap()
    );
    stdout_of(&["convert", "-q", s(&csv), s(&mat)]);
    let info = stdout_of(&["info", s(&mat)]);
    assert!(
        info.contains("FRFs: 2 outputs x 2 inputs, 33 lines"),
        "{info}"
    );
    expect_input_error(
        &["convert", s(&csv), s(&dir.path().join("x.bin"))],
        "x.bin: cannot tell the output format",
    );
    expect_input_error(
        &["convert", "--binary", s(&csv), s(&dir.path().join("x.csv"))],
        "--binary and --single apply to UFF output",
    );
}

#[test]
fn identify_reads_uff_and_writes_modes_uff_and_model_mat() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out");
    let text = stdout_of(&[
        "identify",
        s(&golden("binary_complex_double_even.uff")),
        "--preset",
        "thesis",
        "--states",
        "4",
        "--hankel-factor",
        "4",
        "--out",
        s(&out),
    ]);
    assert!(text.contains("output 1 = node 11 +Z"), "{text}");
    let modes = std::fs::read_to_string(out.join("modes.uff")).unwrap();
    assert_eq!(modes.matches("\n    55").count(), 2, "{modes}");
    assert!(modes.contains("        12\n"), "node 12 in:\n{modes}");
    assert!(out.join("model.mat").is_file());
    // The model's synthesised FRFs, as binary UFF with the measurement's channels.
    let info = stdout_of(&["info", s(&out.join("model_frf.uff"))]);
    assert!(
        info.contains("4 binary 58b") && info.contains("output 2 = node 12 -Y"),
        "{info}"
    );
    // The pyuff-checked modes file came from the same command on the CSV copy.
    let again = dir.path().join("again");
    stdout_of(&[
        "identify",
        "-q",
        s(&golden("era/era_source.csv")),
        "--preset",
        "thesis",
        "--states",
        "4",
        "--hankel-factor",
        "4",
        "--out",
        s(&again),
    ]);
    assert_eq!(
        std::fs::read_to_string(again.join("modes.uff")).unwrap(),
        std::fs::read_to_string(golden("era/era_modes.uff")).unwrap()
    );
}

#[test]
fn a_truncated_record_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let cut = edited(dir.path(), "cut.uff", |t| t[..t.len() * 6 / 10].to_string());
    expect_input_error(&["info", s(&cut)], "cut.uff");
    expect_input_error(&["identify", s(&cut), "--states", "4"], "truncated record");
    // A binary record cut inside its data.
    let bin = std::fs::read(golden("binary_real_double_even.uff")).unwrap();
    let path = dir.path().join("cut_binary.uff");
    std::fs::write(&path, &bin[..900]).unwrap();
    expect_input_error(
        &["convert", s(&path), "x.csv"],
        "record 1 (dataset 58 at line 1)",
    );
}

#[test]
fn a_wrong_field_width_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    // Record 7 written with 5-wide integers instead of 10.
    let header = edited(dir.path(), "narrow.uff", |t| {
        t.replacen(
            "         6        33         1",
            "    6   33    1               ",
            1,
        )
    });
    expect_input_error(&["info", s(&header)], "record 7 (data form)");
    expect_input_error(&["info", s(&header)], "line 25");
    // Double values written 13 wide, as single values are.
    let data = edited(dir.path(), "data13.uff", |t| {
        let mut lines: Vec<String> = t.lines().map(str::to_string).collect();
        let first_data = lines
            .iter()
            .position(|l| l.starts_with("         0    0    0    0 NONE"))
            .unwrap()
            + 1;
        lines[first_data] = "  1.00000e+00  2.00000e+00  3.00000e+00  4.00000e+00".into();
        lines.join("\n") + "\n"
    });
    expect_input_error(
        &["identify", s(&data), "--states", "4"],
        "check the field widths",
    );
}

#[test]
fn a_binary_length_that_disagrees_with_the_header_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let bin = std::fs::read(golden("binary_real_double_even.uff")).unwrap();
    // Record 1 claims 40 points; its header and data hold 33.
    let mut edited = bin.clone();
    let at = bin
        .windows(20)
        .position(|w| w == b"        33         1")
        .unwrap();
    edited[at..at + 10].copy_from_slice(b"        40");
    let path = dir.path().join("length.uff");
    std::fs::write(&path, &edited).unwrap();
    expect_input_error(
        &["info", s(&path)],
        "binary length disagrees with the header: the header says 264 bytes, 40 real double values need 320",
    );
}

#[test]
fn an_unsupported_mat_class_is_refused() {
    expect_input_error(
        &["identify", s(&fixture("cell_only.mat")), "--states", "4"],
        "unsupported class: names (cell), label (char or logical)",
    );
}

#[test]
fn a_corrupt_compressed_block_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let mut bytes = std::fs::read(fixture("frf_v7.mat")).unwrap();
    // Inside the first zlib stream (the 128-byte header, then an 8-byte tag).
    for b in &mut bytes[150..190] {
        *b ^= 0x5a;
    }
    let path = dir.path().join("corrupt.mat");
    std::fs::write(&path, &bytes).unwrap();
    expect_input_error(&["identify", s(&path), "--states", "4"], "corrupt.mat");
    expect_input_error(&["info", s(&path)], "not a readable MAT v5 file");
}

#[test]
fn an_empty_file_is_refused_in_every_format() {
    let dir = tempfile::tempdir().unwrap();
    for name in ["empty.uff", "empty.mat", "empty.csv", "empty"] {
        let path = dir.path().join(name);
        std::fs::write(&path, b"").unwrap();
        expect_input_error(&["info", s(&path)], &format!("{name}: the file is empty"));
        expect_input_error(
            &["identify", s(&path), "--states", "2"],
            "the file is empty",
        );
    }
}

#[test]
fn missing_duplicate_and_mismatched_records_and_unknown_types_are_listed() {
    let dir = tempfile::tempdir().unwrap();
    let text = std::fs::read_to_string(golden("ascii_complex_double_even.uff")).unwrap();
    // Records: 151, 164, then four FRFs; each record starts with "    -1\n    NN".
    let starts: Vec<usize> = text
        .match_indices("    -1\n    58")
        .map(|(i, _)| i)
        .collect();
    let without_last = &text[..starts[3]];
    let missing = dir.path().join("missing.uff");
    std::fs::write(&missing, without_last).unwrap();
    expect_input_error(
        &["identify", s(&missing), "--states", "2"],
        "missing FRF pairs (1 of 4): output 2 (12:-Y) from input 2 (102:+Z)",
    );
    let twice = dir.path().join("twice.uff");
    std::fs::write(&twice, format!("{text}{}", &text[starts[0]..starts[1]])).unwrap();
    expect_input_error(
        &["identify", s(&twice), "--states", "2"],
        "duplicate FRF pairs: 11:+Z from 101:+Z in records 3 and 7",
    );
    // The last FRF record on a coarser grid.
    let coarse = dir.path().join("coarse.uff");
    let (head, last) = text.split_at(starts[3]);
    std::fs::write(
        &coarse,
        format!("{head}{}", last.replacen("2.50000e-01", "5.00000e-01", 1)),
    )
    .unwrap();
    expect_input_error(
        &["identify", s(&coarse), "--states", "2"],
        "abscissas disagree with record 3 (33 points from 0 step 0.25): record 6 (12:-Y from 102:+Z): 33 points from 0 step 0.5",
    );
    let unknown = dir.path().join("unknown.uff");
    std::fs::write(
        &unknown,
        text.replacen("    4         0    0", "   77         0    0", 1),
    )
    .unwrap();
    expect_input_error(
        &["identify", s(&unknown), "--states", "2"],
        "unknown function types (0-28 are defined): record 3 has function type 77",
    );
}
