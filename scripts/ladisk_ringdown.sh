#!/usr/bin/env bash
# The LADISK plate's damping read from its time histories (ring-down after the sweep has
# passed each mode) and from a local fit to its H1: scripts/ladisk_ringdown.py, with
# numpy, scipy and h5py in a venv under target/.
set -euo pipefail
cd "$(dirname "$0")/.."
venv=target/py-venv
[ -x "$venv/bin/python" ] || python3 -m venv "$venv"
"$venv/bin/python" -c "import numpy, scipy, h5py" 2>/dev/null || "$venv/bin/pip" install -q numpy scipy h5py
"$venv/bin/python" scripts/ladisk_ringdown.py "$@"
