#!/usr/bin/env bash
# Why the DaISy subframe's output-only modes lie below its input-output ones: era's
# input-output model driven by the measured forces and by white ones, each through era
# oma (scripts/daisy_oma_forces.py), with numpy and scipy in a venv under target/.
set -euo pipefail
cd "$(dirname "$0")/.."
venv=target/py-venv
[ -x "$venv/bin/python" ] || python3 -m venv "$venv"
"$venv/bin/python" -c "import numpy, scipy" 2>/dev/null || "$venv/bin/pip" install -q numpy scipy
"$venv/bin/python" scripts/daisy_oma_forces.py "$@"
