//! Hostile inputs through the `era` binary, under a 4 GB address-space cap and a hang
//! watchdog: FIFOs with and without a writer, endless devices, folders, standard input,
//! a UFF far above 0 Hz, an HDF5 declaring an unwritten huge dataset, a scipy MAT file,
//! byte-order marks and escape sequences.

use crate::common;
use common::hostile::*;
use common::s;
use std::path::{Path, PathBuf};

use era_testkit::paths::io_fixture as fixture;

const FRF_CSV: &str =
    "# quantity: velocity\nfrequency_hz,H1_1_re,H1_1_im\n0,1,0\n0.5,2,-1\n1,3,0.5\n1.5,1,1\n";

fn mkfifo(path: &Path) {
    let c = std::ffi::CString::new(s(path)).unwrap();
    // SAFETY: a valid NUL-terminated path.
    assert_eq!(unsafe { libc::mkfifo(c.as_ptr(), 0o600) }, 0);
}

#[test]
fn a_fifo_without_a_writer_is_an_empty_file_not_a_hang() {
    let dir = tempfile::tempdir().unwrap();
    let fifo = dir.path().join("in.csv");
    mkfifo(&fifo);
    run_capped(&["info", s(&fifo)], None, None)
        .assert_input_error()
        .says("empty");
}

#[test]
fn a_fifo_with_a_writer_is_read_once() {
    use std::io::Write;
    use std::os::unix::io::AsRawFd;
    let dir = tempfile::tempdir().unwrap();
    let fifo = dir.path().join("in.csv");
    mkfifo(&fifo);
    // Read-write: opening never waits, and the writer exists before era opens. The data
    // fits the pipe's buffer; the writer closes once era has taken it all.
    let mut writer = std::fs::OpenOptions::new()
        .read(true)
        .write(true)
        .open(&fifo)
        .unwrap();
    writer.write_all(FRF_CSV.as_bytes()).unwrap();
    let fd = writer.as_raw_fd();
    let closer = std::thread::spawn(move || {
        loop {
            let mut pending: libc::c_int = 0;
            // SAFETY: FIONREAD writes one int.
            let r = unsafe { libc::ioctl(fd, libc::FIONREAD, &mut pending) };
            if r != 0 || pending == 0 {
                break;
            }
            std::thread::yield_now();
        }
        drop(writer);
    });
    let out = run_capped(&["info", s(&fifo)], None, None);
    closer.join().unwrap();
    out.assert_no_crash();
    assert_eq!(out.code, Some(0), "{}", out.stderr);
    assert!(
        out.stdout.contains("1 outputs x 1 inputs, 4 lines"),
        "{}",
        out.stdout
    );
}

#[test]
fn standard_input_is_read_once() {
    let out = run_capped(&["info", "/dev/stdin"], None, Some(FRF_CSV.as_bytes()));
    out.assert_no_crash();
    assert_eq!(out.code, Some(0), "{}", out.stderr);
    assert!(
        out.stdout.contains("1 outputs x 1 inputs, 4 lines"),
        "{}",
        out.stdout
    );
    let dir = tempfile::tempdir().unwrap();
    let o = dir.path().join("o.uff");
    let out = run_capped(
        &["convert", "/dev/stdin", s(&o)],
        None,
        Some(FRF_CSV.as_bytes()),
    );
    assert_eq!(out.code, Some(0), "{}", out.stderr);
    assert!(o.is_file());
}

#[test]
fn an_endless_device_stops_at_the_input_limit() {
    for args in [
        vec!["info", "/dev/zero"],
        vec!["convert", "/dev/zero", "o.csv"],
    ] {
        let dir = tempfile::tempdir().unwrap();
        run_capped_env(
            &args,
            Some(dir.path()),
            None,
            &[("ERA_MAX_INPUT_BYTES", "20000000")],
        )
        .assert_input_error()
        .says("ERA_MAX_INPUT_BYTES");
        assert!(!dir.path().join("o.csv").exists());
    }
}

#[test]
fn a_folder_is_refused_as_input() {
    let dir = tempfile::tempdir().unwrap();
    for args in [
        vec!["info", "."],
        vec!["convert", ".", "o.csv"],
        vec![
            "frf",
            "--inputs",
            "1",
            "--outputs",
            "2",
            "--out",
            "o.csv",
            ".",
        ],
    ] {
        run_capped(&args, Some(dir.path()), None)
            .assert_input_error()
            .says("folder");
    }
}

/// An ASCII UFF of the FRF CSV with the abscissa of record 7 starting at `start_hz`.
fn uff_starting_at(dir: &Path, start_hz: f64) -> PathBuf {
    let csv = dir.join("f.csv");
    std::fs::write(&csv, FRF_CSV).unwrap();
    let uff = dir.join("f.uff");
    let out = run_capped(&["convert", s(&csv), s(&uff)], None, None);
    assert_eq!(out.code, Some(0), "{}", out.stderr);
    let text = std::fs::read_to_string(&uff).unwrap();
    let lines: Vec<&str> = text.lines().collect();
    let mut patched = String::new();
    for (k, line) in lines.iter().enumerate() {
        // Line 9 of the record (after -1, 58, 5 ID lines, record 6) is record 7.
        if k == 8 {
            patched.push_str(&format!(
                "{}{:13.6e}{:13.6e}{}\n",
                &line[..30],
                start_hz,
                0.5,
                &line[56..]
            ));
        } else {
            patched.push_str(line);
            patched.push('\n');
        }
    }
    std::fs::write(&uff, patched).unwrap();
    uff
}

#[test]
fn a_uff_starting_far_above_zero_is_refused_not_padded() {
    let dir = tempfile::tempdir().unwrap();
    for start in [5e6, 1e7, 3.5e8] {
        let uff = uff_starting_at(dir.path(), start);
        run_capped(&["convert", s(&uff), "o.csv"], Some(dir.path()), None)
            .assert_input_error()
            .says("ERA_MAX_LINES");
    }
    // Near 0 Hz the missing lines are still added.
    let uff = uff_starting_at(dir.path(), 1.0);
    let out = run_capped(&["convert", s(&uff), "o.csv"], Some(dir.path()), None);
    assert_eq!(out.code, Some(0), "{}", out.stderr);
}

#[test]
fn an_hdf5_declaring_an_unwritten_huge_dataset_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let h5 = fixture("hdf5_declared_1e8x2.hdf5");
    run_capped(
        &[
            "frf",
            "--inputs",
            "1",
            "--outputs",
            "2",
            "--out",
            "o.csv",
            s(&h5),
        ],
        Some(dir.path()),
        None,
    )
    .assert_input_error()
    .says("declares shape");
}

#[test]
fn a_mat_file_written_by_scipy_is_read() {
    let mat = fixture("scipy_frf.mat");
    let out = run_capped(&["info", s(&mat)], None, None);
    assert_eq!(out.code, Some(0), "{}", out.stderr);
    assert!(out.stdout.contains("FRF: 5x2 complex"), "{}", out.stdout);
    let dir = tempfile::tempdir().unwrap();
    let out = run_capped(
        &["convert", "--outputs", "2", s(&mat), "o.csv"],
        Some(dir.path()),
        None,
    );
    assert_eq!(out.code, Some(0), "{}", out.stderr);
    let csv = std::fs::read_to_string(dir.path().join("o.csv")).unwrap();
    assert_eq!(csv.lines().filter(|l| !l.starts_with('#')).count(), 6);
}

#[test]
fn byte_order_marks_are_accepted() {
    let dir = tempfile::tempdir().unwrap();
    let frf = dir.path().join("bom.csv");
    std::fs::write(&frf, format!("\u{feff}{FRF_CSV}")).unwrap();
    let out = run_capped(&["info", s(&frf)], None, None);
    assert_eq!(out.code, Some(0), "{}", out.stderr);
    let mut time = String::from("\u{feff}time_s,force,acc\n");
    for k in 0..256 {
        let t = k as f64 / 64.0;
        time.push_str(&format!("{t},{},{}\n", (t * 3.0).sin(), (t * 5.0).cos()));
    }
    let th = dir.path().join("time.csv");
    std::fs::write(&th, time).unwrap();
    let out = run_capped(
        &[
            "frf",
            "--inputs",
            "force",
            "--outputs",
            "acc",
            "--frame",
            "64",
            "--out",
            "h.csv",
            s(&th),
        ],
        Some(dir.path()),
        None,
    );
    out.assert_no_crash();
    assert_eq!(out.code, Some(0), "{}", out.stderr);
}

#[test]
fn escape_sequences_in_a_file_are_not_echoed_raw() {
    let dir = tempfile::tempdir().unwrap();
    let cases = [
        "frequency_hz,H1_1_re,\u{1b}]0;owned\u{7}\u{1b}[2J\n0,1,0\n",
        "# quantity: \u{1b}[31mred\nfrequency_hz,H1_1_re,H1_1_im\n0,1,0\n",
        "frequency_hz,H1_1_re,H1_1_im\n0,1,\u{1b}[5mx\n",
    ];
    for (k, body) in cases.iter().enumerate() {
        let f = dir.path().join(format!("esc{k}.csv"));
        std::fs::write(&f, body).unwrap();
        run_capped(&["info", s(&f)], None, None)
            .assert_input_error()
            .says("\\u{1b}");
    }
}

#[test]
fn mutated_uff_and_mat_files_through_the_binary() {
    let dir = tempfile::tempdir().unwrap();
    let uff = std::fs::read(uff_starting_at(dir.path(), 0.0)).unwrap();
    let mat = std::fs::read(fixture("scipy_frf.mat")).unwrap();
    let mut rng = Rng(0x5eed_1234);
    for k in 0..16 {
        let (base, ext) = if k % 2 == 0 {
            (&uff, "uff")
        } else {
            (&mat, "mat")
        };
        let bytes = if k % 4 < 2 {
            bit_flips(base, &mut rng, 3)
        } else {
            truncation(base, &mut rng)
        };
        let f = dir.path().join(format!("m{k}.{ext}"));
        std::fs::write(&f, bytes).unwrap();
        run_capped(
            &["convert", "--outputs", "2", s(&f), "o.csv"],
            Some(dir.path()),
            None,
        )
        .assert_no_crash();
        run_capped(&["info", s(&f)], None, None).assert_no_crash();
    }
}
