//! UFF files written by pyuff 2.5.8 (`scripts/uff_peer.sh golden`): era must read
//! every record exactly as pyuff reads it back (where pyuff's own read-back is right).

use era::Quantity;
use era_io::uff::{frf_from_uff, read_frf_uff, read_uff, Dof};
use serde_json::Value;
use std::path::{Path, PathBuf};

fn golden() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/golden_uff")
}

fn floats(v: &Value) -> Vec<f64> {
    v.as_array()
        .unwrap()
        .iter()
        .map(|x| x.as_f64().unwrap())
        .collect()
}

#[test]
fn every_pyuff_file_reads_identically() {
    let expected: Value = era_testkit::files::read_json(golden().join("expected.json"));
    let files = expected.as_object().unwrap();
    assert_eq!(
        files.len(),
        16,
        "ASCII/binary x real/complex x single/double x even/uneven"
    );
    for (name, records) in files {
        let path = golden().join(name);
        let contents = read_uff(&path, true).unwrap_or_else(|e| panic!("{name}: {e}"));
        let records = records.as_array().unwrap();
        assert_eq!(contents.functions.len(), records.len(), "{name}");
        for (k, ((f, data), want)) in contents.functions.iter().zip(records).enumerate() {
            let data = data.as_ref().unwrap();
            let dof = |v: &Value| Dof {
                node: v[0].as_i64().unwrap(),
                direction: v[1].as_i64().unwrap(),
            };
            assert_eq!(f.response, dof(&want["response"]), "{name} record {k}");
            assert_eq!(f.reference, dof(&want["reference"]), "{name} record {k}");
            assert_eq!(f.ordinate.code(), want["ordinate"].as_i64().unwrap());
            let (x, re, im) = (floats(&want["x"]), floats(&want["re"]), floats(&want["im"]));
            // Even abscissas are min + k·inc in both readers.
            assert_eq!(data.abscissa, x, "{name} record {k}: abscissa");
            let got_re: Vec<f64> = data.values.iter().map(|v| v.re).collect();
            let got_im: Vec<f64> = data.values.iter().map(|v| v.im).collect();
            assert_eq!(got_re, re, "{name} record {k}: real parts");
            assert_eq!(got_im, im, "{name} record {k}: imaginary parts");
        }
    }
}

#[test]
fn the_frf_matrix_and_its_channel_table() {
    let path = golden().join("ascii_complex_double_even.uff");
    let contents = read_uff(&path, true).unwrap();
    assert_eq!(contents.skipped.get(&151), Some(&1));
    assert_eq!(contents.skipped.get(&164), Some(&1));
    let file = frf_from_uff(&path, &contents, Quantity::Displacement).unwrap();
    assert_eq!(
        (file.frf.outputs(), file.frf.inputs(), file.frf.lines()),
        (2, 2, 33)
    );
    assert_eq!(file.frf.quantity(), Quantity::Acceleration);
    assert!(file.quantity_given);
    let table = file.channels.unwrap();
    assert_eq!(
        table.describe(),
        [
            "output 1 = node 11 +Z (golden)",
            "output 2 = node 12 -Y (golden)",
            "input 1 = node 101 +Z (golden)",
            "input 2 = node 102 +Z (golden)"
        ]
    );
    assert!(file.metadata["notes"].contains("dataset 151"));
    // Every even file gives the same matrix to the precision it stores.
    for name in [
        "ascii_complex_single_even.uff",
        "binary_complex_double_even.uff",
        "binary_complex_single_even.uff",
    ] {
        let other = read_frf_uff(&golden().join(name), Quantity::Displacement).unwrap();
        let tol = if name.contains("single") { 1e-5 } else { 1e-11 };
        for (a, b) in file.frf.values().iter().zip(other.frf.values()) {
            assert!(
                (a - b).norm() <= tol * a.norm().max(1e-12),
                "{name}: {a} vs {b}"
            );
        }
    }
}

#[test]
fn pyuff_binary_quirks_are_read_and_noted() {
    // Complex double: the header counts half the bytes. Single: 8-byte values.
    for name in [
        "binary_complex_double_even.uff",
        "binary_real_single_even.uff",
    ] {
        let c = read_uff(&golden().join(name), true).unwrap();
        assert_eq!(c.notes.len(), 1, "{name}: {:?}", c.notes);
        assert!(
            c.notes[0].starts_with("4 binary records")
                && c.notes[0].contains("closing -1 confirms"),
            "{:?}",
            c.notes
        );
    }
    let c = read_uff(&golden().join("binary_real_double_even.uff"), true).unwrap();
    assert!(c.notes.is_empty(), "{:?}", c.notes);
}

#[test]
fn uneven_abscissa_is_read_but_refused_for_era() {
    let path = golden().join("ascii_complex_double_uneven.uff");
    let contents = read_uff(&path, true).unwrap();
    assert!(contents.functions.iter().all(|(f, _)| !f.even));
    let err = frf_from_uff(&path, &contents, Quantity::Acceleration)
        .unwrap_err()
        .to_string();
    assert!(
        err.contains("ascii_complex_double_uneven.uff")
            && err.contains("uniformly spaced")
            && err.contains("uneven"),
        "{err}"
    );
}

#[test]
fn header_only_reads_agree_with_full_reads() {
    for entry in std::fs::read_dir(golden()).unwrap() {
        let path = entry.unwrap().path();
        if path.extension().is_some_and(|e| e == "uff") {
            let full = read_uff(&path, true).unwrap();
            let heads = read_uff(&path, false).unwrap();
            let a: Vec<_> = full.functions.iter().map(|(f, _)| f).collect();
            let b: Vec<_> = heads.functions.iter().map(|(f, _)| f).collect();
            assert_eq!(a, b, "{}", path.display());
            assert_eq!(full.skipped, heads.skipped);
        }
    }
}
