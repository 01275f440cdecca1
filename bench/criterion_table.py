#!/usr/bin/env python3
"""Markdown tables from criterion's saved estimates (target/criterion/GROUP/ID/new).

    bench/criterion_table.py GROUP [GROUP ...]            # one row per benchmark
    bench/criterion_table.py --summary GROUP [GROUP ...]  # one row per group: the
                                                          # median, fastest and slowest
                                                          # of its benchmarks' medians

Each time is criterion's median estimate, with its 95 % confidence interval in the
per-benchmark form. A group or benchmark that criterion has not saved is an error
(exit 2), so a table is never written from a run that did not happen.
"""
import json
import os
import statistics
import sys


def fail(message):
    print(f"criterion_table.py: {message}", file=sys.stderr)
    sys.exit(2)


def target_dir():
    return os.environ.get("CARGO_TARGET_DIR") or os.path.join(
        os.path.dirname(os.path.abspath(__file__)), "..", "target")


def estimates(group):
    """(benchmark id, median s, low s, high s) for every benchmark of GROUP."""
    root = os.path.join(target_dir(), "criterion", group)
    if not os.path.isdir(root):
        fail(f"no saved run of group {group!r} under {root}")
    rows = []
    for folder, _, files in sorted(os.walk(root)):
        if os.path.basename(folder) != "new" or "estimates.json" not in files:
            continue
        bench = os.path.relpath(os.path.dirname(folder), root)
        if bench.startswith("report") or bench == ".":
            continue
        path = os.path.join(folder, "estimates.json")
        median = json.load(open(path))["median"]
        ci = median["confidence_interval"]
        rows.append((bench, median["point_estimate"] / 1e9,
                     ci["lower_bound"] / 1e9, ci["upper_bound"] / 1e9))
    if not rows:
        fail(f"group {group!r} has no benchmark with estimates")
    return rows


def show(seconds):
    if seconds >= 1:
        return f"{seconds:.2f} s"
    if seconds >= 1e-3:
        return f"{1e3 * seconds:.3g} ms"
    return f"{1e6 * seconds:.3g} µs"


def main(argv):
    summary = "--summary" in argv
    groups = [a for a in argv if a != "--summary"]
    if not groups:
        fail("name at least one criterion group\n" + __doc__)
    found = {group: estimates(group) for group in groups}
    print()  # a table of its own, even right after a table the bench printed
    if summary:
        print("| group | benchmarks | median of the medians | fastest | slowest |")
        print("|---|---:|---:|---:|---:|")
        for group in groups:
            medians = [m for _, m, _, _ in found[group]]
            print(f"| `{group}` | {len(medians)} | {show(statistics.median(medians))} "
                  f"| {show(min(medians))} | {show(max(medians))} |")
    else:
        print("| group | benchmark | median | 95 % interval |")
        print("|---|---|---:|---:|")
        for group in groups:
            for bench, m, lo, hi in found[group]:
                print(f"| `{group}` | `{bench}` | {show(m)} | {show(lo)} … {show(hi)} |")


if __name__ == "__main__":
    main(sys.argv[1:])
