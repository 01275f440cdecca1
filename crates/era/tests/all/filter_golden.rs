//! The zero-phase Butterworth against scipy's `sosfiltfilt(butter(..., output='sos'))`
//! (golden values made by scripts/make_filter_golden.py).

use crate::common;

use era::pipeline::filter::LowPass;

#[test]
fn matches_scipy_sosfiltfilt() {
    let (header, rows) = common::read_csv("filter_scipy.csv");
    let column = |c: usize| -> Vec<f64> { rows.iter().map(|r| r[c].parse().unwrap()).collect() };
    let x = column(0);
    assert_eq!(x.len(), 2048);
    for (c, name) in header.iter().enumerate().skip(1) {
        // "order4_wn0.1": normalised cut-off 2·fc·Ts = wn, so with Ts = 1 s, fc = wn/2.
        let (order, wn) = name.trim_start_matches("order").split_once("_wn").unwrap();
        let filter = LowPass::design(
            order.parse().unwrap(),
            wn.parse::<f64>().unwrap() / 2.0,
            1.0,
        )
        .unwrap();
        let y = filter.apply(&x).unwrap();
        let expected = column(c);
        let scale = expected.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        let worst = y
            .iter()
            .zip(&expected)
            .fold(0.0f64, |m, (a, b)| m.max((a - b).abs()));
        assert!(
            worst <= 1e-10 * scale,
            "{name}: max difference {worst:e} of {scale:e}"
        );
    }
}

#[test]
fn rejects_cutoff_at_nyquist_and_short_signals() {
    assert!(LowPass::design(4, 0.5, 1.0).is_err());
    assert!(LowPass::design(0, 0.1, 1.0).is_err());
    let f = LowPass::design(4, 0.1, 1.0).unwrap();
    assert!(f.apply(&[1.0; 10]).is_err());
}
