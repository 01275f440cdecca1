//! The cost of a stabilization diagram (docs/src/design.md §10) against one identification at
//! its largest order, at the thesis's DTA size: 8×8 continuous-time FRFs with 5 % noise,
//! 40 modes, 801 lines, thesis preprocessing (lh 5, ni 1, nz 3, ndpts 1024). The scan
//! covers 40 orders, 4..160:4, from one factorization of the H0 of 160 states; the
//! identification is `--states 160`. Target: the scan within 3× the identification.
//!
//! `cargo bench -p era --bench stabilization`.

use criterion::{criterion_group, criterion_main, Criterion};
use era::identify::{identify, EraOptions, Order, ScanOptions};
use era::modal::stabilization::OrderRange;
use era::sim::{add_noise, ModalSpec, ModalStructure};
use era::Quantity;
use std::hint::black_box;

fn stabilization(c: &mut Criterion) {
    let spec = ModalSpec {
        collocated: true,
        ..ModalSpec::default()
    };
    let structure = ModalStructure::random(&spec).unwrap();
    let frf = add_noise(
        &structure.frf(801, 0.025, Quantity::Acceleration).unwrap(),
        0.05,
        1,
    )
    .unwrap();
    let at_160 = {
        let mut o = EraOptions::thesis_dta();
        o.order = Order::Fixed(160);
        o
    };
    // The scan beside a tiny fixed-order model, so that it is what the bench times.
    let small = {
        let mut o = at_160.clone();
        o.order = Order::Scan { states: 2 };
        o.scan = ScanOptions::default();
        o.scan.orders = Some(OrderRange::parse("4..160:4").unwrap());
        o
    };
    let mut g = c.benchmark_group("dta_8x8_noisy");
    g.sample_size(10);
    g.bench_function("identify_160_states", |b| {
        b.iter(|| identify(black_box(&frf), &at_160).unwrap())
    });
    g.bench_function("stabilization_40_orders_to_160", |b| {
        b.iter(|| identify(black_box(&frf), &small).unwrap())
    });
    g.finish();
}

criterion_group!(benches, stabilization);
criterion_main!(benches);
