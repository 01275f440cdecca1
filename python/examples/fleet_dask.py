"""A fleet of records on Dask: every file identified by `era.process_record`, one task a
record, the modes gathered into a table.

    python python/examples/fleet_dask.py FILE...   (CSV/MAT/HDF5 time files; default:
                                                   8 simulated records in a temp folder)

Needs `pip install "dask[distributed]"` beside era. `LocalCluster` runs worker processes
on this machine; `Client("scheduler:8786")` sends the same tasks to a cluster (each
worker needs era installed and the files on a shared path). `threads=1` makes each task
single-threaded, so one worker process per core keeps every core busy.

The same function runs unchanged on Ray:

    import ray
    ray.init()                                  # or ray.init(address="auto")
    task = ray.remote(era.process_record)
    rows = ray.get([task.remote(p, outputs=[0, 1, 2, 3], threads=1) for p in paths])

and in a pool of the standard library's concurrent.futures (era releases the GIL, so a
thread pool runs records side by side as well as a process pool does):

    import functools
    from concurrent.futures import ProcessPoolExecutor
    with ProcessPoolExecutor(2) as pool:
        rows = list(pool.map(functools.partial(era.process_record, threads=1), paths))

A failed record raises on `gather` (or `future.result()`); pass `errors="skip"` to
`client.gather` to keep the others, or wrap the call to turn its error into a row.
`era batch MANIFEST.toml --out DIR` does the same from the command line, with Parquet
tables, resume and Slurm shards.
"""

import pathlib
import sys
import tempfile

import numpy as np
from dask.distributed import Client, LocalCluster

import era


def simulated_records(count: int = 8) -> list:
    """`count` 5-minute records of a 3-mode structure (6 channels at 64 Hz) as CSV."""
    folder = pathlib.Path(tempfile.mkdtemp(prefix="era-fleet-"))
    rate, n, paths = 64.0, 64 * 300, []
    for seed in range(count):
        rng = np.random.default_rng(seed)
        t = np.arange(n) / rate
        data = np.zeros((6, n))
        for k, (f, z) in enumerate(((2.1, 0.02), (5.3, 0.015), (8.9, 0.01))):
            w = 2 * np.pi * f
            h = np.exp(-z * w * t[:4096]) * np.sin(w * t[:4096])  # impulse response
            q = np.convolve(rng.standard_normal(n + 4096), h, "valid")[:n]
            data += np.outer(np.sin((k + 1) * np.pi * np.arange(1, 7) / 7), q)
        data += 0.02 * data.std() * rng.standard_normal(data.shape)
        path = folder / f"rec_{seed:03d}.csv"
        np.savetxt(path, np.column_stack([t, data.T]), delimiter=",", comments="",
                   header="time_s," + ",".join(f"acc{c}" for c in range(1, 7)))
        paths.append(path)
    return paths


def main() -> None:
    paths = [pathlib.Path(p) for p in sys.argv[1:]] or simulated_records()
    # --- the fleet on Dask: ten lines ---------------------------------------------
    with LocalCluster(n_workers=2, threads_per_worker=1) as cluster, Client(cluster) as client:
        futures = client.map(era.process_record, paths, threads=1)
        rows = client.gather(futures)
    print(f"{'record':<16} {'mode':>4} {'f (Hz)':>9} {'± (Hz)':>8} {'zeta (%)':>8} {'± (%)':>6}")
    for path, row in zip(paths, rows):
        for k in np.flatnonzero(row["physical"]):
            print(f"{path.name:<16} {k + 1:>4} {row['frequency_hz'][k]:9.4f} "
                  f"{row['frequency_std_hz'][k]:8.4f} {100 * row['damping_ratio'][k]:8.3f} "
                  f"{100 * row['damping_ratio_std'][k]:6.3f}")
    # -------------------------------------------------------------------------------
    seconds = sum(r["seconds"] for r in rows)
    print(f"{len(rows)} records, {seconds:.2f} s of identification in the workers")


if __name__ == "__main__":
    main()
