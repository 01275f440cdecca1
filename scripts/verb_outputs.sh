#!/usr/bin/env bash
# Every verb of the CLI run once on small simulated data, its stdout, stderr, exit code
# and files kept in OUT: the second yardstick of a change that must not change results,
# beside golden_outputs.sh (which covers identify, frf, friction and the demo at the
# thesis's settings). Compare two builds with scripts/golden_compare.py; timings and the
# file times inside batch fingerprints differ from run to run, nothing else should.
#
# Usage: scripts/verb_outputs.sh ERA_BIN OUT
set -u
bin=$(realpath "$1")
out=$2
rm -rf "$out"
mkdir -p "$out"
cd "$out" || exit 1
run() {
    local name=$1
    shift
    "$bin" "$@" >"$name.out" 2>"$name.err"
    echo "exit $?" >>"$name.out"
}
run sim_modal simulate modal --outputs 4 --inputs 2 --modes 6 --fmax 15 --noise 0.05 --seed 3 --out m.csv
run sim_truth simulate truth-model --noise 0.02 --out t.uff
run fleet simulate fleet --records 4 --record-length 120 --seed 2 --out fl
run batch batch fl/fleet.toml --out bo --json
run shaker simulate shaker --modes 4 --outputs 3 --inputs 1 --duration 30 --out sh.csv
run experiment simulate experiment --averages 2 --out ex.csv --exact-out exact.csv
run info_m info m.csv --json
run info_t info t.uff
run convert convert m.csv m.uff
run compare compare m.csv m.csv --bands 1,10,20 --json --identify --states 12 --hankel-factor 5
run oma oma fl/records/r0001.csv --outputs 1-8 --json
run frf frf sh.csv --inputs 1 --outputs 2-4 --frame 256 --out shf.csv
run ident_ft identify sh.csv --from-time --inputs 1 --outputs 2-4 --frame 256 --states auto --refine --no-figures --out idft
run ident_okid identify sh.csv --from-time --inputs 1 --outputs 2-4 --markov okid --no-figures --out idok
run refine refine idft/model.json shf.csv --no-figures --out rf
run fr_sim friction simulate --out d.csv --coulomb-force 0.1 --stiffness 100
run fr_est friction estimate d.csv --stiffness 100 --json
run fr_tune friction tune d.csv --stiffness 100
run plot plot m.csv --out pl
run plot_model plot shf.csv --model idft/model.json --out plm --json
run track track bo --out tr --json
grep -L "^exit 0$" ./*.out | sed 's/^/not exit 0: /'
