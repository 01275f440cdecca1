#!/usr/bin/env python3
"""Fixtures for era-io's reader tests that only other tools can make.

- scipy_frf.mat: an FRF file as `scipy.io.savemat` writes it (header text
  "MATLAB 5.0 MAT-file Platform: ..., Created on: ...", no comma after "MAT-file"),
  a 2x1 set of 5 lines at 0.5 Hz in the `FRF` + `FreqV` layout.
- hdf5_declared_1e8x2.hdf5: a ~1.4 kB HDF5 file declaring a float64 dataset of shape
  (100000000, 2) whose data is never written (HDF5 allocates it lazily).

Run with a Python that has numpy, scipy and h5py:
    python3 -m venv /tmp/venv && /tmp/venv/bin/pip install scipy numpy h5py
    /tmp/venv/bin/python scripts/make_hostile_fixtures.py crates/era-io/tests/fixtures
"""
import sys
import numpy as np
import scipy.io
import h5py

out = sys.argv[1] if len(sys.argv) > 1 else "."
f = np.arange(5) * 0.5
frf = np.zeros((5, 2), dtype=complex)
frf[:, 0] = 1.0 + 0.5j * np.arange(5)
frf[:, 1] = -2.0 + 0.25j * np.arange(5)
scipy.io.savemat(f"{out}/scipy_frf.mat", {"FRF": frf, "FreqV": f.reshape(-1, 1)})

with h5py.File(f"{out}/hdf5_declared_1e8x2.hdf5", "w", libver="earliest") as h:
    h.create_dataset("data", shape=(100_000_000, 2), dtype="f8")
