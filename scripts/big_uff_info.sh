#!/usr/bin/env bash
# Generates a ~1 GB ASCII UFF 58 file (32 outputs x 8 inputs, 100 000 lines each, 256
# records) and a binary 58b copy, then times `era info` (headers only) and a full read
# (`era convert` to binary). Not committed, not a test: issue 3 asks for `era info` on a
# 1 GB UFF in under 2 s. Usage: scripts/big_uff_info.sh [DIR] (default TARGET/big-uff,
# TARGET being CARGO_TARGET_DIR or target/)
set -euo pipefail
here=$(cd "$(dirname "$0")/.." && pwd)
cd "$here"
. scripts/era_bin.sh
dir=${1:-$target_dir/big-uff}
mkdir -p "$dir"
big=$dir/big.uff
if [ ! -f "$big" ]; then
  "$era" simulate modal -q --outputs 32 --inputs 8 --modes 40 --lines 100000 --df 0.0005 \
    --fmin 1 --fmax 45 --out "$big"
fi
ls -l "$big"
sync
for run in 1 2 3; do
  /usr/bin/time -f "era info (ASCII, run $run): %e s, %M KB peak RSS" "$era" info -q "$big"
done
"$era" info "$big" | head -8
/usr/bin/time -f "full read of the ASCII file and 58b write: %e s, %M KB peak RSS" \
  "$era" convert -q --binary "$big" "$dir/big_b.uff"
ls -l "$dir/big_b.uff"
for run in 1 2 3; do
  /usr/bin/time -f "era info (58b, run $run): %e s, %M KB peak RSS" "$era" info -q "$dir/big_b.uff"
done
/usr/bin/time -f "full read of the 58b file and CSV write: %e s, %M KB peak RSS" \
  "$era" convert -q "$dir/big_b.uff" "$dir/big.csv"
rm -f "$dir/big.csv"
