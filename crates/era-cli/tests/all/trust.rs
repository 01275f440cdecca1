//! Which modes to trust, on the data users have: simulated shaker tests with exact truth
//! through era's own analyzer (`--from-time`), exact FRFs through the refinement in both
//! time domains, the real DaISy subframe and the real LADISK plate.

use crate::common;
use common::assert_success;
use common::{data_file, era, json_of, s, stdout_of};
use std::path::Path;

/// (frequency Hz, damping ratio) of every mode of a JSON (`model.json`, or the truth
/// `era simulate --json` prints).
fn modes_of(v: &serde_json::Value) -> Vec<(f64, f64)> {
    common::modes_of(v, false)
}

/// Physical modes of a model.json: (frequency Hz, damping ratio).
fn physical(v: &serde_json::Value) -> Vec<(f64, f64)> {
    common::modes_of(v, true)
}

use common::match_frequencies as matched;

/// The shaker test: 10 modes 1.9–20 Hz, 2 shakers, 8 accelerometers, 64 Hz,
/// 300 s, 2 % sensor noise; returns the record and the true (frequency, damping).
fn shaker_test(dir: &Path, seed: u64) -> (std::path::PathBuf, Vec<(f64, f64)>) {
    let file = dir.join(format!("shaker{seed}.csv"));
    let seed = seed.to_string();
    let v = json_of(&[
        "simulate",
        "shaker",
        "--noise",
        "0.02",
        "--seed",
        &seed,
        "--out",
        s(&file),
        "--json",
    ]);
    (file, modes_of(&v))
}

/// Frames of 1024, 2048 and 4096 samples, on seeds the tuning did not use (21–23):
/// at least 9 of the 10 modes found within 2 % in every case, and the median damping
/// error of the found modes below 10 % of the true damping. Before the window
/// correction, the noise test and the satellite rule, every case had 3–6 spurious
/// physical modes and damping 10–20 % off. The target is no spurious mode at
/// all; today a weak pole beside the lowest, most lightly damped mode still passes in
/// some cases (docs/src/trust.md), so this asserts what holds: at most 2 in a case and 4
/// over the nine.
#[test]
fn a_simulated_shaker_test_gives_its_modes_and_few_spurious_ones_at_every_frame() {
    let dir = tempfile::tempdir().unwrap();
    let mut total_spurious = Vec::new();
    for seed in [21, 22, 23] {
        let (file, truth) = shaker_test(dir.path(), seed);
        for frame in ["1024", "2048", "4096"] {
            let v = json_of(&from_time(
                s(&file),
                frame,
                &["--states", "auto", "--json", "-q"],
            ));
            let found = physical(&v);
            let tf: Vec<f64> = truth.iter().map(|t| t.0).collect();
            let ff: Vec<f64> = found.iter().map(|f| f.0).collect();
            let (pairs, left) = matched(&tf, &ff, 0.02);
            assert!(
                pairs.len() >= 9,
                "seed {seed}, frame {frame}: {} of 10 found; truth {tf:?}, physical {ff:?}",
                pairs.len()
            );
            assert!(
                left.len() <= 2,
                "seed {seed}, frame {frame}: spurious {:?}; truth {tf:?}",
                left.iter().map(|&j| ff[j]).collect::<Vec<_>>()
            );
            total_spurious.extend(left.iter().map(|&j| (seed, frame, ff[j])));
            let mut errors: Vec<f64> = pairs
                .iter()
                .map(|&(i, j)| (found[j].1 - truth[i].1).abs() / truth[i].1)
                .collect();
            errors.sort_by(f64::total_cmp);
            let median = errors[errors.len() / 2];
            assert!(
                median < 0.10,
                "seed {seed}, frame {frame}: median damping error {median}"
            );
        }
    }
    assert!(total_spurious.len() <= 4, "spurious: {total_spurious:?}");
}

/// `--no-window-correction` brings the bias back: the damping of the uncorrected
/// estimate is further from the truth (the correction is what the test above measures).
/// `era identify --from-time` of a shaker test's record (2 forces, 8 accelerations) at
/// `frame`-sample frames, then `extra`.
fn from_time<'a>(file: &'a str, frame: &'a str, extra: &[&'a str]) -> Vec<&'a str> {
    let mut args = vec![
        "identify",
        file,
        "--from-time",
        "--inputs",
        "1-2",
        "--outputs",
        "3-10",
        "--frame",
        frame,
    ];
    args.extend_from_slice(extra);
    args
}

#[test]
fn the_window_correction_is_said_and_can_be_turned_off() {
    let dir = tempfile::tempdir().unwrap();
    let (file, truth) = shaker_test(dir.path(), 24);
    let args = |extra: &[&'static str]| {
        let mut args = from_time(s(&file), "1024", &["--states", "auto"]);
        args.extend_from_slice(extra);
        args
    };
    let run = |extra: &[&'static str]| stdout_of(&args(extra));
    let on = run(&[]);
    assert!(
        on.contains("window correction: the Welch estimate's hann lag window"),
        "{on}"
    );
    let off = run(&["--no-window-correction"]);
    assert!(
        !off.contains("window correction: the Welch")
            && off.contains("window correction: off (as asked)"),
        "{off}"
    );
    let damping_error = |extra: &[&'static str]| {
        let mut a = args(extra);
        a.extend(["--json", "-q", "--timings"]);
        let v = json_of(&a);
        // The frame check, a second identification, is a stage of its own.
        let check = v["timings_s"]["frame_check"].as_f64();
        assert!(check.is_some_and(|t| t > 0.0), "{}", v["timings_s"]);
        let found = physical(&v);
        let tf: Vec<f64> = truth.iter().map(|t| t.0).collect();
        let ff: Vec<f64> = found.iter().map(|f| f.0).collect();
        let (pairs, _) = matched(&tf, &ff, 0.02);
        let mut e: Vec<f64> = pairs
            .iter()
            .map(|&(i, j)| (found[j].1 - truth[i].1).abs() / truth[i].1)
            .collect();
        e.sort_by(f64::total_cmp);
        e[e.len() / 2]
    };
    let (corrected, raw) = (
        damping_error(&[]),
        damping_error(&["--no-window-correction"]),
    );
    assert!(
        corrected < raw,
        "corrected {corrected} against uncorrected {raw}"
    );
}

/// An exact continuous 3-DOF receptance through `--states auto --refine` in either
/// time domain: exactly its 3 modes, within 1e-6 (the default discrete domain used to
/// fit the zero-order-hold image to continuous data and grow junk poles from the
/// mismatch).
#[test]
fn an_exact_receptance_refines_to_its_three_modes_in_either_time_domain() {
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("r3.csv");
    let v = json_of(&[
        "simulate",
        "modal",
        "--outputs",
        "3",
        "--inputs",
        "3",
        "--modes",
        "3",
        "--fmin",
        "2",
        "--fmax",
        "10",
        "--lines",
        "401",
        "--df",
        "0.05",
        "--quantity",
        "displacement",
        "--collocated",
        "--seed",
        "5",
        "--out",
        s(&file),
        "--json",
    ]);
    let truth = modes_of(&v);
    for domain in ["discrete", "continuous"] {
        let out = era()
            .args([
                "identify",
                s(&file),
                "--states",
                "auto",
                "--refine",
                "--time-domain",
                domain,
                "--json",
            ])
            .output()
            .unwrap();
        assert_success(&out);
        let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
        let modes = v["modes"].as_array().unwrap();
        assert_eq!(modes.len(), 3, "{domain}: {} modes", modes.len());
        let found = physical(&v);
        assert_eq!(found.len(), 3, "{domain}: {found:?}");
        for ((f, z), (tf, tz)) in found.iter().zip(&truth) {
            assert!((f - tf).abs() <= 1e-6 * tf, "{domain}: {f} vs {tf}");
            assert!((z - tz).abs() <= 1e-6 * tz, "{domain}: {z} vs {tz}");
        }
        let text = String::from_utf8_lossy(&out.stderr);
        assert!(
            text.contains("fitted domain: a continuous model"),
            "{domain}: {text}"
        );
    }
}

/// The DaISy subframe (real, 28 x 2, white-noise shakers) through `--from-time
/// --states auto` at three frame lengths: at least 12 of the PROVENANCE's 14
/// reference frequencies within 0.5 Hz of physical modes, and at most 20 physical.
#[test]
fn the_daisy_subframe_gives_its_reference_modes_and_few_others() {
    for frame in ["1024", "4096"] {
        let v = common::daisy_json(&["--frame", frame, "--states", "auto", "--json", "-q"]);
        let phys: Vec<f64> = physical(&v).iter().map(|m| m.0).collect();
        let (hits, _) = common::daisy_hits(&phys);
        assert!(
            hits >= 12,
            "frame {frame}: {hits} of 14 within 0.5 Hz among {phys:?}"
        );
        assert!(
            phys.len() <= 20,
            "frame {frame}: {} physical: {phys:?}",
            phys.len()
        );
    }
}

/// The LADISK plate (real, SISO swept sine 60–500 Hz, 5 runs): with the swept band
/// given, no physical mode outside it, at most 6 physical, and the PROVENANCE's four
/// peaks (126.5, 215–221, 348.5, 454 Hz) within 2 % of physical modes, before and after
/// the refinement.
#[test]
fn the_ladisk_plate_over_its_swept_band_gives_its_four_peaks() {
    let dir = tempfile::tempdir().unwrap();
    let frf = dir.path().join("plate.csv");
    let runs: Vec<String> = ["view_0", "view_0_02", "view_0_03", "view_0_04", "view_1"]
        .iter()
        .map(|r| {
            data_file(&format!("ladisk-plate-sweep/{r}.hdf5"))
                .display()
                .to_string()
        })
        .collect();
    let mut args: Vec<&str> = vec!["frf"];
    args.extend(runs.iter().map(String::as_str));
    args.extend([
        "--inputs",
        "force",
        "--outputs",
        "acc",
        "--frame",
        "51200",
        "--window",
        "rectangular",
        "--overlap",
        "0",
        "--max-hz",
        "560",
        "--out",
        s(&frf),
        "-q",
    ]);
    let out = era().args(&args).output().unwrap();
    assert_success(&out);
    for refine in [false, true] {
        let mut args = vec![
            "identify",
            s(&frf),
            "--states",
            "auto",
            "--band",
            "60..500",
            "--json",
            "-q",
        ];
        // The default route refines (in continuous time); plain ERA is asked for.
        if !refine {
            args.push("--no-refine");
        }
        let v = json_of(&args);
        let phys: Vec<f64> = physical(&v).iter().map(|m| m.0).collect();
        assert!(
            phys.iter().all(|f| (60.0..=500.0).contains(f)),
            "refine {refine}: {phys:?}"
        );
        for (lo, hi) in [
            (126.5, 126.5),
            (215.0, 221.0),
            (348.5, 348.5),
            (454.0, 454.0),
        ] {
            assert!(
                phys.iter().any(|f| *f >= 0.98 * lo && *f <= 1.02 * hi),
                "refine {refine}: no physical mode within 2 % of {lo}..{hi} Hz in {phys:?}"
            );
        }
        if refine {
            assert!(phys.len() <= 6, "{} physical: {phys:?}", phys.len());
        }
    }
}

/// `--from-time` checks the physical modes against a second estimate at twice the
/// frame, says so, and `--no-frame-check` leaves it out.
#[test]
fn the_frame_check_is_said_and_can_be_turned_off() {
    let dir = tempfile::tempdir().unwrap();
    let (file, _) = shaker_test(dir.path(), 29);
    let run = |extra: &[&str]| stdout_of(&from_time(s(&file), "1024", extra));
    let on = run(&[]);
    assert!(
        on.contains("frame check: identified again from frames of 2048 samples"),
        "{on}"
    );
    let off = run(&["--no-frame-check"]);
    assert!(!off.contains("frame check"), "{off}");
}
