#!/usr/bin/env bash
# Regenerates the figures shown in the README (docs/src/img/) with the era binary:
# the truth model with 15 % noise (seed 1), Measurement 1 / Actuator 2 (thesis Fig. 5.3),
# its singular values, the DTA-like 8x8 set's overview grid and collocated pair 1/1
# (thesis settings), the DaISy steel subframe's output 3 / input 1 and coherence, and
# its output-only (era oma) stabilization diagram, spectral singular values and MAC.
set -euo pipefail
here=$(cd "$(dirname "$0")/.." && pwd)
cd "$here"
. scripts/era_bin.sh
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
"$era" demo -q --out "$work/demo"
"$era" simulate modal -q --collocated --seed 987654321 --out "$work/dta.csv"
"$era" identify "$work/dta.csv" -q --preset thesis --states 80 --hankel-factor 5 --integrations 1 --zero-lines 3 --pad-to 1024 --out "$work/dta"
cp "$work/demo/noisy/pairs/pair_1_2.png" docs/src/img/truth_noisy_y1_f2.png
cp "$work/demo/noisy/singular_values.png" docs/src/img/truth_noisy_singular_values.png
cp "$work/dta/grid.png" docs/src/img/dta_grid.png
cp "$work/dta/pairs/pair_1_1.png" docs/src/img/dta_y1_f1.png
"$era" identify --from-time data/daisy-steel-subframe/flexible_structure_dat.mat -q \
  --inputs 1,2 --outputs 3-30 --sample-rate 1024 --frame 2048 --states auto --out "$work/daisy"
cp "$work/daisy/pairs/pair_3_1.png" docs/src/img/daisy_y3_f1.png
cp "$work/daisy/coherence.png" docs/src/img/daisy_coherence.png
"$era" simulate modal -q --collocated --seed 1 --noise 0.05 --out "$work/dtan.csv"
"$era" identify "$work/dtan.csv" -q --states auto --hankel-factor 5 --integrations 1 --zero-lines 3 --pad-to 1024 --out "$work/auto"
cp "$work/auto/stabilization.png" docs/src/img/dta_stabilization.png
# The OMA chapter: the subframe's responses alone (docs/src/oma.md).
"$era" oma data/daisy-steel-subframe/flexible_structure_dat.mat -q --outputs 3-30 \
  --sample-rate 1024 --out "$work/oma"
cp "$work/oma/stabilization.png" docs/src/img/daisy_oma_stabilization.png
cp "$work/oma/spectral.png" docs/src/img/daisy_oma_spectral.png
cp "$work/oma/mac.png" docs/src/img/daisy_oma_mac.png
echo "wrote docs/src/img/truth_noisy_y1_f2.png, truth_noisy_singular_values.png, dta_grid.png, dta_y1_f1.png, daisy_y3_f1.png, daisy_coherence.png, dta_stabilization.png, daisy_oma_stabilization.png, daisy_oma_spectral.png, daisy_oma_mac.png"
