#!/usr/bin/env bash
# The LADISK plate's damping read from its time histories (ring-down after the sweep has
# passed each mode) and from a local fit to its H1: scripts/ladisk_ringdown.py, with
# numpy, scipy and h5py in a venv under target/.
exec bash "$(dirname "$0")/py_venv.sh" "numpy scipy h5py" scripts/ladisk_ringdown.py "$@"
