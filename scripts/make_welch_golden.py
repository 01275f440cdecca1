#!/usr/bin/env python3
"""Golden values for era's FRF estimation (crates/era/src/estimate.rs).

Writes crates/era/tests/golden/welch_scipy.json: deterministic test signals (2 inputs,
3 outputs, 1500 samples at 1000 Hz) and, for a few Welch settings, scipy's `csd` of
every input/output pair, `coherence` of every output/input pair, and the H1, H2 and Hv
estimates and the multiple coherence computed from those spectra with numpy. The test
crates/era/tests/welch_golden.rs compares era with them to 1e-10 relative. Run once;
re-run only to regenerate:

    scripts/make_welch_golden.sh        # makes target/py-venv with numpy and scipy
"""
import json
import os

import numpy as np
import scipy
from scipy import signal

FS = 1000.0
N = 1500
rng = np.random.default_rng(20261121)
x = rng.standard_normal((2, N))
x[1] += 0.3 * x[0]  # correlated inputs, as two shakers on one structure are
# Three outputs: two resonant filters of the inputs plus a little noise and an offset.
b1, a1 = signal.iirpeak(120.0, 15.0, fs=FS)
b2, a2 = signal.iirpeak(310.0, 25.0, fs=FS)
y = np.empty((3, N))
y[0] = signal.lfilter(b1, a1, x[0]) + 0.5 * signal.lfilter(b2, a2, x[1])
y[1] = signal.lfilter(b2, a2, x[0]) - signal.lfilter(b1, a1, x[1])
y[2] = 0.2 * x[0] + signal.lfilter(b1, a1, x[1]) + 0.05 * rng.standard_normal(N)
y += np.array([[0.3], [-1.0], [2.0]])
y += np.linspace(0.0, 0.5, N)  # a drift, for the linear detrend

CASES = [
    {"window": "hann", "detrend": "mean", "frame": 256, "overlap": 0.5},
    {"window": "rectangular", "detrend": "linear", "frame": 200, "overlap": 0.25},
    {"window": "flat-top", "detrend": "none", "frame": 128, "overlap": 0.0},
    {"window": "hann", "detrend": "linear", "frame": 255, "overlap": 0.6},
]
SCIPY_WINDOW = {"hann": "hann", "rectangular": "boxcar", "flat-top": "flattop"}
SCIPY_DETREND = {"mean": "constant", "linear": "linear", "none": False}


def cplx(a):
    return {"re": np.real(a).tolist(), "im": np.imag(a).tolist()}


cases = []
for case in CASES:
    kw = dict(fs=FS, window=SCIPY_WINDOW[case["window"]], nperseg=case["frame"],
              noverlap=int(round(case["overlap"] * case["frame"])),
              detrend=SCIPY_DETREND[case["detrend"]])
    p, q = x.shape[0], y.shape[0]
    # G_ab = E[A B*] is scipy's csd(b, a).
    f, _ = signal.csd(x[0], x[0], **kw)
    L = f.size
    gxx = np.array([[signal.csd(x[k], x[j], **kw)[1] for k in range(p)] for j in range(p)])
    gyx = np.array([[signal.csd(x[j], y[i], **kw)[1] for j in range(p)] for i in range(q)])
    gyy = np.array([[signal.csd(y[m], y[i], **kw)[1] for m in range(q)] for i in range(q)])
    coh = np.array([[signal.coherence(x[j], y[i], **kw)[1] for j in range(p)] for i in range(q)])
    h1 = np.empty((q, p, L), complex)
    h2 = np.empty((q, p, L), complex)
    hv = np.empty((q, p, L), complex)
    mult = np.empty((q, L))
    for k in range(L):
        Gxx, Gyx, Gyy = gxx[:, :, k], gyx[:, :, k], gyy[:, :, k]
        H1 = np.linalg.solve(Gxx, Gyx.conj().T).conj().T
        h1[:, :, k] = H1
        h2[:, :, k] = Gyy @ np.linalg.pinv(Gyx).conj().T  # = Gyy Gyx (Gyx^H Gyx)^-1
        for i in range(q):
            G = np.zeros((p + 1, p + 1), complex)
            G[:p, :p] = Gxx
            G[p, :p] = Gyx[i]
            G[:p, p] = Gyx[i].conj()
            G[p, p] = Gyy[i, i]
            w, v = np.linalg.eigh(G)
            vec = v[:, 0]
            hv[i, :, k] = -vec[:p].conj() / vec[p].conj()
            mult[i, k] = np.real(H1[i] @ Gyx[i].conj()) / np.real(Gyy[i, i])
    cases.append({**case, "frequency_hz": f.tolist(), "gxx": cplx(gxx), "gyx": cplx(gyx),
                  "gyy": cplx(gyy), "coherence": coh.tolist(), "h1": cplx(h1), "h2": cplx(h2),
                  "hv": cplx(hv), "multiple_coherence": mult.tolist()})

out = os.path.join(os.path.dirname(__file__), "..", "crates", "era", "tests", "golden", "welch_scipy.json")
with open(out, "w") as fh:
    json.dump({"generator": f"scripts/make_welch_golden.py, scipy {scipy.__version__}, numpy {np.__version__}",
               "sample_rate_hz": FS, "inputs": x.tolist(), "outputs": y.tolist(), "cases": cases}, fh)
print("wrote", out)
