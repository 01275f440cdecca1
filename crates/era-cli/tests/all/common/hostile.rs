//! The harness of the hostile test suites: runs the `era` binary the way an attacker's
//! input would reach it, under a 4 GB address-space cap and a hang watchdog, and checks
//! the promise: exit 0 or 2, never a panic, an internal error (exit 1), an allocation
//! abort (a signal) or a hang.
#![allow(dead_code)]

use std::io::{Read, Write};
use std::os::unix::process::CommandExt;
use std::path::Path;
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

/// The address-space cap every hostile run gets: an allocation that would need more is
/// refused by the kernel, and a Rust program then aborts (SIGABRT) — which these tests
/// report as a failure.
pub const ADDRESS_SPACE_CAP: u64 = 4 << 30;

/// A run is called hung past this wall time. It is a watchdog, not a performance check:
/// every hostile case finishes in well under a second when era behaves, and this is far
/// above any legitimate run on a loaded 2-core machine.
pub const WATCHDOG: Duration = Duration::from_secs(60);

/// What a capped run did.
#[derive(Debug)]
pub struct Outcome {
    /// The exit code, `None` when killed by a signal (abort, or the watchdog).
    pub code: Option<i32>,
    /// Standard output.
    pub stdout: String,
    /// Standard error.
    pub stderr: String,
    /// True when the watchdog killed it.
    pub hung: bool,
    /// The arguments, for messages.
    pub args: Vec<String>,
}

impl Outcome {
    /// Asserts the promise for bad input: exit 2, a message, no panic.
    pub fn assert_input_error(&self) -> &Self {
        self.assert_no_crash();
        assert_eq!(
            self.code,
            Some(2),
            "{:?}: expected exit 2:\n{}",
            self.args,
            self.stderr
        );
        assert!(
            self.stderr.contains("era: error:"),
            "{:?}: exit 2 without a message:\n{}",
            self.args,
            self.stderr
        );
        self
    }

    /// Asserts that the run ended by itself with 0 or 2, without a panic or an internal
    /// error.
    pub fn assert_no_crash(&self) -> &Self {
        assert!(
            !self.hung,
            "{:?}: still running after {WATCHDOG:?}",
            self.args
        );
        assert!(
            matches!(self.code, Some(0) | Some(2)),
            "{:?}: exit {:?} (a signal when None: allocation abort?):\n{}",
            self.args,
            self.code,
            self.stderr
        );
        for bad in [
            "panicked",
            "internal error",
            "memory allocation",
            "RUST_BACKTRACE",
        ] {
            assert!(
                !self.stderr.contains(bad),
                "{:?}: '{bad}' in stderr:\n{}",
                self.args,
                self.stderr
            );
        }
        // Raw escape sequences from a file must never reach the terminal.
        assert!(
            !self.stderr.contains('\u{1b}'),
            "{:?}: a raw ESC in stderr: {:?}",
            self.args,
            self.stderr
        );
        self
    }

    /// Asserts that stderr names `needle`.
    pub fn says(&self, needle: &str) -> &Self {
        assert!(
            self.stderr.contains(needle),
            "{:?}: expected '{needle}' in:\n{}",
            self.args,
            self.stderr
        );
        self
    }
}

/// Runs `era ARGS` in `cwd` (or the current folder) with `stdin` piped in (or none),
/// under [`ADDRESS_SPACE_CAP`] and [`WATCHDOG`].
pub fn run_capped(args: &[&str], cwd: Option<&Path>, stdin: Option<&[u8]>) -> Outcome {
    run_capped_env(args, cwd, stdin, &[])
}

/// [`run_capped`] with extra environment variables.
pub fn run_capped_env(
    args: &[&str],
    cwd: Option<&Path>,
    stdin: Option<&[u8]>,
    env: &[(&str, &str)],
) -> Outcome {
    run_capped_full(args, cwd, stdin, env, None)
}

/// [`run_capped`] as on a disk that fills up after `file_size` bytes of any one file:
/// RLIMIT_FSIZE is set, and SIGXFSZ ignored so that a write past it fails with EFBIG
/// (as a full disk fails with ENOSPC) instead of killing the process.
pub fn run_capped_disk_full(args: &[&str], cwd: Option<&Path>, file_size: u64) -> Outcome {
    run_capped_full(args, cwd, None, &[], Some(file_size))
}

/// [`run_capped_env`] with an optional file size cap (see [`run_capped_disk_full`]).
pub fn run_capped_full(
    args: &[&str],
    cwd: Option<&Path>,
    stdin: Option<&[u8]>,
    env: &[(&str, &str)],
    file_size: Option<u64>,
) -> Outcome {
    let mut cmd = Command::new(env!("CARGO_BIN_EXE_era"));
    cmd.args(args)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .stdin(if stdin.is_some() {
            Stdio::piped()
        } else {
            Stdio::null()
        })
        .env_remove("RUST_BACKTRACE");
    for (k, v) in env {
        cmd.env(k, v);
    }
    if let Some(dir) = cwd {
        cmd.current_dir(dir);
    }
    // SAFETY: setrlimit and signal are async-signal-safe and touch no state of the
    // parent.
    unsafe {
        cmd.pre_exec(move || {
            let lim = libc::rlimit {
                rlim_cur: ADDRESS_SPACE_CAP as libc::rlim_t,
                rlim_max: ADDRESS_SPACE_CAP as libc::rlim_t,
            };
            if libc::setrlimit(libc::RLIMIT_AS, &lim) != 0 {
                return Err(std::io::Error::last_os_error());
            }
            if let Some(bytes) = file_size {
                let lim = libc::rlimit {
                    rlim_cur: bytes as libc::rlim_t,
                    rlim_max: bytes as libc::rlim_t,
                };
                if libc::setrlimit(libc::RLIMIT_FSIZE, &lim) != 0
                    || libc::signal(libc::SIGXFSZ, libc::SIG_IGN) == libc::SIG_ERR
                {
                    return Err(std::io::Error::last_os_error());
                }
            }
            Ok(())
        });
    }
    let mut child = cmd.spawn().expect("spawn era");
    if let Some(bytes) = stdin {
        let mut pipe = child.stdin.take().unwrap();
        let bytes = bytes.to_vec();
        // A writer thread, so a child that never reads cannot block the test.
        std::thread::spawn(move || {
            let _ = pipe.write_all(&bytes);
        });
    }
    let mut out_pipe = child.stdout.take().unwrap();
    let mut err_pipe = child.stderr.take().unwrap();
    let out_t = std::thread::spawn(move || {
        let mut s = Vec::new();
        let _ = out_pipe.read_to_end(&mut s);
        s
    });
    let err_t = std::thread::spawn(move || {
        let mut s = Vec::new();
        let _ = err_pipe.read_to_end(&mut s);
        s
    });
    let start = Instant::now();
    let mut hung = false;
    let status = loop {
        if let Some(st) = child.try_wait().expect("wait") {
            break st;
        }
        if start.elapsed() > WATCHDOG {
            hung = true;
            let _ = child.kill();
            break child.wait().expect("wait");
        }
        std::thread::sleep(Duration::from_millis(5));
    };
    Outcome {
        code: status.code(),
        stdout: String::from_utf8_lossy(&out_t.join().unwrap()).into_owned(),
        stderr: String::from_utf8_lossy(&err_t.join().unwrap()).into_owned(),
        hung,
        args: args.iter().map(|s| s.to_string()).collect(),
    }
}

/// A small seeded generator (SplitMix64) for the mutation generators: deterministic, so
/// a failing case can be replayed from its seed.
pub struct Rng(pub u64);

impl Rng {
    /// The next 64 random bits.
    pub fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }
    /// Uniform in `0..n` (n > 0).
    pub fn below(&mut self, n: usize) -> usize {
        (self.next_u64() % n as u64) as usize
    }
}

/// `bytes` with `flips` random bits flipped.
pub fn bit_flips(bytes: &[u8], rng: &mut Rng, flips: usize) -> Vec<u8> {
    let mut v = bytes.to_vec();
    if v.is_empty() {
        return v;
    }
    for _ in 0..flips {
        let i = rng.below(v.len());
        v[i] ^= 1 << rng.below(8);
    }
    v
}

/// `bytes` cut at a random point.
pub fn truncation(bytes: &[u8], rng: &mut Rng) -> Vec<u8> {
    let n = rng.below(bytes.len().max(1));
    bytes[..n].to_vec()
}
