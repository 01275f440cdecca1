use super::parse::*;
use super::write58::*;
use super::*;
use era::data::frf::uniform_lines;
use era::{Complex64, FrfData, Quantity};

fn sample(q: usize, p: usize, lines: usize) -> FrfData {
    FrfData::from_fn(
        uniform_lines(lines, 0.25),
        q,
        p,
        Quantity::Acceleration,
        |i, j, k| {
            Complex64::new(
                (i + 1) as f64 * 1.234_567_890_123_4 - k as f64 / 7.0,
                -((j + 1) as f64) * 1e-7 / 3.0 + k as f64,
            )
        },
    )
    .unwrap()
}

#[test]
fn fortran_e_matches_the_fortran_layout() {
    assert_eq!(fortran_e(0.0, 13, 5), "  0.00000e+00");
    assert_eq!(fortran_e(-1.5e-3, 20, 12), " -1.500000000000e-03");
    assert_eq!(fortran_e(2.5e120, 20, 11), "  2.50000000000e+120");
    assert_eq!(fortran_e(0.25, 13, 6), " 2.500000e-01");
}

fn round_trip(opts: UffWriteOptions) -> (FrfData, FrfData) {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("x.uff");
    let frf = sample(3, 2, 11);
    write_uff58(&path, &frf, None, (Some("m/s^2"), Some("N")), opts).unwrap();
    let back = read_frf_uff(&path, Quantity::Velocity).unwrap();
    assert_eq!(back.channels, Some(ChannelTable::numbered(3, 2)));
    assert!(back.quantity_given);
    assert_eq!(back.metadata["response_unit"], "m/s^2");
    assert_eq!(back.metadata["force_unit"], "N");
    (frf, back.frf)
}

#[test]
fn binary_double_round_trip_is_exact() {
    let (a, b) = round_trip(UffWriteOptions {
        binary: true,
        single: false,
    });
    assert_eq!(a, b);
}

#[test]
fn ascii_and_single_round_trips_keep_their_digits() {
    for (opts, tol) in [
        (UffWriteOptions::default(), 1e-12),
        (
            UffWriteOptions {
                binary: true,
                single: true,
            },
            1e-7,
        ),
        (
            UffWriteOptions {
                binary: false,
                single: true,
            },
            1e-5,
        ),
    ] {
        let (a, b) = round_trip(opts);
        assert_eq!(a.frequency_hz(), b.frequency_hz());
        for (x, y) in a.values().iter().zip(b.values()) {
            assert!(
                (x - y).norm() <= tol * x.norm().max(1e-300),
                "{opts:?}: {x} vs {y}"
            );
        }
    }
}

#[test]
fn header_only_read_skips_the_data() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("x.uff");
    write_uff58(
        &path,
        &sample(2, 2, 37),
        None,
        (None, None),
        UffWriteOptions::default(),
    )
    .unwrap();
    let c = read_uff(&path, false).unwrap();
    assert_eq!(c.functions.len(), 4);
    assert!(c
        .functions
        .iter()
        .all(|(f, d)| d.is_none() && f.points == 37));
}

#[test]
fn delimiters_and_closings() {
    assert_eq!(closing_after(b"    -1\n", 0), Some(7));
    assert_eq!(closing_after(b"\r\n    -1", 0), Some(8));
    assert_eq!(closing_after(b"    -12\n", 0), None);
    assert!(looks_like_uff(b"\n    -1\n    58\n"));
    assert!(!looks_like_uff(b"frequency_hz,H1_1_re\n"));
}
