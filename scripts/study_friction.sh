#!/usr/bin/env bash
# The friction study of issue 15 (thesis §4–5), end to end in software:
#   1. simulated free decays of the 8 actuators (their true Coulomb forces, 2 % viscous
#      damping, 1 % sensor noise) -> `era friction estimate`, then `era friction tune`
#      for each actuator's neutral compensation coefficient;
#   2. the FRF test with and without compensation (`era simulate experiment`, 0.6 V
#      without, 0.3 V with, the tuned coefficients), plus the exact linear FRFs;
#   3. both sets identified with the thesis settings (--states 80 --hankel-factor 5
#      --integrations 1 --zero-lines 3 --pad-to 1024);
#   4. `era compare` of the two sets with their models, and of each against the exact FRFs.
# Usage: scripts/study_friction.sh [OUT_DIR]   (AVERAGES=20 SEED=1 by default)
set -euo pipefail
cd "$(dirname "$0")/.."
. scripts/era_bin.sh
out=${1:-study}
averages=${AVERAGES:-20}
seed=${SEED:-1}
mkdir -p "$out"/decays
# True Coulomb forces of the simulated actuators (lbf): Table 5.1's free-decay values
# for actuators 1-6, the adjusted ones for the horizontal actuators 9 and 10 (see
# era::sim::experiment::thesis_actuators).
forces=(0.0591 0.0565 0.0549 0.0353 0.0574 0.0518 0.0325 0.0175)
coefficients=()
echo "== 1. free decays -> estimate -> tune"
for j in "${!forces[@]}"; do
  n=$((j + 1))
  "$era" friction simulate --coulomb-force "${forces[$j]}" --stiffness 1 \
    --viscous-damping-ratio 0.02 --x0 1.0 --noise 0.01 --seed "$n" \
    --out "$out/decays/actuator$n.csv" -q
  "$era" friction estimate "$out/decays/actuator$n.csv" --stiffness 1 --json \
    >"$out/decays/estimate$n.json" 2>/dev/null
  "$era" friction tune "$out/decays/actuator$n.csv" --stiffness 1 --json \
    >"$out/decays/tune$n.json" 2>/dev/null
  est=$(sed -n 's/.*"coulomb_force_mean": \([^,]*\),/\1/p' "$out/decays/estimate$n.json")
  c=$(sed -n 's/.*"neutral_coefficient": \([^,]*\),*/\1/p' "$out/decays/tune$n.json")
  printf '  actuator %d: true F_C %s lbf, estimated %.4f, neutral coefficient %.4f\n' \
    "$n" "${forces[$j]}" "$est" "$c"
  coefficients+=("$c")
done
list=$(IFS=,; echo "${coefficients[*]}")
echo "== 2. the experiment ($averages averages per actuator, seed $seed)"
"$era" simulate experiment --compensation off --averages "$averages" --seed "$seed" \
  --out "$out/off.csv" --exact-out "$out/exact.csv" --timings
"$era" simulate experiment --compensation on --coefficients "$list" \
  --averages "$averages" --seed "$seed" --out "$out/on.csv" --timings
echo "== 3. ERA with the thesis settings"
for s in off on exact; do
  mkdir -p "$out/id_$s"
  "$era" identify "$out/$s.csv" --states 80 --hankel-factor 5 --integrations 1 \
    --zero-lines 3 --pad-to 1024 --out "$out/id_$s" -q
done
echo "== 4. compare"
mkdir -p "$out/compare_off_on" "$out/compare_off_exact" "$out/compare_on_exact"
"$era" compare "$out/off.csv" "$out/on.csv" --model-a "$out/id_off/model.json" \
  --model-b "$out/id_on/model.json" --out "$out/compare_off_on"
"$era" compare "$out/off.csv" "$out/exact.csv" --model-a "$out/id_off/model.json" \
  --model-b "$out/id_exact/model.json" --out "$out/compare_off_exact"
"$era" compare "$out/on.csv" "$out/exact.csv" --model-a "$out/id_on/model.json" \
  --model-b "$out/id_exact/model.json" --out "$out/compare_on_exact"
echo "done: $out/compare_off_on/compare.html"
