#!/usr/bin/env bash
# era's ERA core against python-control's eigensys_realization on the same Markov data:
# wall time of the realization call and peak RSS of the whole process (/usr/bin/time -v),
# side by side; then era's growth with m at a fixed order, with the fitted exponent.
#
#   bench/peers.sh            # python-control where it finishes in about a minute
#   bench/peers.sh --all      # also python-control at 8000^2 (minutes, GBs)
#   bench/peers.sh --thesis   # only the thesis case (DTA-like FRFs), three runs each
#   bench/peers.sh --large    # only the larger cases (no thesis case)
#
# The thesis case comes first: the Markov data of the DTA-like 8x8 set at the thesis
# settings (ns 80, lh 5, ni 1, nz 3, ndpts 1024; H0 1592^2), noise-free and with 5 %
# noise on the FRFs, era's Hankel + SVD + realization against python-control's
# eigensys_realization, both in the same run (medians of three, alternating).
#
# Creates a virtual environment with numpy and python-control from PyPI
# (target/peers-venv, or $ERA_PEERS_VENV). Data: 8x8 lightly damped structures
# (era::sim::lightly_damped_markov, seed 7), H0 = m x m blocks from Y_1, as
# python-control builds it.
set -euo pipefail
all=${1:-}
. "$(dirname "$0")/peers_env.sh"
cargo build --release -q --example era_core
target_dir=$(cargo metadata --format-version 1 --no-deps | sed -n 's/.*"target_directory":"\([^"]*\)".*/\1/p')
core="${target_dir:-${CARGO_TARGET_DIR:-$here/target}}/release/examples/era_core"
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT

# run CMD...: prints "seconds rss_mb" from the JSON line and /usr/bin/time -v.
run() {
  /usr/bin/time -v "$@" > "$work/out" 2> "$work/err" || { echo "failed: $*" >&2; tail -3 "$work/err" >&2; echo "- -"; return; }
  local s rss
  s=$(sed -n 's/.*"seconds": \([0-9.e+-]*\).*/\1/p' "$work/out")
  rss=$(awk -F: '/Maximum resident set size/ {printf "%.0f", $2/1024}' "$work/err")
  echo "$s $rss"
}

median3() { printf '%s\n' "$@" | sort -g | sed -n 2p; }
if [ "$all" != --large ]; then
echo "thesis case: DTA-like 8x8 FRFs, ns 80, lh 5, ni 1, nz 3, ndpts 1024 (H0 1592 x 1592), $(uptime | sed 's/.*load/load/')"
echo
echo "| data | era | passes | python-control $("$venv/bin/python" -c 'import control; print(control.__version__)') | speed-up |"
echo "|---|---:|---:|---:|---:|"
for noise in 0 0.05; do
  "$core" dta "$work/dta.bin" "$noise"
  e=(); pyt=()
  for _ in 1 2 3; do
    "$core" realize "$work/dta.bin" 8 8 2048 80 199 matrix-free > "$work/era.json"
    e+=("$(sed -n 's/.*"seconds": \([0-9.e+-]*\).*/\1/p' "$work/era.json")")
    passes=$(sed -n 's/.*"iterations": \([0-9]*\).*/\1/p' "$work/era.json")
    pyt+=("$("$venv/bin/python" "$here/bench/pc_era.py" "$work/dta.bin" 8 8 2048 80 199 | sed -n 's/.*"seconds": \([0-9.e+-]*\).*/\1/p')")
  done
  es=$(median3 "${e[@]}"); ps=$(median3 "${pyt[@]}")
  printf '| %s | %.3f s | %s | %.3f s | %.0f× |\n' "$(awk -v n="$noise" 'BEGIN { print n == 0 ? "noise-free" : 100 * n " % noise" }')" \
    "$es" "$passes" "$ps" "$(awk -v a="$ps" -v b="$es" 'BEGIN { print a / b }')"
done
fi
[ "$all" = --thesis ] && exit 0
big=no; [ "$all" = --all ] && big=yes
echo

echo "| case (q × p, m, states) | H0 | era (matrix-free) | era RSS | python-control | its RSS | speed-up |"
echo "|---|---|---:|---:|---:|---:|---:|"
# q p modes m python?
cases="8 8 40 200 yes
8 8 120 600 yes
8 8 200 1000 $big
8 8 200 2000 no
151 8 40 400 no"
while read -r q p modes m py; do
  k=$((2 * m + 2)); n=$((2 * modes))
  "$core" generate "$work/y.bin" "$q" "$p" "$modes" "$k" 7
  read -r es em < <(run "$core" realize "$work/y.bin" "$q" "$p" "$k" "$n" "$m" auto)
  if [ "$py" = yes ]; then
    read -r ps pm < <(run "$venv/bin/python" "$here/bench/pc_era.py" "$work/y.bin" "$q" "$p" "$k" "$n" "$m")
    speed=$(awk -v a="$ps" -v b="$es" 'BEGIN { if (a+0 > 0 && b+0 > 0) printf "%.0f×", a / b; else print "-" }')
  else
    ps="skipped"; pm="-"; speed="-"
  fi
  [ "$ps" = skipped ] || ps=$(printf '%.3f s' "$ps")
  [ "$pm" = - ] || pm="$pm MB"
  printf '| %s | %s | %.3f s | %s MB | %s | %s | %s |\n' "${q} × ${p}, m = ${m}, ${n} states" "$((m * q)) × $((m * p))" "$es" "$em" "$ps" "$pm" "$speed"
done <<< "$cases"
echo
echo "md: python-control is skipped where its dense Hankel plus full U and V would need 6 GB or more (16000², and a 60400² U for 151 outputs), and at 8000² unless \`--all\` is given."

echo
echo "| growth with m at 80 states (8 × 8, matrix-free) | H0 | era | era RSS |"
echo "|---|---|---:|---:|"
: > "$work/growth"
for m in 200 400 800 1600 3200; do
  k=$((2 * m + 2))
  "$core" generate "$work/y.bin" 8 8 40 "$k" 7
  read -r es em < <(run "$core" realize "$work/y.bin" 8 8 "$k" 80 "$m" matrix-free)
  printf '| m = %s | %s² | %.3f s | %s MB |\n' "$m" $((8 * m)) "$es" "$em"
  echo "$m $es" >> "$work/growth"
done
"$venv/bin/python" - "$work/growth" <<'PY'
import sys, numpy as np
d = np.loadtxt(sys.argv[1])
slope = np.polyfit(np.log(d[:, 0]), np.log(d[:, 1]), 1)[0]
print(f"\nmd: The fitted exponent of the growth is time ∝ m^{slope:.2f} (m log m would read about 1.1 over this range; a dense SVD 3).")
PY
