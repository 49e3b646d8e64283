"""The wrench-frame check: readings in base axes or the sensor's, told apart by the data."""

from __future__ import annotations

import numpy as np
import pytest

from ftkin.calibration import Samples, SensorModel, check_wrench_frame
from ftkin.exceptions import ConventionMistake, InvalidInput
from ftkin.kinematics.robots import load_robot


def _turn(rotations, wrenches, transpose: bool) -> np.ndarray:
    pattern = "nji,nkj->nki" if transpose else "nij,nkj->nki"
    return np.einsum(pattern, rotations, wrenches.reshape(-1, 2, 3)).reshape(-1, 6)


@pytest.fixture(scope="module")
def recorded():
    """Twelve UR5e poses of a 1.2 kg tool with a bias, 0.05 N / 0.002 N·m noise, in the sensor
    frame (``in_sensor``) and as UR sends them, in base axes (``in_base``)."""
    rng = np.random.default_rng(8)
    arm = load_robot("ur5e")
    rotations = arm.rotation_sensor_to_base(arm.random_configurations(12, rng, margin=0.3))
    tool = SensorModel.from_tool(1.2, [0.01, -0.02, 0.06], [1.5, -2.0, 3.0], [0.05, -0.04, 0.03])
    in_sensor = tool.predict(rotations) + rng.normal(0.0, [0.05] * 3 + [0.002] * 3, (12, 6))
    return rotations, in_sensor, _turn(rotations, in_sensor, transpose=False)


def test_the_right_frame_passes_either_way(recorded):
    rotations, in_sensor, in_base = recorded
    converted = _turn(rotations, in_base, transpose=True)  # what UrArm does for "base"
    np.testing.assert_allclose(converted, in_sensor, atol=1e-12)
    assert check_wrench_frame(Samples(converted, rotations), "base").verdict == "ok"
    assert check_wrench_frame(Samples(in_sensor, rotations), "sensor").verdict == "ok"


def test_base_axes_taken_as_the_sensors_are_refused_naming_the_flag(recorded):
    rotations, _, in_base = recorded
    with pytest.raises(ConventionMistake, match="--wrench-frame base") as error:
        check_wrench_frame(Samples(in_base, rotations), "sensor")
    assert error.value.fix == "--wrench-frame base"
    assert "base" in error.value.reading


def test_sensor_axes_turned_as_if_base_are_refused_naming_the_flag(recorded):
    rotations, in_sensor, _ = recorded
    turned = _turn(rotations, in_sensor, transpose=True)
    with pytest.raises(ConventionMistake, match="--wrench-frame sensor"):
        check_wrench_frame(Samples(turned, rotations), "base")
    check = check_wrench_frame(
        Samples(turned, rotations), "base", flag="wrench_frame=", raise_on_mistake=False
    )
    assert check.verdict == "mistake" and check.fix == "wrench_frame='sensor'"
    assert "wrench_frame='sensor'" in check.message and check.other_frame == "sensor"


def test_a_weightless_bias_in_base_axes_is_caught_by_its_weight():
    """No tool, only a bias: in base axes the readings turn, read as the sensor's they fit a tool
    that weighs nothing (doctor's plausibility rule)."""
    rng = np.random.default_rng(2)
    arm = load_robot("ur10e")
    rotations = arm.rotation_sensor_to_base(arm.random_configurations(10, rng, margin=0.3))
    tool = SensorModel.from_tool(0.8, [0.0, 0.0, 0.04], [0.0, 0.0, 0.0], [0.0, 0.0, 0.0])
    in_base = _turn(rotations, tool.predict(rotations), transpose=False)
    in_base += rng.normal(0.0, [0.02] * 3 + [0.001] * 3, in_base.shape)
    with pytest.raises(ConventionMistake, match="--wrench-frame base"):
        check_wrench_frame(Samples(in_base, rotations), "sensor")


def test_poses_that_cannot_tell_are_undetermined_not_refused(recorded):
    rotations, in_sensor, in_base = recorded
    two = Samples(in_base[:2], rotations[:2])
    assert check_wrench_frame(two, "sensor").verdict == "undetermined"
    one_orientation = Samples(np.repeat(in_base[:1], 5, axis=0), np.repeat(rotations[:1], 5, 0))
    assert check_wrench_frame(one_orientation, "sensor").verdict == "undetermined"


def test_bad_frame_name():
    with pytest.raises(InvalidInput, match="'base', 'sensor'"):
        check_wrench_frame(Samples(np.zeros((3, 6)), np.tile(np.eye(3), (3, 1, 1))), "tool")
