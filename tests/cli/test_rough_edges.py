"""Rough edges a new user hits: floor by default, frame names, readable reprs, warnings once, fault
'none'.
"""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest

import ftkin
from ftkin.cli import main
from ftkin.io.csv_table import read_table


def _heights(arm, q):
    """Base-frame z [m] of the sensor and tool (or flange) origins at each configuration, by
    Pinocchio directly.
    """
    model, data = arm.model, arm.model.createData()
    frames = [arm.sensor_frame_id] + ([arm.tool_frame_id] if arm.tool_frame_id is not None else [])
    out = []
    for config in q:
        pin.forwardKinematics(model, data, config)
        out.append([pin.updateFramePlacement(model, data, f).translation[2] for f in frames])
    return np.array(out)


@pytest.mark.parametrize("robot", ["ftkin_c4", "ur10"])
def test_default_plan_keeps_sensor_and_tool_above_the_floor(robot, tmp_path, capsys):
    out = tmp_path / "plan.csv"
    assert main(["plan", "-n", "6", "--robot", robot, "--no-self-collision", "-o", str(out)]) == 0
    assert "sensor and tool above 0.1 m (base z)" in capsys.readouterr().out
    table = read_table(out)
    arm = ftkin.load_robot(robot)
    q = table.floats(table.header[1:])
    assert _heights(arm, q).min() >= 0.1 - 1e-9


def test_no_floor_is_explicit(capsys):
    assert main(["plan", "-n", "4", "--no-self-collision", "--no-floor"]) == 0
    assert "sensor and tool above" not in capsys.readouterr().out


def test_frame_names_are_suggested(tmp_path):
    with pytest.raises(ftkin.FrameNotFound, match="did you mean 'ft_sensor'") as info:
        ftkin.Arm.from_urdf(ftkin.kinematics.bundled_urdf_path(), "FT_sensor")
    assert "--sensor-parent" not in str(info.value)  # a near miss: no advice to add a frame
    from ftkin.kinematics.robots import ROBOT_SPECS, example_robot_data_share

    ur5 = example_robot_data_share() / "example-robot-data" / "robots" / ROBOT_SPECS["ur5"].urdf
    with pytest.raises(
        ftkin.FrameNotFound,
        match=r"add it at the link the sensor is bolted to, e.g. --sensor-parent tool0",
    ):
        ftkin.Arm.from_urdf(ur5, "ft_sensor")


def test_readable_reprs(arm, truth):
    assert repr(arm) == "Arm(ftkin_c4: 6 joints, sensor frame 'ft_sensor', tool frame 'tool')"
    text = repr(truth)
    assert (
        text.startswith("SensorModel(tool_weight=3.15")
        and "center_of_mass=[0.0001, -0.0003, 0.047] m" in text
    )
    compensator = repr(ftkin.Compensator(truth, arm))
    assert (
        compensator.startswith("Compensator(tool 3.155 N")
        and "arm ft_sensor of ftkin_c4.urdf" in compensator
    )
    assert str(ftkin.control.StepStatus.__dataclass_fields__["fault"].default) == "none"
    assert f"{ftkin.control.SensorFault.NONE}" == "none"


def test_each_warning_is_printed_once(arm, truth, tmp_path, capsys):
    from ftkin.io.csv_table import write_csv

    rng = np.random.default_rng(9)
    q = arm.random_configurations(4, rng, margin=0.3)
    wrenches = truth.predict(arm.rotation_sensor_to_base(q)) + rng.normal(scale=0.05, size=(4, 6))
    path = write_csv(
        tmp_path / "few.csv",
        [f"q{i + 1}" for i in range(6)] + ["fx", "fy", "fz", "mx", "my", "mz"],
        np.hstack([q, wrenches]).tolist(),
    )
    assert main(["calibrate", str(path)]) == 0
    captured = capsys.readouterr()
    text = captured.out + captured.err
    warnings = [
        line.split("WARNING: ")[-1].removeprefix("ftkin: ")
        for line in text.splitlines()
        if "poorly determined" in line
    ]
    assert warnings and len(warnings) == len(set(warnings))
