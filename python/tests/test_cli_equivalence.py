"""The Python package gives the CLI's answer on the same file: model.json's eigenvalues
to 1e-10 (they are computed by the same code, so in fact to the last bit), and the
same singular values, matrices and parameters."""

import json

import numpy as np
import pytest

import era
from settings import DTA_FLAGS, DTA_SETTINGS, TRUTH_FLAGS, TRUTH_SETTINGS


def eigenvalues_of(model: dict) -> np.ndarray:
    return np.array([m["eigenvalue_re"] + 1j * m["eigenvalue_im"] for m in model["modes"]])


def cli_model(era_cli, path, *flags) -> dict:
    done = era_cli("identify", path, *flags, "--json", "--quiet")
    return json.loads(done.stdout)


THESIS = ["--preset", "thesis"]
CASES = [
    # file written by, CLI flags, Python keywords
    ("truth.csv", THESIS + ["--states", "8", *TRUTH_FLAGS],
     dict(states=8, **TRUTH_SETTINGS, preset="thesis")),
    ("truth.uff", THESIS + ["--states", "8", *TRUTH_FLAGS, "--time-domain", "continuous"],
     dict(states=8, **TRUTH_SETTINGS, time_domain="continuous", preset="thesis")),
    ("dta.mat", THESIS + ["--states", "80", *DTA_FLAGS],
     dict(states=80, **DTA_SETTINGS, preset="thesis")),
    ("dta.csv", THESIS + ["--states", "40", "--lowpass-hz", "12", "--lowpass-order", "6", "--direct-term", "markov0", "--svd", "matrix-free"],
     dict(states=40, lowpass=(6, 12.0), direct_term="markov0", svd="matrix-free", preset="thesis")),
    # The default route (measured: refinement, continuous time) gives the same model too.
    ("truth.csv", ["--states", "8", *TRUTH_FLAGS],
     dict(states=8, **TRUTH_SETTINGS)),
]


@pytest.fixture(scope="module")
def files(tmp_path_factory, era_cli):
    """Files written by the CLI itself, so that the reading side is compared too."""
    d = tmp_path_factory.mktemp("cli")
    era_cli("simulate", "truth-model", "--noise", "0.15", "--seed", "3", "--out", d / "truth.csv", "--quiet")
    era_cli("simulate", "truth-model", "--noise", "0.15", "--seed", "3", "--out", d / "truth.uff", "--quiet")
    for name in ("dta.mat", "dta.csv"):
        era_cli("simulate", "modal", "--collocated", "--noise", "0.05", "--out", d / name, "--quiet")
    return d


@pytest.mark.parametrize("name,flags,keywords", CASES, ids=[c[0] + ":" + c[2].get("time_domain", c[2].get("svd", "")) + ":" + c[2].get("preset", "measured") for c in CASES])
def test_python_equals_cli_model_json(files, era_cli, name, flags, keywords):
    path = files / name
    expected = cli_model(era_cli, path, *flags)
    found = era.identify(era.read_frf(path), **keywords)

    want = eigenvalues_of(expected)
    got = found.eigenvalues
    assert got.shape == want.shape and len(want) > 0
    assert np.max(np.abs(got - want)) <= 1e-10 * max(1.0, np.max(np.abs(want)))

    assert np.allclose(found.singular_values, expected["singular_values"], rtol=1e-10, atol=0)
    assert np.allclose(found.frequency_hz, [m["frequency_hz"] for m in expected["modes"]], rtol=1e-10)
    assert np.allclose(found.damping_ratio, [m["damping_ratio"] for m in expected["modes"]], rtol=1e-9, atol=1e-12)
    for key in ("a", "b", "c", "d"):
        assert np.allclose(getattr(found, key), np.array(expected[key]), rtol=1e-10, atol=1e-300), key

    # to_json() is model.json: same keys, same parameters, same numbers.
    mine = json.loads(found.to_json())
    assert mine.keys() == expected.keys()
    assert mine["parameters"] == expected["parameters"]
    assert mine["hankel"] == expected["hankel"]
    assert mine["time_domain"] == expected["time_domain"] == found.time_domain
    assert np.allclose(eigenvalues_of(mine), want, rtol=0, atol=1e-10 * max(1.0, np.max(np.abs(want))))


def test_fit_matches_fit_json(files, era_cli, tmp_path):
    path = files / "truth.csv"
    era_cli("identify", path, "--states", "8", *TRUTH_FLAGS, "--out", tmp_path / "out", "--quiet")
    expected = json.loads((tmp_path / "out" / "fit.json").read_text())
    found = era.identify(era.read_frf(path), 8, **TRUTH_SETTINGS)
    fit = found.fit
    assert fit["lines"] == expected["lines"] and fit["first_line"] == expected["first_line"]
    assert [(p["output"], p["input"]) for p in fit["pairs"]] == [(p["output"], p["input"]) for p in expected["pairs"]]
    mine = np.array([p["relative_error"] for p in fit["pairs"]])
    theirs = np.array([p["relative_error"] for p in expected["pairs"]])
    assert np.allclose(mine, theirs, rtol=1e-10)
    # The (q, p) grid holds the same numbers as the pairs.
    for p in fit["pairs"]:
        assert fit["relative_error"][p["output"] - 1, p["input"] - 1] == p["relative_error"]


def test_estimate_frf_equals_era_frf(data_dir, era_cli, tmp_path):
    """DaISy steel subframe: Python's H1 estimate equals `era frf`'s CSV."""
    mat = data_dir / "daisy-steel-subframe" / "flexible_structure_dat.mat"
    out = tmp_path / "subframe.csv"
    era_cli("frf", mat, "--inputs", "1,2", "--outputs", "3-30", "--sample-rate", "1024",
            "--frame", "1024", "--out", out, "--quiet")
    data, rate, _ = era.read_time(mat)
    assert data.shape == (30, 8523) and rate is None
    frf, coherence = era.estimate_frf(data, 1024.0, [0, 1], list(range(2, 30)), 1024)
    cli = era.read_frf(out)
    assert (frf.outputs, frf.inputs, frf.lines) == (cli.outputs, cli.inputs, cli.lines) == (28, 2, 513)
    assert np.array_equal(frf.frequency_hz, cli.frequency_hz)
    scale = np.max(np.abs(cli.values))
    assert np.max(np.abs(frf.values - cli.values)) <= 1e-12 * scale
    assert coherence.shape == (28, 2, 513)
    assert np.all((coherence >= 0) & (coherence <= 1 + 1e-12))


def test_friction_estimate_equals_cli(era_cli, tmp_path):
    record = tmp_path / "decay.csv"
    era_cli("friction", "simulate", "--coulomb-force", "0.05", "--stiffness", "1.0",
            "--noise", "0.01", "--seed", "4", "--out", record, "--quiet")
    expected = json.loads(era_cli("friction", "estimate", record, "--stiffness", "1.0", "--json", "--quiet").stdout)
    row = expected["records"][0]
    lines = [ln for ln in record.read_text().splitlines() if ln and not ln.startswith("#")]
    header = lines[0].split(",")
    table = np.array([[float(x) for x in ln.split(",")] for ln in lines[1:]])
    time_s = table[:, header.index("time_s")]
    velocity = table[:, header.index("velocity")]
    found = era.friction.estimate(time_s, velocity, 1.0)
    for key, value in row.items():
        if key == "file":
            continue
        if isinstance(value, float):
            assert found[key] == pytest.approx(value, rel=1e-12, abs=1e-15), key
        else:
            assert found[key] == value, key
    assert found["stiffness"] == 1.0
