"""era.process_record: one record of a fleet as one pure function. The same modes as
`era oma FILE --json` (to 1e-9) from a file or from its arrays; the function and its
result pickle; it runs unchanged in a process pool and on a real dask.distributed
LocalCluster of two worker processes; bad input is a ValueError or OSError that names
what is wrong."""

import functools
import json
import multiprocessing
import pickle
import subprocess
import sys
from concurrent.futures import ProcessPoolExecutor, ThreadPoolExecutor

import numpy as np
import pytest

import era
from fleet_records import fleet, responses, write_csv

CHANNELS = 6


@pytest.fixture(scope="module")
def records(tmp_path_factory):
    """Three 2-minute records of a 3-mode structure, 6 channels at 64 Hz."""
    return fleet(tmp_path_factory.mktemp("fleet"), 3, channels=CHANNELS, seconds=120.0)


def cli_modes(era_cli, path, *flags):
    done = era_cli("oma", path, "--outputs", f"1-{CHANNELS}", *flags, "--json", "--quiet")
    return json.loads(done.stdout)


def assert_same_modes(row, cli):
    """The row's modes are the CLI's, to 1e-9 relative."""
    modes = cli["modes"]
    assert len(modes) == len(row["frequency_hz"]) > 0
    assert row["states"] == cli["states"]

    def column(key, nan=float("nan")):
        return np.array([nan if m.get(key) is None else m[key] for m in modes], dtype=float)

    for key in ("frequency_hz", "damping_ratio", "frequency_std_hz", "damping_ratio_std"):
        np.testing.assert_allclose(row[key], column(key), rtol=1e-9, atol=0, equal_nan=True,
                                   err_msg=key)
    for key in ("mpc", "emac"):
        want = np.array([(m.get("indicators") or {}).get(key, np.nan) for m in modes], dtype=float)
        np.testing.assert_allclose(row[key], want, rtol=1e-9, atol=1e-15, equal_nan=True,
                                   err_msg=key)
    assert row["physical"].tolist() == [bool(m.get("physical")) for m in modes]
    shapes = np.array([np.array(m["shape_re"]) + 1j * np.array(m["shape_im"]) for m in modes]).T
    assert row["shapes"].shape == shapes.shape == (CHANNELS, len(modes))
    np.testing.assert_allclose(row["shapes"], shapes, rtol=1e-9, atol=1e-9)


def test_a_file_gives_the_command_lines_modes(records, era_cli):
    path = records[0]
    row = era.process_record(path)
    cli = cli_modes(era_cli, path)
    assert_same_modes(row, cli)
    # The sample rate is the CSV's time column's, as the CLI reads it.
    assert row["sample_rate_hz"] == cli["sample_rate_hz"] == 64.0
    assert row["source"] == str(path) and row["verb"] == "oma" and row["judged"]
    # The structure's three modes are among the physical ones.
    found = row["frequency_hz"][row["physical"]]
    for f in (2.1, 5.3, 8.9):
        assert np.min(np.abs(found - f)) < 0.02 * f, (f, found)
    assert np.all(row["frequency_std_hz"][row["physical"]] > 0)
    assert row["seconds"] > 0


def test_options_are_the_flags(records, era_cli):
    path = records[1]
    row = era.process_record(path, verb="oma", references=["acc2", 4], method="next-era",
                             states=14, time_lags=96, blocks=4, threads=1)
    cli = cli_modes(era_cli, path, "--references", "2,5", "--method", "next-era",
                    "--states", "14", "--time-lags", "96", "--blocks", "4")
    assert cli["lags"] == 96 and cli["blocks"] == 4
    assert_same_modes(row, cli)
    # The same record as arrays gives the same numbers.
    data, rate, _ = era.read_time(path)
    arrays = era.process_record(data, sample_rate_hz=rate, references=[1, 4],
                                method="next-era", states=14, time_lags=96, blocks=4)
    assert arrays["source"] == "arrays"
    for key in ("frequency_hz", "damping_ratio", "frequency_std_hz", "shapes"):
        np.testing.assert_array_equal(arrays[key], row[key])


def test_records_of_one_test_are_pooled(records, era_cli):
    row = era.process_record(records[:2], states=12, blocks=4)
    cli = cli_modes(era_cli, records[0], records[1], "--states", "12", "--blocks", "4")
    assert_same_modes(row, cli)
    assert row["source"] == f"{records[0]};{records[1]}"
    data = [era.read_time(p)[0] for p in records[:2]]
    arrays = era.process_record(data, sample_rate_hz=64.0, states=12, blocks=4)
    np.testing.assert_array_equal(arrays["frequency_hz"], row["frequency_hz"])


def test_identify_verb_takes_identifys_keywords(era_cli, tmp_path):
    path = tmp_path / "truth.uff"
    era_cli("simulate", "truth-model", "--noise", "0.15", "--seed", "3", "--out", path, "--quiet")
    row = era.process_record(path, verb="identify", states=8, hankel_factor=4, pad_to=1024,
                             preset="thesis")
    cli = json.loads(era_cli("identify", path, "--states", "8", "--hankel-factor", "4",
                             "--pad-to", "1024", "--preset", "thesis", "--json", "--quiet").stdout)
    np.testing.assert_allclose(row["frequency_hz"], [m["frequency_hz"] for m in cli["modes"]],
                               rtol=1e-10)
    assert row["states"] == 8 and row["shapes"].shape == (3, 4)
    # Time histories with inputs and outputs: era.identify_time's answer.
    data = responses(4, channels=4, seconds=60.0)
    found = era.identify_time(data, 64.0, [0], [1, 2, 3], states=6)
    row = era.process_record(data, verb="identify", sample_rate_hz=64.0, inputs=[0],
                             outputs=[1, 2, 3], states=6)
    np.testing.assert_array_equal(row["frequency_hz"], found.frequency_hz)
    assert row["sample_rate_hz"] == 64.0


def test_the_function_and_its_result_pickle(records):
    assert pickle.loads(pickle.dumps(era.process_record)) is era.process_record
    row = era.process_record(records[2], states=10, blocks=1)
    back = pickle.loads(pickle.dumps(row))
    assert back.keys() == row.keys()
    for key, value in row.items():
        assert type(value).__module__ in ("builtins", "numpy"), key
        if isinstance(value, np.ndarray):
            np.testing.assert_array_equal(back[key], value)
        else:
            assert back[key] == value, key
    # One block: no jackknife, so no standard deviations.
    assert np.all(np.isnan(row["frequency_std_hz"]))


def test_thread_and_process_pools_give_the_same_rows(records):
    serial = [era.process_record(p, threads=1) for p in records]
    with ThreadPoolExecutor(2) as pool:
        threaded = list(pool.map(lambda p: era.process_record(p, threads=1), records))
    spawn = multiprocessing.get_context("spawn")
    with ProcessPoolExecutor(2, mp_context=spawn) as pool:
        processed = list(pool.map(functools.partial(era.process_record, threads=1), records))
    for a, b, c in zip(serial, threaded, processed):
        for key in ("frequency_hz", "damping_ratio", "frequency_std_hz", "physical", "shapes"):
            np.testing.assert_array_equal(a[key], b[key])
            np.testing.assert_array_equal(a[key], c[key])


FORKED = """
import multiprocessing, sys
from concurrent.futures import ProcessPoolExecutor
import era

def task(path):
    era.simulate_truth_model()
    return era.process_record(path)["frequency_hz"].tolist()

if __name__ == "__main__":
    paths = sys.argv[1:]
    before = [task(p) for p in paths]  # era's pools have run in this process
    with ProcessPoolExecutor(2, mp_context=multiprocessing.get_context("fork")) as pool:
        after = list(pool.map(task, paths))
    print(before == after)
"""


@pytest.mark.skipif("fork" not in multiprocessing.get_all_start_methods(), reason="no fork here")
def test_a_process_forked_after_a_call_can_call_again(records, tmp_path):
    """Each call runs in a pool of its own, never in rayon's global pool, which a forked
    child inherits without its threads (the call would wait for ever)."""
    script = tmp_path / "forked.py"
    script.write_text(FORKED)
    done = subprocess.run([sys.executable, str(script), *map(str, records[:2])],
                          capture_output=True, text=True, timeout=120)
    assert done.returncode == 0, done.stderr
    assert done.stdout.strip() == "True"


def test_on_a_dask_local_cluster_of_two_processes(records, era_cli):
    # Not skipped when absent: scripts/python_tests.sh installs dask[distributed].
    from dask import distributed
    with distributed.LocalCluster(n_workers=2, processes=True, threads_per_worker=1,
                                  dashboard_address=None) as cluster, \
            distributed.Client(cluster) as client:
        assert len(client.scheduler_info()["workers"]) == 2
        futures = client.map(era.process_record, records, threads=1)
        rows = client.gather(futures)
    assert [r["source"] for r in rows] == [str(p) for p in records]
    for path, row in zip(records, rows):
        assert_same_modes(row, cli_modes(era_cli, path))


def test_bad_input_names_what_is_wrong(records, tmp_path, data_dir):
    with pytest.raises(ValueError, match=r"unknown keyword 'time_lag'.*time_lags"):
        era.process_record(records[0], time_lag=64)
    with pytest.raises(ValueError, match=r"verb 'ssi'.*'oma', 'identify'"):
        era.process_record(records[0], verb="ssi")
    missing = tmp_path / "nowhere" / "rec.csv"
    with pytest.raises(OSError, match="nowhere"):
        era.process_record(missing)
    with pytest.raises(FileNotFoundError):
        era.process_record(str(missing))
    with pytest.raises(ValueError, match="sample_rate_hz"):
        era.process_record(np.zeros((3, 100)))
    with pytest.raises(ValueError, match="path_or_arrays.*NoneType"):
        era.process_record(None)
    with pytest.raises(ValueError, match="not both"):
        era.process_record([records[0], np.zeros((3, 100))])
    with pytest.raises(ValueError, match="verb"):
        era.process_record(records[0], verb=["oma"])
    # A MAT file without a sample rate needs one, as `era oma --sample-rate` (DaISy).
    mat = data_dir / "daisy-steel-subframe" / "flexible_structure_dat.mat"
    with pytest.raises(ValueError, match=r"flexible_structure_dat.mat.*set sample_rate_hz"):
        era.process_record(mat, outputs=list(range(2, 30)))
    with pytest.raises(ValueError, match=r"no channel named 'strain'.*acc1"):
        era.process_record(records[0], outputs=["acc1", "strain"])
    with pytest.raises(ValueError, match="time_lags 5000"):
        era.process_record(records[0], time_lags=5000)
    with pytest.raises(ValueError, match="inputs="):
        era.process_record(np.zeros((3, 100)), verb="identify", sample_rate_hz=64.0)
    bad = tmp_path / "bad.csv"
    bad.write_text("time_s,acc1\n0,1\n0.1,oops\n")
    with pytest.raises(ValueError, match="bad.csv"):
        era.process_record(bad)
    write_csv(tmp_path / "slow.csv", responses(1, channels=2, seconds=10.0, rate=32.0), rate=32.0)
    with pytest.raises(ValueError, match="sample rate 32.0 Hz, the first file's is 64.0"):
        era.process_record([records[0], tmp_path / "slow.csv"])
