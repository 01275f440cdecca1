"""era.identify_time: a model from time histories, OKID's or H1's Markov parameters, the
same answer as `era identify --from-time`, and ValueError for what OKID cannot take."""

import json

import numpy as np
import pytest

import era

REFERENCE_HZ = [62.1, 119.0, 154.7, 192.5, 215.0, 229.5, 239.3, 286.8, 321.2, 334.1,
                352.2, 398.1, 417.5, 467.2]


def shaker(era_cli, tmp_path, seed, noise="0.02", duration="60"):
    """A simulated shaker test (2 forces, 8 accelerations, 64 Hz) as (channels,
    samples), and its true frequencies."""
    path = tmp_path / f"shaker{seed}.csv"
    truth = json.loads(era_cli("simulate", "shaker", "--noise", noise, "--seed", seed,
                               "--duration", duration, "--out", path, "--json").stdout)
    data, rate, names = era.read_time(path)
    assert rate == 64.0 and names[:3] == ["force1", "force2", "acc1"]
    return data, sorted(m["frequency_hz"] for m in truth["modes"])


def test_okid_equals_the_cli(era_cli, tmp_path):
    data, truth = shaker(era_cli, tmp_path, 51, duration="300")
    found = era.identify_time(data, 64.0, [0, 1], list(range(2, 10)))
    params = found.parameters
    assert params["markov"] == "okid" and params["okid"]["route"] == "recursion"
    physical = sorted(m.frequency_hz for m in found.modes if m.physical)
    assert len(physical) == 10
    assert max(abs(f - t) / t for f, t in zip(physical, truth)) < 0.01
    cli = json.loads(era_cli("identify", tmp_path / "shaker51.csv", "--from-time", "--inputs", "1-2",
                             "--outputs", "3-10", "--markov", "okid", "--json", "-q").stdout)
    theirs = sorted(m["frequency_hz"] for m in cli["modes"] if m["physical"])
    assert np.allclose(physical, theirs, rtol=1e-9)
    assert cli["parameters"]["okid"]["observer_order"] == params["okid"]["observer_order"]


def test_daisy_subframe_through_okid(data_dir):
    data, _, _ = era.read_time(data_dir / "daisy-steel-subframe" / "flexible_structure_dat.mat")
    found = era.identify_time(data, 1024.0, [0, 1], list(range(2, 30)))
    assert found.parameters["okid"]["route"] == "unit_circle"
    physical = [m.frequency_hz for m in found.modes if m.physical]
    hits = sum(any(abs(f - r) < 0.5 for f in physical) for r in REFERENCE_HZ)
    assert hits >= 12, physical


def test_h1_route_and_era_dc(era_cli, tmp_path):
    data, truth = shaker(era_cli, tmp_path, 52, duration="300")
    h1 = era.identify_time(data, 64.0, [0, 1], list(range(2, 10)), markov="frf", refine=False)
    assert h1.parameters["markov"] == "frf" and "okid" not in h1.parameters
    dc = era.identify_time(data, 64.0, [0, 1], list(range(2, 10)), states=20, era_dc=True)
    assert dc.parameters["realizer"] == "era-dc" and dc.states == 20
    for found in (h1, dc):
        freqs = sorted(m.frequency_hz for m in found.modes if m.physical or found is dc)
        assert all(any(abs(f - t) < 0.02 * t for f in freqs) for t in truth)


def test_refined_okid_model_has_uncertainties(era_cli, tmp_path):
    """refine=True refines OKID's model against the H1 FRFs (weighted by the coherence);
    weighting='coherence' on the FRF route too, and a bad weighting is a ValueError."""
    data, truth = shaker(era_cli, tmp_path, 54)
    found = era.identify_time(data, 64.0, [0, 1], list(range(2, 10)), refine=True)
    physical = [m for m in found.modes if m.physical]
    assert len(physical) >= 8
    assert all(m.frequency_std_hz is not None and m.frequency_std_hz > 0 for m in physical)
    h1 = era.identify_time(data, 64.0, [0, 1], list(range(2, 10)), markov="frf", frame=512,
                           refine=True, weighting="coherence")
    assert any(m.physical for m in h1.modes)
    with pytest.raises(ValueError, match="weighting"):
        era.identify_time(data, 64.0, [0, 1], list(range(2, 10)), refine=True, weighting="arx")


def test_what_okid_cannot_take_is_a_value_error(era_cli, tmp_path):
    data, _ = shaker(era_cli, tmp_path, 53, duration="20")
    ins, outs = [0, 1], list(range(2, 10))
    with pytest.raises(ValueError, match="observer_order = 100: .*needs at least"):
        era.identify_time(data, 64.0, ins, outs, observer_order=100)
    dead = data.copy()
    dead[1] = 0.5
    with pytest.raises(ValueError, match="input"):
        era.identify_time(dead, 64.0, ins, outs)
    twin = data.copy()
    twin[1] = -2.0 * twin[0]
    with pytest.raises(ValueError, match="input"):
        era.identify_time(twin, 64.0, ins, outs)
    nan = data.copy()
    nan[3, 300] = np.nan
    with pytest.raises(ValueError, match="non-finite"):
        era.identify_time(nan, 64.0, ins, outs)
    with pytest.raises(ValueError, match="markov='okid' only"):
        era.identify_time(data, 64.0, ins, outs, markov="frf", observer_order=4)
    with pytest.raises(ValueError, match="markov"):
        era.identify_time(data, 64.0, ins, outs, markov="arx")
    with pytest.raises(ValueError, match="sample_rate_hz"):
        era.identify_time(data, float("nan"), ins, outs)
    with pytest.raises(ValueError, match="outputs: channel 12"):
        era.identify_time(data, 64.0, ins, [2, 12])
    # More Markov blocks than the record holds (10**8 once aborted on 16 GB); the
    # default follows a record shorter than 2048 samples.
    for n in (1281, 10**8):
        with pytest.raises(ValueError, match=f"markov_samples = {n}: the longest record has 1280 samples"):
            era.identify_time(data, 64.0, ins, outs, markov_samples=n)
    short = era.identify_time(data, 64.0, ins, outs, states=20, refine=False)
    assert short.parameters["okid"]["markov_samples"] == 1280
