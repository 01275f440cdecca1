#!/usr/bin/env bash
# Output-only modal analysis side by side, in the same run: era oma (when the build has
# it), pyOMA2's SSI-cov with its automatic clustering, and koma's covssi with its
# stabilization and clustering, on simulated records with exact truth (era simulate
# shaker, the forces dropped), koma's shear frame and the DaISy subframe (forces dropped).
# Prints markdown: modes found and spurious, damping and frequency errors, seconds per
# record, the Monte Carlo check of the reported standard deviations, the DaISy count.
# See bench/oma_peers.py for what each number is.
#
#   bench/oma_peers.sh [--records N] [--no-unc] [--preset NAME] [--skip seeds,one,koma,daisy]
#
# The records go to a temporary folder, removed at the end. pyOMA2's uncertainty run
# (calc_unc, only on the records of one structure) takes about 100 s a record on 2 cores;
# --no-unc skips it. Creates target/oma-venv (or $ERA_OMA_VENV): see bench/oma_env.sh.
set -euo pipefail
. "$(dirname "$0")/oma_env.sh"
cargo build --release -q -p era-cli --bin era
era=${ERA:-$here/target/release/era}
exec "$venv/bin/python" bench/oma_peers.py --era "$era" "$@"
