//! Issue 16's messages and facts through the `era` binary: a file of the wrong kind
//! (time histories, HDF5, semicolons) is refused with the remedy; FRFs starting a whole
//! number of increments above 0 Hz are padded in every format; `--units` and
//! `--freq-variable`; a missing file is named once; CSV → MAT → UFF keeps the quantity,
//! the units and the channel table.

use crate::common;
use common::assert_success;
use common::hostile::run_capped;
use common::{data_file, era, expect_input_error, json_of, s, write};

/// A 2 x 1 velocity FRF in SI units at nodes 11 -Y and 12 +Z, driven at node 101 +X.
const SI_CSV: &str = "# quantity: velocity\n# response_unit: m/s\n# force_unit: N\n\
# output_1: node 11 -Y\n# output_2: node 12 +Z\n# input_1: node 101 +X\n\
frequency_hz,H1_1_re,H1_1_im,H2_1_re,H2_1_im\n\
0,0,0,0,0\n0.5,1,-1,2,0.5\n1,3,0.5,-1,1\n1.5,1,1,0.25,-2\n";

#[test]
fn time_histories_given_as_frfs_are_sent_to_era_frf() {
    let dir = tempfile::tempdir().unwrap();
    let csv = write(
        dir.path(),
        "th.csv",
        "time_s,force,accel\n0,1,2\n0.001,3,4\n",
    );
    let h5 = data_file("ladisk-plate-sweep/view_0.hdf5");
    let mat = data_file("daisy-steel-subframe/flexible_structure_dat.mat");
    for file in [&csv, &h5, &mat] {
        let out = run_capped(&["identify", s(file), "--states", "2"], None, None);
        out.assert_input_error()
            .says(s(file))
            .says(&format!("era frf {}", s(file)))
            .says(&format!("era identify --from-time {}", s(file)));
        assert!(!out.stderr.contains("UTF-8"), "{}", out.stderr);
    }
}

#[test]
fn a_semicolon_csv_is_told_its_separator_not_echoed() {
    let dir = tempfile::tempdir().unwrap();
    let f = write(
        dir.path(),
        "semi.csv",
        "frequency_hz;H1_1_re;H1_1_im\n0;1;1\n1;2;2\n",
    );
    let out = run_capped(&["identify", s(&f), "--states", "2"], None, None);
    out.assert_input_error()
        .says("separated by semicolons")
        .says("save the file with ','");
    assert!(
        !out.stderr.contains("frequency_hz;H1_1_re"),
        "{}",
        out.stderr
    );
}

#[test]
fn a_missing_file_is_named_once() {
    let dir = tempfile::tempdir().unwrap();
    let missing = dir.path().join("nothing_here.csv");
    for verb in [
        vec!["identify", s(&missing), "--states", "2"],
        vec!["info", s(&missing)],
    ] {
        let out = run_capped(&verb, None, None);
        out.assert_input_error().says("No such file");
        assert_eq!(
            out.stderr.matches("nothing_here.csv").count(),
            1,
            "{}",
            out.stderr
        );
    }
}

#[test]
fn a_late_start_is_padded_in_csv_and_mat_and_an_off_grid_one_refused() {
    let dir = tempfile::tempdir().unwrap();
    let late = write(
        dir.path(),
        "late.csv",
        "# quantity: velocity\nfrequency_hz,H1_1_re,H1_1_im\n1,1,2\n1.5,3,4\n2,5,6\n",
    );
    let out = era()
        .args(["convert", s(&late), "late.mat"])
        .current_dir(dir.path())
        .output()
        .unwrap();
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert_success(&out);
    assert!(
        stdout.contains("the lines start at 1 Hz; the 2 lines below were added as zeros"),
        "{stdout}"
    );
    let info = json_of(&["info", s(&dir.path().join("late.mat")), "--json"]);
    assert_eq!(info["lines"], 5, "{info}");
    assert_eq!(info["quantity"], "velocity", "{info}");
    // The padded values are zeros and the file's own follow.
    let back = dir.path().join("back.csv");
    let status = era()
        .args(["convert", s(&dir.path().join("late.mat")), s(&back)])
        .output()
        .unwrap();
    assert!(status.status.success());
    let text = std::fs::read_to_string(&back).unwrap();
    let rows: Vec<&str> = text.lines().filter(|l| !l.starts_with('#')).collect();
    assert_eq!(rows[1], "0,0e0,0e0", "{text}");
    assert_eq!(rows[2], "0.5,0e0,0e0", "{text}");
    assert_eq!(rows[3], "1,1e0,2e0", "{text}");
    let off = write(
        dir.path(),
        "off.csv",
        "frequency_hz,H1_1_re,H1_1_im\n0.3,1,2\n0.8,3,4\n",
    );
    run_capped(&["identify", s(&off), "--states", "2"], None, None)
        .assert_input_error()
        .says("line 2, column frequency_hz: the first line is 0.3 Hz")
        .says("export the FRFs from 0 Hz");
}

#[test]
fn units_and_channels_survive_csv_to_mat_to_uff() {
    let dir = tempfile::tempdir().unwrap();
    let csv = write(dir.path(), "si.csv", SI_CSV);
    let mat = dir.path().join("si.mat");
    let uff = dir.path().join("si.uff");
    json_of(&["convert", s(&csv), s(&mat), "--json"]);
    json_of(&["convert", s(&mat), s(&uff), "--json"]);
    let info = json_of(&["info", s(&uff), "--json"]);
    assert_eq!(info["quantity"], "velocity", "{info}");
    assert_eq!(info["response_unit"], "m/s", "{info}");
    assert_eq!(info["force_unit"], "N", "{info}");
    let channels: Vec<String> = serde_json::from_value(info["channels"].clone()).unwrap();
    assert_eq!(
        channels,
        [
            "output 1 = node 11 -Y",
            "output 2 = node 12 +Z",
            "input 1 = node 101 +X"
        ]
    );
}

#[test]
fn units_flag_sets_the_units_every_writer_keeps() {
    let dir = tempfile::tempdir().unwrap();
    let csv = write(dir.path(), "si.csv", SI_CSV);
    let out = dir.path().join("g.csv");
    let run = era()
        .args(["convert", s(&csv), s(&out), "--units", "m/s^2,N"])
        .output()
        .unwrap();
    let stdout = String::from_utf8_lossy(&run.stdout);
    assert_success(&run);
    assert!(
        stdout.contains("units m/s^2 / N from --units; the file says m/s / N"),
        "{stdout}"
    );
    let text = std::fs::read_to_string(&out).unwrap();
    assert!(
        text.contains("# response_unit: m/s^2\n") && text.contains("# force_unit: N\n"),
        "{text}"
    );
    for bad in [
        "m/s^2/N",
        "m/s^2,",
        ",N",
        "m/s^2,N,V",
        "m/s^2,a_force_unit_far_too_long",
    ] {
        // clap refuses the value: exit 2 naming the flag and the value.
        expect_input_error(&["convert", s(&csv), s(&out), "--units", bad], "--units");
        expect_input_error(&["convert", s(&csv), s(&out), "--units", bad], bad);
    }
}

#[test]
fn the_mat_frequency_variable_is_named_by_a_flag() {
    let dir = tempfile::tempdir().unwrap();
    let csv = write(dir.path(), "si.csv", SI_CSV);
    let mat = dir.path().join("si.mat");
    json_of(&["convert", s(&csv), s(&mat), "--json"]);
    let info = json_of(&["info", s(&mat), "--freq-variable", "FreqV", "--json"]);
    assert_eq!(info["lines"], 4, "{info}");
    run_capped(
        &[
            "identify",
            s(&mat),
            "--states",
            "2",
            "--freq-variable",
            "f_hz",
        ],
        None,
        None,
    )
    .assert_input_error()
    .says("no numeric variable f_hz")
    .says("FreqV 4x1");
}

#[test]
fn the_cores_remedies_reach_the_cli_as_flags() {
    let dir = tempfile::tempdir().unwrap();
    let csv = write(dir.path(), "si.csv", SI_CSV);
    run_capped(
        &[
            "identify",
            s(&csv),
            "--states",
            "2",
            "--hankel-factor",
            "300",
        ],
        None,
        None,
    )
    .assert_input_error()
    .says("Markov samples (states 2 x hankel factor 300")
    .says("lower --hankel-factor or --states, or pad with --pad-to");
}

#[test]
fn a_simulator_names_its_flags_as_they_are_typed() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("x.csv");
    let shaker = [
        "simulate",
        "shaker",
        "--modes",
        "4",
        "--outputs",
        "3",
        "--inputs",
        "1",
        "--duration",
        "30",
        "--sample-rate",
        "-5",
        "--out",
        s(&out),
    ];
    let stderr = expect_input_error(&shaker, "--sample-rate -5");
    assert!(!stderr.contains("--sample_rate"), "{stderr}");
    assert!(!out.exists());
    let fleet = dir.path().join("fleet");
    let stderr = expect_input_error(
        &[
            "simulate",
            "fleet",
            "--records",
            "2",
            "--modes",
            "0",
            "--out",
            s(&fleet),
        ],
        "--modes 0",
    );
    assert!(stderr.contains("mode"), "{stderr}");
}
