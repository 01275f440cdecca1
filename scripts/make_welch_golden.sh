#!/usr/bin/env bash
# Regenerates crates/era/tests/golden/welch_scipy.json with scipy in a venv under target/.
set -euo pipefail
cd "$(dirname "$0")/.."
venv=target/py-venv
[ -x "$venv/bin/python" ] || python3 -m venv "$venv"
"$venv/bin/python" -c "import numpy, scipy" 2>/dev/null || "$venv/bin/pip" install -q numpy scipy
"$venv/bin/python" scripts/make_welch_golden.py
