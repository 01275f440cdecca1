#!/usr/bin/env bash
# The Python package's tests: a fresh virtual environment, `pip install .` (the release
# build of crates/era-py by maturin, in the workspace's target folder so that it is
# incremental), pytest, numpy and dask.distributed (required: the fleet tests run
# era.process_record on its LocalCluster), python-control when it installs, then pytest
# on python/tests. The CLI the tests compare with is the workspace's release build.
#
# Usage: scripts/python_tests.sh [pytest args...]
# Environment: PYTHON (default python3), VENV (default TARGET/python-venv, made anew),
# CARGO_TARGET_DIR (default target/).
set -euo pipefail
cd "$(dirname "$0")/.."
repo=$(pwd)
export CARGO_TARGET_DIR=${CARGO_TARGET_DIR:-$repo/target}
case "$CARGO_TARGET_DIR" in /*) ;; *) CARGO_TARGET_DIR=$repo/$CARGO_TARGET_DIR ;; esac
python=${PYTHON:-python3}
venv=${VENV:-$CARGO_TARGET_DIR/python-venv}
SECONDS=0

# The CLI the results are compared with (a no-op after `cargo test --workspace --release`).
cargo build --release -p era-cli --bin era --quiet
export ERA_BIN=$CARGO_TARGET_DIR/release/era

rm -rf "$venv"
"$python" -m venv "$venv"
pip=("$venv/bin/python" -m pip --disable-pip-version-check --no-input)
"${pip[@]}" install --quiet --upgrade pip >/dev/null 2>&1 || true
"${pip[@]}" install --quiet numpy pytest "dask[distributed]"
# python-control for to_control() and the side-by-side example: optional (the tests
# that need it are skipped without it).
"${pip[@]}" install --quiet control >/dev/null 2>&1 \
  || echo "python_tests.sh: python-control did not install; its tests are skipped" >&2
t1=$SECONDS
"${pip[@]}" install --quiet .
t2=$SECONDS
echo "python_tests.sh: CLI build, venv and test tools ${t1} s, pip install . $((t2 - t1)) s"

# Run from outside the source tree, so that `import era` is the installed package.
cd "$venv"
"$venv/bin/python" -m pytest "$repo/python/tests" -q -p no:cacheprovider "$@"
