#!/usr/bin/env bash
# Runs a Python script with the PyPI packages it needs, in one virtual environment
# under target/ (target/py-venv, made on first use, packages added when missing), from
# the repository's root:
#
#   bash scripts/py_venv.sh "numpy scipy" scripts/SCRIPT.py [ARGS...]
set -euo pipefail
cd "$(dirname "$0")/.."
packages=$1
shift
venv=target/py-venv
[ -x "$venv/bin/python" ] || python3 -m venv "$venv"
# shellcheck disable=SC2086 # one word per package
"$venv/bin/python" -c "import ${packages// /, }" 2>/dev/null || "$venv/bin/pip" install -q $packages
exec "$venv/bin/python" "$@"
