"""A pose plan written to a file by the library (ftkin.io.plan_file), as ``ftkin plan -o`` writes
it: each format read back by another reader (csv, json, PyYAML) and compared with the plan."""

from __future__ import annotations

import csv
import json

import numpy as np
import pytest
import yaml

from ftkin import InvalidInput
from ftkin.io.plan_file import plan_format, write_plan
from ftkin.planning.plan import plan_poses


@pytest.fixture(scope="module")
def plan(arm):
    return plan_poses(arm, 4, seed=1, candidates=200, drift_rate=[0.002, 4e-5], pose_interval=20.0)


def test_the_file_name_chooses_the_format_unless_one_is_given():
    assert [plan_format(name) for name in ("p.csv", "p.YML", "p.yaml", "p.json", "p.txt")] == [
        "csv",
        "yaml",
        "yaml",
        "json",
        "csv",
    ]
    assert plan_format("p.json", "csv") == "csv"
    with pytest.raises(InvalidInput, match="plan format 'xml' is not one of csv, yaml, json"):
        plan_format("p.xml", "xml")


def test_each_format_holds_the_plan(plan, tmp_path):
    assert write_plan(plan, tmp_path / "p.csv") == "csv"
    with open(tmp_path / "p.csv", newline="") as stream:
        rows = list(csv.reader(stream))
    assert rows[0] == ["pose", *plan.joint_names]
    np.testing.assert_array_equal([int(row[0]) for row in rows[1:]], np.arange(4))
    np.testing.assert_allclose(
        [[float(v) for v in row[1:]] for row in rows[1:]], plan.joint_positions, rtol=1e-15
    )
    for name, read in (("p.json", json.loads), ("p.yaml", yaml.safe_load)):
        write_plan(plan, tmp_path / name)
        document = read((tmp_path / name).read_text())
        np.testing.assert_allclose(document["joint_positions_rad"], plan.joint_positions)
        assert document["joint_names"] == list(plan.joint_names) and document["seed"] == 1
        np.testing.assert_allclose(document["drift_rate"], [0.002, 4e-5])
        assert document["pose_interval_s"] == pytest.approx(20.0)
        np.testing.assert_allclose(
            document["predicted_standard_errors"]["tool_weight"],
            np.atleast_1d(plan.standard_errors["tool_weight"]),
        )


def test_the_printed_pose_table_holds_the_joint_positions_to_four_decimals(plan):
    lines = plan.pose_table().splitlines()
    assert lines[0] == "joint positions [rad], in visiting order:"
    assert lines[1].split() == ["pose", *[name[:12] for name in plan.joint_names]]
    values = np.array([[float(v) for v in line.split()] for line in lines[2:]])
    np.testing.assert_array_equal(values[:, 0], np.arange(4))
    np.testing.assert_allclose(values[:, 1:], plan.joint_positions, atol=5e-5)
