"""Identification.shapes_on: each mode's displacement at the nodes of a geometry, from a
path or from era.read_geometry's dict; nodes without a channel are NaN, channels without
a node listed, and a geometry that carries no output raises ValueError."""

import numpy as np
import pytest

import era
from conftest import REPO

ARTEMIS = REPO / "data" / "pyuff-artemis-geometry" / "artemis_geometry_rpbc.uff"


@pytest.fixture(scope="module")
def found():
    # The truth model: 3 outputs, era's numbering (nodes 1..3, +Z), four modes.
    return era.identify(era.simulate_truth_model(), states=8, preset="thesis")


def frame(tmp_path, text="node,x,y,z\n1,0,0,0\n2,1,0,0\n7,2,0,0.5\nfrom,to\n1,2\n2,7\n"):
    path = tmp_path / "g.csv"
    path.write_text(text)
    return path


def test_each_node_moves_as_its_channels_say(found, tmp_path):
    s = found.shapes_on(frame(tmp_path))
    modes = found.modes
    assert s["displacement"].shape == (len(modes), 3, 3)
    assert s["displacement"].dtype == np.complex128
    np.testing.assert_array_equal(s["ids"], [1, 2, 7])
    np.testing.assert_array_equal(s["measured"], [True, True, False])
    for k, m in enumerate(modes):
        # Nodes 1 and 2 carry outputs 1 and 2 in +Z: the shape's entries, unscaled.
        np.testing.assert_array_equal(s["displacement"][k, 0], [0, 0, m.shape[0]])
        np.testing.assert_array_equal(s["displacement"][k, 1], [0, 0, m.shape[1]])
        # Node 7 has no channel: NaN, not zero.
        assert np.isnan(s["displacement"][k, 2]).all()
    # Output 3 is on node 3, which the geometry does not have.
    np.testing.assert_array_equal(s["not_drawn_outputs"], [2])
    assert s["not_drawn"] == ["output 3 (node 3 +Z): node 3 is not in the geometry"]


def test_the_dict_of_read_geometry_and_a_channel_table(found, tmp_path):
    g = era.read_geometry(frame(tmp_path))
    # Output 1 at node 7 in -X, output 2 at node 1 in +Y, output 3 at node 2 (Z by number).
    s = found.shapes_on(g, channels=[(7, "-X"), (1, "+Y"), (2, 3)])
    np.testing.assert_array_equal(s["measured"], [True, True, True])
    for k, m in enumerate(found.modes):
        np.testing.assert_array_equal(s["displacement"][k, 2], [-m.shape[0], 0, 0])
        np.testing.assert_array_equal(s["displacement"][k, 0], [0, m.shape[1], 0])
        np.testing.assert_array_equal(s["displacement"][k, 1], [0, 0, m.shape[2]])
    assert s["not_drawn"] == []


def test_the_artemis_geometry_by_path(found):
    s = found.shapes_on(ARTEMIS, channels=[(16, "+Z"), (17, "+Z"), (999, "+Z")])
    assert s["xyz"].shape == (74, 3)
    assert s["measured"].sum() == 2
    np.testing.assert_array_equal(s["not_drawn_outputs"], [2])


def test_a_geometry_that_does_not_fit_raises_value_error(found, tmp_path):
    away = frame(tmp_path, "node,x,y,z\n50,0,0,0\n51,1,0,0\n")
    with pytest.raises(ValueError, match="carries none of the 3 outputs"):
        found.shapes_on(away)
    with pytest.raises(ValueError, match="3 outputs"):
        found.shapes_on(frame(tmp_path), channels=[(1, "+Z")])
    with pytest.raises(ValueError, match="direction"):
        found.shapes_on(frame(tmp_path), channels=[(1, "up"), (2, "+Z"), (7, "+Z")])
    with pytest.raises(ValueError, match="defined twice"):
        found.shapes_on({"ids": np.array([1, 1]), "xyz": np.zeros((2, 3))})
    with pytest.raises(ValueError, match="line 3"):
        found.shapes_on(frame(tmp_path, "node,x,y,z\n1,0,0,0\n2,NaN,0,0\n"))
    with pytest.raises(FileNotFoundError):
        found.shapes_on(tmp_path / "missing.csv")
