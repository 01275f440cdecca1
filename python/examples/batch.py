"""A batch study: identify many FRF files at once.

`identify_file` is a plain function of a path: it reads the file, identifies, and
returns a small dict of plain Python values. era releases the GIL while it reads and
computes, so a thread pool runs the files in parallel on every core; a process pool
works the same way (FrfData and the results pickle).

    python python/examples/batch.py [FOLDER]   (default: 16 simulated files in a temp folder)

For a fleet of records (time files identified the same way, on Dask, Ray or a process
pool) `era.process_record` is that function already, for `oma` and `identify`:
python/examples/fleet_dask.py and the book's "A fleet on Dask". This example stays as
the pattern for a function of your own (a study's own keywords, its own result dict).
"""

import pathlib
import sys
import tempfile
import time
from concurrent.futures import ThreadPoolExecutor

import era


def identify_file(path, states=8, hankel_factor=4, pad_to=1024):
    """One file in, its modes out, as plain Python values (cheap to send between
    processes or machines)."""
    found = era.identify(era.read_frf(path), states, hankel_factor=hankel_factor, pad_to=pad_to,
                         preset="thesis")
    return {
        "file": str(path),
        "frequency_hz": found.frequency_hz.tolist(),
        "damping_ratio": found.damping_ratio.tolist(),
        "mean_relative_error": float(found.fit["relative_error"].mean()),
    }


def simulated_folder(n: int) -> pathlib.Path:
    folder = pathlib.Path(tempfile.mkdtemp(prefix="era-batch-"))
    for seed in range(1, n + 1):
        era.write_frf(folder / f"truth_{seed:02d}.uff", era.simulate_truth_model(noise=0.15, seed=seed),
                      binary=True)
    return folder


def main() -> None:
    folder = pathlib.Path(sys.argv[1]) if len(sys.argv) > 1 else simulated_folder(16)
    paths = sorted(p for p in folder.iterdir() if p.suffix in (".csv", ".uff", ".unv", ".mat"))
    t0 = time.perf_counter()
    serial = [identify_file(p) for p in paths]
    t_serial = time.perf_counter() - t0
    t0 = time.perf_counter()
    with ThreadPoolExecutor() as pool:
        parallel = list(pool.map(identify_file, paths))
    t_parallel = time.perf_counter() - t0
    assert parallel == serial  # same answers, in the same order
    for row in parallel:
        modes = ", ".join(f"{f:7.1f} Hz" for f in row["frequency_hz"])
        print(f"{pathlib.Path(row['file']).name}: {modes}  (fit {row['mean_relative_error']:.3f})")
    print(f"{len(paths)} files: {t_serial:.2f} s one by one, {t_parallel:.2f} s in a thread pool")


if __name__ == "__main__":
    main()
