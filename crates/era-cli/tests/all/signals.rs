//! Signals and concurrency: SIGINT, SIGTERM and SIGHUP end a run within a second with
//! 128 + the signal, the outputs of earlier runs whole and nothing of era's left behind;
//! two runs into one `--out` folder never mix, the second is refused while the first
//! holds it.

use crate::common::{s, truth_identify};
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

/// The longest any run here may take before the test calls it hung.
const HANG: Duration = Duration::from_secs(120);

/// Starts era with SIGINT, SIGTERM and SIGHUP at their defaults: a test runner started
/// in the background of a script has SIGINT ignored, and era keeps a signal it was
/// started with ignored.
fn spawn(args: &[&str]) -> Child {
    use std::os::unix::process::CommandExt;
    let mut command = Command::new(assert_cmd::cargo::cargo_bin("era"));
    command
        .args(args)
        .stdout(Stdio::null())
        .stderr(Stdio::piped());
    // SAFETY: between fork and exec only async-signal-safe calls (signal(2)).
    unsafe {
        command.pre_exec(|| {
            for s in [libc::SIGINT, libc::SIGTERM, libc::SIGHUP] {
                libc::signal(s, libc::SIG_DFL);
            }
            Ok(())
        });
    }
    command.spawn().unwrap()
}

/// Waits for `child`; its exit code (128 + signal when a signal ended it uncaught), its
/// stderr, and when it ended.
fn finish(mut child: Child) -> (i32, String, Instant) {
    let start = Instant::now();
    loop {
        if let Some(status) = child.try_wait().unwrap() {
            let ended = Instant::now();
            let mut err = String::new();
            use std::io::Read;
            child
                .stderr
                .take()
                .unwrap()
                .read_to_string(&mut err)
                .unwrap();
            use std::os::unix::process::ExitStatusExt;
            let code = status
                .code()
                .unwrap_or_else(|| 128 + status.signal().unwrap_or(0));
            return (code, err, ended);
        }
        assert!(start.elapsed() < HANG, "era did not end");
        std::thread::sleep(Duration::from_millis(2));
    }
}

/// Waits until an entry of `dir` whose name starts with `prefix` exists, or `child` ends.
fn wait_for_entry(dir: &Path, prefix: &str, child: &mut Child) -> bool {
    let start = Instant::now();
    while start.elapsed() < HANG {
        if entries(dir).iter().any(|n| n.starts_with(prefix)) {
            return true;
        }
        if child.try_wait().unwrap().is_some() {
            return false;
        }
        std::thread::sleep(Duration::from_millis(2));
    }
    false
}

fn entries(dir: &Path) -> Vec<String> {
    std::fs::read_dir(dir)
        .map(|r| {
            r.flatten()
                .map(|e| e.file_name().to_string_lossy().into_owned())
                .collect()
        })
        .unwrap_or_default()
}

/// Every file under `dir` (relative name → bytes).
fn snapshot(dir: &Path) -> BTreeMap<PathBuf, Vec<u8>> {
    fn walk(root: &Path, dir: &Path, out: &mut BTreeMap<PathBuf, Vec<u8>>) {
        for e in std::fs::read_dir(dir).unwrap().flatten() {
            let p = e.path();
            if e.file_type().unwrap().is_dir() {
                walk(root, &p, out);
            } else {
                out.insert(
                    p.strip_prefix(root).unwrap().to_path_buf(),
                    std::fs::read(&p).unwrap(),
                );
            }
        }
    }
    let mut out = BTreeMap::new();
    walk(dir, dir, &mut out);
    out
}

/// [`snapshot`] without the run's time stamps (the MAT header's "Created on", the
/// report's UTC time), so two runs of one command compare equal.
fn contents(dir: &Path) -> BTreeMap<PathBuf, Vec<u8>> {
    let mut files = snapshot(dir);
    for (name, bytes) in files.iter_mut() {
        match name.extension().and_then(|e| e.to_str()) {
            Some("mat") => bytes.drain(..bytes.len().min(128)).for_each(drop),
            Some("html") => {
                let text = String::from_utf8_lossy(bytes).into_owned();
                let mut kept = String::new();
                let mut rest = text.as_str();
                while let Some(at) = rest.find(" UTC") {
                    let cut = rest[..at].len().saturating_sub(19);
                    kept.push_str(&rest[..cut]);
                    rest = &rest[at + 4..];
                }
                kept.push_str(rest);
                *bytes = kept.into_bytes();
            }
            _ => {}
        }
    }
    files
}

fn no_era_leftovers(dir: &Path) {
    let left: Vec<String> = entries(dir)
        .into_iter()
        .filter(|n| n.starts_with(".era-"))
        .collect();
    assert!(
        left.is_empty(),
        "left behind in {}: {left:?}",
        dir.display()
    );
}

fn kill(child: &Child, signal: i32) -> Instant {
    let sent = Instant::now();
    // SAFETY: kill(2) on our own child's pid.
    assert_eq!(unsafe { libc::kill(child.id() as i32, signal) }, 0);
    sent
}

#[test]
fn a_signal_ends_a_long_run_within_a_second_and_leaves_the_earlier_set_whole() {
    let inputs = tempfile::tempdir().unwrap();
    let long = crate::common::dta_like_set(inputs.path(), "dta.uff");
    let small = crate::common::simulated_truth(inputs.path());
    let out = tempfile::tempdir().unwrap();
    let o = out.path();
    crate::common::era()
        .args(truth_identify(&small, "8", o))
        .assert()
        .success();
    let earlier = snapshot(o);
    assert!(earlier.contains_key(Path::new("model.json")) && earlier.len() > 8);
    for (signal, code) in [
        (libc::SIGINT, 130),
        (libc::SIGTERM, 143),
        (libc::SIGHUP, 129),
    ] {
        let mut child = spawn(&[
            "identify",
            s(&long),
            "--states",
            "auto",
            "--refine",
            "-q",
            "--out",
            s(o),
        ]);
        // The run holds the folder and has staged nothing yet: it is in its long work.
        assert!(
            wait_for_entry(o, ".era-staging-", &mut child),
            "no staging folder"
        );
        std::thread::sleep(Duration::from_millis(300));
        let sent = kill(&child, signal);
        let (exit, err, ended) = finish(child);
        let latency = ended - sent;
        eprintln!("signal {signal}: exit {exit} after {latency:?}");
        assert_eq!(exit, code, "{err}");
        assert!(latency <= Duration::from_secs(1), "{latency:?}");
        assert!(err.contains("era: stopped by SIG"), "{err}");
        assert_eq!(snapshot(o), earlier);
        no_era_leftovers(o);
    }
}

/// A signal ignored when era starts stays ignored (`nohup era …`): the run completes.
#[test]
fn a_signal_ignored_at_the_start_stays_ignored() {
    use std::os::unix::process::CommandExt;
    let inputs = tempfile::tempdir().unwrap();
    let small = crate::common::simulated_truth(inputs.path());
    let out = tempfile::tempdir().unwrap();
    let mut command = Command::new(assert_cmd::cargo::cargo_bin("era"));
    command
        .args(truth_identify(&small, "8", out.path()))
        .stdout(Stdio::null())
        .stderr(Stdio::piped());
    // SAFETY: between fork and exec only async-signal-safe calls (signal(2)).
    unsafe {
        command.pre_exec(|| {
            libc::signal(libc::SIGHUP, libc::SIG_IGN);
            Ok(())
        });
    }
    let mut child = command.spawn().unwrap();
    assert!(wait_for_entry(out.path(), ".era-staging-", &mut child));
    let _ = kill(&child, libc::SIGHUP);
    let (exit, err, _) = finish(child);
    assert_eq!(exit, 0, "{err}");
    assert!(out.path().join("model.json").exists());
}

#[test]
fn a_signal_while_a_large_file_is_written_removes_its_staged_file() {
    let out = tempfile::tempdir().unwrap();
    let o = out.path();
    let target = o.join("record.csv");
    crate::common::era()
        .args([
            "simulate",
            "shaker",
            "--duration",
            "20",
            "-q",
            "--out",
            s(&target),
        ])
        .assert()
        .success();
    let earlier = snapshot(o);
    let mut child = spawn(&[
        "simulate",
        "shaker",
        "--duration",
        "10000",
        "-q",
        "--out",
        s(&target),
    ]);
    // Its staging folder is made first; the record (140 MB) takes a second to write.
    assert!(
        wait_for_entry(o, ".era-staging-", &mut child),
        "no staging folder"
    );
    std::thread::sleep(Duration::from_millis(300));
    let sent = kill(&child, libc::SIGTERM);
    let (exit, err, ended) = finish(child);
    assert_eq!(exit, 143, "{err}");
    assert!(ended - sent <= Duration::from_secs(1));
    assert_eq!(snapshot(o), earlier);
    no_era_leftovers(o);
}

#[test]
fn a_second_run_into_a_held_folder_is_refused_and_the_first_run_s_set_is_whole() {
    let inputs = tempfile::tempdir().unwrap();
    let long = crate::common::dta_like_set(inputs.path(), "dta.uff");
    let small = crate::common::simulated_truth(inputs.path());
    let out = tempfile::tempdir().unwrap();
    let o = out.path();
    let mut first = spawn(&[
        "identify",
        s(&long),
        "--states",
        "auto",
        "-q",
        "--out",
        s(o),
    ]);
    // The staging folder is made once the lock is held and the holder's id written.
    assert!(
        wait_for_entry(o, ".era-staging-", &mut first),
        "no staging folder"
    );
    let second = crate::common::era()
        .args(truth_identify(&small, "8", o))
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&second.stderr);
    assert_eq!(second.status.code(), Some(2), "{err}");
    assert!(
        err.contains(&format!(
            "another era run (process {}) is writing into this folder",
            first.id()
        )),
        "{err}"
    );
    let (exit, err, _) = finish(first);
    assert_eq!(exit, 0, "{err}");
    // The first run's set, whole: its model is the long set's 8 x 8.
    let model: serde_json::Value =
        serde_json::from_slice(&std::fs::read(o.join("model.json")).unwrap()).unwrap();
    assert_eq!(model["outputs"], 8, "{model}");
    no_era_leftovers(o);
    // The folder is free again.
    crate::common::era()
        .args(truth_identify(&small, "8", o))
        .assert()
        .success();
}

/// Signals at every moment of a short run, its commit included: the folder is always
/// one run's whole set, the earlier or the new, never a mix.
#[test]
fn a_signal_at_any_moment_leaves_one_whole_set() {
    let inputs = tempfile::tempdir().unwrap();
    let small = crate::common::simulated_truth(inputs.path());
    let out = tempfile::tempdir().unwrap();
    let o = out.path();
    let identify = |states: &str| truth_identify(&small, states, o);
    let run = |states: &str| {
        crate::common::era()
            .args(identify(states))
            .assert()
            .success();
        contents(o)
    };
    let new = run("8");
    let old = run("6");
    assert_ne!(old, new);
    let started = Instant::now();
    run("8");
    let span = started.elapsed();
    let mut seen = BTreeMap::<&str, usize>::new();
    for k in 0..24u32 {
        // Restore the earlier set, then interrupt the new run at a point along its span.
        run("6");
        let args = identify("8");
        let args: Vec<&str> = args.iter().map(String::as_str).collect();
        let child = spawn(&args);
        std::thread::sleep(span.mul_f64(f64::from(k) / 20.0));
        let _ = kill(&child, libc::SIGINT);
        let (exit, err, _) = finish(child);
        assert!(exit == 130 || exit == 0, "exit {exit}: {err}");
        let now = contents(o);
        let which = if now == old {
            "earlier"
        } else if now == new {
            "new"
        } else {
            panic!("a mix of two runs after a signal at {k}/20 of the run");
        };
        *seen.entry(which).or_default() += 1;
        no_era_leftovers(o);
    }
    eprintln!("after the signals: {seen:?}");
    // The first signals land before or during the run: some runs were interrupted.
    assert!(seen.get("earlier").copied().unwrap_or(0) >= 1, "{seen:?}");
}
