#!/usr/bin/env python3
"""Compare two folders written by scripts/golden_outputs.sh (issue 32: no result changes).

    python3 scripts/golden_compare.py BEFORE AFTER [--rel 1e-12]

Every file of either folder is compared: JSON as data (wall times and the version left
out), text token by token with numbers compared to a relative tolerance (1e-12 by
default: |a − b| ≤ rel·max(|a|, |b|)), binary files byte by byte. Prints one line per file
that differs and a summary; exits 1 when anything differs beyond the tolerance.
"""
import json
import math
import os
import re
import sys

SKIP_KEYS = re.compile(r"(timings?(_s)?|seconds|wall_s|elapsed.*|era_version|version|created.*)$")
NUMBER = re.compile(r"[-+]?(?:\d+\.\d*|\.\d+|\d+)(?:[eE][-+]?\d+)?|[-+]?(?:inf|NaN|nan)\b")
TIMING_LINE = re.compile(r"(\bin \d+(\.\d+)? ?(ms|s)\b|wall|took|seconds|timings?)", re.I)


class Worst:
    def __init__(self):
        self.rel = 0.0
        self.where = ""
        self.text = []

    def number(self, a, b, where):
        if a == b or (math.isnan(a) and math.isnan(b)):
            return
        scale = max(abs(a), abs(b))
        r = abs(a - b) / scale if scale > 0 else 0.0
        if math.isinf(r) or math.isnan(r):
            r = math.inf
        if r > self.rel:
            self.rel, self.where = r, f"{where}: {a!r} vs {b!r}"


def walk_json(a, b, path, w):
    if isinstance(a, dict) and isinstance(b, dict):
        keys = {k for k in set(a) | set(b) if not SKIP_KEYS.match(k)}
        for k in sorted(keys):
            if k not in a or k not in b:
                w.text.append(f"{path}.{k}: only in {'after' if k not in a else 'before'}")
            else:
                walk_json(a[k], b[k], f"{path}.{k}", w)
    elif isinstance(a, list) and isinstance(b, list):
        if len(a) != len(b):
            w.text.append(f"{path}: length {len(a)} vs {len(b)}")
        for k, (x, y) in enumerate(zip(a, b)):
            walk_json(x, y, f"{path}[{k}]", w)
    elif isinstance(a, bool) or isinstance(b, bool) or a is None or b is None:
        if a != b:
            w.text.append(f"{path}: {a!r} vs {b!r}")
    elif isinstance(a, (int, float)) and isinstance(b, (int, float)):
        w.number(float(a), float(b), path)
    elif isinstance(a, str) and isinstance(b, str):
        walk_text(a, b, path, w)
    elif a != b:
        w.text.append(f"{path}: {a!r} vs {b!r}")


def walk_text(a, b, where, w):
    la, lb = a.splitlines(), b.splitlines()
    if len(la) != len(lb):
        w.text.append(f"{where}: {len(la)} vs {len(lb)} lines")
    for k, (x, y) in enumerate(zip(la, lb), 1):
        if x == y or (TIMING_LINE.search(x) and TIMING_LINE.search(y)):
            continue
        nx, ny = NUMBER.findall(x), NUMBER.findall(y)
        if NUMBER.sub("#", x) != NUMBER.sub("#", y) or len(nx) != len(ny):
            w.text.append(f"{where}:{k}: {x.strip()[:90]!r} vs {y.strip()[:90]!r}")
            continue
        for p, q in zip(nx, ny):
            w.number(float(p), float(q), f"{where}:{k}")


BINARY = re.compile(r"[^\s\"<>]*/target/release/era\b")
DATE = re.compile(r"\d{4}-\d\d-\d\d[ T]\d\d:\d\d:\d\d(\.\d+)?( ?UTC|Z)?")


def compare(pa, pb, name, w, roots):
    ba, bb = open(pa, "rb").read(), open(pb, "rb").read()
    if name.endswith(".mat"):
        # a MAT v5 file's first 116 bytes are its descriptive text, with the date
        ba, bb = ba[116:], bb[116:]
    if ba == bb:
        return
    try:
        ta, tb = ba.decode("utf-8"), bb.decode("utf-8")
    except UnicodeDecodeError:
        w.text.append(f"{name}: binary files differ")
        return
    # the output folder's own name, the binary's path and the dates of the runs are not
    # results
    ta, tb = (BINARY.sub("era", t) for t in (ta, tb))
    ta = DATE.sub("DATE", ta.replace(os.path.abspath(roots[0]), "OUT").replace(roots[0], "OUT"))
    tb = DATE.sub("DATE", tb.replace(os.path.abspath(roots[1]), "OUT").replace(roots[1], "OUT"))
    if ta == tb:
        return
    if name.endswith(".json") or ta.lstrip().startswith("{"):
        try:
            walk_json(json.loads(ta), json.loads(tb), name, w)
            return
        except json.JSONDecodeError:
            pass
    walk_text(ta, tb, name, w)


def files(root):
    out = set()
    for d, _, fs in os.walk(root):
        for f in fs:
            out.add(os.path.relpath(os.path.join(d, f), root))
    return out


def main():
    args = [a for a in sys.argv[1:] if not a.startswith("--")]
    rel = 1e-12
    if "--rel" in sys.argv:
        rel = float(sys.argv[sys.argv.index("--rel") + 1])
        args = [a for a in args if a != sys.argv[sys.argv.index("--rel") + 1]]
    before, after = args[:2]
    fa, fb = files(before), files(after)
    bad, identical, within = 0, 0, 0
    for name in sorted(fa | fb):
        if name not in fa or name not in fb:
            print(f"{name}: only in {'before' if name in fa else 'after'}")
            bad += 1
            continue
        w = Worst()
        compare(os.path.join(before, name), os.path.join(after, name), name, w, (before, after))
        if w.text or w.rel > rel:
            bad += 1
            for t in w.text[:5]:
                print("  ", t)
            if w.rel > rel:
                print(f"{name}: max relative difference {w.rel:.3g} at {w.where}")
        elif w.rel > 0:
            within += 1
            print(f"{name}: within {rel:g} (max relative {w.rel:.3g} at {w.where})")
        else:
            identical += 1
    print(f"{len(fa | fb)} files: {identical} identical, {within} within {rel:g}, {bad} differ")
    sys.exit(1 if bad else 0)


if __name__ == "__main__":
    main()
