//! Hostile output situations: targets that are not regular files, planted symbolic
//! links, a disk that fills up mid-run, half-failed multi-output runs, leftovers of
//! killed runs, folders that take no files. Every case runs the binary through
//! `run_capped`, and checks that nothing but era's own regular outputs is touched.

use crate::common;
use common::hostile::*;
use common::s;
use std::collections::BTreeMap;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

/// Asserts a successful run.
fn ok(o: Outcome) {
    assert_eq!(o.code, Some(0), "{:?}: {}", o.args, o.stderr);
}

/// Every entry under `dir` (not following links): relative path → content (files),
/// `<link -> target>` (symbolic links), `<dir>`, `<fifo>` or `<other>`.
fn snapshot(dir: &Path) -> BTreeMap<String, Vec<u8>> {
    fn walk(root: &Path, dir: &Path, out: &mut BTreeMap<String, Vec<u8>>) {
        for e in std::fs::read_dir(dir).unwrap() {
            let e = e.unwrap();
            let p = e.path();
            let rel = p.strip_prefix(root).unwrap().to_string_lossy().into_owned();
            let t = e.file_type().unwrap();
            use std::os::unix::fs::FileTypeExt;
            let v = if t.is_symlink() {
                format!("<link -> {}>", std::fs::read_link(&p).unwrap().display()).into_bytes()
            } else if t.is_dir() {
                walk(root, &p, out);
                b"<dir>".to_vec()
            } else if t.is_file() {
                std::fs::read(&p).unwrap()
            } else if t.is_fifo() {
                b"<fifo>".to_vec()
            } else {
                b"<other>".to_vec()
            };
            out.insert(rel, v);
        }
    }
    let mut out = BTreeMap::new();
    walk(dir, dir, &mut out);
    out
}

fn mkfifo(path: &Path) {
    let c = std::ffi::CString::new(s(path)).unwrap();
    // SAFETY: a valid NUL-terminated path.
    assert_eq!(unsafe { libc::mkfifo(c.as_ptr(), 0o644) }, 0, "mkfifo");
}

/// A character device like /dev/null, made in a temp folder (root only; `false` when
/// not permitted), so that a broken writer could only ever damage this node.
fn mknull(path: &Path) -> bool {
    let c = std::ffi::CString::new(s(path)).unwrap();
    // SAFETY: a valid NUL-terminated path.
    unsafe { libc::mknod(c.as_ptr(), libc::S_IFCHR | 0o666, libc::makedev(1, 3)) == 0 }
}

fn is_root() -> bool {
    // SAFETY: geteuid has no preconditions.
    unsafe { libc::geteuid() == 0 }
}

/// The hostile kinds of target planted at `path`, beside a decoy file and a decoy
/// folder in `decoys` (outside the output folder). Returns a label per kind.
fn plant(kind: usize, path: &Path, decoys: &Path) -> Option<&'static str> {
    match kind {
        0 => {
            mkfifo(path);
            Some("FIFO")
        }
        1 => {
            std::fs::create_dir(path).unwrap();
            std::fs::write(path.join("inside"), b"keep").unwrap();
            Some("a folder")
        }
        2 => {
            std::os::unix::fs::symlink(decoys.join("decoy.txt"), path).unwrap();
            Some("a symbolic link")
        }
        3 => {
            std::os::unix::fs::symlink(decoys.join("no-such-file"), path).unwrap();
            Some("a symbolic link")
        }
        4 => mknull(path).then_some("a character device"),
        _ => None,
    }
}

const KINDS: usize = 5;

fn decoys() -> tempfile::TempDir {
    let d = tempfile::tempdir().unwrap();
    std::fs::write(d.path().join("decoy.txt"), b"precious, not era's").unwrap();
    d
}

/// A small FRF file (2 outputs x 2 inputs, 161 lines) for identify, plot and convert.
fn small_frf(dir: &Path, name: &str) -> PathBuf {
    let p = dir.join(name);
    run_capped(
        &[
            "simulate",
            "modal",
            "-q",
            "--outputs",
            "2",
            "--inputs",
            "2",
            "--modes",
            "2",
            "--fmin",
            "2",
            "--fmax",
            "6",
            "--lines",
            "161",
            "--df",
            "0.05",
            "--out",
            s(&p),
        ],
        None,
        None,
    )
    .assert_no_crash();
    assert!(p.exists(), "no {}", p.display());
    p
}

/// A two-channel time history (force, response) for `era frf`.
fn small_time(dir: &Path) -> PathBuf {
    let mut rng = Rng(17);
    let mut text = String::from("time_s,force,acc\n");
    let mut prev = 0.0;
    for k in 0..1024 {
        let u = (rng.below(2001) as f64 - 1000.0) / 1000.0;
        let y = 0.6 * u + 0.3 * prev;
        prev = u;
        let _ = writeln!(text, "{},{u},{y}", k as f64 * 0.001);
    }
    let p = dir.join("time.csv");
    std::fs::write(&p, text).unwrap();
    p
}

/// `simulate experiment` at its smallest: a two-mode structure, one actuator, one frame.
const TINY_EXPERIMENT: &[&str] = &[
    "simulate",
    "experiment",
    "-q",
    "--modes",
    "2",
    "--dofs",
    "2",
    "--fmin",
    "2",
    "--fmax",
    "5",
    "--actuators",
    "1",
    "--averages",
    "1",
];

/// The verbs that write one named file (plus, for frf, its coherence beside it), as
/// argument lists with `OUT` where the output path goes.
fn single_output_verbs(inputs: &Path) -> Vec<Vec<String>> {
    let frf = small_frf(inputs, "in.csv");
    let time = small_time(inputs);
    let v = |a: &[&str]| a.iter().map(|x| x.to_string()).collect::<Vec<_>>();
    vec![
        v(&["simulate", "truth-model", "-q", "--out", "OUT.csv"]),
        v(&[
            "simulate",
            "modal",
            "-q",
            "--outputs",
            "1",
            "--inputs",
            "1",
            "--modes",
            "1",
            "--fmin",
            "1",
            "--fmax",
            "2",
            "--lines",
            "65",
            "--df",
            "0.05",
            "--out",
            "OUT.uff",
        ]),
        v(&["convert", s(&frf), "OUT.mat", "-q"]),
        v(&["convert", s(&frf), "OUT.uff", "-q"]),
        v(&[
            "frf",
            s(&time),
            "--inputs",
            "force",
            "--outputs",
            "acc",
            "--frame",
            "128",
            "-q",
            "--out",
            "OUT.csv",
        ]),
        // The coherence goes beside it.
        v(&[TINY_EXPERIMENT, &["--out", "OUT.csv"]].concat()),
        v(&[
            "friction",
            "simulate",
            "-q",
            "--stiffness",
            "1",
            "--natural-frequency-hz",
            "1.5",
            "--coulomb-force",
            "0.05",
            "--out",
            "OUT.csv",
        ]),
    ]
}

fn with_out(args: &[String], out: &Path) -> Vec<String> {
    args.iter()
        .map(|a| match a.strip_prefix("OUT") {
            Some(ext) => format!("{}{ext}", s(out)),
            None => a.clone(),
        })
        .collect()
}

fn run(args: &[String], cwd: Option<&Path>) -> Outcome {
    let refs: Vec<&str> = args.iter().map(String::as_str).collect();
    run_capped(&refs, cwd, None)
}

#[test]
fn single_output_verbs_refuse_every_non_regular_target() {
    let inputs = tempfile::tempdir().unwrap();
    let decoy = decoys();
    let before_decoys = snapshot(decoy.path());
    for (v, verb) in single_output_verbs(inputs.path()).iter().enumerate() {
        // The verb works on a regular target.
        let ok = tempfile::tempdir().unwrap();
        let out = ok.path().join("target");
        let o = run(&with_out(verb, &out), None);
        assert_eq!(o.code, Some(0), "{verb:?}: {}", o.stderr);
        assert!(
            std::fs::read_dir(ok.path()).unwrap().count() >= 1,
            "{verb:?} wrote nothing"
        );
        for kind in 0..KINDS {
            let dir = tempfile::tempdir().unwrap();
            let ext = verb.iter().find_map(|a| a.strip_prefix("OUT")).unwrap();
            let out = dir.path().join("target");
            let target = PathBuf::from(format!("{}{ext}", s(&out)));
            let Some(what) = plant(kind, &target, decoy.path()) else {
                continue;
            };
            let before = snapshot(dir.path());
            let o = run(&with_out(verb, &out), None);
            o.assert_input_error().says(s(&target)).says(what);
            assert_eq!(
                snapshot(dir.path()),
                before,
                "verb {v} {verb:?}, kind {kind}: the folder changed"
            );
        }
    }
    assert_eq!(snapshot(decoy.path()), before_decoys);
}

/// `frf --out o.csv` whose coherence file cannot be written: o.csv keeps its old
/// content (before, it was replaced and the run failed after).
#[test]
fn frf_leaves_the_old_output_when_the_coherence_cannot_be_written() {
    let inputs = tempfile::tempdir().unwrap();
    let time = small_time(inputs.path());
    let decoy = decoys();
    for kind in 0..KINDS {
        let dir = tempfile::tempdir().unwrap();
        let out = dir.path().join("o.csv");
        std::fs::write(&out, b"old FRFs\n").unwrap();
        if plant(kind, &dir.path().join("o.coherence.csv"), decoy.path()).is_none() {
            continue;
        }
        let before = snapshot(dir.path());
        run_capped(
            &[
                "frf",
                s(&time),
                "--inputs",
                "force",
                "--outputs",
                "acc",
                "--frame",
                "128",
                "--out",
                s(&out),
            ],
            None,
            None,
        )
        .assert_input_error()
        .says("o.coherence.csv");
        assert_eq!(snapshot(dir.path()), before, "kind {kind}");
    }
    assert_eq!(
        std::fs::read(decoy.path().join("decoy.txt")).unwrap(),
        b"precious, not era's"
    );
}

/// The folder verbs (identify --out, demo --out, plot --out, compare --out,
/// simulate experiment --time-histories) refuse a hostile entry at
/// any of their output names, including the `pairs` folder, before writing anything.
#[test]
fn folder_verbs_refuse_hostile_entries_and_change_nothing() {
    let inputs = tempfile::tempdir().unwrap();
    let frf = small_frf(inputs.path(), "in.csv");
    let experiment_out = inputs.path().join("experiment.csv");
    let decoy = decoys();
    let outside = tempfile::tempdir().unwrap();
    let verbs: Vec<(Vec<&str>, &[&str])> = vec![
        (
            vec!["identify", s(&frf), "--states", "4", "-q", "--out"],
            &[
                "model.json",
                "fit.json",
                "model.mat",
                "modes.uff",
                "report.html",
                "grid.png",
            ],
        ),
        (
            vec!["plot", s(&frf), "-q", "--out"],
            &["grid.svg", "pairs/pair_2_1.png"],
        ),
        (
            vec!["compare", s(&frf), s(&frf), "-q", "--out"],
            &["compare.html", "pair_2_1.png"],
        ),
        (
            [
                TINY_EXPERIMENT,
                &["--out", s(&experiment_out), "--time-histories"],
            ]
            .concat(),
            &["run1.csv", "run1.png", "run1.svg"],
        ),
        (
            vec!["demo", "-q", "--out"],
            &[
                "truth_frf.csv",
                "noisy/model.json",
                "no_noise/pairs/pair_3_3.svg",
            ],
        ),
    ];
    let mut rng = Rng(2026);
    for (args, names) in &verbs {
        for name in names.iter() {
            // Two kinds per name, drawn from the seed (all would be slow for demo).
            for _ in 0..2 {
                let kind = rng.below(KINDS);
                let dir = tempfile::tempdir().unwrap();
                let target = dir.path().join(name);
                std::fs::create_dir_all(target.parent().unwrap()).unwrap();
                std::fs::write(dir.path().join("notes.txt"), b"the user's").unwrap();
                let Some(what) = plant(kind, &target, decoy.path()) else {
                    continue;
                };
                let before = snapshot(dir.path());
                let mut a = args.clone();
                a.push(s(dir.path()));
                run_capped(&a, None, None)
                    .assert_input_error()
                    .says(name)
                    .says(what);
                assert_eq!(snapshot(dir.path()), before, "{a:?} with {name} as {what}");
            }
        }
        // `pairs` as a symbolic link to a folder elsewhere: nothing lands there (compare
        // and the time histories write no sub-folder).
        if args[0] == "compare" || args[0] == "simulate" {
            continue;
        }
        let dir = tempfile::tempdir().unwrap();
        let pairs = if args[0] == "demo" {
            std::fs::create_dir(dir.path().join("noisy")).unwrap();
            dir.path().join("noisy/pairs")
        } else {
            dir.path().join("pairs")
        };
        std::os::unix::fs::symlink(outside.path(), &pairs).unwrap();
        let before = snapshot(dir.path());
        let mut a = args.clone();
        a.push(s(dir.path()));
        run_capped(&a, None, None)
            .assert_input_error()
            .says("pairs")
            .says("real folders");
        assert_eq!(snapshot(dir.path()), before);
        assert!(snapshot(outside.path()).is_empty());
    }
    assert_eq!(
        std::fs::read(decoy.path().join("decoy.txt")).unwrap(),
        b"precious, not era's"
    );
}

/// A full disk part way through `identify --out DIR`: the previous run's files stay
/// byte-identical, and no temporary or staging entry is left.
#[test]
fn a_full_disk_mid_run_leaves_the_previous_outputs_whole() {
    let inputs = tempfile::tempdir().unwrap();
    let frf = small_frf(inputs.path(), "in.csv");
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("run");
    ok(run_capped(
        &["identify", s(&frf), "--states", "4", "-q", "--out", s(&out)],
        None,
        None,
    ));
    let before = snapshot(&out);
    let size = |n: &str| before[n].len() as u64;
    let largest = before.values().map(|v| v.len() as u64).max().unwrap();
    // Room for the first outputs (model.json, fit.json, model.mat), not for the
    // largest (a figure): the run fails part way, after some outputs were written.
    let cap = size("model.json")
        .max(size("fit.json"))
        .max(size("model.mat"))
        + 64;
    assert!(cap < largest, "cap {cap}, largest {largest}");
    for states in ["2", "6"] {
        let o = run_capped_disk_full(
            &[
                "identify",
                s(&frf),
                "--states",
                states,
                "-q",
                "--out",
                s(&out),
            ],
            None,
            cap,
        );
        o.assert_input_error();
        assert!(
            o.stderr.contains("too large") || o.stderr.contains("disk full"),
            "{}",
            o.stderr
        );
        assert_eq!(snapshot(&out), before, "--states {states}");
    }
    // A full disk for a single output: the old file stays.
    let csv = dir.path().join("sim.csv");
    std::fs::write(&csv, b"old").unwrap();
    run_capped_disk_full(
        &["simulate", "truth-model", "-q", "--out", s(&csv)],
        None,
        4096,
    )
    .assert_input_error()
    .says("sim.csv");
    assert_eq!(snapshot(dir.path()).get("sim.csv").unwrap(), b"old");
    assert_eq!(
        snapshot(dir.path())
            .keys()
            .filter(|k| !k.starts_with("run"))
            .count(),
        1
    );
}

/// Symbolic links planted at the names earlier versions used for temporary and probe
/// files (`.{stem}.tmp-{pid}.{ext}`, `.era-probe-{pid}`), for the pids the next runs
/// are likely to get: nothing is written through them.
#[test]
fn links_planted_at_predictable_names_are_harmless() {
    let decoy = decoys();
    let target = decoy.path().join("decoy.txt");
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let next = std::fs::read_to_string("/proc/sys/kernel/ns_last_pid")
        .ok()
        .and_then(|t| t.trim().parse::<u32>().ok())
        .unwrap_or(std::process::id());
    for pid in next..next + 400 {
        for name in [
            format!(".out.tmp-{pid}.csv"),
            format!(".era-probe-{pid}"),
            format!(".model.tmp-{pid}.json"),
        ] {
            std::os::unix::fs::symlink(&target, d.join(name)).unwrap();
        }
    }
    let frf = small_frf(d, "in.csv");
    let before = snapshot(d);
    let out = d.join("out.csv");
    ok(run_capped(
        &["simulate", "truth-model", "-q", "--out", s(&out)],
        None,
        None,
    ));
    ok(run_capped(&["convert", s(&frf), s(&out), "-q"], None, None));
    ok(run_capped(
        &["identify", s(&frf), "--states", "4", "-q", "--out", s(d)],
        None,
        None,
    ));
    assert_eq!(std::fs::read(&target).unwrap(), b"precious, not era's");
    let after = snapshot(d);
    for (name, v) in &before {
        if v.starts_with(b"<link") {
            assert_eq!(after.get(name), Some(v), "{name}");
        }
    }
    assert!(after["out.csv"].starts_with(b"#") || after["out.csv"].starts_with(b"f"));
    assert!(after.contains_key("model.json"));
}

/// Leftovers of killed runs: era's temporary files and staging folders of dead
/// processes go when era next writes into the folder; a live process's, look-alikes,
/// and links or folders of the wrong kind stay.
#[test]
fn stale_leftovers_of_dead_runs_are_removed_and_nothing_else() {
    let decoy = decoys();
    let dead = 4_194_999u32; // above any pid_max
    let live = std::process::id();
    let r = "Zq9x".repeat(3);
    for verb in [
        vec!["simulate", "truth-model", "-q", "--out", "OUT"],
        vec!["identify", "IN", "--states", "4", "-q", "--out", "DIR"],
    ] {
        let dir = tempfile::tempdir().unwrap();
        let d = dir.path();
        let inputs = tempfile::tempdir().unwrap();
        let frf = small_frf(inputs.path(), "in.csv");
        let gone = [
            format!(".era-tmp-{dead}-{r}.csv"),
            format!(".era-tmp-{dead}-{r}.png"),
            format!(".era-tmp-{dead}-{r}"),
            format!(".era-staging-{dead}-{r}"),
        ];
        for g in &gone[..3] {
            std::fs::write(d.join(g), b"half").unwrap();
        }
        std::fs::create_dir_all(d.join(&gone[3]).join("pairs")).unwrap();
        std::fs::write(d.join(&gone[3]).join("pairs/p.png"), b"half").unwrap();
        let kept = [
            format!(".era-tmp-{live}-{r}.csv"),
            format!(".era-staging-{live}-{r}"),
            format!(".era-tmp-{dead}-{r}~"),
            format!(".era-tmp-{dead}-short.csv"),
            format!("era-tmp-{dead}-{r}.csv"),
            format!(".era-tmp-x{dead}-{r}.csv"),
            format!(".era-staging-{dead}-{r}.old"),
            "notes.txt".to_string(),
        ];
        for k in &kept {
            std::fs::write(d.join(k), b"keep").unwrap();
        }
        // Era's names, wrong kinds.
        let q = "Q".repeat(12);
        let wrong = [
            format!(".era-tmp-{dead}-{q}.csv"),
            format!(".era-staging-{dead}-{q}"),
        ];
        std::os::unix::fs::symlink(decoy.path().join("decoy.txt"), d.join(&wrong[0])).unwrap();
        std::os::unix::fs::symlink(decoy.path(), d.join(&wrong[1])).unwrap();
        let args: Vec<String> = verb
            .iter()
            .map(|a| match *a {
                "OUT" => s(&d.join("sim.csv")).to_string(),
                "DIR" => s(d).to_string(),
                "IN" => s(&frf).to_string(),
                x => x.to_string(),
            })
            .collect();
        ok(run(&args, None));
        let after = snapshot(d);
        for g in &gone {
            assert!(!after.contains_key(g), "{verb:?}: {g} stayed");
        }
        for k in kept.iter().chain(&wrong) {
            assert!(after.contains_key(k), "{verb:?}: {k} was removed");
        }
        assert!(
            !after.keys().any(|k| k.starts_with(".era-staging-")
                && !k.contains(&dead.to_string())
                && !k.contains(&live.to_string())),
            "{verb:?}: a staging folder was left: {:?}",
            after.keys().collect::<Vec<_>>()
        );
        assert_eq!(
            std::fs::read(decoy.path().join("decoy.txt")).unwrap(),
            b"precious, not era's"
        );
    }
}

/// A folder that takes no files, and an --out folder that is a file: exit 2 before the
/// long work, nothing changed.
#[test]
fn folders_that_take_no_files_are_refused_early() {
    let inputs = tempfile::tempdir().unwrap();
    let frf = small_frf(inputs.path(), "in.csv");
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("a-file");
    std::fs::write(&file, b"x").unwrap();
    for args in [
        vec!["identify", s(&frf), "--states", "4", "--out", s(&file)],
        vec!["plot", s(&frf), "--out", s(&file)],
        vec!["demo", "--out", s(&file)],
    ] {
        run_capped(&args, None, None)
            .assert_input_error()
            .says("a-file");
    }
    assert_eq!(std::fs::read(&file).unwrap(), b"x");
    if is_root() {
        // Root writes into a read-only folder regardless: nothing to test.
        return;
    }
    use std::os::unix::fs::PermissionsExt;
    let ro = dir.path().join("ro");
    std::fs::create_dir(&ro).unwrap();
    std::fs::write(ro.join("model.json"), b"old").unwrap();
    std::fs::set_permissions(&ro, std::fs::Permissions::from_mode(0o555)).unwrap();
    run_capped(
        &["identify", s(&frf), "--states", "4", "--out", s(&ro)],
        None,
        None,
    )
    .assert_input_error()
    .says("cannot write there");
    run_capped(
        &["simulate", "truth-model", "--out", s(&ro.join("x.csv"))],
        None,
        None,
    )
    .assert_input_error()
    .says("ro");
    assert_eq!(std::fs::read(ro.join("model.json")).unwrap(), b"old");
    std::fs::set_permissions(&ro, std::fs::Permissions::from_mode(0o755)).unwrap();
}
