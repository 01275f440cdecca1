"""pyuff as a peer for era's UFF reader and writer (issue 3).

    python scripts/uff_peer.py golden DIR      pyuff writes UFF 58 files into DIR, with
                                               expected.json: what pyuff reads back
    python scripts/uff_peer.py check DIR       pyuff reads the files era wrote into DIR
                                               (era_*.uff) and compares them with
                                               era_source.json

Run through scripts/uff_peer.sh, which makes the virtual environment.
"""

import json
import os
import sys

import numpy as np
import pyuff

LINES = 33
SPACING = 0.25


def frf_values(out, inp):
    """A 2x2 accelerance of two lightly damped modes, with irregular digits."""
    f = np.arange(LINES) * SPACING
    s = 2j * np.pi * f
    h = np.zeros(LINES, complex)
    for k, (fn, zeta) in enumerate([(1.7321, 0.021), (5.4142, 0.013)]):
        wn = 2 * np.pi * fn
        shape = [[1.0, 0.61803398875], [0.57735026919, -1.41421356237]][k]
        h += shape[out] * shape[inp] * s**2 / (s**2 + 2 * zeta * wn * s + wn**2)
    return f, h


def uneven_abscissa():
    return np.round(np.geomspace(0.5, 8.0, LINES), 6)


def frf_record(out, inp, data, x, ordinate, binary, even):
    return pyuff.prepare_58(
        binary=binary,
        id1=f"pyuff golden H{out + 1}_{inp + 1}",
        func_type=4,
        rsp_ent_name="golden",
        rsp_node=out + 11,
        rsp_dir=3 if out == 0 else -2,
        ref_ent_name="golden",
        ref_node=inp + 101,
        ref_dir=3,
        ord_data_type=ordinate,
        abscissa_spacing=1 if even else 0,
        abscissa_spec_data_type=18,
        abscissa_axis_units_lab="Hz",
        ordinate_spec_data_type=12,
        ordinate_len_unit_exp=1,
        ordinate_axis_units_lab="m/s^2",
        orddenom_spec_data_type=13,
        orddenom_force_unit_exp=1,
        orddenom_axis_units_lab="N",
        z_axis_spec_data_type=0,
        data=data,
        x=x,
    )


def golden(folder):
    os.makedirs(folder, exist_ok=True)
    expected = {}
    for binary in (0, 1):
        for complex_ in (True, False):
            for double in (True, False):
                for even in (True, False):
                    name = "%s_%s_%s_%s.uff" % (
                        "binary" if binary else "ascii",
                        "complex" if complex_ else "real",
                        "double" if double else "single",
                        "even" if even else "uneven",
                    )
                    ordinate = {(True, True): 6, (True, False): 5, (False, True): 4, (False, False): 2}[
                        (complex_, double)
                    ]
                    path = os.path.join(folder, name)
                    if os.path.exists(path):
                        os.remove(path)
                    uff = pyuff.UFF(path)
                    sets = []
                    if name == "ascii_complex_double_even.uff":
                        # Other datasets that a reader must skip.
                        sets.append(pyuff.prepare_151(model_name="golden", description="pyuff golden",
                                                      db_app="pyuff", program="uff_peer.py"))
                        sets.append(pyuff.prepare_164(units_code=1, units_description="SI",
                                                      temp_mode=1, length=1.0, force=1.0,
                                                      temp=1.0, temp_offset=273.15))
                    given = []
                    for out in range(2):
                        for inp in range(2):
                            f, h = frf_values(out, inp)
                            x = f if even else uneven_abscissa()
                            data = h if complex_ else h.real.copy()
                            sets.append(frf_record(out, inp, data, x, ordinate, binary, even))
                            given.append((x, data))
                    # pyuff's 'overwrite' mode truncates binary records: add to a new file.
                    for s in sets:
                        uff.write_sets(s, mode="add", force_double=False)
                    back = pyuff.UFF(path).read_sets()
                    back = [b for b in back if b["type"] == 58]
                    records = []
                    for b, (x, data) in zip(back, given):
                        # pyuff writes 8-byte values under a single-precision binary
                        # header and then reads them back as 4-byte values: its own
                        # read-back is wrong there, so the values it was given stand.
                        trusted = not (binary and not double)
                        xs, ys = (b["x"], b["data"]) if trusted else (x, data)
                        ys = np.asarray(ys, complex)
                        records.append({
                            "response": [int(b["rsp_node"]), int(b["rsp_dir"])],
                            "reference": [int(b["ref_node"]), int(b["ref_dir"])],
                            "ordinate": int(b["ord_data_type"]),
                            "pyuff_reads_back": trusted,
                            "x": [float(v) for v in xs],
                            "re": [float(v) for v in ys.real],
                            "im": [float(v) for v in ys.imag],
                        })
                    expected[name] = records
    with open(os.path.join(folder, "expected.json"), "w") as fh:
        json.dump(expected, fh, separators=(",", ":"))
        fh.write("\n")
    print("wrote", len(expected), "files and expected.json to", folder)


def check(folder):
    source = json.load(open(os.path.join(folder, "era_source.json")))
    want = {(r["output"], r["input"]): np.array(r["re"]) + 1j * np.array(r["im"]) for r in source["pairs"]}
    failures = 0
    report = {}
    for name in sorted(os.listdir(folder)):
        if not (name.startswith("era_") and name.endswith(".uff")) or name == "era_modes.uff":
            continue
        sets = pyuff.UFF(os.path.join(folder, name)).read_sets()
        sets = sets if isinstance(sets, list) else [sets]
        # ASCII single keeps 6 significant digits (half a unit: 5e-6), f32 24 bits.
        tol = {("ascii", True): 1e-5, ("binary", True): 1e-7, ("ascii", False): 1e-12, ("binary", False): 0.0}[
            ("ascii" if "ascii" in name else "binary", "single" in name)]
        worst = 0.0
        for s in sets:
            key = (int(s["rsp_node"]), int(s["ref_node"]))
            got = np.asarray(s["data"], complex)
            ref = want[key]
            err = float(np.max(np.abs(got - ref) / np.maximum(np.abs(ref), 1e-300)))
            worst = max(worst, err)
            x = np.asarray(s["x"])
            if np.max(np.abs(x - np.arange(len(x)) * source["spacing_hz"])) > 1e-9:
                failures += 1
                print(name, "abscissa differs")
        ok = worst <= tol
        failures += 0 if ok else 1
        report[name] = {"records": len(sets), "max_relative_difference": worst, "tolerance": tol}
        print("%-28s %d records, max relative difference %.3g (tolerance %g) %s"
              % (name, len(sets), worst, tol, "ok" if ok else "FAIL"))
    modes_path = os.path.join(folder, "era_modes.uff")
    if os.path.exists(modes_path):
        modes = pyuff.UFF(modes_path).read_sets()
        modes = modes if isinstance(modes, list) else [modes]
        for m in modes:
            hz = abs(m["eig"]) / (2 * np.pi)
            print("modes.uff: mode %d, analysis type %d, |s|/2pi = %.5f Hz, %d nodes"
                  % (m["mode_n"], m["analysis_type"], hz, len(m["node_nums"])))
        report["era_modes.uff"] = {"modes": len(modes)}
    with open(os.path.join(folder, "pyuff_check.json"), "w") as fh:
        json.dump(report, fh, indent=1)
        fh.write("\n")
    if failures:
        sys.exit("pyuff disagrees with era on %d files" % failures)


if __name__ == "__main__":
    if len(sys.argv) != 3 or sys.argv[1] not in ("golden", "check"):
        sys.exit(__doc__)
    (golden if sys.argv[1] == "golden" else check)(sys.argv[2])
