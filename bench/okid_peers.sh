#!/usr/bin/env bash
# Time histories to a model on the real DaISy steel subframe (8523 samples x 30
# channels, 2 shakers, 28 accelerometers): era's OKID-ERA end to end (the MAT file in,
# model files out) against python-control's `markov` + `eigensys_realization` on the
# same record, Markov length (301 blocks) and order (60 states), in the same run:
# the median wall time of three runs each, alternating, the peak RSS of each process,
# and how many of the 14 indicative frequencies of the data's PROVENANCE lie within
# 0.5 Hz of a pole.
#
#   bench/okid_peers.sh
#
# Creates a virtual environment with numpy, scipy and python-control from PyPI
# (target/peers-venv, or $ERA_PEERS_VENV), as bench/peers.sh does.
set -euo pipefail
. "$(dirname "$0")/peers_env.sh"
cargo build --release -q -p era-cli --bin era
era=${ERA:-$here/target/release/era}
mat=data/daisy-steel-subframe/flexible_structure_dat.mat
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
samples=301 states=60 blocks=149

era_run() {
  /usr/bin/time -f "%e %M" -o "$work/time" "$era" identify --from-time "$mat" \
    --inputs 1,2 --outputs 3-30 --sample-rate 1024 --markov okid \
    --markov-samples "$samples" --states "$states" --no-refine --no-figures \
    --out "$work/out" --json --timings -q > "$work/era.json" 2>/dev/null
  local facts
  # The reference modes found, and the seconds of the OKID and ERA stages alone (the
  # counterpart of python-control's two calls).
  facts=$(python3 -c "
import json
v = json.load(open('$work/era.json'))
f = [m['frequency_hz'] for m in v['modes']]
refs = [62.1, 119.0, 154.7, 192.5, 215.0, 229.5, 239.3, 286.8, 321.2, 334.1, 352.2, 398.1, 417.5, 467.2]
t = v['timings_s']
print(sum(any(abs(x - r) <= 0.5 for x in f) for r in refs), t['okid'] + t['hankel_svd'] + t['realize'])")
  echo "$(cat "$work/time") $facts"
}

pc_run() {
  /usr/bin/time -f "%e %M" -o "$work/time" "$venv/bin/python" bench/pc_okid.py "$mat" \
    "$samples" "$states" "$blocks" > "$work/pc.json"
  local hits calls
  hits=$(sed -n 's/.*"found": \([0-9]*\).*/\1/p' "$work/pc.json")
  calls=$(sed -n 's/.*"seconds": \([0-9.e+-]*\).*/\1/p' "$work/pc.json")
  echo "$(cat "$work/time") $hits $calls"
}

median3() { printf '%s\n' "$@" | sort -g | sed -n 2p; }
echo "# OKID-ERA on the DaISy subframe: era against python-control, $(date -u '+%Y-%m-%d %H:%M'), $(uname -m) $(nproc) cores, $(uptime | sed 's/.*load/load/')"
echo "# command: bench/okid_peers.sh (Markov blocks $samples, $states states, python-control's Hankel $blocks x $blocks blocks)"
echo "# python-control $("$venv/bin/python" -c 'import control; print(control.__version__)')"
e_s=(); e_m=(); e_c=(); p_s=(); p_m=(); p_c=()
for _ in 1 2 3; do
  read -r s m h c < <(era_run); e_s+=("$s"); e_m+=("$m"); e_c+=("$c"); e_hits=$h
  read -r s m h c < <(pc_run); p_s+=("$s"); p_m+=("$m"); p_c+=("$c"); p_hits=$h
done
es=$(median3 "${e_s[@]}"); ec=$(median3 "${e_c[@]}"); ps=$(median3 "${p_s[@]}"); pc=$(median3 "${p_c[@]}")
echo
echo "| tool | process wall s (median of 3) | the calls alone s | peak RSS MB | reference modes within 0.5 Hz |"
echo "|---|---:|---:|---:|---:|"
printf '| era identify --markov okid (file to model files; the calls: OKID, Hankel SVD, realization) | %s | %.3f | %.0f | %s of 14 |\n' "$es" "$ec" "$(median3 "${e_m[@]}" | awk '{print $1/1024}')" "$e_hits"
printf '| python-control markov + eigensys_realization | %s | %.2f | %.0f | %s of 14 |\n' "$ps" "$pc" "$(median3 "${p_m[@]}" | awk '{print $1/1024}')" "$p_hits"
echo
awk -v a="$pc" -v b="$es" -v c="$ps" -v d="$ec" 'BEGIN { printf "md: era end to end: %.1fx faster than python-control'"'"'s two calls alone, %.1fx process to process; the calls alone against the calls alone: %.1fx\n", a / b, c / b, a / d }'
