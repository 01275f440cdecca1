#!/usr/bin/env python3
"""python-control's ERA on a raw Markov file written by `era_core generate`.

usage: pc_era.py FILE OUTPUTS INPUTS SAMPLES STATES M
Prints one JSON line: the wall time of eigensys_realization alone and the model order.
"""
import json
import sys
import time

import numpy as np
import control

f, q, p, k, r, m = sys.argv[1], *map(int, sys.argv[2:7])
yy = np.fromfile(f, dtype="<f8").reshape(k, q, p).transpose(1, 2, 0).copy()  # (q, p, K)
t = time.perf_counter()
sysd, s = control.eigensys_realization(yy, r, m=m, n=m)
seconds = time.perf_counter() - t
print(json.dumps({"seconds": seconds, "states": int(sysd.nstates), "control": control.__version__}))
