"""era.oma: output-only modal analysis, the same answer as `era oma`, standard deviations
on every physical mode, several records pooled, and ValueError for what it cannot take."""

import json

import numpy as np
import pytest

import era


def responses(era_cli, tmp_path, seed, duration="300"):
    """A simulated shaker test's 8 accelerations (64 Hz) with the 2 forces left out, as
    (channels, samples); the file; and the true frequencies."""
    path = tmp_path / f"shaker{seed}.csv"
    truth = json.loads(era_cli("simulate", "shaker", "--noise", "0.02", "--seed", seed,
                               "--duration", duration, "--out", path, "--json").stdout)
    data, rate, names = era.read_time(path)
    assert rate == 64.0 and names[:3] == ["force1", "force2", "acc1"]
    return np.ascontiguousarray(data[2:]), path, sorted(m["frequency_hz"] for m in truth["modes"])


def physical(found):
    return [m for m in found.modes if m.physical]


def test_the_modes_of_responses_alone_with_their_spread(era_cli, tmp_path):
    data, _, truth = responses(era_cli, tmp_path, 3)
    found = era.oma(data, 64.0)
    modes = physical(found)
    hits = [f for f in truth if any(abs(m.frequency_hz - f) < 0.01 * f for m in modes)]
    assert len(hits) >= 8, (truth, [m.frequency_hz for m in modes])
    for m in modes:
        assert m.frequency_std_hz > 0 and m.damping_ratio_std > 0
    facts = found.oma
    assert facts["method"] == "ssi-cov" and facts["shapes"] == "unscaled"
    assert facts["references"] == list(range(8)) and facts["outputs"] == list(range(8))
    assert facts["samples"] == data.shape[1] and facts["blocks"] == 6  # the default
    assert len(facts["shape_std"]) == len(found.modes)
    # The other identifications have no such facts.
    assert era.identify(era.simulate_truth_model(), states=8).oma is None


def test_the_same_answer_as_the_command_line(era_cli, tmp_path):
    data, path, _ = responses(era_cli, tmp_path, 5, duration="200")
    found = era.oma(data, 64.0, references=[0, 4], method="next-era", time_lags=160,
                    states=20)
    cli = json.loads(era_cli("oma", path, "--outputs", "3-10", "--references", "3,7",
                             "--method", "next-era", "--time-lags", "160", "--states", "20",
                             "--json", "--quiet").stdout)
    assert cli["method"] == "next-era" and cli["lags"] == 160 and cli["shapes"] == "unscaled"
    assert cli["references"] == [3, 7] and found.oma["references"] == [0, 4]
    assert len(cli["modes"]) == len(found.modes)
    for a, b in zip(cli["modes"], found.modes):
        assert a["frequency_hz"] == pytest.approx(b.frequency_hz, rel=1e-12)
        assert a["damping_ratio"] == pytest.approx(b.damping_ratio, rel=1e-12)
        assert a["physical"] == b.physical
        if b.frequency_std_hz is not None:
            assert a["frequency_std_hz"] == pytest.approx(b.frequency_std_hz, rel=1e-9)


def test_records_are_pooled(era_cli, tmp_path):
    data, _, _ = responses(era_cli, tmp_path, 7, duration="100")
    half = data.shape[1] // 2
    first, second = np.ascontiguousarray(data[:, :half]), np.ascontiguousarray(data[:, half:])
    found = era.oma([first, second], 64.0, states=20, blocks=4)
    assert found.oma["samples"] == first.shape[1] + second.shape[1]
    assert found.states > 0


def test_bad_input_is_a_value_error(era_cli, tmp_path):
    data, _, _ = responses(era_cli, tmp_path, 9, duration="60")
    with pytest.raises(ValueError, match="not among the outputs"):
        era.oma(data, 64.0, outputs=[0, 1, 2], references=[5])
    dead = data.copy()
    dead[3] = 0.0
    with pytest.raises(ValueError, match="channel 3 is constant"):
        era.oma(dead, 64.0)
    nan = data.copy()
    nan[2, 100] = np.nan
    with pytest.raises(ValueError, match="channel 2 of record 1 is not finite at sample 100"):
        era.oma(nan, 64.0)
    with pytest.raises(ValueError, match="time_lags 3000.*twice the lags"):
        era.oma(data, 64.0, time_lags=3000)
    with pytest.raises(ValueError, match="blocks 0"):
        era.oma(data, 64.0, blocks=0)
    with pytest.raises(ValueError, match="method"):
        era.oma(data, 64.0, method="fdd")
    with pytest.raises(ValueError, match="sample_rate_hz"):
        era.oma(data, -1.0)
    with pytest.raises(ValueError, match="same channels"):
        era.oma([data, np.ascontiguousarray(data[:5])], 64.0)
