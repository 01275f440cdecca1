"""`era.identify(..., refine=True)`: the refined model of `era identify --refine`, with
standard deviations on the modes (issue 14)."""

import json

import numpy as np
import pytest

import era
from settings import TRUTH_FLAGS, TRUTH_SETTINGS


@pytest.fixture(scope="module")
def noisy_truth(tmp_path_factory, era_cli):
    d = tmp_path_factory.mktemp("refine")
    path = d / "truth.csv"
    era_cli("simulate", "truth-model", "--noise", "0.15", "--seed", "3", "--out", path, "--quiet")
    return path


def test_refine_gives_the_cli_refined_model(noisy_truth, era_cli):
    frf = era.read_frf(str(noisy_truth))
    found = era.identify(frf, 8, **TRUTH_SETTINGS, refine=True, preset="thesis")
    done = era_cli("identify", noisy_truth, "--states", "8", *TRUTH_FLAGS,
                   "--refine", "--preset", "thesis", "--json", "--quiet")
    cli = json.loads(done.stdout)
    ours = np.array([m.eigenvalue for m in found.modes])
    theirs = np.array([m["eigenvalue_re"] + 1j * m["eigenvalue_im"] for m in cli["modes"]])
    assert ours.shape == theirs.shape == (4,)
    assert np.max(np.abs(ours - theirs)) < 1e-10
    for m, c in zip(found.modes, cli["modes"]):
        assert m.frequency_std_hz == pytest.approx(c["frequency_std_hz"], rel=1e-9)
        assert m.damping_ratio_std == pytest.approx(c["damping_ratio_std"], rel=1e-9)
        assert m.frequency_std_hz > 0 and m.damping_ratio_std > 0
    text = json.loads(found.to_json())
    assert text["refinement"]["converged"] is True
    assert text["refinement"]["fit_after"] <= text["refinement"]["fit_before"]
    assert text["parameters"]["refine"] is True


def test_refine_options_and_plain_identify_have_no_std(noisy_truth):
    frf = era.read_frf(str(noisy_truth))
    plain = era.identify(frf, 8, **TRUTH_SETTINGS, preset="thesis")
    assert all(m.frequency_std_hz is None for m in plain.modes)
    refined = era.identify(frf, 8, **TRUTH_SETTINGS, refine=True,
                           residuals="none", reciprocal=True, weighting="uniform",
                           max_iterations=30, preset="thesis")
    assert len(refined.modes) == 4
    # The refined model's own FRF is what the fit compared: a better fit than ERA's.
    assert np.mean(refined.fit["relative_error"]) < np.mean(plain.fit["relative_error"])


def test_modes_the_start_missed_are_added_as_the_cli_adds_them(noisy_truth, era_cli):
    # Four states give ERA two of the four modes; the refinement finds the others in
    # its residual, as `era identify --refine` does.
    frf = era.read_frf(str(noisy_truth))
    found = era.identify(frf, 4, refine=True, time_domain="discrete")
    done = era_cli("identify", noisy_truth, "--states", "4", "--refine", "--time-domain", "discrete",
                   "--json", "--quiet")
    cli = json.loads(done.stdout)
    ours = np.array([m.eigenvalue for m in found.modes])
    theirs = np.array([m["eigenvalue_re"] + 1j * m["eigenvalue_im"] for m in cli["modes"]])
    assert ours.shape == theirs.shape == (4,)
    assert np.max(np.abs(ours - theirs)) < 1e-10
    assert all(m.physical for m in found.modes)
    added = json.loads(found.to_json())["refinement"]["added_hz"]
    assert len(added) == 2 and added == pytest.approx(cli["refinement"]["added_hz"])
    only_start = era.identify(frf, 4, refine=True, added_modes=False, time_domain="discrete")
    assert len(only_start.modes) == 2
    assert json.loads(only_start.to_json())["parameters"]["added_modes"] is False
