//! FRF estimation against scipy: `csd`/`coherence` and the H1, H2, Hv estimates and
//! multiple coherence computed with numpy from those spectra
//! (`scripts/make_welch_golden.py` wrote `golden/welch_scipy.json`).
//!
//! Agreement is asked to 1e-10 relative, value by value: `|era − scipy| ≤ 1e-10·|scipy|`,
//! with a floor of 1e-13 of the array's largest magnitude for values that are zero in
//! exact arithmetic (a cross-spectrum that cancels).

use era::estimate::{self, Detrend, Estimator, WelchOptions, Window};
use era::{Complex64, Quantity};
use serde_json::Value;

const REL: f64 = 1e-10;

fn load() -> Value {
    era_testkit::files::read_json(crate::common::golden("welch_scipy.json"))
}

fn rows(v: &Value) -> Vec<Vec<f64>> {
    v.as_array()
        .unwrap()
        .iter()
        .map(|r| {
            r.as_array()
                .unwrap()
                .iter()
                .map(|x| x.as_f64().unwrap())
                .collect()
        })
        .collect()
}

/// Flattens a nested array of any depth.
fn flat(v: &Value, out: &mut Vec<f64>) {
    match v {
        Value::Array(a) => a.iter().for_each(|x| flat(x, out)),
        x => out.push(x.as_f64().unwrap()),
    }
}

fn complex(v: &Value) -> Vec<Complex64> {
    let (mut re, mut im) = (vec![], vec![]);
    flat(&v["re"], &mut re);
    flat(&v["im"], &mut im);
    re.into_iter()
        .zip(im)
        .map(|(r, i)| Complex64::new(r, i))
        .collect()
}

fn real(v: &Value) -> Vec<f64> {
    let mut out = vec![];
    flat(v, &mut out);
    out
}

fn compare(what: &str, case: &str, ours: &[Complex64], theirs: &[Complex64]) -> f64 {
    compare_lines(what, case, ours, theirs, &[], 1)
}

/// As [`compare`], leaving out the given lines of each of the arrays' `lines`-long rows.
fn compare_lines(
    what: &str,
    case: &str,
    ours: &[Complex64],
    theirs: &[Complex64],
    skip: &[usize],
    lines: usize,
) -> f64 {
    assert_eq!(ours.len(), theirs.len(), "{case}: {what} length");
    let floor = 1e-13 * theirs.iter().map(|v| v.norm()).fold(0.0, f64::max);
    let mut worst = 0.0f64;
    for (k, (a, b)) in ours.iter().zip(theirs).enumerate() {
        if skip.contains(&(k % lines)) {
            assert_eq!(a.norm(), 0.0, "{case}: {what}[{k}] on an unexcited line");
            continue;
        }
        let err = (a - b).norm();
        assert!(
            err <= REL * b.norm() + floor,
            "{case}: {what}[{k}] era {a} scipy {b} (|diff| {err:.3e})"
        );
        if b.norm() > floor {
            worst = worst.max(err / b.norm());
        }
    }
    if std::env::var_os("WELCH_VERBOSE").is_some() {
        println!("  {what}: {worst:.2e}");
    }
    worst
}

fn options(case: &Value, fs: f64) -> WelchOptions {
    let mut o = WelchOptions::new(fs, case["frame"].as_u64().unwrap() as usize);
    o.overlap = case["overlap"].as_f64().unwrap();
    o.window = case["window"].as_str().unwrap().parse().unwrap();
    o.detrend = case["detrend"].as_str().unwrap().parse().unwrap();
    o
}

#[test]
fn spectra_coherence_and_estimators_match_scipy() {
    let golden = load();
    let fs = golden["sample_rate_hz"].as_f64().unwrap();
    let x = rows(&golden["inputs"]);
    let y = rows(&golden["outputs"]);
    let xs: Vec<&[f64]> = x.iter().map(Vec::as_slice).collect();
    let ys: Vec<&[f64]> = y.iter().map(Vec::as_slice).collect();
    let (p, q) = (xs.len(), ys.len());
    let cases = golden["cases"].as_array().unwrap();
    assert_eq!(cases.len(), 4);
    for case in cases {
        let opts = options(case, fs);
        let name = format!(
            "{} {} frame {} overlap {}",
            opts.window.name(),
            opts.detrend.name(),
            opts.frame,
            opts.overlap
        );
        let s = estimate::spectra(&xs, &ys, &opts, true).unwrap();
        let f = real(&case["frequency_hz"]);
        assert_eq!(s.frequency_hz().len(), f.len(), "{name}: lines");
        for (a, b) in s.frequency_hz().iter().zip(&f) {
            assert!(
                (a - b).abs() <= 1e-12 * b.abs(),
                "{name}: frequency {a} vs scipy {b}"
            );
        }
        let l = s.lines();
        let gather = |f: &dyn Fn(usize, usize) -> Vec<Complex64>, a: usize, b: usize| {
            (0..a)
                .flat_map(|i| (0..b).flat_map(move |j| f(i, j)))
                .collect::<Vec<_>>()
        };
        let mut worst = 0.0f64;
        worst = worst.max(compare(
            "Gxx",
            &name,
            &gather(&|j, k| s.gxx(j, k).to_vec(), p, p),
            &complex(&case["gxx"]),
        ));
        worst = worst.max(compare(
            "Gyx",
            &name,
            &gather(&|i, j| s.gyx(i, j).to_vec(), q, p),
            &complex(&case["gyx"]),
        ));
        worst = worst.max(compare(
            "Gyy",
            &name,
            &gather(&|i, m| s.gyy(i, m).unwrap().to_vec(), q, q),
            &complex(&case["gyy"]),
        ));
        for (est, key) in [
            (Estimator::H1, "h1"),
            (Estimator::H2, "h2"),
            (Estimator::Hv, "hv"),
        ] {
            let e = estimate::estimate(&xs, &ys, &opts, est, Quantity::Acceleration).unwrap();
            // Unexcited lines: 0 Hz when a rectangular window follows a detrend (the
            // frame sums to zero); scipy's ratios there are rounding noise.
            let skip = &e.unexcited_lines;
            let expected: Vec<usize> =
                if opts.window == Window::Rectangular && opts.detrend != Detrend::None {
                    vec![0]
                } else {
                    vec![]
                };
            assert_eq!(skip, &expected, "{name}: unexcited lines");
            worst = worst.max(compare_lines(
                key,
                &name,
                e.frf.values(),
                &complex(&case[key]),
                skip,
                l,
            ));
            let coh: Vec<Complex64> = e
                .ordinary_coherence
                .iter()
                .map(|&v| Complex64::new(v, 0.0))
                .collect();
            let theirs: Vec<Complex64> = real(&case["coherence"])
                .into_iter()
                .map(|v| Complex64::new(v, 0.0))
                .collect();
            worst = worst.max(compare_lines("coherence", &name, &coh, &theirs, skip, l));
            let mult: Vec<Complex64> = e
                .multiple_coherence
                .iter()
                .map(|&v| Complex64::new(v, 0.0))
                .collect();
            let theirs: Vec<Complex64> = real(&case["multiple_coherence"])
                .into_iter()
                .map(|v| Complex64::new(v, 0.0))
                .collect();
            worst = worst.max(compare_lines(
                "multiple coherence",
                &name,
                &mult,
                &theirs,
                skip,
                l,
            ));
            assert_eq!(e.frf.lines(), l);
        }
        println!(
            "{name}: {} frames, worst relative difference {worst:.2e}",
            s.frames()
        );
    }
}
