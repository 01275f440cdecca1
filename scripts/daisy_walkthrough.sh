#!/usr/bin/env bash
# The DaISy steel subframe walkthrough (docs/src/walkthroughs.md): 2 shaker forces and 28
# accelerations, 1024 Hz, 8523 samples -> 28 x 2 H1 FRFs and coherence -> ERA models at
# several orders and two frame lengths, with the stability check.
# Usage: scripts/daisy_walkthrough.sh [OUT_DIR]   (default TARGET/walkthrough/daisy, TARGET
# being CARGO_TARGET_DIR or target/)
set -euo pipefail
cd "$(dirname "$0")/.."
mat=data/daisy-steel-subframe/flexible_structure_dat.mat
[ -f "$mat" ] || { echo "$mat is absent: the repository's data/ folder should hold it" >&2; exit 2; }
. scripts/era_bin.sh
out=${1:-$target_dir/walkthrough/daisy}
mkdir -p "$out"
for frame in 2048 1024; do
  echo "=== frame $frame samples"
  "$era" frf "$mat" --inputs 1,2 --outputs 3-30 --sample-rate 1024 --frame "$frame" \
      --window hann --overlap 0.5 --estimator h1 --out "$out/frf_$frame.csv"
  "$era" identify "$out/frf_$frame.csv" --states 60 --no-refine --orders 50,70,80 --out "$out/model_$frame"
done
echo "outputs in $out (FRFs, coherence, model.json, fit.json, report.html per frame)"
