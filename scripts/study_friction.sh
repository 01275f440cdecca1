#!/usr/bin/env bash
# The friction study of issue 15 (thesis §4–5), end to end in software:
#   1. simulated free decays of the 8 actuators (their true Coulomb forces, 2 % viscous
#      damping, 1 % sensor noise) -> `era friction estimate` (Eq. 3.12, and the combined
#      law that separates friction from viscous damping) and `era friction tune` (the
#      thesis's neutral coefficient);
#   2. the FRF test for each seed in SEEDS: the thesis's protocol (0.6 V without
#      compensation, 0.3 V with, the combined-law coefficients) and, to tell the effect
#      of compensation from that of the drive level, both at equal drive (0.6 V and
#      0.3 V with and without); plus the exact linear FRFs;
#   3. every set identified with the thesis settings (--states 80 --hankel-factor 5
#      --integrations 1 --zero-lines 3 --pad-to 1024);
#   4. `era compare` of the pairs, with their models; a table of the fit errors;
#   5. one short run of each thesis case with time histories and their figures.
# Usage: scripts/study_friction.sh [OUT_DIR]   (AVERAGES=20 SEEDS="1" by default)
set -euo pipefail
cd "$(dirname "$0")/.."
. scripts/era_bin.sh
out=${1:-study}
averages=${AVERAGES:-20}
seeds=${SEEDS:-1}
mkdir -p "$out"/decays
# True Coulomb forces of the simulated actuators (lbf): Table 5.1's free-decay values
# for actuators 1-6, the adjusted ones for the horizontal actuators 9 and 10 (see
# era::sim::experiment::thesis_actuators).
forces=(0.0591 0.0565 0.0549 0.0353 0.0574 0.0518 0.0325 0.0175)
json_field() { sed -n "s/.*\"$1\": \([^,]*\),*/\1/p" "$2" | head -1; }
coefficients=()
echo "== 1. free decays -> estimate (Eq. 3.12 and combined) -> tune"
printf '  %-9s %9s %10s %10s %11s %12s\n' actuator "true F_C" "Eq. 3.12" combined "comb. zeta" "tune neutral"
for j in "${!forces[@]}"; do
  n=$((j + 1))
  "$era" friction simulate --coulomb-force "${forces[$j]}" --stiffness 1 \
    --viscous-damping-ratio 0.02 --x0 1.0 --noise 0.01 --seed "$n" \
    --out "$out/decays/actuator$n.csv" -q
  "$era" friction estimate "$out/decays/actuator$n.csv" --stiffness 1 --json \
    >"$out/decays/estimate$n.json" 2>/dev/null
  "$era" friction tune "$out/decays/actuator$n.csv" --stiffness 1 --json \
    >"$out/decays/tune$n.json" 2>/dev/null
  est=$(json_field coulomb_force_mean "$out/decays/estimate$n.json")
  comb=$(json_field combined_coulomb_force_mean "$out/decays/estimate$n.json")
  zeta=$(json_field combined_viscous_damping_ratio_mean "$out/decays/estimate$n.json")
  neutral=$(json_field neutral_coefficient "$out/decays/tune$n.json")
  printf '  %-9s %9s %10.4f %10.4f %11.4f %12.4f\n' "$n" "${forces[$j]}" "$est" "$comb" "$zeta" "$neutral"
  coefficients+=("$comb")
done
list=$(IFS=,; echo "${coefficients[*]}")
identify() {
  mkdir -p "$out/id_$1"
  "$era" identify "$out/$1.csv" --preset thesis --states 80 --hankel-factor 5 --integrations 1 \
    --zero-lines 3 --pad-to 1024 --out "$out/id_$1" -q
}
compare() {
  mkdir -p "$out/compare_$1_$2"
  "$era" compare "$out/$1.csv" "$out/$2.csv" --model-a "$out/id_$1/model.json" \
    --model-b "$out/id_$2/model.json" --out "$out/compare_$1_$2" --json \
    >"$out/compare_$1_$2.json" 2>/dev/null
  # The two fit errors, "a b", from the JSON's fit_percent block.
  tr -d ' \n' <"$out/compare_$1_$2.json" |
    sed -n 's/.*"fit_percent":{"a":\([^,]*\),"b":\([^,]*\),.*/\1 \2/p'
  echo # the JSON has no final newline, and `read` needs one
}
rows=()
for seed in $seeds; do
  echo "== 2. the experiment, seed $seed ($averages averages per actuator)"
  s="_s$seed"
  "$era" simulate experiment --compensation off --averages "$averages" --seed "$seed" \
    --out "$out/off06$s.csv" --exact-out "$out/exact$s.csv" -q
  "$era" simulate experiment --compensation on --coefficients "$list" \
    --averages "$averages" --seed "$seed" --out "$out/on03$s.csv" -q
  "$era" simulate experiment --compensation off --excitation 0.3 \
    --averages "$averages" --seed "$seed" --out "$out/off03$s.csv" -q
  "$era" simulate experiment --compensation on --coefficients "$list" --excitation 0.6 \
    --averages "$averages" --seed "$seed" --out "$out/on06$s.csv" -q
  echo "== 3. ERA with the thesis settings"
  for c in off06 on03 off03 on06 exact; do identify "$c$s"; done
  echo "== 4. compare"
  read -r f_off06 f_on03 < <(compare "off06$s" "on03$s")
  read -r f_off03 f_on03b < <(compare "off03$s" "on03$s")
  read -r f_off06b f_on06 < <(compare "off06$s" "on06$s")
  read -r _ f_exact < <(compare "off06$s" "exact$s")
  compare "on03$s" "exact$s" >/dev/null
  rows+=("$(printf '  %-5s %13.1f %13.1f %13.1f %13.1f %9.1f' "$seed" "$f_off06" "$f_on03" "$f_off03" "$f_on06" "$f_exact")")
done
echo "== 5. one short run of each thesis case, with time histories and figures"
mkdir -p "$out/time_off06" "$out/time_on03"
"$era" simulate experiment --compensation on --coefficients "$list" --averages 1 --seed 1 \
  --out "$out/time_on03/frf.csv" --time-histories "$out/time_on03" \
  | grep 'excited actuators' || true
"$era" simulate experiment --compensation off --averages 1 --seed 1 \
  --out "$out/time_off06/frf.csv" --time-histories "$out/time_off06" \
  | grep 'excited actuators' || true
echo
echo "ERA fit error (%, 0.1-14 Hz, each model against its own data; lower is better)"
printf '  %-5s %13s %13s %13s %13s %9s\n' seed "off 0.6 V" "on 0.3 V" "off 0.3 V" "on 0.6 V" exact
printf '%s\n' "${rows[@]}"
echo "thesis protocol: off 0.6 V against on 0.3 V; equal drive: off against on at 0.3 V and at 0.6 V"
echo "done: $out/compare_off06_s1_on03_s1/compare.html"
