//! `era simulate experiment` and `era compare` end to end: bytes per seed, the linear
//! check through the files, bad input (exit 2 naming the flag), and compare on identical
//! sets (zero difference, MAC 1).

use crate::common;
use common::assert_success;

use common::era;
use common::hostile::run_capped;

/// A small, fast experiment: 3 DOFs, 8 modes, 3 actuators, 1 average.
const SMALL: &[&str] = &[
    "simulate",
    "experiment",
    "--actuators",
    "3",
    "--dofs",
    "3",
    "--modes",
    "8",
    "--fmin",
    "1",
    "--fmax",
    "12",
];

fn run_small(dir: &std::path::Path, extra: &[&str]) {
    let mut args: Vec<&str> = SMALL.to_vec();
    if !extra.contains(&"--averages") {
        args.extend(["--averages", "1"]);
    }
    args.extend(extra);
    let out = era().current_dir(dir).args(&args).output().unwrap();
    assert!(
        out.status.success(),
        "{args:?}: {}",
        String::from_utf8_lossy(&out.stderr)
    );
}

#[test]
fn same_seed_same_bytes_and_coherence_beside() {
    let dir = tempfile::tempdir().unwrap();
    run_small(
        dir.path(),
        &["--seed", "4", "--compensation", "on", "--out", "a.csv"],
    );
    run_small(
        dir.path(),
        &["--seed", "4", "--compensation", "on", "--out", "b.csv"],
    );
    run_small(
        dir.path(),
        &["--seed", "5", "--compensation", "on", "--out", "c.csv"],
    );
    let read = |n: &str| std::fs::read(dir.path().join(n)).unwrap();
    assert_eq!(read("a.csv"), read("b.csv"));
    // The coherence files differ only in the first line, which names the FRF file.
    let body = |n: &str| {
        let text = String::from_utf8(read(n)).unwrap();
        text.split_once('\n').unwrap().1.to_string()
    };
    assert_eq!(body("a.coherence.csv"), body("b.coherence.csv"));
    assert_ne!(read("a.csv"), read("c.csv"));
    let coherence = String::from_utf8(read("a.coherence.csv")).unwrap();
    assert!(coherence.contains("coh3_3"));
}

#[test]
fn frictionless_experiment_matches_its_exact_frfs_through_the_files() {
    let dir = tempfile::tempdir().unwrap();
    run_small(
        dir.path(),
        &[
            "--friction-scale",
            "0",
            "--averages",
            "10",
            // Damping the analyzer's 0.025 Hz lines resolve (the Hann window's bias on
            // sharper peaks is the analyzer's, not the simulation's).
            "--damping",
            "0.02..0.05",
            "--out",
            "h1.uff",
            "--exact-out",
            "exact.csv",
        ],
    );
    // era compare of the two: small differences over the structure's band.
    let out = era()
        .current_dir(dir.path())
        .args([
            "compare",
            "h1.uff",
            "exact.csv",
            "--bands",
            "1,12",
            "--json",
        ])
        .output()
        .unwrap();
    assert_success(&out);
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    let median = v["median_difference_percent"][0].as_f64().unwrap();
    assert!(median < 10.0, "median difference {median} %");
    assert!(median > 0.0);
}

#[test]
fn compare_of_a_set_with_itself_is_zero_difference_and_mac_one() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let ok = |args: &[&str]| {
        let out = era().current_dir(d).args(args).output().unwrap();
        assert!(
            out.status.success(),
            "{args:?}: {}",
            String::from_utf8_lossy(&out.stderr)
        );
        out
    };
    ok(&[
        "simulate",
        "modal",
        "--outputs",
        "3",
        "--inputs",
        "3",
        "--modes",
        "4",
        "--fmax",
        "10",
        "--collocated",
        "--out",
        "a.csv",
    ]);
    std::fs::copy(d.join("a.csv"), d.join("b.csv")).unwrap();
    std::fs::create_dir(d.join("cmp")).unwrap();
    let out = ok(&[
        "compare",
        "a.csv",
        "b.csv",
        "--json",
        "--out",
        "cmp",
        "--identify",
        "--states",
        "8",
        "--hankel-factor",
        "5",
    ]);
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    for x in v["worst_difference_percent"].as_array().unwrap() {
        assert_eq!(x.as_f64().unwrap(), 0.0);
    }
    let modes = v["modes"].as_array().unwrap();
    assert_eq!(modes.len(), 4);
    for m in modes {
        assert!((m["mac"].as_f64().unwrap() - 1.0).abs() < 1e-9, "{m}");
        assert_eq!(m["frequency_a_hz"], m["frequency_b_hz"]);
    }
    let fit = &v["fit_percent"];
    assert_eq!(fit["a"], fit["b"]);
    let html = std::fs::read_to_string(d.join("cmp/compare.html")).unwrap();
    assert!(html.contains("Modes side by side") && html.contains("<svg"));
    assert!(d.join("cmp/pair_3_3.png").exists());
}

#[test]
fn bad_input_exits_2_naming_the_flag() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let case = |extra: &[&str], needle: &str| {
        let mut args: Vec<&str> = vec!["simulate", "experiment"];
        if !extra.contains(&"--averages") {
            args.extend(["--averages", "1"]);
        }
        args.extend(extra);
        run_capped(&args, Some(d), None)
            .assert_input_error()
            .says(needle);
    };
    case(
        &["--friction-scale", "-0.5", "--out", "x.csv"],
        "--friction-scale",
    );
    case(
        &["--dofs", "4", "--modes", "6", "--out", "x.csv"],
        "--actuators",
    );
    case(&["--actuators", "9", "--out", "x.csv"], "--actuators");
    case(&["--averages", "0", "--out", "x.csv"], "--averages");
    case(&["--out", "x.dat"], "--out");
    case(
        &[
            "--compensation",
            "on",
            "--coefficients",
            "0.1,0.2",
            "--out",
            "x.csv",
        ],
        "--coefficients",
    );
    // A structure model whose shape does not fit: 2 outputs for 3 inputs.
    let model = serde_json::json!({
        "outputs": 2, "inputs": 3, "states": 2, "time_domain": "continuous",
        "sample_time_s": null, "a": [[0.0, 1.0], [-100.0, -0.2]],
        "b": [[0.0, 0.0, 0.0], [1.0, 1.0, 1.0]], "c": [[1.0, 0.0], [0.0, 1.0]],
        "d": [[0.0, 0.0, 0.0], [0.0, 0.0, 0.0]], "singular_values": [], "modes": [],
        "real_poles": [], "parameters": {}, "hankel": {"rows": 0, "cols": 0, "path": "none"}
    });
    std::fs::write(d.join("model.json"), model.to_string()).unwrap();
    case(
        &[
            "--structure",
            "model.json",
            "--actuators",
            "2",
            "--out",
            "x.csv",
        ],
        "--structure",
    );
    // compare: sets of different shapes.
    run_capped(
        &[
            "simulate",
            "modal",
            "--outputs",
            "2",
            "--inputs",
            "2",
            "--modes",
            "2",
            "--out",
            "p.csv",
        ],
        Some(d),
        None,
    );
    run_capped(
        &[
            "simulate",
            "modal",
            "--outputs",
            "3",
            "--inputs",
            "2",
            "--modes",
            "2",
            "--out",
            "r.csv",
        ],
        Some(d),
        None,
    );
    run_capped(&["compare", "p.csv", "r.csv"], Some(d), None)
        .assert_input_error()
        .says("not on the same pairs");
    // compare --identify: identify's output flags would be silently dropped.
    for flag in [
        &["--pairs", "1:1"][..],
        &["--out", "elsewhere"],
        &["--geometry", "g.csv"],
    ] {
        let mut args = vec!["compare", "p.csv", "p.csv", "--identify", "--states", "4"];
        args.extend(flag);
        run_capped(&args, Some(d), None)
            .assert_input_error()
            .says("compare writes its own outputs");
    }
}

/// `--time-histories`: one CSV `era frf` reads and one figure per run, and the share of
/// time the excited masses stick (0 without friction, positive with it).
#[test]
fn time_histories_come_with_figures_and_the_stick_share() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let shares = |scale: &str, folder: &str| {
        std::fs::create_dir(d.join(folder)).unwrap();
        let mut args: Vec<&str> = SMALL.to_vec();
        args.extend([
            "--averages",
            "1",
            "--friction-scale",
            scale,
            "--out",
            "x.csv",
            "--time-histories",
            folder,
            "--json",
        ]);
        let out = era().current_dir(d).args(&args).output().unwrap();
        assert_success(&out);
        let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
        for run in 1..=3 {
            let png = std::fs::read(d.join(folder).join(format!("run{run}.png"))).unwrap();
            assert!(png.starts_with(b"\x89PNG") && png.len() > 10_000);
            let svg =
                std::fs::read_to_string(d.join(folder).join(format!("run{run}.svg"))).unwrap();
            assert!(svg.contains("LVT velocity") && svg.contains("dead zone"));
            assert!(d.join(folder).join(format!("run{run}.csv")).exists());
        }
        (
            v["excited_stuck_fraction"].as_f64().unwrap(),
            v["excited_above_dead_zone_fraction"].as_f64().unwrap(),
        )
    };
    let (stuck, above) = shares("0", "linear");
    assert_eq!(stuck, 0.0);
    assert!(above > 0.0 && above < 1.0, "{above}");
    let (stuck, _) = shares("1", "friction");
    assert!(stuck > 0.01, "{stuck}");
}
