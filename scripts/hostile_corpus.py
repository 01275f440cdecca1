#!/usr/bin/env python3
"""A wide hostile corpus for the `era` binary, kept apart from the test suite.

The test suite's hostile tests (crates/*/tests/hostile_*.rs) are fixed and fast. This
script makes a wider, seeded corpus of its own and runs every case the way a user's
shell would: under a 4 GB address-space cap (`prlimit --as`) and a 20 s wall-clock kill
(`timeout`). Each case must end by itself with exit 0 or 2, print no panic or internal
error and no raw escape character, and leave the decoy files and device nodes it set up
untouched.

Cases:
- mutated input files (bit flips, truncations, extreme numbers in place of numbers,
  control characters, byte-order marks, repeated chunks) of every format era reads: FRF
  CSV, UFF 58 ASCII, UFF 58b, MAT, time-history CSV, free-decay CSV, model.json;
- absurd values for every numeric flag of every verb;
- hostile output targets (a FIFO, a folder, a symlink to a decoy, character-device nodes
  made with mknod when root) and hostile inputs (a FIFO with no writer, /dev/zero, a
  folder, standard input);
- time histories through OKID (`identify --from-time --markov okid`), mutated and with
  absurd observer flags;
- output-only records through `era oma`, mutated and with absurd lags, blocks, orders,
  references and sample rates;
- geometries for `--geometry` (our CSV and the ARTeMIS UFF export in data/), mutated,
  through `identify` with its report and through `refine`;
- fleets: mutated `era batch` manifests and `era track` tables (modes.parquet), absurd
  `--jobs`, `--shard`, tracking and `simulate fleet` values, special files as manifests;
- signals: SIGINT, SIGTERM or SIGHUP at a random moment of a run (exit 0, or 128 + the
  signal within 1 s; nothing of era's left; the earlier outputs whole, or the new set);
- two runs into one `--out` folder at once (one is refused, or they run one after the
  other; the folder is one run's whole set, nothing of era's left).

Usage: scripts/hostile_corpus.py [--seed N] [--mutants N] [--era PATH] [--keep DIR]
Prints a summary per category and every failing case; exits 1 if any case failed.
Only the standard library is needed.
"""

import argparse
import os
import random
import shutil
import stat
import subprocess
import sys
import tempfile
import time

CAP_BYTES = 4 << 30
KILL_AFTER_S = 20


def era_binary(explicit):
    if explicit:
        return explicit
    target = os.environ.get("CARGO_TARGET_DIR") or os.path.join(
        os.path.dirname(os.path.abspath(__file__)), "..", "target"
    )
    path = os.path.join(target, "release", "era")
    if not os.path.exists(path):
        sys.exit(f"no era binary at {path}: run `cargo build --release` first (or --era PATH)")
    return os.path.abspath(path)


class Runner:
    def __init__(self, era, work):
        self.era = era
        self.work = work
        self.results = {}  # category -> [count, failures]
        self.failures = []
        self.slowest = (0.0, None)

    def run(self, category, args, stdin=None, env=None, check=None, setup_note=""):
        cmd = [
            "prlimit",
            f"--as={CAP_BYTES}",
            "timeout",
            "-s",
            "KILL",
            str(KILL_AFTER_S),
            self.era,
        ] + [str(a) for a in args]
        full_env = dict(os.environ)
        full_env.pop("RUST_BACKTRACE", None)
        if env:
            full_env.update(env)
        t0 = time.monotonic()
        try:
            p = subprocess.run(
                cmd,
                cwd=self.work,
                input=stdin,
                stdin=None if stdin is not None else subprocess.DEVNULL,
                capture_output=True,
                env=full_env,
                timeout=KILL_AFTER_S + 10,
            )
            code, err = p.returncode, p.stderr.decode("utf-8", "replace")
        except subprocess.TimeoutExpired:
            code, err = None, "(harness timeout)"
        dt = time.monotonic() - t0
        if dt > self.slowest[0]:
            self.slowest = (dt, " ".join(str(a) for a in args))
        problems = []
        if code is None or code == -9 or code == 137:
            problems.append(f"killed after {KILL_AFTER_S} s (hang)")
        elif code not in (0, 2):
            problems.append(f"exit {code}")
        for bad in ("panicked", "internal error", "memory allocation", "RUST_BACKTRACE"):
            if bad in err:
                problems.append(f"'{bad}' in stderr")
        if "\x1b" in err:
            problems.append("raw ESC in stderr")
        if code == 2 and "error:" not in err:  # era's own, or clap's for a malformed flag
            problems.append("exit 2 without a message")
        if check:
            extra = check()
            if extra:
                problems.append(extra)
        entry = self.results.setdefault(category, [0, 0])
        entry[0] += 1
        if problems:
            entry[1] += 1
            self.failures.append(
                (category, " ".join(str(a) for a in args), setup_note, problems, err[-400:])
            )
        return code, err


def sh(era, work, *args):
    subprocess.run([era] + list(args), cwd=work, check=True, capture_output=True)


# --- mutation generators ------------------------------------------------------------

EXTREMES = [
    b"1e308", b"-1.7e308", b"nan", b"NaN", b"inf", b"-inf", b"1e-320", b"0",
    b"-1", b"99999999999999999999999", b"18446744073709551615", b"4294967296",
    b"1e154", b"-0", b"0x10", b"1,5", b"", b"\x1b[31mred",
]


def number_spans(data):
    spans = []
    i, n = 0, len(data)
    while i < n:
        if data[i : i + 1].isdigit():
            j = i
            while j < n and data[j : j + 1] in b"0123456789.eE+-":
                j += 1
            spans.append((i, j))
            i = j
        else:
            i += 1
    return spans


def mutate(data, rng):
    kind = rng.randrange(8)
    d = bytearray(data)
    if kind == 0 and d:  # bit flips
        for _ in range(rng.choice([1, 2, 8, 64])):
            i = rng.randrange(len(d))
            d[i] ^= 1 << rng.randrange(8)
        return bytes(d), "bit flips"
    if kind == 1:  # truncation
        return bytes(d[: rng.randrange(len(d) + 1)]), "truncation"
    if kind == 2:  # extreme numbers in place of numbers
        spans = number_spans(data)
        if spans:
            for _ in range(rng.choice([1, 3, 10])):
                a, b = rng.choice(spans)
                d[a:b] = rng.choice(EXTREMES).ljust(b - a)[: max(b - a, 1)] if rng.random() < 0.5 else rng.choice(EXTREMES)
                spans = number_spans(bytes(d))
                if not spans:
                    break
        return bytes(d), "extreme numbers"
    if kind == 3:  # control characters
        for _ in range(4):
            i = rng.randrange(len(d) + 1)
            d[i:i] = rng.choice([b"\x1b[2J", b"\x00", b"\x07", b"\r", b"\xe2\x80\x8b", b"\xc2\x9b"])
        return bytes(d), "control characters"
    if kind == 4:  # BOM and line endings
        out = b"\xef\xbb\xbf" + bytes(d)
        if rng.random() < 0.5:
            out = out.replace(b"\n", b"\r\n")
        return out, "BOM / CRLF"
    if kind == 5 and d:  # repeated chunk
        a = rng.randrange(len(d))
        b = min(len(d), a + rng.randrange(1, 2000))
        d[a:a] = d[a:b] * rng.choice([2, 10])
        return bytes(d), "repeated chunk"
    if kind == 6 and d:  # random bytes overwritten
        a = rng.randrange(len(d))
        for i in range(a, min(len(d), a + rng.randrange(1, 64))):
            d[i] = rng.randrange(256)
        return bytes(d), "random bytes"
    # huge integer fields (declared counts)
    spans = [s for s in number_spans(data) if b"." not in data[s[0] : s[1]]]
    if spans:
        for _ in range(rng.choice([1, 4])):
            a, b = rng.choice(spans)
            d[a:b] = rng.choice([b"2147483647", b"99999999", b"4000000000", b"100000000000"])
            spans = [s for s in number_spans(bytes(d)) if b"." not in bytes(d)[s[0] : s[1]]]
            if not spans:
                break
    return bytes(d), "huge counts"


def binary_mutate(data, rng):
    """For binary formats: flips, truncations, and 32-bit fields set to huge values."""
    d = bytearray(data)
    kind = rng.randrange(4)
    if kind == 0 and d:
        for _ in range(rng.choice([1, 4, 32])):
            i = rng.randrange(len(d))
            d[i] ^= 1 << rng.randrange(8)
        return bytes(d), "bit flips"
    if kind == 1:
        return bytes(d[: rng.randrange(len(d) + 1)]), "truncation"
    if kind == 2 and len(d) > 8:
        for _ in range(rng.choice([1, 3])):
            i = rng.randrange(0, len(d) - 4) & ~3
            d[i : i + 4] = rng.choice(
                [b"\xff\xff\xff\x7f", b"\x00\x00\x00\x80", b"\xff\xff\xff\xff", b"\x00\xe1\xf5\x05"]
            )
        return bytes(d), "huge 32-bit fields"
    return mutate(data, rng)


# --- the corpus ---------------------------------------------------------------------


def era_entries(folder):
    return sorted(n for n in os.listdir(folder) if n.startswith(".era-"))


def folder_state(folder):
    """Every file under `folder` with its bytes, the run's time stamps taken out (the MAT
    header, the report's UTC time), so that two runs of one command compare equal."""
    import re

    out = {}
    for root, _, files in os.walk(folder):
        for name in files:
            path = os.path.join(root, name)
            with open(path, "rb") as f:
                data = f.read()
            if name.endswith(".mat"):
                data = data[128:]
            elif name.endswith(".html"):
                data = re.sub(rb"\d{4}-\d\d-\d\d \d\d:\d\d:\d\d UTC", b"", data)
            out[os.path.relpath(path, folder)] = data
    return out


def record_case(r, category, args, problems, err=""):
    entry = r.results.setdefault(category, [0, 0])
    entry[0] += 1
    if problems:
        entry[1] += 1
        r.failures.append((category, " ".join(args), "", problems, err[-400:]))


def signal_cases(r, era, work, rng, count=24):
    """A signal at a random moment of a run: exit 0 (it had ended), or 128 + the signal
    within 1 s; the output folder holds the earlier set or the new one, whole, and
    nothing of era's."""
    import signal as sig

    sh(era, work, "simulate", "modal", "--collocated", "--noise", "0.05", "--out", "long.uff")
    verbs = [
        (["identify", "long.uff", "--states", "auto", "--refine", "-q", "--out", "{o}"],
         ["identify", "truth.csv", "--states", "8", "--hankel-factor", "4", "--pad-to", "1024", "-q", "--out", "{o}"]),
        (["identify", "truth.csv", "--states", "8", "--hankel-factor", "4", "--pad-to", "1024", "-q", "--out", "{o}"],
         ["identify", "truth.csv", "--states", "6", "--hankel-factor", "4", "--pad-to", "1024", "-q", "--out", "{o}"]),
        (["simulate", "shaker", "--duration", "4000", "-q", "--out", "{o}/record.csv"],
         ["simulate", "shaker", "--duration", "20", "-q", "--out", "{o}/record.csv"]),
        (["identify", "time.csv", "--from-time", "--inputs", "force", "--outputs", "acc", "--markov", "okid",
          "--states", "2", "-q", "--out", "{o}"],
         ["identify", "truth.csv", "--states", "8", "--hankel-factor", "4", "--pad-to", "1024", "-q", "--out", "{o}"]),
    ]
    signals = [(sig.SIGINT, 130), (sig.SIGTERM, 143), (sig.SIGHUP, 129)]
    for k in range(count):
        new_args, earlier_args = verbs[k % len(verbs)]
        signal, code_expected = signals[rng.randrange(len(signals))]
        out = os.path.join(work, f"sig-out-{k}")
        shutil.rmtree(out, ignore_errors=True)
        os.mkdir(out)
        fill = lambda a: [x.replace("{o}", out) for x in a]
        sh(era, work, *fill(earlier_args))
        earlier = folder_state(out)
        p = subprocess.Popen([era] + fill(new_args), cwd=work, stdout=subprocess.DEVNULL,
                             stderr=subprocess.PIPE)
        time.sleep(rng.uniform(0.0, 1.2))
        sent = time.monotonic()
        p.send_signal(signal)
        problems = []
        try:
            _, err = p.communicate(timeout=10)
        except subprocess.TimeoutExpired:
            p.kill()
            _, err = p.communicate()
            problems.append("still running 10 s after the signal")
        latency = time.monotonic() - sent
        err = err.decode("utf-8", "replace")
        code = p.returncode
        if code not in (0, code_expected):
            problems.append(f"exit {code} after signal {signal}, expected 0 or {code_expected}")
        if code == code_expected and latency > 1.0:
            problems.append(f"ended {latency:.2f} s after the signal")
        left = era_entries(out)
        if left:
            problems.append(f"left {left}")
        now = folder_state(out)
        if code != 0 and now != earlier:
            # Interrupted: the earlier set, or (a signal after the commit) the new one.
            sh(era, work, *fill(new_args))
            if folder_state(out) != now:
                problems.append("the folder is neither the earlier set nor the new one")
        for bad in ("panicked", "internal error"):
            if bad in err:
                problems.append(f"'{bad}' in stderr")
        record_case(r, "signal during a run", new_args, problems, err)
        shutil.rmtree(out, ignore_errors=True)


def concurrency_cases(r, era, work, rng, count=8):
    """Two runs into one --out folder at once: one is refused with a message naming the
    other, or they ran one after the other; the folder is one run's whole set."""
    a_args = ["identify", "long.uff", "--states", "auto", "-q", "--out", "{o}"]
    b_args = ["identify", "truth.csv", "--states", "8", "--hankel-factor", "4", "--pad-to", "1024", "-q",
              "--out", "{o}"]
    for k in range(count):
        out = os.path.join(work, f"conc-out-{k}")
        shutil.rmtree(out, ignore_errors=True)
        fill = lambda a: [x.replace("{o}", out) for x in a]
        first = subprocess.Popen([era] + fill(a_args), cwd=work, stdout=subprocess.DEVNULL,
                                 stderr=subprocess.PIPE)
        time.sleep(rng.uniform(0.0, 0.5))
        second = subprocess.run([era] + fill(b_args), cwd=work, capture_output=True, timeout=60)
        _, first_err = first.communicate(timeout=120)
        problems = []
        err = second.stderr.decode("utf-8", "replace")
        if second.returncode == 2:
            if "another era run" not in err:
                problems.append(f"refused without saying why: {err[-200:]}")
        elif second.returncode != 0:
            problems.append(f"second run exit {second.returncode}")
        if first.returncode != 0:
            problems.append(f"first run exit {first.returncode}: {first_err[-200:]!r}")
        if era_entries(out):
            problems.append(f"left {era_entries(out)}")
        # One run's whole set: the model's size names the run, and every output of that
        # run is there with it.
        state = folder_state(out)
        try:
            import json
            outputs = json.loads(state["model.json"])["outputs"]
        except (KeyError, ValueError) as e:
            outputs = None
            problems.append(f"no readable model.json: {e}")
        if outputs is not None:
            redo = os.path.join(work, f"conc-redo-{k}")
            shutil.rmtree(redo, ignore_errors=True)
            chosen = a_args if outputs == 8 else b_args
            sh(era, work, *[x.replace("{o}", redo) for x in chosen])
            if set(folder_state(redo)) != set(state):
                problems.append("the folder's files are not one run's set")
            shutil.rmtree(redo, ignore_errors=True)
        record_case(r, "two runs into one --out", a_args + ["&"] + b_args, problems, err)
        shutil.rmtree(out, ignore_errors=True)


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seed", type=int, default=20261122)
    ap.add_argument("--mutants", type=int, default=40, help="mutants per seed file")
    ap.add_argument("--era", help="the era binary (default: $CARGO_TARGET_DIR/release/era)")
    ap.add_argument("--keep", help="keep the work folder here")
    a = ap.parse_args()
    era = era_binary(a.era)
    rng = random.Random(a.seed)
    work = a.keep or tempfile.mkdtemp(prefix="era-hostile-")
    os.makedirs(work, exist_ok=True)
    r = Runner(era, work)
    t_start = time.monotonic()

    # Seeds made by era itself, plus hand-made time and decay records.
    sh(era, work, "simulate", "truth-model", "--out", "truth.csv", "--noise", "0.05")
    sh(era, work, "simulate", "modal", "--outputs", "2", "--inputs", "2", "--modes", "3",
       "--lines", "257", "--df", "0.1", "--fmin", "1", "--fmax", "10", "--out", "modal.uff")
    sh(era, work, "convert", "truth.csv", "truth_b.uff", "--binary")
    sh(era, work, "convert", "modal.uff", "modal.mat")
    sh(era, work, "identify", "truth.csv", "--states", "8", "--hankel-factor", "4",
       "--pad-to", "1024", "--out", "model-out", "-q")
    shutil.copy(os.path.join(work, "model-out", "model.json"), os.path.join(work, "model.json"))
    sh(era, work, "friction", "simulate", "--coulomb-force", "0.2", "--stiffness", "1",
       "--duration", "5", "--out", "decay.csv")
    with open(os.path.join(work, "time.csv"), "w") as f:
        f.write("time_s,force,acc\n")
        prng = random.Random(7)
        y = 0.0
        for k in range(2048):
            u = prng.gauss(0, 1)
            y = 0.9 * y + u
            f.write(f"{k / 256:.6f},{u:.6e},{y:.6e}\n")
    # Three responses of two lightly damped resonators to unmeasured noise, for era oma.
    with open(os.path.join(work, "oma.csv"), "w") as f:
        f.write("time_s,y1,y2,y3\n")
        prng = random.Random(11)
        r1 = [0.0, 0.0]
        r2 = [0.0, 0.0]
        for k in range(4096):
            u, v = prng.gauss(0, 1), prng.gauss(0, 1)
            r1 = [1.80 * r1[0] - 0.98 * r1[1] + u, r1[0]]
            r2 = [1.20 * r2[0] - 0.97 * r2[1] + v, r2[0]]
            f.write(f"{k / 128:.6f},{r1[0] + 0.3 * r2[0]:.6e},{r1[0] - r2[0]:.6e},{0.5 * r1[0] + r2[0]:.6e}\n")

    # A manifest of two records of oma.csv, and the modes table its batch writes.
    with open(os.path.join(work, "fleet.toml"), "w") as f:
        f.write('verb = "oma"\nargs = ["--outputs", "1-3", "--states", "4", "--blocks", "2"]\n'
                '[[record]]\nid = "a"\npath = "oma.csv"\ntime = 2026-05-01T10:00:00Z\n'
                '[[record]]\nid = "b"\npath = ["oma.csv", "oma.csv"]\ntime = "2026-05-01T11:00:00Z"\n')
    sh(era, work, "batch", "fleet.toml", "--out", "batch-seed", "-q")
    shutil.copy(os.path.join(work, "batch-seed", "modes.parquet"), os.path.join(work, "modes.parquet"))

    # Geometries for --geometry: our CSV (the truth model's three outputs on nodes 1-3)
    # and the real ARTeMIS export shipped in data/.
    with open(os.path.join(work, "geometry.csv"), "w") as f:
        f.write("# three masses and a ground\nnode,x,y,z\n1,0,0,1\n2,0,0,2\n3,0,0,3\n9,0,0,0\n"
                "from,to\n9,1\n1,2\n2,3\n")
    shutil.copy(os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "data",
                             "pyuff-artemis-geometry", "artemis_geometry_rpbc.uff"),
                os.path.join(work, "geometry.uff"))

    commands = {
        "geometry.csv": [["identify", "truth.csv", "--states", "8", "--hankel-factor", "4", "--pad-to", "1024",
                          "--geometry", "{f}", "--out", "geo-out", "-q"]],
        "geometry.uff": [["identify", "truth.csv", "--states", "8", "--hankel-factor", "4", "--pad-to", "1024",
                          "--geometry", "{f}", "--no-figures", "--out", "geo-out", "-q"],
                         ["refine", "model.json", "truth.csv", "--geometry", "{f}", "--out", "geo-out", "-q"]],
        "truth.csv": [["info", "{f}"], ["identify", "{f}", "--states", "8", "--hankel-factor", "4", "--pad-to", "1024"],
                      ["convert", "{f}", "o.uff"], ["plot", "{f}", "--out", "plotdir"]],
        "modal.uff": [["info", "{f}"], ["identify", "{f}", "--states", "6"], ["convert", "{f}", "o.csv"]],
        "truth_b.uff": [["info", "{f}"], ["identify", "{f}", "--states", "8", "--hankel-factor", "4", "--pad-to", "1024"]],
        "modal.mat": [["info", "{f}"], ["identify", "{f}", "--states", "6", "--outputs", "2"]],
        "time.csv": [["frf", "{f}", "--inputs", "force", "--outputs", "acc", "--frame", "256", "--out", "o.csv"],
                     ["identify", "{f}", "--from-time", "--inputs", "force", "--outputs", "acc",
                      "--markov", "okid", "--states", "4", "--no-figures", "--out", "okid-out"],
                     ["identify", "{f}", "--from-time", "--inputs", "force", "--outputs", "acc",
                      "--markov", "okid", "--era-dc", "--states", "2", "--json", "-q"]],
        "oma.csv": [["oma", "{f}", "--outputs", "2-4", "--states", "4", "--blocks", "4", "--json", "-q"],
                    ["oma", "{f}", "--outputs", "y1,y2,y3", "--references", "y1", "--method", "next-era",
                     "--no-figures", "--out", "oma-out"],
                    ["oma", "{f}", "{f}", "--outputs", "2-4", "--time-lags", "40", "--out", "oma-out"]],
        "decay.csv": [["friction", "estimate", "{f}", "--stiffness", "1"]],
        "model.json": [["plot", "truth.csv", "--model", "{f}", "--out", "plotdir"]],
        "fleet.toml": [["batch", "{f}", "--out", "batch-out", "-q"],
                       ["batch", "{f}", "--out", "batch-out", "--jobs", "2", "--resume"]],
        # `{d}`: a folder holding the mutant as modes.parquet.
        "modes.parquet": [["track", "{d}", "--out", "track-out", "-q"],
                          ["track", "{d}", "{d}", "--out", "track-out", "--all-modes"]],
    }
    binary = {"truth_b.uff", "modal.mat", "modes.parquet"}
    for seed_name, cmds in commands.items():
        with open(os.path.join(work, seed_name), "rb") as f:
            original = f.read()
        ext = os.path.splitext(seed_name)[1]
        for k in range(a.mutants):
            data, how = (binary_mutate if seed_name in binary else mutate)(original, rng)
            name = f"m_{os.path.splitext(seed_name)[0]}_{k}{ext}"
            folder = None
            if seed_name == "modes.parquet":
                folder = f"m_modes_{k}"
                os.makedirs(os.path.join(work, folder), exist_ok=True)
                name = os.path.join(folder, "modes.parquet")
            with open(os.path.join(work, name), "wb") as f:
                f.write(data)
            cmd = rng.choice(cmds)
            r.run(f"mutated {seed_name}",
                  [c.replace("{f}", name).replace("{d}", folder or "") for c in cmd], setup_note=how)
            if folder:
                shutil.rmtree(os.path.join(work, folder))
            else:
                os.remove(os.path.join(work, name))

    # Absurd flag values.
    absurd = ["0", "-1", "1e-300", "1e300", "NaN", "inf", "-inf", "18446744073709551614",
              "4294967297", "1e9", "100000000", "0.5", "abc", ""]
    flag_cases = [
        (["identify", "truth.csv"], ["--states", "--hankel-factor", "--integrations", "--lowpass-hz",
                                     "--lowpass-order", "--zero-lines", "--pad-to", "--orders"],
         ["--states", "8", "--hankel-factor", "4", "--pad-to", "1024"]),
        (["simulate", "modal", "--out", "s.csv"], ["--outputs", "--inputs", "--modes", "--fmin", "--fmax",
                                                   "--lines", "--df", "--noise", "--seed"], []),
        (["simulate", "truth-model", "--out", "t.csv"], ["--noise", "--seed"], []),
        (["friction", "simulate", "--out", "d.csv"], ["--coulomb-force", "--stiffness", "--natural-frequency-hz",
                                                      "--viscous-damping-ratio", "--x0", "--sample-rate", "--hold",
                                                      "--duration", "--noise"],
         ["--coulomb-force", "0.2", "--stiffness", "1"]),
        (["friction", "tune", "decay.csv"], ["--stiffness", "--coulomb-force", "--natural-frequency-hz",
                                             "--viscous-damping-ratio", "--x0", "--sample-rate", "--dead-zone",
                                             "--fraction", "--cycles"], ["--stiffness", "1"]),
        (["frf", "time.csv", "--inputs", "force", "--outputs", "acc", "--out", "f.csv"],
         ["--frame", "--overlap", "--max-hz", "--sample-rate"], ["--frame", "256"]),
        (["demo"], ["--noise", "--seed"], []),
        (["identify", "time.csv", "--from-time", "--inputs", "force", "--outputs", "acc", "--markov", "okid",
          "--no-figures", "--out", "okid-out"],
         ["--observer-order", "--markov-samples", "--states", "--frame", "--sample-rate"],
         ["--states", "4"]),
        (["plot", "truth.csv", "--out", "p"], ["--integrations", "--zero-lines", "--pairs"], []),
        (["oma", "oma.csv", "--outputs", "2-4", "--no-figures", "--out", "oma-out"],
         ["--time-lags", "--blocks", "--states", "--sample-rate", "--orders", "--references", "--outputs"],
         ["--blocks", "4"]),
        (["batch", "fleet.toml", "--out", "batch-out", "-q"], ["--jobs", "--shard"], []),
        (["track", "batch-seed", "--out", "track-out", "-q"],
         ["--min-records", "--frequency-tolerance", "--mac-min"], []),
        (["simulate", "fleet", "--records", "2", "--record-length", "60", "--out", "fleet-out", "-q"],
         ["--records", "--record-length", "--interval", "--sample-rate", "--drift", "--daily", "--missing",
          "--damage", "--outputs", "--modes", "--noise", "--start"],
         ["--records", "2", "--record-length", "60"]),
    ]
    for base, flags, defaults in flag_cases:
        for flag in flags:
            for value in rng.sample(absurd, 6):
                args = list(base)
                d = list(defaults)
                if flag in d:
                    i = d.index(flag)
                    del d[i : i + 2]
                args += d + [flag, value]
                r.run(f"flag {base[0]} {flag}", args)

    # --pairs lists that are not pairs, or name a pair outside the set (truth.csv is
    # 6 x 3): exit 2 with a message naming the flag and the value.
    for value in ["1:0", "99:1", "1:99", "1:2,", "all,1:1", "1-2", ":", "1:1:1", "\u00b9:1", "1:1,,2:2",
                  "999999999999999999999:1", " ", "collocated,1:1"]:
        code, err = r.run("flag --pairs", ["plot", "truth.csv", "--out", "p", "--pairs", value])
        if code != 2 or "--pairs" not in err or value.strip() not in err:
            r.failures.append(("flag --pairs", f"plot truth.csv --pairs {value!r}", "",
                               [f"exit {code}, the flag and value not both named"], err[-400:]))
            r.results["flag --pairs"][1] += 1
        for verb in (["identify", "truth.csv", "--states", "4", "--pad-to", "1024", "-q", "--out", "pairs-out"],):
            code, err = r.run("flag --pairs", verb + ["--pairs", value])
            if code != 2 or "--pairs" not in err:
                r.failures.append(("flag --pairs", " ".join(verb) + f" --pairs {value!r}", "",
                                   [f"exit {code}, the flag not named"], err[-400:]))
                r.results["flag --pairs"][1] += 1

    # Hostile output targets.
    decoy = os.path.join(work, "decoy.txt")
    root = os.geteuid() == 0

    def target_cases():
        yield "fifo", lambda p: os.mkfifo(p)
        yield "folder", lambda p: os.mkdir(p)
        yield "symlink to a decoy", lambda p: os.symlink(decoy, p)
        yield "dangling symlink", lambda p: os.symlink(os.path.join(work, "nowhere", "x"), p)
        if root:
            yield "char device (null)", lambda p: os.mknod(p, stat.S_IFCHR | 0o600, os.makedev(1, 3))
            yield "char device (full)", lambda p: os.mknod(p, stat.S_IFCHR | 0o600, os.makedev(1, 7))

    writers = [
        ["simulate", "truth-model", "--out", "{t}"],
        ["convert", "truth.csv", "{t}"],
        ["frf", "time.csv", "--inputs", "force", "--outputs", "acc", "--frame", "256", "--out", "{t}"],
        ["friction", "simulate", "--coulomb-force", "0.2", "--stiffness", "1", "--out", "{t}"],
    ]
    for label, make in target_cases():
        for w in writers:
            for ext in (".csv", ".uff"):
                if w[0] == "friction" and ext != ".csv":
                    continue
                with open(decoy, "w") as f:
                    f.write("decoy: must stay as it is\n")
                t = os.path.join(work, "target" + ext)
                if os.path.lexists(t):
                    if os.path.isdir(t) and not os.path.islink(t):
                        shutil.rmtree(t)
                    else:
                        os.remove(t)
                make(t)
                kind_before = os.lstat(t).st_mode

                def check(t=t, kind_before=kind_before):
                    if open(decoy).read() != "decoy: must stay as it is\n":
                        return "the decoy was changed"
                    if not os.path.lexists(t) or stat.S_IFMT(os.lstat(t).st_mode) != stat.S_IFMT(kind_before):
                        return "the target was replaced"
                    return None

                r.run(f"output target: {label}", [c.replace("{t}", t) for c in w], check=check)
        # identify --out DIR where a file inside is hostile.
        out = os.path.join(work, "outdir")
        shutil.rmtree(out, ignore_errors=True)
        os.mkdir(out)
        t = os.path.join(out, "model.json")
        make(t)
        kind_before = os.lstat(t).st_mode
        r.run(f"output target: {label}",
              ["identify", "truth.csv", "--states", "8", "--hankel-factor", "4", "--pad-to", "1024", "--out", out],
              check=lambda t=t, kb=kind_before: None
              if os.path.lexists(t) and stat.S_IFMT(os.lstat(t).st_mode) == stat.S_IFMT(kb) else "model.json replaced")

    # Hostile input paths.
    fifo = os.path.join(work, "in.fifo")
    os.mkfifo(fifo)
    for args in (["info", fifo], ["identify", fifo, "--states", "4"], ["info", "/dev/zero"],
                 ["identify", "/dev/zero", "--states", "4"], ["info", work], ["info", "/dev/null"],
                 ["frf", "/dev/zero", "--inputs", "1", "--outputs", "2", "--out", "x.csv"],
                 ["oma", fifo, "--outputs", "1"], ["oma", "/dev/zero", "--outputs", "1"],
                 ["oma", work, "--outputs", "1"], ["oma", "/dev/null", "--outputs", "1"],
                 ["batch", fifo, "--out", "b"], ["batch", "/dev/zero", "--out", "b"],
                 ["batch", work, "--out", "b"], ["batch", "/dev/null", "--out", "b"],
                 ["track", work + "/nowhere", "--out", "t"], ["track", "/dev", "--out", "t"],
                 *(["identify", "truth.csv", "--states", "8", "--geometry", g, "--no-figures", "--out", "g"]
                   for g in (fifo, "/dev/zero", work, "/dev/null"))):
        r.run("input: special file", args, env={"ERA_MAX_INPUT_BYTES": "50000000"})
    with open(os.path.join(work, "truth.csv"), "rb") as f:
        truth = f.read()
    code, err = r.run("input: standard input", ["info", "/dev/stdin"], stdin=truth)
    if code != 0:
        r.failures.append(("input: standard input", "info /dev/stdin", "", [f"exit {code} on a valid CSV"], err[-400:]))
        r.results["input: standard input"][1] += 1

    signal_cases(r, era, work, rng)
    concurrency_cases(r, era, work, rng)

    total = sum(v[0] for v in r.results.values())
    failed = sum(v[1] for v in r.results.values())
    print(f"{'category':<46} {'cases':>6} {'failed':>7}")
    for cat, (n, bad) in sorted(r.results.items()):
        print(f"{cat:<46} {n:>6} {bad:>7}")
    print(f"{'all':<46} {total:>6} {failed:>7}")
    print(f"wall time {time.monotonic() - t_start:.0f} s; slowest case {r.slowest[0]:.1f} s: {r.slowest[1]}")
    for cat, cmd, note, problems, err in r.failures:
        print(f"\nFAILED [{cat}] era {cmd} ({note}): {'; '.join(problems)}\n  stderr tail: {err!r}")
    if not a.keep:
        shutil.rmtree(work, ignore_errors=True)
    sys.exit(1 if failed else 0)


if __name__ == "__main__":
    main()
