//! The cost model of the matrix-free ERA core (docs/src/design.md §7): wall time against the
//! Hankel's size `m` (block rows = block columns), the outputs `q`, the inputs `p` and the
//! order `n`, one varied at a time around the thesis case, with the fitted exponent of
//! each, and the ratio of the time to its floor.
//!
//! `cargo run --release -p era --example cost_model [-- REPEATS]` (default 3, medians)
//! prints markdown tables; `bench/tables.sh cost_model` writes them into the book.
//!
//! **The floor** of a run is what its truncated SVD cannot avoid: the FFT Hankel
//! products alone ([`era::pipeline::hankel_op::HankelOperator`]), one `H·X` and one `Hᵀ·Y` with as
//! many columns as the run's passes multiplied in all (`TruncatedSvd::columns`: a narrow
//! block a pass in the unrestarted phase, `n + oversample` in the restarted one), timed
//! here on their own. `total / floor` is then what orthogonalisation, the small SVDs, the
//! restarts and the products of the realization (§1.9) add.
//!
//! Data: [`era::sim::lightly_damped_markov`] (lightly damped modes, seed 7, `n/2` modes
//! of `n` states), with 1 % white noise on every Markov sample so that the spectrum past
//! the order has no gap, as measured data has none; and the DTA-like thesis case
//! (`ModalSpec::default()`, 801 lines, 5 % noise on the FRFs, thesis preprocessing).
//!
//! **The automatic path** (a second table): `identify` at `Order::Auto` with the measured
//! preset's preprocessing (what `era identify FILE --states auto` runs on a CSV), then
//! the refinement from its start with the CLI's defaults, on 8 × 8 sets of 10, 20, 40
//! and 60 modes in 0.5–14 Hz (5 % noise, 801 lines), each stage from `StageTimings`:
//! the probe and the scan's factorization (`hankel_svd`), the realizations of the scan,
//! the choice, and the refinement, with the exponent of each in the number of modes.

use era::identify::identify;
use era::linalg::rng::Minstd;
use era::linalg::tsvd::TruncatedSvdOptions;
use era::linalg::LinearOperator;
use era::pipeline::hankel::HankelShape;
use era::pipeline::hankel_op::HankelOperator;
use era::pipeline::realize::{realize_general, RealizeOptions, SvdPath};
use era::refine::identification::refine_identification;
use era::refine::{RefineOptions, Weighting};
use era::sim::{add_noise, lightly_damped_markov, ModalSpec, ModalStructure};
use era::sources::frf::preprocess::preprocess;
use era::sources::frf::{markov_from_frf, MarkovSequence};
use era::Quantity;
use faer::Mat;
use std::time::Instant;

#[path = "../benches/support/sets.rs"]
mod sets;

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

/// `markov` with white noise of `level` times its RMS added to every sample.
fn noisy(markov: &MarkovSequence, level: f64) -> MarkovSequence {
    let (q, p, k) = (markov.outputs(), markov.inputs(), markov.samples());
    let mut sum = 0.0;
    for s in 0..k {
        for i in 0..q {
            for j in 0..p {
                sum += markov.get(s, i, j).powi(2);
            }
        }
    }
    let rms = (sum / (k * q * p) as f64).sqrt();
    let mut rng = Minstd::new(11);
    let noise: Vec<f64> = (0..k * q * p).map(|_| rng.normal() * level * rms).collect();
    MarkovSequence::from_fn(q, p, k, |s, i, j| {
        markov.get(s, i, j) + noise[(s * q + i) * p + j]
    })
}

struct Row {
    label: String,
    m: usize,
    q: usize,
    p: usize,
    n: usize,
    seconds: f64,
    passes: usize,
    floor: f64,
    /// The truncated SVD alone, by kind of work: products, orthogonalisation,
    /// Rayleigh–Ritz (s).
    parts: (f64, f64, f64),
}

fn measure(label: String, markov: &MarkovSequence, m: usize, n: usize, repeats: usize) -> Row {
    let shape = HankelShape {
        block_rows: m,
        block_cols: m,
        first_sample: 1,
    };
    let options = {
        let mut o = RealizeOptions::new(n, 1);
        o.svd = SvdPath::MatrixFree;
        o
    };
    let mut times = Vec::new();
    let mut passes = 0;
    for _ in 0..repeats {
        let clock = Instant::now();
        let r = realize_general(markov, 1.0, &options, shape).expect("realizes");
        times.push(clock.elapsed().as_secs_f64());
        passes = r.svd_iterations.unwrap_or(0);
    }
    // The floor: the products each way of as many columns as the SVD multiplied.
    let op = HankelOperator::new(markov, shape).expect("shape fits");
    let svd =
        era::linalg::tsvd::truncated_svd(&op, &TruncatedSvdOptions::new(n)).expect("converges");
    assert_eq!(svd.iterations, passes, "the same SVD as the run's");
    let t = svd.timings;
    let x = Mat::from_fn(op.ncols(), svd.columns, |i, j| {
        ((i * 31 + j * 17) % 101) as f64 - 50.0
    });
    let y = Mat::from_fn(op.nrows(), svd.columns, |i, j| {
        ((i * 29 + j * 13) % 97) as f64 - 48.0
    });
    let mut floors = Vec::new();
    for _ in 0..repeats {
        let clock = Instant::now();
        std::hint::black_box(op.apply(x.as_ref()));
        std::hint::black_box(op.apply_transpose(y.as_ref()));
        floors.push(clock.elapsed().as_secs_f64());
    }
    Row {
        label,
        m,
        q: markov.outputs(),
        p: markov.inputs(),
        n,
        seconds: median(times),
        passes,
        floor: median(floors),
        parts: (t.products, t.orthogonalisation, t.rayleigh_ritz),
    }
}

/// Least-squares slope of `ln y` on `ln x`.
fn exponent(points: &[(f64, f64)]) -> f64 {
    let k = points.len() as f64;
    let (lx, ly): (Vec<f64>, Vec<f64>) = points.iter().map(|(x, y)| (x.ln(), y.ln())).unzip();
    let (mx, my) = (lx.iter().sum::<f64>() / k, ly.iter().sum::<f64>() / k);
    let sxy: f64 = lx.iter().zip(&ly).map(|(a, b)| (a - mx) * (b - my)).sum();
    let sxx: f64 = lx.iter().map(|a| (a - mx).powi(2)).sum();
    sxy / sxx
}

/// One markdown row: the case, its Hankel, the time, the passes, the floor and the
/// split of the SVD's time.
fn print(row: &Row) {
    let parts = row.parts.0 + row.parts.1 + row.parts.2;
    println!(
        "| {} | {} × {} | {:.4} s | {} | {:.4} s | {:.1} | {:.0} / {:.0} / {:.0} % |",
        row.label,
        row.m * row.q,
        row.m * row.p,
        row.seconds,
        row.passes,
        row.floor,
        row.seconds / row.floor,
        100.0 * row.parts.0 / parts,
        100.0 * row.parts.1 / parts,
        100.0 * row.parts.2 / parts,
    );
}

fn main() {
    let repeats: usize = std::env::args()
        .nth(1)
        .map_or(3, |r| r.parse().expect("REPEATS: a count"));
    println!(
        "| case | H0 | time | passes | floor (products) | × floor | SVD: products / orth. / Ritz |"
    );
    println!("|---|---|---:|---:|---:|---:|---:|");
    // The thesis case first.
    let structure = ModalStructure::random(&ModalSpec::default()).expect("DTA-like set");
    let clean = structure
        .frf(801, 0.025, Quantity::Acceleration)
        .expect("FRF");
    let frf = add_noise(&clean, 0.05, 42).expect("noise");
    let pre = preprocess(&frf, 1, 1024, 3).expect("preprocess");
    let dta = markov_from_frf(&pre.frf).expect("Markov");
    print(&measure(
        "thesis: DTA-like, 5 % noise".into(),
        &dta,
        199,
        80,
        repeats,
    ));

    let data = |q: usize, p: usize, n: usize, m: usize| {
        noisy(&lightly_damped_markov(q, p, n / 2, 2 * m + 2, 7), 0.01)
    };
    let mut fits = Vec::new();
    let mut sweep = |name: &str, rows: Vec<Row>, x: fn(&Row) -> usize| {
        for r in &rows {
            print(r);
        }
        let points: Vec<(f64, f64)> = rows.iter().map(|r| (x(r) as f64, r.seconds)).collect();
        let floor: Vec<(f64, f64)> = rows.iter().map(|r| (x(r) as f64, r.floor)).collect();
        fits.push((name.to_string(), exponent(&points), exponent(&floor)));
    };
    sweep(
        "m (8x8, n 80)",
        [200, 400, 800, 1600]
            .into_iter()
            .map(|m| {
                measure(
                    format!("m {m} (8×8, n 80)"),
                    &data(8, 8, 80, m),
                    m,
                    80,
                    repeats,
                )
            })
            .collect(),
        |r| r.m,
    );
    sweep(
        "q (p 8, m 200, n 80)",
        [4, 8, 16, 32]
            .into_iter()
            .map(|q| {
                measure(
                    format!("q {q} (p 8, m 200, n 80)"),
                    &data(q, 8, 80, 200),
                    200,
                    80,
                    repeats,
                )
            })
            .collect(),
        |r| r.q,
    );
    sweep(
        "p (q 8, m 200, n 80)",
        [2, 4, 8, 16]
            .into_iter()
            .map(|p| {
                measure(
                    format!("p {p} (q 8, m 200, n 80)"),
                    &data(8, p, 80, 200),
                    200,
                    80,
                    repeats,
                )
            })
            .collect(),
        |r| r.p,
    );
    sweep(
        "n (8x8, m 400)",
        [40, 80, 160, 320]
            .into_iter()
            .map(|n| {
                measure(
                    format!("n {n} (8×8, m 400)"),
                    &data(8, 8, n, 400),
                    400,
                    n,
                    repeats,
                )
            })
            .collect(),
        |r| r.n,
    );
    println!("\n| fitted exponent (time ∝ xᵏ) | the whole core | the FFT products alone |");
    println!("|---|---:|---:|");
    for (name, k, kf) in fits {
        println!("| {name} | {k:.2} | {kf:.2} |");
    }
    auto_path(repeats);
}

/// The automatic path's stages against the number of modes (module doc), medians of
/// `repeats` runs each.
fn auto_path(repeats: usize) {
    println!("\n| modes (8×8, 5 %) | states scanned | probe + factorization | scan | choice | refinement | refinement iterations | found physical |");
    println!("|---:|---:|---:|---:|---:|---:|---:|---:|");
    let options = sets::measured_auto();
    let mut refine = RefineOptions::default();
    refine.weighting = Weighting::PairNoise;
    let mut points: [Vec<(f64, f64)>; 4] = Default::default();
    for modes in [10usize, 20, 40, 60] {
        let spec = ModalSpec {
            modes,
            collocated: true,
            seed: 11,
            ..ModalSpec::default()
        };
        let structure = ModalStructure::random(&spec).expect("DTA-like set");
        let frf = add_noise(
            &structure
                .frf(801, 0.025, Quantity::Acceleration)
                .expect("FRF"),
            0.05,
            11,
        )
        .expect("noise");
        let mut stages: [Vec<f64>; 4] = Default::default();
        let (mut scanned, mut iterations, mut physical) = (0, 0, 0);
        for _ in 0..repeats {
            let found = identify(&frf, &options).expect("the automatic order");
            let t = found.timings;
            scanned = found
                .stabilization
                .as_ref()
                .map_or(0, |s| s.scan.orders.last().copied().unwrap_or(0));
            let refined = refine_identification(found, &frf, &refine, &mut |_| {}, &mut |_, _| {})
                .expect("the refinement");
            iterations = refined
                .refinement
                .as_ref()
                .map_or(0, |r| r.refinement.iterations);
            physical = refined.quality.iter().filter(|q| q.physical).count();
            for (slot, v) in
                stages
                    .iter_mut()
                    .zip([t.hankel_svd, t.scan, t.selection, refined.timings.refine])
            {
                slot.push(v);
            }
        }
        let medians: Vec<f64> = stages.into_iter().map(median).collect();
        for (p, &m) in points.iter_mut().zip(&medians) {
            p.push((modes as f64, m));
        }
        println!(
            "| {modes} | {scanned} | {:.3} s | {:.3} s | {:.3} s | {:.3} s | {iterations} | {physical} |",
            medians[0], medians[1], medians[2], medians[3]
        );
    }
    let k: Vec<String> = points
        .iter()
        .map(|p| format!("{:.2}", exponent(p)))
        .collect();
    println!(
        "| exponent in the modes | | {} | {} | {} | {} | | |",
        k[0], k[1], k[2], k[3]
    );
}
