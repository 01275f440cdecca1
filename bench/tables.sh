#!/usr/bin/env bash
# Writes the performance tables of the book: runs a table's benchmark and writes
# docs/src/perf/NAME.md with the markdown it printed, under a line that says the command,
# the date, the machine, its load and the commit. docs/src/performance.md includes them.
#
#   bench/tables.sh NAME [NAME ...]     # the tables named
#   bench/tables.sh all                 # every table (about 50 minutes on 2 cores;
#                                       # oma_peers alone takes about 25)
#   bench/tables.sh --list              # the names and their commands
#
# A benchmark prints markdown: the wrapper keeps its table rows (lines that begin with
# "|"), its blank lines between tables, and its prose lines marked "md: ". A table whose
# command fails, or prints no row, is not written, and the earlier file stays.
#
# The python table needs PYTHON, a Python with the era package and python-control
# (for example: VENV=target/python-venv bash scripts/python_tests.sh, then
# target/python-venv/bin/pip install control).
set -euo pipefail
cd "$(dirname "$0")/.."
out_dir=docs/src/perf
all_names="thesis_peers hankel_peers cost_model partial_svd auto_order auto_peers okid okid_peers oma oma_peers batch stages read refine python"

command_of() {
  case $1 in
    thesis_peers) echo "bash bench/peers.sh --thesis" ;;
    hankel_peers) echo "bash bench/peers.sh --large" ;;
    cost_model) echo "cargo run --release -q -p era --example cost_model" ;;
    partial_svd) echo "cargo run --release -q -p era --example partial_svd_peer" ;;
    auto_order) echo "cargo bench -q -p era --bench auto_seeds && python3 bench/criterion_table.py --summary auto_order_5_percent refine_from_auto_5_percent" ;;
    auto_peers) echo "bash bench/auto_peers.sh" ;;
    okid) echo "cargo bench -q -p era --bench okid && python3 bench/criterion_table.py okid" ;;
    okid_peers) echo "bash bench/okid_peers.sh" ;;
    oma) echo "cargo bench -q -p era --bench oma && python3 bench/criterion_table.py oma" ;;
    oma_peers) echo "bash bench/oma_peers.sh --no-unc" ;;
    batch) echo "bash bench/batch.sh" ;;
    stages) echo "cargo bench -q -p era --bench stages && python3 bench/criterion_table.py dta_8x8_ns80_lh5 tsvd_dta_1592" ;;
    read) echo "cargo bench -q -p era-io --bench read && python3 bench/criterion_table.py read_dta_8x8_801" ;;
    refine) echo "cargo bench -q -p era --bench refine && python3 bench/criterion_table.py refine_dta_8x8_40modes_801lines refine_2x2_4modes_401lines refine_dta_from_era_auto" ;;
    python) echo "\"\$PYTHON\" python/bench/bench_python.py --repeats 11 --control-repeats 3" ;;
    *) return 1 ;;
  esac
}

# The criterion groups a table reads: cleared before its run, so that a benchmark that no
# longer exists cannot leave an old estimate in the table.
groups_of() {
  command_of "$1" | sed -n 's/.*criterion_table.py \(--summary \)\{0,1\}//p'
}

machine() {
  local cpu
  cpu=$(sed -n 's/^model name[[:space:]]*: //p' /proc/cpuinfo 2>/dev/null | head -1)
  echo "${cpu:-$(uname -m)}, $(nproc) cores, load $(cut -d' ' -f1 /proc/loadavg)"
}

write_table() {
  local name=$1 cmd started commit tmp
  cmd=$(command_of "$name") || { echo "bench/tables.sh: no table named '$name' (see --list)" >&2; exit 2; }
  if [ "$name" = python ] && [ -z "${PYTHON:-}" ]; then
    echo "bench/tables.sh: the python table needs PYTHON, a Python with era and python-control" >&2
    exit 2
  fi
  for group in $(groups_of "$name"); do rm -rf "target/criterion/$group"; done
  commit=$(git rev-parse --short HEAD 2>/dev/null || echo unknown)
  # The tables themselves are not the code they measure.
  git diff --quiet HEAD -- . ":(exclude)$out_dir" 2>/dev/null || commit="$commit with local changes"
  started="$(date -u '+%Y-%m-%d %H:%M') UTC, $(machine)"
  echo "bench/tables.sh: $name: $cmd" >&2
  tmp=$(mktemp)
  if ! bash -c "set -o pipefail; $cmd" > "$tmp.raw"; then
    echo "bench/tables.sh: $name: the command failed; $out_dir/$name.md is unchanged" >&2
    rm -f "$tmp" "$tmp.raw"
    exit 1
  fi
  if ! grep -q '^|' "$tmp.raw"; then
    echo "bench/tables.sh: $name: the command printed no table; $out_dir/$name.md is unchanged" >&2
    rm -f "$tmp" "$tmp.raw"
    exit 1
  fi
  {
    echo "*Written by \`bench/tables.sh $name\` (\`$cmd\`) on $started at the start,"
    echo "load $(cut -d' ' -f1 /proc/loadavg) at the end; era $commit.*"
    echo
    # Table rows and prose marked "md: ", a blank line between blocks.
    awk 'BEGIN { last = "start" }
         /^\|/ { if (last == "other") print ""; print; last = "row"; next }
         /^md: / { if (last != "start") print ""; print substr($0, 5); last = "other"; next }
         { if (last == "row") last = "other" }' "$tmp.raw"
  } > "$tmp"
  mkdir -p "$out_dir"
  chmod 644 "$tmp"
  mv "$tmp" "$out_dir/$name.md"
  rm -f "$tmp.raw"
  echo "bench/tables.sh: wrote $out_dir/$name.md" >&2
}

case ${1:-} in
  "" | -h | --help) sed -n '2,17p' "$0" | sed 's/^# \{0,1\}//'; exit 2 ;;
  --list) for n in $all_names; do printf '%-13s %s\n' "$n" "$(command_of "$n")"; done; exit 0 ;;
  all) set -- $all_names ;;
esac
for name in "$@"; do command_of "$name" > /dev/null || { echo "bench/tables.sh: no table named '$name' (see --list)" >&2; exit 2; }; done
for name in "$@"; do write_table "$name"; done
