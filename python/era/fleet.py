"""One record of a fleet as one pure function: ``process_record``.

A monitored structure gives a record every few minutes; a test campaign hundreds of
runs. Each record is identified the same way, and the loop over them belongs to an
engine that already exists: ``concurrent.futures``, Dask, Ray. ``process_record`` is
the task such an engine runs: a module-level function (so it pickles by name) of a
path or arrays and keywords, returning a dict of plain Python values and numpy arrays
(cheap to send between processes and machines). The work is era's Rust core, which
releases the GIL, so threads run records side by side too.

>>> import era
>>> row = era.process_record("rec_0001.csv", outputs=[2, 3, 4, 5], threads=1)  # doctest: +SKIP
>>> row["frequency_hz"], row["physical"]  # doctest: +SKIP
"""

import os
import time
from typing import Any, Dict, List, Optional, Sequence, Tuple

import numpy as np

from ._era import FrfData, identify, identify_time, oma, read_frf, read_time

__all__ = ["process_record", "VERBS"]

VERBS = ("oma", "identify")

# Keywords of each verb: its Python function's (but the data), and what reads a path.
_OMA = ("sample_rate_hz", "outputs", "references", "method", "states", "time_lags", "blocks",
        "threads")
_IDENTIFY = ("states", "hankel_factor", "integrations", "zero_lines", "pad_to", "lowpass",
             "time_domain", "direct_term", "svd", "era_dc", "refine", "residuals", "reciprocal",
             "weighting", "max_iterations", "added_modes", "band", "preset", "threads")
_IDENTIFY_TIME = ("sample_rate_hz", "inputs", "outputs", "states", "markov", "observer_order",
                  "markov_samples", "era_dc", "frame", "window", "overlap", "estimator",
                  "detrend", "quantity", "hankel_factor", "lowpass", "time_domain", "direct_term",
                  "svd", "refine", "residuals", "weighting", "max_iterations", "added_modes",
                  "band", "preset", "threads")
_READ_TIME = ("variables", "datasets")
_READ_FRF = ("quantity", "outputs", "freq_variable")

_KNOWN = {
    "oma": sorted(set(_OMA + _READ_TIME)),
    "identify": sorted(set(_IDENTIFY + _IDENTIFY_TIME + _READ_TIME + _READ_FRF)),
}


def process_record(path_or_arrays: Any, verb: str = "oma", **options: Any) -> Dict[str, Any]:
    """Identifies one record and returns its modes as plain values and numpy arrays.

    Parameters
    ----------
    path_or_arrays : str, os.PathLike, array_like, or a list of them
        A time file (CSV with a ``time_s`` column, MAT v5 or HDF5, as ``era oma`` reads
        them), a numpy array (channels, samples), or a list of files or of arrays:
        records of one test, pooled (``oma``). With ``verb="identify"`` also an FRF
        file (CSV, UFF 58, MAT) or an ``era.FrfData``.
    verb : {"oma", "identify"}
        ``"oma"``: output-only, as ``era.oma`` (and ``era oma FILE --json``).
        ``"identify"``: FRFs (a file or ``FrfData``) as ``era.identify``; time histories
        with ``inputs=`` and ``outputs=`` (arrays, or a time file) as
        ``era.identify_time`` (``era identify --from-time``).
    **options
        The keywords of that verb's function: for ``oma`` ``outputs``,
        ``sample_rate_hz``, ``references``, ``method``, ``states``, ``time_lags``,
        ``blocks``, ``threads``; for ``identify`` those of ``era.identify`` or
        ``era.identify_time``. Reading a file: ``variables`` (MAT) and ``datasets``
        (HDF5) as ``era.read_time``; ``quantity``, ``freq_variable`` and ``outputs`` (a
        count) as ``era.read_frf``. ``sample_rate_hz`` is the file's unless given (a MAT
        file needs it); arrays need it. On a file, ``outputs`` and ``references`` may
        name channels by their names in the file as well as by 0-based index.

    Returns
    -------
    dict
        Per mode (arrays of one entry a mode, by frequency): ``frequency_hz``,
        ``damping_ratio``, ``frequency_std_hz`` and ``damping_ratio_std`` (NaN where the
        run gives none), ``physical`` (bool; False where the run did not judge),
        ``mpc``, ``emac`` (NaN where not computed) and ``shapes`` (complex, outputs ×
        modes, unscaled for ``oma``). And ``states`` (the model's order), ``judged``
        (whether the run judged the modes physical), ``sample_rate_hz`` (time records),
        ``verb``, ``seconds`` (wall time of the call) and ``source`` (the path, the paths
        joined by ``;``, or ``"arrays"``).

    Raises
    ------
    ValueError
        An unknown verb or keyword (naming it and listing the known ones), a bad value,
        a malformed file (the CLI's messages).
    OSError
        A file that is missing or cannot be read (``FileNotFoundError``,
        ``PermissionError``, ``IsADirectoryError``), naming the path.
    """
    clock = time.perf_counter()
    if not isinstance(verb, str) or verb not in _KNOWN:
        raise ValueError(f"verb {verb!r}: expected one of {', '.join(map(repr, VERBS))}")
    unknown = [k for k in options if k not in _KNOWN[verb]]
    if unknown:
        raise ValueError(
            f"{verb}: unknown keyword{'s' if len(unknown) > 1 else ''} "
            f"{', '.join(map(repr, unknown))}; the known ones are: {', '.join(_KNOWN[verb])}")
    if verb == "oma":
        found, rate, source = _oma(path_or_arrays, options)
    else:
        found, rate, source = _identify(path_or_arrays, options)
    row = _modes_of(found)
    row.update(verb=verb, sample_rate_hz=rate, source=source,
               seconds=time.perf_counter() - clock)
    return row


def _is_path(value: Any) -> bool:
    return isinstance(value, (str, os.PathLike))


def _paths_of(record: Any) -> Optional[List[Any]]:
    """The record as a list of paths, or None when it is arrays; a ValueError for
    anything else (None, a mix of paths and arrays)."""
    if _is_path(record):
        return [record]
    if isinstance(record, (list, tuple)):
        paths = [_is_path(p) for p in record]
        if record and all(paths):
            return list(record)
        if any(paths):
            raise ValueError("path_or_arrays: a list of paths or a list of arrays, not both")
        return None
    if isinstance(record, np.ndarray) or hasattr(record, "__array__"):
        return None
    raise ValueError("path_or_arrays: expected a path (str or os.PathLike), a list of paths, "
                     f"or arrays (channels, samples); got {type(record).__name__}")


def _source(paths: Optional[List[Any]]) -> str:
    return "arrays" if paths is None else ";".join(os.fspath(p) for p in paths)


def _read(paths: List[Any], options: Dict[str, Any]) -> Tuple[List[np.ndarray], float, Optional[List[str]]]:
    """The time files as records, their common sample rate (given or the files'), and
    the first file's channel names."""
    given = options.pop("sample_rate_hz", None)
    selection = {k: options.pop(k) for k in _READ_TIME if k in options}
    records, rate, names = [], None, None
    for path in paths:
        # The reader on the call's threads too: a task given one thread stays on one.
        data, file_rate, file_names = read_time(path, threads=options.get("threads"), **selection)
        here = given if given is not None else file_rate
        if here is None:
            raise ValueError(f"{os.fspath(path)}: this file does not give the sample rate: "
                             "set sample_rate_hz")
        if rate is None:
            rate, names = here, file_names
        elif abs(here - rate) > 1e-9 * rate:
            raise ValueError(f"{os.fspath(path)}: sample rate {here} Hz, the first file's is "
                             f"{rate} Hz: records of one test must share it")
        records.append(data)
    return records, float(rate), names


def _channels(keyword: str, value: Any, names: Optional[List[str]]) -> Any:
    """Channels given by name (a file's names) as 0-based indices; others as given."""
    if isinstance(value, str):
        value = [value]
    if not isinstance(value, (list, tuple)):
        return value
    out = []
    for c in value:
        if isinstance(c, str):
            if names is None or c not in names:
                have = f"the file has: {', '.join(names)}" if names else "the file has no channel names"
                raise ValueError(f"{keyword}: no channel named {c!r} ({have})")
            out.append(names.index(c))
        else:
            out.append(c)
    return out


def _array_rate(options: Dict[str, Any]) -> float:
    """The sample rate of a record given as arrays (taken out of `options`), which no
    file-reading keyword may accompany."""
    for k in _READ_TIME:
        if k in options:
            raise ValueError(f"{k}: reads a file; the record here is arrays")
    if options.get("sample_rate_hz") is None:
        raise ValueError("sample_rate_hz: arrays need the sample rate (a file may give it)")
    return float(options.pop("sample_rate_hz"))


def _oma(record: Any, options: Dict[str, Any]) -> Tuple[Any, float, str]:
    options = dict(options)
    paths = _paths_of(record)
    if paths is None:
        rate = _array_rate(options)
        return oma(record, rate, **options), rate, "arrays"
    records, rate, names = _read(paths, options)
    for k in ("outputs", "references"):
        if k in options:
            options[k] = _channels(k, options[k], names)
    data = records[0] if len(records) == 1 else records
    return oma(data, rate, **options), rate, _source(paths)


def _identify(record: Any, options: Dict[str, Any]) -> Tuple[Any, Optional[float], str]:
    options = dict(options)
    if isinstance(record, FrfData) or ("inputs" not in options and _is_path(record)):
        extra = sorted(k for k in options if k not in _IDENTIFY + _READ_FRF)
        if extra:
            raise ValueError(f"identify of FRFs: {', '.join(extra)} are keywords of time "
                             "histories (give inputs= and outputs= for those)")
        reading = {k: options.pop(k) for k in _READ_FRF if k in options}
        if isinstance(record, FrfData):
            if reading:
                raise ValueError(f"{', '.join(reading)}: read a file; the record here is FrfData")
            return identify(record, **options), None, "arrays"
        try:
            frf = read_frf(record, **reading)
        except ValueError as e:
            raise ValueError(f"{e} (time histories need inputs= and outputs=)") from None
        return identify(frf, **options), None, os.fspath(record)
    extra = sorted(k for k in options if k not in _IDENTIFY_TIME + _READ_TIME)
    if extra:
        raise ValueError(f"identify of time histories: {', '.join(extra)} are keywords of FRFs")
    for k in ("inputs", "outputs"):
        if k not in options:
            raise ValueError(f"identify of time histories needs {k}= (0-based channels)")
    paths = _paths_of(record)
    if paths is None:
        rate = _array_rate(options)
        data = record
        names = None
    else:
        records, rate, names = _read(paths, options)
        if len(records) > 1:
            raise ValueError("identify of time histories takes one file")
        data = records[0]
    if isinstance(data, (list, tuple)) and len(data) == 1 and np.ndim(data[0]) == 2:
        data = data[0]
    for k in ("inputs", "outputs"):
        options[k] = _channels(k, options[k], names)
    inputs, outputs = options.pop("inputs"), options.pop("outputs")
    return identify_time(data, rate, inputs, outputs, **options), rate, _source(paths)


def _modes_of(found: Any) -> Dict[str, Any]:
    """The identification's modes as plain values and numpy arrays."""
    modes = found.modes
    n = len(modes)

    def floats(values: Sequence[Optional[float]]) -> np.ndarray:
        return np.array([np.nan if v is None else float(v) for v in values], dtype=float)

    indicators = [m.indicators or {} for m in modes]
    outputs = found.c.shape[0]
    shapes = np.zeros((outputs, n), dtype=complex)
    for k, m in enumerate(modes):
        shapes[:, k] = m.shape
    return {
        "frequency_hz": floats([m.frequency_hz for m in modes]),
        "damping_ratio": floats([m.damping_ratio for m in modes]),
        "frequency_std_hz": floats([m.frequency_std_hz for m in modes]),
        "damping_ratio_std": floats([m.damping_ratio_std for m in modes]),
        "physical": np.array([bool(m.physical) for m in modes], dtype=bool),
        "mpc": floats([d.get("mpc") for d in indicators]),
        "emac": floats([d.get("emac") for d in indicators]),
        "shapes": shapes,
        "states": int(found.states),
        "judged": bool(n) and all(m.physical is not None for m in modes),
    }
