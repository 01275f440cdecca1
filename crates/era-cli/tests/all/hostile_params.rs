//! Hostile parameters: every verb with absurd values for each numeric flag, and the
//! parameter cases of issue 12, each run under a 4 GB address-space cap and a hang
//! watchdog (`common::hostile`). The promise: exit 0 or 2, never a panic, an internal
//! error, an allocation abort or a hang; an exit 2 names the flag (or parameter) at
//! fault; nothing written holds NaN or infinity.

use crate::common;
use common::hostile::*;
use std::f64::consts::PI;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

/// A 1 × 1 FRF CSV of two light modes (2 and 7 Hz), `lines` lines 0.25 Hz apart, every
/// value multiplied by `scale`; `poke` replaces line `k`'s real part.
fn frf_csv(
    dir: &Path,
    name: &str,
    lines: usize,
    scale: f64,
    poke: Option<(usize, f64)>,
) -> PathBuf {
    let mut text = String::from("# quantity: displacement\nfrequency_hz,H1_1_re,H1_1_im\n");
    for k in 0..lines {
        let f = 0.25 * k as f64;
        let w = 2.0 * PI * f;
        let (mut re, mut im) = (0.0, 0.0);
        for (fr, z, r) in [(2.0, 0.02, 1.0), (7.0, 0.01, 0.5)] {
            let wr = 2.0 * PI * fr;
            let (a, b) = (wr * wr - w * w, 2.0 * z * wr * w);
            let d = a * a + b * b;
            re += r * a / d;
            im -= r * b / d;
        }
        let (mut re, im) = (re * scale, im * scale);
        if let Some((line, v)) = poke {
            if line == k {
                re = v;
            }
        }
        let _ = writeln!(text, "{f},{re:e},{im:e}");
    }
    let p = dir.join(name);
    std::fs::write(&p, text).unwrap();
    p
}

/// A time-history CSV: a random force and a lagged, filtered response, 1024 samples at
/// 256 Hz.
fn time_csv(dir: &Path) -> PathBuf {
    let mut rng = Rng(7);
    let mut text = String::from("time_s,force,acc\n");
    let mut y = 0.0;
    for k in 0..1024 {
        let x = (rng.next_u64() % 2001) as f64 / 1000.0 - 1.0;
        y = 0.8 * y + 0.3 * x;
        let _ = writeln!(text, "{},{x},{y}", k as f64 / 256.0);
    }
    let p = dir.join("time.csv");
    std::fs::write(&p, text).unwrap();
    p
}

/// A free-decay record written by era itself.
fn decay_csv(dir: &Path) -> PathBuf {
    let p = dir.join("decay.csv");
    run_capped(
        &[
            "friction",
            "simulate",
            "--stiffness",
            "1",
            "--coulomb-force",
            "0.05",
            "--out",
            p.to_str().unwrap(),
            "-q",
        ],
        None,
        None,
    )
    .assert_no_crash();
    assert!(p.is_file());
    p
}

/// The absurd values every numeric flag gets: zero, negative, tiny, huge, not a number,
/// infinite, the largest counts (`2^64 − 2`, `2^32 + 1`) and a billion.
const ABSURD: &[&str] = &[
    "0",
    "-1",
    "1e-300",
    "1e300",
    "NaN",
    "inf",
    "-inf",
    "18446744073709551614",
    "4294967297",
    "1000000000",
];

/// One verb: its fixed arguments, and the numeric flags to attack (with extra arguments
/// a flag needs, such as `--lowpass-order` needing `--lowpass-hz`).
struct Verb {
    args: Vec<String>,
    flags: Vec<(&'static str, Vec<&'static str>)>,
}

fn verbs(dir: &Path, frf: &Path, time: &Path, decay: &Path) -> Vec<Verb> {
    let s = |v: &[&str]| v.iter().map(|x| x.to_string()).collect::<Vec<_>>();
    let p = |p: &Path| p.to_str().unwrap().to_string();
    let out = |name: &str| p(&dir.join(name));
    let no_extra = Vec::new;
    vec![
        Verb {
            args: [
                s(&["identify", &p(frf), "--states", "4", "-q"]),
                vec!["--out".into(), out("id")],
            ]
            .concat(),
            flags: vec![
                ("--states", no_extra()),
                ("--hankel-factor", no_extra()),
                ("--integrations", no_extra()),
                ("--lowpass-hz", no_extra()),
                ("--lowpass-order", vec!["--lowpass-hz", "2"]),
                ("--zero-lines", no_extra()),
                ("--pad-to", no_extra()),
                ("--orders", no_extra()),
            ],
        },
        Verb {
            args: [
                s(&[
                    "simulate",
                    "modal",
                    "--outputs",
                    "1",
                    "--inputs",
                    "1",
                    "--modes",
                    "2",
                ]),
                s(&[
                    "--lines", "65", "--df", "0.5", "--fmin", "2", "--fmax", "20", "-q",
                ]),
                vec!["--out".into(), out("modal.csv")],
            ]
            .concat(),
            flags: [
                "--outputs",
                "--inputs",
                "--modes",
                "--fmin",
                "--fmax",
                "--lines",
                "--df",
                "--noise",
                "--seed",
            ]
            .iter()
            .map(|f| (*f, no_extra()))
            .collect(),
        },
        Verb {
            args: [
                s(&["simulate", "truth-model", "-q"]),
                vec!["--out".into(), out("truth.csv")],
            ]
            .concat(),
            flags: vec![("--noise", no_extra())],
        },
        Verb {
            args: [
                s(&[
                    "friction",
                    "simulate",
                    "--stiffness",
                    "1",
                    "--coulomb-force",
                    "0.05",
                ]),
                s(&["-q", "--out"]),
                vec![out("decay_out.csv")],
            ]
            .concat(),
            flags: [
                "--coulomb-force",
                "--stiffness",
                "--natural-frequency-hz",
                "--viscous-damping-ratio",
                "--x0",
                "--sample-rate",
                "--hold",
                "--duration",
                "--noise",
            ]
            .iter()
            .map(|f| (*f, no_extra()))
            .collect(),
        },
        Verb {
            args: s(&[
                "friction",
                "tune",
                "--stiffness",
                "1",
                "--coulomb-force",
                "0.05",
                "--cycles",
                "3",
                "-q",
            ]),
            flags: [
                "--coulomb-force",
                "--stiffness",
                "--natural-frequency-hz",
                "--viscous-damping-ratio",
                "--x0",
                "--sample-rate",
                "--dead-zone",
                "--fraction",
                "--cycles",
            ]
            .iter()
            .map(|f| (*f, no_extra()))
            .collect(),
        },
        Verb {
            args: s(&["friction", "estimate", &p(decay), "-q"]),
            flags: vec![("--stiffness", no_extra())],
        },
        Verb {
            args: [
                s(&[
                    "frf",
                    &p(time),
                    "--inputs",
                    "1",
                    "--outputs",
                    "2",
                    "--frame",
                    "256",
                ]),
                s(&["-q", "--out"]),
                vec![out("est.csv")],
            ]
            .concat(),
            flags: ["--frame", "--overlap", "--max-hz", "--sample-rate"]
                .iter()
                .map(|f| (*f, no_extra()))
                .collect(),
        },
        Verb {
            args: [s(&["plot", &p(frf), "-q", "--out"]), vec![out("plot")]].concat(),
            flags: vec![("--integrations", no_extra()), ("--zero-lines", no_extra())],
        },
    ]
}

/// Every verb × numeric flag × absurd value: exit 0 or 2, an exit 2 that names the
/// flag, and nothing written with NaN or infinity. The runs go through a few threads
/// (each is small); in all they take seconds. Each thread writes into output folders of
/// its own: two runs into one `--out` folder at once are refused (one run holds it).
#[test]
fn absurd_values_for_every_numeric_flag() {
    let dir = tempfile::tempdir().unwrap();
    let frf = frf_csv(dir.path(), "frf.csv", 65, 1.0, None);
    let time = time_csv(dir.path());
    let decay = decay_csv(dir.path());
    let mut cases: Vec<(String, Vec<String>)> = Vec::new();
    for verb in verbs(dir.path(), &frf, &time, &decay) {
        for (flag, extra) in &verb.flags {
            for value in ABSURD {
                // The flag given last overrides a fixed value (clap keeps the last one
                // only for flags it allows twice), so drop the fixed one first.
                let mut args = Vec::new();
                let mut skip = false;
                for a in &verb.args {
                    if skip {
                        skip = false;
                        continue;
                    }
                    if a == flag {
                        skip = true;
                        continue;
                    }
                    args.push(a.clone());
                }
                // --flag=value, so that clap takes "-1" or "-inf" as the value and
                // not as a flag of its own.
                args.push(format!("{flag}={value}"));
                args.extend(extra.iter().map(|e| e.to_string()));
                cases.push((flag.to_string(), args));
            }
        }
    }
    assert!(cases.len() > 300, "{} cases", cases.len());
    let cases = std::sync::Mutex::new(cases.into_iter());
    let failures = std::sync::Mutex::new(Vec::new());
    std::thread::scope(|scope| {
        for worker in 0..3 {
            let (cases, failures) = (&cases, &failures);
            scope.spawn(move || loop {
                let Some((flag, args)) = cases.lock().unwrap().next() else {
                    break;
                };
                let args = own_outputs(&args, worker);
                let refs: Vec<&str> = args.iter().map(String::as_str).collect();
                let outcome = run_capped(&refs, None, None);
                let check = std::panic::catch_unwind(|| {
                    outcome.assert_no_crash();
                    if outcome.code == Some(2) {
                        // The flag is named, with or without its dashes.
                        outcome.says(flag.trim_start_matches('-'));
                    }
                });
                if check.is_err() {
                    failures.lock().unwrap().push(format!(
                        "{args:?}: exit {:?}: {}",
                        outcome.code, outcome.stderr
                    ));
                }
            });
        }
    });
    let failures = failures.into_inner().unwrap();
    assert!(
        failures.is_empty(),
        "{} failures:\n{}",
        failures.len(),
        failures.join("\n")
    );
    // Whatever the runs wrote holds only finite numbers.
    for entry in walk(dir.path()) {
        if entry.extension().is_some_and(|e| e == "csv") {
            let text = std::fs::read_to_string(&entry).unwrap_or_default();
            for bad in ["NaN", "inf", "Infinity"] {
                assert!(!text.contains(bad), "{}: holds '{bad}'", entry.display());
            }
        }
    }
}

/// `args` with the value of `--out` made the worker's own: `id` becomes `id-w1`,
/// `s.csv` becomes `s-w1.csv`.
fn own_outputs(args: &[String], worker: usize) -> Vec<String> {
    let mut out = Vec::with_capacity(args.len());
    let mut next_is_out = false;
    for a in args {
        if next_is_out {
            let p = Path::new(a);
            let stem = p
                .file_stem()
                .map(|s| s.to_string_lossy().into_owned())
                .unwrap_or_default();
            let name = match p.extension() {
                Some(ext) => format!("{stem}-w{worker}.{}", ext.to_string_lossy()),
                None => format!("{stem}-w{worker}"),
            };
            out.push(p.with_file_name(name).to_string_lossy().into_owned());
        } else {
            out.push(a.clone());
        }
        next_is_out = a == "--out";
    }
    out
}

fn walk(dir: &Path) -> Vec<PathBuf> {
    let mut out = Vec::new();
    for e in std::fs::read_dir(dir).unwrap().flatten() {
        let p = e.path();
        if p.is_dir() {
            out.extend(walk(&p));
        } else {
            out.push(p);
        }
    }
    out
}

fn run(args: &[&str]) -> Outcome {
    run_capped(args, None, None)
}

/// A dense SVD's memory is checked before the Hankel is built: a 3-line FRF padded to
/// 300 000 lines at 2000 states asked a 4999 × 4999 dense SVD, which aborted on an
/// allocation under a 4 GB cap. Under a lowered ERA_MAX_DENSE_VALUES it is refused at
/// once, naming the limit and the matrix-free path.
#[test]
fn a_dense_svd_is_checked_against_its_memory_limit() {
    let dir = tempfile::tempdir().unwrap();
    let frf = frf_csv(dir.path(), "tiny.csv", 3, 1.0, None);
    let f = frf.to_str().unwrap();
    let args = [
        "identify", f, "--pad-to", "300000", "--states", "2000", "--svd", "dense", "--preset",
        "thesis",
    ];
    run_capped_env(&args, None, None, &[("ERA_MAX_DENSE_VALUES", "10000000")])
        .assert_input_error()
        .says("ERA_MAX_DENSE_VALUES")
        .says("--svd matrix-free")
        .says("4999 x 4999");
}

#[test]
fn sizes_from_flags_are_refused_before_allocating() {
    let dir = tempfile::tempdir().unwrap();
    let frf = frf_csv(dir.path(), "frf.csv", 65, 1.0, None);
    let f = frf.to_str().unwrap();
    // --pad-to 2^64 − 2 wrapped to a capacity-overflow panic; 1e8 aborted on allocation.
    for pad in ["18446744073709551614", "18446744073709551615", "100000000"] {
        run(&["identify", f, "--states", "4", "--pad-to", pad])
            .assert_input_error()
            .says("--pad-to")
            .says("ERA_MAX_LINES");
    }
    // The limit can be raised: then the request goes on to the next check (the value
    // limit), still before any allocation.
    run_capped_env(
        &["identify", f, "--states", "4", "--pad-to", "100000000"],
        None,
        None,
        &[("ERA_MAX_LINES", "200000000"), ("ERA_MAX_VALUES", "1000")],
    )
    .assert_input_error()
    .says("ERA_MAX_VALUES");
    run(&["identify", f, "--states", "1000000", "-q"])
        .assert_input_error()
        .says("--states")
        .says("ERA_MAX_STATES");
    let out = dir.path().join("m.csv");
    let o = out.to_str().unwrap();
    for (flag, value, env) in [
        ("--lines", "1000000000", "ERA_MAX_LINES"),
        ("--modes", "1000000000", "ERA_MAX_STATES"),
        ("--outputs", "100000", "ERA_MAX_CHANNELS"),
    ] {
        run(&["simulate", "modal", flag, value, "--out", o])
            .assert_input_error()
            .says(flag)
            .says(env);
    }
    // 3000 x 3000 x 801 values are within each count's limit but not the value limit.
    run(&[
        "simulate",
        "modal",
        "--outputs",
        "3000",
        "--inputs",
        "3000",
        "--out",
        o,
    ])
    .assert_input_error()
    .says("ERA_MAX_VALUES");
    assert!(!out.exists());
    let d = dir.path().join("d.csv");
    let d = d.to_str().unwrap();
    let base = [
        "friction",
        "simulate",
        "--stiffness",
        "1",
        "--coulomb-force",
        "0.05",
    ];
    for extra in [
        &["--sample-rate", "1e9"][..],
        &["--duration", "1e9"],
        &["--hold", "1e300"],
        &["--natural-frequency-hz", "1e-9"],
    ] {
        let mut args = base.to_vec();
        args.extend_from_slice(extra);
        args.extend_from_slice(&["--out", d]);
        run(&args)
            .assert_input_error()
            .says(&extra[0][2..])
            .says("ERA_MAX_SAMPLES");
    }
    assert!(!Path::new(d).exists());
}

#[test]
fn friction_tune_work_is_bounded_and_its_result_finite() {
    let base = [
        "friction",
        "tune",
        "--stiffness",
        "1",
        "--coulomb-force",
        "0.05",
    ];
    // 100 000 cycles ran for minutes; a tiny natural frequency panicked.
    for extra in [
        &["--cycles", "100000"][..],
        &["--natural-frequency-hz", "1e-9"],
        &["--sample-rate", "1e12"],
    ] {
        let mut args = base.to_vec();
        args.extend_from_slice(extra);
        run(&args)
            .assert_input_error()
            .says(&extra[0][2..])
            .says("ERA_MAX_STEPS");
    }
    // An overflowing spring force printed "neutral coefficient inf" with exit 0, and
    // values of 1e300 ran for 15 s and printed 300 digits: no actuator has them.
    for (flag, value) in [
        ("--stiffness", "1e300"),
        ("--x0", "1e308"),
        ("--dead-zone", "1e308"),
        ("--coulomb-force", "1e300"),
    ] {
        let mut args = base.to_vec();
        let own = args.iter().position(|a| *a == flag);
        if let Some(at) = own {
            args.drain(at..at + 2);
        }
        args.extend([flag, value]);
        let o = run(&args);
        o.assert_input_error().says(flag).says("1e12");
        assert!(!o.stdout.contains("inf"), "{}", o.stdout);
    }
    // Friction above the spring force: nothing moves, no coefficient is neutral.
    run(&[
        "friction",
        "tune",
        "--stiffness",
        "1",
        "--coulomb-force",
        "100",
    ])
    .assert_input_error()
    .says("never moves");
    // The estimate refuses such a stiffness too (it printed inf and NaN with exit 0).
    let dir = tempfile::tempdir().unwrap();
    let decay = dir.path().join("decay.csv");
    run(&["friction", "simulate", "--out", decay.to_str().unwrap()]).assert_no_crash();
    run(&[
        "friction",
        "estimate",
        decay.to_str().unwrap(),
        "--stiffness",
        "1e308",
    ])
    .assert_input_error()
    .says("--stiffness")
    .says("1e12");
    // Large values inside the range print in scientific notation, never as long rows of
    // digits.
    let o = run(&[
        "friction",
        "tune",
        "--stiffness",
        "1e11",
        "--natural-frequency-hz",
        "1e6",
        "--coulomb-force",
        "1e9",
        "--x0",
        "1e3",
        "--sample-rate",
        "1e8",
    ]);
    o.assert_no_crash();
    let longest = o
        .stdout
        .split(|c: char| !c.is_ascii_digit())
        .map(str::len)
        .max()
        .unwrap_or(0);
    assert!(longest <= 12, "a number of {longest} digits: {}", o.stdout);
    // The default case still works.
    let o = run(&[
        "friction",
        "tune",
        "--stiffness",
        "1",
        "--coulomb-force",
        "0.05",
    ]);
    o.assert_no_crash();
    assert_eq!(o.code, Some(0), "{}", o.stderr);
}

#[test]
fn friction_simulate_never_writes_non_finite_samples() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path().join("d.csv");
    let o = run(&[
        "friction",
        "simulate",
        "--stiffness",
        "1",
        "--coulomb-force",
        "0",
        "--x0",
        "1e308",
        "--natural-frequency-hz",
        "100",
        "--sample-rate",
        "1000",
        "--duration",
        "1",
        "--out",
        d.to_str().unwrap(),
    ]);
    o.assert_input_error().says("x0 1e308").says("not finite");
    assert!(!d.exists());
}

#[test]
fn lowpass_cutoffs_are_checked_before_sci_rs() {
    let dir = tempfile::tempdir().unwrap();
    let frf = frf_csv(dir.path(), "frf.csv", 65, 1.0, None);
    let f = frf.to_str().unwrap();
    // 1e-300 panicked inside sci-rs; 1e-10 gave exit 1 (a NaN SVD).
    for hz in ["1e-300", "1e-10", "5e-310", "16", "1e300"] {
        run(&["identify", f, "--states", "4", "--lowpass-hz", hz])
            .assert_input_error()
            .says("lowpass-hz")
            .says("Nyquist");
    }
    let o = run(&["identify", f, "--states", "4", "--lowpass-hz", "10", "-q"]);
    assert_eq!(o.code, Some(0), "{}", o.stderr);
}

#[test]
fn huge_and_tiny_frf_magnitudes_are_identified() {
    // 1e154 and more overflowed the SVD (exit 1): the data is now identified at an exact
    // power-of-two scale and the model is of the data as given.
    let dir = tempfile::tempdir().unwrap();
    let mut frequencies = Vec::new();
    for (k, scale) in [1.0, 1e154, 1e250, 1e300, 1e-300].iter().enumerate() {
        let frf = frf_csv(dir.path(), &format!("f{k}.csv"), 65, *scale, None);
        let out = dir.path().join(format!("out{k}"));
        let args = [
            "identify",
            frf.to_str().unwrap(),
            "--states",
            "4",
            "--json",
            "-q",
            "--out",
            out.to_str().unwrap(),
        ];
        // The default route refines. Up to 1e154 it refines; beyond (1e250, 1e300,
        // 1e-300) the refinement's squared norms leave the doubles and it stops with
        // exit 2, naming the refinement (a known limit: ERA alone, below, takes them).
        let o = run(&args);
        o.assert_no_crash();
        if *scale == 1.0 || *scale == 1e154 {
            assert_eq!(o.code, Some(0), "refined x {scale:e}: {}", o.stderr);
        } else {
            assert_eq!(o.code, Some(2), "refined x {scale:e}: {}", o.stderr);
            assert!(o.stderr.contains("refining"), "{}", o.stderr);
        }
        // ERA itself identifies every scale.
        let mut plain = args.to_vec();
        plain.push("--no-refine");
        let o = run(&plain);
        o.assert_no_crash();
        assert_eq!(o.code, Some(0), "x {scale:e}: {}", o.stderr);
        let v: serde_json::Value = serde_json::from_str(&o.stdout).unwrap();
        let modes = v["modes"].as_array().expect("modes");
        let f: Vec<f64> = modes
            .iter()
            .map(|m| m["frequency_hz"].as_f64().unwrap())
            .collect();
        frequencies.push(f);
        // The plots of such a model and data render (its singular values reach 1e300).
        let o = run(&[
            "plot",
            frf.to_str().unwrap(),
            "--model",
            out.join("model.json").to_str().unwrap(),
            "-q",
            "--out",
            dir.path().join(format!("plot{k}")).to_str().unwrap(),
        ]);
        o.assert_no_crash();
        assert_eq!(o.code, Some(0), "plot x {scale:e}: {}", o.stderr);
    }
    for f in &frequencies[1..] {
        assert_eq!(f.len(), frequencies[0].len());
        for (a, b) in f.iter().zip(&frequencies[0]) {
            assert!((a - b).abs() < 1e-6 * b, "{a} vs {b}");
        }
    }
}

#[test]
fn plots_of_extreme_values_end() {
    // A 1.7e308 value made plotters loop forever (the log range rounded up to inf).
    let dir = tempfile::tempdir().unwrap();
    let cases = [
        frf_csv(dir.path(), "big.csv", 9, 1.0, Some((3, 1.7e308))),
        frf_csv(dir.path(), "max.csv", 9, 1.0, Some((3, f64::MAX))),
        frf_csv(dir.path(), "zero.csv", 9, 0.0, None),
        frf_csv(dir.path(), "sub.csv", 9, 1e-320, None),
        frf_csv(dir.path(), "two.csv", 2, 1.0, None),
        frf_csv(dir.path(), "neg.csv", 9, -1.7e308, None),
    ];
    for (k, f) in cases.iter().enumerate() {
        let o = run(&[
            "plot",
            f.to_str().unwrap(),
            "-q",
            "--out",
            dir.path().join(format!("p{k}")).to_str().unwrap(),
        ]);
        o.assert_no_crash();
        assert_eq!(o.code, Some(0), "{}: {}", f.display(), o.stderr);
    }
}

#[test]
fn counts_in_messages_never_wrap() {
    let dir = tempfile::tempdir().unwrap();
    let frf = frf_csv(dir.path(), "frf.csv", 65, 1.0, None);
    let f = frf.to_str().unwrap();
    // "needs 18446744073709551609 Markov samples" came from a wrapped product.
    for args in [
        &["--hankel-factor", "18446744073709551615"][..],
        &["--orders", "18446744073709551615"],
        &["--orders", "4,3074457345618258603"],
    ] {
        let mut all = vec!["identify", f, "--states", "4"];
        all.extend_from_slice(args);
        let o = run(&all);
        o.assert_input_error();
        for wrapped in ["18446744073709551613", "18446744073709551609"] {
            assert!(!o.stderr.contains(wrapped), "{args:?}: {}", o.stderr);
        }
    }
    // A product that saturated is said as such, not as a 20-digit number that reads like
    // a wrapped one (friction tune's work estimate for the most cycles a count holds).
    let o = run(&[
        "friction",
        "tune",
        "--stiffness",
        "1",
        "--coulomb-force",
        "0.05",
        "--cycles",
        "18446744073709551615",
    ]);
    o.assert_input_error().says("more than 1.8e19");
    // The flag's own value is echoed once; the saturated product never appears.
    assert_eq!(
        o.stderr.matches("18446744073709551615").count(),
        1,
        "{}",
        o.stderr
    );
}
