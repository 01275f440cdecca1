"""era: the Eigensystem Realization Algorithm for lightly damped structures, from Python.

Measured frequency response functions (FRFs) in, a state-space model ``(A, B, C, D)``,
its Hankel singular values, modes and fit out: the same Rust core, checks and messages
as the ``era`` command line, with numpy arrays in and out. The axis order is
``[output, input, frequency]`` everywhere.

>>> import era
>>> frf = era.simulate_truth_model()            # the thesis's 4-mass truth model
>>> found = era.identify(frf, states=8, hankel_factor=4, pad_to=1024)
>>> [round(f, 2) for f in found.frequency_hz]   # Table 5.2
[1748.64, 5031.8, 7709.75, 9458.39]

Time histories of forces and responses, ``data`` of shape (channels, samples), go
through ``era.identify_time(data, sample_rate_hz, inputs, outputs)``: the Markov
parameters from OKID's observer (``markov="okid"``) or the Welch H1 FRFs
(``markov="frf"``), the model fitted and judged against the H1 FRFs.

Responses alone, to unmeasured forces (operational modal analysis), go through
``era.oma(data, sample_rate_hz)``: SSI-cov or NExT-ERA on the output correlations,
modes with ``frequency_std_hz`` and ``damping_ratio_std`` from a jackknife.

A fleet of records (a monitored structure's every ten minutes, a campaign's runs) goes
through ``era.process_record(path_or_arrays, verb="oma", **options)``: one record in, a
dict of plain values and numpy arrays out, a picklable task for ``concurrent.futures``,
Dask or Ray.

Thesis names (Woods 1994, Appendix J) beside ours: ``states`` = ns, ``hankel_factor``
= lh, ``integrations`` = ni, ``zero_lines`` = nz, ``pad_to`` = ndpts, ``lowpass`` =
(ford, Hzbreak), ``time_domain`` = cord.

Errors: bad values and malformed files raise ``ValueError`` with the CLI's message, a
missing file ``FileNotFoundError``, a folder ``IsADirectoryError``, an unreadable one ``OSError``; a value of the wrong
type ``TypeError``. Heavy calls release the GIL, so threads identify in parallel.
"""

from ._era import (
    FrfData,
    Identification,
    Mode,
    __version__,
    estimate_frf,
    identify,
    identify_time,
    oma,
    read_frf,
    read_geometry,
    read_time,
    simulate_modal,
    simulate_truth_model,
    write_frf,
)
from . import friction
from .fleet import process_record

__all__ = [
    "FrfData",
    "Identification",
    "Mode",
    "__version__",
    "estimate_frf",
    "friction",
    "identify",
    "identify_time",
    "oma",
    "process_record",
    "read_frf",
    "read_geometry",
    "read_time",
    "simulate_modal",
    "simulate_truth_model",
    "write_frf",
]
