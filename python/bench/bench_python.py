"""Benchmarks of the Python package at the thesis size (the DTA-like 8 x 8 set, 801
lines; ns 80, lh 5, ni 1, nz 3, ndpts 1024):

1. Call overhead: `era.identify` from Python against the same work in Rust, the stage
   times the CLI measures inside the process (`era identify --timings --json`: preprocess,
   Markov, Hankel + SVD, realization, modes, fit, the zero-start check; reading the file
   is left out on both sides). Runs alternate between the two so that machine load falls
   on both alike; the medians are compared.
2. era against python-control's `eigensys_realization` on the same Markov data, in the
   same process (python/examples/python_control_side_by_side.py explains the data).

    python python/bench/bench_python.py [--repeats 15] [--control-repeats 1] [--era PATH]
                                        [--noise 0.05] [--seed 1]

Prints markdown tables and a JSON line (`bench/tables.sh python` writes the tables into
the book). Not a test: timings go here, never into assertions.
"""

import argparse
import json
import os
import pathlib
import statistics
import subprocess
import sys
import tempfile
import time

import numpy as np

import era

REPO = pathlib.Path(__file__).resolve().parents[2]
SETTINGS = dict(states=80, hankel_factor=5, integrations=1, zero_lines=3, pad_to=1024, preset="thesis")
FLAGS = ["--preset", "thesis", "--states", "80", "--hankel-factor", "5", "--integrations", "1",
         "--zero-lines", "3", "--pad-to", "1024"]
STAGES = ("preprocess", "markov", "hankel_svd", "realize", "modes", "fit", "zero_start")


def default_binary() -> pathlib.Path:
    target = pathlib.Path(os.environ.get("CARGO_TARGET_DIR", REPO / "target"))
    return (target if target.is_absolute() else REPO / target) / "release" / "era"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=15)
    parser.add_argument("--control-repeats", type=int, default=1)
    parser.add_argument("--era", type=pathlib.Path, default=default_binary())
    parser.add_argument("--noise", type=float, default=0.05, help="noise of the set (fraction)")
    parser.add_argument("--seed", type=int, default=1, help="seed of the set and its noise")
    args = parser.parse_args()

    frf = era.simulate_modal(collocated=True, noise=args.noise, seed=args.seed)
    folder = pathlib.Path(tempfile.mkdtemp(prefix="era-bench-"))
    path = folder / "dta.csv"
    era.write_frf(path, frf)
    frf = era.read_frf(path)
    era.identify(frf, **SETTINGS)  # warm caches and the thread pool

    python_s, rust_s = [], []
    for _ in range(args.repeats):
        t0 = time.perf_counter()
        era.identify(frf, **SETTINGS)
        python_s.append(time.perf_counter() - t0)
        done = subprocess.run([str(args.era), "identify", str(path), *FLAGS, "--timings",
                               "--json", "--quiet"], capture_output=True, text=True, check=True)
        timings = json.loads(done.stdout)["timings_s"]
        rust_s.append(sum(timings[s] for s in STAGES))
    py, rs = statistics.median(python_s), statistics.median(rust_s)
    print(f"| thesis size, {args.repeats} runs each (medians) | time |")
    print("|---|---:|")
    print(f"| `era.identify` from Python | {1e3 * py:.1f} ms |")
    print(f"| the same stages in Rust (`era identify --timings`) | {1e3 * rs:.1f} ms |")
    print(f"| Python / Rust | {py / rs:.3f} (overhead {100 * (py / rs - 1):+.1f} %) |")

    result = {"python_ms": 1e3 * py, "rust_ms": 1e3 * rs, "python_over_rust": py / rs}
    try:
        import control
    except ImportError:
        print("python-control is not installed: pip install control for the second part")
    else:
        sys.path.insert(0, str(REPO / "python" / "examples"))
        from python_control_side_by_side import markov_of

        markov = markov_of(frf, 1, 3, 1024)
        blocks = (80 * 5 // 4 * 4) // 2 - 1
        found = era.identify(frf, **SETTINGS)
        era_s, ctrl_s = [], []
        for _ in range(args.control_repeats):
            t0 = time.perf_counter()
            era.identify(frf, **SETTINGS)
            era_s.append(time.perf_counter() - t0)
            t0 = time.perf_counter()
            sys_, _ = control.eigensys_realization(markov, r=80, m=blocks, n=blocks,
                                                   dt=found.sample_time_s)
            ctrl_s.append(time.perf_counter() - t0)
        gap = np.max(np.abs(np.sort_complex(np.linalg.eigvals(found.a))
                            - np.sort_complex(sys_.poles())))
        e, c = min(era_s), min(ctrl_s)
        print()
        print(f"| era against python-control {control.__version__} on the same Markov data "
              f"(H0 {found.hankel_size[0]} × {found.hankel_size[1]}, best of {args.control_repeats}) | time |")
        print("|---|---:|")
        print(f"| `era.identify` (Markov data, Hankel SVD, realization, modes, fit, zero-start check) | {1e3 * e:.1f} ms |")
        print(f"| `control.eigensys_realization` | {1e3 * c:.1f} ms |")
        print(f"| ratio | {c / e:.1f}× (eigenvalues {gap:.1e} apart) |")
        result.update({"era_ms": 1e3 * e, "control_ms": 1e3 * c, "control_over_era": c / e,
                       "eigenvalue_gap": gap})
    print(json.dumps(result))


if __name__ == "__main__":
    main()
