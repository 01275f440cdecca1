"""FrfData from numpy arrays, and round trips through the files and pickle."""

import pickle

import numpy as np
import pytest

import era
from settings import TRUTH_SETTINGS


def small(q=2, p=3, lines=65, seed=0):
    rng = np.random.default_rng(seed)
    f = np.arange(lines) * 0.5
    v = rng.standard_normal((q, p, lines)) + 1j * rng.standard_normal((q, p, lines))
    return f, v


def test_arrays_read_back_as_given():
    f, v = small()
    frf = era.FrfData(f, v, quantity="velocity")
    assert (frf.outputs, frf.inputs, frf.lines) == (2, 3, 65)
    assert frf.quantity == "velocity"
    assert frf.spacing_hz == 0.5
    assert np.array_equal(frf.values, v) and frf.values.dtype == np.complex128
    assert np.array_equal(frf.frequency_hz, f)
    # The arrays mirror immutable data: numpy refuses writes, and the input array can
    # change afterwards without changing the FrfData.
    with pytest.raises(ValueError):
        frf.values[0, 0, 0] = 1.0
    v[0, 0, 0] = 1e9
    assert frf.values[0, 0, 0] != 1e9


def test_lists_real_arrays_and_fortran_order_are_accepted():
    f, v = small(1, 1, 8)
    assert era.FrfData(list(f), v.real.tolist()).values.dtype == np.complex128
    fortran = np.asfortranarray(small(2, 2, 16)[1])
    frf = era.FrfData(np.arange(16.0), fortran)
    assert np.array_equal(frf.values, fortran)
    assert era.FrfData(f, v.astype(np.complex64)).values.dtype == np.complex128


@pytest.mark.parametrize("ext,binary,exact", [
    ("csv", False, True), ("uff", True, True), ("uff", False, False), ("mat", False, True),
])
def test_file_round_trips(tmp_path, ext, binary, exact):
    f, v = small()
    frf = era.FrfData(f, v, "displacement")
    path = tmp_path / f"h.{ext}"
    era.write_frf(path, frf, binary=binary)
    # A MAT file (FRF + FreqV) does not say what it measures: the reader is told.
    back = era.read_frf(path, quantity="displacement" if ext == "mat" else None)
    assert back.quantity == "displacement"
    assert np.array_equal(back.frequency_hz, f)
    if exact:
        assert back == frf
        assert np.array_equal(back.values, v)
    else:  # ASCII UFF: 13 significant digits in E format
        assert np.allclose(back.values, v, rtol=1e-11, atol=0)
    # read_frf takes str too, and quantity overrides the file's tag.
    assert era.read_frf(str(path), quantity="velocity").quantity == "velocity"


def test_pickle_and_with_quantity():
    f, v = small()
    frf = era.FrfData(f, v)
    again = pickle.loads(pickle.dumps(frf))
    assert again == frf and again is not frf
    assert frf.with_quantity("velocity").quantity == "velocity"
    assert frf.quantity == "acceleration"
    assert frf != "not an FrfData"
    assert "2 outputs x 3 inputs, 65 lines" in repr(frf)


def test_simulators_match_their_cli_shapes():
    truth = era.simulate_truth_model()
    assert (truth.outputs, truth.inputs, truth.lines, truth.quantity) == (3, 3, 1025, "displacement")
    assert truth.frequency_hz[-1] == 12800.0
    noisy = era.simulate_truth_model(noise=0.15, seed=1)
    assert noisy != truth and noisy == era.simulate_truth_model(noise=0.15, seed=1)
    assert era.simulate_truth_model(noise=0.0) == truth
    modal = era.simulate_modal(outputs=3, inputs=2, modes=5, lines=201, df=0.1, fmax=15.0)
    assert (modal.outputs, modal.inputs, modal.lines) == (3, 2, 201)
    found = era.identify(modal, 10, hankel_factor=8, preset="thesis")
    assert len(found.frequency_hz) == 5
    assert np.all((found.frequency_hz > 0.4) & (found.frequency_hz < 15.1))


def test_identification_results_are_plain_numpy():
    found = era.identify(era.simulate_truth_model(), 8, **TRUTH_SETTINGS, preset="thesis")
    n, q, p = 8, 3, 3
    assert found.a.shape == (n, n) and found.b.shape == (n, p)
    assert found.c.shape == (q, n) and found.d.shape == (q, p)
    assert found.states == 8 and found.time_domain == "discrete"
    assert found.sample_time_s == pytest.approx(1 / (2 * 12.5 * 1024))
    assert np.allclose(found.frequency_hz, [1748.64, 5031.80, 7709.75, 9458.39], atol=0.01)
    assert len(found.modes) == 4
    mode = found.modes[0]
    assert mode.frequency_hz == found.frequency_hz[0]
    assert mode.shape.shape == (q,) and mode.participation.shape == (p,)
    assert np.max(np.abs(mode.shape)) == pytest.approx(1.0)
    # The truth model's four modes are judged physical, with near-real shapes.
    assert mode.physical is True
    assert mode.indicators["mpc"] > 0.999
    assert mode.indicators["emac"] > 0.9 and mode.indicators["reason"] is None
    # states="auto" scans the orders and keeps the same four modes.
    auto = era.identify(era.simulate_truth_model(), "auto", **TRUTH_SETTINGS)
    physical = [m.frequency_hz for m in auto.modes if m.physical]
    assert np.allclose(physical, [1748.64, 5031.80, 7709.75, 9458.39], atol=0.01)
    assert found.hankel_size[0] > 0 and isinstance(found.warnings, list)
    assert found.parameters["states"] == 8 and found.parameters["pad_to"] == 1024
    # The model's FRF on the data's lines reproduces the noise-free truth model.
    truth = era.simulate_truth_model()
    model = found.response(truth.frequency_hz)
    assert model.shape == (3, 3, 1025)
    assert np.max(np.abs(model - truth.values)) <= 1e-8 * np.max(np.abs(truth.values))
    assert found.fit["relative_error"].shape == (3, 3)
    assert found.processed == truth


def test_to_control_state_space():
    control = pytest.importorskip("control")
    found = era.identify(era.simulate_truth_model(), 8, **TRUTH_SETTINGS, preset="thesis")
    sys = found.to_control()
    assert isinstance(sys, control.StateSpace)
    assert sys.dt == found.sample_time_s
    assert np.allclose(np.sort_complex(sys.poles()), np.sort_complex(np.linalg.eigvals(found.a)))
    cont = era.identify(era.simulate_truth_model(), 8, **TRUTH_SETTINGS, time_domain="continuous")
    assert cont.to_control().dt == 0


def test_to_control_without_python_control_is_an_import_error(monkeypatch):
    import sys
    monkeypatch.setitem(sys.modules, "control", None)  # import control now fails
    found = era.identify(era.simulate_truth_model(), 8, **TRUTH_SETTINGS)
    with pytest.raises(ImportError, match="pip install control"):
        found.to_control()


def test_estimate_frf_of_a_known_gain():
    rng = np.random.default_rng(5)
    x = rng.standard_normal(8192)
    data = np.vstack([x, 2.5 * x, -x])
    frf, coherence = era.estimate_frf(data, 100.0, [0], [1, 2], 256, window="hann", overlap=0.5)
    assert (frf.outputs, frf.inputs, frf.lines) == (2, 1, 129)
    assert np.allclose(frf.values[0, 0, 1:], 2.5) and np.allclose(frf.values[1, 0, 1:], -1.0)
    assert np.allclose(coherence[:, :, 1:], 1.0)
    assert frf.spacing_hz == pytest.approx(100.0 / 256)
