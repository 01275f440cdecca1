"""era.read_geometry: a test geometry's nodes and trace lines as numpy arrays, from the
ARTeMIS export shipped in data/ and from era's geometry CSV; bad files raise ValueError
or OSError with the CLI's message."""

import numpy as np
import pytest

import era
from conftest import REPO

ARTEMIS = REPO / "data" / "pyuff-artemis-geometry" / "artemis_geometry_rpbc.uff"


def test_the_artemis_geometry_is_read_as_the_file_says():
    g = era.read_geometry(ARTEMIS)
    assert g["ids"].shape == (74,) and g["xyz"].shape == (74, 3)
    assert g["lines"].shape == (108, 2) and g["line_rows"].shape == (108, 2)
    row = {int(i): k for k, i in enumerate(g["ids"])}
    # Checked by hand against the file (data/pyuff-artemis-geometry/PROVENANCE.md).
    np.testing.assert_array_equal(g["xyz"][row[93]], [-4.24, 0.875, 0.365])
    np.testing.assert_array_equal(g["xyz"][row[142]], [0.0, 0.1, 1.665])
    np.testing.assert_array_equal(g["lines"][:3], [[16, 17], [16, 20], [16, 18]])
    # line_rows index xyz: the same segments.
    np.testing.assert_array_equal(g["ids"][g["line_rows"]], g["lines"])
    assert g["notes"] == ["skipped: 1 × dataset 2412"]
    assert not g["displacement_systems"].any()


def test_the_csv_is_read(tmp_path):
    path = tmp_path / "g.csv"
    path.write_text("node,x,y,z\n1,0,0,0\n2,1.5,0,0\n3,1.5,2,0.5\nfrom,to\n1,2\n2,3\n")
    g = era.read_geometry(path)
    np.testing.assert_array_equal(g["ids"], [1, 2, 3])
    np.testing.assert_array_equal(g["xyz"][2], [1.5, 2.0, 0.5])
    np.testing.assert_array_equal(g["lines"], [[1, 2], [2, 3]])


@pytest.mark.parametrize(
    "text, message",
    [
        ("node,x,y,z\n1,0,0,0\n1,1,0,0\n", "node 1 is defined twice (lines 2 and 3)"),
        ("node,x,y,z\n1,0,0,0\n2,0,nan,0\n", "node 2 (line 3): coordinate y is NaN"),
        ("node,x,y,z\n1,0,0,0\nfrom,to\n1,4\n", "trace line 1 (line 4) names node 4"),
        ("1,0,0,0\n", "line 1: expected the header 'node,x,y,z'"),
    ],
)
def test_bad_files_raise_value_error_naming_the_line(tmp_path, text, message):
    path = tmp_path / "bad.csv"
    path.write_text(text)
    with pytest.raises(ValueError, match="bad.csv") as e:
        era.read_geometry(path)
    assert message in str(e.value)


def test_a_missing_file_raises_file_not_found(tmp_path):
    with pytest.raises(FileNotFoundError):
        era.read_geometry(tmp_path / "absent.uff")
    with pytest.raises(OSError):
        era.read_geometry(tmp_path)
