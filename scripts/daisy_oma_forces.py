"""Why the DaISy subframe's output-only modes lie below the input-output ones.

Without its forces, `era oma` finds seven of the subframe's modes 0.5 to 1.2 Hz below
the frequencies the input-output analysis (`era identify --from-time`, forces measured)
gives, and pyOMA2 and koma find the same. Output-only analysis assumes white
excitation. The shakers' forces are not white: an electrodynamic shaker's force drops
near each resonance of the structure it drives.

The test here: take era's input-output model of the subframe (28 outputs, 2 inputs),
drive it once with the two *measured* forces and once with white forces of the same
RMS (three draws), add 1 % noise to the responses, and run `era oma` on each, at the
record's own length. If the forces' spectra cause the shift, the measured forces
reproduce it and the white ones do not.

`bash scripts/daisy_oma_forces.sh [ERA_BINARY]` (numpy and scipy in target/py-venv).
"""

import json
import os
import subprocess
import sys
import tempfile

import numpy as np
import scipy.io
from scipy import signal

HERE = os.path.dirname(os.path.abspath(__file__))
DATA = os.path.join(HERE, "..", "data", "daisy-steel-subframe", "flexible_structure_dat.mat")
FS = 1024.0
# The PROVENANCE's reference frequencies (input-output, Hz).
REFERENCES = [62.1, 119.0, 154.7, 192.5, 215.0, 229.5, 239.3, 286.8, 321.2, 334.1, 352.2, 398.1, 417.5, 467.2]
NEAR_HZ = 2.0  # a reference's mode: the nearest physical mode within this


def era_json(era, args):
    out = subprocess.run([era, *args, "--json", "-q"], capture_output=True, text=True)
    if out.returncode != 0:
        sys.exit(f"era {' '.join(args)}: {out.stderr.strip()}")
    return json.loads(out.stdout)


def physical(doc):
    return [m["frequency_hz"] for m in doc["modes"] if m.get("physical")]


def shifts(found):
    """Per reference: the nearest found frequency minus the reference, None beyond NEAR_HZ."""
    cells = []
    for r in REFERENCES:
        near = min(found, key=lambda f: abs(f - r), default=None)
        cells.append(near - r if near is not None and abs(near - r) <= NEAR_HZ else None)
    return cells


def oma_of_responses(era, y, folder, name):
    path = os.path.join(folder, f"{name}.csv")
    t = np.arange(len(y)) / FS
    with open(path, "w") as f:
        f.write("time_s," + ",".join(f"y{k + 1}" for k in range(y.shape[1])) + "\n")
        np.savetxt(f, np.column_stack([t, y]), delimiter=",", fmt="%.9e")
    return physical(era_json(era, ["oma", path, "--outputs", f"1-{y.shape[1]}"]))


def main():
    era = sys.argv[1] if len(sys.argv) > 1 else os.path.join(HERE, "..", "target", "release", "era")
    data = scipy.io.loadmat(DATA)["flexible_structure_dat"]
    data = data - data.mean(axis=0)
    forces = data[:, :2]
    with tempfile.TemporaryDirectory() as folder:
        model_dir = os.path.join(folder, "io")
        io_doc = era_json(era, ["identify", "--from-time", DATA, "--inputs", "1,2", "--outputs", "3-30",
                                "--sample-rate", "1024", "--no-figures", "--out", model_dir])
        model = json.load(open(os.path.join(model_dir, "model.json")))
        if model["time_domain"] != "continuous":
            sys.exit("expected a continuous-time model from the measured preset")
        system = tuple(np.array(model[k], dtype=float) for k in ("a", "b", "c", "d"))
        discrete = signal.cont2discrete(system, 1.0 / FS, method="zoh")[:4]
        rng = np.random.default_rng(1)

        def responses(u):
            _, y, _ = signal.dlsim((*discrete, 1.0 / FS), u)
            return y + 0.01 * y.std(axis=0) * rng.standard_normal(y.shape)

        record = physical(era_json(era, ["oma", DATA, "--outputs", "3-30", "--sample-rate", "1024"]))
        rows = {
            "input-output (era identify --from-time)": shifts(physical(io_doc)),
            "era oma on the record": shifts(record),
            "era oma, model driven by the measured forces": shifts(
                oma_of_responses(era, responses(forces), folder, "measured")
            ),
        }
        white = []
        for draw in range(3):
            u = rng.standard_normal(forces.shape) * forces.std(axis=0)
            white.append(shifts(oma_of_responses(era, responses(u), folder, f"white{draw}")))
        rows["era oma, model driven by white forces (median of 3)"] = [
            float(np.median(v)) if len(v := [w[k] for w in white if w[k] is not None]) else None
            for k in range(len(REFERENCES))
        ]

    print("Shift of each reference's nearest physical mode (Hz; - when none within 2 Hz)\n")
    print("| reference (Hz) | " + " | ".join(rows) + " |")
    print("|---:|" + "---:|" * len(rows))
    for k, r in enumerate(REFERENCES):
        cells = ["–" if v[k] is None else f"{v[k]:+.2f}" for v in rows.values()]
        print(f"| {r:.1f} | " + " | ".join(cells) + " |")
    print("\nwithin 0.5 Hz: " + "; ".join(
        f"{name}: {sum(1 for v in cells if v is not None and abs(v) <= 0.5)}/14" for name, cells in rows.items()))


if __name__ == "__main__":
    main()
