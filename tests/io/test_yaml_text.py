"""ftkin's YAML writer, read back with PyYAML."""

from __future__ import annotations

import numpy as np
import pytest

from ftkin import InvalidInput
from ftkin.io.yaml_text import yaml_text

yaml = pytest.importorskip("yaml")


def test_nested_blocks_rows_and_escaped_strings_read_back():
    tree = {
        "name": 'a "quoted": name',
        "params": {
            "mass": np.float64(0.3215),
            "cog": np.array([0.0, -0.0003, 0.047]),
            "flag": True,
            "none": None,
        },
        "rows": [[0.1, 0.2], [0.3, 0.4]],
    }
    parsed = yaml.safe_load(yaml_text(tree))
    assert parsed["name"] == tree["name"]
    assert parsed["params"] == {
        "mass": 0.3215,
        "cog": [0.0, -0.0003, 0.047],
        "flag": True,
        "none": None,
    }
    assert parsed["rows"] == tree["rows"]


@pytest.mark.parametrize("bad", [float("nan"), np.array([1.0, np.inf]), object()])
def test_non_finite_or_unknown_values_are_refused(bad):
    with pytest.raises(InvalidInput, match="cannot write"):
        yaml_text({"x": bad})


@pytest.mark.parametrize(
    "name",
    [
        "node\ninjected: 1",
        "a: b",
        "# not a comment",
        "- item",
        "{x: 1}",
        "'quote",
        "key\n  nested: true",
        "ü ∑ 🙂",
        "null",
        "1e3",
    ],
)
def test_no_key_or_value_can_inject_structure(name):
    tree = {name: {"ros__parameters": {"frame": name, "values": [1.0, 2.5]}}}
    text = yaml_text(tree, comments=["header", "two\nlines: injected"])
    assert yaml.safe_load(text) == tree
    assert [line for line in text.splitlines() if line.startswith("#")] == [
        "# header",
        "# two",
        "# lines: injected",
    ]


def test_export_cannot_be_injected_through_the_node_name(truth):
    """Names are checked against ROS's rules before the YAML writer sees them."""
    from ftkin.exceptions import InvalidInput
    from ftkin.io.export import export_text

    with pytest.raises(InvalidInput, match="--node-name 'ctrl.*' is not a valid ROS node name"):
        export_text(truth, "admittance", node_name="ctrl\ninjected: 1")
    with pytest.raises(InvalidInput, match="--frame-id 'f.*' is not a valid ROS frame"):
        export_text(truth, "admittance", frame_id="f\nx: 2")
