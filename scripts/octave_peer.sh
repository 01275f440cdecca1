#!/usr/bin/env bash
# Runs the Octave peer (the thesis's routines transcribed; not shipped in this repository:
# ERA_OCTAVE_PEER names its folder, default ../shared/reference/octave beside the checkout)
# on the truth model, and either stores its results as golden test data or puts them
# beside `era demo` for the same noise seed.
#
#   scripts/octave_peer.sh golden [SEED]    # writes crates/era/tests/golden/octave_{truth_*,dta_eigs}.csv
#   scripts/octave_peer.sh compare [SEED]   # Table 5.2 from both, side by side
#
# Needs Octave: apt-get install -y --no-install-recommends octave octave-control octave-signal
# Tests never need Octave: they read the golden files this script wrote.
set -euo pipefail
mode=${1:-compare}
seed=${2:-123456789}
here=$(cd "$(dirname "$0")/.." && pwd)
peer=${ERA_OCTAVE_PEER:-$here/../shared/reference/octave}
[ -d "$peer" ] || { echo "no Octave peer at $peer" >&2; exit 2; }
command -v octave >/dev/null || { echo "octave is not installed (see the header of $0)" >&2; exit 2; }
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
cp -r "$peer"/. "$work"/   # the peer writes results/ beside itself; shared/ is read-only
(cd "$work" && octave --no-gui -q -H --eval "run_truth($seed);" > "$work/run.log" 2>&1)
case "$mode" in
  golden)
    dest="$here/crates/era/tests/golden"
    for f in modes eigs sv; do
      { echo "# Octave peer run_truth($seed), $(octave --version 2>/dev/null | head -1); made by scripts/octave_peer.sh"
        cat "$work/results/truth_$f.csv"; } > "$dest/octave_truth_${f}_seed$seed.csv"
    done
    cp "$here/scripts/octave_dta_eigs.m" "$work/"
    (cd "$work" && octave --no-gui -q -H --eval "octave_dta_eigs('dta_eigs.csv');" > "$work/dta.log" 2>&1)
    { echo "# Octave peer frffilt on mkdta() (seed 987654321), thesis DTA settings, $(octave --version 2>/dev/null | head -1); made by scripts/octave_peer.sh"
      cat "$work/dta_eigs.csv"; } > "$dest/octave_dta_eigs.csv"
    echo "wrote $dest/octave_truth_{modes,eigs,sv}_seed$seed.csv and octave_dta_eigs.csv"
    ;;
  compare)
    echo "== Octave peer (run_truth($seed)) =="
    grep -A5 "^Table 5.2 reproduction" "$work/run.log"
    echo "== era demo --seed $seed =="
    (cd "$here" && cargo run --release -q -p era-cli -- demo --seed "$seed")
    ;;
  *) echo "usage: $0 golden|compare [SEED]" >&2; exit 2 ;;
esac
