"""Records of a fleet made with numpy alone: a few lightly damped modes of one structure
driven by white noise, seen by a row of accelerometers with a little sensor noise, and
written as the CSV era reads (a ``time_s`` column, then one column a channel). Used by
python/tests/test_fleet.py and bench/dask_fleet.py."""

import pathlib

import numpy as np

# (frequency Hz, damping ratio) of the structure's modes.
MODES = ((2.1, 0.02), (5.3, 0.015), (8.9, 0.01))


def responses(seed: int, channels: int = 6, seconds: float = 120.0, rate: float = 64.0,
              modes=MODES, drift: float = 0.0) -> np.ndarray:
    """(channels, samples) responses: each mode's coordinate is white noise through its
    impulse response (an FFT convolution, started well before the kept window so that
    no transient remains), times a sine shape over the channels; the frequencies are
    scaled by ``1 + drift``; 2 % sensor noise."""
    rng = np.random.default_rng(seed)
    n = int(round(seconds * rate))
    dt = 1.0 / rate
    out = np.zeros((channels, n))
    where = np.arange(1, channels + 1) / (channels + 1)
    for k, (f, z) in enumerate(modes):
        w = 2 * np.pi * f * (1.0 + drift)
        wd = w * np.sqrt(1 - z * z)
        lead = int(np.ceil(np.log(1e8) / (z * w * dt)))  # decays by 1e-8
        t = np.arange(lead) * dt
        h = np.exp(-z * w * t) * np.sin(wd * t) / wd
        force = rng.standard_normal(n + lead)
        size = 1 << int(np.ceil(np.log2(n + 2 * lead)))
        q = np.fft.irfft(np.fft.rfft(force, size) * np.fft.rfft(h, size), size)[lead:lead + n]
        out += np.outer(np.sin((k + 1) * np.pi * where), q / np.std(q))
    out += 0.02 * rng.standard_normal(out.shape)
    return out


def write_csv(path: pathlib.Path, data: np.ndarray, rate: float = 64.0) -> pathlib.Path:
    """``data`` (channels, samples) as a CSV with a ``time_s`` column (k / rate)."""
    channels, n = data.shape
    table = np.column_stack([np.arange(n) / rate, data.T])
    header = ",".join(["time_s"] + [f"acc{c + 1}" for c in range(channels)])
    np.savetxt(path, table, delimiter=",", header=header, comments="", fmt="%.12g")
    return path


def fleet(folder: pathlib.Path, count: int, **kwargs) -> list:
    """``count`` records (seeds 1..count) as CSV files in ``folder``; their paths."""
    folder.mkdir(parents=True, exist_ok=True)
    rate = kwargs.get("rate", 64.0)
    return [write_csv(folder / f"rec_{s:04d}.csv", responses(s, **kwargs), rate)
            for s in range(1, count + 1)]
