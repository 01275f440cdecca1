#!/usr/bin/env python3
"""Which modes to trust: era's automatic choice on measured-like data with exact truth.

For each case (record length, sensor noise, excitation, frame, window, seed) it simulates a
shaker test (`era simulate shaker`), runs `era identify --from-time ... --states auto`
(the FRFs come from era's own Welch analyzer), and compares the modes marked physical
with the truth: found (a physical mode within 2 % in frequency of a true mode, one to
one), spurious (a physical mode that matches none) and the median relative damping
error of the found modes. It prints a Markdown table, one row per case.

Standard library only. The era binary is $ERA, or target/release/era.

    python3 scripts/trust_study.py                   # the default grid
    python3 scripts/trust_study.py --quick           # frames 1024/2048/4096, one seed
    python3 scripts/trust_study.py --seeds 1,2,3 --frames 2048 --extra=--refine
"""

import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile
import time

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


def era_binary():
    exe = os.environ.get("ERA") or os.path.join(
        os.environ.get("CARGO_TARGET_DIR", os.path.join(ROOT, "target")), "release", "era"
    )
    if not os.path.exists(exe):
        sys.exit(f"trust_study: {exe} not found: build it with cargo build --release")
    return exe


def match(physical, truth, tolerance=0.02):
    """One-to-one matching by increasing relative frequency distance."""
    pairs = sorted(
        (abs(p["frequency_hz"] - t["frequency_hz"]) / t["frequency_hz"], i, j)
        for i, p in enumerate(physical)
        for j, t in enumerate(truth)
    )
    used_p, used_t, found = set(), set(), []
    for d, i, j in pairs:
        if d > tolerance or i in used_p or j in used_t:
            continue
        used_p.add(i)
        used_t.add(j)
        found.append((physical[i], truth[j]))
    return found, len(physical) - len(used_p)


def run_case(exe, folder, case, extra):
    base = os.path.join(folder, "rec.csv")
    sim = [
        exe, "simulate", "shaker", "--out", base, "-q",
        "--modes", str(case["modes"]), "--outputs", str(case["outputs"]), "--inputs", str(case["inputs"]),
        "--fmin", str(case["fmin"]), "--fmax", str(case["fmax"]),
        "--sample-rate", str(case["rate"]), "--duration", str(case["duration"]),
        "--excitation", case["excitation"], "--noise", str(case["noise"]), "--seed", str(case["seed"]),
    ]
    subprocess.run(sim, check=True)
    with open(os.path.join(folder, "rec.truth.json")) as f:
        truth = json.load(f)["modes"]
    p = case["inputs"]
    ident = [
        exe, "identify", base, "--from-time", "--inputs", f"1-{p}",
        "--outputs", f"{p + 1}-{p + case['outputs']}", "--frame", str(case["frame"]),
        "--window", case["window"], "--states", "auto", "--no-figures", "--json",
        "--out", os.path.join(folder, "out"),
    ] + extra
    clock = time.monotonic()
    done = subprocess.run(ident, capture_output=True, text=True)
    seconds = time.monotonic() - clock
    if done.returncode != 0:
        return {"error": done.stderr.strip().splitlines()[-1] if done.stderr else "failed"}
    model = json.loads(done.stdout)
    physical = [m for m in model["modes"] if m.get("physical")]
    found, spurious = match(physical, truth)
    damping = [abs(m["damping_ratio"] - t["damping_ratio"]) / t["damping_ratio"] for m, t in found]
    return {
        "found": len(found),
        "true": len(truth),
        "spurious": spurious,
        "physical": len(physical),
        "damping_error": statistics.median(damping) if damping else float("nan"),
        "seconds": seconds,
    }


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", default="1,2,3")
    ap.add_argument("--frames", default="1024,2048,4096")
    ap.add_argument("--windows", default="hann")
    ap.add_argument("--noises", default="0.02")
    ap.add_argument("--durations", default="300")
    ap.add_argument("--excitations", default="white")
    ap.add_argument("--modes", type=int, default=10)
    ap.add_argument("--quick", action="store_true", help="one seed")
    ap.add_argument("--extra", default="", help="more era identify flags, space separated")
    a = ap.parse_args()
    exe = era_binary()
    seeds = [int(s) for s in (["1"] if a.quick else a.seeds.split(","))]
    extra = a.extra.split()
    print(f"# era trust study: {time.strftime('%Y-%m-%d')}, {exe}, extra flags: {' '.join(extra) or '-'}")
    print("| excitation | duration s | noise | frame | window | seed | found | spurious | physical | damping error (median) | s |")
    print("|---|---:|---:|---:|---|---:|---:|---:|---:|---:|---:|")
    totals = {"found": 0, "true": 0, "spurious": 0}
    for excitation in a.excitations.split(","):
        for duration in a.durations.split(","):
            for noise in a.noises.split(","):
                for frame in a.frames.split(","):
                    for window in a.windows.split(","):
                        for seed in seeds:
                            case = dict(modes=a.modes, outputs=8, inputs=2, fmin=1.9, fmax=20, rate=64,
                                        duration=float(duration), excitation=excitation,
                                        noise=float(noise), seed=seed, frame=int(frame), window=window)
                            with tempfile.TemporaryDirectory() as folder:
                                r = run_case(exe, folder, case, extra)
                            if "error" in r:
                                print(f"| {excitation} | {duration} | {noise} | {frame} | {window} | {seed} | error: {r['error']} |")
                                continue
                            for k in totals:
                                totals[k] += r[k]
                            print(f"| {excitation} | {duration} | {noise} | {frame} | {window} | {seed} | "
                                  f"{r['found']}/{r['true']} | {r['spurious']} | {r['physical']} | "
                                  f"{100 * r['damping_error']:.1f} % | {r['seconds']:.2f} |", flush=True)
    print(f"\ntotal: {totals['found']}/{totals['true']} found, {totals['spurious']} spurious")


if __name__ == "__main__":
    main()
