#!/usr/bin/env python3
"""Golden values for era's zero-phase Butterworth low-pass (crates/era/src/filter.rs).

Writes crates/era/tests/golden/filter_scipy.csv: one deterministic test signal (a
decaying impulse-response-like mix of sines, 2048 samples) and its scipy
`sosfiltfilt(butter(order, wn, output='sos'), x)` for a few (order, wn) cases, each
column full precision. Run once; re-run only to regenerate:

    python3 -m venv /tmp/pyenv && /tmp/pyenv/bin/pip install numpy scipy
    /tmp/pyenv/bin/python scripts/make_filter_golden.py
"""
import os
import numpy as np
import scipy
from scipy import signal

CASES = [(2, 0.25), (4, 0.1), (6, 0.4), (8, 0.05)]

t = np.arange(2048, dtype=float)
x = (np.exp(-t / 300.0) * np.sin(0.05 * t)
     + 0.3 * np.exp(-t / 900.0) * np.sin(1.9 * t + 0.4)
     + 0.1 * np.cos(2.7 * t))

cols = {"x": x}
for order, wn in CASES:
    sos = signal.butter(order, wn, output="sos")
    cols[f"order{order}_wn{wn}"] = signal.sosfiltfilt(sos, x)

out = os.path.join(os.path.dirname(__file__), "..", "crates", "era", "tests", "golden", "filter_scipy.csv")
with open(out, "w") as f:
    f.write(f"# scipy {scipy.__version__}, numpy {np.__version__}; made by scripts/make_filter_golden.py\n")
    f.write(",".join(cols) + "\n")
    for k in range(len(t)):
        f.write(",".join(repr(float(cols[c][k])) for c in cols) + "\n")
print("wrote", os.path.normpath(out))
