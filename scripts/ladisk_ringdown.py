"""Damping of the LADISK plate's modes read from the time histories, not from an FRF.

The plate is driven by a 60-500 Hz sweep. Once the sweep has moved well past a mode, the
mode rings down almost freely while the shaker drives other frequencies. Band-pass the
acceleration around the mode (zero phase), take the Hilbert envelope, and its log-slope
over the first part of the decay is -zeta * 2 pi f.

The same reading is applied to the response of a single mode of known damping (0.3 and
0.6 %) driven by the measured force of the same run: it shows what the reading returns for
a mode that light, with this sweep, filter and window. Beside it, a local fit of one mode
plus a straight background to the H1 of the five runs (one rectangular frame each, as
the walkthrough's `era frf` makes it) gives the damping an FRF method sees.

`bash scripts/ladisk_ringdown.sh` (numpy, scipy and h5py in target/py-venv).
"""

import glob
import os
import sys

import h5py
import numpy as np
from scipy import signal
from scipy.optimize import least_squares

FS = 25600.0
HALF_BAND_HZ = 15.0  # the band-pass is f0 +- this
PAST_HZ = 40.0  # the fit starts when the sweep is this far above the mode
FLOOR = 0.05  # ... and ends when the envelope has fallen to this fraction
MIN_SECONDS = 0.02
# The PROVENANCE's single peaks and era's 264 Hz mode; 215-221 Hz is a close pair,
# whose envelope beats in one band and is no single decay.
MODES_HZ = (126.5, 264.0, 348.5, 454.0)


def read(path):
    data = h5py.File(path, "r")["InputTask/data"][:]
    return data[:, 0], data[:, 1]


def sweep_track(force):
    """Times and the sweep's frequency (the force's spectral peak, never falling)."""
    n = 1024
    freqs = np.fft.rfftfreq(n, 1.0 / FS)
    times, peaks = [], []
    for k in range(0, len(force) - n, n // 4):
        spectrum = np.abs(np.fft.rfft(force[k : k + n] * np.hanning(n)))
        times.append((k + n / 2) / FS)
        peaks.append(freqs[spectrum.argmax()])
    return np.array(times), np.maximum.accumulate(np.array(peaks))


def ring_down(acc, f0, start_s):
    """Damping ratio from the envelope's log-slope after `start_s`, and the window."""
    b, a = signal.butter(2, [f0 - HALF_BAND_HZ, f0 + HALF_BAND_HZ], btype="band", fs=FS)
    envelope = np.abs(signal.hilbert(signal.filtfilt(b, a, acc)))
    t = np.arange(len(acc)) / FS
    keep = (t > start_s) & (t < t[-1] - 0.03)
    ts, env = t[keep], envelope[keep]
    below = np.flatnonzero(env < FLOOR * env[0])
    end = max(below[0] if below.size else len(env), int(MIN_SECONDS * FS))
    slope = np.polyfit(ts[:end], np.log(env[:end]), 1)[0]
    return -slope / (2 * np.pi * f0), ts[0], ts[end - 1]


def one_mode_response(force, f0, zeta):
    """Acceleration of one mode (accelerance s^2 / (s^2 + 2 zeta w s + w^2)) to `force`."""
    w = 2 * np.pi * f0
    b, a = signal.bilinear([1.0, 0.0, 0.0], [1.0, 2 * zeta * w, w * w], FS)
    return signal.lfilter(b, a, force)


def h1(paths):
    sxy, sxx = 0.0, 0.0
    for path in paths:
        force, acc = read(path)
        x, y = np.fft.rfft(force), np.fft.rfft(acc)
        sxy = sxy + y * np.conj(x)
        sxx = sxx + np.abs(x) ** 2
    return np.fft.rfftfreq(len(force), 1.0 / FS), sxy / sxx


def local_fit(freqs, frf, f0, half_hz=8.0):
    """Frequency and damping of one mode plus a complex constant and slope, fitted to
    the FRF within f0 +- half_hz (the best of four starting dampings)."""
    sel = (freqs > f0 - half_hz) & (freqs < f0 + half_hz)
    w, h = 2 * np.pi * freqs[sel], frf[sel]
    mid = w.mean()

    def residual(p):
        w0 = 2 * np.pi * p[0]
        model = (
            -(w**2) * (p[2] + 1j * p[3]) / (w0**2 - w**2 + 2j * p[1] * w0 * w)
            + (p[4] + 1j * p[5])
            + (p[6] + 1j * p[7]) * (w - mid) / mid
        )
        r = model - h
        return np.r_[r.real, r.imag]

    lower = [f0 - 5, 1e-5] + [-np.inf] * 6
    upper = [f0 + 5, 0.3] + [np.inf] * 6
    best = min(
        (
            least_squares(residual, [f0, z0, 0.1, 0.1, 0, 0, 0, 0], bounds=(lower, upper))
            for z0 in (0.003, 0.007, 0.015, 0.03)
        ),
        key=lambda r: r.cost,
    )
    return best.x[0], best.x[1]


def main():
    here = os.path.dirname(os.path.abspath(__file__))
    folder = sys.argv[1] if len(sys.argv) > 1 else os.path.join(here, "..", "data", "ladisk-plate-sweep")
    paths = sorted(glob.glob(os.path.join(folder, "*.hdf5")))
    if not paths:
        sys.exit(f"no .hdf5 files in {folder}")
    readings = {f0: [] for f0 in MODES_HZ}
    print("ring-down damping (%) per run; in brackets the same reading of one mode of 0.3 / 0.6 % driven by that run's force")
    for path in paths:
        force, acc = read(path)
        times, sweep = sweep_track(force)
        cells = []
        for f0 in MODES_HZ:
            past = np.flatnonzero(sweep > f0 + PAST_HZ)
            if not past.size:
                cells.append(f"{f0:.0f} Hz: the sweep ends first")
                continue
            start = times[past[0]]
            zeta, t0, t1 = ring_down(acc, f0, start)
            checks = [ring_down(one_mode_response(force, f0, z), f0, start)[0] for z in (0.003, 0.006)]
            readings[f0].append(zeta)
            cells.append(
                f"{f0:.0f} Hz: {100 * zeta:.2f} over {t0:.2f}-{t1:.2f} s "
                f"[{100 * checks[0]:.2f} / {100 * checks[1]:.2f}]"
            )
        print(f"  {os.path.basename(path)}: " + "; ".join(cells))
    freqs, frf = h1(paths)
    print("\nmode   ring-down median (runs)   one mode fitted to the H1 of the runs (f, zeta)")
    for f0 in MODES_HZ:
        f, z = local_fit(freqs, frf, f0)
        values = readings[f0]
        median = f"{100 * np.median(values):.2f} % ({len(values)})" if values else "-"
        print(f"{f0:5.1f}  {median:>24}   {f:.2f} Hz, {100 * z:.2f} %")


if __name__ == "__main__":
    main()
