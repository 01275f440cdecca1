//! Output-only identification (`era::oma`, SSI-cov at the automatic order with the
//! 12-block jackknife) on noisy records with the forces left out: 10 minutes of 8
//! accelerometers at 64 Hz (the target case: 10 modes 1–20 Hz, 2 unmeasured
//! white-noise forces, 2 % sensor noise), 60 minutes of the same, and 60 minutes of 30
//! channels at 100 Hz (12 modes 0.5–30 Hz, 3 forces); then the peak heap of each run
//! beside the size of its record.
//!
//! `cargo bench -p era --bench oma`. The heap is counted by this binary's allocator: the
//! correlations are summed chunk by chunk, so a longer record adds its own bytes and
//! nothing more. `bench/oma_peers.sh` runs pyOMA2 and koma beside the `era oma` process.

use criterion::{criterion_group, Criterion};
use era::sim::shaker::{simulate_shaker_test, ShakerRecord, ShakerTest};
use era::sim::ModalSpec;
use era::{oma, Oma, OmaOptions};
use std::hint::black_box;
use std::sync::atomic::Ordering;
use std::time::Duration;

#[path = "support/counting.rs"]
mod counting;
use counting::{Counting, LIVE, PEAK};

#[global_allocator]
static ALLOCATOR: Counting = Counting;

/// A record case: name, outputs, forces, modes, band, sample rate, minutes.
struct Case {
    name: &'static str,
    outputs: usize,
    forces: usize,
    modes: usize,
    band_hz: (f64, f64),
    fs: f64,
    minutes: f64,
}

const CASES: [Case; 3] = [
    Case {
        name: "10min_8ch_64Hz",
        outputs: 8,
        forces: 2,
        modes: 10,
        band_hz: (1.0, 20.0),
        fs: 64.0,
        minutes: 10.0,
    },
    Case {
        name: "60min_8ch_64Hz",
        outputs: 8,
        forces: 2,
        modes: 10,
        band_hz: (1.0, 20.0),
        fs: 64.0,
        minutes: 60.0,
    },
    Case {
        name: "60min_30ch_100Hz",
        outputs: 30,
        forces: 3,
        modes: 12,
        band_hz: (0.5, 30.0),
        fs: 100.0,
        minutes: 60.0,
    },
];

fn record(case: &Case) -> ShakerRecord {
    let spec = ModalSpec {
        fmin_hz: case.band_hz.0,
        fmax_hz: case.band_hz.1,
        seed: 5,
        ..ModalSpec::new(case.outputs, case.forces, case.modes)
    };
    let mut test = ShakerTest::new(spec, case.fs, 60.0 * case.minutes);
    test.noise = 0.02;
    simulate_shaker_test(&test).expect("a valid test")
}

fn run(rec: &ShakerRecord, fs: f64) -> Oma {
    let outs: Vec<&[f64]> = rec.outputs.iter().map(Vec::as_slice).collect();
    oma(&[outs.as_slice()], &OmaOptions::new(fs)).expect("OMA runs")
}

fn timing(c: &mut Criterion) {
    let mut g = c.benchmark_group("oma");
    g.sample_size(10).warm_up_time(Duration::from_millis(500));
    for case in &CASES {
        let rec = record(case);
        g.bench_function(case.name, |b| b.iter(|| run(black_box(&rec), case.fs)));
    }
    g.finish();
}

/// The peak heap of one run of each record, beside the record's size, and what it found.
fn memory() {
    println!("\nmd: `era::oma` peak heap (this process's allocator; the record is live before the call):");
    println!("| record | samples | record MB | heap peak above what was live before, MB | lags | physical modes (true) |");
    println!("|---|---:|---:|---:|---:|---:|");
    for case in &CASES {
        let rec = record(case);
        let samples = rec.outputs[0].len();
        let record_mb = (samples * case.outputs * 8) as f64 / 1e6;
        PEAK.store(LIVE.load(Ordering::Relaxed), Ordering::Relaxed);
        let before = LIVE.load(Ordering::Relaxed);
        let found = run(&rec, case.fs);
        let peak = PEAK.load(Ordering::Relaxed);
        let physical = found
            .identification
            .quality
            .iter()
            .filter(|q| q.physical)
            .count();
        println!(
            "| {} | {samples} | {record_mb:.1} | {:.1} | {} | {physical} ({}) |",
            case.name,
            (peak - before) as f64 / 1e6,
            found.lags,
            case.modes
        );
    }
}

criterion_group!(benches, timing);

fn main() {
    benches();
    Criterion::default().configure_from_args().final_summary();
    memory();
}
