"""Throughput of era.process_record on a dask.distributed LocalCluster: 1 worker against
2 (processes, one thread each, `threads=1` to era so that every task is single-threaded).

    VENV=/tmp/venv bash scripts/python_tests.sh -k fleet   # a venv with era and dask
    /tmp/venv/bin/python bench/dask_fleet.py [--records 16] [--channels 8] [--minutes 10]
                                             [--rate 64] [--repeat 2] [--folder DIR]
                                             [--fleet DIR]

The records are made with numpy (python/tests/fleet_records.py: three modes driven by
white noise, 2 % sensor noise) and written as CSV once; `--folder` keeps them between
runs. Each cluster is started and warmed up (every worker has imported era and run one
record) before the clock starts, so the figures are the fleet's, not the start-up's.
Prints records/s for each cluster, the best of `--repeat` runs, and the speed-up; the
issue's target is 1.8x from 1 worker to 2. Beside them, the seconds of a task as the
worker saw it and how many tasks ran at once on average (the tasks' seconds over the
wall time): with 2 workers close to 2 means Dask keeps both busy, and a task that takes
longer than with 1 worker means the cores were shared. The load average is printed too:
on a machine shared with other work the speed-up is lower than the cores allow. Last,
the same fleet in a process pool of the standard library with 1 and 2 processes, no
Dask: the speed-up two independent processes get from the cores at that moment.
"""

import argparse
import functools
import multiprocessing
import os
import pathlib
import sys
import tempfile
import time
from concurrent.futures import ProcessPoolExecutor

REPO = pathlib.Path(__file__).resolve().parents[1]
sys.path.insert(0, str(REPO / "python" / "tests"))

import era  # noqa: E402
from dask.distributed import Client, LocalCluster, wait  # noqa: E402
from fleet_records import fleet  # noqa: E402


def records(args) -> list:
    if args.fleet:
        paths = sorted(pathlib.Path(args.fleet).glob("records/*.csv"))[: args.records]
        if len(paths) < args.records:
            sys.exit(f"{args.fleet}: {len(paths)} records, {args.records} asked for")
        return paths
    folder = pathlib.Path(args.folder) if args.folder else pathlib.Path(
        tempfile.mkdtemp(prefix="era-dask-fleet-"))
    existing = sorted(folder.glob("rec_*.csv")) if folder.exists() else []
    if len(existing) == args.records:
        return existing
    clock = time.perf_counter()
    paths = fleet(folder, args.records, channels=args.channels, seconds=60.0 * args.minutes,
                  rate=args.rate)
    print(f"wrote {len(paths)} records of {args.channels} channels x {args.minutes} min at "
          f"{args.rate:g} Hz to {folder} in {time.perf_counter() - clock:.1f} s")
    return paths


def timed(client: Client, paths: list) -> tuple:
    """The fleet's wall time, and the sum of the tasks' own (each record's `seconds`)."""
    clock = time.perf_counter()
    futures = client.map(era.process_record, paths, threads=1, pure=False)
    wait(futures)
    seconds = time.perf_counter() - clock
    rows = client.gather(futures)
    assert all(r["physical"].any() for r in rows), "a record without a physical mode"
    return seconds, sum(r["seconds"] for r in rows)


def run(workers: int, paths: list, repeat: int) -> tuple:
    with LocalCluster(n_workers=workers, threads_per_worker=1, processes=True,
                      dashboard_address=None) as cluster, Client(cluster) as client:
        # Warm-up: every worker imports era and identifies one record.
        client.run(lambda: __import__("era") and None)
        warm = client.map(era.process_record, paths[:workers], threads=1, pure=False)
        wait(warm)
        return min(timed(client, paths) for _ in range(repeat))


def pooled(workers: int, paths: list, repeat: int) -> float:
    """The same fleet in a process pool of the standard library, without Dask: what the
    cores give two independent processes, the ceiling of Dask's speed-up."""
    task = functools.partial(era.process_record, threads=1)
    spawn = multiprocessing.get_context("spawn")
    with ProcessPoolExecutor(workers, mp_context=spawn) as pool:
        list(pool.map(task, paths[:workers]))  # warm-up: every process imports era
        best = float("inf")
        for _ in range(repeat):
            clock = time.perf_counter()
            list(pool.map(task, paths))
            best = min(best, time.perf_counter() - clock)
    return best


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--records", type=int, default=16)
    parser.add_argument("--channels", type=int, default=8)
    parser.add_argument("--minutes", type=float, default=10.0)
    parser.add_argument("--rate", type=float, default=64.0)
    parser.add_argument("--repeat", type=int, default=2)
    parser.add_argument("--folder", default=None)
    parser.add_argument("--fleet", default=None,
                        help="the records of an `era simulate fleet` folder instead (such as "
                        "target/bench-fleet-1000 of bench/batch.sh): the CLI's throughput data")
    args = parser.parse_args()
    paths = records(args)
    serial = time.perf_counter()
    row = era.process_record(paths[0], threads=1)
    serial = time.perf_counter() - serial
    print(f"one record in this process: {serial:.2f} s, {row['states']} states, "
          f"{int(row['physical'].sum())} physical modes")
    rates = {}
    for workers in (1, 2):
        load = os.getloadavg()[0]
        seconds, tasks = run(workers, paths, args.repeat)
        rates[workers] = len(paths) / seconds
        print(f"{workers} worker{'s' if workers > 1 else ' '}: {len(paths)} records in "
              f"{seconds:6.2f} s, {rates[workers]:5.2f} records/s, {tasks / len(paths):.3f} s a "
              f"task in the worker, {tasks / seconds:.2f} tasks running on average "
              f"(load average before: {load:.2f})")
    print(f"speed-up from 1 to 2 workers: {rates[2] / rates[1]:.2f}x (target 1.8x); "
          f"{os.cpu_count()} cores, load average now {os.getloadavg()[0]:.2f}")
    alone = {w: len(paths) / pooled(w, paths, args.repeat) for w in (1, 2)}
    print(f"without Dask (a process pool of 1, then 2): {alone[1]:5.2f} and {alone[2]:5.2f} "
          f"records/s, {alone[2] / alone[1]:.2f}x; load average now {os.getloadavg()[0]:.2f}")


if __name__ == "__main__":
    main()
