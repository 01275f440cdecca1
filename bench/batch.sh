#!/usr/bin/env bash
# The throughput of `era batch` on a fleet like a monitoring system's: N output-only
# records of 8 channels x 10 minutes at 64 Hz (`era simulate fleet`), `era oma
# --outputs 1-8` with the automatic order and the jackknife, on this machine's cores.
# Side by side in one run, each on the same records:
#   - the loop a user writes today: one `era oma FILE --threads 1` process per record;
#   - `era batch --jobs 1` (one thread): its overhead over that loop, and over the sum
#     of its records' own seconds (records.jsonl);
#   - `era batch --jobs 2`: the speed-up over --jobs 1.
# Prints markdown (bench/tables.sh batch writes it to docs/src/perf/batch.md).
#
#   bash bench/batch.sh [RECORDS]     (default 1000; the records are kept in
#                                      target/bench-fleet-RECORDS and reused)
set -euo pipefail
cd "$(dirname "$0")/.."
n=${1:-1000}
cargo build --release -q -p era-cli --bin era
era=$PWD/target/release/era
fleet=target/bench-fleet-$n
if [ ! -f "$fleet/fleet.toml" ]; then
  "$era" simulate fleet --records "$n" --out "$fleet" --seed 3 -q
fi
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT

now() { date +%s.%N; }
t0=$(now)
for f in "$fleet"/records/*.csv; do
  "$era" oma "$f" --outputs 1-8 --threads 1 -q --json > /dev/null
done
t1=$(now)
"$era" batch "$fleet/fleet.toml" --out "$work/one" --jobs 1 -q
t2=$(now)
"$era" batch "$fleet/fleet.toml" --out "$work/two" --jobs 2 -q
t3=$(now)
own=$(python3 -c "
import json,sys
print(sum(json.loads(l)['seconds'] for l in open('$work/one/records.jsonl')))")
cmp -s <(python3 -c "
import json
for l in open('$work/one/records.jsonl'): d=json.loads(l); print(d['id'], d['status'], d['modes'])") <(python3 -c "
import json
for l in open('$work/two/records.jsonl'): d=json.loads(l); print(d['id'], d['status'], d['modes'])") \
  || { echo "bench/batch.sh: --jobs 1 and --jobs 2 disagree" >&2; exit 1; }
python3 - "$n" "$t0" "$t1" "$t2" "$t3" "$own" <<'PY'
import sys
n = int(sys.argv[1])
t0, t1, t2, t3, own = map(float, sys.argv[2:])
loop, one, two = t1 - t0, t2 - t1, t3 - t2
print(f"md: {n} records of 8 channels x 600 s at 64 Hz, `era oma --outputs 1-8` (automatic order, 6 jackknife blocks).")
print()
print("| run | wall, s | records/s | vs the loop of processes |")
print("|---|---|---|---|")
print(f"| a loop of `era oma --threads 1`, one process per record | {loop:.1f} | {n/loop:.2f} | 1.00 |")
print(f"| `era batch --jobs 1` | {one:.1f} | {n/one:.2f} | {loop/one:.2f}x |")
print(f"| `era batch --jobs 2` | {two:.1f} | {n/two:.2f} | {loop/two:.2f}x |")
print()
print("| measure | value |")
print("|---|---|")
print(f"| batch --jobs 1 over the loop of processes | {100*(one/loop-1):+.1f} % |")
print(f"| batch --jobs 1 over its records' own seconds | {100*(one/own-1):+.1f} % |")
print(f"| --jobs 2 speed-up over --jobs 1 | {one/two:.2f}x |")
PY
