#!/usr/bin/env bash
# A fixed set of runs whose outputs a refactoring must not change (issue 32): the demo's
# JSON; identify at the thesis settings, with --states auto, and on the default route
# (automatic order + refinement) on a DTA-like set and on the DaISy subframe; frf on DaISy
# and LADISK; the friction verbs; Python's identify when the package is installed.
#
#   scripts/golden_outputs.sh OUT_DIR                  # with target/release/era
#   python3 scripts/golden_compare.py BEFORE_DIR AFTER_DIR
#
# Every run is single-threaded (--threads 1), so that the refinement's sums are in one
# order; figures and reports are not written (--no-figures where the verb has it).
# Environment: ERA_BIN (default: the workspace's release build), PYTHON (a Python with
# the era package; default target/python-venv/bin/python, skipped with a note if absent).
set -euo pipefail
cd "$(dirname "$0")/.."
out=${1:?usage: scripts/golden_outputs.sh OUT_DIR}
. scripts/era_bin.sh
era=${ERA_BIN:-$era}
rm -rf "$out" && mkdir -p "$out"
run() { # name, then the command; stdout to NAME.out, stderr to NAME.err
  local name=$1; shift
  "$@" >"$out/$name.out" 2>"$out/$name.err" || echo "exit $?" >>"$out/$name.err"
}
export RAYON_NUM_THREADS=1

run demo "$era" --threads 1 demo --json -q --out "$out/demo"

"$era" simulate modal -q --collocated --seed 987654321 --out "$out/dta.csv"
"$era" simulate modal -q --collocated --seed 1 --noise 0.05 --out "$out/dtan.csv"
thesis=(--hankel-factor 5 --integrations 1 --zero-lines 3 --pad-to 1024 --no-figures --json -q)
run dta_thesis "$era" --threads 1 identify "$out/dta.csv" --preset thesis --states 80 "${thesis[@]}" --out "$out/dta_thesis"
run dtan_auto "$era" --threads 1 identify "$out/dtan.csv" --preset thesis --states auto "${thesis[@]}" --out "$out/dtan_auto"
run dtan_refine "$era" --threads 1 identify "$out/dtan.csv" "${thesis[@]}" --out "$out/dtan_refine"

daisy=data/daisy-steel-subframe/flexible_structure_dat.mat
mkdir -p "$out/daisy_frf" "$out/ladisk_frf"
run daisy_frf "$era" --threads 1 frf "$daisy" --inputs 1,2 --outputs 3-30 --sample-rate 1024 \
  --frame 2048 --json -q --out "$out/daisy_frf/subframe.csv"
run daisy_thesis "$era" --threads 1 identify "$out/daisy_frf/subframe.csv" --preset thesis --states 60 \
  --no-figures --json -q --out "$out/daisy_thesis"
run daisy_refine "$era" --threads 1 identify --from-time "$daisy" --inputs 1,2 --outputs 3-30 \
  --sample-rate 1024 --frame 2048 --no-figures --json -q --out "$out/daisy_refine"
run ladisk_frf "$era" --threads 1 frf data/ladisk-plate-sweep/view_*.hdf5 --inputs force --outputs acc \
  --frame 51200 --window rectangular --overlap 0 --max-hz 560 --units m/s^2,N --json -q \
  --out "$out/ladisk_frf/plate.csv"

for s in 1 2 3 4; do
  "$era" friction simulate --coulomb-force 0.0591 --stiffness 1 --natural-frequency-hz 1.5 \
    --x0 1.5 --noise 0.05 --seed $s --sample-rate 200 -q --out "$out/decay$s.csv"
done
run friction_estimate "$era" friction estimate "$out"/decay{1,2,3,4}.csv --stiffness 1 --json -q
run friction_tune_records "$era" friction tune "$out"/decay{1,2,3,4}.csv --stiffness 1 --fraction 0.85 --json -q
run friction_tune_model "$era" friction tune --coulomb-force 0.0591 --stiffness 1 \
  --natural-frequency-hz 1.5 --viscous-damping-ratio 0.002 --dead-zone 0.2 --json -q
"$era" friction simulate --coulomb-force 0.0591 --stiffness 1 --natural-frequency-hz 1.5 \
  --viscous-damping-ratio 0.002 --x0 1.5 --sample-rate 200 --method integrate -q --out "$out/decay_integrated.csv"

python=${PYTHON:-target/python-venv/bin/python}
if "$python" -c "import era" 2>/dev/null; then
  "$python" - "$out/dtan.csv" "$out/python" <<'PY' >"$out/python.out" 2>"$out/python.err"
import sys, era
frf = era.read_frf(sys.argv[1])
kw = dict(hankel_factor=5, integrations=1, zero_lines=3, pad_to=1024)
for name, extra in [("thesis", dict(preset="thesis", states=80)),
                    ("auto", dict(preset="thesis", states="auto")),
                    ("refine", dict())]:
    found = era.identify(frf, **kw, **extra)
    with open(f"{sys.argv[2]}_{name}.json", "w") as f:
        f.write(found.to_json())
    print(name, "A", found.a.tolist())
    print(name, "fit", found.fit)
PY
else
  echo "golden_outputs.sh: no Python era package at $python; Python's identify not recorded" >&2
fi
echo "golden outputs in $out"
