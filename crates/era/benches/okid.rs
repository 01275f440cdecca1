//! OKID on noisy shaker records of 1, 5 and 60 minutes (2 shakers, 8 accelerometers,
//! 64 Hz, 2 % sensor noise; [`era::sim::shaker`]), with the automatic observer order and
//! 2048 Markov blocks, as `era identify --from-time --markov okid` runs it; then the peak
//! heap of each run beside the size of its record.
//!
//! `cargo bench -p era --bench okid`. The heap is counted by this binary's allocator (the
//! bytes live at once, the record's own included), so it shows what the blocked QR
//! promises: a long record is read in place, never copied into a data matrix.
//! `bench/okid_peers.sh` runs python-control's `markov` + `eigensys_realization` beside
//! era on the DaISy record.

use criterion::{criterion_group, Criterion};
use era::sim::shaker::{simulate_shaker_test, ShakerRecord, ShakerTest};
use era::sim::ModalSpec;
use era::sources::okid::{okid, OkidOptions, Record};
use std::hint::black_box;
use std::sync::atomic::Ordering;
use std::time::Duration;

#[path = "support/counting.rs"]
mod counting;
use counting::{Counting, LIVE, PEAK};

#[global_allocator]
static ALLOCATOR: Counting = Counting;

fn record(minutes: f64) -> ShakerRecord {
    let spec = ModalSpec {
        fmin_hz: 1.9,
        fmax_hz: 20.0,
        seed: 3,
        ..ModalSpec::new(8, 2, 10)
    };
    let mut test = ShakerTest::new(spec, 64.0, 60.0 * minutes);
    test.noise = 0.02;
    simulate_shaker_test(&test).expect("a valid test")
}

fn run(rec: &ShakerRecord) -> era::sources::okid::Okid {
    let ins: Vec<&[f64]> = rec.inputs.iter().map(Vec::as_slice).collect();
    let outs: Vec<&[f64]> = rec.outputs.iter().map(Vec::as_slice).collect();
    let record = Record {
        inputs: &ins,
        outputs: &outs,
    };
    let mut options = OkidOptions::default();
    options.markov_samples = 2048;
    okid(std::slice::from_ref(&record), &options).expect("OKID runs")
}

const MINUTES: [f64; 3] = [1.0, 5.0, 60.0];

fn timing(c: &mut Criterion) {
    let mut g = c.benchmark_group("okid");
    g.sample_size(10).warm_up_time(Duration::from_millis(500));
    for minutes in MINUTES {
        let rec = record(minutes);
        g.bench_function(format!("{minutes}min_2x8_64Hz"), |b| {
            b.iter(|| run(black_box(&rec)))
        });
    }
    g.finish();
}

/// The peak heap of one run of each record, beside the record's size.
fn memory() {
    println!("\nokid peak heap (this process's allocator; the record is live before OKID starts):");
    println!("| record | samples | record MB | heap peak above what was live before, MB | observer order |");
    println!("|---|---:|---:|---:|---:|");
    for minutes in MINUTES {
        let rec = record(minutes);
        let samples = rec.inputs[0].len();
        let record_mb = (samples * 10 * 8) as f64 / 1e6;
        PEAK.store(LIVE.load(Ordering::Relaxed), Ordering::Relaxed);
        let before = LIVE.load(Ordering::Relaxed);
        let found = run(&rec);
        let peak = PEAK.load(Ordering::Relaxed);
        println!(
            "| {minutes} min | {samples} | {record_mb:.1} | {:.1} | {} |",
            (peak - before) as f64 / 1e6,
            found.observer_order
        );
    }
}

criterion_group!(benches, timing);

fn main() {
    benches();
    Criterion::default().configure_from_args().final_summary();
    memory();
}
