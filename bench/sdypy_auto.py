#!/usr/bin/env python3
"""sdypy-EMA's automatic route on an era FRF CSV: LSCF poles up to order 100, the poles
that are stable in frequency and damping at the highest order picked automatically
(0 < damping <= 20 %, inside the band, one per 0.5 % in frequency), then LSFD for the
modal constants. Prints one JSON line: the seconds of the calls (LSCF, the pick, LSFD),
the frequencies and damping ratios found.

usage: sdypy_auto.py FRF_CSV LOWER_HZ UPPER_HZ
"""
import io
import json
import sys
import time
import warnings
from contextlib import redirect_stderr

import numpy as np
from sdypy import EMA
from sdypy.EMA import stabilization

path, lower, upper = sys.argv[1], float(sys.argv[2]), float(sys.argv[3])
lines = [l for l in open(path) if not l.startswith("#") and l.strip()]
header = lines[0].strip().split(",")
rows = np.array([[float(v) for v in l.split(",")] for l in lines[1:]])
freq = rows[:, 0]
pairs = (len(header) - 1) // 2
frf = np.array([rows[:, 1 + 2 * k] + 1j * rows[:, 2 + 2 * k] for k in range(pairs)])

t0 = time.perf_counter()
model = EMA.Model(frf=frf, freq=freq, lower=lower, upper=upper, pol_order_high=100,
                  frf_form="accelerance")
with redirect_stderr(io.StringIO()):
    model.get_poles(method="lscf", show_progress=False)
t1 = time.perf_counter()
# The automatic pick: poles stable in frequency (0.1 %) and damping (5 %) against the
# order below, at the highest order that has any, as sdypy-EMA's own stability test.
with warnings.catch_warnings(), redirect_stderr(io.StringIO()):
    warnings.simplefilter("ignore")
    fn, xi, test_fn, test_xi = stabilization._stabilization(
        model.all_poles, model.n_bands * model.pol_order_high, err_fn=0.001, err_xi=0.05)
stable = (test_fn > 0) & (test_xi > 0) & (xi > 0) & (xi <= 0.2) & (fn >= lower) & (fn <= upper)
orders = [j for j in range(stable.shape[1]) if stable[:, j].any()]
picked = []
if orders:
    top = orders[-1]
    for f in sorted(fn[stable[:, top], top]):
        if not picked or f > picked[-1] * 1.005:
            picked.append(float(f))
# The picked poles of the top order, by index, as sdypy-EMA's own pickers leave them
# (its `select_closest_poles` returned zeros for every pole here).
if picked:
    poles = np.asarray(model.all_poles[top])
    index = []
    for f in picked:
        hz = np.where(poles.imag > 0, np.abs(poles) / (2 * np.pi), np.inf)
        index.append([top, int(np.argmin(np.abs(hz - f)))])
    model.pole_ind = np.asarray(index, dtype=int)
    chosen = np.array([poles[j] for _, j in index])
    model.nat_freq = np.abs(chosen) / (2 * np.pi)
    model.nat_xi = -chosen.real / np.abs(chosen)
t2 = time.perf_counter()
with warnings.catch_warnings(), redirect_stderr(io.StringIO()):
    warnings.simplefilter("ignore")
    if picked:
        model.get_constants(method="lsfd")
t3 = time.perf_counter()
print(json.dumps({
    "lscf_s": t1 - t0, "pick_s": t2 - t1, "lsfd_s": t3 - t2, "seconds": t3 - t0,
    "frequency_hz": [float(f) for f in getattr(model, "nat_freq", [])],
    "damping_ratio": [float(x) for x in getattr(model, "nat_xi", [])],
    "version": EMA.__version__,
}))
