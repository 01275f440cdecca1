#!/usr/bin/env bash
# Loads era's model.mat in GNU Octave the way a MATLAB user would
# (load model.mat; sys = ss(a,b,c,d,Ts)), compares the modes with model.json, then eig(a)
# with the eigenvalues in model.json (issue 3).
# Needs: apt-get install -y --no-install-recommends octave octave-control
set -euo pipefail
here=$(cd "$(dirname "$0")/.." && pwd)
cd "$here"
command -v octave >/dev/null || { echo "octave is not installed (see the header of $0)" >&2; exit 2; }
. scripts/era_bin.sh
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
"$era" simulate truth-model -q --out "$work/truth.csv"
"$era" identify "$work/truth.csv" -q --preset thesis --states 8 --hankel-factor 4 --pad-to 1024 --out "$work/out"
python3 -c "import json; [print('%.10f %.10f' % (m['frequency_hz'], m['damping_ratio'])) for m in json.load(open('$work/out/model.json'))['modes']]" > "$work/json_modes.txt"
(cd "$work/out" && octave --no-gui -q -H --eval "pkg load control; load model.mat; sys = ss(a,b,c,d,Ts); [wn, z] = damp(sys); [wn, i] = unique(round(wn*1e6)/1e6); z = z(i); printf('%.10f %.10f\n', [wn(:)/(2*pi), z(:)]'); printf('freq_hz from the file: '); printf('%.4f ', freq_hz); printf('\n');" 2>/dev/null) > "$work/octave.txt"
echo "model.json:"; cat "$work/json_modes.txt"
echo "Octave, ss(a,b,c,d,Ts) from model.mat:"; cat "$work/octave.txt"
# The issue's one-liner: eig(a) from model.mat against the eigenvalues in model.json.
(cd "$work/out" && octave --no-gui -q -H --eval "load model.mat; e = eig(a); printf('%.17g %.17g\n', [real(e), imag(e)]');" 2>/dev/null) > "$work/octave_eig.txt"
python3 - "$work/out/model.json" "$work/octave_eig.txt" <<'PY'
import json, sys
model = json.load(open(sys.argv[1]))
want = [complex(m["eigenvalue_re"], s * m["eigenvalue_im"]) for m in model["modes"] for s in (1, -1)]
want += [complex(p["eigenvalue"], 0) for p in model["real_poles"]]
got = [complex(*map(float, l.split())) for l in open(sys.argv[2]) if l.strip()]
assert len(got) == len(want), (len(got), len(want))
worst = max(min(abs(g - w) for g in got) / abs(w) for w in want)
print("eig(a) in Octave vs model.json eigenvalues: %d values, max relative difference %.2e" % (len(want), worst))
sys.exit(0 if worst < 1e-12 else 1)
PY
