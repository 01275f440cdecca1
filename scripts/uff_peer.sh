#!/usr/bin/env bash
# pyuff (from PyPI, in a virtual environment) as a peer for era's UFF 58 reader and writer.
#   scripts/uff_peer.sh golden   pyuff writes the golden files of crates/era-io/tests/golden_uff
#                                (ASCII and binary, real and complex, single and double, even
#                                and uneven) with expected.json: what pyuff reads back.
#   scripts/uff_peer.sh check    era writes UFF files (ASCII and binary, double and single) and
#                                modes.uff; pyuff reads them and must find equal values.
#                                era's files and pyuff's report are kept in
#                                crates/era-io/tests/golden_uff/era/ for the tests.
set -euo pipefail
here=$(cd "$(dirname "$0")/.." && pwd)
cd "$here"
venv=target/uff-venv
if [ ! -x "$venv/bin/python" ]; then
  python3 -m venv "$venv"
  "$venv/bin/pip" install -q "pyuff==2.5.8" "numpy<3"
fi
golden=crates/era-io/tests/golden_uff
case "${1:-}" in
  golden)
    "$venv/bin/python" scripts/uff_peer.py golden "$golden"
    ;;
  check)
    . scripts/era_bin.sh
    out=$golden/era
    mkdir -p "$out"
    # The source: the pyuff golden FRFs (2 x 2, 33 lines) as era reads them.
    "$era" convert -q "$golden/ascii_complex_double_even.uff" "$out/era_source.csv"
    "$era" convert -q "$out/era_source.csv" "$out/era_ascii_double.uff"
    "$era" convert -q --binary "$out/era_source.csv" "$out/era_binary_double.uff"
    "$era" convert -q --single "$out/era_source.csv" "$out/era_ascii_single.uff"
    "$era" convert -q --binary --single "$out/era_source.csv" "$out/era_binary_single.uff"
    "$era" identify -q "$out/era_source.csv" --preset thesis --states 4 --hankel-factor 4 --out "$out/model"
    cp "$out/model/modes.uff" "$out/era_modes.uff"
    rm -rf "$out/model"
    # era's values in full precision, for the comparison.
    python3 - "$out" <<'PY'
import csv, json, sys
folder = sys.argv[1]
rows = [r for r in csv.reader(l for l in open(f"{folder}/era_source.csv") if not l.startswith("#"))]
head, body = rows[0], rows[1:]
pairs = []
for c, name in enumerate(head):
    if name.endswith("_re"):
        i, j = (int(v) for v in name[1:-3].split("_"))
        pairs.append({"output": i + 10, "input": j + 100,
                      "re": [float(r[c]) for r in body], "im": [float(r[c + 1]) for r in body]})
spacing = float(body[1][0])
json.dump({"pairs": pairs, "spacing_hz": spacing}, open(f"{folder}/era_source.json", "w"))
PY
    "$venv/bin/python" scripts/uff_peer.py check "$out"
    rm -f "$out/era_source.json"
    ;;
  *)
    echo "usage: $0 golden|check" >&2
    exit 2
    ;;
esac
