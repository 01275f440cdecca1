#!/usr/bin/env bash
# Why the DaISy subframe's output-only modes lie below its input-output ones: era's
# input-output model driven by the measured forces and by white ones, each through era
# oma (scripts/daisy_oma_forces.py), with numpy and scipy in a venv under target/.
exec bash "$(dirname "$0")/py_venv.sh" "numpy scipy" scripts/daisy_oma_forces.py "$@"
