#!/usr/bin/env python3
"""Which route from time histories: H1-ERA, OKID-ERA and OKID-ERA/DC on simulated shaker
tests with exact truth, side by side in one run.

For each excitation, record length, noise and seed it simulates a test
(`era simulate shaker`: 10 modes 1.9-20 Hz, 2 shakers, 8 accelerometers, 64 Hz) and runs
`era identify --from-time ...` once per route: H1-ERA as the measured preset runs it
(automatic order, refined against the H1 FRFs) and without the refinement, OKID-ERA at
the automatic order (the preset does not refine it), and OKID-ERA and OKID-ERA/DC at the
true order (20 states; ERA/DC has no automatic order). Against the truth it counts
the modes marked physical that match a true mode within 2 % in frequency (found, one to
one), those that match none (spurious), and the median relative error of the found
modes' frequency and damping. It prints a Markdown table with the date, the machine and
the command, one row per case and route, and the totals per route.

Standard library only (the matching is scripts/trust_study.py's). The era binary is
$ERA, or target/release/era.

    python3 bench/time_routes.py                       # white, burst; 300 s and 60 s; 3 seeds
    python3 bench/time_routes.py --quick               # one seed
    python3 bench/time_routes.py --routes h1,okid --excitations white --durations 300
    python3 bench/time_routes.py --extra "--frame 1024"     # flags for every route
"""

import argparse
import json
import os
import platform
import statistics
import subprocess
import sys
import tempfile
import time

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, os.path.join(ROOT, "scripts"))
from trust_study import era_binary, match  # noqa: E402

ROUTES = {
    "h1": ("H1-ERA, refined (auto)", ["--markov", "frf", "--states", "auto"]),
    "h1-plain": ("H1-ERA (auto)", ["--markov", "frf", "--states", "auto", "--no-refine"]),
    "okid": ("OKID-ERA (auto)", ["--markov", "okid", "--states", "auto"]),
    "okid-20": ("OKID-ERA (20 states)", ["--markov", "okid", "--states", "20"]),
    "okid-dc": ("OKID-ERA/DC (auto)", ["--markov", "okid", "--era-dc", "--states", "auto"]),
    "okid-dc-20": ("OKID-ERA/DC (20 states)", ["--markov", "okid", "--era-dc", "--states", "20"]),
    "h1-dc-20": ("H1-ERA/DC (20 states)", ["--markov", "frf", "--era-dc", "--states", "20", "--no-refine"]),
}

EXCITATIONS = {"white": ["--excitation", "white"], "burst": ["--excitation", "burst"]}


def simulate(exe, folder, case):
    base = os.path.join(folder, "rec.csv")
    subprocess.run([
        exe, "simulate", "shaker", "--out", base, "-q",
        "--modes", "10", "--outputs", "8", "--inputs", "2", "--fmin", "1.9", "--fmax", "20",
        "--sample-rate", "64", "--duration", str(case["duration"]),
        *EXCITATIONS.get(case["excitation"], ["--excitation", case["excitation"]]),
        "--noise", str(case["noise"]), "--seed", str(case["seed"]),
    ], check=True)
    with open(os.path.join(folder, "rec.truth.json")) as f:
        return base, json.load(f)["modes"]


def identify(exe, base, folder, flags):
    cmd = [exe, "identify", base, "--from-time", "--inputs", "1-2", "--outputs", "3-10",
           "--no-figures", "--json", "--out", os.path.join(folder, "out")] + flags
    clock = time.monotonic()
    done = subprocess.run(cmd, capture_output=True, text=True)
    seconds = time.monotonic() - clock
    if done.returncode != 0:
        lines = done.stderr.strip().splitlines()
        return {"error": lines[-1] if lines else "failed"}
    return {"model": json.loads(done.stdout), "seconds": seconds}


def score(model, truth):
    physical = [m for m in model["modes"] if m.get("physical")]
    found, spurious = match(physical, truth)
    rel = lambda key: statistics.median(abs(m[key] - t[key]) / t[key] for m, t in found) if found else float("nan")
    return len(found), spurious, rel("frequency_hz"), rel("damping_ratio")


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--routes", default="h1,h1-plain,okid,okid-20,okid-dc,okid-dc-20")
    ap.add_argument("--excitations", default="white,burst")
    ap.add_argument("--durations", default="300,60")
    ap.add_argument("--noises", default="0.02")
    ap.add_argument("--seeds", default="1,2,3")
    ap.add_argument("--quick", action="store_true", help="one seed")
    ap.add_argument("--extra", default="", help="more era identify flags for every route")
    a = ap.parse_args()
    exe = era_binary()
    routes = [r for r in a.routes.split(",") if r]
    for r in routes:
        if r not in ROUTES:
            sys.exit(f"time_routes: unknown route {r!r}: one of {', '.join(ROUTES)}")
    seeds = [1] if a.quick else [int(s) for s in a.seeds.split(",")]
    extra = a.extra.split()
    print(f"# era routes from time histories: {time.strftime('%Y-%m-%d %H:%M')}, "
          f"{platform.machine()} {os.cpu_count()} cores, {platform.platform()}")
    print(f"# command: python3 bench/time_routes.py {' '.join(sys.argv[1:])}".rstrip())
    print()
    print("| excitation | duration s | noise | seed | route | found | spurious | frequency error | damping error | s |")
    print("|---|---:|---:|---:|---|---:|---:|---:|---:|---:|")
    totals = {r: {"found": 0, "true": 0, "spurious": 0, "damping": [], "errors": 0} for r in routes}
    for excitation in a.excitations.split(","):
        for duration in a.durations.split(","):
            for noise in a.noises.split(","):
                for seed in seeds:
                    case = dict(excitation=excitation, duration=float(duration), noise=float(noise), seed=seed)
                    with tempfile.TemporaryDirectory() as folder:
                        base, truth = simulate(exe, folder, case)
                        for r in routes:
                            name, flags = ROUTES[r]
                            run = identify(exe, base, folder, flags + extra)
                            head = f"| {excitation} | {duration} | {noise} | {seed} | {name} |"
                            if "error" in run:
                                totals[r]["errors"] += 1
                                print(f"{head} error: {run['error']} |||||", flush=True)
                                continue
                            found, spurious, f_err, z_err = score(run["model"], truth)
                            t = totals[r]
                            t["found"] += found
                            t["true"] += len(truth)
                            t["spurious"] += spurious
                            t["damping"].append(z_err)
                            print(f"{head} {found}/{len(truth)} | {spurious} | {f_err:.1e} | "
                                  f"{100 * z_err:.1f} % | {run['seconds']:.2f} |", flush=True)
    print()
    print("| route | found | spurious | median of the damping errors | failed runs |")
    print("|---|---:|---:|---:|---:|")
    for r in routes:
        t = totals[r]
        d = [v for v in t["damping"] if v == v]
        med = f"{100 * statistics.median(d):.1f} %" if d else "-"
        print(f"| {ROUTES[r][0]} | {t['found']}/{t['true']} | {t['spurious']} | {med} | {t['errors']} |")


if __name__ == "__main__":
    main()
