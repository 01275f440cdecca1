"""Output-only modal analysis side by side: era oma, pyOMA2's SSI-cov with its automatic
clustering, and koma's covssi with its stabilization and HDBSCAN clustering, on records
with exact truth. Run through bench/oma_peers.sh, which makes the environment.

Cases (all output-only: the simulator's force channels are never given to any tool):
- "seeds": one record per seed of `era simulate shaker` (10 modes 1..20 Hz, 8 outputs,
  2 unmeasured white-noise forces, 64 Hz, 600 s, 2 % sensor noise): a different structure
  each, for modes found, spurious modes and the errors.
- "one structure": one long record of one seed cut into records of 600 s: the same
  structure under independent excitation, for the Monte Carlo check of the reported
  standard deviations (the scatter of the estimates over the records against the median
  reported std).
- koma's shear frame (data/koma-shear-frame) against its exact reference.
- The DaISy steel subframe with its two force channels dropped: how many of the 14
  reference frequencies of its PROVENANCE.md each tool finds within 0.5 Hz.

Time per record: for the Python peers, the wall time of the call from the data array to
the clustered modes (identification and clustering; import and file reading excluded,
which favours them); for era, the wall time of the whole `era oma` process, reading the
file included.

Every number printed is measured here; a tool that fails on a record gets no modes for it,
and the failure is printed.
"""

import argparse
import json
import math
import os
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
import warnings

os.environ.setdefault("MPLBACKEND", "Agg")  # headless: no window, ever
os.environ.setdefault("PYVISTA_OFF_SCREEN", "true")
os.environ.setdefault("TQDM_DISABLE", "1")  # pyOMA2's progress bars
import logging  # noqa: E402

import numpy as np  # noqa: E402

warnings.filterwarnings("ignore")
logging.disable(logging.INFO)  # pyOMA2 logs every step at INFO

HERE = os.path.dirname(os.path.abspath(__file__))
REPO = os.path.dirname(HERE)
DAISY = os.path.join(REPO, "data", "daisy-steel-subframe", "flexible_structure_dat.mat")
KOMA = os.path.join(REPO, "data", "koma-shear-frame")
# data/daisy-steel-subframe/PROVENANCE.md, "Reference modal parameters" (Hz).
DAISY_REFERENCE = [62.1, 119.0, 154.7, 192.5, 215.0, 229.5, 239.3, 286.8, 321.2, 334.1,
                   352.2, 398.1, 417.5, 467.2]
FREQ_TOL = 0.03  # relative, for a match to the truth
MAC_MIN = 0.7  # when shapes are known
RECORD_S = 600.0


# ------------------------------------------------------------------ data


def read_time_csv(path):
    """An era time CSV: `# key: value` lines, the header `time_s,...`, rows."""
    with open(path) as f:
        skip = 0
        for line in f:
            skip += 1
            if line.startswith("time_s"):
                break
    data = np.loadtxt(path, delimiter=",", skiprows=skip, dtype=float)
    return data


def write_time_csv(path, t, columns, names, note):
    with open(path, "w") as f:
        f.write(f"# note: {note}\n")
        f.write("time_s," + ",".join(names) + "\n")
        block = np.column_stack([t] + list(columns))
        np.savetxt(f, block, delimiter=",", fmt="%.17g")


T0 = time.perf_counter()


def progress(text):
    print(f"  [{time.perf_counter() - T0:6.1f} s] {text}", file=sys.stderr, flush=True)


def simulate(era, out, seed, duration, modes, outputs, inputs, rate, noise):
    subprocess.run([era, "simulate", "shaker", "--modes", str(modes), "--fmin", "1",
                    "--fmax", "20", "--outputs", str(outputs), "--inputs", str(inputs),
                    "--sample-rate", str(rate), "--duration", str(duration),
                    "--noise", str(noise), "--seed", str(seed), "--out", out, "-q"],
                   check=True, stdout=subprocess.DEVNULL)
    truth = json.load(open(out[:-4] + ".truth.json"))
    return truth


def make_records(era, work, n, args):
    """The two simulated sets: [(csv, truth, fs, output columns 1-based)]."""
    seeds, one = [], []
    p, m = args.inputs, args.outputs
    cols = list(range(p + 1, p + m + 1))
    for k in range(n):
        path = os.path.join(work, f"seed{k + 1}.csv")
        truth = simulate(era, path, k + 1, RECORD_S, args.modes, m, p, args.rate, args.noise)
        seeds.append((path, truth, args.rate, cols))
    long_path = os.path.join(work, "long.csv")
    truth = simulate(era, long_path, args.mc_seed, RECORD_S * n, args.modes, m, p,
                     args.rate, args.noise)
    data = read_time_csv(long_path)
    names = [f"force{j + 1}" for j in range(p)] + [f"acc{j + 1}" for j in range(m)]
    per = int(round(RECORD_S * args.rate))
    for k in range(n):
        seg = data[k * per:(k + 1) * per]
        path = os.path.join(work, f"one{k + 1}.csv")
        write_time_csv(path, np.arange(per) / args.rate, seg[:, 1:].T, names,
                       f"seconds {k * RECORD_S:g}..{(k + 1) * RECORD_S:g} of era simulate "
                       f"shaker seed {args.mc_seed}")
        one.append((path, truth, args.rate, cols))
    os.remove(long_path)
    return seeds, one


def load_outputs(path, cols):
    if path.endswith(".mat"):
        from scipy.io import loadmat
        mat = loadmat(path)
        (key,) = [k for k in mat if not k.startswith("__")]
        data = np.asarray(mat[key], dtype=float)
        y = data[:, [c - 1 for c in cols]]
    else:
        data = read_time_csv(path)
        y = data[:, cols]  # column 0 is time_s, so channel c is column c
    return y - y.mean(axis=0)


# ------------------------------------------------------------------ tools


class PyOMA2:
    name = "pyOMA2"

    def __init__(self, preset, br, ordmax, calc_unc):
        import pyoma2
        from importlib.metadata import version
        self.version = version("pyOMA-2")
        del pyoma2
        self.preset, self.br, self.ordmax, self.calc_unc = preset, br, ordmax, calc_unc
        if calc_unc:
            self.name = "pyOMA2 (calc_unc)"

    def describe(self):
        return (f"pyOMA2 {self.version}: SSI(method='cov', br={self.br}, ordmax={self.ordmax}, "
                f"step=2, calc_unc={self.calc_unc}) + Clustering(quick='{self.preset}')")

    def run(self, y, fs, br=None, ordmax=None):
        from pyoma2.algorithms.data.run_params import Clustering
        from pyoma2.algorithms.ssi import SSI
        from pyoma2.setup.single import SingleSetup
        setup = SingleSetup(y, fs=fs)
        ssi = SSI(name="ssicov", method="cov", br=br or self.br, ordmax=ordmax or self.ordmax,
                  step=2, calc_unc=self.calc_unc)
        ssi.add_clustering(Clustering(name="auto", quick=self.preset))
        setup.add_algorithms(ssi)
        setup.run_by_name("ssicov")
        ssi.run_clustering("auto")
        res = ssi.result.clustering_results["auto"]
        fn = np.atleast_1d(res.Fn) if res.Fn is not None else np.zeros(0)
        xi = np.atleast_1d(res.Xi)
        phi = np.asarray(res.Phi).reshape(y.shape[1], -1) if len(fn) else None
        fstd = np.atleast_1d(res.Fn_std) if self.calc_unc and res.Fn_std is not None else None
        xstd = np.atleast_1d(res.Xi_std) if self.calc_unc and res.Xi_std is not None else None
        modes = []
        for j in range(len(fn)):
            modes.append({
                "frequency_hz": float(fn[j]), "damping_ratio": float(xi[j]),
                "shape": None if phi is None else phi[:, j],
                "frequency_std_hz": None if fstd is None else float(fstd[j]),
                "damping_ratio_std": None if xstd is None else float(xstd[j]),
            })
        return modes


class Koma:
    name = "koma"

    def __init__(self, i, ordmax):
        from importlib.metadata import version
        self.version = version("koma-python")
        self.i, self.ordmax = i, ordmax

    def describe(self):
        return (f"koma {self.version}: covssi(i={self.i}, orders 2..{self.ordmax} step 2), "
                "find_stable_poles(s=3, freq 0.05, damping 0.2, mac 0.2), PoleClusterer("
                "min_cluster_size=min_samples=15, scaling mac 0.4 omega_n 0.8, "
                "avoid_same_order) as in koma's 'Automatic OMA' example; its std is the "
                "spread of the poles in a cluster")

    def run(self, y, fs, i=None, ordmax=None):
        import koma.clustering
        import koma.oma
        i = i or self.i
        orders = np.arange(2, (ordmax or self.ordmax) + 2, 2)
        lambd, phi, order = koma.oma.covssi(y, fs, i, orders, showinfo=False)
        stab = koma.oma.find_stable_poles(
            lambd, phi, order, 3, stabcrit={"freq": 0.05, "damping": 0.2, "mac": 0.2},
            valid_range={"freq": [0, np.inf], "damping": [0, 0.2], "mpc": [0, 1]},
            indicator="freq")
        lambd_s, phi_s, order_s, _ = stab
        if len(lambd_s) < 15:
            return []
        clus = koma.clustering.PoleClusterer(
            lambd_s, phi_s, order_s, min_cluster_size=15, min_samples=15,
            scaling={"mac": 0.4, "omega_n": 0.8}, normalize_distances=False,
            boolean_stops="avoid_same_order")
        out = clus.postprocess(prob_threshold=0.0, normalize_and_maxreal=True)
        if len(out[0]) == 0:
            return []
        xi_c, om_c, phi_c, *_ = koma.clustering.group_clusters(*out)
        modes = []
        for xi, om, ph in zip(xi_c, om_c, phi_c):
            modes.append({
                "frequency_hz": float(np.mean(om) / (2 * np.pi)),
                "damping_ratio": float(np.mean(xi)),
                "shape": np.mean(ph, axis=1),
                "frequency_std_hz": float(np.std(om) / (2 * np.pi)),
                "damping_ratio_std": float(np.std(xi)),
            })
        return modes


class Era:
    name = "era"

    def __init__(self, era):
        self.era = era

    def describe(self):
        return "era oma FILE --outputs LIST --states auto --json (the whole process)"

    def run_file(self, path, cols, fs):
        cmd = [self.era, "oma", path, "--outputs", ",".join(map(str, cols)),
               "--states", "auto", "--json", "-q"]
        if path.endswith(".mat"):
            cmd += ["--sample-rate", str(fs)]
        t0 = time.perf_counter()
        proc = subprocess.run(cmd, capture_output=True, text=True)
        seconds = time.perf_counter() - t0
        if proc.returncode != 0:
            raise RuntimeError(f"exit {proc.returncode}: {proc.stderr.strip()[:300]}")
        doc = json.loads(proc.stdout)
        modes = []
        for m in doc["modes"]:
            if m.get("physical", True) is False:
                continue
            shape = era_shape(m)
            modes.append({"frequency_hz": m["frequency_hz"],
                          "damping_ratio": m["damping_ratio"], "shape": shape,
                          "frequency_std_hz": m.get("frequency_std_hz"),
                          "damping_ratio_std": m.get("damping_ratio_std")})
        return modes, seconds


def era_shape(m):
    """A mode's shape from era's JSON, complex: `shape_re`/`shape_im` as model.json writes
    them, or `shape` as numbers, [re, im] pairs or {re, im} objects; None when absent."""
    if m.get("shape_re") is not None:
        return np.array(m["shape_re"]) + 1j * np.array(m.get("shape_im") or 0.0)
    shape = m.get("shape")
    if shape is None:
        return None
    return np.array([complex(*v) if isinstance(v, list) else
                     complex(v["re"], v["im"]) if isinstance(v, dict) else v for v in shape])


def era_has_oma(era):
    proc = subprocess.run([era, "oma", "--help"], capture_output=True, text=True)
    return proc.returncode == 0


def run_tool(tool, path, cols, fs, **kw):
    """(modes, seconds, error)."""
    try:
        if isinstance(tool, Era):
            modes, seconds = tool.run_file(path, cols, fs)
            return modes, seconds, None
        y = load_outputs(path, cols)
        t0 = time.perf_counter()
        modes = tool.run(y, fs, **kw)
        return modes, time.perf_counter() - t0, None
    except Exception as e:  # a failing peer is a result, not the end of the run
        return [], float("nan"), f"{type(e).__name__}: {e}"


# ------------------------------------------------------------------ scoring


def mac(a, b):
    a = np.asarray(a, dtype=complex)
    b = np.asarray(b, dtype=complex)
    return float(abs(np.vdot(a, b)) ** 2 / (np.vdot(a, a).real * np.vdot(b, b).real))


def match(modes, truth):
    """One-to-one: pairs (estimate, truth index) within FREQ_TOL and MAC_MIN, closest
    in frequency first. Returns {truth index: estimate}, spurious count."""
    pairs = []
    for i, m in enumerate(modes):
        for j, t in enumerate(truth):
            d = abs(m["frequency_hz"] - t["frequency_hz"]) / t["frequency_hz"]
            if d > FREQ_TOL:
                continue
            if m.get("shape") is not None and t.get("shape") is not None \
                    and len(m["shape"]) == len(t["shape"]) and mac(m["shape"], t["shape"]) < MAC_MIN:
                continue
            pairs.append((d, i, j))
    used_i, found = set(), {}
    for d, i, j in sorted(pairs):
        if i in used_i or j in found:
            continue
        used_i.add(i)
        found[j] = modes[i]
    return found, len(modes) - len(used_i)


def fmt(x, digits=1, pct=False):
    if x is None or (isinstance(x, float) and math.isnan(x)):
        return "–"
    return f"{100 * x:.{digits}f} %" if pct else f"{x:.{digits}f}"


def accuracy_rows(results, truths):
    """results: {tool: [(modes, seconds, error)]}; one row per tool."""
    rows = []
    for tool, runs in results.items():
        found = total = spurious = 0
        derr, ferr, secs = [], [], []
        for (modes, seconds, _), truth in zip(runs, truths):
            hit, spur = match(modes, truth["modes"])
            found += len(hit)
            total += len(truth["modes"])
            spurious += spur
            for j, m in hit.items():
                t = truth["modes"][j]
                derr.append(abs(m["damping_ratio"] - t["damping_ratio"]) / t["damping_ratio"])
                ferr.append(abs(m["frequency_hz"] - t["frequency_hz"]) / t["frequency_hz"])
            if not math.isnan(seconds):
                secs.append(seconds)
        failed = sum(1 for r in runs if r[2])
        rows.append((tool, f"{found} / {total}", str(spurious),
                     fmt(statistics.median(derr) if derr else None, 1, True),
                     fmt(statistics.median(ferr) if ferr else None, 2, True),
                     fmt(statistics.median(secs) if secs else None, 2),
                     f"{min(secs):.2f}–{max(secs):.2f}" if secs else "–",
                     str(failed)))
    return rows


def print_table(header, rows):
    print("| " + " | ".join(header) + " |")
    print("|" + "|".join(":---" if i == 0 else "---:" for i in range(len(header))) + "|")
    for r in rows:
        print("| " + " | ".join(r) + " |")
    print()


def monte_carlo_rows(results, truth):
    """The scatter over the records of each true mode's estimates against the median
    reported std: ratio = reported / actual, per mode, then the median and range."""
    rows = []
    for tool, runs in results.items():
        per_mode = {}
        for modes, _, _ in runs:
            hit, _ = match(modes, truth["modes"])
            for j, m in hit.items():
                per_mode.setdefault(j, []).append(m)
        if not any(m.get("frequency_std_hz") is not None
                   for ms in per_mode.values() for m in ms):
            continue
        rf, rd = [], []
        enough = max(3, len(runs) // 2)
        for j, ms in per_mode.items():
            if len(ms) < enough:
                continue
            f = [m["frequency_hz"] for m in ms]
            d = [m["damping_ratio"] for m in ms]
            sf = [m["frequency_std_hz"] for m in ms if m.get("frequency_std_hz") is not None]
            sd = [m["damping_ratio_std"] for m in ms if m.get("damping_ratio_std") is not None]
            if sf and statistics.stdev(f) > 0:
                rf.append(statistics.median(sf) / statistics.stdev(f))
            if sd and statistics.stdev(d) > 0:
                rd.append(statistics.median(sd) / statistics.stdev(d))

        def summary(r):
            if not r:
                return "–", "–"
            return f"{statistics.median(r):.2f}", f"{min(r):.2f}–{max(r):.2f}"
        mf, rgf = summary(rf)
        md, rgd = summary(rd)
        rows.append((tool, str(len(rf)), mf, rgf, md, rgd))
    return rows


# ------------------------------------------------------------------ sections

HEADER = ["tool", "modes found", "spurious", "median damping error", "median frequency error",
          "s per record (median)", "s range", "failed runs"]


def simulated_section(label, recs, tools, monte_carlo):
    results = {}
    for tool in tools:
        runs = []
        for path, _, fs, cols in recs:
            r = run_tool(tool, path, cols, fs)
            if r[2]:
                progress(f"{tool.name} failed on {os.path.basename(path)}: {r[2]}")
            progress(f"{tool.name} {os.path.basename(path)}: {len(r[0])} modes, {r[1]:.2f} s")
            runs.append(r)
        results[tool.name] = runs
    print(f"md: **{label}**")
    print()
    print_table(HEADER, accuracy_rows(results, [r[1] for r in recs]))
    if monte_carlo:
        print("md: **Monte Carlo check** over the same records: for each true mode found in at "
              "least half of them, the median std the tool reports divided by the actual "
              "scatter (std over the records) of its estimate; 1 = the std holds, > 1 "
              "overstated. Median over the modes, and range.")
        print()
        print_table(["tool", "modes", "frequency: reported / actual", "range",
                     "damping: reported / actual", "range"],
                    monte_carlo_rows(results, recs[0][1]))


def koma_section(tools):
    exact = json.load(open(os.path.join(KOMA, "reference.json")))
    # The record's own poles: the exact ones as the Newmark integration shifted them
    # (data/koma-shear-frame/PROVENANCE.md).
    ref = {"modes": [{"frequency_hz": m["frequency_hz_as_integrated"],
                      "damping_ratio": m["damping_ratio_as_integrated"],
                      "shape": m["shape"]} for m in exact["modes"]]}
    path = os.path.join(KOMA, "shear_frame.csv")
    results = {}
    for tool in tools:
        kw = {} if isinstance(tool, Era) else (
            {"br": 50, "ordmax": 60} if isinstance(tool, PyOMA2) else {"i": 50, "ordmax": 60})
        results[tool.name] = [run_tool(tool, path, [1, 2, 3, 4, 5], 12.0, **kw)]
        if results[tool.name][0][2]:
            progress(f"{tool.name} failed on the shear frame: {results[tool.name][0][2]}")
    print("md: **koma's shear frame** (data/koma-shear-frame: 5 floors, displacements with "
          "noise, 12 Hz, 1200 s, 5 modes 0.18–1.18 Hz as integrated); peers at block rows 50, "
          "orders 2..60, as koma's example.")
    print()
    print_table(HEADER, accuracy_rows(results, [ref]))
    for tool, runs in results.items():
        found, _ = match(runs[0][0], ref["modes"])
        line = ", ".join(
            f"{t['frequency_hz']:.3f} Hz {100 * t['damping_ratio']:.2f} % → " + (
                f"{found[j]['frequency_hz']:.3f} Hz {100 * found[j]['damping_ratio']:.2f} %"
                if j in found else "–")
            for j, t in enumerate(ref["modes"]))
        print(f"md: {tool}: {line}")
    print()


def daisy_section(tools):
    cols = list(range(3, 31))
    rows = []
    for tool in tools:
        kw = {} if isinstance(tool, Era) else (
            {"br": 30, "ordmax": 120} if isinstance(tool, PyOMA2) else {"i": 30, "ordmax": 120})
        modes, seconds, err = run_tool(tool, DAISY, cols, 1024.0, **kw)
        if err:
            progress(f"{tool.name} failed on DaISy: {err}")
        within = [r for r in DAISY_REFERENCE
                  if any(abs(m["frequency_hz"] - r) <= 0.5 for m in modes)]
        missed = ", ".join(f"{r:g}" for r in DAISY_REFERENCE if r not in within) or "none"
        rows.append((tool.name, f"{len(within)} / {len(DAISY_REFERENCE)}", str(len(modes)),
                     fmt(seconds, 2), "failed" if err else missed))
    print("md: **DaISy steel subframe, outputs only** (28 accelerations, forces dropped, "
          "1024 Hz, 8523 samples): reference frequencies (its PROVENANCE.md) with a reported "
          "mode within 0.5 Hz; peers at block rows 30, orders up to 120, channel means "
          "removed.")
    print()
    print_table(["tool", "references found", "modes reported", "seconds", "missed"], rows)


# ------------------------------------------------------------------ main


def parse_args():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--era", required=True)
    ap.add_argument("--records", type=int, default=10)
    ap.add_argument("--modes", type=int, default=10)
    ap.add_argument("--outputs", type=int, default=8)
    ap.add_argument("--inputs", type=int, default=2)
    ap.add_argument("--rate", type=float, default=64.0)
    ap.add_argument("--noise", type=float, default=0.02)
    ap.add_argument("--mc-seed", type=int, default=101)
    ap.add_argument("--preset", default="hier_avg", help="pyOMA2's Clustering(quick=...)")
    ap.add_argument("--br", type=int, default=20, help="block rows (pyOMA2 br, koma i)")
    ap.add_argument("--ordmax", type=int, default=80)
    ap.add_argument("--no-unc", action="store_true", help="skip pyOMA2's calc_unc run")
    ap.add_argument("--skip", default="", help="comma list of: seeds,one,koma,daisy")
    ap.add_argument("--work", help="folder for the records (default: a temp dir, removed)")
    return ap.parse_args()


def main():
    args = parse_args()
    skip = set(filter(None, args.skip.split(",")))
    tools = [PyOMA2(args.preset, args.br, args.ordmax, False), Koma(args.br, args.ordmax)]
    unc = None if args.no_unc else PyOMA2(args.preset, args.br, args.ordmax, True)
    has_era = era_has_oma(args.era)
    if has_era:
        tools.insert(0, Era(args.era))

    print(f"# Output-only modal analysis: era against pyOMA2 and koma, "
          f"{time.strftime('%Y-%m-%d %H:%M', time.gmtime())} UTC")
    print()
    if not has_era:
        print(f"md: **`{args.era} oma` does not exist in this build**: the peers run alone, "
              "and there is no era row.")
        print()
    print("md: " + "; ".join(t.describe() for t in tools + ([unc] if unc else [])) + ".")
    print()
    print(f"md: A match: frequency within {100 * FREQ_TOL:g} % of a true mode and, where the "
          f"shapes are known, MAC ≥ {MAC_MIN}, one to one, closest first; every other mode a "
          "tool reports is spurious. Seconds: the Python peers from the array to the "
          "clustered modes (import and reading excluded); era the whole process.")
    print()
    work = args.work or tempfile.mkdtemp(prefix="oma-peers-")
    os.makedirs(work, exist_ok=True)
    try:
        seeds, one = make_records(args.era, work, args.records, args)
        progress(f"{2 * args.records} records written in {work}")
        if "seeds" not in skip:
            simulated_section(
                f"{args.records} records, seeds 1..{args.records} (a structure each): "
                f"{args.modes} modes 1–20 Hz, {args.outputs} outputs, {args.inputs} unmeasured "
                f"white-noise forces, {args.rate:g} Hz, {RECORD_S:g} s, "
                f"{100 * args.noise:g} % sensor noise", seeds, tools, False)
        if "one" not in skip:
            simulated_section(
                f"{args.records} records of one structure (seed {args.mc_seed}): one "
                f"{args.records * RECORD_S:g} s record cut into {RECORD_S:g} s records",
                one, tools + ([unc] if unc else []), True)
        if "koma" not in skip:
            koma_section(tools)
        if "daisy" not in skip:
            daisy_section(tools)
    finally:
        if not args.work:
            shutil.rmtree(work, ignore_errors=True)


if __name__ == "__main__":
    main()
