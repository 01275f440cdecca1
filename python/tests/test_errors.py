"""Every error path: bad values raise ValueError, files FileNotFoundError / OSError /
ValueError, wrong types TypeError, each with the CLI's message; none raises pyo3's
PanicException (a BaseException, which these pytest.raises would let through)."""

import os
import re

import numpy as np
import pytest

import era
from settings import TRUTH_SETTINGS as TRUTH


@pytest.fixture(scope="module")
def truth():
    return era.simulate_truth_model()


def as_python(cli_message: str) -> str:
    """The CLI's message with its flags under their Python names."""
    text = re.sub(r"--([a-z0-9-]+)", lambda m: m.group(1).replace("-", "_"), cli_message)
    return text.replace("lowpass_hz", "lowpass").replace("lowpass_order", "lowpass order")


def cli_error(era_cli, *args) -> str:
    done = era_cli(*args, check=False)
    assert done.returncode == 2, done.stderr
    line = done.stderr.strip().splitlines()[-1]
    assert line.startswith("era: error: ")
    return line[len("era: error: "):]


# --- FrfData -------------------------------------------------------------------------

def test_frfdata_values_are_validated_like_a_file():
    f = np.arange(5) * 2.0
    v = np.ones((1, 2, 5), complex)
    v[0, 1, 3] = np.nan
    with pytest.raises(ValueError, match=r"^non-finite value in FRF at output 1, input 2, line 3$"):
        era.FrfData(f, v)
    # A start off the grid of the spacing is refused, with the remedy (one on it is
    # padded with zero lines, as a file's is: test_route.py).
    with pytest.raises(ValueError, match="frequency_hz: the first line is 1 Hz, 0.5000 increments of the 2 Hz spacing"):
        era.FrfData(f + 1, np.ones((1, 1, 5)))
    with pytest.raises(ValueError, match="not uniformly spaced: line 2 is 5 Hz, expected 4 Hz"):
        era.FrfData([0, 2, 5, 6, 8], np.ones((1, 1, 5)))
    with pytest.raises(ValueError, match="need at least 2 frequency lines, got 1"):
        era.FrfData([0.0], np.ones((1, 1, 1)))
    with pytest.raises(ValueError, match=r"^non-finite value in frequency at line 1$"):
        era.FrfData([0, np.inf], np.ones((1, 1, 2)))
    with pytest.raises(ValueError, match=r"^frequencies must increase from 0 Hz: line 1 is -12.5 Hz$"):
        era.FrfData([0, -12.5, -25], np.ones((1, 1, 3)))
    with pytest.raises(ValueError, match=r"values: expected 3 dimensions \(outputs, inputs, lines\), got shape \(2, 5\)"):
        era.FrfData(f, np.ones((2, 5)))
    with pytest.raises(ValueError, match="frequency_hz: expected 1 dimension "):
        era.FrfData(np.zeros((2, 2)), np.ones((1, 1, 2)))
    with pytest.raises(ValueError, match="inconsistent shapes: frequency lines.*expected 5, got 4"):
        era.FrfData(f, np.ones((1, 1, 4)))
    with pytest.raises(ValueError, match="inconsistent shapes: number of outputs and inputs"):
        era.FrfData(f, np.ones((0, 1, 5)))
    with pytest.raises(ValueError, match="quantity 'force': expected 'acceleration', 'velocity' or 'displacement'"):
        era.FrfData(f, np.ones((1, 1, 5)), quantity="force")
    # Text is not a number: the wrong type, named (issue 36).
    with pytest.raises(TypeError, match="values: expected an array of real or complex numbers, got dtype <U1"):
        era.FrfData(f, [[["a"] * 5]])


# --- identify ------------------------------------------------------------------------

@pytest.mark.parametrize("kwargs,message", [
    (dict(states=0), "states 0: the model needs at least one state"),
    (dict(states=-3), "states -3: cannot be negative"),
    (dict(states="eight"), "states 'eight': expected a number of states"),
    (dict(states=8, hankel_factor=0), "hankel_factor 0: must be at least 1"),
    (dict(states=10**30), "states: more than 1.8e19 states asked for, the limit is 20000 (set ERA_MAX_STATES to raise it)"),
    (dict(states=30000), "states: 30000 states asked for, the limit is 20000"),
    (dict(states=8, pad_to=10**8), "pad_to (lines, pad-to + 1): 100000001 frequency lines asked for"),
    (dict(states=8, lowpass=(0, 100.0)), "lowpass order 0: the Butterworth order must be 1 to 20"),
    (dict(states=8, lowpass=-5.0), "lowpass -5: must be a positive frequency"),
    (dict(states=8, lowpass=float("nan")), "lowpass NaN: must be a positive frequency"),
    (dict(states=8, lowpass="fast"), "lowpass 'fast': expected a cut-off in Hz or (order, cut-off Hz)"),
    (dict(states=8, time_domain="z"), "time_domain 'z': expected 'discrete' or 'continuous'"),
    (dict(states=8, direct_term="one"), "direct_term 'one': expected 'zero' or 'markov0'"),
    (dict(states=8, svd="lanczos"), "svd 'lanczos': expected 'auto', 'dense' or 'matrix-free'"),
    (dict(states=8, refine=True, residuals="sideways"), "residuals 'sideways': expected"),
    (dict(states=8, refine=True, weighting="loud"), "weighting 'loud': expected"),
    (dict(states=8, refine=True, max_iterations=0), "max_iterations 0: the refinement needs at least one iteration"),
    (dict(states=8, hankel_factor=400), "the Hankel matrix needs"),
    (dict(states=8, zero_lines=10**6), "invalid parameter zero_lines = 1000000: the data has only"),
    (dict(states=8, pad_to=5), "invalid parameter pad_to = 5: padding to 6 lines would truncate"),
    (dict(states=8, integrations=3), "integrat"),
])
def test_identify_refuses_bad_parameters(truth, kwargs, message):
    with pytest.raises(ValueError) as caught:
        era.identify(truth, **kwargs)
    assert message in str(caught.value)


@pytest.mark.parametrize("kwargs", [dict(states=8.0), dict(states=True), dict(states=8, hankel_factor=2.5), dict(states=[8])])
def test_identify_refuses_wrong_types(truth, kwargs):
    with pytest.raises(TypeError):
        era.identify(truth, **kwargs)


def test_identify_needs_an_frfdata():
    with pytest.raises(TypeError):
        era.identify(np.ones((1, 1, 5)), 2)


def test_all_zero_data(tmp_path):
    zero = era.FrfData(np.arange(64.0), np.zeros((1, 1, 64)))
    with pytest.raises(ValueError, match="every FRF value is zero: there is nothing to identify"):
        era.identify(zero, 2)


def test_response_refuses_non_finite_frequencies(truth):
    found = era.identify(truth, 8, **TRUTH)
    with pytest.raises(ValueError, match="frequency_hz: non-finite value NaN at index 1"):
        found.response([0.0, np.nan])
    with pytest.raises(ValueError, match="frequency_hz: expected 1 dimension "):
        found.response(np.zeros((2, 2)))


@pytest.mark.parametrize("flags,kwargs", [
    (["--states", "0"], dict(states=0)),
    (["--states", "8", "--hankel-factor", "0"], dict(states=8, hankel_factor=0)),
    (["--states", "30000"], dict(states=30000)),
    (["--states", "8", "--hankel-factor", "400"], dict(states=8, hankel_factor=400)),
    (["--states", "8", "--lowpass-hz", "-5"], dict(states=8, lowpass=-5.0)),
    (["--states", "8", "--lowpass-hz", "100", "--lowpass-order", "30"], dict(states=8, lowpass=(30, 100.0))),
    (["--states", "8", "--pad-to", "100000000"], dict(states=8, pad_to=10**8)),
])
def test_identify_messages_are_the_clis(truth, tmp_path, era_cli, flags, kwargs):
    path = tmp_path / "truth.csv"
    era.write_frf(path, truth)
    expected = as_python(cli_error(era_cli, "identify", path, *flags))
    with pytest.raises(ValueError) as caught:
        era.identify(era.read_frf(path), **kwargs)
    # The CLI adds "identifying FILE: " before the core's own errors, which are passed
    # on word for word, the options they quote named as flags there and keywords here.
    raw = cli_error(era_cli, "identify", path, *flags)
    assert expected.endswith(str(caught.value)) or raw.endswith(str(caught.value)), (raw, str(caught.value))


# --- files ---------------------------------------------------------------------------

def test_missing_file_is_file_not_found(tmp_path, era_cli):
    missing = tmp_path / "absent.csv"
    with pytest.raises(FileNotFoundError) as caught:
        era.read_frf(missing)
    assert str(missing) in str(caught.value)
    assert str(caught.value) in cli_error(era_cli, "identify", missing, "--states", "8")


@pytest.mark.parametrize("text,where", [
    ("frequency_hz,H1_1_re,H1_1_im\n0,1,0\n1,x,0\n", "line 3"),
    ("frequency_hz,H1_1_re\n0,1\n", "H1_1_im"),
    ("", "the file is empty"),
])
def test_malformed_files_are_value_errors_naming_the_file(tmp_path, era_cli, text, where):
    path = tmp_path / "bad.csv"
    path.write_text(text)
    with pytest.raises(ValueError) as caught:
        era.read_frf(path)
    message = str(caught.value)
    assert str(path) in message and where in message
    assert message in cli_error(era_cli, "info", path)


def test_mat_frequency_variable(tmp_path, truth, era_cli):
    path = tmp_path / "truth.mat"
    era.write_frf(path, truth)
    named = era.read_frf(path, freq_variable="FreqV")
    np.testing.assert_array_equal(named.frequency_hz, truth.frequency_hz)
    with pytest.raises(ValueError) as caught:
        era.read_frf(path, freq_variable="f_hz")
    message = str(caught.value)
    assert "no numeric variable f_hz" in message and "FreqV 1025x1" in message
    assert message in cli_error(era_cli, "identify", path, "--states", "8", "--freq-variable", "f_hz")


def test_folder_and_wrong_format(tmp_path):
    with pytest.raises(IsADirectoryError, match="is a folder, not a file: name a file inside it") as caught:
        era.read_frf(tmp_path)
    assert str(tmp_path) in str(caught.value)
    named = tmp_path / "fake.uff"
    named.write_text("frequency_hz,H1_1_re,H1_1_im\n")
    with pytest.raises(ValueError, match="the name says UFF but the content does not start like one"):
        era.read_frf(named)
    with pytest.raises(ValueError, match="outputs -1: cannot be negative"):
        era.read_frf(named, outputs=-1)
    with pytest.raises(ValueError, match="quantity 'jerk'"):
        era.read_frf(named, quantity="jerk")


@pytest.mark.skipif(os.geteuid() == 0, reason="root reads any file")
def test_unreadable_file_is_permission_error(tmp_path):
    path = tmp_path / "locked.csv"
    path.write_text("x")
    path.chmod(0)
    with pytest.raises(PermissionError):
        era.read_frf(path)


def test_write_errors(tmp_path, truth):
    with pytest.raises(ValueError, match="cannot tell the output format from the extension"):
        era.write_frf(tmp_path / "h.xyz", truth)
    with pytest.raises(ValueError, match=r"binary=True applies to UFF output \(.uff, .unv\), not to CSV"):
        era.write_frf(tmp_path / "h.csv", truth, binary=True)
    with pytest.raises(OSError) as caught:
        era.write_frf(tmp_path / "no" / "such" / "folder" / "h.csv", truth)
    assert "h.csv" in str(caught.value)
    assert not (tmp_path / "no").exists()
    with pytest.raises(TypeError):
        era.write_frf(tmp_path / "h.csv", "not an FrfData")


def test_read_time_errors(tmp_path):
    with pytest.raises(FileNotFoundError):
        era.read_time(tmp_path / "absent.mat")
    bad = tmp_path / "t.csv"
    bad.write_text("time_s,a\n0,2\n0.1,oops\n")
    with pytest.raises(ValueError, match="line 3"):
        era.read_time(bad)


# --- estimate_frf --------------------------------------------------------------------

@pytest.fixture(scope="module")
def record():
    rng = np.random.default_rng(2)
    x = rng.standard_normal(4096)
    return np.vstack([x, np.convolve(x, [1.0, 0.5, 0.25])[:4096]])


@pytest.mark.parametrize("kwargs,message", [
    (dict(window="kaiser"), "window 'kaiser': expected 'hann', 'rectangular' or 'flat-top'"),
    (dict(estimator="h3"), "estimator 'h3': expected 'h1', 'h2' or 'hv'"),
    (dict(detrend="cubic"), "detrend 'cubic': expected 'none', 'mean' or 'linear'"),
    (dict(quantity="force"), "quantity 'force'"),
    (dict(sample_rate_hz=-1.0), "sample_rate_hz -1: must be a positive number of samples per second"),
    (dict(frame=-2), "frame -2: cannot be negative"),
    (dict(frame=0), "frame"),
    (dict(frame=10**6), "frame"),
    (dict(overlap=1.0), "overlap"),
    (dict(inputs=[5]), "inputs: channel 5 is out of range: data has 2 channels (0-based, axis 0)"),
    (dict(outputs=[]), "outputs: give at least one channel"),
    (dict(inputs=[-1]), "inputs -1: cannot be negative"),
])
def test_estimate_frf_refuses_bad_parameters(record, kwargs, message):
    args = dict(sample_rate_hz=100.0, inputs=[0], outputs=[1], frame=256)
    args.update(kwargs)
    with pytest.raises(ValueError) as caught:
        era.estimate_frf(record, **args)
    assert message in str(caught.value)


def test_estimate_frf_refuses_bad_data(record):
    bad = record.copy()
    bad[1, 100] = np.inf
    with pytest.raises(ValueError, match="non-finite sample in output 1 at sample 100"):
        era.estimate_frf(bad, 100.0, [0], [1], 256)
    with pytest.raises(ValueError, match=r"data: expected 2 dimensions \(channels, samples\)"):
        era.estimate_frf(record[0], 100.0, [0], [0], 256)
    with pytest.raises(ValueError, match="singular"):
        era.estimate_frf(np.vstack([record[0], record[0], record[1]]), 100.0, [0, 1], [2], 256)


# --- simulators and friction ---------------------------------------------------------

@pytest.mark.parametrize("kwargs,flags", [
    (dict(noise=-0.1), ["--noise", "-0.1"]),
    (dict(noise=float("inf")), ["--noise", "inf"]),
    (dict(fmax=30.0), ["--fmax", "30"]),
    (dict(df=0.0), ["--df", "0"]),
    (dict(fmin=-1.0), ["--fmin", "-1"]),
    (dict(collocated=True, inputs=2), ["--collocated", "--inputs", "2"]),
    (dict(outputs=5000), ["--outputs", "5000"]),
    (dict(lines=10**8), ["--lines", "100000000"]),
])
def test_simulate_modal_messages_are_the_clis(tmp_path, era_cli, kwargs, flags):
    expected = as_python(cli_error(era_cli, "simulate", "modal", "--out", tmp_path / "x.csv", *flags))
    with pytest.raises(ValueError) as caught:
        era.simulate_modal(**kwargs)
    assert str(caught.value) == expected


def test_simulate_truth_model_errors(tmp_path, era_cli):
    expected = as_python(cli_error(era_cli, "simulate", "truth-model", "--noise", "2000", "--out", tmp_path / "t.csv"))
    with pytest.raises(ValueError) as caught:
        era.simulate_truth_model(noise=2000)
    assert str(caught.value) == expected
    with pytest.raises(ValueError, match="seed -1: cannot be negative"):
        era.simulate_truth_model(seed=-1)
    with pytest.raises(ValueError, match="modes -1: cannot be negative"):
        era.simulate_modal(modes=-1)


def test_friction_errors(era_cli, tmp_path):
    t = np.linspace(0, 10, 2001)
    v = np.exp(-0.1 * t) * np.sin(2 * np.pi * 1.5 * t)
    expected = as_python(cli_error(era_cli, "friction", "estimate", tmp_path / "x.csv", "--stiffness", "0"))
    with pytest.raises(ValueError) as caught:
        era.friction.estimate(t, v, 0.0)
    assert str(caught.value) == expected
    with pytest.raises(ValueError, match="stiffness NaN: must be a positive stiffness"):
        era.friction.estimate(t, v, float("nan"))
    with pytest.raises(ValueError, match="same length"):
        era.friction.estimate(t, v[:-1], 1.0)
    with pytest.raises(ValueError):
        era.friction.estimate(t[:10], v[:10], 1.0)
    bad = v.copy()
    bad[7] = np.nan
    with pytest.raises(ValueError, match="non-finite"):
        era.friction.estimate(t, bad, 1.0)
    backwards = t.copy()
    backwards[50] = backwards[49]
    with pytest.raises(ValueError):
        era.friction.estimate(backwards, v, 1.0)


def test_signatures_show_the_defaults():
    # help() and editors read these: the real defaults, not "..." placeholders.
    import inspect

    identify = inspect.signature(era.identify).parameters
    assert identify["hankel_factor"].default == 5
    # The route's choices default to None: the preset (measured) fills them.
    assert identify["time_domain"].default is None
    assert identify["refine"].default is None
    assert identify["preset"].default == "measured"
    assert str(identify["states"]).endswith("'auto'")
    assert inspect.signature(era.simulate_modal).parameters["modes"].default == 40
    assert inspect.signature(era.simulate_truth_model).parameters["seed"].default == 1
