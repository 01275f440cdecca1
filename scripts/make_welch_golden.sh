#!/usr/bin/env bash
# Regenerates crates/era/tests/golden/welch_scipy.json with scipy in a venv under target/.
exec bash "$(dirname "$0")/py_venv.sh" "numpy scipy" scripts/make_welch_golden.py
