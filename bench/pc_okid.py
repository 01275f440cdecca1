#!/usr/bin/env python3
"""python-control's route from time histories to a model on the DaISy steel subframe:
`markov` (least squares of the outputs on past inputs) then `eigensys_realization`, with
the Markov length and Hankel size era's OKID-ERA uses at the same order.

usage: pc_okid.py MAT_FILE MARKOV_SAMPLES STATES BLOCKS
Prints one JSON line: the wall time of each call, and how many of the 14 indicative
frequencies of data/daisy-steel-subframe/PROVENANCE.md lie within 0.5 Hz of a pole.
"""
import json
import sys
import time

import numpy as np
import scipy.io
import control

path, samples, states, blocks = sys.argv[1], *map(int, sys.argv[2:5])
data = scipy.io.loadmat(path)["flexible_structure_dat"]
data = data - data.mean(axis=0)
u, y = data[:, :2].T, data[:, 2:].T
fs = 1024.0
t0 = time.perf_counter()
markov = control.markov(y, u, samples, dt=1 / fs)
t1 = time.perf_counter()
model, _ = control.eigensys_realization(markov, states, m=blocks, n=blocks, dt=1 / fs)
t2 = time.perf_counter()
poles = np.log(np.linalg.eigvals(model.A).astype(complex)) * fs
freq = np.abs(poles) / (2 * np.pi)
refs = [62.1, 119.0, 154.7, 192.5, 215.0, 229.5, 239.3, 286.8, 321.2, 334.1, 352.2, 398.1, 417.5, 467.2]
hits = sum(bool(np.min(np.abs(freq - r)) <= 0.5) for r in refs)
print(json.dumps({"markov_s": t1 - t0, "era_s": t2 - t1, "seconds": t2 - t0, "found": hits,
                  "control": control.__version__}))
