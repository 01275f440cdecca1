"""era beside python-control's eigensys_realization on the same Markov data.

Both build the block Hankel H0[r][c] = Y(1+r+c) from the Markov parameters
Y(k) = C A^(k-1) B, take its SVD and realize the balanced model (Juang & Pappa 1985),
so the eigenvalues agree to rounding. The Markov parameters are the inverse FFT of the
FRFs (numpy's irfft, as era computes them); era takes the FRFs and does that step
itself. Timed in the same process at two sizes: the truth model (3 x 3, ns 8) and the
thesis size (the DTA-like 8 x 8 set, 801 lines, ns 80, lh 5, ni 1, nz 3, ndpts 1024).

    pip install control
    python python/examples/python_control_side_by_side.py
"""

import time

import numpy as np

import era

try:
    import control
except ImportError:
    raise SystemExit("this example needs python-control: pip install control") from None


def markov_of(frf: era.FrfData, integrations: int, zero_lines: int, pad_to: int) -> np.ndarray:
    """era's preprocessing and Markov step in numpy: integrate (G / jω), pad to
    pad_to + 1 lines, zero the first lines, inverse real FFT (1/n, Hermitian)."""
    f = frf.frequency_hz
    g = frf.values.copy()
    for _ in range(integrations):
        w = 2j * np.pi * f
        w[0] = np.inf  # the 0 Hz line of an integrated FRF is 0
        g = g / w
    lines = max(pad_to + 1, frf.lines) if pad_to else frf.lines
    padded = np.zeros(g.shape[:2] + (lines,), complex)
    padded[:, :, : frf.lines] = g
    padded[:, :, :zero_lines] = 0
    return np.fft.irfft(padded, n=2 * (lines - 1), axis=2)


def side_by_side(name, frf, states, hankel_factor=5, integrations=0, zero_lines=0, pad_to=0):
    t0 = time.perf_counter()
    found = era.identify(frf, states, hankel_factor=hankel_factor, integrations=integrations,
                         zero_lines=zero_lines, pad_to=pad_to, preset="thesis")
    t_era = time.perf_counter() - t0

    markov = markov_of(frf, integrations, zero_lines, pad_to)
    blocks = (states * hankel_factor // 4 * 4) // 2 - 1  # era's H0: blocks x blocks
    assert found.hankel_size == (blocks * frf.outputs, blocks * frf.inputs)
    t0 = time.perf_counter()
    sys, _ = control.eigensys_realization(markov, r=states, m=blocks, n=blocks,
                                          dt=found.sample_time_s)
    t_ctrl = time.perf_counter() - t0

    ours = np.sort_complex(np.linalg.eigvals(found.a))
    theirs = np.sort_complex(sys.poles())
    gap = np.max(np.abs(ours - theirs))
    print(f"{name}: H0 {found.hankel_size[0]} x {found.hankel_size[1]}, {states} states")
    print(f"  largest eigenvalue difference {gap:.2e}")
    print(f"  era {1e3 * t_era:8.1f} ms (FRFs -> model, modes and fit)")
    print(f"  python-control {1e3 * t_ctrl:8.1f} ms (Markov -> model)   ratio {t_ctrl / t_era:5.1f}x")
    return gap


if __name__ == "__main__":
    side_by_side("truth model", era.simulate_truth_model(noise=0.15), 8, hankel_factor=4, pad_to=1024)
    side_by_side("thesis size (DTA-like)", era.simulate_modal(collocated=True, noise=0.05), 80,
                 hankel_factor=5, integrations=1, zero_lines=3, pad_to=1024)
