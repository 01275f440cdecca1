//! Reading an FRF file at the thesis's size: the DTA-like 8×8 set, 801 lines, as CSV
//! (2.1 MB, about 100 000 numbers), UFF 58b and MAT, written by era's own writers.
//!
//! `cargo bench -p era-io --bench read`. "csv_numbers_serial" is the floor of one thread:
//! splitting the same text on commas and parsing every number, nothing else.

use criterion::{criterion_group, criterion_main, Criterion};
use era::sim::{ModalSpec, ModalStructure};
use era::Quantity;
use era_io::format::{read_frf_file, ReadOptions};
use std::hint::black_box;

fn numbers(text: &str) -> usize {
    text.lines()
        .filter(|l| !l.starts_with('#') && !l.starts_with('f'))
        .flat_map(|l| l.split(','))
        .filter(|c| c.trim().parse::<f64>().is_ok_and(f64::is_finite))
        .count()
}

fn read(c: &mut Criterion) {
    let structure = ModalStructure::random(&ModalSpec::default()).unwrap();
    let frf = structure.frf(801, 0.025, Quantity::Acceleration).unwrap();
    let dir = tempfile::tempdir().unwrap();
    let csv = dir.path().join("dta.csv");
    era_io::csv::write_frf_csv(&csv, &frf, &[]).unwrap();
    let uff = dir.path().join("dta.uff");
    era_io::uff::write_uff58(
        &uff,
        &frf,
        None,
        (None, None),
        era_io::uff::UffWriteOptions {
            binary: true,
            single: false,
        },
    )
    .unwrap();
    let mat = dir.path().join("dta.mat");
    era_io::mat::write_frf_mat(&mat, &frf).unwrap();
    let text = std::fs::read_to_string(&csv).unwrap();
    let opts = ReadOptions::default();

    let mut g = c.benchmark_group("read_dta_8x8_801");
    g.sample_size(30);
    g.bench_function("csv", |b| {
        b.iter(|| read_frf_file(black_box(&csv), &opts).unwrap())
    });
    g.bench_function("csv_numbers_serial", |b| {
        b.iter(|| numbers(black_box(&text)))
    });
    g.bench_function("uff58b", |b| {
        b.iter(|| read_frf_file(black_box(&uff), &opts).unwrap())
    });
    g.bench_function("mat", |b| {
        b.iter(|| read_frf_file(black_box(&mat), &opts).unwrap())
    });
    g.finish();
}

criterion_group!(benches, read);
criterion_main!(benches);
