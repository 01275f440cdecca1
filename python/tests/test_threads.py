"""Eight threads identifying at once give what one thread gives, bit for bit."""

from concurrent.futures import ThreadPoolExecutor

import numpy as np

import era
from settings import DTA_SETTINGS, TRUTH_SETTINGS


def test_eight_threads_equal_one():
    # The thesis size: the DTA-like 8 x 8 set, 801 lines, and its settings (ns 80,
    # lh 5, ni 1, nz 3, ndpts 1024).
    frf = era.simulate_modal(collocated=True, noise=0.05)
    settings = dict(states=80, **DTA_SETTINGS, preset="thesis")
    alone = era.identify(frf, **settings)
    with ThreadPoolExecutor(max_workers=8) as pool:
        results = list(pool.map(lambda _: era.identify(frf, **settings), range(8)))
    for found in results:
        assert np.array_equal(found.eigenvalues, alone.eigenvalues)
        assert np.array_equal(found.singular_values, alone.singular_values)
        assert np.array_equal(found.a, alone.a)
        assert found.to_json() == alone.to_json()


def test_threads_on_different_data():
    frfs = [era.simulate_truth_model(noise=0.15, seed=s) for s in range(1, 9)]
    one = [era.identify(f, 8, **TRUTH_SETTINGS, preset="thesis").eigenvalues for f in frfs]
    with ThreadPoolExecutor(max_workers=8) as pool:
        many = list(pool.map(lambda f: era.identify(f, 8, **TRUTH_SETTINGS, preset="thesis").eigenvalues, frfs))
    for a, b in zip(one, many):
        assert np.array_equal(a, b)
    # Different noise, different models: the comparison above could fail.
    assert not np.array_equal(one[0], one[1])


def test_a_thread_count_per_call():
    # threads=N runs the call in a pool of N threads (rayon's loops and faer's kernels):
    # one thread gives the model all cores give, to round-off.
    frf = era.simulate_truth_model(noise=0.15, seed=3)
    every_core = era.identify(frf, 8, **TRUTH_SETTINGS, preset="thesis")
    one = era.identify(frf, 8, **TRUTH_SETTINGS, threads=1, preset="thesis")
    assert np.allclose(one.eigenvalues, every_core.eigenvalues, rtol=1e-10, atol=1e-12)
    for bad in (0, 5000):
        try:
            era.identify(frf, 8, threads=bad)
        except ValueError as e:
            assert str(e).startswith(f"threads {bad}: must be between 1 and 1024"), str(e)
        else:
            raise AssertionError(f"threads={bad} was accepted")
