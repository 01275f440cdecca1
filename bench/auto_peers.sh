#!/usr/bin/env bash
# The whole automatic path against sdypy-EMA on the same FRFs, in the same run:
# era identify --states auto --refine --time-domain continuous --no-figures (file to model
# files) against sdypy-EMA's LSCF (order 100), an automatic pick of the poles stable at
# its highest order, and LSFD (bench/sdypy_auto.py). Data: DTA-like 8 x 8 sets with 40
# modes and 5 % noise (era simulate modal --collocated), one per seed, the truth from the
# simulation. For each tool: the median wall time of three runs (alternating), the peak
# RSS, the modes found within 0.5 % of the truth (one to one), the spurious ones, and the
# median relative damping error of the found ones.
#
#   bench/auto_peers.sh [SEEDS]       # default 101,102,103
#
# Creates a virtual environment with numpy, scipy, python-control and sdypy-EMA from PyPI
# (target/peers-venv, or $ERA_PEERS_VENV), as bench/peers.sh does.
set -euo pipefail
. "$(dirname "$0")/peers_env.sh"
"$venv/bin/python" -c 'import sdypy.EMA' 2>/dev/null || "$venv/bin/pip" install -q sdypy-EMA
cargo build --release -q -p era-cli --bin era
era=${ERA:-$here/target/release/era}
seeds=${1:-101,102,103}
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT

score() { # score TRUTH_JSON FOUND_JSON: "found spurious median_damping_error_%"
  python3 - "$1" "$2" <<'PY'
import json, statistics, sys
truth = json.load(open(sys.argv[1]))["modes"]
found = json.load(open(sys.argv[2]))
pairs = sorted((abs(f - t["frequency_hz"]) / t["frequency_hz"], i, j)
               for i, (f, _) in enumerate(found) for j, t in enumerate(truth))
used_i, used_j, errors = set(), set(), []
for d, i, j in pairs:
    if d > 0.005 or i in used_i or j in used_j:
        continue
    used_i.add(i); used_j.add(j)
    errors.append(abs(found[i][1] - truth[j]["damping_ratio"]) / truth[j]["damping_ratio"])
median = 100 * statistics.median(errors) if errors else float("nan")
print(len(used_j), len(found) - len(used_i), f"{median:.1f}")
PY
}

median3() { printf '%s\n' "$@" | sort -g | sed -n 2p; }
echo "# The automatic path: era against sdypy-EMA, $(date -u '+%Y-%m-%d %H:%M'), $(uname -m) $(nproc) cores, $(uptime | sed 's/.*load/load/')"
echo "# command: bench/auto_peers.sh $seeds; sdypy-EMA $("$venv/bin/python" -c 'from sdypy import EMA; print(EMA.__version__)')"
echo
echo "| seed | era s | era MB | era found / spurious | era damping error | sdypy-EMA s (its calls) | sdypy-EMA MB | sdypy-EMA found / spurious | sdypy-EMA damping error | speed-up |"
echo "|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|"
for seed in ${seeds//,/ }; do
  frf=$work/set$seed.csv
  "$era" simulate modal --collocated --noise 0.05 --seed "$seed" --out "$frf" --json -q > "$work/truth$seed.json"
  e_s=(); e_m=(); p_s=(); p_m=(); p_c=()
  for _ in 1 2 3; do
    /usr/bin/time -f "%e %M" -o "$work/time" "$era" identify "$frf" --states auto --refine \
      --time-domain continuous --no-figures --out "$work/out" --json -q > "$work/era.json"
    read -r s m < "$work/time"; e_s+=("$s"); e_m+=("$m")
    /usr/bin/time -f "%e %M" -o "$work/time" "$venv/bin/python" bench/sdypy_auto.py "$frf" 0.3 15 \
      > "$work/sdypy.json" 2>/dev/null
    read -r s m < "$work/time"; p_s+=("$s"); p_m+=("$m")
    p_c+=("$(python3 -c "import json; print(json.load(open('$work/sdypy.json'))['seconds'])")")
  done
  python3 -c "
import json
v = json.load(open('$work/era.json'))
json.dump([[m['frequency_hz'], m['damping_ratio']] for m in v['modes'] if m.get('physical')], open('$work/era_modes.json', 'w'))
v = json.load(open('$work/sdypy.json'))
json.dump(list(zip(v['frequency_hz'], v['damping_ratio'])), open('$work/sdypy_modes.json', 'w'))"
  read -r ef es ed < <(score "$work/truth$seed.json" "$work/era_modes.json")
  read -r pf ps pd < <(score "$work/truth$seed.json" "$work/sdypy_modes.json")
  es_=$(median3 "${e_s[@]}"); ps_=$(median3 "${p_s[@]}"); pc_=$(median3 "${p_c[@]}")
  printf '| %s | %s | %.0f | %s / %s | %s %% | %s (%.2f) | %.0f | %s / %s | %s %% | %.1fx |\n' \
    "$seed" "$es_" "$(median3 "${e_m[@]}" | awk '{print $1/1024}')" "$ef" "$es" "$ed" \
    "$ps_" "$pc_" "$(median3 "${p_m[@]}" | awk '{print $1/1024}')" "$pf" "$ps" "$pd" \
    "$(awk -v a="$pc_" -v b="$es_" 'BEGIN { print a / b }')"
done
echo
echo "speed-up: sdypy-EMA's calls alone (LSCF, pick, LSFD) over era's whole process (file to model files)."
