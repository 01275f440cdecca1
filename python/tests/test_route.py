"""The route `era.identify` takes by default (the measured preset) and with
`preset="thesis"`, as `era identify` takes it; a late start padded as the CLI pads it,
with the warning of what the padding costs."""

import numpy as np
import pytest

import era
from settings import TRUTH_SETTINGS

TRUTH_HZ = [1748.64, 5031.80, 7709.75, 9458.39]


def route_of(found):
    return {name: value for name, value, _ in found.route}


def test_the_default_route_refines_in_continuous_time_and_says_why():
    noisy = era.simulate_truth_model(noise=0.15, seed=3)
    found = era.identify(noisy)
    route = route_of(found)
    assert route["order"] == "automatic" and route["refinement"] == "on"
    assert route["time domain"] == "continuous" and found.time_domain == "continuous"
    # Receptance has no direct term.
    assert route["direct term"] == "D = 0"
    assert all(reason for _, _, reason in found.route)
    physical = [m.frequency_hz for m in found.modes if m.physical]
    assert np.allclose(physical, TRUTH_HZ, rtol=0.01)
    assert all(m.frequency_std_hz is not None for m in found.modes)
    assert "\"preset\": \"measured\"" in found.to_json()


def test_the_thesis_preset_is_plain_era_and_explicit_keywords_win():
    truth = era.simulate_truth_model()
    plain = era.identify(truth, 8, **TRUTH_SETTINGS, preset="thesis")
    route = route_of(plain)
    assert route["refinement"] == "off" and plain.time_domain == "discrete"
    assert all(m.frequency_std_hz is None for m in plain.modes)
    assert np.allclose(plain.frequency_hz, TRUTH_HZ, atol=0.01)
    refined = era.identify(truth, 8, **TRUTH_SETTINGS, preset="thesis", refine=True)
    assert route_of(refined)["refinement"] == "on" and refined.time_domain == "discrete"
    cautioned = era.identify(truth, 8, **TRUTH_SETTINGS, refine=False, time_domain="continuous")
    assert any("without refinement" in w for w in cautioned.warnings)
    with pytest.raises(ValueError, match="preset 'fast': expected 'measured' or 'thesis'"):
        era.identify(truth, preset="fast")
    with pytest.raises(ValueError, match=r"band \(30(\.0)?, 10(\.0)?\): need 0 <= lo < hi"):
        era.identify(truth, band=(30.0, 10.0))


def receptance(modes, f):
    w = 2 * np.pi * f
    total = np.zeros_like(f, dtype=complex)
    for fn, zeta in modes:
        wn = 2 * np.pi * fn
        total += 1.0 / (wn**2 - w**2 + 2j * zeta * wn * w)
    return total[None, None, :]


def test_a_late_start_is_padded_with_a_warning_and_its_cost_is_said():
    f = np.arange(50, 401) * 0.1  # 5 .. 40 Hz
    with pytest.warns(UserWarning, match="the lines start at 5"):
        frf = era.FrfData(f, receptance([(6.0, 0.02), (13.0, 0.01)], f), "displacement")
    assert frf.lines == 401 and frf.frequency_hz[0] == 0.0
    assert np.all(frf.values[0, 0, :50] == 0)
    plain = era.identify(frf, 4, hankel_factor=20, preset="thesis")
    text = "\n".join(plain.warnings)
    assert "the lines below 5 Hz are zero" in text and "zero_lines" in text, text
    # The refinement fits the measured lines only: the modes are exact again.
    refined = era.identify(frf, 4, hankel_factor=20)
    zeta = sorted((m.frequency_hz, m.damping_ratio) for m in refined.modes)
    assert abs(zeta[0][0] - 6.0) < 1e-6 and abs(zeta[0][1] - 0.02) < 1e-6, zeta
    assert any("free of it" in w for w in refined.warnings)
    # Off the grid: refused with the remedy, as a file would be.
    with pytest.raises(ValueError, match="not on that grid"):
        era.FrfData(f + 0.03, receptance([(6.0, 0.02)], f + 0.03), "displacement")
