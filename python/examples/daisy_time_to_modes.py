"""DaISy steel subframe: from time histories to modes.

Two shakers (channels 1-2) and 28 accelerometers (channels 3-30), sampled at 1024 Hz
(data/daisy-steel-subframe, BSD 3-Clause, see its PROVENANCE.md). Read the MAT file,
estimate 28 x 2 H1 FRFs with Welch averaging, identify a 60-state model, and list the
lightly damped modes with their fit. The same steps as scripts/daisy_walkthrough.sh.

    python python/examples/daisy_time_to_modes.py
"""

import pathlib

import numpy as np

import era

REPO = pathlib.Path(__file__).resolve().parents[2]
mat = REPO / "data" / "daisy-steel-subframe" / "flexible_structure_dat.mat"

data, rate, names = era.read_time(mat)  # (30 channels, 8523 samples); the file has no rate
print(f"{mat.name}: {data.shape[0]} channels x {data.shape[1]} samples")
frf, coherence = era.estimate_frf(
    data, sample_rate_hz=1024.0, inputs=[0, 1], outputs=list(range(2, 30)),
    frame=2048, window="hann", overlap=0.5, estimator="h1",
)
print(f"{frf!r}; median coherence {np.median(coherence[:, :, 1:]):.3f}")

# The default route: the order from the stabilization diagram, refined in continuous
# time; the band where the coherence is high carries the structure's modes.
found = era.identify(frf, band=(60.0, 500.0))
for name, value, reason in found.route:
    print(f"  {name}: {value} ({reason})")
print(f"{found!r}\n")
print(f"{'f (Hz)':>9} {'zeta (%)':>9} {'largest |shape|':>16}")
for mode in found.modes:
    if mode.physical:  # the modes judged physical; the rest fit noise and leakage
        print(f"{mode.frequency_hz:>9.2f} {100 * mode.damping_ratio:>9.2f} "
              f"{np.argmax(np.abs(mode.shape)) + 3:>13} (channel)")
fit = found.fit
print(f"\nmean relative fit error {np.nanmean(fit['relative_error']):.3f} over "
      f"{len(fit['pairs'])} pairs")
